//! The candidate automata of an NNF formula: which constructions of
//! [`super::construct`] a formula's shape admits, and the patterns they
//! recognise.
//!
//! Contract: [`build_nnf`] returns at least one transition-based generalised
//! Rabin automaton, each accepting exactly the words of the formula (the
//! weak automaton alone for an obligation; otherwise the pattern automata
//! that apply, then the Master Theorem automaton). A pattern construction
//! that runs out of budget is skipped when another candidate exists. Errors:
//! those of the constructions ([`TranslateError::TooManyFixpoints`],
//! [`TranslateError::TooManyMarks`], [`TranslateError::TooManyPropositions`]
//! for the fresh monitor proposition), with a budget failure reported as
//! [`TranslateError::Budget`] naming the subformula that blew up.

use super::budget;
use super::construct;
use super::formula::{self, Formula};
use super::{TranslateError, af};
use crate::automaton::MAX_PROPOSITIONS;

/// [`build_candidates`], with a construction that ran out of its budget
/// reported as [`TranslateError::Budget`] naming `nnf` (the innermost
/// formula whose construction failed keeps its name).
pub(super) fn build_nnf(
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
