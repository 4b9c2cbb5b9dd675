//! Sparse linear solves of `A x = b` and `A^T y = c` for the transient part
//! of a Markov chain, `A = I - Q` (method.md sections 1 and 2).
//!
//! [`LuSolver`] hides faer's sparse LU behind three operations: the symbolic
//! analysis of a fixed sparsity pattern (once per support structure),
//! numeric factorisation for new values (once per parameter vector), and
//! forward/transposed solves (each checked by its residual). `A` is given
//! row-wise (compressed sparse rows), which is the compressed sparse column
//! form of `A^T`; faer factorises `A^T`, so `A x = b` is its transposed solve
//! and `A^T y = c` its plain solve.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{LuRef, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};
use thiserror::Error;

/// The largest residual `max_i |(A x - b)_i|` accepted by default.
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

/// Why a linear system could not be solved to the required accuracy.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SolverError {
    /// The matrix is singular (structurally or numerically).
    #[error("the linear system is singular ({0})")]
    Singular(String),
    /// A coefficient or a solution entry is NaN or infinite.
    #[error("non-finite number in the linear system ({0})")]
    NonFinite(&'static str),
    /// The residual exceeds the tolerance.
    #[error("residual {residual:e} exceeds the tolerance {tolerance:e}")]
    Inaccurate {
        /// `max_i |(A x - b)_i|`.
        residual: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
    /// The tolerance is not a finite positive number.
    #[error("the tolerance must be finite and positive, not {0}")]
    InvalidTolerance(f64),
    /// Memory for the factorisation could not be allocated.
    #[error("out of memory in the sparse LU factorisation")]
    OutOfMemory,
    /// The pattern or values have inconsistent sizes or unsorted columns.
    #[error("malformed sparse matrix: {0}")]
    Malformed(String),
}

/// A square sparse matrix `A` in compressed sparse row form with sorted,
/// distinct column indices per row.
#[derive(Debug, Clone, PartialEq)]
pub struct SparsePattern {
    /// `n`: rows and columns.
    pub n: usize,
    /// Row offsets, `n + 1` entries.
    pub row_offsets: Vec<usize>,
    /// Column indices.
    pub columns: Vec<usize>,
}

impl SparsePattern {
    /// The number of stored entries.
    pub fn nnz(&self) -> usize {
        self.columns.len()
    }

    fn check(&self) -> Result<(), SolverError> {
        let bad = |m: &str| Err(SolverError::Malformed(m.to_string()));
        if self.row_offsets.len() != self.n + 1 || self.row_offsets[self.n] != self.columns.len() {
            return bad("row offsets do not match the entries");
        }
        for row in 0..self.n {
            let cols = &self.columns[self.row_offsets[row]..self.row_offsets[row + 1]];
            if cols.windows(2).any(|w| w[0] >= w[1]) || cols.iter().any(|&c| c >= self.n) {
                return bad("columns must be sorted, distinct and in range");
            }
        }
        Ok(())
    }

    /// `max_i |(A x - b)_i|` for the matrix with this pattern and `values`.
    pub fn residual(&self, values: &[f64], x: &[f64], b: &[f64]) -> f64 {
        (0..self.n)
            .map(|row| {
                let range = self.row_offsets[row]..self.row_offsets[row + 1];
                let ax: f64 = self.columns[range.clone()]
                    .iter()
                    .zip(&values[range])
                    .map(|(&c, &a)| a * x[c])
                    .sum();
                (ax - b[row]).abs()
            })
            .fold(0.0, f64::max)
    }

    /// `max_i |(A^T y - c)_i|` for the matrix with this pattern and `values`.
    pub fn transposed_residual(&self, values: &[f64], y: &[f64], c: &[f64]) -> f64 {
        let mut aty = vec![0.0; self.n];
        for (row, &y_row) in y.iter().enumerate().take(self.n) {
            for k in self.row_offsets[row]..self.row_offsets[row + 1] {
                aty[self.columns[k]] += values[k] * y_row;
            }
        }
        aty.iter()
            .zip(c)
            .map(|(a, c)| (a - c).abs())
            .fold(0.0, f64::max)
    }
}

/// Sparse LU of `A` with a fixed pattern: analyse once, factorise per values,
/// solve many times.
pub struct LuSolver {
    pattern: SparsePattern,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    values: Vec<f64>,
    factorised: bool,
    workspace: MemBuffer,
    tolerance: f64,
}

impl LuSolver {
    /// Symbolic analysis (fill-reducing ordering, elimination structure) of
    /// `pattern`; solves are accepted when their residual is at most `tolerance`.
    pub fn new(pattern: SparsePattern, tolerance: f64) -> Result<Self, SolverError> {
        if !(tolerance.is_finite() && tolerance > 0.0) {
            return Err(SolverError::InvalidTolerance(tolerance));
        }
        pattern.check()?;
        let symbolic = factorize_symbolic_lu(transpose_view(&pattern), Default::default())
            .map_err(|_| SolverError::OutOfMemory)?;
        let scratch = symbolic
            .factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let workspace = MemBuffer::try_new(scratch).map_err(|_| SolverError::OutOfMemory)?;
        let values = vec![0.0; pattern.nnz()];
        Ok(Self {
            pattern,
            symbolic,
            numeric: NumericLu::new(),
            values,
            factorised: false,
            workspace,
            tolerance,
        })
    }

    /// The pattern of `A`.
    pub fn pattern(&self) -> &SparsePattern {
        &self.pattern
    }

    /// Numeric LU of `A` with `values` (aligned with the pattern's entries),
    /// reusing the symbolic analysis and the numeric storage.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), SolverError> {
        if values.len() != self.pattern.nnz() {
            return Err(SolverError::Malformed(
                "values do not match the pattern".into(),
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(SolverError::NonFinite("matrix entry"));
        }
        self.values.copy_from_slice(values);
        self.factorised = false;
        let matrix = SparseColMatRef::new(transpose_view(&self.pattern), &self.values);
        self.symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                matrix,
                Par::Seq,
                MemStack::new(&mut self.workspace),
                Default::default(),
            )
            .map_err(|e| SolverError::Singular(format!("{e:?}")))?;
        self.factorised = true;
        Ok(())
    }

    /// Solves `A x = b`: `rhs` holds `b` on entry and `x` on return.
    /// Returns the residual `max_i |(A x - b)_i|`.
    pub fn solve(&mut self, rhs: &mut [f64]) -> Result<f64, SolverError> {
        self.solve_checked(rhs, true)
    }

    /// Solves `A^T y = c`: `rhs` holds `c` on entry and `y` on return.
    /// Returns the residual `max_i |(A^T y - c)_i|`.
    pub fn solve_transpose(&mut self, rhs: &mut [f64]) -> Result<f64, SolverError> {
        self.solve_checked(rhs, false)
    }

    fn solve_checked(&mut self, rhs: &mut [f64], forward: bool) -> Result<f64, SolverError> {
        if !self.factorised {
            return Err(SolverError::Malformed(
                "solve called before a successful factorisation".into(),
            ));
        }
        if rhs.len() != self.pattern.n {
            return Err(SolverError::Malformed(
                "right-hand side has the wrong length".into(),
            ));
        }
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err(SolverError::NonFinite("right-hand side"));
        }
        let original = rhs.to_vec();
        let lu = LuRef::new_unchecked(&self.symbolic, &self.numeric);
        let n = self.pattern.n;
        let stack = MemStack::new(&mut self.workspace);
        let column = MatMut::from_column_major_slice_mut(rhs, n, 1);
        if forward {
            lu.solve_transpose_in_place_with_conj(Conj::No, column, Par::Seq, stack);
        } else {
            lu.solve_in_place_with_conj(Conj::No, column, Par::Seq, stack);
        }
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err(SolverError::Singular("the solution is not finite".into()));
        }
        let residual = if forward {
            self.pattern.residual(&self.values, rhs, &original)
        } else {
            self.pattern
                .transposed_residual(&self.values, rhs, &original)
        };
        if residual.is_nan() || residual > self.tolerance {
            return Err(SolverError::Inaccurate {
                residual,
                tolerance: self.tolerance,
            });
        }
        Ok(residual)
    }
}

/// The CSR pattern of `A` read as the CSC pattern of `A^T`.
fn transpose_view(pattern: &SparsePattern) -> SymbolicSparseColMatRef<'_, usize> {
    SymbolicSparseColMatRef::new_checked(
        pattern.n,
        pattern.n,
        &pattern.row_offsets,
        None,
        &pattern.columns,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tridiagonal(n: usize) -> (SparsePattern, Vec<f64>) {
        let mut row_offsets = vec![0];
        let mut columns = Vec::new();
        let mut values = Vec::new();
        for i in 0..n {
            for j in i.saturating_sub(1)..(i + 2).min(n) {
                columns.push(j);
                values.push(if i == j { 1.0 } else { -0.4 });
            }
            row_offsets.push(columns.len());
        }
        (
            SparsePattern {
                n,
                row_offsets,
                columns,
            },
            values,
        )
    }

    #[test]
    fn forward_and_transposed_solves_match_a_nonsymmetric_system() {
        let pattern = SparsePattern {
            n: 3,
            row_offsets: vec![0, 2, 4, 5],
            columns: vec![0, 1, 1, 2, 2],
        };
        let values = [1.0, -0.5, 1.0, -0.25, 1.0];
        let mut solver = LuSolver::new(pattern, DEFAULT_TOLERANCE).unwrap();
        solver.factorize(&values).unwrap();
        let mut x = vec![0.0, 0.0, 1.0];
        solver.solve(&mut x).unwrap();
        assert!(
            (x[2] - 1.0).abs() < 1e-15
                && (x[1] - 0.25).abs() < 1e-15
                && (x[0] - 0.125).abs() < 1e-15
        );
        let mut y = vec![1.0, 0.0, 0.0];
        solver.solve_transpose(&mut y).unwrap();
        assert!(
            (y[0] - 1.0).abs() < 1e-15
                && (y[1] - 0.5).abs() < 1e-15
                && (y[2] - 0.125).abs() < 1e-15
        );
    }

    #[test]
    fn refactorisation_reuses_the_pattern() {
        let (pattern, mut values) = tridiagonal(50);
        let mut solver = LuSolver::new(pattern, DEFAULT_TOLERANCE).unwrap();
        for scale in [0.4, 0.2, 0.45] {
            for (k, v) in values.iter_mut().enumerate() {
                if *v != 1.0 {
                    *v = -scale - 1e-3 * (k % 7) as f64;
                }
            }
            solver.factorize(&values).unwrap();
            let mut x = vec![1.0; 50];
            assert!(solver.solve(&mut x).unwrap() < 1e-12);
        }
    }

    #[test]
    fn a_singular_system_is_an_error_not_a_number() {
        let pattern = SparsePattern {
            n: 2,
            row_offsets: vec![0, 2, 4],
            columns: vec![0, 1, 0, 1],
        };
        let mut solver = LuSolver::new(pattern, DEFAULT_TOLERANCE).unwrap();
        let result = solver
            .factorize(&[1.0, -1.0, -1.0, 1.0])
            .and_then(|()| solver.solve(&mut [0.0, 1.0]));
        assert!(result.is_err(), "{result:?}");
    }

    #[test]
    fn a_tolerance_that_accepts_everything_is_refused() {
        for tolerance in [f64::NAN, f64::INFINITY, 0.0, -1.0] {
            let (pattern, _) = tridiagonal(3);
            assert!(matches!(
                LuSolver::new(pattern, tolerance),
                Err(SolverError::InvalidTolerance(_))
            ));
        }
    }

    #[test]
    fn non_finite_values_are_rejected() {
        let (pattern, mut values) = tridiagonal(4);
        values[0] = f64::NAN;
        let mut solver = LuSolver::new(pattern, DEFAULT_TOLERANCE).unwrap();
        assert_eq!(
            solver.factorize(&values),
            Err(SolverError::NonFinite("matrix entry"))
        );
    }
}
