//! What the library checks once for every face (command line, Python):
//! controller sizes against the game ([`Sizes::check`]) and the objective's
//! automata with its propositions ([`Automata::for_game`]).

use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::game::grid::GridSpec;
use posg_fsc::ltl::TranslationBudget;
use posg_fsc::pipeline::{Automata, PipelineError, Sizes};

/// A two-state POMDP: the defender alone, `goal` in state b.
fn pomdp() -> Posg {
    from_json_str(
        r#"{"posg": 1, "states": ["a", "b"], "initial": {"a": 1.0},
            "labels": {"b": ["goal"]},
            "defender": {"actions": ["go"], "observe": "full"},
            "transitions": [{"state": "a", "defender": "go", "next": {"b": 0.25, "a": 0.75}},
                            {"state": "b", "defender": "go", "next": {"b": 1.0}}]}"#,
        "small.posg.json",
    )
    .unwrap()
}

fn sizes(defender: usize, adversary: usize) -> Sizes {
    Sizes {
        defender,
        adversary,
    }
}

const BUDGET: TranslationBudget = TranslationBudget { seconds: 60.0 };

#[test]
fn sizes_errors_name_the_callers_options() {
    let game = GridSpec::default().build().unwrap();
    assert!(
        sizes(2, 3)
            .check(&game, ["--def-nodes", "--adv-nodes"])
            .is_ok()
    );
    let zero = sizes(0, 1)
        .check(&game, ["def_nodes", "adv_nodes"])
        .unwrap_err();
    assert_eq!(zero.path, "def_nodes");
    assert!(zero.message.contains("at least one node"), "{zero}");
    let huge = sizes(1, 1 << 40).check(&game, ["--def-nodes", "--adv-nodes"]);
    assert_eq!(huge.unwrap_err().path, "--adv-nodes");
}

#[test]
fn a_pomdp_takes_exactly_one_adversary_node() {
    let game = pomdp();
    assert!(
        sizes(3, 1)
            .check(&game, ["--def-nodes", "--adv-nodes"])
            .is_ok()
    );
    let error = sizes(1, 2)
        .check(&game, ["--def-nodes", "--adv-nodes"])
        .unwrap_err();
    assert_eq!(
        error.to_string(),
        "--adv-nodes 2: the game has no adversary (it is a POMDP), whose controller has \
         exactly one node; drop --adv-nodes"
    );
    let error = sizes(1, 2)
        .check(&game, ["def_nodes", "adv_nodes"])
        .unwrap_err();
    assert!(error.to_string().starts_with("adv_nodes 2: "), "{error}");
}

#[test]
fn the_objective_comes_with_its_negation_only_when_asked() {
    let game = pomdp();
    let (with, warnings) = Automata::for_game(&game, "F goal", &BUDGET, true, false).unwrap();
    assert!(warnings.is_empty());
    assert!(with.not_phi.is_some());
    assert_eq!(with.description, "F goal");
    let (without, _) = Automata::for_game(&game, "F goal", &BUDGET, false, false).unwrap();
    assert!(without.not_phi.is_none());
    assert_eq!(without.phi.num_states(), with.phi.num_states());
}

#[test]
fn an_unused_proposition_warns_and_refuses_an_objective_it_makes_unsatisfiable() {
    let game = pomdp();
    // `gaol` labels no state: false everywhere. `F goal | F gaol` can hold.
    let (_, warnings) = Automata::for_game(&game, "F goal | F gaol", &BUDGET, true, false).unwrap();
    assert_eq!(warnings.len(), 1);
    assert!(warnings[0].contains("'gaol'") && warnings[0].contains("did you mean goal?"));
    // `F gaol` cannot: an error, unless allowed.
    match Automata::for_game(&game, "F gaol", &BUDGET, true, false) {
        Err(error @ PipelineError::Propositions(_)) => {
            let message = error.to_string();
            assert!(message.contains("can never hold"), "{message}");
            assert!(
                message.contains("allow_unused_propositions=True"),
                "{message}"
            );
            let PipelineError::Propositions(check) = error else {
                unreachable!()
            };
            assert_eq!(check.warnings.len(), 1, "the warning comes with the error");
        }
        other => panic!(
            "expected a proposition error, got {:?}",
            other.map(|(_, w)| w)
        ),
    }
    assert!(Automata::for_game(&game, "F gaol", &BUDGET, true, true).is_ok());
}

#[test]
fn a_formula_that_does_not_parse_is_a_parse_error() {
    let game = pomdp();
    let result = Automata::for_game(&game, "F (goal", &BUDGET, true, false);
    assert!(matches!(result, Err(PipelineError::Parse(_))));
}
