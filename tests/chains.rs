//! Slowly mixing chains with closed-form values (issue 13; method.md
//! section 8): `eval` and `certify` give the value within 1e-9 and within
//! their own error bound, or an error, never a wrong number. The fixtures
//! are in `tests/data/chains/`; the 60,001-state walk is built here.

use posg_fsc::automaton::Dra;
use posg_fsc::certify::MdpError;
use posg_fsc::certify::{CertifyError, lower_bound, upper_bound};
use posg_fsc::controller::{Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::value::{SolverError, SolverMethod, SolverSettings};
use posg_fsc::value::{ValueError, evaluate_controllers};

const CHAINS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/chains");

fn read(name: &str) -> Posg {
    posg_fsc::game::file::read(&std::path::Path::new(CHAINS).join(name)).unwrap()
}

fn formula(text: &str) -> Dra {
    posg_fsc::ltl::translate(&posg_fsc::ltl::parse(text).unwrap()).unwrap()
}

fn uniform(game: &Posg, role: Role) -> Fsc {
    posg_fsc::controller::file::resolve("uniform:1", game, role).unwrap()
}

/// The fixtures and their values on paper.
fn fixtures() -> Vec<(&'static str, f64)> {
    let ruin = |q_over_p: f64, i: i32, n: i32| (q_over_p.powi(i) - 1.0) / (q_over_p.powi(n) - 1.0);
    vec![
        // s0 -> {s0: 1 - 3e-13, s1: 1e-13, s2: 2e-13}: 1e-13 / 3e-13.
        ("slow-three.posg.json", 1.0 / 3.0),
        // A symmetric walk that moves with probability 2e-12, from the middle.
        ("lazy-walk-11.posg.json", 0.5),
        // 10 steps, each progressing with 1e-15 and failing with 1e-16.
        ("slow-path-10.posg.json", (1.0f64 / 1.1).powi(10)),
        // Gambler's ruin from 10 of 20, up 0.4 and down 0.6 (times 1e-10).
        ("lazy-gamblers-ruin-20.posg.json", ruin(1.5, 10, 20)),
    ]
}

fn methods() -> [SolverMethod; 3] {
    [SolverMethod::Lu, SolverMethod::Krylov, SolverMethod::Auto]
}

#[test]
fn eval_gives_the_closed_form_values_within_its_error_bound() {
    let dra = formula("F goal");
    for (name, exact) in fixtures() {
        let game = read(name);
        let (def, adv) = (
            uniform(&game, Role::Defender),
            uniform(&game, Role::Adversary),
        );
        for method in methods() {
            let settings = SolverSettings {
                method,
                ..SolverSettings::default()
            };
            let (_, evaluation) = evaluate_controllers(&game, &dra, &def, &adv, &settings)
                .unwrap_or_else(|e| panic!("{name} ({method:?}): {e}"));
            let error = (evaluation.value - exact).abs();
            assert!(
                error < 1e-9,
                "{name} ({method:?}): {} vs {exact}",
                evaluation.value
            );
            assert!(
                error <= evaluation.error_bound + 4.0 * f64::EPSILON,
                "{name} ({method:?}): error {error:e} above the bound {:e}",
                evaluation.error_bound
            );
            assert!(evaluation.error_bound <= settings.tolerance + 1e-15);
        }
    }
}

#[test]
fn certify_brackets_the_closed_form_values_of_chains() {
    let (phi, not_phi) = (formula("F goal"), formula("!F goal"));
    for (name, exact) in fixtures() {
        let game = read(name);
        let lower = lower_bound(&game, &not_phi, &uniform(&game, Role::Defender)).unwrap();
        let upper = upper_bound(&game, &phi, &uniform(&game, Role::Adversary)).unwrap();
        for bound in [&lower, &upper] {
            let error = (bound.value - exact).abs();
            assert!(error < 1e-9, "{name}: {} vs {exact}", bound.value);
            assert!(error <= bound.error_bound + 4.0 * f64::EPSILON, "{name}");
        }
        posg_fsc::certify::check_consistent(&lower, &upper).unwrap();
    }
}

/// A symmetric walk on `0..n` that moves left or right with probability
/// `step` each, absorbing at both ends, `goal` at `n - 1`, started in the
/// middle: the value is 1/2, the expected time in `T` about `n^2 / (8 step)`.
fn walk_json(n: usize, step: f64) -> String {
    let mut transitions = vec![
        r#"{"state": "w0", "defender": "*", "next": {"w0": 1.0}}"#.to_string(),
        format!(
            r#"{{"state": "w{0}", "defender": "*", "next": {{"w{0}": 1.0}}}}"#,
            n - 1
        ),
    ];
    for i in 1..n - 1 {
        transitions.push(format!(
            r#"{{"state": "w{i}", "defender": "*", "next": {{"w{i}": {}, "w{}": {step:e}, "w{}": {step:e}}}}}"#,
            1.0 - 2.0 * step,
            i - 1,
            i + 1
        ));
    }
    let states: Vec<String> = (0..n).map(|i| format!("\"w{i}\"")).collect();
    format!(
        r#"{{"posg": 1, "states": [{}], "initial": {{"w{}": 1.0}}, "labels": {{"w{}": ["goal"]}},
           "defender": {{"actions": ["go"], "observe": "full"}}, "transitions": [{}]}}"#,
        states.join(", "),
        n / 2,
        n - 1,
        transitions.join(",\n")
    )
}

#[test]
fn a_walk_too_slow_to_certify_is_an_error_or_right_never_wrong() {
    let game = posg_fsc::game::file::from_json_str(&walk_json(60_001, 1e-9), "walk").unwrap();
    let dra = formula("F goal");
    let (def, adv) = (
        uniform(&game, Role::Defender),
        uniform(&game, Role::Adversary),
    );
    for method in methods() {
        let settings = SolverSettings {
            method,
            ..SolverSettings::default()
        };
        match evaluate_controllers(&game, &dra, &def, &adv, &settings) {
            Ok((_, evaluation)) => assert!(
                (evaluation.value - 0.5).abs() < 1e-9,
                "{method:?}: {}",
                evaluation.value
            ),
            Err(ValueError::Solver(
                SolverError::Unbounded { expected_time, .. }
                | SolverError::TooLargeForExact { expected_time, .. },
            )) => {
                assert!(expected_time > 1e17, "{method:?}: {expected_time:e}")
            }
            Err(other) => panic!("{method:?}: {other}"),
        }
    }
    // Policy iteration's qualitative steps are quadratic on a path: a
    // shorter, lazier walk is as slow to mix (about 5e17 expected steps).
    let game = posg_fsc::game::file::from_json_str(&walk_json(2_001, 1e-12), "walk").unwrap();
    let (def, adv) = (
        uniform(&game, Role::Defender),
        uniform(&game, Role::Adversary),
    );
    let lower = lower_bound(&game, &formula("!F goal"), &def);
    let upper = upper_bound(&game, &dra, &adv);
    match (lower, upper) {
        (Ok(lower), Ok(upper)) => {
            assert!((lower.value - 0.5).abs() < 1e-9 && (upper.value - 0.5).abs() < 1e-9);
        }
        (lower, upper) => {
            for result in [lower, upper] {
                assert!(
                    matches!(
                        result,
                        Ok(_)
                            | Err(CertifyError::Mdp(MdpError::Solver(
                                SolverError::Unbounded { .. }
                                    | SolverError::TooLargeForExact { .. }
                            )))
                    ),
                    "{result:?}"
                );
            }
        }
    }
}

#[test]
fn a_looser_tolerance_gets_the_walk_within_the_bound_it_states() {
    let game = posg_fsc::game::file::from_json_str(&walk_json(20_001, 1e-9), "walk").unwrap();
    let dra = formula("F goal");
    let (def, adv) = (
        uniform(&game, Role::Defender),
        uniform(&game, Role::Adversary),
    );
    let settings = SolverSettings {
        method: SolverMethod::Lu,
        tolerance: 1e-6,
        ..SolverSettings::default()
    };
    let (_, evaluation) = evaluate_controllers(&game, &dra, &def, &adv, &settings).unwrap();
    assert!(
        evaluation.error_bound > 1e-12,
        "{:e}",
        evaluation.error_bound
    );
    assert!((evaluation.value - 0.5).abs() <= evaluation.error_bound);
}
