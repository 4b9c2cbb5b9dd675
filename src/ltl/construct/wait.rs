//! The automaton of `G (l | G psi)`: a waiting state in front of an
//! automaton of `G psi`.
//!
//! Contract: [`wait_then`] takes a propositional `l` and any automaton of
//! `G psi` and returns an automaton of `G (l | G psi)` with one state and
//! one mark (with its own `Inf` disjunct) more; it cannot fail.

use super::{Disjunct, Tgr};
use crate::automaton::Letter;
use crate::automaton::emerson_lei::Edge;
use crate::ltl::af::Context;
use crate::ltl::bdd::TRUE;
use crate::ltl::formula::Formula;

/// The automaton of `G (l | G psi)` for a propositional formula `l`, from an
/// automaton `then` of `G psi`.
///
/// `G (l | G psi)` holds iff `l` holds forever or, at the first position
/// where `l` fails, `G psi` holds (then `G psi` holds at every later position
/// too). The automaton waits in a new state while `l` holds, marking its
/// loop with a new mark that a new disjunct `Inf` accepts, and on the first
/// letter violating `l` moves as `then` does from its initial state. That
/// transition is taken at most once, so it carries the waiting mark too
/// (then all transitions of the waiting state carry the same marks).
pub(crate) fn wait_then(context: &mut Context, l: &Formula, then: &Tgr) -> Tgr {
    let letters = then.letters;
    let class = context.class(l);
    let wait_mark = then.num_marks;
    let shifted = |e: &Edge| Edge {
        target: e.target + 1,
        marks: e.marks,
    };
    let mut edges: Vec<Edge> = (0..letters as Letter)
        .map(|a| {
            let target = if context.after(class, a) == TRUE {
                0
            } else {
                then.edges[then.initial * letters + a as usize].target + 1
            };
            Edge {
                target,
                marks: 1 << wait_mark,
            }
        })
        .collect();
    edges.extend(then.edges.iter().map(shifted));
    let mut disjuncts = then.disjuncts.clone();
    disjuncts.push(Disjunct {
        fin: 0,
        inf: vec![wait_mark],
    });
    Tgr {
        letters,
        initial: 0,
        edges,
        num_marks: wait_mark + 1,
        disjuncts,
    }
}
