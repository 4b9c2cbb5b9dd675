//! BiCGSTAB (van der Vorst, 1992; faer's implementation) right-preconditioned
//! by ILU(0), warm-started from the caller's vector.
//!
//! The tolerance bounds the residual `r = b - A x`, but the error of the
//! value is `y^T r` with `y` the adjoint solution (expected visits to each
//! transient state), which can be 10^4 times larger on slowly mixing
//! chains. LU reaches residuals near rounding (1e-16) at no extra cost;
//! BiCGSTAB's cost grows only with the logarithm of its target, so it aims
//! at [`ACCURACY_MARGIN`] times the tolerance (1e-13 by default: about 1.5x
//! the iterations of stopping at the tolerance) and accepts any iterate
//! within the tolerance when it cannot get further.
//!
//! faer stops when the recursively updated residual has Euclidean norm below
//! its threshold; that residual can drift from the true one. So every solve
//! is followed by the true residual `max_i |(A x - b)_i|`, and when that is
//! above the tolerance BiCGSTAB restarts from the current `x` with a
//! tenfold stricter threshold, up to [`RESTARTS`] times. The Euclidean norm
//! bounds the maximum norm, so the recursion's threshold suffices when it is
//! faithful.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::matrix_free::IdentityPrecond;
use faer::matrix_free::bicgstab::{BicgError, BicgParams, bicgstab, bicgstab_scratch};
use faer::{MatMut, MatRef, Par};

use super::ilu::{IluPreconditioner, MatrixOperator};
use super::{
    Direction, Ilu0, SolveReport, SolverError, SolverSettings, SparsePattern, accept,
    check_solve_inputs, check_values,
};

/// BiCGSTAB aims at this fraction of the tolerance.
pub const ACCURACY_MARGIN: f64 = 1e-4;

/// Restarts allowed when BiCGSTAB's own residual is below its threshold but
/// the true residual is not.
pub const RESTARTS: usize = 3;

/// Preconditioned BiCGSTAB for `A x = b` and `A^T y = c` with a fixed pattern.
pub struct KrylovSolver {
    pattern: SparsePattern,
    values: Vec<f64>,
    ilu: Ilu0,
    factorised: bool,
    workspace: MemBuffer,
    residual_work: Vec<f64>,
    tolerance: f64,
    max_iterations: usize,
}

impl KrylovSolver {
    /// Prepares solves with `pattern` (which must store every diagonal entry)
    /// to the tolerance and iteration limit of `settings`.
    pub fn new(pattern: SparsePattern, settings: &SolverSettings) -> Result<Self, SolverError> {
        settings.check()?;
        pattern.check()?;
        let ilu = Ilu0::new(&pattern)?;
        let n = pattern.n;
        let values = vec![0.0; pattern.nnz()];
        let scratch = {
            let operator = MatrixOperator {
                pattern: &pattern,
                values: &values,
                direction: Direction::Forward,
            };
            let preconditioner = IluPreconditioner {
                pattern: &pattern,
                ilu: &ilu,
                direction: Direction::Forward,
            };
            bicgstab_scratch(
                IdentityPrecond { dim: n },
                preconditioner,
                operator,
                1,
                Par::Seq,
            )
        };
        let workspace = MemBuffer::try_new(scratch).map_err(|_| SolverError::OutOfMemory)?;
        Ok(Self {
            pattern,
            values,
            ilu,
            factorised: false,
            workspace,
            residual_work: vec![0.0; n],
            tolerance: settings.tolerance,
            max_iterations: settings.max_iterations,
        })
    }

    /// The pattern of `A`.
    pub fn pattern(&self) -> &SparsePattern {
        &self.pattern
    }

    /// Takes the values of `A` and computes its ILU(0) preconditioner.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), SolverError> {
        check_values(&self.pattern, values)?;
        self.factorised = false;
        self.values.copy_from_slice(values);
        self.ilu.factorize(&self.pattern, &self.values)?;
        self.factorised = true;
        Ok(())
    }

    /// Solves `A x = b` starting from `x` (a non-finite start is replaced by 0).
    pub fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<SolveReport, SolverError> {
        self.solve_checked(b, x, Direction::Forward)
    }

    /// Solves `A^T y = c` starting from `y` (a non-finite start is replaced by 0).
    pub fn solve_transpose(
        &mut self,
        c: &[f64],
        y: &mut [f64],
    ) -> Result<SolveReport, SolverError> {
        self.solve_checked(c, y, Direction::Transposed)
    }

    fn true_residual(&mut self, rhs: &[f64], solution: &[f64], direction: Direction) -> f64 {
        match direction {
            Direction::Forward => self.pattern.residual(&self.values, solution, rhs),
            Direction::Transposed => self.pattern.transposed_residual(
                &self.values,
                solution,
                rhs,
                &mut self.residual_work,
            ),
        }
    }

    fn solve_checked(
        &mut self,
        rhs: &[f64],
        solution: &mut [f64],
        direction: Direction,
    ) -> Result<SolveReport, SolverError> {
        if !self.factorised {
            return Err(SolverError::Malformed(
                "solve called before a successful factorisation".into(),
            ));
        }
        check_solve_inputs(self.pattern.n, rhs, solution)?;
        if solution.iter().any(|v| !v.is_finite()) {
            solution.fill(0.0);
        }
        let target = ACCURACY_MARGIN * self.tolerance;
        let mut threshold = target;
        let mut iterations = 0;
        let mut residual = self.true_residual(rhs, solution, direction);
        for _ in 0..=RESTARTS {
            if residual <= target {
                break;
            }
            let outcome = self.run_bicgstab(rhs, solution, direction, threshold, iterations);
            residual = self.true_residual(rhs, solution, direction);
            if !residual.is_finite() {
                solution.fill(0.0);
                residual = self.true_residual(rhs, solution, direction);
            }
            match outcome {
                Ok(done) => iterations += done,
                Err(()) => {
                    iterations = self.max_iterations;
                    break;
                }
            }
            threshold *= 0.1;
        }
        if iterations >= self.max_iterations && (residual.is_nan() || residual > self.tolerance) {
            return Err(SolverError::NotConverged {
                iterations,
                residual,
                tolerance: self.tolerance,
            });
        }
        let residual = accept(residual, solution, self.tolerance)?;
        Ok(SolveReport {
            residual,
            iterations,
        })
    }

    /// One BiCGSTAB run from `solution`; the iterations it took, or `Err`
    /// when it used up the remaining iteration budget.
    fn run_bicgstab(
        &mut self,
        rhs: &[f64],
        solution: &mut [f64],
        direction: Direction,
        threshold: f64,
        used: usize,
    ) -> Result<usize, ()> {
        let n = self.pattern.n;
        let operator = MatrixOperator {
            pattern: &self.pattern,
            values: &self.values,
            direction,
        };
        let preconditioner = IluPreconditioner {
            pattern: &self.pattern,
            ilu: &self.ilu,
            direction,
        };
        let params = BicgParams {
            abs_tolerance: threshold,
            rel_tolerance: 0.0,
            max_iters: self.max_iterations.saturating_sub(used).max(1),
            ..BicgParams::default()
        };
        let result = bicgstab(
            MatMut::from_column_major_slice_mut(solution, n, 1),
            IdentityPrecond { dim: n },
            preconditioner,
            operator,
            MatRef::from_column_major_slice(rhs, n, 1),
            params,
            |_| {},
            Par::Seq,
            MemStack::new(&mut self.workspace),
        );
        match result {
            Ok(info) => Ok(info.iter_count),
            Err(BicgError::NoConvergence { .. }) => Err(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_systems::random_chain;
    use super::*;

    fn settings(tolerance: f64) -> SolverSettings {
        SolverSettings {
            tolerance,
            ..SolverSettings::default()
        }
    }

    #[test]
    fn a_warm_start_near_the_solution_needs_fewer_iterations() {
        let (pattern, values) = random_chain(2000, 5, 0.01, 3);
        let b = vec![0.01; 2000];
        let mut solver = KrylovSolver::new(pattern, &settings(1e-11)).unwrap();
        solver.factorize(&values).unwrap();
        let mut x = vec![0.0; 2000];
        let cold = solver.solve(&b, &mut x).unwrap();
        let perturbed: Vec<f64> = values
            .iter()
            .enumerate()
            .map(|(k, v)| {
                if *v < 0.0 {
                    v * (1.0 + 1e-4 * (k % 3) as f64)
                } else {
                    *v
                }
            })
            .collect();
        solver.factorize(&perturbed).unwrap();
        let warm = solver.solve(&b, &mut x).unwrap();
        let mut from_zero = vec![0.0; 2000];
        let cold_again = solver.solve(&b, &mut from_zero).unwrap();
        assert!(cold.iterations > 0 && warm.residual <= 1e-11);
        assert!(
            warm.iterations < cold_again.iterations,
            "warm {} vs cold {}",
            warm.iterations,
            cold_again.iterations
        );
    }

    #[test]
    fn an_exact_start_takes_no_iteration() {
        let (pattern, values) = random_chain(100, 3, 0.1, 1);
        let mut solver = KrylovSolver::new(pattern, &settings(1e-10)).unwrap();
        solver.factorize(&values).unwrap();
        let b = vec![1.0; 100];
        let mut x = vec![0.0; 100];
        solver.solve(&b, &mut x).unwrap();
        let again = solver.solve(&b, &mut x).unwrap();
        assert_eq!(again.iterations, 0);
    }

    #[test]
    fn running_out_of_iterations_is_an_error() {
        let (pattern, values) = random_chain(500, 5, 1e-6, 2);
        let limited = SolverSettings {
            tolerance: 1e-14,
            max_iterations: 1,
            ..SolverSettings::default()
        };
        let mut solver = KrylovSolver::new(pattern, &limited).unwrap();
        solver.factorize(&values).unwrap();
        let mut x = vec![0.0; 500];
        let result = solver.solve(&vec![1.0; 500], &mut x);
        assert!(
            matches!(result, Err(SolverError::NotConverged { iterations: 1, .. })),
            "{result:?}"
        );
    }
}
