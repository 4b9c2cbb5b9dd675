#!/usr/bin/env python3
"""Cost of the exact rational fallback solve (method.md section 8).

Question: up to how many transient unknowns does the exact solve that
replaces a refused double-precision solve stay cheap (under about one
second)? Runs `examples/exact_solve.rs` once per (walk length, controller
nodes) under /usr/bin/time and writes results/exact-solve.csv: the
unknowns, the seconds of `eval` refused in double precision (no fallback)
and with the exact fallback, the process's CPU seconds (user + system),
the value, its error bound and its distance to the value on paper.
The chosen limit is `posg_fsc::value::exact::DEFAULT_EXACT_LIMIT`.

Usage: python3 experiments/exact-solve/run.py [--lengths 51 101 ...] [--nodes 2 3]
"""
import argparse
import csv
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLE = os.path.join(ROOT, "target", "release", "examples", "exact_solve")
COLUMNS = ["length", "nodes", "unknowns", "double_ok", "double_seconds", "exact_used",
           "exact_seconds", "value", "error_bound", "distance_to_paper", "cpu_seconds"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lengths", type=int, nargs="+",
                        default=[51, 101, 251, 501, 751, 1001, 1251, 1501, 2001])
    parser.add_argument("--nodes", type=int, nargs="+", default=[2, 3])
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "exact-solve.csv"))
    args = parser.parse_args()
    subprocess.run(["cargo", "build", "--release", "--locked", "--quiet", "--example", "exact_solve"],
                   cwd=ROOT, check=True)
    version = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT,
                             capture_output=True, text=True).stdout.strip()
    with open(args.out, "w", newline="") as file:
        file.write(f"# {' '.join(sys.argv)} (posg-fsc {version}); one process per row, "
                   "a shared 2-core machine\n")
        writer = csv.writer(file)
        writer.writerow(COLUMNS)
        for length in args.lengths:
            for nodes in args.nodes:
                done = subprocess.run(["/usr/bin/time", "-f", "%U %S", EXAMPLE, str(length), str(nodes)],
                                      capture_output=True, text=True, check=True)
                user, system = map(float, done.stderr.strip().splitlines()[-1].split())
                row = done.stdout.strip().split(",") + [f"{user + system:.2f}"]
                writer.writerow(row)
                file.flush()
                print(",".join(row), flush=True)


if __name__ == "__main__":
    main()
