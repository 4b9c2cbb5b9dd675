//! The certificate of an expected total reward (module documentation of
//! [`super`], step 3): the check of `y = x +- eps T` for every kept action.

use super::{Optimum, UNIT_ROUNDOFF};
use crate::mdp::{Mdp, MdpError};

/// What the certificate's check reads: the unknowns and their position by
/// state (`usize::MAX` for the others), the kept actions, the rewards and
/// the direction.
pub(super) struct Scale<'a> {
    pub(super) unknowns: &'a [usize],
    pub(super) index: &'a [usize],
    pub(super) kept: &'a [bool],
    pub(super) rewards: &'a [f64],
    pub(super) optimum: Optimum,
}

/// The values of the unknowns read by state: 0 on the target.
struct ByState<'a> {
    index: &'a [usize],
    values: &'a [f64],
}

impl ByState<'_> {
    fn at(&self, t: usize) -> f64 {
        match self.index[t] {
            usize::MAX => 0.0,
            i => self.values[i],
        }
    }

    /// `c + sum_{t != s} P(t | action) (v(t) - v(s))` for unknown `s`
    /// (position `i`), the Bellman gap of the model the policy systems
    /// solve (whose diagonal is the probability of leaving `s`, method.md
    /// section 8), and the sum of its terms' magnitudes (for its rounding).
    fn advance(
        &self,
        mdp: &Mdp,
        (s, i, action): (usize, usize, usize),
        constant: f64,
    ) -> (f64, f64) {
        let here = self.values[i];
        let (mut sum, mut size) = (constant, constant.abs());
        for &(t, p) in mdp
            .global_distribution(action)
            .iter()
            .filter(|&&(t, _)| t != s)
        {
            let there = self.at(t);
            sum += p * (there - here);
            size += p * (there.abs() + here.abs());
        }
        (sum, size)
    }
}

impl Scale<'_> {
    /// `values` (one per unknown) read by state.
    fn by_state<'v>(&'v self, values: &'v [f64]) -> ByState<'v> {
        ByState {
            index: self.index,
            values,
        }
    }

    /// The kept actions whose gain `+-(r + P x - x)` is at least `-tau`
    /// (the others lose more than `tau` against `x`).
    pub(super) fn near_optimal(&self, mdp: &Mdp, x: &[f64], tau: f64) -> Vec<bool> {
        let values = self.by_state(x);
        let mut near = vec![false; mdp.num_state_actions()];
        for (i, &s) in self.unknowns.iter().enumerate() {
            for action in mdp.global_actions(s).filter(|&a| self.kept[a]) {
                let (gain, _) = values.advance(mdp, (s, i, action), self.rewards[action]);
                near[action] = self.optimum.sign() * gain >= -tau;
            }
        }
        near
    }

    /// `y = x + eps T` (`x - eps T` for a minimum) on the unknowns, with
    /// the smallest `eps >= 0` whose check passes for every kept action
    /// (module documentation, step 3); `None` where none does.
    pub(super) fn certify(
        &self,
        mdp: &Mdp,
        x: &[f64],
        steps: &[f64],
    ) -> Result<Option<Vec<f64>>, MdpError> {
        let (values, potential) = (self.by_state(x), self.by_state(steps));
        let sign = self.optimum.sign();
        // Each constraint `g <= eps d`, with `g` rounded up and `d` down.
        let (mut least, mut most) = (0.0_f64, f64::INFINITY);
        for (i, &s) in self.unknowns.iter().enumerate() {
            for action in mdp.global_actions(s).filter(|&a| self.kept[a]) {
                let (gain, gain_size) = values.advance(mdp, (s, i, action), self.rewards[action]);
                let (rise, rise_size) = potential.advance(mdp, (s, i, action), 0.0);
                let terms = mdp.global_distribution(action).len() + 3;
                let rounding = terms as f64 * UNIT_ROUNDOFF * 1.01;
                let g = sign * gain + rounding * gain_size;
                let d = -rise - rounding * rise_size;
                if !(g.is_finite() && d.is_finite()) {
                    // A potential or a value that is not finite proves
                    // nothing.
                    return Ok(None);
                }
                if d > 0.0 {
                    least = least.max(g / d * (1.0 + 4.0 * UNIT_ROUNDOFF));
                } else if g > 0.0 {
                    return Ok(None);
                } else if d < 0.0 {
                    most = most.min(g / d);
                }
            }
        }
        if !least.is_finite() || least > most * (1.0 - 4.0 * UNIT_ROUNDOFF) {
            return Ok(None);
        }
        let eps = least;
        Ok(Some(
            x.iter()
                .zip(steps)
                .map(|(&v, &t)| {
                    let y = v + sign * eps * t;
                    let rounding = 4.0 * UNIT_ROUNDOFF * (v.abs() + eps * t.abs());
                    y + sign * (rounding + f64::MIN_POSITIVE)
                })
                .collect(),
        ))
    }
}
