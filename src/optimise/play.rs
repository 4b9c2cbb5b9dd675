//! The solver of the max-min loop: one outer iteration of alternating
//! projected gradient play (method.md sections 3-4), in argmin's shape: a
//! [`GradientPlay`] owns its step sizes and update rules (Adam's moments,
//! the optimistic memory) and turns one [`PlayState`] into the next; the
//! driver ([`super::Optimiser`]) decides when to check, when to stop and
//! what to keep.
//!
//! Iteration `t` ends at the point the best-response checks look at, where
//! the adversary has just responded to `phi_def(t)`:
//!
//! 1. (`t > 0`) the defender's ascent step from iteration `t - 1`:
//!    `phi_def(t) = clip_c(phi_def(t-1) + eta_def(t-1) d_def)`,
//!    `eta_def(t) = eta_def / sqrt(1 + decay t)`;
//! 2. `k_adv` adversary descent steps `phi_adv <- clip_c(phi_adv - eta_adv d_adv)`;
//! 3. the value and both gradients at `(phi_def(t), phi_adv(t))`.
//!
//! `d` is the logit gradient (plain) or Adam's direction, made optimistic
//! (`d_t + optimism (d_t - d_{t-1})`) when `optimism > 0`; `clip_c` is the
//! projection onto `[-c, c]` with the state's logit bound `c`.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::objective::Objective;
use super::softmax::clip;
use super::solver::{Iterate, PlayState, Solver, norm};
use super::{OptimiseError, Settings, UpdateRule};

/// Alternating projected gradient ascent (defender) and descent
/// (adversary) on `V(softmax(phi_def), softmax(phi_adv))`: the step sizes
/// and each player's update rule.
pub(super) struct GradientPlay {
    adversary_steps: usize,
    adversary_step: f64,
    defender_step: f64,
    defender_decay: f64,
    defender: Update,
    adversary: Update,
}

impl GradientPlay {
    /// The solver for `defender_parameters` and `adversary_parameters`
    /// logits, with the step sizes and update rule of `settings`.
    pub fn new(
        settings: &Settings,
        defender_parameters: usize,
        adversary_parameters: usize,
    ) -> Self {
        Self {
            adversary_steps: settings.adversary_steps,
            adversary_step: settings.adversary_step,
            defender_step: settings.defender_step,
            defender_decay: settings.defender_decay,
            defender: Update::new(settings.update, settings.optimism, defender_parameters),
            adversary: Update::new(settings.update, settings.optimism, adversary_parameters),
        }
    }

    /// The defender's step size `eta_def(t) = eta_def / sqrt(1 + decay t)`.
    pub fn defender_step(&self, t: usize) -> f64 {
        self.defender_step / (1.0 + self.defender_decay * t as f64).sqrt()
    }

    /// The adversary's step size `eta_adv`.
    pub fn adversary_step(&self) -> f64 {
        self.adversary_step
    }

    /// The adversary's `k_adv` descent steps
    /// `phi_adv <- clip_c(phi_adv - eta_adv d_adv)` against the iterate's
    /// defender, then the value and gradients where they end.
    fn respond(
        &mut self,
        objective: &mut Objective,
        mut iterate: Iterate,
    ) -> Result<PlayState, OptimiseError> {
        let mut adversary_gradient_norm = 0.0;
        for _ in 0..self.adversary_steps {
            let point = objective.point(&iterate.defender, &iterate.adversary)?;
            iterate.max_residual = iterate.max_residual.max(point.residual);
            adversary_gradient_norm = norm(&point.adversary);
            self.adversary.step(
                &mut iterate.adversary,
                &point.adversary,
                -self.adversary_step,
                iterate.bound,
            );
        }
        let point = objective.point(&iterate.defender, &iterate.adversary)?;
        iterate.max_residual = iterate.max_residual.max(point.residual);
        Ok(PlayState {
            iterate,
            point,
            adversary_gradient_norm,
        })
    }
}

impl Solver for GradientPlay {
    /// Iteration 0: the adversary's response to the starting defender.
    fn init(
        &mut self,
        objective: &mut Objective,
        start: Iterate,
    ) -> Result<PlayState, OptimiseError> {
        self.respond(objective, start)
    }

    /// Iteration `t + 1` from the state of iteration `t`: the defender's
    /// ascent step `phi_def(t+1) = clip_c(phi_def(t) + eta_def(t) d_def)`,
    /// then the adversary's response.
    fn next_iter(
        &mut self,
        objective: &mut Objective,
        state: PlayState,
    ) -> Result<PlayState, OptimiseError> {
        let PlayState {
            mut iterate, point, ..
        } = state;
        let eta = self.defender_step(iterate.iteration);
        self.defender
            .step(&mut iterate.defender, &point.defender, eta, iterate.bound);
        iterate.iteration += 1;
        self.respond(objective, iterate)
    }

    /// `eta_def(t)` and `eta_adv`.
    fn steps(&self, t: usize) -> (f64, f64) {
        (self.defender_step(t), self.adversary_step())
    }
}

/// `logits` plus noise uniform in `[-spread, spread]`, clipped to `[-bound, bound]`.
pub(super) fn perturbed(
    logits: Vec<f64>,
    spread: f64,
    bound: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let mut perturbed: Vec<f64> = logits
        .into_iter()
        .map(|phi| phi + spread * rng.random_range(-1.0..=1.0))
        .collect();
    clip(&mut perturbed, bound);
    perturbed
}

const ADAM_BETA1: f64 = 0.9;
const ADAM_BETA2: f64 = 0.999;
const ADAM_EPSILON: f64 = 1e-8;

/// One player's update rule and its state (Adam's moment estimates).
struct Update {
    rule: UpdateRule,
    first: Vec<f64>,
    second: Vec<f64>,
    previous: Vec<f64>,
    optimism: f64,
    steps: i32,
}

impl Update {
    fn new(rule: UpdateRule, optimism: f64, n: usize) -> Self {
        Self {
            rule,
            first: vec![0.0; n],
            second: vec![0.0; n],
            previous: vec![0.0; n],
            optimism,
            steps: 0,
        }
    }

    /// `phi <- clip(phi + eta (d_t + optimism (d_t - d_{t-1})))` with `d` the
    /// gradient (plain) or Adam's bias-corrected `m_hat / (sqrt(v_hat) +
    /// epsilon)`; `eta < 0` descends. With `optimism = 1` this is the
    /// optimistic update (Popov 1980; Daskalakis et al. 2018), whose
    /// iterates converge where plain alternating play cycles around a
    /// mixed saddle point.
    fn step(&mut self, phi: &mut [f64], gradient: &[f64], eta: f64, bound: f64) {
        match self.rule {
            UpdateRule::Plain => {
                for (k, (p, &g)) in phi.iter_mut().zip(gradient).enumerate() {
                    *p += eta * (g + self.optimism * (g - self.previous[k]));
                    self.previous[k] = g;
                }
            }
            UpdateRule::Adam => {
                self.steps = self.steps.saturating_add(1);
                let c1 = 1.0 - ADAM_BETA1.powi(self.steps);
                let c2 = 1.0 - ADAM_BETA2.powi(self.steps);
                for (k, (p, &g)) in phi.iter_mut().zip(gradient).enumerate() {
                    self.first[k] = ADAM_BETA1 * self.first[k] + (1.0 - ADAM_BETA1) * g;
                    self.second[k] = ADAM_BETA2 * self.second[k] + (1.0 - ADAM_BETA2) * g * g;
                    let d = (self.first[k] / c1) / ((self.second[k] / c2).sqrt() + ADAM_EPSILON);
                    *p += eta * (d + self.optimism * (d - self.previous[k]));
                    self.previous[k] = d;
                }
            }
        }
        clip(phi, bound);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_optimistic_plain_step_extrapolates_and_clips() {
        let mut update = Update::new(UpdateRule::Plain, 1.0, 2);
        let mut phi = vec![0.0, 0.0];
        update.step(&mut phi, &[1.0, -2.0], 0.5, 10.0);
        assert_eq!(phi, [1.0, -2.0], "0.5 (g + (g - 0))");
        update.step(&mut phi, &[3.0, 0.0], 0.5, 1.5);
        assert_eq!(
            phi,
            [1.5, -1.0],
            "[1 + 0.5 (3 + 2), -2 + 0.5 (0 + 2)], clipped to 1.5"
        );
    }

    #[test]
    fn adams_first_step_moves_each_logit_by_the_step_size() {
        let mut update = Update::new(UpdateRule::Adam, 0.0, 2);
        let mut phi = vec![0.0, 0.0];
        update.step(&mut phi, &[4.0, -0.01], -0.1, 10.0);
        assert!(
            (phi[0] + 0.1).abs() < 1e-8 && (phi[1] - 0.1).abs() < 1e-6,
            "{phi:?}"
        );
    }

    #[test]
    fn the_defender_step_decays_with_the_square_root_of_the_iteration() {
        let settings = Settings {
            defender_step: 0.3,
            defender_decay: 3.0,
            adversary_step: 0.7,
            ..Settings::default()
        };
        let play = GradientPlay::new(&settings, 1, 1);
        assert_eq!(play.defender_step(0), 0.3);
        assert_eq!(play.defender_step(1), 0.15);
        assert_eq!(play.adversary_step(), 0.7);
    }
}
