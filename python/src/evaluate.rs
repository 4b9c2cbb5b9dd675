//! `Game.evaluate`: the exact value of a controller pair and its adjoint
//! gradient (docs/method.md sections 1-2), as `posg-fsc eval` computes them
//! ([`posg_fsc::value::Evaluator`]).

use std::time::Instant;

use numpy::ndarray::{Array1, Array4};
use numpy::{IntoPyArray, PyArray1, PyArray4};
use posg_fsc::controller::{Fsc, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::ltl::props::Query as PropsQuery;
use posg_fsc::pipeline::{QueryValue, RewardObjective};
use posg_fsc::value::{
    EvaluationReport, Evaluator, Gradient, SolverMethod, SolverSettings, ValueError,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::controller::Controller;
use crate::errors::compute;
use crate::game::Game;
use crate::objective::{self, Asked};

/// The keyword options of `Game.evaluate`.
pub struct Options<'a> {
    pub gradient: bool,
    pub solver: &'a str,
    pub tolerance: Option<f64>,
    pub lu_limit: Option<usize>,
    pub allow_unused_propositions: bool,
}

/// The value of a controller pair (`Game.evaluate`), with the names of
/// `posg-fsc eval`'s JSON report; with `gradient=True` also `dV/d mu` of
/// both players as arrays shaped like the controllers' `probabilities`.
#[pyclass(module = "posg_fsc", name = "Evaluation", frozen, get_all)]
pub struct Evaluation {
    /// `V = P(trace |= phi)`, or the expected reward of a reward query
    /// (`inf` where the target is missed with positive probability).
    pub value: f64,
    /// With `props=`, the query restated in its own terms.
    pub query: Option<Query>,
    /// A bound on `|value - exact value|` (docs/method.md section 8).
    pub error_bound: f64,
    /// `max |(I - Q) x - b|` of the linear solve.
    pub residual: f64,
    /// The global Markov chain's explored states.
    pub gmc_states: usize,
    /// Its transitions.
    pub gmc_transitions: usize,
    /// Explored states whose automaton state decides the formula.
    pub decided_states: usize,
    /// Bottom strongly connected components (recurrence classes).
    pub bsccs: usize,
    /// The phi-feasible ones.
    pub feasible_bsccs: usize,
    /// Transient states (unknowns of the linear system).
    pub transient_states: usize,
    /// `lu` or `krylov`.
    pub solver: String,
    /// Why that solver was used.
    pub solver_reason: String,
    /// BiCGSTAB iterations (0 for LU).
    pub solver_iterations: usize,
    /// Wall-clock seconds (automaton, chain, analysis and solves).
    pub seconds: f64,
    /// `dV/d mu_def(g', u | g, o)` with axes `(node, observation,
    /// next_node, action)` (zero outside the support), with `gradient=True`.
    pub defender_gradient: Option<Py<PyArray4<f64>>>,
    /// `dV/d mu_adv(h', v | h, o')`, likewise.
    pub adversary_gradient: Option<Py<PyArray4<f64>>>,
    /// `dV/d init_def(g)`, shape `(nodes,)`, with `gradient=True`.
    pub defender_initial_gradient: Option<Py<PyArray1<f64>>>,
    /// `dV/d init_adv(h)`, shape `(nodes,)`, with `gradient=True`.
    pub adversary_initial_gradient: Option<Py<PyArray1<f64>>>,
}

/// A property file's query restated in its own terms (`eval`'s `query`):
/// for `Pmin=? [F "goal"]`, 1 - the value of its complement `G !goal`.
#[pyclass(module = "posg_fsc", name = "Query", frozen, get_all)]
#[derive(Clone)]
pub struct Query {
    /// The query as written.
    pub text: String,
    /// Its value (`inf` for an infinite expected reward).
    pub value: f64,
    /// A bound on `|value - exact value|` (docs/method.md section 8).
    pub error_bound: f64,
    /// For a solved query, `[lo, hi]` in the query's terms (for `Pmin`,
    /// `hi` is what the returned defender guarantees).
    pub certified: Option<[f64; 2]>,
    /// For a reward query, the probability of reaching its target.
    pub target_probability: Option<f64>,
}

impl From<QueryValue> for Query {
    fn from(query: QueryValue) -> Self {
        let QueryValue {
            text,
            value,
            error_bound,
            certified,
            target_probability,
        } = query;
        Self {
            text,
            value,
            error_bound,
            certified,
            target_probability,
        }
    }
}

#[pymethods]
impl Query {
    fn __repr__(&self) -> String {
        format!("Query(text={:?}, value={})", self.text, self.value)
    }
}

#[pymethods]
impl Evaluation {
    fn __repr__(&self) -> String {
        format!(
            "Evaluation(value={}, error_bound={:e}, gmc_states={})",
            self.value, self.error_bound, self.gmc_states
        )
    }
}

/// The solver settings of `solver`, `tolerance` and `lu_limit` (the
/// command line's `--solver`, `--tolerance`, `--lu-limit`).
pub fn solver_settings(
    solver: &str,
    tolerance: Option<f64>,
    lu_limit: Option<usize>,
) -> PyResult<SolverSettings> {
    let defaults = SolverSettings::default();
    let method: SolverMethod = solver
        .parse()
        .map_err(|e: String| PyValueError::new_err(format!("solver: {e}")))?;
    let tolerance = tolerance.unwrap_or(defaults.tolerance);
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(crate::errors::raise(
            crate::errors::Kind::Settings,
            format!("tolerance must be a finite number greater than 0, got {tolerance}"),
        ));
    }
    Ok(SolverSettings {
        method,
        tolerance,
        lu_limit: lu_limit.unwrap_or(defaults.lu_limit),
        ..defaults
    })
}

/// `Game.evaluate`.
pub fn evaluate(
    game: &Bound<'_, Game>,
    asked: Asked,
    defender: Option<&Bound<'_, PyAny>>,
    adversary: Option<&Bound<'_, PyAny>>,
    options: Options,
) -> PyResult<Evaluation> {
    let py = game.py();
    let clock = Instant::now();
    let posg = &game.get().inner;
    let settings = solver_settings(options.solver, options.tolerance, options.lu_limit)?;
    let defender = Controller::resolve("defender", defender, posg, Role::Defender)?;
    let adversary = Controller::resolve("adversary", adversary, posg, Role::Adversary)?;
    let allow = options.allow_unused_propositions;
    let pair = (&defender, &adversary);
    let gradient = options.gradient;
    let (report, gradient, query) = match &asked {
        Asked::Props(property) => match &property.query {
            PropsQuery::Reward(query) => {
                let objective = objective::reward(py, posg, query, property.maximise, allow)?;
                let (report, gradient, target_probability) = compute(py, || {
                    expected_reward(posg, &objective, pair, &settings, gradient)
                })?;
                let query = QueryValue::evaluated(property, &report.0, Some(target_probability));
                (report.1, gradient, Some(query))
            }
            PropsQuery::Probability { .. } => {
                let (evaluation, report, gradient) =
                    probability(py, posg, &asked, allow, pair, &settings, gradient)?;
                (
                    report,
                    gradient,
                    Some(QueryValue::evaluated(property, &evaluation, None)),
                )
            }
        },
        Asked::Ltl(_) => {
            let (_, report, gradient) =
                probability(py, posg, &asked, allow, pair, &settings, gradient)?;
            (report, gradient, None)
        }
    };
    let dense = |fsc, values: &[f64]| -> Py<PyArray4<f64>> {
        let array: Array4<f64> = Controller::dense(fsc, values);
        array.into_pyarray(py).unbind()
    };
    let vector = |values: &[f64]| Array1::from(values.to_vec()).into_pyarray(py).unbind();
    let g = gradient.as_ref();
    Ok(Evaluation {
        value: report.value,
        query: query.map(Query::from),
        error_bound: report.error_bound,
        residual: report.residual,
        gmc_states: report.gmc_states,
        gmc_transitions: report.gmc_transitions,
        decided_states: report.decided_states,
        bsccs: report.bsccs,
        feasible_bsccs: report.feasible_bsccs,
        transient_states: report.transient_states,
        solver: report.solver.to_string(),
        solver_reason: report.solver_reason,
        solver_iterations: report.solver_iterations,
        seconds: clock.elapsed().as_secs_f64(),
        defender_gradient: g.map(|g| dense(&defender, &g.defender)),
        adversary_gradient: g.map(|g| dense(&adversary, &g.adversary)),
        defender_initial_gradient: g.map(|g| vector(&g.defender_initial)),
        adversary_initial_gradient: g.map(|g| vector(&g.adversary_initial)),
    })
}

/// The value (and gradient) of the probability of the formula `asked`
/// names, as `eval` computes it.
fn probability(
    py: Python<'_>,
    posg: &Posg,
    asked: &Asked,
    allow_unused: bool,
    (defender, adversary): (&Fsc, &Fsc),
    settings: &SolverSettings,
    gradient: bool,
) -> PyResult<(
    posg_fsc::value::Evaluation,
    EvaluationReport,
    Option<Gradient>,
)> {
    let formula = asked.formula("Game.evaluate")?;
    let objective = objective::automata(py, posg, &formula, allow_unused, false)?;
    compute(py, || {
        let mut evaluator = Evaluator::new(
            posg,
            &objective.phi,
            &Support::of(defender),
            &Support::of(adversary),
            settings,
        )?;
        let (def, adv) = (
            Support::probabilities_of(defender),
            Support::probabilities_of(adversary),
        );
        let (evaluation, gradient) = if gradient {
            let (evaluation, gradient) = evaluator.evaluate_with_gradient(&def, &adv)?;
            (evaluation, Some(gradient))
        } else {
            (evaluator.evaluate(&def, &adv)?, None)
        };
        Ok::<_, ValueError>((evaluation, evaluator.report(&evaluation), gradient))
    })
}

/// The expected reward of `objective` (method.md section 9), its report,
/// the gradient when asked, and the probability of reaching the target
/// (computed where the reward is infinite, 1 otherwise).
#[allow(clippy::type_complexity)]
fn expected_reward(
    posg: &Posg,
    objective: &RewardObjective,
    (defender, adversary): (&Fsc, &Fsc),
    settings: &SolverSettings,
    gradient: bool,
) -> Result<
    (
        (posg_fsc::value::Evaluation, EvaluationReport),
        Option<Gradient>,
        f64,
    ),
    ValueError,
> {
    let (def_support, adv_support) = (Support::of(defender), Support::of(adversary));
    let (def, adv) = (
        Support::probabilities_of(defender),
        Support::probabilities_of(adversary),
    );
    let mut evaluator = Evaluator::for_expected_reward(
        posg,
        &objective.target,
        &objective.rewards,
        &def_support,
        &adv_support,
        settings,
    )?;
    let (evaluation, gradient) = if gradient {
        let (evaluation, gradient) = evaluator.evaluate_with_gradient(&def, &adv)?;
        (evaluation, Some(gradient))
    } else {
        (evaluator.evaluate(&def, &adv)?, None)
    };
    let target_probability = objective.target_probability(
        posg,
        &evaluator,
        (&def_support, &adv_support),
        (&def, &adv),
        settings,
    )?;
    let report = evaluator.report(&evaluation);
    Ok(((evaluation, report), gradient, target_probability))
}
