#!/usr/bin/env python3
"""The cost model of `--solver auto`: sparse LU against BiCGSTAB + ILU(0).

Question (issue 15): how many BiCGSTAB iterations does one LU cost on the
grid family, and does `auto` (a 15-iteration trial predicts the iterations
of a whole solve, compared with that LU cost) stay close to the better of
the two? For each grid it runs `eval` (2-node uniform controllers for both
players, `!unsafe U goal`, value only and with `--gradient`) with `--solver
lu`, `--solver krylov` and `--solver auto --lu-limit 0` (the trial decides
at every size), one process each, and records the phases `eval` reports.
The LU's cost is its symbolic analysis (the difference of
`build_and_analyse` between LU and BiCGSTAB) plus its factorise-and-solve
phase; a BiCGSTAB iteration costs the krylov phase divided by its
iterations (which leave out the few of the error bound's solve). Writes
results/solver-choice.csv (the command, version and settings in the header).

Usage: python3 experiments/solver-choice/run.py [--sizes 64 96 128 192]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
FORMULA = "!unsafe U goal"
CONTROLLERS = ["--defender", "uniform:2", "--adversary", "uniform:2"]
SOLVERS = {"lu": ["--solver", "lu"], "krylov": ["--solver", "krylov"],
           "auto": ["--solver", "auto", "--lu-limit", "0"]}


def evaluate(binary, game, options):
    done = subprocess.run([binary, "eval", game, "--ltl", FORMULA, *CONTROLLERS, *options],
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


def solve_seconds(report):
    phases = report["phase_seconds"]
    return phases.get("factorise_and_solve", phases.get("value_and_gradient"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "posg-fsc"))
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 96, 128, 192])
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "solver-choice.csv"))
    args = parser.parse_args()
    if args.binary == os.path.join(ROOT, "target", "release", "posg-fsc"):
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    version = subprocess.run([args.binary, "--version"], capture_output=True, text=True,
                             check=True).stdout.strip()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes:
            game = os.path.join(tmp, f"grid{size}.posg.json")
            subprocess.run([args.binary, "example", "grid", "--width", str(size), "--height",
                            str(size), "--unsafe", f"s{size + 1}", "--goal",
                            f"s{size * size - 1}", "--out", game], check=True)
            for gradient in (False, True):
                extra = ["--gradient"] if gradient else []
                reports = {name: evaluate(args.binary, game, options + extra)
                           for name, options in SOLVERS.items()}
                lu, krylov, auto = reports["lu"], reports["krylov"], reports["auto"]
                symbolic = max(0.0, lu["phase_seconds"]["build_and_analyse"]
                               - krylov["phase_seconds"]["build_and_analyse"])
                lu_seconds = symbolic + solve_seconds(lu)
                per_iteration = solve_seconds(krylov) / max(1, krylov["solver_iterations"])
                auto_seconds = (auto["phase_seconds"]["build_and_analyse"]
                                - krylov["phase_seconds"]["build_and_analyse"] + solve_seconds(auto))
                rows.append({
                    "grid": f"{size}x{size}", "gradient": gradient,
                    "unknowns": lu["transient_states"], "value_lu": lu["value"],
                    "value_auto": auto["value"], "lu_seconds": lu_seconds,
                    "krylov_seconds": solve_seconds(krylov),
                    "krylov_iterations": krylov["solver_iterations"],
                    "krylov_seconds_per_iteration": per_iteration,
                    "lu_cost_in_iterations": lu_seconds / per_iteration,
                    "auto_method": auto["solver"], "auto_seconds": auto_seconds,
                    "auto_over_best": auto_seconds / min(lu_seconds, solve_seconds(krylov)),
                    "auto_reason": auto["solver_reason"],
                })
                print({k: rows[-1][k] for k in ("grid", "gradient", "lu_seconds", "krylov_seconds",
                                                "lu_cost_in_iterations", "auto_method",
                                                "auto_over_best")}, flush=True)
    with open(args.out, "w", newline="") as handle:
        handle.write(f"# {' '.join(sys.argv)}; {version}; formula '{FORMULA}', "
                     f"{' '.join(CONTROLLERS)}; one process per cell, machine shared; auto runs "
                     f"with --lu-limit 0 so that its trial decides\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
