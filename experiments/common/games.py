"""Game files for the experiments.

`grid(...)` asks `posg-fsc example grid` for an instance of the paper's grid
family; while that command is not in the binary, it writes the same model
itself (src/game/grid.rs: moves R/L/U/D, attack A/NA, a move to the target
cell t succeeds with p_v and otherwise lands uniformly on ({s} + N(s)) - {t};
each player sees its true cell with p_obs, otherwise a uniform neighbour).
"""
import json
import os
import random
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The binary: $POSG_FSC if set, else the release build (made by `build()`).
BINARY = os.environ.get("POSG_FSC", os.path.join(ROOT, "target", "release", "posg-fsc"))
MOVES = [("R", 1, 0), ("L", -1, 0), ("U", 0, -1), ("D", 0, 1)]


def build():
    if "POSG_FSC" in os.environ:
        return
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)


def grid(path, width, height, unsafe, goal, labels=None, p_na=0.8, p_a=0.6, p_def=0.8, p_adv=0.6):
    """Writes a grid game to `path`: `unsafe` and `goal` are cell lists,
    `labels` maps extra propositions to cell lists."""
    labels = labels or {}
    command = [BINARY, "example", "grid", "--width", str(width), "--height", str(height),
               "--unsafe", ",".join(f"s{c}" for c in unsafe) or "none",
               "--goal", ",".join(f"s{c}" for c in goal), "--out", path]
    if not labels and subprocess.run(command, capture_output=True).returncode == 0:
        return
    with open(path, "w") as handle:
        json.dump(grid_json(width, height, unsafe, goal, labels, p_na, p_a, p_def, p_adv), handle)


def grid_json(width, height, unsafe, goal, labels, p_na, p_a, p_def, p_adv):
    cells = width * height

    def step(c, dx, dy):
        x, y = c % width + dx, c // width + dy
        return x + width * y if 0 <= x < width and 0 <= y < height else None

    neighbours = [[t for _, dx, dy in MOVES if (t := step(c, dx, dy)) is not None] for c in range(cells)]
    names = [f"s{c}" for c in range(cells)]

    def observe(p_obs):
        table = {}
        for c in range(cells):
            dist = {names[c]: p_obs} if neighbours[c] else {names[c]: 1.0}
            for n in neighbours[c]:
                dist[names[n]] = dist.get(names[n], 0.0) + (1 - p_obs) / len(neighbours[c])
            table[names[c]] = dist
        return table

    transitions = []
    for c in range(cells):
        for u, dx, dy in MOVES:
            t = step(c, dx, dy)
            for v, p in (("A", p_a), ("NA", p_na)):
                if t is None:
                    nxt = {names[c]: 1.0}
                else:
                    nxt = {names[t]: p}
                    for o in [c] + neighbours[c]:
                        if o != t:
                            nxt[names[o]] = nxt.get(names[o], 0.0) + (1 - p) / len(neighbours[c])
                transitions.append({"state": names[c], "defender": u, "adversary": v, "next": nxt})
    label_map = {}
    for prop, where in [("unsafe", unsafe), ("goal", goal)] + sorted(labels.items()):
        for c in where:
            label_map.setdefault(names[c], []).append(prop)
    return {
        "posg": 1, "name": f"grid-{width}x{height}", "states": names, "initial": {"s0": 1.0},
        "labels": label_map,
        "defender": {"actions": [m[0] for m in MOVES], "observations": names, "observe": observe(p_def)},
        "adversary": {"actions": ["A", "NA"], "observations": names, "observe": observe(p_adv)},
        "transitions": transitions,
    }


def solve(game, formula, out, def_nodes, adv_nodes, *settings):
    """Runs `posg-fsc solve` and returns its summary.json as a dict."""
    subprocess.run([BINARY, "solve", game, "--ltl", formula, "--def-nodes", str(def_nodes),
                    "--adv-nodes", str(adv_nodes), "--out", out, *map(str, settings)],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as handle:
        return json.load(handle)


def unsafe_cells(width, height, count, seed, keep):
    """`count` cells chosen reproducibly, avoiding the cells in `keep`."""
    free = [c for c in range(width * height) if c not in keep]
    return sorted(random.Random(seed).sample(free, count))
