#!/usr/bin/env python3
"""Time per gradient: the adjoint method against forward sensitivities (one
solve per parameter, the method of gradient-based parameter synthesis in
probabilistic model checkers), from `benches/gradient.rs`, group
`gradient-methods`.

Question: how much cheaper is the adjoint gradient (one factorisation, two
solves, one pass over the GMC) than forward sensitivities (one
factorisation, one solve per parameter) at about 1e3, 1e4 and 1e5 GMC
states? Runs `cargo bench --bench gradient -- gradient-methods` (unless
--no-run), reads criterion's mean estimates and writes
results/gradient-methods.csv and results/gradient-methods.md.

The forward gradient's time is `value + forward_setup + forward_gradient`
(the K solves, timed together) at the smallest size; at the larger sizes
K solves would take minutes to hours, so only one solve is timed and the
K solves are extrapolated as `K * forward_solve` (column
`forward_extrapolated`).

Usage: python3 experiments/gradient-methods/run.py [--no-run]
"""
import argparse
import csv
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CRITERION = os.path.join(ROOT, "target", "criterion", "gradient-methods")
COMMAND = ["cargo", "bench", "--bench", "gradient", "--", "gradient-methods"]


def mean_seconds(kind, case):
    path = os.path.join(CRITERION, kind, case, "new", "estimates.json")
    if not os.path.exists(path):
        return None
    with open(path) as handle:
        return json.load(handle)["mean"]["point_estimate"] * 1e-9


def version():
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    with open(os.path.join(ROOT, "Cargo.toml")) as handle:
        crate = next(line.split('"')[1] for line in handle if line.startswith("version"))
    return f"posg-fsc {crate} ({commit})"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-run", action="store_true", help="only read existing criterion estimates")
    args = parser.parse_args()
    if not args.no_run:
        subprocess.run(COMMAND, cwd=ROOT, check=True)
    cases = [c for c in os.listdir(os.path.join(CRITERION, "adjoint")) if c != "report"]
    cases.sort(key=lambda c: int(c.split("-s")[1].split("-")[0]))
    rows = []
    for case in cases:
        grid, states, parameters = case.split("-")
        k = int(parameters[1:])
        value, adjoint, setup, solve, full = (mean_seconds(kind, case) for kind in (
            "value", "adjoint", "forward_setup", "forward_solve", "forward_gradient"))
        forward = value + setup + (k * solve if full is None else full)
        rows.append({"grid": grid, "gmc_states": int(states[1:]), "parameters": k,
                     "value_s": value, "adjoint_value_and_gradient_s": adjoint,
                     "forward_setup_s": setup, "forward_solve_s": solve,
                     "forward_value_and_gradient_s": forward,
                     "forward_extrapolated": full is None,
                     "forward_gradient_measured_s": "" if full is None else full,
                     "forward_over_adjoint": forward / adjoint})
    settings = (f"# {' '.join(COMMAND)}; {version()}; criterion means, release build, 2 shared cores; "
                "grids of the paper's family (unsafe s(w+1), goal last cell), '!unsafe U goal', "
                "2-node full-support controllers for both players at fixed non-uniform logits, sparse LU")
    with open(os.path.join(ROOT, "results", "gradient-methods.csv"), "w", newline="") as handle:
        handle.write(settings + "\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        "# Gradient methods: adjoint against forward sensitivities", "",
        f"Made by `python3 {os.path.relpath(os.path.abspath(__file__), ROOT)}` "
        f"(`{' '.join(COMMAND)}`), {version()}.", "",
        "Grids of the paper's family, `!unsafe U goal`, 2-node full-support controllers for both players "
        "at fixed non-uniform logits; both methods use the same sparse LU of `I - Q` "
        "(`--solver lu`). Criterion means on 2 cores shared with other work: expect noise of "
        "tens of percent. Value + gradient by forward sensitivities = value + set-up (LU and all "
        "right-hand sides `r_k`) + K solves; where marked *extrapolated*, the K solves were not run and "
        "their time is K times the mean of one solve (at the smallest size, K times one solve gives "
        f"{format_seconds(rows[0]['parameters'] * rows[0]['forward_solve_s'])} against the "
        f"{format_seconds(rows[0]['forward_gradient_measured_s'])} measured for the K solves: the extrapolation "
        "is good to tens of percent).", "",
        "| grid | GMC states | parameters K | value | adjoint value + gradient | forward: set-up | "
        "forward: one solve | forward value + gradient | forward / adjoint |",
        "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        forward = format_seconds(r["forward_value_and_gradient_s"])
        if r["forward_extrapolated"]:
            forward += " (extrapolated)"
        else:
            forward += " (measured)"
        lines.append(f"| {r['grid']} | {r['gmc_states']} | {r['parameters']} | {format_seconds(r['value_s'])} | "
                     f"{format_seconds(r['adjoint_value_and_gradient_s'])} | {format_seconds(r['forward_setup_s'])} | "
                     f"{format_seconds(r['forward_solve_s'])} | {forward} | {r['forward_over_adjoint']:.0f} |")
    with open(os.path.join(ROOT, "results", "gradient-methods.md"), "w") as handle:
        handle.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def format_seconds(seconds):
    if seconds >= 100:
        return f"{seconds / 3600:.2f} h" if seconds >= 3600 else f"{seconds:.0f} s"
    if seconds >= 1:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds * 1e6:.0f} µs"


if __name__ == "__main__":
    sys.exit(main())
