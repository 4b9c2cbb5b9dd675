#!/usr/bin/env python3
"""posg-fsc against PAYNT on PAYNT's expected-reward POMDPs.

Question: on the reward POMDPs of PAYNT's repository (SAYNT's benchmarks,
archive/cav23-saynt: `R{"r"}max=? [F "discount_sink"]` with the discount
as a sink, and `R{"r"}min=? [F "goal"]` costs), does `posg-fsc solve` with
its default settings and k = 1, 2, 3 controller nodes reach the value of
PAYNT 0.5's FSC synthesis, with how much CPU, and is the value it prints
the value of the controller it returns?

For each model and k, one tool at a time:

* posg-fsc: `posg-fsc solve model.drn --props sketch.props --def-nodes K
  --out DIR --quiet` (docs/method.md section 9); its value is summary.json's
  `value`, the returned defender's expected reward evaluated exactly, and
  `mdp_bound` its certificate's `best_possible`: what no controller of any
  memory beats, from the defender that sees the state;
* Storm (stormpy 2.0) re-evaluates that defender: `posg-fsc export-gmc
  model.drn --defender DIR/defender.fsc.json` writes the chain with the
  one-step rewards, and Storm checks `R{"r"}=? [F T]` in its fresh initial
  state (sound mode, Eigen's sparse LU);
* PAYNT 0.5.0: `python -m paynt DIR --sketch sketch.templ --props
  sketch.props --fsc-memory-size K --timeout T`; its value is the optimum
  it reports (the best found when the timeout stops it). PAYNT synthesises
  deterministic FSCs; posg-fsc's are randomised, which a POMDP can reward
  even without memory.

`better` compares the two values in the query's direction (posg-fsc's
minus PAYNT's for Rmax, the reverse for Rmin), relative to PAYNT's
magnitude. CPU is the process's (user + system), start-up and parsing
included for both tools.

The models are split in two halves: `tune` (the set future tuning may
use) and `check` (held out). No setting of posg-fsc was tuned on either
half for this table (the reward optimiser is the single-player ascent with
the defaults of the probability objectives); both halves are reported.

Models in PRISM (not DRN) are built with stormpy and exported as DRN with
their reward models, choice labels and labels; a PRISM formula used as a
target (`F goal`) is added as a label of the same name.

Usage: pip install stormpy==2.0.0 paynt==0.5.0;
python3 experiments/rewards/run.py --repo PATH/TO/synthesis/.git [--timeout 60]
Writes results/rewards.csv and results/rewards.png.
"""
import argparse
import csv
import json
import os
import re
import resource
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BINARY = os.path.join(ROOT, "target", "release", "posg-fsc")
SAYNT = "models/archive/cav23-saynt"
# name -> (half, label to add for a PRISM formula target, or None)
MODELS = {
    "4x3-95": ("tune", None),
    "mini-hall2": ("tune", None),
    "network": ("tune", None),
    "query-s2": ("tune", None),
    "web-mall": ("tune", None),
    "grid-large-10-5": ("tune", None),
    "4x5x2-95": ("check", None),
    "hallway": ("check", None),
    "milos-aaai97": ("check", None),
    "query-s3": ("check", None),
    "stand-tiger-95": ("check", None),
    "rocks-12": ("check", None),
    "maze-alex": ("check", "goal"),
}


def set_binary(path):
    global BINARY
    BINARY = os.path.abspath(path)


def git_show(repo, path):
    return subprocess.run(["git", "--git-dir", repo, "show", f"HEAD:{path}"], check=True,
                          capture_output=True, text=True).stdout


def is_drn(text):
    lines = (line.strip() for line in text.splitlines())
    return next((line for line in lines if line and not line.startswith("//")), "").startswith("@")


def prepare(repo, work, name, label):
    """DIR/NAME with sketch.templ, sketch.props and model.drn; the query."""
    directory = os.path.join(work, name)
    os.makedirs(directory, exist_ok=True)
    model = git_show(repo, f"{SAYNT}/{name}/sketch.templ")
    props = next(line for line in git_show(repo, f"{SAYNT}/{name}/sketch.props").splitlines()
                 if line.strip() and not line.startswith("//")).strip()
    if label:
        model += f'\n// added by experiments/rewards/run.py\nlabel "{label}" = {label};\n'
        props = props.replace(f"F {label}", f'F "{label}"')
    with open(os.path.join(directory, "sketch.templ"), "w") as handle:
        handle.write(model)
    with open(os.path.join(directory, "sketch.props"), "w") as handle:
        handle.write(props + "\n")
    drn = os.path.join(directory, "model.drn")
    if is_drn(model):
        with open(drn, "w") as handle:
            handle.write(model)
    elif not os.path.exists(drn):
        import stormpy
        program = stormpy.parse_prism_program(os.path.join(directory, "sketch.templ"))
        options = stormpy.BuilderOptions(build_full=True)
        options.set_build_choice_labels(True)
        options.set_build_all_labels()
        options.set_build_all_reward_models(True)
        stormpy.io.export_to_drn(stormpy.build_model(program, options=options), drn)
    return directory, props


def timed(command, limit):
    """Runs `command`; (output or None when killed at `limit`, exit code, wall s, CPU s)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=limit)
        output, code = done.stdout + done.stderr, done.returncode
    except subprocess.TimeoutExpired:
        output, code = None, None
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return output, code, time.monotonic() - start, cpu


def run_posg(directory, k, limit):
    out = os.path.join(directory, f"posg-fsc-{k}")
    command = [BINARY, "solve", os.path.join(directory, "model.drn"), "--props",
               os.path.join(directory, "sketch.props"), "--def-nodes", str(k), "--out", out,
               "--force", "--quiet"]
    log, code, wall, cpu = timed(command, limit)
    if log is None or code != 0:
        return {"status": "timeout" if log is None else "error: " + log.strip()[-300:],
                "wall_seconds": wall, "cpu_seconds": cpu}
    with open(os.path.join(out, "summary.json")) as handle:
        summary = json.load(handle)
    bound = (summary.get("certificate") or {}).get("best_possible")
    return {"status": "ok", "value": float(summary["value"]), "error_bound": summary["error_bound"],
            "bound": None if bound is None else float(bound),
            "wall_seconds": wall, "cpu_seconds": cpu, "out": out}


def storm_value(directory, out, props):
    """Storm's value of posg-fsc's returned defender on the exported chain."""
    import stormpy
    import stormpy.developer
    chain = os.path.join(out, "chain")
    subprocess.run([BINARY, "export-gmc", os.path.join(directory, "model.drn"), "--defender",
                    os.path.join(out, "defender.fsc.json"), "--out", chain, "--force"],
                   check=True, capture_output=True)
    query = re.sub(r"^R(\{[^}]*\})?(min|max)=\?", lambda m: f"R{m.group(1) or ''}=?", props)
    model = stormpy.build_model_from_drn(os.path.join(chain, "chain.drn"))
    prop = stormpy.parse_properties(query.rstrip(";"))[0]
    env = stormpy.Environment()
    env.solver().force_soundness = True
    env.solver().set_linear_equation_solver_type(stormpy.developer.EquationSolverType.EIGEN)
    return float(stormpy.model_checking(model, prop, environment=env).get_value(model.initial_states[0]))


def run_paynt(directory, k, timeout):
    command = [sys.executable, "-m", "paynt", directory, "--sketch", "sketch.templ", "--props",
               "sketch.props", "--fsc-memory-size", str(k), "--timeout", str(timeout)]
    log, code, wall, cpu = timed(command, timeout + 120)
    log = log or ""
    optimum = re.search(r"^optimum: (\S+)", log, re.M)
    explored = re.search(r"^explored: (\d+) %", log, re.M)
    finished = explored is not None and explored.group(1) == "100"
    status = ("optimal" if finished and optimum else
              "timeout" if "time limit reached" in log or code is None else
              "no value" if finished else "error")
    return {"status": status, "value": float(optimum.group(1)) if optimum else None,
            "wall_seconds": wall, "cpu_seconds": cpu}


def paynt_rows(path):
    """PAYNT's results of an earlier run of this script, by (model, k)."""
    with open(path) as handle:
        rows = csv.DictReader(line for line in handle if not line.startswith("#"))
        return {(r["model"], int(r["nodes"])): {
            "status": r["paynt_status"], "value": float(r["paynt"]) if r["paynt"] else None,
            "wall_seconds": None, "cpu_seconds": float(r["paynt_cpu"])} for r in rows}


def better(posg, paynt, maximise):
    """How much posg-fsc's value beats PAYNT's, in the query's direction,
    relative to PAYNT's magnitude (negative: PAYNT is better)."""
    if posg is None or paynt is None:
        return None
    gain = posg - paynt if maximise else paynt - posg
    return gain / max(abs(paynt), 1e-9)


def version():
    done = subprocess.run([BINARY, "--version"], capture_output=True, text=True)
    return done.stdout.strip()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", required=True, help="the git directory of randriu/synthesis")
    parser.add_argument("--work", default="/tmp/posg-fsc-rewards")
    parser.add_argument("--timeout", type=int, default=60, help="PAYNT's --timeout, seconds")
    parser.add_argument("--posg-limit", type=int, default=300, help="posg-fsc's limit, seconds")
    parser.add_argument("--nodes", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "rewards.csv"))
    parser.add_argument("--binary", default=BINARY, help="the posg-fsc binary (default: the build's)")
    parser.add_argument("--paynt-from", help="reuse PAYNT's rows (value, status, CPU) of an earlier CSV")
    parser.add_argument("--plot-from", help="only draw the plot of this CSV (next to it, as .png)")
    args = parser.parse_args()
    if args.plot_from:
        with open(args.plot_from) as handle:
            rows = list(csv.DictReader(line for line in handle if not line.startswith("#")))
        plot(rows, args.plot_from.replace(".csv", ".png"))
        return
    set_binary(args.binary)
    if not os.path.exists(BINARY):
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    earlier = paynt_rows(args.paynt_from) if args.paynt_from else {}
    rows = []
    for name, (half, label) in MODELS.items():
        directory, props = prepare(args.repo, args.work, name, label)
        maximise = "max=?" in props
        for k in args.nodes:
            posg = run_posg(directory, k, args.posg_limit)
            storm = storm_value(directory, posg["out"], props) if posg["status"] == "ok" else None
            paynt = earlier.get((name, k)) or run_paynt(directory, k, args.timeout)
            row = {
                "model": name, "half": half, "query": props, "nodes": k,
                "posg_fsc": posg.get("value"), "posg_fsc_error_bound": posg.get("error_bound"),
                "mdp_bound": posg.get("bound"),
                "storm_on_posg_fsc_controller": storm,
                "storm_difference": None if storm is None else abs(storm - posg["value"]),
                "paynt": paynt["value"], "paynt_status": paynt["status"],
                "posg_fsc_better_relative": better(posg.get("value"), paynt["value"], maximise),
                "posg_fsc_cpu": round(posg["cpu_seconds"], 3), "paynt_cpu": round(paynt["cpu_seconds"], 3),
                "posg_fsc_status": posg["status"],
            }
            rows.append(row)
            print(json.dumps(row), flush=True)
    with open(args.out, "w", newline="") as handle:
        handle.write(f"# {' '.join(sys.argv)}; {version()}; paynt 0.5.0, stormpy 2.0.0\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, args.out.replace(".csv", ".png"))


def number(text):
    """A CSV cell (or a row's value) as a float; None where it is empty."""
    return None if text in (None, "") else float(text)


def plot(rows, path):
    """posg-fsc's gain over PAYNT (relative, in the query's direction) and
    the CPU ratio, per model and k, tune and check halves side by side."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = sorted(rows, key=lambda r: (r["half"] != "tune", r["model"], r["nodes"]))
    labels = [f"{r['model']} k={r['nodes']}" for r in rows]
    colours = ["tab:blue" if r["half"] == "tune" else "tab:orange" for r in rows]
    figure, (gain, cpu) = plt.subplots(2, 1, figsize=(12, 7), sharex=True)
    gains = [number(r["posg_fsc_better_relative"]) for r in rows]
    gain.bar(range(len(rows)), [0 if g is None else g for g in gains], color=colours)
    for i, g in enumerate(gains):
        if g is None:
            gain.text(i, 0.05, "no PAYNT value", rotation=90, ha="center", va="bottom", fontsize=7)
    gain.axhline(0, color="black", linewidth=0.8)
    gain.axhline(-1e-3, color="grey", linewidth=0.8, linestyle="--")
    gain.set_ylabel("posg-fsc better than PAYNT\n(relative, query's direction)")
    gain.set_title("Expected-reward POMDPs of PAYNT's repository: blue = tune half, orange = check half")
    ratios = [number(r["posg_fsc_cpu"]) / max(number(r["paynt_cpu"]), 1e-3) for r in rows]
    cpu.bar(range(len(rows)), ratios, color=colours)
    cpu.set_yscale("log")
    cpu.axhline(1, color="black", linewidth=0.8)
    cpu.set_ylabel("CPU posg-fsc / PAYNT")
    cpu.set_xticks(range(len(rows)))
    cpu.set_xticklabels(labels, rotation=70, ha="right", fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
