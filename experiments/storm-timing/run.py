#!/usr/bin/env python3
"""CPU time of `posg-fsc eval` (whole process) against Storm's model checking
alone of the chain that `posg-fsc export-gmc` writes.

Question (issue 15): at about 10^5 GMC states, is `eval` at least 5x cheaper
in CPU than Storm 2.0's LTL model checking (Spot, product, BSCCs, Eigen's
sparse LU in sound mode: experiments/storm-check/recipe.py) of the same
chain? Both compute the same value (checked to 1e-8).

For each grid size it writes the paper's grid family (`example grid`,
unsafe cell (1, 1), goal in the far corner) in the fastest form the tool
reads (`--form binary`, the default: `example grid --binary`, the
`*.posg.bin` of docs/formats.md section 11; `--form json` for the
pretty-printed JSON), runs `eval` with 2-node uniform
controllers for both players (`!unsafe U goal`) `--repeats` times under
`/usr/bin/time` (user + system CPU of the process, wall, peak RSS), and
as often with one worker thread (`RAYON_NUM_THREADS=1`: Storm's check runs
on one thread, and on a loaded 2-core machine eval's parallel parts cost
CPU without saving wall time), exports
the chain once, and runs Storm's check `--repeats` times, each in a fresh
Python process that reads the DRN file first (not timed) and then times
`model_checking` alone with `time.process_time` (CPU of that process, all
threads). Each repeat runs `eval`, `eval` on one thread and Storm's check
one after the other, so that the load of the shared machine affects all
three alike; a ratio is the median over the repeats of the ratio within
each repeat. Writes results/storm-timing.csv (medians per size, the
command, the posg-fsc version and the Storm settings in the header) and
prints the ratios eval CPU / Storm CPU, with the default threads and with
one.

`gmc_states` counts the states eval explores: it stops at decided states
(docs/method.md section 1); Storm builds the whole product of the chain
with its automaton.

Usage: pip install stormpy; python3 experiments/storm-timing/run.py [--sizes 96] [--repeats 3]
       [--form binary|json]
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
FORMULA = "!unsafe U goal"
STORM_FORMULA = '!"unsafe" U "goal"'
CONTROLLERS = ["--defender", "uniform:2", "--adversary", "uniform:2"]
STORM_SETTINGS = "force_soundness=True, EquationSolverType.EIGEN (sparse LU), P=? [ X phi ] in state 0"

# Run in a child process: reading the DRN file is not timed, model checking is.
STORM_CHILD = r"""
import json, sys, time
import stormpy, stormpy.developer
model = stormpy.build_model_from_drn(sys.argv[1])
prop = stormpy.parse_properties(f"P=? [ X ({sys.argv[2]}) ]")[0]
env = stormpy.Environment()
env.solver().force_soundness = True
env.solver().set_linear_equation_solver_type(stormpy.developer.EquationSolverType.EIGEN)
cpu, wall = time.process_time(), time.perf_counter()
result = stormpy.model_checking(model, prop, environment=env)
cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
print(json.dumps({"value": result.get_value(model.initial_states[0]), "cpu": cpu, "wall": wall,
                  "states": model.nr_states}))
"""


def run_timed(command, env=None):
    """Runs `command` under /usr/bin/time; returns (stdout, cpu s, wall s, peak GiB)."""
    timed = ["/usr/bin/time", "-f", "TIMING %U %S %e %M", *command]
    done = subprocess.run(timed, capture_output=True, text=True, check=True, env=env)
    line = next(l for l in done.stderr.splitlines() if l.startswith("TIMING"))
    user, system, wall, peak_kib = map(float, line.split()[1:])
    return done.stdout, user + system, wall, peak_kib / 1024 / 1024


# The game file's form: (`example grid` options, file extension).
FORMS = {"binary": (["--binary"], "posg.bin"), "json": ([], "posg.json")}


def make_grid(binary, size, path, form):
    subprocess.run([binary, "example", "grid", "--width", str(size), "--height", str(size),
                    "--unsafe", f"s{size + 1}", "--goal", f"s{size * size - 1}", *FORMS[form][0],
                    "--out", path],
                   check=True)


def measure(binary, size, repeats, tmp, form):
    game = os.path.join(tmp, f"grid{size}.{FORMS[form][1]}")
    make_grid(binary, size, game, form)
    command = [binary, "eval", game, "--ltl", FORMULA, *CONTROLLERS]
    chain = os.path.join(tmp, f"chain{size}")
    subprocess.run([binary, "export-gmc", game, *CONTROLLERS, "--out", chain, "--force"],
                   check=True, stdout=subprocess.DEVNULL)
    # One repeat runs all three, so that each ratio compares runs made
    # under the same load of this shared machine.
    evals, one_thread, storms = [], [], []
    for _ in range(repeats):
        out, cpu, wall, peak = run_timed(command)
        evals.append((json.loads(out), cpu, wall, peak))
        _, cpu, wall, _ = run_timed(command, env={**os.environ, "RAYON_NUM_THREADS": "1"})
        one_thread.append((cpu, wall))
        done = subprocess.run([sys.executable, "-c", STORM_CHILD, os.path.join(chain, "chain.drn"),
                               STORM_FORMULA], capture_output=True, text=True, check=True)
        storms.append(json.loads(done.stdout.strip().splitlines()[-1]))
    report = evals[0][0]
    storm_value = storms[0]["value"]
    if abs(storm_value - report["value"]) > 1e-8:
        sys.exit(f"{size}x{size}: eval {report['value']} but Storm {storm_value}")
    eval_cpu = statistics.median(e[1] for e in evals)
    eval_cpu_one_thread = statistics.median(e[0] for e in one_thread)
    storm_cpu = statistics.median(s["cpu"] for s in storms)
    phases = {k: statistics.median(e[0]["phase_seconds"][k] for e in evals)
              for k in report["phase_seconds"]}
    return {
        "grid": f"{size}x{size}", "gmc_states": report["gmc_states"],
        "decided_states": report["decided_states"],
        "transient_states": report["transient_states"], "game_mib": os.path.getsize(game) / 2**20,
        "value": report["value"], "storm_value": storm_value, "solver": report["solver"],
        "eval_cpu_s": eval_cpu, "eval_wall_s": statistics.median(e[2] for e in evals),
        "eval_peak_gib": statistics.median(e[3] for e in evals),
        "eval_cpu_one_thread_s": eval_cpu_one_thread,
        "eval_wall_one_thread_s": statistics.median(e[1] for e in one_thread),
        **{f"eval_{k}_s": v for k, v in phases.items()},
        "storm_chain_states": storms[0]["states"], "storm_check_cpu_s": storm_cpu,
        "storm_check_wall_s": statistics.median(s["wall"] for s in storms),
        "ratio_eval_to_storm_cpu": statistics.median(
            e[1] / s["cpu"] for e, s in zip(evals, storms)),
        "ratio_one_thread_eval_to_storm_cpu": statistics.median(
            e[0] / s["cpu"] for e, s in zip(one_thread, storms)),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "posg-fsc"))
    parser.add_argument("--sizes", type=int, nargs="+", default=[96])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--form", choices=sorted(FORMS), default="binary",
                        help="the game file's form (binary: docs/formats.md section 11)")
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "storm-timing.csv"))
    args = parser.parse_args()
    if args.binary == os.path.join(ROOT, "target", "release", "posg-fsc"):
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    version = subprocess.run([args.binary, "--version"], capture_output=True, text=True,
                             check=True).stdout.strip()
    import stormpy
    with tempfile.TemporaryDirectory() as tmp:
        rows = [measure(args.binary, size, args.repeats, tmp, args.form) for size in args.sizes]
    with open(args.out, "w", newline="") as handle:
        handle.write(f"# {' '.join(sys.argv)}; {version}; stormpy {stormpy.__version__}; "
                     f"game form {args.form} (*.{FORMS[args.form][1]}; game_mib is its size); "
                     f"formula '{FORMULA}', {' '.join(CONTROLLERS)}; Storm: {STORM_SETTINGS}; "
                     f"medians of {args.repeats} runs, eval and Storm interleaved; ratios: median of the "
                     f"per-repeat ratios; CPU = user + system\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    for row in rows:
        print(f"{row['grid']}: {row['gmc_states']} GMC states, eval CPU {row['eval_cpu_s']:.2f} s, "
              f"Storm check CPU {row['storm_check_cpu_s']:.2f} s, ratio "
              f"{row['ratio_eval_to_storm_cpu']:.2f} (one thread: eval CPU "
              f"{row['eval_cpu_one_thread_s']:.2f} s, ratio "
              f"{row['ratio_one_thread_eval_to_storm_cpu']:.2f})")


if __name__ == "__main__":
    main()
