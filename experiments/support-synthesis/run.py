#!/usr/bin/env python3
"""Support synthesis by SAT (docs/method.md section 7): sizes and times.

Question: how large are the SAT problems `posg-fsc support` solves, how long
do they take, and what do they decide, on the paper's grid family with its
own objective `GF goal & G !unsafe`?

For each grid (the paper's 3x2 grid, and n x n grids with the goal in the
far corner, `unsafe` next to the start and n*n/10 random unsafe cells, seed
1) and each defender size, it runs `posg-fsc support` in both modes
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
OUT = os.path.join(ROOT, "results", "support-synthesis.csv")


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


def support(game, nodes, mode, engine, directory):
    """Runs `posg-fsc support` and returns (command, support.json)."""
    out = os.path.join(directory, "out")
    command = [BINARY, "support", game, "--ltl", FORMULA, "--def-nodes", str(nodes),
               "--engine", engine, "--out", out, "--force"]
    if mode == "almost-sure":
        command.append("--almost-sure")
    if engine == "certificate":
        command.append("--no-maximise")
    subprocess.run(command, check=True, stderr=subprocess.DEVNULL)
    with open(os.path.join(out, "support.json")) as f:
        return command, json.load(f)


def main():
    cases = [(0, nodes, "lazy") for nodes in (1, 2, 3, 4)]
    cases += [(0, 1, "certificate"), (0, 2, "certificate")]
    cases += [(n, nodes, "lazy") for n in (4, 8, 16) for nodes in (1, 2, 3)]
    rows = []
    with tempfile.TemporaryDirectory() as directory:
        games = {n: grid(directory, n) for n in sorted({c[0] for c in cases})}
        for n, nodes, engine in cases:
            for mode in ("almost-sure", "positive"):
                command, result = support(games[n], nodes, mode, engine, directory)
                sat = result["sat"]
                rows.append({
                    "grid": "3x2 (paper)" if n == 0 else f"{n}x{n}",
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
                    "command": " ".join(os.path.basename(c) if c.endswith(".json") else c
                                        for c in command[1:]),
                    "version": result["version"],
                })
                print(rows[-1]["grid"], nodes, mode, engine, result["found"],
                      rows[-1]["seconds"], file=sys.stderr)
    with open(OUT, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {OUT}", file=sys.stderr)


if __name__ == "__main__":
    main()
