#!/usr/bin/env python3
"""Independent check of `posg-fsc eval` with Storm (stormpy).

Question: does the value posg-fsc computes on the GMC equal what Storm's
LTL model checker computes on the exported Markov chain on (s, g, h)?
For several grids, formulas and controller pairs it runs `eval`, exports the
chain with `export-gmc`, checks `P=? [ X phi ]` in the fresh initial state
with stormpy (Eigen's sparse LU as Storm's linear equation solver), and writes results/storm-check.csv.

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
import stormpy.developer

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

GRIDS = {
    "paper 3x2": [],
    "paper 3x2 blind": ["--observation", "blind"],
    "5x4, a=s3,s12": ["--width", "5", "--height", "4", "--unsafe", "s6,s13", "--goal", "s19",
                      "--label", "a=s3,s12"],
}
PROPOSITIONS = ["unsafe", "goal", "a"]
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
CONTROLLERS = [("uniform:1", "uniform:1"), ("uniform:2", "uniform:1"), ("uniform:2", "uniform:2"),
               ("uniform:3", "uniform:2")]


def to_storm_explicit(chain):
    """Rewrites PRISM's explicit files (count header, `i="name"` labels) in
    Storm's explicit dialect (`dtmc` header, #DECLARATION block)."""
    with open(os.path.join(chain, "chain.tra")) as handle:
        lines = handle.read().splitlines()
    with open(os.path.join(chain, "storm.tra"), "w") as handle:
        handle.write("dtmc\n" + "\n".join(lines[1:]) + "\n")
    with open(os.path.join(chain, "chain.lab")) as handle:
        header, *rows = handle.read().splitlines()
    names = dict(item.split("=") for item in header.split())
    names = {index: name.strip('"') for index, name in names.items()}
    with open(os.path.join(chain, "storm.lab"), "w") as handle:
        declared = list(names.values()) + [p for p in PROPOSITIONS if p not in names.values()]
        handle.write("#DECLARATION\n" + " ".join(declared) + "\n#END\n")
        for row in rows:
            state, ids = row.split(":")
            handle.write(state + " " + " ".join(names[i] for i in ids.split()) + "\n")
    return os.path.join(chain, "storm.tra"), os.path.join(chain, "storm.lab")


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
            for defender, adversary in CONTROLLERS:
                chain = os.path.join(tmp, "chain")
                subprocess.run([args.binary, "export-gmc", game, "--defender", defender, "--adversary", adversary,
                                "--out", chain], check=True, capture_output=True)
                model = stormpy.build_model_from_explicit(*to_storm_explicit(chain))
                for formula, storm_text in FORMULAS:
                    done = subprocess.run([args.binary, "eval", game, "--ltl", formula, "--defender", defender,
                                           "--adversary", adversary], check=True, capture_output=True, text=True)
                    ours = json.loads(done.stdout)["value"]
                    prop = stormpy.parse_properties(f"P=? [ X ({storm_text}) ]")[0]
                    env = stormpy.Environment()
                    env.solver().set_linear_equation_solver_type(stormpy.developer.EquationSolverType.EIGEN)
                    result = stormpy.model_checking(model, prop, environment=env)
                    storm = result.get_value(model.initial_states[0])
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
