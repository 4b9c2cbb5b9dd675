#!/usr/bin/env python3
"""The best deterministic memoryless controller of a small POMDP for an
expected-reward query, by enumeration, each evaluated exactly by
`posg-fsc eval`.

Question: is a value a 1-node FSC synthesiser reports attainable at all by
a deterministic memoryless controller? PAYNT synthesises exactly such
controllers with `--fsc-memory-size 1`; this enumerates every one of them
(one enabled action per observation, at most --limit combinations) and
prints the best value and its controller.

Usage: python3 experiments/rewards/brute_force.py MODEL.drn SKETCH.props [--binary PATH]
"""
import argparse
import itertools
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model")
    parser.add_argument("props")
    parser.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "posg-fsc"))
    parser.add_argument("--limit", type=int, default=20000)
    args = parser.parse_args()
    game = json.loads(subprocess.run([args.binary, "import-drn", args.model], check=True,
                                     capture_output=True, text=True).stdout)
    defender = game["defender"]
    observations = defender.get("observations") or sorted({o for row in defender["observe"].values()
                                                          for o in row})
    enabled = defender.get("enabled", {})
    choices = [enabled.get(o, defender["actions"]) for o in observations]
    count = math.prod(len(c) for c in choices)
    if count > args.limit:
        sys.exit(f"{count} controllers: more than --limit {args.limit}")
    maximise = "max=?" in open(args.props).read()
    best = None
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "d.fsc.json")
        for combination in itertools.product(*choices):
            rules = [{"node": 0, "observation": o, "choices": [{"next": 0, "action": a, "p": 1.0}]}
                     for o, a in zip(observations, combination)]
            with open(path, "w") as handle:
                json.dump({"fsc": 1, "player": "defender", "nodes": 1, "initial": [1.0],
                           "rules": rules, "default": "error"}, handle)
            done = subprocess.run([args.binary, "eval", args.model, "--props", args.props,
                                   "--defender", path], capture_output=True, text=True)
            if done.returncode != 0:
                continue
            value = float(json.loads(done.stdout)["query"]["value"])
            if best is None or (value > best[0] if maximise else value < best[0]):
                best = (value, dict(zip(observations, combination)))
    print(json.dumps({"controllers": count, "best_value": best[0], "best": best[1]}))


if __name__ == "__main__":
    main()
