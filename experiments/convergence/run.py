#!/usr/bin/env python3
"""Convergence of the max-min optimiser on an 8x8 grid of the paper's family
(start s0, goal s63, `a` on s7, `b` on s56, 4 unsafe cells chosen with seed 3),
2-node defender, 1-node adversary, full support structure, seed 1.

Question: how do the value of the iterates and the best-response (worst-case)
estimate evolve for `F goal & G !unsafe`, `GF goal & G !unsafe`,
`GF a & GF b & G !unsafe`, and for the reach-avoid objectives
`!unsafe U goal` and `!unsafe U (a & (!unsafe U b))`? Writes
results/convergence/<objective>.csv and .svg, and results/convergence/summary.csv.

Usage: python3 experiments/convergence/run.py [--iterations 300]
"""
import argparse
import csv
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import games  # noqa: E402

OBJECTIVES = {
    "f-goal-g-safe": "F goal & G !unsafe",
    "gf-goal-g-safe": "GF goal & G !unsafe",
    "gf-a-gf-b-g-safe": "GF a & GF b & G !unsafe",
    "safe-until-goal": "!unsafe U goal",
    "safe-until-a-then-b": "!unsafe U (a & (!unsafe U b))",
}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=300)
    args = parser.parse_args()
    games.build()
    results = os.path.join(games.ROOT, "results", "convergence")
    os.makedirs(results, exist_ok=True)
    unsafe = games.unsafe_cells(8, 8, 4, seed=3, keep={0, 7, 56, 63})
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        game = os.path.join(tmp, "grid-8x8.posg.json")
        games.grid(game, 8, 8, unsafe=unsafe, goal=[63], labels={"a": [7], "b": [56]})
        for slug, formula in OBJECTIVES.items():
            out = os.path.join(tmp, slug)
            summary = games.solve(game, formula, out, 2, 1, "--seed", 1,
                                  "--max-iterations", args.iterations, "--check-every", 10, "--restarts", 2)
            for ext in ("csv", "svg"):
                shutil.copy(os.path.join(out, f"curve.{ext}"), os.path.join(results, f"{slug}.{ext}"))
            rows.append({"objective": formula, "unsafe_cells": " ".join(f"s{c}" for c in unsafe),
                         "gmc_states": summary["structures"][0]["gmc"]["states"],
                         "worst_case": summary["worst_case"], "last_value": summary["last_value"],
                         "seconds": summary["seconds"]})
            print(f"{formula}: worst-case estimate {summary['worst_case']:.6f} in {summary['seconds']:.1f} s")
    with open(os.path.join(results, "summary.csv"), "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
