//! Language-preserving simplifications of an automaton before its
//! state-based conversion.
//!
//! Contract: [`normalise_marks`] changes marks only where they cannot affect
//! acceptance, and [`merge_bisimilar`] merges states with the same marks and
//! classes of targets on every letter; both keep the letters, the number of
//! marks and the disjuncts, accept the same words and cannot fail.

use rustc_hash::FxHashMap;

use super::{Successors, Tgr};
use crate::automaton::MarkSet;
use crate::automaton::emerson_lei::Edge;
use crate::graph;

/// `tgr` with bisimilar states merged: the coarsest partition in which two
/// states of a class have, on every letter, the same marks and targets in
/// the same class. Corresponding runs of the two automata see the same
/// marks, so they accept the same words.
pub(crate) fn merge_bisimilar(tgr: &Tgr) -> Tgr {
    let (n, letters) = (tgr.num_states(), tgr.letters);
    let mut class: Vec<u32> = vec![0; n];
    let mut count = 1;
    loop {
        let mut ids: FxHashMap<Vec<(u32, MarkSet)>, u32> = FxHashMap::default();
        let next: Vec<u32> = (0..n)
            .map(|q| {
                let signature: Vec<(u32, MarkSet)> = std::iter::once((class[q], 0))
                    .chain(
                        tgr.edges[q * letters..(q + 1) * letters]
                            .iter()
                            .map(|e| (class[e.target as usize], e.marks)),
                    )
                    .collect();
                let fresh = ids.len() as u32;
                *ids.entry(signature).or_insert(fresh)
            })
            .collect();
        class = next;
        if ids.len() == count {
            break;
        }
        count = ids.len();
    }
    let mut edges = vec![
        Edge {
            target: 0,
            marks: 0
        };
        count * letters
    ];
    for q in 0..n {
        let c = class[q] as usize;
        for (a, e) in tgr.edges[q * letters..(q + 1) * letters].iter().enumerate() {
            edges[c * letters + a] = Edge {
                target: class[e.target as usize],
                marks: e.marks,
            };
        }
    }
    Tgr {
        letters,
        initial: class[tgr.initial] as usize,
        edges,
        num_marks: tgr.num_marks,
        disjuncts: tgr.disjuncts.clone(),
    }
}

/// `tgr` with marks changed where they cannot affect acceptance, so that
/// more states have the same marks on all outgoing transitions:
///
/// * a transition between two strongly connected components is taken at
///   most once by a run, so it gets the marks shared by all transitions of
///   its source inside the source's component, if they share them (no
///   marks if there are none);
/// * an `Inf` mark that no disjunct uses in a `Fin` set is cleared on the
///   transitions of a state `q` if every disjunct using it has a `Fin` mark
///   on every transition of `q` inside its component: a run that takes
///   those transitions infinitely often satisfies none of these disjuncts
///   anyway, and one that takes them finitely often does not depend on them.
pub(crate) fn normalise_marks(tgr: &Tgr) -> Tgr {
    let (n, letters) = (tgr.num_states(), tgr.letters);
    let components = graph::strongly_connected_components(&Successors(tgr));
    let inside =
        |q: usize, e: &Edge| components.component[e.target as usize] == components.component[q];
    let fin_all: MarkSet = tgr.disjuncts.iter().fold(0, |m, d| m | d.fin);
    let mut edges = tgr.edges.clone();
    for q in 0..n {
        let out = &mut edges[q * letters..(q + 1) * letters];
        let mut cleared: MarkSet = 0;
        for m in 0..tgr.num_marks {
            if (fin_all >> m) & 1 == 1 {
                continue;
            }
            let mut users = tgr
                .disjuncts
                .iter()
                .filter(|d| d.inf.contains(&m))
                .peekable();
            if users.peek().is_some()
                && users.all(|d| {
                    out.iter()
                        .filter(|e| inside(q, e))
                        .all(|e| e.marks & d.fin != 0)
                })
            {
                cleared |= 1 << m;
            }
        }
        for e in out.iter_mut() {
            e.marks &= !cleared;
        }
        let mut shared = out.iter().filter(|e| inside(q, e)).map(|e| e.marks);
        let first = shared.next().unwrap_or(0);
        if shared.all(|m| m == first) {
            for e in out.iter_mut() {
                e.marks = first;
            }
        }
    }
    Tgr {
        letters,
        initial: tgr.initial,
        edges,
        num_marks: tgr.num_marks,
        disjuncts: tgr.disjuncts.clone(),
    }
}
