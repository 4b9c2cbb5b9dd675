#!/usr/bin/env python3
"""Wall time and peak memory against the number of GMC states, for one
value (`posg-fsc eval`), value + adjoint gradient (`eval --gradient`) and
one optimiser iteration (`solve`), with sparse LU and with BiCGSTAB + ILU(0).

Question: how do time and memory grow with the size of the GMC, from about
1e3 to 1e6 states, and which solver reaches the largest sizes? Grids of the
paper's family (`posg-fsc example grid`, unsafe cell s(w+1), goal the last
cell), `!unsafe U goal`, 2-node uniform controllers for both players. Each
measurement is one process under `/usr/bin/time -v` (wall clock from start
to exit, maximum resident set size; `reported_seconds` is the program's
own `seconds`, without process start-up); the median of --repeats runs when one run takes under
--repeat-below seconds, else one run. A run is stopped (and recorded as
not run) when it exceeds --max-seconds or --max-gib; a method is not tried
at larger sizes after that, nor after it failed (an error exit) at two sizes. Writes results/scaling.csv (one row per size,
kind and solver, fitted exponents in the header) and results/scaling.svg.

"One optimiser iteration" is `posg-fsc solve --automaton` (no certified
bracket) with --max-iterations 1 --adversary-steps 1 --check-every 1
--restarts 0 --starts 1 --best-response-iterations 1 --structures full: one
start, one adversary and one defender step (two value + gradient
evaluations) plus the best-response check `solve` always runs at
iteration 0 (one L-BFGS iteration from the current adversary, for the
defender and for its suffix average, each with a line search), the
set-up (GMC, analysis, solver) and the output files.

Usage: python3 experiments/scaling/run.py [--sides 10 20 ...] [--repeats 3]
       python3 experiments/scaling/run.py --plot-only
"""
import argparse
import csv
import json
import math
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from games import BINARY, ROOT, build  # noqa: E402

FORMULA = "!unsafe U goal"
KINDS = ("eval", "eval+gradient", "one-iteration")
SOLVERS = ("lu", "krylov")
CSV_PATH = os.path.join(ROOT, "results", "scaling.csv")
SVG_PATH = os.path.join(ROOT, "results", "scaling.svg")
FIELDS = ["side", "gmc_states", "gmc_transitions", "transient_states", "kind", "solver", "status", "runs",
          "wall_seconds", "peak_gib", "all_wall_seconds", "reported_seconds", "value", "residual"]


def version():
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    crate = subprocess.run([BINARY, "--version"], capture_output=True, text=True).stdout.strip()
    return f"{crate} ({commit})"


def rss_kib(pid):
    """Resident memory of `pid` and its descendants in KiB."""
    total = 0
    try:
        with open(f"/proc/{pid}/status") as handle:
            total += next((int(line.split()[1]) for line in handle if line.startswith("VmRSS")), 0)
        with open(f"/proc/{pid}/task/{pid}/children") as handle:
            children = [int(c) for c in handle.read().split()]
    except (FileNotFoundError, ProcessLookupError, StopIteration):
        return total
    return total + sum(rss_kib(child) for child in children)


def timed(command, max_seconds, max_gib):
    """Runs `command` under /usr/bin/time -v; returns (status, wall seconds
    from start to exit, peak GiB from /usr/bin/time, stdout). status is
    "ok", "timeout", "memory" or "failed"."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        process = subprocess.Popen(["/usr/bin/time", "-v", *command], stdout=out, stderr=err,
                                   start_new_session=True, text=True)
        start = time.monotonic()
        stopped = []
        watching = threading.Event()

        def watch():
            while not watching.wait(0.05):
                if time.monotonic() - start > max_seconds:
                    stopped.append("timeout")
                elif rss_kib(process.pid) > max_gib * 1024 * 1024:
                    stopped.append("memory")
                if stopped:
                    os.killpg(process.pid, signal.SIGKILL)
                    return

        watcher = threading.Thread(target=watch)
        watcher.start()
        process.wait()
        seconds = time.monotonic() - start
        watching.set()
        watcher.join()
        if stopped:
            return stopped[0], seconds, None, ""
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    if process.returncode != 0:
        sys.stderr.write(stderr.split("\tCommand being timed")[0][-2000:])
        return "failed", seconds, None, stdout
    peak_kib = next(int(line.split(":")[1]) for line in stderr.splitlines() if "Maximum resident set size" in line)
    return "ok", seconds, peak_kib / 1024 / 1024, stdout


def command_for(kind, solver, game, hoa, out):
    if kind == "one-iteration":
        return [BINARY, "solve", game, "--automaton", hoa, "--def-nodes", "2", "--adv-nodes", "2",
                "--out", out, "--max-iterations", "1", "--adversary-steps", "1", "--check-every", "1",
                "--restarts", "0", "--starts", "1", "--best-response-iterations", "1", "--structures", "full",
                "--solver", solver,
                "--force"]
    command = [BINARY, "eval", game, "--ltl", FORMULA, "--defender", "uniform:2", "--adversary", "uniform:2",
               "--solver", solver]
    return command + (["--gradient"] if kind == "eval+gradient" else [])


def measure(args):
    build()
    rows = []
    given_up = set()
    failures = {}
    with tempfile.TemporaryDirectory() as tmp:
        hoa = os.path.join(tmp, "objective.hoa")
        with open(hoa, "w") as handle:
            subprocess.run([BINARY, "translate", FORMULA, "--hoa"], stdout=handle, check=True)
        for side in args.sides:
            game = os.path.join(tmp, f"grid{side}.posg.json")
            subprocess.run([BINARY, "example", "grid", "--width", str(side), "--height", str(side),
                            "--unsafe", f"s{side + 1}", "--goal", f"s{side * side - 1}", "--out", game],
                           check=True, stdout=subprocess.DEVNULL)
            size = None
            for kind in KINDS:
                for solver in SOLVERS:
                    row = {"side": side, "kind": kind, "solver": solver}
                    if (kind, solver) in given_up:
                        row.update(status="not run (failed twice or over a limit at a smaller size)", runs=0)
                        rows.append(row)
                        continue
                    walls, peaks, reported = [], [], []
                    while True:
                        status, wall, peak, stdout = timed(command_for(kind, solver, game, hoa, os.path.join(tmp, "out")),
                                                           args.max_seconds, args.max_gib)
                        if status != "ok":
                            break
                        walls.append(wall)
                        peaks.append(peak)
                        if kind != "one-iteration":
                            report = json.loads(stdout)
                            size = size or report
                            row.update(value=report["value"], residual=report["residual"])
                        else:
                            with open(os.path.join(tmp, "out", "summary.json")) as handle:
                                report = json.load(handle)
                        reported.append(report["seconds"])
                        if len(walls) >= args.repeats or wall >= args.repeat_below:
                            break
                    if status != "ok":
                        failures[(kind, solver)] = failures.get((kind, solver), 0) + 1
                        if status != "failed" or failures[(kind, solver)] >= 2:
                            given_up.add((kind, solver))
                        limit = {"timeout": f"over {args.max_seconds:g} s", "memory": f"over {args.max_gib:g} GiB",
                                 "failed": f"failed after {wall:.1f} s"}[status]
                        row.update(status=f"not run ({limit})", runs=len(walls))
                        walls = []
                    else:
                        row.update(status="ok", runs=len(walls), wall_seconds=statistics.median(walls),
                                   peak_gib=statistics.median(peaks), reported_seconds=statistics.median(reported),
                                   all_wall_seconds=" ".join(f"{w:.2f}" for w in walls))
                    print(side, kind, solver, row.get("status"), row.get("wall_seconds"), row.get("peak_gib"), flush=True)
                    rows.append(row)
            for row in rows:
                if row["side"] == side and size:
                    row.update(gmc_states=size["gmc_states"], gmc_transitions=size["gmc_transitions"],
                               transient_states=size["transient_states"])
    return rows


def fits(rows):
    """Least-squares slope of log(y) on log(GMC states) per kind and solver."""
    result = {}
    for kind in KINDS:
        for solver in SOLVERS:
            for column in ("wall_seconds", "peak_gib"):
                points = [(math.log(float(r["gmc_states"])), math.log(float(r[column]))) for r in rows
                          if r["kind"] == kind and r["solver"] == solver and r["status"] == "ok"
                          and float(r["gmc_states"]) >= 1e4]
                if len(points) >= 2:
                    mx = sum(x for x, _ in points) / len(points)
                    my = sum(y for _, y in points) / len(points)
                    slope = sum((x - mx) * (y - my) for x, y in points) / sum((x - mx) ** 2 for x, _ in points)
                    result[(kind, solver, column)] = slope
    return result


def write_csv(rows, header):
    with open(CSV_PATH, "w", newline="") as handle:
        for line in header:
            handle.write(f"# {line}\n")
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: row.get(k, "") for k in FIELDS})


def read_csv():
    with open(CSV_PATH) as handle:
        lines = handle.read().splitlines()
    header = [line[2:] for line in lines if line.startswith("# ")]
    rows = list(csv.DictReader(line for line in lines if not line.startswith("#")))
    return rows, header


COLOURS = {"eval": "#1f77b4", "eval+gradient": "#d62728", "one-iteration": "#2ca02c"}
DASHES = {"lu": "", "krylov": "6,4"}


def svg(rows, fitted, title):
    """Two log-log panels (wall seconds, peak GiB) against GMC states."""
    width, height, margin = 460, 360, 60
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{2 * width}" height="{height + 80}" '
           'font-family="sans-serif" font-size="12">', '<rect width="100%" height="100%" fill="white"/>',
           f'<text x="{width}" y="18" text-anchor="middle" font-size="14">{title}</text>']
    done = [r for r in rows if r["status"] == "ok"]
    xs = [float(r["gmc_states"]) for r in done]
    for panel, (column, label) in enumerate((("wall_seconds", "wall seconds"), ("peak_gib", "peak memory (GiB)"))):
        ys = [float(r[column]) for r in done]
        x0, x1 = math.floor(math.log10(min(xs))), math.ceil(math.log10(max(xs)))
        y0, y1 = math.floor(math.log10(min(ys))), math.ceil(math.log10(max(ys)))
        left, top = panel * width + margin, 30
        plot_w, plot_h = width - margin - 20, height - margin - 10

        def px(x):
            return left + (math.log10(x) - x0) / (x1 - x0) * plot_w

        def py(y):
            return top + plot_h - (math.log10(y) - y0) / (y1 - y0) * plot_h

        out.append(f'<rect x="{left}" y="{top}" width="{plot_w}" height="{plot_h}" fill="none" stroke="black"/>')
        for e in range(x0, x1 + 1):
            x = px(10 ** e)
            out.append(f'<line x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{top + plot_h}" stroke="#ddd"/>')
            out.append(f'<text x="{x:.1f}" y="{top + plot_h + 16}" text-anchor="middle">1e{e}</text>')
        for e in range(y0, y1 + 1):
            y = py(10 ** e)
            out.append(f'<line x1="{left}" y1="{y:.1f}" x2="{left + plot_w}" y2="{y:.1f}" stroke="#ddd"/>')
            out.append(f'<text x="{left - 6}" y="{y + 4:.1f}" text-anchor="end">1e{e}</text>')
        out.append(f'<text x="{left + plot_w / 2}" y="{top + plot_h + 34}" text-anchor="middle">GMC states</text>')
        out.append(f'<text x="{left - 44}" y="{top + plot_h / 2}" text-anchor="middle" '
                   f'transform="rotate(-90 {left - 44} {top + plot_h / 2})">{label}</text>')
        for kind in KINDS:
            for solver in SOLVERS:
                points = sorted((float(r["gmc_states"]), float(r[column])) for r in done
                                if r["kind"] == kind and r["solver"] == solver)
                if not points:
                    continue
                path = " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in points)
                dash = f' stroke-dasharray="{DASHES[solver]}"' if DASHES[solver] else ""
                out.append(f'<polyline points="{path}" fill="none" stroke="{COLOURS[kind]}" stroke-width="2"{dash}/>')
                for x, y in points:
                    out.append(f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="3" fill="{COLOURS[kind]}"/>')
    legend_y = height + 30
    for i, kind in enumerate(KINDS):
        for j, solver in enumerate(SOLVERS):
            x, y = 40 + i * 300, legend_y + j * 18
            slope = fitted.get((kind, solver, "wall_seconds"))
            text = f"{kind}, {solver}" + (f" (t ~ n^{slope:.2f})" if slope is not None else " (not run)")
            dash = f' stroke-dasharray="{DASHES[solver]}"' if DASHES[solver] else ""
            out.append(f'<line x1="{x}" y1="{y}" x2="{x + 24}" y2="{y}" stroke="{COLOURS[kind]}" '
                       f'stroke-width="2"{dash}/>')
            out.append(f'<text x="{x + 28}" y="{y + 4}" font-size="11">{text}</text>')
    out.append("</svg>")
    with open(SVG_PATH, "w") as handle:
        handle.write("\n".join(out) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sides", type=int, nargs="+", default=[10, 20, 40, 80, 128, 200, 288])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--repeat-below", type=float, default=20.0,
                        help="repeat a measurement only when one run takes less (seconds)")
    parser.add_argument("--max-seconds", type=float, default=120.0)
    parser.add_argument("--max-gib", type=float, default=12.0)
    parser.add_argument("--plot-only", action="store_true", help="redraw the SVG from results/scaling.csv")
    args = parser.parse_args()
    if args.plot_only:
        rows, header = read_csv()
    else:
        rows = measure(args)
        header = [f"experiments/scaling/run.py {' '.join(sys.argv[1:])}".strip() + f"; {version()}",
                  f"grids of the paper's family (unsafe s(w+1), goal last cell), formula '{FORMULA}', "
                  "2-node uniform controllers for both players; one process per measurement under "
                  "/usr/bin/time -v, 2 cores shared with other work",
                  f"median of {args.repeats} runs when one run takes under {args.repeat_below:g} s; "
                  f"limits {args.max_seconds:g} s and {args.max_gib:g} GiB per run"]
    fitted = fits(rows)
    header = [line for line in header if not line.startswith("fitted exponent")]
    header.append("fitted exponent (least squares of log y on log GMC states, sizes >= 1e4): " +
                  ", ".join(f"{kind}/{solver}/{'time' if column == 'wall_seconds' else 'memory'} {slope:.2f}"
                            for (kind, solver, column), slope in sorted(fitted.items())))
    write_csv(rows, header)
    svg(rows, fitted, "posg-fsc scaling: grids, '!unsafe U goal', 2-node controllers (log-log)")
    for line in header:
        print("#", line)


if __name__ == "__main__":
    main()
