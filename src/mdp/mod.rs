//! Markov decision processes (MDPs) and the analyses behind the certified
//! bounds of method.md section 6.
//!
//! An [`Mdp`] has states `0..n`; state `s` offers actions `0..k_s` (local
//! numbers, `k_s >= 1`), and action `a` in `s` is a distribution
//! `P(. | s, a)` over successors. One player resolves the choices; the other
//! player's controller and the game's randomness are already inside `P`.
//!
//! Three analyses build on each other:
//!
//! * [`maximal_end_components`] ([`end_components`]): the maximal end
//!   components (MECs) inside a set of states, by iterated strongly connected
//!   component decomposition (Baier and Katoen, *Principles of Model
//!   Checking*, Algorithm 47);
//! * [`max_reachability`] ([`reachability`]): `sup_sigma P^sigma(reach target)`
//!   for every state, exact, by policy iteration with sparse LU evaluations;
//! * [`max_rabin_analysis`] ([`rabin`]): `sup_sigma P^sigma(Rabin)`, the
//!   maximum reachability probability of the union of the accepting end
//!   components (per pair `(L_i, K_i)`: the MECs of the sub-MDP without `L_i`
//!   that meet `K_i`), with an optimal deterministic memoryless strategy.

pub mod end_components;
mod optimality;
mod pattern;
pub mod rabin;
pub mod reachability;
pub mod total_reward;

pub use end_components::{EndComponent, maximal_end_components, maximal_end_components_using};
pub use rabin::{
    AcceptingComponent, accepting_end_components, accepting_union, max_rabin_analysis,
    max_rabin_qualitative,
};
pub use reachability::{
    PolicySystems, QualitativeReachability, Reachability, max_reachability, max_reachability_with,
    qualitative_reachability,
};
pub use total_reward::{Optimum, optimal_total_reward};

use thiserror::Error;

use crate::graph::Digraph;
use crate::solver::SolverError;

/// How far a distribution's sum may be from 1 when an [`Mdp`] is built.
pub const SUM_TOLERANCE: f64 = 1e-9;

/// Why an MDP could not be built or analysed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MdpError {
    /// The states, actions or distributions are inconsistent.
    #[error("malformed MDP: {0}")]
    Malformed(String),
    /// A policy evaluation could not be solved accurately.
    #[error("solving a policy evaluation of the best response (method.md section 6): {0}")]
    Solver(#[from] SolverError),
    /// Policy iteration kept improving for too long (a numerical problem).
    #[error("policy iteration did not stabilise within {0} iterations")]
    NotConverged(usize),
    /// The optimality of policy iteration's result could not be proved
    /// (method.md section 6, the optimality certificate).
    #[error("the optimum of the best response could not be proved: {0}")]
    OptimalityUnproved(String),
    /// An expected total reward whose optimum this analysis does not prove:
    /// an end component outside the target with an action that earns
    /// nothing or less (method.md section 9).
    #[error("the optimal expected reward is not computed here: {0}")]
    RewardCycle(String),
}

impl MdpError {
    /// State `s` has no action: every state of an MDP needs one.
    pub(crate) fn no_action(s: usize) -> Self {
        Self::Malformed(format!("state {s} has no action"))
    }
}

/// A finite MDP in compressed form: the actions of state `s` are the global
/// actions `action_offsets[s]..action_offsets[s + 1]`, and global action `a`
/// has the successors `entries[entry_offsets[a]..entry_offsets[a + 1]]`:
/// distinct states with positive probabilities summing to 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Mdp {
    action_offsets: Vec<usize>,
    entry_offsets: Vec<usize>,
    entries: Vec<(usize, f64)>,
}

impl Mdp {
    /// `n`, the number of states.
    pub fn num_states(&self) -> usize {
        self.action_offsets.len() - 1
    }

    /// `k_s`, the number of actions of state `s`.
    pub fn num_actions(&self, s: usize) -> usize {
        self.action_offsets[s + 1] - self.action_offsets[s]
    }

    /// The total number of state-action pairs.
    pub fn num_state_actions(&self) -> usize {
        self.entry_offsets.len() - 1
    }

    /// `P(. | s, a)` as `(successor, probability)` pairs: distinct successors,
    /// positive probabilities.
    pub fn distribution(&self, s: usize, a: usize) -> &[(usize, f64)] {
        self.global_distribution(self.action_offsets[s] + a)
    }

    /// Whether `other` has the same states, actions and successors (its
    /// probabilities aside): then every graph analysis of one (end
    /// components, qualitative reachability) holds for the other.
    pub fn same_graph(&self, other: &Mdp) -> bool {
        self.action_offsets == other.action_offsets
            && self.entry_offsets == other.entry_offsets
            && self
                .entries
                .iter()
                .zip(&other.entries)
                .all(|(a, b)| a.0 == b.0)
    }

    /// Overwrites the probabilities, entry after entry in the order of
    /// [`Mdp::distribution`] over states and actions, keeping the graph,
    /// after the checks [`MdpBuilder::build`] makes on them (one positive,
    /// finite value per entry, each action's summing to 1 within
    /// [`SUM_TOLERANCE`]); on an error nothing is written.
    pub(crate) fn set_probabilities(&mut self, probabilities: &[f64]) -> Result<(), MdpError> {
        if probabilities.len() != self.entries.len() {
            return Err(MdpError::Malformed(format!(
                "{} probabilities for {} transitions",
                probabilities.len(),
                self.entries.len()
            )));
        }
        for s in 0..self.num_states() {
            for (a, action) in self.global_actions(s).enumerate() {
                let range = self.entry_offsets[action]..self.entry_offsets[action + 1];
                check_probabilities(probabilities[range].iter().copied())
                    .map_err(|m| MdpError::Malformed(format!("state {s}, action {a}: {m}")))?;
            }
        }
        for (entry, &p) in self.entries.iter_mut().zip(probabilities) {
            entry.1 = p;
        }
        Ok(())
    }

    fn global_distribution(&self, action: usize) -> &[(usize, f64)] {
        &self.entries[self.entry_offsets[action]..self.entry_offsets[action + 1]]
    }

    /// The global indices of the actions of state `s`.
    pub(crate) fn global_actions(&self, s: usize) -> std::ops::Range<usize> {
        self.action_offsets[s]..self.action_offsets[s + 1]
    }

    /// For every state, the `(predecessor, local action)` pairs whose
    /// distribution reaches it.
    pub(crate) fn predecessors(&self) -> Predecessors {
        let n = self.num_states();
        let mut offsets = vec![0usize; n + 1];
        for &(t, _) in &self.entries {
            offsets[t + 1] += 1;
        }
        for t in 0..n {
            offsets[t + 1] += offsets[t];
        }
        let mut fill = offsets.clone();
        let mut sources = vec![(0, 0); self.entries.len()];
        for s in 0..n {
            for a in 0..self.num_actions(s) {
                for &(t, _) in self.distribution(s, a) {
                    sources[fill[t]] = (s, a);
                    fill[t] += 1;
                }
            }
        }
        Predecessors { offsets, sources }
    }
}

/// The reverse graph of an MDP, remembering the action of each edge.
pub(crate) struct Predecessors {
    offsets: Vec<usize>,
    sources: Vec<(usize, usize)>,
}

impl Predecessors {
    /// The `(s, a)` with `P(t | s, a) > 0`.
    pub(crate) fn of(&self, t: usize) -> &[(usize, usize)] {
        &self.sources[self.offsets[t]..self.offsets[t + 1]]
    }
}

impl Digraph for Predecessors {
    fn num_vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        self.of(v).iter().map(|&(s, _)| s)
    }
}

/// Builds an [`Mdp`] state by state: [`MdpBuilder::add_action`] for each
/// action of the current state, then [`MdpBuilder::end_state`].
#[derive(Debug, Clone)]
pub struct MdpBuilder {
    mdp: Mdp,
    scratch: Vec<(usize, f64)>,
}

impl Default for MdpBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl MdpBuilder {
    /// An empty MDP.
    pub fn new() -> Self {
        Self {
            mdp: Mdp {
                action_offsets: vec![0],
                entry_offsets: vec![0],
                entries: Vec::new(),
            },
            scratch: Vec::new(),
        }
    }

    /// Adds an action to the current state with the distribution `terms`:
    /// `(successor, probability)` pairs, where repeated successors are summed
    /// and zero probabilities dropped.
    pub fn add_action(&mut self, terms: impl IntoIterator<Item = (usize, f64)>) {
        self.scratch.clear();
        self.scratch.extend(terms);
        self.scratch.sort_by_key(|&(t, _)| t);
        let mdp = &mut self.mdp;
        let start = mdp.entries.len();
        for &(t, p) in self.scratch.iter().filter(|&&(_, p)| p != 0.0) {
            match mdp.entries[start..].last_mut() {
                Some(last) if last.0 == t => last.1 += p,
                _ => mdp.entries.push((t, p)),
            }
        }
        mdp.entry_offsets.push(mdp.entries.len());
    }

    /// Closes the current state: the actions added since the last call are its actions.
    pub fn end_state(&mut self) {
        let actions = self.mdp.entry_offsets.len() - 1;
        self.mdp.action_offsets.push(actions);
    }

    /// Checks and returns the MDP: every state has an action, every
    /// successor is a state, every probability is finite and positive, and
    /// every distribution sums to 1 within [`SUM_TOLERANCE`].
    pub fn build(self) -> Result<Mdp, MdpError> {
        let mdp = self.mdp;
        if mdp.action_offsets.last() != Some(&(mdp.entry_offsets.len() - 1)) {
            return Err(MdpError::Malformed(
                "actions were added after the last state was closed".into(),
            ));
        }
        let n = mdp.num_states();
        for s in 0..n {
            if mdp.num_actions(s) == 0 {
                return Err(MdpError::no_action(s));
            }
            for a in 0..mdp.num_actions(s) {
                check_distribution(mdp.distribution(s, a), n)
                    .map_err(|m| MdpError::Malformed(format!("state {s}, action {a}: {m}")))?;
            }
        }
        Ok(mdp)
    }
}

fn check_distribution(distribution: &[(usize, f64)], n: usize) -> Result<(), String> {
    if let Some(&(t, _)) = distribution.iter().find(|&&(t, _)| t >= n) {
        return Err(format!("successor {t} is not a state"));
    }
    check_probabilities(distribution.iter().map(|&(_, p)| p))
}

/// Every probability positive and finite, their sum 1 within
/// [`SUM_TOLERANCE`].
fn check_probabilities(probabilities: impl Iterator<Item = f64> + Clone) -> Result<(), String> {
    if let Some(p) = probabilities.clone().find(|&p| !(p > 0.0 && p.is_finite())) {
        return Err(format!("probability {p} is not positive and finite"));
    }
    let total: f64 = probabilities.sum();
    if (total - 1.0).abs() > SUM_TOLERANCE {
        return Err(format!("probabilities sum to {total}, not 1"));
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An MDP from `actions[s][a]` = list of `(successor, probability)`.
    pub(crate) fn mdp(actions: &[&[&[(usize, f64)]]]) -> Mdp {
        let mut builder = MdpBuilder::new();
        for state in actions {
            for &action in *state {
                builder.add_action(action.iter().copied());
            }
            builder.end_state();
        }
        builder.build().unwrap()
    }

    #[test]
    fn repeated_successors_are_summed_and_zeros_dropped() {
        let m = mdp(&[
            &[&[(1, 0.25), (0, 0.0), (1, 0.25), (0, 0.5)]],
            &[&[(1, 1.0)]],
        ]);
        assert_eq!(m.distribution(0, 0), &[(0, 0.5), (1, 0.5)]);
        assert_eq!(m.num_state_actions(), 2);
    }

    #[test]
    fn a_state_without_actions_is_an_error() {
        let mut builder = MdpBuilder::new();
        builder.end_state();
        assert!(matches!(builder.build(), Err(MdpError::Malformed(_))));
    }

    #[test]
    fn a_distribution_not_summing_to_one_is_an_error() {
        let mut builder = MdpBuilder::new();
        builder.add_action([(0, 0.7)]);
        builder.end_state();
        assert!(matches!(builder.build(), Err(MdpError::Malformed(_))));
    }

    #[test]
    fn a_successor_out_of_range_is_an_error() {
        let mut builder = MdpBuilder::new();
        builder.add_action([(3, 1.0)]);
        builder.end_state();
        assert!(matches!(builder.build(), Err(MdpError::Malformed(_))));
    }
}
