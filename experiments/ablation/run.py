"""Issue 62's ablation: what carries the optimiser's result.

On the grid family of the issue (`example grid --width N --height N --unsafe
none --goal s{N*N-1} --random-unsafe N*N/10 --seed SEED`, `GF goal & G
!unsafe`, 2 defender nodes, 1 adversary node) and the seed paper's 3x2 grid
(`!unsafe U goal`, 1 and 2 defender nodes), `posg-fsc solve` runs under
configurations that add one part at a time:

- `gradient`: gradient play alone on the full and SAT supports
  (`--structures full,sat --no-local-search --no-grow`);
- `+informed`: and the informed structure (`--structures full,informed,sat`);
- `+local-search`: and the local search on the supports;
- `+grow` (the defaults): and the defender grown from 1 node.

Per run it records the certified bracket, the ratio lower/upper, the
seconds at which the first certified value above 0 was reached (from
curve.csv), the source of the returned defender, the process's wall and
CPU seconds and its peak memory. Seeds are split: `--tune` seeds (1 by
default) are the ones the informed source was developed on; the others
are held out, and the CSV says which half each row is in.

With `--pomdps REPO` (a git directory of randriu/synthesis; run with a
Python that has stormpy), it also runs PAYNT's POMDPs with 1, 2 and 3
defender nodes from their property files: the models of
experiments/pomdp-peers (tuned: the project's POMDP benchmarks) and four
it never ran before issue 62 (held out: refuel-08, drone-4-2 and drone-8-2
of archive/cav23-saynt, geo-2-8 of models/pomdp/large), exported to DRN by
stormpy as experiments/pomdp-peers does.

    python3 experiments/ablation/run.py [--sizes 32,48,64] [--seeds 1,2,3]
        [--configs gradient,+informed,+local-search,+grow] [--pomdps REPO]
        [--models NAME,...] [--no-grids] [--out results/ablation.csv]

Writes the CSV (appending rows to an existing file of the same columns, so
runs can be split) with the command, the binary's version and git commit in
its header comment.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
from common.games import BINARY, ROOT, build  # noqa: E402

CONFIGS = {
    "gradient": ["--structures", "full,sat", "--no-local-search", "--no-grow"],
    "+informed": ["--structures", "full,informed,sat", "--no-local-search", "--no-grow"],
    "+local-search": ["--structures", "full,informed,sat", "--no-grow"],
    "+grow": [],
}
COLUMNS = ["case", "half", "config", "def_nodes", "gmc_states", "certified_lower", "upper_bound",
           "ratio", "first_positive_seconds", "returned_source", "structure_used", "wall_seconds",
           "cpu_seconds", "peak_mb", "status"]


def grid(directory, side, seed):
    path = os.path.join(directory, f"grid{side}-{seed}.posg.json")
    if not os.path.exists(path):
        subprocess.run([BINARY, "example", "grid", "--width", str(side), "--height", str(side),
                        "--unsafe", "none", "--goal", f"s{side * side - 1}", "--random-unsafe",
                        str(side * side // 10), "--seed", str(seed), "--binary", "--out", path],
                       check=True, stdout=subprocess.DEVNULL)
    return path


def paper(directory):
    path = os.path.join(directory, "paper.posg.json")
    if not os.path.exists(path):
        subprocess.run([BINARY, "example", "grid", "--out", path], check=True,
                       stdout=subprocess.DEVNULL)
    return path


def first_positive(curve):
    """Seconds of the first row of curve.csv with a certified lower bound above 0."""
    with open(curve) as handle:
        for row in csv.DictReader(handle):
            if row["certified_lower"] and float(row["certified_lower"]) > 0:
                return float(row["seconds"])
    return None


# PAYNT's POMDPs never run before issue 62: name -> (path, property).
HELD_OUT_POMDPS = {
    "refuel-08": ("models/archive/cav23-saynt/refuel-08", 'Pmax=? ["notbad" U "goal"]'),
    "drone-4-2": ("models/archive/cav23-saynt/drone-4-2", 'Pmax=? ["notbad" U "goal"]'),
    "drone-8-2": ("models/archive/cav23-saynt/drone-8-2", 'Pmax=? ["notbad" U "goal"]'),
    "geo-2-8": ("models/pomdp/large/geo-2-8", 'Pmax=? ["notbad" U "goal"]'),
}


def pomdp_cases(repo, directory, only):
    """(name, half, model.drn, --props args) of every POMDP, exported once."""
    sys.path.insert(0, os.path.join(HERE, "..", "pomdp-peers"))
    import run as peers  # noqa: E402 - experiments/pomdp-peers/run.py
    models = {name: (path, prop, "tuned") for name, (path, prop, _) in peers.MODELS.items()}
    models.update({name: (path, prop, "held-out")
                   for name, (path, prop) in HELD_OUT_POMDPS.items()})
    cases = []
    for name, (path, prop, half) in models.items():
        if only and name not in only:
            continue
        model_dir = os.path.join(directory, name)
        os.makedirs(model_dir, exist_ok=True)
        with open(os.path.join(model_dir, "sketch.templ"), "w") as handle:
            handle.write(peers.git_show(repo, f"{path}/sketch.templ"))
        with open(os.path.join(model_dir, "sketch.props"), "w") as handle:
            handle.write(prop + "\n")
        peers.export_model(model_dir)
        cases.append((name, half, os.path.join(model_dir, "model.drn"),
                      ["--props", os.path.join(model_dir, "sketch.props")]))
    return cases


def run(game, objective, nodes, config, directory, limit):
    out = os.path.join(directory, "out")
    command = [BINARY, "solve", game, *objective, "--def-nodes", str(nodes),
               "--out", out, "--force", "--quiet", *CONFIGS[config]]
    started = time.time()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL)
    killed = threading.Event()

    def kill():
        killed.set()
        child.kill()

    timer = threading.Timer(limit, kill)
    timer.start()
    _, status, usage = os.wait4(child.pid, 0)
    timer.cancel()
    wall = time.time() - started
    cpu = usage.ru_utime + usage.ru_stime
    if killed.is_set():
        return {"def_nodes": nodes, "status": f"killed after {limit} s", "wall_seconds": round(wall, 2),
                "cpu_seconds": round(cpu, 2), "peak_mb": round(usage.ru_maxrss / 1024, 1)}
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(command)} failed")
    with open(os.path.join(out, "summary.json")) as handle:
        summary = json.load(handle)
    certified = summary["certified"] or {}
    lower, upper = certified.get("certified_lower"), certified.get("upper_bound")
    used = next(s for s in summary["structures"] if s["name"] == summary["structure_used"])
    with open(os.path.join(out, "curve.csv")) as handle:
        rows = list(csv.DictReader(handle))
    returned = [r["source"] for r in rows if r.get("returned") == "true"]
    return {
        "def_nodes": nodes,
        "gmc_states": used["gmc"]["states"],
        "certified_lower": lower,
        "upper_bound": upper,
        "ratio": (lower / upper) if lower is not None and upper else None,
        "first_positive_seconds": first_positive(os.path.join(out, "curve.csv")),
        "returned_source": returned[0] if returned else "",
        "structure_used": summary["structure_used"],
        "wall_seconds": round(wall, 2),
        "cpu_seconds": round(cpu, 2),
        "peak_mb": round(usage.ru_maxrss / 1024, 1),
        "status": "done",
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", default="32,48,64")
    parser.add_argument("--seeds", default="1,2,3")
    parser.add_argument("--tune", default="1", help="seeds tuned on (the rest are held out)")
    parser.add_argument("--configs", default=",".join(CONFIGS))
    parser.add_argument("--no-paper", action="store_true")
    parser.add_argument("--no-grids", action="store_true")
    parser.add_argument("--pomdps", metavar="REPO", help="git directory of randriu/synthesis")
    parser.add_argument("--models", default="", help="only these POMDPs (comma-separated)")
    parser.add_argument("--limit", type=float, default=1800, help="kill a run after this many "
                        "wall seconds (the row says so)")
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "ablation.csv"))
    args = parser.parse_args()
    build()
    version = subprocess.run([BINARY, "--version"], capture_output=True, text=True).stdout.strip()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    tune = {int(s) for s in args.tune.split(",")}
    configs = args.configs.split(",")
    fresh = not os.path.exists(args.out)
    with tempfile.TemporaryDirectory() as directory, open(args.out, "a", newline="") as handle:
        if fresh:
            handle.write(f"# {' '.join(sys.argv)}\n# {version}, commit {commit}\n")
        writer = csv.DictWriter(handle, COLUMNS)
        if fresh:
            writer.writeheader()
        cases = []
        one_adversary_node = ["--adv-nodes", "1"]
        if not args.no_paper:
            for nodes in (1, 2):
                cases.append(("paper-3x2", "tuned", paper(directory),
                              ["--ltl", "!unsafe U goal", *one_adversary_node], nodes))
        for side in map(int, args.sizes.split(",")) if not args.no_grids else []:
            for seed in map(int, args.seeds.split(",")):
                half = "tuned" if seed in tune else "held-out"
                cases.append((f"grid{side}-seed{seed}", half, grid(directory, side, seed),
                              ["--ltl", "GF goal & G !unsafe", *one_adversary_node], 2))
        if args.pomdps:
            only = {m for m in args.models.split(",") if m}
            for name, half, model, objective in pomdp_cases(args.pomdps, directory, only):
                cases.extend((name, half, model, objective, k) for k in (1, 2, 3))
        for name, half, game, objective, nodes in cases:
            for config in configs:
                row = {"case": name, "half": half, "config": config,
                       **run(game, objective, nodes, config, directory, args.limit)}
                writer.writerow(row)
                handle.flush()
                print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
