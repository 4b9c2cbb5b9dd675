#!/usr/bin/env python3
"""posg-fsc against PAYNT on PAYNT's own partially observable games.

Question: on the turn-based partially observable stochastic games (POSMGs)
of PAYNT's repository (models/posmg/), does posg-fsc's certified lower bound
with k defender nodes reach PAYNT's optimal deterministic k-memory
controller, and how long do both take?

For each model and k = 1, 2, 3 the script runs

* PAYNT 0.5.0: `python -m paynt DIR --sketch sketch.templ --props
  sketch.props --fsc-memory-size K --timeout T` (its value: the optimum it
  reports, or the best found when the timeout stops it);
* posg-fsc: `posg-fsc solve sketch.templ --props sketch.props --def-nodes K
  --seed 1 --quiet` (the DRN read directly, docs/formats.md section 6); its
  value is the certified lower bound of the defender it returns;

and once per model the fully observable game value from Storm (the same
game with both players seeing the state, `<<P>> Pmax=?` checked on the SMG),
an upper bound for both tools. Values are the defender's: for a `Pmin`
property (the defender minimises P(F goal)) PAYNT's and Storm's numbers are
turned into 1 - p, the probability of `G !goal` that posg-fsc maximises.
`winner` compares the two tools' values with a tolerance of 1e-4.

Writes results/paynt-posmg.csv (first line: command, settings, versions).
Raw per-run records are cached in --work (default target/paynt-posmg), so
`--phase paynt` can run first in the background and `--phase posg` later,
after a rebuild; `--phase all` runs what is missing and writes the CSV.

Models: read from a checkout of PAYNT's repository (--repo, a git directory
such as the one `git clone https://github.com/randriu/synthesis` makes) at
the pinned commit, or downloaded from GitHub at that commit.

Usage:
  python3 -m venv venv && venv/bin/pip install paynt==0.5.0 stormpy==2.0.0
  venv/bin/python experiments/paynt-posmg/run.py [--repo DIR] [--timeout 300]
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
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "common"))
from games import BINARY, ROOT, build  # noqa: E402

COMMIT = "8eb05ea143c3d9feb5f2ab219187fcc6c7195dd1"
RAW = "https://raw.githubusercontent.com/randriu/synthesis/{commit}/{path}"
# Every POSMG of models/posmg/ with a probability objective. testing-rewards
# (a reward objective) and multi-dodge4 (PRISM only) are left out.
MODELS = [
    "test-game", "test-game2", "mec-test", "grid-walls", "dice-and-coin", "dice-and-coin2",
    "attacker-one-defender", "attacker-defender", "dodge-6-lines", "dodge-6-lines-position",
    "dodge-8", "pursuit-evasion",
]
# pursuit-evasion comes as a DRN without a property file; the pursuer
# (player 0) maximises the probability of catching the evader, as in the
# PRISM source's `<<1>> Pmax` for the evader's opposite objective.
EXTRA_PROPS = {"pursuit-evasion": '<<0>> Pmax=? [F "goal"]\n'}
NODES = [1, 2, 3]
TOLERANCE = 1e-4


def model_files(name):
    """Repository paths of a model's DRN and property file (None: not in the repository)."""
    if name == "pursuit-evasion":
        return "models/posmg/pursuit-evasion/pursuit-evasion.drn", None
    return f"models/posmg/{name}/sketch.templ", f"models/posmg/{name}/sketch.props"


def fetch(repo, path):
    if repo:
        return subprocess.run(["git", "--git-dir", repo, "show", f"{COMMIT}:{path}"], check=True,
                              capture_output=True, text=True).stdout
    with urllib.request.urlopen(RAW.format(commit=COMMIT, path=path)) as response:
        return response.read().decode()


def prepare(models_dir, repo):
    """Writes each model as DIR/NAME/sketch.templ and sketch.props."""
    for name in MODELS:
        directory = os.path.join(models_dir, name)
        if os.path.exists(os.path.join(directory, "sketch.props")):
            continue
        os.makedirs(directory, exist_ok=True)
        drn, props = model_files(name)
        with open(os.path.join(directory, "sketch.templ"), "w") as handle:
            handle.write(fetch(repo, drn))
        with open(os.path.join(directory, "sketch.props"), "w") as handle:
            handle.write(EXTRA_PROPS[name] if props is None else fetch(repo, props))


def prop_of(directory):
    """(player, 'max' or 'min', the property's text)."""
    text = open(os.path.join(directory, "sketch.props")).read().strip()
    match = re.match(r'<<\s*(\d+)\s*>>\s*P(max|min)=\?', text)
    return int(match.group(1)), match.group(2), text


def timed(command, limit, **kwargs):
    """Runs `command`; returns (completed process or None on the outer
    time limit, wall seconds, CPU seconds of the child and its children)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=limit, **kwargs)
    except subprocess.TimeoutExpired:
        done = None
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return done, wall, cpu


def run_paynt(directory, k, timeout):
    command = [sys.executable, "-m", "paynt", directory, "--sketch", "sketch.templ", "--props",
               "sketch.props", "--fsc-memory-size", str(k), "--timeout", str(timeout)]
    done, wall, cpu = timed(command, timeout + 600)
    log = "" if done is None else done.stdout + done.stderr
    optimum = re.search(r"^optimum: (\S+)", log, re.M)
    explored = re.search(r"^explored: (\d+) %", log, re.M)
    synthesis = re.search(r"synthesis time: ([\d.]+) s", log)
    finished = explored is not None and explored.group(1) == "100"
    return {
        "command": " ".join(["python", "-m", "paynt", *command[3:]]),
        "value": float(optimum.group(1)) if optimum else None,
        "status": "optimal" if finished and optimum else
                  "timeout" if "time limit reached" in log or done is None else
                  "infeasible" if finished else "error",
        "explored_percent": int(explored.group(1)) if explored else None,
        "synthesis_seconds": float(synthesis.group(1)) if synthesis else None,
        "wall_seconds": wall, "cpu_seconds": cpu,
        "log_tail": log[-2000:],
    }


def storm_full_value(directory):
    """The fully observable game value of `<<P>> Pmax/Pmin=? [F goal]` (Storm, SMG)."""
    import payntbind
    import stormpy
    player, _, text = prop_of(directory)
    source = open(os.path.join(directory, "sketch.templ")).read()
    players = [int(m) for m in re.findall(r"^state \d+ (?:\{\d+\} )?<(\d+)>", source, re.M)]
    mdp_text = re.sub(r"^@type: POSMG", "@type: MDP", source, flags=re.M)
    mdp_text = re.sub(r"^(state \d+) (?:\{\d+\} )?<\d+>", r"\1", mdp_text, flags=re.M)
    mdp_text = mdp_text.replace(" []", "")
    path = os.path.join(directory, "fully-observable.drn")
    with open(path, "w") as handle:
        handle.write(mdp_text)
    options = stormpy.io.DirectEncodingParserOptions()
    options.build_choice_labeling = True
    mdp = stormpy.build_model_from_drn(path, options=options)
    assert mdp.nr_states == len(players)
    components = stormpy.models.SparseModelComponents(transition_matrix=mdp.transition_matrix,
                                                      state_labeling=mdp.labeling)
    components.state_player_indications = players
    smg = stormpy.models.SparseSmg(components)
    formula = stormpy.parse_properties(text)[0].get_raw_formula()
    result = payntbind.synthesis.model_check_smg(smg, formula, only_initial_states=False,
                                                 set_produce_schedulers=False,
                                                 env=stormpy.Environment())
    return float(result.get_value(smg.initial_states[0])), mdp.nr_states, player


def run_posg(directory, k, limit, budget, seed=1, out=None):
    out = out or os.path.join(directory, f"posg-fsc-{k}")
    command = [BINARY, "solve", os.path.join(directory, "sketch.templ"), "--props",
               os.path.join(directory, "sketch.props"), "--def-nodes", str(k), "--out", out,
               "--force", "--seed", str(seed), "--quiet"]
    if budget:
        command += ["--time-budget", str(budget)]
    done, wall, cpu = timed(command, limit)
    record = {"command": " ".join(["posg-fsc", *command[1:]]), "wall_seconds": wall,
              "cpu_seconds": cpu, "certified_lower": None, "worst_case": None, "status": "error"}
    if done is None:
        record["status"] = f"killed after {limit} s"
        return record
    if done.returncode != 0:
        record["status"] = "error: " + done.stderr.strip()[-500:]
        return record
    with open(os.path.join(out, "summary.json")) as handle:
        summary = json.load(handle)
    record.update({
        "certified_lower": (summary.get("certified") or {}).get("certified_lower"),
        "upper_bound": (summary.get("certified") or {}).get("upper_bound"),
        "worst_case": summary.get("worst_case"),
        "solve_seconds": summary.get("seconds"),
        "status": "ok" if summary.get("certified") else "no certificate",
    })
    return record


NOT_RUN = {"status": "not run", "value": None, "certified_lower": None, "worst_case": None,
           "cpu_seconds": 0.0, "wall_seconds": 0.0, "synthesis_seconds": None}


def cached(path, compute, only_cached=False):
    """The record at `path`, else `compute()` stored there (or NOT_RUN if `only_cached`)."""
    if os.path.exists(path):
        with open(path) as handle:
            return json.load(handle)
    if only_cached:
        return dict(NOT_RUN)
    record = compute()
    with open(path, "w") as handle:
        json.dump(record, handle, indent=1)
    return record


def seed_peer_records(path, models_dir, timeout):
    """Writes the cached PAYNT and Storm records of every row of the earlier
    results CSV at `path` whose records are missing, so that only posg-fsc
    runs again. Values go back to the tools' own (p, not 1 - p)."""
    with open(path) as handle:
        lines = [line for line in handle if not line.startswith("#")]
    for row in csv.DictReader(lines):
        directory = os.path.join(models_dir, row["model"])
        if not os.path.isdir(directory):
            continue
        _, direction, _ = prop_of(directory)
        number = lambda text: float(text) if text else None
        paynt = os.path.join(directory, f"paynt-{row['k']}-t{timeout}.json")
        if not os.path.exists(paynt):
            with open(paynt, "w") as handle:
                json.dump({"command": f"from {path}", "value": number(row["paynt_value"]),
                           "status": row["paynt_status"],
                           "synthesis_seconds": number(row["paynt_synthesis_s"]),
                           "wall_seconds": number(row["paynt_wall_s"]),
                           "cpu_seconds": number(row["paynt_cpu_s"])}, handle, indent=1)
        storm = os.path.join(directory, "storm.json")
        if not os.path.exists(storm):
            value = defender(number(row["fully_observable_defender_value"]), direction)
            with open(storm, "w") as handle:
                json.dump({"value": value, "states": int(row["states"]),
                           "player": prop_of(directory)[0]}, handle, indent=1)


def defender(value, direction):
    """A probability of F goal as the defender's value (1 - p when it minimises)."""
    if value is None:
        return None
    return value if direction == "max" else 1.0 - value


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repo", help="git directory of a clone of randriu/synthesis")
    parser.add_argument("--work", default=os.path.join(ROOT, "target", "paynt-posmg"))
    parser.add_argument("--timeout", type=int, default=300, help="PAYNT's --timeout (s)")
    parser.add_argument("--posg-limit", type=int, default=600,
                        help="posg-fsc runs are killed after this many seconds")
    parser.add_argument("--time-budget", type=float, default=None,
                        help="posg-fsc's --time-budget per structure (s; default: none)")
    parser.add_argument("--phase", choices=["paynt", "posg", "all", "csv"], default="all",
                        help="csv: write the CSV from the cached records only")
    parser.add_argument("--peers-from", metavar="CSV",
                        help="take PAYNT's and Storm's records from this earlier results CSV "
                             "where none is cached (rerun posg-fsc alone; the CSV's first line "
                             "then names it)")
    parser.add_argument("--models", nargs="*", default=MODELS)
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "paynt-posmg.csv"))
    args = parser.parse_args()
    models_dir = os.path.join(args.work, "models")
    prepare(models_dir, args.repo)
    if args.peers_from:
        seed_peer_records(args.peers_from, models_dir, args.timeout)
    if args.phase != "paynt":
        build()
    if args.phase == "posg":
        # k outer: every model gets its 1-node run before any 2-node run.
        for k in NODES:
            for name in args.models:
                directory = os.path.join(models_dir, name)
                posg = cached(os.path.join(directory, f"posg-{k}.json"),
                              lambda: run_posg(directory, k, args.posg_limit, args.time_budget))
                print(f"{name} k={k}: posg-fsc {posg['status']} {posg['certified_lower']} "
                      f"({posg['cpu_seconds']:.1f} s CPU)", flush=True)
        return
    rows = []
    for name in args.models:
        directory = os.path.join(models_dir, name)
        _, direction, text = prop_of(directory)
        if args.phase != "posg":
            full = cached(os.path.join(directory, "storm.json"),
                          lambda: dict(zip(["value", "states", "player"], storm_full_value(directory))))
        for k in NODES:
            paynt = None
            if args.phase != "posg":
                paynt = cached(os.path.join(directory, f"paynt-{k}-t{args.timeout}.json"),
                               lambda: run_paynt(directory, k, args.timeout), args.phase == "csv")
                print(f"{name} k={k}: PAYNT {paynt['status']} {paynt['value']} "
                      f"({paynt['cpu_seconds']:.1f} s CPU)", flush=True)
            if args.phase == "paynt":
                continue
            posg = cached(os.path.join(directory, f"posg-{k}.json"),
                          lambda: run_posg(directory, k, args.posg_limit, args.time_budget),
                          args.phase == "csv")
            print(f"{name} k={k}: posg-fsc {posg['status']} {posg['certified_lower']} "
                  f"({posg['cpu_seconds']:.1f} s CPU)", flush=True)
            ours = posg["certified_lower"]
            theirs = defender(paynt["value"], direction)
            if "not run" in (paynt["status"], posg["status"]):
                winner = "not run"
            elif ours is None and theirs is None:
                winner = "none"
            elif theirs is None or (ours is not None and ours > theirs + TOLERANCE):
                winner = "posg-fsc"
            elif ours is None or ours < theirs - TOLERANCE:
                winner = "paynt"
            else:
                winner = "tie"
            rows.append({
                "model": name, "states": full["states"], "property": text, "k": k,
                "paynt_value": paynt["value"], "paynt_defender_value": theirs,
                "paynt_status": paynt["status"], "paynt_cpu_s": round(paynt["cpu_seconds"], 2),
                "paynt_wall_s": round(paynt["wall_seconds"], 2),
                "paynt_synthesis_s": paynt["synthesis_seconds"],
                "posg_certified_lower": ours, "posg_worst_case": posg["worst_case"],
                "posg_status": posg["status"], "posg_cpu_s": round(posg["cpu_seconds"], 2),
                "posg_wall_s": round(posg["wall_seconds"], 2),
                "fully_observable_defender_value": defender(full["value"], direction),
                "winner": winner,
            })
    if args.phase not in ("all", "csv"):
        return
    import paynt  # noqa: F401  (its version for the record)
    import stormpy
    version = subprocess.run([BINARY, "--version"], capture_output=True, text=True).stdout.strip()
    with open(args.out, "w", newline="") as handle:
        handle.write(f"# {' '.join(sys.argv)}; PAYNT 0.5.0 (--timeout {args.timeout}), stormpy "
                     f"{stormpy.__version__}, {version}; models: randriu/synthesis@{COMMIT}; "
                     f"posg-fsc: solve --props --def-nodes K --seed 1"
                     f"{f' --time-budget {args.time_budget:g}' if args.time_budget else ''}, defaults "
                     f"otherwise, killed after {args.posg_limit} s; "
                     f"values are the defender's (1 - p for Pmin); CPU s include children\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.out}\n")
    print(markdown(rows))


def markdown(rows):
    """The table of results/README.md ("Moved from the README (stop 66)"):
    defender's values and CPU seconds per model and k."""
    show = lambda v: "-" if v is None else f"{v:.4f}"
    lines = ["| model | states | k | PAYNT | PAYNT CPU s | posg-fsc certified | posg-fsc CPU s "
             "| fully observable | winner |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        paynt = show(r["paynt_defender_value"]) + ("" if r["paynt_status"] == "optimal" else
                                                   f" ({r['paynt_status']})")
        lines.append(f"| {r['model']} | {r['states']} | {r['k']} | {paynt} | {r['paynt_cpu_s']} | "
                     f"{show(r['posg_certified_lower'])} | {r['posg_cpu_s']} | "
                     f"{show(r['fully_observable_defender_value'])} | {r['winner']} |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
