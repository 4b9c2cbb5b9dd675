//! Certified bounds (method.md section 6) against independent computations:
//! exhaustive enumeration of deterministic memoryless strategies on a dense
//! product built here from formats.md section 3, the exact value of
//! controller pairs (`common::reference_value`), and a hand-made game whose
//! bounds are derived on paper.

mod common;

use common::automata;

use common::dense::{self, DMatrix, DVector};
use posg_fsc::automaton::Dra;
use posg_fsc::certify::belief::{BeliefBudget, belief_upper_bound};
use posg_fsc::certify::{Bound, CertifyError, lower_bound, upper_bound};
use posg_fsc::controller::{Fsc, Role};
use posg_fsc::game::file::from_json_str;
use posg_fsc::game::{AdversaryAction, DefenderAction, Posg};
use posg_fsc::value::SolverSettings;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Map, Value, json};

const FORMULAS: [&str; 4] = [
    "F goal",
    "G !unsafe",
    "GF goal & G !unsafe",
    "!unsafe U goal",
];

fn random_distribution(rng: &mut ChaCha8Rng, outcomes: &[String], most: usize) -> Value {
    let mut chosen: Vec<&String> = Vec::new();
    for _ in 0..rng.random_range(1..=most) {
        let name = &outcomes[rng.random_range(0..outcomes.len())];
        if !chosen.contains(&name) {
            chosen.push(name);
        }
    }
    let weights: Vec<f64> = chosen.iter().map(|_| rng.random_range(0.1..1.0)).collect();
    let total: f64 = weights.iter().sum();
    let map: Map<String, Value> = chosen
        .into_iter()
        .zip(weights)
        .map(|(name, w)| (name.clone(), json!(w / total)))
        .collect();
    Value::Object(map)
}

fn random_player(rng: &mut ChaCha8Rng, states: &[String], prefix: &str, full: bool) -> Value {
    let actions = vec![format!("{prefix}0"), format!("{prefix}1")];
    if full {
        return json!({"actions": actions, "observe": "full"});
    }
    let observations = vec![format!("{prefix}o0"), format!("{prefix}o1")];
    let observe: Map<String, Value> = states
        .iter()
        .map(|s| (s.clone(), random_distribution(rng, &observations, 2)))
        .collect();
    json!({"actions": actions, "observations": observations, "observe": observe})
}

/// A small random game: 3-4 states labelled from {goal, unsafe}, two
/// actions per player, transitions with 1-2 successors.
fn small_game(seed: u64, full: bool) -> Posg {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let states: Vec<String> = (0..rng.random_range(3..=4))
        .map(|i| format!("s{i}"))
        .collect();
    let defender = random_player(&mut rng, &states, "u", full);
    let adversary = random_player(&mut rng, &states, "v", full);
    let labels: Map<String, Value> = states
        .iter()
        .map(|s| {
            let props: Vec<&str> = ["goal", "unsafe"]
                .into_iter()
                .filter(|_| rng.random_bool(0.3))
                .collect();
            (s.clone(), json!(props))
        })
        .collect();
    let mut transitions = Vec::new();
    for s in &states {
        for u in ["u0", "u1"] {
            for v in ["v0", "v1"] {
                let next = random_distribution(&mut rng, &states, 2);
                transitions.push(json!({"state": s, "defender": u, "adversary": v, "next": next}));
            }
        }
    }
    let game = json!({
        "posg": 1, "states": states, "initial": random_distribution(&mut rng, &states[..2], 2),
        "labels": labels, "defender": defender, "adversary": adversary, "transitions": transitions,
    });
    from_json_str(&game.to_string(), "small.posg.json").unwrap()
}

/// The MDP of the free player against `fixed`, dense over all `(s, q, node)`
/// (index `(s * |Q| + q) * |G| + node`), straight from formats.md section 3:
/// `p[w][(m, m')]` for the free player's action `w`.
struct DenseMdp {
    p: Vec<DMatrix>,
    p0: DVector,
    key: Vec<(usize, usize, usize)>,
}

fn dense_mdp(game: &Posg, dra: &Dra, fixed: &Fsc) -> DenseMdp {
    let (ns, nq, ng) = (game.num_states(), dra.num_states(), fixed.num_nodes());
    let n = ns * nq * ng;
    let index = |s: usize, q: usize, g: usize| (s * nq + q) * ng + g;
    let letter = |s: usize| dra.letter_of(game.label_names(s));
    let (fixed_player, free_actions) = match fixed.role() {
        Role::Defender => (game.defender(), game.adversary().num_actions()),
        Role::Adversary => (game.adversary(), game.defender().num_actions()),
    };
    let mut p = vec![DMatrix::zeros(n); free_actions];
    let mut key = vec![(0, 0, 0); n];
    for s in 0..ns {
        for q in 0..nq {
            for g in 0..ng {
                let from = index(s, q, g);
                key[from] = (s, q, g);
                for (w, pw) in p.iter_mut().enumerate() {
                    for &(o, po) in fixed_player.observation_distribution(s) {
                        for c in fixed.choices(g, o) {
                            let (u, v) = match fixed.role() {
                                Role::Defender => (c.action, w),
                                Role::Adversary => (w, c.action),
                            };
                            for &(t, pt) in
                                game.transition(s, DefenderAction(u), AdversaryAction(v))
                            {
                                let to = index(t, dra.successor(q, letter(t)), c.next);
                                pw[(from, to)] += po * c.probability * pt;
                            }
                        }
                    }
                }
            }
        }
    }
    let mut p0 = dense::zeros(n);
    for &(s, ps) in game.initial() {
        for g in 0..ng {
            p0[index(s, dra.successor(dra.initial(), letter(s)), g)] += ps * fixed.initial()[g];
        }
    }
    DenseMdp { p, p0, key }
}

/// Reflexive-transitive closure of the graph of `p` (entries > 0).
fn closure(p: &DMatrix) -> Vec<Vec<bool>> {
    let n = p.nrows();
    let mut reach: Vec<Vec<bool>> = (0..n)
        .map(|a| (0..n).map(|b| a == b || p[(a, b)] > 0.0).collect())
        .collect();
    for k in 0..n {
        let through = reach[k].clone();
        for row in reach.iter_mut().filter(|row| row[k]) {
            for (to, &via) in row.iter_mut().zip(&through) {
                *to |= via;
            }
        }
    }
    reach
}

/// The probability that the Markov chain `p` from `p0` satisfies the DRA's
/// Rabin condition read on `q_of`: BSCCs by mutual reachability, accepting
/// BSCCs by the pairs, then a dense solve for reaching them.
fn chain_value(p: &DMatrix, p0: &[f64], q_of: &[usize], dra: &Dra) -> f64 {
    let n = p.nrows();
    let reach = closure(p);
    let accepting: Vec<bool> = (0..n)
        .map(|a| {
            let class: Vec<usize> = (0..n).filter(|&b| reach[a][b]).collect();
            class.iter().all(|&b| reach[b][a])
                && dra.pairs().iter().any(|pair| {
                    class.iter().any(|&b| pair.inf[q_of[b]])
                        && !class.iter().any(|&b| pair.fin[q_of[b]])
                })
        })
        .collect();
    let unknown: Vec<usize> = (0..n)
        .filter(|&a| !accepting[a] && (0..n).any(|b| accepting[b] && reach[a][b]))
        .collect();
    let mut x: DVector = accepting.iter().map(|&f| f64::from(f)).collect();
    let k = unknown.len();
    if k > 0 {
        let mut a = DMatrix::identity(k);
        let mut rhs = dense::zeros(k);
        for (i, &m) in unknown.iter().enumerate() {
            for (j, &m2) in unknown.iter().enumerate() {
                a[(i, j)] -= p[(m, m2)];
            }
            rhs[i] = (0..n).filter(|&b| accepting[b]).map(|b| p[(m, b)]).sum();
        }
        let solution = a.solve(&rhs).expect("transient system is nonsingular");
        for (i, &m) in unknown.iter().enumerate() {
            x[m] = solution[i];
        }
    }
    dense::dot(p0, &x)
}

impl DenseMdp {
    /// The states reachable from `p0` under some choice of actions.
    fn reachable(&self) -> Vec<usize> {
        let union = self
            .p
            .iter()
            .fold(DMatrix::zeros(self.p0.len()), |acc, p| acc + p);
        let reach = closure(&union);
        (0..self.p0.len())
            .filter(|&b| (0..self.p0.len()).any(|a| self.p0[a] > 0.0 && reach[a][b]))
            .collect()
    }

    /// `P^sigma(Rabin)` for the memoryless strategy `choice` on `states`.
    fn value(&self, states: &[usize], choice: &[usize], dra: &Dra) -> f64 {
        let k = states.len();
        let p = DMatrix::from_fn(k, |i, j| self.p[choice[i]][(states[i], states[j])]);
        let p0: DVector = states.iter().map(|&m| self.p0[m]).collect();
        let q_of: Vec<usize> = states.iter().map(|&m| self.key[m].1).collect();
        chain_value(&p, &p0, &q_of, dra)
    }

    /// `max` over all deterministic memoryless strategies of `P(Rabin)`, or
    /// `None` when there are more than `limit` strategies.
    fn best_by_enumeration(&self, dra: &Dra, limit: usize) -> Option<f64> {
        let states = self.reachable();
        let actions = self.p.len();
        let count = actions.checked_pow(states.len() as u32)?;
        if count > limit {
            return None;
        }
        let mut best = f64::NEG_INFINITY;
        for code in 0..count {
            let choice: Vec<usize> = (0..states.len())
                .map(|i| code / actions.pow(i as u32) % actions)
                .collect();
            best = best.max(self.value(&states, &choice, dra));
        }
        Some(best)
    }

    /// `P(Rabin)` of the strategy a bound exported, read by names.
    fn value_of_exported(&self, game: &Posg, bound: &Bound, dra: &Dra, actions: &[String]) -> f64 {
        let states = self.reachable();
        let choice: Vec<usize> = states
            .iter()
            .map(|&m| {
                let (s, q, g) = self.key[m];
                let rule = bound
                    .strategy
                    .rules
                    .iter()
                    .find(|r| r.state == game.states()[s] && r.automaton_state == q && r.node == g)
                    .expect("every reachable product state has a rule");
                actions.iter().position(|a| *a == rule.action).unwrap()
            })
            .collect();
        self.value(&states, &choice, dra)
    }
}

const LIMIT: usize = 1 << 12;

#[test]
fn lower_bound_is_the_minimum_over_enumerated_adversary_strategies() {
    let mut checked = 0;
    for seed in 0..30 {
        let game = small_game(seed, seed % 3 == 0);
        let defender = common::random::controller_with_nodes(
            seed + 100,
            &game,
            Role::Defender,
            1 + seed as usize % 2,
        );
        for formula in FORMULAS {
            let (_, not_phi) = automata(formula);
            let bound = lower_bound(&game, &not_phi, &defender).unwrap();
            let dense = dense_mdp(&game, &not_phi, &defender);
            let Some(best) = dense.best_by_enumeration(&not_phi, LIMIT) else {
                continue;
            };
            checked += 1;
            assert!(
                (bound.value - (1.0 - best)).abs() < 1e-9,
                "seed {seed}, {formula}: bound {} vs enumeration {}",
                bound.value,
                1.0 - best
            );
            let attack =
                dense.value_of_exported(&game, &bound, &not_phi, game.adversary().actions());
            assert!(
                (attack - best).abs() < 1e-9,
                "seed {seed}, {formula}: exported {attack} vs {best}"
            );
        }
    }
    assert!(checked >= 40, "only {checked} cases were small enough");
}

#[test]
fn upper_bound_is_the_maximum_over_enumerated_defender_strategies() {
    let mut checked = 0;
    for seed in 0..30 {
        let game = small_game(seed + 1000, seed % 3 == 1);
        let adversary = common::random::controller_with_nodes(
            seed + 200,
            &game,
            Role::Adversary,
            1 + seed as usize % 2,
        );
        for formula in FORMULAS {
            let (phi, _) = automata(formula);
            let bound = upper_bound(&game, &phi, &adversary).unwrap();
            let dense = dense_mdp(&game, &phi, &adversary);
            let Some(best) = dense.best_by_enumeration(&phi, LIMIT) else {
                continue;
            };
            checked += 1;
            assert!(
                (bound.value - best).abs() < 1e-9,
                "seed {seed}, {formula}: bound {} vs enumeration {best}",
                bound.value
            );
            let play = dense.value_of_exported(&game, &bound, &phi, game.defender().actions());
            assert!(
                (play - best).abs() < 1e-9,
                "seed {seed}, {formula}: exported {play} vs {best}"
            );
        }
    }
    assert!(checked >= 40, "only {checked} cases were small enough");
}

#[test]
fn bounds_hold_against_every_controller_tried_on_random_games() {
    for seed in 0..24 {
        let game = from_json_str(&common::random::game_json(seed), "random.posg.json").unwrap();
        let formula = FORMULAS[seed as usize % FORMULAS.len()];
        let (phi, not_phi) = automata(formula);
        let defender = common::random::controller(seed, &game, Role::Defender);
        let lower = lower_bound(&game, &not_phi, &defender).unwrap().value;
        for trial in 0..4 {
            let adversary = common::random::controller(seed * 10 + trial, &game, Role::Adversary);
            let value = common::reference_value(&game, &phi, &defender, &adversary);
            assert!(
                lower <= value + 1e-9,
                "seed {seed}, {formula}: lower {lower} > {value}"
            );
            let upper = upper_bound(&game, &phi, &adversary).unwrap().value;
            let other = common::random::controller(seed * 10 + trial + 5, &game, Role::Defender);
            let value = common::reference_value(&game, &phi, &other, &adversary);
            assert!(
                value <= upper + 1e-9,
                "seed {seed}, {formula}: {value} > upper {upper}"
            );
        }
    }
}

/// The belief bound of a one-player game (method.md section 6) holds
/// against every defender tried, of 1-3 nodes, valued on the dense product
/// (`common::reference_value`), and is at most the fully informed bound.
#[test]
fn the_belief_bound_holds_against_every_defender_tried_on_random_pomdps() {
    let mut checked = 0;
    for seed in 0..200 {
        let game = from_json_str(&common::random::game_json(seed), "random.posg.json").unwrap();
        let formula = FORMULAS[seed as usize % FORMULAS.len()];
        let (phi, _) = automata(formula);
        let budget = BeliefBudget::default();
        let settings = SolverSettings::default();
        let Some(belief) = belief_upper_bound(&game, &phi, &budget, &settings).unwrap() else {
            continue;
        };
        checked += 1;
        let adversary = Fsc::uniform_enabled(Role::Adversary, 1, game.adversary());
        let informed = upper_bound(&game, &phi, &adversary).unwrap().value;
        assert!(
            belief.value <= informed + 1e-9,
            "seed {seed}, {formula}: belief {} > informed {informed}",
            belief.value
        );
        for trial in 0..6 {
            let nodes = 1 + trial as usize % 3;
            let defender = common::random::controller_with_nodes(
                seed * 10 + trial,
                &game,
                Role::Defender,
                nodes,
            );
            let value = common::reference_value(&game, &phi, &defender, &adversary);
            assert!(
                value <= belief.value + 1e-9,
                "seed {seed}, {formula}, {nodes} nodes: {value} > belief {}",
                belief.value
            );
        }
    }
    assert!(checked >= 20, "only {checked} one-player games");
}

#[test]
fn with_full_observation_and_one_node_the_bounds_bracket_the_value() {
    for seed in 0..20 {
        let game = small_game(seed + 500, true);
        for formula in FORMULAS {
            let (phi, not_phi) = automata(formula);
            let defender =
                common::random::controller_with_nodes(seed + 300, &game, Role::Defender, 1);
            let adversary =
                common::random::controller_with_nodes(seed + 400, &game, Role::Adversary, 1);
            let value = common::reference_value(&game, &phi, &defender, &adversary);
            let lower = lower_bound(&game, &not_phi, &defender).unwrap();
            let upper = upper_bound(&game, &phi, &adversary).unwrap();
            assert!(
                lower.value <= value + 1e-9 && value <= upper.value + 1e-9,
                "seed {seed}, {formula}: {} <= {value} <= {}",
                lower.value,
                upper.value
            );
            assert!(lower.residual < 1e-9 && upper.residual < 1e-9);
        }
    }
}

#[test]
fn with_full_observation_and_one_node_the_bounds_bracket_the_optimised_value() {
    let settings = posg_fsc::optimise::Settings {
        max_iterations: 40,
        ..posg_fsc::optimise::Settings::default()
    };
    for seed in 0..6 {
        let game = small_game(seed + 700, true);
        for formula in FORMULAS {
            let (phi, not_phi) = automata(formula);
            let solution = common::solve_one_node(&game, &phi, Some(&not_phi), &settings).unwrap();
            let best = solution.best();
            let value = common::reference_value(&game, &phi, &best.defender, &best.adversary);
            let lower = lower_bound(&game, &not_phi, &best.defender).unwrap().value;
            let upper = upper_bound(&game, &phi, &best.adversary).unwrap().value;
            let bracket = solution.certified.expect("a formula's bracket");
            assert!(
                (bracket.certified_lower - lower).abs() < 1e-12 && bracket.upper_bound <= upper,
                "seed {seed}, {formula}: the pipeline's bracket {bracket:?} against {lower}, {upper}"
            );
            assert!(
                lower <= value + 1e-9 && value <= upper + 1e-9,
                "seed {seed}, {formula}: {lower} <= {value} <= {upper}"
            );
            assert!(
                lower <= best.report.worst_case + 1e-9,
                "seed {seed}, {formula}: the certified lower bound {lower} exceeds the estimate {}",
                best.report.worst_case
            );
        }
    }
}

/// s0 is left for the goal s1 only if the adversary plays `block` with
/// probability below 1. Any adversary FSC with full support on {pass, block}
/// gives `P(F goal) = 1`; the adversary that never plays `pass` gives 0.
fn blockable_goal() -> Posg {
    let game = json!({
        "posg": 1, "states": ["s0", "s1"], "initial": {"s0": 1.0},
        "labels": {"s1": ["goal"]},
        "defender": {"actions": ["go"], "observe": "full"},
        "adversary": {"actions": ["pass", "block"], "observe": "full"},
        "transitions": [
            {"state": "s0", "defender": "go", "adversary": "pass", "next": {"s1": 0.5, "s0": 0.5}},
            {"state": "s0", "defender": "go", "adversary": "block", "next": {"s0": 1.0}},
            {"state": "s1", "defender": "*", "adversary": "*", "next": {"s1": 1.0}}
        ]
    });
    from_json_str(&game.to_string(), "blockable.posg.json").unwrap()
}

#[test]
fn an_adversary_that_never_passes_is_seen_by_the_lower_bound() {
    let game = blockable_goal();
    let (phi, not_phi) = automata("F goal");
    let defender = Fsc::uniform(Role::Defender, 1, 2, 1);
    let adversary = Fsc::uniform(Role::Adversary, 1, 2, 2);
    assert!((common::reference_value(&game, &phi, &defender, &adversary) - 1.0).abs() < 1e-12);
    let lower = lower_bound(&game, &not_phi, &defender).unwrap();
    assert_eq!(lower.value, 0.0);
    let s0 = lower
        .strategy
        .rules
        .iter()
        .find(|r| r.state == "s0")
        .unwrap();
    assert_eq!(s0.action, "block");
    assert_eq!(s0.free_player_value, 1.0);
    let upper = upper_bound(&game, &phi, &adversary).unwrap();
    assert!((upper.value - 1.0).abs() < 1e-12);
    let json = serde_json::to_value(&lower).unwrap();
    assert_eq!(json["strategy"]["player"], "adversary");
    assert_eq!(json["mdp_states"], lower.mdp_states);
}

#[test]
fn a_controller_for_the_wrong_player_is_an_error() {
    let game = blockable_goal();
    let (phi, not_phi) = automata("F goal");
    let adversary = Fsc::uniform(Role::Adversary, 1, 2, 2);
    let defender = Fsc::uniform(Role::Defender, 1, 2, 1);
    assert!(matches!(
        lower_bound(&game, &not_phi, &adversary),
        Err(CertifyError::Mismatch { .. })
    ));
    assert!(matches!(
        upper_bound(&game, &phi, &defender),
        Err(CertifyError::Mismatch { .. })
    ));
}

#[test]
fn the_reference_dense_solver_pivots_and_refuses_singular_systems() {
    // [[0, 1], [2, 1]] x = [1, 4]  =>  x = [1.5, 1].
    let mut a = DMatrix::zeros(2);
    a[(0, 1)] = 1.0;
    a[(1, 0)] = 2.0;
    a[(1, 1)] = 1.0;
    let x = a.solve(&[1.0, 4.0]).unwrap();
    assert_eq!(x, vec![1.5, 1.0]);
    assert_eq!(DMatrix::zeros(2).solve(&[1.0, 1.0]), None);
}

/// The lower bound's gradient (Danskin, method.md section 6) against
/// central finite differences of the bound itself along a random direction
/// in the defender's logits, at a random point. Returns whether the point
/// was smooth with a nonzero slope; a point where the two one-sided
/// differences disagree (the optimal adversary switches there) is skipped.
fn lower_bound_gradient_matches_finite_differences(
    game: &Posg,
    not_phi: &Dra,
    template: &Fsc,
    seed: u64,
) -> bool {
    use posg_fsc::certify::gradient::lower_bound_gradient;
    use posg_fsc::optimise::Softmax;
    use posg_fsc::value::SolverSettings;
    let softmax = Softmax::new(template, true);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let logits: Vec<f64> = (0..softmax.num_parameters())
        .map(|_| rng.random_range(-1.0..1.0))
        .collect();
    let direction: Vec<f64> = (0..logits.len())
        .map(|_| rng.random_range(-1.0..1.0))
        .collect();
    let bound_at = |t: f64| {
        let moved: Vec<f64> = logits
            .iter()
            .zip(&direction)
            .map(|(l, d)| l + t * d)
            .collect();
        lower_bound(game, not_phi, &softmax.controller(&moved).unwrap())
            .unwrap()
            .value
    };
    let defender = softmax.controller(&logits).unwrap();
    let found = lower_bound_gradient(game, not_phi, &defender, &SolverSettings::default()).unwrap();
    let (ahead, here, behind) = (bound_at(1e-5), bound_at(0.0), bound_at(-1e-5));
    assert!((found.value - here).abs() < 1e-12, "seed {seed}");
    let mu = softmax.probabilities(&logits);
    let gradient = softmax.chain_rule(&mu, &found.entries, &found.initial);
    let analytic: f64 = gradient.iter().zip(&direction).map(|(g, d)| g * d).sum();
    let (forward, backward) = ((ahead - here) / 1e-5, (here - behind) / 1e-5);
    if (forward - backward).abs() > 1e-3 * (1.0 + forward.abs()) {
        return false;
    }
    let central = (ahead - behind) / 2e-5;
    assert!(
        (analytic - central).abs() < 1e-6 * (1.0 + central.abs()),
        "seed {seed}: analytic {analytic} vs finite differences {central}"
    );
    central.abs() > 1e-6
}

#[test]
fn the_lower_bounds_gradient_matches_finite_differences_of_the_bound() {
    use posg_fsc::game::grid::GridSpec;
    let mut checked = 0;
    for seed in 0..40u64 {
        let game = from_json_str(&common::random::game_json(seed), "random.posg.json").unwrap();
        let (_, not_phi) = automata(FORMULAS[seed as usize % FORMULAS.len()]);
        let template = common::random::controller(seed, &game, Role::Defender);
        checked += usize::from(lower_bound_gradient_matches_finite_differences(
            &game, &not_phi, &template, seed,
        ));
    }
    let grids = [GridSpec::default(), GridSpec::square(4)];
    for (i, grid) in grids.iter().enumerate() {
        let game = grid.build().unwrap();
        for seed in 0..24u64 {
            let (_, not_phi) = automata(FORMULAS[seed as usize % FORMULAS.len()]);
            let nodes = 1 + seed as usize % 2;
            let template = common::random::controller_with_nodes(
                seed + 100 * i as u64,
                &game,
                Role::Defender,
                nodes,
            );
            checked += usize::from(lower_bound_gradient_matches_finite_differences(
                &game, &not_phi, &template, seed,
            ));
        }
    }
    assert!(
        checked >= 10,
        "only {checked} smooth points with a nonzero slope"
    );
}

/// One `LowerBoundGradients` evaluating many controllers of one support
/// (reusing its graph analysis and warm-starting policy iteration from the
/// last strategy) certifies what a fresh `lower_bound` certifies for each.
#[test]
fn lower_bounds_of_one_support_reuse_the_analysis_and_agree_with_fresh_ones() {
    use posg_fsc::certify::gradient::LowerBoundGradients;
    use posg_fsc::game::grid::GridSpec;
    use posg_fsc::optimise::Softmax;
    use posg_fsc::value::SolverSettings;
    let game = GridSpec::square(4).build().unwrap();
    let mut between = 0;
    for (i, formula) in FORMULAS.iter().enumerate() {
        let (_, not_phi) = automata(formula);
        let template = common::random::controller_with_nodes(i as u64, &game, Role::Defender, 2);
        let softmax = Softmax::new(&template, false);
        let mut bounds = LowerBoundGradients::new(&game, &not_phi, SolverSettings::default());
        let mut rng = ChaCha8Rng::seed_from_u64(i as u64);
        for _ in 0..6 {
            let logits: Vec<f64> = (0..softmax.num_parameters())
                .map(|_| rng.random_range(-3.0..3.0))
                .collect();
            let defender = softmax.controller(&logits).unwrap();
            let fresh = lower_bound(&game, &not_phi, &defender).unwrap();
            let reused = bounds.at(&defender).unwrap();
            let slack = fresh.error_bound + reused.error_bound + 1e-15;
            assert!(
                (fresh.value - reused.value).abs() <= slack,
                "{formula}: fresh {} reused {}",
                fresh.value,
                reused.value
            );
            let value = bounds.value_or_trivial(&defender).unwrap();
            assert!((fresh.value - value).abs() <= slack, "{formula}");
            between += usize::from(fresh.value > 1e-9 && fresh.value < 1.0 - 1e-9);
        }
    }
    assert!(
        between >= 6,
        "only {between} bounds strictly between 0 and 1"
    );
}

/// The gradient over every enabled pair (`LowerBoundGradients::at_over`,
/// which ranks the local search's moves) gives the one-sided derivative of
/// the bound when a defender starts playing a pair it never played, a move
/// to its unused second node included: on random games and grids, with node 0 a
/// random one-node controller and node 1 never entered,
/// `d/de L((1 - e) mu_b + e pair)` at `e = 0+` against a Richardson
/// difference of the bound. Points where the bound jumps or bends (the
/// pair opens an end component, or the adversary's optimum switches) are
/// skipped, and so are blocks played in decided states only, which the
/// gradient leaves out.
#[test]
fn the_gradient_over_every_pair_gives_the_gain_of_a_pair_not_played() {
    use posg_fsc::certify::gradient::LowerBoundGradients;
    use posg_fsc::controller::{Choice, Support};
    use posg_fsc::game::grid::GridSpec;
    use posg_fsc::value::SolverSettings;
    let (mut checked, mut to_unused_node) = (0, 0);
    for seed in 0..120u64 {
        let game = match seed % 3 {
            0 => from_json_str(&common::random::game_json(seed), "random.posg.json").unwrap(),
            1 => GridSpec::default().build().unwrap(),
            _ => GridSpec::square(4).build().unwrap(),
        };
        let (_, not_phi) = automata(FORMULAS[seed as usize / 3 % FORMULAS.len()]);
        let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let support = Support::of(&universe);
        let observations = universe.num_observations();
        // Node 0 a random controller of its own, node 1 a copy never entered.
        let node = common::random::controller_with_nodes(seed, &game, Role::Defender, 1);
        let blocks: Vec<Vec<Choice>> = (0..2 * observations)
            .map(|b| {
                let next = b / observations;
                let own = node.choices(0, b % observations).iter();
                own.map(|&c| Choice { next, ..c }).collect()
            })
            .collect();
        let defender = with_blocks(&universe, blocks.clone());
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let b = rng.random_range(0..observations);
        let pairs = universe.choices(0, b);
        let pair = pairs[rng.random_range(0..pairs.len())];
        if blocks[b]
            .iter()
            .any(|c| (c.next, c.action) == (pair.next, pair.action))
        {
            continue;
        }
        let mut gradients = LowerBoundGradients::new(&game, &not_phi, SolverSettings::default());
        let found = gradients.at_over(&defender, &support).unwrap();
        let entry = |c: &Choice| {
            let k = support
                .block(0, b)
                .find(|&k| support.entry(k) == (c.next, c.action));
            found.entries[k.unwrap()]
        };
        let played: f64 = blocks[b].iter().map(|c| c.probability * entry(c)).sum();
        let analytic = entry(&pair) - played;
        let bound_at = |e: f64| {
            let mut mixed = blocks.clone();
            for c in &mut mixed[b] {
                c.probability *= 1.0 - e;
            }
            mixed[b].push(Choice {
                probability: e,
                ..pair
            });
            lower_bound(&game, &not_phi, &with_blocks(&universe, mixed))
                .unwrap()
                .value
        };
        let here = lower_bound(&game, &not_phi, &defender).unwrap().value;
        let e = 1e-4;
        let (one, two) = (bound_at(e) - here, bound_at(2.0 * e) - here);
        let richardson = (4.0 * one - two) / (2.0 * e);
        // Exactly 0: the block is played in decided states only.
        let bends = (one / e - richardson).abs() > 1e-2 * (1.0 + richardson.abs());
        if !analytic.is_finite() || analytic == 0.0 || bends {
            continue;
        }
        assert!(
            (analytic - richardson).abs() < 1e-4 * (1.0 + richardson.abs()),
            "seed {seed}: analytic {analytic} vs finite differences {richardson}"
        );
        checked += 1;
        to_unused_node += usize::from(pair.next == 1);
    }
    assert!(
        checked >= 15 && to_unused_node >= 8,
        "only {checked} smooth moves, {to_unused_node} to node 1"
    );
}

/// A two-node defender of `universe`'s shape starting in node 0, with
/// `blocks`.
fn with_blocks(universe: &Fsc, blocks: Vec<Vec<posg_fsc::controller::Choice>>) -> Fsc {
    Fsc::new(
        Role::Defender,
        universe.num_nodes(),
        universe.num_observations(),
        universe.num_actions(),
        vec![1.0, 0.0],
        blocks,
    )
    .unwrap()
}
