//! The single-player solver: `max over phi_def of V(phi_def)` when the
//! adversary cannot influence the game (it has one action), so max-min
//! reduces to max and no best-response check is needed.
//!
//! argmin's L-BFGS (`LBFGS::new(BacktrackingLineSearch::new(Armijo), m)`,
//! `m = lbfgs_memory`, Armijo constant `1e-4`, step halved on each
//! rejection) minimises `-ln V` (maximising `ln V` maximises `V`;
//! on long horizons, where `V` is a product of many probabilities, `ln V`
//! is far better scaled) in the unconstrained coordinates `z` of
//! `phi = c tanh(z)` with `c = logit_bound` ([`Reparametrisation`],
//! method.md section 3: every supported choice keeps probability at least
//! `exp(-2c) / |block|`, so the support never changes).
//!
//! The solver is stepped one L-BFGS iteration at a time
//! ([`Ascent::next_iter`]), so that a driver between iterations owns the
//! stopping rules and the observer. The line search's trial points are
//! guarded ([`LineGuard`]): a trial that moves some coordinate of `z` by
//! more than [`MAX_STEP`] is rejected unevaluated (a long step saturates
//! `tanh`, where the gradient vanishes and the ascent would stall far from
//! an optimum), and so is one whose linear system cannot be solved to the
//! tolerance (nearly deterministic choices can make `I - Q` nearly
//! singular); the search fails on a direction that does not ascend (where
//! the curvature pairs mislead) and after [`HALVINGS`] rejections. When
//! argmin's iteration fails or stops on its own tolerances, the memory is
//! cleared once and the iteration retried from the same point (a
//! steepest-ascent step); if that fails too, the point is stationary to
//! working precision.
//!
//! Requirements on the problem: `V` smooth in `phi` on the fixed support
//! (it is: a rational function without poles there). Reference: Nocedal
//! and Wright, Numerical Optimization (2006), algorithm 7.5.

use std::cell::{Cell, RefCell};
use std::time::Instant;

use argmin::core::{
    CostFunction, Error, Gradient, IterState, Problem, Solver, State, TerminationReason,
};
use argmin::solver::linesearch::BacktrackingLineSearch;
use argmin::solver::linesearch::condition::ArmijoCondition;
use argmin::solver::quasinewton::LBFGS;

use super::objective::{Objective, Point};
use super::observer::{IterationRecord, Observer};
use super::optimiser::{Incumbent, PhaseSeconds, RunOutcome, gained_little, norm};
use super::reparam::Reparametrisation;
use super::{Cancel, OptimiseError, Settings, Status};

/// argmin's L-BFGS on `Vec<f64>` with Armijo backtracking.
type Lbfgs = LBFGS<
    BacktrackingLineSearch<Vec<f64>, Vec<f64>, ArmijoCondition<f64>, f64>,
    Vec<f64>,
    Vec<f64>,
    f64,
>;

/// The largest change of any `z` coordinate in one trial step.
const MAX_STEP: f64 = 1.0;

/// Armijo's sufficient-decrease constant.
const ARMIJO: f64 = 1e-4;

/// Rejected trial points before a line search gives up.
const HALVINGS: usize = 30;

/// argmin's L-BFGS with memory `m` and the Armijo backtracking line search
/// (the step halves on each rejection).
fn lbfgs(memory: usize) -> Result<Lbfgs, OptimiseError> {
    let search = ArmijoCondition::new(ARMIJO)
        .and_then(|armijo| BacktrackingLineSearch::new(armijo).rho(0.5))
        .map_err(|error| OptimiseError::BestResponse(format!("L-BFGS ascent: {error}")))?;
    Ok(LBFGS::new(search, memory))
}

/// argmin's state of that solver: `z`, `-ln V` and its `z`-gradient.
type LbfgsState = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

/// The single-player L-BFGS ascent on the defender's logits with the
/// adversary fixed: argmin's solver, its state and the accepted point.
pub(super) struct Ascent {
    solver: Lbfgs,
    state: LbfgsState,
    memory: usize,
    map: Reparametrisation,
    adversary: Vec<f64>,
    /// The accepted point's `z` (argmin's state loses it when an iteration
    /// fails).
    z: Vec<f64>,
    /// Whether the memory was cleared and no iteration has succeeded since.
    fresh: bool,
}

/// Where an accepted iteration of the ascent ends.
pub(super) struct AscentStep {
    /// The defender's logits `phi = c tanh(z)`.
    pub defender: Vec<f64>,
    /// The value and gradients there.
    pub point: Point,
    /// The Euclidean length of the step in `z` (0 at the start).
    pub step: f64,
}

impl Ascent {
    /// The ascent from the defender's logits `start` against the adversary
    /// `adversary` (fixed), with memory `lbfgs_memory` and `c =
    /// logit_bound` from `settings`, and its starting point.
    pub fn init(
        objective: &mut Objective,
        start: &[f64],
        adversary: Vec<f64>,
        settings: &Settings,
    ) -> Result<(Self, AscentStep), OptimiseError> {
        let map = Reparametrisation::new(settings.logit_bound);
        let z = map.to_z(start);
        let mut ascent = Self {
            solver: lbfgs(settings.lbfgs_memory)?,
            state: IterState::new(),
            memory: settings.lbfgs_memory,
            map,
            adversary,
            z,
            fresh: true,
        };
        ascent.restart(objective)?;
        let step = ascent.accepted(objective, 0.0)?;
        Ok((ascent, step))
    }

    /// The logit bound `c`.
    pub fn bound(&self) -> f64 {
        self.map.bound()
    }

    /// One L-BFGS iteration that increases `V` (retried once with a cleared
    /// memory, see the module documentation); `None` when no step does (a
    /// stationary point to working precision).
    pub fn next_iter(
        &mut self,
        objective: &mut Objective,
    ) -> Result<Option<AscentStep>, OptimiseError> {
        if let Some(step) = self.iterate(objective)? {
            return Ok(Some(step));
        }
        if self.fresh {
            return Ok(None);
        }
        self.restart(objective)?;
        self.iterate(objective)
    }

    /// A fresh solver (empty memory) and state at the accepted point.
    fn restart(&mut self, objective: &mut Objective) -> Result<(), OptimiseError> {
        self.solver = lbfgs(self.memory)?;
        let mut problem = log_value(objective, &self.adversary, self.map, None);
        let started = self
            .solver
            .init(&mut problem, IterState::new().param(self.z.clone()));
        let failure = problem.problem.and_then(|p| p.failure.into_inner());
        self.state = started.map_err(|error| lost(error, failure))?.0;
        self.fresh = true;
        Ok(())
    }

    /// One iteration of argmin's solver, accepted when it ends at a higher
    /// value; `None` when the solver had stopped, failed or did not ascend.
    fn iterate(&mut self, objective: &mut Objective) -> Result<Option<AscentStep>, OptimiseError> {
        let stopped = <Lbfgs as Solver<LogValue<'_>, LbfgsState>>::terminate_internal(
            &mut self.solver,
            &self.state,
        );
        if self.state.terminated() || stopped.terminated() {
            return Ok(None);
        }
        let before = self.state.get_cost();
        let gradient = self.state.get_gradient().cloned().unwrap_or_default();
        let guard = LineGuard {
            anchor: self.z.clone(),
            gradient: gradient.clone(),
            trials: Cell::new(0),
        };
        let state = std::mem::replace(&mut self.state, IterState::new());
        let mut problem = log_value(objective, &self.adversary, self.map, Some(guard));
        let stepped = self.solver.next_iter(&mut problem, state);
        let failure = problem.problem.and_then(|p| p.failure.into_inner());
        let mut state = match (stepped, failure) {
            (Err(error), failure) => return Err(lost(error, failure)),
            (Ok(_), Some(error)) if !error.is_numerical() => return Err(error),
            (Ok((state, _)), _) => state,
        };
        let ascended = !state.terminated() && state.get_cost() < before;
        let next = state.get_param().cloned();
        match next {
            Some(z) if ascended => {
                state.update();
                state.increment_iter();
                let curved = positive_curvature(
                    (&z, &self.z),
                    (
                        state.get_gradient().map_or(&[][..], Vec::as_slice),
                        &gradient,
                    ),
                );
                self.state = state;
                let step = distance(&z, &self.z);
                self.z = z;
                self.fresh = false;
                if !curved {
                    self.restart(objective)?;
                }
                self.accepted(objective, step).map(Some)
            }
            _ => {
                self.state =
                    state.terminate_with(TerminationReason::SolverExit("no ascent".into()));
                Ok(None)
            }
        }
    }

    /// The accepted point's numbers (the objective's cache answers them).
    fn accepted(&self, objective: &mut Objective, step: f64) -> Result<AscentStep, OptimiseError> {
        let defender = self.map.to_phi(&self.z);
        let point = objective.point(&defender, &self.adversary)?;
        Ok(AscentStep {
            defender,
            point,
            step,
        })
    }
}

/// argmin's problem `z -> -ln V(c tanh(z), adversary)`, its trial points
/// guarded by `guard` during a line search.
fn log_value<'a>(
    objective: &'a mut Objective,
    adversary: &'a [f64],
    map: Reparametrisation,
    guard: Option<LineGuard>,
) -> Problem<LogValue<'a>> {
    Problem::new(LogValue {
        objective: RefCell::new(objective),
        adversary,
        map,
        guard,
        failure: RefCell::new(None),
    })
}

/// The guard of one line search from the accepted point `anchor`, where
/// the gradient of `-ln V` is `gradient`: it counts the trial points.
struct LineGuard {
    anchor: Vec<f64>,
    gradient: Vec<f64>,
    trials: Cell<usize>,
}

/// What the guard says about a trial point.
enum Trial {
    /// Evaluate it.
    Evaluate,
    /// Reject it unevaluated (too long a step): the search halves the step.
    Reject,
    /// End the search: the direction does not descend, or too many trials
    /// were rejected.
    Fail(&'static str),
}

impl LineGuard {
    fn judge(&self, z: &[f64]) -> Trial {
        let step: Vec<f64> = z.iter().zip(&self.anchor).map(|(a, b)| a - b).collect();
        if step.iter().all(|&d| d == 0.0) {
            return Trial::Evaluate;
        }
        let trials = self.trials.get() + 1;
        self.trials.set(trials);
        let slope: f64 = step.iter().zip(&self.gradient).map(|(d, g)| d * g).sum();
        if slope >= 0.0 {
            Trial::Fail("the L-BFGS direction does not ascend")
        } else if trials > HALVINGS {
            Trial::Fail("no step of the line search ascends enough")
        } else if step.iter().any(|d| d.abs() > MAX_STEP) {
            Trial::Reject
        } else {
            Trial::Evaluate
        }
    }
}

/// The error of a failed solver call: the objective's own when it failed,
/// else argmin's.
fn lost(error: Error, failure: Option<OptimiseError>) -> OptimiseError {
    failure.unwrap_or_else(|| OptimiseError::BestResponse(format!("L-BFGS ascent: {error}")))
}

/// Whether the step `s = z_next - z` and the gradient change
/// `y = g_next - g` have positive curvature `s . y > 1e-12 |s| |y|`: a pair
/// without it would make argmin's inverse Hessian estimate indefinite (a
/// Wolfe line search would exclude it; Armijo backtracking does not), so
/// the memory is cleared instead of keeping it.
fn positive_curvature((z_next, z): (&[f64], &[f64]), (g_next, g): (&[f64], &[f64])) -> bool {
    let s: Vec<f64> = z_next.iter().zip(z).map(|(a, b)| a - b).collect();
    let y: Vec<f64> = g_next.iter().zip(g).map(|(a, b)| a - b).collect();
    let curvature: f64 = s.iter().zip(&y).map(|(a, b)| a * b).sum();
    curvature > 1e-12 * norm(&s) * norm(&y) && curvature > 0.0
}

/// `|a - b|_2`.
fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// argmin's view of `z -> -ln V(c tanh(z), phi_adv)`; the first failure
/// of the objective is kept (argmin's errors lose its type).
struct LogValue<'a> {
    objective: RefCell<&'a mut Objective>,
    adversary: &'a [f64],
    map: Reparametrisation,
    guard: Option<LineGuard>,
    failure: RefCell<Option<OptimiseError>>,
}

impl LogValue<'_> {
    /// Whether the objective's failure is numerical trouble (which rejects
    /// a trial point); it is then forgotten.
    fn numerical_failure(&self) -> bool {
        let mut failure = self.failure.borrow_mut();
        let numerical = failure.as_ref().is_some_and(OptimiseError::is_numerical);
        if numerical {
            *failure = None;
        }
        numerical
    }

    fn point(&self, z: &[f64]) -> Result<Point, Error> {
        let phi = self.map.to_phi(z);
        match self.objective.borrow_mut().point(&phi, self.adversary) {
            Ok(point) => Ok(point),
            Err(error) => {
                let message = error.to_string();
                self.failure
                    .borrow_mut()
                    .get_or_insert(OptimiseError::Value(error));
                Err(Error::msg(message))
            }
        }
    }
}

impl CostFunction for LogValue<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    /// `-ln V`; `+inf` at a trial point the guard rejects or whose linear
    /// system cannot be solved to the tolerance (the search then halves
    /// the step).
    fn cost(&self, z: &Vec<f64>) -> Result<f64, Error> {
        match self.guard.as_ref().map_or(Trial::Evaluate, |g| g.judge(z)) {
            Trial::Evaluate => {}
            Trial::Reject => return Ok(f64::INFINITY),
            Trial::Fail(why) => return Err(Error::msg(why)),
        }
        match self.point(z) {
            Ok(point) => Ok(-point.value.max(f64::MIN_POSITIVE).ln()),
            Err(_) if self.guard.is_some() && self.numerical_failure() => Ok(f64::INFINITY),
            Err(error) => Err(error),
        }
    }
}

impl Gradient for LogValue<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    /// `-d ln V / dz = -(dV/dz) / V`.
    fn gradient(&self, z: &Vec<f64>) -> Result<Vec<f64>, Error> {
        let point = self.point(z)?;
        let value = point.value.max(f64::MIN_POSITIVE);
        Ok(self
            .map
            .chain_rule(z, &point.defender)
            .into_iter()
            .map(|d| -d / value)
            .collect())
    }
}

/// Maximises `V` (as `ln V`) over the defender's logits from `start`
/// (adversary fixed at `adversary`), reporting one record per iteration to
/// `observer`, stopping early once `cancel` is set.
pub fn ascend(
    objective: &mut Objective,
    (start, adversary): (&[f64], &[f64]),
    settings: &Settings,
    observer: &mut dyn Observer,
    cancel: &Cancel,
) -> Result<RunOutcome, OptimiseError> {
    let clock = Instant::now();
    let (mut ascent, mut here) = Ascent::init(objective, start, adversary.to_vec(), settings)?;
    let c = ascent.bound();
    let mut max_residual = here.point.residual;
    let mut history = vec![here.point.value];
    let mut best = (here.point.value, here.defender.clone(), 0);
    let window = settings.ascent_stall_iterations;
    let mut t = 0;
    let status = loop {
        let seconds = clock.elapsed().as_secs_f64();
        let mut status = if cancel.is_cancelled() {
            Some(Status::Cancelled)
        } else if t + 1 >= settings.max_iterations {
            Some(Status::MaxIterations)
        } else if settings.time_budget > 0.0 && seconds >= settings.time_budget {
            Some(Status::TimeBudget)
        } else if window > 0 && gained_little(&history, window, settings.stall_tolerance) {
            Some(Status::Stalled)
        } else {
            None
        };
        if status.is_none() {
            match ascent.next_iter(objective)? {
                Some(next) => {
                    here = next;
                    max_residual = max_residual.max(here.point.residual);
                }
                None => {
                    here.step = 0.0;
                    status = Some(Status::Converged);
                }
            }
        } else {
            here.step = 0.0;
        }
        let value = here.point.value;
        if value > best.0 {
            best = (value, here.defender.clone(), t + 1);
        }
        history.push(value);
        observer.observe(&IterationRecord {
            start: 0,
            iteration: t,
            seconds,
            value,
            defender_gradient_norm: norm(&here.point.defender),
            adversary_gradient_norm: 0.0,
            defender_step: here.step,
            adversary_step: 0.0,
            worst_case: Some(value),
            certified_lower: None,
            upper_bound: None,
            logit_bound: c,
        });
        if let Some(status) = status {
            break status;
        }
        t += 1;
    };
    let seconds = clock.elapsed().as_secs_f64();
    Ok(RunOutcome {
        best: Incumbent {
            defender: best.1,
            adversary: adversary.to_vec(),
            worst_case: best.0,
            certified_lower: None,
            iteration: best.2,
        },
        upper_bound: None,
        last_value: here.point.value,
        iterations: t + 1,
        checks: 0,
        status,
        seconds,
        phases: PhaseSeconds {
            optimisation: seconds,
            ..PhaseSeconds::default()
        },
        logit_bound: c,
        max_residual,
    })
}
