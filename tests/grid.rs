//! The paper's 3x2 grid with uniform and hand-written sparse controllers:
//! `eval` equals an independent dense computation on the product and lies
//! within the 95% interval of a Monte Carlo simulation.

mod common;

use posg_fsc::automaton::Dra;
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::game::grid::{GridSpec, ObservationModel};
use posg_fsc::value::evaluate_controllers;
use posg_fsc::value::{DEFAULT_TOLERANCE, SolverSettings};
use posg_fsc::value::{SimulationSettings, simulate};

fn objectives() -> Vec<(&'static str, Dra)> {
    vec![
        ("!unsafe U goal", common::safe_until_goal()),
        ("F goal", common::eventually_goal()),
        ("GF goal & G !unsafe", common::recurrent_goal_safe()),
    ]
}

fn uniform(game: &Posg, role: Role, nodes: usize) -> Fsc {
    let player = if role == Role::Defender {
        game.defender()
    } else {
        game.adversary()
    };
    Fsc::uniform(role, nodes, player.num_observations(), player.num_actions())
}

/// A 1-node defender that, on observing cell `o`, plays `plan[o]` with
/// probability 0.9 and `D` otherwise (or only `plan[o]` when it is `D`).
fn planned_defender(game: &Posg, plan: &[&str]) -> Fsc {
    let action = |name: &str| {
        game.defender()
            .actions()
            .iter()
            .position(|a| a == name)
            .unwrap()
    };
    let blocks = plan
        .iter()
        .map(|&name| {
            if name == "D" {
                vec![Choice {
                    next: 0,
                    action: action("D"),
                    probability: 1.0,
                    logit: None,
                }]
            } else {
                vec![
                    Choice {
                        next: 0,
                        action: action(name),
                        probability: 0.9,
                        logit: None,
                    },
                    Choice {
                        next: 0,
                        action: action("D"),
                        probability: 0.1,
                        logit: None,
                    },
                ]
            }
        })
        .collect();
    let d = game.defender();
    Fsc::new(
        Role::Defender,
        1,
        d.num_observations(),
        d.num_actions(),
        vec![1.0],
        blocks,
    )
    .unwrap()
}

/// A 2-node adversary that attacks only in node 1 and switches node on
/// every observation of s2.
fn switching_adversary(game: &Posg) -> Fsc {
    let a = game.adversary();
    let attack = a.actions().iter().position(|x| x == "A").unwrap();
    let idle = a.actions().iter().position(|x| x == "NA").unwrap();
    let mut blocks = Vec::new();
    for g in 0..2 {
        for o in 0..a.num_observations() {
            let next = if a.observations()[o] == "s2" {
                1 - g
            } else {
                g
            };
            let action = if g == 1 { attack } else { idle };
            blocks.push(vec![Choice {
                next,
                action,
                probability: 1.0,
                logit: None,
            }]);
        }
    }
    Fsc::new(
        Role::Adversary,
        2,
        a.num_observations(),
        a.num_actions(),
        vec![1.0, 0.0],
        blocks,
    )
    .unwrap()
}

fn controller_pairs(game: &Posg) -> Vec<(&'static str, Fsc, Fsc)> {
    vec![
        (
            "uniform 1 / 1",
            uniform(game, Role::Defender, 1),
            uniform(game, Role::Adversary, 1),
        ),
        (
            "uniform 2 / 2",
            uniform(game, Role::Defender, 2),
            uniform(game, Role::Adversary, 2),
        ),
        (
            "sparse right-then-down / switching",
            planned_defender(game, &["R", "R", "D", "R", "R", "D"]),
            switching_adversary(game),
        ),
        (
            "sparse down-then-right / uniform",
            planned_defender(game, &["D", "D", "D", "R", "R", "D"]),
            uniform(game, Role::Adversary, 1),
        ),
    ]
}

fn check_grid(game: &Posg) {
    for (formula, dra) in objectives() {
        for (name, defender, adversary) in controller_pairs(game) {
            let (evaluator, evaluation) = evaluate_controllers(
                game,
                &dra,
                &defender,
                &adversary,
                &SolverSettings::default(),
            )
            .unwrap();
            let value = evaluation.value;
            let reference = common::reference_value(game, &dra, &defender, &adversary);
            assert!(
                (value - reference).abs() < 1e-9,
                "{formula}, {name}: eval {value} vs dense {reference}"
            );
            let settings = SimulationSettings {
                runs: 20_000,
                seed: 7,
            };
            let estimate =
                simulate(game, &dra, &defender, &adversary, &evaluator, settings).unwrap();
            assert!(
                estimate.lower - DEFAULT_TOLERANCE <= value
                    && value <= estimate.upper + DEFAULT_TOLERANCE,
                "{formula}, {name}: eval {value} outside the simulated interval {estimate:?}"
            );
        }
    }
}

#[test]
fn paper_grid_eval_matches_dense_reference_and_simulation() {
    check_grid(&GridSpec::default().build().unwrap());
}

#[test]
fn paper_grid_with_blind_observations_matches_too() {
    let spec = GridSpec {
        observation: ObservationModel::Blind,
        ..GridSpec::default()
    };
    let game = spec.build().unwrap();
    for (formula, dra) in objectives() {
        for nodes in [1, 2] {
            let (defender, adversary) = (
                uniform(&game, Role::Defender, nodes),
                uniform(&game, Role::Adversary, nodes),
            );
            let (_, evaluation) = evaluate_controllers(
                &game,
                &dra,
                &defender,
                &adversary,
                &SolverSettings::default(),
            )
            .unwrap();
            let value = evaluation.value;
            let reference = common::reference_value(&game, &dra, &defender, &adversary);
            assert!(
                (value - reference).abs() < 1e-9,
                "{formula}, {nodes} nodes: {value} vs {reference}"
            );
        }
    }
}

#[test]
fn full_support_makes_recurrent_safety_exactly_zero() {
    let game = GridSpec::default().build().unwrap();
    let dra = common::recurrent_goal_safe();
    for nodes in 1..=3 {
        let (defender, adversary) = (
            uniform(&game, Role::Defender, nodes),
            uniform(&game, Role::Adversary, 1),
        );
        let (evaluator, evaluation) = evaluate_controllers(
            &game,
            &dra,
            &defender,
            &adversary,
            &SolverSettings::default(),
        )
        .unwrap();
        assert_eq!(evaluation.value, 0.0, "{nodes} nodes");
        assert_eq!(evaluator.recurrence().feasible().count(), 0);
    }
}
