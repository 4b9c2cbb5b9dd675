//! Support synthesis (method.md section 7) against brute force: on random
//! tiny games every 1-node support is certified exactly, and SAT's "found"
//! must agree in both modes and with both engines; a hand-made game needs
//! memory; supports found with several Rabin pairs certify.

use posg_fsc::automaton::Dra;
use posg_fsc::certify::{Qualitative, lower_bound};
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::synthesis::{Confirmation, Engine, Mode, Settings, Synthesis, SynthesisError};
use posg_fsc::value::SolverSettings;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Map, Value, json};

/// [`posg_fsc::synthesis::synthesise`] with the default linear solver.
fn synthesise(
    game: &Posg,
    phi: &Dra,
    not_phi: &Dra,
    nodes: usize,
    settings: &Settings,
) -> Result<Synthesis, SynthesisError> {
    let solver = SolverSettings::default();
    posg_fsc::synthesis::synthesise(game, phi, not_phi, nodes, settings, &solver)
}

/// The single-pair formulas of the issue.
const ONE_PAIR: [&str; 5] = ["G !b", "GF a & G !b", "FG a", "!b U a", "G (a | c) & GF a"];

/// Formulas whose automata have two Rabin pairs. (The second with two
/// nodes is left out of the test: its negation's automaton has no surely
/// accepting cells, the lazy engine's lemmas stay weak, and some of these
/// games take minutes.)
const TWO_PAIRS: [&str; 2] = ["GF a | FG b", "(FG a & GF b) | FG c"];

fn automata(formula: &str) -> (Dra, Dra) {
    let phi = posg_fsc::ltl::parse(formula).unwrap();
    (
        posg_fsc::ltl::translate(&phi).unwrap(),
        posg_fsc::ltl::translate(&phi.negate()).unwrap(),
    )
}

fn names(prefix: &str, n: usize) -> Vec<String> {
    (0..n).map(|i| format!("{prefix}{i}")).collect()
}

/// A random distribution over a non-empty random subset of `outcomes`.
fn distribution(rng: &mut ChaCha8Rng, outcomes: &[String], density: f64) -> Map<String, Value> {
    let mut chosen: Vec<&String> = outcomes
        .iter()
        .filter(|_| rng.random_bool(density))
        .collect();
    if chosen.is_empty() {
        chosen.push(&outcomes[rng.random_range(0..outcomes.len())]);
    }
    let weights: Vec<f64> = chosen.iter().map(|_| rng.random_range(0.1..1.0)).collect();
    let total: f64 = weights.iter().sum();
    chosen
        .into_iter()
        .zip(weights)
        .map(|(name, w)| (name.clone(), json!(w / total)))
        .collect()
}

/// A tiny game: 3-7 states labelled from {a, b, c}, 1-3 defender
/// observations, 2-3 defender actions, 1-2 adversary actions (fully
/// observing), sparse transitions. Every third seed also restricts the
/// actions (`enabled`): some observations of the defender enable a random
/// subset, some states let the adversary play only one of its actions.
fn tiny_game(seed: u64) -> Posg {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let states = names("s", rng.random_range(3..=7));
    let observations = names("o", rng.random_range(1..=3));
    let def_actions = names("u", rng.random_range(2..=3));
    let adv_actions = names("v", rng.random_range(1..=2));
    let observe: Map<String, Value> = states
        .iter()
        .map(|s| {
            (
                s.clone(),
                Value::Object(distribution(&mut rng, &observations, 0.4)),
            )
        })
        .collect();
    let labels: Map<String, Value> = states
        .iter()
        .map(|s| {
            let props: Vec<&str> = ["a", "b", "c"]
                .into_iter()
                .filter(|_| rng.random_bool(0.35))
                .collect();
            (s.clone(), json!(props))
        })
        .collect();
    let mut transitions = Vec::new();
    for s in &states {
        for u in &def_actions {
            for v in &adv_actions {
                let next = distribution(&mut rng, &states, 0.3);
                transitions.push(json!({"state": s, "defender": u, "adversary": v, "next": next}));
            }
        }
    }
    let initial = distribution(&mut rng, &states[..2], 0.3);
    let mut game = json!({
        "posg": 1, "states": states, "initial": initial, "labels": labels,
        "defender": {"actions": def_actions, "observations": observations, "observe": observe},
        "adversary": {"actions": adv_actions, "observe": "full"},
        "transitions": transitions,
    });
    if seed % 3 == 0 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed + 1_000_000);
        let mut defender = Map::new();
        for o in &observations {
            if rng.random_bool(0.6) {
                let mut actions: Vec<&String> = def_actions
                    .iter()
                    .filter(|_| rng.random_bool(0.5))
                    .collect();
                if actions.is_empty() {
                    actions.push(&def_actions[0]);
                }
                defender.insert(o.clone(), json!(actions));
            }
        }
        let mut adversary = Map::new();
        for s in &states {
            if rng.random_bool(0.4) {
                let only = &adv_actions[rng.random_range(0..adv_actions.len())];
                adversary.insert(s.clone(), json!([only]));
            }
        }
        game["defender"]["enabled"] = Value::Object(defender);
        game["adversary"]["enabled"] = Value::Object(adversary);
    }
    from_json_str(&game.to_string(), &format!("tiny-{seed}")).unwrap()
}

/// The 1-node defender uniform on `masks[o]` (a bit set of actions per
/// observation).
fn one_node(game: &Posg, masks: &[usize]) -> Fsc {
    let player = game.defender();
    let blocks = masks
        .iter()
        .map(|&mask| {
            let actions: Vec<usize> = (0..player.num_actions())
                .filter(|u| mask >> u & 1 == 1)
                .collect();
            let p = 1.0 / actions.len() as f64;
            actions
                .into_iter()
                .map(|action| Choice {
                    next: 0,
                    action,
                    probability: p,
                    logit: None,
                })
                .collect()
        })
        .collect();
    Fsc::new(
        Role::Defender,
        1,
        player.num_observations(),
        player.num_actions(),
        vec![1.0],
        blocks,
    )
    .unwrap()
}

/// Every 1-node support (a non-empty set of enabled actions per
/// observation) with the exact class of its certified lower bound.
fn all_one_node_supports(game: &Posg, not_phi: &Dra) -> Vec<(Vec<usize>, Qualitative)> {
    let (no, nu) = (
        game.defender().num_observations(),
        game.defender().num_actions(),
    );
    let per_block = (1usize << nu) - 1;
    let total = per_block.pow(no as u32);
    let enabled: Vec<usize> = (0..no)
        .map(|o| game.defender().enabled_actions(o).map(|u| 1 << u).sum())
        .collect();
    (0..total)
        .filter_map(|mut code| {
            let masks: Vec<usize> = (0..no)
                .map(|_| {
                    let mask = code % per_block + 1;
                    code /= per_block;
                    mask
                })
                .collect();
            masks
                .iter()
                .zip(&enabled)
                .all(|(&m, &e)| m & !e == 0)
                .then_some(masks)
        })
        .map(|masks| {
            let class = lower_bound(game, not_phi, &one_node(game, &masks))
                .unwrap()
                .qualitative;
            (masks, class)
        })
        .collect()
}

fn settings(mode: Mode, engine: Engine, maximise: bool) -> Settings {
    Settings {
        mode,
        engine,
        maximise,
        ..Settings::default()
    }
}

fn wins(mode: Mode, class: Qualitative) -> bool {
    match mode {
        Mode::Positive => class.is_positive(),
        Mode::AlmostSure => class == Qualitative::One,
    }
}

/// The action masks of a 1-node defender.
fn masks_of(fsc: &Fsc) -> Vec<usize> {
    (0..fsc.num_observations())
        .map(|o| fsc.choices(0, o).iter().map(|c| 1 << c.action).sum())
        .collect()
}

#[test]
fn sat_agrees_with_brute_force_on_every_one_node_support() {
    let mut found = [0usize; 2];
    for seed in 0..300 {
        let game = tiny_game(seed);
        let formula = ONE_PAIR[seed as usize % ONE_PAIR.len()];
        let (phi, not_phi) = automata(formula);
        let table = all_one_node_supports(&game, &not_phi);
        for (i, mode) in [Mode::Positive, Mode::AlmostSure].into_iter().enumerate() {
            let expected = table.iter().any(|&(_, class)| wins(mode, class));
            let context = format!("seed {seed}, '{formula}', {mode:?}");
            let lazy = synthesise(
                &game,
                &phi,
                &not_phi,
                1,
                &settings(mode, Engine::Lazy, true),
            )
            .unwrap_or_else(|e| panic!("{context}: {e}"));
            assert_eq!(lazy.defender.is_some(), expected, "lazy engine, {context}");
            assert!(lazy.exact, "{context}");
            let eager = synthesise(
                &game,
                &phi,
                &not_phi,
                1,
                &settings(mode, Engine::Certificate, false),
            )
            .unwrap_or_else(|e| panic!("{context}: {e}"));
            assert_eq!(
                eager.defender.is_some(),
                expected,
                "certificate engine, {context}"
            );
            assert!(eager.exact, "{context}: one pair, exact rank bound");
            if let Some(defender) = &lazy.defender {
                assert_eq!(lazy.confirmation, Confirmation::Confirmed, "{context}");
                assert_maximal(&table, &masks_of(defender), mode, &context);
                found[i] += 1;
            }
        }
    }
    assert!(
        found[0] > 30 && found[1] > 10 && found[0] < 290,
        "the random games must exercise both answers: found {found:?}"
    );
}

/// The support is winning and adding any one action to any observation
/// makes it losing.
fn assert_maximal(table: &[(Vec<usize>, Qualitative)], masks: &[usize], mode: Mode, context: &str) {
    let class_of = |m: &[usize]| table.iter().find(|(t, _)| t == m).map(|&(_, c)| c).unwrap();
    assert!(
        wins(mode, class_of(masks)),
        "{context}: the support found must win"
    );
    for o in 0..masks.len() {
        for u in 0..usize::BITS as usize {
            let larger = masks[o] | 1 << u;
            if larger == masks[o] || table.iter().all(|(t, _)| t[o] != larger) {
                continue;
            }
            let mut extended = masks.to_vec();
            extended[o] = larger;
            assert!(
                !wins(mode, class_of(&extended)),
                "{context}: adding action {u} under observation {o} still wins: not maximal"
            );
        }
    }
}

#[test]
fn with_two_pairs_every_support_found_certifies_and_the_lazy_engine_stays_exact() {
    for seed in 0..120 {
        let game = tiny_game(1000 + seed);
        let formula = TWO_PAIRS[seed as usize % TWO_PAIRS.len()];
        let (phi, not_phi) = automata(formula);
        assert_eq!(phi.pairs().len(), 2, "{formula}");
        let table = all_one_node_supports(&game, &not_phi);
        for mode in [Mode::Positive, Mode::AlmostSure] {
            let context = format!("seed {}, '{formula}', {mode:?}", 1000 + seed);
            let expected = table.iter().any(|&(_, class)| wins(mode, class));
            let run = |engine, nodes| -> Synthesis {
                synthesise(&game, &phi, &not_phi, nodes, &settings(mode, engine, false))
                    .unwrap_or_else(|e| panic!("{context}: {e}"))
            };
            let lazy = run(Engine::Lazy, 1);
            assert_eq!(lazy.defender.is_some(), expected, "lazy, {context}");
            let eager = run(Engine::Certificate, 1);
            assert!(
                eager.defender.is_none() || expected,
                "the certificate engine is sound, {context}"
            );
            if let Some(lower) = eager.certified_lower {
                assert!(lower > 0.0, "{context}");
            }
            if formula == TWO_PAIRS[0] {
                let two = run(Engine::Lazy, 2);
                assert!(
                    !expected || two.defender.is_some(),
                    "a 1-node support embeds into 2 nodes, {context}"
                );
            }
        }
    }
}

/// Blind defender, `GF goal & G !bad` on the cycle s0 -a-> s1 (goal)
/// -b-> s0, where the wrong action leads to the absorbing `bad`. With one
/// node the defender plays the same distribution in s0 and s1: a
/// deterministic choice errs at once, a random one errs with probability 1
/// over infinitely many steps, so no 1-node support wins even positively.
/// Two nodes alternate a, b, a, b, ... and win almost surely.
#[test]
fn memory_is_needed_to_alternate_blindly() {
    let game = from_json_str(
        r#"{"posg": 1, "states": ["s0", "s1", "bad"], "initial": {"s0": 1},
            "labels": {"s1": ["goal"], "bad": ["bad"]},
            "defender": {"actions": ["a", "b"], "observations": ["o"],
                         "observe": {"s0": {"o": 1}, "s1": {"o": 1}, "bad": {"o": 1}}},
            "transitions": [
              {"state": "s0", "defender": "a", "next": {"s1": 1}},
              {"state": "s0", "defender": "b", "next": {"bad": 1}},
              {"state": "s1", "defender": "b", "next": {"s0": 1}},
              {"state": "s1", "defender": "a", "next": {"bad": 1}},
              {"state": "bad", "defender": "*", "next": {"bad": 1}}]}"#,
        "alternate.posg.json",
    )
    .unwrap();
    let (phi, not_phi) = automata("GF goal & G !bad");
    for engine in [Engine::Lazy, Engine::Certificate] {
        for mode in [Mode::Positive, Mode::AlmostSure] {
            let one = synthesise(&game, &phi, &not_phi, 1, &settings(mode, engine, true)).unwrap();
            assert!(
                one.defender.is_none() && one.exact,
                "{engine:?} {mode:?}: {}",
                one.reason
            );
            let two = synthesise(&game, &phi, &not_phi, 2, &settings(mode, engine, true)).unwrap();
            assert_eq!(two.certified_lower, Some(1.0), "{engine:?} {mode:?}");
        }
    }
}

#[test]
fn an_unsatisfiable_formula_is_answered_at_once() {
    let game = tiny_game(7);
    let (phi, not_phi) = automata("a & !a");
    let result = synthesise(&game, &phi, &not_phi, 2, &Settings::default()).unwrap();
    assert!(result.defender.is_none() && result.exact && result.statistics.is_none());
    assert!(result.reason.contains("no run"), "{}", result.reason);
}

#[test]
fn zero_nodes_and_a_zero_rank_bound_are_errors() {
    let game = tiny_game(3);
    let (phi, not_phi) = automata("FG a");
    assert!(synthesise(&game, &phi, &not_phi, 0, &Settings::default()).is_err());
    let bad = Settings {
        rank_bound: Some(0),
        ..Settings::default()
    };
    assert!(synthesise(&game, &phi, &not_phi, 1, &bad).is_err());
}

#[test]
fn a_clause_budget_too_small_is_an_error_naming_the_budget() {
    let game = tiny_game(11);
    let (phi, not_phi) = automata("GF a & G !b");
    let tight = Settings {
        engine: Engine::Certificate,
        clause_budget: 50,
        ..Settings::default()
    };
    let error = synthesise(&game, &phi, &not_phi, 2, &tight).unwrap_err();
    assert!(
        error.to_string().contains("budget of 50 clauses"),
        "{error}"
    );
}
