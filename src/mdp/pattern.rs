//! The union pattern of the policies' systems `(I - Q_sigma) x = b_sigma`
//! on a set of unknown states, shared by every policy iteration of this
//! module (maximum reachability, expected total rewards): each policy's
//! matrix is written into the same pattern through the [`Slot`] of every
//! MDP entry, so one symbolic analysis serves all of them.

use super::Mdp;
use crate::solver::SparsePattern;

/// Where one transition `s -> t` of an unknown's action goes in its
/// policy's system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Slot {
    /// An off-diagonal entry `-P(t | s)` at this position of the values.
    Inside(usize),
    /// Leaving the unknowns: into the exits, and where `t` is in the target
    /// the caller gave, into its right-hand side too.
    Leaving {
        /// `t` is a target state.
        target: bool,
    },
    /// A self-loop, an entry of a state that is not unknown, or of an
    /// action not kept.
    Unused,
}

/// The pattern of the systems on `unknowns` (their position by state in
/// `index`, `usize::MAX` for the others) over the actions `kept` keeps,
/// with a place for each diagonal (formed by the solver from the exits,
/// method.md section 8), and the [`Slot`] of every MDP entry; `target`
/// marks the states whose entering counts as reaching the target.
pub(super) fn union_pattern(
    mdp: &Mdp,
    (unknowns, index): (&[usize], &[usize]),
    target: &[bool],
    kept: impl Fn(usize) -> bool,
) -> (SparsePattern, Vec<Slot>) {
    let mut row_offsets = vec![0];
    let mut columns = Vec::new();
    let mut slots = vec![Slot::Unused; mdp.entries.len()];
    for (i, &s) in unknowns.iter().enumerate() {
        let row_start = columns.len();
        columns.push(i);
        for action in mdp.global_actions(s).filter(|&a| kept(a)) {
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
        for action in mdp.global_actions(s).filter(|&a| kept(a)) {
            let entries = mdp.entry_offsets[action]..mdp.entry_offsets[action + 1];
            for (slot, &(t, _)) in slots[entries.clone()].iter_mut().zip(&mdp.entries[entries]) {
                *slot = if t == s {
                    Slot::Unused
                } else if index[t] == usize::MAX {
                    Slot::Leaving { target: target[t] }
                } else {
                    let offset = row
                        .binary_search(&index[t])
                        .expect("every kept edge among the unknowns is in the union pattern");
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
    (pattern, slots)
}
