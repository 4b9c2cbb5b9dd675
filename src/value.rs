//! The exact value of a controller pair and its gradient (method.md
//! sections 1 and 2).
//!
//! With `B`, `Z`, `T` from [`Recurrence`], `Q = P` restricted to
//! `T x T` and `b(m) = P(B | m)`:
//!
//! ```text
//! x = 1 on B,  x = 0 on Z,  (I - Q) x_T = b,        V = sum_m p0(m) x(m),
//! (I - Q)^T y = p0 restricted to T,
//! dV/dtheta = sum_{m in T} y(m) sum_m' dP(m'|m)/dtheta x(m') + sum_m dp0(m)/dtheta x(m).
//! ```
//!
//! [`Evaluator`] builds the GMC, its analysis and the solver's set-up (the
//! LU's symbolic factorisation, or the ILU(0) structure) once per support
//! structure; each evaluation then refills the numbers, factorises once and
//! solves once (value) or twice (value and gradient), followed by one pass
//! over the GMC for the gradient of all parameters of both players. The
//! vectors `b`, `x`, `p0` and `y` live in the evaluator: an evaluation
//! allocates nothing, and an iterative solver starts from the previous
//! evaluation's `x` and `y` (warm start). The gradient pass ([`GradientPass`])
//! and its buffers belong to the evaluator too.

mod gradient;
mod reward;

use thiserror::Error;

use crate::automaton::Dra;
use crate::controller::{Fsc, Probabilities, Support};
use crate::game::{Posg, RewardModel};
use crate::solver::LinearSolver;
pub(crate) use reward::RewardVector;

pub use crate::analysis::{Bscc, Recurrence, StateClass};
pub use crate::product::{Exploration, Gmc, GmcState, ProductError};
pub use crate::sensitivity::{ForwardGradient, ForwardSensitivities};
pub use crate::simulate::{
    CONFIDENCE, Estimate, EstimateReport, RewardEstimate, STEP_LIMIT, Simulated, SimulationCheck,
    SimulationError, SimulationSettings, simulate, simulate_and_check, simulate_reward,
};
pub use crate::solver::{
    DEFAULT_LU_LIMIT, DEFAULT_TOLERANCE, LuSolver, SolveReport, SolverError, SolverMethod,
    SolverSettings, SparsePattern, exact,
};
pub use gradient::{GradientPass, PARALLEL_GRADIENT_ROWS};
pub(crate) use gradient::{RowWorkspace, row_derivatives};

/// Why a value could not be computed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ValueError {
    /// The GMC could not be built.
    #[error(transparent)]
    Product(#[from] ProductError),
    /// The linear system could not be solved accurately.
    #[error(
        "solving the linear system of the value, (I - Q) x = b on the transient states (or its adjoint for the gradient): {0}"
    )]
    Solver(#[from] SolverError),
    /// The expected reward is infinite, so it has no gradient.
    #[error(
        "the expected reward is infinite: the target is missed with positive probability \
         (method.md section 9), so the value has no gradient"
    )]
    InfiniteReward,
}

/// The value `V` of a controller pair and the accuracy of its linear solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// `V = P(trace |= phi)`, or for an expected-reward objective the
    /// expected total reward until the target (method.md section 9),
    /// `f64::INFINITY` where the target is missed with positive probability.
    pub value: f64,
    /// `max_i |((I - Q) x - b)_i|` (0 when `T` is empty).
    pub residual: f64,
    /// BiCGSTAB iterations of the solve (0 for LU or when `T` is empty).
    pub iterations: usize,
    /// A bound on `|V - V_exact|` and on every `|x(m) - x_exact(m)|`, with
    /// `x_exact` the exact solution of the system as stored: `max(t)
    /// ||r||_inf` plus the rounding in computing `r` and `V` (method.md
    /// section 8). At most the solver's tolerance.
    pub error_bound: f64,
}

/// What every face reports of one evaluation (`eval`'s JSON, Python's
/// `Evaluation`; docs/formats.md section 8): the value, the GMC's size and
/// analysis (method.md section 1), the solver and the accuracy it proved
/// (method.md section 8). Made by [`Evaluator::report`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EvaluationReport {
    /// `V = P(trace |= phi)`, or the expected reward (method.md section 9;
    /// written `"inf"` in JSON where it is infinite).
    #[serde(serialize_with = "number_or_inf")]
    pub value: f64,
    /// The GMC's explored states (by default the exploration stops at the
    /// decided states).
    pub gmc_states: usize,
    /// Its transitions.
    pub gmc_transitions: usize,
    /// The explored states whose automaton state decides the formula
    /// (value 1 or 0 whatever follows): not expanded, and in no BSCC.
    pub decided_states: usize,
    /// Bottom strongly connected components (recurrence classes).
    pub bsccs: usize,
    /// The phi-feasible ones.
    pub feasible_bsccs: usize,
    /// Transient states: the unknowns of `(I - Q) x = b`.
    pub transient_states: usize,
    /// `lu` or `krylov`.
    pub solver: &'static str,
    /// Why `solver` was used: the setting, `auto`'s size limits, or its
    /// prediction from a short BiCGSTAB trial.
    pub solver_reason: String,
    /// `max_i |((I - Q) x - b)_i|`.
    pub residual: f64,
    /// A bound on `|value - exact value|` (method.md section 8).
    pub error_bound: f64,
    /// BiCGSTAB iterations (0 for LU).
    pub solver_iterations: usize,
}

/// A value as JSON: a number, or `"inf"`/`"-inf"` (as Storm prints them;
/// Python's `float()` reads them) where it is infinite, which JSON numbers
/// cannot say.
pub(crate) fn number_or_inf<S: serde::Serializer>(
    value: &f64,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    match *value {
        f64::INFINITY => serializer.serialize_str("inf"),
        f64::NEG_INFINITY => serializer.serialize_str("-inf"),
        finite => serializer.serialize_f64(finite),
    }
}

/// Partial derivatives of `V` with respect to every controller probability,
/// aligned with the players' [`Support`]s.
#[derive(Debug, Clone, PartialEq)]
pub struct Gradient {
    /// `dV/d mu_def(g', u | g, o)` per defender support entry.
    pub defender: Vec<f64>,
    /// `dV/d mu_adv(h', v | h, o')` per adversary support entry.
    pub adversary: Vec<f64>,
    /// `dV/d init_def(g)` per defender node.
    pub defender_initial: Vec<f64>,
    /// `dV/d init_adv(h)` per adversary node.
    pub adversary_initial: Vec<f64>,
    /// The residual of the adjoint solve `(I - Q)^T y = p0`.
    pub adjoint_residual: f64,
    /// BiCGSTAB iterations of the adjoint solve (0 for LU).
    pub adjoint_iterations: usize,
}

/// The linear system on `T`: the pattern of `I - Q` and where each entry's
/// number comes from in the GMC, `b`'s sources, and the vectors of both
/// solves (kept between evaluations as warm starts).
struct TransientSystem {
    solver: LinearSolver,
    sources: Vec<u32>,
    target_offsets: Vec<usize>,
    target_sources: Vec<u32>,
    /// Per row, the GMC entries that leave `T` (to `B` or `Z`): their sum
    /// is the row's exit, `(I - Q) 1`.
    exit_offsets: Vec<usize>,
    exit_sources: Vec<u32>,
    /// For an expected-reward objective, `b` is the one-step reward
    /// (method.md section 9) instead of `P(B | m)`.
    rewards: Option<RewardVector>,
    b: Vec<f64>,
    x: Vec<f64>,
    p0: Vec<f64>,
    y: Vec<f64>,
}

const NO_SOURCE: u32 = u32::MAX;

impl TransientSystem {
    fn build(
        gmc: &Gmc,
        recurrence: &Recurrence,
        rewards: Option<RewardVector>,
        settings: &SolverSettings,
    ) -> Result<Self, SolverError> {
        let n = recurrence.transient.len();
        let most_entries = n + recurrence
            .transient
            .iter()
            .map(|&m| gmc.row_range(m).len())
            .sum::<usize>();
        let mut row_offsets = Vec::with_capacity(n + 1);
        row_offsets.push(0);
        let mut columns = Vec::with_capacity(most_entries);
        let mut sources = Vec::with_capacity(most_entries);
        let mut target_offsets = Vec::with_capacity(n + 1);
        target_offsets.push(0);
        let mut target_sources = Vec::new();
        let mut exit_offsets = Vec::with_capacity(n + 1);
        exit_offsets.push(0);
        let mut exit_sources = Vec::new();
        for (i, &m) in recurrence.transient.iter().enumerate() {
            let row_start = columns.len();
            let (row_columns, _) = gmc.row(m);
            for (k, &c) in gmc.row_range(m).zip(row_columns) {
                match recurrence.classes[c as usize] {
                    StateClass::Transient => {
                        columns.push(recurrence.transient_index[c as usize] as usize);
                        sources.push(k as u32);
                    }
                    StateClass::Target | StateClass::Sure => {
                        target_sources.push(k as u32);
                        exit_sources.push(k as u32);
                    }
                    StateClass::Zero => exit_sources.push(k as u32),
                }
            }
            let entry = row_start + columns[row_start..].partition_point(|&c| c < i);
            if columns.get(entry) != Some(&i) {
                columns.insert(entry, i);
                sources.insert(entry, NO_SOURCE);
            }
            row_offsets.push(columns.len());
            target_offsets.push(target_sources.len());
            exit_offsets.push(exit_sources.len());
        }
        let solver = LinearSolver::new(
            SparsePattern {
                n,
                row_offsets,
                columns,
            },
            settings,
        )?;
        Ok(Self {
            solver,
            sources,
            target_offsets,
            target_sources,
            exit_offsets,
            exit_sources,
            rewards,
            b: vec![0.0; n],
            x: vec![0.0; n],
            p0: vec![0.0; n],
            y: vec![0.0; n],
        })
    }

    fn len(&self) -> usize {
        self.b.len()
    }

    /// Writes `I - Q` and `b` from the GMC's numbers and factorises. `I - Q`
    /// is given by its off-diagonal entries and its row sums, the
    /// probabilities of leaving `T` (to `B` or `Z`): these keep every digit
    /// when the chain leaves a block of states with probability `1e-13`,
    /// where any diagonal entry, `1 - P(m | m)` or a sum, keeps none of
    /// them (method.md section 8).
    fn factorize(
        &mut self,
        gmc: &Gmc,
        defender: &Probabilities,
        adversary: &Probabilities,
    ) -> Result<(), SolverError> {
        self.write_b(gmc, defender, adversary);
        let matrix = MatrixSources {
            sources: &self.sources,
            exit_offsets: &self.exit_offsets,
            exit_sources: &self.exit_sources,
        };
        self.solver
            .factorize_with(|values, exits| matrix.write(values, exits, gmc))
    }

    /// [`Self::factorize`] and the solve of `(I - Q) x = b` (from the
    /// previous `x`) for a system solved once
    /// ([`LinearSolver::factorize_and_solve`]: with LU, `L` is applied
    /// during the factorisation, not stored).
    fn factorize_and_solve_value(
        &mut self,
        gmc: &Gmc,
        defender: &Probabilities,
        adversary: &Probabilities,
    ) -> Result<SolveReport, SolverError> {
        if self.len() == 0 {
            self.factorize(gmc, defender, adversary)?;
            return Ok(NO_SOLVE);
        }
        self.write_b(gmc, defender, adversary);
        let matrix = MatrixSources {
            sources: &self.sources,
            exit_offsets: &self.exit_offsets,
            exit_sources: &self.exit_sources,
        };
        self.solver.factorize_and_solve(
            |values, exits| matrix.write(values, exits, gmc),
            &self.b,
            &mut self.x,
        )
    }

    /// `b(m) = sum_{m' in B} P(m' | m)` from the GMC's numbers, or for an
    /// expected-reward objective the one-step reward `r(m)` of the
    /// probabilities (method.md section 9).
    fn write_b(&mut self, gmc: &Gmc, defender: &Probabilities, adversary: &Probabilities) {
        if let Some(rewards) = &self.rewards {
            rewards.write(defender, adversary, &mut self.b);
            return;
        }
        let p = gmc.values();
        for (b, w) in self.b.iter_mut().zip(self.target_offsets.windows(2)) {
            *b = self.target_sources[w[0]..w[1]]
                .iter()
                .map(|&k| p[k as usize])
                .sum();
        }
    }

    /// Solves `(I - Q) x = b` and `(I - Q)^T y = p0` from the previous `x`
    /// and `y`, at once.
    fn solve_both(
        &mut self,
    ) -> (
        Result<SolveReport, SolverError>,
        Result<SolveReport, SolverError>,
    ) {
        if self.len() == 0 {
            return (Ok(NO_SOLVE), Ok(NO_SOLVE));
        }
        self.solver
            .solve_both(&self.b, &mut self.x, &self.p0, &mut self.y)
    }
}

/// The report of the solve of an empty system.
const NO_SOLVE: SolveReport = SolveReport {
    residual: 0.0,
    iterations: 0,
    error_bound: Some(0.0),
};

/// Where the numbers of `I - Q` on `T` come from in the GMC.
struct MatrixSources<'a> {
    sources: &'a [u32],
    exit_offsets: &'a [usize],
    exit_sources: &'a [u32],
}

impl MatrixSources<'_> {
    /// Writes `I - Q` on `T` from the GMC's numbers: `-P(c | m)` at each
    /// off-diagonal entry's `source`, and per row the probability of
    /// leaving `T`, `sum_{m' in B or Z} P(m' | m)`, from which the solver
    /// forms the diagonal (method.md section 8).
    fn write(&self, values: &mut [f64], exits: &mut [f64], gmc: &Gmc) {
        let p = gmc.values();
        for (value, &source) in values.iter_mut().zip(self.sources) {
            *value = if source == NO_SOURCE {
                0.0
            } else {
                -p[source as usize]
            };
        }
        for (exit, w) in exits.iter_mut().zip(self.exit_offsets.windows(2)) {
            *exit = self.exit_sources[w[0]..w[1]]
                .iter()
                .map(|&k| p[k as usize])
                .sum();
        }
    }
}

/// The evaluator for the supports of two controllers and the value of
/// their probabilities: the one-shot form of [`Evaluator::new`] followed by
/// [`Evaluator::evaluate`].
pub fn evaluate_controllers(
    game: &Posg,
    dra: &Dra,
    defender: &Fsc,
    adversary: &Fsc,
    settings: &SolverSettings,
) -> Result<(Evaluator, Evaluation), ValueError> {
    let mut evaluator = Evaluator::new(
        game,
        dra,
        &Support::of(defender),
        &Support::of(adversary),
        settings,
    )?;
    let evaluation = evaluator.evaluate(
        &Support::probabilities_of(defender),
        &Support::probabilities_of(adversary),
    )?;
    Ok((evaluator, evaluation))
}

/// Exact values and gradients for one support structure.
pub struct Evaluator {
    gmc: Gmc,
    recurrence: Recurrence,
    /// For an expected-reward objective: whether some state misses the
    /// target with positive probability, which makes the value infinite.
    infinite: bool,
    system: TransientSystem,
    values: Vec<f64>,
    adjoint: Vec<f64>,
    gradient_pass: GradientPass,
}

impl Evaluator {
    /// Builds the GMC under the supports up to its decided states
    /// ([`Exploration::UntilDecided`]), analyses its recurrence classes and
    /// prepares the solver of `I - Q` chosen by `settings`.
    pub fn new(
        game: &Posg,
        dra: &Dra,
        defender: &Support,
        adversary: &Support,
        settings: &SolverSettings,
    ) -> Result<Self, ValueError> {
        let exploration = Exploration::UntilDecided;
        Self::with_exploration(game, dra, defender, adversary, settings, exploration)
    }

    /// [`Evaluator::new`] on the GMC explored as far as `exploration` says:
    /// [`Exploration::Full`] keeps the recurrence classes that lie beyond
    /// the decided states (as `eval --explain` lists them); the value and
    /// the gradient are the same.
    pub fn with_exploration(
        game: &Posg,
        dra: &Dra,
        defender: &Support,
        adversary: &Support,
        settings: &SolverSettings,
        exploration: Exploration,
    ) -> Result<Self, ValueError> {
        let gmc = Gmc::build_with(game, dra, defender, adversary, exploration)?;
        let recurrence = Recurrence::analyse(&gmc, dra);
        let system = TransientSystem::build(&gmc, &recurrence, None, settings)?;
        let values = recurrence
            .classes
            .iter()
            .map(|&c| f64::from(matches!(c, StateClass::Target | StateClass::Sure)))
            .collect();
        Ok(Self::with_system(gmc, recurrence, false, system, values))
    }

    /// The evaluator of the expected total reward of `rewards` until the
    /// target `T` (method.md section 9), on the GMC built with `target`,
    /// the automaton of `F T` ([`crate::ltl::props::RewardQuery::reach_target`]),
    /// explored up to its decided states: `(I - Q) x = r` on the states
    /// that reach `T` with probability 1 ([`Recurrence::until_target`]),
    /// with the one-step reward `r(m)` as right-hand side. Where some state
    /// misses `T` with positive probability, the value is infinite. The
    /// solver's tolerance, made for values in [0, 1], is scaled by the
    /// largest step reward ([`RewardModel::largest_step_reward`], at least
    /// 1): the residual of a reward's solve grows with its right-hand side.
    pub fn for_expected_reward(
        game: &Posg,
        target: &Dra,
        rewards: &RewardModel,
        defender: &Support,
        adversary: &Support,
        settings: &SolverSettings,
    ) -> Result<Self, ValueError> {
        let gmc = Gmc::build_with(game, target, defender, adversary, Exploration::UntilDecided)?;
        let recurrence = Recurrence::until_target(&gmc, target);
        let reward = RewardVector::new(
            game,
            &gmc,
            &recurrence.transient,
            rewards,
            defender,
            adversary,
        );
        let scaled = SolverSettings {
            tolerance: settings.tolerance * rewards.largest_step_reward().max(1.0),
            ..*settings
        };
        let system = TransientSystem::build(&gmc, &recurrence, Some(reward), &scaled)?;
        let values = recurrence
            .classes
            .iter()
            .map(|&c| match c {
                StateClass::Zero => f64::INFINITY,
                _ => 0.0,
            })
            .collect();
        let infinite = recurrence.classes.contains(&StateClass::Zero);
        Ok(Self::with_system(gmc, recurrence, infinite, system, values))
    }

    fn with_system(
        gmc: Gmc,
        recurrence: Recurrence,
        infinite: bool,
        system: TransientSystem,
        values: Vec<f64>,
    ) -> Self {
        let adjoint = vec![0.0; gmc.num_states()];
        Self {
            gmc,
            recurrence,
            infinite,
            system,
            values,
            adjoint,
            gradient_pass: GradientPass::new(),
        }
    }

    /// For an expected-reward objective, whether the value is infinite
    /// (the target is missed with positive probability: method.md section
    /// 9); decided by the supports alone. `false` for a probability.
    pub fn is_infinite(&self) -> bool {
        self.infinite
    }

    /// The GMC (numbers as of the last evaluation).
    pub fn gmc(&self) -> &Gmc {
        &self.gmc
    }

    /// The recurrence classes and the partition `B`, `Z`, `T`.
    pub fn recurrence(&self) -> &Recurrence {
        &self.recurrence
    }

    /// The method solving `(I - Q) x = b` ([`SolverMethod::Lu`] or
    /// [`SolverMethod::Krylov`]).
    pub fn solver_method(&self) -> SolverMethod {
        self.system.solver.method()
    }

    /// Why [`Self::solver_method`] is in use: the setting, or `auto`'s size
    /// limits, or its switch to LU after a slow BiCGSTAB solve.
    pub fn solver_reason(&self) -> &str {
        self.system.solver.reason()
    }

    /// The report of `evaluation`, this evaluator's last.
    pub fn report(&self, evaluation: &Evaluation) -> EvaluationReport {
        let recurrence = self.recurrence();
        EvaluationReport {
            value: evaluation.value,
            gmc_states: self.gmc.num_states(),
            gmc_transitions: self.gmc.num_transitions(),
            decided_states: self.gmc.num_decided(),
            bsccs: recurrence.bsccs.len(),
            feasible_bsccs: recurrence.feasible().count(),
            transient_states: recurrence.transient.len(),
            solver: self.solver_method().name(),
            solver_reason: self.solver_reason().to_string(),
            residual: evaluation.residual,
            error_bound: evaluation.error_bound,
            solver_iterations: evaluation.iterations,
        }
    }

    /// The pattern of `I - Q` on `T` and its numbers as of the last evaluation.
    pub fn system(&self) -> (&SparsePattern, &[f64]) {
        (self.system.solver.pattern(), self.system.solver.values())
    }

    /// The row sums `(I - Q) 1` on `T` as of the last evaluation: the
    /// probabilities of leaving `T`, which define the diagonal of
    /// [`Self::system`] (method.md section 8).
    pub fn exits(&self) -> &[f64] {
        self.system.solver.exits()
    }

    /// Frees the solver's factors until the next evaluation
    /// ([`LinearSolver::release`]): for an evaluator idle for a while (a
    /// start of a race between its rounds), whose next evaluation
    /// factorises anyway.
    pub fn release(&mut self) {
        self.system.solver.release();
    }

    /// `x(m)`, the probability of phi from each GMC state, as of the last evaluation.
    pub fn state_values(&self) -> &[f64] {
        &self.values
    }

    /// The value `V` for the given probabilities: one factorisation, with
    /// the solve done during it (docs/method.md section 1; a correction of
    /// the solution for its error bound factorises again).
    pub fn evaluate(
        &mut self,
        defender: &Probabilities,
        adversary: &Probabilities,
    ) -> Result<Evaluation, ValueError> {
        self.gmc.refill(defender, adversary);
        let report = self
            .system
            .factorize_and_solve_value(&self.gmc, defender, adversary)?;
        Ok(self.store_values(report))
    }

    /// Writes the GMC's numbers for the probabilities, then `I - Q` and `b`,
    /// and factorises.
    fn refill_and_factorize(
        &mut self,
        defender: &Probabilities,
        adversary: &Probabilities,
    ) -> Result<(), SolverError> {
        self.gmc.refill(defender, adversary);
        self.system.factorize(&self.gmc, defender, adversary)
    }

    /// Copies `x` from `T` into the state values and computes `V`; its
    /// error bound adds the rounding of the sum `sum_m p0(m) x(m)` (at most
    /// `gamma_k sum_m p0(m) |x(m)|` for `k` initial states) to the solve's.
    /// An infinite expected reward is exact (its error bound is 0).
    fn store_values(&mut self, report: SolveReport) -> Evaluation {
        for (&m, &xm) in self.recurrence.transient.iter().zip(&self.system.x) {
            self.values[m] = xm;
        }
        let value: f64 = self.gmc.initial().map(|(m, p)| p * self.values[m]).sum();
        if value.is_infinite() {
            return Evaluation {
                value,
                residual: report.residual,
                iterations: report.iterations,
                error_bound: 0.0,
            };
        }
        let terms = self.gmc.initial().count() as f64;
        let magnitude: f64 = self
            .gmc
            .initial()
            .map(|(m, p)| p * self.values[m].abs())
            .sum();
        let rounding = 2.0 * terms * f64::EPSILON * magnitude;
        Evaluation {
            value,
            residual: report.residual,
            iterations: report.iterations,
            error_bound: report.error_bound.unwrap_or(f64::INFINITY) + rounding,
        }
    }

    /// The value and its gradient with respect to every probability of both
    /// controllers (adjoint method: one factorisation, two solves, at once
    /// on two threads from `PARALLEL_SOLVE_ROWS` unknowns, and one pass over
    /// the GMC).
    pub fn evaluate_with_gradient(
        &mut self,
        defender: &Probabilities,
        adversary: &Probabilities,
    ) -> Result<(Evaluation, Gradient), ValueError> {
        if self.infinite {
            return Err(ValueError::InfiniteReward);
        }
        self.refill_and_factorize(defender, adversary)?;
        self.system.p0.fill(0.0);
        for (m, p) in self.gmc.initial() {
            let i = self.recurrence.transient_index[m];
            if i != u32::MAX {
                self.system.p0[i as usize] += p;
            }
        }
        let (value_report, adjoint_report) = self.system.solve_both();
        let evaluation = self.store_values(value_report?);
        let report = adjoint_report?;
        for (&m, &ym) in self.recurrence.transient.iter().zip(&self.system.y) {
            self.adjoint[m] = ym;
        }
        let mut gradient = Gradient {
            defender: vec![0.0; defender.entries.len()],
            adversary: vec![0.0; adversary.entries.len()],
            defender_initial: vec![0.0; defender.initial.len()],
            adversary_initial: vec![0.0; adversary.initial.len()],
            adjoint_residual: report.residual,
            adjoint_iterations: report.iterations,
        };
        self.gradient_pass.add_adjoint_gradient(
            &self.gmc,
            &self.values,
            &self.adjoint,
            &mut gradient.defender,
            &mut gradient.adversary,
        );
        if let Some(rewards) = &self.system.rewards {
            rewards.add_gradient(
                &self.system.y,
                defender,
                adversary,
                &mut gradient.defender,
                &mut gradient.adversary,
            );
        }
        gradient::add_initial_gradient(
            &self.gmc,
            &self.values,
            defender,
            adversary,
            &mut gradient.defender_initial,
            &mut gradient.adversary_initial,
        );
        Ok((evaluation, gradient))
    }
}
