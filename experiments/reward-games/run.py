#!/usr/bin/env python3
"""Expected rewards on games with an adversary: what `solve` certifies.

Question: on games where an adversary plays against the defender, does
`posg-fsc solve GAME --props P` (defaults, `--def-nodes K`) return a
defender whose certified worst case against every adversary is close to
the bound no defender beats (docs/method.md section 9), with how much
CPU; and does `posg-fsc certify` of the returned defender print the same
guarantee?

Cases:
* `two-roads` (tests/data/rewards/two-roads.posg.json): a matrix game
  whose value is 8/3 on paper, at a mixed strategy;
* PAYNT's POSMG `testing-rewards` (`<<0>> Rmax=? [F "done"]`, with its two
  unnamed reward models named `rew0` and `rew1`: the query names each);
* the grid games of issue 62's family (`example grid --width N --height N
  --unsafe none --goal s{N*N-1} --random-unsafe N*N/10 --seed S`) with a
  reward model `cost` (1 per step, 10 more per step from an unsafe cell)
  and `R{"cost"}min=? [F "goal"]`: N = 8, 12, 16, seeds 1-3.

Nothing was tuned for this table (the reward race runs the probability
objectives' defaults); every row is held out.

Columns: the certified `guaranteed` value (summary.json's `value`), the
`best_possible` bound and their relative `gap`, the value `certify` prints
for the returned defender, CPU (user + system of the solve process) and
wall seconds.

Usage: python3 experiments/reward-games/run.py --repo PATH/TO/synthesis
[--binary target/release/posg-fsc] [--out results/reward-games.csv]
"""
import argparse
import csv
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(binary, *arguments):
    """Runs the CLI; returns (stdout, user + system CPU seconds, wall seconds)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    clock = time.time()
    process = subprocess.run([binary, *map(str, arguments)], capture_output=True, text=True)
    wall = time.time() - clock
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if process.returncode != 0:
        raise RuntimeError(f"{arguments}: {process.stderr.strip()}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return process.stdout, cpu, wall


def grid_game(binary, work, size, seed):
    """Issue 62's grid of side `size` and `seed`, with the reward model `cost`."""
    path = os.path.join(work, f"grid{size}-{seed}.posg.json")
    run(binary, "example", "grid", "--width", size, "--height", size, "--unsafe", "none",
        "--goal", f"s{size * size - 1}", "--random-unsafe", size * size // 10, "--seed", seed,
        "--out", path)
    with open(path) as f:
        game = json.load(f)
    unsafe = {s for s, labels in game["labels"].items() if "unsafe" in labels}
    cost = {s: 11.0 if s in unsafe else 1.0 for s in game["states"]}
    game["rewards"] = {"cost": {"states": cost}}
    with open(path, "w") as f:
        json.dump(game, f)
    return path


def testing_rewards(repo, work):
    """PAYNT's POSMG testing-rewards as a DRN file."""
    path = os.path.join(work, "testing-rewards.drn")
    text = subprocess.run(
        ["git", "--git-dir", repo, "show", "HEAD:models/posmg/testing-rewards/sketch.templ"],
        capture_output=True, text=True, check=True).stdout
    with open(path, "w") as f:
        f.write(text)
    return path


def cases(binary, repo, work):
    """(name, game file, query, defender nodes) of every run."""
    yield "two-roads", os.path.join(ROOT, "tests/data/rewards/two-roads.posg.json"), \
        'R{"cost"}min=? [F "goal"]', 1
    drn = testing_rewards(repo, work)
    for model in ["rew0", "rew1"]:
        for nodes in [1, 2]:
            yield f"testing-rewards/{model}", drn, f'<<0>> R{{"{model}"}}max=? [F "done"]', nodes
    for size in [8, 12, 16]:
        for seed in [1, 2, 3]:
            game = grid_game(binary, work, size, seed)
            for nodes in [1, 2]:
                yield f"grid{size}-seed{seed}", game, 'R{"cost"}min=? [F "goal"]', nodes


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", required=True, help="PAYNT's synthesis repository (its .git)")
    parser.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "posg-fsc"))
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "reward-games.csv"))
    args = parser.parse_args()
    repo = args.repo if args.repo.endswith(".git") or os.path.isfile(os.path.join(args.repo, "HEAD")) \
        else os.path.join(args.repo, ".git")
    version = run(args.binary, "--version")[0].strip()
    work = tempfile.mkdtemp(prefix="reward-games-")
    rows = []
    try:
        for name, game, query, nodes in cases(args.binary, repo, work):
            props = os.path.join(work, "query.props")
            with open(props, "w") as f:
                f.write(query + "\n")
            out = os.path.join(work, "out")
            shutil.rmtree(out, ignore_errors=True)
            _, cpu, wall = run(args.binary, "solve", game, "--props", props, "--def-nodes", nodes,
                               "--out", out, "--quiet")
            with open(os.path.join(out, "summary.json")) as f:
                certificate = json.load(f)["certificate"]
            certified = json.loads(run(args.binary, "certify", game, "--props", props,
                                       "--defender", os.path.join(out, "defender.fsc.json"))[0])
            guaranteed, best = certificate["guaranteed"], certificate["best_possible"]
            gap = abs(guaranteed - best) / max(abs(guaranteed), abs(best), 1e-12)
            rows.append({
                "case": name, "query": query, "def_nodes": nodes, "half": "check",
                "guaranteed": guaranteed, "best_possible": best, "gap": f"{gap:.3g}",
                "certify_guaranteed": certified["guaranteed"],
                "cpu_s": f"{cpu:.2f}", "wall_s": f"{wall:.2f}",
            })
            print(f"{name} K={nodes}: [{best:.6g}, {guaranteed:.6g}] gap {gap:.3g}, "
                  f"{cpu:.1f} s CPU", file=sys.stderr)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    with open(args.out, "w", newline="") as f:
        f.write(f"# {' '.join(sys.argv)} ({version})\n")
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
