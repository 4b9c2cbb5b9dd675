"""The optimiser's benchmark set (issue 12), built from public descriptions:

* `grid_pomdp(n)`: PRISM-style grid navigation POMDPs, n x n cells, a robot
  that moves north/east/south/west (probability 0.9 to the intended
  neighbour, 0.1 it stays; walls and the border block), interior wall cells,
  absorbing hazard cells and an absorbing goal in the bottom-right corner.
  The robot starts uniformly in the left column and observes only which of
  its four sides are blocked, or that it is on the goal or on a hazard.
  Objective `F goal`.
* `maze()`: the Littman-Cassandra maze (Littman, Cassandra and Kaelbling,
  "Learning policies for partially observable environments: scaling up",
  1995) in the 14-cell form with two traps:

      0  1  2  3  4
      5     6     7
      8     9    10
     11    13    12

  13 the goal, 11 and 12 absorbing traps, deterministic moves, uniform start
  over cells 0..12, observations of the surrounding walls (cells 1 and 3
  look alike, cells 5..10 look alike). `F goal` has optimum 11/13: from every
  cell but the traps a 2-node controller reaches the goal surely (climb to
  the top row, walk to cell 2, descend), and no controller leaves a trap.
* `concurrent_game(seed)`: small fully observable concurrent stochastic
  games, both players see the state, random transitions with probability at
  least 0.05 of stopping in an absorbing trap at every step (so the game
  stops surely and both players have optimal memoryless strategies:
  Shapley 1953). `game_value` computes the value of `F goal` by value
  iteration with a matrix-game linear programme (scipy) per state.
* `matrix_game(a, b, c, d)`: one state, the defender picks a row, the
  adversary a column, the goal is reached with the entry's probability (else
  a trap): the value is the 2x2 matrix game's.
"""
import json
import random

import numpy as np

DIRECTIONS = {"N": (0, -1), "E": (1, 0), "S": (0, 1), "W": (-1, 0)}


def grid_layout(n, slip=0.1):
    """Walls and hazards of the n x n grid (cells (x, y), y down), drawn
    reproducibly from n until the goal (n-1, n-1) is reachable from every
    start cell (the left column) and, under full observation, the best
    probability of `F goal` is between 0.5 and 0.95 (some risk of a hazard
    cannot be avoided, so a partially observing robot has work to do)."""
    rng = random.Random(1000 + n)
    goal = (n - 1, n - 1)
    while True:
        inner = [(x, y) for x in range(1, n) for y in range(n) if (x, y) != goal]
        count_walls = max(1, n // 3)
        picked = rng.sample(inner, count_walls + max(2, (n * n) // 5))
        walls = set(picked[:count_walls])
        hazards = set(picked[count_walls:])
        value = full_observation_value(n, walls, hazards, slip)
        starts = [(0, y) for y in range(n) if (0, y) not in hazards]
        if all(value[c] > 0 for c in starts):
            mean = sum(value[c] for c in starts) / len(starts)
            if 0.5 <= mean <= 0.95:
                return walls, hazards


def moves(n, walls, c, d, slip):
    """The successor distribution of cell c under direction d."""
    out = {}
    sides = "EW" if d in "NS" else "NS"
    for move, p in ((d, 1.0 - 2 * slip), (sides[0], slip), (sides[1], slip)):
        dx, dy = DIRECTIONS[move]
        t = (c[0] + dx, c[1] + dy)
        if not (0 <= t[0] < n and 0 <= t[1] < n) or t in walls:
            t = c
        out[t] = out.get(t, 0.0) + p
    return out


def full_observation_value(n, walls, hazards, slip):
    """max P(F goal) per cell of the fully observable grid (value iteration)."""
    goal = (n - 1, n - 1)
    cells = [(x, y) for x in range(n) for y in range(n) if (x, y) not in walls]
    value = {c: 1.0 if c == goal else 0.0 for c in cells}
    for _ in range(2000):
        change = 0.0
        for c in cells:
            if c == goal or c in hazards:
                continue
            best = max(sum(p * value[t] for t, p in moves(n, walls, c, d, slip).items())
                       for d in "NESW")
            change = max(change, abs(best - value[c]))
            value[c] = best
        if change < 1e-10:
            break
    return value


def grid_pomdp(n, slip=0.1):
    """The n x n grid POMDP as a posg.json dict."""
    walls, hazards = grid_layout(n, slip)
    goal = (n - 1, n - 1)
    cells = [(x, y) for y in range(n) for x in range(n) if (x, y) not in walls]
    name = {c: f"x{c[0]}y{c[1]}" for c in cells}

    def blocked(c, d):
        dx, dy = DIRECTIONS[d]
        t = (c[0] + dx, c[1] + dy)
        return not (0 <= t[0] < n and 0 <= t[1] < n) or t in walls

    def observation(c):
        if c == goal:
            return "goal"
        if c in hazards:
            return "hazard"
        return "walls-" + ("".join(d for d in "NESW" if blocked(c, d)) or "none")

    observations = sorted({observation(c) for c in cells})
    transitions = []
    for c in cells:
        if c == goal or c in hazards:
            transitions.append({"state": name[c], "defender": "*", "next": {name[c]: 1.0}})
            continue
        for d in "NESW":
            nxt = {name[t]: p for t, p in moves(n, walls, c, d, slip).items()}
            transitions.append({"state": name[c], "defender": d, "next": nxt})
    starts = [name[(0, y)] for y in range(n) if (0, y) not in hazards]
    return {
        "posg": 1,
        "name": f"grid-pomdp-{n}",
        "states": [name[c] for c in cells],
        "initial": {s: 1.0 / len(starts) for s in starts},
        "labels": {name[goal]: ["goal"], **{name[h]: ["hazard"] for h in sorted(hazards)}},
        "defender": {
            "actions": list("NESW"),
            "observations": observations,
            "observe": {name[c]: {observation(c): 1.0} for c in cells},
        },
        "transitions": transitions,
    }


MAZE_MOVES = {
    # cell: (north, east, south, west); a blocked move stays.
    0: (0, 1, 5, 0), 1: (1, 2, 1, 0), 2: (2, 3, 6, 1), 3: (3, 4, 3, 2), 4: (4, 4, 7, 3),
    5: (0, 5, 8, 5), 6: (2, 6, 9, 6), 7: (4, 7, 10, 7),
    8: (5, 8, 11, 8), 9: (6, 9, 13, 9), 10: (7, 10, 12, 10),
}
MAZE_OBSERVATIONS = {
    0: "NW", 1: "NS", 2: "N", 3: "NS", 4: "NE", 5: "EW", 6: "EW", 7: "EW",
    8: "EW", 9: "EW", 10: "EW", 11: "trap", 12: "trap", 13: "goal",
}


def maze():
    """The maze as a posg.json dict (optimum of `F goal`: 11/13)."""
    states = [f"s{i}" for i in range(14)]
    transitions = []
    for i in range(14):
        if i not in MAZE_MOVES:
            transitions.append({"state": f"s{i}", "defender": "*", "next": {f"s{i}": 1.0}})
            continue
        for action, target in zip("NESW", MAZE_MOVES[i]):
            transitions.append({"state": f"s{i}", "defender": action, "next": {f"s{target}": 1.0}})
    observations = sorted(set(MAZE_OBSERVATIONS.values()))
    return {
        "posg": 1,
        "name": "maze",
        "states": states,
        "initial": {f"s{i}": 1.0 / 13 for i in range(13)},
        "labels": {"s13": ["goal"], "s11": ["trap"], "s12": ["trap"]},
        "defender": {
            "actions": list("NESW"),
            "observations": observations,
            "observe": {f"s{i}": {MAZE_OBSERVATIONS[i]: 1.0} for i in range(14)},
        },
        "transitions": transitions,
    }


def concurrent_game(seed, states=4, actions=(2, 2), stop=0.05):
    """A random fully observable concurrent game (posg.json dict) and its
    matrices: `states` playing states, `goal` and `trap` absorbing."""
    rng = random.Random(seed)
    names = [f"s{i}" for i in range(states)] + ["goal", "trap"]
    transitions = []
    for i in range(states):
        for u in range(actions[0]):
            for v in range(actions[1]):
                targets = rng.sample(names[:states] + ["goal"], rng.randint(1, 3))
                weights = [rng.random() + 0.05 for _ in targets]
                total = sum(weights)
                stay = 1.0 - stop - rng.random() * 0.2
                nxt = {"trap": 1.0 - stay}
                for t, w in zip(targets, weights):
                    nxt[t] = nxt.get(t, 0.0) + stay * w / total
                transitions.append({"state": names[i], "defender": f"u{u}", "adversary": f"v{v}",
                                    "next": nxt})
    for absorbing in ("goal", "trap"):
        transitions.append({"state": absorbing, "defender": "*", "adversary": "*",
                            "next": {absorbing: 1.0}})
    return {
        "posg": 1,
        "name": f"concurrent-{seed}",
        "states": names,
        "initial": {"s0": 1.0},
        "labels": {"goal": ["goal"]},
        "defender": {"actions": [f"u{u}" for u in range(actions[0])], "observe": "full"},
        "adversary": {"actions": [f"v{v}" for v in range(actions[1])], "observe": "full"},
        "transitions": transitions,
    }


def matrix_game(a, b, c, d):
    """One state; rows H, T for the defender, columns H, T for the adversary;
    the goal is reached with probability [[a, b], [c, d]][row][column]."""
    entries = {("H", "H"): a, ("H", "T"): b, ("T", "H"): c, ("T", "T"): d}
    transitions = [{"state": "s", "defender": u, "adversary": v,
                    "next": {"goal": p, "trap": 1.0 - p}} for (u, v), p in entries.items()]
    transitions += [{"state": t, "defender": "*", "adversary": "*", "next": {t: 1.0}}
                    for t in ("goal", "trap")]
    return {
        "posg": 1,
        "name": f"matrix-{a}-{b}-{c}-{d}",
        "states": ["s", "goal", "trap"],
        "initial": {"s": 1.0},
        "labels": {"goal": ["goal"]},
        "defender": {"actions": ["H", "T"], "observe": "full"},
        "adversary": {"actions": ["H", "T"], "observe": "full"},
        "transitions": transitions,
    }


def matrix_value(matrix):
    """The value max_p min_q p^T M q of a matrix game (rows maximise), by LP."""
    from scipy.optimize import linprog
    m = np.asarray(matrix, dtype=float)
    rows, cols = m.shape
    # variables p_1..p_rows, v; maximise v s.t. sum_i p_i m_ij >= v, sum p = 1.
    c = np.zeros(rows + 1)
    c[-1] = -1.0
    a_ub = np.hstack([-m.T, np.ones((cols, 1))])
    a_eq = np.hstack([np.ones((1, rows)), np.zeros((1, 1))])
    result = linprog(c, A_ub=a_ub, b_ub=np.zeros(cols), A_eq=a_eq, b_eq=[1.0],
                     bounds=[(0, None)] * rows + [(None, None)], method="highs")
    assert result.success, result.message
    return -result.fun


def game_value(game, tolerance=1e-12):
    """The value of `F goal` from the initial state of a fully observable
    concurrent game dict (as built above), by value iteration with a
    matrix-game LP per state (Shapley)."""
    states = game["states"]
    dactions = game["defender"]["actions"]
    aactions = game["adversary"]["actions"]
    table = {}
    for t in game["transitions"]:
        table[(t["state"], t["defender"], t["adversary"])] = t["next"]
    value = {s: (1.0 if s == "goal" else 0.0) for s in states}
    for _ in range(100000):
        new = dict(value)
        for s in states:
            if s in ("goal", "trap"):
                continue
            matrix = [[sum(p * value[n] for n, p in table[(s, u, v)].items())
                       for v in aactions] for u in dactions]
            new[s] = matrix_value(matrix)
        change = max(abs(new[s] - value[s]) for s in states)
        value = new
        if change < tolerance:
            break
    return sum(p * value[s] for s, p in game["initial"].items())


def write(game, path):
    with open(path, "w") as handle:
        json.dump(game, handle, indent=1)
