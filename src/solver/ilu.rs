//! The incomplete LU factorisation without fill-in, ILU(0), of a sparse
//! matrix `A`: `A ≈ L U` with `L` unit lower and `U` upper triangular, both
//! restricted to the pattern of `A` (Saad, *Iterative Methods for Sparse
//! Linear Systems*, 2nd ed., 2003, Algorithm 10.4, the IKJ variant). For an
//! M-matrix such as `I - Q` it exists and its pivots are positive
//! (Meijerink and van der Vorst, 1977). It is the preconditioner of
//! [`super::KrylovSolver`]: `M = L U` for `A x = b`, `M^T = U^T L^T` for
//! `A^T y = c`.

use faer::dyn_stack::{MemStack, StackReq};
use faer::matrix_free::{LinOp, Precond};
use faer::reborrow::ReborrowMut;
use faer::{MatMut, MatRef, Par};

use super::{Direction, SolverError, SparsePattern};

const NONE: usize = usize::MAX;

/// The factors `L` (strictly below the diagonal, unit diagonal implied) and
/// `U` (diagonal and above) of ILU(0), stored in the entry order of `A`'s
/// pattern.
#[derive(Debug, Clone)]
pub struct Ilu0 {
    factors: Vec<f64>,
    diagonal: Vec<usize>,
    position: Vec<usize>,
}

impl Ilu0 {
    /// Prepares the factorisation of matrices with `pattern`, which must
    /// store every diagonal entry.
    pub fn new(pattern: &SparsePattern) -> Result<Self, SolverError> {
        let diagonal = (0..pattern.n)
            .map(|row| {
                pattern
                    .row_range(row)
                    .find(|&k| pattern.columns[k] == row)
                    .ok_or_else(|| {
                        SolverError::Malformed(format!("row {row} stores no diagonal entry"))
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            factors: vec![0.0; pattern.nnz()],
            diagonal,
            position: vec![NONE; pattern.n],
        })
    }

    /// Computes `L` and `U` for `values` (aligned with `pattern`'s entries).
    /// A zero or non-finite pivot makes `A` unusable: an error.
    pub fn factorize(
        &mut self,
        pattern: &SparsePattern,
        values: &[f64],
    ) -> Result<(), SolverError> {
        self.factors.copy_from_slice(values);
        for row in 0..pattern.n {
            let range = pattern.row_range(row);
            for k in range.clone() {
                self.position[pattern.columns[k]] = k;
            }
            for k in range.start..self.diagonal[row] {
                let pivot_row = pattern.columns[k];
                let pivot_position = self.diagonal[pivot_row];
                let multiplier = self.factors[k] / self.factors[pivot_position];
                self.factors[k] = multiplier;
                for j in pivot_position + 1..pattern.row_offsets[pivot_row + 1] {
                    let target = self.position[pattern.columns[j]];
                    if target != NONE {
                        self.factors[target] -= multiplier * self.factors[j];
                    }
                }
            }
            for k in range {
                self.position[pattern.columns[k]] = NONE;
            }
            let pivot = self.factors[self.diagonal[row]];
            if !pivot.is_finite() || pivot == 0.0 {
                return Err(SolverError::Singular(format!(
                    "ILU(0) pivot {pivot} in row {row}"
                )));
            }
        }
        Ok(())
    }

    /// `r := (L U)^{-1} r`.
    pub fn solve_in_place(&self, pattern: &SparsePattern, r: &mut [f64]) {
        for row in 0..pattern.n {
            let lower = pattern.row_offsets[row]..self.diagonal[row];
            let sum: f64 = lower.map(|k| self.factors[k] * r[pattern.columns[k]]).sum();
            r[row] -= sum;
        }
        for row in (0..pattern.n).rev() {
            let upper = self.diagonal[row] + 1..pattern.row_offsets[row + 1];
            let sum: f64 = upper.map(|k| self.factors[k] * r[pattern.columns[k]]).sum();
            r[row] = (r[row] - sum) / self.factors[self.diagonal[row]];
        }
    }

    /// `r := (U^T L^T)^{-1} r`, the transposed preconditioner.
    pub fn solve_transpose_in_place(&self, pattern: &SparsePattern, r: &mut [f64]) {
        for row in 0..pattern.n {
            r[row] /= self.factors[self.diagonal[row]];
            let w = r[row];
            for k in self.diagonal[row] + 1..pattern.row_offsets[row + 1] {
                r[pattern.columns[k]] -= self.factors[k] * w;
            }
        }
        for row in (0..pattern.n).rev() {
            let z = r[row];
            for k in pattern.row_offsets[row]..self.diagonal[row] {
                r[pattern.columns[k]] -= self.factors[k] * z;
            }
        }
    }
}

/// `A` (or `A^T`) as faer's matrix-free operator.
#[derive(Debug)]
pub(super) struct MatrixOperator<'a> {
    pub pattern: &'a SparsePattern,
    pub values: &'a [f64],
    pub direction: Direction,
}

/// ILU(0) of `A` as faer's preconditioner for `A` (or for `A^T`).
#[derive(Debug)]
pub(super) struct IluPreconditioner<'a> {
    pub pattern: &'a SparsePattern,
    pub ilu: &'a Ilu0,
    pub direction: Direction,
}

/// The columns of `out` and `rhs` as slices (faer's BiCGSTAB passes
/// column-major blocks with one column per right-hand side).
fn for_each_column(
    mut out: MatMut<'_, f64>,
    rhs: MatRef<'_, f64>,
    mut apply: impl FnMut(&mut [f64], &[f64]),
) {
    for j in 0..rhs.ncols() {
        let source: Vec<f64>;
        let input = match rhs.col(j).try_as_col_major() {
            Some(column) => column.as_slice(),
            None => {
                source = rhs.col(j).iter().copied().collect();
                &source
            }
        };
        let mut column = out.rb_mut().col_mut(j);
        match column.rb_mut().try_as_col_major_mut() {
            Some(contiguous) => apply(contiguous.as_slice_mut(), input),
            None => {
                let mut result = vec![0.0; input.len()];
                apply(&mut result, input);
                for (i, value) in result.into_iter().enumerate() {
                    column[i] = value;
                }
            }
        }
    }
}

impl LinOp<f64> for MatrixOperator<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }

    fn nrows(&self) -> usize {
        self.pattern.n
    }

    fn ncols(&self) -> usize {
        self.pattern.n
    }

    fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _stack: &mut MemStack) {
        for_each_column(out, rhs, |out, x| match self.direction {
            Direction::Forward => self.pattern.multiply(self.values, x, out),
            Direction::Transposed => self.pattern.multiply_transposed(self.values, x, out),
        });
    }

    fn conj_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) {
        self.apply(out, rhs, par, stack);
    }
}

impl LinOp<f64> for IluPreconditioner<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }

    fn nrows(&self) -> usize {
        self.pattern.n
    }

    fn ncols(&self) -> usize {
        self.pattern.n
    }

    fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _stack: &mut MemStack) {
        for_each_column(out, rhs, |out, r| {
            out.copy_from_slice(r);
            match self.direction {
                Direction::Forward => self.ilu.solve_in_place(self.pattern, out),
                Direction::Transposed => self.ilu.solve_transpose_in_place(self.pattern, out),
            }
        });
    }

    fn conj_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) {
        self.apply(out, rhs, par, stack);
    }
}

impl Precond<f64> for IluPreconditioner<'_> {}

#[cfg(test)]
mod tests {
    use super::super::test_systems::{random_chain, tridiagonal};
    use super::*;

    #[test]
    fn on_a_tridiagonal_matrix_ilu0_is_the_exact_lu() {
        let (pattern, values) = tridiagonal(20, 0.45);
        let mut ilu = Ilu0::new(&pattern).unwrap();
        ilu.factorize(&pattern, &values).unwrap();
        let b: Vec<f64> = (0..20).map(|i| 1.0 + i as f64).collect();
        let mut x = b.clone();
        ilu.solve_in_place(&pattern, &mut x);
        assert!(pattern.residual(&values, &x, &b) < 1e-13);
        let mut y = b.clone();
        ilu.solve_transpose_in_place(&pattern, &mut y);
        let mut work = vec![0.0; 20];
        assert!(pattern.transposed_residual(&values, &y, &b, &mut work) < 1e-13);
    }

    #[test]
    fn the_transposed_preconditioner_is_the_transpose() {
        let (pattern, values) = random_chain(60, 3, 0.1, 7);
        let mut ilu = Ilu0::new(&pattern).unwrap();
        ilu.factorize(&pattern, &values).unwrap();
        let u: Vec<f64> = (0..60).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let v: Vec<f64> = (0..60).map(|i| ((i * 13) % 7) as f64 - 3.0).collect();
        let (mut mu, mut mtv) = (u.clone(), v.clone());
        ilu.solve_in_place(&pattern, &mut mu);
        ilu.solve_transpose_in_place(&pattern, &mut mtv);
        let left: f64 = v.iter().zip(&mu).map(|(a, b)| a * b).sum();
        let right: f64 = mtv.iter().zip(&u).map(|(a, b)| a * b).sum();
        assert!(
            (left - right).abs() < 1e-10 * left.abs().max(1.0),
            "{left} vs {right}"
        );
    }

    #[test]
    fn a_missing_diagonal_or_zero_pivot_is_an_error() {
        let pattern = SparsePattern {
            n: 2,
            row_offsets: vec![0, 1, 2],
            columns: vec![1, 1],
        };
        assert!(matches!(
            Ilu0::new(&pattern),
            Err(SolverError::Malformed(_))
        ));
        let (pattern, _) = tridiagonal(2, 1.0);
        let mut ilu = Ilu0::new(&pattern).unwrap();
        assert!(matches!(
            ilu.factorize(&pattern, &[1.0, -1.0, -1.0, 1.0]),
            Err(SolverError::Singular(_))
        ));
    }
}
