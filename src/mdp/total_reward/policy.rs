//! Policy iteration on the unknowns of an expected total reward (module
//! documentation of [`super`], step 2): the systems of the strategies, a
//! proper start, and the longest expected time the certificate falls back
//! on.

use super::{MAX_ITERATIONS, Optimum, REWARD_IMPROVEMENT_THRESHOLD, components_within};
use crate::mdp::pattern::{Slot, union_pattern};
use crate::mdp::{Mdp, MdpError};
use crate::solver::{LinearSolver, SolverSettings};

/// The largest expected number of steps to the target over the strategies
/// that play `allowed` actions on the unknowns: policy iteration for the
/// reward 1 per step, to the maximum; `None` where such a strategy may
/// never reach the target (an end component among them).
pub(super) fn longest_steps(
    mdp: &Mdp,
    target: &[bool],
    unknowns: &[usize],
    allowed: &[bool],
    settings: &SolverSettings,
) -> Result<Option<Vec<f64>>, MdpError> {
    if !components_within(mdp, unknowns, allowed).is_empty() {
        return Ok(None);
    }
    let ones = vec![1.0; mdp.num_state_actions()];
    let mut strategy = proper_start(mdp, target, unknowns, allowed)?;
    let mut system = PolicySystem::new(mdp, target, (unknowns, allowed), settings)?;
    // A potential needs no proved accuracy: the certificate's check makes
    // its errors harmless.
    let threshold = REWARD_IMPROVEMENT_THRESHOLD;
    system.iterate(mdp, &ones, (Optimum::Max, threshold), false, &mut strategy)?;
    system.expected_steps().map(Some)
}

/// A proper strategy on the unknowns: a backward search from the target
/// over kept actions gives each unknown an action with an edge to a state
/// found before it. Every other state keeps action 0.
pub(super) fn proper_start(
    mdp: &Mdp,
    target: &[bool],
    unknowns: &[usize],
    kept: &[bool],
) -> Result<Vec<usize>, MdpError> {
    let n = mdp.num_states();
    let mut strategy = vec![0; n];
    let mut found = target.to_vec();
    let mut frontier: Vec<usize> = (0..n).filter(|&s| target[s]).collect();
    let predecessors = mdp.predecessors();
    while let Some(t) = frontier.pop() {
        for &(s, a) in predecessors.of(t) {
            let action = mdp.global_actions(s).start + a;
            if !found[s] && kept[action] {
                found[s] = true;
                strategy[s] = a;
                frontier.push(s);
            }
        }
    }
    match unknowns.iter().find(|&&s| !found[s]) {
        Some(s) => Err(MdpError::Malformed(format!(
            "state {s} has a finite expected reward but no kept action towards the target"
        ))),
        None => Ok(strategy),
    }
}

/// The systems `(I - Q_sigma) x = r_sigma` of the strategies on the
/// unknowns (kept actions only), on the union of their patterns.
pub(super) struct PolicySystem {
    unknowns: Vec<usize>,
    /// The position of each state among the unknowns (`usize::MAX` if none).
    index: Vec<usize>,
    slots: Vec<Slot>,
    /// Per global action: whether policy iteration may play it.
    kept: Vec<bool>,
    solver: Option<LinearSolver>,
}

impl PolicySystem {
    pub(super) fn new(
        mdp: &Mdp,
        target: &[bool],
        (unknowns, kept): (&[usize], &[bool]),
        settings: &SolverSettings,
    ) -> Result<Self, MdpError> {
        let mut index = vec![usize::MAX; mdp.num_states()];
        for (i, &s) in unknowns.iter().enumerate() {
            index[s] = i;
        }
        // Every state outside the unknowns that a kept action reaches is
        // in the target (value 0): the right-hand side is the reward alone.
        let (pattern, slots) = union_pattern(mdp, (unknowns, &index), target, |a| kept[a]);
        let solver = match unknowns.is_empty() {
            true => None,
            false => Some(LinearSolver::new(pattern, settings)?),
        };
        Ok(Self {
            unknowns: unknowns.to_vec(),
            index,
            slots,
            kept: kept.to_vec(),
            solver,
        })
    }

    /// The position of each state among the unknowns (`usize::MAX` for
    /// the others).
    pub(super) fn index(&self) -> &[usize] {
        &self.index
    }

    /// Factorises the system of `strategy`; returns `r_sigma` on the
    /// unknowns for `rewards`.
    fn factorise(
        &mut self,
        mdp: &Mdp,
        strategy: &[usize],
        rewards: &[f64],
    ) -> Result<Vec<f64>, MdpError> {
        let Self {
            unknowns,
            slots,
            solver,
            ..
        } = self;
        let rhs = unknowns
            .iter()
            .map(|&s| rewards[mdp.global_actions(s).start + strategy[s]])
            .collect();
        if let Some(solver) = solver {
            solver.factorize_with(|values, exits| {
                values.fill(0.0);
                exits.fill(0.0);
                for (i, &s) in unknowns.iter().enumerate() {
                    let action = mdp.global_actions(s).start + strategy[s];
                    let entries = mdp.entry_offsets[action]..mdp.entry_offsets[action + 1];
                    for (slot, &(_, p)) in slots[entries.clone()].iter().zip(&mdp.entries[entries])
                    {
                        match *slot {
                            Slot::Inside(k) => values[k] = -p,
                            Slot::Leaving { .. } => exits[i] += p,
                            Slot::Unused => {}
                        }
                    }
                }
            })?;
        }
        Ok(rhs)
    }

    /// Policy iteration from the proper `strategy` (module documentation,
    /// step 2), switching for gains above `threshold`; returns the last
    /// strategy's values on the unknowns and their error bound (proved to
    /// the tolerance where `prove`, else that of a trial solve), and leaves
    /// its system factorised.
    pub(super) fn iterate(
        &mut self,
        mdp: &Mdp,
        rewards: &[f64],
        (optimum, threshold): (Optimum, f64),
        prove: bool,
        strategy: &mut [usize],
    ) -> Result<(Vec<f64>, f64), MdpError> {
        let mut x = vec![0.0; self.unknowns.len()];
        if self.solver.is_none() {
            return Ok((x, 0.0));
        }
        for _ in 0..MAX_ITERATIONS {
            let rhs = self.factorise(mdp, strategy, rewards)?;
            let trial = self.solver_mut()?.solve_trial(&rhs, &mut x)?;
            let bound = trial.error_bound.unwrap_or(f64::INFINITY);
            if !self.improve(
                mdp,
                rewards,
                optimum,
                threshold.max(4.0 * bound),
                &x,
                strategy,
            ) {
                if !prove {
                    return Ok((x, bound));
                }
                let proved = self.solver_mut()?.solve(&rhs, &mut x)?;
                return Ok((x, proved.error_bound.unwrap_or(f64::INFINITY)));
            }
        }
        Err(MdpError::NotConverged(MAX_ITERATIONS))
    }

    /// The solver (there are unknowns).
    fn solver_mut(&mut self) -> Result<&mut LinearSolver, MdpError> {
        self.solver
            .as_mut()
            .ok_or_else(|| MdpError::Malformed("a policy system without unknowns".into()))
    }

    /// One greedy step: switches each unknown to a kept action whose
    /// one-step value on leaving the state beats its own by more than
    /// `threshold`; returns whether one did.
    fn improve(
        &self,
        mdp: &Mdp,
        rewards: &[f64],
        optimum: Optimum,
        threshold: f64,
        x: &[f64],
        strategy: &mut [usize],
    ) -> bool {
        let sign = optimum.sign();
        let mut switched = false;
        for &s in &self.unknowns {
            let first = mdp.global_actions(s).start;
            let score = |a: usize| self.leaving_value(mdp, s, a, rewards[first + a], x);
            let current = score(strategy[s]).map_or(f64::NEG_INFINITY, |v| sign * v);
            let best = mdp
                .global_actions(s)
                .filter(|&a| self.kept[a])
                .filter_map(|a| score(a - first).map(|v| (a - first, sign * v)))
                .fold(
                    (strategy[s], current),
                    |best, c| if c.1 > best.1 { c } else { best },
                );
            if best.1 > current + threshold {
                strategy[s] = best.0;
                switched = true;
            }
        }
        switched
    }

    /// The value of playing local action `a` in unknown `s` until it
    /// leaves `s`, then following `x`: `(r + sum_{t != s} P(t) x(t)) /
    /// sum_{t != s} P(t)`; `None` for an action that never leaves `s`.
    fn leaving_value(&self, mdp: &Mdp, s: usize, a: usize, reward: f64, x: &[f64]) -> Option<f64> {
        let (mut leaving, mut expectation) = (0.0, reward);
        for &(t, p) in mdp.distribution(s, a).iter().filter(|&&(t, _)| t != s) {
            leaving += p;
            if self.index[t] != usize::MAX {
                expectation += p * x[self.index[t]];
            }
        }
        (leaving > 0.0).then(|| expectation / leaving)
    }

    /// `T`, the expected number of steps to the target under the strategy
    /// whose system is factorised: `(I - Q_sigma) T = 1`, solved without
    /// an error bound (the certificate's check makes its errors harmless).
    pub(super) fn expected_steps(&mut self) -> Result<Vec<f64>, MdpError> {
        let mut steps = vec![0.0; self.unknowns.len()];
        if let Some(solver) = &mut self.solver {
            let ones = vec![1.0; self.unknowns.len()];
            solver.solve_unbounded(&ones, &mut steps)?;
        }
        Ok(steps)
    }
}
