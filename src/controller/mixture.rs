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

use super::Support;
use crate::game::Player;

/// The mixture on a fixed support: for each `(s, g)` the distinct supported
/// `(g', u)` in increasing order and their values for the probabilities of
/// the last [`Mixture::refill`]. A value is the sum of its *terms*
/// `O(o | s) mu_k`, one per observation `o` of `s` and support entry `k` of
/// block `(g, o)` with `k = (g', u)`; the terms are met in that order (`o`
/// as `O(. | s)` lists them, then `k`), and each records only the entry it
/// adds to: `O(. | s)` and the blocks are kept once, not per term.
#[derive(Debug, Clone)]
pub(crate) struct Mixture {
    num_nodes: usize,
    num_observations: usize,
    /// The entries of `(s, g)` are `offsets[s |G| + g]..offsets[s |G| + g + 1]`.
    offsets: Vec<usize>,
    entries: Vec<(u32, u32)>,
    /// The terms of `(s, g)` are `term_offsets[s |G| + g]..`, in the order met.
    term_offsets: Vec<usize>,
    /// The entry of each term, counted from the first entry of its `(s, g)`.
    term_entries: Vec<u32>,
    /// `O(. | s)`: the pairs `(o, O(o | s))` of `s` are
    /// `observations[observation_offsets[s]..observation_offsets[s + 1]]`.
    observation_offsets: Vec<usize>,
    observations: Vec<(u32, f64)>,
    /// The support entries `k` of block `b = g |O| + o` are
    /// `block_offsets[b]..block_offsets[b + 1]`.
    block_offsets: Vec<usize>,
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
        let mut entries = Vec::new();
        let mut term_offsets = Vec::with_capacity(num_states * num_nodes + 1);
        term_offsets.push(0);
        let mut term_entries = vec![0; most_terms];
        let mut order: Vec<u128> = Vec::new();
        for s in 0..num_states {
            for g in 0..num_nodes {
                order.clear();
                for &(o, _) in player.observation_distribution(s) {
                    for k in support.block(g, o) {
                        order.push(sort_key(support.entry(k), order.len()));
                    }
                }
                order.sort_unstable();
                let first_term = term_offsets[term_offsets.len() - 1];
                let first_entry = entries.len();
                for group in order.chunk_by(|a, b| a >> 32 == b >> 32) {
                    let entry = (entries.len() - first_entry) as u32;
                    for &key in group {
                        term_entries[first_term + key as u32 as usize] = entry;
                    }
                    entries.push(((group[0] >> 64) as u32, (group[0] >> 32) as u32));
                }
                term_offsets.push(first_term + order.len());
                offsets.push(entries.len());
            }
        }
        let mut observation_offsets = Vec::with_capacity(num_states + 1);
        observation_offsets.push(0);
        let mut observations = Vec::new();
        for s in 0..num_states {
            let distribution = player.observation_distribution(s);
            observations.extend(distribution.iter().map(|&(o, p)| (o as u32, p)));
            observation_offsets.push(observations.len());
        }
        let values = vec![0.0; entries.len()];
        Self {
            num_nodes,
            num_observations: support.num_observations(),
            offsets,
            entries,
            term_offsets,
            term_entries,
            observation_offsets,
            observations,
            block_offsets: support.block_offsets().to_vec(),
            values,
        }
    }

    /// The number of terms `(k, O(o | s))` over all `(s, g)`: the length of
    /// the term list, and a bound on the number of entries (checked against
    /// [`crate::limits::MAX_MIXTURE_TERMS`] before [`Mixture::build`]).
    pub(crate) fn count_terms(player: &Player, support: &Support, num_states: usize) -> usize {
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

    /// Writes every entry's value, the sum of its terms `O(o | s) mu[k]`
    /// in the order met, for the probabilities `mu` (aligned with the
    /// support).
    pub(crate) fn refill(&mut self, mu: &[f64]) {
        let mut values = std::mem::take(&mut self.values);
        // -0.0, the neutral element of f64 addition, as `Iterator::sum` starts.
        values.fill(-0.0);
        let num_states = self.observation_offsets.len() - 1;
        for s in 0..num_states {
            for g in 0..self.num_nodes {
                let own = &mut values[self.at(s, g)];
                self.for_each_term(s, g, |entry, k, weight| own[entry] += weight * mu[k]);
            }
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

    /// Calls `visit(entry, k, O(o | s))` for every term of `(s, g)` in the
    /// order met, `entry` counted from the first entry of `(s, g)`
    /// ([`Self::at`]): the term `O(o | s) mu_k` adds to that entry. Each
    /// support entry `k` has at most one term in `(s, g)`.
    #[inline]
    pub(crate) fn for_each_term(
        &self,
        s: usize,
        g: usize,
        mut visit: impl FnMut(usize, usize, f64),
    ) {
        let i = s * self.num_nodes + g;
        let mut terms = self.term_entries[self.term_offsets[i]..self.term_offsets[i + 1]].iter();
        let observations = self.observation_offsets[s]..self.observation_offsets[s + 1];
        for &(o, weight) in &self.observations[observations] {
            let b = g * self.num_observations + o as usize;
            for (k, &entry) in (self.block_offsets[b]..self.block_offsets[b + 1]).zip(&mut terms) {
                visit(entry as usize, k, weight);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::{Fsc, Role};
    use crate::game::grid::GridSpec;

    /// The grid's players observe their cell with noise: several
    /// observations per state, so entries have several terms.
    #[test]
    fn refill_sums_each_entrys_terms_in_the_order_met() {
        let game = GridSpec::square(7).build().unwrap();
        for (player, role) in [
            (game.defender(), Role::Defender),
            (game.adversary(), Role::Adversary),
        ] {
            let support = Support::of(&Fsc::uniform_enabled(role, 3, player));
            let mu: Vec<f64> = (0..support.num_entries())
                .map(|k| ((k * 7919) % 97 + 1) as f64 / 97.0)
                .collect();
            let mut mixture = Mixture::build(player, &support, game.num_states());
            mixture.refill(&mu);
            let mut several_terms = false;
            for s in 0..game.num_states() {
                for g in 0..support.num_nodes() {
                    let entries = mixture.at(s, g);
                    let mut seen = vec![false; support.num_entries()];
                    mixture.for_each_term(s, g, |entry, k, _| {
                        let (next, action) = support.entry(k);
                        let key = mixture.entry(entries.start + entry);
                        assert_eq!((key.0 as usize, key.1 as usize), (next, action));
                        assert!(!std::mem::replace(&mut seen[k], true), "k twice");
                    });
                    let mu = &mu;
                    for j in entries.clone() {
                        let (next, action) = mixture.entry(j);
                        let terms: Vec<f64> = player
                            .observation_distribution(s)
                            .iter()
                            .flat_map(|&(o, weight)| {
                                support
                                    .block(g, o)
                                    .filter(|&k| {
                                        support.entry(k) == (next as usize, action as usize)
                                    })
                                    .map(move |k| weight * mu[k])
                            })
                            .collect();
                        several_terms |= terms.len() > 1;
                        let expected: f64 = terms.iter().sum();
                        assert_eq!(mixture.values()[j].to_bits(), expected.to_bits());
                    }
                    let keys: Vec<_> = entries.map(|j| mixture.entry(j)).collect();
                    assert!(
                        keys.windows(2).all(|w| w[0] < w[1]),
                        "entries sorted, distinct"
                    );
                }
            }
            assert!(several_terms, "no entry with several terms was tried");
        }
    }
}
