"""Sweeps the defender's controller size on a grid of the paper's family and
compares the certified bounds: for each size, the value the defender is
guaranteed against every adversary (certified lower bound) and the bound no
defender of any size can beat (game upper bound).

Writes compare_sizes.csv always, and compare_sizes.png when matplotlib is
installed. Usage:

    python examples/python/compare_sizes.py [--width 3 --height 2]
        [--observation blind] [--def-nodes 1 2 3] [--adv-nodes 1]
        [--max-iterations 300] [--out DIR]

With the paper's literal observation model (`blind`: only "correct" or
"wrong"), memory pays: on the 3x2 grid the certified lower bound grows with
the defender's size (it never falls: each size is warm-started from the
smaller one), below the game upper bound.
"""

import argparse
import csv
import sys
from pathlib import Path

import posg_fsc

COLUMNS = [
    "defender_nodes", "adversary_nodes", "certified_lower", "upper_bound",
    "worst_case", "structure", "gmc_states", "iterations", "seconds",
]


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--width", type=int, default=3)
    parser.add_argument("--height", type=int, default=2)
    parser.add_argument("--ltl", default="!unsafe U goal")
    parser.add_argument("--observation", choices=["blind", "neighbourhood"], default="blind")
    parser.add_argument("--def-nodes", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--adv-nodes", type=int, default=1)
    parser.add_argument("--max-iterations", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("."))
    return parser.parse_args()


def main():
    args = arguments()
    cells = args.width * args.height
    # The paper's layout: an unsafe cell next to the start, the goal in the far corner.
    game = posg_fsc.example_grid(
        width=args.width,
        height=args.height,
        unsafe=[min(args.width + 1, cells - 2)],
        goal=[cells - 1],
        observation=args.observation,
    )
    rows = posg_fsc.sweep(
        game, args.ltl, def_nodes=args.def_nodes, adv_nodes=args.adv_nodes,
        max_iterations=args.max_iterations, seed=args.seed, starts=1,
    )
    args.out.mkdir(parents=True, exist_ok=True)
    table = args.out / "compare_sizes.csv"
    with table.open("w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=COLUMNS, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {table}")
    for row in rows:
        print(
            f"defender {row['defender_nodes']} nodes: certified lower bound "
            f"{row['certified_lower']:.6f}, game upper bound {row['upper_bound']:.6f}"
        )
    plot(rows, args, game)


def plot(rows, args, game):
    """compare_sizes.png: both bounds against the defender's size."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)", file=sys.stderr)
        return
    sizes = [row["defender_nodes"] for row in rows]
    figure, axes = plt.subplots(figsize=(6, 4))
    axes.plot(sizes, [row["certified_lower"] for row in rows], "o-", label="certified lower bound")
    axes.plot(sizes, [row["upper_bound"] for row in rows], "s--", label="game upper bound")
    axes.set_xlabel("defender controller size (nodes)")
    axes.set_ylabel(f"P({args.ltl})")
    axes.set_xticks(sizes)
    axes.set_ylim(0, 1.02)
    axes.set_title(f"{game.name}, {args.observation} observations: adversary {args.adv_nodes} node(s)")
    axes.grid(alpha=0.3)
    axes.legend(loc="lower right")
    figure.tight_layout()
    path = args.out / "compare_sizes.png"
    figure.savefig(path, dpi=120)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
