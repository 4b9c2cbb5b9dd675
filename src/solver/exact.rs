//! The exact solve of the transient system `A x = b`, `A = I - Q`
//! (method.md section 8, "When double precision cannot prove the bound"):
//! the fallback of the linear solver (`LinearSolver`) when a solve in double
//! precision cannot prove its error bound ([`super::SolverError::Unbounded`])
//! or its residual ([`super::SolverError::Inaccurate`]), on systems of at
//! most [`DEFAULT_EXACT_LIMIT`] unknowns and within a work budget
//! ([`ExactBudget`]).
//!
//! The doubles that define `A` (the off-diagonal entries `-Q`, the row sums
//! `A 1`, the probabilities of leaving `T`) and `b` are dyadic rationals:
//! each row, `b`'s entry included, is multiplied by the power of two that
//! makes it integer, and the diagonal is the exact sum of the row. The
//! integer system is solved by Dixon's p-adic lifting (`lifting`): one
//! sparse LU of `A mod p` for a prime `p` below `2^62` (`modular`), then
//! the digits of `x = sum_t d_t p^t`, each from an exact integer residual,
//! until rational reconstruction finds a common denominator `D` and
//! numerators `N`; `A N = D b` is then checked in integers, which proves
//! `x = N / D` whatever the method (`A` is nonsingular: its LU modulo `p`
//! has nonzero pivots). Each entry is rounded to the nearest double, and
//! the error bound is the largest of these roundings, computed exactly and
//! rounded up: the value is the exact value of the chain the doubles
//! describe, to the last bit.
//!
//! [`solve_by_rational_elimination`] is the earlier method, kept as a
//! reference: sparse Gaussian elimination in [`BigRational`], whose numbers
//! (and time) grow with every elimination step when the probabilities are
//! full-precision doubles.

mod lifting;
mod modular;

use num_bigint::{BigInt, BigUint};
use num_integer::Integer;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};
use rustc_hash::FxHashMap;

use super::{SolverError, SparsePattern};

/// The most unknowns solved exactly by default ([`super::SolverSettings::exact_limit`]).
/// Measured (`examples/exact_fallback.rs`, `results/exact-fallback.csv`) on
/// stiff lazy walks with full-precision random probabilities split by 1-
/// to 3-node memories: the p-adic solve takes 0.2 to 2.3 s of CPU at this
/// size on a shared 2-core machine.
pub const DEFAULT_EXACT_LIMIT: usize = 1_000;

/// The most entries of the LU modulo a prime, per unknown of the limit:
/// fill beyond this (a system far from a chain, e.g. a grid) stops the
/// exact solve, which would be slow, with an error instead.
pub const EXACT_ENTRIES_PER_UNKNOWN: usize = 40;

/// The most units of work of one exact solve, per unknown of the limit.
/// A unit is an estimated word operation of the lifting (a product or sum
/// of 64-bit words, counted from the sizes of the LU, the matrix and the
/// numbers): measured at 3 to 5 ns each on a shared 2-core machine
/// (`examples/exact_fallback.rs`), so that with [`DEFAULT_EXACT_LIMIT`]
/// the budget of 3e9 units is some ten seconds, several times what the
/// stiff walks of `results/exact-fallback.csv` need up to 1,000 unknowns.
pub const EXACT_WORK_PER_UNKNOWN: u64 = 3_000_000;

/// What an exact solve may spend before it refuses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExactBudget {
    /// The most entries of the LU modulo a prime.
    pub entries: usize,
    /// The most units of work ([`EXACT_WORK_PER_UNKNOWN`]).
    pub work: u64,
}

impl ExactBudget {
    /// The budget of a solver whose exact limit is `exact_limit` unknowns:
    /// [`EXACT_ENTRIES_PER_UNKNOWN`] and [`EXACT_WORK_PER_UNKNOWN`] per
    /// unknown of the limit.
    pub fn for_limit(exact_limit: usize) -> Self {
        Self {
            entries: EXACT_ENTRIES_PER_UNKNOWN.saturating_mul(exact_limit),
            work: EXACT_WORK_PER_UNKNOWN.saturating_mul(exact_limit as u64),
        }
    }

    /// No limit.
    pub fn unlimited() -> Self {
        Self {
            entries: usize::MAX,
            work: u64::MAX,
        }
    }
}

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
    /// The LU modulo a prime (or, by [`solve_by_rational_elimination`],
    /// the elimination) needed more entries than its budget (`limit`).
    TooMuchFill {
        /// The budget on the entries.
        limit: usize,
    },
    /// The solve used its budget of work units without finding the
    /// solution: its numbers are longer than `bits` bits.
    TooMuchWork {
        /// The budget of work units ([`EXACT_WORK_PER_UNKNOWN`]).
        limit: u64,
        /// The bits of the modulus `p^t` reached: the exact solution's
        /// numerators and denominator have about half as many bits or more.
        bits: u64,
    },
    /// The matrix is not a valid chain system.
    Solver(SolverError),
}

/// Solves `A x = b` exactly (module documentation) for the matrix given by
/// its off-diagonal `values` (aligned with `pattern`, the diagonal's
/// entries ignored) and its row sums `exits` (method.md section 8), within
/// `budget`.
pub fn solve_exactly(
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    b: &[f64],
    budget: &ExactBudget,
) -> Result<ExactSolution, ExactRefusal> {
    check(pattern, values, exits, b).map_err(ExactRefusal::Solver)?;
    let system = integer_system(pattern, values, exits, b);
    if system.rows.is_empty() {
        return Ok(ExactSolution {
            x: Vec::new(),
            error_bound: 0.0,
        });
    }
    let solution =
        lifting::solve(&system, budget.entries, budget.work).map_err(|failure| match failure {
            lifting::LiftFailure::Singular(row) => {
                ExactRefusal::Solver(SolverError::Singular(format!(
                    "the exact solve met a zero pivot at row {row} modulo each prime it \
                     tried: the matrix is singular, or needs pivoting (not a chain's M-matrix)"
                )))
            }
            lifting::LiftFailure::TooMuchFill => ExactRefusal::TooMuchFill {
                limit: budget.entries,
            },
            lifting::LiftFailure::TooMuchWork(bits) => ExactRefusal::TooMuchWork {
                limit: budget.work,
                bits,
            },
        })?;
    let mut x = Vec::with_capacity(solution.numerators.len());
    let mut error_bound: f64 = 0.0;
    for numerator in &solution.numerators {
        let (nearest, error) = nearest_with_error(numerator, &solution.denominator);
        x.push(nearest);
        error_bound = error_bound.max(error);
    }
    Ok(ExactSolution { x, error_bound })
}

/// The sizes and finiteness that both exact solves require.
fn check(
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    b: &[f64],
) -> Result<(), SolverError> {
    let n = pattern.n;
    let finite = |v: &f64| v.is_finite();
    if values.len() != pattern.nnz() || exits.len() != n || b.len() != n {
        return Err(SolverError::Malformed("sizes of the exact solve".into()));
    }
    if !(values.iter().all(finite) && exits.iter().all(finite) && b.iter().all(finite)) {
        return Err(SolverError::NonFinite("input of the exact solve"));
    }
    Ok(())
}

/// A finite nonzero double as `(m, e)` with value `m 2^e`, `m` odd.
fn dyadic(value: f64) -> (i64, i32) {
    let bits = value.to_bits();
    let exponent_field = ((bits >> 52) & 0x7ff) as i32;
    let fraction = (bits & ((1 << 52) - 1)) as i64;
    let (mut mantissa, mut exponent) = if exponent_field == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1 << 52), exponent_field - 1075)
    };
    let zeros = mantissa.trailing_zeros();
    mantissa >>= zeros;
    exponent += zeros as i32;
    (if value < 0.0 { -mantissa } else { mantissa }, exponent)
}

/// The system scaled row by row to integers: row `i` (its off-diagonal
/// entries, exit and `b_i`) times `2^-e` for the smallest exponent `e` of
/// its nonzero doubles; the diagonal is the exit minus the off-diagonal
/// entries, exactly.
fn integer_system(
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    b: &[f64],
) -> lifting::IntegerSystem {
    let mut rows = Vec::with_capacity(pattern.n);
    let mut rhs = Vec::with_capacity(pattern.n);
    for row in 0..pattern.n {
        let off_diagonal: Vec<(usize, (i64, i32))> = pattern
            .row_range(row)
            .filter(|&k| pattern.columns[k] != row && values[k] != 0.0)
            .map(|k| (pattern.columns[k], dyadic(values[k])))
            .collect();
        let exit = (exits[row] != 0.0).then(|| dyadic(exits[row]));
        let right = (b[row] != 0.0).then(|| dyadic(b[row]));
        let lowest = off_diagonal
            .iter()
            .map(|(_, d)| d.1)
            .chain(exit.map(|d| d.1))
            .chain(right.map(|d| d.1))
            .min()
            .unwrap_or(0);
        let integer = |d: Option<(i64, i32)>| match d {
            Some((m, e)) => BigInt::from(m) << ((e - lowest) as u32),
            None => BigInt::zero(),
        };
        let mut diagonal = integer(exit);
        let mut entries = Vec::with_capacity(off_diagonal.len() + 1);
        for (column, d) in off_diagonal {
            let a = integer(Some(d));
            diagonal -= &a;
            entries.push((column, a));
        }
        entries.push((row, diagonal));
        rows.push(entries);
        rhs.push(integer(right));
    }
    lifting::IntegerSystem { rows, b: rhs }
}

/// `2^e` for `-1074 <= e <= 1023`, exactly.
fn power_of_two(e: i64) -> f64 {
    if e >= -1022 {
        f64::from_bits(((e + 1023) as u64) << 52)
    } else {
        f64::from_bits(1u64 << (e + 1074))
    }
}

/// `x 2^e`, rounded at most once per step of at most 2^1000 (a double at
/// least the exact product once the smallest subnormal is added).
fn scaled(mut x: f64, mut e: i64) -> f64 {
    while e > 1000 {
        x *= power_of_two(1000);
        e -= 1000;
    }
    while e < -1000 {
        x *= power_of_two(-1000);
        e += 1000;
    }
    x * power_of_two(e)
}

/// `a 2^s / d` as `(quotient, remainder)` of the shifted numerator or
/// denominator.
fn shifted_quotient(a: &BigUint, d: &BigUint, s: i64) -> (BigUint, BigUint, BigUint) {
    if s >= 0 {
        let (q, r) = (a << (s as u64)).div_rem(d);
        (q, r, d.clone())
    } else {
        let d = d << ((-s) as u64);
        let (q, r) = a.div_rem(&d);
        (q, r, d)
    }
}

/// A double at least `num / den 2^e` (`den > 0`).
fn rounded_up_quotient(num: &BigUint, den: &BigUint, e: i64) -> f64 {
    if num.is_zero() {
        return 0.0;
    }
    let s = 64 - (num.bits() as i64 - den.bits() as i64);
    let (q, _, _) = shifted_quotient(num, den, s);
    let above = (q + 1u8).to_f64().unwrap_or(f64::INFINITY) * (1.0 + 2f64.powi(-50));
    scaled(above, e - s) * (1.0 + 2f64.powi(-50)) + f64::from_bits(1)
}

/// The double nearest to `numerator / denominator` (ties to even) and a
/// double at least their distance.
fn nearest_with_error(numerator: &BigInt, denominator: &BigUint) -> (f64, f64) {
    if numerator.is_zero() {
        return (0.0, 0.0);
    }
    let a = numerator.magnitude();
    // x 2^shift = q + r / d' with q of 55 or 56 bits.
    let shift = 55 - (a.bits() as i64 - denominator.bits() as i64);
    let (q, r, d) = shifted_quotient(a, denominator, shift);
    let top = q.bits() as i64 - 1 - shift;
    if top > 1023 {
        return (f64::INFINITY.copysign(sign_of(numerator)), f64::INFINITY);
    }
    let lowest = (top - 52).max(-1074);
    let drop = (lowest + shift) as u64;
    let kept = &q >> drop;
    let low = &q - (&kept << drop);
    let half = BigUint::one() << (drop - 1);
    let up = match low.cmp(&half) {
        std::cmp::Ordering::Greater => true,
        std::cmp::Ordering::Equal => !r.is_zero() || kept.is_odd(),
        std::cmp::Ordering::Less => false,
    };
    let kept = kept + u8::from(up);
    let nearest = kept.to_f64().unwrap_or(f64::INFINITY) * power_of_two(lowest);
    // |nearest - x| 2^shift = |kept 2^drop d' - q d' - r| / d'.
    let above = BigInt::from(&kept << drop) - BigInt::from(q);
    let distance = (above * BigInt::from(d.clone()) - BigInt::from(r))
        .magnitude()
        .clone();
    let error = if nearest.is_infinite() {
        f64::INFINITY
    } else {
        rounded_up_quotient(&distance, &d, -shift)
    };
    (nearest.copysign(sign_of(numerator)), error)
}

/// `1.0` or `-1.0` by the sign of `x`.
fn sign_of(x: &BigInt) -> f64 {
    if x.is_negative() { -1.0 } else { 1.0 }
}

/// Solves `A x = b` exactly like [`solve_exactly`], by sparse Gaussian
/// elimination in [`BigRational`] in the states' order, without pivoting
/// (`A` is a nonsingular M-matrix, so every pivot is positive), and back
/// substitution, holding at most `entry_limit` entries: the earlier
/// method, kept as a reference for tests and measurements. Its numbers
/// grow with every elimination step on full-precision data (42 s for 174
/// unknowns, issue 57).
pub fn solve_by_rational_elimination(
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
        check(pattern, values, exits, b)?;
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
pub(super) fn next_double(x: f64, sign: f64) -> f64 {
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
        let budget = ExactBudget::unlimited();
        let solution =
            solve_exactly(&pattern, &values, &[0.5, 0.75], &[1.0, 0.0], &budget).unwrap();
        let reference =
            solve_by_rational_elimination(&pattern, &values, &[0.5, 0.75], &[1.0, 0.0], 100);
        assert_eq!(reference.unwrap().x, solution.x);
        assert_eq!(solution.x, vec![8.0 / 7.0, 2.0 / 7.0]);
        assert_eq!(next_double(1.0, 1.0), 1.0 + f64::EPSILON);
        assert_eq!(next_double(-1.0, 1.0), -1.0 + f64::EPSILON / 2.0);
        assert_eq!(next_double(0.0, -1.0), -f64::from_bits(1));
        assert!(solution.error_bound > 0.0 && solution.error_bound < 2e-16);
    }

    proptest::proptest! {
        /// The rounding of `N / D` against the reference (the nearest
        /// double by search), across the range of doubles, subnormals
        /// included.
        #[test]
        fn quotients_round_to_the_nearest_double_with_a_sound_error(
            numerator in proptest::num::i128::ANY,
            denominator in 1u128..,
            shift in -1200i32..1200,
        ) {
            let (mut num, mut den) = (BigInt::from(numerator), BigUint::from(denominator));
            if shift >= 0 {
                num <<= shift as u32;
            } else {
                den <<= (-shift) as u32;
            }
            let exact = BigRational::new(num.clone(), BigInt::from(den.clone()));
            let (nearest, error) = nearest_with_error(&num, &den);
            if nearest.is_finite() {
                let reference = nearest_double(&exact);
                let distance = (rational(nearest) - &exact).abs();
                let reference_distance = (rational(reference) - &exact).abs();
                proptest::prop_assert!(distance <= reference_distance, "{} {}", nearest, reference);
                proptest::prop_assert!(rational(error) >= distance);
                proptest::prop_assert!(error <= rounded_up(&distance) * (1.0 + 1e-14) + f64::from_bits(2));
            } else {
                proptest::prop_assert!(exact.abs() > rational(f64::MAX));
            }
        }
    }

    #[test]
    fn ties_round_to_even_and_tiny_values_to_subnormals() {
        let power = |k: u32| BigUint::one() << k;
        let int = |k: u32, plus: i64| (BigInt::one() << k) + plus;
        // 1 + 2^-53, halfway between 1 and 1 + 2^-52: the even one, 1.
        let (nearest, error) = nearest_with_error(&int(53, 1), &power(53));
        assert_eq!(nearest, 1.0);
        assert!(error >= 2f64.powi(-53) && error < 2f64.powi(-53) * (1.0 + 1e-14));
        // 1 + 3 2^-54 is nearer 1 + 2^-52.
        assert_eq!(
            nearest_with_error(&int(54, 3), &power(54)).0,
            1.0 + f64::EPSILON
        );
        // 2^-1075, halfway between 0 and the smallest subnormal: 0.
        assert_eq!(nearest_with_error(&BigInt::one(), &power(1075)).0, 0.0);
        // 3/4 of the smallest subnormal: the smallest subnormal.
        let three = BigInt::from(3);
        assert_eq!(
            nearest_with_error(&three, &power(1076)).0,
            f64::from_bits(1)
        );
        assert_eq!(
            nearest_with_error(&-BigInt::one(), &BigUint::from(3u8)).0,
            -1.0 / 3.0
        );
        let (huge, error) = nearest_with_error(&int(1100, 0), &BigUint::one());
        assert!(huge == f64::INFINITY && error == f64::INFINITY);
    }

    #[test]
    fn fill_beyond_the_budget_is_refused() {
        let pattern = SparsePattern {
            n: 2,
            row_offsets: vec![0, 2, 4],
            columns: vec![0, 1, 0, 1],
        };
        let values = [0.0, -0.5, -0.25, 0.0];
        let budget = ExactBudget {
            entries: 2,
            work: u64::MAX,
        };
        let refused = solve_exactly(&pattern, &values, &[0.5, 0.75], &[1.0, 0.0], &budget);
        assert_eq!(refused, Err(ExactRefusal::TooMuchFill { limit: 2 }));
        let refused =
            solve_by_rational_elimination(&pattern, &values, &[0.5, 0.75], &[1.0, 0.0], 2);
        assert_eq!(refused, Err(ExactRefusal::TooMuchFill { limit: 2 }));
        let budget = ExactBudget {
            entries: 100,
            work: 10,
        };
        let refused = solve_exactly(&pattern, &values, &[0.5, 0.75], &[1.0, 0.0], &budget);
        assert!(
            matches!(
                refused,
                Err(ExactRefusal::TooMuchWork { limit: 10, bits: 1 })
            ),
            "{refused:?}"
        );
    }
}
