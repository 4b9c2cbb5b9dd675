#!/usr/bin/env python3
"""Time of every pipeline stage by size, from `benches/stages.rs`.

Question: where does the time of one evaluation, one gradient and one
optimiser iteration go, from about 1e3 to 1e6 GMC states? Runs
`cargo bench --bench stages` (unless --no-run; `--max-states N` sets
POSG_FSC_BENCH_MAX_STATES to leave out larger sizes), reads criterion's
mean estimates and writes results/stages.csv and results/stages.md (one
row per size, one column per stage; empty where the bench skips a stage).

Usage: python3 experiments/stages/run.py [--no-run] [--max-states N]
"""
import argparse
import csv
import json
import os
import re
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CRITERION = os.path.join(ROOT, "target", "criterion")
STAGES = ["game load", "gmc build", "refill", "analysis", "lu symbolic", "lu numeric", "value",
          "value+gradient", "gradient pass", "optimiser iteration", "certify"]


def version():
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    with open(os.path.join(ROOT, "Cargo.toml")) as handle:
        crate = next(line.split('"')[1] for line in handle if line.startswith("version"))
    return f"posg-fsc {crate} ({commit})"


def seconds(stage, size):
    path = os.path.join(CRITERION, stage, size, "new", "estimates.json")
    if not os.path.exists(path):
        return None
    with open(path) as handle:
        return json.load(handle)["mean"]["point_estimate"] * 1e-9


def shown(value):
    if value is None:
        return "-"
    if value >= 1:
        return f"{value:.2f} s"
    if value >= 1e-3:
        return f"{value * 1e3:.1f} ms"
    return f"{value * 1e6:.0f} µs"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-run", action="store_true", help="only read existing criterion estimates")
    parser.add_argument("--max-states", type=int, help="POSG_FSC_BENCH_MAX_STATES for the run")
    parser.add_argument("--note", help="a sentence added to the settings (e.g. which stages were re-run when)")
    args = parser.parse_args()
    command = ["cargo", "bench", "--bench", "stages"]
    env = dict(os.environ)
    if args.max_states:
        env["POSG_FSC_BENCH_MAX_STATES"] = str(args.max_states)
    if not args.no_run:
        subprocess.run(command, cwd=ROOT, env=env, check=True)
    sizes = sorted({size for stage in STAGES if os.path.isdir(os.path.join(CRITERION, stage))
                    for size in os.listdir(os.path.join(CRITERION, stage)) if size != "report"},
                   key=lambda size: int(re.search(r"\((\d+) states\)", size).group(1)))
    rows = [{"size": size, **{stage: seconds(stage, size) for stage in STAGES}} for size in sizes]
    setting = (f"{'POSG_FSC_BENCH_MAX_STATES=' + str(args.max_states) + ' ' if args.max_states else ''}"
               f"{' '.join(command)}; {version()}; criterion means in seconds, release build, 2 cores shared "
               "with other work; grids of the paper's family, '!unsafe U goal', uniform controllers"
               + (f"; {args.note}" if args.note else ""))
    with open(os.path.join(ROOT, "results", "stages.csv"), "w", newline="") as handle:
        handle.write(f"# {setting}\n")
        writer = csv.DictWriter(handle, fieldnames=["size", *STAGES])
        writer.writeheader()
        writer.writerows({k: ("" if v is None else v) for k, v in row.items()} for row in rows)
    lines = ["# Pipeline stages by size", "", f"Made by `python3 experiments/stages/run.py"
             f"{' --max-states ' + str(args.max_states) if args.max_states else ''}` ({setting}).", "",
             "| size | " + " | ".join(STAGES) + " |", "|---" * (len(STAGES) + 1) + "|"]
    lines += ["| " + row["size"] + " | " + " | ".join(shown(row[s]) for s in STAGES) + " |" for row in rows]
    with open(os.path.join(ROOT, "results", "stages.md"), "w") as handle:
        handle.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
