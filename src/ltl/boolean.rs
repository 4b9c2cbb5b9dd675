//! The automaton of a formula without temporal operators, by evaluating it
//! on every letter.
//!
//! Contract: [`is_boolean`] says whether a formula has no temporal operator;
//! [`boolean_automaton`] returns the minimised three-state automaton (an
//! initial state, an accepting and a rejecting sink) of such a formula,
//! without expanding its Boolean structure. Errors:
//! [`TranslateError::Budget`] when the time budget runs out while letters are
//! evaluated, [`TranslateError::Automaton`] if [`Dra::new`] refuses the table.

use super::TranslateError;
use super::construct;
use super::formula::Formula;
use crate::automaton::minimise::minimise_with_free_start;
use crate::automaton::{Dra, Letter, RabinPair};

/// Whether `formula` has no temporal operator.
pub(super) fn is_boolean(formula: &Formula) -> bool {
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
pub(super) fn boolean_automaton(
    formula: &Formula,
    propositions: Vec<String>,
) -> Result<Dra, TranslateError> {
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
