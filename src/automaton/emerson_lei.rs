//! Deterministic automata with transition-based marks and an Emerson-Lei
//! acceptance condition (a positive Boolean formula over `Fin(m)` and
//! `Inf(m)`), as in HOA v1.

use super::{AutomatonError, Letter, MAX_PROPOSITIONS};

/// A set of acceptance marks `0..64`: bit `m` set iff mark `m` is present.
pub type MarkSet = u64;

/// An Emerson-Lei acceptance condition over marks, HOA's `Acceptance:` formula.
///
/// `Fin(m)` holds on a run iff the transitions carrying mark `m` are taken
/// finitely often; `Inf(m)` iff infinitely often. `complemented` stands for
/// HOA's `Fin(!m)` / `Inf(!m)`: the set of transitions *not* carrying `m`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Acceptance {
    /// `t` (true) or `f` (false).
    Constant(bool),
    /// `Fin(m)` or `Fin(!m)`.
    Fin {
        /// The mark.
        mark: u32,
        /// Whether the complement of the mark's set is meant.
        complemented: bool,
    },
    /// `Inf(m)` or `Inf(!m)`.
    Inf {
        /// The mark.
        mark: u32,
        /// Whether the complement of the mark's set is meant.
        complemented: bool,
    },
    /// Conjunction.
    And(Vec<Acceptance>),
    /// Disjunction.
    Or(Vec<Acceptance>),
}

impl Acceptance {
    /// Whether a run is accepted whose transitions taken infinitely often
    /// carry the mark sets `recurring` (a non-empty list).
    pub fn holds_on(&self, recurring: &[MarkSet]) -> bool {
        let taken = |mark: u32, complemented: bool| {
            recurring
                .iter()
                .any(|&marks| ((marks >> mark) & 1 == 1) != complemented)
        };
        match self {
            Acceptance::Constant(value) => *value,
            Acceptance::Fin { mark, complemented } => !taken(*mark, *complemented),
            Acceptance::Inf { mark, complemented } => taken(*mark, *complemented),
            Acceptance::And(parts) => parts.iter().all(|p| p.holds_on(recurring)),
            Acceptance::Or(parts) => parts.iter().any(|p| p.holds_on(recurring)),
        }
    }
}

/// One transition: the target state and the marks it carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// The successor state.
    pub target: u32,
    /// The acceptance marks on the transition.
    pub marks: MarkSet,
}

/// A deterministic, complete automaton over `2^AP` with marks on transitions
/// and an Emerson-Lei acceptance condition. State-based marks (HOA's
/// `State: 0 {1}`) are represented by putting the state's marks on all of its
/// outgoing transitions, which accepts the same runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EmersonLeiAutomaton {
    propositions: Vec<String>,
    initial: usize,
    edges: Vec<Edge>,
    num_marks: u32,
    acceptance: Acceptance,
}

impl EmersonLeiAutomaton {
    /// Builds an automaton with states `0..num_states`, where
    /// `edges[q * 2^|AP| + a]` is the transition from `q` on letter `a`.
    pub fn new(
        propositions: Vec<String>,
        num_states: usize,
        initial: usize,
        edges: Vec<Edge>,
        num_marks: u32,
        acceptance: Acceptance,
    ) -> Result<Self, AutomatonError> {
        if propositions.len() > MAX_PROPOSITIONS {
            return Err(AutomatonError::TooManyPropositions {
                count: propositions.len(),
            });
        }
        if num_marks > MarkSet::BITS {
            return Err(AutomatonError::Malformed(format!(
                "{num_marks} acceptance marks; at most {} are supported",
                MarkSet::BITS
            )));
        }
        if num_states == 0 || initial >= num_states {
            return Err(AutomatonError::Malformed(format!(
                "initial state {initial} with {num_states} states"
            )));
        }
        let letters = 1usize << propositions.len();
        if edges.len() != num_states * letters {
            return Err(AutomatonError::Malformed(format!(
                "transition table has {} entries, expected {} states x {} letters",
                edges.len(),
                num_states,
                letters
            )));
        }
        if edges.iter().any(|e| e.target as usize >= num_states) {
            return Err(AutomatonError::Malformed("successor out of range".into()));
        }
        let used = if num_marks == MarkSet::BITS {
            MarkSet::MAX
        } else {
            (1 << num_marks) - 1
        };
        if edges.iter().any(|e| e.marks & !used != 0) {
            return Err(AutomatonError::Malformed(format!(
                "a transition carries a mark >= {num_marks}"
            )));
        }
        Ok(Self {
            propositions,
            initial,
            edges,
            num_marks,
            acceptance,
        })
    }

    /// The atomic propositions, in the bit order of [`Letter`].
    pub fn propositions(&self) -> &[String] {
        &self.propositions
    }

    /// The number of states.
    pub fn num_states(&self) -> usize {
        self.edges.len() >> self.propositions.len()
    }

    /// The initial state.
    pub fn initial(&self) -> usize {
        self.initial
    }

    /// The transition from `q` on `letter`.
    pub fn edge(&self, q: usize, letter: Letter) -> Edge {
        self.edges[(q << self.propositions.len()) | letter as usize]
    }

    /// The number of acceptance marks (HOA's `Acceptance: n ...`).
    pub fn num_marks(&self) -> u32 {
        self.num_marks
    }

    /// The acceptance condition.
    pub fn acceptance(&self) -> &Acceptance {
        &self.acceptance
    }

    /// Whether the automaton accepts `prefix cycle^omega` (`cycle` non-empty).
    pub fn accepts_lasso(&self, prefix: &[Letter], cycle: &[Letter]) -> bool {
        assert!(
            !cycle.is_empty(),
            "the cycle of a lasso word must be non-empty"
        );
        let mut q = prefix
            .iter()
            .fold(self.initial, |q, &a| self.edge(q, a).target as usize);
        let mut first_seen = vec![usize::MAX; self.num_states() * cycle.len()];
        let mut marks = Vec::new();
        let loop_start = loop {
            let position = marks.len() % cycle.len();
            let key = q * cycle.len() + position;
            if first_seen[key] != usize::MAX {
                break first_seen[key];
            }
            first_seen[key] = marks.len();
            let edge = self.edge(q, cycle[position]);
            marks.push(edge.marks);
            q = edge.target as usize;
        };
        self.acceptance.holds_on(&marks[loop_start..])
    }
}
