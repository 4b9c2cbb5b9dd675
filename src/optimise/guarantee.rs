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

use std::time::Instant;

use super::ascent::{DefenderObjective, DefenderPoint, Lbfgs};
use super::softmax::Softmax;
use super::stopping::{budget_spent, gained_little};
use super::{Cancel, OptimiseError, Settings};
use crate::certify::gradient::LowerBoundGradients;

/// `L(phi_def)`: the certified lower bound of the defender with logits
/// `phi_def` on the softmax map's support.
pub(super) struct Guarantee<'a, 'b> {
    bounds: &'b mut LowerBoundGradients<'a>,
    defender: &'b Softmax,
}

impl<'a, 'b> Guarantee<'a, 'b> {
    /// The bound of `defender`'s controllers by `bounds` (the run's, so
    /// that the graph analysis of the support is shared with its checks).
    pub fn new(bounds: &'b mut LowerBoundGradients<'a>, defender: &'b Softmax) -> Self {
        Self { bounds, defender }
    }
}

impl DefenderObjective for Guarantee<'_, '_> {
    fn point(&mut self, logits: &[f64]) -> Result<DefenderPoint, OptimiseError> {
        let controller = self.defender.controller(logits)?;
        let found = self.bounds.at(&controller)?;
        let mu = self.defender.probabilities(logits);
        Ok(DefenderPoint {
            value: found.value,
            gradient: self
                .defender
                .chain_rule(&mu, &found.entries, &found.initial),
            residual: 0.0,
        })
    }
}

/// Where a guarantee ascent ended: the certified lower bound there and the
/// defender's logits.
pub(super) struct Ascended {
    /// The certified lower bound.
    pub bound: f64,
    /// The defender's logits.
    pub defender: Vec<f64>,
}

/// The guarantee ascent: [`Lbfgs`] steps on `L(phi_def)` from the logits
/// `start`, within `settings.logit_bound`. It stops on the driver's
/// budgets ([`budget_spent`]: the cancel flag, `max_iterations`, a
/// positive `max_work` spent by this ascent, a positive time budget), at a
/// stationary point, or when the bound gained at most `stall_tolerance`
/// times itself over `ascent_stall_iterations` steps: the slow tail of
/// this ascent still pays where the max-min loop's stall rule would have
/// stopped it (a 20-step window lost 1.3e-4 on the 8x8 grid).
pub(super) fn ascend(
    guarantee: &mut Guarantee<'_, '_>,
    start: &[f64],
    settings: &Settings,
    cancel: &Cancel,
) -> Result<Ascended, OptimiseError> {
    let clock = Instant::now();
    let work_before = guarantee.bounds.work();
    let mut lbfgs = Lbfgs::start(guarantee, start, settings.logit_bound, settings)?;
    let mut history = vec![lbfgs.value()];
    let window = settings.ascent_stall_iterations;
    for t in 0.. {
        let work = guarantee.bounds.work() - work_before;
        let spent = budget_spent(settings, t, work, clock.elapsed().as_secs_f64(), cancel);
        let stalled = window > 0 && gained_little(&history, window, settings.stall_tolerance);
        if spent.is_some() || stalled || lbfgs.step(guarantee)?.is_none() {
            break;
        }
        history.push(lbfgs.value());
    }
    Ok(Ascended {
        bound: lbfgs.value(),
        defender: lbfgs.logits(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::lower_bound;
    use crate::controller::{Fsc, Role};
    use crate::game::grid::GridSpec;
    use crate::pipeline::Automata;

    /// From the uniform 2-node defender on a 6x6 grid the ascent climbs the
    /// certified lower bound well above its start, and what it returns is
    /// what `certify::lower_bound` certifies for the returned controller.
    #[test]
    fn the_ascent_raises_the_bound_it_reports_and_certify_agrees() {
        let game = GridSpec {
            width: 6,
            height: 6,
            unsafe_cells: vec![8, 15, 20],
            goal_cells: vec![35],
            ..GridSpec::default()
        }
        .build()
        .unwrap();
        let automata = Automata::from_ltl("!unsafe U goal").unwrap();
        let not_phi = automata.not_phi.unwrap();
        let template = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let softmax = Softmax::new(&template, false);
        let settings = Settings::default();
        let start = softmax.logits_of_template(settings.logit_bound);
        let before = lower_bound(&game, &not_phi, &template).unwrap().value;
        let mut bounds = LowerBoundGradients::new(&game, &not_phi, settings.solver_settings());
        let mut guarantee = Guarantee::new(&mut bounds, &softmax);
        let ascended = ascend(&mut guarantee, &start, &settings, &Cancel::new()).unwrap();
        let reached = ascended.bound;
        assert!(reached > before + 0.1, "{before} -> {reached}");
        let controller = softmax.controller(&ascended.defender).unwrap();
        let certified = lower_bound(&game, &not_phi, &controller).unwrap();
        assert!(
            (certified.value - reached).abs() <= 2.0 * certified.error_bound + 1e-15,
            "ascent {reached}, certify {}",
            certified.value
        );
    }
}
