//! The synchronous products of two automata: [`union`] and
//! [`intersection`], and the clean-up [`drop_subsumed_disjuncts`] of their
//! conditions.
//!
//! Contract: both products take two automata over the same letters and
//! explore the pairs of states reachable from the initial pair; marks of the
//! second automaton are shifted past those of the first. [`union`] accepts
//! the words either accepts (the disjuncts of both), [`intersection`] those
//! both accept (one disjunct per pair of disjuncts, subsumed ones dropped).
//! Errors: [`TranslateError::TooManyMarks`] when the marks do not fit a
//! [`MarkSet`], [`TranslateError::TooLarge`] when the intersection would
//! have more than [`MAX_PRODUCT_DISJUNCTS`] disjuncts or the exploration
//! more than [`MAX_STATES`] states, [`TranslateError::OutOfTime`].

use super::{Disjunct, MAX_STATES, Tgr, explore};
use crate::automaton::MarkSet;
use crate::automaton::emerson_lei::Edge;
use crate::ltl::TranslateError;

/// The number of marks of the product of `first` and `second` (theirs
/// added up), or an error when a [`MarkSet`] cannot hold them.
fn marks_of_product(first: &Tgr, second: &Tgr) -> Result<u32, TranslateError> {
    let num_marks = first.num_marks + second.num_marks;
    if num_marks > MarkSet::BITS {
        return Err(TranslateError::TooManyMarks {
            count: num_marks as usize,
            limit: MarkSet::BITS as usize,
        });
    }
    Ok(num_marks)
}

/// The edges of the synchronous product of `first` and `second` from their
/// initial states: each edge carries `first`'s marks followed by `second`'s,
/// shifted past `first`'s.
fn product_edges(first: &Tgr, second: &Tgr) -> Result<Vec<Edge>, TranslateError> {
    let (letters, shift) = (first.letters, first.num_marks);
    let shifted = |marks: MarkSet| marks.checked_shl(shift).unwrap_or(0);
    let (_, edges) = explore(
        (first.initial as u32, second.initial as u32),
        letters,
        |&(p, q), a| {
            let e = first.edges[p as usize * letters + a as usize];
            let f = second.edges[q as usize * letters + a as usize];
            ((e.target, f.target), e.marks | shifted(f.marks))
        },
    )?;
    Ok(edges)
}

/// The union of two automata over the same letters: their product, whose
/// marks are those of `first` followed by those of `second` (shifted past
/// `first`'s), accepting a run iff some disjunct of either automaton holds on
/// its component. It accepts exactly the words one of them accepts.
pub(crate) fn union(first: &Tgr, second: &Tgr) -> Result<Tgr, TranslateError> {
    let (letters, shift, num_marks) = (
        first.letters,
        first.num_marks,
        marks_of_product(first, second)?,
    );
    let edges = product_edges(first, second)?;
    let shifted = |marks: MarkSet| marks.checked_shl(shift).unwrap_or(0);
    let disjuncts = first
        .disjuncts
        .iter()
        .cloned()
        .chain(second.disjuncts.iter().map(|d| Disjunct {
            fin: shifted(d.fin),
            inf: d.inf.iter().map(|&m| m + shift).collect(),
        }))
        .collect();
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks,
        disjuncts,
    })
}

/// Removes every disjunct that another one subsumes (its `Fin` marks and
/// its `Inf` marks include the other's: every run it accepts, the other
/// accepts too), and duplicates: the condition accepts the same runs.
pub(crate) fn drop_subsumed_disjuncts(disjuncts: &mut Vec<Disjunct>) {
    for d in disjuncts.iter_mut() {
        d.inf.sort_unstable();
        d.inf.dedup();
    }
    disjuncts.sort();
    disjuncts.dedup();
    let subsumes = |weaker: &Disjunct, stronger: &Disjunct| {
        weaker.fin & !stronger.fin == 0 && weaker.inf.iter().all(|m| stronger.inf.contains(m))
    };
    let kept: Vec<Disjunct> = disjuncts
        .iter()
        .enumerate()
        .filter(|&(i, d)| {
            !disjuncts
                .iter()
                .enumerate()
                .any(|(j, other)| j != i && subsumes(other, d))
        })
        .map(|(_, d)| d.clone())
        .collect();
    *disjuncts = kept;
}

/// The largest number of disjuncts an [`intersection`] may have.
pub(crate) const MAX_PRODUCT_DISJUNCTS: usize = 4096;

/// The product of two automata over the same letters accepting the words
/// both accept: a run satisfies the disjunct pair `(d1, d2)` iff it avoids
/// the `Fin` marks of both and visits every `Inf` mark of both infinitely
/// often, so the condition is the disjunction over all pairs (a generalised
/// Rabin condition again; for conjunctions of `GF`, `FG` and `G (a -> F b)`
/// terms the states multiply, the marks add up and no guess is enumerated).
pub(crate) fn intersection(first: &Tgr, second: &Tgr) -> Result<Tgr, TranslateError> {
    let (letters, shift, num_marks) = (
        first.letters,
        first.num_marks,
        marks_of_product(first, second)?,
    );
    let count = first.disjuncts.len() * second.disjuncts.len();
    if count > MAX_PRODUCT_DISJUNCTS {
        return Err(TranslateError::TooLarge { limit: MAX_STATES });
    }
    let edges = product_edges(first, second)?;
    let shifted = |marks: MarkSet| marks.checked_shl(shift).unwrap_or(0);
    let mut disjuncts = Vec::with_capacity(count);
    for d in &first.disjuncts {
        for e in &second.disjuncts {
            let mut inf = d.inf.clone();
            inf.extend(e.inf.iter().map(|&m| m + shift));
            disjuncts.push(Disjunct {
                fin: d.fin | shifted(e.fin),
                inf,
            });
        }
    }
    drop_subsumed_disjuncts(&mut disjuncts);
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks,
        disjuncts,
    })
}
