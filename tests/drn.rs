//! Importing Storm's explicit DRN format (formats.md section 6): a
//! hand-written POMDP whose values are derived on paper, small MDPs and
//! DTMCs, and one test per construct the importer must refuse.

use std::path::Path;

use posg_fsc::certify::{lower_bound, upper_bound};
use posg_fsc::controller::Role;
use posg_fsc::controller::file::{from_json_str as fsc_from_json, resolve};
use posg_fsc::game::drn::{from_drn_str, read};
use posg_fsc::game::file::{from_json_str, to_json_string};
use posg_fsc::game::{AdversaryAction, DefenderAction, Posg};
use posg_fsc::ltl;
use posg_fsc::value::SolverSettings;
use posg_fsc::value::evaluate_controllers;
use serde_json::json;

fn dark_corridor() -> Posg {
    let import = read(Path::new("tests/data/drn/dark-corridor.drn")).unwrap();
    assert!(import.warnings.is_empty(), "{:?}", import.warnings);
    import.game
}

fn drn(text: &str) -> Result<Posg, String> {
    from_drn_str(text, "m.drn", None)
        .map(|import| import.game)
        .map_err(|e| e.to_string())
}

fn value(game: &Posg, formula: &str, defender: &str) -> f64 {
    let dra = ltl::translate(&ltl::parse(formula).unwrap()).unwrap();
    let def = resolve(defender, game, Role::Defender).unwrap();
    let adv = resolve("uniform:1", game, Role::Adversary).unwrap();
    evaluate_controllers(game, &dra, &def, &adv, &SolverSettings::default())
        .unwrap()
        .1
        .value
}

#[test]
fn the_dark_corridor_is_read_as_a_pomdp_game() {
    let g = dark_corridor();
    assert_eq!(g.name(), Some("dark-corridor"));
    assert!(!g.has_adversary());
    assert_eq!(g.states(), ["s0", "s1", "s2", "s3", "s4"]);
    assert_eq!(g.initial(), [(0, 0.5), (1, 0.5)]);
    assert_eq!(g.propositions(), ["goal", "trap"]);
    assert_eq!(g.label_names(2).collect::<Vec<_>>(), ["goal"]);
    assert_eq!(g.label_names(3).collect::<Vec<_>>(), ["trap"]);
    let def = g.defender();
    assert_eq!(def.actions(), ["left", "right", "stay"]);
    assert_eq!(def.observations(), ["o0", "o1", "o2"]);
    assert_eq!(def.observation_distribution(4), [(1, 1.0)]);
    assert_eq!(def.enabled_actions(0).collect::<Vec<_>>(), [0, 1]);
    assert_eq!(def.enabled_actions(1).collect::<Vec<_>>(), [2]);
    assert!(
        g.transition(0, DefenderAction(2), AdversaryAction(0))
            .is_empty()
    );
    assert_eq!(
        g.transition(0, DefenderAction(0), AdversaryAction(0)).len(),
        3
    );
    let left = g.transition(0, DefenderAction(0), AdversaryAction(0));
    assert!((left[1].1 - 0.3).abs() < 1e-15 && left[1].0 == 2);
}

#[test]
fn the_dark_corridor_has_the_values_derived_on_paper() {
    // uniform:1 in the dark: x0 = (0.3 + 0.6 x0)/2 + (0.8 x1 + 0.2 x0)/2,
    // x1 = x0/2 + 1/4, so x0 = 5/8, x1 = 9/16, and the value is (x0 + x1)/2.
    let g = dark_corridor();
    let v = value(&g, "F goal", "uniform:1");
    assert!((v - 0.59375).abs() < 1e-12, "{v}");
    // Full observation: s0 plays left (0.3 / 0.4 = 3/4), s1 goes back left.
    let phi = ltl::parse("F goal").unwrap();
    let adv = resolve("uniform:1", &g, Role::Adversary).unwrap();
    let upper = upper_bound(&g, &ltl::translate(&phi).unwrap(), &adv).unwrap();
    assert!((upper.value - 0.75).abs() < 1e-12, "{}", upper.value);
    // "Always left" attains it without seeing the state: a lower bound of 3/4.
    let always_left = fsc_from_json(
        &json!({"fsc": 1, "player": "defender", "nodes": 1, "initial": [1.0], "rules": [
            {"node": 0, "observation": "o0", "choices": [{"next": 0, "action": "left", "p": 1.0}]}
        ], "default": "uniform"})
        .to_string(),
        "left.fsc.json",
        &g,
        Role::Defender,
    )
    .unwrap();
    let lower = lower_bound(&g, &ltl::translate(&phi.negate()).unwrap(), &always_left).unwrap();
    assert!((lower.value - 0.75).abs() < 1e-12, "{}", lower.value);
}

#[test]
fn an_imported_game_is_written_and_read_back_unchanged() {
    let g = dark_corridor();
    let text = to_json_string(&g);
    assert_eq!(from_json_str(&text, "again.posg.json").unwrap(), g);
}

const MDP: &str = "@type: MDP
@nr_states
3
@nr_choices
4
@model
state 0 init
\taction a
\t\t1 : 1
\taction b
\t\t2 : 1
state 1 goal
\taction c
\t\t1 : 1
state 2
\taction a
\t\t2 : 1
";

#[test]
fn an_mdp_is_fully_observed_with_actions_enabled_per_state() {
    let g = drn(MDP).unwrap();
    let def = g.defender();
    assert!(def.observes_fully());
    assert_eq!(def.observations(), ["s0", "s1", "s2"]);
    assert_eq!(def.actions(), ["a", "b", "c"]);
    assert_eq!(def.enabled_actions(0).collect::<Vec<_>>(), [0, 1]);
    assert_eq!(def.enabled_actions(1).collect::<Vec<_>>(), [2]);
    assert_eq!(def.enabled_actions(2).collect::<Vec<_>>(), [0]);
    assert!((value(&g, "F goal", "uniform:1") - 0.5).abs() < 1e-12);
}

#[test]
fn a_dtmc_has_one_action_per_state() {
    let text = "@type: DTMC\n@nr_states\n2\n@model\nstate 0 init\n\taction __NOLABEL__\n\t\t0 : 1/4\n\t\t1 : 3/4\nstate 1 done\n\taction __NOLABEL__\n\t\t1 : 1\n";
    let g = drn(text).unwrap();
    // Issue 59: Storm's `__NOLABEL__` is the state's choice `#0`.
    assert_eq!(g.defender().actions(), ["unlabelled_0"]);
    assert_eq!(g.defender().action_labels(), ["(unlabelled #0)"]);
    assert!((value(&g, "F done", "uniform:1") - 1.0).abs() < 1e-12);
    assert!((value(&g, "X done", "uniform:1") - 0.75).abs() < 1e-12);
}

/// The dark corridor with `from` replaced by `to`.
fn corridor_with(from: &str, to: &str) -> String {
    let text = std::fs::read_to_string("tests/data/drn/dark-corridor.drn").unwrap();
    assert!(text.contains(from), "{from}");
    text.replacen(from, to, 1)
}

#[test]
fn constructs_the_game_format_cannot_say_are_errors_naming_the_line() {
    let cases = [
        (
            corridor_with("@type: POMDP", "@type: CTMC"),
            "m.drn: line 7: model type `CTMC` cannot be imported",
        ),
        (
            corridor_with("@parameters\n\n", "@parameters\np q\n"),
            "m.drn: line 10: parametric models cannot be imported",
        ),
        (
            corridor_with("@value_type: double", "@value_type: double-interval"),
            "line 8: value type `double-interval`",
        ),
        (
            corridor_with(
                "state 1 {0} [1] init\n\taction left [1]",
                "state 1 {0} [1] init\n\taction back [1]",
            ),
            "m.drn: line 27: state 1 offers {right, back}, but state 0 (line 18) with the same observation offers {left, right}",
        ),
        (
            corridor_with(
                "\taction right [1]\n\t\t1 : 0.8",
                "\taction left [1]\n\t\t1 : 0.8",
            ),
            "line 24: a second choice labelled `left` in this state (the first is at line 20)",
        ),
        (
            corridor_with("\t\t1 : 0.8", "\t\t1 : 0.7"),
            "line 24: the probabilities of this choice sum to 0.8999999999999999, not 1",
        ),
        (
            corridor_with("\t\t1 : 0.8", "\t\t7 : 0.8"),
            "line 25: target 7 is not a state (@nr_states is 5)",
        ),
        (
            corridor_with("\t\t0 : 0.2", "\t\t0 : 0.2\n\t\t0 : 0.0"),
            "line 27: target 0 appears twice in this choice",
        ),
        (
            corridor_with("state 1 {0}", "state 2 {0}"),
            "line 27: expected state 1 (states are numbered in order), found `2`",
        ),
        (
            corridor_with("trap deadlock", "Trap deadlock"),
            "line 37: label `Trap` is not a valid proposition name",
        ),
        (
            corridor_with("@nr_choices\n7", "@nr_choices\n8"),
            "m.drn: line 16: @nr_choices declares 8 choices, the model has 7",
        ),
        (
            corridor_with("@nr_states\n5", "@nr_states\n6"),
            "m.drn: line 14: @nr_states declares 6 states, the model has 5",
        ),
        (
            corridor_with(
                "state 0 {0} [1] init\n//[x=0]\n\taction left [1]\n",
                "state 0 {0} [1] init\n",
            ),
            "line 19: a transition before the first `action` line of its state",
        ),
        (
            corridor_with("state 3 {2} [0] trap deadlock", "state 3 [0] trap deadlock"),
            "line 37: a POMDP state needs its observation `{k}`",
        ),
        (
            corridor_with("\t\t1 : 0.8", "\t\t1 : eight"),
            "line 25: `eight` is not a probability",
        ),
        (
            corridor_with("@model", "@states"),
            "line 17: unexpected header line `@states`",
        ),
        (
            corridor_with("@model", ""),
            "m.drn: line 18: unexpected header line `state 0 {0} [1] init`",
        ),
        (
            "@type: MDP\n@nr_states\n1\n".to_string(),
            "m.drn: the file ends before `@model`",
        ),
        (
            corridor_with("[1] init\n//[x=0]", "[1]\n//[x=0]").replacen("[1] init", "[1]", 1),
            "m.drn: no state is labelled `init`",
        ),
        (
            corridor_with("@nr_states", "@placeholders\n$a : 0.5\n@nr_states"),
            "line 13: placeholders",
        ),
    ];
    for (text, expected) in cases {
        let error = drn(&text).unwrap_err();
        assert!(
            error.contains(expected),
            "expected `{expected}` in `{error}`"
        );
    }
}

#[test]
fn a_state_without_choices_is_an_error() {
    let error = drn("@type: MDP\n@nr_states\n1\n@model\nstate 0 init\n").unwrap_err();
    assert!(
        error.contains("m.drn: line 5: a state without choices"),
        "{error}"
    );
}
