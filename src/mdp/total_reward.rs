//! The optimal expected total reward until a target in an MDP, bracketed
//! (method.md section 9, "the worst case over adversaries").
//!
//! For a target set `B` and a reward `r(s, a)` per state-action pair, the
//! value of a strategy `sigma` in `s` is the expected sum of the rewards
//! of the steps taken before the first visit to `B`, with Storm's
//! convention: `+inf` wherever `sigma` misses `B` with positive
//! probability. [`optimal_total_reward`] computes `x*(s) = max_sigma` or
//! `min_sigma` of it, whatever the signs of the rewards:
//!
//! 1. **Where it is finite.** The maximum is infinite exactly where some
//!    strategy avoids `B` with positive probability: the states that reach,
//!    with positive probability and without passing `B`, an end component
//!    outside `B`. Elsewhere every strategy reaches `B` almost surely. The
//!    minimum is infinite exactly where no strategy reaches `B` almost
//!    surely ([`super::qualitative_reachability`]); elsewhere the actions
//!    that may leave the almost-sure set are never worth playing (they
//!    cost `+inf`) and are dropped. What remains of a minimum may hold an
//!    end component outside `B`: staying in it forever misses `B`, so it
//!    costs `+inf`, and leaving it after `n` rounds costs `n` times its
//!    rounds' reward. The end components whose actions earn nothing are
//!    collapsed first, as Storm does ([`collapsed`]: the minimiser moves
//!    inside one for free, to its best way out). Then, where no action
//!    inside an end component loses, every round earns a positive reward,
//!    staying is never worth it and the minimum is attained; where one
//!    loses, the minimum may be `-inf` and the function refuses it
//!    ([`MdpError::RewardCycle`]) rather than return a number it cannot
//!    prove.
//! 2. **Policy iteration** on the finite non-target states (the unknowns),
//!    from a proper strategy (a backward search from `B` over the kept
//!    actions gives each unknown an action with an edge to a state found
//!    earlier): evaluate `(I - Q_sigma) x = r_sigma` (the diagonal from the
//!    probabilities of leaving, method.md section 8), switch each state to
//!    an action whose one-step value beats its own by more than the
//!    threshold, until none does. Every strategy on a maximum's unknowns
//!    is proper; on a minimum's, a strict improvement from a proper
//!    strategy stays proper where every cycle outside `B` earns a positive
//!    reward (Bertsekas and Tsitsiklis, stochastic shortest paths). The
//!    last strategy's values are solved with a proved error bound, so they
//!    bound `x*` on one side.
//! 3. **The certificate** bounds it on the other. With `T >= 0` a
//!    potential (the expected number of steps to `B` under the last
//!    strategy, or where that does not prove it, the largest over the
//!    strategies that play actions within [`NEAR_OPTIMAL`] of the best)
//!    and `y = x + eps T` for a maximum (`x - eps T` for a minimum), the
//!    Bellman operator `F` of the model the policy systems solve (whose
//!    self-loops leave the diagonal as the probability of leaving)
//!    satisfies `F(y) <= y` (`>= y`) when, for every kept action `a` of
//!    every unknown `s`,
//!
//!    ```text
//!    g_a(s) <= eps d_a(s),   g_a(s) = +-(r(s, a) + sum_{t != s} P(t | s, a) (x(t) - x(s))),
//!                            d_a(s) = sum_{t != s} P(t | s, a) (T(s) - T(t)),
//!    ```
//!
//!    and then `x* <= y` (`>= y`): `F` is monotone and its iterates from
//!    any vector converge to `x*` when every cycle outside `B` earns a
//!    positive reward or none is possible. Both sides are evaluated in
//!    double precision and widened by a bound on their rounding, so the
//!    check proves the inequality for the doubles `x` and `T` as they are;
//!    the smallest admissible `eps` is taken. No admissible `eps` (or a
//!    value or potential that is not finite) is an error
//!    ([`MdpError::OptimalityUnproved`]), never a number.

use super::{
    EndComponent, Mdp, MdpBuilder, MdpError, maximal_end_components, maximal_end_components_using,
    qualitative_reachability,
};
use crate::solver::{LinearSolver, SolverSettings, SparsePattern};

/// Policy iteration switches an action only if it improves the one-step
/// value by more than this times the largest reward (at least 1).
pub const REWARD_IMPROVEMENT_THRESHOLD: f64 = 1e-12;

/// Policy iteration gives up (as a numerical failure) after this many
/// evaluations.
const MAX_ITERATIONS: usize = 10_000;

/// Where the potential of the last strategy does not prove the optimum,
/// the certificate's second potential is the longest expected time over
/// the actions within this much (times the largest reward, at least 1) of
/// the best: ties, whose gains the rounding can make look positive, then
/// lower the potential, and the actions it leaves out lose more than that.
const NEAR_OPTIMAL: f64 = 1e-6;

/// The unit roundoff of `f64`.
const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;

/// Which way the strategies optimise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Optimum {
    /// `max_sigma`: infinite wherever some strategy misses the target.
    Max,
    /// `min_sigma`: infinite wherever no strategy reaches it almost surely.
    Min,
}

impl Optimum {
    /// `+1` for a maximum, `-1` for a minimum: the sign that makes a gain
    /// positive.
    fn sign(self) -> f64 {
        match self {
            Self::Max => 1.0,
            Self::Min => -1.0,
        }
    }
}

/// The optimal expected total reward `x*` of every state, bracketed
/// (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct TotalReward {
    /// `lower[s] <= x*(s)`; `+inf` where `x*(s)` is infinite, 0 on the target.
    pub lower: Vec<f64>,
    /// `x*(s) <= upper[s]`; `+inf` where `x*(s)` is infinite, 0 on the target.
    pub upper: Vec<f64>,
    /// An optimal memoryless strategy (local action numbers), up to the
    /// bracket: policy iteration's last strategy on the unknowns, a proper
    /// action elsewhere where one exists, else 0.
    pub strategy: Vec<usize>,
}

impl TotalReward {
    /// The bracket of `sum_s p0(s) x*(s)` for the initial distribution
    /// `initial` (`(state, probability)` pairs), widened by the rounding of
    /// the sums; `(+inf, +inf)` where an initial state of positive
    /// probability has an infinite value.
    pub fn of_initial(&self, initial: &[(usize, f64)]) -> (f64, f64) {
        let weighted = |values: &[f64], direction: f64| {
            let (mut sum, mut magnitude) = (0.0, 0.0);
            for &(s, p) in initial.iter().filter(|&&(_, p)| p > 0.0) {
                if values[s].is_infinite() {
                    return f64::INFINITY;
                }
                sum += p * values[s];
                magnitude += (p * values[s]).abs();
            }
            let rounding = (initial.len() + 2) as f64 * UNIT_ROUNDOFF * magnitude;
            sum + direction * rounding
        };
        (weighted(&self.lower, -1.0), weighted(&self.upper, 1.0))
    }
}

/// `x*` for `target` and the rewards `rewards[global action]` (actions
/// numbered state after state, as [`Mdp::num_state_actions`] counts them),
/// optimised as `optimum` says, with the policy evaluations solved by
/// `settings` (module documentation).
pub fn optimal_total_reward(
    mdp: &Mdp,
    target: &[bool],
    rewards: &[f64],
    optimum: Optimum,
    settings: &SolverSettings,
) -> Result<TotalReward, MdpError> {
    let n = mdp.num_states();
    if target.len() != n || rewards.len() != mdp.num_state_actions() {
        return Err(MdpError::Malformed(format!(
            "a target of {} states and {} rewards for {n} states and {} actions",
            target.len(),
            rewards.len(),
            mdp.num_state_actions()
        )));
    }
    if let Some(a) = rewards.iter().position(|r| !r.is_finite()) {
        return Err(MdpError::Malformed(format!(
            "the reward of action {a} is not finite"
        )));
    }
    if optimum == Optimum::Min {
        let free = free_components(mdp, target, rewards)?;
        if !free.is_empty() {
            return collapsed(mdp, target, rewards, &free, settings);
        }
    }
    optimum_without_free_cycles(mdp, target, rewards, optimum, settings)
}

/// [`optimal_total_reward`] where no end component of actions that earn
/// nothing lies among a minimum's unknowns (module documentation, steps 1
/// to 3).
fn optimum_without_free_cycles(
    mdp: &Mdp,
    target: &[bool],
    rewards: &[f64],
    optimum: Optimum,
    settings: &SolverSettings,
) -> Result<TotalReward, MdpError> {
    let n = mdp.num_states();
    let finite = finite_states(mdp, target, optimum)?;
    let kept = kept_actions(mdp, &finite);
    let unknowns: Vec<usize> = (0..n).filter(|&s| finite[s] && !target[s]).collect();
    check_cycles(mdp, &unknowns, &kept, rewards)?;
    let mut strategy = proper_start(mdp, target, &unknowns, &kept)?;
    let largest = rewards.iter().fold(1.0_f64, |m, r| m.max(r.abs()));
    let scaled = SolverSettings {
        tolerance: settings.tolerance * largest,
        ..*settings
    };
    let mut system = PolicySystem::new(mdp, &unknowns, &kept, &scaled)?;
    let threshold = REWARD_IMPROVEMENT_THRESHOLD * largest;
    let (values, error) =
        system.iterate(mdp, rewards, (optimum, threshold), true, &mut strategy)?;
    let steps = system.expected_steps()?;
    let scale = Scale {
        kept: &kept,
        rewards,
        optimum,
    };
    let certified = match scale.certify(mdp, &unknowns, &values, &steps)? {
        Some(y) => y,
        None => {
            let near = scale.near_optimal(mdp, &unknowns, &values, NEAR_OPTIMAL * largest);
            let longest = longest_steps(mdp, target, &unknowns, &near, &scaled)?;
            longest
                .and_then(|longest| scale.certify(mdp, &unknowns, &values, &longest).transpose())
                .transpose()?
                .ok_or_else(|| {
                    MdpError::OptimalityUnproved(
                        "no potential proves the optimum of the expected reward".into(),
                    )
                })?
        }
    };
    let mut lower = vec![f64::INFINITY; n];
    let mut upper = vec![f64::INFINITY; n];
    for s in (0..n).filter(|&s| target[s]) {
        lower[s] = 0.0;
        upper[s] = 0.0;
    }
    for (i, &s) in unknowns.iter().enumerate() {
        let (policy_low, policy_high) = (values[i] - error, values[i] + error);
        (lower[s], upper[s]) = match optimum {
            Optimum::Max => (policy_low, certified[i]),
            Optimum::Min => (certified[i], policy_high),
        };
    }
    Ok(TotalReward {
        lower,
        upper,
        strategy,
    })
}

/// The states where `x*` is finite (module documentation, step 1), the
/// target included.
fn finite_states(mdp: &Mdp, target: &[bool], optimum: Optimum) -> Result<Vec<bool>, MdpError> {
    match optimum {
        Optimum::Min => Ok(qualitative_reachability(mdp, target)?.almost_sure),
        Optimum::Max => {
            let outside: Vec<bool> = target.iter().map(|&b| !b).collect();
            let mut avoiding = vec![false; mdp.num_states()];
            let mut frontier = Vec::new();
            for component in maximal_end_components(mdp, &outside) {
                for s in component.states {
                    avoiding[s] = true;
                    frontier.push(s);
                }
            }
            let predecessors = mdp.predecessors();
            while let Some(t) = frontier.pop() {
                for &(s, _) in predecessors.of(t) {
                    if !target[s] && !avoiding[s] {
                        avoiding[s] = true;
                        frontier.push(s);
                    }
                }
            }
            Ok(avoiding.iter().map(|&a| !a).collect())
        }
    }
}

/// Per global action: whether all its successors are `finite` (the
/// actions of a finite state that policy iteration may play).
fn kept_actions(mdp: &Mdp, finite: &[bool]) -> Vec<bool> {
    (0..mdp.num_state_actions())
        .map(|a| mdp.global_distribution(a).iter().all(|&(t, _)| finite[t]))
        .collect()
}

/// The end components of a minimum's unknowns whose actions earn nothing
/// (kept actions of reward 0): the minimiser moves inside one for free.
fn free_components(
    mdp: &Mdp,
    target: &[bool],
    rewards: &[f64],
) -> Result<Vec<EndComponent>, MdpError> {
    let finite = finite_states(mdp, target, Optimum::Min)?;
    let kept = kept_actions(mdp, &finite);
    let unknowns: Vec<usize> = (0..mdp.num_states())
        .filter(|&s| finite[s] && !target[s])
        .collect();
    let free: Vec<bool> = (kept.iter().zip(rewards))
        .map(|(&k, &r)| k && r == 0.0)
        .collect();
    Ok(components_within(mdp, &unknowns, &free))
}

/// The minimum where the end components `free` earn nothing (Storm's
/// collapse): the minimiser moves inside each for free, so every state of
/// one has the same optimum, that of the best way out. The quotient MDP
/// has one state per component, with the actions of its states that are
/// not the component's own free ones (a positive reward inside it becomes
/// a self-loop that costs); its optimum, brackets included, is the
/// original's ([`optimum_without_free_cycles`]: it has no free component
/// left, since a free one of the quotient would make a larger one of the
/// original). The strategy leaves a component by the quotient's chosen
/// action, from its state, and every other state of the component walks
/// there along the component's free actions (almost surely, at no cost).
fn collapsed(
    mdp: &Mdp,
    target: &[bool],
    rewards: &[f64],
    free: &[EndComponent],
    settings: &SolverSettings,
) -> Result<TotalReward, MdpError> {
    let n = mdp.num_states();
    let mut class = vec![usize::MAX; n];
    let mut members: Vec<Vec<usize>> = Vec::new();
    let mut internal = vec![false; mdp.num_state_actions()];
    for component in free {
        for (&s, actions) in component.states.iter().zip(&component.actions) {
            class[s] = members.len();
            let first = mdp.global_actions(s).start;
            for &a in actions {
                internal[first + a] = true;
            }
        }
        members.push(component.states.clone());
    }
    for (s, class) in class.iter_mut().enumerate() {
        if *class == usize::MAX {
            *class = members.len();
            members.push(vec![s]);
        }
    }
    let mut builder = MdpBuilder::new();
    let mut origin = Vec::new();
    let mut quotient_rewards = Vec::new();
    for states in &members {
        for &s in states {
            for action in mdp.global_actions(s).filter(|&a| !internal[a]) {
                let distribution = mdp.global_distribution(action);
                builder.add_action(distribution.iter().map(|&(t, p)| (class[t], p)));
                origin.push((s, action - mdp.global_actions(s).start));
                quotient_rewards.push(rewards[action]);
            }
        }
        builder.end_state();
    }
    let quotient = builder.build()?;
    let quotient_target: Vec<bool> = members.iter().map(|m| target[m[0]]).collect();
    let solved = optimum_without_free_cycles(
        &quotient,
        &quotient_target,
        &quotient_rewards,
        Optimum::Min,
        settings,
    )?;
    let mut strategy = vec![0; n];
    let predecessors = mdp.predecessors();
    let mut routed = vec![false; n];
    for (q, states) in members.iter().enumerate() {
        let (exit, action) = origin[quotient.global_actions(q).start + solved.strategy[q]];
        strategy[exit] = action;
        routed[exit] = true;
        // Backwards from the exit along the component's free actions.
        let mut found = vec![exit];
        let mut next = 0;
        while next < found.len() {
            let t = found[next];
            next += 1;
            for &(s, a) in predecessors.of(t) {
                if class[s] == q && !routed[s] && internal[mdp.global_actions(s).start + a] {
                    strategy[s] = a;
                    routed[s] = true;
                    found.push(s);
                }
            }
        }
        debug_assert!(found.len() == states.len(), "a component reaches its exit");
    }
    Ok(TotalReward {
        lower: (0..n).map(|s| solved.lower[class[s]]).collect(),
        upper: (0..n).map(|s| solved.upper[class[s]]).collect(),
        strategy,
    })
}

/// The end components among `unknowns` with `kept` actions only (where
/// staying costs `+inf`, so only a minimum's have any).
fn components_within(mdp: &Mdp, unknowns: &[usize], kept: &[bool]) -> Vec<EndComponent> {
    let mut within = vec![false; mdp.num_states()];
    for &s in unknowns {
        within[s] = true;
    }
    maximal_end_components_using(mdp, &within, kept)
}

/// An error where an end component among the unknowns (with kept actions
/// only) has an action that earns a negative reward (module
/// documentation, step 1), or (a malformed call: [`collapsed`] removed
/// them) where the actions that earn nothing form an end component of
/// their own. What passes has a positive reward on every round of every
/// end component: each round uses an action that earns something, and
/// none loses.
fn check_cycles(
    mdp: &Mdp,
    unknowns: &[usize],
    kept: &[bool],
    rewards: &[f64],
) -> Result<(), MdpError> {
    for component in components_within(mdp, unknowns, kept) {
        for (&s, actions) in component.states.iter().zip(&component.actions) {
            let first = mdp.global_actions(s).start;
            if let Some(&a) = actions.iter().find(|&&a| rewards[first + a] < 0.0) {
                return Err(MdpError::RewardCycle(format!(
                    "state {s} lies in an end component outside the target whose action {a} \
                     earns {}: the optimum may be -inf",
                    rewards[first + a]
                )));
            }
        }
    }
    let free: Vec<bool> = (kept.iter().zip(rewards))
        .map(|(&k, &r)| k && r == 0.0)
        .collect();
    if let Some(component) = components_within(mdp, unknowns, &free).first() {
        return Err(MdpError::Malformed(format!(
            "states {:?} form an end component whose rounds earn nothing after the collapse",
            component.states
        )));
    }
    Ok(())
}

/// The largest expected number of steps to the target over the strategies
/// that play `allowed` actions on the unknowns: policy iteration for the
/// reward 1 per step, to the maximum; `None` where such a strategy may
/// never reach the target (an end component among them).
fn longest_steps(
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
    let mut system = PolicySystem::new(mdp, unknowns, allowed, settings)?;
    // A potential needs no proved accuracy: the certificate's check makes
    // its errors harmless.
    let threshold = REWARD_IMPROVEMENT_THRESHOLD;
    system.iterate(mdp, &ones, (Optimum::Max, threshold), false, &mut strategy)?;
    system.expected_steps().map(Some)
}

/// A proper strategy on the unknowns: a backward search from the target
/// over kept actions gives each unknown an action with an edge to a state
/// found before it. Every other state keeps action 0.
fn proper_start(
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

/// Where one transition of an unknown's action goes in a policy's system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    /// An off-diagonal entry `-P(t | s)` at this position of the values.
    Inside(usize),
    /// Into the target (value 0): only into the exits.
    Leaving,
    /// A self-loop, or an entry of an action not kept.
    Unused,
}

/// The systems `(I - Q_sigma) x = r_sigma` of the strategies on the
/// unknowns (kept actions only), on the union of their patterns.
struct PolicySystem {
    unknowns: Vec<usize>,
    /// The position of each state among the unknowns (`usize::MAX` if none).
    index: Vec<usize>,
    slots: Vec<Slot>,
    /// Per global action: whether policy iteration may play it.
    kept: Vec<bool>,
    solver: Option<LinearSolver>,
}

impl PolicySystem {
    fn new(
        mdp: &Mdp,
        unknowns: &[usize],
        kept: &[bool],
        settings: &SolverSettings,
    ) -> Result<Self, MdpError> {
        let mut index = vec![usize::MAX; mdp.num_states()];
        for (i, &s) in unknowns.iter().enumerate() {
            index[s] = i;
        }
        let mut row_offsets = vec![0];
        let mut columns = Vec::new();
        let mut slots = vec![Slot::Unused; mdp.entries.len()];
        for (i, &s) in unknowns.iter().enumerate() {
            let row_start = columns.len();
            columns.push(i);
            for action in mdp.global_actions(s).filter(|&a| kept[a]) {
                columns.extend(
                    mdp.global_distribution(action)
                        .iter()
                        .filter(|&&(t, _)| t != s && index[t] != usize::MAX)
                        .map(|&(t, _)| index[t]),
                );
            }
            columns[row_start..].sort_unstable();
            let mut row: Vec<usize> = columns.drain(row_start..).collect();
            row.dedup();
            for action in mdp.global_actions(s).filter(|&a| kept[a]) {
                let entries = mdp.entry_offsets[action]..mdp.entry_offsets[action + 1];
                for (slot, &(t, _)) in slots[entries.clone()].iter_mut().zip(&mdp.entries[entries])
                {
                    *slot = if t == s {
                        Slot::Unused
                    } else if index[t] == usize::MAX {
                        Slot::Leaving
                    } else {
                        let offset = row
                            .binary_search(&index[t])
                            .expect("every kept edge among the unknowns is in the pattern");
                        Slot::Inside(row_start + offset)
                    };
                }
            }
            columns.extend(row);
            row_offsets.push(columns.len());
        }
        let pattern = SparsePattern {
            n: unknowns.len(),
            row_offsets,
            columns,
        };
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
                            Slot::Leaving => exits[i] += p,
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
    fn iterate(
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
    fn expected_steps(&mut self) -> Result<Vec<f64>, MdpError> {
        let mut steps = vec![0.0; self.unknowns.len()];
        if let Some(solver) = &mut self.solver {
            let ones = vec![1.0; self.unknowns.len()];
            solver.solve_unbounded(&ones, &mut steps)?;
        }
        Ok(steps)
    }
}

/// What the certificate's check reads: the kept actions, the rewards and
/// the direction.
struct Scale<'a> {
    kept: &'a [bool],
    rewards: &'a [f64],
    optimum: Optimum,
}

/// The values of the unknowns read by state: 0 on the target.
struct ByState<'a> {
    index: Vec<usize>,
    values: &'a [f64],
}

impl<'a> ByState<'a> {
    fn new(mdp: &Mdp, unknowns: &[usize], values: &'a [f64]) -> Self {
        let mut index = vec![usize::MAX; mdp.num_states()];
        for (i, &s) in unknowns.iter().enumerate() {
            index[s] = i;
        }
        Self { index, values }
    }

    fn at(&self, t: usize) -> f64 {
        match self.index[t] {
            usize::MAX => 0.0,
            i => self.values[i],
        }
    }

    /// `c + sum_{t != s} P(t | action) (v(t) - v(s))` for unknown `s`
    /// (position `i`), the Bellman gap of the model the policy systems
    /// solve (whose diagonal is the probability of leaving `s`, method.md
    /// section 8), and the sum of its terms' magnitudes (for its rounding).
    fn advance(
        &self,
        mdp: &Mdp,
        (s, i, action): (usize, usize, usize),
        constant: f64,
    ) -> (f64, f64) {
        let here = self.values[i];
        let (mut sum, mut size) = (constant, constant.abs());
        for &(t, p) in mdp
            .global_distribution(action)
            .iter()
            .filter(|&&(t, _)| t != s)
        {
            let there = self.at(t);
            sum += p * (there - here);
            size += p * (there.abs() + here.abs());
        }
        (sum, size)
    }
}

impl Scale<'_> {
    /// The kept actions whose gain `+-(r + P x - x)` is at least `-tau`
    /// (the others lose more than `tau` against `x`).
    fn near_optimal(&self, mdp: &Mdp, unknowns: &[usize], x: &[f64], tau: f64) -> Vec<bool> {
        let values = ByState::new(mdp, unknowns, x);
        let mut near = vec![false; mdp.num_state_actions()];
        for (i, &s) in unknowns.iter().enumerate() {
            for action in mdp.global_actions(s).filter(|&a| self.kept[a]) {
                let (gain, _) = values.advance(mdp, (s, i, action), self.rewards[action]);
                near[action] = self.optimum.sign() * gain >= -tau;
            }
        }
        near
    }

    /// `y = x + eps T` (`x - eps T` for a minimum) on the unknowns, with
    /// the smallest `eps >= 0` whose check passes for every kept action
    /// (module documentation, step 3); `None` where none does.
    fn certify(
        &self,
        mdp: &Mdp,
        unknowns: &[usize],
        x: &[f64],
        steps: &[f64],
    ) -> Result<Option<Vec<f64>>, MdpError> {
        let values = ByState::new(mdp, unknowns, x);
        let potential = ByState::new(mdp, unknowns, steps);
        let sign = self.optimum.sign();
        // Each constraint `g <= eps d`, with `g` rounded up and `d` down.
        let (mut least, mut most) = (0.0_f64, f64::INFINITY);
        for (i, &s) in unknowns.iter().enumerate() {
            for action in mdp.global_actions(s).filter(|&a| self.kept[a]) {
                let (gain, gain_size) = values.advance(mdp, (s, i, action), self.rewards[action]);
                let (rise, rise_size) = potential.advance(mdp, (s, i, action), 0.0);
                let terms = mdp.global_distribution(action).len() + 3;
                let rounding = terms as f64 * UNIT_ROUNDOFF * 1.01;
                let g = sign * gain + rounding * gain_size;
                let d = -rise - rounding * rise_size;
                if !(g.is_finite() && d.is_finite()) {
                    // A potential or a value that is not finite proves
                    // nothing.
                    return Ok(None);
                }
                if d > 0.0 {
                    least = least.max(g / d * (1.0 + 4.0 * UNIT_ROUNDOFF));
                } else if g > 0.0 {
                    return Ok(None);
                } else if d < 0.0 {
                    most = most.min(g / d);
                }
            }
        }
        if !least.is_finite() || least > most * (1.0 - 4.0 * UNIT_ROUNDOFF) {
            return Ok(None);
        }
        let eps = least;
        Ok(Some(
            x.iter()
                .zip(steps)
                .map(|(&v, &t)| {
                    let y = v + sign * eps * t;
                    let rounding = 4.0 * UNIT_ROUNDOFF * (v.abs() + eps * t.abs());
                    y + sign * (rounding + f64::MIN_POSITIVE)
                })
                .collect(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::mdp;
    use super::*;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn settings() -> SolverSettings {
        SolverSettings::default()
    }

    /// State 0 may go on (action 0: to 1, reward 2) or gamble (action 1:
    /// the target 2 or back to 0, half each, reward 1); 1 goes to the
    /// target with reward 3 or back to 0 with probability 1/4. On paper,
    /// with `x1 = 3 + x0 / 4`: on, `x0 = 2 + x1 = 5 + x0 / 4`, `x0 = 20/3`;
    /// gamble, `x0 = 1 + x0 / 2`, `x0 = 2`. The maximum is 20/3 (and
    /// `x1 = 14/3`), the minimum 2 (and `x1 = 3.5`).
    fn on_or_gamble() -> (Mdp, Vec<bool>, Vec<f64>) {
        let m = mdp(&[
            &[&[(1, 1.0)], &[(2, 0.5), (0, 0.5)]],
            &[&[(2, 0.75), (0, 0.25)]],
            &[&[(2, 1.0)]],
        ]);
        (m, vec![false, false, true], vec![2.0, 1.0, 3.0, 0.0])
    }

    #[test]
    fn the_optima_of_a_small_mdp_are_those_on_paper() {
        let (m, target, rewards) = on_or_gamble();
        let max = optimal_total_reward(&m, &target, &rewards, Optimum::Max, &settings()).unwrap();
        let min = optimal_total_reward(&m, &target, &rewards, Optimum::Min, &settings()).unwrap();
        for (bracket, expected) in [
            ((max.lower[0], max.upper[0]), 20.0 / 3.0),
            ((max.lower[1], max.upper[1]), 14.0 / 3.0),
            ((min.lower[0], min.upper[0]), 2.0),
            ((min.lower[1], min.upper[1]), 3.5),
        ] {
            assert!(
                bracket.0 <= expected && expected <= bracket.1,
                "{bracket:?} {expected}"
            );
            assert!(bracket.1 - bracket.0 < 1e-9, "{bracket:?}");
        }
        assert_eq!((max.strategy[0], min.strategy[0]), (0, 1));
        assert_eq!((max.lower[2], max.upper[2]), (0.0, 0.0));
    }

    /// State 0 may loop (action 0) or go to the target (action 1). The
    /// maximum is infinite (looping misses the target); the minimum is
    /// action 1's reward where the loop earns a positive reward or nothing
    /// (collapsed: staying forever is not a way out), and refused where it
    /// loses (the minimum is `-inf`).
    #[test]
    fn a_loop_makes_the_maximum_infinite_and_the_minimum_refused_unless_it_costs() {
        let m = mdp(&[&[&[(0, 1.0)], &[(1, 1.0)]], &[&[(1, 1.0)]]]);
        let target = [false, true];
        let max = optimal_total_reward(&m, &target, &[1.0, 5.0, 0.0], Optimum::Max, &settings());
        assert_eq!(
            max.unwrap().of_initial(&[(0, 1.0)]),
            (f64::INFINITY, f64::INFINITY)
        );
        let min = optimal_total_reward(&m, &target, &[1.0, 5.0, 0.0], Optimum::Min, &settings());
        let (low, high) = min.unwrap().of_initial(&[(0, 1.0)]);
        assert!(low <= 5.0 && 5.0 <= high && high - low < 1e-9);
        let free = optimal_total_reward(&m, &target, &[0.0, 5.0, 0.0], Optimum::Min, &settings());
        let free = free.unwrap();
        assert_eq!(free.strategy[0], 1);
        let (low, high) = free.of_initial(&[(0, 1.0)]);
        assert!(low <= 5.0 && 5.0 <= high && high - low < 1e-9);
        let losing = [-1.0, 5.0, 0.0];
        let min = optimal_total_reward(&m, &target, &losing, Optimum::Min, &settings());
        assert!(matches!(min, Err(MdpError::RewardCycle(_))), "{min:?}");
    }

    /// State 0 moves to 1 for nothing (action 0) or pays 10 for the target
    /// (action 1); 1 moves back to 0 for 1 (action 0) or pays 5 for the
    /// target (action 1). Every round of the cycle earns 1, though one of
    /// its actions earns nothing: the minimum is attained, 5 from both.
    #[test]
    fn a_free_action_on_a_cycle_that_costs_is_accepted() {
        let m = mdp(&[
            &[&[(1, 1.0)], &[(2, 1.0)]],
            &[&[(0, 1.0)], &[(2, 1.0)]],
            &[&[(2, 1.0)]],
        ]);
        let rewards = [0.0, 10.0, 1.0, 5.0, 0.0];
        let min = optimal_total_reward(
            &m,
            &[false, false, true],
            &rewards,
            Optimum::Min,
            &settings(),
        )
        .unwrap();
        for s in 0..2 {
            assert!(min.lower[s] <= 5.0 && 5.0 <= min.upper[s], "{min:?}");
            assert!(min.upper[s] - min.lower[s] < 1e-9, "{min:?}");
        }
        assert_eq!(min.strategy[..2], [0, 1]);
    }

    /// A random MDP: `n` states, the last one the target (absorbing), each
    /// other with 1 to 3 actions of 1 to 3 successors, and a reward per
    /// action drawn from `rewards`.
    fn random_mdp(seed: u64, n: usize, rewards: (f64, f64)) -> (Mdp, Vec<bool>, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut actions: Vec<Vec<Vec<(usize, f64)>>> = Vec::new();
        for _ in 0..n - 1 {
            let k = rng.random_range(1..=3);
            actions.push(
                (0..k)
                    .map(|_| {
                        let successors = rng.random_range(1..=3);
                        let weights: Vec<(usize, f64)> = (0..successors)
                            .map(|_| (rng.random_range(0..n), rng.random_range(1..=4) as f64))
                            .collect();
                        let total: f64 = weights.iter().map(|w| w.1).sum();
                        weights.iter().map(|&(t, w)| (t, w / total)).collect()
                    })
                    .collect(),
            );
        }
        actions.push(vec![vec![(n - 1, 1.0)]]);
        let borrowed: Vec<Vec<&[(usize, f64)]>> = actions
            .iter()
            .map(|state| state.iter().map(Vec::as_slice).collect())
            .collect();
        let nested: Vec<&[&[(usize, f64)]]> = borrowed.iter().map(Vec::as_slice).collect();
        let m = mdp(&nested);
        let mut target = vec![false; n];
        target[n - 1] = true;
        let r = (0..m.num_state_actions())
            .map(|_| (rng.random_range(rewards.0..rewards.1) * 4.0).round() / 4.0)
            .collect();
        (m, target, r)
    }

    /// The value of every deterministic memoryless strategy by Gaussian
    /// elimination (`+inf` where it misses the target with positive
    /// probability), then the optimum per state: independent of the
    /// policy iteration and of the graph analyses above.
    fn brute_force(m: &Mdp, target: &[bool], rewards: &[f64], optimum: Optimum) -> Vec<f64> {
        let n = m.num_states();
        let mut best = vec![
            match optimum {
                Optimum::Max => f64::NEG_INFINITY,
                Optimum::Min => f64::INFINITY,
            };
            n
        ];
        let mut choice = vec![0; n];
        loop {
            let values = strategy_values(m, target, rewards, &choice);
            for s in 0..n {
                best[s] = match optimum {
                    Optimum::Max => best[s].max(values[s]),
                    Optimum::Min => best[s].min(values[s]),
                };
            }
            let Some(s) = (0..n).find(|&s| choice[s] + 1 < m.num_actions(s)) else {
                return best;
            };
            choice[s] += 1;
            choice[..s].fill(0);
        }
    }

    fn strategy_values(m: &Mdp, target: &[bool], rewards: &[f64], choice: &[usize]) -> Vec<f64> {
        let n = m.num_states();
        // The states that reach the target surely: those from which every
        // path that avoids the target can still reach it.
        let mut reaches = target.to_vec();
        loop {
            let before = reaches.clone();
            for s in 0..n {
                reaches[s] |= m
                    .distribution(s, choice[s])
                    .iter()
                    .any(|&(t, _)| reaches[t]);
            }
            if reaches == before {
                break;
            }
        }
        let mut sure: Vec<bool> = reaches.clone();
        loop {
            let before = sure.clone();
            for s in (0..n).filter(|&s| !target[s]) {
                sure[s] &= m.distribution(s, choice[s]).iter().all(|&(t, _)| sure[t]);
            }
            if sure == before {
                break;
            }
        }
        let unknowns: Vec<usize> = (0..n).filter(|&s| sure[s] && !target[s]).collect();
        let k = unknowns.len();
        let mut a = vec![vec![0.0; k + 1]; k];
        for (i, &s) in unknowns.iter().enumerate() {
            a[i][i] += 1.0;
            a[i][k] = rewards[m.global_actions(s).start + choice[s]];
            for &(t, p) in m.distribution(s, choice[s]) {
                if let Some(j) = unknowns.iter().position(|&u| u == t) {
                    a[i][j] -= p;
                }
            }
        }
        for col in 0..k {
            let pivot = (col..k)
                .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
                .unwrap();
            a.swap(col, pivot);
            let pivot_row = a[col].clone();
            for (_, entries) in a.iter_mut().enumerate().filter(|&(row, _)| row != col) {
                let factor = entries[col] / pivot_row[col];
                for (entry, &p) in entries[col..].iter_mut().zip(&pivot_row[col..]) {
                    *entry -= factor * p;
                }
            }
        }
        let mut values: Vec<f64> = (0..n)
            .map(|s| if target[s] { 0.0 } else { f64::INFINITY })
            .collect();
        for (i, &s) in unknowns.iter().enumerate() {
            values[s] = a[i][k] / a[i][i];
        }
        values
    }

    fn assert_brackets(result: &TotalReward, expected: &[f64]) {
        for (s, &e) in expected.iter().enumerate() {
            let (low, high) = (result.lower[s], result.upper[s]);
            if e.is_infinite() {
                assert!(
                    low.is_infinite() && high.is_infinite(),
                    "state {s}: {low} {high} {e}"
                );
            } else {
                let slack = 1e-9 * e.abs().max(1.0);
                assert!(
                    low <= e + slack && e <= high + slack,
                    "state {s}: [{low}, {high}] {e}"
                );
                assert!(
                    high - low <= 1e-7 * e.abs().max(1.0),
                    "state {s}: [{low}, {high}]"
                );
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn the_maximum_is_the_best_strategy_s(seed in any::<u64>(), n in 2usize..7) {
            let (m, target, rewards) = random_mdp(seed, n, (-2.0, 3.0));
            let result = optimal_total_reward(&m, &target, &rewards, Optimum::Max, &settings()).unwrap();
            assert_brackets(&result, &brute_force(&m, &target, &rewards, Optimum::Max));
        }

        #[test]
        fn the_minimum_of_positive_rewards_is_the_best_strategy_s(seed in any::<u64>(), n in 2usize..7) {
            let (m, target, rewards) = random_mdp(seed, n, (0.25, 3.0));
            let result = optimal_total_reward(&m, &target, &rewards, Optimum::Min, &settings()).unwrap();
            assert_brackets(&result, &brute_force(&m, &target, &rewards, Optimum::Min));
        }

        /// Rewards of 0 a third of the time: the free end components are
        /// collapsed, and nothing is refused.
        #[test]
        fn the_minimum_of_rewards_that_never_lose_is_the_best_strategy_s(seed in any::<u64>(), n in 2usize..7) {
            let (m, target, rewards) = random_mdp(seed, n, (-1.0, 2.0));
            let rewards: Vec<f64> = rewards.iter().map(|r| r.max(0.0)).collect();
            let result = optimal_total_reward(&m, &target, &rewards, Optimum::Min, &settings()).unwrap();
            assert_brackets(&result, &brute_force(&m, &target, &rewards, Optimum::Min));
            let played = strategy_values(&m, &target, &rewards, &result.strategy);
            assert_brackets(&result, &played);
        }

        #[test]
        fn a_minimum_of_either_sign_is_right_or_refused(seed in any::<u64>(), n in 2usize..7) {
            let (m, target, rewards) = random_mdp(seed, n, (-2.0, 3.0));
            match optimal_total_reward(&m, &target, &rewards, Optimum::Min, &settings()) {
                Ok(result) => assert_brackets(&result, &brute_force(&m, &target, &rewards, Optimum::Min)),
                Err(e) => prop_assert!(matches!(e, MdpError::RewardCycle(_)), "{e}"),
            }
        }
    }
}
