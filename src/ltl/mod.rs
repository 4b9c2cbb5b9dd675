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
    AutomatonError, Dra, EmersonLeiAutomaton, Letter, MAX_PROPOSITIONS, RabinPair,
    minimise::minimise_with_free_start, to_state_based_rabin,
};
use crate::interner::{Interner, TooManyKeys};
use construct::budget;

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

/// [`build_candidates`], with a construction that ran out of its budget
/// reported as [`TranslateError::Budget`] naming `nnf` (the innermost
/// formula whose construction failed keeps its name).
fn build_nnf(
    context: &mut af::Context,
    nnf: &Formula,
    letters: usize,
) -> Result<Vec<construct::Tgr>, TranslateError> {
    build_candidates(context, nnf, letters).map_err(|error| {
        let problem = match &error {
            TranslateError::TooLarge { limit } => format!(
                "needs more than {limit} automaton states or {} edges",
                crate::limits::MAX_AUTOMATON_EDGES
            ),
            TranslateError::OutOfTime => "runs past its time budget".to_string(),
            _ => return error,
        };
        let mut subformula = nnf.to_string();
        if subformula.chars().count() > 200 {
            subformula = subformula.chars().take(200).collect::<String>() + "...";
        }
        TranslateError::Budget {
            subformula,
            problem,
            budget: budget::describe(),
        }
    })
}

/// Transition-based generalised Rabin automata for the NNF formula `nnf`,
/// each accepting exactly its words:
///
/// * the weak automaton if `nnf` is an obligation (syntactically, or as
///   certified by [`construct::weak_agrees`]);
/// * for `G (l | G psi)` with `l` propositional, the automata of `G psi`
///   behind a state waiting for `l` to fail ([`construct::wait_then`]);
/// * for `G (l | (psi U (r | G theta)))` with `l` and `r` propositional,
///   the unions of [`escaping_until`];
/// * for `G chi` with `chi` an obligation or `chi = l | (psi W r)` with `l`
///   and `r` propositional and `psi` an obligation, the breakpoint automaton
///   ([`construct::guarded_globally`]);
/// * the Master Theorem automaton ([`construct::master`]).
fn build_candidates(
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
    if let Some(parts) = conjuncts(nnf)
        && let Ok(product) = conjunction_product(context, &parts, letters)
    {
        candidates.push(product);
    }
    if let Formula::Globally(chi) = nnf {
        if let Some((l, psi)) = waiting_form(chi) {
            for then in build_nnf(context, &formula::globally(psi), letters)? {
                candidates.push(construct::wait_then(context, &l, &then));
            }
        } else {
            if let Some((l, psi, r, theta)) = escape_form(chi)
                && let Ok(unions) = escaping_until(context, &l, &psi, &r, &theta, letters)
            {
                candidates.extend(unions);
            }
            if let Some((l, psi, r)) = guarded_form(chi)
                && is_semantic_obligation(context, &psi, letters)
            {
                match construct::guarded_globally(context, &l, &psi, &r, letters) {
                    Ok(automaton) => candidates.push(automaton),
                    Err(e) if !is_budget(&e) => return Err(e),
                    Err(_) => {}
                }
            }
            if is_semantic_obligation(context, chi, letters) {
                let breakpoint = construct::guarded_globally(
                    context,
                    &Formula::False,
                    chi,
                    &Formula::False,
                    letters,
                );
                match breakpoint {
                    Ok(automaton) => candidates.push(automaton),
                    Err(e) if !is_budget(&e) => return Err(e),
                    Err(_) => {}
                }
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

/// Whether a construction failed for want of budget (states, edges, time).
fn is_budget(error: &TranslateError) -> bool {
    matches!(
        error,
        TranslateError::TooLarge { .. } | TranslateError::OutOfTime | TranslateError::Budget { .. }
    )
}

/// The formulas whose conjunction `nnf` is, when it is one of at least two:
/// the parts of `f_1 & ... & f_n`, and `G f_1, ..., G f_n` for
/// `G (f_1 & ... & f_n)`.
fn conjuncts(nnf: &Formula) -> Option<Vec<Formula>> {
    match nnf {
        Formula::And(parts) => Some(parts.clone()),
        Formula::Globally(chi) => match &**chi {
            Formula::And(parts) => Some(parts.iter().cloned().map(formula::globally).collect()),
            _ => None,
        },
        _ => None,
    }
}

/// The [`construct::intersection`] of the smallest candidate automaton of
/// every part: an automaton of their conjunction.
fn conjunction_product(
    context: &mut af::Context,
    parts: &[Formula],
    letters: usize,
) -> Result<construct::Tgr, TranslateError> {
    let mut product: Option<construct::Tgr> = None;
    for part in parts {
        let smallest = build_nnf(context, part, letters)?
            .into_iter()
            .map(|mut tgr| {
                construct::drop_subsumed_disjuncts(&mut tgr.disjuncts);
                tgr
            })
            .min_by_key(|tgr| (tgr.disjuncts.len(), tgr.num_states()))
            .ok_or(TranslateError::TooLarge {
                limit: construct::MAX_STATES,
            })?;
        product = Some(match product {
            None => smallest,
            Some(so_far) => construct::intersection(&so_far, &smallest)?,
        });
    }
    product.ok_or(TranslateError::TooLarge {
        limit: construct::MAX_STATES,
    })
}

/// `(l, psi, r)` if `chi` is `l | (psi W r)` with `l` and `r` propositional
/// (`l` may be `false`).
fn guarded_form(chi: &Formula) -> Option<(Formula, Formula, Formula)> {
    let (l, (psi, r)) = split_disjuncts(disjuncts(chi), |part| match part {
        Formula::WeakUntil(psi, r) if formula::is_propositional(r) => {
            Some(((**psi).clone(), (**r).clone()))
        }
        _ => None,
    })?;
    Some((l, psi, r))
}

/// `(l, psi, r, theta)` if `chi` is `l | (psi U (r | G theta))` with `l`
/// and `r` propositional (either may be `false`).
fn escape_form(chi: &Formula) -> Option<(Formula, Formula, Formula, Formula)> {
    let (l, (psi, (r, theta))) = split_disjuncts(disjuncts(chi), |part| match part {
        Formula::Until(psi, goal) => globally_form(goal).map(|found| ((**psi).clone(), found)),
        _ => None,
    })?;
    Some((l, psi, r, theta))
}

/// `(r, theta)` if `goal` is `r | G theta` with `r` propositional (`r` may
/// be `false`).
fn globally_form(goal: &Formula) -> Option<(Formula, Formula)> {
    split_disjuncts(disjuncts(goal), globally)
}

/// `theta` if `part` is `G theta`.
fn globally(part: &Formula) -> Option<Formula> {
    match part {
        Formula::Globally(theta) => Some((**theta).clone()),
        _ => None,
    }
}

/// The disjuncts of `chi`: its parts if it is a disjunction, else itself.
fn disjuncts(chi: &Formula) -> &[Formula] {
    match chi {
        Formula::Or(parts) => parts,
        other => std::slice::from_ref(other),
    }
}

/// `(l, t)` for the first disjunct of `parts` that `pick` maps to `Some(t)`,
/// if all the other disjuncts are propositional; `l` is their disjunction.
fn split_disjuncts<T>(
    parts: &[Formula],
    pick: impl Fn(&Formula) -> Option<T>,
) -> Option<(Formula, T)> {
    let (at, picked) = parts
        .iter()
        .enumerate()
        .find_map(|(i, part)| pick(part).map(|t| (i, t)))?;
    let rest: Vec<Formula> = parts
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != at)
        .map(|(_, p)| p.clone())
        .collect();
    rest.iter()
        .all(formula::is_propositional)
        .then(|| (formula::or(rest), picked))
}

/// Automata of `G (l | (psi U (r | G theta)))` for propositional `l` and
/// `r`: the [`construct::union`] of every candidate automaton of
///
/// * `D1 = G (l | (psi U r))` with every one of
/// * `D2 = (!m | psi) U G theta`, read through the past monitor `m` of
///   [`construct::with_pending_monitor`] (`m_k` iff some `j <= k` violates
///   `l` and `r` holds nowhere in `j..=k`).
///
/// Correctness: the positions `k` with `m_k` are those inside the window
/// `[j, first r at or after j)` of some `j` violating `l`. So the formula is
/// `G (!m | psi | G theta) & (FG theta | GF !m)` (a window that never
/// closes needs `G theta` eventually; `G theta` at a position gives it at
/// every later one). If `G theta` holds nowhere this is `G (!m | psi) & GF
/// !m`, which is `D1`; otherwise, with `i` the first position where `G
/// theta` holds, it is `!m | psi` at every position before `i`, which is
/// `D2` (a later `i` only asks more). Both `D1` and `D2` imply the formula.
/// (`D1` is `G (!m | psi) & GF !m`: every window closes.)
fn escaping_until(
    context: &mut af::Context,
    l: &Formula,
    psi: &Formula,
    r: &Formula,
    theta: &Formula,
    letters: usize,
) -> Result<Vec<construct::Tgr>, TranslateError> {
    let closing = formula::globally(formula::or(vec![
        l.clone(),
        formula::until(psi.clone(), r.clone()),
    ]));
    let firsts = build_nnf(context, &closing, letters)?;
    let mut extended = context.propositions();
    if extended.len() >= MAX_PROPOSITIONS {
        return Err(TranslateError::TooManyPropositions {
            count: extended.len() + 1,
        });
    }
    let mut fresh = String::from("pending");
    while extended.contains(&fresh) {
        fresh.push('_');
    }
    let m = Formula::prop(&fresh);
    extended.push(fresh);
    let escaping = formula::until(
        formula::or(vec![formula::nnf(&m, false), psi.clone()]),
        formula::globally(theta.clone()),
    );
    let mut inner_context = af::Context::new(&extended);
    let mut unions = Vec::new();
    for inner in build_nnf(&mut inner_context, &escaping, 2 * letters)? {
        let second = construct::with_pending_monitor(context, l, r, &inner)?;
        for first in &firsts {
            unions.push(construct::union(first, &second)?);
        }
    }
    Ok(unions)
}

/// `(l, psi)` if `chi` is `l | G psi` with `l` propositional.
fn waiting_form(chi: &Formula) -> Option<(Formula, Formula)> {
    let Formula::Or(parts) = chi else {
        return None;
    };
    split_disjuncts(parts, globally)
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
    let deadline = std::time::Instant::now().checked_add(
        std::time::Duration::try_from_secs_f64(budget.seconds).unwrap_or(std::time::Duration::MAX),
    );
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

/// For an automaton whose condition is one disjunct `Fin(F) & Inf(m_1) &
/// ... & Inf(m_k)`, the state-based Rabin automaton of the classic
/// degeneralisation: states `(q, i, accepting, finite)` where `i` is the
/// next mark awaited (marks are awaited in turn; a transition carrying
/// `m_i` moves on to `m_{i+1}`, several at once if it carries them), a
/// state is *accepting* (in `K`) when the transition into it completed the
/// round, and *finite* (in `L`) when that transition carried a mark of `F`.
/// A run visits `K` infinitely often iff every `m_j` recurs, and `L`
/// finitely often iff `F` does. `None` for other conditions.
fn degeneralise(
    tgr: &construct::Tgr,
    propositions: &[String],
) -> Result<Option<Dra>, TranslateError> {
    let [disjunct] = tgr.disjuncts.as_slice() else {
        return Ok(None);
    };
    let marks = &disjunct.inf;
    let letters = tgr.letters;
    type Key = (u32, u32, bool, bool);
    let too_large = |TooManyKeys| TranslateError::TooLarge {
        limit: construct::MAX_STATES,
    };
    let mut states: Interner<Key> = Interner::default();
    states
        .intern((tgr.initial as u32, 0, false, false))
        .map_err(too_large)?;
    let mut successors = Vec::new();
    let mut next = 0;
    while next < states.len() {
        if (states.len() as u128) * (letters as u128) > crate::limits::MAX_AUTOMATON_EDGES
            || states.len() > construct::MAX_STATES
        {
            return Err(TranslateError::TooLarge {
                limit: construct::MAX_STATES,
            });
        }
        let (q, awaited, _, _) = states.keys()[next];
        for letter in 0..letters {
            let edge = tgr.edges[q as usize * letters + letter];
            let mut i = awaited as usize;
            while i < marks.len() && (edge.marks >> marks[i]) & 1 == 1 {
                i += 1;
            }
            let completed = i == marks.len();
            let key = (
                edge.target,
                if completed { 0 } else { i as u32 },
                completed,
                edge.marks & disjunct.fin != 0,
            );
            successors.push(states.intern(key).map_err(too_large)?);
        }
        next += 1;
    }
    let states = states.into_keys();
    let pair = RabinPair {
        fin: states.iter().map(|s| s.3).collect(),
        inf: states.iter().map(|s| s.2).collect(),
    };
    Ok(Some(Dra::new(
        propositions.to_vec(),
        states.len(),
        0,
        successors,
        vec![pair],
    )?))
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

/// The most nodes the negation normal form of a formula may have: `xor`
/// and `<->` duplicate both operands (in both polarities), so a chain of
/// them over temporal formulas grows exponentially when written out.
pub const MAX_NNF_NODES: u128 = 1_000_000;

/// An upper bound on the number of nodes of the negation normal form of
/// `formula` (either polarity), saturating.
fn nnf_size(formula: &Formula) -> u128 {
    match formula {
        Formula::True | Formula::False | Formula::Prop(_) => 1,
        Formula::Not(g) => nnf_size(g),
        Formula::And(parts) | Formula::Or(parts) => parts
            .iter()
            .fold(1u128, |total, part| total.saturating_add(nnf_size(part))),
        Formula::Equiv(l, r) | Formula::Xor(l, r) => nnf_size(l)
            .saturating_add(nnf_size(r))
            .saturating_mul(2)
            .saturating_add(3),
        Formula::Next(g) | Formula::Finally(g) | Formula::Globally(g) => {
            nnf_size(g).saturating_add(1)
        }
        Formula::Implies(l, r)
        | Formula::Until(l, r)
        | Formula::WeakUntil(l, r)
        | Formula::Release(l, r)
        | Formula::StrongRelease(l, r) => nnf_size(l).saturating_add(nnf_size(r)).saturating_add(1),
    }
}

/// Refuses a formula whose negation normal form would exceed
/// [`MAX_NNF_NODES`], naming its smallest subformula that does.
fn check_nnf_size(formula: &Formula) -> Result<(), TranslateError> {
    if nnf_size(formula) <= MAX_NNF_NODES {
        return Ok(());
    }
    let mut culprit = formula;
    loop {
        let children: Vec<&Formula> = match culprit {
            Formula::Not(g) | Formula::Next(g) | Formula::Finally(g) | Formula::Globally(g) => {
                vec![g]
            }
            Formula::And(parts) | Formula::Or(parts) => parts.iter().collect(),
            Formula::Implies(l, r)
            | Formula::Equiv(l, r)
            | Formula::Xor(l, r)
            | Formula::Until(l, r)
            | Formula::WeakUntil(l, r)
            | Formula::Release(l, r)
            | Formula::StrongRelease(l, r) => vec![l, r],
            _ => Vec::new(),
        };
        match children.into_iter().find(|c| nnf_size(c) > MAX_NNF_NODES) {
            Some(child) => culprit = child,
            None => break,
        }
    }
    let mut subformula = culprit.to_string();
    if subformula.chars().count() > 200 {
        subformula = subformula.chars().take(200).collect::<String>() + "...";
    }
    Err(TranslateError::Budget {
        subformula,
        problem: format!(
            "has a negation normal form of more than {MAX_NNF_NODES} nodes (`xor` and `<->` \
             over temporal formulas double it per operator)"
        ),
        budget: budget::describe(),
    })
}

/// Whether `formula` has no temporal operator.
fn is_boolean(formula: &Formula) -> bool {
    match formula {
        Formula::True | Formula::False | Formula::Prop(_) => true,
        Formula::Not(g) => is_boolean(g),
        Formula::And(parts) | Formula::Or(parts) => parts.iter().all(is_boolean),
        Formula::Implies(l, r) | Formula::Equiv(l, r) | Formula::Xor(l, r) => {
            is_boolean(l) && is_boolean(r)
        }
        _ => false,
    }
}

/// The truth of a Boolean formula in the letter (bit `i`: `propositions[i]`).
fn holds_in(formula: &Formula, letter: Letter, propositions: &[String]) -> bool {
    let holds = |g: &Formula| holds_in(g, letter, propositions);
    match formula {
        Formula::True => true,
        Formula::Prop(name) => propositions
            .iter()
            .position(|p| p == name)
            .is_some_and(|bit| (letter >> bit) & 1 == 1),
        Formula::Not(g) => !holds(g),
        Formula::And(parts) => parts.iter().all(holds),
        Formula::Or(parts) => parts.iter().any(holds),
        Formula::Implies(l, r) => !holds(l) || holds(r),
        Formula::Equiv(l, r) => holds(l) == holds(r),
        Formula::Xor(l, r) => holds(l) != holds(r),
        _ => false,
    }
}

/// The automaton of a Boolean formula: from the initial state, the first
/// letter leads to an accepting sink if it satisfies the formula and to a
/// rejecting sink otherwise; then minimised.
fn boolean_automaton(formula: &Formula, propositions: Vec<String>) -> Result<Dra, TranslateError> {
    const ACCEPT: u32 = 1;
    const REJECT: u32 = 2;
    let letters = 1usize << propositions.len();
    let mut successors = Vec::with_capacity(3 * letters);
    for letter in 0..letters as Letter {
        if construct::budget::out_of_time() {
            return Err(TranslateError::Budget {
                subformula: "the Boolean formula".into(),
                problem: "runs past its time budget".into(),
                budget: construct::budget::describe(),
            });
        }
        successors.push(if holds_in(formula, letter, &propositions) {
            ACCEPT
        } else {
            REJECT
        });
    }
    successors.extend(std::iter::repeat_n(ACCEPT, letters));
    successors.extend(std::iter::repeat_n(REJECT, letters));
    let pair = RabinPair {
        fin: vec![false; 3],
        inf: vec![false, true, false],
    };
    let dra = Dra::new(propositions, 3, 0, successors, vec![pair])?;
    Ok(minimise_with_free_start(&dra))
}
