//! The paper's indicator `I_*(g', u | g, o)` as a mutable subset of an
//! initial support, with the "last option" guard of Algorithm 1's line 9.

use crate::controller::{Choice, Fsc, Support};
use crate::game::ModelError;

/// Which entries of an initial [`Support`] are still allowed: `alive[k]` is
/// `I(g', u | g, o)` for the support's `k`-th entry `(g', u)` of block `(g, o)`.
#[derive(Debug, Clone)]
pub(crate) struct Indicator<'a> {
    support: &'a Support,
    entry_block: Vec<u32>,
    alive: Vec<bool>,
    remaining: Vec<usize>,
}

/// A removal refused because entry `k` is the last option of its block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LastOption {
    /// The block `b = g * |O| + o`.
    pub block: usize,
    /// The entry that would have been removed.
    pub entry: usize,
}

impl<'a> Indicator<'a> {
    /// Line 8 of Algorithm 1: every entry of the initial support is allowed.
    pub(crate) fn full(support: &'a Support) -> Self {
        let mut entry_block = vec![0; support.num_entries()];
        let mut remaining = Vec::with_capacity(support.num_blocks());
        for b in 0..support.num_blocks() {
            let range = support.block_by_index(b);
            remaining.push(range.len());
            for k in range {
                entry_block[k] = b as u32;
            }
        }
        Self {
            support,
            entry_block,
            alive: vec![true; support.num_entries()],
            remaining,
        }
    }

    /// The initial support this indicator restricts.
    pub(crate) fn support(&self) -> &'a Support {
        self.support
    }

    /// The block `b = g * |O| + o` of entry `k`.
    pub(crate) fn block_of(&self, k: usize) -> usize {
        self.entry_block[k] as usize
    }

    /// The allowed entries of block `(g, o)`.
    pub(crate) fn alive_in(&self, g: usize, o: usize) -> impl Iterator<Item = usize> + '_ {
        self.support.block(g, o).filter(|&k| self.alive[k])
    }

    /// Sets `I = 0` for entry `k` unless that would leave its block without
    /// any option (the condition of line 9); removing an entry twice is a no-op.
    pub(crate) fn remove(&mut self, k: usize) -> Result<(), LastOption> {
        if !self.alive[k] {
            return Ok(());
        }
        let block = self.block_of(k);
        if self.remaining[block] == 1 {
            return Err(LastOption { block, entry: k });
        }
        self.alive[k] = false;
        self.remaining[block] -= 1;
        Ok(())
    }

    /// The number of entries removed from the initial support.
    pub(crate) fn removed(&self) -> usize {
        self.alive.iter().filter(|&&a| !a).count()
    }

    /// The allowed entries as a bit vector (identifies the structure).
    pub(crate) fn key(&self) -> &[bool] {
        &self.alive
    }

    /// The controller with the same role, sizes and initial distribution as
    /// `initial` that is uniform over the allowed entries of every block
    /// (lines 13 and 19: `mu = I / sum I`).
    pub(crate) fn uniform_fsc(&self, initial: &Fsc) -> Result<Fsc, ModelError> {
        let blocks = (0..self.support.num_blocks())
            .map(|b| {
                let allowed: Vec<usize> = self
                    .support
                    .block_by_index(b)
                    .filter(|&k| self.alive[k])
                    .collect();
                let probability = 1.0 / allowed.len() as f64;
                allowed
                    .into_iter()
                    .map(|k| {
                        let (next, action) = self.support.entry(k);
                        Choice {
                            next,
                            action,
                            probability,
                            logit: None,
                        }
                    })
                    .collect()
            })
            .collect();
        Fsc::new(
            initial.role(),
            initial.num_nodes(),
            initial.num_observations(),
            initial.num_actions(),
            initial.initial().to_vec(),
            blocks,
        )
    }
}
