//! `export-gmc`'s chain: the DRN file read back by the crate's own DRN
//! importer is a DTMC on which `X phi` has the value of `phi` on the game;
//! the PRISM explicit files describe the same chain as the DRN file.

mod common;

use posg_fsc::automaton::Dra;
use posg_fsc::controller::{Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::game::drn::from_drn_str;
use posg_fsc::game::file::from_json_str;
use posg_fsc::ltl;
use posg_fsc::output::export::explicit_chain;
use posg_fsc::value::SolverSettings;
use posg_fsc::value::evaluate_controllers;
use proptest::prelude::*;

fn value(game: &Posg, dra: &Dra, def: &Fsc, adv: &Fsc) -> f64 {
    evaluate_controllers(game, dra, def, adv, &SolverSettings::default())
        .unwrap()
        .1
        .value
}

fn translate(formula: &str) -> Dra {
    ltl::translate(&ltl::parse(formula).unwrap()).unwrap()
}

/// `(source, target, probability)` of every transition of the DRN chain
/// (an independent little reader: states in order, one action each).
fn drn_transitions(drn: &str) -> Vec<(usize, usize, f64)> {
    let mut state = 0;
    let mut out = Vec::new();
    for line in drn.lines().map(str::trim) {
        if let Some(rest) = line.strip_prefix("state ") {
            state = rest.split_whitespace().next().unwrap().parse().unwrap();
        } else if let Some((target, p)) = line.split_once(" : ") {
            out.push((state, target.parse().unwrap(), p.parse().unwrap()));
        }
    }
    out
}

/// The same from `chain.tra`: a `states transitions` line, then triples.
fn tra_transitions(tra: &str) -> Vec<(usize, usize, f64)> {
    tra.lines()
        .skip(1)
        .map(|line| {
            let mut words = line.split_whitespace();
            let mut next = || words.next().unwrap();
            (
                next().parse().unwrap(),
                next().parse().unwrap(),
                next().parse().unwrap(),
            )
        })
        .collect()
}

#[test]
fn the_drn_chain_of_the_paper_grid_has_one_initial_state_and_the_labels() {
    let game = posg_fsc::game::grid::GridSpec::default().build().unwrap();
    let def = posg_fsc::controller::file::resolve("uniform:2", &game, Role::Defender).unwrap();
    let adv = posg_fsc::controller::file::resolve("uniform:1", &game, Role::Adversary).unwrap();
    let chain = explicit_chain(&game, &def, &adv).unwrap();
    assert!(chain.drn.contains("\n@type: DTMC\n"));
    let initial = chain
        .drn
        .lines()
        .filter(|l| l.split_whitespace().any(|w| w == "init"));
    assert_eq!(initial.collect::<Vec<_>>(), ["state 0 init"]);
    assert!(chain.drn.contains("\nstate 0 init\n"));
    assert_eq!(chain.drn.matches("\nstate ").count(), chain.summary.states);
    let goal_states = chain
        .drn
        .lines()
        .filter(|l| l.starts_with("state ") && l.ends_with(" goal"))
        .count();
    assert_eq!(goal_states, 2, "s5 with defender nodes 0 and 1");
    let mut drn = drn_transitions(&chain.drn);
    let mut tra = tra_transitions(&chain.tra);
    drn.sort_by(|a, b| a.partial_cmp(b).unwrap());
    tra.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(drn, tra);
    assert_eq!(drn.len(), chain.summary.transitions);
}

#[test]
fn propositions_of_unreachable_states_are_carried_by_one_unreachable_state() {
    let game = from_json_str(
        r#"{"posg": 1, "states": ["a", "b", "c"], "initial": {"a": 1.0},
            "labels": {"b": ["goal"], "c": ["unsafe", "goal"]},
            "defender": {"actions": ["go"], "observe": "full"},
            "transitions": [{"state": "a", "defender": "go", "next": {"b": 1.0}},
                            {"state": "b", "defender": "go", "next": {"b": 1.0}},
                            {"state": "c", "defender": "go", "next": {"c": 1.0}}]}"#,
        "unreachable.posg.json",
    )
    .unwrap();
    let one = |role| posg_fsc::controller::file::resolve("uniform:1", &game, role).unwrap();
    let chain = explicit_chain(&game, &one(Role::Defender), &one(Role::Adversary)).unwrap();
    assert_eq!(chain.summary.states, 3, "the fresh initial state, a and b");
    assert!(chain.drn.contains("\nstate 3 unsafe\n"), "{}", chain.drn);
    assert!(chain.drn.contains("\t\t3 : 1e0\n"));
    assert!(
        !chain.drn.contains("\t\t3 : 1e0\nstate"),
        "nothing after the carrier"
    );
    let dtmc = from_drn_str(&chain.drn, "chain.drn", None).unwrap().game;
    assert_eq!(dtmc.propositions(), ["goal", "unsafe"]);
    let x = value(
        &dtmc,
        &translate("X G !unsafe"),
        &one_of(&dtmc, Role::Defender),
        &one_of(&dtmc, Role::Adversary),
    );
    assert_eq!(x, 1.0);
}

fn one_of(game: &Posg, role: Role) -> Fsc {
    posg_fsc::controller::file::resolve("uniform:1", game, role).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(40)
    })]

    /// On random games and controllers: import the exported DRN as a DTMC
    /// game and evaluate `X phi` there; it equals the value of `phi`.
    #[test]
    fn the_exported_drn_gives_the_value_of_x_phi(seed in any::<u64>(), formula in 0usize..4) {
        let text = common::random::game_json(seed);
        let game = from_json_str(&text, "random.posg.json").unwrap();
        let def = common::random::controller(seed, &game, Role::Defender);
        let adv = common::random::controller(seed ^ 1, &game, Role::Adversary);
        let formula = ["F goal", "G !unsafe", "GF goal & G !unsafe", "!unsafe U goal"][formula];
        let expected = value(&game, &translate(formula), &def, &adv);
        let chain = explicit_chain(&game, &def, &adv).unwrap();
        let dtmc = from_drn_str(&chain.drn, "chain.drn", None).unwrap().game;
        let carrier = usize::from(dtmc.num_states() > chain.summary.states);
        prop_assert_eq!(dtmc.num_states(), chain.summary.states + carrier);
        prop_assert_eq!(dtmc.propositions(), game.propositions());
        prop_assert_eq!(dtmc.initial(), &[(0, 1.0)][..]);
        let one = |role| posg_fsc::controller::file::resolve("uniform:1", &dtmc, role).unwrap();
        let next = translate(&format!("X ({formula})"));
        let ours = value(&dtmc, &next, &one(Role::Defender), &one(Role::Adversary));
        prop_assert!((ours - expected).abs() < 1e-9, "{}: {} vs {}", formula, ours, expected);
    }
}
