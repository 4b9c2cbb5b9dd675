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

mod certificate;
mod policy;
#[cfg(test)]
mod tests;

use super::{
    EndComponent, Mdp, MdpBuilder, MdpError, maximal_end_components, maximal_end_components_using,
    qualitative_reachability,
};
use crate::solver::SolverSettings;
use certificate::Scale;
use policy::{PolicySystem, longest_steps, proper_start};

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
    let region = Region::of(mdp, target, optimum)?;
    if optimum == Optimum::Min {
        let free = region.free_components(mdp, rewards);
        if !free.is_empty() {
            return collapsed(mdp, target, rewards, &free, settings);
        }
        check_losing_cycles(mdp, &region, rewards)?;
    }
    optimum_on(mdp, target, rewards, (optimum, &region), settings)
}

/// The states and actions policy iteration works on (module
/// documentation, step 1).
struct Region {
    /// The finite states outside the target, increasing.
    unknowns: Vec<usize>,
    /// Per global action: whether all its successors are finite (the
    /// actions policy iteration may play).
    kept: Vec<bool>,
}

impl Region {
    /// The region of `optimum` for `target`.
    fn of(mdp: &Mdp, target: &[bool], optimum: Optimum) -> Result<Self, MdpError> {
        let finite = finite_states(mdp, target, optimum)?;
        let kept = (0..mdp.num_state_actions())
            .map(|a| mdp.global_distribution(a).iter().all(|&(t, _)| finite[t]))
            .collect();
        let unknowns = (0..mdp.num_states())
            .filter(|&s| finite[s] && !target[s])
            .collect();
        Ok(Self { unknowns, kept })
    }

    /// The end components among the unknowns whose actions earn nothing
    /// (kept actions of reward 0): a minimiser moves inside one for free.
    fn free_components(&self, mdp: &Mdp, rewards: &[f64]) -> Vec<EndComponent> {
        let free: Vec<bool> = (self.kept.iter().zip(rewards))
            .map(|(&k, &r)| k && r == 0.0)
            .collect();
        components_within(mdp, &self.unknowns, &free)
    }
}

/// [`optimal_total_reward`] on `region`, where no end component of actions
/// that earn nothing or less lies among a minimum's unknowns (module
/// documentation, steps 2 and 3).
fn optimum_on(
    mdp: &Mdp,
    target: &[bool],
    rewards: &[f64],
    (optimum, region): (Optimum, &Region),
    settings: &SolverSettings,
) -> Result<TotalReward, MdpError> {
    let n = mdp.num_states();
    let Region { unknowns, kept } = region;
    let mut strategy = proper_start(mdp, target, unknowns, kept)?;
    let largest = rewards.iter().fold(1.0_f64, |m, r| m.max(r.abs()));
    let scaled = SolverSettings {
        tolerance: settings.tolerance * largest,
        ..*settings
    };
    let mut system = PolicySystem::new(mdp, target, (unknowns, kept), &scaled)?;
    let threshold = REWARD_IMPROVEMENT_THRESHOLD * largest;
    let (values, error) =
        system.iterate(mdp, rewards, (optimum, threshold), true, &mut strategy)?;
    let steps = system.expected_steps()?;
    let scale = Scale {
        unknowns,
        index: system.index(),
        kept,
        rewards,
        optimum,
    };
    let certified = match scale.certify(mdp, &values, &steps)? {
        Some(y) => y,
        None => {
            let near = scale.near_optimal(mdp, &values, NEAR_OPTIMAL * largest);
            let longest = longest_steps(mdp, target, unknowns, &near, &scaled)?;
            longest
                .and_then(|longest| scale.certify(mdp, &values, &longest).transpose())
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

/// The minimum where the end components `free` earn nothing (Storm's
/// collapse): the minimiser moves inside each for free, so every state of
/// one has the same optimum, that of the best way out. The quotient MDP
/// has one state per component, with the actions of its states that are
/// not the component's own free ones (a positive reward inside it becomes
/// a self-loop that costs); its optimum, brackets included, is the
/// original's. The strategy leaves a component by the quotient's chosen
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
    // A free component of the quotient would make a larger one of the
    // original: the quotient has none.
    let region = Region::of(&quotient, &quotient_target, Optimum::Min)?;
    check_losing_cycles(&quotient, &region, &quotient_rewards)?;
    let solved = optimum_on(
        &quotient,
        &quotient_target,
        &quotient_rewards,
        (Optimum::Min, &region),
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

/// An error where an end component among a minimum's unknowns (with kept
/// actions only) has an action that earns a negative reward (module
/// documentation, step 1). Once the free components are collapsed, what
/// passes has a positive reward on every round of every end component:
/// each round uses an action that earns something, and none loses.
fn check_losing_cycles(mdp: &Mdp, region: &Region, rewards: &[f64]) -> Result<(), MdpError> {
    for component in components_within(mdp, &region.unknowns, &region.kept) {
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
    Ok(())
}
