//! The constructions of deterministic automata from NNF formulas:
//!
//! * [`weak`]: for obligation formulas, the automaton of `af`-classes with a
//!   verdict per strongly connected component, and [`weak_agrees`], which
//!   certifies it for formulas that are not syntactically obligations;
//! * [`guarded_globally`]: for `G (l | (chi W r))` with `chi` an obligation,
//!   the breakpoint automaton over copies of the weak automaton of `chi`;
//! * [`wait_then`]: for `G (l | G psi)`, a waiting state in front of an
//!   automaton of `G psi`;
//! * [`union`] and [`with_pending_monitor`]: for `G (l | (psi U (r | G
//!   theta)))`, the union of an automaton of `G (l | (psi U r))` with one of
//!   `(!m | psi) U G theta` read through the past monitor `m`;
//! * [`normalise_marks`] and [`merge_bisimilar`]: language-preserving
//!   simplifications of any of these automata before the state-based
//!   conversion;
//! * [`master`]: for every formula, the product of the `af`-tracker with the
//!   co-Büchi and Büchi monitors of the Master Theorem, with a transition-based
//!   generalised Rabin condition (one disjunct per guess `(X, Y)`).
//!
//! Each construction lives in its own file; this one holds what they share:
//! the automaton type [`Tgr`], the state bound [`MAX_STATES`], the time
//! [`budget`] and the on-the-fly exploration [`explore`] that every
//! construction runs its states through.

mod breakpoint;
pub(crate) mod budget;
mod master;
mod pending;
mod product;
mod simplify;
mod wait;
mod weak;

pub(crate) use breakpoint::guarded_globally;
pub(crate) use master::master;
pub(crate) use pending::with_pending_monitor;
pub(crate) use product::{drop_subsumed_disjuncts, intersection, union};
pub(crate) use simplify::{merge_bisimilar, normalise_marks};
pub(crate) use wait::wait_then;
pub(crate) use weak::{weak, weak_agrees};

use rustc_hash::FxHashMap;

use super::TranslateError;
use crate::automaton::emerson_lei::Edge;
use crate::automaton::{Letter, MarkSet};
use crate::graph::Digraph;

/// One disjunct of a generalised Rabin condition: the transitions carrying a
/// mark of `fin` are taken finitely often and, for every mark of `inf`, the
/// transitions carrying it infinitely often.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Disjunct {
    pub(crate) fin: MarkSet,
    pub(crate) inf: Vec<u32>,
}

/// A deterministic complete automaton with transition-based generalised
/// Rabin acceptance: a run is accepted iff it satisfies some disjunct.
#[derive(Debug, Clone)]
pub(crate) struct Tgr {
    pub(crate) letters: usize,
    pub(crate) initial: usize,
    /// `edges[q * letters + a]`.
    pub(crate) edges: Vec<Edge>,
    pub(crate) num_marks: u32,
    pub(crate) disjuncts: Vec<Disjunct>,
}

impl Tgr {
    /// The automaton on `edges` (from state 0) whose only acceptance is
    /// `Inf(0)`: a run is accepted iff it takes edges carrying mark 0
    /// infinitely often.
    pub(crate) fn infinitely_often_mark_0(letters: usize, edges: Vec<Edge>) -> Self {
        Tgr {
            letters,
            initial: 0,
            edges,
            num_marks: 1,
            disjuncts: vec![Disjunct {
                fin: 0,
                inf: vec![0],
            }],
        }
    }

    pub(crate) fn num_states(&self) -> usize {
        self.edges.len() / self.letters
    }
}

/// The transition graph of a [`Tgr`] (letters and marks forgotten).
struct Successors<'a>(&'a Tgr);

impl Digraph for Successors<'_> {
    fn num_vertices(&self) -> usize {
        self.0.num_states()
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        self.0.edges[v * self.0.letters..(v + 1) * self.0.letters]
            .iter()
            .map(|e| e.target as usize)
    }
}

/// The largest number of product states built before giving up.
pub(crate) const MAX_STATES: usize = 200_000;

/// Explores the states reachable from `initial` under `step`, which gives the
/// successor and the marks of a state on a letter.
fn explore<S: Clone + Eq + std::hash::Hash>(
    initial: S,
    letters: usize,
    mut step: impl FnMut(&S, Letter) -> (S, MarkSet),
) -> Result<(Vec<S>, Vec<Edge>), TranslateError> {
    let mut index = FxHashMap::default();
    index.insert(initial.clone(), 0u32);
    let mut states = vec![initial];
    let mut edges = Vec::new();
    let mut next = 0;
    while next < states.len() {
        if budget::out_of_time() {
            return Err(TranslateError::OutOfTime);
        }
        if (states.len() as u128) * (letters as u128) > crate::limits::MAX_AUTOMATON_EDGES {
            return Err(TranslateError::TooLarge { limit: MAX_STATES });
        }
        let state = states[next].clone();
        for letter in 0..letters as Letter {
            let (target, marks) = step(&state, letter);
            let fresh = states.len() as u32;
            let target = *index.entry(target.clone()).or_insert_with(|| {
                states.push(target);
                fresh
            });
            edges.push(Edge { target, marks });
        }
        if states.len() > MAX_STATES {
            return Err(TranslateError::TooLarge { limit: MAX_STATES });
        }
        next += 1;
    }
    Ok((states, edges))
}
