//! Slowly mixing chains with values on paper, evaluated with controllers
//! that have memory (issue 26; method.md section 8). Every game has one
//! defender action, so every controller gives the chain's value; memory
//! splits each lazy state into a block of GMC states that pass the walk
//! among themselves, whose escape elimination by subtraction loses. `eval`
//! and `certify` give the value within 1e-8 and within their own error
//! bound, or refuse with the expected time that makes the bound unprovable.

use posg_fsc::automaton::Dra;
use posg_fsc::certify::{lower_bound_within, upper_bound_within};
use posg_fsc::controller::{Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::value::{SolverError, SolverMethod, SolverSettings};
use posg_fsc::value::{ValueError, evaluate_controllers};

const CHAINS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/chains");

fn formula(text: &str) -> Dra {
    posg_fsc::ltl::translate(&posg_fsc::ltl::parse(text).unwrap()).unwrap()
}

fn uniform(game: &Posg, role: Role, nodes: usize) -> Fsc {
    posg_fsc::controller::file::resolve(&format!("uniform:{nodes}"), game, role).unwrap()
}

/// A game with one defender action whose states `names` move by `rows`
/// (`(state, [(successor, probability)])`), starting in `start`, `goal` labelled.
fn chain_json(names: &[String], rows: &[(String, Vec<(String, f64)>)], start: &str) -> String {
    let states: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
    let transitions: Vec<String> = rows
        .iter()
        .map(|(state, next)| {
            let next: Vec<String> = next
                .iter()
                .map(|(t, p)| format!("\"{t}\": {p:e}"))
                .collect();
            format!(
                r#"{{"state": "{state}", "defender": "*", "next": {{{}}}}}"#,
                next.join(", ")
            )
        })
        .collect();
    format!(
        r#"{{"posg": 1, "states": [{}], "initial": {{"{start}": 1.0}}, "labels": {{"goal": ["goal"]}},
           "defender": {{"actions": ["go"], "observe": "full"}}, "transitions": [{}]}}"#,
        states.join(", "),
        transitions.join(",\n")
    )
}

/// A symmetric walk on `w1..w(n-2)` between `fail` (left) and `goal`
/// (right), moving each way with probability `step`, from the middle:
/// the value is `(n / 2) / (n - 1)` (gambler's ruin with fair steps).
fn lazy_walk(n: usize, step: f64) -> (Posg, f64) {
    let name = |i: usize| match i {
        0 => "fail".to_string(),
        i if i == n - 1 => "goal".to_string(),
        i => format!("w{i}"),
    };
    let names: Vec<String> = (0..n).map(name).collect();
    let mut rows = vec![
        (name(0), vec![(name(0), 1.0)]),
        (name(n - 1), vec![(name(n - 1), 1.0)]),
    ];
    for i in 1..n - 1 {
        rows.push((
            name(i),
            vec![
                (name(i), 1.0 - 2.0 * step),
                (name(i - 1), step),
                (name(i + 1), step),
            ],
        ));
    }
    let json = chain_json(&names, &rows, &name(n / 2));
    let game = posg_fsc::game::file::from_json_str(&json, "walk").unwrap();
    (game, (n / 2) as f64 / (n - 1) as f64)
}

/// A path `p0 .. p(n-1)`, `goal` after the last, each step progressing
/// with `progress` and failing with `failure`: `(progress / (progress +
/// failure))^n`.
fn path_with_tiny_escapes(n: usize, progress: f64, failure: f64) -> (Posg, f64) {
    let name = |i: usize| {
        if i == n {
            "goal".to_string()
        } else {
            format!("p{i}")
        }
    };
    let mut names: Vec<String> = (0..=n).map(name).collect();
    names.push("fail".into());
    let mut rows = vec![
        ("goal".to_string(), vec![("goal".to_string(), 1.0)]),
        ("fail".to_string(), vec![("fail".to_string(), 1.0)]),
    ];
    for i in 0..n {
        rows.push((
            name(i),
            vec![
                (name(i), 1.0 - progress - failure),
                (name(i + 1), progress),
                ("fail".to_string(), failure),
            ],
        ));
    }
    let json = chain_json(&names, &rows, "p0");
    let game = posg_fsc::game::file::from_json_str(&json, "path").unwrap();
    (game, (progress / (progress + failure)).powi(n as i32))
}

/// A lazy state that leaves with probability `escape`, to `goal` with
/// 40% of it: the value is 0.4.
fn lazy_state(escape: f64) -> (Posg, f64) {
    let names: Vec<String> = ["s", "goal", "fail"].map(String::from).to_vec();
    let rows = vec![
        (
            "s".to_string(),
            vec![
                ("s".to_string(), 1.0 - escape),
                ("goal".to_string(), 0.4 * escape),
                ("fail".to_string(), 0.6 * escape),
            ],
        ),
        ("goal".to_string(), vec![("goal".to_string(), 1.0)]),
        ("fail".to_string(), vec![("fail".to_string(), 1.0)]),
    ];
    let json = chain_json(&names, &rows, "s");
    (
        posg_fsc::game::file::from_json_str(&json, "lazy").unwrap(),
        0.4,
    )
}

/// The fixture files of `tests/data/chains` (label `goal`) and their values.
fn fixture(name: &str) -> Posg {
    posg_fsc::game::file::read(&std::path::Path::new(CHAINS).join(name)).unwrap()
}

/// Every chain and its value on paper.
fn chains() -> Vec<(String, Posg, f64)> {
    let ruin = |q_over_p: f64, i: i32, n: i32| (q_over_p.powi(i) - 1.0) / (q_over_p.powi(n) - 1.0);
    let mut chains = vec![
        (
            "slow-three".to_string(),
            fixture("slow-three.posg.json"),
            1.0 / 3.0,
        ),
        (
            "lazy gambler's ruin".to_string(),
            fixture("lazy-gamblers-ruin-20.posg.json"),
            ruin(1.5, 10, 20),
        ),
        (
            "slow path".to_string(),
            fixture("slow-path-10.posg.json"),
            (1.0f64 / 1.1).powi(10),
        ),
    ];
    for (label, (game, value)) in [
        ("lazy walk of 10", lazy_walk(10, 1e-12)),
        ("lazy walk of 2,001", lazy_walk(2_001, 1e-12)),
        ("path of 12", path_with_tiny_escapes(12, 1e-13, 1e-16)),
        ("lazy state 1e-14", lazy_state(1e-14)),
        ("lazy state 1e-10", lazy_state(1e-10)),
    ] {
        chains.push((label.to_string(), game, value));
    }
    chains
}

#[test]
fn eval_with_memory_gives_values_on_paper_within_the_printed_bound() {
    let dra = formula("F goal");
    for (label, game, exact) in chains() {
        let adversary = uniform(&game, Role::Adversary, 1);
        for nodes in 1..=3 {
            let defender = uniform(&game, Role::Defender, nodes);
            for method in [SolverMethod::Auto, SolverMethod::Lu] {
                let settings = SolverSettings {
                    method,
                    ..SolverSettings::default()
                };
                match evaluate_controllers(&game, &dra, &defender, &adversary, &settings) {
                    Ok((_, evaluation)) => {
                        let error = (evaluation.value - exact).abs();
                        let context = format!(
                            "{label}, uniform:{nodes}, {method:?}: {} vs {exact} (bound {:e})",
                            evaluation.value, evaluation.error_bound
                        );
                        assert!(error < 1e-8, "{context}");
                        assert!(
                            error <= evaluation.error_bound + 4.0 * f64::EPSILON,
                            "{context}"
                        );
                    }
                    Err(ValueError::Solver(SolverError::TooLargeForExact {
                        expected_time,
                        unknowns,
                        exact_limit,
                        ..
                    })) => {
                        // Double precision cannot certify 1e-9 when memory
                        // splits states the chain stays in for 1e15 steps
                        // and more (method.md section 8), and the system is
                        // too large for the exact fallback.
                        assert!(
                            expected_time >= 1e15 && unknowns > exact_limit,
                            "{label}, uniform:{nodes}: refused at expected time {expected_time:e}"
                        );
                        eprintln!(
                            "{label}, uniform:{nodes}: refused, expected time {expected_time:e}"
                        );
                    }
                    Err(other) => panic!("{label}, uniform:{nodes}: {other}"),
                }
            }
        }
    }
}

#[test]
fn certify_with_memory_brackets_the_values_on_paper() {
    let (phi, not_phi) = (formula("F goal"), formula("!F goal"));
    let settings = SolverSettings::default();
    for (label, game, exact) in chains() {
        if game.num_states() > 100 {
            // Policy iteration's qualitative steps are quadratic on a path.
            continue;
        }
        for nodes in 1..=3 {
            let defender = uniform(&game, Role::Defender, nodes);
            let adversary = uniform(&game, Role::Adversary, 1);
            let lower = match lower_bound_within(&game, &not_phi, &defender, &settings) {
                Ok(lower) => lower,
                Err(error) if error.is_slow_mixing() && label == "slow path" && nodes > 1 => {
                    eprintln!("{label}, uniform:{nodes}: certify refused: {error}");
                    continue;
                }
                Err(error) => panic!("{label}, uniform:{nodes}: {error}"),
            };
            let upper = upper_bound_within(&game, &phi, &adversary, &settings)
                .unwrap_or_else(|e| panic!("{label}, uniform:{nodes}: {e}"));
            let context = format!(
                "{label}, uniform:{nodes}: lower {} ± {:e}, upper {} ± {:e}, exact {exact}",
                lower.value, lower.error_bound, upper.value, upper.error_bound
            );
            assert!(
                lower.value - lower.error_bound <= exact + 4.0 * f64::EPSILON,
                "lower bound above the value: {context}"
            );
            assert!(
                upper.value + upper.error_bound >= exact - 4.0 * f64::EPSILON,
                "upper bound below the value: {context}"
            );
            assert!((lower.value - exact).abs() < 1e-8, "{context}");
            assert!((upper.value - exact).abs() < 1e-8, "{context}");
        }
    }
}

#[test]
fn where_double_precision_cannot_prove_the_bound_small_chains_are_solved_exactly() {
    let dra = formula("F goal");
    let (game, exact) = (fixture("slow-path-10.posg.json"), (1.0f64 / 1.1).powi(10));
    let defender = uniform(&game, Role::Defender, 3);
    let adversary = uniform(&game, Role::Adversary, 1);
    let without = SolverSettings {
        exact_limit: 0,
        ..SolverSettings::default()
    };
    let refused = evaluate_controllers(&game, &dra, &defender, &adversary, &without);
    assert!(
        matches!(
            refused,
            Err(ValueError::Solver(SolverError::TooLargeForExact { expected_time, .. }))
                if expected_time > 1e15
        ),
        "double precision alone proves no bound here"
    );
    let (evaluator, evaluation) = evaluate_controllers(
        &game,
        &dra,
        &defender,
        &adversary,
        &SolverSettings::default(),
    )
    .unwrap();
    assert!(evaluator.solver_reason().contains("exact rational solve"));
    let error = (evaluation.value - exact).abs();
    assert!(
        evaluation.error_bound <= 1e-15,
        "{:e}",
        evaluation.error_bound
    );
    assert!(error <= evaluation.error_bound + 1e-15);
    // The exact value of the chain the doubles describe; the paper's value
    // differs by the rounding of the transition probabilities only.
    assert!(error < 1e-14, "{} vs {exact}", evaluation.value);
}

#[test]
fn chains_too_large_for_the_exact_solve_are_refused_saying_so() {
    let dra = formula("F goal");
    let (game, _) = lazy_walk(2_001, 1e-12);
    let defender = uniform(&game, Role::Defender, 3);
    let adversary = uniform(&game, Role::Adversary, 1);
    let error = evaluate_controllers(
        &game,
        &dra,
        &defender,
        &adversary,
        &SolverSettings::default(),
    )
    .err()
    .expect("refused")
    .to_string();
    assert!(
        error.contains("exact rational solve")
            && error.contains("this one has 5997")
            && error.contains("--tolerance"),
        "{error}"
    );
}
