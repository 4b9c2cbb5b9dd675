#!/usr/bin/env python3
"""Cost of the adjoint gradient against one value evaluation and against
finite differences (one solve per parameter), from `benches/gradient.rs`.

Question: does value + gradient cost at most 3x one value evaluation, and
does the advantage over finite differences grow with the number of
parameters? Runs `cargo bench --bench gradient` (unless --no-run), reads
criterion's mean estimates and writes results/gradient-cost.csv and
results/gradient-cost.md.

Usage: python3 experiments/gradient-cost/run.py [--no-run]
"""
import argparse
import csv
import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CRITERION = os.path.join(ROOT, "target", "criterion", "gradient")
KINDS = ("value", "value_and_gradient", "finite_differences")


def mean_seconds(kind, case):
    with open(os.path.join(CRITERION, kind, case, "new", "estimates.json")) as handle:
        return json.load(handle)["mean"]["point_estimate"] * 1e-9


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-run", action="store_true", help="only read existing criterion estimates")
    args = parser.parse_args()
    if not args.no_run:
        subprocess.run(["cargo", "bench", "--bench", "gradient"], cwd=ROOT, check=True)
    cases = sorted(os.listdir(os.path.join(CRITERION, "value")), key=lambda c: int(c.split("-p")[-1]))
    rows = []
    for case in cases:
        if case == "report":
            continue
        grid, def_nodes, adv_nodes, parameters = case.split("-")
        value, gradient, fd = (mean_seconds(kind, case) for kind in KINDS)
        rows.append({"grid": grid, "defender_nodes": def_nodes, "adversary_nodes": adv_nodes,
                     "parameters": int(parameters[1:]), "value_s": value, "value_and_gradient_s": gradient,
                     "finite_differences_s": fd, "gradient_over_value": gradient / value,
                     "finite_differences_over_gradient": fd / gradient})
    with open(os.path.join(ROOT, "results", "gradient-cost.csv"), "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = ["| grid | nodes (def, adv) | parameters | value | value + gradient | ratio | "
             "finite differences | FD / adjoint |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['grid']} | {r['defender_nodes']}, {r['adversary_nodes']} | {r['parameters']} | "
                     f"{r['value_s'] * 1e3:.3f} ms | {r['value_and_gradient_s'] * 1e3:.3f} ms | "
                     f"{r['gradient_over_value']:.2f} | {r['finite_differences_s'] * 1e3:.1f} ms | "
                     f"{r['finite_differences_over_gradient']:.0f} |")
    with open(os.path.join(ROOT, "results", "gradient-cost.md"), "w") as handle:
        handle.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
