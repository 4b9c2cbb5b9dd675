//! Error bounds on the solutions of `A x = b`, `A = I - Q` a nonsingular
//! M-matrix (method.md section 8).
//!
//! `A^{-1} >= 0` entrywise, so for any `x` with residual `r = A x - b`,
//!
//! ```text
//! |x - A^{-1} b| = |A^{-1} r| <= A^{-1} |r| <= ||r||_inf t,    t = A^{-1} 1,
//! ```
//!
//! where `t(m)` is the expected number of steps the chain spends in `T` from
//! `m`. Neither `r` nor `t` is known exactly; both are bounded soundly:
//!
//! * **the residual**: [`residual_bound`] computes `r_i` in floating point
//!   and adds the rounding of that computation: for a sum of `k` products
//!   the error is at most `gamma_{k+1} (|A| |x| + |b|)_i` with
//!   `gamma_k = k u / (1 - k u)` (Higham, *Accuracy and Stability of
//!   Numerical Algorithms*, 2nd ed., 2002, section 3.1). The compensated
//!   variant evaluates the row as if in twice the working precision
//!   (Ogita, Rump and Oishi, "Accurate sum and dot product", SIAM J. Sci.
//!   Comput. 26(6), 2005, algorithm Dot2: error at most
//!   `u |r_i| + gamma_k^2 (|A| |x| + |b|)_i`), which iterative refinement
//!   needs once the plain rounding term dominates;
//! * **the expected time**: for any `t_hat` with `sigma >= ||A t_hat - 1||_inf`
//!   (a residual bound as above) and `sigma < 1`,
//!   `t = t_hat - A^{-1}(A t_hat - 1) <= t_hat + sigma t`, so
//!   `max t <= max t_hat / (1 - sigma)`. [`ExpectedTime`] keeps `t_hat`
//!   between factorisations: while the matrix changes little (the optimiser's
//!   steps) one matrix-vector product re-certifies it, and only when
//!   `sigma` exceeds [`REUSE_LIMIT`] is `A t = 1` solved again.
//!
//! The floating-point environment is Rust's default (round to nearest,
//! subnormals kept), which these error bounds assume.

use super::SparsePattern;

/// The unit roundoff `u = 2^-53` of `f64`.
const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;

/// A stored estimate `t_hat` of `A^{-1} 1` is re-used while
/// `||A t_hat - 1||_inf` is at most this (the bound on `max t` is then at
/// most twice `max t_hat`).
pub const REUSE_LIMIT: f64 = 0.5;

/// The most rounds of iterative refinement a solve gets to bring its error
/// bound under the tolerance.
pub const MAX_REFINEMENTS: usize = 4;

/// The most rounds of iterative refinement in extended precision (the
/// solution carried as a double-double, [`residual_bound_of_sum`]) after
/// refinement in double precision stalled above the tolerance.
pub const MAX_EXTENDED_REFINEMENTS: usize = 8;

/// `gamma_k = k u / (1 - k u)`, the bound on the relative rounding error of
/// `k` floating-point operations (Higham, Lemma 3.1); infinite when `k u >= 1`.
fn gamma(k: usize) -> f64 {
    let ku = k as f64 * UNIT_ROUNDOFF;
    if ku >= 1.0 {
        f64::INFINITY
    } else {
        ku / (1.0 - ku)
    }
}

/// How a residual is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Evaluation {
    /// Plain floating point, rounding bounded by `gamma_{k+1} (|A||x| + |b|)`.
    Plain,
    /// Compensated (Dot2), rounding bounded by `u |r| + gamma_k^2 (|A||x| + |b|)`.
    Compensated,
}

/// `(s, e)` with `s = fl(a + b)` and `a + b = s + e` exactly (Knuth's TwoSum).
#[inline]
pub(super) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let z = s - a;
    (s, (a - (s - z)) + (b - z))
}

/// `(hi, lo)` with `a = hi + lo`, each of at most 26 significant bits
/// (Veltkamp's splitting).
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a;
    let hi = c - (c - a);
    (hi, a - hi)
}

/// `(p, e)` with `p = fl(a b)` and `a b = p + e` exactly (Dekker's
/// TwoProduct; no fused multiply-add needed).
#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    (p, al * bl - (((p - ah * bh) - al * bh) - ah * bl))
}

/// A bound on `max_i |(A x - rhs)_i|` (the true residual, not its rounded
/// value) for the matrix with `pattern`, off-diagonal `values` and row sums
/// `exits` (its diagonal entries are not read); `rhs(i)` gives the
/// right-hand side. When `rounded` is given, it receives the computed
/// residual `fl((A x - rhs)_i)`. NaN if any number is not finite.
///
/// Each row is evaluated in the form of Grassmann, Taksar and Heyman,
///
/// ```text
/// (A x - rhs)_i = sum_{j != i} |a_ij| (x_i - x_j) + exit_i x_i - rhs_i,
/// ```
///
/// never through the diagonal: on a block of states that the chain leaves
/// with probability `1e-13`, `a_ii x_i` and `sum_j a_ij x_j` agree to 13
/// digits and their rounding would swamp the residual, while here every
/// term is as small as the residual's true size.
pub fn residual_bound(
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    x: &[f64],
    rhs: impl Fn(usize) -> f64,
    evaluation: Evaluation,
    rounded: Option<&mut [f64]>,
) -> f64 {
    worst_row_bound(pattern, rounded, |row| {
        let b = rhs(row);
        match evaluation {
            Evaluation::Plain => plain_row(pattern, values, exits, x, row, b),
            Evaluation::Compensated => compensated_row(pattern, values, exits, x, None, row, b),
        }
    })
}

/// [`residual_bound`] (compensated) for the solution `high + low`, held
/// as the unevaluated sum of two vectors (a double-double solution of
/// iterative refinement in extended precision): every difference
/// `x_i - x_j` and the exit term see both parts.
pub fn residual_bound_of_sum(
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    high: &[f64],
    low: &[f64],
    rhs: impl Fn(usize) -> f64,
    rounded: Option<&mut [f64]>,
) -> f64 {
    worst_row_bound(pattern, rounded, |row| {
        compensated_row(pattern, values, exits, high, Some(low), row, rhs(row))
    })
}

/// One row's computed residual and what bounds its rounding.
struct RowResidual {
    /// `fl((A x - rhs)_i)`.
    residual: f64,
    /// The rounding of the computation, before its own rounding is added.
    rounding: f64,
    /// The floating-point operations of the row (for `gamma`).
    terms: usize,
}

/// The largest row bound `(|r_i| + rounding (1 + gamma)) (1 + u)` plus the
/// underflow allowance; the computed residuals go to `rounded`. NaN if any
/// row's is.
fn worst_row_bound(
    pattern: &SparsePattern,
    mut rounded: Option<&mut [f64]>,
    row_residual: impl Fn(usize) -> RowResidual,
) -> f64 {
    let mut worst: f64 = 0.0;
    for row in 0..pattern.n {
        let RowResidual {
            residual,
            rounding,
            terms,
        } = row_residual(row);
        if let Some(out) = rounded.as_deref_mut() {
            out[row] = residual;
        }
        // The magnitude itself is rounded (relative gamma_k); underflow in
        // a product or in TwoProduct's splitting errs by less than the
        // smallest normal number per operation.
        let underflow = 4.0 * terms as f64 * f64::MIN_POSITIVE;
        let bound = (residual.abs() + rounding * (1.0 + gamma(terms + 2))) * (1.0 + UNIT_ROUNDOFF)
            + underflow;
        if bound.is_nan() {
            return f64::NAN;
        }
        worst = worst.max(bound);
    }
    worst
}

/// Row `row` of the residual in plain floating point: each product of a
/// rounded difference costs two roundings, `gamma_{k+1} (|A||x| + |b|)`.
fn plain_row(
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    x: &[f64],
    row: usize,
    b: f64,
) -> RowResidual {
    let xi = x[row];
    let exit_term = exits[row] * xi;
    let mut magnitude = b.abs() + exit_term.abs();
    let mut terms = 2;
    let mut sum = exit_term - b;
    for k in pattern.row_range(row) {
        let column = pattern.columns[k];
        if column != row {
            let product = -values[k] * (xi - x[column]);
            magnitude += product.abs();
            sum += product;
            terms += 2;
        }
    }
    RowResidual {
        residual: sum,
        rounding: gamma(terms + 2) * magnitude,
        terms,
    }
}

/// Row `row` of the residual by Dot2 on the exact expansion
/// `x_i - x_j = d + d_low` (TwoSum): rounding at most
/// `2 u |r_i| + 2 gamma^2 (|A||x| + |b|)`. With `low`, the solution is
/// `x + low`: the low parts join `d_low` and the exit term, and their own
/// roundings (a relative `3 u` of each such product, bounded term by term)
/// are added to the rounding.
fn compensated_row(
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    x: &[f64],
    low: Option<&[f64]>,
    row: usize,
    b: f64,
) -> RowResidual {
    let xi = x[row];
    let low_i = low.map_or(0.0, |low| low[row]);
    let (exit_term, exit_error) = two_product(exits[row], xi);
    let mut magnitude = b.abs() + exit_term.abs();
    let mut terms = 2;
    let (mut sum, mut correction) = two_sum(exit_term, -b);
    correction += exit_error;
    // Products of low parts, each rounded once and summed once.
    let mut low_rounding = 0.0;
    if low.is_some() {
        let exit_low = exits[row] * low_i;
        correction += exit_low;
        magnitude += exit_low.abs();
        low_rounding += 3.0 * UNIT_ROUNDOFF * exit_low.abs();
    }
    for k in pattern.row_range(row) {
        let column = pattern.columns[k];
        if column != row {
            let weight = -values[k];
            let (difference, mut difference_low) = two_sum(xi, -x[column]);
            if let Some(low) = low {
                let low_difference = low_i - low[column];
                difference_low += low_difference;
                low_rounding += 3.0
                    * UNIT_ROUNDOFF
                    * weight.abs()
                    * (difference_low.abs() + low_i.abs() + low[column].abs());
            }
            let (product, product_error) = two_product(weight, difference);
            let (next, sum_error) = two_sum(sum, product);
            let low_product = weight * difference_low;
            sum = next;
            correction += product_error + sum_error + low_product;
            magnitude += product.abs() + low_product.abs();
            terms += 2;
        }
    }
    let residual = sum + correction;
    RowResidual {
        residual,
        rounding: 2.0 * UNIT_ROUNDOFF * residual.abs()
            + 2.0 * gamma(terms + 2).powi(2) * magnitude
            + low_rounding * (1.0 + gamma(terms + 2)),
        terms,
    }
}

/// An estimate `t_hat` of the expected times `t = A^{-1} 1` and what it
/// certifies: see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct ExpectedTime {
    estimate: Vec<f64>,
    largest: f64,
}

impl ExpectedTime {
    /// No estimate yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// The estimate `t_hat` (empty before the first [`Self::store`]).
    #[cfg(test)]
    pub fn estimate(&self) -> &[f64] {
        &self.estimate
    }

    /// A mutable estimate of length `n`, to be solved for.
    pub fn estimate_mut(&mut self, n: usize) -> &mut [f64] {
        self.estimate.resize(n, 0.0);
        &mut self.estimate
    }

    /// `max t_hat` of the last estimate stored (not certified).
    pub fn largest(&self) -> f64 {
        self.largest
    }

    /// Records that the estimate was replaced.
    pub fn store(&mut self) {
        self.largest = self.estimate.iter().copied().fold(0.0, f64::max);
    }

    /// `max t <= max t_hat / (1 - sigma)` for the matrix `values` when the
    /// estimate's residual bound `sigma` is below `limit`; `None` when there
    /// is no estimate of the right size or it does not certify.
    pub fn certify(
        &self,
        pattern: &SparsePattern,
        values: &[f64],
        exits: &[f64],
        limit: f64,
    ) -> Option<f64> {
        if self.estimate.len() != pattern.n || pattern.n == 0 {
            return None;
        }
        let sigma = residual_bound(
            pattern,
            values,
            exits,
            &self.estimate,
            |_| 1.0,
            Evaluation::Plain,
            None,
        );
        let certified = |sigma: f64| {
            (sigma < limit && self.largest.is_finite())
                .then(|| self.largest.max(1.0) / (1.0 - sigma))
        };
        certified(sigma).or_else(|| {
            let sigma = residual_bound(
                pattern,
                values,
                exits,
                &self.estimate,
                |_| 1.0,
                Evaluation::Compensated,
                None,
            );
            certified(sigma)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_systems::tridiagonal;
    use super::*;

    fn row_sums(pattern: &SparsePattern, values: &[f64]) -> Vec<f64> {
        let mut exits = vec![0.0; pattern.n];
        super::super::derive_exits(pattern, values, &mut exits);
        exits
    }

    #[test]
    fn exact_products_and_sums_recover_what_rounding_loses() {
        let (s, e) = two_sum(1.0, 1e-20);
        assert_eq!((s, e), (1.0, 1e-20));
        let a = 1.0 + f64::EPSILON;
        let (p, e) = two_product(a, a);
        assert_eq!(p, 1.0 + 2.0 * f64::EPSILON);
        assert_eq!(e, f64::EPSILON * f64::EPSILON);
    }

    #[test]
    fn the_residual_bound_covers_the_true_residual_of_a_lazy_row() {
        // One row: (1e-13) x = 1e-13 / 3 at x = fl(1/3); the true residual is
        // 1e-13 (fl(1/3) - 1/3) - (fl(1e-13/3) - 1e-13/3), at most ~1e-29.
        let pattern = SparsePattern {
            n: 1,
            row_offsets: vec![0, 1],
            columns: vec![0],
        };
        let values = [1e-13];
        let x = [1.0 / 3.0];
        let b = 1e-13 / 3.0;
        for evaluation in [Evaluation::Plain, Evaluation::Compensated] {
            let bound = residual_bound(&pattern, &values, &[1e-13], &x, |_| b, evaluation, None);
            assert!(bound > 0.0 && bound < 1e-28, "{evaluation:?}: {bound:e}");
        }
    }

    #[test]
    fn a_nan_makes_the_bound_nan() {
        let (pattern, values) = tridiagonal(3, 0.4);
        let x = [0.0, f64::NAN, 0.0];
        let exits = row_sums(&pattern, &values);
        let bound = residual_bound(
            &pattern,
            &values,
            &exits,
            &x,
            |_| 1.0,
            Evaluation::Plain,
            None,
        );
        assert!(bound.is_nan());
    }

    #[test]
    fn an_estimate_of_the_expected_time_certifies_its_matrix_and_its_neighbours() {
        // Tridiagonal 1 / -0.4: t solves A t = 1 exactly enough by LU.
        let (pattern, values) = tridiagonal(30, 0.4);
        let mut lu = super::super::LuSolver::new(pattern.clone(), 1e-9).unwrap();
        lu.factorize(&values).unwrap();
        let mut time = ExpectedTime::new();
        lu.solve(&vec![1.0; 30], time.estimate_mut(30)).unwrap();
        time.store();
        let exact_max = time.estimate().iter().copied().fold(0.0, f64::max);
        let bound = time
            .certify(&pattern, &values, &row_sums(&pattern, &values), REUSE_LIMIT)
            .unwrap();
        assert!(bound >= exact_max && bound < exact_max * (1.0 + 1e-12));
        let nearby: Vec<f64> = values
            .iter()
            .map(|&v| if v < 0.0 { v * 1.01 } else { v })
            .collect();
        let mut lu_nearby = super::super::LuSolver::new(pattern.clone(), 1e-9).unwrap();
        lu_nearby.factorize(&nearby).unwrap();
        let mut exact = vec![0.0; 30];
        lu_nearby.solve(&vec![1.0; 30], &mut exact).unwrap();
        let true_max = exact.iter().copied().fold(0.0, f64::max);
        let reused = time
            .certify(&pattern, &nearby, &row_sums(&pattern, &nearby), REUSE_LIMIT)
            .unwrap();
        assert!(reused >= true_max, "{reused} < {true_max}");
        let far: Vec<f64> = values
            .iter()
            .map(|&v| if v < 0.0 { v * 1.24 } else { v })
            .collect();
        assert_eq!(
            time.certify(&pattern, &far, &row_sums(&pattern, &far), REUSE_LIMIT),
            None
        );
    }
}
