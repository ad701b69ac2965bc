"""Reads a Rerun file with rerun's own reader and prints every logged value as JSON lines, sorted:
one line per (entity, step, component column) with the value, static data under step null.

Row ids and the given entities (say /stats/step_ms, which holds wall-clock times) are left out,
so two files of the same run compare equal line for line.

Usage: python3 rrd_dump.py FILE.rrd [SKIP_ENTITY...]   (needs rerun-sdk==0.36.3)
"""
import json
import sys

import rerun.experimental as rx

path, skip = sys.argv[1], set(sys.argv[2:])
lines = []
for chunk in rx.RrdReader(path).store().stream().to_chunks():
    entity = str(chunk.entity_path)
    if entity in skip or entity.startswith("/__"):
        continue
    batch = chunk.to_record_batch()
    names = batch.schema.names
    steps = batch.column("step").to_pylist() if "step" in names else [None] * batch.num_rows
    for name in names:
        if name in ("step", "sim_time", "log_time", "log_tick") or "RowId" in name or "row_id" in name:
            continue
        for step, value in zip(steps, batch.column(name).to_pylist()):
            if value is None:
                continue
            lines.append(json.dumps([entity, step, name, value], default=str))
lines.sort()
print("\n".join(lines))
