#!/usr/bin/env python3
"""An independent decoder: reads a critterbox recording with the Python `mcap` package and
`json.loads` only, and checks one critter's trajectory against the CSV that `critterbox export`
(the Rust reader) wrote from the same file. Floats are compared exactly.

Usage: python3 tests/python/read_recording.py RECORDING.mcap CSV_DIR
"""
import csv
import json
import math
import sys

from mcap.reader import make_reader


def number(v):
    # Non-finite floats are written as strings ("inf", "-inf", "nan").
    return float(v) if isinstance(v, str) else v


def same(a, b):
    return a == b or (math.isnan(a) and math.isnan(b))


def main(path, csv_dir):
    failures = []
    with open(path, "rb") as f:
        reader = make_reader(f)
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    with open(path, "rb") as f:
        reader = make_reader(f)
        scripts = [a.name for a in reader.iter_attachments()]
    run = meta.get("critterbox")
    if run is None or run.get("format") not in ("critterbox-recording/1", "critterbox-recording/2"):
        failures.append("no critterbox metadata record")
        run = {}
    print(f"scene {run.get('scene')} ({run.get('dim')}D), seed {run.get('seed')}, "
          f"{len(scripts)} script attachments, ended: {meta.get('critterbox.end', {}).get('outcome')}")

    # Every state message, decoded with json.loads alone.
    trajectory = {}  # step -> (x, y, vx, vy) of the chosen critter
    chosen = None
    hashes = 0
    schemas = set()
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            schemas.add((channel.topic, schema.name if schema else None, schema.encoding if schema else None))
            if channel.topic == "/critterbox/hash":
                hashes += 1
            if channel.topic != "/critterbox/state":
                continue
            state = json.loads(message.data)
            ids = state["id"]
            if chosen is None:
                # The first critter that is not a wall.
                walls = {k for k, name in enumerate(state["kinds"]) if name == "wall"}
                chosen = next(i for i, k in zip(ids, state["kind"]) if k not in walls)
            if chosen not in ids:
                continue
            i = ids.index(chosen)
            trajectory[state["step"]] = tuple(number(state[c][i]) for c in ("x", "y", "vx", "vy"))
    for topic, name, encoding in sorted(schemas):
        if encoding != "jsonschema":
            failures.append(f"{topic}: schema encoding {encoding}, not jsonschema")

    # The same critter in the Rust reader's CSV.
    label = f"#{chosen & 0xFFFFFFFF}" + (f"v{chosen >> 32}" if chosen >> 32 else "")
    from_csv = {}
    with open(f"{csv_dir}/states.csv", newline="") as f:
        for row in csv.DictReader(f):
            if row["id"] == label:
                from_csv[int(row["step"])] = tuple(float(row[c]) for c in ("x", "y", "vx", "vy"))
    with open(f"{csv_dir}/steps.csv", newline="") as f:
        steps = sum(1 for _ in csv.DictReader(f))

    if not trajectory:
        failures.append("no state messages")
    if sorted(trajectory) != sorted(from_csv):
        failures.append(f"steps differ: {len(trajectory)} in the MCAP file, {len(from_csv)} in the CSV")
    for step in sorted(set(trajectory) & set(from_csv)):
        a, b = trajectory[step], from_csv[step]
        if not all(same(x, y) for x, y in zip(a, b)):
            failures.append(f"critter {label} at step {step}: mcap {a}, csv {b}")
            break
    if hashes != steps:
        failures.append(f"{hashes} hash messages, {steps} rows in steps.csv")

    print(f"critter {label}: {len(trajectory)} states decoded with json.loads, "
          f"{len(from_csv)} rows from critterbox export, {hashes} step hashes")
    for f in failures:
        print("FAILED:", f)
    print(f"{0 if failures else 1} passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
