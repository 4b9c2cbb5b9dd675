//! The support structure of a controller (the paper's indicator
//! `I_*(g', u | g, o)`) and probability vectors aligned with it.
//!
//! The optimiser changes probabilities but never supports, so everything
//! built from a [`Support`] (the GMC's sparsity pattern, its recurrence
//! classes, the LU's symbolic analysis) is built once.

use super::{Choice, Fsc};

/// The supported entries `(g', u)` of every block `(g, o)`, in a fixed order,
/// and the supported initial nodes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Support {
    num_nodes: usize,
    num_observations: usize,
    block_offsets: Vec<usize>,
    entries: Vec<(u32, u32)>,
    initial_nodes: Vec<u32>,
}

/// Probabilities on a [`Support`]: `entries[k]` is `mu(g', u | g, o)` of the
/// support's `k`-th entry, `initial[g]` the probability of starting in node `g`.
#[derive(Debug, Clone, PartialEq)]
pub struct Probabilities {
    /// `mu` per support entry.
    pub entries: Vec<f64>,
    /// The initial node distribution (dense over nodes; zero off the support).
    pub initial: Vec<f64>,
}

impl Support {
    /// The support of a controller: its listed choices and its initial nodes
    /// with positive probability.
    pub fn of(fsc: &Fsc) -> Self {
        let mut block_offsets = vec![0];
        let mut entries = Vec::new();
        for block in &fsc.blocks {
            entries.extend(block.iter().map(|c| (c.next as u32, c.action as u32)));
            block_offsets.push(entries.len());
        }
        let initial_nodes = (0..fsc.num_nodes)
            .filter(|&g| fsc.initial[g] > 0.0)
            .map(|g| g as u32)
            .collect();
        Self {
            num_nodes: fsc.num_nodes,
            num_observations: fsc.num_observations,
            block_offsets,
            entries,
            initial_nodes,
        }
    }

    /// Whether `fsc`'s support is this one ([`Support::of`]`(fsc) == *self`),
    /// decided without building it: the same numbers of nodes and
    /// observations, the same choices listed in each block and the same
    /// initial nodes.
    pub fn describes(&self, fsc: &Fsc) -> bool {
        let listed_alike = |b: usize, block: &[Choice]| {
            let listed = &self.entries[self.block_by_index(b)];
            listed.len() == block.len()
                && (listed.iter().zip(block)).all(|(&(next, action), c)| {
                    (next as usize, action as usize) == (c.next, c.action)
                })
        };
        let initial_nodes = (0..fsc.num_nodes)
            .filter(|&g| fsc.initial[g] > 0.0)
            .map(|g| g as u32);
        self.num_nodes == fsc.num_nodes
            && self.num_observations == fsc.num_observations
            && self.num_blocks() == fsc.blocks.len()
            && (fsc.blocks.iter().enumerate()).all(|(b, block)| listed_alike(b, block))
            && self.initial_nodes.iter().copied().eq(initial_nodes)
    }

    /// The controller's probabilities, aligned with [`Support::of`]'s order.
    pub fn probabilities_of(fsc: &Fsc) -> Probabilities {
        Probabilities {
            entries: fsc.blocks.iter().flatten().map(|c| c.probability).collect(),
            initial: fsc.initial.clone(),
        }
    }

    /// `|G|`.
    pub fn num_nodes(&self) -> usize {
        self.num_nodes
    }

    /// The number of observations of the player.
    pub fn num_observations(&self) -> usize {
        self.num_observations
    }

    /// The number of supported entries over all blocks.
    pub fn num_entries(&self) -> usize {
        self.entries.len()
    }

    /// The number of blocks `(g, o)`.
    pub fn num_blocks(&self) -> usize {
        self.block_offsets.len() - 1
    }

    /// The entry indices of block `(g, o)`.
    pub fn block(&self, g: usize, o: usize) -> std::ops::Range<usize> {
        let b = g * self.num_observations + o;
        self.block_offsets[b]..self.block_offsets[b + 1]
    }

    /// The entry indices of block number `b = g * |O| + o`.
    pub fn block_by_index(&self, b: usize) -> std::ops::Range<usize> {
        self.block_offsets[b]..self.block_offsets[b + 1]
    }

    /// The offsets of the blocks: block `b` holds the entries
    /// `block_offsets[b]..block_offsets[b + 1]`.
    pub(crate) fn block_offsets(&self) -> &[usize] {
        &self.block_offsets
    }

    /// Entry `k` as `(g', u)`.
    pub fn entry(&self, k: usize) -> (usize, usize) {
        let (next, action) = self.entries[k];
        (next as usize, action as usize)
    }

    /// The nodes with positive initial probability.
    pub fn initial_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.initial_nodes.iter().map(|&g| g as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::Role;
    use crate::game::grid::GridSpec;

    /// `describes` agrees with comparing the built supports: on the
    /// controller itself, other probabilities on its support, a dropped
    /// choice, another initial node, another number of nodes.
    #[test]
    fn describes_is_equality_of_the_built_supports() {
        let game = GridSpec::square(4).build().unwrap();
        let fsc = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let mut reweighted = fsc.clone();
        let block = reweighted.blocks.iter_mut().find(|b| b.len() > 1).unwrap();
        block[0].probability += block[1].probability / 2.0;
        block[1].probability /= 2.0;
        let mut dropped = fsc.clone();
        let block = dropped.blocks.iter_mut().find(|b| b.len() > 1).unwrap();
        let choice = block.pop().unwrap();
        block[0].probability += choice.probability;
        let mut elsewhere = fsc.clone();
        elsewhere.initial = vec![0.5, 0.5];
        let larger = Fsc::uniform_enabled(Role::Defender, 3, game.defender());
        let support = Support::of(&fsc);
        for (name, other, same) in [
            ("itself", &fsc, true),
            ("reweighted", &reweighted, true),
            ("a choice dropped", &dropped, false),
            ("another initial node", &elsewhere, false),
            ("more nodes", &larger, false),
        ] {
            assert_eq!(support.describes(other), same, "{name}");
            assert_eq!(Support::of(other) == support, same, "{name}");
        }
    }
}
