//! An automaton read through the past monitor `m` of `G (l | (psi U (r | G
//! theta)))`.
//!
//! Contract: [`with_pending_monitor`] takes an automaton over `2^(AP +
//! {m})` and returns one over `2^AP` that tracks `m_k` itself (the state is a
//! pair of an inner state and `m_{k-1}`) with the inner marks and disjuncts.
//! Errors: [`TranslateError::TooLarge`] and [`TranslateError::OutOfTime`]
//! from the exploration.

use super::{Tgr, explore};
use crate::automaton::Letter;
use crate::ltl::TranslateError;
use crate::ltl::af::Context;
use crate::ltl::bdd::TRUE;
use crate::ltl::formula::Formula;

/// The automaton over `2^AP` accepting the words `w` whose extension `w^m`
/// is accepted by `inner`, an automaton over `2^(AP + {m})` that reads the
/// fresh proposition `m` as the highest letter bit; `w^m` adds `m` at every
/// position `k` with `m_k = !r(w_k) & (!l(w_k) | m_{k-1})`, `m_{-1} = false`,
/// for the propositional formulas `l` and `r` (classes of `context`, whose
/// letters are those over `AP`).
///
/// `m_k` holds iff some position `j <= k` violates `l` and `r` holds
/// nowhere in `j..=k`. The states are pairs of a state of `inner` and
/// `m_{k-1}`; every transition is the one `inner` takes on `w_k` plus `m_k`.
pub(crate) fn with_pending_monitor(
    context: &mut Context,
    l: &Formula,
    r: &Formula,
    inner: &Tgr,
) -> Result<Tgr, TranslateError> {
    let letters = inner.letters / 2;
    let (l, r) = (context.class(l), context.class(r));
    let pending: Vec<bool> = (0..letters as Letter)
        .map(|a| context.after(r, a) != TRUE && context.after(l, a) != TRUE)
        .collect();
    let kept: Vec<bool> = (0..letters as Letter)
        .map(|a| context.after(r, a) != TRUE)
        .collect();
    let (_, edges) = explore((inner.initial as u32, false), letters, |&(q, m), a| {
        let m = pending[a as usize] || (m && kept[a as usize]);
        let extended = a as usize | (usize::from(m) * letters);
        let e = inner.edges[q as usize * inner.letters + extended];
        ((e.target, m), e.marks)
    })?;
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks: inner.num_marks,
        disjuncts: inner.disjuncts.clone(),
    })
}
