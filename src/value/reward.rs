//! The one-step reward vector of the expected-reward objective (method.md
//! section 9) and its derivatives.
//!
//! A step of the GMC from `m = (s, q, g, h)` earns
//!
//! ```text
//! r(m) = r(s) + sum_{u,v} a_def(u | s, g) a_adv(v | s, h) r(s, u, v),
//! a_def(u | s, g) = sum_o O_def(o | s) sum_{g'} mu_def(g', u | g, o)
//! ```
//!
//! (`a_adv` likewise): the state reward of `s` and the action rewards of
//! the actions the controllers draw. `r(m)` is bilinear in the two
//! controllers' probabilities, so it is stored as a constant `r(s)` plus
//! terms `w mu_def[k] mu_adv[l]`, `w = O_def(o | s) O_adv(o' | s) r(s, u, v)`,
//! one per pair of support entries `k = (g', u | g, o)`, `l = (h', v | h, o')`
//! with a non-zero reward; then
//!
//! ```text
//! dr(m)/d mu_def[k] = sum_l w mu_adv[l],   dr(m)/d mu_adv[l] = sum_k w mu_def[k].
//! ```

use crate::controller::{Probabilities, Support};
use crate::game::{AdversaryAction, DefenderAction, Posg, RewardModel};
use crate::product::Gmc;

/// `r(m)` on the unknowns of the linear system, as a bilinear form in the
/// controllers' probabilities (module documentation).
#[derive(Debug, Clone)]
pub(crate) struct RewardVector {
    /// `r(s)` of each unknown's game state.
    constant: Vec<f64>,
    /// Unknown `i`'s terms are `terms[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<usize>,
    terms: Vec<Term>,
}

/// `w mu_def[defender] mu_adv[adversary]`.
#[derive(Debug, Clone, Copy)]
struct Term {
    defender: u32,
    adversary: u32,
    weight: f64,
}

impl RewardVector {
    /// The reward vector of `rewards` on the GMC states `unknowns` (in the
    /// order of the linear system) under the controllers' supports.
    pub(crate) fn new(
        game: &Posg,
        gmc: &Gmc,
        unknowns: &[usize],
        rewards: &RewardModel,
        defender: &Support,
        adversary: &Support,
    ) -> Self {
        let mut constant = Vec::with_capacity(unknowns.len());
        let mut offsets = Vec::with_capacity(unknowns.len() + 1);
        offsets.push(0);
        let mut terms = Vec::new();
        for &m in unknowns {
            let state = gmc.state(m);
            let s = state.s as usize;
            constant.push(rewards.state_reward(s));
            for &(o, p_o) in game.defender().observation_distribution(s) {
                for k in defender.block(state.g as usize, o) {
                    let u = defender.entry(k).1;
                    for &(o2, p_o2) in game.adversary().observation_distribution(s) {
                        for l in adversary.block(state.h as usize, o2) {
                            let v = adversary.entry(l).1;
                            let reward = rewards
                                .action_reward(s, DefenderAction(u), AdversaryAction(v))
                                .unwrap_or(0.0);
                            if reward != 0.0 {
                                terms.push(Term {
                                    defender: k as u32,
                                    adversary: l as u32,
                                    weight: p_o * p_o2 * reward,
                                });
                            }
                        }
                    }
                }
            }
            offsets.push(terms.len());
        }
        Self {
            constant,
            offsets,
            terms,
        }
    }

    /// The terms of unknown `i`.
    fn terms(&self, i: usize) -> &[Term] {
        &self.terms[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Writes `b(i) = r(m_i)` for the probabilities.
    pub(crate) fn write(&self, defender: &Probabilities, adversary: &Probabilities, b: &mut [f64]) {
        for (i, (b, &constant)) in b.iter_mut().zip(&self.constant).enumerate() {
            *b = constant
                + self
                    .terms(i)
                    .iter()
                    .map(|t| {
                        t.weight
                            * defender.entries[t.defender as usize]
                            * adversary.entries[t.adversary as usize]
                    })
                    .sum::<f64>();
        }
    }

    /// Adds `sum_i y(i) dr(m_i)/d mu` to both players' gradients: the term
    /// of the adjoint gradient that the reward's dependence on the
    /// controllers adds (method.md section 9).
    pub(crate) fn add_gradient(
        &self,
        y: &[f64],
        defender: &Probabilities,
        adversary: &Probabilities,
        gradient_defender: &mut [f64],
        gradient_adversary: &mut [f64],
    ) {
        for (i, &y) in y.iter().enumerate() {
            if y == 0.0 {
                continue;
            }
            for t in self.terms(i) {
                let (k, l) = (t.defender as usize, t.adversary as usize);
                gradient_defender[k] += y * t.weight * adversary.entries[l];
                gradient_adversary[l] += y * t.weight * defender.entries[k];
            }
        }
    }
}
