//! The weak automaton of an obligation formula, and its certification for
//! formulas that are obligations without being syntactically so.
//!
//! Contract: [`weak`] explores the classes `af(phi, u)` reachable from
//! `phi` and marks every transition of a strongly connected component whose
//! cycle word satisfies the component's formulas; the result has one mark
//! and the single disjunct `Inf(0)`. It accepts exactly the words of `phi`
//! when `phi` is an obligation. [`weak_agrees`] decides, by two product
//! explorations, whether a weak automaton agrees with automata of a formula
//! and of its negation. Errors: [`TranslateError::TooLarge`] and
//! [`TranslateError::OutOfTime`] from the exploration ([`weak_agrees`]
//! reads them as "not certified").

use rustc_hash::FxHashMap;

use super::{Successors, Tgr, explore};
use crate::automaton::emerson_lei::Edge;
use crate::automaton::{Letter, MarkSet};
use crate::graph;
use crate::ltl::TranslateError;
use crate::ltl::af::Context;
use crate::ltl::bdd::Node;
use crate::ltl::formula::Formula;

/// A shortest non-empty word leading from `from` back to `from` inside the
/// component `members` (`component[q] == comp`), if there is one.
fn cycle_word(tgr: &Tgr, from: usize, component: &[u32]) -> Option<Vec<Letter>> {
    let comp = component[from];
    let mut parent: FxHashMap<usize, (usize, Letter)> = FxHashMap::default();
    let mut queue = std::collections::VecDeque::from([from]);
    while let Some(q) = queue.pop_front() {
        for letter in 0..tgr.letters {
            let target = tgr.edges[q * tgr.letters + letter].target as usize;
            if component[target] != comp {
                continue;
            }
            if target == from {
                let mut word = vec![letter as Letter];
                let mut at = q;
                while at != from {
                    let (before, a) = parent[&at];
                    word.push(a);
                    at = before;
                }
                word.reverse();
                return Some(word);
            }
            if let std::collections::hash_map::Entry::Vacant(e) = parent.entry(target) {
                e.insert((q, letter as Letter));
                queue.push_back(target);
            }
        }
    }
    None
}

/// The weak automaton of an obligation formula: the states are the classes
/// `af(phi, u)`; a strongly connected component is accepting iff the word
/// `v^omega` of any cycle `v` through a state `psi` of it satisfies `psi`.
///
/// Correctness: the language of an obligation formula is recognised by a
/// weak deterministic automaton, and then all cycles through one component
/// of any deterministic automaton whose states determine the residual
/// language agree (Maler and Staiger 1997): so one cycle decides.
pub(crate) fn weak(
    context: &mut Context,
    formula: &Formula,
    letters: usize,
) -> Result<Tgr, TranslateError> {
    weak_with_classes(context, formula, letters).map(|(_, tgr)| tgr)
}

/// [`weak`] together with the class of every state.
pub(super) fn weak_with_classes(
    context: &mut Context,
    formula: &Formula,
    letters: usize,
) -> Result<(Vec<Node>, Tgr), TranslateError> {
    let root = context.class(formula);
    let (states, edges) = explore(root, letters, |&q, a| (context.after(q, a), 0))?;
    let mut tgr = Tgr::infinitely_often_mark_0(letters, edges);
    let components = graph::strongly_connected_components(&Successors(&tgr));
    let mut verdict: Vec<Option<bool>> = vec![None; components.count];
    for (q, &class) in states.iter().enumerate() {
        let comp = components.component[q] as usize;
        if verdict[comp].is_none() {
            verdict[comp] = cycle_word(&tgr, q, &components.component)
                .map(|word| context.holds_on_cycle(class, &word));
        }
    }
    for q in 0..states.len() {
        if verdict[components.component[q] as usize] == Some(true) {
            for edge in &mut tgr.edges[q * letters..(q + 1) * letters] {
                edge.marks = 1;
            }
        }
    }
    Ok((states, tgr))
}

/// Whether some word is accepted by `other` while the run of the weak
/// automaton `weak` on it ends in a component with the given verdict
/// (accepting or not).
///
/// The product of the two deterministic automata is explored; the answer is
/// yes iff for some disjunct `Fin(L) & Inf(K_1) & ... & Inf(K_m)` of `other`
/// a strongly connected part of the product, restricted to states whose weak
/// component has the verdict and to transitions outside `L`, has internal
/// transitions in every `K_j` (then a cycle through all of them is the loop
/// of an accepted lasso, and conversely).
fn meets(weak: &Tgr, verdict: bool, other: &Tgr) -> Result<bool, TranslateError> {
    let letters = weak.letters;
    let (states, edges) = explore(
        (weak.initial as u32, other.initial as u32),
        letters,
        |&(w, o), a| {
            let we = weak.edges[w as usize * letters + a as usize];
            let oe = other.edges[o as usize * letters + a as usize];
            ((we.target, oe.target), oe.marks)
        },
    )?;
    let good: Vec<bool> = states
        .iter()
        .map(|&(w, _)| (weak.edges[w as usize * letters].marks != 0) == verdict)
        .collect();
    for d in &other.disjuncts {
        let allowed =
            |s: usize, e: &Edge| good[s] && good[e.target as usize] && e.marks & d.fin == 0;
        let mut offsets = vec![0];
        let mut targets = Vec::new();
        for s in 0..states.len() {
            targets.extend(
                edges[s * letters..(s + 1) * letters]
                    .iter()
                    .filter(|e| allowed(s, e))
                    .map(|e| e.target),
            );
            offsets.push(targets.len());
        }
        let components = graph::strongly_connected_components(&graph::CsrGraph {
            offsets: &offsets,
            targets: &targets,
        });
        let mut cyclic = vec![false; components.count];
        let mut seen: Vec<MarkSet> = vec![0; components.count];
        for s in 0..states.len() {
            let c = components.component[s] as usize;
            for e in &edges[s * letters..(s + 1) * letters] {
                if allowed(s, e) && components.component[e.target as usize] as usize == c {
                    cyclic[c] = true;
                    seen[c] |= e.marks;
                }
            }
        }
        if (0..components.count)
            .any(|c| cyclic[c] && d.inf.iter().all(|&m| (seen[c] >> m) & 1 == 1))
        {
            return Ok(true);
        }
    }
    Ok(false)
}

/// Whether the weak automaton `weak` accepts exactly the words that
/// `positive` accepts, given an automaton `negative` for the complement.
///
/// This certifies the weak automaton of a formula that is an obligation
/// property without being syntactically one: it must accept no word of the
/// negation and reject no word of the formula.
pub(crate) fn weak_agrees(weak: &Tgr, positive: &Tgr, negative: &Tgr) -> bool {
    matches!(meets(weak, true, negative), Ok(false))
        && matches!(meets(weak, false, positive), Ok(false))
}
