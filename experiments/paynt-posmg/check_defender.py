"""The exact value of a posg-fsc defender on a PAYNT POSMG, computed without
posg-fsc: a check of its certified lower bound.

    python3 check_defender.py sketch.templ defender.fsc.json [--label goal]

The game is PAYNT's DRN file (`state N {obs} <player>`, player 0 the
defender, the query `<<0>> Pmin=? [F "goal"]`), the controller a
`*.fsc.json` written by `posg-fsc solve` on it (docs/formats.md sections 2
and 6): in player 0's states the defender draws (next node, action) from
its rule for (node, `o<obs>`), in the opponent's states the rule for (node,
`opponent`) moves its node only. The product of the two is an MDP on
(state, node) in which the opponent, who sees both, maximises the
probability of reaching the label; the defender's value is 1 minus that
maximum, from the controller's initial node distribution. The
controller's probabilities are taken as the exact rationals of their
doubles. It is computed in exact rationals by policy
iteration, from a policy that reaches the label with positive probability
wherever the maximum is positive (the attractor's), switching only on
strict gains, which keeps that property and ends at the maximum (Baier and
Katoen, Principles of Model Checking, section 10.6). Python's standard
library only; a few seconds for a product of a few hundred states.
"""
import argparse
import json
import re
from fractions import Fraction


def read_drn(path):
    """{state: (observation, player, labels, {action: [(successor, p)]})}."""
    states, current, action = {}, None, None
    for line in open(path):
        header = re.match(r"state (\d+) \{(\d+)\} <(\d+)>(.*)", line)
        if header:
            current = int(header[1])
            states[current] = (int(header[2]), int(header[3]), header[4].split(), {})
            continue
        named = re.match(r"\s+action (\S+)", line)
        if named and current is not None:
            action = named[1]
            states[current][3][action] = []
            continue
        move = re.match(r"\s+(\d+) : (\S+)", line)
        if move and current is not None:
            states[current][3][action].append((int(move[1]), Fraction(move[2])))
    return states


def read_rules(path):
    """The controller's initial {node: p} and {(node, observation): [(next,
    action, p)]}."""
    fsc = json.load(open(path))
    rules = {(rule["node"], rule["observation"]):
             [(c["next"], c["action"], Fraction(c["p"])) for c in rule["choices"]]
             for rule in fsc["rules"]}
    initial = {g: Fraction(p) for g, p in enumerate(fsc["initial"]) if p > 0}
    return initial, rules


def product(states, initial, rules):
    """The reachable product MDP: its initial distribution {pair: p} and
    {pair: [distribution]} (a successor may repeat within a distribution)."""
    def actions(s, g):
        observation, player, _, moves = states[s]
        if player == 0:
            return [[((t, h), q * p) for h, action, q in rules[(g, f"o{observation}")]
                     for t, p in moves[action]]]
        updates = rules[(g, "opponent")]
        return [[((t, h), q * p) for h, _, q in updates for t, p in moves[a]] for a in moves]
    state = next(s for s, d in states.items() if "init" in d[2])
    start = {(state, g): p for g, p in initial.items()}
    order = list(start)
    mdp, seen = {}, set(order)
    for pair in order:
        mdp[pair] = actions(*pair)
        for distribution in mdp[pair]:
            for successor, _ in distribution:
                if successor not in seen:
                    seen.add(successor)
                    order.append(successor)
    return start, mdp


def solve(maybe, goal, policy, mdp):
    """The exact reachability probabilities of `policy` on `maybe` (0 where it
    cannot reach `goal`)."""
    reaching = set(goal)
    grew = True
    while grew:
        grew = False
        for v in maybe:
            if v not in reaching and any(w in reaching for w, _ in mdp[v][policy[v]]):
                reaching.add(v)
                grew = True
    unknowns = [v for v in maybe if v in reaching]
    index = {v: i for i, v in enumerate(unknowns)}
    n = len(unknowns)
    rows = []
    for v in unknowns:
        row = [Fraction(0)] * (n + 1)
        row[index[v]] += 1
        for w, p in mdp[v][policy[v]]:
            if w in goal:
                row[n] += p
            elif w in index:
                row[index[w]] -= p
        rows.append(row)
    for c in range(n):
        pivot = next(r for r in range(c, n) if rows[r][c] != 0)
        rows[c], rows[pivot] = rows[pivot], rows[c]
        rows[c] = [x / rows[c][c] for x in rows[c]]
        for r in range(n):
            if r != c and rows[r][c] != 0:
                factor = rows[r][c]
                rows[r] = [a - factor * b for a, b in zip(rows[r], rows[c])]
    values = {v: Fraction(0) for v in maybe}
    values.update({v: rows[index[v]][n] for v in unknowns})
    return values


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("game", help="PAYNT's DRN file (sketch.templ)")
    parser.add_argument("defender", help="a deterministic *.fsc.json of posg-fsc solve")
    parser.add_argument("--label", default="goal", help="the label of Pmin=? [F label]")
    args = parser.parse_args()
    states = read_drn(args.game)
    start, mdp = product(states, *read_rules(args.defender))
    goal = {v for v in mdp if args.label in states[v[0]][2]}
    attractor, policy = set(goal), {}
    grew = True
    while grew:
        grew = False
        for v in mdp:
            if v in attractor:
                continue
            for a, distribution in enumerate(mdp[v]):
                if any(w in attractor for w, _ in distribution):
                    attractor.add(v)
                    policy[v] = a
                    grew = True
                    break
    maybe = [v for v in mdp if v in attractor and v not in goal]
    value = lambda values, w: Fraction(1) if w in goal else values.get(w, Fraction(0))
    rounds = 0
    while True:
        rounds += 1
        values = solve(maybe, goal, policy, mdp)
        switched = False
        for v in maybe:
            gain = lambda a: sum(p * value(values, w) for w, p in mdp[v][a])
            best = max(range(len(mdp[v])), key=gain)
            if gain(best) > gain(policy[v]):
                policy[v], switched = best, True
        if not switched:
            break
    top = sum(p * value(values, v) for v, p in start.items())
    print(json.dumps({
        "product_states": len(mdp), "policy_iteration_rounds": rounds,
        "opponent_max_probability": float(top), "defender_value": float(1 - top),
        "defender_value_exact": str(1 - top),
    }, indent=1))


if __name__ == "__main__":
    main()
