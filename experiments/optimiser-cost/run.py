"""What the optimiser's parts cost: `solve` under several builds or options
on the same POMDPs, one run each in turn, certified lower bound and CPU.

    python3 experiments/optimiser-cost/run.py \
        --config "s54=/path/to/posg-fsc-of-stop-54" \
        --config "now=target/release/posg-fsc" \
        --config "no-informed=target/release/posg-fsc --structures full,sat,paper" \
        --peers-models target/pomdp-peers/models --models refuel-06,crypt-4,drone-4-1 \
        --csv results/optimiser-cost-stop66.csv

The PRISM grid POMDPs of experiments/time-to-quality (`F goal`, n = 6, 8,
10) are written into `--work`; `--peers-models` is the `models/` directory
of an experiments/pomdp-peers run (each model's `model.drn` and
`sketch.props`). Every case runs with K = 1, 2, 3 defender nodes and the
defaults otherwise. CPU is user+sys of the child process (getrusage).
"""

import argparse
import csv
import importlib.util
import json
import os
import resource
import shlex
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(HERE, "..", "benchmarks"))


def time_to_quality():
    """experiments/time-to-quality/run.py as a module (its grid POMDPs)."""
    path = os.path.join(HERE, "..", "time-to-quality", "run.py")
    spec = importlib.util.spec_from_file_location("time_to_quality", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def cases(work, peers_models, models):
    """(name, model arguments, K) of every case."""
    ttq = time_to_quality()
    out = []
    for n in (6, 8, 10):
        path = os.path.join(work, f"pomdp-grid{n}.posg.json")
        ttq.write(ttq.grid_pomdp(n), path)
        out += [(f"pomdp-grid{n}", [path, "--ltl", "F goal"], k) for k in (1, 2, 3)]
    for model in models:
        directory = os.path.join(peers_models, model)
        arguments = [os.path.join(directory, "model.drn"), "--props",
                     os.path.join(directory, "sketch.props")]
        out += [(model, arguments, k) for k in (1, 2, 3)]
    return out


def solve(binary, options, model, k, out):
    """One run: its certified lower bound, structure, CPU and wall seconds."""
    command = [binary, "solve", *model, "--def-nodes", str(k), "--out", out, "--force",
               "--quiet", *options]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.time()
    done = subprocess.run(command, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    certified, structure = None, f"exit {done.returncode}: {done.stderr.strip()[-200:]}"
    if done.returncode == 0:
        with open(os.path.join(out, "summary.json")) as handle:
            summary = json.load(handle)
        certified = (summary.get("certified") or {}).get("certified_lower")
        structure = summary["structure_used"]
    return certified, structure, round(cpu, 2), round(time.time() - started, 2)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--config", action="append", required=True,
                        help="NAME=BINARY [OPTIONS...]: a build and the options it runs with")
    parser.add_argument("--peers-models", required=True)
    parser.add_argument("--models", default="refuel-06,crypt-4,drone-4-1")
    parser.add_argument("--work", default=os.path.join(HERE, "..", "..", "target", "optimiser-cost"))
    parser.add_argument("--csv", required=True)
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    configs = []
    for spec in args.config:
        name, command = spec.split("=", 1)
        binary, *options = shlex.split(command)
        configs.append((name, binary, options))
    with open(args.csv, "w", newline="") as handle:
        handle.write("# " + " ".join(shlex.quote(a) for a in sys.argv) + "\n")
        writer = csv.writer(handle)
        writer.writerow(["case", "k", "config", "certified_lower", "structure", "cpu_seconds",
                         "wall_seconds"])
        for name, model, k in cases(args.work, args.peers_models, args.models.split(",")):
            for config, binary, options in configs:
                out = os.path.join(args.work, f"out-{config}")
                row = [name, k, config, *solve(binary, options, model, k, out)]
                writer.writerow(row)
                handle.flush()
                print(row, flush=True)


if __name__ == "__main__":
    main()
