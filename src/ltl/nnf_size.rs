//! The size guard on the negation normal form of a formula.
//!
//! Contract: [`check_nnf_size`] bounds the node count of the negation normal
//! form (either polarity, saturating) without building it, and refuses a
//! formula past [`MAX_NNF_NODES`] with a [`TranslateError::Budget`] naming
//! its smallest subformula that is too large.

use super::formula::Formula;
use super::{TranslateError, budget};

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
pub(super) fn check_nnf_size(formula: &Formula) -> Result<(), TranslateError> {
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
