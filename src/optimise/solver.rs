//! What every solver of the optimiser shares, in argmin's shape: the
//! [`Solver`] trait (one outer iteration; the driver, `optimiser.rs`, owns
//! everything else) and the state it turns into the next ([`Iterate`],
//! [`PlayState`]).

use super::OptimiseError;
use super::objective::{Objective, Point};

/// One outer iteration of an optimisation run, in argmin's shape: the
/// solver owns its update rules and state between iterations, the driver
/// ([`Optimiser`]) everything else.
pub(super) trait Solver: Send {
    /// Iteration 0 from `start`: the state the first check judges.
    fn init(
        &mut self,
        objective: &mut Objective,
        start: Iterate,
    ) -> Result<PlayState, OptimiseError>;

    /// Iteration `t + 1` from the state of iteration `t`.
    fn next_iter(
        &mut self,
        objective: &mut Objective,
        state: PlayState,
    ) -> Result<PlayState, OptimiseError>;

    /// The defender's and the adversary's step sizes at iteration `t`, for
    /// the iteration record.
    fn steps(&self, t: usize) -> (f64, f64);

    /// Whether the solver found no further step (the run then stops as
    /// [`Status::Converged`]).
    fn converged(&self) -> bool {
        false
    }
}

/// The players' logits at the start of an iteration, before the adversary
/// responds.
pub(super) struct Iterate {
    /// The outer iteration `t`.
    pub iteration: usize,
    /// `phi_def(t)`.
    pub defender: Vec<f64>,
    /// `phi_adv` before the adversary's steps of iteration `t`.
    pub adversary: Vec<f64>,
    /// The logit bound `c` of the projection (the driver widens it).
    pub bound: f64,
    /// The largest residual of any linear solve so far.
    pub max_residual: f64,
}

/// The state at the end of iteration `t`: the iterate after the
/// adversary's response and the value and gradients there.
pub(super) struct PlayState {
    /// `(phi_def(t), phi_adv(t))`, the bound and the residual so far.
    pub iterate: Iterate,
    /// `V`, `dV/dphi_def` and `dV/dphi_adv` at `(phi_def(t), phi_adv(t))`.
    pub point: Point,
    /// `|dV/dphi_adv|_2` before the adversary's last step of iteration `t`.
    pub adversary_gradient_norm: f64,
}

/// The Euclidean norm `|v|_2`.
pub(super) fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}
