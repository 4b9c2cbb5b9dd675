"""The shape of the API: numpy axes as documented, every exception class
raised by a bad input with the CLI's message, wrong Python types."""

import warnings

import numpy as np
import pytest

import posg_fsc
from conftest import FORMULA, cli_error


def test_probabilities_have_the_documented_axes():
    game = posg_fsc.example_grid()
    controller = posg_fsc.Controller.uniform(game, "defender", 3)
    mu = controller.probabilities
    # (node, observation, next_node, action)
    assert mu.shape == (3, len(game.defender_observations), 3, len(game.defender_actions))
    assert mu.dtype == np.float64
    np.testing.assert_allclose(mu.sum(axis=(2, 3)), 1.0)
    assert list(controller.initial) == [1.0, 0.0, 0.0]
    # One entry set by index appears in the file under the names of its axes.
    weights = np.zeros((2, 6, 2, 4))
    weights[:, :, 0, 0] = 1.0
    weights[1, 2] = 0.0
    weights[1, 2, 1, 3] = 1.0
    fsc = posg_fsc.Controller.from_probabilities(game, "defender", weights)
    np.testing.assert_array_equal(fsc.probabilities, weights)
    text = fsc.to_json()
    observation, action = game.defender_observations[2], game.defender_actions[3]
    assert observation in text and action in text
    round_trip = posg_fsc.Controller.from_json(text, game, "defender")
    np.testing.assert_array_equal(round_trip.probabilities, weights)
    evaluation = game.evaluate(FORMULA, defender=fsc, gradient=True)
    assert evaluation.defender_gradient.shape == weights.shape
    assert evaluation.adversary_gradient.shape == (1, len(game.adversary_observations), 1, 2)
    assert evaluation.defender_initial_gradient.shape == (2,)


def test_game_properties():
    game = posg_fsc.example_grid()
    assert game.states == [f"s{i}" for i in range(6)]
    assert game.defender_actions == ["R", "L", "U", "D"]
    assert game.adversary_actions == ["A", "NA"]
    assert dict(game.labels)["s4"] == ["unsafe"] and dict(game.labels)["s5"] == ["goal"]
    assert game.initial == [("s0", 1.0)]
    assert posg_fsc.Game.from_json(game.to_json()).to_json() == game.to_json()


def test_a_truncated_game_is_a_game_format_error_with_the_cli_message(cli, grid_file, tmp_path):
    text = grid_file.read_text()
    truncated = tmp_path / "truncated.posg.json"
    truncated.write_text(text[: len(text) // 2])
    with pytest.raises(posg_fsc.GameFormatError) as raised:
        posg_fsc.Game.load(truncated)
    assert str(raised.value) == cli_error(cli, "check", truncated)
    assert isinstance(raised.value, posg_fsc.Error)


def test_a_bad_formula_is_a_formula_error_with_the_cli_message(cli, grid_file):
    game = posg_fsc.Game.load(grid_file)
    with pytest.raises(posg_fsc.FormulaError) as raised:
        game.evaluate("G (goal &")
    assert str(raised.value) == cli_error(cli, "eval", grid_file, "--ltl", "G (goal &")
    with pytest.raises(posg_fsc.FormulaError):
        posg_fsc.solve(game, "F (", max_iterations=5)


def test_an_unsolvable_tolerance_is_a_numerical_error_with_the_cli_message(cli, grid_file):
    game = posg_fsc.Game.load(grid_file)
    with pytest.raises(posg_fsc.NumericalError) as raised:
        game.evaluate(FORMULA, tolerance=1e-300)
    assert str(raised.value) == cli_error(
        cli, "eval", grid_file, "--ltl", FORMULA, "--tolerance", "1e-300"
    )


def test_an_unknown_keyword_is_a_type_error_naming_it():
    game = posg_fsc.example_grid()
    with pytest.raises(TypeError, match="max_iteration"):
        posg_fsc.solve(game, FORMULA, max_iteration=5)
    with pytest.raises(TypeError, match="colour"):
        posg_fsc.support(game, FORMULA, colour="red")


def test_zero_nodes_is_a_settings_error():
    game = posg_fsc.example_grid()
    with pytest.raises(posg_fsc.SettingsError, match="def_nodes"):
        posg_fsc.solve(game, FORMULA, def_nodes=0)
    with pytest.raises(ValueError, match="nodes"):
        posg_fsc.Controller.uniform(game, "defender", 0)
    with pytest.raises(posg_fsc.SettingsError, match="starts"):
        posg_fsc.solve(game, FORMULA, starts=0)
    assert issubclass(posg_fsc.SettingsError, posg_fsc.Error)
    assert issubclass(posg_fsc.SettingsError, ValueError)


@pytest.mark.parametrize(
    "call, error, name",
    [
        (lambda g: posg_fsc.solve(g, FORMULA, def_nodes="2"), TypeError, "def_nodes"),
        (lambda g: posg_fsc.solve(g, FORMULA, def_nodes=1.5), TypeError, "def_nodes"),
        (lambda g: posg_fsc.solve(g, FORMULA, adv_nodes=-1), ValueError, "adv_nodes"),
        (lambda g: posg_fsc.solve(g, FORMULA, max_iterations="many"), TypeError, "max_iterations"),
        (lambda g: posg_fsc.solve(g, FORMULA, starts=-2), ValueError, "starts"),
        (lambda g: posg_fsc.solve(g, FORMULA, update="newton"), ValueError, "update"),
        (lambda g: posg_fsc.solve(g, FORMULA, structures=["full", "magic"]), ValueError, "structures"),
        (lambda g: posg_fsc.solve(g, 42), TypeError, "ltl"),
        (lambda g: posg_fsc.Controller.uniform(g, "attacker", 1), ValueError, "role"),
        (lambda g: posg_fsc.Controller.uniform(g, "defender", "two"), TypeError, "nodes"),
        (
            lambda g: posg_fsc.Controller.from_probabilities(g, "defender", np.ones((2, 6, 2))),
            ValueError,
            "probabilities",
        ),
        (
            lambda g: posg_fsc.Controller.from_probabilities(g, "defender", [[["x"]]]),
            TypeError,
            "probabilities",
        ),
        (lambda g: g.evaluate(FORMULA, defender=3), TypeError, "defender"),
        (lambda g: g.evaluate(FORMULA, solver="gauss"), ValueError, "solver"),
        (lambda g: posg_fsc.example_grid(width=-1), ValueError, "width"),
        (lambda g: posg_fsc.example_grid(unsafe="s4"), TypeError, "unsafe"),
        (lambda g: posg_fsc.sweep(g, FORMULA, def_nodes=[1, 0]), ValueError, "def_nodes"),
    ],
)
def test_wrong_python_types_name_the_argument(call, error, name):
    game = posg_fsc.example_grid()
    with pytest.raises(error, match=name):
        call(game)


def test_every_public_name_has_a_docstring():
    for name in posg_fsc.__all__ if hasattr(posg_fsc, "__all__") else dir(posg_fsc):
        if name.startswith("_"):
            continue
        item = getattr(posg_fsc, name)
        assert item.__doc__ and item.__doc__.strip(), name
    for cls in [posg_fsc.Game, posg_fsc.Controller]:
        for name, member in vars(cls).items():
            if not name.startswith("_"):
                assert member.__doc__ and member.__doc__.strip(), f"{cls.__name__}.{name}"


def test_a_proposition_that_labels_no_state_is_a_warning_or_an_error(cli, grid_file):
    game = posg_fsc.Game.load(grid_file)
    with pytest.warns(UserWarning, match="did you mean goal"):
        value = game.evaluate("(!unsafe U goal) | F gaol").value
    assert value == game.evaluate(FORMULA).value
    with pytest.warns(UserWarning), pytest.raises(posg_fsc.FormulaError) as raised:
        game.evaluate("F gaol")
    assert str(raised.value) == cli_error(cli, "eval", grid_file, "--ltl", "F gaol")
    with pytest.warns(UserWarning):
        assert game.evaluate("F gaol", allow_unused_propositions=True).value == 0.0


def test_a_drn_model_imports_as_the_cli_imports_it(cli, tmp_path):
    from conftest import REPOSITORY, run_cli

    model = REPOSITORY / "tests" / "data" / "drn" / "dark-corridor.drn"
    run_cli(cli, "import-drn", model, "--out", tmp_path / "corridor.posg.json")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # rewards are kept, the labels are names
        game = posg_fsc.Game.from_drn(model)
    assert game.to_json() == posg_fsc.Game.load(tmp_path / "corridor.posg.json").to_json()
    assert not game.has_adversary and game.name == "dark-corridor"


def test_a_game_from_numpy_arrays_is_the_json_game_it_describes():
    import numpy as np

    # The probe POMDP of tests/data/rewards: s0 (observed "start") probes or
    # guesses; s1, s2 (observed "end") stay.
    t = np.zeros((3, 3, 3))
    t[0, 0] = [0.0, 0.5, 0.5]  # probe
    t[0, 1] = [0.0, 1.0, 0.0]  # guess
    t[1, 2, 1] = t[2, 2, 2] = 1.0  # stay
    game = posg_fsc.Game.from_arrays(
        t,
        observations=[0, 1, 1],
        observation_names=["start", "end"],
        actions=["probe", "guess", "stay"],
        labels={"goal": [1, 2]},
        rewards={"cost": np.array([[2.0, 5.0, 0.0]] + [[0.0] * 3] * 2)},
        name="probe",
    )
    assert game.defender_observations == ["start", "end"]
    assert game.evaluate(props='R{"cost"}min=? [F "goal"]').value == 3.5
    assert game.evaluate("F goal").value == 1.0
    again = posg_fsc.Game.from_json(game.to_json())
    assert again.to_json() == game.to_json()
    labels = np.array([False, True, True])
    assert posg_fsc.Game.from_arrays(t, observations=[0, 1, 1], labels={"goal": labels}).evaluate(
        "F goal"
    ).value == 1.0
    # A game: the adversary's axis before the successor, full observation.
    g = np.zeros((2, 1, 2, 2))
    g[0, 0, 0] = [0.5, 0.5]
    g[0, 0, 1] = [1.0, 0.0]
    g[1, 0, :, 1] = 1.0
    duel = posg_fsc.Game.from_arrays(g, labels={"goal": [1]}, adversary_actions=["let", "block"])
    assert duel.adversary_actions == ["let", "block"]
    assert duel.evaluate("F goal").value == 1.0  # the uniform adversary lets through eventually
    bad = t.copy()
    bad[0, 1] = [0.0, 0.9, 0.0]
    with pytest.raises(posg_fsc.SettingsError, match=r"transitions\[0, 1\] \(state s0, action guess\) sums to 0.9"):
        posg_fsc.Game.from_arrays(bad, observations=[0, 1, 1], actions=["probe", "guess", "stay"])
    with pytest.raises(posg_fsc.SettingsError, match="share the observation"):
        posg_fsc.Game.from_arrays(t, observations=[0, 0, 1])
    with pytest.raises(posg_fsc.SettingsError, match="shape"):
        posg_fsc.Game.from_arrays(np.zeros((3, 2)))
    with pytest.raises(posg_fsc.SettingsError, match="not an observation index"):
        posg_fsc.Game.from_arrays(t, observations=[0, 1e300, 1])
    with pytest.raises(posg_fsc.SettingsError, match="boolean array"):
        posg_fsc.Game.from_arrays(t, observations=[0, 1, 1], labels={"goal": [True, False]})
    blocked = np.zeros((2, 2, 2, 2))
    blocked[0, 0, 0] = blocked[0, 1, 1] = [0.0, 1.0]
    blocked[1, :, :, 1] = 1.0
    with pytest.raises(posg_fsc.SettingsError, match="every pair of them needs a distribution"):
        posg_fsc.Game.from_arrays(blocked)


def test_help_lists_every_setting_with_its_default_and_meaning():
    listed = {s["keyword"]: s for s in posg_fsc.settings()}
    for keyword in ["max_iterations", "max_work", "starts", "tolerance", "lu_limit",
                    "structures", "engine", "synthesis_time_budget", "grow_defender"]:
        assert keyword in listed, keyword
        assert listed[keyword]["meaning"], keyword
    assert listed["max_iterations"]["default"] == 3000
    assert "synthesis" not in listed and "mode" not in listed
    for function in [posg_fsc.solve, posg_fsc.sweep]:
        assert "max_work=3500000.0: The most work one start's max-min loop" in function.__doc__
        assert function.__name__ in ("solve", "sweep")
    # Every listed keyword is taken.
    grid = posg_fsc.example_grid()
    posg_fsc.solve(grid, "F goal", lu_limit=listed["lu_limit"]["default"], max_iterations=2, starts=1)
