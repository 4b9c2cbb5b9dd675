"""solve and sweep: the CLI's controllers for the same seed, the callback
and Ctrl-C stopping a run, the GIL released while Rust computes."""

import _thread
import csv
import json
import signal
import subprocess
import sys
import threading
import time

import pytest

import posg_fsc
from conftest import FORMULA, REPOSITORY, run_cli

QUICK = dict(max_iterations=40, starts=1, restarts=1, best_response_iterations=30)
# A run that only a stop ends early: no stall or gap rule, many iterations.
LONG = dict(max_iterations=100000, starts=1, structures=["full"], stall_checks=0, gap_tolerance=0.0)


def test_solve_with_a_seed_gives_the_cli_controllers(cli, grid_file, tmp_path):
    out = tmp_path / "cli"
    run_cli(
        cli, "solve", grid_file, "--ltl", FORMULA, "--def-nodes", "2", "--adv-nodes", "1",
        "--seed", "7", "--max-iterations", "40", "--starts", "1", "--restarts", "1",
        "--best-response-iterations", "30", "--out", out,
    )
    game = posg_fsc.Game.load(grid_file)
    result = posg_fsc.solve(game, FORMULA, def_nodes=2, adv_nodes=1, seed=7, **QUICK)
    summary = json.loads((out / "summary.json").read_text())
    assert result.defender.to_json().strip() == (out / "defender.fsc.json").read_text().strip()
    assert result.adversary.to_json().strip() == (out / "adversary.fsc.json").read_text().strip()
    assert result.worst_case == summary["worst_case"]
    assert result.certified == summary["certified"]
    assert result.structure_used == summary["structure_used"]
    assert result.settings == summary["settings"]
    assert result.certified["certified_lower"] <= result.certified["upper_bound"]
    # The curve is the best structure's records, one dict per iteration.
    assert [r["iteration"] for r in result.curve] == list(range(len(result.curve)))
    assert {"value", "worst_case", "certified_lower", "upper_bound"} <= set(result.curve[0])


def test_a_different_seed_gives_other_controllers():
    game = posg_fsc.example_grid()
    settings = dict(QUICK, structures=["full"], round=False)
    first = posg_fsc.solve(game, FORMULA, 2, 1, seed=1, **settings)
    second = posg_fsc.solve(game, FORMULA, 2, 1, seed=2, **settings)
    again = posg_fsc.solve(game, FORMULA, 2, 1, seed=1, **settings)
    assert first.defender.to_json() == again.defender.to_json()
    assert first.defender.to_json() != second.defender.to_json()


def test_the_callback_sees_every_record_and_can_stop_the_run():
    game = posg_fsc.example_grid()
    seen = []

    def on_iteration(record):
        seen.append(record)
        return len(seen) < 5

    started = time.monotonic()
    result = posg_fsc.solve(game, FORMULA, 2, 1, on_iteration=on_iteration, **LONG)
    assert time.monotonic() - started < 60
    assert 5 <= len(seen) < 100
    assert result.structures[0]["iterations"] < 100
    assert seen[0]["structure"] == "full" and seen[0]["iteration"] == 0
    # The callback saw the records of the curve, as they happened: after it
    # returned False it is not called again, while the run stops at its
    # next iteration.
    assert len(seen) == 5 and len(result.curve) <= 10
    for record, kept in zip(seen, result.curve):
        assert {k: v for k, v in record.items() if k != "structure"} == kept


def test_an_exception_in_the_callback_stops_the_run_and_is_raised():
    game = posg_fsc.example_grid()

    def on_iteration(record):
        if record["iteration"] == 3:
            raise LookupError("stop here")

    with pytest.raises(LookupError, match="stop here"):
        posg_fsc.solve(game, FORMULA, 2, 1, on_iteration=on_iteration, **LONG)


def test_ctrl_c_stops_a_long_solve_cleanly():
    # A runner started in the background (`cmd &`) inherits SIGINT ignored,
    # and Python then installs no handler, so that interrupt_main() is a
    # no-op: install Python's own, as an interactive session has it.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    game = posg_fsc.example_grid()
    seen = []

    def on_iteration(record):
        seen.append(record)
        if len(seen) == 3:
            _thread.interrupt_main()  # what Ctrl-C does

    started = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            posg_fsc.solve(game, FORMULA, 2, 1, on_iteration=on_iteration, **LONG)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert time.monotonic() - started < 60
    assert len(seen) < 1000


def test_the_gil_is_released_while_rust_computes():
    game = posg_fsc.example_grid(width=6, height=6, unsafe=[5], goal=[35])
    ticks = []
    running = threading.Event()
    running.set()

    def count():
        while running.is_set():
            ticks.append(1)
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    started = time.monotonic()
    # Long enough to measure (about 0.2 s here): no gap or stall rule ends it.
    posg_fsc.solve(game, FORMULA, 2, 1, **dict(LONG, max_iterations=200))
    elapsed = time.monotonic() - started
    running.clear()
    counter.join()
    # Had the GIL been held, the counter could not have run during the solve.
    assert elapsed > 0.05
    assert len(ticks) > 0.2 * elapsed / 0.001 * 0.1


def test_sweep_rows_are_monotone_in_the_defender_size():
    game = posg_fsc.example_grid()
    rows = posg_fsc.sweep(game, FORMULA, def_nodes=[1, 2], adv_nodes=1, **QUICK)
    assert [(r["defender_nodes"], r["adversary_nodes"]) for r in rows] == [(1, 1), (2, 1)]
    assert [r["warm_started"] for r in rows] == [False, True]
    assert rows[1]["certified_lower"] >= rows[0]["certified_lower"]
    assert rows[1]["solved"].defender.nodes == 2


def test_the_example_script_writes_its_table(tmp_path):
    script = REPOSITORY / "examples" / "python" / "compare_sizes.py"
    subprocess.run(
        [sys.executable, str(script), "--def-nodes", "1", "2", "--max-iterations", "20",
         "--out", str(tmp_path)],
        check=True,
    )
    rows = list(csv.DictReader((tmp_path / "compare_sizes.csv").open()))
    assert [int(r["defender_nodes"]) for r in rows] == [1, 2]
    for row in rows:
        assert 0 <= float(row["certified_lower"]) <= float(row["upper_bound"]) <= 1


def test_the_notebook_runs_and_its_curve_ends_at_the_certified_value(tmp_path):
    pytest.importorskip("pandas")
    script = REPOSITORY / "examples" / "python" / "notebook.py"
    run = subprocess.run(
        [sys.executable, str(script), "--out", str(tmp_path), "--max-iterations", "60"],
        check=True, capture_output=True, text=True,
    )
    assert "2 nodes: done in" in run.stderr, run.stderr  # progress=True
    summary = json.loads((tmp_path / "solve" / "summary.json").read_text())
    curve = list(csv.DictReader((tmp_path / "solve" / "curve.csv").open()))
    best = max(float(r["certified_lower"]) for r in curve if r["certified_lower"])
    assert best == summary["certified"]["certified_lower"]
    sizes = list(csv.DictReader((tmp_path / "sizes.csv").open()))
    assert [int(r["defender_nodes"]) for r in sizes] == [1, 2]
    assert float(sizes[1]["certified_lower"]) >= float(sizes[0]["certified_lower"])
    simulation = json.loads((tmp_path / "simulation.json").read_text())
    assert simulation["estimate"]["runs"] == 20_000
    assert abs(simulation["estimate"]["mean"] - simulation["exact_value"]) < 0.01


def test_eight_threads_at_once_give_the_results_of_one():
    # Every call releases the GIL while Rust computes; shared games and
    # concurrent solves, evaluations and certificates must not change a digit.
    game = posg_fsc.example_grid(width=5, height=4, unsafe=[7], goal=[19])
    settings = dict(QUICK, structures=["full"])

    def work(seed):
        solved = posg_fsc.solve(game, FORMULA, 2, 1, seed=seed, **settings)
        value = game.evaluate(FORMULA, defender=solved.defender, adversary=solved.adversary).value
        certified = posg_fsc.certify(game, FORMULA, solved.defender)
        return solved.defender.to_json(), value, certified["lower"]["value"]

    seeds = [1, 2, 3, 4, 1, 2, 3, 4]
    alone = {seed: work(seed) for seed in set(seeds)}
    results = [None] * len(seeds)
    errors = []

    def thread(k):
        try:
            results[k] = work(seeds[k])
        except BaseException as error:  # noqa: BLE001 - reported below
            errors.append(error)

    threads = [threading.Thread(target=thread, args=(k,)) for k in range(len(seeds))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    assert results == [alone[seed] for seed in seeds]
    assert len({alone[seed][0] for seed in alone}) > 1, "the seeds gave one defender: vacuous"


def test_ctrl_c_leaves_out_complete_or_untouched(tmp_path):
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    game = posg_fsc.example_grid()
    out = tmp_path / "run"
    seen = []

    def on_iteration(record):
        seen.append(record)
        if len(seen) == 3:
            _thread.interrupt_main()

    started = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            posg_fsc.solve(game, FORMULA, 2, 1, on_iteration=on_iteration, out=str(out), **LONG)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert time.monotonic() - started < 60
    # Nothing half-written beside the target: no staging directory, no lock.
    assert sorted(p.name for p in tmp_path.iterdir()) in ([], ["run"])
    if out.exists():
        # Whole: every file of a solve directory, the summary readable (its
        # status depends on where the interrupt met the run).
        summary = json.loads((out / "summary.json").read_text())
        assert summary["certified"]["certified_lower"] <= summary["certified"]["upper_bound"]
        for name in ("defender.fsc.json", "adversary.fsc.json", "curve.csv", "defender.dot"):
            assert (out / name).is_file(), name


def test_progress_prints_the_command_line_s_lines_on_stderr(capsys):
    game = posg_fsc.example_grid(width=6, height=6, unsafe=[5], goal=[35])
    result = posg_fsc.solve(
        game, FORMULA, 2, 1, progress=0.01, **dict(LONG, max_iterations=200)
    )
    lines = capsys.readouterr().err.splitlines()
    stamps = [float(line[1:].split(" s] ")[0]) for line in lines]
    assert stamps == sorted(stamps), lines
    assert any(" racing (iteration " in line for line in lines), lines
    done = [line for line in lines if line.split("] ")[1].startswith("2 nodes: done in ")]
    assert done and f"certified [{result.certified['certified_lower']:.6f}, " in done[-1], lines
    posg_fsc.solve(game, FORMULA, 1, 1, **QUICK)
    assert capsys.readouterr().err == ""
    with pytest.raises(posg_fsc.SettingsError, match="progress"):
        posg_fsc.solve(game, FORMULA, 1, 1, progress=-1.0, **QUICK)
