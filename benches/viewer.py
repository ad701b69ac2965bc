"""What watching a run in Rerun costs the simulation: `critterbox run gas -n N` with no viewer,
streaming live to a Rerun server (the `rerun` CLI of rerun-sdk 0.36.3 as a headless gRPC
receiver, on the same machine), and saving an .rrd file; modes interleaved, ROUNDS rounds,
medians. Prints a markdown table for docs/viewer.md.

Usage: cargo build --release --features rerun && python3 benches/viewer.py [ROUNDS]
"""
import re
import statistics
import subprocess
import sys
import tempfile
import time

ROUNDS = int(sys.argv[1]) if len(sys.argv) > 1 else 5
BIN = "target/release/critterbox"
PORT = 9877
SIZES = [(100, 2000), (1000, 1000), (10000, 300)]


def run(n, steps, mode, rrd):
    cmd = [BIN, "run", "gas", "-n", str(n), "--steps", str(steps), "--no-record"]
    if mode == "live":
        cmd += ["--rerun-connect", f"rerun+http://127.0.0.1:{PORT}/proxy"]
    elif mode == "save":
        cmd += ["--rerun-save", rrd]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    ms = float(re.search(r"\(([\d.]+) ms/step\)", out).group(1))
    viewer = re.search(r"viewer\s+([\d.]+) s of the simulation thread", out)
    sim_thread = float(viewer.group(1)) * 1e3 / steps if viewer else 0.0
    skipped = re.search(r"(\d+) steps not shown", out)
    return ms, sim_thread, int(skipped.group(1)) if skipped else 0


server = subprocess.Popen(["rerun", "--serve-grpc", "--port", str(PORT)],
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
time.sleep(3)
try:
    with tempfile.TemporaryDirectory() as d:
        rows = []
        for n, steps in SIZES:
            got = {m: [] for m in ("none", "live", "save")}
            for _ in range(ROUNDS):
                for m in got:
                    got[m].append(run(n, steps, m, f"{d}/run.rrd"))
            med = {m: (statistics.median(x[0] for x in v), statistics.median(x[1] for x in v),
                       max(x[2] for x in v)) for m, v in got.items()}
            base = med["none"][0]
            for m in ("live", "save"):
                ms, sim, skipped = med[m]
                rows.append(f"| {n:,} | {m} | {base:.4f} | {ms:.4f} | {ms / base:.2f}x "
                            f"| {sim:.4f} ({100 * sim / base:.0f}% of a step) | {skipped} |")
        print("| critters | viewer | ms/step, no viewer | ms/step, viewing | ratio "
              "| simulation thread's share, ms/step | steps skipped (max) |")
        print("|---|---|---|---|---|---|---|")
        print("\n".join(rows))
finally:
    server.terminate()
