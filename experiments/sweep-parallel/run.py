#!/usr/bin/env python3
"""Wall time of `posg-fsc sweep` over 6x3 controller-size pairs against the
sum of the 18 single `solve` runs it replaces.

Question (issue 7): on this 2-core machine, is a sweep's wall time at most
0.6x the sum of the single runs? The sweep runs the size pairs in parallel
(rayon), each with the same settings as the single runs. Both use a fixed
iteration count, so they do the same work. Writes
results/sweep-parallel.csv (one row per run) and prints the ratio.

Usage: python3 experiments/sweep-parallel/run.py [--repeats 3]
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BINARY = os.path.join(ROOT, "target", "release", "posg-fsc")
OUT = os.path.join(ROOT, "results", "sweep-parallel.csv")
FORMULA = "!unsafe U goal"
DEF_NODES = range(1, 7)
ADV_NODES = range(1, 4)
SETTINGS = ["--max-iterations", "30", "--check-every", "10", "--restarts", "2", "--seed", "1"]


def timed(command):
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    version = subprocess.run([BINARY, "--version"], capture_output=True, text=True, check=True).stdout.strip()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        game = os.path.join(tmp, "grid6.posg.json")
        subprocess.run([BINARY, "example", "grid", "--width", "6", "--height", "6", "--unsafe", "s14,s21",
                        "--goal", "s35", "--out", game], check=True)
        for repeat in range(args.repeats):
            singles = 0.0
            for n in DEF_NODES:
                for m in ADV_NODES:
                    command = [BINARY, "solve", game, "--ltl", FORMULA, "--def-nodes", str(n),
                               "--adv-nodes", str(m), "--out", os.path.join(tmp, f"s{n}-{m}")] + SETTINGS
                    seconds = timed(command)
                    singles += seconds
                    rows.append({"repeat": repeat, "run": f"solve def{n} adv{m}", "seconds": f"{seconds:.3f}"})
            sweep = timed([BINARY, "sweep", game, "--ltl", FORMULA, "--def-nodes", "1..6", "--adv-nodes", "1..3",
                           "--out", os.path.join(tmp, "sweep")] + SETTINGS)
            rows.append({"repeat": repeat, "run": "sum of single solves", "seconds": f"{singles:.3f}"})
            rows.append({"repeat": repeat, "run": "sweep 6x3", "seconds": f"{sweep:.3f}"})
            rows.append({"repeat": repeat, "run": "ratio sweep / sum", "seconds": f"{sweep / singles:.3f}"})
            print(f"repeat {repeat}: singles {singles:.1f} s, sweep {sweep:.1f} s, ratio {sweep / singles:.3f}",
                  file=sys.stderr)
    ratios = [float(r["seconds"]) for r in rows if r["run"] == "ratio sweep / sum"]
    with open(OUT, "w", newline="") as handle:
        handle.write(f"# command: python3 experiments/sweep-parallel/run.py --repeats {args.repeats}\n")
        handle.write(f"# {version}; grid 6x6, formula '{FORMULA}', solve/sweep settings: {' '.join(SETTINGS)}; "
                     f"{os.cpu_count()} logical cores; median ratio {statistics.median(ratios):.3f}\n")
        writer = csv.DictWriter(handle, fieldnames=["repeat", "run", "seconds"])
        writer.writeheader()
        writer.writerows(rows)
    print(f"median ratio sweep / sum of singles: {statistics.median(ratios):.3f}")


if __name__ == "__main__":
    main()
