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
//! its threshold; that residual can drift from the true one. So every run
//! is followed by the true residual `max_i |(A x - b)_i|`, and when that is
//! above the target BiCGSTAB restarts from the current `x` with a tenfold
//! stricter threshold. The Euclidean norm bounds the maximum norm, so the
//! recursion's threshold suffices when it is faithful. Runs are also cut
//! into rounds of [`ROUND_ITERATIONS`], each restarting from the current
//! iterate, and a solve without a usable start begins at the
//! preconditioner's guess `M^{-1} b`: both guard against BiCGSTAB's
//! stagnation. A round that does not improve the true residual is undone
//! and ends the solve (restarting from the same iterate would repeat it);
//! once within the tolerance, a round that no longer halves the residual
//! also ends it (the target lies below what rounding allows). The solve is
//! accepted if the residual is within the tolerance. The whole
//! solve is limited to [`SolverSettings::max_iterations`] iterations.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::matrix_free::IdentityPrecond;
use faer::matrix_free::bicgstab::{BicgError, BicgParams, bicgstab, bicgstab_scratch};
use faer::{MatMut, MatRef, Par};

use super::ilu::{IluPreconditioner, MatrixOperator};
use super::{
    Direction, Ilu0, SolvePair, SolveReport, SolverError, SolverSettings, SparsePattern, accept,
    check_chain, check_solve_inputs, complete_diagonal, join_directions,
};
#[cfg(test)]
use super::{check_values, derive_exits};

/// BiCGSTAB aims at this fraction of the tolerance.
pub const ACCURACY_MARGIN: f64 = 1e-4;

/// BiCGSTAB restarts from its current iterate (with a fresh shadow residual)
/// after this many iterations without reaching its target: restarting cures
/// the stagnation that a shadow residual nearly orthogonal to the Krylov
/// space causes.
pub const ROUND_ITERATIONS: usize = 200;

/// The outcome of [`KrylovSolver::probe`]: true residuals
/// `max_i |(A x - b)_i|` before and after some iterations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KrylovProbe {
    /// Iterations performed.
    pub iterations: usize,
    /// The residual of the start.
    pub start_residual: f64,
    /// The residual of the returned `x` (at most `start_residual`).
    pub residual: f64,
}

impl KrylovProbe {
    /// The iterations a solve from the probe's start would need to bring the
    /// residual to `target` if it kept falling at the probe's mean rate per
    /// iteration (`k log(target / r_0) / log(r_k / r_0)`); 0 when the start
    /// already meets it, infinite when the residual did not fall.
    pub fn predicted_iterations(&self, target: f64) -> f64 {
        if self.start_residual <= target {
            return 0.0;
        }
        if self.residual <= target {
            return self.iterations as f64;
        }
        let fallen = (self.residual / self.start_residual).ln();
        if fallen.is_nan() || fallen >= 0.0 {
            return f64::INFINITY;
        }
        self.iterations.max(1) as f64 * (target / self.start_residual).ln() / fallen
    }
}

/// Preconditioned BiCGSTAB for `A x = b` and `A^T y = c` with a fixed pattern.
pub struct KrylovSolver {
    system: System,
    forward: Workspace,
    transposed: Workspace,
}

/// What both directions share: `A` and its ILU(0).
struct System {
    pattern: SparsePattern,
    values: Vec<f64>,
    ilu: Ilu0,
    factorised: bool,
    tolerance: f64,
    max_iterations: usize,
}

/// The memory of one direction's solves: faer's BiCGSTAB workspace, a
/// buffer for `A^T y`, and the best iterate so far.
struct Workspace {
    bicgstab: MemBuffer,
    product: Vec<f64>,
    best: Vec<f64>,
}

impl Workspace {
    fn new(system: &System, direction: Direction) -> Result<Self, SolverError> {
        let n = system.pattern.n;
        let scratch = bicgstab_scratch(
            IdentityPrecond { dim: n },
            system.preconditioner(direction),
            system.operator(direction),
            1,
            Par::Seq,
        );
        Ok(Self {
            bicgstab: MemBuffer::try_new(scratch).map_err(|_| SolverError::OutOfMemory)?,
            product: vec![0.0; n],
            best: vec![0.0; n],
        })
    }
}

impl KrylovSolver {
    /// Prepares solves with `pattern` (which must store every diagonal entry)
    /// to the tolerance and iteration limit of `settings`.
    pub fn new(pattern: SparsePattern, settings: &SolverSettings) -> Result<Self, SolverError> {
        settings.check()?;
        pattern.check()?;
        let system = System {
            ilu: Ilu0::new(&pattern)?,
            values: vec![0.0; pattern.nnz()],
            pattern,
            factorised: false,
            tolerance: settings.tolerance,
            max_iterations: settings.max_iterations,
        };
        Ok(Self {
            forward: Workspace::new(&system, Direction::Forward)?,
            transposed: Workspace::new(&system, Direction::Transposed)?,
            system,
        })
    }

    /// The pattern of `A`.
    pub fn pattern(&self) -> &SparsePattern {
        &self.system.pattern
    }

    /// Allows each solve from now on `max_iterations` BiCGSTAB iterations
    /// ([`super::LinearSolver`] where no LU can take over a slow solve).
    pub fn allow_iterations(&mut self, max_iterations: usize) {
        self.system.max_iterations = max_iterations;
    }

    /// The values of `A` as of the last factorisation.
    pub fn values(&self) -> &[f64] {
        &self.system.values
    }

    /// Takes the values of `A` and computes its ILU(0) preconditioner.
    #[cfg(test)]
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), SolverError> {
        let system = &mut self.system;
        system.factorised = false;
        check_values(&system.pattern, values)?;
        let mut exits = vec![0.0; system.pattern.n];
        derive_exits(&system.pattern, values, &mut exits);
        check_chain(&system.pattern, values, &exits)?;
        system.values.copy_from_slice(values);
        system.ilu.factorize(&system.pattern, &system.values)?;
        system.factorised = true;
        Ok(())
    }

    /// [`Self::factorize`] of `A` as `fill` writes it into the solver's
    /// own copy of the values (aligned with the pattern; it holds the
    /// previous values on entry) and into `exits`, as
    /// [`super::LuSolver::factorize_with`]: off-diagonal entries and row
    /// sums, the diagonal then being their sum.
    pub fn factorize_with(
        &mut self,
        exits: &mut [f64],
        fill: impl FnOnce(&mut [f64], &mut [f64]),
    ) -> Result<(), SolverError> {
        let system = &mut self.system;
        system.factorised = false;
        fill(&mut system.values, exits);
        check_chain(&system.pattern, &system.values, exits)?;
        complete_diagonal(&system.pattern, &mut system.values, exits);
        system.ilu.factorize(&system.pattern, &system.values)?;
        system.factorised = true;
        Ok(())
    }

    /// Solves `A x = b` starting from `x` (see the module documentation for
    /// starts that are zero or not finite).
    #[cfg(test)]
    pub fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<SolveReport, SolverError> {
        let tolerance = self.system.tolerance;
        self.solve_within(b, x, tolerance)
    }

    /// [`Self::solve`] to the residual `tolerance` instead of the solver's own.
    pub fn solve_within(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        tolerance: f64,
    ) -> Result<SolveReport, SolverError> {
        self.system
            .solve(&mut self.forward, b, x, Direction::Forward, tolerance)
    }

    /// Solves `A^T y = c` starting from `y`, as [`Self::solve`].
    pub fn solve_transpose(
        &mut self,
        c: &[f64],
        y: &mut [f64],
    ) -> Result<SolveReport, SolverError> {
        let tolerance = self.system.tolerance;
        self.system
            .solve(&mut self.transposed, c, y, Direction::Transposed, tolerance)
    }

    /// A short trial of BiCGSTAB on `A x = b`: from `x` (or the
    /// preconditioner's guess, as in [`Self::solve`]), at most `iterations`
    /// iterations; `x` becomes the better of its start and the trial's
    /// iterate. The rate at which the true residual falls estimates how
    /// fast the chain mixes, hence the cost of a whole solve.
    pub fn probe(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        iterations: usize,
    ) -> Result<KrylovProbe, SolverError> {
        self.system.probe(&mut self.forward, b, x, iterations)
    }

    /// [`Self::solve`] and [`Self::solve_transpose`], at once on two threads
    /// from `PARALLEL_SOLVE_ROWS` unknowns.
    pub fn solve_both(&mut self, b: &[f64], x: &mut [f64], c: &[f64], y: &mut [f64]) -> SolvePair {
        let system = &self.system;
        let (forward, transposed) = (&mut self.forward, &mut self.transposed);
        let tolerance = system.tolerance;
        join_directions(
            b.len(),
            || system.solve(forward, b, x, Direction::Forward, tolerance),
            || system.solve(transposed, c, y, Direction::Transposed, tolerance),
        )
    }
}

impl System {
    fn operator(&self, direction: Direction) -> MatrixOperator<'_> {
        MatrixOperator {
            pattern: &self.pattern,
            values: &self.values,
            direction,
        }
    }

    fn preconditioner(&self, direction: Direction) -> IluPreconditioner<'_> {
        IluPreconditioner {
            pattern: &self.pattern,
            ilu: &self.ilu,
            direction,
        }
    }

    fn true_residual(
        &self,
        workspace: &mut Workspace,
        rhs: &[f64],
        solution: &[f64],
        direction: Direction,
    ) -> f64 {
        match direction {
            Direction::Forward => self.pattern.residual(&self.values, solution, rhs),
            Direction::Transposed => self.pattern.transposed_residual(
                &self.values,
                solution,
                rhs,
                &mut workspace.product,
            ),
        }
    }

    fn solve(
        &self,
        workspace: &mut Workspace,
        rhs: &[f64],
        solution: &mut [f64],
        direction: Direction,
        tolerance: f64,
    ) -> Result<SolveReport, SolverError> {
        if !self.factorised {
            return Err(SolverError::Malformed(
                "solve called before a successful factorisation".into(),
            ));
        }
        check_solve_inputs(self.pattern.n, rhs, solution)?;
        if solution.iter().all(|&v| v == 0.0) || solution.iter().any(|v| !v.is_finite()) {
            self.preconditioned_start(rhs, solution, direction);
        }
        let target = ACCURACY_MARGIN * tolerance;
        let mut threshold = target;
        let mut iterations = 0;
        let mut residual = self.true_residual(workspace, rhs, solution, direction);
        workspace.best.copy_from_slice(solution);
        while residual > target && iterations < self.max_iterations {
            let budget = ROUND_ITERATIONS.min(self.max_iterations - iterations);
            let run = self.run_bicgstab(workspace, rhs, solution, direction, threshold, budget);
            let converged = match run {
                Ok(done) => {
                    iterations += done.max(1);
                    true
                }
                Err(()) => {
                    iterations += budget;
                    false
                }
            };
            let previous = residual;
            residual = self.true_residual(workspace, rhs, solution, direction);
            if residual.is_finite() && residual < previous {
                workspace.best.copy_from_slice(solution);
                if residual > 0.5 * previous && residual <= tolerance {
                    break;
                }
                if converged && residual > target {
                    threshold *= 0.1;
                }
            } else {
                solution.copy_from_slice(&workspace.best);
                residual = previous;
                break;
            }
        }
        if residual.is_nan() || residual > tolerance {
            return Err(SolverError::NotConverged {
                iterations,
                residual,
                tolerance,
            });
        }
        let residual = accept(residual, solution, tolerance)?;
        Ok(SolveReport {
            residual,
            iterations,
            error_bound: None,
        })
    }

    fn probe(
        &self,
        workspace: &mut Workspace,
        rhs: &[f64],
        solution: &mut [f64],
        iterations: usize,
    ) -> Result<KrylovProbe, SolverError> {
        if !self.factorised {
            return Err(SolverError::Malformed(
                "solve called before a successful factorisation".into(),
            ));
        }
        check_solve_inputs(self.pattern.n, rhs, solution)?;
        if solution.iter().all(|&v| v == 0.0) || solution.iter().any(|v| !v.is_finite()) {
            self.preconditioned_start(rhs, solution, Direction::Forward);
        }
        let start_residual = self.true_residual(workspace, rhs, solution, Direction::Forward);
        workspace.best.copy_from_slice(solution);
        let done = self
            .run_bicgstab(
                workspace,
                rhs,
                solution,
                Direction::Forward,
                0.0,
                iterations,
            )
            .unwrap_or(iterations);
        let mut residual = self.true_residual(workspace, rhs, solution, Direction::Forward);
        if !(residual.is_finite() && residual <= start_residual) {
            solution.copy_from_slice(&workspace.best);
            residual = start_residual;
        }
        Ok(KrylovProbe {
            iterations: done,
            start_residual,
            residual,
        })
    }

    /// `solution := M^{-1} rhs` (or `M^{-T} rhs`): the preconditioner's
    /// guess, a far better start than 0, whose residual is also dense. A
    /// right-hand side with a single nonzero, such as the adjoint's `p0`,
    /// otherwise gives BiCGSTAB a shadow residual nearly orthogonal to the
    /// Krylov space, and it stagnates.
    fn preconditioned_start(&self, rhs: &[f64], solution: &mut [f64], direction: Direction) {
        solution.copy_from_slice(rhs);
        match direction {
            Direction::Forward => self.ilu.solve_in_place(&self.pattern, solution),
            Direction::Transposed => self.ilu.solve_transpose_in_place(&self.pattern, solution),
        }
    }

    /// One BiCGSTAB run of at most `budget` iterations from `solution`; the
    /// iterations it took, or `Err` when it used up the budget.
    fn run_bicgstab(
        &self,
        workspace: &mut Workspace,
        rhs: &[f64],
        solution: &mut [f64],
        direction: Direction,
        threshold: f64,
        budget: usize,
    ) -> Result<usize, ()> {
        let n = self.pattern.n;
        let params = BicgParams {
            abs_tolerance: threshold,
            rel_tolerance: 0.0,
            max_iters: budget,
            ..BicgParams::default()
        };
        let result = bicgstab(
            MatMut::from_column_major_slice_mut(solution, n, 1),
            IdentityPrecond { dim: n },
            self.preconditioner(direction),
            self.operator(direction),
            MatRef::from_column_major_slice(rhs, n, 1),
            params,
            |_| {},
            Par::Seq,
            MemStack::new(&mut workspace.bicgstab),
        );
        match result {
            Ok(info) => Ok(info.iter_count),
            Err(BicgError::NoConvergence { .. }) => Err(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_systems::{grid_walk, random_chain};
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
    fn a_right_hand_side_with_one_nonzero_converges_in_both_directions() {
        let (pattern, values) = grid_walk(60);
        let n = pattern.n;
        let mut solver = KrylovSolver::new(pattern.clone(), &settings(1e-9)).unwrap();
        solver.factorize(&values).unwrap();
        let mut unit = vec![0.0; n];
        unit[0] = 1.0;
        let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
        let forward = solver.solve(&unit, &mut x).unwrap();
        let backward = solver.solve_transpose(&unit, &mut y).unwrap();
        assert!(forward.residual <= 1e-9 && backward.residual <= 1e-9);
        let mut lu = crate::solver::LuSolver::new(pattern, 1e-9).unwrap();
        lu.factorize(&values).unwrap();
        let mut exact = vec![0.0; n];
        lu.solve_transpose(&unit, &mut exact).unwrap();
        let error = exact
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(error < 1e-9, "largest error {error}");
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
