//! The support structure of a controller (the paper's indicator
//! `I_*(g', u | g, o)`) and probability vectors aligned with it.
//!
//! The optimiser changes probabilities but never supports, so everything
//! built from a [`Support`] (the GMC's sparsity pattern, its recurrence
//! classes, the LU's symbolic analysis) is built once.

use super::Fsc;

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
