"""Shared helpers of the optimiser's experiments: build the binary, write
grid games with `posg-fsc example grid`, run `posg-fsc solve`."""
import json
import os
import random
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The binary: $POSG_FSC if set, else the release build (made by `build()`).
BINARY = os.environ.get("POSG_FSC", os.path.join(ROOT, "target", "release", "posg-fsc"))


def build():
    if "POSG_FSC" in os.environ:
        return
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)


def grid(path, width, height, unsafe, goal, labels=None):
    """Writes a grid game of the paper's family (`posg-fsc example grid`,
    default probabilities) to `path`: `unsafe` and `goal` are cell lists,
    `labels` maps extra propositions to cell lists."""
    cells = lambda where: ",".join(f"s{c}" for c in where)
    command = [BINARY, "example", "grid", "--width", str(width), "--height", str(height),
               "--unsafe", cells(unsafe), "--goal", cells(goal), "--out", path]
    for name, where in sorted((labels or {}).items()):
        command += ["--label", f"{name}={cells(where)}"]
    subprocess.run(command, check=True)


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
