"""Issue 57's bad inputs from Python: each raises a posg_fsc error with the
CLI's message (or runs), and the interpreter survives."""

import numpy as np
import pytest

import posg_fsc
from conftest import FORMULA, cli_error


def test_a_huge_grid_is_a_game_format_error_with_the_cli_message(cli, tmp_path):
    # It allocated terabytes and killed the interpreter.
    with pytest.raises(posg_fsc.GameFormatError) as raised:
        posg_fsc.example_grid(10**6, 10**6)
    out = tmp_path / "big.posg.json"
    arguments = ("example", "grid", "--width", 10**6, "--height", 10**6, "--out", out)
    assert str(raised.value) == cli_error(cli, *arguments)
    assert "MAX_TRANSITION_TRIPLES" in str(raised.value)


@pytest.mark.parametrize("name", ["time_budget", "synthesis_time_budget"])
def test_a_time_budget_beyond_the_clock_means_no_limit(name):
    # Duration::from_secs_f64 panicked on these.
    game = posg_fsc.example_grid()
    for seconds in [1e20, 1e308]:
        result = posg_fsc.solve(game, FORMULA, max_iterations=2, **{name: seconds})
        assert 0.0 <= result.worst_case <= 1.0
    with pytest.raises(ValueError, match=name):
        posg_fsc.solve(game, FORMULA, max_iterations=2, **{name: float("nan")})


def test_a_row_within_the_tolerance_is_rescaled_and_beyond_it_refused():
    # A row summing to 1 + 1e-7 was kept as it was: not a distribution.
    game = posg_fsc.example_grid()
    weights = np.zeros((1, len(game.defender_observations), 1, len(game.defender_actions)))
    weights[0, :, 0, :2] = 0.5
    weights[0, 1, 0, 1] += 1e-7
    fsc = posg_fsc.Controller.from_probabilities(game, "defender", weights)
    assert abs(fsc.probabilities[0, 1].sum() - 1.0) <= 2 * np.finfo(float).eps
    weights[0, 1, 0, 1] += 1e-5
    with pytest.raises(posg_fsc.GameFormatError) as raised:
        posg_fsc.Controller.from_probabilities(game, "defender", weights)
    message = str(raised.value)
    assert "node 0, observation 1" in message and "tolerance 1e-6" in message, message
