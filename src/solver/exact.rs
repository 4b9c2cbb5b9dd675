//! The exact rational solve of the transient system `A x = b`, `A = I - Q`
//! (method.md section 8, "When double precision cannot prove the bound"):
//! the fallback of the linear solver (`LinearSolver`) when a solve in double precision
//! cannot prove its error bound ([`super::SolverError::Unbounded`]) or its
//! residual ([`super::SolverError::Inaccurate`]), on systems small enough
//! for rational arithmetic to be cheap ([`DEFAULT_EXACT_LIMIT`]).
//!
//! The doubles that define `A` (the off-diagonal entries `-Q`, the row sums
//! `A 1`, the probabilities of leaving `T`) and `b` are turned into
//! rationals without rounding; the diagonal is their exact sum, and sparse
//! Gaussian elimination in the states' order, without pivoting (`A` is a
//! nonsingular M-matrix, so every pivot is positive), then back
//! substitution give `A^{-1} b` exactly. Each entry is rounded to the
//! nearest double, and the error bound is the largest of these roundings,
//! computed exactly and rounded up: the value is the exact value of the
//! chain the doubles describe, to the last bit.

use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{Signed, ToPrimitive, Zero};
use rustc_hash::FxHashMap;

use super::{SolverError, SparsePattern};

/// The most unknowns solved exactly by default ([`super::SolverSettings::exact_limit`]).
/// Measured (`experiments/exact-solve`, `results/exact-solve.csv`) on lazy
/// walks whose states a 2- or 3-node controller splits into blocks (escape
/// 1e-12, the chains of `tests/chains_memory.rs`): the exact solve stays
/// under about one second up to this many unknowns on a shared 2-core
/// machine.
pub const DEFAULT_EXACT_LIMIT: usize = 1_000;

/// The most matrix entries the elimination may hold at once, per unknown
/// of the limit: fill beyond this (a system far from a chain, e.g. a grid)
/// stops the exact solve, which would be slow, with an error instead.
pub const EXACT_ENTRIES_PER_UNKNOWN: usize = 40;

/// The exact solution of `A x = b`, rounded.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactSolution {
    /// Each entry of `A^{-1} b` rounded to the nearest double.
    pub x: Vec<f64>,
    /// `max_i |x_i - (A^{-1} b)_i|`, computed exactly and rounded up.
    pub error_bound: f64,
}

/// Why the exact solve was not carried out.
#[derive(Debug, Clone, PartialEq)]
pub enum ExactRefusal {
    /// The elimination needed more entries than its budget (`limit`).
    TooMuchFill {
        /// The budget on the entries held at once.
        limit: usize,
    },
    /// The matrix is not a valid chain system.
    Solver(SolverError),
}

/// Solves `A x = b` exactly, for the matrix given by its off-diagonal
/// `values` (aligned with `pattern`, the diagonal's entries ignored) and
/// its row sums `exits` (method.md section 8), holding at most
/// `entry_limit` entries during the elimination.
pub fn solve_exactly(
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    b: &[f64],
    entry_limit: usize,
) -> Result<ExactSolution, ExactRefusal> {
    let mut system = ExactSystem::of(pattern, values, exits, b).map_err(ExactRefusal::Solver)?;
    system.eliminate(entry_limit)?;
    let exact = system.back_substitute();
    let x: Vec<f64> = exact.iter().map(nearest_double).collect();
    let error_bound = exact
        .iter()
        .zip(&x)
        .map(|(e, &xi)| rounded_up(&(rational(xi) - e).abs()))
        .fold(0.0, f64::max);
    Ok(ExactSolution { x, error_bound })
}

/// `A` and `b` in rationals, row by row, with the rows below each
/// diagonal position that hold an entry in its column.
struct ExactSystem {
    rows: Vec<FxHashMap<usize, BigRational>>,
    below: Vec<Vec<usize>>,
    b: Vec<BigRational>,
    entries: usize,
}

impl ExactSystem {
    fn of(
        pattern: &SparsePattern,
        values: &[f64],
        exits: &[f64],
        b: &[f64],
    ) -> Result<Self, SolverError> {
        let n = pattern.n;
        let finite = |v: &f64| v.is_finite();
        if values.len() != pattern.nnz() || exits.len() != n || b.len() != n {
            return Err(SolverError::Malformed("sizes of the exact solve".into()));
        }
        if !(values.iter().all(finite) && exits.iter().all(finite) && b.iter().all(finite)) {
            return Err(SolverError::NonFinite("input of the exact solve"));
        }
        let mut rows = Vec::with_capacity(n);
        let mut below = vec![Vec::new(); n];
        let mut entries = 0;
        for (row, &exit) in exits.iter().enumerate() {
            let mut entries_of_row = FxHashMap::default();
            let mut diagonal = rational(exit);
            for k in pattern.row_range(row) {
                let column = pattern.columns[k];
                if column != row && values[k] != 0.0 {
                    let a = rational(values[k]);
                    diagonal -= &a;
                    entries_of_row.insert(column, a);
                    if column < row {
                        below[column].push(row);
                    }
                }
            }
            entries_of_row.insert(row, diagonal);
            entries += entries_of_row.len();
            rows.push(entries_of_row);
        }
        Ok(Self {
            rows,
            below,
            b: b.iter().map(|&v| rational(v)).collect(),
            entries,
        })
    }

    /// Gaussian elimination in the states' order: afterwards row `k` holds
    /// only columns `>= k`.
    fn eliminate(&mut self, entry_limit: usize) -> Result<(), ExactRefusal> {
        for k in 0..self.rows.len() {
            let pivot_row: Vec<(usize, BigRational)> = self.rows[k]
                .iter()
                .filter(|&(&j, _)| j > k)
                .map(|(&j, a)| (j, a.clone()))
                .collect();
            let pivot = self.rows[k][&k].clone();
            if !pivot.is_positive() {
                return Err(ExactRefusal::Solver(SolverError::Singular(format!(
                    "exact pivot {k} is not positive"
                ))));
            }
            let pivot_b = self.b[k].clone();
            for i in std::mem::take(&mut self.below[k]) {
                let Some(a_ik) = self.rows[i].remove(&k) else {
                    continue;
                };
                self.entries -= 1;
                let factor = a_ik / &pivot;
                for (j, a_kj) in &pivot_row {
                    let update = &factor * a_kj;
                    match self.rows[i].get_mut(j) {
                        Some(a_ij) => *a_ij -= update,
                        None => {
                            self.rows[i].insert(*j, -update);
                            self.entries += 1;
                            if *j < i {
                                self.below[*j].push(i);
                            }
                        }
                    }
                }
                let update = &factor * &pivot_b;
                self.b[i] -= update;
                if self.entries > entry_limit {
                    return Err(ExactRefusal::TooMuchFill { limit: entry_limit });
                }
            }
        }
        Ok(())
    }

    /// `x_k = (b_k - sum_{j > k} a_kj x_j) / a_kk`, from the last row up.
    fn back_substitute(&self) -> Vec<BigRational> {
        let n = self.rows.len();
        let mut x = vec![BigRational::zero(); n];
        for k in (0..n).rev() {
            let mut sum = self.b[k].clone();
            for (&j, a_kj) in &self.rows[k] {
                if j > k {
                    sum -= a_kj * &x[j];
                }
            }
            x[k] = sum / &self.rows[k][&k];
        }
        x
    }
}

/// A finite double as the rational it is.
fn rational(value: f64) -> BigRational {
    BigRational::from_float(value).unwrap_or_else(|| BigRational::from_integer(BigInt::zero()))
}

/// The double nearest to `value`: num-rational's conversion (which may be
/// off by a few units in the last place on long numbers), then moved one
/// double at a time while a neighbour is closer.
fn nearest_double(value: &BigRational) -> f64 {
    let Some(mut nearest) = value.to_f64().filter(|x| x.is_finite()) else {
        return f64::NAN;
    };
    let distance = |x: f64| (rational(x) - value).abs();
    let mut best = distance(nearest);
    loop {
        let closer = [next_double(nearest, -1.0), next_double(nearest, 1.0)]
            .into_iter()
            .filter(|x| x.is_finite())
            .map(|x| (distance(x), x))
            .find(|(d, _)| *d < best);
        match closer {
            Some((d, x)) => (best, nearest) = (d, x),
            None => return nearest,
        }
    }
}

/// The double next to the finite `x` in the direction of `sign`.
fn next_double(x: f64, sign: f64) -> f64 {
    if x == 0.0 {
        return sign * f64::from_bits(1);
    }
    let bits = x.to_bits();
    if (x > 0.0) == (sign > 0.0) {
        f64::from_bits(bits + 1)
    } else {
        f64::from_bits(bits - 1)
    }
}

/// A double at least `value` (non-negative): the nearest double, raised by
/// a relative `2^-50` and the smallest subnormal to cover its rounding.
fn rounded_up(value: &BigRational) -> f64 {
    let nearest = nearest_double(value);
    nearest * (1.0 + 2f64.powi(-50)) + f64::from_bits(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `A = [[1, -1/2], [-1/4, 1]]` (exits 1/2 and 3/4), `b = (1, 0)`:
    /// `x = (8/7, 2/7)`.
    #[test]
    fn a_two_state_system_is_solved_to_the_nearest_double() {
        let pattern = SparsePattern {
            n: 2,
            row_offsets: vec![0, 2, 4],
            columns: vec![0, 1, 0, 1],
        };
        let values = [0.0, -0.5, -0.25, 0.0];
        let solution = solve_exactly(&pattern, &values, &[0.5, 0.75], &[1.0, 0.0], 100).unwrap();
        assert_eq!(solution.x, vec![8.0 / 7.0, 2.0 / 7.0]);
        assert_eq!(next_double(1.0, 1.0), 1.0 + f64::EPSILON);
        assert_eq!(next_double(-1.0, 1.0), -1.0 + f64::EPSILON / 2.0);
        assert_eq!(next_double(0.0, -1.0), -f64::from_bits(1));
        assert!(solution.error_bound > 0.0 && solution.error_bound < 2e-16);
    }

    #[test]
    fn fill_beyond_the_budget_is_refused() {
        let pattern = SparsePattern {
            n: 2,
            row_offsets: vec![0, 2, 4],
            columns: vec![0, 1, 0, 1],
        };
        let values = [0.0, -0.5, -0.25, 0.0];
        let refused = solve_exactly(&pattern, &values, &[0.5, 0.75], &[1.0, 0.0], 2);
        assert_eq!(refused, Err(ExactRefusal::TooMuchFill { limit: 2 }));
    }
}
