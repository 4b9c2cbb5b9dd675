//! Strategy files of the certified bounds (docs/formats.md section 7):
//! written, read back and checked, and replayed as controllers whose exact
//! value is the bound itself.

mod common;

use common::automata;

use posg_fsc::automaton::Dra;
use posg_fsc::certify::strategy::{Objective, StrategyFile};
use posg_fsc::certify::{Bound, lower_bound, upper_bound};
use posg_fsc::controller::{Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::value::SolverSettings;
use posg_fsc::value::evaluate_controllers;
use serde_json::{Value, json};

const FORMULAS: [&str; 4] = [
    "F goal",
    "G !unsafe",
    "GF goal & G !unsafe",
    "!unsafe U goal",
];

fn value(game: &Posg, dra: &Dra, def: &Fsc, adv: &Fsc) -> f64 {
    evaluate_controllers(game, dra, def, adv, &SolverSettings::default())
        .unwrap()
        .1
        .value
}

fn file(game: &Posg, dra: &Dra, bound: &Bound, nodes: usize) -> StrategyFile {
    StrategyFile::new(game, dra, bound, nodes, "F goal", vec!["test".into()])
}

/// The paper's grid where both players see their cell exactly.
fn exact_grid() -> Posg {
    posg_fsc::game::grid::GridSpec {
        defender_p_obs: 1.0,
        adversary_p_obs: 1.0,
        ..Default::default()
    }
    .build()
    .unwrap()
}

#[test]
fn a_strategy_file_is_read_back_unchanged() {
    let game = exact_grid();
    let (phi, not_phi) = automata("GF goal & G !unsafe");
    let defender = common::random::controller_with_nodes(3, &game, Role::Defender, 2);
    let lower = lower_bound(&game, &not_phi, &defender).unwrap();
    let written = file(&game, &not_phi, &lower, 2);
    assert_eq!(written.objective, Objective::NotPhi);
    assert!((written.free_player_value - (1.0 - lower.value)).abs() < 1e-12);
    let read =
        StrategyFile::from_json_str(&written.to_json_string(), "attack.json", &game).unwrap();
    assert_eq!(read, written);
    let adversary = common::random::controller(4, &game, Role::Adversary);
    let upper = upper_bound(&game, &phi, &adversary).unwrap();
    let response = file(&game, &phi, &upper, adversary.num_nodes());
    assert_eq!(response.objective, Objective::Phi);
    assert_eq!(response.free_player_value, upper.value);
}

#[test]
fn replayed_strategies_attain_the_bounds_on_fully_observed_random_games() {
    let mut replayed = 0;
    for seed in 0..300u64 {
        let text = if seed % 2 == 0 {
            common::random::game_json(seed)
        } else {
            common::random::game_json_with_enabled(seed)
        };
        let game = from_json_str(&text, "random.posg.json").unwrap();
        let formula = FORMULAS[(seed % 4) as usize];
        let (phi, not_phi) = automata(formula);
        let defender = common::random::controller_with_nodes(seed, &game, Role::Defender, 1);
        let adversary = common::random::controller_with_nodes(seed ^ 1, &game, Role::Adversary, 1);
        let lower = lower_bound(&game, &not_phi, &defender).unwrap();
        let attack = file(&game, &not_phi, &lower, 1);
        if let Ok(attacker) = attack.to_fsc(&game) {
            let v = value(&game, &phi, &defender, &attacker);
            assert!(
                (v - lower.value).abs() < 1e-9,
                "seed {seed}, {formula}: attack {v} vs lower bound {}",
                lower.value
            );
            replayed += 1;
        } else if game.adversary().observes_fully() {
            panic!("seed {seed}: a fully observing adversary's attack is a controller");
        }
        let upper = upper_bound(&game, &phi, &adversary).unwrap();
        let response = file(&game, &phi, &upper, 1);
        if let Ok(responder) = response.to_fsc(&game) {
            let v = value(&game, &phi, &responder, &adversary);
            assert!(
                (v - upper.value).abs() < 1e-9,
                "seed {seed}, {formula}: response {v} vs upper bound {}",
                upper.value
            );
            replayed += 1;
        } else if game.defender().observes_fully() {
            panic!("seed {seed}: a fully observing defender's response is a controller");
        }
    }
    assert!(replayed > 100, "{replayed} strategies replayed");
}

#[test]
fn a_strategy_that_depends_on_the_fixed_node_is_not_a_controller() {
    let game = exact_grid();
    let (_, not_phi) = automata("F goal & G !unsafe");
    let defender = posg_fsc::controller::file::resolve("uniform:2", &game, Role::Defender).unwrap();
    let lower = lower_bound(&game, &not_phi, &defender).unwrap();
    let mut attack = file(&game, &not_phi, &lower, 2);
    let rule = attack.rules.iter().position(|r| r.node == 1).unwrap();
    let other = if attack.rules[rule].action == "A" {
        "NA"
    } else {
        "A"
    };
    attack.rules[rule].action = other.to_string();
    let error = attack.to_fsc(&game).unwrap_err();
    assert!(
        error.contains("the strategy depends on the fixed player's node"),
        "{error}"
    );
    let noisy = posg_fsc::game::grid::GridSpec::default().build().unwrap();
    let error = file(
        &noisy,
        &not_phi,
        &lower_bound(&noisy, &not_phi, &defender).unwrap(),
        2,
    )
    .to_fsc(&noisy)
    .unwrap_err();
    assert!(
        error.contains("the adversary does not observe the state exactly"),
        "{error}"
    );
}

/// A change to a strategy file's JSON.
type Edit = Box<dyn Fn(&mut Value)>;

#[test]
fn bad_strategy_files_are_errors_with_their_json_path() {
    let game = exact_grid();
    let (_, not_phi) = automata("F goal & G !unsafe");
    let defender = posg_fsc::controller::file::resolve("uniform:1", &game, Role::Defender).unwrap();
    let lower = lower_bound(&game, &not_phi, &defender).unwrap();
    let good: Value =
        serde_json::from_str(&file(&game, &not_phi, &lower, 1).to_json_string()).unwrap();
    let cases: Vec<(Edit, &str)> = vec![
        (
            Box::new(|f| f["rules"][0]["state"] = json!("s9")),
            "a.json: rules[0].state: unknown state `s9`",
        ),
        (
            Box::new(|f| f["rules"][1]["action"] = json!("R")),
            "a.json: rules[1].action: unknown action `R` of the adversary",
        ),
        (
            Box::new(|f| f["rules"][0]["node"] = json!(1)),
            "rules[0].node: node 1 is out of range (the fixed controller has 1)",
        ),
        (
            Box::new(|f| f["rules"][0]["automaton_state"] = json!(7)),
            "rules[0].automaton_state: automaton state 7 is out of range",
        ),
        (
            Box::new(|f| f["rules"][2]["free_player_value"] = json!(1.5)),
            "rules[2].free_player_value: value 1.5 is not in [0, 1]",
        ),
        (
            Box::new(|f| {
                let r = f["rules"][0].clone();
                f["rules"].as_array_mut().unwrap().push(r);
            }),
            "a second rule for state `s0`",
        ),
        (
            Box::new(|f| f["rules"][0]["probability"] = json!(0.5)),
            "a.json: rules[0].probability: unknown field `probability`",
        ),
        (
            Box::new(|f| f["automaton"]["letters"] = json!([[], ["goal"]])),
            "automaton.successors[0]: 3 successors for 2 letters",
        ),
        (
            Box::new(|f| {
                f["automaton"]["letters"] = json!([[], ["goal"], ["other"]]);
            }),
            "automaton.letters: no entry for the label [\"unsafe\"] of state `s4`",
        ),
        (
            Box::new(|f| f["automaton"]["successors"][1][0] = json!(3)),
            "automaton.successors[1][0]: automaton state 3 is out of range",
        ),
        (
            Box::new(|f| f["strategy"] = json!(2)),
            "strategy: unsupported format version 2",
        ),
    ];
    for (change, expected) in cases {
        let mut bad = good.clone();
        change(&mut bad);
        let error = StrategyFile::from_json_str(&bad.to_string(), "a.json", &game)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains(expected),
            "expected `{expected}` in `{error}`"
        );
    }
}
