#!/usr/bin/env python3
"""Fill and time of faer's sparse LU of `I - Q` under different fill-reducing
orderings (issue 15: does another ordering than faer's COLAMD cut the fill on
grid-like chains?).

For each (grid side, ordering, factorisation) it runs
`cargo run --release --example lu_ordering -- SIDE ORDERING FACTORISATION`
once under `/usr/bin/time` (peak RSS of the process) and writes
results/lu-ordering.csv with the command and the posg-fsc version in the
header. Grids of the paper's family (unsafe cell (1, 1), goal in the far
corner), `!unsafe U goal`, 2-node uniform controllers for both players;
`examples/lu_ordering.rs` says what each column means. One run per row on a
shared 2-core machine: compare rows of one run only.

`--reuse results/lu-ordering.csv --reuse-candidates colamd:faer amd:simplicial --reuse-sides
288` copies those rows from an earlier CSV instead of measuring them again
(faer's rows do not depend on posg-fsc's own LU; the slowest take 10
minutes at 288x288); the header names the copied rows and the earlier
CSV's header.

Usage: python3 experiments/lu-ordering/run.py [--sides 128 288] [--reuse OLD.csv
       --reuse-candidates ORDERING:FACTORISATION ... --reuse-sides SIDE ...]
"""
import argparse
import csv
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
# (ordering, factorisation); at the larger sides only the ones that fit in
# memory and time (AMD's A^T A structure at 288x288 needs over 10 GiB).
CANDIDATES = [
    ("colamd", "faer"),
    ("colamd", "supernodal"),
    ("amd", "supernodal"),
    ("natural", "supernodal"),
    ("colamd", "simplicial"),
    ("amd", "simplicial"),
    ("auto", "multifrontal"),
]
LARGE_CANDIDATES = [("colamd", "faer"), ("amd", "simplicial"), ("auto", "multifrontal")]
HEADER = ["grid", "unknowns", "nonzeros", "ordering", "factorisation", "ordering_s", "symbolic_s",
          "numeric_s", "solve_s", "fill", "numeric_mib", "relative_residual", "peak_gib"]


def version():
    out = subprocess.run(["cargo", "run", "--release", "--quiet", "--", "--version"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout.strip()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True, check=True).stdout.strip()
    return f"{out} ({commit})"


def measure(side, ordering, factorisation):
    binary = os.path.join(ROOT, "target", "release", "examples", "lu_ordering")
    command = ["/usr/bin/time", "-f", "PEAK %M", binary, str(side), ordering, factorisation]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    peak_kib = next(int(l.split()[1]) for l in done.stderr.splitlines() if l.startswith("PEAK"))
    row = done.stdout.strip().split(",")
    return row + [peak_kib / 2**20]


def earlier_rows(path):
    """The rows of an earlier results CSV by (grid, ordering, factorisation), and its header."""
    if path is None:
        return {}, None
    with open(path) as handle:
        header = handle.readline().lstrip("# ").strip()
        reader = csv.reader(handle)
        next(reader)
        return {tuple(row[0:1] + row[3:5]): row for row in reader}, header


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sides", type=int, nargs="+", default=[128, 288])
    parser.add_argument("--reuse", help="an earlier results CSV to copy rows from")
    parser.add_argument("--reuse-candidates", nargs="+", default=[],
                        help="ORDERING:FACTORISATION pairs copied from --reuse")
    parser.add_argument("--reuse-sides", type=int, nargs="+", default=[],
                        help="the sides at which --reuse-candidates are copied")
    args = parser.parse_args()
    reusable, reused_from = earlier_rows(args.reuse)
    reused = {tuple(pair.split(":")) for pair in args.reuse_candidates}
    subprocess.run(["cargo", "build", "--release", "--example", "lu_ordering"], cwd=ROOT, check=True)
    rows, copied = [], []
    for side in args.sides:
        for ordering, factorisation in CANDIDATES if side <= 128 else LARGE_CANDIDATES:
            key = (f"{side}x{side}", ordering, factorisation)
            if side in args.reuse_sides and (ordering, factorisation) in reused:
                row = reusable[key]
                copied.append(":".join(key))
            else:
                row = measure(side, ordering, factorisation)
            print(",".join(str(v) for v in row), flush=True)
            rows.append(row)
    path = os.path.join(ROOT, "results", "lu-ordering.csv")
    with open(path, "w", newline="") as out:
        out.write(f"# python3 {' '.join(sys.argv)}; "
                  f"{version()}; '!unsafe U goal', --defender uniform:2 --adversary uniform:2; "
                  "one run per row; fill = nnz(L)+nnz(U) for simplicial, sum of the A^T A "
                  "Cholesky column counts for supernodal and faer, stored entries (dense supernode "
                  "blocks whole) for multifrontal; multifrontal is posg-fsc's LuSolver with the "
                  "ordering it picks (auto)"
                  + (f"; rows {' '.join(copied)} copied from {args.reuse} ({reused_from})"
                     if copied else "") + "\n")
        writer = csv.writer(out)
        writer.writerow(HEADER)
        writer.writerows(rows)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
