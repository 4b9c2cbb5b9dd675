//! The paper's Equations (BigEqn1) and (BigEqn2): whether one term of the
//! GMC transition sum is positive under the current indicators,
//!
//! ```text
//! O_def(o|s) O_adv(o'|s) mu_def(g', u | g, o) mu_adv(h', v | h, o') T^phi((s',q') | (s,q), u, v) > 0,
//! ```
//!
//! with `mu_* = I_* / sum I_*` (lines 13 and 19), so that a term is positive
//! iff both observations have positive probability, both entries are allowed
//! and `T(s' | s, u, v) > 0` with `q' = delta(q, L(s'))`.

use crate::automaton::{Dra, Letter};
use crate::game::{AdversaryAction, DefenderAction, Posg, StateId};
use crate::product::GmcState;

use super::indicator::Indicator;

/// The game and the automaton letters `L(s)`, for evaluating the equations.
pub(crate) struct Terms<'a> {
    game: &'a Posg,
    dra: &'a Dra,
    letters: Vec<Letter>,
}

impl<'a> Terms<'a> {
    pub(crate) fn new(game: &'a Posg, dra: &'a Dra) -> Self {
        let letters = dra.state_letters(game);
        Self { game, dra, letters }
    }

    /// Whether `T^phi((s', q') | (s, q), u, v) > 0`.
    fn product_step(&self, from: GmcState, to: GmcState, u: usize, v: usize) -> bool {
        let next = to.s as StateId;
        self.dra.successor(from.q as usize, self.letters[next]) == to.q as usize
            && self
                .game
                .transition(from.s as usize, DefenderAction(u), AdversaryAction(v))
                .iter()
                .any(|&(t, _)| t == next)
    }

    /// Lines 12-16, default reading: pushes onto `out` every allowed defender
    /// entry `k = (to.g, u | from.g, o)` with `O_def(o | from.s) > 0` for
    /// which some allowed adversary entry `(to.h, v | from.h, o')` with
    /// `O_adv(o' | from.s) > 0` makes Equation (BigEqn1) hold for `from -> to`.
    pub(crate) fn defender_entries_into(
        &self,
        from: GmcState,
        to: GmcState,
        defender: &Indicator<'_>,
        adversary: &Indicator<'_>,
        out: &mut Vec<usize>,
    ) {
        let s = from.s as usize;
        for &(o, _) in self.game.defender().observation_distribution(s) {
            for k in defender.alive_in(from.g as usize, o) {
                let (next, u) = defender.support().entry(k);
                if next == to.g as usize && self.adversary_completes(from, to, u, adversary) {
                    out.push(k);
                }
            }
        }
    }

    /// `exists o', (to.h, v)` allowed under `(from.h, o')` with `O_adv(o'|s) > 0`
    /// such that `T^phi(to | from, u, v) > 0`.
    fn adversary_completes(
        &self,
        from: GmcState,
        to: GmcState,
        u: usize,
        adversary: &Indicator<'_>,
    ) -> bool {
        let s = from.s as usize;
        self.game
            .adversary()
            .observation_distribution(s)
            .iter()
            .any(|&(o, _)| {
                adversary.alive_in(from.h as usize, o).any(|l| {
                    let (next, v) = adversary.support().entry(l);
                    next == to.h as usize && self.product_step(from, to, u, v)
                })
            })
    }

    /// Lines 18-22: pushes onto `out` every allowed adversary entry
    /// `l = (good.h, v | from.h, o')` with `O_adv(o' | from.s) > 0` such that
    /// Equation (BigEqn2) holds for `from -> good` for **every** defender
    /// action `u in U_def` that some observation of `from.s` enables
    /// (formats.md section 6; the others cannot be played there): some allowed `(good.g, u | from.g, o)` with
    /// `O_def(o | from.s) > 0` and `T^phi(good | from, u, v) > 0`.
    pub(crate) fn adversary_entries_toward_good(
        &self,
        from: GmcState,
        good: GmcState,
        defender: &Indicator<'_>,
        adversary: &Indicator<'_>,
        out: &mut Vec<usize>,
    ) {
        let s = from.s as usize;
        let defender_player = self.game.defender();
        for &(o, _) in self.game.adversary().observation_distribution(s) {
            for l in adversary.alive_in(from.h as usize, o) {
                let (next, v) = adversary.support().entry(l);
                if next == good.h as usize
                    && (0..defender_player.num_actions())
                        .filter(|&u| defender_player.action_enabled_in_state(s, u))
                        .all(|u| self.defender_completes(from, good, u, v, defender))
                {
                    out.push(l);
                }
            }
        }
    }

    /// `exists o, (good.g, u)` allowed under `(from.g, o)` with `O_def(o|s) > 0`
    /// such that `T^phi(good | from, u, v) > 0`.
    fn defender_completes(
        &self,
        from: GmcState,
        good: GmcState,
        u: usize,
        v: usize,
        defender: &Indicator<'_>,
    ) -> bool {
        let s = from.s as usize;
        self.game
            .defender()
            .observation_distribution(s)
            .iter()
            .any(|&(o, _)| {
                defender
                    .alive_in(from.g as usize, o)
                    .any(|k| defender.support().entry(k) == (good.g as usize, u))
            })
            && self.product_step(from, good, u, v)
    }

    /// The paper's literal lines 14-16: for each defender entry `k` of
    /// `matched` (under observation `o`, action `u`), every allowed entry
    /// `(g', u | g, o)` for all `g, g'`, pushed onto `out`.
    pub(crate) fn same_action_and_observation(
        &self,
        matched: &[usize],
        defender: &Indicator<'_>,
        out: &mut Vec<usize>,
    ) {
        let support = defender.support();
        let observations = support.num_observations();
        for &k in matched {
            let o = defender.block_of(k) % observations;
            let u = support.entry(k).1;
            for g in 0..support.num_nodes() {
                out.extend(
                    defender
                        .alive_in(g, o)
                        .filter(|&k2| support.entry(k2).1 == u),
                );
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}
