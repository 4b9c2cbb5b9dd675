//! The certified lower bound as a function of the defender's logits: what
//! the guarantee ascent maximises after the max-min loop (method.md section
//! 6, "the lower bound's gradient").
//!
//! The max-min loop plays against an adversary FSC of the structure's
//! size; the number reported is the lower bound against an adversary that
//! sees everything. Ascending that bound itself, with its Danskin gradient
//! ([`lower_bound_gradient`]) and the single-player L-BFGS of
//! [`super::ascent`], moves the defender to where the reported number is
//! larger; every value it sees is a certified bound (policy iteration,
//! method.md section 8).

use super::OptimiseError;
use super::ascent::{DefenderObjective, DefenderPoint};
use super::softmax::Softmax;
use crate::automaton::Dra;
use crate::certify::gradient::lower_bound_gradient;
use crate::game::Posg;
use crate::solver::SolverSettings;

/// `L(phi_def)`: the certified lower bound of the defender with logits
/// `phi_def` on the softmax map's support.
pub(super) struct Guarantee<'a> {
    /// The game.
    pub game: &'a Posg,
    /// An automaton for `!phi`.
    pub not_phi: &'a Dra,
    /// The defender's softmax map.
    pub defender: &'a Softmax,
    /// The solver of the policy evaluations.
    pub solver: SolverSettings,
}

impl DefenderObjective for Guarantee<'_> {
    fn point(&mut self, logits: &[f64]) -> Result<DefenderPoint, OptimiseError> {
        let controller = self.defender.controller(logits)?;
        let found = lower_bound_gradient(self.game, self.not_phi, &controller, &self.solver)?;
        let mu = self.defender.probabilities(logits);
        Ok(DefenderPoint {
            value: found.value,
            gradient: self.defender.chain_rule(&mu, &found.entries, &found.initial),
            residual: 0.0,
        })
    }
}
