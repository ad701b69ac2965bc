#!/usr/bin/env python3
"""Prints criterion medians from target/criterion as markdown tables, with ratios taken in the same run.

Usage: python3 benches/report.py [target/criterion]
"""
import glob
import json
import os
import sys

root = sys.argv[1] if len(sys.argv) > 1 else "target/criterion"
medians = {}
for path in glob.glob(os.path.join(root, "*", "*", "*", "new", "estimates.json")):
    group, name, n = path.split(os.sep)[-5:-2]
    with open(path) as f:
        medians[(group, name, int(n))] = json.load(f)["median"]["point_estimate"] / 1e6  # ms

for group in sorted({g for g, _, _ in medians}):
    names = sorted({name for g, name, _ in medians if g == group})
    sizes = sorted({n for g, _, n in medians if g == group})
    print(f"\n### {group} (median ms per step)\n")
    header = "| N | " + " | ".join(names) + (f" | {names[1]} / {names[0]} |" if len(names) == 2 else " |")
    print(header)
    print("|" + "---|" * (header.count("|") - 1))
    for n in sizes:
        row = [medians.get((group, name, n)) for name in names]
        cells = [f"{v:.4f}" if v is not None else "-" for v in row]
        ratio = ""
        if len(names) == 2:
            ratio = f" {row[1] / row[0]:.2f} |" if None not in row else " - |"
        print(f"| {n} | " + " | ".join(cells) + " |" + ratio)
