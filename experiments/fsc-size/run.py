#!/usr/bin/env python3
"""FSC-size comparison: `posg-fsc sweep` over defender sizes 1..6 and
adversary sizes 1..3 on the paper's 3x2 grid, objective `!unsafe U goal`.

Question: how does the worst-case estimate change with the defender's and the
adversary's number of nodes? Writes results/fsc-size/sweep.csv and sweep.svg.

Usage: python3 experiments/fsc-size/run.py [--iterations 200]
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
import games  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=200)
    args = parser.parse_args()
    games.build()
    results = os.path.join(games.ROOT, "results", "fsc-size")
    os.makedirs(results, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        game = os.path.join(tmp, "grid-3x2.posg.json")
        games.grid(game, 3, 2, unsafe=[4], goal=[5])
        out = os.path.join(tmp, "sweep")
        subprocess.run([games.BINARY, "sweep", game, "--ltl", "!unsafe U goal", "--def-nodes", "1..6",
                        "--adv-nodes", "1..3", "--out", out, "--seed", "1",
                        "--max-iterations", str(args.iterations), "--check-every", "10", "--restarts", "2"],
                       check=True)
        for name in ("sweep.csv", "sweep.svg"):
            shutil.copy(os.path.join(out, name), os.path.join(results, name))


if __name__ == "__main__":
    main()
