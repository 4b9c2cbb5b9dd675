//! The single-player fast path: `max over phi_def of V(phi_def)` when the
//! adversary cannot influence the game (it has one action), so max-min
//! reduces to max and no best-response check is needed.
//!
//! L-BFGS (two-loop recursion, memory `lbfgs_memory`) with a backtracking
//! Armijo line search, in the unconstrained coordinates `z` of
//! `phi = c tanh(z)` with `c = logit_bound` ([`Reparametrisation`],
//! method.md section 3: every supported choice keeps probability at least
//! `exp(-2c) / |block|`, so the support never changes). Each trial step moves no
//! coordinate of `z` by more than [`MAX_STEP`].
//!
//! Requirements on the problem: `V` smooth in `phi` on the fixed support
//! (it is: a rational function without poles there). Reference: Nocedal
//! and Wright, Numerical Optimization (2006), algorithms 7.4 and 3.1.

use std::collections::VecDeque;
use std::time::Instant;

use super::objective::Objective;
use super::observer::{IterationRecord, Observer};
use super::optimiser::{Incumbent, PhaseSeconds, RunOutcome, gained_little, norm};
use super::reparam::Reparametrisation;
use super::{Cancel, OptimiseError, Settings, Status};

/// The largest change of any `z` coordinate in one trial step.
const MAX_STEP: f64 = 1.0;

/// Armijo's sufficient-increase constant.
const ARMIJO: f64 = 1e-4;

/// Backtracking halvings before the line search gives up.
const HALVINGS: usize = 30;

/// A function of the defender's logits that the ascent maximises.
pub(super) trait DefenderObjective {
    /// The value at `defender`, its logit gradient and the larger residual
    /// of the linear solves behind them.
    fn point(&mut self, defender: &[f64]) -> Result<DefenderPoint, OptimiseError>;

    /// The work of the evaluations so far, in states solved (the unit of
    /// [`Settings::max_work`]).
    fn work(&self) -> f64;
}

/// A value of the defender's logits with its gradient.
pub(super) struct DefenderPoint {
    /// The value.
    pub value: f64,
    /// Its derivatives with respect to the defender's logits.
    pub gradient: Vec<f64>,
    /// The larger residual of the linear solves behind the two.
    pub residual: f64,
}

/// `V(phi_def, phi_adv)` with the adversary's logits fixed: what the
/// single-player ascent maximises.
pub(super) struct AgainstFixed<'a> {
    /// The value and its gradients.
    pub objective: &'a mut Objective,
    /// The adversary's logits.
    pub adversary: &'a [f64],
}

impl DefenderObjective for AgainstFixed<'_> {
    fn point(&mut self, defender: &[f64]) -> Result<DefenderPoint, OptimiseError> {
        let point = self.objective.point(defender, self.adversary)?;
        Ok(DefenderPoint {
            value: point.value,
            gradient: point.defender,
            residual: point.residual,
        })
    }

    fn work(&self) -> f64 {
        self.objective.work()
    }
}

/// Maximises the objective (as its logarithm) over the defender's logits
/// from `start`, reporting one record per iteration to `observer`,
/// stopping early once `cancel` is set, and at `max_iterations`, at a
/// positive `max_work` spent by this ascent, at the time budget or on a
/// stall; `adversary` is the adversary's logits recorded with the result.
pub(super) fn ascend(
    objective: &mut dyn DefenderObjective,
    (start, adversary): (&[f64], &[f64]),
    settings: &Settings,
    observer: &mut dyn Observer,
    cancel: &Cancel,
) -> Result<RunOutcome, OptimiseError> {
    let clock = Instant::now();
    let work_before = objective.work();
    let c = Reparametrisation::new(settings.logit_bound);
    let mut z = c.to_z(start);
    let mut here = Evaluated::at(objective, &z, c)?;
    let mut max_residual = here.residual;
    let mut memory = Memory::new(settings.lbfgs_memory);
    let mut history = vec![here.value];
    let mut best = (here.value, c.to_phi(&z), 0);
    let window = settings.ascent_stall_iterations;
    let mut t = 0;
    let status = loop {
        let seconds = clock.elapsed().as_secs_f64();
        let mut status = if cancel.is_cancelled() {
            Some(Status::Cancelled)
        } else if t + 1 >= settings.max_iterations {
            Some(Status::MaxIterations)
        } else if settings.max_work > 0.0 && objective.work() - work_before >= settings.max_work {
            Some(Status::WorkBudget)
        } else if settings.time_budget > 0.0 && seconds >= settings.time_budget {
            Some(Status::TimeBudget)
        } else if window > 0 && gained_little(&history, window, settings.stall_tolerance) {
            Some(Status::Stalled)
        } else {
            None
        };
        let step = if status.is_none() {
            match line_search(objective, &z, &here, &mut memory, c)? {
                Some((next_z, next, step)) => {
                    memory.remember(&next_z, &z, &next.ascent, &here.ascent);
                    z = next_z;
                    here = next;
                    max_residual = max_residual.max(here.residual);
                    step
                }
                None => {
                    status = Some(Status::Converged);
                    0.0
                }
            }
        } else {
            0.0
        };
        if here.value > best.0 {
            best = (here.value, c.to_phi(&z), t + 1);
        }
        history.push(here.value);
        observer.observe(&IterationRecord {
            start: 0,
            iteration: t,
            seconds,
            value: here.value,
            defender_gradient_norm: norm(&here.phi_gradient),
            adversary_gradient_norm: 0.0,
            defender_step: step,
            adversary_step: 0.0,
            worst_case: Some(here.value),
            certified_lower: None,
            upper_bound: None,
            logit_bound: c.bound(),
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
        last_value: here.value,
        iterations: t + 1,
        checks: 0,
        status,
        seconds,
        phases: PhaseSeconds {
            optimisation: seconds,
            ..PhaseSeconds::default()
        },
        logit_bound: c.bound(),
        max_residual,
        last_response: None,
    })
}

/// The value, the ascent objective `ln V` and its `z`-gradient at one point.
struct Evaluated {
    value: f64,
    /// `ln V` (maximising `ln V` maximises `V`; on long horizons, where `V`
    /// is a product of many probabilities, `ln V` is far better scaled).
    log_value: f64,
    /// `d ln V / dz = (dV/dz) / V`.
    ascent: Vec<f64>,
    /// `dV/dphi`.
    phi_gradient: Vec<f64>,
    residual: f64,
}

impl Evaluated {
    fn at(
        objective: &mut dyn DefenderObjective,
        z: &[f64],
        c: Reparametrisation,
    ) -> Result<Self, OptimiseError> {
        let point = objective.point(&c.to_phi(z))?;
        let value = point.value.max(f64::MIN_POSITIVE);
        let ascent = c
            .chain_rule(z, &point.gradient)
            .into_iter()
            .map(|d| d / value)
            .collect();
        Ok(Self {
            value: point.value,
            log_value: value.ln(),
            ascent,
            phi_gradient: point.gradient,
            residual: point.residual,
        })
    }
}

/// A step along the L-BFGS direction (steepest ascent when that is not an
/// ascent direction) with Armijo backtracking; `None` when no step of the
/// line search increases `V` enough (a stationary point to working
/// precision). A trial point whose linear system cannot be solved to the
/// tolerance (nearly deterministic choices can make `I - Q` nearly
/// singular) is rejected like one that does not increase `V`.
fn line_search(
    objective: &mut dyn DefenderObjective,
    z: &[f64],
    here: &Evaluated,
    memory: &mut Memory,
    c: Reparametrisation,
) -> Result<Option<(Vec<f64>, Evaluated, f64)>, OptimiseError> {
    let mut direction = memory.direction(&here.ascent);
    let mut slope = dot(&direction, &here.ascent);
    if slope <= 0.0 {
        memory.clear();
        direction.clone_from(&here.ascent);
        slope = dot(&direction, &here.ascent);
    }
    if slope <= 0.0 {
        return Ok(None);
    }
    let longest = direction.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let mut step = (MAX_STEP / longest).min(1.0);
    for _ in 0..HALVINGS {
        let trial: Vec<f64> = z
            .iter()
            .zip(&direction)
            .map(|(zi, d)| zi + step * d)
            .collect();
        match Evaluated::at(objective, &trial, c) {
            Ok(next) if next.log_value >= here.log_value + ARMIJO * step * slope => {
                return Ok(Some((trial, next, step)));
            }
            Ok(_) => {}
            Err(error) if error.is_numerical() => {}
            Err(error) => return Err(error),
        }
        step /= 2.0;
    }
    Ok(None)
}

/// The last `m` pairs `s = z_{k+1} - z_k`, `y = g_k - g_{k+1}` (`g` the
/// ascent gradient, so `y` is the gradient change of `-V`).
struct Memory {
    capacity: usize,
    pairs: VecDeque<(Vec<f64>, Vec<f64>, f64)>,
}

impl Memory {
    fn new(capacity: usize) -> Self {
        Self {
            capacity,
            pairs: VecDeque::with_capacity(capacity),
        }
    }

    fn clear(&mut self) {
        self.pairs.clear();
    }

    /// Stores the pair when it has positive curvature (`s . y > 0`).
    fn remember(&mut self, z_next: &[f64], z: &[f64], g_next: &[f64], g: &[f64]) {
        let s: Vec<f64> = z_next.iter().zip(z).map(|(a, b)| a - b).collect();
        let y: Vec<f64> = g.iter().zip(g_next).map(|(a, b)| a - b).collect();
        let curvature = dot(&s, &y);
        if curvature > 1e-12 * norm(&s) * norm(&y) && curvature > 0.0 {
            if self.pairs.len() == self.capacity {
                self.pairs.pop_front();
            }
            self.pairs.push_back((s, y, 1.0 / curvature));
        }
    }

    /// `H g` by the two-loop recursion, `H` the inverse Hessian estimate of
    /// `-V` scaled by `s.y / y.y` of the newest pair: an ascent direction of `V`.
    fn direction(&self, gradient: &[f64]) -> Vec<f64> {
        let mut q = gradient.to_vec();
        let mut alphas = Vec::with_capacity(self.pairs.len());
        for (s, y, rho) in self.pairs.iter().rev() {
            let alpha = rho * dot(s, &q);
            for (qi, yi) in q.iter_mut().zip(y) {
                *qi -= alpha * yi;
            }
            alphas.push(alpha);
        }
        if let Some((s, y, _)) = self.pairs.back() {
            let gamma = dot(s, y) / dot(y, y);
            for qi in &mut q {
                *qi *= gamma;
            }
        }
        for ((s, y, rho), alpha) in self.pairs.iter().zip(alphas.into_iter().rev()) {
            let beta = rho * dot(y, &q);
            for (qi, si) in q.iter_mut().zip(s) {
                *qi += (alpha - beta) * si;
            }
        }
        q
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
