#!/usr/bin/env python3
"""Cost of the exact fallback solve on stiff chains (method.md section 8, issue 57).

Question: how long does the exact solve that replaces a refused
double-precision solve take on stiff chains of 100 to 1,000 unknowns (and
beyond) whose probabilities are full-precision doubles, with Dixon's
p-adic lifting against the earlier elimination in rationals? Runs
`examples/exact_fallback.rs` (`chain WALK NODES SEED`) once per (unknowns,
nodes, seed) under /usr/bin/time, then, for the first seed, again with
`old` (the reference elimination, `solve_by_rational_elimination`) under a
timeout; once the old method times out for a number of nodes, larger
sizes are not tried with it. Writes results/exact-fallback.csv.

Usage: python3 experiments/exact-fallback/run.py [--unknowns 100 200 ...]
       [--nodes 1 2 3] [--seeds 1 2 3] [--old-timeout 60]
"""
import argparse
import csv
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
EXAMPLE = os.path.join(TARGET, "release", "examples", "exact_fallback")
COLUMNS = ["walk", "nodes", "seed", "unknowns", "seconds", "error_bound", "largest_value",
           "cpu_seconds", "old_seconds", "old_same_doubles"]


def timed(arguments, timeout=None):
    """The example's CSV fields and the CPU seconds, or None on timeout."""
    try:
        done = subprocess.run(["/usr/bin/time", "-f", "%U %S", EXAMPLE] + arguments,
                              capture_output=True, text=True, check=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    user, system = map(float, done.stderr.strip().splitlines()[-1].split())
    return done.stdout.strip().split(","), user + system


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--unknowns", type=int, nargs="+",
                        default=[100, 200, 300, 400, 500, 600, 800, 1000, 2000, 3000])
    parser.add_argument("--nodes", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--old-timeout", type=float, default=60.0)
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "exact-fallback.csv"))
    args = parser.parse_args()
    subprocess.run(["cargo", "build", "--release", "--locked", "--quiet", "--example",
                    "exact_fallback"], cwd=ROOT, check=True)
    version = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT,
                             capture_output=True, text=True).stdout.strip()
    old_gave_up = set()
    with open(args.out, "w", newline="") as file:
        file.write(f"# {' '.join(sys.argv)} (posg-fsc {version}); escapes 1e-15 x U(0.5, 1.5) "
                   f"random doubles; one process per run, old timeout {args.old_timeout:g} s, "
                   "a shared 2-core machine\n")
        writer = csv.writer(file)
        writer.writerow(COLUMNS)
        for unknowns in args.unknowns:
            for nodes in args.nodes:
                walk = max(1, round(unknowns / nodes))
                for seed in args.seeds:
                    fields, cpu = timed(["chain", str(walk), str(nodes), str(seed)])
                    row = fields[:7] + [f"{cpu:.2f}"]
                    if seed == args.seeds[0] and nodes not in old_gave_up:
                        old = timed(["chain", str(walk), str(nodes), str(seed), "old"],
                                    timeout=args.old_timeout)
                        if old is None:
                            old_gave_up.add(nodes)
                            row += [f">{args.old_timeout:g}", ""]
                        else:
                            row += old[0][7:9]
                    else:
                        row += ["", ""]
                    writer.writerow(row)
                    file.flush()
                    print(",".join(row), flush=True)


if __name__ == "__main__":
    main()
