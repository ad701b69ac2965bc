"""Reads a Rerun file with rerun's own reader and prints, as JSON: the entity paths, the number
of distinct values on the `step` timeline, and one entity's n-th position at every step.

Usage: python3 rrd_summary.py FILE.rrd ENTITY INDEX   (needs rerun-sdk==0.36.3)
"""
import json
import sys

import rerun.experimental as rx

path, entity, index = sys.argv[1], sys.argv[2], int(sys.argv[3])
entities, steps, track = set(), set(), {}
for chunk in rx.RrdReader(path).store().stream().to_chunks():
    name = str(chunk.entity_path)
    entities.add(name)
    if chunk.is_static:
        continue
    batch = chunk.to_record_batch()
    columns = batch.schema.names
    if "step" not in columns:
        continue
    at = batch.column("step").to_pylist()
    steps.update(at)
    if name == entity:
        column = next(c for c in columns if c.endswith(":positions") or c.endswith(":centers"))
        for step, points in zip(at, batch.column(column).to_pylist()):
            if points is not None and len(points) > index:
                track[step] = points[index]
print(json.dumps({"entities": sorted(entities), "steps": len(steps),
                  "track": [[k, track[k]] for k in sorted(track)]}))
