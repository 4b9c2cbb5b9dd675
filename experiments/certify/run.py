#!/usr/bin/env python3
"""Certified brackets and the cost of certification.

Questions: (1) on the paper's 3x2 grid, what do the best defenders of sizes
1..3 found by `posg-fsc solve` guarantee against every adversary, and how
far is that from the game upper bound? (2) how long does `posg-fsc certify`
take next to `posg-fsc eval` on a 64x64 grid with 2-node controllers?
Writes results/certify-bracket.csv and results/certify-timing.csv.

Usage: python3 experiments/certify/run.py
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BINARY = os.environ.get("POSG_FSC", os.path.join(ROOT, "target", "release", "posg-fsc"))
FORMULAS = ["!unsafe U goal", "GF goal & G !unsafe"]


def run(*args):
    return subprocess.run([BINARY, *args], check=True, capture_output=True, text=True).stdout


def timed(*args):
    done = subprocess.run(["/usr/bin/time", "-v", BINARY, *args], check=True, capture_output=True, text=True)
    lines = done.stderr.splitlines()
    peak = next(int(l.split(":")[1]) for l in lines if "Maximum resident set size" in l) / 1024 / 1024
    wall = next(l.split(": ")[1] for l in lines if "Elapsed (wall clock)" in l)
    minutes, seconds = wall.split(":")[-2:]
    return float(minutes) * 60 + float(seconds), peak


def write(name, rows):
    with open(os.path.join(ROOT, "results", name), "w", newline="") as handle:
        handle.write(f"# {' '.join(sys.argv)}\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def main():
    if "POSG_FSC" not in os.environ:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    with tempfile.TemporaryDirectory() as tmp:
        game = os.path.join(tmp, "grid.posg.json")
        run("example", "grid", "--out", game)
        rows = []
        for formula in FORMULAS:
            for nodes in [1, 2, 3]:
                out = os.path.join(tmp, f"solve-{nodes}")
                run("solve", game, "--ltl", formula, "--def-nodes", str(nodes), "--adv-nodes", "1",
                    "--seed", "1", "--out", out)
                summary = json.load(open(os.path.join(out, "summary.json")))
                rows.append({"formula": formula, "defender_nodes": nodes, "adversary_nodes": 1,
                             "structure": summary["structure_used"], "worst_case_estimate": summary["worst_case"],
                             "certified_lower": summary["certified"]["certified_lower"],
                             "upper_bound": summary["certified"]["upper_bound"]})
        write("certify-bracket.csv", rows)
        big = os.path.join(tmp, "grid64.posg.json")
        run("example", "grid", "--width", "64", "--height", "64", "--unsafe", "none", "--goal", "s4095",
            "--random-unsafe", "204", "--seed", "1", "--out", big)
        timing = []
        for repeat in range(3):
            common = [big, "--ltl", "!unsafe U goal", "--defender", "uniform:2"]
            eval_seconds, eval_peak = timed("eval", *common, "--adversary", "uniform:2")
            certify_seconds, certify_peak = timed("certify", *common, "--adversary", "uniform:2")
            timing.append({"repeat": repeat, "eval_seconds": eval_seconds, "eval_peak_gib": eval_peak,
                           "certify_seconds": certify_seconds, "certify_peak_gib": certify_peak,
                           "ratio": certify_seconds / eval_seconds})
        write("certify-timing.csv", timing)
    for row in rows:
        print(row)
    for row in timing:
        print(row)


if __name__ == "__main__":
    main()
