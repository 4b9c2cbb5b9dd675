#!/usr/bin/env python3
"""Independent check of `posg-fsc eval` with Storm (stormpy).

Question: does the value posg-fsc computes on the GMC equal what Storm's
LTL model checker computes on the exported Markov chain on (s, g, h)?
For several grids, formulas and controller pairs it runs `eval`, exports the
chain with `export-gmc`, and checks `P=? [ X phi ]` in the fresh initial
state of `chain.drn`, read by Storm as it is, with the recipe of docs/guide.md
(`recipe.py`: sound mode, Eigen's sparse LU); writes results/storm-check.csv.

Usage: pip install stormpy; python3 experiments/storm-check/run.py [--binary PATH]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

import stormpy

from recipe import storm_value

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

GRIDS = {
    "paper 3x2": [],
    "paper 3x2 blind": ["--observation", "blind"],
    "5x4, a=s3,s12": ["--width", "5", "--height", "4", "--unsafe", "s6,s13", "--goal", "s19",
                      "--label", "a=s3,s12"],
}
# (posg-fsc formula, the same formula in Storm's syntax: ! & | X F G U only)
FORMULAS = [
    ("!unsafe U goal", '!"unsafe" U "goal"'),
    ("F goal", 'F "goal"'),
    ("GF goal & G !unsafe", 'G F "goal" & G !"unsafe"'),
    ("F goal & G !unsafe", 'F "goal" & G !"unsafe"'),
    ("GF goal", 'G F "goal"'),
    ("FG !unsafe", 'F G !"unsafe"'),
    ("(GF a -> GF goal) & G !unsafe", '(!(G F "a") | G F "goal") & G !"unsafe"'),
    ("G(a -> X !unsafe) | F goal", 'G (!"a" | X !"unsafe") | F "goal"'),
]
PROPOSITIONS = ["unsafe", "goal", "a"]
CONTROLLERS = [("uniform:1", "uniform:1"), ("uniform:2", "uniform:1"), ("uniform:2", "uniform:2"),
               ("uniform:3", "uniform:2")]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "posg-fsc"))
    args = parser.parse_args()
    if not os.path.exists(args.binary):
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    rows = []
    worst = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for grid, options in GRIDS.items():
            game = os.path.join(tmp, "game.posg.json")
            subprocess.run([args.binary, "example", "grid", *options, "--out", game], check=True)
            with open(game) as handle:
                labels = {p for props in json.load(handle).get("labels", {}).values() for p in props}
            for defender, adversary in CONTROLLERS:
                chain = os.path.join(tmp, "chain")
                subprocess.run([args.binary, "export-gmc", game, "--defender", defender, "--adversary", adversary,
                                "--out", chain], check=True, capture_output=True)
                for formula, storm_text in FORMULAS:
                    if not all(f'"{p}"' not in storm_text or p in labels for p in PROPOSITIONS):
                        continue  # Storm refuses a label the model does not have
                    done = subprocess.run([args.binary, "eval", game, "--ltl", formula, "--defender", defender,
                                           "--adversary", adversary], check=True, capture_output=True, text=True)
                    ours = json.loads(done.stdout)["value"]
                    storm = storm_value(os.path.join(chain, "chain.drn"), storm_text)
                    worst = max(worst, abs(ours - storm))
                    rows.append({"grid": grid, "defender": defender, "adversary": adversary, "formula": formula,
                                 "posg_fsc": ours, "storm": storm, "difference": abs(ours - storm)})
    out = os.path.join(ROOT, "results", "storm-check.csv")
    with open(out, "w", newline="") as handle:
        handle.write(f"# {' '.join(sys.argv)}; stormpy {stormpy.__version__}\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"{len(rows)} checks, largest |posg-fsc - Storm| = {worst:.3e}; wrote {out}")
    sys.exit(0 if worst < 1e-6 else 1)


if __name__ == "__main__":
    main()
