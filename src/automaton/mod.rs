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

use crate::game::Posg;
use crate::graph::backward_reachable;

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

    /// The state letters `L(s)` of a game: for each game state `s`, the
    /// letter in which exactly the propositions labelling `s` hold
    /// ([`Dra::letter_of`] of [`Posg::label_names`]), indexed by `s`.
    pub fn state_letters(&self, game: &Posg) -> Vec<Letter> {
        (0..game.num_states())
            .map(|s| self.letter_of(game.label_names(s)))
            .collect()
    }

    /// Whether the automaton accepts some infinite word whose letters all
    /// satisfy `allowed`: a state on an accepting cycle of allowed letters
    /// (for some pair `(L_i, K_i)`, a cycle that avoids `L_i` and meets
    /// `K_i`) is reachable from `q_0` by allowed letters.
    pub fn accepts_some_word(&self, allowed: impl Fn(Letter) -> bool) -> bool {
        let letters: Vec<Letter> = (0..1 << self.propositions.len())
            .filter(|&a| allowed(a))
            .collect();
        let everything = vec![true; self.num_states()];
        let reverse = LetterGraph::new(self, &letters, &everything).reversed();
        backward_reachable(&reverse, &self.accepting_cycle_states(&letters))[self.initial]
    }

    /// The states that lie on an accepting cycle over `letters`: for some
    /// pair `(L_i, K_i)`, a cycle that avoids `L_i` and meets `K_i` (the
    /// states of a strongly connected component of the graph without `L_i`
    /// that contains a `K_i` state and a cycle). A word read from `q` can be
    /// accepted iff such a state is reachable from `q`.
    fn accepting_cycle_states(&self, letters: &[Letter]) -> Vec<bool> {
        let n = self.num_states();
        let mut live = vec![false; n];
        for pair in &self.pairs {
            let keep: Vec<bool> = pair.fin.iter().map(|&fin| !fin).collect();
            let graph = LetterGraph::new(self, letters, &keep);
            let components = crate::graph::strongly_connected_components(&graph);
            for members in components.members() {
                let cyclic =
                    members.len() > 1 || graph.successors[members[0]].contains(&members[0]);
                if keep[members[0]] && cyclic && members.iter().any(|&q| pair.inf[q]) {
                    for &q in &members {
                        live[q] = true;
                    }
                }
            }
        }
        live
    }

    /// Which states decide the formula whatever the input, for words over
    /// `letters`: `Some(false)` when no word read from `q` is accepted (no
    /// state on an accepting cycle is reachable from `q`),
    /// `Some(true)` when every word is (for some pair `i`, every state
    /// reachable from `q` is in `K_i` and not in `L_i`: a sufficient
    /// condition, exact for accepting sinks), `None` otherwise. The states
    /// reachable from a decided state are decided the same way (method.md
    /// section 1, "decided states").
    pub fn decided_states(&self, letters: &[Letter]) -> Vec<Option<bool>> {
        let everything = vec![true; self.num_states()];
        let reverse = LetterGraph::new(self, letters, &everything).reversed();
        let live = self.accepting_cycle_states(letters);
        let can_accept = backward_reachable(&reverse, &live);
        let mut decided: Vec<Option<bool>> = can_accept
            .iter()
            .map(|&can| (!can).then_some(false))
            .collect();
        for pair in &self.pairs {
            let outside: Vec<bool> = (0..self.num_states())
                .map(|q| pair.fin[q] || !pair.inf[q])
                .collect();
            let can_leave = backward_reachable(&reverse, &outside);
            for (q, verdict) in decided.iter_mut().enumerate() {
                if !can_leave[q] {
                    *verdict = Some(true);
                }
            }
        }
        decided
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

    /// The same graph with every edge reversed.
    fn reversed(&self) -> Self {
        let mut predecessors = vec![Vec::new(); self.successors.len()];
        for (q, next) in self.successors.iter().enumerate() {
            for &t in next {
                predecessors[t].push(q);
            }
        }
        Self {
            successors: predecessors,
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `!a U b` over propositions `a` (bit 0) and `b` (bit 1): state 0
    /// waits, 1 is the accepting sink (b seen), 2 the rejecting sink.
    fn until() -> Dra {
        let successors = vec![0, 2, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2];
        let pair = RabinPair {
            fin: vec![false; 3],
            inf: vec![false, true, false],
        };
        Dra::new(vec!["a".into(), "b".into()], 3, 0, successors, vec![pair]).unwrap()
    }

    #[test]
    fn the_sinks_of_an_until_are_decided_and_the_waiting_state_is_not() {
        assert_eq!(
            until().decided_states(&[0, 1, 2, 3]),
            vec![None, Some(true), Some(false)]
        );
        assert_eq!(
            until().decided_states(&[0, 1]),
            vec![Some(false), Some(true), Some(false)],
            "without a letter holding b, the waiting state can never accept"
        );
    }

    prop_compose! {
        /// A random complete automaton over two propositions with up to five
        /// states and one or two Rabin pairs, and a non-empty set of letters.
        fn random_automaton()(n in 1usize..6)(
            successors in proptest::collection::vec(0..n as u32, n * 4),
            marks in proptest::collection::vec((any::<bool>(), any::<bool>()), n * 2),
            two_pairs in any::<bool>(),
            letters in 1u32..16,
            n in Just(n),
        ) -> (Dra, Vec<Letter>) {
            let pairs = (0..1 + usize::from(two_pairs))
                .map(|i| RabinPair {
                    fin: (0..n).map(|q| marks[i * n + q].0).collect(),
                    inf: (0..n).map(|q| marks[i * n + q].1).collect(),
                })
                .collect();
            let letters = (0..4).filter(|a| letters & (1 << a) != 0).collect();
            (Dra::new(vec!["a".into(), "b".into()], n, 0, successors, pairs).unwrap(), letters)
        }
    }

    proptest! {
        #[test]
        fn every_lasso_word_read_from_a_decided_state_gets_its_verdict(
            (dra, letters) in random_automaton(),
            picks in proptest::collection::vec(
                (proptest::collection::vec(any::<prop::sample::Index>(), 0..6),
                 proptest::collection::vec(any::<prop::sample::Index>(), 1..6)),
                32,
            ),
        ) {
            let decided = dra.decided_states(&letters);
            for (q, verdict) in decided.iter().enumerate() {
                let from_q = Dra { initial: q, ..dra.clone() };
                let can_accept = from_q.accepts_some_word(|a| letters.contains(&a));
                prop_assert_eq!(*verdict == Some(false), !can_accept, "state {}", q);
                let Some(verdict) = *verdict else { continue };
                for (u, v) in &picks {
                    let word = |picks: &Vec<prop::sample::Index>| -> Vec<Letter> {
                        picks.iter().map(|i| *i.get(&letters)).collect()
                    };
                    prop_assert_eq!(from_q.accepts_lasso(&word(u), &word(v)), verdict,
                        "state {} on {:?} ({:?})^omega", q, word(u), word(v));
                }
            }
        }
    }
}
