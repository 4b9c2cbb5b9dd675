//! Sparse LU of `A = I - Q`: the analysis once per pattern, the numeric
//! factorisation once per values, any number of solves in both directions
//! ([`super::multifrontal`] does the work).

use super::multifrontal::MultifrontalLu;
use super::{
    Direction, SolvePair, SolveReport, SolverError, SparsePattern, accept, check_solve_inputs,
    check_values, join_directions,
};

/// Sparse LU of `A` with a fixed pattern: analyse once, factorise per values,
/// solve many times.
pub struct LuSolver {
    system: System,
    forward: Workspace,
    transposed: Workspace,
}

/// What both directions share: `A` and its factorisation.
struct System {
    pattern: SparsePattern,
    lu: MultifrontalLu,
    values: Vec<f64>,
    factorised: bool,
    tolerance: f64,
}

/// The memory of one direction's solves: the permuted right-hand side and a
/// buffer for `A^T y`.
struct Workspace {
    permuted: Vec<f64>,
    product: Vec<f64>,
}

impl Workspace {
    fn new(n: usize) -> Self {
        Self {
            permuted: Vec::with_capacity(n),
            product: vec![0.0; n],
        }
    }
}

impl LuSolver {
    /// Symbolic analysis (fill-reducing ordering, elimination structure) of
    /// `pattern`; solves are accepted when their residual is at most `tolerance`.
    pub fn new(pattern: SparsePattern, tolerance: f64) -> Result<Self, SolverError> {
        super::SolverSettings::with_tolerance(tolerance).check()?;
        pattern.check()?;
        let lu = MultifrontalLu::new(&pattern)?;
        let values = vec![0.0; pattern.nnz()];
        Ok(Self {
            forward: Workspace::new(pattern.n),
            transposed: Workspace::new(pattern.n),
            system: System {
                pattern,
                lu,
                values,
                factorised: false,
                tolerance,
            },
        })
    }

    /// The pattern of `A`.
    pub fn pattern(&self) -> &SparsePattern {
        &self.system.pattern
    }

    /// Numeric LU of `A` with `values` (aligned with the pattern's entries),
    /// reusing the symbolic analysis and the numeric storage.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), SolverError> {
        check_values(&self.system.pattern, values)?;
        self.factorize_with(|own| own.copy_from_slice(values))
    }

    /// [`Self::factorize`] with the values that `fill` writes into the
    /// solver's own copy of `A` (aligned with the pattern; it holds the
    /// previous values on entry), without a second copy.
    pub fn factorize_with(&mut self, fill: impl FnOnce(&mut [f64])) -> Result<(), SolverError> {
        self.set_values_with(fill)?;
        let system = &mut self.system;
        system.lu.factorize(&system.values)?;
        system.factorised = true;
        Ok(())
    }

    /// Takes the values that `fill` writes into the solver's own copy of
    /// `A` (as [`Self::factorize_with`]) without factorising them: for
    /// [`Self::factorize_and_solve`], after the caller has looked at them
    /// ([`Self::values`]).
    pub fn set_values_with(&mut self, fill: impl FnOnce(&mut [f64])) -> Result<(), SolverError> {
        let system = &mut self.system;
        system.factorised = false;
        fill(&mut system.values);
        check_values(&system.pattern, &system.values)
    }

    /// Factorises the values of the last [`Self::set_values_with`] and
    /// solves `A x_r = b_r` for `K` right-hand sides on the way, each
    /// accepted within its own tolerance (the outer error: the inputs or
    /// the factorisation). `L` is not stored but applied front by front
    /// (forward elimination during the factorisation), which saves the
    /// larger half of the factors' memory; a later solve factorises again,
    /// keeping `L`. The solutions are bit for bit those of
    /// [`Self::factorize_with`] and [`Self::solve_within`].
    pub fn factorize_and_solve<const K: usize>(
        &mut self,
        rhs: [&[f64]; K],
        mut solutions: [&mut [f64]; K],
        tolerances: [f64; K],
    ) -> Result<[Result<SolveReport, SolverError>; K], SolverError> {
        let system = &mut self.system;
        system.factorised = false;
        for (b, x) in rhs.iter().zip(solutions.iter_mut()) {
            check_solve_inputs(system.pattern.n, b, x)?;
            x.copy_from_slice(b);
        }
        let in_place = solutions.each_mut().map(|solution| &mut **solution);
        let work = &mut self.forward.permuted;
        system
            .lu
            .factorize_and_solve(&system.values, in_place, work)?;
        system.factorised = true;
        let factors = system.factors_as_factorised();
        Ok(std::array::from_fn(|r| {
            factors.accepted(rhs[r], solutions[r], tolerances[r])
        }))
    }

    /// The number of stored entries of the factors `L` and `U` (the fill:
    /// their dense supernode blocks counted whole).
    pub fn factor_entries(&self) -> usize {
        self.system.lu.stored_entries()
    }

    /// Whether the factors keep `L`: false after [`Self::factorize_and_solve`]
    /// until a later solve factorises again.
    pub fn keeps_lower(&self) -> bool {
        self.system.lu.lower_kept()
    }

    /// The values of `A` as of the last factorisation.
    pub fn values(&self) -> &[f64] {
        &self.system.values
    }

    /// Solves `A x = b` into `x` (whose entry value is ignored).
    pub fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<SolveReport, SolverError> {
        let tolerance = self.system.tolerance;
        self.solve_within(b, x, tolerance)
    }

    /// [`Self::solve`], accepting a residual up to `tolerance` instead of
    /// the solver's own.
    pub fn solve_within(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        tolerance: f64,
    ) -> Result<SolveReport, SolverError> {
        let factors = self.system.factors()?;
        factors.solve(&mut self.forward, b, x, Direction::Forward, tolerance)
    }

    /// Solves `A x = b` into `x` and `A t = c` into `t` (entry values
    /// ignored), each accepted within its own tolerance, in one pass over
    /// the factors; each solution is the one [`Self::solve_within`] gives.
    pub fn solve_pair_within(
        &mut self,
        (b, x, tolerance): (&[f64], &mut [f64], f64),
        (c, t, c_tolerance): (&[f64], &mut [f64], f64),
    ) -> SolvePair {
        let factors = match self.system.factors() {
            Ok(factors) => factors,
            Err(error) => return (Err(error.clone()), Err(error)),
        };
        let [first, second] =
            factors.solve_forward(&mut self.forward, [b, c], [x, t], [tolerance, c_tolerance]);
        (first, second)
    }

    /// Solves `A^T y = c` into `y` (whose entry value is ignored).
    pub fn solve_transpose(
        &mut self,
        c: &[f64],
        y: &mut [f64],
    ) -> Result<SolveReport, SolverError> {
        let tolerance = self.system.tolerance;
        let factors = self.system.factors()?;
        factors.solve(&mut self.transposed, c, y, Direction::Transposed, tolerance)
    }

    /// [`Self::solve`] and [`Self::solve_transpose`] at once, on two threads.
    pub fn solve_both(&mut self, b: &[f64], x: &mut [f64], c: &[f64], y: &mut [f64]) -> SolvePair {
        let tolerance = self.system.tolerance;
        let factors = match self.system.factors() {
            Ok(factors) => factors,
            Err(error) => return (Err(error.clone()), Err(error)),
        };
        let (forward, transposed) = (&mut self.forward, &mut self.transposed);
        join_directions(
            || factors.solve(forward, b, x, Direction::Forward, tolerance),
            || factors.solve(transposed, c, y, Direction::Transposed, tolerance),
        )
    }
}

impl System {
    /// The factors for any solve: after [`LuSolver::factorize_and_solve`],
    /// which did not keep `L`, the values are factorised again, keeping it.
    fn factors(&mut self) -> Result<Factors<'_>, SolverError> {
        if !self.factorised {
            return Err(SolverError::Malformed(
                "solve called before a successful factorisation".into(),
            ));
        }
        if !self.lu.lower_kept() {
            self.factorised = false;
            self.lu.factorize(&self.values)?;
            self.factorised = true;
        }
        Ok(self.factors_as_factorised())
    }

    /// The factors as the last factorisation left them.
    fn factors_as_factorised(&self) -> Factors<'_> {
        Factors {
            pattern: &self.pattern,
            values: &self.values,
            lu: &self.lu,
        }
    }
}

/// A successful factorisation, shared by the two directions' solves.
#[derive(Clone, Copy)]
struct Factors<'a> {
    pattern: &'a SparsePattern,
    values: &'a [f64],
    lu: &'a MultifrontalLu,
}

impl Factors<'_> {
    fn solve(
        &self,
        workspace: &mut Workspace,
        rhs: &[f64],
        solution: &mut [f64],
        direction: Direction,
        tolerance: f64,
    ) -> Result<SolveReport, SolverError> {
        if direction == Direction::Forward {
            let [report] = self.solve_forward(workspace, [rhs], [solution], [tolerance]);
            return report;
        }
        check_solve_inputs(self.pattern.n, rhs, solution)?;
        solution.copy_from_slice(rhs);
        self.lu
            .solve_transpose_in_place(solution, &mut workspace.permuted);
        let residual =
            self.pattern
                .transposed_residual(self.values, solution, rhs, &mut workspace.product);
        Ok(report_of(accept(residual, solution, tolerance)?))
    }

    /// The report of a forward solution `solution` of `A x = rhs`, if its
    /// residual is within `tolerance`.
    fn accepted(
        &self,
        rhs: &[f64],
        solution: &[f64],
        tolerance: f64,
    ) -> Result<SolveReport, SolverError> {
        let residual = self.pattern.residual(self.values, solution, rhs);
        Ok(report_of(accept(residual, solution, tolerance)?))
    }

    /// Solves `A x_r = b_r` for `K` right-hand sides in one pass over the
    /// factors, each accepted within its own tolerance.
    fn solve_forward<const K: usize>(
        &self,
        workspace: &mut Workspace,
        rhs: [&[f64]; K],
        mut solutions: [&mut [f64]; K],
        tolerances: [f64; K],
    ) -> [Result<SolveReport, SolverError>; K] {
        let checked: [Result<(), SolverError>; K] =
            std::array::from_fn(|r| check_solve_inputs(self.pattern.n, rhs[r], solutions[r]));
        if checked.iter().all(Result::is_ok) {
            for (solution, rhs) in solutions.iter_mut().zip(rhs) {
                solution.copy_from_slice(rhs);
            }
            let in_place = solutions.each_mut().map(|solution| &mut **solution);
            self.lu
                .solve_many_in_place(in_place, &mut workspace.permuted);
        }
        std::array::from_fn(|r| {
            checked[r].clone()?;
            self.accepted(rhs[r], solutions[r], tolerances[r])
        })
    }
}

/// The report of a direct solve with this residual.
fn report_of(residual: f64) -> SolveReport {
    SolveReport {
        residual,
        iterations: 0,
        error_bound: None,
    }
}

#[cfg(test)]
mod tests {
    use super::super::DEFAULT_TOLERANCE;
    use super::super::test_systems::tridiagonal;
    use super::*;

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
        let mut x = vec![0.0; 3];
        solver.solve(&[0.0, 0.0, 1.0], &mut x).unwrap();
        assert!(
            (x[2] - 1.0).abs() < 1e-15
                && (x[1] - 0.25).abs() < 1e-15
                && (x[0] - 0.125).abs() < 1e-15
        );
        let mut y = vec![0.0; 3];
        solver.solve_transpose(&[1.0, 0.0, 0.0], &mut y).unwrap();
        assert!(
            (y[0] - 1.0).abs() < 1e-15
                && (y[1] - 0.5).abs() < 1e-15
                && (y[2] - 0.125).abs() < 1e-15
        );
    }

    #[test]
    fn refactorisation_reuses_the_pattern() {
        let (pattern, mut values) = tridiagonal(50, 0.4);
        let mut solver = LuSolver::new(pattern, DEFAULT_TOLERANCE).unwrap();
        for scale in [0.4, 0.2, 0.45] {
            for (k, v) in values.iter_mut().enumerate() {
                if *v != 1.0 {
                    *v = -scale - 1e-3 * (k % 7) as f64;
                }
            }
            solver.factorize(&values).unwrap();
            let mut x = vec![0.0; 50];
            assert!(solver.solve(&[1.0; 50], &mut x).unwrap().residual < 1e-12);
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
        let mut x = [0.0; 2];
        let result = solver
            .factorize(&[1.0, -1.0, -1.0, 1.0])
            .and_then(|()| solver.solve(&[0.0, 1.0], &mut x));
        assert!(result.is_err(), "{result:?}");
    }
}
