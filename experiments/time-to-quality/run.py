"""Issue 25's time-to-quality benchmark: `posg-fsc solve` with default
settings on games of the paper's family, an objective that needs memory,
the blind-observation variant, fully observable concurrent games (with
their true values) and the POMDP benchmarks, for one or more binaries
(today's defaults against a former build, in the same run).

Per case and binary it records, from `curve.csv` and `summary.json`: the
wall seconds at which the best certified lower bound of any start first
(the best exact value, for single-player runs, which have no checks)
came within 1e-2 and 1e-3 of the run's final certified lower bound (the
returned defender's, reached at the latest when the process ends: a
candidate of the rounding or of the local search may raise it after the
last point of the curve; the plot marks it with a dot), the
final bracket, why it stopped, the phase seconds (thread seconds summed
over starts), wall and CPU seconds of the whole process.

    python3 experiments/time-to-quality/run.py [--binary NAME=PATH ...] [--cases REGEX] [--quick]

Writes results/time-to-quality.csv and results/time-to-quality.png (the
best certified lower bound against seconds, one panel per case). Needs
numpy and scipy (the reference values of the concurrent games), matplotlib
for the plot. Without --binary it builds and runs this checkout's release
binary as `current`.
"""
import argparse
import csv
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(HERE, "..", "benchmarks"))
from games import concurrent_game, game_value, grid_pomdp, matrix_game, maze, write  # noqa: E402
from common.games import BINARY, ROOT, build  # noqa: E402

GRID8_UNSAFE = "s9,s10,s27,s28,s44"
GRID16_UNSAFE = "s17,s18,s50,s51,s85,s86,s119,s120,s153,s154,s187,s188,s221"


def example(binary, path, *options):
    subprocess.run([binary, "example", "grid", *options, "--out", path], check=True,
                   stdout=subprocess.DEVNULL)


def cases(directory, binary, quick):
    """(name, game path, formula, defender nodes, adversary nodes, reference value or None)."""
    out = []
    paper = os.path.join(directory, "paper-3x2.posg.json")
    example(binary, paper)
    out.append(("paper-3x2 1+1", paper, "!unsafe U goal", 1, 1, None))
    out.append(("paper-3x2 2+1", paper, "!unsafe U goal", 2, 1, None))
    grid8 = os.path.join(directory, "grid8.posg.json")
    example(binary, grid8, "--width", "8", "--height", "8", "--unsafe", GRID8_UNSAFE, "--goal", "s63")
    for adv in (1, 2):
        out.append((f"grid8 until 2+{adv}", grid8, "!unsafe U goal", 2, adv, None))
        out.append((f"grid8 GF 2+{adv}", grid8, "GF goal & G !unsafe", 2, adv, None))
    if not quick:
        grid16 = os.path.join(directory, "grid16.posg.json")
        example(binary, grid16, "--width", "16", "--height", "16", "--unsafe", GRID16_UNSAFE,
                "--goal", "s255")
        out.append(("grid16 until 2+1", grid16, "!unsafe U goal", 2, 1, None))
        out.append(("grid16 GF 2+1", grid16, "GF goal & G !unsafe", 2, 1, None))
    memory = os.path.join(directory, "memory6.posg.json")
    example(binary, memory, "--width", "6", "--height", "6", "--unsafe", "s14,s21",
            "--goal", "s35", "--label", "a=s5", "--label", "b=s30")
    out.append(("memory6 corners 2+1", memory, "F (a & F b) & G !unsafe", 2, 1, None))
    blind = os.path.join(directory, "blind8.posg.json")
    example(binary, blind, "--width", "8", "--height", "8", "--unsafe", GRID8_UNSAFE, "--goal", "s63",
            "--observation", "blind")
    out.append(("blind8 until 2+1", blind, "!unsafe U goal", 2, 1, None))
    seed, found = 0, 0
    while found < (2 if quick else 8):
        game = concurrent_game(seed)
        value = game_value(game)
        if 0.1 < value < 0.95:
            path = os.path.join(directory, f"concurrent-{seed}.posg.json")
            write(game, path)
            out.append((f"concurrent-{seed} 1+1", path, "F goal", 1, 1, value))
            found += 1
        seed += 1
    for name, matrix in (("matching-pennies", (1, 0, 0, 1)), ("matrix-0.48", (0.9, 0.2, 0.3, 0.6))):
        game = matrix_game(*matrix)
        path = os.path.join(directory, f"{name}.posg.json")
        write(game, path)
        out.append((f"{name} 1+1", path, "F goal", 1, 1, game_value(game)))
    for n in ((4, 8) if quick else (4, 6, 8, 10)):
        path = os.path.join(directory, f"pomdp-grid{n}.posg.json")
        write(grid_pomdp(n), path)
        for k in (1, 2, 3):
            out.append((f"pomdp-grid{n} {k}", path, "F goal", k, 1, None))
    path = os.path.join(directory, "maze.posg.json")
    write(maze(), path)
    for k in (1, 2):
        out.append((f"maze {k}", path, "F goal", k, 1, 11 / 13))
    return out


def best_so_far(curve_path):
    """(seconds, best so far) at every check: the best certified lower bound of
    any start, or, for a single-player run (the L-BFGS ascent: exact values,
    no checks), the best exact value of any start."""
    with open(curve_path) as handle:
        rows = list(csv.DictReader(handle))
    rows.sort(key=lambda r: float(r["seconds"]))
    column = "certified_lower" if any(r.get("certified_lower") for r in rows) else "value"
    points, best = [], None
    for row in rows:
        if row.get(column):
            number = float(row[column])
            if best is None or number > best:
                best = number
            points.append((float(row["seconds"]), best))
    return points


def first_within(points, final, tolerance):
    for seconds, lower in points:
        if lower >= final - tolerance:
            return seconds
    return None


def run_case(binary, label, case, directory, options):
    name, game, formula, k, m, reference = case
    out = os.path.join(directory, re.sub(r"\W+", "-", f"{label}-{name}"))
    command = [binary, "solve", game, "--ltl", formula, "--def-nodes", str(k), "--adv-nodes", str(m),
               "--out", out, "--force", "--quiet", *options]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    clock = time.monotonic()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.monotonic() - clock
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with open(os.path.join(out, "summary.json")) as handle:
        summary = json.load(handle)
    best = next(s for s in summary["structures"] if s["name"] == summary["structure_used"])
    certified = summary.get("certified") or {}
    final = certified.get("certified_lower")
    points = best_so_far(os.path.join(out, "curve.csv"))
    if final is not None:
        # The returned defender (after rounding and the local search) is
        # there when the process ends, whether or not the curve shows it.
        points.append((wall, max(final, points[-1][1]) if points else final))
    phases = best.get("phases", {})
    row = {
        "case": name, "binary": label, "formula": formula, "defender_nodes": k, "adversary_nodes": m,
        "certified_lower": final, "upper_bound": certified.get("upper_bound"),
        "reference": reference,
        "seconds_to_1e-2": first_within(points, final, 1e-2) if final is not None else None,
        "seconds_to_1e-3": first_within(points, final, 1e-3) if final is not None else None,
        "wall_seconds": round(wall, 3), "cpu_seconds": round(cpu, 3),
        "iterations": best["iterations"], "status": best["status"], "method": best.get("method"),
        "rounding": best.get("rounding"),
        **{f"phase_{p}": round(v, 3) for p, v in phases.items()},
        "command": " ".join([os.path.basename(binary), "solve", os.path.basename(game)] + command[3:9]
                            + [o for o in options]),
    }
    return row, points


SECONDS_TICKS = (0, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500)


def seconds_axis(axis, first, last):
    """A panel's seconds axis for curves from `first` to `last` seconds:
    linear (matplotlib's own ticks) where they span less than a decade or
    end within a second, else symlog (linear below 0.1 s) with round numbers
    of seconds up to the last point (symlog alone labels only the decades)."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator
    if last < 1 or first >= 0.1 * last:
        return
    axis.set_xscale("symlog", linthresh=0.1)
    ticks = [t for t in SECONDS_TICKS if t <= 1.05 * last]
    axis.xaxis.set_major_locator(FixedLocator(ticks))
    axis.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    axis.xaxis.set_minor_locator(NullLocator())


def plot(rows, curves, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot", file=sys.stderr)
        return
    names = list(dict.fromkeys(r["case"] for r in rows))
    columns = 4
    lines = (len(names) + columns - 1) // columns
    figure, axes = plt.subplots(lines, columns, figsize=(4 * columns, 2.8 * lines), squeeze=False)
    for axis, name in zip(axes.flat, names):
        first, last = float("inf"), 0.0
        for (case, label), points in curves.items():
            if case == name and points:
                xs, ys = zip(*points)
                line, = axis.step(xs, ys, where="post", label=label)
                axis.plot(xs[-1:], ys[-1:], "o", color=line.get_color(), markersize=4)
                first, last = min(first, xs[0]), max(last, xs[-1])
        axis.set_title(name, fontsize=9)
        seconds_axis(axis, first, last)
        axis.set_xlabel("seconds", fontsize=8)
        single = name.startswith(("pomdp", "maze"))
        axis.set_ylabel("best exact value (POMDP)" if single else "best certified lower bound",
                        fontsize=8)
        axis.tick_params(labelsize=7)
        axis.legend(fontsize=7)
    for axis in list(axes.flat)[len(names):]:
        axis.axis("off")
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--binary", action="append", default=[],
                        help="'NAME=PATH [solve options]': a posg-fsc binary and extra solve options "
                             "(repeatable); default: current=this checkout's release build")
    parser.add_argument("--cases", default=".", help="run only cases whose name matches this regex")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--csv", default=os.path.join(ROOT, "results", "time-to-quality.csv"))
    parser.add_argument("--plot", default=os.path.join(ROOT, "results", "time-to-quality.png"))
    args = parser.parse_args()
    binaries = []
    for spec in args.binary:
        label, rest = spec.split("=", 1)
        binary, *options = rest.split()
        binaries.append((label, binary, options))
    if not binaries:
        build()
        binaries = [("current", BINARY, [])]
    rows, curves = [], {}
    with tempfile.TemporaryDirectory() as directory:
        for case in cases(directory, binaries[0][1], args.quick):
            if not re.search(args.cases, case[0]):
                continue
            for label, binary, options in binaries:
                row, points = run_case(binary, label, case, directory, options)
                rows.append(row)
                curves[(case[0], label)] = points
                print(json.dumps(row), flush=True)
    header = "# " + " ".join(sys.argv) + "; binaries: " + ", ".join(
        f"{label}={binary} {' '.join(options)}".strip() for label, binary, options in binaries)
    with open(args.csv, "w", newline="") as handle:
        handle.write(header + "\n")
        writer = csv.DictWriter(handle, fieldnames=list(dict.fromkeys(k for r in rows for k in r)))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, curves, args.plot)


if __name__ == "__main__":
    main()
