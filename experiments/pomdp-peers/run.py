#!/usr/bin/env python3
"""posg-fsc against PAYNT and Storm's gradient descent on PRISM POMDPs.

Question: on the PRISM POMDP benchmarks of PAYNT's repository, does
`posg-fsc solve` with its default settings and k = 1, 2, 3 controller
nodes reach the value of PAYNT's FSC synthesis and of Storm's gradient
descent for randomised FSCs (Heck et al., VMCAI 2022), and with how much
CPU?

For each model and k, one tool at a time:

* posg-fsc: `posg-fsc solve model.drn --props model.props --def-nodes K
  --out DIR --quiet` (the DRN exported by stormpy, read directly,
  docs/formats.md section 6); its value is the certified lower bound of
  the controller it returns (summary.json), the best exact value of the
  single-player ascent when nothing was certified;
* PAYNT 0.5.0: `python -m paynt DIR --sketch sketch.templ --props
  sketch.props --fsc-memory-size K --timeout T`; its value is the optimum
  it reports (the best found when the timeout stops it);
* Storm GD: the POMDP made canonic, a full k-state memory unfolded
  (`create_memory(FULL, k)`, `unfold_memory`, `make_simple`), the unknown
  FSC applied (`apply_unknown_fsc(SIMPLE_LINEAR)`) giving a parametric
  DTMC, then `stormpy.pars.check_feasibility(..., method=GD)` (stormpy 2.0
  exposes Storm's GradientDescentInstantiationSearcher only as a
  feasibility check: it descends until the value meets a bound or stops
  changing, and returns the instantiation only when the bound is met).
  The bound is the better of posg-fsc's and PAYNT's values on the case,
  `P>=best`: "does GD reach the best of the other two?". Its instantiation
  is re-evaluated by Storm on the instantiated DTMC (exact arithmetic).
  If GD stops (converges, status `below-bound`) or is stopped (`timeout`)
  without meeting the bound, its value is only known to be below it: the
  binding returns no point, and Storm's "Currently at" progress lines do
  not reach stdout from stormpy 2.0, not even at log level INFO. Then a
  second run towards `best - 1e-2` (`storm-gd>=best-0.01`) asks whether GD
  comes close; where the first run met its bound, a second run towards
  `best + 1e-4` (`storm-gd>best`, --beat-timeout) asks whether GD beats both.
  With --long-gd S, where neither run met its bound and posg-fsc's CPU is
  above a tenth of theirs (the target of issue 25), a third run towards
  `best - 1e-2` is given S seconds (`storm-gd>=best-0.01 (long)`).

* Storm's belief MDP (`verify_with_belief_unfolding`, no clipping,
  exploration stopped after --timeout s): where its exploration completes,
  its value is the POMDP's optimum over all observation-based controllers
  of any memory size, an upper bound for every tool and every k. A value
  above it (by more than 1e-4) cannot be the value of a controller of
  the POMDP: it is marked, and it does not count as best.

CPU and wall seconds are the process's (start-up, parsing and model
building included, for every tool alike); a run of any tool that took
under a second of CPU is a warm-up: it is made eleven times more and
the medians of those eleven are reported.
`posg_cpu_over_gd_cpu` divides posg-fsc's CPU by GD's: by the CPU of the
first GD run where it met its bound, else by the most CPU any GD run of
the case spent without meeting the first run's bound (GD stops at the
first point that meets a bound, so reaching the best would take it at
least that long): the ratio is then an upper bound
(`gd_cpu_is_lower_bound`).

Properties: probabilities only (posg-fsc computes probabilities); the
models' formulas name labels that are added to the PRISM text where the
original uses a formula or an expression (see MODELS). For a `Pmin`
query all values are the probability of the complement (1 - p), which
posg-fsc maximises as `G !target`.

Writes results/pomdp-peers.csv (first line: command, settings, versions)
and a sidecar results/pomdp-peers.json with the per-run records. Runs
are cached in --work, so an interrupted run resumes.

Usage:
  POSG_FSC=path/to/posg-fsc /work/venv-paynt/bin/python experiments/pomdp-peers/run.py \\
      --repo /path/to/synthesis.git --timeout 60   (as in results/pomdp-peers.csv)
"""
import argparse
import csv
import hashlib
import json
import os
import re
import resource
import signal
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "common"))
from games import BINARY, ROOT, build  # noqa: E402

COMMIT = "8eb05ea143c3d9feb5f2ab219187fcc6c7195dd1"
# name -> (path in randriu/synthesis, property used by all three tools,
#          PRISM lines appended to the model (labels for formulas)).
MODELS = {
    "grid-avoid-4-0": ("models/archive/uai22-pomdp/grid-avoid-4-0",
                       'Pmax=? [!"bad" U "goal"]', ""),
    "grid-avoid-4-0.1": ("models/archive/uai22-pomdp/grid-avoid-4-0.1",
                         'Pmax=? [!"bad" U "goal"]', ""),
    "grid-simple-4x4": ("models/pomdp/grid/simple/4x4", 'Pmax=? [F "goal"]',
                        'label "goal" = goal;'),
    "grid-simple-2x2": ("models/pomdp/grid/simple/2x2", 'Pmin=? [F "trap"]',
                        'label "trap" = trap;'),
    "nrp-8": ("models/archive/uai22-pomdp/nrp-8", 'Pmax=? [F "unfair"]', ""),
    "refuel-06": ("models/archive/uai22-pomdp/refuel-06", 'Pmax=? ["notbad" U "goal"]', ""),
    "crypt-4": ("models/archive/uai22-pomdp/crypt-4", 'Pmax=? [F "goal"]', ""),
    "drone-4-1": ("models/archive/uai22-pomdp/drone-4-1", 'Pmax=? ["notbad" U "goal"]', ""),
}
NODES = [1, 2, 3]
TOLERANCE = 1e-4
# Where GD does not come within TOLERANCE of the best, a second run asks
# whether it comes within NEAR (its value is otherwise unknown).
NEAR = 1e-2
GD_REGION_BOUND = 1e-6
# Issue 25's target: posg-fsc at most this fraction of Storm GD's CPU.
TARGET_CPU_RATIO = 0.1


def git_show(repo, path):
    return subprocess.run(["git", "--git-dir", repo, "show", f"{COMMIT}:{path}"], check=True,
                          capture_output=True, text=True).stdout


def prepare(models_dir, repo):
    """Writes each model as DIR/NAME/sketch.templ (PRISM), sketch.props and
    model.drn (stormpy's export, choice labels kept); returns the state counts.
    A model is built once for its sources: its count is kept in
    DIR/NAME/states.json with a hash of sketch.templ and sketch.props.
    Building the eight models in this process right before the first timed
    run left memory the next runs got back cold (on this host's VM, 3-5x
    the CPU of a run of 10 ms; stop 54)."""
    states = {}
    for name, (path, prop, extra) in MODELS.items():
        directory = os.path.join(models_dir, name)
        os.makedirs(directory, exist_ok=True)
        prism = git_show(repo, f"{path}/sketch.templ")
        if extra:
            prism += f"\n// added by experiments/pomdp-peers/run.py\n{extra}\n"
        with open(os.path.join(directory, "sketch.templ"), "w") as handle:
            handle.write(prism)
        with open(os.path.join(directory, "sketch.props"), "w") as handle:
            handle.write(prop + "\n")
        source = hashlib.sha256((prism + "\n" + prop).encode()).hexdigest()
        kept = os.path.join(directory, "states.json")
        counted = {}
        if os.path.exists(kept):
            with open(kept) as handle:
                counted = json.load(handle)
        if counted.get("source") != source:
            counted = {"source": source, "states": export_model(directory)}
            with open(kept, "w") as handle:
                json.dump(counted, handle, indent=1)
        states[name] = counted["states"]
    return states


def export_model(directory):
    """Builds the model of `directory`, writes it as model.drn, and returns
    its state count."""
    import stormpy
    model = build_pomdp(directory)
    stormpy.io.export_to_drn(model, os.path.join(directory, "model.drn"))
    return model.nr_states


def build_pomdp(directory):
    import stormpy
    program = stormpy.parse_prism_program(os.path.join(directory, "sketch.templ"))
    options = stormpy.BuilderOptions(build_full=True)
    options.set_build_choice_labels(True)
    options.set_build_all_labels()
    return stormpy.build_model(program, options=options)


def prop_of(directory):
    return open(os.path.join(directory, "sketch.props")).read().strip()


def complement(value, prop):
    """The value as posg-fsc's objective: 1 - p for a Pmin query."""
    if value is None:
        return None
    return 1.0 - value if prop.startswith("Pmin") else value


# A run of any tool that took under SHORT_RUN CPU seconds is made
# REPEATS times more and the median CPU and wall seconds of those repeats
# are reported, the first run a warm-up: one sample of a run of a few
# milliseconds is mostly the host's noise and the kernel's accounting tick
# (one posg-fsc run of nrp-8 measured 0.03 s, ten of them 0.007 s each),
# and the first runs after other work are the slow ones (posg-fsc on
# grid-avoid-4-0, 15 runs in a row: 0.046, 0.024, 0.029, then 0.014-0.015 s).
# Eleven, not five: on this host one run in a few takes 3-4 times the CPU
# of the others (a 54 ms run among 14 ms ones, with 105 context switches
# instead of 31 and 38 ms of system time), and five repeats of grid-avoid-4-0
# with 2 nodes once held three such runs.
SHORT_RUN = 1.0
REPEATS = 11


def timed(command, limit, interrupt_after=None, **kwargs):
    """Runs `command`; returns (stdout+stderr or None when killed at `limit`,
    return code, wall seconds, CPU seconds (user+sys) of the child and its
    children, the CPU seconds of every run made, the warm-up first). With
    `interrupt_after`, the child gets SIGINT after that many seconds. A
    run that exited with 0 before any interrupt within SHORT_RUN CPU
    seconds is a warm-up: REPEATS more runs are made (each must end the
    same way, or the experiment stops) and the seconds are their medians;
    the output is the first run's (each tool here is deterministic for
    its inputs, posg-fsc by its seed: every repeat writes the same)."""
    out, code, wall, cpu = timed_once(command, limit, interrupt_after, **kwargs)
    interrupted = interrupt_after is not None and wall >= interrupt_after
    if out is None or code != 0 or interrupted or cpu >= SHORT_RUN:
        return out, code, wall, cpu, [cpu]
    warmup, walls, cpus = cpu, [], []
    for _ in range(REPEATS):
        again, code, wall, cpu = timed_once(command, limit, interrupt_after, **kwargs)
        if again is None or code != 0 or (interrupt_after is not None and wall >= interrupt_after):
            raise RuntimeError(f"a repeat of {' '.join(command)} did not end as its first run: "
                               f"exit code {code}, {wall:.1f} s")
        walls.append(wall)
        cpus.append(cpu)
    return out, 0, statistics.median(walls), statistics.median(cpus), [warmup] + cpus


def timed_once(command, limit, interrupt_after=None, **kwargs):
    """One run of `command` (see `timed`)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, **kwargs)
    try:
        out, _ = process.communicate(timeout=interrupt_after or limit)
    except subprocess.TimeoutExpired:
        out = None
        if interrupt_after:
            process.send_signal(signal.SIGINT)
            try:
                out, _ = process.communicate(timeout=limit - interrupt_after)
            except subprocess.TimeoutExpired:
                out = None
        if out is None:
            process.kill()
            process.communicate()
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return out, process.returncode, wall, cpu


def run_posg(directory, k, limit):
    out = os.path.join(directory, f"posg-fsc-{k}")
    command = [BINARY, "solve", os.path.join(directory, "model.drn"), "--props",
               os.path.join(directory, "sketch.props"), "--def-nodes", str(k), "--out", out,
               "--force", "--quiet"]
    log, code, wall, cpu, samples = timed(command, limit)
    record = {"command": " ".join(["posg-fsc", *command[1:]]), "wall_seconds": wall,
              "cpu_seconds": cpu, "cpu_samples": samples, "value": None}
    if log is None:
        record["status"] = "timeout"
        return record
    if code != 0:
        record["status"] = "error: " + log.strip()[-500:]
        return record
    with open(os.path.join(out, "summary.json")) as handle:
        summary = json.load(handle)
    certified = (summary.get("certified") or {}).get("certified_lower")
    record.update({
        "certified_lower": certified,
        "upper_bound": (summary.get("certified") or {}).get("upper_bound"),
        "worst_case": summary.get("worst_case"),
        "stop_reason": summary.get("stop_reason"),
        "solve_seconds": summary.get("seconds"),
        "value": certified if certified is not None else summary.get("worst_case"),
        "status": "ok" if certified is not None else "uncertified",
    })
    return record


def run_paynt(directory, k, timeout):
    prop = prop_of(directory)
    command = [sys.executable, "-m", "paynt", directory, "--sketch", "sketch.templ", "--props",
               "sketch.props", "--fsc-memory-size", str(k), "--timeout", str(timeout)]
    log, code, wall, cpu, samples = timed(command, timeout + 120)
    log = log or ""
    optimum = re.search(r"^optimum: (\S+)", log, re.M)
    explored = re.search(r"^explored: (\d+) %", log, re.M)
    finished = explored is not None and explored.group(1) == "100"
    value = float(optimum.group(1)) if optimum else None
    status = ("optimal" if finished and optimum else
              "timeout" if "time limit reached" in log or code is None else
              "infeasible" if finished else "error")
    return {"command": " ".join(["python", "-m", "paynt", *command[3:]]),
            "optimum": value, "value": complement(value, prop),
            "status": status, "explored_percent": int(explored.group(1)) if explored else None,
            "wall_seconds": wall, "cpu_seconds": cpu, "cpu_samples": samples, "log_tail": log[-1500:]}


def run_gd(directory, k, bound, limit):
    """Storm's gradient descent in a child process (this script with --gd-worker),
    interrupted by SIGINT after `limit` seconds (Storm then stops the descent)."""
    command = [sys.executable, os.path.abspath(__file__), "--gd-worker", directory, str(k),
               repr(bound)]
    log, code, wall, cpu, samples = timed(command, limit + 60, interrupt_after=limit)
    record = {"command": f"stormpy GD, bound P>={bound!r}, k={k}", "bound": bound,
              "wall_seconds": wall, "cpu_seconds": cpu, "cpu_samples": samples, "value": None}
    if log is None:
        record["status"] = "timeout (killed)"
        return record
    result = re.search(r"^RESULT (.*)$", log, re.M)
    if result is None:
        # Storm aborts 30 s after the SIGINT when the descent has not reached
        # a point where it checks for it (model construction, a long solve).
        # A child killed by SIGKILL before its time limit: on this host the
        # kernel's out-of-memory killer (Storm building the pMC of
        # drone-4-1 with 3 nodes reached 24 GB).
        aborted = "received signal" in log
        status = ("timeout (aborted)" if aborted else
                  "killed (SIGKILL, out of memory?)" if code == -signal.SIGKILL else "error")
        record.update(status=status, return_code=code, log_tail=log[-1500:])
        return record
    record.update(json.loads(result.group(1)))
    record["interrupted"] = wall >= limit
    if record["witness_value"] is not None:
        record["value"] = record["exact_value"]
        record["status"] = "reached-bound"
    else:
        record["status"] = "timeout" if record["interrupted"] else "below-bound"
    return record


def gd_worker(directory, k, bound):
    """Builds the parametric DTMC of an unknown k-state FSC and runs Storm's GD
    towards `P>=bound`; prints one line `RESULT {json}`."""
    import stormpy
    import stormpy.developer
    import stormpy.pars
    import stormpy.pomdp
    stormpy.developer.install_signal_handler(30)
    prop = prop_of(directory)
    pomdp = stormpy.pomdp.make_canonic(build_pomdp(directory))
    memory = stormpy.pomdp.create_memory(stormpy.pomdp.PomdpMemoryPattern.FULL, k)
    product = stormpy.pomdp.unfold_memory(pomdp, memory, add_memory_labels=False,
                                          keep_state_valuations=False)
    product = stormpy.pomdp.make_simple(product, keep_state_valuations=False)
    pmc = stormpy.pomdp.apply_unknown_fsc(product, stormpy.pomdp.PomdpFscApplicationMode.SIMPLE_LINEAR)
    # GD maximises towards P>=b; for Pmin it minimises towards P<=1-b.
    if prop.startswith("Pmin"):
        bounded = prop.replace("Pmin=?", f"P<={1.0 - bound!r}", 1)
    else:
        bounded = prop.replace("Pmax=?", f"P>={bound!r}", 1)
    formula = stormpy.parse_properties(bounded)[0]
    start = time.process_time()
    result = stormpy.pars.check_feasibility(pmc, formula, region_bound=GD_REGION_BOUND,
                                            method=stormpy.pars.FeasibilityMethod.GD)
    gd_cpu = time.process_time() - start
    record = {"pmc_states": pmc.nr_states, "parameters": len(pmc.collect_all_parameters()),
              "gd_status": str(result.status), "gd_cpu_seconds": gd_cpu, "witness_value": None,
              "exact_value": None, "bounded_property": bounded}
    if result.witness is not None:
        valuation = {p: stormpy.RationalFunctionCoefficient(v) if not isinstance(
            v, stormpy.RationalFunctionCoefficient) else v
            for p, v in result.witness.valuation.items()}
        dtmc = stormpy.pars.ModelInstantiator(pmc).instantiate(valuation)
        exact = stormpy.Environment()
        exact.solver().force_exact = True
        check = stormpy.parse_properties(prop.replace("Pmin=?", "P=?").replace("Pmax=?", "P=?"))[0]
        value = stormpy.model_checking(dtmc, check, environment=exact).get_value(dtmc.initial_states[0])
        record["witness_value"] = complement(float(result.witness.value), prop)
        record["exact_value"] = complement(float(value), prop)
    print("RESULT " + json.dumps(record), flush=True)


def run_belief(directory, limit):
    """Storm's belief-MDP unfolding in a child process (this script with
    --belief-worker), exploration stopped after `limit` seconds."""
    command = [sys.executable, os.path.abspath(__file__), "--belief-worker", directory,
               str(limit)]
    log, code, wall, cpu, samples = timed(command, limit + 120)
    record = {"command": f"stormpy verify_with_belief_unfolding, max_exploration_time={limit}",
              "wall_seconds": wall, "cpu_seconds": cpu, "cpu_samples": samples, "value": None, "completed": False}
    result = re.search(r"^RESULT (.*)$", log or "", re.M)
    if result is None:
        record.update(status="timeout (killed)" if log is None else "error",
                      log_tail=(log or "")[-1500:])
        return record
    record.update(json.loads(result.group(1)))
    record["status"] = "optimum" if record["completed"] else "incomplete"
    return record


def belief_worker(directory, limit):
    """Unfolds the belief MDP of the POMDP (no clipping) for at most `limit`
    seconds; prints one line `RESULT {json}`: its value (1 - p for Pmin)
    and whether the exploration completed (then the value is the POMDP's
    optimum over all observation-based controllers)."""
    import stormpy
    import stormpy.pomdp
    prop = prop_of(directory)
    pomdp = build_pomdp(directory)
    result = stormpy.pomdp.verify_with_belief_unfolding(
        pomdp, stormpy.parse_properties(prop)[0], max_exploration_time=limit)
    print("RESULT " + json.dumps({"value": complement(float(result.value), prop),
                                  "completed": bool(result.completed_exploration)}), flush=True)


def pomdp_optimum(belief):
    """The POMDP's optimum where the belief exploration completed, else None."""
    return belief["value"] if belief.get("completed") else None


def cached(path, compute):
    if os.path.exists(path):
        with open(path) as handle:
            return json.load(handle)
    record = compute()
    with open(path, "w") as handle:
        json.dump(record, handle, indent=1)
    return record


def versions():
    import stormpy
    posg = subprocess.run([BINARY, "--version"], capture_output=True, text=True).stdout.strip()
    with open(BINARY, "rb") as handle:
        digest = hashlib.sha256(handle.read()).hexdigest()[:16]
    return {"posg-fsc": f"{posg} ({BINARY}, sha256 {digest}...)",
            "stormpy": stormpy.__version__, "paynt": "0.5.0",
            "models": f"randriu/synthesis@{COMMIT}"}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repo", required=True, help="git directory of randriu/synthesis")
    parser.add_argument("--work", default=os.path.join(ROOT, "target", "pomdp-peers"))
    parser.add_argument("--timeout", type=int, default=120,
                        help="per-run limit (s): PAYNT's --timeout, GD's interrupt, the belief "
                             "MDP's exploration")
    parser.add_argument("--posg-timeout", type=int, default=120,
                        help="posg-fsc runs are killed after this many seconds")
    parser.add_argument("--beat-timeout", type=int, default=30,
                        help="limit (s) of the second GD run, towards P>=best+1e-4")
    parser.add_argument("--peers-from", metavar="JSON",
                        help="take PAYNT's and Storm GD's runs from this earlier sidecar "
                             "(results/pomdp-peers.json) where none is cached: posg-fsc runs "
                             "again alone; a GD run asked against another bound still runs")
    parser.add_argument("--long-gd", type=int, default=0, metavar="SECONDS",
                        help="where no GD run met its bound and posg-fsc's CPU is above "
                             f"{TARGET_CPU_RATIO} of GD's, one more GD run towards best-{NEAR} "
                             "with this limit (0: none)")
    parser.add_argument("--models", nargs="*", default=list(MODELS))
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "pomdp-peers.csv"))
    args = parser.parse_args()
    build()
    models_dir = os.path.join(args.work, "models")
    states = prepare(models_dir, args.repo)
    if args.peers_from:
        seed_peer_runs(args, models_dir)
    records, rows = [], []
    for name in args.models:
        directory = os.path.join(models_dir, name)
        belief = cached(os.path.join(directory, f"belief-t{args.timeout}.json"),
                        lambda: run_belief(directory, args.timeout))
        records.append({"model": name, "k": None, "tool": "storm-belief", **belief})
        optimum = pomdp_optimum(belief)
        for k in NODES:
            posg = cached(os.path.join(directory, f"posg-{k}.json"),
                          lambda: run_posg(directory, k, args.posg_timeout))
            paynt = cached(os.path.join(directory, f"paynt-{k}-t{args.timeout}.json"),
                           lambda: run_paynt(directory, k, args.timeout))
            peers = [v for v in (posg["value"], paynt["value"]) if v is not None]
            bound = max(max(peers) - TOLERANCE, 0.0) if peers else 0.0
            gd = cached(os.path.join(directory, f"gd-{k}-t{args.timeout}.json"),
                        lambda: run_gd(directory, k, bound, args.timeout))
            case = {"posg-fsc": posg, "paynt": paynt, "storm-gd": gd}
            if gd["status"] != "reached-bound" and max(peers) > NEAR:
                # GD did not come within TOLERANCE: does it come within NEAR?
                case["storm-gd>=best-0.01"] = cached(
                    os.path.join(directory, f"gd-near-{k}-t{args.timeout}.json"),
                    lambda: run_gd(directory, k, max(peers) - NEAR, args.timeout))
            if gd["status"] == "reached-bound" and max(peers) + TOLERANCE <= 1.0:
                # GD matched the best within TOLERANCE; can it beat it by more?
                case["storm-gd>best"] = cached(
                    os.path.join(directory, f"gd-beat-{k}-t{args.beat_timeout}.json"),
                    lambda: run_gd(directory, k, max(peers) + TOLERANCE, args.beat_timeout))
            gd_cpu, lower_bound = gd_cpu_to_best(case)
            none_reached = all(r["status"] != "reached-bound" for tool, r in case.items()
                               if tool.startswith("storm-gd"))
            if (args.long_gd and none_reached and max(peers) > NEAR
                    and posg["cpu_seconds"] > TARGET_CPU_RATIO * gd_cpu):
                case["storm-gd>=best-0.01 (long)"] = cached(
                    os.path.join(directory, f"gd-long-{k}-t{args.long_gd}.json"),
                    lambda: run_gd(directory, k, max(peers) - NEAR, args.long_gd))
                gd_cpu, lower_bound = gd_cpu_to_best(case)
            for tool, record in case.items():
                print(f"{name} k={k} {tool}: {record['status']} {record['value']} "
                      f"({record['cpu_seconds']:.1f} s CPU)", flush=True)
                records.append({"model": name, "k": k, "tool": tool, **record})
            best = best_tools(case, optimum)
            ratio = (posg["cpu_seconds"] / gd_cpu) if gd_cpu > 0 else None
            for tool, record in case.items():
                rows.append({
                    "model": name, "states": states[name], "k": k, "tool": tool,
                    "value": None if record["value"] is None else round(record["value"], 6),
                    "cpu_seconds": round(record["cpu_seconds"], 2),
                    "wall_seconds": round(record["wall_seconds"], 2),
                    "status": record["status"],
                    "above_pomdp_optimum": above_optimum(record["value"], optimum),
                    "pomdp_optimum": None if optimum is None else round(optimum, 6),
                    "best": best,
                    "posg_cpu_over_gd_cpu": None if ratio is None else round(ratio, 4),
                    "gd_cpu_is_lower_bound": lower_bound,
                })
    write(args, rows, records)


def seed_peer_runs(args, models_dir):
    """Writes the cached runs of PAYNT and Storm GD from the earlier sidecar
    `args.peers_from` where they are missing. A GD run's record holds the
    bound it was asked for; it stands as it was, whatever posg-fsc now finds."""
    with open(args.peers_from) as handle:
        runs = json.load(handle)["runs"]
    files = {"paynt": "paynt-{k}-t{t}.json", "storm-gd": "gd-{k}-t{t}.json",
             "storm-gd>=best-0.01": "gd-near-{k}-t{t}.json", "storm-gd>best": "gd-beat-{k}-t{b}.json"}
    for run in runs:
        if run["tool"] not in files or run["model"] not in MODELS:
            continue
        name = files[run["tool"]].format(k=run["k"], t=args.timeout, b=args.beat_timeout)
        path = os.path.join(models_dir, run["model"], name)
        if not os.path.exists(path):
            record = {key: value for key, value in run.items() if key not in ("model", "k", "tool")}
            with open(path, "w") as handle:
                json.dump(record, handle, indent=1)


def above_optimum(value, optimum):
    """Whether `value` exceeds the POMDP's optimum by more than TOLERANCE
    (no controller of the POMDP has it); None where either is unknown."""
    if value is None or optimum is None:
        return None
    return value > optimum + TOLERANCE


def gd_cpu_to_best(case):
    """GD's CPU towards the case's best value and whether it is only a
    lower bound: the first GD run's CPU where it met its bound, else the
    most any GD run spent without meeting that bound (module docstring)."""
    first = case["storm-gd"]
    if first["status"] == "reached-bound":
        return first["cpu_seconds"], False
    runs = [r for tool, r in case.items() if tool.startswith("storm-gd") and tool != "storm-gd>best"]
    return max(r["cpu_seconds"] for r in runs), True


def best_tools(case, optimum):
    """The tools within TOLERANCE of the best value found in the case,
    among the values not above the POMDP's optimum."""
    values = {tool: r["value"] for tool, r in case.items()
              if r["value"] is not None and not above_optimum(r["value"], optimum)}
    if not values:
        return "none"
    top = max(values.values())
    return "+".join(tool for tool, v in values.items() if v >= top - TOLERANCE)


def write(args, rows, records):
    settings = {
        "command": " ".join(sys.argv), "timeout_seconds": args.timeout, "posg_timeout_seconds": args.posg_timeout, "nodes": NODES,
        "posg-fsc": "solve model.drn --props sketch.props --def-nodes K --quiet (defaults)",
        "paynt": "python -m paynt DIR --sketch sketch.templ --props sketch.props "
                 f"--fsc-memory-size K --timeout {args.timeout}",
        "storm-gd": "make_canonic, create_memory(FULL, K), unfold_memory, make_simple, "
                    "apply_unknown_fsc(SIMPLE_LINEAR), check_feasibility(method=GD, "
                    f"region_bound={GD_REGION_BOUND}) towards P>=max(posg-fsc, PAYNT)-{TOLERANCE}, "
                    f"SIGINT after {args.timeout} s",
        "storm-gd>=best-0.01": "the same GD towards P>=max(posg-fsc, PAYNT)-"
                               f"{NEAR}, run only where the first GD run did not meet its "
                               f"bound, SIGINT after {args.timeout} s",
        "storm-gd>=best-0.01 (long)": "the same GD towards P>=max(posg-fsc, PAYNT)-"
                                      f"{NEAR}, run only where no GD run met its bound and "
                                      f"posg-fsc's CPU is above {TARGET_CPU_RATIO} of GD's, "
                                      f"SIGINT after {args.long_gd} s (0: never run)",
        "posg_cpu_over_gd_cpu": "posg-fsc's CPU over the first GD run's where it met its "
                                "bound, else over the most CPU a GD run spent without meeting "
                                "it (gd_cpu_is_lower_bound: the ratio is an upper bound)",
        "storm-gd>best": "the same GD towards P>=max(posg-fsc, PAYNT)+"
                         f"{TOLERANCE}, run only where the first GD run met its bound, "
                         f"SIGINT after {args.beat_timeout} s",
        "storm-belief": "verify_with_belief_unfolding (no clipping), "
                        f"max_exploration_time={args.timeout}: where the exploration completes, "
                        "the POMDP's optimum (pomdp_optimum); above_pomdp_optimum marks values "
                        f"above it by more than {TOLERANCE}",
        "versions": versions(),
        "peers_from": args.peers_from,
        "values": "probability of the property's path formula (1 - p for Pmin)",
        "cpu_seconds": "user+sys of the child process and its children (getrusage deltas); "
                       f"a run of any tool under {SHORT_RUN} s of CPU: the median of {REPEATS} runs "
                       "after it, itself a warm-up (cpu_samples: the warm-up, then the "
                       f"{REPEATS} runs)",
    }
    with open(args.out, "w", newline="") as handle:
        handle.write("# " + json.dumps(settings) + "\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    with open(os.path.splitext(args.out)[0] + ".json", "w") as handle:
        json.dump({"settings": settings, "runs": records}, handle, indent=1)
    print(f"wrote {args.out}\n")
    print(markdown(rows, args.long_gd))


def markdown(rows, long_gd):
    """The table of results/README.md: one line per model and k
    (`long_gd`: the limit of the long GD runs)."""
    show = lambda r: "-" if r is None or r["value"] is None else f"{r['value']:.4f}"
    lines = ["| model | states | k | POMDP optimum | posg-fsc | CPU s | PAYNT | CPU s | Storm GD "
             "| CPU s | GD > best + 1e-4? | best | posg-fsc CPU / GD CPU |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    above = lambda r: " (above the optimum)" if r.get("above_pomdp_optimum") else ""
    cases = {}
    for r in rows:
        cases.setdefault((r["model"], r["states"], r["k"]), {})[r["tool"]] = r
    for (model, states, k), c in cases.items():
        posg, paynt, gd = c["posg-fsc"], c["paynt"], c["storm-gd"]
        beat = c.get("storm-gd>best")
        near = c.get("storm-gd>=best-0.01")
        paynt_text = show(paynt) + ("" if paynt["status"] == "optimal" else f" ({paynt['status']})")
        gd_text = show(gd) if gd["status"] == "reached-bound" else f"{gd['status']}"
        for label, run in [("", near), (f" in {long_gd} s", c.get("storm-gd>=best-0.01 (long)"))]:
            if run is not None:
                gd_text += (f"; within 1e-2{label}: {show(run)}" if run["status"] == "reached-bound"
                            else f"; not within 1e-2{label} ({run['status']})")
        beat_text = ("-" if beat is None else
                     f"yes: {show(beat)}{above(beat)}" if beat["status"] == "reached-bound" else
                     f"no ({beat['status']})")
        optimum = "-" if posg["pomdp_optimum"] is None else f"{posg['pomdp_optimum']:.4f}"
        lines.append(f"| {model} | {states} | {k} | {optimum} | {show(posg)} | "
                     f"{posg['cpu_seconds']} | "
                     f"{paynt_text} | {paynt['cpu_seconds']} | {gd_text} | {gd['cpu_seconds']} | "
                     f"{beat_text} | {posg['best']} | "
                     f"{'<= ' if posg['gd_cpu_is_lower_bound'] else ''}{posg['posg_cpu_over_gd_cpu']} |")
    return "\n".join(lines)


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "--gd-worker":
        gd_worker(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]))
    elif len(sys.argv) == 4 and sys.argv[1] == "--belief-worker":
        belief_worker(sys.argv[2], int(sys.argv[3]))
    else:
        main()
