#!/usr/bin/env python3
"""Expected rewards of `posg-fsc eval` against Storm and exact rationals.

Question: is the expected total reward until a target that posg-fsc
computes (`R{"r"}min=? [F "goal"]`, docs/method.md section 9) the one
Storm computes, and the exact one?

For 60 random small games with rewards of both signs (seeded; half with a
trap state, so that some values are infinite), each under a controller pair
(`uniform:1` or `uniform:2` per player), it runs `posg-fsc eval --props`,
exports the chain with `posg-fsc export-gmc` (chain.drn carries the
one-step rewards) and computes `R{"r"}=? [F "goal"]` in its fresh initial
state twice: with Storm (sound mode, Eigen's sparse LU; the recipe of
experiments/storm-check) and with exact rational arithmetic on the
exported numbers (Python's fractions: qualitative analysis by graph
search, then Gaussian elimination). Writes results/reward-check.csv and
exits non-zero when a finite value differs from the exact one by more than
1e-9 relative, or when the three disagree on which values are infinite.

Usage: pip install stormpy==2.0.0; python3 experiments/reward-check/run.py [--binary PATH]
"""
import argparse
import csv
import json
import os
import random
import subprocess
import sys
import tempfile
from fractions import Fraction

import stormpy
import stormpy.developer

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CASES = 60
TOLERANCE = 1e-9


def distribution(rng, outcomes):
    """A random distribution over some of `outcomes` (at least one)."""
    chosen = rng.sample(outcomes, rng.randint(1, min(3, len(outcomes))))
    weights = [rng.randint(1, 9) for _ in chosen]
    return {o: w / sum(weights) for o, w in zip(chosen, weights)}


def random_game(seed):
    """A game as JSON: 3-9 states, 1-2 goal states, observations, an
    adversary in 2 of 3 games, a trap in half of them, rewards of both signs."""
    rng = random.Random(seed)
    states = [f"s{i}" for i in range(rng.randint(3, 9))]
    goals = rng.sample(states[1:], rng.randint(1, 2))
    others = [s for s in states if s not in goals]
    trap = rng.choice(others[1:]) if rng.random() < 0.5 and len(others) > 1 else None

    def player(prefix):
        actions = [f"{prefix}{i}" for i in range(rng.randint(1, 3))]
        observations = [f"{prefix}o{i}" for i in range(rng.randint(1, 3))]
        observe = {s: distribution(rng, observations) for s in states}
        return {"actions": actions, "observations": observations, "observe": observe}

    defender = player("u")
    adversary = player("v") if rng.random() < 2 / 3 else None
    adversary_actions = adversary["actions"] if adversary else ["*"]
    transitions, action_rewards = [], []
    for s in states:
        for u in defender["actions"]:
            for v in adversary_actions:
                nxt = {s: 1.0} if s == trap else distribution(rng, states)
                transitions.append({"state": s, "defender": u, "adversary": v, "next": nxt})
                if rng.random() < 0.5:
                    action_rewards.append({"state": s, "defender": u, "adversary": v,
                                           "reward": rng.randint(-20, 40) / 8})
    game = {
        "posg": 1, "name": f"reward-{seed}", "states": states, "initial": {states[0]: 1.0},
        "labels": {g: ["goal"] for g in goals}, "defender": defender, "transitions": transitions,
        "rewards": {"r": {"states": {s: rng.randint(-20, 40) / 8 for s in states if rng.random() < 0.6},
                          "actions": action_rewards}},
    }
    if adversary:
        game["adversary"] = adversary
    return game, rng.choice(["uniform:1", "uniform:2"]), rng.choice(["uniform:1", "uniform:2"]) if adversary else "uniform:1"


def storm_value(drn_file):
    """R{"r"}=? [F "goal"] in state 0 with Storm in sound mode (Eigen's sparse LU)."""
    model = stormpy.build_model_from_drn(drn_file)
    prop = stormpy.parse_properties('R{"r"}=? [F "goal"]')[0]
    env = stormpy.Environment()
    env.solver().force_soundness = True
    env.solver().set_linear_equation_solver_type(stormpy.developer.EquationSolverType.EIGEN)
    return model_value(stormpy.model_checking(model, prop, environment=env), model)


def model_value(result, model):
    return float(result.get_value(model.initial_states[0]))


def read_chain(drn_file):
    """States of chain.drn: (labels, reward, [(target, probability)]), exact."""
    chain, current = [], None
    with open(drn_file) as handle:
        lines = handle.read().split("@model\n", 1)[1].splitlines()
    for line in lines:
        if line.startswith("state "):
            words = line.split()
            reward = Fraction(0)
            if "[" in line:
                reward = Fraction(line[line.index("[") + 1:line.index("]")].split(",")[0].strip())
                words = line[:line.index("[")].split() + line[line.index("]") + 1:].split()
            current = (set(words[2:]), reward, [])
            chain.append(current)
        elif " : " in line:
            target, p = line.split(" : ")
            current[2].append((int(target), Fraction(p.strip())))
    return chain


def exact_value(drn_file):
    """R=? [F goal] in state 0 by exact rationals: infinite where goal can be
    missed (graph search with goal states absorbing), else Gaussian elimination."""
    chain = read_chain(drn_file)
    n = len(chain)
    goal = [("goal" in labels) for labels, _, _ in chain]
    successors = [[t for t, p in row if p > 0] if not goal[i] else [] for i, (_, _, row) in enumerate(chain)]

    def reachable(start):
        seen, stack = {start}, [start]
        while stack:
            for t in successors[stack.pop()]:
                if t not in seen:
                    seen.add(t)
                    stack.append(t)
        return seen

    reach = [reachable(i) for i in range(n)]
    hits = [any(goal[t] for t in reach[i]) for i in range(n)]
    infinite = [any(not hits[t] for t in reach[i]) for i in range(n)]
    if infinite[0]:
        return float("inf")
    unknown = [i for i in sorted(reach[0]) if not goal[i]]
    index = {m: k for k, m in enumerate(unknown)}
    k = len(unknown)
    a = [[Fraction(int(i == j)) for j in range(k)] + [chain[m][1]] for i, m in enumerate(unknown)]
    for i, m in enumerate(unknown):
        for t, p in chain[m][2]:
            if t in index:
                a[i][index[t]] -= p
    for col in range(k):
        pivot = next(r for r in range(col, k) if a[r][col] != 0)
        a[col], a[pivot] = a[pivot], a[col]
        for r in range(k):
            if r != col and a[r][col] != 0:
                factor = a[r][col] / a[col][col]
                a[r] = [x - factor * y for x, y in zip(a[r], a[col])]
    return float(a[index[0]][k] / a[index[0]][index[0]])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "posg-fsc"))
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "reward-check.csv"))
    args = parser.parse_args()
    rows, failures = [], 0
    with tempfile.TemporaryDirectory() as tmp:
        props = os.path.join(tmp, "r.props")
        with open(props, "w") as handle:
            handle.write('R{"r"}min=? [F "goal"]\n')
        for seed in range(1, CASES + 1):
            game, defender, adversary = random_game(seed)
            path = os.path.join(tmp, f"{seed}.posg.json")
            with open(path, "w") as handle:
                json.dump(game, handle)
            controllers = ["--defender", defender, "--adversary", adversary]
            done = subprocess.run([args.binary, "eval", path, "--props", props, *controllers],
                                  check=True, capture_output=True, text=True)
            ours = float(json.loads(done.stdout)["query"]["value"])
            chain = os.path.join(tmp, f"chain-{seed}")
            subprocess.run([args.binary, "export-gmc", path, *controllers, "--out", chain],
                           check=True, capture_output=True)
            drn = os.path.join(chain, "chain.drn")
            storm, exact = storm_value(drn), exact_value(drn)
            if exact == float("inf"):
                ok = ours == storm == exact
                difference = 0.0 if ok else float("inf")
            else:
                difference = abs(ours - exact) / max(1.0, abs(exact))
                ok = difference <= TOLERANCE and storm != float("inf")
            failures += not ok
            rows.append({"seed": seed, "states": len(game["states"]), "adversary": "adversary" in game,
                         "defender_controller": defender, "adversary_controller": adversary,
                         "posg_fsc": ours, "storm": storm, "exact": exact,
                         "relative_difference_to_exact": difference,
                         "storm_relative_difference_to_exact":
                             0.0 if exact == float("inf") and storm == exact
                             else abs(storm - exact) / max(1.0, abs(exact)),
                         "agree": ok})
    with open(args.out, "w", newline="") as handle:
        version = subprocess.run([args.binary, "--version"], capture_output=True, text=True).stdout.strip()
        handle.write(f"# {' '.join(sys.argv)}; {version}; stormpy {stormpy.__version__}\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    finite = [r for r in rows if r["exact"] != float("inf")]
    print(f"{len(rows)} chains ({len(finite)} finite, {len(rows) - len(finite)} infinite); "
          f"largest relative difference to exact: posg-fsc "
          f"{max(r['relative_difference_to_exact'] for r in finite):.2e}, Storm "
          f"{max(r['storm_relative_difference_to_exact'] for r in finite):.2e}; {failures} failures")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
