//! One player's action mixture (method.md's `A_*`, the paper's sum over
//! observations in `T^{phi,C_def,C_adv}`):
//!
//! ```text
//! A(g', u | s, g) = sum_o O(o | s) mu(g', u | g, o),
//! ```
//!
//! the probability that the controller in node `g`, in game state `s`, moves
//! to node `g'` and plays `u`. The global Markov chain ([`crate::product`])
//! and the certification products ([`crate::certify`]) are built from it.

use super::{Fsc, Support};
use crate::game::Player;

/// The mixture on a fixed support: for each `(s, g)` the distinct supported
/// `(g', u)` in increasing order, each with the terms `(support entry k,
/// O(o | s))` whose products with `mu_k` sum to it (in observation order,
/// then support order), and its value for the probabilities of the last
/// [`Mixture::refill`].
#[derive(Debug, Clone)]
pub(crate) struct Mixture {
    num_nodes: usize,
    offsets: Vec<usize>,
    entries: Vec<(u32, u32)>,
    term_offsets: Vec<usize>,
    /// The support entry `k` of each term.
    term_entries: Vec<u32>,
    /// The weight `O(o | s)` of each term.
    term_weights: Vec<f64>,
    values: Vec<f64>,
}

/// The key sorting a term of support entry `(g', u)` met at position
/// `met`: by `g'`, then `u`, then `met` (32 bits each).
fn sort_key((next, action): (usize, usize), met: usize) -> u128 {
    ((next as u128) << 64) | ((action as u128) << 32) | met as u128
}

impl Mixture {
    /// The mixture's entries and terms for `player` on `support`, over game
    /// states `0..num_states`; every value is 0 until [`Mixture::refill`].
    pub(crate) fn build(player: &Player, support: &Support, num_states: usize) -> Self {
        let num_nodes = support.num_nodes();
        let most_terms = Self::count_terms(player, support, num_states);
        let mut offsets = Vec::with_capacity(num_states * num_nodes + 1);
        offsets.push(0);
        let mut entries = Vec::with_capacity(most_terms);
        let mut term_offsets = Vec::with_capacity(most_terms + 1);
        term_offsets.push(0);
        let mut term_entries = Vec::with_capacity(most_terms);
        let mut term_weights = Vec::with_capacity(most_terms);
        let mut met: Vec<(u32, f64)> = Vec::new();
        let mut order: Vec<u128> = Vec::new();
        for s in 0..num_states {
            for g in 0..num_nodes {
                met.clear();
                order.clear();
                for &(o, weight) in player.observation_distribution(s) {
                    for k in support.block(g, o) {
                        order.push(sort_key(support.entry(k), met.len()));
                        met.push((k as u32, weight));
                    }
                }
                // The met position breaks ties: an entry's terms keep the
                // order in which they were met.
                order.sort_unstable();
                for group in order.chunk_by(|a, b| a >> 32 == b >> 32) {
                    entries.push(((group[0] >> 64) as u32, (group[0] >> 32) as u32));
                    for &key in group {
                        let (k, weight) = met[key as u32 as usize];
                        term_entries.push(k);
                        term_weights.push(weight);
                    }
                    term_offsets.push(term_entries.len());
                }
                offsets.push(entries.len());
            }
        }
        let values = vec![0.0; entries.len()];
        Self {
            num_nodes,
            offsets,
            entries,
            term_offsets,
            term_entries,
            term_weights,
            values,
        }
    }

    /// The number of terms `(k, O(o | s))` over all `(s, g)`: the length of
    /// the term list, and a bound on the number of entries.
    fn count_terms(player: &Player, support: &Support, num_states: usize) -> usize {
        let per_observation: Vec<usize> = (0..support.num_observations())
            .map(|o| {
                (0..support.num_nodes())
                    .map(|g| support.block(g, o).len())
                    .sum()
            })
            .collect();
        (0..num_states)
            .flat_map(|s| player.observation_distribution(s))
            .map(|&(o, _)| per_observation[o])
            .sum()
    }

    /// The mixture of `controller` for `player`: [`Mixture::build`] on its
    /// support, refilled with its probabilities.
    pub(crate) fn of(player: &Player, controller: &Fsc, num_states: usize) -> Self {
        let mut mixture = Self::build(player, &Support::of(controller), num_states);
        mixture.refill(&Support::probabilities_of(controller).entries);
        mixture
    }

    /// Writes every entry's value `sum_terms O(o | s) mu[k]` for the
    /// probabilities `mu` (aligned with the support).
    pub(crate) fn refill(&mut self, mu: &[f64]) {
        let mut values = std::mem::take(&mut self.values);
        for (j, value) in values.iter_mut().enumerate() {
            *value = self.terms_of(j).map(|(k, weight)| weight * mu[k]).sum();
        }
        self.values = values;
    }

    /// `|G|`, the controller's number of nodes.
    #[inline]
    pub(crate) fn num_nodes(&self) -> usize {
        self.num_nodes
    }

    /// The entry indices `j` of `(s, g)`.
    #[inline]
    pub(crate) fn at(&self, s: usize, g: usize) -> std::ops::Range<usize> {
        let i = s * self.num_nodes + g;
        self.offsets[i]..self.offsets[i + 1]
    }

    /// Entry `j` as `(g', u)`.
    #[inline]
    pub(crate) fn entry(&self, j: usize) -> (u32, u32) {
        self.entries[j]
    }

    /// The value `A(g', u | s, g)` of every entry, as of the last refill.
    #[inline]
    pub(crate) fn values(&self) -> &[f64] {
        &self.values
    }

    /// The terms `(support entry k, O(o | s))` of entry `j`.
    #[inline]
    pub(crate) fn terms_of(&self, j: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let terms = self.term_offsets[j]..self.term_offsets[j + 1];
        let entries = self.term_entries[terms.clone()].iter();
        entries
            .zip(&self.term_weights[terms])
            .map(|(&k, &weight)| (k as usize, weight))
    }
}
