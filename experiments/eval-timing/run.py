#!/usr/bin/env python3
"""Time and peak memory of `posg-fsc eval` on grids of the paper's family.

Question: how long does one exact evaluation take, and how much memory does
it need, on 16x16, 64x64 and 128x128 grids with 2-node uniform controllers
for both players? Writes results/eval-timing.csv (one row per grid and
repetition) and prints the medians.

The grids are written in the fastest form the tool reads (`--form binary`,
the default: `example grid --binary`, docs/formats.md section 11; `--form
json` for the pretty-printed JSON); the CSV header records the form.

Usage: python3 experiments/eval-timing/run.py [--repeats 3] [--form binary|json]
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BINARY = os.path.join(ROOT, "target", "release", "posg-fsc")
FORMULA = "!unsafe U goal"


def build():
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)


# The game file's form: (`example grid` options, file extension).
FORMS = {"binary": (["--binary"], "posg.bin"), "json": ([], "posg.json")}


def make_grid(size, path, form):
    cells = size * size
    subprocess.run(
        [BINARY, "example", "grid", "--width", str(size), "--height", str(size),
         "--unsafe", "none", "--goal", f"s{cells - 1}", "--random-unsafe", str(max(1, cells // 20)),
         "--seed", "1", *FORMS[form][0], "--out", path],
        check=True)


def timed_eval(game):
    command = ["/usr/bin/time", "-v", BINARY, "eval", game, "--ltl", FORMULA,
               "--defender", "uniform:2", "--adversary", "uniform:2"]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    report = json.loads(done.stdout)
    peak_kib = next(int(line.split(":")[1]) for line in done.stderr.splitlines()
                    if "Maximum resident set size" in line)
    wall = next(line.split(": ")[1] for line in done.stderr.splitlines() if "Elapsed (wall clock)" in line)
    minutes, seconds = wall.split(":")[-2:]
    return report, float(minutes) * 60 + float(seconds), peak_kib / 1024 / 1024


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--sizes", type=int, nargs="+", default=[16, 64, 128])
    parser.add_argument("--form", choices=sorted(FORMS), default="binary",
                        help="the game file's form (binary: docs/formats.md section 11)")
    args = parser.parse_args()
    build()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes:
            game = os.path.join(tmp, f"grid{size}.{FORMS[args.form][1]}")
            make_grid(size, game, args.form)
            for repeat in range(args.repeats):
                report, wall, peak_gib = timed_eval(game)
                rows.append({"grid": f"{size}x{size}", "repeat": repeat, "gmc_states": report["gmc_states"],
                             "gmc_transitions": report["gmc_transitions"],
                             "transient_states": report["transient_states"], "value": report["value"],
                             "residual": report["residual"], "eval_seconds": report["seconds"],
                             "process_seconds": wall, "peak_gib": peak_gib})
    out = os.path.join(ROOT, "results", "eval-timing.csv")
    with open(out, "w", newline="") as handle:
        handle.write(f"# {' '.join(sys.argv)}; game form {args.form} (*.{FORMS[args.form][1]}); "
                     f"formula '{FORMULA}', defender uniform:2, adversary uniform:2\n")
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    for size in args.sizes:
        mine = [r for r in rows if r["grid"] == f"{size}x{size}"]
        print(f"{size}x{size}: {mine[0]['gmc_states']} GMC states, median eval "
              f"{statistics.median(r['process_seconds'] for r in mine):.2f} s, "
              f"peak {statistics.median(r['peak_gib'] for r in mine):.2f} GiB")


if __name__ == "__main__":
    main()
