//! Certified bounds for expected rewards on games (method.md section 9,
//! "the worst case over adversaries"): the adversary's optimum of the
//! certification product against the best of every deterministic
//! memoryless adversary that sees the state, each evaluated on the GMC
//! (an independent computation: the GMC's reward vector and linear system
//! against the product MDP's step rewards and policy iteration).

mod common;

use posg_fsc::certify::reward::reward_certificate;
use posg_fsc::certify::{CertifyError, MdpError};
use posg_fsc::controller::{Choice, Fsc, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::ltl::TranslationBudget;
use posg_fsc::ltl::props::{Query, parse_props};
use posg_fsc::pipeline::RewardObjective;
use posg_fsc::value::{Evaluator, SolverSettings};
use proptest::prelude::*;
use serde_json::{Value, json};

/// `R{"r"}min=? [F "goal"]` (or `max`) on `game`, when a state is labelled `goal`.
fn objective(game: &Posg, minimise: bool) -> Option<RewardObjective> {
    let text = if minimise {
        "Rmin=? [F \"goal\"]"
    } else {
        "Rmax=? [F \"goal\"]"
    };
    let property = parse_props(text).unwrap();
    let Query::Reward(query) = &property.query else {
        unreachable!()
    };
    let budget = TranslationBudget::default();
    RewardObjective::for_game(game, query, minimise, &budget, false)
        .ok()
        .map(|o| o.0)
}

/// The random game of `seed` with rewards, its adversary seeing the state.
fn game_with_seeing_adversary(seed: u64) -> Option<Posg> {
    let mut game: Value =
        serde_json::from_str(&common::random::game_json_with_rewards(seed)).unwrap();
    game.get("adversary")?;
    game["adversary"]["observations"] = game["states"].clone();
    let observe: serde_json::Map<String, Value> = game["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            (
                s.as_str().unwrap().to_string(),
                json!({ s.as_str().unwrap(): 1.0 }),
            )
        })
        .collect();
    game["adversary"]["observe"] = Value::Object(observe);
    Some(from_json_str(&game.to_string(), "r.posg.json").unwrap())
}

/// The adversary playing `choice[s]` in state `s` (its observation).
fn memoryless(game: &Posg, choice: &[usize]) -> Fsc {
    let player = game.adversary();
    let blocks = choice
        .iter()
        .map(|&action| {
            vec![Choice {
                next: 0,
                action,
                probability: 1.0,
                logit: None,
            }]
        })
        .collect();
    Fsc::new(
        Role::Adversary,
        1,
        player.num_observations(),
        player.num_actions(),
        vec![1.0],
        blocks,
    )
    .unwrap()
}

fn expected_reward(game: &Posg, objective: &RewardObjective, def: &Fsc, adv: &Fsc) -> f64 {
    let mut evaluator = Evaluator::for_expected_reward(
        game,
        &objective.target,
        &objective.rewards,
        &Support::of(def),
        &Support::of(adv),
        &SolverSettings::default(),
    )
    .unwrap();
    let (pd, pa) = (
        Support::probabilities_of(def),
        Support::probabilities_of(adv),
    );
    evaluator.evaluate(&pd, &pa).unwrap().value
}

/// The best value for the adversary (the largest cost, the smallest
/// reward) over its deterministic memoryless strategies on the states;
/// `None` where there are more than 729.
fn best_memoryless(game: &Posg, objective: &RewardObjective, def: &Fsc) -> Option<f64> {
    let (n, k) = (game.num_states(), game.adversary().num_actions());
    if (k as f64).powi(n as i32) > 729.0 {
        return None;
    }
    let mut choice = vec![0; n];
    let mut best: Option<f64> = None;
    loop {
        let value = expected_reward(game, objective, def, &memoryless(game, &choice));
        best = Some(match (best, objective.minimise) {
            (None, _) => value,
            (Some(b), true) => b.max(value),
            (Some(b), false) => b.min(value),
        });
        let Some(s) = (0..n).find(|&s| choice[s] + 1 < k) else {
            return best;
        };
        choice[s] += 1;
        choice[..s].fill(0);
    }
}

fn assert_within(bracket: (f64, f64), value: f64) {
    if value.is_infinite() {
        assert!(
            bracket.0.is_infinite() && bracket.1.is_infinite(),
            "{bracket:?} {value}"
        );
    } else {
        let slack = 1e-8 * (1.0 + value.abs());
        assert!(
            bracket.0 - slack <= value && value <= bracket.1 + slack,
            "{bracket:?} {value}"
        );
        assert!(
            bracket.1 - bracket.0 <= 1e-7 * (1.0 + value.abs()),
            "{bracket:?}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        cases: 300,
        ..ProptestConfig::default()
    })]

    /// A 1-node defender meets each product state `(s, q)` before the
    /// target once per `s`, so the adversary that sees the product is one
    /// that sees the state: its optimum is the best of its deterministic
    /// memoryless strategies, evaluated on the GMC.
    #[test]
    fn the_worst_case_is_the_best_adversary_that_sees_the_state(seed in any::<u64>(), minimise in any::<bool>()) {
        let Some(game) = game_with_seeing_adversary(seed) else { return Ok(()) };
        let Some(objective) = objective(&game, minimise) else { return Ok(()) };
        let def = common::random::controller_with_nodes(seed, &game, Role::Defender, 1);
        let Some(best) = best_memoryless(&game, &objective, &def) else { return Ok(()) };
        let certified = reward_certificate(
            &game,
            (&objective.target, &objective.rewards, objective.minimise),
            &def,
            None,
            &SolverSettings::default(),
        );
        match certified {
            Ok(certificate) => {
                let worst = certificate.worst_case;
                assert_within((worst.lower, worst.upper), best);
                let guaranteed = certificate.guaranteed();
                let slack = 1e-8 * (1.0 + best.abs());
                let safe = guaranteed == best || match minimise {
                    true => guaranteed >= best - slack,
                    false => guaranteed <= best + slack,
                };
                prop_assert!(safe, "guaranteed {} against the best adversary's {}", guaranteed, best);
            }
            // A minimum the analysis refuses (a cycle outside the target
            // that earns nothing or less): never for a maximum.
            Err(CertifyError::Mdp(MdpError::RewardCycle(_))) => prop_assert!(!minimise),
            Err(e) => prop_assert!(false, "{e}"),
        }
    }
}
