#!/usr/bin/env python3
"""How much posg-fsc's results on PAYNT's games depend on the seed.

Question: run.py solves each model with `--seed 1`; does posg-fsc reach
PAYNT's value for the same k with other seeds as well, or was seed 1 lucky?
The seed draws the starts of the gradient race and the restarts and kicks
of the local search (docs/method.md section 6), so two seeds can end at
different local optima of the certified lower bound.

For each model (by default those under 400 states, the "small models" of
the issue's 2 s target), k = 1, 2, 3 and each seed, the script runs
`posg-fsc solve sketch.templ --props sketch.props --def-nodes K --seed S`
(defaults otherwise) and records its certified lower bound and times;
PAYNT's values come from run.py's cached records (--work, filled by run.py
or from an earlier results CSV with --peers-from).

Writes results/paynt-posmg-seeds.csv (first line: command, versions), one
row per run, and prints a summary table (results/README.md quotes it): per
model and k, the lowest, median and highest certified lower bound over the
seeds and on how many seeds it is at least PAYNT's value (tolerance 1e-4;
not counted where PAYNT has no value). Each run's record is cached in
--work as posg-K-seedS.json; --fresh runs them again (after a rebuild).

Usage:
  venv/bin/python experiments/paynt-posmg/seeds.py --repo DIR \\
      --peers-from results/paynt-posmg.csv [--seeds 0 1 2 3 4 5 6 7]
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from run import (NODES, ROOT, TOLERANCE, BINARY, build, cached, defender,  # noqa: E402
                 prepare, prop_of, run_posg, seed_peer_records)

SMALL = ["test-game", "test-game2", "mec-test", "grid-walls", "dice-and-coin", "dice-and-coin2",
         "attacker-one-defender"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repo", help="git directory of a clone of randriu/synthesis")
    parser.add_argument("--work", default=os.path.join(ROOT, "target", "paynt-posmg"))
    parser.add_argument("--timeout", type=int, default=300, help="PAYNT's --timeout of the records")
    parser.add_argument("--peers-from", metavar="CSV",
                        help="take PAYNT's records from this earlier results CSV of run.py")
    parser.add_argument("--seeds", type=int, nargs="*", default=list(range(8)))
    parser.add_argument("--models", nargs="*", default=SMALL)
    parser.add_argument("--posg-limit", type=int, default=600,
                        help="posg-fsc runs are killed after this many seconds")
    parser.add_argument("--fresh", action="store_true",
                        help="run posg-fsc again where a record is cached")
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "paynt-posmg-seeds.csv"))
    args = parser.parse_args()
    if not args.seeds or not args.models:
        parser.error("no seeds or no models to run")
    models_dir = os.path.join(args.work, "models")
    prepare(models_dir, args.repo)
    if args.peers_from:
        seed_peer_records(args.peers_from, models_dir, args.timeout)
    build()
    rows = []
    for name in args.models:
        directory = os.path.join(models_dir, name)
        _, direction, _ = prop_of(directory)
        for k in NODES:
            paynt_record = os.path.join(directory, f"paynt-{k}-t{args.timeout}.json")
            if not os.path.exists(paynt_record):
                parser.error(f"no PAYNT record {paynt_record}: run run.py first or pass "
                             "--peers-from")
            with open(paynt_record) as handle:
                paynt = json.load(handle)
            theirs = defender(paynt["value"], direction)
            for seed in args.seeds:
                record = os.path.join(directory, f"posg-{k}-seed{seed}.json")
                if args.fresh and os.path.exists(record):
                    os.remove(record)
                out = os.path.join(directory, f"posg-fsc-{k}-seed{seed}")
                posg = cached(record, lambda: run_posg(directory, k, args.posg_limit, None, seed, out))
                ours = posg["certified_lower"]
                reached = None not in (ours, theirs) and ours >= theirs - TOLERANCE
                print(f"{name} k={k} seed {seed}: {ours} ({posg['wall_seconds']:.2f} s)", flush=True)
                rows.append({
                    "model": name, "k": k, "seed": seed, "posg_certified_lower": ours,
                    "posg_status": posg["status"], "posg_wall_s": round(posg["wall_seconds"], 2),
                    "posg_cpu_s": round(posg["cpu_seconds"], 2),
                    "paynt_defender_value": theirs, "paynt_status": paynt["status"],
                    "reaches_paynt": reached,
                })
    version = subprocess.run([BINARY, "--version"], capture_output=True, text=True).stdout.strip()
    with open(args.out, "w", newline="") as handle:
        handle.write(f"# {' '.join(sys.argv)}; {version}; posg-fsc: solve --props --def-nodes K "
                     f"--seed S, defaults otherwise; PAYNT 0.5.0 (--timeout {args.timeout}) from "
                     f"run.py's records; values are the defender's (1 - p for Pmin); reaches_paynt: "
                     f"at least PAYNT's value - {TOLERANCE:g}\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.out}\n")
    print(summary(rows))


def summary(rows):
    """Per model and k: PAYNT's value, posg-fsc's lowest, median and highest
    certified lower bound over the seeds, the seeds that reach PAYNT's value,
    and the slowest run's wall seconds."""
    show = lambda v: "-" if v is None else f"{v:.4f}"
    lines = ["| model | k | PAYNT | posg-fsc lowest | median | highest | seeds at PAYNT "
             "| slowest wall s |", "|---|---|---|---|---|---|---|---|"]
    groups = {}
    for r in rows:
        groups.setdefault((r["model"], r["k"]), []).append(r)
    for (model, k), runs in groups.items():
        values = [r["posg_certified_lower"] for r in runs if r["posg_certified_lower"] is not None]
        reached = sum(r["reaches_paynt"] for r in runs)
        lines.append(f"| {model} | {k} | {show(runs[0]['paynt_defender_value'])} | "
                     f"{show(min(values) if values else None)} | "
                     f"{show(statistics.median(values) if values else None)} | "
                     f"{show(max(values) if values else None)} | {reached} of {len(runs)} | "
                     f"{max(r['posg_wall_s'] for r in runs):.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
