//! Deterministic automata with transition-based marks and an Emerson-Lei
//! acceptance condition (a positive Boolean formula over `Fin(m)` and
//! `Inf(m)`), as in HOA v1, and their conversion to state-based Rabin
//! automata ([`to_state_based_rabin`]).

use crate::interner::{Interner, TooManyKeys};

use super::{AutomatonError, Dra, Letter, MAX_PROPOSITIONS, RabinPair};

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

/// The largest number of disjuncts [`to_state_based_rabin`] lets the
/// disjunctive normal form of an acceptance condition (or of any of its
/// subformulas) reach before simplification; past it the conversion fails
/// rather than blow up.
pub const MAX_DNF_DISJUNCTS: usize = 4096;

/// The largest transition table (states times letters) that
/// [`to_state_based_rabin`] builds.
pub const MAX_TABLE_ENTRIES: usize = crate::limits::MAX_AUTOMATON_EDGES as usize;

/// Converts a transition-based Emerson-Lei automaton into an equivalent
/// deterministic, complete, state-based Rabin automaton.
///
/// The construction:
///
/// 1. **Acceptance to generalised Rabin.** A set of transitions is named by
///    mark literals: `m` (the transitions carrying mark `m`) or `!m` (those
///    not carrying it). The formula is put in disjunctive normal form by
///    distributing `&` over `|`; constants are folded, and so are atoms on
///    literals no transition satisfies (`Fin(l)` = `t`, `Inf(l)` = `f`).
///    Each disjunct is a conjunction `Fin(F) & Inf(I_1) & ... & Inf(I_k)`
///    where the `Fin` atoms are merged into one by `Fin(a) & Fin(b) =
///    Fin(a | b)`, so `F` is a union of literals and each `I_j` is one
///    literal: a generalised Rabin pair. Disjuncts that cannot hold (`Fin` of
///    both `m` and `!m`, or `Inf(l)` with `l` inside `F`) and disjuncts
///    implied by another one are dropped. If a normal form (of the whole
///    formula or of a subformula) would exceed [`MAX_DNF_DISJUNCTS`]
///    disjuncts, the conversion fails.
/// 2. **Marks onto states.** Only the literals some pair mentions are
///    *relevant*. A state whose outgoing transitions all satisfy the same
///    relevant literals is *uniform* and labelled by them (state-based
///    acceptance in disguise): every visit is followed by such a transition.
///    The transitions leaving a non-uniform state are represented at their
///    targets instead: a state is split by the relevant literals of the
///    transition entering it when that transition's source is not uniform
///    (`(q, M)`; the initial state has no entering transition). So each
///    transition of a run is represented by a state visited just before or
///    after it, and every label literal by an adjacent transition: a literal
///    is seen on states infinitely often iff on transitions.
/// 3. **Degeneralisation.** A pair with `k >= 2` `Inf` literals gets a
///    counter `c` in `0..k` that a transition advances past every
///    `I_c, I_{c+1}, ...` it lies in; when it passes `k` it restarts at 0 and
///    the entered state records that the pair completed a round.
/// 4. **Rabin pairs on states.** `L_i` is the set of states whose label
///    meets `F_i`; `K_i` is the set of states whose label contains `I_1` if
///    `k_i = 1`, the states entered when pair `i` completed a round if `k_i
///    >= 2`, and all states if `k_i = 0`.
///
/// `Constant(true)` thus gives the single pair `(empty set, all states)` and
/// `Constant(false)` no pair at all. States are numbered in breadth-first
/// order from the initial state `0`, letters in increasing order. The result
/// fails if its table would exceed [`MAX_TABLE_ENTRIES`] entries.
pub fn to_state_based_rabin(aut: &EmersonLeiAutomaton) -> Result<Dra, AutomatonError> {
    let letters = 1usize << aut.propositions().len();
    let n = aut.num_states();
    let satisfied =
        |q: usize, a: usize| literals_of(aut.edges[q * letters + a].marks, aut.num_marks);
    let available = (0..n * letters).fold(0, |acc, e| acc | satisfied(e / letters, e % letters));
    let pairs = generalised_pairs(aut.acceptance(), aut.num_marks(), available)?;
    let relevant: Literals = pairs.iter().fold(0, |acc, p| {
        p.infs.iter().fold(acc | p.fin, |acc, l| acc | l)
    });
    let uniform: Vec<bool> = (0..n)
        .map(|q| (1..letters).all(|a| (satisfied(q, a) ^ satisfied(q, 0)) & relevant == 0))
        .collect();
    let counted: Vec<usize> = (0..pairs.len())
        .filter(|&i| pairs[i].infs.len() >= 2)
        .collect();
    // The relevant literals of the transitions leaving `q` if they agree,
    // and of the entering transition if its source's do not.
    let label_of = |source: Option<usize>, q: usize, seen: Literals| {
        let own = if uniform[q] { satisfied(q, 0) } else { 0 };
        let entering = match source {
            Some(p) if !uniform[p] => seen,
            _ => 0,
        };
        (own | entering) & relevant
    };
    let initial = State {
        q: aut.initial() as u32,
        label: label_of(None, aut.initial(), 0),
        counters: vec![0; counted.len()],
        completed: vec![false; counted.len()],
    };
    let mut states = Interner::default();
    let too_large = |count: usize| {
        AutomatonError::Malformed(format!(
            "the state-based Rabin automaton would exceed {count} states"
        ))
    };
    states
        .intern(initial)
        .map_err(|TooManyKeys| too_large(u32::MAX as usize))?;
    let mut successors = Vec::new();
    let mut next = 0;
    while next < states.len() {
        for letter in 0..letters {
            let state = &states.keys()[next];
            let q = state.q as usize;
            let seen = satisfied(q, letter);
            let (counters, completed) = counted
                .iter()
                .zip(&state.counters)
                .map(|(&i, &c)| {
                    let infs = &pairs[i].infs;
                    let mut c = c as usize;
                    while c < infs.len() && seen & infs[c] != 0 {
                        c += 1;
                    }
                    if c == infs.len() {
                        (0, true)
                    } else {
                        (c as u8, false)
                    }
                })
                .unzip();
            let target = aut.edges[q * letters + letter].target as usize;
            let key = State {
                q: target as u32,
                label: label_of(Some(q), target, seen),
                counters,
                completed,
            };
            let id = match states.get(&key) {
                Some(id) => id,
                None if (states.len() + 1) * letters > MAX_TABLE_ENTRIES => {
                    return Err(too_large(MAX_TABLE_ENTRIES / letters));
                }
                None => states
                    .intern(key)
                    .map_err(|TooManyKeys| too_large(u32::MAX as usize))?,
            };
            successors.push(id);
        }
        next += 1;
    }
    let states = states.into_keys();
    let rabin_pairs = pairs
        .iter()
        .enumerate()
        .map(|(i, pair)| {
            let counter = counted.iter().position(|&j| j == i);
            RabinPair {
                fin: states.iter().map(|s| s.label & pair.fin != 0).collect(),
                inf: states
                    .iter()
                    .map(|s| match (pair.infs.as_slice(), counter) {
                        ([], _) => true,
                        (_, Some(c)) => s.completed[c],
                        ([only], None) => s.label & only != 0,
                        (_, None) => unreachable!("pairs with two or more Inf are counted"),
                    })
                    .collect(),
            }
        })
        .collect();
    Dra::new(
        aut.propositions().to_vec(),
        states.len(),
        0,
        successors,
        rabin_pairs,
    )
}

/// A state of [`to_state_based_rabin`]'s result: the original state `q`, its
/// label (relevant literals), and per counted pair the counter and whether
/// the entering transition completed a round.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct State {
    q: u32,
    label: Literals,
    counters: Vec<u8>,
    completed: Vec<bool>,
}

/// A set of transitions named by mark literals: bit `2m` stands for the
/// transitions carrying mark `m`, bit `2m + 1` for those not carrying it; a
/// set of literals stands for the union of their transitions.
type Literals = u128;

/// The bits `2m` of [`Literals`] (the positive literals).
const POSITIVE_LITERALS: Literals = 0x5555_5555_5555_5555_5555_5555_5555_5555;

/// The literal for `m` (`complemented = false`) or `!m`.
fn literal(mark: u32, complemented: bool) -> Literals {
    1 << (2 * mark + u32::from(complemented))
}

/// The literals a transition carrying `marks` satisfies.
fn literals_of(marks: MarkSet, num_marks: u32) -> Literals {
    (0..num_marks).fold(0, |acc, m| acc | literal(m, (marks >> m) & 1 == 0))
}

/// One disjunct of an acceptance condition in normal form:
/// `Fin(fin) & Inf(l_1) & ... & Inf(l_k)` over the literals `l_j` of `inf`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Conjunct {
    /// The union of the `Fin` literals.
    fin: Literals,
    /// The `Inf` literals, each its own atom.
    inf: Literals,
}

impl Conjunct {
    /// The empty conjunction, `t`.
    const TRUE: Conjunct = Conjunct { fin: 0, inf: 0 };

    /// The conjunction of both.
    fn and(self, other: Conjunct) -> Conjunct {
        Conjunct {
            fin: self.fin | other.fin,
            inf: self.inf | other.inf,
        }
    }

    /// False iff the conjunct can hold on no run: `Fin` of all transitions
    /// (`m` and `!m`), or `Inf` of a literal inside the `Fin` set.
    fn satisfiable(self) -> bool {
        let fin_of_all = self.fin & (self.fin >> 1) & POSITIVE_LITERALS;
        fin_of_all == 0 && self.fin & self.inf == 0
    }

    /// Whether every run satisfying `self` satisfies `other`.
    fn implies(self, other: Conjunct) -> bool {
        other.fin & !self.fin == 0 && other.inf & !self.inf == 0
    }
}

/// A generalised Rabin pair: `Fin(fin) & Inf(infs[0]) & ... `.
#[derive(Debug, Clone, PartialEq, Eq)]
struct GeneralisedPair {
    fin: Literals,
    infs: Vec<Literals>,
}

/// The generalised Rabin pairs of an acceptance condition (step 1 of
/// [`to_state_based_rabin`]).
fn generalised_pairs(
    acceptance: &Acceptance,
    num_marks: u32,
    available: Literals,
) -> Result<Vec<GeneralisedPair>, AutomatonError> {
    let folded = to_dnf(acceptance, num_marks)?
        .into_iter()
        .filter(|c| c.inf & !available == 0)
        .map(|c| Conjunct {
            fin: c.fin & available,
            inf: c.inf,
        })
        .collect();
    let pairs = simplify(folded)
        .into_iter()
        .map(|c| GeneralisedPair {
            fin: c.fin,
            infs: (0..Literals::BITS)
                .map(|bit| 1 << bit)
                .filter(|l| c.inf & l != 0)
                .collect(),
        })
        .collect();
    Ok(pairs)
}

/// `t` as `[TRUE]`, `f` as `[]`.
fn constant(value: bool) -> Vec<Conjunct> {
    if value { vec![Conjunct::TRUE] } else { vec![] }
}

/// The simplified disjunctive normal form of `acceptance`.
fn to_dnf(acceptance: &Acceptance, num_marks: u32) -> Result<Vec<Conjunct>, AutomatonError> {
    match acceptance {
        Acceptance::Constant(value) => Ok(constant(*value)),
        Acceptance::Fin { mark, complemented } if *mark >= num_marks => Ok(constant(!complemented)),
        Acceptance::Inf { mark, complemented } if *mark >= num_marks => Ok(constant(*complemented)),
        Acceptance::Fin { mark, complemented } => Ok(vec![Conjunct {
            fin: literal(*mark, *complemented),
            inf: 0,
        }]),
        Acceptance::Inf { mark, complemented } => Ok(vec![Conjunct {
            fin: 0,
            inf: literal(*mark, *complemented),
        }]),
        Acceptance::And(parts) => parts.iter().try_fold(constant(true), |acc, part| {
            let other = to_dnf(part, num_marks)?;
            check_dnf_size(acc.len() * other.len())?;
            let product = acc
                .iter()
                .flat_map(|a| other.iter().map(move |b| a.and(*b)))
                .collect();
            Ok(simplify(product))
        }),
        Acceptance::Or(parts) => parts.iter().try_fold(constant(false), |mut acc, part| {
            let other = to_dnf(part, num_marks)?;
            check_dnf_size(acc.len() + other.len())?;
            acc.extend(other);
            Ok(simplify(acc))
        }),
    }
}

/// Fails past [`MAX_DNF_DISJUNCTS`].
fn check_dnf_size(disjuncts: usize) -> Result<(), AutomatonError> {
    if disjuncts > MAX_DNF_DISJUNCTS {
        return Err(AutomatonError::Malformed(format!(
            "the acceptance condition has more than {MAX_DNF_DISJUNCTS} disjuncts \
             in disjunctive normal form"
        )));
    }
    Ok(())
}

/// Drops unsatisfiable disjuncts and disjuncts implied by another one (of two
/// equal disjuncts the first stays), keeping the order otherwise.
fn simplify(disjuncts: Vec<Conjunct>) -> Vec<Conjunct> {
    let candidates: Vec<Conjunct> = disjuncts.into_iter().filter(|c| c.satisfiable()).collect();
    let redundant = |i: usize, c: Conjunct| {
        candidates
            .iter()
            .enumerate()
            .any(|(j, &d)| j != i && c.implies(d) && (j < i || !d.implies(c)))
    };
    candidates
        .iter()
        .enumerate()
        .filter(|&(i, &c)| !redundant(i, c))
        .map(|(_, &c)| c)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fin(mark: u32) -> Acceptance {
        Acceptance::Fin {
            mark,
            complemented: false,
        }
    }

    fn inf(mark: u32) -> Acceptance {
        Acceptance::Inf {
            mark,
            complemented: false,
        }
    }

    #[test]
    fn rabin_formula_gives_its_pairs_in_order() {
        let rabin = Acceptance::Or(vec![
            Acceptance::And(vec![fin(0), inf(1)]),
            Acceptance::And(vec![fin(2), inf(3)]),
        ]);
        let pairs = generalised_pairs(&rabin, 4, Literals::MAX).expect("small");
        assert_eq!(
            pairs,
            [
                GeneralisedPair {
                    fin: literal(0, false),
                    infs: vec![literal(1, false)],
                },
                GeneralisedPair {
                    fin: literal(2, false),
                    infs: vec![literal(3, false)],
                },
            ]
        );
    }

    #[test]
    fn fin_atoms_merge_and_contradictions_vanish() {
        let merged = generalised_pairs(&Acceptance::And(vec![fin(0), fin(1)]), 2, Literals::MAX)
            .expect("small");
        assert_eq!(merged.len(), 1);
        assert_eq!(merged[0].fin, literal(0, false) | literal(1, false));
        let fin_and_inf = Acceptance::And(vec![fin(0), inf(0)]);
        assert!(
            generalised_pairs(&fin_and_inf, 1, Literals::MAX)
                .expect("small")
                .is_empty()
        );
        let fin_of_all = Acceptance::And(vec![
            fin(0),
            Acceptance::Fin {
                mark: 0,
                complemented: true,
            },
        ]);
        assert!(
            generalised_pairs(&fin_of_all, 1, Literals::MAX)
                .expect("small")
                .is_empty()
        );
    }

    #[test]
    fn implied_disjuncts_are_dropped() {
        let formula = Acceptance::Or(vec![Acceptance::And(vec![inf(0), inf(1)]), inf(0)]);
        let pairs = generalised_pairs(&formula, 2, Literals::MAX).expect("small");
        assert_eq!(
            pairs,
            [GeneralisedPair {
                fin: 0,
                infs: vec![literal(0, false)],
            }]
        );
    }

    #[test]
    fn literals_no_transition_satisfies_are_folded() {
        let only_positive = literal(0, false) | literal(1, false);
        let formula = Acceptance::Or(vec![
            Acceptance::And(vec![fin(1), inf(0)]),
            Acceptance::Inf {
                mark: 0,
                complemented: true,
            },
        ]);
        let pairs = generalised_pairs(&formula, 2, only_positive).expect("small");
        assert_eq!(
            pairs,
            [GeneralisedPair {
                fin: literal(1, false),
                infs: vec![literal(0, false)],
            }]
        );
    }

    #[test]
    fn marks_no_transition_carries_are_folded() {
        assert_eq!(to_dnf(&fin(3), 2).expect("small"), [Conjunct::TRUE]);
        assert!(to_dnf(&inf(3), 2).expect("small").is_empty());
    }

    #[test]
    fn generalised_buchi_is_degeneralised_with_a_counter() {
        let edges = (0..4)
            .map(|letter| Edge {
                target: 0,
                marks: letter,
            })
            .collect();
        let aut = EmersonLeiAutomaton::new(
            vec!["a".into(), "b".into()],
            1,
            0,
            edges,
            2,
            Acceptance::And(vec![inf(0), inf(1)]),
        )
        .expect("valid");
        let dra = to_state_based_rabin(&aut).expect("converts");
        assert_eq!(dra.pairs().len(), 1);
        assert!(dra.accepts_lasso(&[], &[1, 2]));
        assert!(dra.accepts_lasso(&[], &[3]));
        assert!(!dra.accepts_lasso(&[3], &[1]));
        assert!(!dra.accepts_lasso(&[], &[2, 0]));
    }
}
