//! Sparse linear solves of `A x = b` and `A^T y = c` for the transient part
//! of a Markov chain, `A = I - Q` (method.md sections 1 and 2).
//!
//! Two methods share one accuracy contract:
//!
//! * [`LuSolver`]: a multifrontal sparse LU without pivoting on the pattern
//!   of `A + A^T` (`multifrontal`, ordered by `ordering`). Exact up to
//!   rounding; its fill-in grows about as `n log n` on grid-like chains, so
//!   memory limits it to about 10^6 unknowns on this kind of machine.
//! * [`KrylovSolver`]: BiCGSTAB (faer's) right-preconditioned by an
//!   incomplete LU factorisation without fill-in, ILU(0). Memory stays
//!   linear in the number of entries, and a solve starts from the caller's
//!   `x`: between optimiser iterations the previous solution is an excellent
//!   starting point (warm start).
//!
//! [`LinearSolver`] picks one by [`SolverSettings`]. Whatever the method,
//! every solve is checked by its true residual `max_i |(A x - b)_i|` (or the
//! transposed one), reported in a [`SolveReport`], and a solve whose residual
//! exceeds the tolerance is an error ([`SolverError::Inaccurate`]), never a
//! number. `A` is an M-matrix (`Q` substochastic, every transient state
//! leaves `T` eventually), so both the LU and ILU(0) exist without pivoting
//! breakdown; a singular `A` is reported, not solved.
//!
//! The residual alone does not bound the error of `x` (method.md section 8):
//! [`LinearSolver::solve`] also bounds it, `|x - A^{-1} b| <= max(t) ||r||_inf`
//! with `t = A^{-1} 1` the expected time in `T` ([`bound`]), refines `x`
//! with the same factors while that bound exceeds the tolerance, and
//! reports the bound as [`SolveReport::error_bound`]. Where double
//! precision cannot prove the bound (or the residual), a system of at most
//! [`SolverSettings::exact_limit`] unknowns is solved again exactly
//! ([`exact`]: p-adic lifting, rational reconstruction, an exact check in
//! integers) within a work budget and its value reported to the last bit;
//! on a larger system, or past the budget, the bound that cannot be proved
//! is an error ([`SolverError::Unbounded`],
//! [`SolverError::TooLargeForExact`]).

pub mod bound;
mod column_counts;
pub mod exact;
mod ilu;
mod krylov;
mod lu;
mod multifrontal;
mod ordering;
#[cfg(test)]
mod stiff_tests;

use bound::ExpectedTime;
pub use ilu::Ilu0;
pub use krylov::KrylovSolver;
pub use lu::LuSolver;

use thiserror::Error;

/// The largest residual `max_i |(A x - b)_i|` accepted by default.
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

/// With [`SolverMethod::Auto`], systems with at most this many unknowns use
/// [`LuSolver`] without a trial. Measured on the grid family with 2-node
/// controllers (`experiments/solver-choice`, one process per cell): the
/// multifrontal LU was 3 to 13 times faster than BiCGSTAB + ILU(0) from 1.6e4
/// to 1.5e5 unknowns, and at 3.3e5 unknowns (995,320 GMC states) value and
/// gradient peak at 2.0 GiB.
pub const DEFAULT_LU_LIMIT: usize = 500_000;

/// With [`SolverMethod::Auto`], a BiCGSTAB solve that needs more iterations
/// than [`lu_cost_in_iterations`], which is at most this, is abandoned for
/// LU, which then stays in use, if the system has at most
/// [`SolverSettings::lu_switch_limit`] unknowns: a one-shot LU cost 20 to 60
/// BiCGSTAB iterations from 1.6e4 to 1.5e5 unknowns.
pub const SLOW_KRYLOV_ITERATIONS: usize = 60;

/// With [`SolverMethod::Auto`], the BiCGSTAB iterations of the trial that
/// predicts the cost of a whole solve (see [`LinearSolver`]).
pub const PROBE_ITERATIONS: usize = 20;

/// The default [`SolverSettings::lu_switch_limit`]: the factors grow about
/// as `n log n` on grid-like chains (0.7 GiB at 3.3e5 unknowns), so LU of
/// 1e6 unknowns needs a few GiB.
pub const DEFAULT_LU_SWITCH_LIMIT: usize = 1_000_000;

/// BiCGSTAB iterations allowed per solve by default.
pub const DEFAULT_MAX_ITERATIONS: usize = 20_000;

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
    #[error(
        "residual {residual:e} exceeds the tolerance {tolerance:e}: the computed solution does \
         not satisfy its equations closely enough (remedies: `--solver lu`, or a larger \
         `--tolerance` where a looser result will do)"
    )]
    Inaccurate {
        /// `max_i |(A x - b)_i|`.
        residual: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
    /// The iterative solver stopped before reaching the tolerance.
    #[error(
        "BiCGSTAB did not reach the tolerance {tolerance:e} in {iterations} iterations \
         (residual {residual:e}); use --solver lu or allow more iterations"
    )]
    NotConverged {
        /// Iterations performed.
        iterations: usize,
        /// `max_i |(A x - b)_i|` of the last iterate.
        residual: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
    /// The bound on the solution's error, `max(t) ||r||_inf` (method.md
    /// section 8), exceeds the tolerance even after iterative refinement.
    #[error(
        "the error bound {error_bound:e} exceeds the tolerance {tolerance:e}: the chain spends \
         up to {expected_time:e} expected steps in the transient states, so even a residual of \
         rounding size in double precision allows an error that large (a slowly mixing chain); \
         the value is not reported (remedy: a larger `--tolerance`, which accepts the looser \
         bound and reports it with the value)"
    )]
    Unbounded {
        /// The smallest bound reached.
        error_bound: f64,
        /// The tolerance asked for.
        tolerance: f64,
        /// The bound on `max(t)`, infinite when none could be certified.
        expected_time: f64,
    },
    /// Double precision could not prove the bound, and the system is too
    /// large for the exact solve ([`exact`]), or its solution too long for
    /// the exact solve's budget.
    #[error(
        "the error bound {error_bound:e} (the best proved in double precision) exceeds the \
         tolerance {tolerance:e}: the chain spends up to {expected_time:e} expected steps in \
         the transient states, too many for double precision to prove the value within the \
         tolerance, and the exact rational solve that proves such values {refusal}; the value \
         is not reported (remedies: a larger `--tolerance`, which accepts the looser bound \
         and reports it with the value, or smaller controllers or a smaller game)"
    )]
    TooLargeForExact {
        /// The smallest bound reached in double precision.
        error_bound: f64,
        /// The tolerance asked for.
        tolerance: f64,
        /// The bound on `max(t)`, infinite when none could be certified.
        expected_time: f64,
        /// The unknowns of the system.
        unknowns: usize,
        /// [`SolverSettings::exact_limit`].
        exact_limit: usize,
        /// What stopped the exact solve (the size, the fill of its LU or its
        /// work budget), in words.
        refusal: String,
    },
    /// The tolerance is not a finite positive number.
    #[error("the tolerance must be finite and positive, not {0}")]
    InvalidTolerance(f64),
    /// Memory for the factorisation could not be allocated.
    #[error("out of memory in the sparse LU factorisation")]
    OutOfMemory,
    /// The sparse LU's symbolic analysis found a dense front whose entries
    /// 32-bit indices cannot address (more than 2^32, about 34 GB of
    /// doubles): the factorisation is out of reach, BiCGSTAB is not.
    #[error(
        "a sparse LU of these {unknowns} unknowns needs a dense front of {front} x {front} \
         entries (beyond 32-bit indices, about {gigabytes:.0} GB); the iterative solver \
         (`krylov`) needs no factorisation",
        gigabytes = (*front as f64).powi(2) * 8.0 / 1e9
    )]
    LuTooLarge {
        /// The unknowns of the system.
        unknowns: usize,
        /// The rows (and columns) of the largest front.
        front: usize,
    },
    /// The pattern or values have inconsistent sizes or unsorted columns.
    #[error("malformed sparse matrix: {0}")]
    Malformed(String),
}

/// Which method solves the linear systems.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverMethod {
    /// [`SolverMethod::Lu`] up to [`SolverSettings::lu_limit`] unknowns,
    /// [`SolverMethod::Krylov`] above.
    #[default]
    Auto,
    /// Sparse LU (direct).
    Lu,
    /// BiCGSTAB with an ILU(0) preconditioner, warm-started (iterative).
    Krylov,
}

impl SolverMethod {
    /// The name used on the command line and in output files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Lu => "lu",
            Self::Krylov => "krylov",
        }
    }
}

impl std::str::FromStr for SolverMethod {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        [Self::Auto, Self::Lu, Self::Krylov]
            .into_iter()
            .find(|method| method.name() == text)
            .ok_or_else(|| format!("unknown solver `{text}` (expected auto, lu or krylov)"))
    }
}

/// How linear systems are solved, and how accurately.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// The method, or [`SolverMethod::Auto`] to choose by size.
    pub method: SolverMethod,
    /// The largest accepted residual `max_i |(A x - b)_i|`.
    pub tolerance: f64,
    /// With [`SolverMethod::Auto`]: the most unknowns solved by LU.
    pub lu_limit: usize,
    /// With [`SolverMethod::Auto`]: the most unknowns for which slow
    /// BiCGSTAB solves (over the iterations one LU costs) give way to LU.
    pub lu_switch_limit: usize,
    /// The most BiCGSTAB iterations per solve.
    pub max_iterations: usize,
    /// The most unknowns of a system solved exactly in rationals
    /// ([`exact`]) when double precision cannot prove its bound (0: never).
    pub exact_limit: usize,
    /// Whether policy iteration proves its optimum (the optimality
    /// certificate of `src/mdp/optimality.rs`, method.md section 6). Off
    /// only where values merely rank candidates, whose winner is then
    /// certified with it on (the local search): a result's proved upper
    /// values are then the final policy's own.
    pub prove_optimum: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            method: SolverMethod::Auto,
            tolerance: DEFAULT_TOLERANCE,
            lu_limit: DEFAULT_LU_LIMIT,
            lu_switch_limit: DEFAULT_LU_SWITCH_LIMIT,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            exact_limit: exact::DEFAULT_EXACT_LIMIT,
            prove_optimum: true,
        }
    }
}

impl SolverSettings {
    /// The default settings with another tolerance.
    pub fn with_tolerance(tolerance: f64) -> Self {
        Self {
            tolerance,
            ..Self::default()
        }
    }

    /// The method used for a system with `n` unknowns: never
    /// [`SolverMethod::Auto`].
    pub fn method_for(&self, n: usize) -> SolverMethod {
        match self.method {
            SolverMethod::Auto if n > self.lu_limit => SolverMethod::Krylov,
            SolverMethod::Auto => SolverMethod::Lu,
            chosen => chosen,
        }
    }

    fn check(&self) -> Result<(), SolverError> {
        if self.tolerance.is_finite() && self.tolerance > 0.0 {
            Ok(())
        } else {
            Err(SolverError::InvalidTolerance(self.tolerance))
        }
    }
}

/// The accuracy and cost of one solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveReport {
    /// `max_i |(A x - b)_i|` (or `|(A^T y - c)_i|`) of the returned solution.
    pub residual: f64,
    /// BiCGSTAB iterations (0 for LU), refinements and `auto`'s trial
    /// included (not those of the solve for the expected time of the error
    /// bound).
    pub iterations: usize,
    /// For a solve of `A x = b`: a bound on `max_i |x_i - (A^{-1} b)_i|`,
    /// `max(t) ||r||_inf` plus the rounding in computing `r` (method.md
    /// section 8). `None` for the solves that bound nothing (transposed
    /// solves and the methods' own).
    pub error_bound: Option<f64>,
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

    /// The stored entries of `row`, as a range into [`Self::columns`].
    pub fn row_range(&self, row: usize) -> std::ops::Range<usize> {
        self.row_offsets[row]..self.row_offsets[row + 1]
    }

    fn check(&self) -> Result<(), SolverError> {
        let bad = |m: &str| Err(SolverError::Malformed(m.to_string()));
        if self.row_offsets.len() != self.n + 1 || self.row_offsets[self.n] != self.columns.len() {
            return bad("row offsets do not match the entries");
        }
        for row in 0..self.n {
            let cols = &self.columns[self.row_range(row)];
            if cols.windows(2).any(|w| w[0] >= w[1]) || cols.iter().any(|&c| c >= self.n) {
                return bad("columns must be sorted, distinct and in range");
            }
        }
        Ok(())
    }

    /// `out = A x` for the matrix with this pattern and `values`.
    pub fn multiply(&self, values: &[f64], x: &[f64], out: &mut [f64]) {
        for (row, out_row) in out.iter_mut().enumerate().take(self.n) {
            let range = self.row_range(row);
            *out_row = self.columns[range.clone()]
                .iter()
                .zip(&values[range])
                .map(|(&c, &a)| a * x[c])
                .sum();
        }
    }

    /// `out = A^T y` for the matrix with this pattern and `values`.
    pub fn multiply_transposed(&self, values: &[f64], y: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (row, &y_row) in y.iter().enumerate().take(self.n) {
            for k in self.row_range(row) {
                out[self.columns[k]] += values[k] * y_row;
            }
        }
    }

    /// `max_i |(A x - b)_i|` for the matrix with this pattern and `values`.
    pub fn residual(&self, values: &[f64], x: &[f64], b: &[f64]) -> f64 {
        (0..self.n)
            .map(|row| {
                let range = self.row_range(row);
                let ax: f64 = self.columns[range.clone()]
                    .iter()
                    .zip(&values[range])
                    .map(|(&c, &a)| a * x[c])
                    .sum();
                (ax - b[row]).abs()
            })
            .fold(0.0, nan_max)
    }

    /// `max_i |(A x - b)_i|` for the matrix with off-diagonal `values` and
    /// row sums `exits`, each row evaluated as `sum_{j != i} |a_ij| (x_i -
    /// x_j) + exit_i x_i - b_i` (method.md section 8): without the diagonal,
    /// whose rounding would swamp the residual of a slowly mixing chain.
    pub fn chain_residual(&self, values: &[f64], exits: &[f64], x: &[f64], b: &[f64]) -> f64 {
        (0..self.n)
            .map(|row| {
                let xi = x[row];
                let range = self.row_range(row);
                let moves: f64 = self.columns[range.clone()]
                    .iter()
                    .zip(&values[range])
                    .filter(|&(&column, _)| column != row)
                    .map(|(&column, &a)| -a * (xi - x[column]))
                    .sum();
                (moves + exits[row] * xi - b[row]).abs()
            })
            .fold(0.0, nan_max)
    }

    /// `max_i |(A^T y - c)_i|`, using `work` (length `n`) for `A^T y`.
    pub fn transposed_residual(
        &self,
        values: &[f64],
        y: &[f64],
        c: &[f64],
        work: &mut [f64],
    ) -> f64 {
        self.multiply_transposed(values, y, work);
        work.iter()
            .zip(c)
            .map(|(a, c)| (a - c).abs())
            .fold(0.0, nan_max)
    }
}

/// `max` that lets NaN win, so a NaN residual is never mistaken for a small one.
fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// Which direction a solve goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Direction {
    /// `A x = b`.
    Forward,
    /// `A^T y = c`.
    Transposed,
}

/// Systems of fewer unknowns solve their two directions one after the
/// other on the calling thread: handing one to another thread (waking it,
/// and its spinning once done) costs more CPU than such a solve (PRISM's
/// grid-avoid-4-0.1 with 2 and 3 nodes, 33 and 49 unknowns: 17% and 21%
/// less CPU per run). The same bound as the gradient pass's
/// `PARALLEL_GRADIENT_ROWS`; below it the portfolio's starts, which run in
/// parallel, keep both threads busy (drone-4-1, 2,305 unknowns: the same
/// CPU and wall time).
const PARALLEL_SOLVE_ROWS: usize = 4096;

/// Runs `forward` and `transposed` of a system of `rows` unknowns: at once
/// on two threads (rayon), or in turn below [`PARALLEL_SOLVE_ROWS`].
fn join_directions(
    rows: usize,
    forward: impl FnOnce() -> Result<SolveReport, SolverError> + Send,
    transposed: impl FnOnce() -> Result<SolveReport, SolverError> + Send,
) -> SolvePair {
    if rows < PARALLEL_SOLVE_ROWS {
        (forward(), transposed())
    } else {
        rayon::join(forward, transposed)
    }
}

/// The cost of a one-shot sparse LU (symbolic analysis, numeric
/// factorisation, one solve) of a grid-like system with `nnz` entries, in
/// BiCGSTAB + ILU(0) iterations on the same system, whose cost is linear in
/// `nnz`: measured on the grid family with 2-node controllers
/// (`experiments/solver-choice`, `results/solver-choice.csv`), 22 to 24
/// iterations at 3.2e5 entries, 20 to 34 at 7.3e5, 31 to 37 at 1.3e6 and 23
/// to 58 at 2.9e6 (single runs on a shared machine); modelled as
/// `30 (nnz / 1.3e6)^(1/4)` and capped at [`SLOW_KRYLOV_ITERATIONS`].
pub fn lu_cost_in_iterations(nnz: usize) -> f64 {
    (30.0 * (nnz as f64 / 1.3e6).powf(0.25)).min(SLOW_KRYLOV_ITERATIONS as f64)
}

/// How many times faster a floating-point operation of the LU's dense
/// kernels runs than one of a BiCGSTAB + ILU(0) iteration (sparse, bound by
/// memory). Measured with `eval --gradient` on PAYNT's dodge-8 (7,938
/// unknowns, 38,684 entries, an LU of 2.5e9 flops) on the 2-core machine:
/// LU 0.18 s against BiCGSTAB's 0.5 ms per iteration, about 14 and 0.8
/// GFlop/s.
pub const DENSE_SPEEDUP: f64 = 16.0;

/// Below this predicted LU cost (in BiCGSTAB iterations), `auto` takes LU
/// without a trial: the trial alone ([`PROBE_ITERATIONS`]) and the two
/// solves of a value and its gradient would cost about as much.
pub const TRIAL_WORTH_ITERATIONS: f64 = 4.0 * PROBE_ITERATIONS as f64;

/// The cost of an LU of `flops` floating-point operations
/// ([`LuSolver::factorisation_flops`]) in BiCGSTAB + ILU(0) iterations on
/// `pattern`, each two products with `A` and two ILU solves (about `8 nnz`
/// flops) and six vector updates (`12 n`), at [`DENSE_SPEEDUP`].
pub fn lu_iterations_from_flops(flops: f64, pattern: &SparsePattern) -> f64 {
    let per_iteration = 8.0 * pattern.nnz() as f64 + 12.0 * pattern.n as f64;
    flops / (DENSE_SPEEDUP * per_iteration.max(1.0))
}

/// The BiCGSTAB settings of a system of `n` unknowns: with `auto` up to the
/// switch limit, at most `lu_cost` iterations per solve (then LU is
/// cheaper).
fn krylov_settings(settings: &SolverSettings, n: usize, lu_cost: f64) -> SolverSettings {
    if settings.method == SolverMethod::Auto && n <= settings.lu_switch_limit.max(settings.lu_limit)
    {
        SolverSettings {
            max_iterations: settings.max_iterations.min(lu_cost.ceil() as usize).max(1),
            ..*settings
        }
    } else {
        *settings
    }
}

/// Why `settings` give the method [`SolverSettings::method_for`] chooses
/// for `n` unknowns, before any solve.
fn initial_reason(settings: &SolverSettings, n: usize) -> String {
    match settings.method {
        SolverMethod::Auto if n <= settings.lu_limit => format!(
            "auto: lu, {n} unknowns, at most the LU limit {}",
            settings.lu_limit
        ),
        SolverMethod::Auto if n > settings.lu_switch_limit => format!(
            "auto: krylov, {n} unknowns, more than the {} up to which LU is tried \
             (LU's memory)",
            settings.lu_switch_limit
        ),
        SolverMethod::Auto => format!(
            "auto: krylov, {n} unknowns, more than the LU limit {}; a trial decides",
            settings.lu_limit
        ),
        chosen => format!("{} as set", chosen.name()),
    }
}

/// The checks every method makes before a solve: sizes and finite inputs.
fn check_solve_inputs(n: usize, rhs: &[f64], x: &[f64]) -> Result<(), SolverError> {
    if rhs.len() != n || x.len() != n {
        return Err(SolverError::Malformed(
            "right-hand side or solution has the wrong length".into(),
        ));
    }
    if rhs.iter().any(|v| !v.is_finite()) {
        return Err(SolverError::NonFinite("right-hand side"));
    }
    Ok(())
}

/// The check every method makes on a matrix's values.
fn check_values(pattern: &SparsePattern, values: &[f64]) -> Result<(), SolverError> {
    if values.len() != pattern.nnz() {
        return Err(SolverError::Malformed(
            "values do not match the pattern".into(),
        ));
    }
    if values.iter().any(|v| !v.is_finite()) {
        return Err(SolverError::NonFinite("matrix entry"));
    }
    Ok(())
}

/// The check of a chain's matrix given as off-diagonal `values` and row
/// sums `exits` (method.md section 8): sizes, finite numbers, off-diagonal
/// entries at most 0 and exits at least 0 (`Q` substochastic), which the
/// subtraction-free elimination needs.
fn check_chain(pattern: &SparsePattern, values: &[f64], exits: &[f64]) -> Result<(), SolverError> {
    check_values(pattern, values)?;
    if exits.len() != pattern.n {
        return Err(SolverError::Malformed(
            "exits do not match the pattern".into(),
        ));
    }
    if exits.iter().any(|e| !e.is_finite()) {
        return Err(SolverError::NonFinite("probability of leaving T"));
    }
    if exits.iter().any(|&e| e < 0.0) {
        return Err(SolverError::Malformed(
            "a negative probability of leaving T".into(),
        ));
    }
    for row in 0..pattern.n {
        let range = pattern.row_range(row);
        let positive = pattern.columns[range.clone()]
            .iter()
            .zip(&values[range])
            .any(|(&column, &a)| column != row && a > 0.0);
        if positive {
            return Err(SolverError::Malformed(format!(
                "row {row} has a positive off-diagonal entry: not I - Q for a substochastic Q"
            )));
        }
    }
    Ok(())
}

/// Sets each diagonal entry of `A` to its row's exit plus the magnitudes of
/// its off-diagonal entries (a sum of nonnegative numbers), so that `A 1 =
/// exits` up to one rounding per row.
fn complete_diagonal(pattern: &SparsePattern, values: &mut [f64], exits: &[f64]) {
    for (row, &exit) in exits.iter().enumerate() {
        let range = pattern.row_range(row);
        let mut diagonal = None;
        let mut sum = exit;
        for k in range {
            if pattern.columns[k] == row {
                diagonal = Some(k);
            } else {
                sum -= values[k];
            }
        }
        if let Some(k) = diagonal {
            values[k] = sum;
        }
    }
}

/// The row sums `A 1` of a matrix given with its diagonal, for callers that
/// do not know the exits: `a_ii - sum_{j != i} |a_ij|`, summed with
/// compensation (TwoSum) and at least 0. The diagonal's own rounding is
/// then the caller's (method.md section 8 says why the exits should be
/// given instead).
fn derive_exits(pattern: &SparsePattern, values: &[f64], exits: &mut [f64]) {
    for (row, exit) in exits.iter_mut().enumerate() {
        let (mut sum, mut correction) = (0.0, 0.0);
        for k in pattern.row_range(row) {
            let term = if pattern.columns[k] == row {
                values[k]
            } else {
                -values[k].abs()
            };
            let (next, error) = bound::two_sum(sum, term);
            sum = next;
            correction += error;
        }
        *exit = (sum + correction).max(0.0);
    }
}

/// The residual contract: a finite solution whose residual is at most the tolerance.
fn accept(residual: f64, x: &[f64], tolerance: f64) -> Result<f64, SolverError> {
    if x.iter().any(|v| !v.is_finite()) {
        return Err(SolverError::Singular("the solution is not finite".into()));
    }
    if residual.is_nan() || residual > tolerance {
        return Err(SolverError::Inaccurate {
            residual,
            tolerance,
        });
    }
    Ok(residual)
}

/// The sparse solver of one fixed pattern, by the method [`SolverSettings`]
/// chooses for its size. With [`SolverMethod::Auto`], a BiCGSTAB solve that
/// does not converge is repeated by LU, which then stays in use: `auto`
/// never fails where LU would succeed. On systems of at most
/// [`SolverSettings::lu_switch_limit`] unknowns it first predicts the cost
/// of BiCGSTAB from a short trial and takes LU at once when that is cheaper
/// (`choose_by_trial`), and it gives BiCGSTAB only as many iterations per
/// solve as an LU costs ([`lu_cost_in_iterations`], or
/// [`lu_iterations_from_flops`] below the LU limit, where the analysis
/// predicts a costly LU and BiCGSTAB is tried first) before turning to LU:
/// slowly mixing chains are solved faster by LU, and a wrong prediction
/// costs at most one LU's worth of iterations (the ski-rental bound: at
/// most about twice the better method per solve). [`Self::reason`] says why
/// the method in use was chosen.
pub struct LinearSolver {
    backend: Backend,
    reason: String,
    probe_pending: bool,
    fall_back_to_lu: bool,
    /// What one LU costs, in BiCGSTAB iterations (the trial's yardstick).
    lu_cost: f64,
    /// The LU analysed to predict that cost, kept for the fall-back.
    spare_lu: Option<Box<LuSolver>>,
    krylov_budget: usize,
    /// [`SolverSettings::max_iterations`]: BiCGSTAB's budget where no LU
    /// can take over.
    max_iterations: usize,
    /// Whether [`Self::factorize_and_solve`] solves during the LU's
    /// factorisation (see there).
    solve_while_factorising: bool,
    tolerance: f64,
    /// [`SolverSettings::exact_limit`].
    exact_limit: usize,
    /// The row sums `A 1` of the last values (the probabilities of leaving
    /// `T`): with the off-diagonal values they define `A` (method.md
    /// section 8).
    exits: Vec<f64>,
    expected_time: ExpectedTime,
    scratch: BoundScratch,
}

/// Vectors of the error bound: all ones (the right-hand side of `A t = 1`),
/// the residual and the correction of a refinement.
#[derive(Default)]
struct BoundScratch {
    ones: Vec<f64>,
    residual: Vec<f64>,
    correction: Vec<f64>,
}

/// `max(t)` certified by an estimate `time` of `t = A^{-1} 1` just solved
/// for (module [`bound`]); a solve of tolerance `tolerance` cannot be
/// bounded if it does not certify.
fn certify_solved(
    time: &ExpectedTime,
    pattern: &SparsePattern,
    values: &[f64],
    exits: &[f64],
    tolerance: f64,
) -> Result<f64, SolverError> {
    time.certify(pattern, values, exits, 1.0)
        .ok_or(SolverError::Unbounded {
            error_bound: f64::INFINITY,
            tolerance,
            expected_time: f64::INFINITY,
        })
}

/// The outcome of a solve for the expected times `A t = 1`: a residual too
/// large to bound `max(t)` (its rounding floor grows with `max(t)`, see
/// [`EXPECTED_TIME_TOLERANCE`]) means that no error bound can be proved,
/// [`SolverError::Unbounded`] with the estimate of `max(t)`.
fn unprovable(
    solved: Result<SolveReport, SolverError>,
    time: &ExpectedTime,
    tolerance: f64,
) -> Result<SolveReport, SolverError> {
    match solved {
        Err(SolverError::Inaccurate { .. } | SolverError::NotConverged { .. }) => {
            Err(SolverError::Unbounded {
                error_bound: f64::INFINITY,
                tolerance,
                expected_time: time.largest(),
            })
        }
        other => other,
    }
}

/// What [`LinearSolver::reason`] adds once a solve was exact.
const EXACT_REASON: &str =
    "; exact rational solve where double precision could not prove the bound";

/// The most unknowns of a system that [`LinearSolver::factorize_and_solve`]
/// solves during the factorisation before any solve has shown whether it
/// needs a refinement: on the grids of `example grid`, whose expected times
/// grow with their size, the bound of 1e-9 is met without refinement up to
/// 2.0e5 unknowns (at 2.0e5 within 1%) and needs one from 2.6e5 on.
pub const SOLVE_WHILE_FACTORISING_UNKNOWNS: usize = 150_000;

/// Residual tolerance of the solve for the expected time `A t = 1`: its
/// bound needs `||A t_hat - 1||_inf` below 1 only (module [`bound`]). On a
/// chain whose controller memory splits a lazy state into a block, the
/// residual of any `t_hat` in double precision is about `u max(t)` times the
/// weight of the moves inside the block, which reaches 1/2 at `max(t) =
/// 1e16`; up to this tolerance the bound on `max(t)` is at most 4 times
/// `max(t_hat)`.
const EXPECTED_TIME_TOLERANCE: f64 = 0.75;

enum Backend {
    Lu(Box<LuSolver>),
    Krylov(Box<KrylovSolver>),
}

/// The outcome of [`LinearSolver::solve_both`]: the forward and the transposed solve.
pub type SolvePair = (
    Result<SolveReport, SolverError>,
    Result<SolveReport, SolverError>,
);

impl LinearSolver {
    /// Prepares solves for matrices with `pattern` (for LU: the symbolic
    /// analysis). With `auto` below the LU limit, the analysis predicts the
    /// LU's cost ([`lu_iterations_from_flops`]); where it exceeds
    /// [`TRIAL_WORTH_ITERATIONS`] (chains whose graph has large separators,
    /// like the products of several moving agents), BiCGSTAB starts with a
    /// trial, and the analysed LU is kept for the fall-back.
    pub fn new(pattern: SparsePattern, settings: &SolverSettings) -> Result<Self, SolverError> {
        let auto = settings.method == SolverMethod::Auto;
        let n = pattern.n;
        let mut reason = initial_reason(settings, n);
        let mut lu_cost = lu_cost_in_iterations(pattern.nnz());
        let mut spare_lu = None;
        // Whether an LU of this pattern can be built at all.
        let mut lu_possible = true;
        let backend = match settings.method_for(n) {
            SolverMethod::Krylov => Backend::Krylov(Box::new(KrylovSolver::new(
                pattern,
                &krylov_settings(settings, n, lu_cost),
            )?)),
            _ => match LuSolver::analyse(&pattern, settings.tolerance) {
                Err(SolverError::LuTooLarge { front, .. }) if auto => {
                    reason = format!(
                        "auto: krylov, {n} unknowns: an LU needs a dense front of {front} x \
                         {front} entries, beyond 32-bit indices"
                    );
                    lu_cost = f64::INFINITY;
                    lu_possible = false;
                    Backend::Krylov(Box::new(KrylovSolver::new(
                        pattern,
                        &krylov_settings(settings, n, lu_cost),
                    )?))
                }
                analysis => {
                    let lu = Box::new(LuSolver::with_analysis(
                        pattern,
                        analysis?,
                        settings.tolerance,
                    ));
                    let flops = lu.factorisation_flops();
                    let predicted = lu_iterations_from_flops(flops, lu.pattern());
                    if auto && predicted > TRIAL_WORTH_ITERATIONS {
                        lu_cost = predicted;
                        reason = format!(
                            "auto: krylov, {n} unknowns: an LU of {flops:.1e} flops costs \
                             about {predicted:.0} BiCGSTAB iterations; a trial decides"
                        );
                        let krylov = KrylovSolver::new(
                            lu.pattern().clone(),
                            &krylov_settings(settings, n, lu_cost),
                        )?;
                        spare_lu = Some(lu);
                        Backend::Krylov(Box::new(krylov))
                    } else {
                        Backend::Lu(lu)
                    }
                }
            },
        };
        let krylov_budget = krylov_settings(settings, n, lu_cost).max_iterations;
        let probe_pending = auto
            && lu_possible
            && matches!(backend, Backend::Krylov(_))
            && (spare_lu.is_some() || n <= settings.lu_switch_limit);
        Ok(Self {
            backend,
            reason,
            probe_pending,
            fall_back_to_lu: auto && lu_possible,
            lu_cost,
            spare_lu,
            solve_while_factorising: n <= SOLVE_WHILE_FACTORISING_UNKNOWNS,
            krylov_budget,
            max_iterations: settings.max_iterations,
            tolerance: settings.tolerance,
            exact_limit: settings.exact_limit,
            exits: vec![0.0; n],
            expected_time: ExpectedTime::new(),
            scratch: BoundScratch::default(),
        })
    }

    /// The values of `A` as of the last factorisation (during
    /// [`Self::factorize_and_solve`], as just set).
    pub fn values(&self) -> &[f64] {
        match &self.backend {
            Backend::Lu(lu) => lu.values(),
            Backend::Krylov(krylov) => krylov.values(),
        }
    }

    /// The method in use ([`SolverMethod::Lu`] or [`SolverMethod::Krylov`]).
    pub fn method(&self) -> SolverMethod {
        match self.backend {
            Backend::Lu(_) => SolverMethod::Lu,
            Backend::Krylov(_) => SolverMethod::Krylov,
        }
    }

    /// Why [`Self::method`] is in use, in words (for reports): the setting,
    /// the size limits, or `auto`'s prediction from a short BiCGSTAB trial.
    pub fn reason(&self) -> &str {
        &self.reason
    }

    /// The pattern of `A`.
    pub fn pattern(&self) -> &SparsePattern {
        match &self.backend {
            Backend::Lu(lu) => lu.pattern(),
            Backend::Krylov(krylov) => krylov.pattern(),
        }
    }

    /// Takes new values of `A` (aligned with the pattern's entries, the
    /// diagonal included) and factorises them: the LU, or the ILU(0)
    /// preconditioner. The exits are derived from the diagonal
    /// ([`derive_exits`]); a caller that knows them uses
    /// [`Self::factorize_with`].
    #[cfg(test)]
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), SolverError> {
        check_values(self.pattern(), values)?;
        let mut exits = std::mem::take(&mut self.exits);
        derive_exits(self.pattern(), values, &mut exits);
        self.exits = exits;
        match &mut self.backend {
            Backend::Lu(lu) => lu.factorize(values),
            Backend::Krylov(krylov) => krylov.factorize(values),
        }
    }

    /// Frees an LU's factors ([`LuSolver::release`]) until the next
    /// factorisation; an iterative solver keeps its preconditioner (the
    /// size of the matrix).
    pub fn release(&mut self) {
        if let Backend::Lu(lu) = &mut self.backend {
            lu.release();
        }
    }

    /// Factorises `A` as `fill` writes it into the solver's own copies
    /// (holding the previous numbers on entry), without a second copy:
    /// the off-diagonal entries `-Q` into the values (aligned with the
    /// pattern) and the row sums `A 1`, the probabilities of leaving `T`,
    /// into the exits. The diagonal is their sum, never `1 - Q(m, m)`
    /// (method.md section 8).
    ///
    /// With `auto`, an ILU(0) that meets a zero pivot (it subtracts, and a
    /// nearly closed block can cancel to 0 where the LU, which never
    /// subtracts, cannot) hands the matrix to LU for good.
    pub fn factorize_with(
        &mut self,
        fill: impl FnOnce(&mut [f64], &mut [f64]),
    ) -> Result<(), SolverError> {
        match &mut self.backend {
            Backend::Lu(lu) => {
                let factorised = lu.factorize_with(fill);
                self.exits.copy_from_slice(lu.exits());
                factorised
            }
            Backend::Krylov(krylov) => match krylov.factorize_with(&mut self.exits, fill) {
                Err(SolverError::Singular(pivot)) if self.fall_back_to_lu => {
                    self.reason = format!(
                        "auto: lu, ILU(0) met a zero pivot (before: {})",
                        self.reason
                    );
                    self.fall_back()?;
                    match self.backend {
                        Backend::Lu(_) => Ok(()),
                        // No LU could be built: the zero pivot stands.
                        Backend::Krylov(_) => Err(SolverError::Singular(pivot)),
                    }
                }
                factorised => factorised,
            },
        }
    }

    /// The row sums `A 1` of the last values (see [`Self::factorize_with`]).
    pub fn exits(&self) -> &[f64] {
        &self.exits
    }

    /// [`Self::factorize_with`] followed by [`Self::solve`], for a system
    /// solved once: LU then solves `A x = b`, and the expected times of the
    /// error bound when no previous estimate certifies them, during the
    /// factorisation, without storing `L` below its pivot blocks (the
    /// larger half of the factors). `x` is bit for bit the solution that
    /// [`Self::factorize_with`] and [`Self::solve`] give; a later solve
    /// (a refinement of `x`, or any other) factorises again, keeping `L`.
    ///
    /// A refinement thus costs a second factorisation, so this solver stops
    /// solving during the factorisation once a solve has needed one, and
    /// starts that way only on systems of at most
    /// [`SOLVE_WHILE_FACTORISING_UNKNOWNS`] unknowns; otherwise it
    /// factorises keeping `L`, then solves.
    ///
    /// Where double precision cannot prove the bound, the exact fallback
    /// of [`Self::solve`] applies.
    pub fn factorize_and_solve(
        &mut self,
        fill: impl FnOnce(&mut [f64], &mut [f64]),
        b: &[f64],
        x: &mut [f64],
    ) -> Result<SolveReport, SolverError> {
        let solved = self.factorize_and_solve_in_double(fill, b, x);
        self.exactly_if_unprovable(solved, b, x)
    }

    /// [`Self::factorize_and_solve`] in double precision only.
    fn factorize_and_solve_in_double(
        &mut self,
        fill: impl FnOnce(&mut [f64], &mut [f64]),
        b: &[f64],
        x: &mut [f64],
    ) -> Result<SolveReport, SolverError> {
        let lu = match &mut self.backend {
            Backend::Lu(lu) if lu.pattern().n > 0 && self.solve_while_factorising => lu,
            _ => {
                self.factorize_with(fill)?;
                return self.solve(b, x);
            }
        };
        let set = lu.set_values_with(fill);
        self.exits.copy_from_slice(lu.exits());
        set?;
        let n = lu.pattern().n;
        let time = &mut self.expected_time;
        let reused = time.certify(lu.pattern(), lu.values(), &self.exits, bound::REUSE_LIMIT);
        let (report, largest_time) = match reused {
            Some(largest) => {
                let [report] = lu.factorize_and_solve([b], [x], [self.tolerance])?;
                (report?, largest)
            }
            None => {
                self.scratch.ones.resize(n, 1.0);
                let solves = lu.factorize_and_solve(
                    [b, &self.scratch.ones],
                    [x, time.estimate_mut(n)],
                    [self.tolerance, EXPECTED_TIME_TOLERANCE],
                );
                time.store();
                let [value, solved] = solves?;
                let report = value?;
                unprovable(solved, time, self.tolerance)?;
                let certified =
                    certify_solved(time, lu.pattern(), lu.values(), &self.exits, self.tolerance);
                (report, certified?)
            }
        };
        let bounded = self.bound_error(b, x, report, Some(largest_time));
        if let Backend::Lu(lu) = &self.backend {
            self.solve_while_factorising = !lu.keeps_lower();
        }
        bounded
    }

    /// Solves `A x = b` and bounds the error of `x` (method.md section 8,
    /// [`SolveReport::error_bound`]), refining `x` while the bound exceeds
    /// the tolerance; a bound that stays above it is an error. On entry `x`
    /// is the starting point of an iterative solve (ignored by LU); on
    /// return it is the solution.
    ///
    /// Where double precision cannot prove the bound (or the residual),
    /// a system of at most [`SolverSettings::exact_limit`] unknowns is
    /// solved exactly ([`exact`]): `x` is then the exact solution rounded
    /// to the nearest doubles and the bound that rounding (method.md
    /// section 8).
    pub fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<SolveReport, SolverError> {
        let solved = self.solve_in_double(b, x);
        self.exactly_if_unprovable(solved, b, x)
    }

    /// [`Self::solve`] for a trial solution, one whose bound need not meet
    /// the tolerance (the policies that policy iteration passes through):
    /// double precision only, never the exact fallback. A bound above the
    /// tolerance is reported in [`SolveReport::error_bound`] instead of
    /// refused, infinite where even the residual is above the tolerance.
    /// The caller must not report such an `x` as a value.
    pub fn solve_trial(&mut self, b: &[f64], x: &mut [f64]) -> Result<SolveReport, SolverError> {
        let error_bound = match self.solve_in_double(b, x) {
            Err(SolverError::Unbounded { error_bound, .. }) => error_bound,
            Err(SolverError::Inaccurate { .. }) => f64::INFINITY,
            solved => return solved,
        };
        Ok(SolveReport {
            residual: self
                .pattern()
                .chain_residual(self.values(), &self.exits, x, b),
            iterations: 0,
            error_bound: Some(error_bound),
        })
    }

    /// One solve of `A x = b` to the residual tolerance, with no bound on
    /// the error of `x` (no expected times, no refinement): for a vector
    /// whose accuracy nothing relies on, such as the optimality
    /// certificate's potential, which its check proves or refuses
    /// whatever its errors. As by [`Self::solve_trial`], LU's residual
    /// above the tolerance is reported, not refused (BiCGSTAB that does not
    /// reach it is an error). The caller must not report such an `x` as a
    /// value.
    pub fn solve_unbounded(
        &mut self,
        b: &[f64],
        x: &mut [f64],
    ) -> Result<SolveReport, SolverError> {
        let probe_iterations = self.choose_by_trial(b, x, 1)?;
        let mut report = match self.solve_in(Direction::Forward, b, x, None) {
            // As for a trial: a residual above the tolerance is reported,
            // not refused.
            Err(SolverError::Inaccurate { residual, .. }) => SolveReport {
                residual,
                iterations: 0,
                error_bound: None,
            },
            solved => solved?,
        };
        report.iterations += probe_iterations;
        Ok(report)
    }

    /// The exact fallback of [`Self::solve`]: `solved` unless it is an
    /// error of a bound or residual that double precision cannot prove;
    /// then the exact solution, or [`SolverError::TooLargeForExact`].
    fn exactly_if_unprovable(
        &mut self,
        solved: Result<SolveReport, SolverError>,
        b: &[f64],
        x: &mut [f64],
    ) -> Result<SolveReport, SolverError> {
        let (error_bound, expected_time) = match &solved {
            Err(SolverError::Unbounded {
                error_bound,
                expected_time,
                ..
            }) => (*error_bound, *expected_time),
            Err(SolverError::Inaccurate { .. }) => (f64::INFINITY, self.expected_time.largest()),
            _ => return solved,
        };
        let n = self.pattern().n;
        let too_large = |refusal: String| SolverError::TooLargeForExact {
            error_bound,
            tolerance: self.tolerance,
            expected_time,
            unknowns: n,
            exact_limit: self.exact_limit,
            refusal,
        };
        if n > self.exact_limit {
            return Err(too_large(format!(
                "runs only on systems of at most {} unknowns, and this one has {n}",
                self.exact_limit
            )));
        }
        let budget = exact::ExactBudget::for_limit(self.exact_limit);
        let exact = exact::solve_exactly(self.pattern(), self.values(), &self.exits, b, &budget);
        match exact {
            Ok(solution) if solution.error_bound > self.tolerance => Err(SolverError::Unbounded {
                error_bound: solution.error_bound,
                tolerance: self.tolerance,
                expected_time,
            }),
            Ok(solution) => {
                x.copy_from_slice(&solution.x);
                if !self.reason.contains(EXACT_REASON) {
                    self.reason.push_str(EXACT_REASON);
                }
                Ok(SolveReport {
                    residual: self
                        .pattern()
                        .chain_residual(self.values(), &self.exits, x, b),
                    iterations: 0,
                    error_bound: Some(solution.error_bound),
                })
            }
            Err(exact::ExactRefusal::TooMuchFill { limit }) => Err(too_large(format!(
                "stopped on this system of {n} unknowns: its LU modulo a prime would hold more \
                 than its budget of {limit} entries ({} per unknown of the limit of {} unknowns)",
                exact::EXACT_ENTRIES_PER_UNKNOWN,
                self.exact_limit
            ))),
            Err(exact::ExactRefusal::TooMuchWork { limit, bits }) => Err(too_large(format!(
                "stopped on this system of {n} unknowns after its budget of {limit:e} units of \
                 work ({} per unknown of the limit of {} unknowns, about ten seconds), its \
                 numbers past {bits} bits without a solution",
                exact::EXACT_WORK_PER_UNKNOWN,
                self.exact_limit
            ))),
            Err(exact::ExactRefusal::Solver(error)) => Err(error),
        }
    }

    /// [`Self::solve`] in double precision only.
    fn solve_in_double(&mut self, b: &[f64], x: &mut [f64]) -> Result<SolveReport, SolverError> {
        let probe_iterations = self.choose_by_trial(b, x, 1)?;
        let (mut report, largest_time) = self.solve_with_expected_time(b, x)?;
        report.iterations += probe_iterations;
        self.bound_error(b, x, report, largest_time)
    }

    /// The forward solve of `A x = b`, with `max(t)` for the error bound
    /// if the previous estimate of `t` still certifies it. Otherwise, with
    /// LU, the expected times `A t = 1` are solved together with `x`,
    /// reading the factors once.
    fn solve_with_expected_time(
        &mut self,
        b: &[f64],
        x: &mut [f64],
    ) -> Result<(SolveReport, Option<f64>), SolverError> {
        let reused = self.reused_expected_time();
        let n = self.pattern().n;
        match &mut self.backend {
            Backend::Lu(lu) if n > 0 && reused.is_none() => {
                self.scratch.ones.resize(n, 1.0);
                let (value, time) = lu.solve_pair_within(
                    (b, x, self.tolerance),
                    (
                        &self.scratch.ones,
                        self.expected_time.estimate_mut(n),
                        EXPECTED_TIME_TOLERANCE,
                    ),
                );
                self.expected_time.store();
                let report = value?;
                unprovable(time, &self.expected_time, self.tolerance)?;
                Ok((report, Some(self.certified_expected_time()?)))
            }
            _ => Ok((self.solve_in(Direction::Forward, b, x, None)?, reused)),
        }
    }

    /// `max(t)` for `t = A^{-1} 1` (module [`bound`]) from a new estimate,
    /// solved for.
    fn solved_expected_time(&mut self) -> Result<f64, SolverError> {
        let n = self.pattern().n;
        self.scratch.ones.resize(n, 1.0);
        let ones = std::mem::take(&mut self.scratch.ones);
        let mut time = std::mem::take(&mut self.expected_time);
        let solved = self.solve_in(
            Direction::Forward,
            &ones,
            time.estimate_mut(n),
            Some(EXPECTED_TIME_TOLERANCE),
        );
        time.store();
        self.scratch.ones = ones;
        self.expected_time = time;
        unprovable(solved, &self.expected_time, self.tolerance)?;
        self.certified_expected_time()
    }

    /// `max(t)` certified by the previous estimate of `t`, if it still fits
    /// the matrix within [`bound::REUSE_LIMIT`].
    fn reused_expected_time(&self) -> Option<f64> {
        self.expected_time.certify(
            self.pattern(),
            self.values(),
            &self.exits,
            bound::REUSE_LIMIT,
        )
    }

    /// `max(t)` certified by an estimate of `t` just solved for.
    fn certified_expected_time(&self) -> Result<f64, SolverError> {
        certify_solved(
            &self.expected_time,
            self.pattern(),
            self.values(),
            &self.exits,
            self.tolerance,
        )
    }

    /// Adds the error bound to the report of a forward solve, refining `x`
    /// (iterative refinement with a compensated residual, each correction
    /// solved with the same factors) while the bound exceeds the tolerance.
    /// `largest_time` is `max(t)` (module [`bound`]) if the caller has it
    /// certified already, from an earlier estimate of `t` or one just solved
    /// for; otherwise `t` is solved for here.
    fn bound_error(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        mut report: SolveReport,
        largest_time: Option<f64>,
    ) -> Result<SolveReport, SolverError> {
        let n = self.pattern().n;
        if n == 0 {
            report.error_bound = Some(0.0);
            return Ok(report);
        }
        let largest_time = match largest_time {
            Some(largest) => largest,
            None => self.solved_expected_time()?,
        };
        let scale = largest_time * (1.0 + 4.0 * f64::EPSILON);
        let plain = bound::residual_bound(
            self.pattern(),
            self.values(),
            &self.exits,
            x,
            |i| b[i],
            bound::Evaluation::Plain,
            None,
        );
        let mut error_bound = scale * plain;
        if error_bound <= self.tolerance {
            report.error_bound = Some(error_bound);
            return Ok(report);
        }
        let mut residual = std::mem::take(&mut self.scratch.residual);
        let mut correction = std::mem::take(&mut self.scratch.correction);
        residual.resize(n, 0.0);
        correction.resize(n, 0.0);
        let mut outcome = self.refine(b, x, scale, &mut residual, &mut correction, &mut report);
        if matches!(outcome, Ok(bound) if bound > self.tolerance) {
            outcome =
                self.refine_extended(b, x, scale, &mut residual, &mut correction, &mut report);
        }
        self.scratch.residual = residual;
        self.scratch.correction = correction;
        error_bound = outcome?;
        if error_bound <= self.tolerance {
            report.error_bound = Some(error_bound);
            Ok(report)
        } else {
            Err(SolverError::Unbounded {
                error_bound,
                tolerance: self.tolerance,
                expected_time: largest_time,
            })
        }
    }

    /// Iterative refinement: at most [`bound::MAX_REFINEMENTS`] corrections
    /// `x <- x - A^{-1} r` (solved for `r / ||r||` and scaled back, so that
    /// an iterative method's absolute tolerance becomes a relative one),
    /// while the bound `scale * ||r||` exceeds the tolerance and halves per
    /// round. Returns the last bound.
    fn refine(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        scale: f64,
        residual: &mut [f64],
        correction: &mut [f64],
        report: &mut SolveReport,
    ) -> Result<f64, SolverError> {
        let mut previous = f64::INFINITY;
        for round in 0..=bound::MAX_REFINEMENTS {
            let bounded = bound::residual_bound(
                self.pattern(),
                self.values(),
                &self.exits,
                x,
                |i| b[i],
                bound::Evaluation::Compensated,
                Some(residual),
            );
            let error_bound = scale * bounded;
            report.residual = residual.iter().fold(0.0, |m: f64, r| m.max(r.abs()));
            let stalled = error_bound.is_nan() || error_bound >= 0.5 * previous;
            if error_bound <= self.tolerance || round == bound::MAX_REFINEMENTS || stalled {
                return Ok(error_bound);
            }
            previous = error_bound;
            let size = report.residual;
            if size == 0.0 || !size.is_finite() {
                return Ok(error_bound);
            }
            self.solve_correction(residual, size, correction, report)?;
            for (xi, di) in x.iter_mut().zip(correction.iter()) {
                *xi -= size * di;
            }
        }
        Ok(previous)
    }

    /// A refinement's correction: solves `A c = r / size` (so that an
    /// iterative method's absolute tolerance becomes a relative one) into
    /// `correction`, counting the iterations in `report`; `r = residual`,
    /// which is overwritten. The correction of the solution is `size * c`.
    fn solve_correction(
        &mut self,
        residual: &mut [f64],
        size: f64,
        correction: &mut [f64],
        report: &mut SolveReport,
    ) -> Result<(), SolverError> {
        residual.iter_mut().for_each(|r| *r /= size);
        correction.fill(0.0);
        report.iterations += self
            .solve_in(Direction::Forward, residual, correction, None)?
            .iterations;
        Ok(())
    }

    /// Iterative refinement in extended precision, for when refinement in
    /// double precision stalls above the tolerance because `x` itself,
    /// rounded to doubles, has a residual of rounding size that the
    /// expected time `scale` magnifies. The solution is carried as the
    /// double-double `y = x + low`; each round computes `y`'s residual
    /// by Dot2 ([`bound::residual_bound_of_sum`]) and subtracts the
    /// correction solved with the same factors, at most
    /// [`bound::MAX_EXTENDED_REFINEMENTS`] rounds while the bound halves.
    /// On return `x = fl(y)`, whose error is at most
    /// `scale * ||A y - b|| + max |y - x|` (the returned bound, rounded up).
    fn refine_extended(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        scale: f64,
        residual: &mut [f64],
        correction: &mut [f64],
        report: &mut SolveReport,
    ) -> Result<f64, SolverError> {
        let mut low = vec![0.0; x.len()];
        let mut previous = f64::INFINITY;
        for round in 0..=bound::MAX_EXTENDED_REFINEMENTS {
            let bounded = bound::residual_bound_of_sum(
                self.pattern(),
                self.values(),
                &self.exits,
                x,
                &low,
                |i| b[i],
                Some(residual),
            );
            let rounding = low.iter().fold(0.0, |m: f64, l| m.max(l.abs()));
            let error_bound = (scale * bounded + rounding) * (1.0 + 4.0 * f64::EPSILON);
            let stalled = error_bound.is_nan() || error_bound >= 0.5 * previous;
            let size = residual.iter().fold(0.0, |m: f64, r| m.max(r.abs()));
            let done = error_bound <= self.tolerance || stalled || size == 0.0;
            if done || round == bound::MAX_EXTENDED_REFINEMENTS || !size.is_finite() {
                report.residual = bound::residual_bound(
                    self.pattern(),
                    self.values(),
                    &self.exits,
                    x,
                    |i| b[i],
                    bound::Evaluation::Compensated,
                    None,
                );
                return Ok(error_bound);
            }
            previous = error_bound;
            self.solve_correction(residual, size, correction, report)?;
            for ((xi, li), di) in x.iter_mut().zip(low.iter_mut()).zip(correction.iter()) {
                let (sum, error) = bound::two_sum(*xi, -size * di);
                let (high, rest) = bound::two_sum(sum, *li + error);
                *xi = high;
                *li = rest;
            }
        }
        Ok(previous)
    }

    /// Solves `A^T y = c`, `y` as `x` in [`Self::solve`] (no error bound:
    /// for adjoint weights, which are directions, not reported numbers).
    pub fn solve_transpose(
        &mut self,
        c: &[f64],
        y: &mut [f64],
    ) -> Result<SolveReport, SolverError> {
        self.solve_in(Direction::Transposed, c, y, None)
    }

    /// One solve by the backend (residual `tolerance`, or the solver's own
    /// when `None`), with `auto`'s fall-back to LU.
    fn solve_in(
        &mut self,
        direction: Direction,
        rhs: &[f64],
        solution: &mut [f64],
        tolerance: Option<f64>,
    ) -> Result<SolveReport, SolverError> {
        let tolerance = tolerance.unwrap_or(self.tolerance);
        let result = match (&mut self.backend, direction) {
            (Backend::Lu(lu), Direction::Forward) => {
                return lu.solve_within(rhs, solution, tolerance);
            }
            (Backend::Lu(lu), Direction::Transposed) => return lu.solve_transpose(rhs, solution),
            (Backend::Krylov(krylov), Direction::Forward) => {
                krylov.solve_within(rhs, solution, tolerance)
            }
            (Backend::Krylov(krylov), Direction::Transposed) => {
                krylov.solve_transpose(rhs, solution)
            }
        };
        if self.should_fall_back(&result) {
            self.fall_back()?;
            return self.solve_in(direction, rhs, solution, Some(tolerance));
        }
        result
    }

    /// [`Self::solve`] and [`Self::solve_transpose`], at once on two threads
    /// from `PARALLEL_SOLVE_ROWS` unknowns
    /// (the two solves share the factorisation and nothing else); the
    /// forward solve's error is then bounded as by [`Self::solve`].
    pub fn solve_both(&mut self, b: &[f64], x: &mut [f64], c: &[f64], y: &mut [f64]) -> SolvePair {
        let probe_iterations = match self.choose_by_trial(b, x, 2) {
            Ok(iterations) => iterations,
            Err(error) => return (Err(error.clone()), Err(error)),
        };
        let (forward, transposed) = self.solve_both_unbounded(b, x, c, y);
        let forward = forward.and_then(|mut report| {
            report.iterations += probe_iterations;
            let largest_time = self.reused_expected_time();
            self.bound_error(b, x, report, largest_time)
        });
        (forward, transposed)
    }

    /// With `auto` on a BiCGSTAB system of at most
    /// [`SolverSettings::lu_switch_limit`] unknowns, before the first solve:
    /// a trial of [`PROBE_ITERATIONS`] BiCGSTAB iterations on `A x = b`, in
    /// two restarted halves, predicts the iterations of a whole solve from
    /// the rate at which the residual falls in the second half (the first
    /// removes the quickly damped error, whose fast fall would make the
    /// prediction optimistic); when the predicted iterations of all `solves` (one
    /// for the value, two with the adjoint) cost more than an LU
    /// ([`lu_cost_in_iterations`]), LU replaces BiCGSTAB at once, otherwise
    /// BiCGSTAB goes on from the trial's iterate. Returns the trial's
    /// iterations.
    fn choose_by_trial(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        solves: usize,
    ) -> Result<usize, SolverError> {
        if !std::mem::take(&mut self.probe_pending) {
            return Ok(0);
        }
        let Backend::Krylov(krylov) = &mut self.backend else {
            return Ok(0);
        };
        let half = (PROBE_ITERATIONS / 2).min(self.krylov_budget / 2).max(1);
        let first = krylov.probe(b, x, half)?;
        let probe = krylov.probe(b, x, half)?;
        let target = krylov::ACCURACY_MARGIN * self.tolerance;
        let predicted = probe.predicted_iterations(target);
        let (n, nnz) = (krylov.pattern().n, krylov.pattern().nnz());
        let lu_cost = self.lu_cost;
        let trial = format!(
            "{n} unknowns, {nnz} nonzeros: a trial of {} BiCGSTAB iterations reduced the \
             residual from {:.1e} to {:.1e} and the next {} to {:.1e}, predicting {} iterations \
             per solve to {target:.0e} ({solves} solve(s)) against an LU costing about \
             {lu_cost:.0} iterations",
            first.iterations,
            first.start_residual,
            first.residual,
            probe.iterations,
            probe.residual,
            if predicted.is_finite() {
                format!("{predicted:.0}")
            } else {
                "unbounded".into()
            }
        );
        if predicted * solves as f64 > lu_cost {
            self.reason = format!("auto: lu, {trial}");
            self.fall_back()?;
        } else {
            self.reason = format!("auto: krylov, {trial}");
        }
        Ok(first.iterations + probe.iterations)
    }

    fn solve_both_unbounded(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        c: &[f64],
        y: &mut [f64],
    ) -> SolvePair {
        let (forward, transposed) = match &mut self.backend {
            Backend::Lu(lu) => return lu.solve_both(b, x, c, y),
            Backend::Krylov(krylov) => krylov.solve_both(b, x, c, y),
        };
        if self.should_fall_back(&forward) || self.should_fall_back(&transposed) {
            return match self.fall_back() {
                Ok(()) => self.solve_both_unbounded(b, x, c, y),
                Err(error) => (Err(error.clone()), Err(error)),
            };
        }
        (forward, transposed)
    }

    /// With `auto`: whether BiCGSTAB failed or used its whole budget (then
    /// it stopped short of its accuracy target, though within the tolerance).
    fn should_fall_back(&self, result: &Result<SolveReport, SolverError>) -> bool {
        self.fall_back_to_lu
            && match result {
                Err(SolverError::NotConverged { .. }) => true,
                Ok(report) => report.iterations >= self.krylov_budget,
                Err(_) => false,
            }
    }

    /// Replaces BiCGSTAB by an LU of the matrix it last took, once and for
    /// all; where no LU can be built ([`SolverError::LuTooLarge`]),
    /// BiCGSTAB stays and the caller's solve goes on with it.
    fn fall_back(&mut self) -> Result<(), SolverError> {
        self.fall_back_to_lu = false;
        let Backend::Krylov(krylov) = &self.backend else {
            return Ok(());
        };
        let slow = format!(
            "BiCGSTAB did not converge within its budget of {} iterations (before: {})",
            self.krylov_budget, self.reason
        );
        let values = krylov.values().to_vec();
        let lu = match self.spare_lu.take() {
            Some(analysed) => analysed,
            None => match LuSolver::new(krylov.pattern().clone(), self.tolerance) {
                Ok(lu) => Box::new(lu),
                // No LU to fall back to: BiCGSTAB goes on from where it is,
                // with every iteration the settings allow.
                Err(SolverError::LuTooLarge { front, .. }) => {
                    if !self.reason.starts_with("auto: lu") {
                        self.reason = format!(
                            "auto: krylov, up to {} iterations: {slow}, and an LU needs a \
                             dense front of {front} x {front} entries, beyond 32-bit indices",
                            self.max_iterations
                        );
                    }
                    self.krylov_budget = self.max_iterations;
                    if let Backend::Krylov(krylov) = &mut self.backend {
                        krylov.allow_iterations(self.max_iterations);
                    }
                    return Ok(());
                }
                Err(error) => return Err(error),
            },
        };
        if !self.reason.starts_with("auto: lu") {
            self.reason = format!("auto: lu, {slow}");
        }
        // BiCGSTAB's memory is freed before the numeric LU needs its own.
        self.backend = Backend::Lu(lu);
        let exits = self.exits.clone();
        self.factorize_with(|own, own_exits| {
            own.copy_from_slice(&values);
            own_exits.copy_from_slice(&exits);
        })
    }
}

#[cfg(test)]
pub(crate) mod test_systems {
    use super::SparsePattern;

    /// A tridiagonal M-matrix: 1 on the diagonal, `-off` beside it.
    pub fn tridiagonal(n: usize, off: f64) -> (SparsePattern, Vec<f64>) {
        let mut row_offsets = vec![0];
        let mut columns = Vec::new();
        let mut values = Vec::new();
        for i in 0..n {
            for j in i.saturating_sub(1)..(i + 2).min(n) {
                columns.push(j);
                values.push(if i == j { 1.0 } else { -off });
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

    /// `I - Q` for the random walk on a `side x side` grid that moves to each
    /// of its four neighbours with probability 0.25 and leaves the system
    /// when it steps off the grid: slowly mixing, as the games' chains are.
    pub fn grid_walk(side: usize) -> (SparsePattern, Vec<f64>) {
        let mut row_offsets = vec![0];
        let mut columns = Vec::new();
        let mut values = Vec::new();
        for i in 0..side * side {
            let (x, y) = (i % side, i / side);
            let mut row = vec![(i, 1.0)];
            if y > 0 {
                row.push((i - side, -0.25));
            }
            if x > 0 {
                row.push((i - 1, -0.25));
            }
            if x + 1 < side {
                row.push((i + 1, -0.25));
            }
            if y + 1 < side {
                row.push((i + side, -0.25));
            }
            row.sort_by_key(|&(j, _)| j);
            for (j, v) in row {
                columns.push(j);
                values.push(v);
            }
            row_offsets.push(columns.len());
        }
        (
            SparsePattern {
                n: side * side,
                row_offsets,
                columns,
            },
            values,
        )
    }

    /// `I - Q` for a random substochastic `Q` on `n` states with about
    /// `per_row` successors per row and escape probability at least `escape`
    /// from each row (a deterministic pseudo-random generator keeps it
    /// reproducible).
    pub fn random_chain(
        n: usize,
        per_row: usize,
        escape: f64,
        seed: u64,
    ) -> (SparsePattern, Vec<f64>) {
        let mut state = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        let mut row_offsets = vec![0];
        let mut columns = Vec::new();
        let mut values = Vec::new();
        for i in 0..n {
            let mut successors: Vec<usize> = (0..per_row).map(|_| next() % n).collect();
            successors.push(i);
            successors.sort_unstable();
            successors.dedup();
            let weights: Vec<f64> = successors
                .iter()
                .map(|_| 1.0 + (next() % 100) as f64)
                .collect();
            let total: f64 = weights.iter().sum::<f64>() / (1.0 - escape);
            for (&j, w) in successors.iter().zip(&weights) {
                columns.push(j);
                values.push(f64::from(i == j) - w / total);
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
}

#[cfg(test)]
mod tests {
    use super::krylov::KrylovProbe;
    use super::test_systems::{random_chain, tridiagonal};
    use super::*;

    #[test]
    fn auto_chooses_by_size_and_explicit_choices_are_kept() {
        let settings = SolverSettings {
            lu_limit: 10,
            ..SolverSettings::default()
        };
        assert_eq!(settings.method_for(10), SolverMethod::Lu);
        assert_eq!(settings.method_for(11), SolverMethod::Krylov);
        for method in [SolverMethod::Lu, SolverMethod::Krylov] {
            let forced = SolverSettings { method, ..settings };
            assert_eq!(forced.method_for(5), method);
            assert_eq!(forced.method_for(500), method);
        }
    }

    /// An unbounded solve meets the residual tolerance with one solve
    /// (no refinement, no error bound) and lands near the bounded one.
    #[test]
    fn an_unbounded_solve_meets_the_residual_tolerance_without_a_bound() {
        let (pattern, values) = random_chain(300, 4, 0.05, 7);
        let ones = vec![1.0; 300];
        for method in [SolverMethod::Lu, SolverMethod::Krylov] {
            let settings = SolverSettings {
                method,
                ..SolverSettings::default()
            };
            let mut solver = LinearSolver::new(pattern.clone(), &settings).unwrap();
            solver.factorize(&values).unwrap();
            let mut rough = vec![0.0; 300];
            let report = solver.solve_unbounded(&ones, &mut rough).unwrap();
            assert_eq!(report.error_bound, None, "{method:?}");
            let residual = pattern.chain_residual(&values, solver.exits(), &rough, &ones);
            assert!(
                residual <= settings.tolerance,
                "{method:?}: residual {residual:e}"
            );
            let mut bounded = vec![0.0; 300];
            let proved = solver.solve(&ones, &mut bounded).unwrap();
            let largest = bounded.iter().copied().fold(0.0, f64::max);
            let apart = (0..300)
                .map(|i| (rough[i] - bounded[i]).abs())
                .fold(0.0, f64::max);
            // Within the residual times the expected times, plus the
            // bounded solve's own error.
            assert!(
                apart <= settings.tolerance * largest + proved.error_bound.unwrap(),
                "{method:?}: {apart:e} apart, times up to {largest}"
            );
        }
    }

    /// Where LU's residual is above a tolerance no double solve meets, the
    /// unbounded solve still returns its `x` with that residual (as a
    /// trial does), where a bounded solve refuses.
    #[test]
    fn an_unbounded_solve_reports_a_residual_above_the_tolerance() {
        let (pattern, values) = random_chain(300, 4, 0.05, 7);
        let ones = vec![1.0; 300];
        let settings = SolverSettings {
            method: SolverMethod::Lu,
            tolerance: 1e-300,
            exact_limit: 0,
            ..SolverSettings::default()
        };
        let mut solver = LinearSolver::new(pattern.clone(), &settings).unwrap();
        solver.factorize(&values).unwrap();
        let mut rough = vec![0.0; 300];
        let report = solver.solve_unbounded(&ones, &mut rough).unwrap();
        assert!(report.residual > settings.tolerance);
        assert_eq!(report.error_bound, None);
        let residual = pattern.chain_residual(&values, solver.exits(), &rough, &ones);
        assert_eq!(report.residual, residual);
        assert!(residual < 1e-9, "still a solve: residual {residual:e}");
        assert!(solver.solve(&ones, &mut vec![0.0; 300]).is_err());
    }

    #[test]
    fn both_methods_agree_on_random_chains() {
        for seed in 0..5 {
            let (pattern, values) = random_chain(300, 4, 0.05, seed);
            let b: Vec<f64> = (0..300).map(|i| (i % 7) as f64 / 7.0).collect();
            let mut solutions = Vec::new();
            for method in [SolverMethod::Lu, SolverMethod::Krylov] {
                let settings = SolverSettings {
                    method,
                    tolerance: 1e-12,
                    ..SolverSettings::default()
                };
                let mut solver = LinearSolver::new(pattern.clone(), &settings).unwrap();
                assert_eq!(solver.method(), method);
                solver.factorize(&values).unwrap();
                let mut x = vec![0.0; 300];
                let forward = solver.solve(&b, &mut x).unwrap();
                let mut y = vec![0.0; 300];
                let backward = solver.solve_transpose(&b, &mut y).unwrap();
                assert!(forward.residual <= 1e-12 && backward.residual <= 1e-12);
                // LU accepts by the residual without the diagonal,
                // BiCGSTAB converges on the plain one.
                let residual = match method {
                    SolverMethod::Lu => pattern.chain_residual(&values, solver.exits(), &x, &b),
                    _ => pattern.residual(&values, &x, &b),
                };
                assert_eq!(residual, forward.residual);
                let (mut x_both, mut y_both) = (vec![0.0; 300], vec![0.0; 300]);
                let (both_forward, both_backward) =
                    solver.solve_both(&b, &mut x_both, &b, &mut y_both);
                let both_forward = both_forward.unwrap();
                assert_eq!(
                    (both_forward.residual, both_forward.iterations),
                    (forward.residual, forward.iterations)
                );
                assert!(forward.error_bound.unwrap() <= 1e-12);
                assert!(both_forward.error_bound.unwrap() <= 1e-12);
                assert_eq!(both_backward.unwrap(), backward);
                assert_eq!((&x_both, &y_both), (&x, &y));
                solutions.push((x, y));
            }
            let (lu, krylov) = (&solutions[0], &solutions[1]);
            for i in 0..300 {
                assert!((lu.0[i] - krylov.0[i]).abs() < 1e-9, "x[{i}]");
                assert!((lu.1[i] - krylov.1[i]).abs() < 1e-9, "y[{i}]");
            }
        }
    }

    #[test]
    fn a_tolerance_that_accepts_everything_is_refused_by_both_methods() {
        for method in [SolverMethod::Lu, SolverMethod::Krylov] {
            for tolerance in [f64::NAN, f64::INFINITY, 0.0, -1.0] {
                let (pattern, _) = tridiagonal(3, 0.4);
                let settings = SolverSettings {
                    method,
                    tolerance,
                    ..SolverSettings::default()
                };
                assert!(matches!(
                    LinearSolver::new(pattern, &settings),
                    Err(SolverError::InvalidTolerance(_))
                ));
            }
        }
    }

    #[test]
    fn non_finite_values_are_rejected_by_both_methods() {
        for method in [SolverMethod::Lu, SolverMethod::Krylov] {
            let (pattern, mut values) = tridiagonal(4, 0.4);
            values[0] = f64::NAN;
            let settings = SolverSettings {
                method,
                ..SolverSettings::default()
            };
            let mut solver = LinearSolver::new(pattern, &settings).unwrap();
            assert_eq!(
                solver.factorize(&values),
                Err(SolverError::NonFinite("matrix entry"))
            );
        }
    }

    #[test]
    fn auto_repeats_a_failed_iterative_solve_by_lu_and_keeps_lu() {
        let (pattern, values) = random_chain(400, 5, 0.01, 4);
        let b = vec![1.0; 400];
        let hopeless = SolverSettings {
            lu_limit: 0,
            max_iterations: 1,
            tolerance: 1e-11,
            ..SolverSettings::default()
        };
        for method in [SolverMethod::Auto, SolverMethod::Krylov] {
            let settings = SolverSettings { method, ..hopeless };
            let mut solver = LinearSolver::new(pattern.clone(), &settings).unwrap();
            assert_eq!(solver.method(), SolverMethod::Krylov);
            solver.factorize(&values).unwrap();
            let mut x = vec![0.0; 400];
            let result = solver.solve(&b, &mut x);
            if method == SolverMethod::Auto {
                assert!(result.unwrap().residual <= 1e-11);
                assert_eq!(solver.method(), SolverMethod::Lu);
            } else {
                assert!(matches!(result, Err(SolverError::NotConverged { .. })));
                assert_eq!(solver.method(), SolverMethod::Krylov);
            }
        }
    }

    #[test]
    fn auto_gives_slow_solves_to_lu_only_below_the_switch_limit() {
        let (pattern, values) = test_systems::grid_walk(220);
        let b = vec![0.01; pattern.n];
        for (lu_switch_limit, switched) in [(pattern.n, true), (pattern.n - 1, false)] {
            let settings = SolverSettings {
                lu_limit: 0,
                lu_switch_limit,
                ..SolverSettings::default()
            };
            let mut solver = LinearSolver::new(pattern.clone(), &settings).unwrap();
            assert_eq!(solver.method(), SolverMethod::Krylov);
            solver.factorize(&values).unwrap();
            let mut x = vec![0.0; pattern.n];
            let report = solver.solve(&b, &mut x).unwrap();
            assert!(report.residual <= DEFAULT_TOLERANCE);
            if switched {
                assert_eq!(
                    (solver.method(), report.iterations),
                    (SolverMethod::Lu, PROBE_ITERATIONS)
                );
                assert!(
                    solver.reason().starts_with("auto: lu") && solver.reason().contains("trial"),
                    "{}",
                    solver.reason()
                );
            } else {
                assert_eq!(solver.method(), SolverMethod::Krylov);
                assert!(report.iterations > SLOW_KRYLOV_ITERATIONS, "{report:?}");
            }
        }
    }

    #[test]
    fn the_trial_predicts_from_the_mean_rate_per_iteration() {
        let probe = KrylovProbe {
            iterations: 10,
            start_residual: 1e-2,
            residual: 1e-4,
        };
        // Two decades per 10 iterations: 1e-2 -> 1e-12 is ten decades.
        assert!((probe.predicted_iterations(1e-12) - 50.0).abs() < 1e-9);
        assert_eq!(probe.predicted_iterations(1e-3), 10.0);
        assert_eq!(probe.predicted_iterations(1e-1), 0.0);
        let stalled = KrylovProbe {
            residual: 1e-2,
            ..probe
        };
        assert_eq!(stalled.predicted_iterations(1e-12), f64::INFINITY);
    }

    #[test]
    fn the_lu_cost_grows_with_the_entries_up_to_the_measured_break_even() {
        assert!((lu_cost_in_iterations(1_300_000) - 30.0).abs() < 1e-9);
        assert!(lu_cost_in_iterations(100_000) < lu_cost_in_iterations(1_300_000));
        assert_eq!(
            lu_cost_in_iterations(50_000_000),
            SLOW_KRYLOV_ITERATIONS as f64
        );
    }

    #[test]
    fn auto_keeps_krylov_on_a_fast_mixing_chain_and_says_why() {
        let (pattern, values) = random_chain(2000, 5, 0.3, 7);
        let b = vec![0.5; 2000];
        let settings = SolverSettings {
            lu_limit: 0,
            ..SolverSettings::default()
        };
        let mut solver = LinearSolver::new(pattern.clone(), &settings).unwrap();
        assert!(
            solver.reason().contains("a trial decides"),
            "{}",
            solver.reason()
        );
        solver.factorize(&values).unwrap();
        let mut x = vec![0.0; 2000];
        let report = solver.solve(&b, &mut x).unwrap();
        assert_eq!(solver.method(), SolverMethod::Krylov);
        assert!(
            solver.reason().starts_with("auto: krylov"),
            "{}",
            solver.reason()
        );
        assert!(report.error_bound.unwrap() <= DEFAULT_TOLERANCE);
        let mut lu = LinearSolver::new(
            pattern,
            &SolverSettings {
                method: SolverMethod::Lu,
                ..settings
            },
        )
        .unwrap();
        assert_eq!(lu.reason(), "lu as set");
        lu.factorize(&values).unwrap();
        let mut exact = vec![0.0; 2000];
        lu.solve(&b, &mut exact).unwrap();
        for (a, e) in x.iter().zip(&exact) {
            assert!((a - e).abs() <= 1e-9);
        }
    }

    #[test]
    fn below_the_lu_limit_auto_tries_krylov_only_where_the_analysed_lu_is_costly() {
        // A random chain fills its LU almost densely; a grid walk hardly.
        let (random, values) = random_chain(3000, 6, 0.3, 11);
        let (grid, _) = test_systems::grid_walk(60);
        let settings = SolverSettings::default();
        let mut solver = LinearSolver::new(random.clone(), &settings).unwrap();
        assert_eq!(solver.method(), SolverMethod::Krylov);
        assert!(
            solver.reason().contains("flops") && solver.reason().contains("a trial decides"),
            "{}",
            solver.reason()
        );
        let walk = LinearSolver::new(grid, &settings).unwrap();
        assert_eq!(walk.method(), SolverMethod::Lu, "{}", walk.reason());
        solver.factorize(&values).unwrap();
        let b = vec![0.5; random.n];
        let mut x = vec![0.0; random.n];
        let report = solver.solve(&b, &mut x).unwrap();
        assert_eq!(solver.method(), SolverMethod::Krylov, "{}", solver.reason());
        assert!(report.error_bound.unwrap() <= DEFAULT_TOLERANCE);
        let mut lu = LinearSolver::new(
            random,
            &SolverSettings {
                method: SolverMethod::Lu,
                ..settings
            },
        )
        .unwrap();
        lu.factorize(&values).unwrap();
        let mut exact = vec![0.0; b.len()];
        lu.solve(&b, &mut exact).unwrap();
        for (a, e) in x.iter().zip(&exact) {
            assert!((a - e).abs() <= 2.0 * DEFAULT_TOLERANCE, "{a} against {e}");
        }
    }

    #[test]
    fn a_slow_krylov_solve_below_the_lu_limit_falls_back_to_the_analysed_lu() {
        // Exits of 1e-3 per step, expected times of 1e3: BiCGSTAB does not
        // reach its target within its 5 iterations.
        let (pattern, values) = random_chain(3000, 6, 1e-3, 12);
        let settings = SolverSettings {
            max_iterations: 5,
            ..SolverSettings::default()
        };
        let mut solver = LinearSolver::new(pattern.clone(), &settings).unwrap();
        assert_eq!(solver.method(), SolverMethod::Krylov);
        solver.factorize(&values).unwrap();
        let b = vec![1.0; pattern.n];
        let mut x = vec![0.0; pattern.n];
        let report = solver.solve(&b, &mut x).unwrap();
        assert_eq!(solver.method(), SolverMethod::Lu, "{}", solver.reason());
        assert!(
            solver.reason().starts_with("auto: lu"),
            "{}",
            solver.reason()
        );
        assert!(report.error_bound.unwrap() <= DEFAULT_TOLERANCE);
        assert!(solver.spare_lu.is_none(), "the analysed LU was used");
    }

    #[test]
    fn the_lu_cost_from_flops_scales_with_the_flops_and_falls_with_the_entries() {
        let (small, _) = test_systems::tridiagonal(100, 0.4);
        let (large, _) = test_systems::tridiagonal(1000, 0.4);
        let cost = lu_iterations_from_flops(1e9, &small);
        assert!((lu_iterations_from_flops(2e9, &small) - 2.0 * cost).abs() < 1e-6 * cost);
        assert!(lu_iterations_from_flops(1e9, &large) < cost);
        // 298 entries and 100 unknowns: 8 * 298 + 12 * 100 flops per iteration.
        assert!((cost - 1e9 / (DENSE_SPEEDUP * 3584.0)).abs() < 1e-6 * cost);
    }

    #[test]
    fn factorising_and_solving_at_once_gives_the_two_steps_bit_for_bit() {
        // A fast chain; a slow walk whose plain bound (7e-11) exceeds 1e-11
        // and whose compensated residual meets it; the same walk at 1e-12,
        // which corrections of `x` (solves after the factorisation, so a
        // second factorisation keeping `L`) do not meet either: an error.
        // Each one twice: with nearby values the second time, where the
        // first expected times are reused. After a correction the solver
        // factorises keeping `L` from the start (whether the slightly
        // larger reused bound of the walk at 1e-11 needs one is not
        // checked).
        let chain = (random_chain(800, 3, 0.05, 3), 1e-9, Some(false));
        let walk = tridiagonal(400, 0.499);
        let compensated = (walk.clone(), 1e-11, None);
        let unbounded = (walk, 1e-12, Some(true));
        for ((pattern, values), tolerance, corrects) in [chain, compensated, unbounded] {
            let n = pattern.n;
            let b: Vec<f64> = (0..n).map(|i| (i % 5) as f64 / 9.0).collect();
            let settings = SolverSettings {
                method: SolverMethod::Lu,
                tolerance,
                ..SolverSettings::default()
            };
            let mut at_once = LinearSolver::new(pattern.clone(), &settings).unwrap();
            let mut two_steps = LinearSolver::new(pattern.clone(), &settings).unwrap();
            for scale in [1.0, 1.0 - 1e-6] {
                let scaled: Vec<f64> = values.iter().map(|v| v * scale).collect();
                let (mut x, mut x_two_steps) = (vec![0.0; n], vec![0.0; n]);
                let mut row_sums = vec![0.0; n];
                derive_exits(&pattern, &scaled, &mut row_sums);
                let fill = |own: &mut [f64], exits: &mut [f64]| {
                    own.copy_from_slice(&scaled);
                    exits.copy_from_slice(&row_sums);
                };
                let report = at_once.factorize_and_solve(fill, &b, &mut x);
                if let Some(corrects) = corrects {
                    assert_eq!(at_once.solve_while_factorising, !corrects);
                }
                two_steps
                    .factorize_with(|own, exits| {
                        own.copy_from_slice(&scaled);
                        exits.copy_from_slice(&row_sums);
                    })
                    .unwrap();
                assert_eq!(report, two_steps.solve(&b, &mut x_two_steps));
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&x), bits(&x_two_steps));
                let (mut y, mut y_two_steps) = (vec![0.0; n], vec![0.0; n]);
                let transposed = at_once.solve_transpose(&b, &mut y);
                assert_eq!(transposed, two_steps.solve_transpose(&b, &mut y_two_steps));
                assert_eq!(bits(&y), bits(&y_two_steps));
            }
        }
    }

    #[test]
    fn a_nan_residual_is_never_accepted() {
        assert!(nan_max(0.0, f64::NAN).is_nan());
        assert!(matches!(
            accept(f64::NAN, &[0.0], 1.0),
            Err(SolverError::Inaccurate { .. })
        ));
    }
}
