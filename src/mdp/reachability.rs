//! Maximum reachability probabilities, exactly, by policy iteration.
//!
//! For a target set `B`, `x*(s) = sup_sigma P^sigma_s(reach B)`. It is the
//! *least* fixed point in `[0, 1]^S` of the Bellman operator
//! `(F x)(s) = 1` on `B`, `max_a sum_t P(t | s, a) x(t)` elsewhere (Baier and
//! Katoen, Section 10.6), and memoryless deterministic strategies attain it.
//!
//! The algorithm:
//!
//! 1. **Qualitative step.** `S_0`, the states that cannot reach `B` in the
//!    graph of all actions, have `x* = 0` under every strategy; `S_1`, the
//!    states from which some strategy reaches `B` almost surely (Baier and
//!    Katoen, Section 10.6), have `x* = 1` exactly. The rest,
//!    `M = S \ (S_1 u S_0)`, are the "maybe" states; below, `B` stands for
//!    `S_1` (which contains it).
//! 2. **Proper start.** A backward search from `B` gives every state of `M`
//!    an action with an edge to a state found earlier, so under this policy
//!    every state of `M` reaches `B` with positive probability: the chain
//!    restricted to `M` is transient and `I - Q` is nonsingular, even when
//!    `M` contains end components (where an arbitrary policy could stay
//!    forever and make the system singular).
//! 3. **Evaluation.** `(I - Q_sigma) x = b_sigma` on `M`, with `Q_sigma =
//!    P_sigma` restricted to `M x M` and `b_sigma(s) = P_sigma(B | s)`, by
//!    sparse LU or, above [`crate::solver::DEFAULT_LU_LIMIT`] unknowns,
//!    BiCGSTAB warm-started from the previous policy's values
//!    ([`crate::solver::LinearSolver`], residual checked).
//! 4. **Improvement.** In each state of `M` switch to an action with the
//!    largest `sum_t P(t | s, a) x(t)` only if it beats the current action's
//!    by more than [`IMPROVEMENT_THRESHOLD`]; keep the current action on ties.
//!    The new policy is again proper: a closed class `C` inside `M` under the
//!    new policy with no switched state would be closed under the old one,
//!    which is proper; with a switched state, its stationary distribution
//!    `pi > 0` would give `pi P x > pi x = pi P x`. Values never decrease and
//!    strictly increase somewhere, so no policy repeats and the loop ends.
//!
//! **Why the result is exact.** The final `x` is the value of a policy, so
//! `x <= x*`; and it is a fixed point of `F` (up to the reported residual),
//! so `x >= x*`, `x*` being the least fixed point. No end-component collapse
//! is needed for this argument; the proper start only keeps every
//! evaluation nonsingular.

use crate::graph::backward_reachable;
use crate::solver::{LinearSolver, SolverSettings, SparsePattern};

use super::{Mdp, MdpError, Predecessors};

/// Policy iteration switches an action only if it improves the expected
/// value by more than this (values are probabilities in `[0, 1]`).
pub const IMPROVEMENT_THRESHOLD: f64 = 1e-12;

/// Policy iteration gives up (as a numerical failure) after this many
/// evaluations; in exact arithmetic it stops after finitely many.
pub const MAX_ITERATIONS: usize = 10_000;

/// Maximum reachability probabilities and a strategy attaining them.
#[derive(Debug, Clone, PartialEq)]
pub struct Reachability {
    /// `x*(s) = sup_sigma P^sigma_s(reach B)` for every state.
    pub values: Vec<f64>,
    /// An optimal memoryless deterministic strategy: the local action in each
    /// state. In `B` and in states that cannot reach `B` it is action 0
    /// (every action is optimal there); in the other states of value 1 it
    /// reaches `B` almost surely.
    pub strategy: Vec<usize>,
    /// The larger of the final linear solve's residual
    /// `max_s |((I - Q) x - b)(s)|` and the Bellman gap
    /// `max_s (F x - x)(s)` (below [`IMPROVEMENT_THRESHOLD`] at the end).
    pub residual: f64,
    /// The number of policy evaluations.
    pub iterations: usize,
    /// `x*(s) > 0` exactly: `s` can reach the target in the graph of all
    /// actions (decided on the graph, not on the computed `values`).
    pub possible: Vec<bool>,
    /// `x*(s) = 1` exactly: some strategy reaches the target from `s`
    /// almost surely (decided on the graph).
    pub almost_sure: Vec<bool>,
}

/// `sup_sigma P^sigma(reach target)` from every state of `mdp`, with an
/// optimal memoryless deterministic strategy (see the module documentation).
pub fn max_reachability(mdp: &Mdp, target: &[bool]) -> Result<Reachability, MdpError> {
    let n = mdp.num_states();
    if target.len() != n {
        return Err(MdpError::Malformed(format!(
            "target set of size {} for {n} states",
            target.len()
        )));
    }
    let predecessors = mdp.predecessors();
    let positive = backward_reachable(&predecessors, target);
    let (almost_sure, sure_strategy) = almost_surely(mdp, &predecessors, target, &positive);
    let maybe: Vec<usize> = (0..n).filter(|&s| positive[s] && !almost_sure[s]).collect();
    let mut strategy = attractor(n, &predecessors, &almost_sure);
    for s in (0..n).filter(|&s| almost_sure[s]) {
        strategy[s] = sure_strategy[s];
    }
    let mut previous: Vec<f64> = almost_sure.iter().map(|&t| f64::from(t)).collect();
    for iterations in 1..=MAX_ITERATIONS {
        let (values, solve_residual) = evaluate(mdp, &almost_sure, &maybe, &strategy, &previous)?;
        let (switched, gap) = improve(mdp, &values, &maybe, &mut strategy);
        if !switched {
            return Ok(Reachability {
                values,
                strategy,
                residual: solve_residual.max(gap),
                iterations,
                possible: positive,
                almost_sure,
            });
        }
        previous = values;
    }
    Err(MdpError::NotConverged(MAX_ITERATIONS))
}

/// `S_1`, the states from which some strategy reaches `target` almost
/// surely, and such a strategy on them (Baier and Katoen, Section 10.6,
/// "Prob1E"): starting from `U` = `positive`, keep the states that reach
/// `target` using only actions whose successors all lie in `U`, until `U`
/// is stable. On the result, each state outside `target` plays an action
/// that stays in `U` and leads one step closer to `target` in that search,
/// so it never leaves `U` and reaches `target` with probability 1.
fn almost_surely(
    mdp: &Mdp,
    predecessors: &Predecessors,
    target: &[bool],
    positive: &[bool],
) -> (Vec<bool>, Vec<usize>) {
    let n = mdp.num_states();
    let mut within = positive.to_vec();
    let mut strategy = vec![0; n];
    loop {
        let mut found = target.to_vec();
        let mut frontier: Vec<usize> = (0..n).filter(|&s| target[s]).collect();
        while let Some(t) = frontier.pop() {
            for &(s, a) in predecessors.of(t) {
                let stays = || mdp.distribution(s, a).iter().all(|&(u, _)| within[u]);
                if within[s] && !found[s] && stays() {
                    found[s] = true;
                    strategy[s] = a;
                    frontier.push(s);
                }
            }
        }
        if found == within {
            return (within, strategy);
        }
        within = found;
    }
}

/// A policy that gives each state able to reach `target` an action with an
/// edge to a state closer to `target` (backward search); action 0 elsewhere.
fn attractor(n: usize, predecessors: &Predecessors, target: &[bool]) -> Vec<usize> {
    let mut strategy = vec![0; n];
    let mut found = target.to_vec();
    let mut frontier: Vec<usize> = (0..n).filter(|&s| target[s]).collect();
    while let Some(t) = frontier.pop() {
        for &(s, a) in predecessors.of(t) {
            if !found[s] {
                found[s] = true;
                strategy[s] = a;
                frontier.push(s);
            }
        }
    }
    strategy
}

/// The reachability probabilities of the policy: 1 on `target`, the solution
/// of `(I - Q) x = b` on `maybe`, 0 elsewhere; and the solve's residual.
/// The linear solver is chosen by size ([`SolverSettings::default`]); an
/// iterative one starts from `start` (the previous policy's values).
fn evaluate(
    mdp: &Mdp,
    target: &[bool],
    maybe: &[usize],
    strategy: &[usize],
    start: &[f64],
) -> Result<(Vec<f64>, f64), MdpError> {
    let n = mdp.num_states();
    let mut values: Vec<f64> = target.iter().map(|&t| f64::from(t)).collect();
    if maybe.is_empty() {
        return Ok((values, 0.0));
    }
    let mut index = vec![usize::MAX; n];
    for (i, &s) in maybe.iter().enumerate() {
        index[s] = i;
    }
    let mut row_offsets = vec![0];
    let mut columns = Vec::new();
    let mut coefficients = Vec::new();
    let mut rhs = vec![0.0; maybe.len()];
    let mut row = Vec::new();
    for (i, &s) in maybe.iter().enumerate() {
        row.clear();
        row.push((i, 1.0));
        for &(t, p) in mdp.distribution(s, strategy[s]) {
            if index[t] != usize::MAX {
                row.push((index[t], -p));
            } else if target[t] {
                rhs[i] += p;
            }
        }
        row.sort_by_key(|&(j, _)| j);
        for &(j, a) in &row {
            if columns.len() > row_offsets[i] && columns.last() == Some(&j) {
                *coefficients.last_mut().expect("a column was pushed") += a;
            } else {
                columns.push(j);
                coefficients.push(a);
            }
        }
        row_offsets.push(columns.len());
    }
    let pattern = SparsePattern {
        n: maybe.len(),
        row_offsets,
        columns,
    };
    let mut solver = LinearSolver::new(pattern, &SolverSettings::default())?;
    solver.factorize(&coefficients)?;
    let mut solution: Vec<f64> = maybe.iter().map(|&s| start[s]).collect();
    let residual = solver.solve(&rhs, &mut solution)?.residual;
    for (&s, &x) in maybe.iter().zip(&solution) {
        values[s] = x;
    }
    Ok((values, residual))
}

/// One greedy improvement step on `maybe` (see the module documentation).
/// Returns whether some action was switched and the Bellman gap
/// `max_s (max_a E_a x - E_sigma(s) x)` before switching.
fn improve(mdp: &Mdp, values: &[f64], maybe: &[usize], strategy: &mut [usize]) -> (bool, f64) {
    let mut switched = false;
    let mut gap: f64 = 0.0;
    for &s in maybe {
        let current = mdp.expectation(s, strategy[s], values);
        let (best_action, best) = (0..mdp.num_actions(s))
            .map(|a| (a, mdp.expectation(s, a, values)))
            .fold((strategy[s], current), |best, candidate| {
                if candidate.1 > best.1 {
                    candidate
                } else {
                    best
                }
            });
        gap = gap.max(best - current);
        if best > current + IMPROVEMENT_THRESHOLD {
            strategy[s] = best_action;
            switched = true;
        }
    }
    (switched, gap)
}

#[cfg(test)]
mod tests {
    use super::super::tests::mdp;
    use super::*;

    /// Target 3, sink 4. State 0 may stay forever (action 0) or gamble
    /// (action 1: 1 or 4, half each); 1 and 2 form an end component through
    /// their actions 1. On paper: x2 = max(0.6, x1), x1 = max(0.3 + 0.7 x0,
    /// x2), x0 = max(x0, 0.5 x1); the least solution is x1 = x2 = 0.6 (1 goes
    /// to 2, which tries for 3), x0 = 0.3, and 0.3 + 0.7 * 0.3 = 0.51 < 0.6.
    fn gamble() -> Mdp {
        mdp(&[
            &[&[(0, 1.0)], &[(1, 0.5), (4, 0.5)]],
            &[&[(3, 0.3), (0, 0.7)], &[(2, 1.0)]],
            &[&[(3, 0.6), (4, 0.4)], &[(1, 1.0)]],
            &[&[(3, 1.0)]],
            &[&[(4, 1.0)]],
        ])
    }

    #[test]
    fn values_derived_on_paper_with_end_components_in_the_maybe_states() {
        let target = [false, false, false, true, false];
        let result = max_reachability(&gamble(), &target).unwrap();
        let expected = [0.3, 0.6, 0.6, 1.0, 0.0];
        for (x, e) in result.values.iter().zip(expected) {
            assert!((x - e).abs() < 1e-14, "{:?}", result.values);
        }
        assert_eq!(&result.strategy[..3], &[1, 1, 0]);
        assert!(result.residual < 1e-12);
        assert!(result.iterations >= 2, "the start policy is not optimal");
    }

    /// Retrying (action 0) reaches 1 almost surely; the one-shot action 1
    /// looks better for one step (0.9) but risks the sink 2.
    #[test]
    fn patience_wins_with_value_exactly_one() {
        let m = mdp(&[
            &[&[(1, 0.5), (0, 0.5)], &[(1, 0.9), (2, 0.1)]],
            &[&[(1, 1.0)]],
            &[&[(2, 1.0)]],
        ]);
        let result = max_reachability(&m, &[false, true, false]).unwrap();
        assert_eq!(result.values, vec![1.0, 1.0, 0.0]);
        assert_eq!(result.strategy[0], 0);
    }

    #[test]
    fn unreachable_target_gives_zero_without_a_solve() {
        let result = max_reachability(&gamble(), &[false; 5]).unwrap();
        assert_eq!(result.values, vec![0.0; 5]);
        assert_eq!(result.iterations, 1);
    }

    #[test]
    fn a_target_set_of_the_wrong_size_is_an_error() {
        assert!(matches!(
            max_reachability(&gamble(), &[true]),
            Err(MdpError::Malformed(_))
        ));
    }
}
