//! Direct evaluation of LTL on ultimately periodic words `u v^omega`.
//!
//! The word has the positions `0 .. |u| + |v|`; the successor of the last one
//! is `|u|`. Every suffix of `u v^omega` equals the suffix at one of these
//! positions, so a formula's truth is a vector of booleans over them, computed
//! bottom-up: `X` reads the successor, `U` and `M` are least fixpoints and
//! `R` and `W` greatest fixpoints of their one-step unfoldings, e.g.
//! `f U g = g | (f & X (f U g))`.

use thiserror::Error;

use super::formula::Formula;
use crate::automaton::Letter;

/// Why a lasso word cannot be evaluated.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum LassoError {
    /// The periodic part `v` of `u v^omega` is empty.
    #[error("the cycle of a lasso word must be non-empty")]
    EmptyCycle,
}

/// Whether the ultimately periodic word `prefix cycle^omega` satisfies
/// `formula` at position 0.
///
/// Letters are bit sets over `propositions`: bit `i` is set iff
/// `propositions[i]` holds. A proposition of the formula that is not in
/// `propositions` (or has an index of 32 or more) is false everywhere.
pub fn holds_on_lasso(
    formula: &Formula,
    propositions: &[String],
    prefix: &[Letter],
    cycle: &[Letter],
) -> Result<bool, LassoError> {
    if cycle.is_empty() {
        return Err(LassoError::EmptyCycle);
    }
    let word = Lasso { prefix, cycle };
    let holds = |name: &str, position: usize| {
        propositions
            .iter()
            .position(|p| p == name)
            .filter(|&bit| bit < Letter::BITS as usize)
            .is_some_and(|bit| (word.letter(position) >> bit) & 1 == 1)
    };
    Ok(word.truth(formula, &holds)[0])
}

/// An ultimately periodic word with a non-empty cycle.
pub(crate) struct Lasso<'a> {
    /// `u`.
    pub(crate) prefix: &'a [Letter],
    /// `v`, non-empty.
    pub(crate) cycle: &'a [Letter],
}

impl Lasso<'_> {
    fn len(&self) -> usize {
        self.prefix.len() + self.cycle.len()
    }

    fn letter(&self, position: usize) -> Letter {
        if position < self.prefix.len() {
            self.prefix[position]
        } else {
            self.cycle[position - self.prefix.len()]
        }
    }

    fn successor(&self, position: usize) -> usize {
        if position + 1 < self.len() {
            position + 1
        } else {
            self.prefix.len()
        }
    }

    /// The fixpoint of `r[i] = now[i] | (stay[i] & r[succ(i)])` (strong:
    /// least, from all false) or of `r[i] = now[i] & (stay[i] | r[succ(i)])`
    /// read dually (weak: greatest, from all true), given as the
    /// until-shaped equation `r[i] = now[i] | (stay[i] & r[succ(i)])`.
    fn fixpoint(&self, now: &[bool], stay: &[bool], least: bool) -> Vec<bool> {
        let n = self.len();
        let mut r = vec![!least; n];
        loop {
            let mut changed = false;
            for i in (0..n).rev() {
                let value = now[i] || (stay[i] && r[self.successor(i)]);
                if value != r[i] {
                    r[i] = value;
                    changed = true;
                }
            }
            if !changed {
                return r;
            }
        }
    }

    /// The truth of `formula` at every position; `holds(p, i)` is the truth
    /// of proposition `p` at position `i`.
    pub(crate) fn truth(
        &self,
        formula: &Formula,
        holds: &dyn Fn(&str, usize) -> bool,
    ) -> Vec<bool> {
        let n = self.len();
        let sub = |f: &Formula| self.truth(f, holds);
        let pointwise = |a: Vec<bool>, b: Vec<bool>, op: fn(bool, bool) -> bool| -> Vec<bool> {
            a.into_iter().zip(b).map(|(x, y)| op(x, y)).collect()
        };
        let not = |a: Vec<bool>| -> Vec<bool> { a.into_iter().map(|x| !x).collect() };
        match formula {
            Formula::True => vec![true; n],
            Formula::False => vec![false; n],
            Formula::Prop(name) => (0..n).map(|i| holds(name, i)).collect(),
            Formula::Not(f) => not(sub(f)),
            Formula::And(fs) => fs.iter().fold(vec![true; n], |acc, f| {
                pointwise(acc, sub(f), |x, y| x && y)
            }),
            Formula::Or(fs) => fs.iter().fold(vec![false; n], |acc, f| {
                pointwise(acc, sub(f), |x, y| x || y)
            }),
            Formula::Implies(f, g) => pointwise(sub(f), sub(g), |x, y| !x || y),
            Formula::Equiv(f, g) => pointwise(sub(f), sub(g), |x, y| x == y),
            Formula::Xor(f, g) => pointwise(sub(f), sub(g), |x, y| x != y),
            Formula::Next(f) => {
                let a = sub(f);
                (0..n).map(|i| a[self.successor(i)]).collect()
            }
            Formula::Finally(f) => self.fixpoint(&sub(f), &vec![true; n], true),
            Formula::Globally(f) => not(self.fixpoint(&not(sub(f)), &vec![true; n], true)),
            Formula::Until(f, g) => self.fixpoint(&sub(g), &sub(f), true),
            Formula::WeakUntil(f, g) => self.fixpoint(&sub(g), &sub(f), false),
            // f R g = !(!f U !g) and f M g = !(!f W !g).
            Formula::Release(f, g) => not(self.fixpoint(&not(sub(g)), &not(sub(f)), true)),
            Formula::StrongRelease(f, g) => not(self.fixpoint(&not(sub(g)), &not(sub(f)), false)),
        }
    }
}
