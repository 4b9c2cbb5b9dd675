#!/usr/bin/env python3
"""Support synthesis by SAT (docs/method.md section 7): sizes and times.

Question: how large are the SAT problems `posg-fsc support` solves, how long
do they take, and what do they decide, on the paper's grid family with its
own objective `GF goal & G !unsafe`?

For each grid (the paper's 3x2 grid, and n x n grids with the goal in the
far corner, `unsafe` next to the start and n*n/10 random unsafe cells, seed
1) and each defender size, and for the 8x8 grid POMDP of the optimiser's
benchmarks (walls, hazards, `F goal` and `!hazard U goal`, 3 nodes), it runs `posg-fsc support` in both modes
(almost-sure, positive) with the default (lazy) engine, and on the smallest
cases also with the certificate engine (without maximisation, which takes
it minutes), and records what support.json
says: found, exact, certified lower bound, support entries, SAT variables,
clauses, calls, lemmas and seconds.

Writes results/support-synthesis.csv (one row per run, with the command and
the posg-fsc version in every row). Needs the release build
(`cargo build --release`). Usage: python3 experiments/support-synthesis/run.py
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
BINARY = os.path.join(ROOT, "target", "release", "posg-fsc")
FORMULA = "GF goal & G !unsafe"
sys.path.insert(0, os.path.join(ROOT, "experiments", "benchmarks"))
import games as benchmark_games  # noqa: E402
OUT = os.path.join(ROOT, "results", "support-synthesis.csv")
BUDGET = 60  # seconds per question; a run that needs more is recorded as "time budget"


def grid(directory, n):
    """The game file of an n x n grid of the paper's family (n = 0: the
    paper's own 3x2 grid)."""
    path = os.path.join(directory, f"grid{n}.posg.json")
    if n == 0:
        args = []
    else:
        args = ["--width", str(n), "--height", str(n), "--goal", f"s{n * n - 1}",
                "--unsafe", f"s{n + 1}", "--random-unsafe", str(n * n // 10), "--seed", "1"]
    subprocess.run([BINARY, "example", "grid", *args, "--out", path], check=True)
    return path


def support(game, nodes, mode, engine, directory, formula=FORMULA):
    """Runs `posg-fsc support` and returns (command, support.json)."""
    out = os.path.join(directory, "out")
    command = [BINARY, "support", game, "--ltl", formula, "--def-nodes", str(nodes),
               "--engine", engine, "--out", out, "--force"]
    if mode == "almost-sure":
        command.append("--almost-sure")
    if engine == "certificate":
        command.append("--no-maximise")
    command += ["--synthesis-time-budget", str(BUDGET)]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        if "time budget" in done.stderr:
            return command, None
        sys.exit(done.stderr)
    with open(os.path.join(out, "support.json")) as f:
        return command, json.load(f)


def shown(command, directory):
    """The command without the binary's path, with scratch paths as bare names."""
    return " ".join(os.path.basename(c) if c.startswith(directory) else c for c in command[1:])


def main():
    cases = [(0, nodes, "lazy") for nodes in (1, 2, 3, 4)]
    cases += [(0, 1, "certificate"), (0, 2, "certificate")]
    cases += [(n, nodes, "lazy") for n in (4, 8, 16) for nodes in (1, 2, 3)]
    rows = []
    with tempfile.TemporaryDirectory() as directory:
        games = {n: grid(directory, n) for n in sorted({c[0] for c in cases})}
        games["pomdp8"] = os.path.join(directory, "pomdp8.posg.json")
        benchmark_games.write(benchmark_games.grid_pomdp(8), games["pomdp8"])
        runs = [(games[n], "3x2 (paper)" if n == 0 else f"{n}x{n}", nodes, engine, FORMULA)
                for n, nodes, engine in cases]
        runs += [(games["pomdp8"], "8x8 POMDP", 3, "lazy", formula)
                 for formula in ("F goal", "!hazard U goal")]
        for game, label, nodes, engine, formula in runs:
            for mode in ("almost-sure", "positive"):
                command, result = support(game, nodes, mode, engine, directory, formula)
                if result is None:
                    rows.append({"grid": label, "formula": formula, "defender_nodes": nodes,
                                 "mode": mode, "engine": engine, "found": "time budget",
                                 "seconds": BUDGET, "command": shown(command, directory)})
                    print(label, nodes, mode, engine, "time budget", file=sys.stderr)
                    continue
                sat = result["sat"]
                rows.append({
                    "grid": label,
                    "formula": formula,
                    "defender_nodes": nodes,
                    "mode": mode,
                    "engine": engine,
                    "maximised": engine != "certificate",
                    "found": result["found"],
                    "exact": result["exact"],
                    "certified_lower": result["certified_lower"],
                    "support_entries": result["support_entries"],
                    "confirmation": result["confirmation"],
                    "variables": sat["variables"],
                    "clauses": sat["clauses"],
                    "product_states": sat["product_states"],
                    "calls": sat["calls"],
                    "judged": sat["judged"],
                    "lemmas": sat["lemmas"],
                    "sat_seconds": round(sat["solve_seconds"], 4),
                    "seconds": round(sat["seconds"], 4),
                    "command": shown(command, directory),
                    "version": result["version"],
                })
                print(rows[-1]["grid"], nodes, mode, engine, result["found"],
                      rows[-1]["seconds"], file=sys.stderr)
    with open(OUT, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]), restval="")
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {OUT}", file=sys.stderr)


if __name__ == "__main__":
    main()
