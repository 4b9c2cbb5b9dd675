//! The max-min optimiser: softmax gradients against central differences,
//! single-player optimisation against exhaustive enumeration, matching
//! pennies, and reproducibility of `curve.csv`.

mod common;

use posg_fsc::automaton::Dra;
use posg_fsc::controller::{Choice, Fsc, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::optimise::{
    Cancel, Objective, Settings, Softmax, Status, Structure, StructureSource, optimise_structure,
};
use posg_fsc::output::CurveCsv;
use posg_fsc::value::Evaluator;
use posg_fsc::value::SolverSettings;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Map, Value, json};

fn game(text: &str) -> Posg {
    from_json_str(text, "test.posg.json").unwrap()
}

fn random_logits(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(-2.0..2.0)).collect()
}

/// Central differences of `V` in every logit of one player.
fn central_differences(
    objective: &mut Objective,
    def: &[f64],
    adv: &[f64],
    player: Role,
) -> Vec<f64> {
    let h = 1e-5;
    let n = if player == Role::Defender {
        def.len()
    } else {
        adv.len()
    };
    (0..n)
        .map(|k| {
            let shifted = |delta: f64| {
                let (mut d, mut a) = (def.to_vec(), adv.to_vec());
                if player == Role::Defender {
                    d[k] += delta
                } else {
                    a[k] += delta
                }
                (d, a)
            };
            let (dp, ap) = shifted(h);
            let (dm, am) = shifted(-h);
            (objective.value(&dp, &ap).unwrap() - objective.value(&dm, &am).unwrap()) / (2.0 * h)
        })
        .collect()
}

fn assert_close(adjoint: &[f64], fd: &[f64], who: &str) -> Result<(), TestCaseError> {
    let scale = adjoint.iter().chain(fd).fold(0.0f64, |m, g| m.max(g.abs()));
    for (k, (a, f)) in adjoint.iter().zip(fd).enumerate() {
        let error = (a - f).abs() / scale.max(1e-3);
        prop_assert!(
            error < 1e-6,
            "{} logit {}: adjoint {} vs differences {} (relative error {})",
            who,
            k,
            a,
            f,
            error
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(48)
    })]

    /// dV/dphi by adjoint + softmax chain rule against central differences,
    /// both players, with and without initial-distribution logits.
    #[test]
    fn logit_gradient_matches_central_differences(seed in any::<u64>(), with_initial in any::<bool>()) {
        let g = game(&common::random::game_json(seed));
        let dra = common::random::dra(seed);
        let def = common::random::controller(seed, &g, Role::Defender);
        let adv = common::random::controller(seed, &g, Role::Adversary);
        let mut objective = Objective::new(&g, &dra, Softmax::new(&def, with_initial), Softmax::new(&adv, with_initial), &SolverSettings::default()).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let phi_def = random_logits(&mut rng, objective.defender().num_parameters());
        let phi_adv = random_logits(&mut rng, objective.adversary().num_parameters());
        let point = objective.point(&phi_def, &phi_adv).unwrap();
        let fd_def = central_differences(&mut objective, &phi_def, &phi_adv, Role::Defender);
        let fd_adv = central_differences(&mut objective, &phi_def, &phi_adv, Role::Adversary);
        assert_close(&point.defender, &fd_def, "defender")?;
        assert_close(&point.adversary, &fd_adv, "adversary")?;
    }
}

/// A random single-player game (no adversary) as JSON: `states` states, the
/// defender observes `observations` noisy observations (0: the state), two
/// or three actions, `goal` and `unsafe` absorbing.
fn single_player_json(seed: u64, states: usize, observations: usize) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let names: Vec<String> = (0..states).map(|i| format!("s{i}")).collect();
    let actions: Vec<String> = (0..rng.random_range(2..=3))
        .map(|i| format!("u{i}"))
        .collect();
    let mut transitions = Vec::new();
    for (i, s) in names.iter().enumerate() {
        if i >= states - 2 {
            transitions.push(json!({"state": s, "defender": "*", "next": {s.clone(): 1.0}}));
            continue;
        }
        for u in &actions {
            let mut next = Map::new();
            let targets: Vec<&String> = names.iter().filter(|_| rng.random_bool(0.4)).collect();
            let targets = if targets.is_empty() {
                vec![&names[0]]
            } else {
                targets
            };
            let weights: Vec<f64> = targets.iter().map(|_| rng.random_range(0.1..1.0)).collect();
            let total: f64 = weights.iter().sum();
            for (t, w) in targets.into_iter().zip(weights) {
                next.insert(t.clone(), json!(w / total));
            }
            transitions.push(json!({"state": s, "defender": u, "next": next}));
        }
    }
    let defender = if observations == 0 {
        json!({"actions": actions, "observe": "full"})
    } else {
        let obs: Vec<String> = (0..observations).map(|i| format!("o{i}")).collect();
        let observe: Map<String, Value> = names
            .iter()
            .map(|s| {
                (
                    s.clone(),
                    json!({obs[rng.random_range(0..observations)].clone(): 1.0}),
                )
            })
            .collect();
        json!({"actions": actions, "observations": obs, "observe": observe})
    };
    json!({
        "posg": 1, "states": names, "initial": {"s0": 1.0},
        "labels": {names[states - 2].clone(): ["goal"], names[states - 1].clone(): ["unsafe"]},
        "defender": defender, "transitions": transitions,
    })
    .to_string()
}

/// The best value over all deterministic 1-node defenders (one action per
/// observation), by exhaustive enumeration.
fn best_deterministic(g: &Posg, dra: &Dra) -> f64 {
    let (no, na) = (g.defender().num_observations(), g.defender().num_actions());
    let adversary = Fsc::uniform(Role::Adversary, 1, 1, 1);
    let adv = Support::probabilities_of(&adversary);
    let mut best = 0.0f64;
    for code in 0..na.pow(no as u32) {
        let blocks = (0..no)
            .map(|o| {
                vec![Choice {
                    next: 0,
                    action: code / na.pow(o as u32) % na,
                    probability: 1.0,
                    logit: None,
                }]
            })
            .collect();
        let fsc = Fsc::new(Role::Defender, 1, no, na, vec![1.0], blocks).unwrap();
        let mut ev = Evaluator::new(
            g,
            dra,
            &Support::of(&fsc),
            &Support::of(&adversary),
            &SolverSettings::default(),
        )
        .unwrap();
        best = best.max(
            ev.evaluate(&Support::probabilities_of(&fsc), &adv)
                .unwrap()
                .value,
        );
    }
    best
}

/// Settings for single-player runs: logit bound c = 10, so a deterministic
/// choice is approximated within exp(-20) per entry, far below 1e-3.
fn single_player_settings() -> Settings {
    Settings {
        logit_bound: 10.0,
        max_iterations: 300,
        defender_step: 0.3,
        check_every: 25,
        restarts: 0,
        ..Settings::default()
    }
}

#[test]
fn single_player_reach_avoid_matches_the_best_deterministic_controller() {
    let dra = common::safe_until_goal();
    for seed in 0..8 {
        let g = game(&single_player_json(seed, 6, 0));
        let optimum = best_deterministic(&g, &dra);
        let found = common::solve_one_node(&g, &dra, None, &single_player_settings()).unwrap();
        let value = found.best().report.worst_case;
        assert!(
            (value - optimum).abs() < 1e-3,
            "seed {seed}: optimised {value}, best deterministic {optimum}"
        );
    }
}

#[test]
fn partially_observed_single_player_is_at_least_the_best_deterministic_controller() {
    // Under partial observation a mixed 1-node controller may beat every
    // deterministic one, never the other way round.
    let dra = common::safe_until_goal();
    for seed in 0..8 {
        let g = game(&single_player_json(100 + seed, 6, 2));
        let optimum = best_deterministic(&g, &dra);
        let found = common::solve_one_node(&g, &dra, None, &single_player_settings()).unwrap();
        let value = found.best().report.worst_case;
        assert!(
            value > optimum - 1e-3,
            "seed {seed}: optimised {value}, best deterministic {optimum}"
        );
    }
}

const MATCHING_PENNIES: &str = include_str!("data/valid/matching-pennies.posg.json");

#[test]
fn matching_pennies_has_max_min_value_one_half_with_both_mixing() {
    let g = game(MATCHING_PENNIES);
    let dra = common::eventually_goal();
    for seed in 0..3 {
        let settings = Settings {
            seed,
            ..Settings::default()
        };
        let found = common::solve_one_node(&g, &dra, None, &settings).unwrap();
        let best = found.best();
        assert!(
            (best.report.worst_case - 0.5).abs() < 1e-3,
            "seed {seed}: worst case {}; {:?}",
            best.report.worst_case,
            best.report.starts
        );
        let s = g.state_index("s").unwrap();
        let heads = best
            .defender
            .choices(0, s)
            .iter()
            .find(|c| c.action == 0)
            .unwrap()
            .probability;
        assert!(
            (heads - 0.5).abs() < 1e-3,
            "seed {seed}: defender plays H with {heads}"
        );
    }
}

/// The curve's lines without the seconds column, the rows (which the
/// parallel starts write interleaved, as they happen) sorted by start and
/// iteration.
fn curve_without_seconds(path: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines: Vec<(Vec<usize>, String)> = text
        .lines()
        .map(|line| {
            let mut fields: Vec<&str> = line.split(',').collect();
            fields.remove(2);
            let key = fields[..2].iter().map(|f| f.parse().unwrap_or(0)).collect();
            (key, fields.join(","))
        })
        .collect();
    lines[1..].sort();
    lines.into_iter().map(|(_, line)| line).collect()
}

#[test]
fn same_seed_and_settings_give_the_same_curve_except_wall_clock_seconds() {
    let g = game(&common::random::game_json(7));
    let dra = common::recurrent_goal_safe();
    let settings = Settings {
        seed: 11,
        max_iterations: 40,
        check_every: 7,
        single_player_ascent: false,
        ..Settings::default()
    };
    let structure = Structure::full(&g, 2, 1, false);
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let curves: Vec<Vec<String>> = ["curve-a.csv", "curve-b.csv"]
        .iter()
        .map(|name| {
            let path = dir.join(name);
            let mut writer = CurveCsv::create(&path).unwrap();
            let outcome = optimise_structure(
                &g,
                &dra,
                None,
                &structure,
                &settings,
                0,
                &mut writer,
                &Cancel::new(),
            )
            .unwrap();
            let iterations: usize = outcome.report.starts.iter().map(|s| s.iterations).sum();
            let curve = curve_without_seconds(&path);
            assert_eq!(
                curve.len(),
                iterations + 2,
                "one row per iteration of every start, and the returned defender's"
            );
            curve
        })
        .collect();
    assert_eq!(
        curves[0][0],
        "start,iteration,value,defender_gradient_norm,adversary_gradient_norm,defender_step,adversary_step,worst_case,certified_lower,upper_bound,logit_bound,source,returned"
    );
    assert_eq!(curves[0], curves[1]);
}

#[test]
fn settings_out_of_range_are_rejected_before_any_work() {
    let g = game(MATCHING_PENNIES);
    let dra = common::eventually_goal();
    let bad = [
        Settings {
            logit_bound: 0.0,
            ..Settings::default()
        },
        Settings {
            defender_step: f64::NAN,
            ..Settings::default()
        },
        Settings {
            check_every: 0,
            ..Settings::default()
        },
        Settings {
            initial_spread: 5.0,
            logit_bound: 4.0,
            ..Settings::default()
        },
    ];
    for settings in bad {
        assert!(settings.validate().is_err(), "{settings:?}");
        assert!(common::solve_one_node(&g, &dra, None, &settings).is_err());
    }
    assert!(Settings::default().validate().is_ok());
}

#[test]
fn a_run_resumes_from_the_logits_it_wrote() {
    let g = game(MATCHING_PENNIES);
    let dra = common::eventually_goal();
    let settings = Settings {
        max_iterations: 20,
        ..Settings::default()
    };
    let first = common::solve_one_node(&g, &dra, None, &settings).unwrap();
    let best = first.best();
    let resumed = Structure {
        name: "resumed".into(),
        defender: best.defender.clone(),
        adversary: best.adversary.clone(),
        warm: None,
    };
    let still = Settings {
        initial_spread: 0.0,
        max_iterations: 1,
        restarts: 0,
        ..Settings::default()
    };
    let again =
        optimise_structure(&g, &dra, None, &resumed, &still, 0, &mut (), &Cancel::new()).unwrap();
    let heads = |f: &Fsc| {
        f.choices(0, 0)
            .iter()
            .find(|c| c.action == 0)
            .unwrap()
            .probability
    };
    assert!((heads(&again.defender) - heads(&best.defender)).abs() < 1e-12);
    assert!((again.report.worst_case - best.report.worst_case).abs() < 1e-3);
}

#[test]
fn runs_stop_on_the_time_budget_and_on_stalled_progress() {
    let g = game(MATCHING_PENNIES);
    let dra = common::eventually_goal();
    let timed = Settings {
        time_budget: 1e-9,
        ..Settings::default()
    };
    let report = common::solve_one_node(&g, &dra, None, &timed)
        .unwrap()
        .best()
        .report
        .clone();
    assert_eq!(
        (report.status, report.iterations, report.checks),
        (Status::TimeBudget, 1, 1)
    );
    let stalling = Settings {
        stall_checks: 1,
        stall_gain: 1.0,
        check_every: 3,
        initial_logit_bound: Settings::default().logit_bound,
        ..Settings::default()
    };
    let report = common::solve_one_node(&g, &dra, None, &stalling)
        .unwrap()
        .best()
        .report
        .clone();
    // The stall rule is judged where suffix-averaging windows end (t + 1 a
    // power of two): at t = 0 and t = 1 (both checked), a gain of at most
    // 100% stops the run at the second.
    assert_eq!(
        (report.status, report.iterations, report.checks),
        (Status::Stalled, 2, 2)
    );
}

#[test]
fn solve_also_optimises_on_pruned_structures_and_picks_the_best() {
    // Noise-free 3x2 grid, `GF goal & G !unsafe`: every controller on the
    // full support has value 0; Algorithm 1 keeps one structure of value 1.
    let g = posg_fsc::game::grid::GridSpec {
        defender_p_obs: 1.0,
        adversary_p_obs: 1.0,
        p_na: 1.0,
        p_a: 1.0,
        ..Default::default()
    }
    .build()
    .unwrap();
    let dra = common::recurrent_goal_safe();
    let settings = Settings {
        max_iterations: 10,
        structures: vec![StructureSource::Full, StructureSource::Paper],
        ..Settings::default()
    };
    let found = common::solve_one_node(&g, &dra, None, &settings).unwrap();
    let names: Vec<&str> = found
        .solution
        .structures
        .iter()
        .map(|s| s.report.name.as_str())
        .collect();
    assert_eq!(names, ["full", "pruned-1"]);
    assert_eq!(found.solution.structures[0].report.worst_case, 0.0);
    assert_eq!(found.best().report.name, "pruned-1");
    assert!(
        (found.best().report.worst_case - 1.0).abs() < 1e-9,
        "{}",
        found.best().report.worst_case
    );
    let unpruned = Settings {
        structures: vec![StructureSource::Full],
        ..settings
    };
    assert_eq!(
        common::solve_one_node(&g, &dra, None, &unpruned)
            .unwrap()
            .solution
            .structures
            .len(),
        1
    );
}
