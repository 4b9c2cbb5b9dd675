//! Sparse LU of `A = I - Q`: the analysis once per pattern, the numeric
//! factorisation once per values, any number of solves in both directions
//! ([`super::multifrontal`] does the work).

use super::multifrontal::MultifrontalLu;
use super::{
    Direction, SolvePair, SolveReport, SolverError, SparsePattern, accept, check_chain,
    check_solve_inputs, check_values, complete_diagonal, derive_exits, join_directions,
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
    /// The row sums `A 1`: the probabilities of leaving `T` (method.md
    /// section 8); with the off-diagonal `values` they define `A`.
    exits: Vec<f64>,
    /// Whether `values` passed [`check_chain`] when they were last set.
    values_checked: bool,
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
        let lu = Self::analyse(&pattern, tolerance)?;
        Ok(Self::with_analysis(pattern, lu, tolerance))
    }

    /// The checks of `pattern` and `tolerance` and the symbolic analysis of
    /// [`Self::new`], the pattern borrowed: where the analysis refuses the
    /// LU ([`SolverError::LuTooLarge`]), the caller keeps the pattern for
    /// another solver.
    pub(crate) fn analyse(
        pattern: &SparsePattern,
        tolerance: f64,
    ) -> Result<MultifrontalLu, SolverError> {
        super::SolverSettings::with_tolerance(tolerance).check()?;
        pattern.check()?;
        MultifrontalLu::new(pattern)
    }

    /// The solver of `pattern` with its symbolic analysis `lu`
    /// ([`Self::analyse`]).
    pub(crate) fn with_analysis(
        pattern: SparsePattern,
        lu: MultifrontalLu,
        tolerance: f64,
    ) -> Self {
        let values = vec![0.0; pattern.nnz()];
        let n = pattern.n;
        Self {
            forward: Workspace::new(pattern.n),
            transposed: Workspace::new(pattern.n),
            system: System {
                pattern,
                lu,
                values,
                exits: vec![0.0; n],
                values_checked: false,
                factorised: false,
                tolerance,
            },
        }
    }

    /// The pattern of `A`.
    pub fn pattern(&self) -> &SparsePattern {
        &self.system.pattern
    }

    /// Numeric LU of `A` with `values` (aligned with the pattern's entries),
    /// reusing the symbolic analysis and the numeric storage. The exits are
    /// derived from the diagonal (`derive_exits`), which is kept as given:
    /// a caller that knows them uses [`Self::factorize_with`].
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), SolverError> {
        let system = &mut self.system;
        system.factorised = false;
        system.values_checked = false;
        check_values(&system.pattern, values)?;
        system.values.copy_from_slice(values);
        derive_exits(&system.pattern, values, &mut system.exits);
        check_chain(&system.pattern, &system.values, &system.exits)?;
        system.values_checked = true;
        system.lu.factorize(&system.values, &system.exits)?;
        system.factorised = true;
        Ok(())
    }

    /// [`Self::factorize`] of `A` as `fill` writes it into the solver's own
    /// copies (holding the previous numbers on entry): the off-diagonal
    /// entries into the values (aligned with the pattern) and the row sums
    /// `A 1` (the probabilities of leaving `T`) into the exits. The
    /// diagonal is then set to their sum (method.md section 8).
    pub fn factorize_with(
        &mut self,
        fill: impl FnOnce(&mut [f64], &mut [f64]),
    ) -> Result<(), SolverError> {
        self.set_values_with(fill)?;
        let system = &mut self.system;
        system.lu.factorize(&system.values, &system.exits)?;
        system.factorised = true;
        Ok(())
    }

    /// Takes `A` as `fill` writes it (as [`Self::factorize_with`]) without
    /// factorising it: for [`Self::factorize_and_solve`], after the caller
    /// has looked at it ([`Self::values`]).
    pub fn set_values_with(
        &mut self,
        fill: impl FnOnce(&mut [f64], &mut [f64]),
    ) -> Result<(), SolverError> {
        let system = &mut self.system;
        system.factorised = false;
        fill(&mut system.values, &mut system.exits);
        let checked = check_chain(&system.pattern, &system.values, &system.exits);
        if checked.is_ok() {
            complete_diagonal(&system.pattern, &mut system.values, &system.exits);
        }
        system.values_checked = checked.is_ok();
        checked
    }

    /// The row sums `A 1` of the last values set.
    pub fn exits(&self) -> &[f64] {
        &self.system.exits
    }

    /// Factorises the values of the last [`Self::set_values_with`] and
    /// solves `A x_r = b_r` for `K` right-hand sides on the way, each
    /// accepted within its own tolerance (the outer error: the values, the
    /// right-hand sides or the factorisation). `L` is not stored but
    /// applied front by front (forward elimination during the
    /// factorisation), which saves the larger half of the factors' memory;
    /// a later solve factorises again, keeping `L`. The solutions are bit
    /// for bit those of [`Self::factorize_with`] and [`Self::solve_within`],
    /// and so are the errors and the state they leave: with a right-hand
    /// side that cannot be solved for, the values are factorised (keeping
    /// `L`) and the error returned.
    pub fn factorize_and_solve<const K: usize>(
        &mut self,
        rhs: [&[f64]; K],
        mut solutions: [&mut [f64]; K],
        tolerances: [f64; K],
    ) -> Result<[Result<SolveReport, SolverError>; K], SolverError> {
        let system = &mut self.system;
        if !system.values_checked {
            return Err(SolverError::Malformed(
                "factorize_and_solve without values set by set_values_with".into(),
            ));
        }
        let n = system.pattern.n;
        let inputs: Result<Vec<()>, SolverError> = (0..K)
            .map(|r| check_solve_inputs(n, rhs[r], solutions[r]))
            .collect();
        if let Err(error) = inputs {
            system.lu.factorize(&system.values, &system.exits)?;
            system.factorised = true;
            return Err(error);
        }
        for (x, b) in solutions.iter_mut().zip(rhs) {
            x.copy_from_slice(b);
        }
        let in_place = solutions.each_mut().map(|solution| &mut **solution);
        let work = &mut self.forward.permuted;
        system
            .lu
            .factorize_and_solve(&system.values, &system.exits, in_place, work)?;
        system.factorised = true;
        let chain = (&system.pattern, &system.values[..], &system.exits[..]);
        Ok(std::array::from_fn(|r| {
            accepted(chain, rhs[r], solutions[r], tolerances[r])
        }))
    }

    /// Frees the factors' storage, keeping the symbolic analysis and the
    /// values: the next factorisation allocates it again; until then no
    /// solve is possible. For a solver idle between uses (a start of a race
    /// waiting for its next round).
    pub fn release(&mut self) {
        self.system.lu.release();
        self.system.factorised = false;
    }

    /// The number of entries of the factors `L` and `U` (the structural
    /// fill: their dense supernode blocks counted whole), whether or not the
    /// last factorisation stored `L`.
    pub fn factor_entries(&self) -> usize {
        self.system.lu.stored_entries()
    }

    /// Floating-point operations of one numeric factorisation, from the
    /// symbolic analysis: what decides whether LU or BiCGSTAB costs less
    /// (see `LinearSolver::new`).
    pub fn factorisation_flops(&self) -> f64 {
        self.system.lu.factorisation_flops()
    }

    /// Whether the factors keep `L`: false after [`Self::factorize_and_solve`]
    /// until a later solve factorises again.
    pub fn keeps_lower(&self) -> bool {
        self.system.lu.lower_kept()
    }

    /// The values of `A` as last set: factorised, unless
    /// [`Self::set_values_with`] set them since.
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

    /// [`Self::solve`] and [`Self::solve_transpose`], at once on two threads
    /// from `PARALLEL_SOLVE_ROWS` unknowns.
    pub fn solve_both(&mut self, b: &[f64], x: &mut [f64], c: &[f64], y: &mut [f64]) -> SolvePair {
        let tolerance = self.system.tolerance;
        let factors = match self.system.factors() {
            Ok(factors) => factors,
            Err(error) => return (Err(error.clone()), Err(error)),
        };
        let (forward, transposed) = (&mut self.forward, &mut self.transposed);
        join_directions(
            b.len(),
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
            self.lu.factorize(&self.values, &self.exits)?;
            self.factorised = true;
        }
        Ok(Factors {
            pattern: &self.pattern,
            values: &self.values,
            exits: &self.exits,
            lu: &self.lu,
        })
    }
}

/// A successful factorisation, shared by the two directions' solves.
#[derive(Clone, Copy)]
struct Factors<'a> {
    pattern: &'a SparsePattern,
    values: &'a [f64],
    exits: &'a [f64],
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

    /// Solves `A x_r = b_r` for `K` right-hand sides in one pass over the
    /// factors, each accepted within its own tolerance.
    fn solve_forward<const K: usize>(
        &self,
        workspace: &mut Workspace,
        rhs: [&[f64]; K],
        mut solutions: [&mut [f64]; K],
        tolerances: [f64; K],
    ) -> [Result<SolveReport, SolverError>; K] {
        let inputs: Result<Vec<()>, SolverError> = (0..K)
            .map(|r| check_solve_inputs(self.pattern.n, rhs[r], solutions[r]))
            .collect();
        if let Err(error) = inputs {
            return std::array::from_fn(|_| Err(error.clone()));
        }
        for (solution, rhs) in solutions.iter_mut().zip(rhs) {
            solution.copy_from_slice(rhs);
        }
        let in_place = solutions.each_mut().map(|solution| &mut **solution);
        self.lu
            .solve_many_in_place(in_place, &mut workspace.permuted);
        std::array::from_fn(|r| {
            accepted(
                (self.pattern, self.values, self.exits),
                rhs[r],
                solutions[r],
                tolerances[r],
            )
        })
    }
}

/// The report of a forward solution `solution` of `A x = rhs` (`A` of
/// `pattern`, off-diagonal `values` and row sums `exits`), if its residual,
/// evaluated without the diagonal ([`SparsePattern::chain_residual`]), is
/// within `tolerance`.
fn accepted(
    (pattern, values, exits): (&SparsePattern, &[f64], &[f64]),
    rhs: &[f64],
    solution: &[f64],
    tolerance: f64,
) -> Result<SolveReport, SolverError> {
    let residual = pattern.chain_residual(values, exits, solution, rhs);
    Ok(report_of(accept(residual, solution, tolerance)?))
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

    /// The pattern of a full 2 x 2 matrix.
    fn dense_two_by_two() -> SparsePattern {
        SparsePattern {
            n: 2,
            row_offsets: vec![0, 2, 4],
            columns: vec![0, 1, 0, 1],
        }
    }

    #[test]
    fn after_an_error_solving_while_factorising_leaves_the_state_of_the_two_steps() {
        let (pattern, values) = tridiagonal(30, 0.4);
        let singular = [1.0, -1.0, -1.0, 1.0];
        let mut solver = LuSolver::new(dense_two_by_two(), DEFAULT_TOLERANCE).unwrap();
        let mut x = [0.0; 2];
        assert!(
            solver
                .factorize_and_solve([&[0.0, 1.0]], [&mut x], [1e-9])
                .is_err()
        );
        solver
            .set_values_with(|own, exits| {
                own.copy_from_slice(&singular);
                exits.fill(0.0);
            })
            .unwrap();
        let outcome = solver.factorize_and_solve([&[0.0, 1.0]], [&mut x], [1e-9]);
        assert!(
            matches!(outcome, Err(SolverError::Singular(_))),
            "{outcome:?}"
        );
        assert!(solver.solve(&[0.0, 1.0], &mut x).is_err());
        solver
            .set_values_with(|own, exits| {
                own.copy_from_slice(&[1.0, -0.5, -0.5, 1.0]);
                exits.fill(0.5);
            })
            .unwrap();
        let [report] = solver
            .factorize_and_solve([&[0.5, 0.5]], [&mut x], [1e-12])
            .unwrap();
        assert!(report.unwrap().residual <= 1e-12 && (x[0] - 1.0).abs() < 1e-12);

        let mut row_sums = vec![0.0; 30];
        super::super::derive_exits(&pattern, &values, &mut row_sums);
        let (mut at_once, mut two_steps) = (
            LuSolver::new(pattern.clone(), DEFAULT_TOLERANCE).unwrap(),
            LuSolver::new(pattern, DEFAULT_TOLERANCE).unwrap(),
        );
        let mut not_finite = vec![1.0; 30];
        not_finite[7] = f64::NAN;
        let mut y = vec![0.0; 30];
        at_once
            .set_values_with(|own, exits| {
                own.copy_from_slice(&values);
                exits.copy_from_slice(&row_sums);
            })
            .unwrap();
        let outcome = at_once.factorize_and_solve([&not_finite], [&mut y], [1e-9]);
        assert!(
            matches!(outcome, Err(SolverError::NonFinite(_))),
            "{outcome:?}"
        );
        two_steps.factorize(&values).unwrap();
        assert!(two_steps.solve(&not_finite, &mut y).is_err());
        let (mut x_at_once, mut x_two_steps) = (vec![0.0; 30], vec![0.0; 30]);
        let ones = vec![1.0; 30];
        assert_eq!(
            at_once.solve(&ones, &mut x_at_once),
            two_steps.solve(&ones, &mut x_two_steps)
        );
        assert_eq!(x_at_once, x_two_steps);
    }

    #[test]
    fn a_singular_system_is_an_error_not_a_number() {
        let mut solver = LuSolver::new(dense_two_by_two(), DEFAULT_TOLERANCE).unwrap();
        let mut x = [0.0; 2];
        let result = solver
            .factorize(&[1.0, -1.0, -1.0, 1.0])
            .and_then(|()| solver.solve(&[0.0, 1.0], &mut x));
        assert!(result.is_err(), "{result:?}");
    }
}
