"""props=: a property file's query (a string or a file) in every function,
restated in its own terms; expected-reward queries in Game.evaluate, with
the values of `posg-fsc eval`."""

import json
import math

import numpy as np
import pytest

import posg_fsc
from conftest import REPOSITORY, cli_json, run_cli

PROBE = REPOSITORY / "tests" / "data" / "rewards" / "probe.drn"
PROBE_PROPS = REPOSITORY / "tests" / "data" / "rewards" / "probe.props"


def test_a_reward_query_from_a_file_or_a_string_gives_eval_s_value(cli):
    game = posg_fsc.Game.from_drn(PROBE)
    report = cli_json(cli, "eval", PROBE, "--props", PROBE_PROPS)
    for props in [PROBE_PROPS, str(PROBE_PROPS), 'Rmin=? [F "goal"]']:
        ours = game.evaluate(props=props)
        assert ours.value == report["value"]
        assert ours.query.value == report["query"]["value"]
        assert ours.query.target_probability == 1.0
    assert abs(ours.value - 16 / 3) < 1e-12
    assert ours.query.text == 'Rmin=? [F "goal"]'
    gradient = game.evaluate(props='R{"cost"}min=? [F "goal"]', gradient=True)
    report = cli_json(cli, "eval", PROBE, "--props", PROBE_PROPS, "--gradient")
    norm = np.linalg.norm(gradient.defender_gradient)
    assert abs(norm - report["gradient"]["defender_norm"]) < 1e-12 * norm


def test_an_infinite_expected_reward_is_inf_with_the_probability_of_the_target(tmp_path):
    game = posg_fsc.Game.from_json(
        """{"posg": 1, "states": ["s", "goal", "pit"], "initial": {"s": 1.0},
        "labels": {"goal": ["goal"]},
        "defender": {"actions": ["a"], "observe": "full"},
        "transitions": [
          {"state": "s", "defender": "a", "next": {"goal": 0.75, "pit": 0.25}},
          {"state": "goal", "defender": "a", "next": {"goal": 1.0}},
          {"state": "pit", "defender": "a", "next": {"pit": 1.0}}],
        "rewards": {"steps": {"states": {"s": 1.0, "pit": 1.0}}}}"""
    )
    evaluation = game.evaluate(props='Rmin=? [F "goal"]')
    assert evaluation.value == math.inf
    assert evaluation.query.target_probability == 0.75
    with pytest.raises(posg_fsc.Error, match="the expected reward is infinite"):
        game.evaluate(props='Rmin=? [F "goal"]', gradient=True)


def test_a_probability_query_is_restated_and_pmin_is_one_minus_its_complement(grid_file):
    game = posg_fsc.Game.load(grid_file)
    pmax = game.evaluate(props='Pmax=? [F "goal"]')
    assert pmax.query.value == pmax.value == game.evaluate("F goal").value
    pmin = game.evaluate(props='Pmin=? [F "goal"]')
    assert pmin.value == game.evaluate("G !goal").value
    assert pmin.query.value == 1 - pmin.value
    assert pmin.query.target_probability is None


def test_props_go_everywhere_ltl_goes_and_reward_queries_are_refused_where_not_taken(grid_file):
    game = posg_fsc.Game.load(grid_file)
    by_props = posg_fsc.certify(game, props='Pmax=? [!"unsafe" U "goal"]', defender="uniform:1")
    by_ltl = posg_fsc.certify(game, "!unsafe U goal", defender="uniform:1")
    assert by_props["lower"]["value"] == by_ltl["lower"]["value"]
    assert by_props["upper"] == by_ltl["upper"]
    settings = {"max_iterations": 5, "starts": 1, "structures": ["full"]}
    by_props = posg_fsc.solve(game, props='Pmax=? [F "goal"]', **settings)
    by_ltl = posg_fsc.solve(game, "F goal", **settings)
    assert by_props.worst_case == by_ltl.worst_case
    assert by_ltl.query is None
    assert by_props.query.value == by_props.worst_case
    # Pmin: the objective is G !goal; restated, the bracket turns over.
    pmin = posg_fsc.solve(game, props='Pmin=? [F "goal"]', **settings)
    assert pmin.query.value == 1 - pmin.worst_case
    bracket = pmin.certified
    assert pmin.query.certified == [1 - bracket["upper_bound"], 1 - bracket["certified_lower"]]
    for function in [
        lambda: posg_fsc.sweep(game, props='R{"r"}min=? [F "goal"]'),
        lambda: posg_fsc.support(game, props='Rmax=? [F "goal"]'),
    ]:
        with pytest.raises(posg_fsc.SettingsError, match="is an expected-reward query"):
            function()


def test_bad_props_are_errors_that_say_what_to_give(grid_file, tmp_path):
    game = posg_fsc.Game.load(grid_file)
    with pytest.raises(posg_fsc.SettingsError, match="not both"):
        game.evaluate("F goal", props='Pmax=? [F "goal"]')
    with pytest.raises(posg_fsc.SettingsError, match="give the objective"):
        game.evaluate()
    with pytest.raises(posg_fsc.FormulaError, match="props: line 1, column 9: a cumulative reward"):
        game.evaluate(props="Rmin=? [C]")
    with pytest.raises(posg_fsc.FormulaError, match='no reward model "steps"'):
        game.evaluate(props='R{"steps"}min=? [F "goal"]')
    with pytest.raises(posg_fsc.SettingsError, match="cannot read"):
        game.evaluate(props=tmp_path / "missing.props")
    with pytest.raises(posg_fsc.SettingsError, match="certify needs the defender"):
        posg_fsc.certify(game, "F goal")


def test_solve_optimises_an_expected_cost_on_a_pomdp_as_the_cli_does(cli, tmp_path):
    game = posg_fsc.Game.from_drn(PROBE)
    seen = []
    result = posg_fsc.solve(game, props=PROBE_PROPS, def_nodes=1, seed=1, on_iteration=seen.append,
                            out=tmp_path / "out")
    assert result.value == 1.0 and result.query.value == 1.0
    assert result.curve[-1]["returned"] and result.curve[-1]["value"] == 1.0
    assert len(result.starts) == 4 and seen
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["value"] == 1.0 and summary["query"]["text"] == 'Rmin=? [F "goal"]'
    run_cli(cli, "solve", PROBE, "--props", PROBE_PROPS, "--seed", "1", "--out", tmp_path / "cli",
            "--quiet")
    by_cli = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert by_cli["value"] == summary["value"]
    assert [s["value"] for s in by_cli["starts"]] == [s["value"] for s in result.starts]
    with pytest.raises(posg_fsc.SettingsError, match="drop defender="):
        posg_fsc.solve(game, props=PROBE_PROPS, defender="uniform:1")
    with pytest.raises(posg_fsc.SettingsError, match="def_nodes"):
        posg_fsc.solve(game, props=PROBE_PROPS, def_nodes=10**9)
    with pytest.warns(UserWarning, match="import-drn --defender-player 1"):
        game.evaluate(props='<<1>> Rmin=? [F "goal"]')


def test_an_infinite_reward_is_inf_in_the_result_and_its_records():
    # `stay` alone never reaches the goal: for Rmax the infinite reward is the optimum.
    game = posg_fsc.Game.from_json(
        """{"posg": 1, "states": ["s", "goal"], "initial": {"s": 1.0},
        "labels": {"goal": ["goal"]},
        "defender": {"actions": ["go", "stay"], "observe": "full"},
        "transitions": [
          {"state": "s", "defender": "go", "next": {"goal": 1.0}},
          {"state": "s", "defender": "stay", "next": {"s": 1.0}},
          {"state": "goal", "defender": "*", "next": {"goal": 1.0}}],
        "rewards": {"steps": {"states": {"s": 1.0}}}}"""
    )
    result = posg_fsc.solve(game, props='Rmax=? [F "goal"]')
    assert result.value == math.inf
    assert result.curve[-1]["returned"] and result.curve[-1]["value"] == math.inf
    assert result.query.target_probability is None
    assert result.dropped_starts == []


def test_simulate_reports_what_the_command_reports(cli, tmp_path):
    game = posg_fsc.Game.from_drn(PROBE)
    ours = posg_fsc.simulate(game, props=PROBE_PROPS, runs=2000, seed=5)
    theirs = cli_json(cli, "simulate", PROBE, "--props", PROBE_PROPS, "--runs", "2000", "--seed", "5")
    for key in ["formula", "query", "settings", "estimate", "exact_value", "exact_within_interval"]:
        assert ours[key] == theirs[key], key
    assert abs(ours["exact_value"] - 16 / 3) < 1e-12
    assert ours["query"]["text"] == PROBE_PROPS.read_text().strip()
    assert ours["estimate"]["lower"] <= ours["estimate"]["mean"] <= ours["estimate"]["upper"]
    grid = posg_fsc.example_grid()
    probability = posg_fsc.simulate(grid, "F goal", runs=500, seed=1)
    assert probability["estimate"]["runs"] == 500
    assert 0 <= probability["estimate"]["lower"] <= probability["estimate"]["upper"] <= 1
    with pytest.raises(posg_fsc.SettingsError, match="runs"):
        posg_fsc.simulate(grid, "F goal", runs=0)
    # A Pmin query is sampled as its complement and restated as itself.
    pmin = posg_fsc.simulate(grid, props='Pmin=? [F "goal"]', runs=500, seed=1)
    complement = pmin["estimate"]
    assert pmin["formula"] == "G !goal"
    assert abs(pmin["query"]["mean"] - (1 - complement["mean"])) < 1e-12
    assert pmin["query"]["interval"] == pytest.approx([1 - complement["upper"], 1 - complement["lower"]])
    assert abs(pmin["query"]["exact_value"] - (1 - pmin["exact_value"])) < 1e-12


def test_a_misspelt_keyword_gets_the_closest_one():
    grid = posg_fsc.example_grid()
    with pytest.raises(TypeError, match="did you mean 'max_iterations'"):
        posg_fsc.solve(grid, "F goal", max_iteratons=3)
    with pytest.raises(TypeError, match="did you mean 'on_iteration'"):
        posg_fsc.solve(grid, "F goal", on_iteraton=print)
    with pytest.raises(TypeError) as raised:
        posg_fsc.solve(grid, "F goal", completely_unknown=1)
    assert "did you mean" not in str(raised.value)


def test_a_stormpy_model_becomes_the_game_of_its_drn_export(tmp_path):
    stormpy = pytest.importorskip("stormpy")
    prism = tmp_path / "probe.prism"
    prism.write_text(
        """pomdp
observables o endobservables
module m
  s : [0..2] init 0;
  o : [0..1] init 0;
  [probe] s=0 -> 0.5 : (s'=1) & (o'=1) + 0.5 : (s'=2) & (o'=1);
  [guess] s=0 -> (s'=1) & (o'=1);
  [stay] s>0 -> (s'=s) & (o'=1);
endmodule
rewards "cost"
  [probe] true : 2;
  [guess] true : 5;
endrewards
label "goal" = s>0;
"""
    )
    program = stormpy.parse_prism_program(str(prism))
    options = stormpy.BuilderOptions()
    options.set_build_choice_labels()
    options.set_build_all_reward_models()
    options.set_build_all_labels()
    options.set_build_state_valuations()
    if hasattr(stormpy, "build_sparse_model_with_options"):  # stormpy before 2.0
        model = stormpy.build_sparse_model_with_options(program, options)
    else:
        model = stormpy.build_model(program, options=options)
    game = posg_fsc.Game.from_stormpy(model)
    assert sorted(game.defender_actions) == ["guess", "probe", "stay"]
    evaluation = game.evaluate(props='R{"cost"}min=? [F "goal"]')
    assert evaluation.value == 3.5  # uniform over {probe, guess}: (2 + 5) / 2
    with pytest.raises(posg_fsc.GameFormatError, match="stormpy"):
        posg_fsc.Game.from_stormpy("not a model")


TWO_ROADS = REPOSITORY / "tests" / "data" / "rewards" / "two-roads.posg.json"


def test_a_cost_on_a_game_is_certified_against_every_adversary_as_the_cli_does(cli, tmp_path):
    # Each round the defender takes a road the adversary may guard: the
    # game's value is 8/3, at the mixed strategy (docs/method.md section 9).
    game = posg_fsc.Game.load(TWO_ROADS)
    props = 'R{"cost"}min=? [F "goal"]'
    result = posg_fsc.solve(game, props=props, seed=1, out=tmp_path / "out")
    certificate = result.certificate
    assert result.value == certificate["guaranteed"]
    assert 8 / 3 - 1e-9 <= certificate["guaranteed"] < 8 / 3 * 1.01
    assert certificate["best_possible"] <= 8 / 3 + 1e-9
    defender = tmp_path / "out" / "defender.fsc.json"
    by_python = posg_fsc.certify(game, props=props, defender=defender, adversary="uniform:1")
    (tmp_path / "cost.props").write_text(props + "\n")
    by_cli = cli_json(cli, "certify", TWO_ROADS, "--props", tmp_path / "cost.props", "--defender",
                      defender, "--adversary", "uniform:1")
    for key in ["guaranteed", "best_possible", "minimise", "query"]:
        assert by_python[key] == by_cli[key]
    assert by_python["guaranteed"] == pytest.approx(certificate["guaranteed"], abs=1e-12)
    assert by_python["best_possible"] == pytest.approx(8 / 3, abs=1e-9)
