//! Linear temporal logic: parsing, simplification, evaluation on lasso words,
//! and translation to deterministic Rabin automata.
//!
//! * [`Formula`] is the syntax tree; [`parse`] reads Spot's syntax and
//!   `Display` prints it back.
//! * [`holds_on_lasso`] evaluates a formula directly on an ultimately
//!   periodic word `u v^omega`; it is the test oracle of the translation.
//! * [`translate`] builds a deterministic, complete, state-based Rabin
//!   automaton ([`Dra`]) over `2^AP` accepting exactly the words that satisfy
//!   the formula; [`translate_to_emerson_lei`] gives the transition-based
//!   generalised Rabin automaton it starts from.
//!
//! # Construction
//!
//! The formula is put in negation normal form and simplified with
//! Spot-style rewriting rules (among them `f U (g | G h) = (f U g) | G h`
//! when `f` implies `h`, which is `f W g` for `h = f`). Then one or more
//! candidate automata with transition-based generalised Rabin acceptance
//! are built:
//!
//! * **obligation formulas** (Boolean combinations of syntactic safety and
//!   co-safety formulas, which covers pure safety and co-safety) get the
//!   *weak* automaton whose states are the propositional equivalence classes
//!   `af(phi, u)` of the "after" function, with one verdict per strongly
//!   connected component, found by evaluating the state's formula on the
//!   word of one cycle. A formula that is not syntactically an obligation
//!   gets it too if it is *certified*: the products of the weak automaton
//!   with the Master Theorem automata of the formula and of its negation
//!   have no accepting lasso where they should disagree;
//! * **`G chi` for an obligation `chi`**, and more generally `G (l | (chi W
//!   r))` for propositional `l`, `r`, gets a deterministic Büchi automaton
//!   by the breakpoint construction of Miyano and Hayashi, "Alternating
//!   finite automata on ω-words", TCS 32, 1984, applied to the copies of the
//!   weak automaton of `chi` started at every position where a past monitor
//!   (`l` failed since the last `r`) requires `chi`;
//! * **`G (l | G psi)`** for propositional `l` (`l W G psi`) gets a state
//!   that waits for `l` to fail in front of the automata of `G psi`;
//! * **`G (l | (psi U (r | G theta)))`** for propositional `l`, `r` (the
//!   Dwyer "constrained chain" patterns) gets the union (product) of the
//!   automata of `G (l | (psi U r))` and of `(!m | psi) U G theta`, the
//!   latter built over the propositions and a fresh one for the past
//!   monitor `m` (`l` failed since the last `r`) and read through that
//!   monitor: the formula is `G (!m | psi | G theta) & (FG theta | GF !m)`,
//!   which is the first automaton's formula when `G theta` holds nowhere
//!   and the second's otherwise (see `escaping_until`);
//! * **every other formula**, and the previous kinds as a further
//!   candidate, gets the construction of Esparza, Křetínský and Sickert, "A
//!   Unified Translation of Linear Temporal Logic to ω-Automata", J. ACM
//!   67(6), 2020 (the "Master Theorem"): the product of the `af`-tracker
//!   with one co-Büchi or Büchi monitor per needed formula and a
//!   transition-based generalised Rabin condition with one disjunct per
//!   guess `(X, Y)` of the mu- and nu-subformulas that hold infinitely
//!   often and almost always.
//!
//! Propositional equivalence classes are reduced ordered BDDs over the
//! formula's temporal subformulas, so equivalent states coincide. In every
//! candidate, marks that cannot matter (on transitions between strongly
//! connected components, and `Inf` marks of disjuncts whose `Fin` marks lie
//! on every transition of the state inside its component) are made uniform
//! and bisimilar states are merged; then it is turned into a state-based
//! Rabin automaton by
//! [`crate::automaton::to_state_based_rabin`] and minimised by
//! [`crate::automaton::minimise::minimise_with_free_start`]; the smallest
//! one is kept.

mod af;
mod bdd;
mod boolean;
mod candidates;
mod construct;
mod degeneralise;
mod formula;
mod lasso;
mod nnf_size;
mod parser;
pub mod props;

pub use formula::Formula;
pub use lasso::{LassoError, holds_on_lasso};
pub use nnf_size::MAX_NNF_NODES;
pub use parser::{ParseError, parse};

use thiserror::Error;

use crate::automaton::emerson_lei::Acceptance;
use crate::automaton::{
    AutomatonError, Dra, EmersonLeiAutomaton, MAX_PROPOSITIONS, minimise::minimise_with_free_start,
    to_state_based_rabin,
};
use boolean::{boolean_automaton, is_boolean};
use candidates::build_nnf;
use construct::budget;
use degeneralise::degeneralise;
use nnf_size::check_nnf_size;

/// Why a formula could not be translated.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum TranslateError {
    /// The formula has more than [`MAX_PROPOSITIONS`] propositions.
    #[error("{count} atomic propositions; at most {MAX_PROPOSITIONS} are supported")]
    TooManyPropositions {
        /// The number of distinct propositions.
        count: usize,
    },
    /// The Master Theorem construction would enumerate too many guesses.
    #[error("{count} temporal subformulas with fixpoints; at most {limit} are supported")]
    TooManyFixpoints {
        /// `|mu(phi)| + |nu(phi)|` after simplification.
        count: usize,
        /// The largest supported number.
        limit: usize,
    },
    /// The acceptance condition would need more marks than a mark set holds.
    #[error("{count} acceptance marks needed; at most {limit} are supported")]
    TooManyMarks {
        /// The number of marks needed.
        count: usize,
        /// The largest supported number.
        limit: usize,
    },
    /// The automaton would have too many states.
    #[error("the automaton exceeds {limit} states")]
    TooLarge {
        /// The largest number of states built.
        limit: usize,
    },
    /// The translation ran past its time budget.
    #[error("the translation ran out of time")]
    OutOfTime,
    /// A construction exceeded the translation budget; `subformula` is the
    /// (simplified, negation normal form) formula whose automaton blew up.
    #[error(
        "translating {subformula} {problem} (budget: {budget}); simplify the formula or split it"
    )]
    Budget {
        /// The subformula, printed (shortened past 200 characters).
        subformula: String,
        /// What was exceeded.
        problem: String,
        /// The budget, as a reader would state it.
        budget: String,
    },
    /// The automaton could not be assembled.
    #[error(transparent)]
    Automaton(#[from] AutomatonError),
}

/// The propositions of `formula`, checked against [`MAX_PROPOSITIONS`].
fn checked_propositions(formula: &Formula) -> Result<Vec<String>, TranslateError> {
    let propositions = formula.propositions();
    if propositions.len() > MAX_PROPOSITIONS {
        return Err(TranslateError::TooManyPropositions {
            count: propositions.len(),
        });
    }
    Ok(propositions)
}

/// Transition-based generalised Rabin automata for `formula`, each accepting
/// exactly its words (see [`build_nnf`]).
fn build(
    formula: &Formula,
    propositions: &[String],
) -> Result<Vec<construct::Tgr>, TranslateError> {
    check_nnf_size(formula)?;
    let nnf = formula::nnf(formula, true);
    let letters = 1usize << propositions.len();
    let mut context = af::Context::new(propositions);
    build_nnf(&mut context, &nnf, letters)
}

/// The resources one translation may use: `seconds` of wall-clock time
/// (checked between automaton states) and at most
/// [`crate::limits::MAX_AUTOMATON_EDGES`] edges and 200,000 states per
/// construction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TranslationBudget {
    /// The wall-clock budget in seconds (infinite: none).
    pub seconds: f64,
}

/// The default time budget of a translation, in seconds.
pub const DEFAULT_TRANSLATION_SECONDS: f64 = 60.0;

impl Default for TranslationBudget {
    fn default() -> Self {
        Self {
            seconds: DEFAULT_TRANSLATION_SECONDS,
        }
    }
}

/// A deterministic, complete, state-based Rabin automaton over `2^AP`, where
/// `AP` is `formula.propositions()` (sorted; bit `i` of a letter is the
/// `i`-th), accepting exactly the infinite words that satisfy `formula`.
///
/// Every candidate automaton of the module's construction is simplified by
/// `construct::normalise_marks` and `construct::merge_bisimilar`, converted by
/// [`crate::automaton::to_state_based_rabin`] and minimised by
/// [`crate::automaton::minimise::minimise_with_free_start`]; the one with the fewest
/// states is returned.
pub fn translate(formula: &Formula) -> Result<Dra, TranslateError> {
    translate_within(formula, &TranslationBudget::default())
}

/// [`translate`] within `budget`: a construction that exceeds it is a
/// [`TranslateError::Budget`] naming the subformula whose automaton blew up.
/// A formula without temporal operators gets its automaton directly
/// (two sinks behind an initial state, by evaluating it on every letter),
/// however long its Boolean structure (a chain of `xor` or `<->` is not
/// expanded into a disjunctive form).
pub fn translate_within(
    formula: &Formula,
    budget: &TranslationBudget,
) -> Result<Dra, TranslateError> {
    let propositions = checked_propositions(formula)?;
    let deadline = crate::seconds::after(std::time::Instant::now(), budget.seconds);
    let _deadline = construct::budget::Deadline::set(deadline, budget.seconds);
    if is_boolean(formula) {
        return boolean_automaton(formula, propositions);
    }
    let mut best: Option<Dra> = None;
    let mut failure = None;
    for tgr in build(formula, &propositions)? {
        let simplified = construct::merge_bisimilar(&construct::normalise_marks(&tgr));
        let mut found = Vec::new();
        if let Some(degeneralised) = degeneralise(&simplified, &propositions)? {
            found.push(minimise_with_free_start(&degeneralised));
        }
        let converted = to_emerson_lei(simplified, propositions.clone())
            .and_then(|automaton| Ok(to_state_based_rabin(&automaton)?));
        match converted {
            Ok(dra) => found.push(minimise_with_free_start(&dra)),
            Err(e) => failure = Some(e),
        }
        for dra in found {
            if best
                .as_ref()
                .is_none_or(|b| dra.num_states() < b.num_states())
            {
                best = Some(dra);
            }
        }
    }
    match (best, failure) {
        (Some(best), _) => Ok(best),
        (None, Some(failure)) => Err(failure),
        (None, None) => Err(TranslateError::TooLarge {
            limit: construct::MAX_STATES,
        }),
    }
}

/// A deterministic, complete automaton over `2^AP` (`AP` as in
/// [`translate`]) with transition-based marks and a generalised Rabin
/// condition `OR_i (Fin(m_i) & AND_j Inf(m_ij))`, accepting exactly the
/// infinite words that satisfy `formula` (the first candidate automaton of
/// the module's construction).
pub fn translate_to_emerson_lei(formula: &Formula) -> Result<EmersonLeiAutomaton, TranslateError> {
    let propositions = checked_propositions(formula)?;
    let tgr = build(formula, &propositions)?.swap_remove(0);
    to_emerson_lei(tgr, propositions)
}

/// `tgr` as an automaton over `propositions` with its generalised Rabin
/// condition written as an Emerson-Lei formula.
fn to_emerson_lei(
    tgr: construct::Tgr,
    propositions: Vec<String>,
) -> Result<EmersonLeiAutomaton, TranslateError> {
    let acceptance = Acceptance::Or(
        tgr.disjuncts
            .iter()
            .map(|d| {
                let fin = (0..tgr.num_marks)
                    .filter(|&m| (d.fin >> m) & 1 == 1)
                    .map(|mark| Acceptance::Fin {
                        mark,
                        complemented: false,
                    });
                let inf = d.inf.iter().map(|&mark| Acceptance::Inf {
                    mark,
                    complemented: false,
                });
                Acceptance::And(fin.chain(inf).collect())
            })
            .collect(),
    );
    let num_states = tgr.num_states();
    Ok(EmersonLeiAutomaton::new(
        propositions,
        num_states,
        tgr.initial,
        tgr.edges,
        tgr.num_marks,
        acceptance,
    )?)
}
