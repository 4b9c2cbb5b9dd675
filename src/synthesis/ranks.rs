//! Bounded integers in CNF and their comparison: the levels and ranks of
//! the support certificates ([`super::encoding`]).
//!
//! A [`Number`] in `0..bound` is a vector of literals. Two encodings:
//!
//! * [`RankEncoding::Binary`]: `ceil(log2(bound))` bits, most significant
//!   last; a comparison costs one auxiliary variable and three clauses per bit.
//! * [`RankEncoding::Order`] (unary): literals `y_k <-> (value >= k)` for
//!   `k = 1..bound-1`, with `y_{k+1} -> y_k`; a comparison costs
//!   `bound - 1` clauses and no auxiliary variable.
//!
//! Comparisons are one-directional: [`less`] returns a literal `t` with
//! `t -> (a < b)` (or `a <= b`), which is all the certificates need, since
//! they only ever require a comparison to hold.

use serde::{Deserialize, Serialize};

use super::SynthesisError;
use super::cnf::{Cnf, FALSE, Lit, TRUE};

/// How levels and ranks are written in CNF.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum RankEncoding {
    /// Binary numbers with comparator chains.
    #[default]
    Binary,
    /// Unary (order) encoding.
    Order,
}

/// A number in `0..bound` (see the module documentation for its encoding).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Number {
    literals: Vec<Lit>,
}

impl RankEncoding {
    /// A fresh number in `0..bound` (`bound >= 1`). Binary numbers range
    /// over `0..2^bits`, which contains `0..bound`.
    pub fn number(self, cnf: &mut Cnf, bound: usize) -> Result<Number, SynthesisError> {
        let literals = match self {
            Self::Binary => cnf.fresh_many(bits_for(bound)),
            Self::Order => {
                let literals = cnf.fresh_many(bound.saturating_sub(1));
                for pair in literals.windows(2) {
                    cnf.implies(pair[1], pair[0])?;
                }
                literals
            }
        };
        Ok(Number { literals })
    }
}

impl RankEncoding {
    /// The constant number `value` in `0..bound` (an error if it does not
    /// fit).
    pub fn constant(self, bound: usize, value: usize) -> Result<Number, SynthesisError> {
        let width = match self {
            Self::Binary => bits_for(bound),
            Self::Order => bound.saturating_sub(1),
        };
        let shape = Number {
            literals: vec![TRUE; width],
        };
        let literals = shape.fixed_to(self, value).ok_or_else(|| {
            SynthesisError::Internal(format!("the value {value} does not fit the bound {bound}"))
        })?;
        Ok(Number { literals })
    }
}

impl Number {
    /// The value, when every literal is a constant.
    fn value(&self, encoding: RankEncoding) -> Option<usize> {
        let bits: Option<Vec<bool>> = self
            .literals
            .iter()
            .map(|&l| match l {
                TRUE => Some(true),
                FALSE => Some(false),
                _ => None,
            })
            .collect();
        let bits = bits?;
        Some(match encoding {
            RankEncoding::Binary => bits
                .iter()
                .enumerate()
                .map(|(k, &b)| usize::from(b) << k)
                .sum(),
            RankEncoding::Order => bits.iter().filter(|&&b| b).count(),
        })
    }

    /// Assumptions that fix the number to `value`, or `None` when `value`
    /// does not fit.
    pub fn fixed_to(&self, encoding: RankEncoding, value: usize) -> Option<Vec<Lit>> {
        let width = self.literals.len();
        let fits = match encoding {
            RankEncoding::Binary => width >= usize::BITS as usize || value >> width == 0,
            RankEncoding::Order => value <= width,
        };
        fits.then(|| {
            self.literals
                .iter()
                .enumerate()
                .map(|(k, &l)| {
                    let set = match encoding {
                        RankEncoding::Binary => value >> k & 1 == 1,
                        RankEncoding::Order => value > k,
                    };
                    if set { l } else { -l }
                })
                .collect()
        })
    }
}

/// `ceil(log2(bound))`: the bits that hold `0..bound`.
fn bits_for(bound: usize) -> usize {
    (usize::BITS - bound.saturating_sub(1).leading_zeros()) as usize
}

/// A literal `t` with `t -> (a < b)` when `strict`, `t -> (a <= b)`
/// otherwise; `a` and `b` must come from the same encoding and bound.
pub fn less(
    encoding: RankEncoding,
    cnf: &mut Cnf,
    a: &Number,
    b: &Number,
    strict: bool,
) -> Result<Lit, SynthesisError> {
    debug_assert_eq!(a.literals.len(), b.literals.len());
    if let (Some(x), Some(y)) = (a.value(encoding), b.value(encoding)) {
        let holds = if strict { x < y } else { x <= y };
        return Ok(if holds { TRUE } else { FALSE });
    }
    match encoding {
        RankEncoding::Binary => binary_less(cnf, &a.literals, &b.literals, strict),
        RankEncoding::Order => order_less(cnf, &a.literals, &b.literals, strict),
    }
}

/// From the least significant bit up, `t_j -> (a[0..=j] < b[0..=j])`
/// (or `<=`): `a_j <= b_j`, and where they are equal the lower bits decide.
fn binary_less(cnf: &mut Cnf, a: &[Lit], b: &[Lit], strict: bool) -> Result<Lit, SynthesisError> {
    let mut below = if strict { FALSE } else { TRUE };
    for (&aj, &bj) in a.iter().zip(b) {
        let t = cnf.fresh();
        cnf.clause([-t, -aj, bj])?;
        cnf.clause([-t, bj, below])?;
        cnf.clause([-t, -aj, below])?;
        below = t;
    }
    Ok(below)
}

/// With `y_k = (value >= k)`: `a <= b` iff `a_k -> b_k` for every `k`, and
/// `a < b` iff `b_1` and `a_k -> b_{k+1}` for every `k`.
fn order_less(cnf: &mut Cnf, a: &[Lit], b: &[Lit], strict: bool) -> Result<Lit, SynthesisError> {
    let width = a.len();
    if width == 0 {
        return Ok(if strict { FALSE } else { TRUE });
    }
    let t = cnf.fresh();
    if strict {
        cnf.clause([-t, b[0]])?;
        for (k, &ak) in a.iter().enumerate() {
            let next = b.get(k + 1).copied().unwrap_or(FALSE);
            cnf.clause([-t, -ak, next])?;
        }
    } else {
        for (&ak, &bk) in a.iter().zip(b) {
            cnf.clause([-t, -ak, bk])?;
        }
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::super::cnf::{Answer, Solver};
    use super::*;

    /// Fixes `number` to `value` by assumptions.
    fn assume(encoding: RankEncoding, number: &Number, value: usize) -> Vec<Lit> {
        number.fixed_to(encoding, value).expect("the value fits")
    }

    #[test]
    fn comparisons_agree_with_integers_in_both_encodings() {
        for encoding in [RankEncoding::Binary, RankEncoding::Order] {
            for bound in 1..=9 {
                let mut cnf = Cnf::new(10_000);
                let a = encoding.number(&mut cnf, bound).unwrap();
                let b = encoding.number(&mut cnf, bound).unwrap();
                let lt = less(encoding, &mut cnf, &a, &b, true).unwrap();
                let le = less(encoding, &mut cnf, &a, &b, false).unwrap();
                let mut solver = Solver::new(&cnf, None);
                for x in 0..bound {
                    for y in 0..bound {
                        let mut fixed = assume(encoding, &a, x);
                        fixed.extend(assume(encoding, &b, y));
                        for (literal, holds) in [(lt, x < y), (le, x <= y)] {
                            let mut with = fixed.clone();
                            with.push(literal);
                            let expected = if holds {
                                Answer::Satisfiable
                            } else {
                                Answer::Unsatisfiable
                            };
                            assert_eq!(
                                solver.solve(&with).unwrap(),
                                expected,
                                "{encoding:?} bound {bound}: {x} vs {y}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn bits_hold_the_bound() {
        assert_eq!(bits_for(1), 0);
        assert_eq!(bits_for(2), 1);
        assert_eq!(bits_for(4), 2);
        assert_eq!(bits_for(5), 3);
        assert_eq!(bits_for(1024), 10);
    }
}
