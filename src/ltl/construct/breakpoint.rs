//! The breakpoint automaton of `G (l | (chi W r))` for an obligation `chi`.
//!
//! Contract: [`guarded_globally`] returns a deterministic Büchi automaton
//! (one mark, the single disjunct `Inf(0)`) accepting exactly the words of
//! `G (l | (chi W r))`, given propositional `l`, `r` and an obligation `chi`
//! (syntactic or certified: the weak automaton of `chi` must be exact).
//! Errors: [`TranslateError::TooLarge`] and [`TranslateError::OutOfTime`]
//! from the exploration.

use super::weak::weak_with_classes;
use super::{Tgr, explore};
use crate::automaton::Letter;
use crate::ltl::TranslateError;
use crate::ltl::af::Context;
use crate::ltl::bdd::{FALSE, Node, TRUE};
use crate::ltl::formula::Formula;

/// The deterministic Büchi automaton of `G (l | (chi W r))` for an
/// obligation formula `chi` and propositional formulas `l` and `r` (`G chi`
/// is the case `l = r = false`), by the breakpoint construction of Miyano
/// and Hayashi (1984) on the weak automaton `A` of `chi` ([`weak`]) read as
/// a universal automaton.
///
/// `chi` must hold at position `k` iff `m_k`, where `m_k = !r(w_k) &
/// (!l(w_k) | m_{k-1})` and `m_{-1} = false`: some position `j <= k` violates
/// `l` and `r` holds nowhere in `j..=k`. So the formula holds iff for every
/// `k` with `m_k` the run of `A` on `w_k w_{k+1} ...` ends in an accepting
/// component. A state is a triple `(m, S, O)`: the last `m`, the set `S` of
/// states of the runs started so far (runs that meet merge, runs that reach
/// `true` are dropped, one reaching `false` rejects for good), and the set
/// `O` of the runs still owed a visit to an accepting component since the
/// last breakpoint. On a letter `a`, `S' = delta(S + {chi if m'}, a)` and
/// `O' = delta(O, a)` minus the states of accepting components, where an
/// empty `O` is first refilled with `S + {chi if m'}`. States with `O` empty
/// are the breakpoints and carry the Büchi mark. By König's lemma a run of
/// the product passes infinitely many breakpoints iff no run of `A` stays in
/// non-accepting states forever; in a weak automaton that is iff every run
/// ends in an accepting component.
pub(crate) fn guarded_globally(
    context: &mut Context,
    l: &Formula,
    chi: &Formula,
    r: &Formula,
    letters: usize,
) -> Result<Tgr, TranslateError> {
    let (classes, inner) = weak_with_classes(context, chi, letters)?;
    let (l, r) = (context.class(l), context.class(r));
    let holds: Vec<(bool, bool)> = (0..letters as Letter)
        .map(|a| (context.after(l, a) == TRUE, context.after(r, a) == TRUE))
        .collect();
    let accepting = |q: u32| inner.edges[q as usize * letters].marks != 0;
    let is_class = |q: u32, class: Node| classes[q as usize] == class;
    let delta = |q: u32, a: Letter| inner.edges[q as usize * letters + a as usize].target;
    // The rejecting sink: a run of `A` reached `false`.
    let dead = (false, vec![u32::MAX], vec![u32::MAX]);
    type State = (bool, Vec<u32>, Vec<u32>);
    let (states, mut edges) = explore(
        (false, Vec::new(), Vec::new()),
        letters,
        |(m, s, o): &State, a| {
            if s.first() == Some(&u32::MAX) {
                return (dead.clone(), 0);
            }
            let (l_holds, r_holds) = holds[a as usize];
            let m = !r_holds && (!l_holds || *m);
            let spawned = m.then_some(0);
            let mut moved: Vec<u32> = s
                .iter()
                .copied()
                .chain(spawned)
                .map(|q| delta(q, a))
                .filter(|&q| !is_class(q, TRUE))
                .collect();
            if moved.iter().any(|&q| is_class(q, FALSE)) {
                return (dead.clone(), 0);
            }
            moved.sort_unstable();
            moved.dedup();
            let mut owed: Vec<u32> = if o.is_empty() {
                moved.clone()
            } else {
                o.iter().map(|&q| delta(q, a)).collect()
            };
            owed.retain(|&q| !accepting(q) && !is_class(q, TRUE));
            owed.sort_unstable();
            owed.dedup();
            ((m, moved, owed), 0)
        },
    )?;
    for (q, (_, _, o)) in states.iter().enumerate() {
        if o.is_empty() {
            for edge in &mut edges[q * letters..(q + 1) * letters] {
                edge.marks = 1;
            }
        }
    }
    Ok(Tgr::infinitely_often_mark_0(letters, edges))
}
