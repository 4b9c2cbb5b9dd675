//! Cost of the exact rational fallback solve ([`posg_fsc::value::exact`],
//! method.md section 8) on the chains that need it: symmetric lazy walks
//! of `LENGTH` states (each step 1e-12 either way, from the middle, value
//! `(LENGTH / 2) / (LENGTH - 1)`) whose states a `uniform:NODES` defender
//! splits into blocks, so that double precision cannot prove 1e-9.
//!
//! `cargo run --release --example exact_solve -- LENGTH NODES` prints one
//! CSV row (`experiments/exact-solve/run.py` collects them): the transient
//! unknowns, the seconds of `eval` without the fallback (`exact_limit` 0:
//! the double-precision attempt, refused) and with it (no limit), whether
//! the exact solve ran, the value, its error bound and its distance to the
//! value on paper.

use std::time::Instant;

use posg_fsc::controller::Role;
use posg_fsc::value::{SolverSettings, evaluate_controllers};

fn walk_json(length: usize, step: f64) -> String {
    let name = |i: usize| match i {
        0 => "fail".to_string(),
        i if i == length - 1 => "goal".to_string(),
        i => format!("w{i}"),
    };
    let states: Vec<String> = (0..length).map(|i| format!("\"{}\"", name(i))).collect();
    let mut transitions = vec![
        r#"{"state": "fail", "defender": "*", "next": {"fail": 1.0}}"#.to_string(),
        r#"{"state": "goal", "defender": "*", "next": {"goal": 1.0}}"#.to_string(),
    ];
    for i in 1..length - 1 {
        transitions.push(format!(
            r#"{{"state": "{}", "defender": "*", "next": {{"{}": {:e}, "{}": {step:e}, "{}": {step:e}}}}}"#,
            name(i),
            name(i),
            1.0 - 2.0 * step,
            name(i - 1),
            name(i + 1)
        ));
    }
    format!(
        r#"{{"posg": 1, "states": [{}], "initial": {{"{}": 1.0}}, "labels": {{"goal": ["goal"]}},
           "defender": {{"actions": ["go"], "observe": "full"}}, "transitions": [{}]}}"#,
        states.join(", "),
        name(length / 2),
        transitions.join(",\n")
    )
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("LENGTH NODES"))
        .collect();
    let [length, nodes] = args[..] else {
        panic!("usage: exact_solve LENGTH NODES")
    };
    let game = posg_fsc::game::file::from_json_str(&walk_json(length, 1e-12), "walk").unwrap();
    let dra = posg_fsc::ltl::translate(&posg_fsc::ltl::parse("F goal").unwrap()).unwrap();
    let uniform = |role, k: usize| {
        posg_fsc::controller::file::resolve(&format!("uniform:{k}"), &game, role).unwrap()
    };
    let (defender, adversary) = (uniform(Role::Defender, nodes), uniform(Role::Adversary, 1));
    let on_paper = (length / 2) as f64 / (length - 1) as f64;
    let timed = |exact_limit| {
        let settings = SolverSettings {
            exact_limit,
            ..SolverSettings::default()
        };
        let start = Instant::now();
        let outcome = evaluate_controllers(&game, &dra, &defender, &adversary, &settings);
        (outcome, start.elapsed().as_secs_f64())
    };
    let (double, double_seconds) = timed(0);
    let (exact, exact_seconds) = timed(usize::MAX);
    let (evaluator, evaluation) = exact.expect("the exact fallback solves every walk");
    let exact_used = evaluator.solver_reason().contains("exact");
    println!(
        "{length},{nodes},{},{},{double_seconds:.4},{exact_used},{exact_seconds:.4},{:e},{:e},{:e}",
        evaluator.system().0.n,
        double.is_ok(),
        evaluation.value,
        evaluation.error_bound,
        (evaluation.value - on_paper).abs()
    );
}
