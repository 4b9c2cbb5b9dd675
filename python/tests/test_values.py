"""Values and gradients: the package against the CLI on the same files, and
the adjoint gradient against finite differences."""

import json

import numpy as np
import pytest

import posg_fsc
from conftest import FORMULA, REPOSITORY, cli_json, run_cli


def random_controller(game, role, nodes, rng):
    """A controller with random probabilities on the full enabled support."""
    uniform = posg_fsc.Controller.uniform(game, role, nodes).probabilities
    weights = np.where(uniform > 0, rng.uniform(0.1, 1.0, uniform.shape), 0.0)
    weights /= weights.sum(axis=(2, 3), keepdims=True)
    return posg_fsc.Controller.from_probabilities(game, role, weights)


def test_value_of_the_paper_grid_equals_the_cli_to_the_last_digit(cli, grid_file, tmp_path):
    game = posg_fsc.Game.load(grid_file)
    rng = np.random.default_rng(3)
    defender = random_controller(game, "defender", 2, rng)
    adversary = random_controller(game, "adversary", 2, rng)
    defender.save(tmp_path / "d.fsc.json")
    adversary.save(tmp_path / "a.fsc.json")
    for spec in [("uniform:1", "uniform:1"), (tmp_path / "d.fsc.json", tmp_path / "a.fsc.json")]:
        report = cli_json(
            cli, "eval", grid_file, "--ltl", FORMULA, "--defender", spec[0], "--adversary", spec[1]
        )
        ours = game.evaluate(FORMULA, defender=str(spec[0]), adversary=str(spec[1]))
        assert ours.value == report["value"]
        assert ours.error_bound == report["error_bound"]
        assert ours.gmc_states == report["gmc_states"]
        assert ours.bsccs == report["bsccs"]
    # The same controllers as objects give the same value as from their files.
    loaded = posg_fsc.Controller.load(tmp_path / "d.fsc.json", game)
    assert game.evaluate(FORMULA, defender=loaded, adversary=adversary).value == report["value"]
    assert 0.0 < report["value"] < 1.0


def test_gradients_equal_finite_differences():
    game = posg_fsc.example_grid()
    rng = np.random.default_rng(11)
    defender = random_controller(game, "defender", 2, rng)
    adversary = random_controller(game, "adversary", 2, rng)
    evaluation = game.evaluate(FORMULA, defender=defender, adversary=adversary, gradient=True)
    for role, controller, gradient in [
        ("defender", defender, evaluation.defender_gradient),
        ("adversary", adversary, evaluation.adversary_gradient),
    ]:
        mu = controller.probabilities
        assert gradient.shape == mu.shape
        assert np.all(gradient[mu == 0] == 0)
        checked = 0
        for g, o in [(0, 0), (1, 2), (0, 3)]:
            support = np.argwhere(mu[g, o] > 0)
            a, b = support[0], support[-1]
            # A direction inside the simplex: mass moves from entry b to entry a.
            step = 1e-6
            values = []
            for sign in (1, -1):
                moved = mu.copy()
                moved[g, o][tuple(a)] += sign * step
                moved[g, o][tuple(b)] -= sign * step
                other = posg_fsc.Controller.from_probabilities(game, role, moved)
                pair = (other, adversary) if role == "defender" else (defender, other)
                values.append(game.evaluate(FORMULA, defender=pair[0], adversary=pair[1]).value)
            finite_difference = (values[0] - values[1]) / (2 * step)
            adjoint = gradient[g, o][tuple(a)] - gradient[g, o][tuple(b)]
            assert finite_difference == pytest.approx(adjoint, rel=1e-5, abs=1e-8)
            checked += abs(adjoint) > 1e-6
        assert checked > 0, "every direction tried was flat: the test would prove nothing"


def test_certify_and_translate_equal_the_cli(cli, grid_file, tmp_path):
    game = posg_fsc.Game.load(grid_file)
    defender = posg_fsc.Controller.uniform(game, "defender", 1)
    defender.save(tmp_path / "d.fsc.json")
    report = cli_json(
        cli, "certify", grid_file, "--ltl", FORMULA,
        "--defender", tmp_path / "d.fsc.json", "--adversary", "uniform:1",
    )
    ours = posg_fsc.certify(game, FORMULA, defender, adversary="uniform:1")
    assert ours["lower"]["value"] == report["lower"]["value"]
    assert ours["upper"]["value"] == report["upper"]["value"]
    assert ours["lower"]["value"] <= ours["upper"]["value"]
    hoa = run_cli(cli, "translate", "--hoa", FORMULA).stdout
    assert posg_fsc.translate(FORMULA) == hoa


def test_a_pomdps_belief_bound_equals_the_cli(cli, grid_file):
    # tests/data/drn/coin.drn: no defender that cannot see the coin wins
    # more than 2/3 (docs/method.md section 6, the belief bound).
    model = REPOSITORY / "tests" / "data" / "drn" / "coin.drn"
    report = cli_json(cli, "certify", model, "--ltl", "F goal", "--defender", "uniform:1")
    game = posg_fsc.Game.from_drn(model)
    ours = posg_fsc.certify(game, "F goal", "uniform:1")
    assert ours["belief"]["value"] == report["belief"]["value"]
    assert ours["belief"]["value"] == pytest.approx(2 / 3, abs=1e-12)
    assert ours["belief"]["complete"] and report["belief"]["complete"]
    assert ours["lower"]["value"] <= ours["belief"]["value"]
    grid = posg_fsc.Game.load(grid_file)
    assert posg_fsc.certify(grid, FORMULA, "uniform:1")["belief"] is None


def test_support_equals_the_cli(cli, grid_file, tmp_path):
    game = posg_fsc.Game.load(grid_file)
    out = tmp_path / "support"
    run_cli(
        cli, "support", grid_file, "--ltl", FORMULA, "--def-nodes", "1", "--out", out
    )
    written = json.loads((out / "support.json").read_text())
    ours = posg_fsc.support(game, FORMULA, def_nodes=1)
    for key in ["found", "mode", "certified_lower", "support_entries", "exact", "reason"]:
        assert ours[key] == written[key], key
    if ours["found"]:
        assert ours["defender"].to_json().strip() == (out / "defender.fsc.json").read_text().strip()
