//! Random small games, automata and controllers for property tests, all
//! derived from one seed.

use posg_fsc::automaton::{Dra, RabinPair};
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::Posg;
use rand::seq::IndexedRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Map, Value, json};

/// A random distribution over `outcomes` with at least one positive entry
/// and some exact zeros.
fn distribution(rng: &mut ChaCha8Rng, outcomes: &[String]) -> Map<String, Value> {
    let mut chosen: Vec<&String> = outcomes.iter().filter(|_| rng.random_bool(0.5)).collect();
    if chosen.is_empty() {
        chosen.push(outcomes.choose(rng).unwrap());
    }
    let weights: Vec<f64> = chosen.iter().map(|_| rng.random_range(0.05..1.0)).collect();
    let total: f64 = weights.iter().sum();
    let mut map = Map::new();
    for (name, w) in chosen.into_iter().zip(weights) {
        map.insert(name.clone(), json!(w / total));
    }
    if let Some(zero) = outcomes.iter().find(|o| !map.contains_key(*o)) {
        map.insert(zero.clone(), json!(0.0));
    }
    map
}

fn names(prefix: &str, n: usize) -> Vec<String> {
    (0..n).map(|i| format!("{prefix}{i}")).collect()
}

fn player(rng: &mut ChaCha8Rng, states: &[String], prefix: &str) -> Value {
    let actions = names(prefix, rng.random_range(1..=3));
    if rng.random_bool(0.3) {
        return json!({"actions": actions, "observe": "full"});
    }
    let observations = names(&format!("{prefix}o"), rng.random_range(1..=3));
    let observe: Map<String, Value> = states
        .iter()
        .map(|s| (s.clone(), Value::Object(distribution(rng, &observations))))
        .collect();
    json!({"actions": actions, "observations": observations, "observe": observe})
}

/// A random game as JSON text: 3-12 states, labels from {goal, unsafe, a},
/// random observation functions (or full observation), an adversary in
/// most games, sparse transitions with exact zeros.
pub fn game_json(seed: u64) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let states = names("s", rng.random_range(3..=12));
    let defender = player(&mut rng, &states, "u");
    let adversary = rng.random_bool(0.8).then(|| player(&mut rng, &states, "v"));
    let mut labels = Map::new();
    for s in &states {
        let props: Vec<&str> = ["goal", "unsafe", "a"]
            .into_iter()
            .filter(|_| rng.random_bool(0.3))
            .collect();
        labels.insert(s.clone(), json!(props));
    }
    let def_actions: Vec<String> = serde_json::from_value(defender["actions"].clone()).unwrap();
    let adv_actions: Vec<String> = match &adversary {
        Some(a) => serde_json::from_value(a["actions"].clone()).unwrap(),
        None => vec!["*".to_string()],
    };
    let mut transitions = Vec::new();
    for s in &states {
        for u in &def_actions {
            for v in &adv_actions {
                let next = distribution(&mut rng, &states);
                transitions.push(json!({"state": s, "defender": u, "adversary": v, "next": next}));
            }
        }
    }
    let initial = distribution(&mut rng, &states[..2]);
    let mut game = json!({
        "posg": 1, "name": format!("random-{seed}"), "states": states, "initial": initial,
        "labels": labels, "defender": defender, "transitions": transitions,
    });
    if let Some(a) = adversary {
        game["adversary"] = a;
    }
    game.to_string()
}

/// [`game_json`] with a random `enabled` map on every player that has
/// several actions (each observation enables a random non-empty subset,
/// some observations are left out) and without the transition entries the
/// game no longer needs: those of `(s, u, v)` where no observation of `s`
/// enables `u`, or none enables `v` (formats.md section 6).
pub fn game_json_with_enabled(seed: u64) -> String {
    let mut game: Value = serde_json::from_str(&game_json(seed)).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xe1ab1ed);
    let states: Vec<String> = serde_json::from_value(game["states"].clone()).unwrap();
    let mut possible: Vec<Vec<Vec<String>>> = Vec::new();
    for role in ["defender", "adversary"] {
        let Some(player) = game.get_mut(role) else {
            possible.push(vec![vec!["*".to_string()]; states.len()]);
            continue;
        };
        let actions: Vec<String> = serde_json::from_value(player["actions"].clone()).unwrap();
        let observations: Vec<String> = match player.get("observations") {
            Some(o) => serde_json::from_value(o.clone()).unwrap(),
            None => states.clone(),
        };
        let mut enabled = Map::new();
        for o in &observations {
            if actions.len() > 1 && rng.random_bool(0.7) {
                let mut subset: Vec<&String> =
                    actions.iter().filter(|_| rng.random_bool(0.5)).collect();
                if subset.is_empty() {
                    subset.push(actions.choose(&mut rng).unwrap());
                }
                enabled.insert(o.clone(), json!(subset));
            }
        }
        let enables = |o: &str, u: &String| {
            enabled
                .get(o)
                .is_none_or(|list| list.as_array().unwrap().iter().any(|a| a == u))
        };
        let per_state = states
            .iter()
            .map(|s| {
                let seen: Vec<String> = match &player["observe"] {
                    Value::String(_) => vec![s.clone()],
                    observe => observe[s.as_str()]
                        .as_object()
                        .unwrap()
                        .iter()
                        .filter(|(_, p)| p.as_f64().unwrap() > 0.0)
                        .map(|(o, _)| o.clone())
                        .collect(),
                };
                actions
                    .iter()
                    .filter(|u| seen.iter().any(|o| enables(o, u)))
                    .cloned()
                    .collect()
            })
            .collect();
        possible.push(per_state);
        player["enabled"] = Value::Object(enabled);
    }
    let transitions: Vec<Value> = serde_json::from_value(game["transitions"].clone()).unwrap();
    let kept: Vec<Value> = transitions
        .into_iter()
        .filter(|t| {
            let s = states.iter().position(|s| t["state"] == *s).unwrap();
            let v = t["adversary"].as_str().unwrap();
            possible[0][s].iter().any(|u| t["defender"] == *u)
                && (v == "*" || possible[1][s].iter().any(|a| a == v))
        })
        .collect();
    game["transitions"] = json!(kept);
    game.to_string()
}

/// A random complete DRA over (goal, unsafe, a) with 1-4 states and 1-2 pairs.
pub fn dra(seed: u64) -> Dra {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let aps = vec!["goal".to_string(), "unsafe".to_string(), "a".to_string()];
    let states = rng.random_range(1..=4);
    let successors = (0..states * 8)
        .map(|_| rng.random_range(0..states) as u32)
        .collect();
    let pairs = (0..rng.random_range(1..=2))
        .map(|_| RabinPair {
            fin: (0..states).map(|_| rng.random_bool(0.3)).collect(),
            inf: (0..states).map(|_| rng.random_bool(0.5)).collect(),
        })
        .collect();
    Dra::new(aps, states, 0, successors, pairs).unwrap()
}

/// A random controller with 1-2 nodes, random non-empty supports and
/// random probabilities on them.
pub fn controller(seed: u64, game: &Posg, role: Role) -> Fsc {
    let nodes = ChaCha8Rng::seed_from_u64(seed ^ 0x90de5).random_range(1..=2);
    controller_with_nodes(seed, game, role, nodes)
}

/// A random controller with `nodes` nodes, random non-empty supports on
/// the enabled actions and random probabilities on them.
pub fn controller_with_nodes(seed: u64, game: &Posg, role: Role, nodes: usize) -> Fsc {
    let mut rng =
        ChaCha8Rng::seed_from_u64(seed ^ if role == Role::Defender { 0xdef } else { 0xad7 });
    let player = if role == Role::Defender {
        game.defender()
    } else {
        game.adversary()
    };
    let (no, na) = (player.num_observations(), player.num_actions());
    let blocks = (0..nodes * no)
        .map(|b| {
            let enabled: Vec<usize> = player.enabled_actions(b % no).collect();
            let mut pairs: Vec<(usize, usize)> = (0..nodes)
                .flat_map(|g| (0..na).map(move |u| (g, u)))
                .filter(|_| rng.random_bool(0.6))
                .filter(|&(_, u)| player.action_enabled(b % no, u))
                .collect();
            if pairs.is_empty() {
                let g = rng.random_range(0..nodes);
                pairs.push((g, enabled[rng.random_range(0..enabled.len())]));
            }
            let weights: Vec<f64> = pairs.iter().map(|_| rng.random_range(0.05..1.0)).collect();
            let total: f64 = weights.iter().sum();
            pairs
                .into_iter()
                .zip(weights)
                .map(|((next, action), w)| Choice {
                    next,
                    action,
                    probability: w / total,
                    logit: None,
                })
                .collect()
        })
        .collect();
    let mut initial = vec![0.0; nodes];
    initial[0] = 1.0;
    if nodes == 2 && rng.random_bool(0.5) {
        initial = vec![0.4, 0.6];
    }
    Fsc::new(role, nodes, no, na, initial, blocks).unwrap()
}

/// [`game_json`] with one reward model `r`: a random state reward on some
/// states and a random action reward on some transition entries, of either
/// sign (some exact zeros). In half of the games, one state not labelled
/// `goal` is made a trap (every transition stays there), so that the goal
/// is often missed with positive probability.
pub fn game_json_with_rewards(seed: u64) -> String {
    let mut game: Value = serde_json::from_str(&game_json(seed)).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x4e3a4d);
    let labels = game["labels"].clone();
    let no_goal: Vec<String> = game["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .filter(|s| !labels[s].as_array().unwrap().contains(&json!("goal")))
        .collect();
    if rng.random_bool(0.5) {
        if let Some(trap) = no_goal.choose(&mut rng) {
            for entry in game["transitions"].as_array_mut().unwrap() {
                if entry["state"] == json!(trap) {
                    entry["next"] = json!({ trap.as_str(): 1.0 });
                }
            }
        }
    }
    let reward = |rng: &mut ChaCha8Rng| (rng.random_range(-20..=40) as f64) / 8.0;
    let mut states = Map::new();
    for s in game["states"].as_array().unwrap() {
        if rng.random_bool(0.6) {
            states.insert(s.as_str().unwrap().to_string(), json!(reward(&mut rng)));
        }
    }
    let mut actions = Vec::new();
    for entry in game["transitions"].as_array().unwrap() {
        if rng.random_bool(0.5) {
            actions.push(json!({
                "state": entry["state"], "defender": entry["defender"],
                "adversary": entry["adversary"], "reward": reward(&mut rng),
            }));
        }
    }
    game["rewards"] = json!({"r": {"states": states, "actions": actions}});
    game.to_string()
}
