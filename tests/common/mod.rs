//! Test support: hand-built automata and an independent reference
//! computation of the value (dense product over all (s, q, g, h), reachability
//! by transitive closure, BSCCs by mutual reachability, a dense LU solve of
//! [`dense`]). It shares no code with the crate's product, graph or solver.
#![allow(dead_code)]

use dense::{DMatrix, DVector};
use posg_fsc::automaton::{Dra, RabinPair};
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::{AdversaryAction, DefenderAction, Posg};

/// A state-based DRA from a per-state transition function over the letters of `aps`.
pub fn dra(
    aps: &[&str],
    states: usize,
    delta: impl Fn(usize, u32) -> usize,
    pairs: &[(&[usize], &[usize])],
) -> Dra {
    let letters = 1u32 << aps.len();
    let successors = (0..states)
        .flat_map(|q| (0..letters).map(move |a| (q, a)))
        .map(|(q, a)| delta(q, a) as u32)
        .collect();
    let pairs = pairs
        .iter()
        .map(|(fin, inf)| RabinPair {
            fin: (0..states).map(|q| fin.contains(&q)).collect(),
            inf: (0..states).map(|q| inf.contains(&q)).collect(),
        })
        .collect();
    Dra::new(
        aps.iter().map(|s| s.to_string()).collect(),
        states,
        0,
        successors,
        pairs,
    )
    .unwrap()
}

/// The DRAs for `phi` and for `!phi` from the crate's translator.
pub fn automata(formula: &str) -> (Dra, Dra) {
    let phi = posg_fsc::ltl::parse(formula).unwrap();
    (
        posg_fsc::ltl::translate(&phi).unwrap(),
        posg_fsc::ltl::translate(&phi.negate()).unwrap(),
    )
}

/// `F goal`: 0 = not yet, 1 = goal seen (accepting sink).
pub fn eventually_goal() -> Dra {
    dra(
        &["goal"],
        2,
        |q, a| if q == 1 || a & 1 == 1 { 1 } else { 0 },
        &[(&[], &[1])],
    )
}

/// `G !unsafe`: 0 = safe so far (accepting), 1 = rejecting sink.
pub fn always_safe() -> Dra {
    dra(
        &["unsafe"],
        2,
        |q, a| if q == 1 || a & 1 == 1 { 1 } else { 0 },
        &[(&[1], &[0])],
    )
}

/// `!unsafe U goal` over (goal, unsafe): 0 = waiting, 1 = accepted, 2 = rejected.
pub fn safe_until_goal() -> Dra {
    dra(
        &["goal", "unsafe"],
        3,
        |q, a| match (q, a & 1 == 1, a & 2 == 2) {
            (0, true, _) => 1,
            (0, false, true) => 2,
            (0, false, false) => 0,
            (q, _, _) => q,
        },
        &[(&[], &[1])],
    )
}

/// `GF goal & G !unsafe` over (goal, unsafe): 0 = safe, last letter not goal;
/// 1 = safe, last letter goal; 2 = rejecting sink. Pair (L = {2}, K = {1}).
pub fn recurrent_goal_safe() -> Dra {
    dra(
        &["goal", "unsafe"],
        3,
        |q, a| match (q, a & 1 == 1, a & 2 == 2) {
            (2, _, _) | (_, _, true) => 2,
            (_, true, false) => 1,
            _ => 0,
        },
        &[(&[2], &[1])],
    )
}

/// A dense description of the GMC over all (s, q, g, h), built directly from
/// formats.md section 3.
pub struct DenseProduct {
    pub p: DMatrix,
    pub p0: DVector,
    pub q_of: Vec<usize>,
}

fn letter(game: &Posg, dra: &Dra, s: usize) -> u32 {
    dra.letter_of(game.label_names(s))
}

pub fn dense_product(game: &Posg, dra: &Dra, def: &Fsc, adv: &Fsc) -> DenseProduct {
    let (ns, nq, ng, nh) = (
        game.num_states(),
        dra.num_states(),
        def.num_nodes(),
        adv.num_nodes(),
    );
    let n = ns * nq * ng * nh;
    let idx = |s: usize, q: usize, g: usize, h: usize| ((s * nq + q) * ng + g) * nh + h;
    let mut p = DMatrix::zeros(n);
    let mut q_of = vec![0; n];
    for s in 0..ns {
        for q in 0..nq {
            for g in 0..ng {
                for h in 0..nh {
                    let from = idx(s, q, g, h);
                    q_of[from] = q;
                    for &(o, po) in game.defender().observation_distribution(s) {
                        for &(o2, po2) in game.adversary().observation_distribution(s) {
                            for cd in def.choices(g, o) {
                                for ca in adv.choices(h, o2) {
                                    for &(t, pt) in game.transition(
                                        s,
                                        DefenderAction(cd.action),
                                        AdversaryAction(ca.action),
                                    ) {
                                        let qt = dra.successor(q, letter(game, dra, t));
                                        p[(from, idx(t, qt, cd.next, ca.next))] +=
                                            po * po2 * cd.probability * ca.probability * pt;
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    let mut p0 = dense::zeros(n);
    for &(s, ps) in game.initial() {
        let q = dra.successor(dra.initial(), letter(game, dra, s));
        for g in 0..ng {
            for h in 0..nh {
                p0[idx(s, q, g, h)] += ps * def.initial()[g] * adv.initial()[h];
            }
        }
    }
    DenseProduct { p, p0, q_of }
}

/// The probability of phi computed from the dense product: reachability by
/// transitive closure, recurrent states as those that every reachable state
/// can return to, feasible classes by the Rabin pairs, then a dense solve.
// The closure reads reach[a][k] and reach[k][b]: index loops are clearer.
#[allow(clippy::needless_range_loop)]
pub fn reference_value(game: &Posg, dra: &Dra, def: &Fsc, adv: &Fsc) -> f64 {
    let product = dense_product(game, dra, def, adv);
    let n = product.p.nrows();
    let mut reach = vec![vec![false; n]; n];
    for a in 0..n {
        reach[a][a] = true;
        for b in 0..n {
            if product.p[(a, b)] > 0.0 {
                reach[a][b] = true;
            }
        }
    }
    for k in 0..n {
        for a in 0..n {
            if reach[a][k] {
                for b in 0..n {
                    if reach[k][b] {
                        reach[a][b] = true;
                    }
                }
            }
        }
    }
    let recurrent: Vec<bool> = (0..n)
        .map(|a| (0..n).all(|b| !reach[a][b] || reach[b][a]))
        .collect();
    let feasible: Vec<bool> = (0..n)
        .map(|a| {
            recurrent[a]
                && dra.pairs().iter().any(|pair| {
                    let class: Vec<usize> = (0..n).filter(|&b| reach[a][b]).collect();
                    class.iter().any(|&b| pair.inf[product.q_of[b]])
                        && !class.iter().any(|&b| pair.fin[product.q_of[b]])
                })
        })
        .collect();
    let unknown: Vec<usize> = (0..n)
        .filter(|&a| !feasible[a] && (0..n).any(|b| feasible[b] && reach[a][b]))
        .collect();
    let mut x: DVector = feasible.iter().map(|&f| f64::from(f)).collect();
    if !unknown.is_empty() {
        let k = unknown.len();
        let mut a = DMatrix::identity(k);
        let mut rhs = dense::zeros(k);
        for (i, &m) in unknown.iter().enumerate() {
            for (j, &m2) in unknown.iter().enumerate() {
                a[(i, j)] -= product.p[(m, m2)];
            }
            rhs[i] = (0..n)
                .filter(|&b| feasible[b])
                .map(|b| product.p[(m, b)])
                .sum();
        }
        let solution = a.solve(&rhs).expect("transient system is nonsingular");
        for (i, &m) in unknown.iter().enumerate() {
            x[m] = solution[i];
        }
    }
    dense::dot(&product.p0, &x)
}

pub mod dense;
pub mod random;

/// The library's pipeline ([`posg_fsc::pipeline::solve`]) with one node
/// per player and no observers: phi, and !phi for the certified bracket.
pub fn solve_one_node(
    game: &Posg,
    phi: &Dra,
    not_phi: Option<&Dra>,
    settings: &posg_fsc::optimise::Settings,
) -> Result<posg_fsc::pipeline::Outcome, posg_fsc::pipeline::PipelineError> {
    let automata = posg_fsc::pipeline::Automata {
        phi: phi.clone(),
        not_phi: not_phi.cloned(),
        description: "phi".into(),
    };
    let sizes = posg_fsc::pipeline::Sizes {
        defender: 1,
        adversary: 1,
    };
    posg_fsc::pipeline::solve(
        game,
        &automata,
        sizes,
        settings,
        posg_fsc::pipeline::Unwatched,
    )
}

/// The expected total reward of `rewards` until the first state labelled
/// `target` (method.md section 9), computed from the dense chain over
/// `(s, g, h)` of formats.md section 3 with the target states made
/// absorbing: infinite when a state that misses the target with positive
/// probability (one that can reach a state from which no target state is
/// reachable) has positive initial probability or is reachable from one;
/// otherwise a dense solve of `(I - Q) x = r` on the non-target states.
/// No automaton, no analysis of the crate.
#[allow(clippy::needless_range_loop)]
pub fn reference_expected_reward(
    game: &Posg,
    rewards: &posg_fsc::game::RewardModel,
    target: &str,
    def: &Fsc,
    adv: &Fsc,
) -> f64 {
    let (ns, ng, nh) = (game.num_states(), def.num_nodes(), adv.num_nodes());
    let n = ns * ng * nh;
    let idx = |s: usize, g: usize, h: usize| (s * ng + g) * nh + h;
    let is_target = |s: usize| game.label_names(s).any(|l| l == target);
    let mut p = DMatrix::zeros(n);
    let mut r = dense::zeros(n);
    for s in (0..ns).filter(|&s| !is_target(s)) {
        for g in 0..ng {
            for h in 0..nh {
                let from = idx(s, g, h);
                r[from] = rewards.state_reward(s);
                for &(o, po) in game.defender().observation_distribution(s) {
                    for &(o2, po2) in game.adversary().observation_distribution(s) {
                        for cd in def.choices(g, o) {
                            for ca in adv.choices(h, o2) {
                                let (u, v) =
                                    (DefenderAction(cd.action), AdversaryAction(ca.action));
                                let weight = po * po2 * cd.probability * ca.probability;
                                r[from] += weight * rewards.action_reward(s, u, v).unwrap();
                                for &(t, pt) in game.transition(s, u, v) {
                                    p[(from, idx(t, cd.next, ca.next))] += weight * pt;
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    let mut reach = vec![vec![false; n]; n];
    for a in 0..n {
        reach[a][a] = true;
        for b in 0..n {
            reach[a][b] |= p[(a, b)] > 0.0;
        }
    }
    for k in 0..n {
        for a in 0..n {
            if reach[a][k] {
                for b in 0..n {
                    reach[a][b] |= reach[k][b];
                }
            }
        }
    }
    let target_state = |m: usize| is_target(m / (ng * nh));
    let hits_target: Vec<bool> = (0..n)
        .map(|a| (0..n).any(|b| reach[a][b] && target_state(b)))
        .collect();
    let infinite: Vec<bool> = (0..n)
        .map(|a| (0..n).any(|b| reach[a][b] && !hits_target[b]))
        .collect();
    let mut p0 = dense::zeros(n);
    for &(s, ps) in game.initial() {
        for g in 0..ng {
            for h in 0..nh {
                p0[idx(s, g, h)] += ps * def.initial()[g] * adv.initial()[h];
            }
        }
    }
    if (0..n).any(|m| p0[m] > 0.0 && infinite[m]) {
        return f64::INFINITY;
    }
    let unknown: Vec<usize> = (0..n)
        .filter(|&m| !target_state(m) && !infinite[m])
        .collect();
    let k = unknown.len();
    let mut a = DMatrix::identity(k);
    let mut rhs = dense::zeros(k);
    for (i, &m) in unknown.iter().enumerate() {
        for (j, &m2) in unknown.iter().enumerate() {
            a[(i, j)] -= p[(m, m2)];
        }
        rhs[i] = r[m];
    }
    let solution = a
        .solve(&rhs)
        .expect("the finite states' system is nonsingular");
    unknown.iter().zip(&solution).map(|(&m, x)| p0[m] * x).sum()
}

/// The directions `e_k - e_first` inside each block of `support`, along
/// which a controller's probabilities stay a distribution: those a finite
/// difference of the value may move in.
pub fn block_directions(support: &posg_fsc::controller::Support) -> Vec<(usize, usize)> {
    (0..support.num_blocks())
        .flat_map(|b| {
            let block = support.block_by_index(b);
            let first = block.start;
            block.skip(1).map(move |k| (first, k))
        })
        .collect()
}

/// The one-node controller of `role` playing, after observation `o`, the
/// `(action, probability)` pairs of `rows[o]` (deterministic or mixed).
pub fn memoryless(game: &Posg, role: Role, rows: &[&[(usize, f64)]]) -> Fsc {
    let player = match role {
        Role::Defender => game.defender(),
        Role::Adversary => game.adversary(),
    };
    let blocks = rows
        .iter()
        .map(|row| {
            row.iter()
                .map(|&(action, probability)| Choice {
                    next: 0,
                    action,
                    probability,
                    logit: None,
                })
                .collect()
        })
        .collect();
    Fsc::new(
        role,
        1,
        player.num_observations(),
        player.num_actions(),
        vec![1.0],
        blocks,
    )
    .unwrap()
}
