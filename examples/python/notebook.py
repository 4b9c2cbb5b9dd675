"""The notebook a security engineer writes with posg-fsc, as a script (each
`# %%` is a cell for Jupyter, VS Code or Jupytext): load PAYNT's
attacker-one-defender game from Storm's DRN with its property, solve it
with the property's query, plot the convergence curve with pandas, compare
controller sizes, and check the returned defender by simulation.

Writes curve.png (with matplotlib), sizes.csv and simulation.json into
--out. Usage:

    python examples/python/notebook.py [--out DIR] [--max-iterations 300]

With a stormpy model instead of a file, `posg_fsc.Game.from_stormpy(model)`
gives the game.
"""

# %% Setup
import argparse
import json
from pathlib import Path

import pandas as pd

import posg_fsc

REPOSITORY = Path(__file__).resolve().parents[2]
MODEL = REPOSITORY / "tests" / "data" / "paynt" / "attacker-one-defender.drn"
QUERY = REPOSITORY / "tests" / "data" / "paynt" / "attacker-one-defender.props"

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--out", type=Path, default=Path("notebook-out"))
parser.add_argument("--max-iterations", type=int, default=300)
args = parser.parse_args()
args.out.mkdir(parents=True, exist_ok=True)
settings = dict(seed=1, max_iterations=args.max_iterations)

# %% Load the game and its query
game = posg_fsc.Game.from_drn(MODEL)
print(game, QUERY.read_text().strip())

# %% Solve: the defender of 2 nodes, its curve in out/solve/curve.csv
result = posg_fsc.solve(
    game, props=QUERY, def_nodes=2, out=args.out / "solve", force=True, progress=True,
    **settings,
)
print(result.query)  # the query in its own terms: Pmin, its value and bracket

# %% The certified bracket over time, with pandas: the best lower bound and
# the lowest upper bound that any start has proved so far (the starts'
# records interleave in curve.csv; `returned` marks the returned defender)
curve = pd.read_csv(args.out / "solve" / "curve.csv")
checks = curve.dropna(subset=["certified_lower"]).sort_values("seconds")
bracket = pd.DataFrame({
    "seconds": checks["seconds"],
    "best certified lower bound": checks["certified_lower"].cummax(),
    "game upper bound": checks["upper_bound"].cummin(),
})
assert bracket["best certified lower bound"].iloc[-1] == result.certified["certified_lower"]
try:
    import matplotlib

    matplotlib.use("Agg")
    axes = bracket.plot(x="seconds", drawstyle="steps-post", title=f"{MODEL.stem}, 2 nodes")
    axes.set_ylabel("P(the defender's objective), G !goal for Pmin F goal")
    axes.figure.savefig(args.out / "curve.png", dpi=120)
except ImportError:
    print("matplotlib is not installed: no curve.png")

# %% Compare controller sizes: each warm-started from the smaller one
rows = posg_fsc.sweep(game, props=QUERY, def_nodes=[1, 2], adv_nodes=1, **settings)
sizes = pd.DataFrame(rows).drop(columns=["solved"])
sizes.to_csv(args.out / "sizes.csv", index=False)
print(sizes[["defender_nodes", "certified_lower", "upper_bound", "result"]])

# %% Check the defender by simulation against its best response found
simulation = posg_fsc.simulate(
    game, props=QUERY, defender=result.defender, adversary=result.adversary, runs=20_000,
    seed=1,
)
(args.out / "simulation.json").write_text(json.dumps(simulation, indent=2))
print(simulation["estimate"], simulation["exact_value"])
