//! What `certify` computes and every face reports (docs/method.md section
//! 6): the defender's certified lower bound, the game upper bound against
//! an adversary (checked consistent with it), and on a one-player game the
//! belief bound, made once by [`certificate`].

use serde::Serialize;

use super::belief::{BeliefBound, belief_bound_above};
use super::{Bound, CertifyError, check_consistent, lower_bound_within, upper_bound_within};
use crate::automaton::Dra;
use crate::controller::Fsc;
use crate::game::Posg;
use crate::value::SolverSettings;

/// The bounds of a defender (and of an adversary, when given), with their
/// strategies (the attack and the best response).
#[derive(Debug, Clone, PartialEq)]
pub struct Certificate {
    /// The defender's guaranteed probability of `phi` against every
    /// adversary.
    pub lower: Bound,
    /// The best probability of `phi` any defender achieves against the
    /// adversary.
    pub upper: Option<Bound>,
    /// On a one-player game, the belief bound: no defender of any memory
    /// does better.
    pub belief: Option<BeliefBound>,
}

/// The certificate of `defender` (and of `adversary`) for `phi`, with
/// automata `dra_phi` and `dra_not_phi` (for `!phi`); the linear systems
/// are solved as `settings` say. An upper bound below the lower bound
/// beyond their error bounds is an error ([`check_consistent`]).
pub fn certificate(
    game: &Posg,
    (dra_phi, dra_not_phi): (&Dra, &Dra),
    defender: &Fsc,
    adversary: Option<&Fsc>,
    settings: &SolverSettings,
) -> Result<Certificate, CertifyError> {
    let lower = lower_bound_within(game, dra_not_phi, defender, settings)?;
    let upper = match adversary {
        Some(adversary) => {
            let upper = upper_bound_within(game, dra_phi, adversary, settings)?;
            check_consistent(&lower, &upper)?;
            Some(upper)
        }
        None => None,
    };
    // The belief bound holds for every defender, this one included.
    let belief = belief_bound_above(game, dra_phi, &lower, settings)?;
    Ok(Certificate {
        lower,
        upper,
        belief,
    })
}

impl Certificate {
    /// The numbers `certify` prints and Python's `certify` returns.
    pub fn report(&self) -> CertificateReport {
        CertificateReport {
            lower: BoundSummary::from(&self.lower),
            upper: self.upper.as_ref().map(BoundSummary::from),
            belief: self.belief,
        }
    }
}

/// A [`Certificate`] without its strategies (docs/formats.md section 8).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CertificateReport {
    /// The lower bound.
    pub lower: BoundSummary,
    /// The upper bound, when an adversary was given.
    pub upper: Option<BoundSummary>,
    /// The belief bound, on a one-player game where it can be had.
    pub belief: Option<BeliefBound>,
}

/// A [`Bound`] without its strategy.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BoundSummary {
    /// The bound on `P(phi)`.
    pub value: f64,
    /// The reachable product MDP states.
    pub mdp_states: usize,
    /// Wall-clock seconds to build and solve the MDP.
    pub seconds: f64,
    /// The MDP solution's residual.
    pub residual: f64,
    /// A bound on the error of `value` (method.md section 8).
    pub error_bound: f64,
}

impl From<&Bound> for BoundSummary {
    fn from(bound: &Bound) -> Self {
        Self {
            value: bound.value,
            mdp_states: bound.mdp_states,
            seconds: bound.seconds,
            residual: bound.residual,
            error_bound: bound.error_bound,
        }
    }
}
