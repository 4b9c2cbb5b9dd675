//! The gradient of the certified lower bound with respect to the defender's
//! controller probabilities (method.md section 6, "the lower bound's
//! gradient").
//!
//! The lower bound `L(mu_def) = 1 - max_sigma P^sigma(!phi)` is the value of
//! the defender's controller against an adversary that sees everything
//! ([`super::lower_bound`]). It is the pointwise minimum, over the
//! adversary's memoryless strategies `sigma` of the product MDP, of the
//! smooth functions `1 - P^sigma(!phi)`, so where the optimal `sigma*` is
//! unique its derivative is that of `1 - P^{sigma*}(!phi)` with `sigma*`
//! held fixed (Danskin's theorem); where several strategies are optimal it
//! is the derivative of one of them, a one-sided derivative of `L`. With
//! `x` the optimal values of `!phi` and `y` the expected visits to the
//! undecided states under `sigma*` ([`expected_visits`]):
//!
//! ```text
//! dL/d mu_def(g', u | g, o) = - sum_{(s, q, g) undecided} y(s, q, g) O_def(o | s)
//!                             sum_s' T(s' | s, u, sigma*(s, q, g)) x(s', delta(q, L(s')), g'),
//! dL/d init_def(g) = - sum_s init(s) x(s, delta(q_0, L(s)), g).
//! ```
//!
//! The decided states (value 0 or 1 whatever the probabilities inside the
//! supports) contribute nothing: their values do not move while the
//! supports stay fixed.

use std::collections::HashMap;

use super::{Analysis, CertifyError, analyse};
use crate::automaton::Dra;
use crate::controller::{Fsc, Role, Support};
use crate::game::{AdversaryAction, DefenderAction, Posg};
use crate::mdp::expected_visits;
use crate::solver::SolverSettings;

/// The certified lower bound of a defender's controller and its gradient.
#[derive(Debug, Clone, PartialEq)]
pub struct LowerBoundGradient {
    /// `L = 1 - max_sigma P^sigma(!phi)`, within `error_bound` of the exact
    /// bound.
    pub value: f64,
    /// The bound on `|value - L_exact|` (method.md section 8).
    pub error_bound: f64,
    /// `dL/d mu_def` per entry of the controller's [`Support`].
    pub entries: Vec<f64>,
    /// `dL/d init_def(g)` per node.
    pub initial: Vec<f64>,
}

/// The certified lower bound of `defender` (as [`super::lower_bound_within`])
/// and its gradient (module documentation), `dra_not_phi` an automaton for
/// `!phi`.
pub fn lower_bound_gradient(
    game: &Posg,
    dra_not_phi: &Dra,
    defender: &Fsc,
    settings: &SolverSettings,
) -> Result<LowerBoundGradient, CertifyError> {
    let analysis = analyse(game, dra_not_phi, defender, Role::Defender, settings)?;
    let x = &analysis.result.values;
    let y = expected_visits(&analysis.mdp, &analysis.result, &analysis.initial, settings)?;
    let index: HashMap<(usize, usize, usize), usize> = analysis
        .states
        .iter()
        .enumerate()
        .map(|(m, &key)| (key, m))
        .collect();
    let value_at = |key: (usize, usize, usize)| index.get(&key).map_or(0.0, |&m| x[m]);
    let letters = dra_not_phi.state_letters(game);
    let support = Support::of(defender);
    let mut entries = vec![0.0; support.num_entries()];
    for (m, &(s, q, g)) in analysis.states.iter().enumerate() {
        if y[m] == 0.0 {
            continue;
        }
        let w = adversary_action(&analysis, m, s);
        for &(o, p_o) in game.defender().observation_distribution(s) {
            for k in support.block(g, o) {
                let (next, u) = support.entry(k);
                let expectation: f64 = game
                    .transition(s, DefenderAction(u), AdversaryAction(w))
                    .iter()
                    .map(|&(s2, t)| t * value_at((s2, dra_not_phi.successor(q, letters[s2]), next)))
                    .sum();
                entries[k] -= y[m] * p_o * expectation;
            }
        }
    }
    let mut initial = vec![0.0; defender.num_nodes()];
    for &(s, p) in game.initial() {
        let q = dra_not_phi.successor(dra_not_phi.initial(), letters[s]);
        for (g, d) in initial.iter_mut().enumerate() {
            *d -= p * value_at((s, q, g));
        }
    }
    let not_phi: f64 = analysis.initial.iter().map(|&(m, p)| p * x[m]).sum();
    let rounding = 2.0 * analysis.initial.len() as f64 * f64::EPSILON;
    Ok(LowerBoundGradient {
        value: (1.0 - not_phi).clamp(0.0, 1.0),
        error_bound: analysis.result.error_bound + rounding,
        entries,
        initial,
    })
}

/// The adversary's action in product state `m` (game state `s`) under the
/// optimal strategy of `analysis`.
fn adversary_action(analysis: &Analysis, m: usize, s: usize) -> usize {
    analysis.free_actions[s][analysis.result.strategy[m]]
}
