//! Exact values: hand-computed chains, random games against an independent
//! dense computation, and the adjoint gradient against finite differences.

mod common;

use posg_fsc::automaton::Dra;
use posg_fsc::controller::{Fsc, Probabilities, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::optimise::Softmax;
use posg_fsc::value::{Evaluator, Exploration, StateClass, evaluate_controllers};
use posg_fsc::value::{SolverMethod, SolverSettings};
use proptest::prelude::*;

fn game(text: &str) -> Posg {
    from_json_str(text, "test.posg.json").unwrap()
}

fn evaluator(game: &Posg, dra: &Dra, def: &Fsc, adv: &Fsc) -> Evaluator {
    Evaluator::new(
        game,
        dra,
        &Support::of(def),
        &Support::of(adv),
        &SolverSettings::default(),
    )
    .unwrap()
}

fn value(game: &Posg, dra: &Dra, def: &Fsc, adv: &Fsc) -> f64 {
    evaluate_controllers(game, dra, def, adv, &SolverSettings::default())
        .unwrap()
        .1
        .value
}

fn uniform(game: &Posg, role: Role, nodes: usize) -> Fsc {
    let player = if role == Role::Defender {
        game.defender()
    } else {
        game.adversary()
    };
    Fsc::uniform(role, nodes, player.num_observations(), player.num_actions())
}

const LOOP_THEN_SPLIT: &str = r#"{
  "posg": 1, "states": ["a", "b", "c"], "initial": {"a": 1.0},
  "labels": {"b": ["goal"]},
  "defender": {"actions": ["go"], "observe": "full"},
  "transitions": [
    {"state": "a", "defender": "go", "next": {"a": 0.25, "b": 0.5, "c": 0.25}},
    {"state": "b", "defender": "*", "next": {"b": 1.0}},
    {"state": "c", "defender": "*", "next": {"c": 1.0}}
  ]
}"#;

#[test]
fn reachability_on_a_three_state_chain_is_two_thirds() {
    // x(a) = 0.25 x(a) + 0.5  =>  x(a) = 2/3.
    let g = game(LOOP_THEN_SPLIT);
    let v = value(
        &g,
        &common::eventually_goal(),
        &uniform(&g, Role::Defender, 1),
        &uniform(&g, Role::Adversary, 1),
    );
    assert!((v - 2.0 / 3.0).abs() < 1e-12, "{v}");
}

const LEAKY_START: &str = r#"{
  "posg": 1, "states": ["s0", "s1", "s2", "s3"], "initial": {"s0": 1.0},
  "labels": {"s1": ["unsafe"]},
  "defender": {"actions": ["stay"], "observe": "full"},
  "transitions": [
    {"state": "s0", "defender": "*", "next": {"s0": 0.5, "s1": 0.3, "s2": 0.2}},
    {"state": "s1", "defender": "*", "next": {"s1": 1.0}},
    {"state": "s2", "defender": "*", "next": {"s3": 1.0}},
    {"state": "s3", "defender": "*", "next": {"s2": 1.0}}
  ]
}"#;

#[test]
fn safety_on_a_four_state_chain_is_two_fifths() {
    // x(s0) = 0.5 x(s0) + 0.2  =>  x(s0) = 0.4; {s2, s3} is a safe recurrent class.
    let g = game(LEAKY_START);
    let v = value(
        &g,
        &common::always_safe(),
        &uniform(&g, Role::Defender, 1),
        &uniform(&g, Role::Adversary, 1),
    );
    assert!((v - 0.4).abs() < 1e-12, "{v}");
}

/// s0 -> s1 (goal) or s2; s1 -> s2; from s2 an attack (A) leads to s3
/// (unsafe, absorbing) or s1, no attack (N) to s1 or s4 (goal, absorbing).
const ATTACKED_LOOP: &str = r#"{
  "posg": 1, "states": ["s0", "s1", "s2", "s3", "s4"], "initial": {"s0": 1.0},
  "labels": {"s1": ["goal"], "s3": ["unsafe"], "s4": ["goal"]},
  "defender": {"actions": ["go"], "observe": "full"},
  "adversary": {"actions": ["A", "N"], "observe": "full"},
  "transitions": [
    {"state": "s0", "defender": "*", "adversary": "*", "next": {"s1": 0.5, "s2": 0.5}},
    {"state": "s1", "defender": "*", "adversary": "*", "next": {"s2": 1.0}},
    {"state": "s2", "defender": "go", "adversary": "A", "next": {"s3": 0.5, "s1": 0.5}},
    {"state": "s2", "defender": "go", "adversary": "N", "next": {"s1": 0.5, "s4": 0.5}},
    {"state": "s3", "defender": "*", "adversary": "*", "next": {"s3": 1.0}},
    {"state": "s4", "defender": "*", "adversary": "*", "next": {"s4": 1.0}}
  ]
}"#;

fn attacker(g: &Posg, p: f64) -> Fsc {
    let mixed: &[(usize, f64)] = if p > 0.0 {
        &[(0, p), (1, 1.0 - p)]
    } else {
        &[(1, 1.0)]
    };
    let idle: &[(usize, f64)] = &[(1, 1.0)];
    common::memoryless(g, Role::Adversary, &[idle, idle, mixed, idle, idle])
}

#[test]
fn recurrence_under_attack_is_one_minus_the_attack_rate() {
    // From s2: x2 = 0.5 x1 + 0.5 (1 - p), x1 = x2  =>  x2 = 1 - p = x0.
    let g = game(ATTACKED_LOOP);
    let defender = uniform(&g, Role::Defender, 1);
    for p in [0.3, 0.75, 0.0] {
        let v = value(
            &g,
            &common::recurrent_goal_safe(),
            &defender,
            &attacker(&g, p),
        );
        assert!((v - (1.0 - p)).abs() < 1e-12, "p = {p}: {v}");
    }
}

#[test]
fn safe_until_goal_under_attack() {
    // From s2: reach goal unless the attack leads to s3: 1 - p/2; V = 1/2 + (1 - p/2)/2.
    let g = game(ATTACKED_LOOP);
    let v = value(
        &g,
        &common::safe_until_goal(),
        &uniform(&g, Role::Defender, 1),
        &attacker(&g, 0.3),
    );
    assert!((v - (1.0 - 0.25 * 0.3)).abs() < 1e-12, "{v}");
}

#[test]
fn a_chain_with_no_feasible_class_has_value_zero_and_no_system() {
    let g = game(LEAKY_START);
    let dra = common::eventually_goal();
    let mut ev = evaluator(
        &g,
        &dra,
        &uniform(&g, Role::Defender, 1),
        &uniform(&g, Role::Adversary, 1),
    );
    assert!(ev.recurrence().transient.is_empty());
    let def = Support::probabilities_of(&uniform(&g, Role::Defender, 1));
    let adv = Support::probabilities_of(&uniform(&g, Role::Adversary, 1));
    assert_eq!(ev.evaluate(&def, &adv).unwrap().value, 0.0);
}

/// Every row sums to 1, except the rows of decided states, which are empty.
fn check_rows_sum_to_one(ev: &Evaluator) -> Result<(), TestCaseError> {
    for m in 0..ev.gmc().num_states() {
        let row = ev.gmc().row(m).1;
        if ev.gmc().verdict(m).is_some() {
            prop_assert!(row.is_empty(), "decided state {} has a row", m);
            continue;
        }
        let total: f64 = row.iter().sum();
        prop_assert!((total - 1.0).abs() < 1e-12, "row {} sums to {}", m, total);
    }
    let p0: f64 = ev.gmc().initial().map(|(_, p)| p).sum();
    prop_assert!((p0 - 1.0).abs() < 1e-12);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(200)
    })]

    #[test]
    fn random_games_agree_with_the_dense_reference(seed in any::<u64>()) {
        let g = game(&common::random::game_json(seed));
        let dra = common::random::dra(seed);
        let def = common::random::controller(seed, &g, Role::Defender);
        let adv = common::random::controller(seed, &g, Role::Adversary);
        let mut ev = evaluator(&g, &dra, &def, &adv);
        let v = ev.evaluate(&Support::probabilities_of(&def), &Support::probabilities_of(&adv)).unwrap();
        check_rows_sum_to_one(&ev)?;
        let reference = common::reference_value(&g, &dra, &def, &adv);
        prop_assert!((v.value - reference).abs() < 1e-9, "value {} vs reference {}", v.value, reference);
        prop_assert!(v.residual < 1e-12);
    }

    /// The adjoint gradient against central differences along the
    /// directions a controller can move in: `e_k - e_first` inside each
    /// block (the probabilities stay a distribution; the value is only
    /// defined there, since the diagonal of `I - Q` comes from the outgoing
    /// probabilities, method.md section 8), and each initial probability.
    #[test]
    fn adjoint_gradient_matches_central_differences(seed in any::<u64>()) {
        let g = game(&common::random::game_json(seed));
        let dra = common::random::dra(seed);
        let def = common::random::controller(seed, &g, Role::Defender);
        let adv = common::random::controller(seed, &g, Role::Adversary);
        let mut ev = evaluator(&g, &dra, &def, &adv);
        let (pd, pa) = (Support::probabilities_of(&def), Support::probabilities_of(&adv));
        let (_, gradient) = ev.evaluate_with_gradient(&pd, &pa).unwrap();
        let mut at = |pd: &Probabilities, pa: &Probabilities| ev.evaluate(pd, pa).unwrap().value;
        let h = 1e-6;
        let scale = 1.0 + gradient.defender.iter().chain(&gradient.adversary).fold(0.0f64, |m, g| m.max(g.abs()));
        for (first, k) in common::block_directions(&Support::of(&def)) {
            let (mut plus, mut minus) = (pd.clone(), pd.clone());
            plus.entries[k] += h;
            plus.entries[first] -= h;
            minus.entries[k] -= h;
            minus.entries[first] += h;
            let fd = (at(&plus, &pa) - at(&minus, &pa)) / (2.0 * h);
            let adjoint = gradient.defender[k] - gradient.defender[first];
            prop_assert!((fd - adjoint).abs() < 1e-6 * scale, "defender {} - {}: fd {} adjoint {}", k, first, fd, adjoint);
        }
        for (first, k) in common::block_directions(&Support::of(&adv)) {
            let (mut plus, mut minus) = (pa.clone(), pa.clone());
            plus.entries[k] += h;
            plus.entries[first] -= h;
            minus.entries[k] -= h;
            minus.entries[first] += h;
            let fd = (at(&pd, &plus) - at(&pd, &minus)) / (2.0 * h);
            let adjoint = gradient.adversary[k] - gradient.adversary[first];
            prop_assert!((fd - adjoint).abs() < 1e-6 * scale, "adversary {} - {}: fd {} adjoint {}", k, first, fd, adjoint);
        }
        for g0 in 0..pd.initial.len() {
            let (mut plus, mut minus) = (pd.clone(), pd.clone());
            plus.initial[g0] += h;
            minus.initial[g0] -= h;
            if pd.initial[g0] == 0.0 { continue; }
            let fd = (at(&plus, &pa) - at(&minus, &pa)) / (2.0 * h);
            prop_assert!((fd - gradient.defender_initial[g0]).abs() < 1e-6 * scale, "initial {}: fd {} adjoint {}", g0, fd, gradient.defender_initial[g0]);
        }
    }

    #[test]
    fn krylov_agrees_with_lu_on_values_and_gradients_also_when_warm_started(seed in any::<u64>()) {
        let g = game(&common::random::game_json(seed));
        let dra = common::random::dra(seed);
        let def = common::random::controller(seed, &g, Role::Defender);
        let adv = common::random::controller(seed, &g, Role::Adversary);
        let (soft_def, soft_adv) = (Softmax::new(&def, true), Softmax::new(&adv, true));
        let evaluator_with = |method| {
            let settings = SolverSettings { method, tolerance: 1e-11, ..SolverSettings::default() };
            Evaluator::new(&g, &dra, &Support::of(&def), &Support::of(&adv), &settings).unwrap()
        };
        let (mut lu, mut krylov) = (evaluator_with(SolverMethod::Lu), evaluator_with(SolverMethod::Krylov));
        prop_assert_eq!(krylov.solver_method(), SolverMethod::Krylov);
        for step in 0..3 {
            let logits = |n: usize, salt: u64| -> Vec<f64> {
                (0..n).map(|i| ((seed ^ salt).wrapping_mul(i as u64 + 7 + step) % 1000) as f64 / 250.0 - 2.0).collect()
            };
            let pd = soft_def.probabilities(&logits(soft_def.num_parameters(), 1));
            let pa = soft_adv.probabilities(&logits(soft_adv.num_parameters(), 2));
            let (v_lu, g_lu) = lu.evaluate_with_gradient(&pd, &pa).unwrap();
            let (v_kr, g_kr) = krylov.evaluate_with_gradient(&pd, &pa).unwrap();
            prop_assert!((v_lu.value - v_kr.value).abs() < 1e-9, "step {}: value {} vs {}", step, v_lu.value, v_kr.value);
            prop_assert!(v_kr.residual <= 1e-11 && g_kr.adjoint_residual <= 1e-11);
            let pairs = g_lu.defender.iter().zip(&g_kr.defender)
                .chain(g_lu.adversary.iter().zip(&g_kr.adversary))
                .chain(g_lu.defender_initial.iter().zip(&g_kr.defender_initial));
            for (a, b) in pairs {
                prop_assert!((a - b).abs() < 1e-7 * (1.0 + a.abs()), "step {}: gradient {} vs {}", step, a, b);
            }
        }
    }
}

/// Stopping the exploration at decided states changes neither the value,
/// nor the gradient, nor the linear system: on 300 random games the
/// truncated GMC's states are those of the full one that are not reached
/// through a decided state only, each decided state gets the class the full
/// chain gives it (`Zero`, or `Target`/`Sure`), and the transient states
/// are the same.
#[test]
fn stopping_at_decided_states_changes_no_value_gradient_or_system() {
    let mut truncated_chains = 0;
    for seed in 0..300u64 {
        let g = game(&common::random::game_json(seed));
        let dra = common::random::dra(seed);
        let def = common::random::controller(seed, &g, Role::Defender);
        let adv = common::random::controller(seed, &g, Role::Adversary);
        let (pd, pa) = (
            Support::probabilities_of(&def),
            Support::probabilities_of(&adv),
        );
        let with = |exploration| {
            let (sd, sa) = (Support::of(&def), Support::of(&adv));
            let settings = SolverSettings::default();
            Evaluator::with_exploration(&g, &dra, &sd, &sa, &settings, exploration).unwrap()
        };
        let (mut full, mut truncated) = (with(Exploration::Full), with(Exploration::UntilDecided));
        let (v_full, g_full) = full.evaluate_with_gradient(&pd, &pa).unwrap();
        let (v_cut, g_cut) = truncated.evaluate_with_gradient(&pd, &pa).unwrap();
        assert!(
            (v_full.value - v_cut.value).abs() < 1e-12,
            "seed {seed}: {v_full:?} vs {v_cut:?}"
        );
        let pairs = g_full
            .defender
            .iter()
            .zip(&g_cut.defender)
            .chain(g_full.adversary.iter().zip(&g_cut.adversary))
            .chain(g_full.defender_initial.iter().zip(&g_cut.defender_initial))
            .chain(
                g_full
                    .adversary_initial
                    .iter()
                    .zip(&g_cut.adversary_initial),
            );
        for (a, b) in pairs {
            assert!(
                (a - b).abs() < 1e-12 * (1.0 + a.abs()),
                "seed {seed}: gradient {a} vs {b}"
            );
        }
        let (cut_gmc, full_gmc) = (truncated.gmc(), full.gmc());
        assert_eq!(full_gmc.num_decided(), 0);
        assert!(cut_gmc.num_states() <= full_gmc.num_states());
        truncated_chains += usize::from(cut_gmc.num_states() < full_gmc.num_states());
        let transient_states = |ev: &Evaluator| -> Vec<_> {
            ev.recurrence()
                .transient
                .iter()
                .map(|&m| ev.gmc().state(m))
                .collect()
        };
        assert_eq!(
            transient_states(&full),
            transient_states(&truncated),
            "seed {seed}"
        );
        for m in 0..cut_gmc.num_states() {
            let state = cut_gmc.state(m);
            let in_full = full_gmc
                .index_of(state)
                .expect("every explored state is in the full chain");
            let (cut_class, full_class) = (
                truncated.recurrence().classes[m],
                full.recurrence().classes[in_full],
            );
            match cut_gmc.verdict(m) {
                None => assert_eq!(cut_class, full_class, "seed {seed}, state {state:?}"),
                Some(holds) => {
                    assert_eq!(
                        cut_class,
                        if holds {
                            StateClass::Sure
                        } else {
                            StateClass::Zero
                        }
                    );
                    let full_holds = matches!(full_class, StateClass::Target | StateClass::Sure);
                    assert!(
                        full_class != StateClass::Transient && full_holds == holds,
                        "seed {seed}, decided state {state:?}: {full_class:?} in the full chain"
                    );
                }
            }
        }
    }
    assert!(
        truncated_chains >= 100,
        "only {truncated_chains} of 300 random chains had decided states"
    );
}
