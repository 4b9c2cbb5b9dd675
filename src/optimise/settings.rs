//! [`Settings`]: every number the optimiser uses, with its default, checked
//! once by [`Settings::validate`] and recorded verbatim in `summary.json`.

use serde::{Deserialize, Serialize};

use super::OptimiseError;
use crate::solver::{SolverMethod, SolverSettings};

/// How a player turns its logit gradient into a step (method.md section 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UpdateRule {
    /// `phi <- phi +/- eta * grad`.
    Plain,
    /// Adam (Kingma and Ba, 2015) with `beta1 = 0.9`, `beta2 = 0.999`,
    /// `epsilon = 1e-8`: `phi <- phi +/- eta * m_hat / (sqrt(v_hat) + epsilon)`,
    /// the update Storm's gradient descent uses by default.
    Adam,
}

/// The optimiser's settings. Every field has a default ([`Settings::default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// Seed of every random choice (initial logits, best-response restarts).
    pub seed: u64,
    /// Logit bound `c`: every logit stays in `[-c, c]`, so every supported
    /// entry keeps probability at least `exp(-2c) / |block|` (method.md section 3).
    pub logit_bound: f64,
    /// Initial logits are drawn uniformly from `[-spread, spread]` (0: uniform controllers).
    pub initial_spread: f64,
    /// Also optimise the initial node distributions (softmax over the initial support).
    pub optimise_initial: bool,
    /// Outer iterations (one defender step each) at most.
    pub max_iterations: usize,
    /// Wall-clock budget in seconds for one structure (0: none).
    pub time_budget: f64,
    /// Adversary descent steps per defender ascent step (the fast time scale).
    pub adversary_steps: usize,
    /// Defender step size `eta_def` at iteration 0.
    pub defender_step: f64,
    /// Adversary step size `eta_adv` (constant).
    pub adversary_step: f64,
    /// Defender step decay `d`: `eta_def(t) = eta_def / sqrt(1 + d t)`.
    pub defender_decay: f64,
    /// The update rule of both players.
    pub update: UpdateRule,
    /// A best-response check every this many outer iterations (and at the end).
    pub check_every: usize,
    /// Random restarts of each best-response minimisation (besides the
    /// start at the current adversary).
    pub restarts: usize,
    /// L-BFGS iterations per best-response start.
    pub best_response_iterations: u64,
    /// L-BFGS memory `m`.
    pub lbfgs_memory: usize,
    /// Stop when the best worst-case estimate has improved by less than
    /// `stall_tolerance` over the last `stall_checks` checks (0: never).
    pub stall_checks: usize,
    /// See `stall_checks`.
    pub stall_tolerance: f64,
    /// Largest residual accepted from a linear solve.
    pub solver_tolerance: f64,
    /// How the linear systems are solved (LU, BiCGSTAB, or by size).
    pub solver: SolverMethod,
    /// Also optimise on every structure the paper's Algorithm 1 keeps
    /// (method.md section 5), in parallel with the starting structure.
    pub prune: bool,
    /// Algorithm 1's lines 14-16 as printed (remove action `u` under
    /// observation `o` for all nodes) instead of only the offending entries.
    pub prune_paper_literal: bool,
    /// Run Algorithm 1's lines 18-22, which restrict the adversary's support:
    /// the worst-case estimate is then against a restricted adversary.
    pub prune_adversary: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            seed: 0,
            logit_bound: 4.0,
            initial_spread: 1.0,
            optimise_initial: false,
            max_iterations: 500,
            time_budget: 0.0,
            adversary_steps: 10,
            defender_step: 0.05,
            adversary_step: 0.5,
            defender_decay: 0.05,
            update: UpdateRule::Adam,
            check_every: 5,
            restarts: 4,
            best_response_iterations: 100,
            lbfgs_memory: 7,
            stall_checks: 0,
            stall_tolerance: 1e-6,
            solver_tolerance: crate::solver::DEFAULT_TOLERANCE,
            solver: SolverMethod::Auto,
            prune: true,
            prune_paper_literal: false,
            prune_adversary: false,
        }
    }
}

impl Settings {
    /// The linear solver's settings: [`Self::solver`] to [`Self::solver_tolerance`].
    pub fn solver_settings(&self) -> SolverSettings {
        SolverSettings {
            method: self.solver,
            tolerance: self.solver_tolerance,
            ..SolverSettings::default()
        }
    }

    /// Checks every field's range; the optimiser cannot fail on settings afterwards.
    pub fn validate(&self) -> Result<(), OptimiseError> {
        let positive = [
            ("logit_bound", self.logit_bound),
            ("defender_step", self.defender_step),
            ("adversary_step", self.adversary_step),
            ("solver_tolerance", self.solver_tolerance),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(invalid(
                    name,
                    format!("must be positive and finite, got {value}"),
                ));
            }
        }
        let non_negative = [
            ("initial_spread", self.initial_spread),
            ("time_budget", self.time_budget),
            ("defender_decay", self.defender_decay),
            ("stall_tolerance", self.stall_tolerance),
        ];
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(invalid(
                    name,
                    format!("must be non-negative and finite, got {value}"),
                ));
            }
        }
        if self.initial_spread > self.logit_bound {
            return Err(invalid(
                "initial_spread",
                "must not exceed logit_bound".into(),
            ));
        }
        let at_least_one = [
            ("max_iterations", self.max_iterations),
            ("adversary_steps", self.adversary_steps),
            ("check_every", self.check_every),
            ("lbfgs_memory", self.lbfgs_memory),
        ];
        for (name, value) in at_least_one {
            if value == 0 {
                return Err(invalid(name, "must be at least 1".into()));
            }
        }
        Ok(())
    }
}

fn invalid(field: &'static str, problem: String) -> OptimiseError {
    OptimiseError::Settings { field, problem }
}
