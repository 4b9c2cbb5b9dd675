//! Deterministic omega-automata over the alphabet 2^AP.
//!
//! Two types meet here:
//!
//! * [`Dra`], the deterministic, complete, **state-based** Rabin automaton that
//!   the product with a game consumes (the paper's Definition of a DRA:
//!   `(Q, 2^AP, delta, q_0, {(L_i, K_i)})`; a run is accepting iff for some pair
//!   `i` it visits `L_i` finitely often and `K_i` infinitely often);
//! * [`EmersonLeiAutomaton`], a deterministic, complete automaton with
//!   **transition-based** marks and an arbitrary positive Boolean acceptance
//!   condition over `Fin`/`Inf` of those marks (HOA's `Acceptance:` line).
//!   HOA input and the LTL translator produce it; its conversion to a `Dra`
//!   is [`to_state_based_rabin`].
//!
//! [`minimise()`] shrinks a `Dra` by partition refinement, and [`parse_hoa`],
//! [`read_hoa_dra`] and [`write_hoa`] read and write both kinds in the HOA v1
//! format.
//!
//! Letters are bit sets: bit `i` of a [`Letter`] is set iff the automaton's
//! `i`-th atomic proposition holds. Transition tables are explicit over all
//! `2^|AP|` letters, so the number of propositions is limited to
//! [`MAX_PROPOSITIONS`].

pub(crate) mod emerson_lei;
pub(crate) mod hoa;
pub(crate) mod minimise;

pub use emerson_lei::{
    Acceptance, Edge, EmersonLeiAutomaton, MAX_DNF_DISJUNCTS, MAX_TABLE_ENTRIES, MarkSet,
    to_state_based_rabin,
};
pub use hoa::{HoaError, parse_hoa, read_hoa_dra, write_hoa};
pub use minimise::{minimise, minimise_with_free_start};

use thiserror::Error;

/// A letter of the alphabet `2^AP`: bit `i` is set iff proposition `i` holds.
pub type Letter = u32;

/// The largest number of atomic propositions an automaton may have (its
/// transition table has `2^|AP|` columns).
pub const MAX_PROPOSITIONS: usize = 16;

/// Why an automaton could not be built.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum AutomatonError {
    /// More propositions than [`MAX_PROPOSITIONS`].
    #[error("{count} atomic propositions; at most {MAX_PROPOSITIONS} are supported")]
    TooManyPropositions {
        /// The number of propositions asked for.
        count: usize,
    },
    /// A structural inconsistency (table size, state index out of range, ...).
    #[error("malformed automaton: {0}")]
    Malformed(String),
}

/// One Rabin pair `(L_i, K_i)` on states: a run satisfies it iff it visits
/// `L_i` (`fin`) finitely often and `K_i` (`inf`) infinitely often.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RabinPair {
    /// `L_i`: membership of each state; must be visited finitely often.
    pub fin: Vec<bool>,
    /// `K_i`: membership of each state; must be visited infinitely often.
    pub inf: Vec<bool>,
}

/// A deterministic, complete, state-based Rabin automaton over `2^AP`.
///
/// `successor(q, a)` is the paper's `delta(q, a)`. The product with a game
/// reads the label of the game's initial state first (formats.md section 3).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Dra {
    propositions: Vec<String>,
    initial: usize,
    successors: Vec<u32>,
    pairs: Vec<RabinPair>,
}

impl Dra {
    /// Builds an automaton with states `0..num_states`, where
    /// `successors[q * 2^|AP| + a]` is `delta(q, a)`. Checks every size and index.
    pub fn new(
        propositions: Vec<String>,
        num_states: usize,
        initial: usize,
        successors: Vec<u32>,
        pairs: Vec<RabinPair>,
    ) -> Result<Self, AutomatonError> {
        if propositions.len() > MAX_PROPOSITIONS {
            return Err(AutomatonError::TooManyPropositions {
                count: propositions.len(),
            });
        }
        if num_states == 0 || initial >= num_states {
            return Err(AutomatonError::Malformed(format!(
                "initial state {initial} with {num_states} states"
            )));
        }
        let letters = 1usize << propositions.len();
        if successors.len() != num_states * letters {
            return Err(AutomatonError::Malformed(format!(
                "transition table has {} entries, expected {} states x {} letters",
                successors.len(),
                num_states,
                letters
            )));
        }
        if let Some(bad) = successors.iter().find(|&&t| t as usize >= num_states) {
            return Err(AutomatonError::Malformed(format!(
                "successor {bad} out of range"
            )));
        }
        for (i, pair) in pairs.iter().enumerate() {
            if pair.fin.len() != num_states || pair.inf.len() != num_states {
                return Err(AutomatonError::Malformed(format!(
                    "Rabin pair {i} does not cover the {num_states} states"
                )));
            }
        }
        Ok(Self {
            propositions,
            initial,
            successors,
            pairs,
        })
    }

    /// The atomic propositions, in the bit order of [`Letter`].
    pub fn propositions(&self) -> &[String] {
        &self.propositions
    }

    /// `|Q|`.
    pub fn num_states(&self) -> usize {
        self.successors.len() >> self.propositions.len()
    }

    /// `q_0`.
    pub fn initial(&self) -> usize {
        self.initial
    }

    /// `delta(q, a)`.
    pub fn successor(&self, q: usize, letter: Letter) -> usize {
        self.successors[(q << self.propositions.len()) | letter as usize] as usize
    }

    /// The Rabin pairs `{(L_i, K_i)}`.
    pub fn pairs(&self) -> &[RabinPair] {
        &self.pairs
    }

    /// The letter in which exactly the named propositions hold; names the
    /// automaton does not know are ignored (they do not occur in its formula).
    pub fn letter_of<'a>(&self, holding: impl IntoIterator<Item = &'a str>) -> Letter {
        holding
            .into_iter()
            .filter_map(|name| self.propositions.iter().position(|p| p == name))
            .fold(0, |letter, bit| letter | (1 << bit))
    }

    /// Whether the automaton accepts some infinite word whose letters all
    /// satisfy `allowed`: for some pair `(L_i, K_i)`, a state reachable from
    /// `q_0` by allowed letters lies on a cycle of allowed letters that
    /// avoids `L_i` and meets `K_i` (a strongly connected component of the
    /// reachable graph without `L_i` that contains a `K_i` state and a cycle).
    pub fn accepts_some_word(&self, allowed: impl Fn(Letter) -> bool) -> bool {
        let letters: Vec<Letter> = (0..1 << self.propositions.len())
            .filter(|&a| allowed(a))
            .collect();
        let n = self.num_states();
        let mut reachable = vec![false; n];
        reachable[self.initial] = true;
        let mut frontier = vec![self.initial];
        while let Some(q) = frontier.pop() {
            for &a in &letters {
                let t = self.successor(q, a);
                if !reachable[t] {
                    reachable[t] = true;
                    frontier.push(t);
                }
            }
        }
        self.pairs.iter().any(|pair| {
            let keep: Vec<bool> = (0..n).map(|q| reachable[q] && !pair.fin[q]).collect();
            let graph = LetterGraph::new(self, &letters, &keep);
            let components = crate::graph::strongly_connected_components(&graph);
            components.members().iter().any(|members| {
                let cyclic =
                    members.len() > 1 || graph.successors[members[0]].contains(&members[0]);
                keep[members[0]] && cyclic && members.iter().any(|&q| pair.inf[q])
            })
        })
    }

    /// Whether the automaton accepts the ultimately periodic word
    /// `prefix cycle^omega` (`cycle` must be non-empty): runs until a
    /// (state, cycle position) pair repeats, then checks the Rabin pairs on the
    /// states visited on the repeating part.
    pub fn accepts_lasso(&self, prefix: &[Letter], cycle: &[Letter]) -> bool {
        assert!(
            !cycle.is_empty(),
            "the cycle of a lasso word must be non-empty"
        );
        let mut q = prefix
            .iter()
            .fold(self.initial, |q, &a| self.successor(q, a));
        let mut first_seen = vec![usize::MAX; self.num_states() * cycle.len()];
        let mut visited = Vec::new();
        let loop_start = loop {
            let position = visited.len() % cycle.len();
            let key = q * cycle.len() + position;
            if first_seen[key] != usize::MAX {
                break first_seen[key];
            }
            first_seen[key] = visited.len();
            visited.push(q);
            q = self.successor(q, cycle[position]);
        };
        let recurring = &visited[loop_start..];
        self.pairs.iter().any(|pair| {
            recurring.iter().all(|&q| !pair.fin[q]) && recurring.iter().any(|&q| pair.inf[q])
        })
    }
}

/// The transition graph of an automaton restricted to some letters and to
/// the states of `keep` (other states have no edges).
struct LetterGraph {
    successors: Vec<Vec<usize>>,
}

impl LetterGraph {
    fn new(dra: &Dra, letters: &[Letter], keep: &[bool]) -> Self {
        let successors = (0..dra.num_states())
            .map(|q| {
                if !keep[q] {
                    return Vec::new();
                }
                let mut next: Vec<usize> = letters
                    .iter()
                    .map(|&a| dra.successor(q, a))
                    .filter(|&t| keep[t])
                    .collect();
                next.sort_unstable();
                next.dedup();
                next
            })
            .collect();
        Self { successors }
    }
}

impl crate::graph::Digraph for LetterGraph {
    fn num_vertices(&self) -> usize {
        self.successors.len()
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        self.successors[v].iter().copied()
    }
}
