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
//! * **every other formula**, and the two previous kinds as a further
//!   candidate, gets the construction of Esparza, Křetínský and Sickert, "A
//!   Unified Translation of Linear Temporal Logic to ω-Automata", J. ACM
//!   67(6), 2020 (the "Master Theorem"): the product of the `af`-tracker
//!   with one co-Büchi or Büchi monitor per needed formula and a
//!   transition-based generalised Rabin condition with one disjunct per
//!   guess `(X, Y)` of the mu- and nu-subformulas that hold infinitely
//!   often and almost always.
//!
//! Propositional equivalence classes are reduced ordered BDDs over the
//! formula's temporal subformulas, so equivalent states coincide. Every
//! candidate is turned into a state-based Rabin automaton by
//! [`crate::automaton::to_state_based_rabin`] and minimised by
//! [`crate::automaton::minimise::minimise_with_free_start`]; the smallest
//! one is kept.

mod af;
mod bdd;
mod construct;
mod formula;
mod lasso;
mod parser;

pub use formula::Formula;
pub use lasso::{LassoError, holds_on_lasso};
pub use parser::{ParseError, parse};

use thiserror::Error;

use crate::automaton::emerson_lei::Acceptance;
use crate::automaton::{
    AutomatonError, Dra, EmersonLeiAutomaton, MAX_PROPOSITIONS, minimise::minimise_with_free_start,
    to_state_based_rabin,
};

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
    let nnf = formula::nnf(formula, true);
    let letters = 1usize << propositions.len();
    let mut context = af::Context::new(propositions);
    build_nnf(&mut context, &nnf, letters)
}

/// Transition-based generalised Rabin automata for the NNF formula `nnf`,
/// each accepting exactly its words:
///
/// * the weak automaton if `nnf` is an obligation (syntactically, or as
///   certified by [`construct::weak_agrees`]);
/// * for `G (l | G psi)` with `l` propositional, the automata of `G psi`
///   behind a state waiting for `l` to fail ([`construct::wait_then`]);
/// * for `G chi` with `chi` an obligation or `chi = l | (psi W r)` with `l`
///   and `r` propositional and `psi` an obligation, the breakpoint automaton
///   ([`construct::guarded_globally`]);
/// * the Master Theorem automaton ([`construct::master`]).
fn build_nnf(
    context: &mut af::Context,
    nnf: &Formula,
    letters: usize,
) -> Result<Vec<construct::Tgr>, TranslateError> {
    if formula::is_obligation(nnf) {
        return Ok(vec![construct::weak(context, nnf, letters)?]);
    }
    let master = construct::master(context, nnf, letters);
    if let Ok(positive) = &master
        && let Some(weak) = certified_weak(context, nnf, positive, letters)
    {
        return Ok(vec![weak]);
    }
    let mut candidates = Vec::new();
    if let Formula::Globally(chi) = nnf {
        if let Some((l, psi)) = waiting_form(chi) {
            for then in build_nnf(context, &formula::globally(psi), letters)? {
                candidates.push(construct::wait_then(context, &l, &then));
            }
        } else {
            if let Some((l, psi, r)) = guarded_form(chi)
                && is_semantic_obligation(context, &psi, letters)
            {
                candidates.push(construct::guarded_globally(context, &l, &psi, &r, letters)?);
            }
            if is_semantic_obligation(context, chi, letters) {
                candidates.push(construct::guarded_globally(
                    context,
                    &Formula::False,
                    chi,
                    &Formula::False,
                    letters,
                )?);
            }
        }
    }
    match master {
        Ok(master) => candidates.push(master),
        Err(e) if candidates.is_empty() => return Err(e),
        Err(_) => {}
    }
    Ok(candidates)
}

/// `(l, psi, r)` if `chi` is `l | (psi W r)` with `l` and `r` propositional
/// (`l` may be `false`).
fn guarded_form(chi: &Formula) -> Option<(Formula, Formula, Formula)> {
    let parts = match chi {
        Formula::Or(parts) => parts.as_slice(),
        other => std::slice::from_ref(other),
    };
    let at = parts
        .iter()
        .position(|p| matches!(p, Formula::WeakUntil(_, r) if formula::is_propositional(r)))?;
    let Formula::WeakUntil(psi, r) = &parts[at] else {
        return None;
    };
    let rest: Vec<Formula> = parts
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != at)
        .map(|(_, p)| p.clone())
        .collect();
    rest.iter()
        .all(formula::is_propositional)
        .then(|| (formula::or(rest), (**psi).clone(), (**r).clone()))
}

/// `(l, psi)` if `chi` is `l | G psi` with `l` propositional.
fn waiting_form(chi: &Formula) -> Option<(Formula, Formula)> {
    let Formula::Or(parts) = chi else {
        return None;
    };
    let at = parts
        .iter()
        .position(|p| matches!(p, Formula::Globally(_)))?;
    let Formula::Globally(psi) = &parts[at] else {
        return None;
    };
    let rest: Vec<Formula> = parts
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != at)
        .map(|(_, p)| p.clone())
        .collect();
    rest.iter()
        .all(formula::is_propositional)
        .then(|| (formula::or(rest), (**psi).clone()))
}

/// The weak automaton of the NNF formula `nnf` if it provably accepts the
/// same words as `positive`, an automaton for `nnf`.
fn certified_weak(
    context: &mut af::Context,
    nnf: &Formula,
    positive: &construct::Tgr,
    letters: usize,
) -> Option<construct::Tgr> {
    let weak = construct::weak(context, nnf, letters).ok()?;
    let negated = formula::nnf(nnf, false);
    let negative = construct::master(context, &negated, letters).ok()?;
    construct::weak_agrees(&weak, positive, &negative).then_some(weak)
}

/// Whether the NNF formula `chi` is an obligation, syntactically or by a
/// certified weak automaton.
fn is_semantic_obligation(context: &mut af::Context, chi: &Formula, letters: usize) -> bool {
    formula::is_obligation(chi)
        || construct::master(context, chi, letters)
            .ok()
            .and_then(|positive| certified_weak(context, chi, &positive, letters))
            .is_some()
}

/// A deterministic, complete, state-based Rabin automaton over `2^AP`, where
/// `AP` is `formula.propositions()` (sorted; bit `i` of a letter is the
/// `i`-th), accepting exactly the infinite words that satisfy `formula`.
///
/// Every candidate automaton of the module's construction is converted by
/// [`crate::automaton::to_state_based_rabin`] and minimised by
/// [`crate::automaton::minimise::minimise_with_free_start`]; the one with the fewest
/// states is returned.
pub fn translate(formula: &Formula) -> Result<Dra, TranslateError> {
    let propositions = checked_propositions(formula)?;
    let mut best: Option<Dra> = None;
    for tgr in build(formula, &propositions)? {
        let automaton = to_emerson_lei(tgr, propositions.clone())?;
        let dra = minimise_with_free_start(&to_state_based_rabin(&automaton)?);
        if best
            .as_ref()
            .is_none_or(|b| dra.num_states() < b.num_states())
        {
            best = Some(dra);
        }
    }
    best.ok_or(TranslateError::TooLarge {
        limit: construct::MAX_STATES,
    })
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
