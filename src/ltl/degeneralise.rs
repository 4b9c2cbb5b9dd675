//! The classic degeneralisation of a one-disjunct generalised Rabin
//! automaton into a state-based Rabin automaton.
//!
//! Contract: [`degeneralise`] returns `None` unless the condition has exactly
//! one disjunct; otherwise a [`Dra`] with one Rabin pair accepting the same
//! words. Errors: [`TranslateError::TooLarge`] past [`construct::MAX_STATES`]
//! states or [`crate::limits::MAX_AUTOMATON_EDGES`] edges, and
//! [`TranslateError::Automaton`] if the result is refused by [`Dra::new`].

use super::{TranslateError, construct};
use crate::automaton::{Dra, RabinPair};

/// For an automaton whose condition is one disjunct `Fin(F) & Inf(m_1) &
/// ... & Inf(m_k)`, the state-based Rabin automaton of the classic
/// degeneralisation: states `(q, i, accepting, finite)` where `i` is the
/// next mark awaited (marks are awaited in turn; a transition carrying
/// `m_i` moves on to `m_{i+1}`, several at once if it carries them), a
/// state is *accepting* (in `K`) when the transition into it completed the
/// round, and *finite* (in `L`) when that transition carried a mark of `F`.
/// A run visits `K` infinitely often iff every `m_j` recurs, and `L`
/// finitely often iff `F` does. `None` for other conditions.
pub(super) fn degeneralise(
    tgr: &construct::Tgr,
    propositions: &[String],
) -> Result<Option<Dra>, TranslateError> {
    let [disjunct] = tgr.disjuncts.as_slice() else {
        return Ok(None);
    };
    let marks = &disjunct.inf;
    let letters = tgr.letters;
    type Key = (u32, u32, bool, bool);
    let mut index: rustc_hash::FxHashMap<Key, u32> = rustc_hash::FxHashMap::default();
    let mut states: Vec<Key> = vec![(tgr.initial as u32, 0, false, false)];
    index.insert(states[0], 0);
    let mut successors = Vec::new();
    let mut next = 0;
    while next < states.len() {
        if (states.len() as u128) * (letters as u128) > crate::limits::MAX_AUTOMATON_EDGES
            || states.len() > construct::MAX_STATES
        {
            return Err(TranslateError::TooLarge {
                limit: construct::MAX_STATES,
            });
        }
        let (q, awaited, _, _) = states[next];
        for letter in 0..letters {
            let edge = tgr.edges[q as usize * letters + letter];
            let mut i = awaited as usize;
            while i < marks.len() && (edge.marks >> marks[i]) & 1 == 1 {
                i += 1;
            }
            let completed = i == marks.len();
            let key = (
                edge.target,
                if completed { 0 } else { i as u32 },
                completed,
                edge.marks & disjunct.fin != 0,
            );
            let fresh = states.len() as u32;
            let target = *index.entry(key).or_insert_with(|| {
                states.push(key);
                fresh
            });
            successors.push(target);
        }
        next += 1;
    }
    let pair = RabinPair {
        fin: states.iter().map(|s| s.3).collect(),
        inf: states.iter().map(|s| s.2).collect(),
    };
    Ok(Some(Dra::new(
        propositions.to_vec(),
        states.len(),
        0,
        successors,
        vec![pair],
    )?))
}
