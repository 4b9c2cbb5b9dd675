//! Certified bounds for expected rewards on games (method.md section 9,
//! "the worst case over adversaries"): the adversary's optimum of the
//! certification product against the best of every deterministic
//! memoryless adversary that sees the state, each evaluated on the GMC
//! (an independent computation: the GMC's reward vector and linear system
//! against the product MDP's step rewards and policy iteration).

mod common;

use std::path::PathBuf;

use posg_fsc::certify::reward::reward_certificate;
use posg_fsc::certify::{CertifyError, MdpError};
use posg_fsc::controller::{Fsc, Role, Support};
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

/// The random game of `seed` with rewards (and an adversary), `player`
/// (`"defender"` or `"adversary"`) seeing the state.
fn game_seen_by(seed: u64, player: &str) -> Option<Posg> {
    let mut game: Value =
        serde_json::from_str(&common::random::game_json_with_rewards(seed)).unwrap();
    game.get("adversary")?;
    game[player]["observations"] = game["states"].clone();
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
    game[player]["observe"] = Value::Object(observe);
    Some(from_json_str(&game.to_string(), "r.posg.json").unwrap())
}

/// `role`'s controller playing `choice[s]` in state `s` (its observation).
fn memoryless(game: &Posg, role: Role, choice: &[usize]) -> Fsc {
    let rows: Vec<[(usize, f64); 1]> = choice.iter().map(|&action| [(action, 1.0)]).collect();
    let rows: Vec<&[(usize, f64)]> = rows.iter().map(|row| row.as_slice()).collect();
    common::memoryless(game, role, &rows)
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

/// The best value for the player who is not `fixed`'s (the adversary: the
/// largest cost, the smallest reward; the defender: the reverse) over its
/// deterministic memoryless strategies on the states; `None` where there
/// are more than 729.
fn best_memoryless(game: &Posg, objective: &RewardObjective, fixed: (&Fsc, Role)) -> Option<f64> {
    let free = fixed.1.other();
    let player = match free {
        Role::Defender => game.defender(),
        Role::Adversary => game.adversary(),
    };
    let (n, k) = (game.num_states(), player.num_actions());
    if (k as f64).powi(n as i32) > 729.0 {
        return None;
    }
    let largest = (free == Role::Adversary) == objective.minimise;
    let mut choice = vec![0; n];
    let mut best: Option<f64> = None;
    loop {
        let played = memoryless(game, free, &choice);
        let value = match free {
            Role::Adversary => expected_reward(game, objective, fixed.0, &played),
            Role::Defender => expected_reward(game, objective, &played, fixed.0),
        };
        best = Some(match (best, largest) {
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
        let Some(game) = game_seen_by(seed, "adversary") else { return Ok(()) };
        let Some(objective) = objective(&game, minimise) else { return Ok(()) };
        let def = common::random::controller_with_nodes(seed, &game, Role::Defender, 1);
        let Some(best) = best_memoryless(&game, &objective, (&def, Role::Defender)) else { return Ok(()) };
        let certified = reward_certificate(
            &game,
            (&objective.target, &objective.rewards, objective.minimise),
            &def,
            &[],
            &SolverSettings::default(),
        );
        match certified {
            Ok(certificate) => {
                let worst = certificate.worst_case;
                assert_within((worst.lower, worst.upper), best);
                let guaranteed = certificate.guaranteed;
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

    /// The other half: against a 1-node adversary, the defender that sees
    /// the state, whose optimum is the best of its deterministic memoryless
    /// strategies (a 1-node adversary meets each state before the target
    /// once), evaluated on the GMC: what no defender beats.
    #[test]
    fn the_best_possible_is_the_best_defender_that_sees_the_state(seed in any::<u64>(), minimise in any::<bool>()) {
        let Some(game) = game_seen_by(seed, "defender") else { return Ok(()) };
        let Some(objective) = objective(&game, minimise) else { return Ok(()) };
        let adv = common::random::controller_with_nodes(seed, &game, Role::Adversary, 1);
        let Some(best) = best_memoryless(&game, &objective, (&adv, Role::Adversary)) else { return Ok(()) };
        let def = Fsc::uniform_enabled(Role::Defender, 1, game.defender());
        let certified = reward_certificate(
            &game,
            (&objective.target, &objective.rewards, objective.minimise),
            &def,
            &[&adv],
            &SolverSettings::default(),
        );
        match certified {
            Ok(certificate) => match certificate.best_response {
                Some(bound) => assert_within((bound.lower, bound.upper), best),
                // Refused (a cycle that loses): only for a minimum.
                None => prop_assert!(minimise),
            },
            Err(CertifyError::Mdp(MdpError::RewardCycle(_))) => prop_assert!(!minimise),
            Err(e) => prop_assert!(false, "{e}"),
        }
    }
}

fn posg_fsc(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(args)
        .output()
        .unwrap()
}

/// `tests/data/rewards/two-roads.posg.json`: each round the defender takes
/// road `a` or `b` and the adversary guards one; a guarded road costs 3 and
/// leads back to the start half the time, a free one costs 1 and reaches the
/// goal. Against a defender taking `a` with probability `p`, a guard of `a`
/// makes `x = (1 + 2p) / (1 - p/2)`: the game's value is `8/3`, at `p =
/// 1/2`, and a deterministic defender (the adversary guards its road)
/// costs 6.
const TWO_ROADS: &str = "tests/data/rewards/two-roads.posg.json";

/// `posg-fsc solve GAME --props QUERY` into `out` under a fresh directory
/// `posg-fsc-NAME-PID`: the directory and `summary.json`.
fn solve(game: &str, query: &str, name: &str) -> (PathBuf, Value) {
    let dir = std::env::temp_dir().join(format!("posg-fsc-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("out");
    let output = posg_fsc(&[
        "solve",
        game,
        "--props",
        query,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(output.status.success(), "{output:?}");
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    (dir, serde_json::from_str(&summary).unwrap())
}

#[test]
fn solve_certifies_the_value_of_a_game_with_a_mixed_optimum() {
    let query = "R{\"cost\"}min=? [F \"goal\"]";
    let (dir, summary) = solve(TWO_ROADS, query, "two-roads");
    let value = summary["value"].as_f64().unwrap();
    let certificate = &summary["certificate"];
    let guaranteed = certificate["guaranteed"].as_f64().unwrap();
    let best_possible = certificate["best_possible"].as_f64().unwrap();
    assert_eq!(value, guaranteed);
    // Sound: no defender guarantees less than 8/3, and no defender gets
    // below the bound; found: within 1% of the optimum.
    assert!(
        (8.0 / 3.0 - 1e-9..8.0 / 3.0 * 1.01).contains(&guaranteed),
        "{summary}"
    );
    assert!(
        best_possible <= 8.0 / 3.0 + 1e-9 && best_possible <= guaranteed,
        "{summary}"
    );

    // `certify` of the returned defender says the same, and of the
    // deterministic defender that always takes `a`: 6.
    let defender = dir.join("out").join("defender.fsc.json");
    let certified = certify(&[
        TWO_ROADS,
        "--props",
        query,
        "--defender",
        defender.to_str().unwrap(),
    ]);
    assert!((certified["guaranteed"].as_f64().unwrap() - guaranteed).abs() < 1e-12);
    assert_eq!(certified["best_possible"], Value::Null);
    let always_a = dir.join("a.fsc.json");
    std::fs::write(
        &always_a,
        r#"{"fsc": 1, "player": "defender", "nodes": 1, "initial": [1.0], "rules": [
          {"node": 0, "observation": "start", "choices": [{"next": 0, "action": "a", "p": 1.0}]},
          {"node": 0, "observation": "goal", "choices": [{"next": 0, "action": "a", "p": 1.0}]}]}"#,
    )
    .unwrap();
    let certified = certify(&[
        TWO_ROADS,
        "--props",
        query,
        "--defender",
        always_a.to_str().unwrap(),
        "--adversary",
        "uniform:1",
    ]);
    assert!(
        (certified["guaranteed"].as_f64().unwrap() - 6.0).abs() < 1e-9,
        "{certified}"
    );
    // Against the uniform guard, the defender that sees the state gets 8/3.
    assert!((certified["best_possible"].as_f64().unwrap() - 8.0 / 3.0).abs() < 1e-9);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `certify`'s JSON for `args`.
fn certify(args: &[&str]) -> Value {
    let output = posg_fsc(&[&["certify"], args].concat());
    assert!(output.status.success(), "{output:?}");
    serde_json::from_slice(&output.stdout).unwrap()
}

/// `tests/data/rewards/trap-door.posg.json`: the defender walks to the goal
/// (cost 1) or takes a door behind which the adversary may keep it forever.
/// A uniform adversary opens the door half the time, so the chain of the
/// full supports reaches the goal; the adversary that sees the state never
/// does, so every defender that may take the door has an infinite worst
/// case. The race runs on the almost-sure support (walking only) and every
/// start certifies 1.
#[test]
fn a_cost_races_where_every_adversary_lets_the_defender_reach_the_target() {
    let game = "tests/data/rewards/trap-door.posg.json";
    let (dir, summary) = solve(game, "R{\"steps\"}min=? [F \"goal\"]", "trap-door");
    assert!(
        (summary["value"].as_f64().unwrap() - 1.0).abs() < 1e-9,
        "{summary}"
    );
    assert!(summary.get("dropped_starts").is_none(), "{summary}");
    for start in summary["starts"].as_array().unwrap() {
        assert!(
            (start["value"].as_f64().unwrap() - 1.0).abs() < 1e-6,
            "{summary}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
