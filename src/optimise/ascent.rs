//! The single-player solver: L-BFGS ascent on `ln V` over the defender's
//! logits, for games where the adversary cannot influence the game (it
//! has one action): max-min reduces to max, and a check's best response is
//! the value itself. [`Ascent`] runs under the same driver as gradient play
//! ([`super::Optimiser`]: the same stopping rules, checks and observers);
//! the guarantee ascent (`guarantee.rs`) takes the same steps
//! ([`Lbfgs`]) on the certified lower bound.
//!
//! L-BFGS (two-loop recursion, memory `lbfgs_memory`) with a backtracking
//! Armijo line search, in the unconstrained coordinates `z` of
//! `phi = c tanh(z)` with `c = logit_bound` ([`Reparametrisation`],
//! method.md section 3: every supported choice keeps probability at least
//! `exp(-2c) / |block|`, so the support never changes). Each trial step
//! moves no coordinate of `z` by more than [`MAX_STEP`], and a trial point
//! whose linear system cannot be solved to the tolerance is rejected like
//! one that does not increase `V` (argmin's L-BFGS, which the best
//! responses use, has neither: its line searches take the first step along
//! the unscaled gradient and stop at the first error).
//!
//! Requirements on the problem: `V` smooth in `phi` on the fixed support
//! (it is: a rational function without poles there). Reference: Nocedal
//! and Wright, Numerical Optimization (2006), algorithms 7.4 and 3.1.

use std::collections::VecDeque;

use super::objective::{Objective, Point};
use super::reparam::Reparametrisation;
use super::solver::{Iterate, PlayState, Solver, norm};
use super::{OptimiseError, Settings};

/// The largest change of any `z` coordinate in one trial step.
const MAX_STEP: f64 = 1.0;

/// A step that gains at most this fraction of `V` gains nothing that a
/// reported digit shows (argmin's `tol_cost`, relative).
const NEGLIGIBLE_GAIN: f64 = 1e-12;

/// The single-player solver has converged after this many consecutive
/// negligible steps (where the line search still finds one: logits
/// creeping towards a face of the box); or, at a stationary point, once
/// this many steps together gained at most the solver's tolerance times
/// `V`, below what the values resolve.
const NEGLIGIBLE_STEPS: usize = 10;

/// A point where `|dV/dphi|` is at most this fraction of `V` is
/// stationary: on PRISM's grid-avoid-4-0.1 the ascent reaches 5e-8 and
/// then creeps by 1e-11 per step for a hundred steps; a slow ascent far
/// from one (pomdp-grid10 with 3 nodes, 4e-3, gaining 1e-10 per step)
/// may still speed up.
const STATIONARY_GRADIENT: f64 = 1e-6;

/// Armijo's sufficient-increase constant.
const ARMIJO: f64 = 1e-4;

/// Backtracking halvings before the line search gives up.
const HALVINGS: usize = 30;

/// A function of the defender's logits that the ascent maximises.
pub(super) trait DefenderObjective {
    /// The value at `defender`, its logit gradient and the larger residual
    /// of the linear solves behind them.
    fn point(&mut self, defender: &[f64]) -> Result<DefenderPoint, OptimiseError>;

    /// Whether the ascent climbs `ln V` (a positive value such as a
    /// probability, far better scaled in its logarithm) rather than `V`
    /// itself (an expected reward, of either sign).
    fn logarithmic(&self) -> bool {
        true
    }
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
/// single-player solver maximises.
struct AgainstFixed<'a> {
    objective: &'a mut Objective,
    adversary: &'a [f64],
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

    fn logarithmic(&self) -> bool {
        self.objective.is_probability()
    }
}

/// The L-BFGS ascent's state: the point `z` it is at, its value there and
/// the curvature pairs it remembers.
pub(super) struct Lbfgs {
    map: Reparametrisation,
    z: Vec<f64>,
    here: Evaluated,
    memory: Memory,
}

impl Lbfgs {
    /// The ascent of `objective` from the logits `start`, in the
    /// coordinates of the logit bound `bound`, remembering
    /// `settings.lbfgs_memory` pairs.
    pub fn start(
        objective: &mut dyn DefenderObjective,
        start: &[f64],
        bound: f64,
        settings: &Settings,
    ) -> Result<Self, OptimiseError> {
        let map = Reparametrisation::new(bound);
        let z = map.to_z(start);
        let here = Evaluated::at(objective, &z, map)?;
        Ok(Self {
            map,
            z,
            here,
            memory: Memory::new(settings.lbfgs_memory),
        })
    }

    /// One step of the line search along the L-BFGS direction: the step
    /// length taken, `None` at a stationary point to working precision
    /// (then the ascent stays where it is).
    pub fn step(
        &mut self,
        objective: &mut dyn DefenderObjective,
    ) -> Result<Option<f64>, OptimiseError> {
        let Some((z, next, step)) =
            line_search(objective, &self.z, &self.here, &mut self.memory, self.map)?
        else {
            return Ok(None);
        };
        self.memory
            .remember(&z, &self.z, &next.ascent, &self.here.ascent);
        self.z = z;
        self.here = next;
        Ok(Some(step))
    }

    /// The value where the ascent is.
    pub fn value(&self) -> f64 {
        self.here.value
    }

    /// The logits `phi = c tanh(z)` where the ascent is.
    pub fn logits(&self) -> Vec<f64> {
        self.map.to_phi(&self.z)
    }

    /// `dV/dphi` where the ascent is.
    fn gradient(&self) -> &[f64] {
        &self.here.phi_gradient
    }

    /// The larger residual of the linear solves behind the last point.
    fn residual(&self) -> f64 {
        self.here.residual
    }
}

/// The single-player solver under the driver: each iteration is one L-BFGS
/// step of the defender on `V` against the adversary's fixed logits; once
/// no step increases `V`, or [`NEGLIGIBLE_STEPS`] consecutive steps each
/// gained at most [`NEGLIGIBLE_GAIN`] of it, or, at a stationary point
/// ([`STATIONARY_GRADIENT`]), together at most `solver_tolerance` of it,
/// the solver has converged ([`super::Status::Converged`]).
pub(super) struct Ascent {
    settings: Settings,
    lbfgs: Option<Lbfgs>,
    last_step: f64,
    /// `V` after each of the last [`NEGLIGIBLE_STEPS`] steps, and before
    /// the first of them: the window both convergence rules judge.
    recent_values: VecDeque<f64>,
    converged: bool,
}

impl Ascent {
    /// The solver with the L-BFGS memory of `settings`.
    pub fn new(settings: &Settings) -> Self {
        Self {
            settings: settings.clone(),
            lbfgs: None,
            last_step: 0.0,
            recent_values: VecDeque::with_capacity(NEGLIGIBLE_STEPS + 1),
            converged: false,
        }
    }

    /// Records `value`, reached by a step, in `recent_values`; whether the
    /// last [`NEGLIGIBLE_STEPS`] steps together gained at most `tolerance`
    /// times it.
    fn gained_little(recent_values: &mut VecDeque<f64>, value: f64, tolerance: f64) -> bool {
        if recent_values.len() > NEGLIGIBLE_STEPS {
            recent_values.pop_front();
        }
        recent_values.push_back(value);
        recent_values.len() > NEGLIGIBLE_STEPS
            && value - recent_values[0] <= tolerance * value.abs()
    }

    /// Whether the window holds [`NEGLIGIBLE_STEPS`] steps and each gained
    /// at most [`NEGLIGIBLE_GAIN`] of the value it reached.
    fn each_step_negligible(recent_values: &VecDeque<f64>) -> bool {
        recent_values.len() > NEGLIGIBLE_STEPS
            && (recent_values.iter().zip(recent_values.iter().skip(1)))
                .all(|(before, after)| after - before <= NEGLIGIBLE_GAIN * after.abs())
    }

    /// The state at `iterate`, the ascent being at `lbfgs`.
    fn state(lbfgs: &Lbfgs, mut iterate: Iterate) -> PlayState {
        iterate.defender = lbfgs.logits();
        iterate.max_residual = iterate.max_residual.max(lbfgs.residual());
        PlayState {
            iterate,
            point: Point {
                value: lbfgs.value(),
                defender: lbfgs.gradient().to_vec(),
                adversary: Vec::new(),
                residual: lbfgs.residual(),
            },
            adversary_gradient_norm: 0.0,
        }
    }
}

impl Solver for Ascent {
    fn init(
        &mut self,
        objective: &mut Objective,
        start: Iterate,
    ) -> Result<PlayState, OptimiseError> {
        let mut against = AgainstFixed {
            objective,
            adversary: &start.adversary,
        };
        let lbfgs = Lbfgs::start(&mut against, &start.defender, start.bound, &self.settings)?;
        let state = Self::state(&lbfgs, start);
        self.last_step = 0.0;
        self.converged = false;
        self.recent_values.clear();
        self.recent_values.push_back(lbfgs.value());
        self.lbfgs = Some(lbfgs);
        Ok(state)
    }

    fn next_iter(
        &mut self,
        objective: &mut Objective,
        state: PlayState,
    ) -> Result<PlayState, OptimiseError> {
        let mut iterate = state.iterate;
        let lbfgs = self.lbfgs.as_mut().ok_or(OptimiseError::BestResponse(
            "the ascent was stepped before it started".into(),
        ))?;
        let mut against = AgainstFixed {
            objective,
            adversary: &iterate.adversary,
        };
        match lbfgs.step(&mut against)? {
            Some(step) => {
                self.last_step = step;
                let value = lbfgs.value();
                let tolerance = self.settings.solver_tolerance;
                let stationary = norm(lbfgs.gradient()) <= STATIONARY_GRADIENT * value.abs();
                let stalled = Self::gained_little(&mut self.recent_values, value, tolerance);
                self.converged =
                    Self::each_step_negligible(&self.recent_values) || (stationary && stalled);
            }
            None => {
                self.last_step = 0.0;
                self.converged = true;
            }
        }
        iterate.iteration += 1;
        Ok(Self::state(lbfgs, iterate))
    }

    fn steps(&self, _iteration: usize) -> (f64, f64) {
        (self.last_step, 0.0)
    }

    fn converged(&self) -> bool {
        self.converged
    }
}

/// The value, the ascent objective (`ln V`, or `V` where the objective is
/// not [`DefenderObjective::logarithmic`]) and its `z`-gradient at one point.
struct Evaluated {
    value: f64,
    /// `ln V` (maximising `ln V` maximises `V`; on long horizons, where `V`
    /// is a product of many probabilities, `ln V` is far better scaled), or
    /// `V`.
    ascended: f64,
    /// `d ln V / dz = (dV/dz) / V`, or `dV/dz`.
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
        let (scale, ascended) = if objective.logarithmic() {
            let value = point.value.max(f64::MIN_POSITIVE);
            (value, value.ln())
        } else {
            (1.0, point.value)
        };
        let ascent = c
            .chain_rule(z, &point.gradient)
            .into_iter()
            .map(|d| d / scale)
            .collect();
        Ok(Self {
            value: point.value,
            ascended,
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
            Ok(next) if next.ascended >= here.ascended + ARMIJO * step * slope => {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Feeds `values` (the first as the start) to a fresh window; whether
    /// each step's value closed it as stalled.
    fn stalls(values: &[f64], tolerance: f64) -> Vec<bool> {
        let mut recent = VecDeque::from([values[0]]);
        (values[1..].iter())
            .map(|&v| Ascent::gained_little(&mut recent, v, tolerance))
            .collect()
    }

    /// The window judges the last [`NEGLIGIBLE_STEPS`] steps together:
    /// not before that many steps, not while they gain more than the
    /// tolerance times `V`, and as soon as they gain less.
    #[test]
    fn the_window_stalls_on_the_gain_of_its_last_steps_together() {
        let creeping: Vec<f64> = (0..=20).map(|i| 0.5 + 1e-11 * i as f64).collect();
        let verdicts = stalls(&creeping, 1e-9);
        assert!(verdicts[..NEGLIGIBLE_STEPS - 1].iter().all(|&s| !s));
        assert!(verdicts[NEGLIGIBLE_STEPS - 1..].iter().all(|&s| s));
        // 1e-10 per step: 1e-9 over ten, above 1e-9 * 0.5.
        let climbing: Vec<f64> = (0..=20).map(|i| 0.5 + 1e-10 * i as f64).collect();
        assert!(stalls(&climbing, 1e-9).iter().all(|&s| !s));
        // A jump leaves the window after ten steps.
        let mut jumped = vec![0.4];
        jumped.extend(std::iter::repeat_n(0.5, 20));
        let verdicts = stalls(&jumped, 1e-9);
        assert!(!verdicts[NEGLIGIBLE_STEPS - 1] && verdicts[NEGLIGIBLE_STEPS]);
    }

    /// The per-step rule holds once the window's last [`NEGLIGIBLE_STEPS`]
    /// steps each gained at most [`NEGLIGIBLE_GAIN`]: a step above it keeps
    /// it off until ten negligible steps follow it (the consecutive count
    /// it replaces).
    #[test]
    fn each_step_must_be_negligible_for_ten_steps_in_a_row() {
        let mut values = vec![0.5, 0.6];
        values.extend((1..=20).map(|i| 0.6 + 1e-14 * i as f64));
        let mut recent = VecDeque::from([values[0]]);
        let verdicts: Vec<bool> = (values[1..].iter())
            .map(|&v| {
                Ascent::gained_little(&mut recent, v, 1e-9);
                Ascent::each_step_negligible(&recent)
            })
            .collect();
        // Step 1 gains 0.1; steps 2.. gain 1e-14 (below 1e-12 * 0.6).
        assert!(verdicts[..NEGLIGIBLE_STEPS].iter().all(|&v| !v));
        assert!(verdicts[NEGLIGIBLE_STEPS..].iter().all(|&v| v));
    }
}
