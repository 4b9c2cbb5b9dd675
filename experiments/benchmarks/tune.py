"""The measurement behind the optimiser's defaults (issue 12): `posg-fsc
solve` (seed 1) on the benchmark set of run.py under a grid of settings.

* POMDPs (grid4..grid10, maze; k = 1, 2, 3): --logit-bound x --starts;
* fully observable concurrent games and the two matrix games (1 + 1
  nodes): --stall-checks x --starts.

Writes results/benchmarks-tuning.csv: one row per setting and game with
the certified lower bound, its shortfall from the reference where known,
CPU seconds, iterations, status and the largest linear-solve residual.

    python3 experiments/benchmarks/tune.py
"""
import csv
import itertools
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
sys.path.insert(0, HERE)
from common.games import ROOT, build  # noqa: E402
from run import game_set, solve  # noqa: E402


def main():
    build()
    rows = []
    with tempfile.TemporaryDirectory() as directory:
        entries = game_set(directory, quick=False)
        pomdps = [e for e in entries if e[0].startswith(("grid", "maze"))]
        games = [e for e in entries if e[0].startswith(("concurrent", "matching", "matrix"))]
        grids = [(pomdps, "logit-bound", [6, 8, 10, 14]), (games, "stall-checks", [25, 50, 100, 200])]
        for subset, option, values in grids:
            for value, starts in itertools.product(values, [1, 2, 4]):
                for name, path, k, m, reference, _, formula in subset:
                    out = os.path.join(directory, f"{name}-{k}-{option}-{value}-{starts}")
                    extra = [f"--{option}", str(value), "--starts", str(starts)]
                    result = solve(path, out, k, m, extra, formula)
                    lower = result["certified_lower"]
                    rows.append({"game": name, "defender_nodes": k, "option": option, "value": value,
                                 "starts": starts, "certified_lower": lower,
                                 "shortfall": None if reference is None else reference - lower,
                                 "cpu_seconds": result["cpu_seconds"],
                                 "iterations": result["iterations"], "status": result["status"],
                                 "max_residual": result["max_residual"]})
                    print(rows[-1], flush=True)
    with open(os.path.join(ROOT, "results", "benchmarks-tuning.csv"), "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
