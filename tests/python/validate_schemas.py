#!/usr/bin/env python3
"""Every message of a critterbox recording against the JSON Schema its channel declares (the
schema record inside the file), with the `mcap` and `jsonschema` packages only: a channel whose
schema and messages disagree fails here, whatever critterbox's own reader accepts.

Usage: python3 tests/python/validate_schemas.py RECORDING.mcap [...]
"""
import json
import sys

import jsonschema
from mcap.reader import make_reader


def main(paths):
    failures = 0
    for path in paths:
        counts = {}
        with open(path, "rb") as f:
            validators = {}
            for schema, channel, message in make_reader(f).iter_messages():
                if schema is None or schema.encoding != "jsonschema":
                    continue
                if schema.id not in validators:
                    doc = json.loads(schema.data)
                    jsonschema.Draft202012Validator.check_schema(doc)
                    validators[schema.id] = jsonschema.Draft202012Validator(doc)
                errors = list(validators[schema.id].iter_errors(json.loads(message.data)))
                counts[channel.topic] = counts.get(channel.topic, 0) + 1
                for e in errors[:3]:
                    failures += 1
                    if failures <= 10:
                        print(f"{path}: {channel.topic} at log time {message.log_time}: {e.message}")
        print(f"{path}: " + ", ".join(f"{t} {n}" for t, n in sorted(counts.items())))
        if len(counts) < 4:
            failures += 1
            print(f"{path}: expected the state, hash, totals and a scene channel at least")
    if failures:
        print(f"{failures} schema violations")
        sys.exit(1)
    print("every message matches its channel's schema")


if __name__ == "__main__":
    main(sys.argv[1:])
