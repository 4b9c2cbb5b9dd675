//! Reward models: named state and action rewards of a game (formats.md
//! sections 1, 6 and 11), kept for expected-reward objectives.
//!
//! A reward model `r` gives each state `s` a reward `r(s)` and each triple
//! `(s, u_def, u_adv)` a reward `r(s, u_def, u_adv)`, of either sign and
//! finite; a step from `s` in which the players play `u_def` and `u_adv`
//! earns `r(s) + r(s, u_def, u_adv)`, as a step of Storm's models earns the
//! state reward of the state it leaves and the action reward of the choice
//! it takes. Rewards play no part in the value of an LTL objective
//! (formats.md section 3).

use super::{AdversaryAction, DefenderAction, StateId};

/// One reward model of a game: its name, the state rewards `r(s)` and the
/// action rewards `r(s, u_def, u_adv)`, each 0 unless given.
#[derive(Debug, Clone, PartialEq)]
pub struct RewardModel {
    name: String,
    /// The non-zero `r(s)` by state, strictly increasing.
    state_rewards: Vec<(StateId, f64)>,
    /// The non-zero `r(s, u, v)` by triple index `(s * |U_def| + u) *
    /// |U_adv| + v` (the order of [`super::Posg::transition`]), strictly
    /// increasing, only for triples the game defines.
    action_rewards: Vec<(usize, f64)>,
    /// `(|U_def|, |U_adv|)`, to turn a triple into its index.
    num_actions: (usize, usize),
}

impl RewardModel {
    /// The model `name` of a game whose players have `num_actions` =
    /// `(|U_def|, |U_adv|)` actions, with the state rewards `state_rewards`
    /// by state and the action rewards `action_rewards` by triple index
    /// (each strictly increasing). Zeros are dropped, so that equal rewards
    /// make equal models whatever the file wrote, and only the non-zero
    /// rewards keep memory.
    pub(crate) fn new(
        name: String,
        state_rewards: Vec<(StateId, f64)>,
        action_rewards: Vec<(usize, f64)>,
        num_actions: (usize, usize),
    ) -> Self {
        let state_rewards = non_zero(state_rewards);
        let action_rewards = non_zero(action_rewards);
        debug_assert!(state_rewards.is_sorted_by(|a, b| a.0 < b.0));
        debug_assert!(action_rewards.is_sorted_by(|a, b| a.0 < b.0));
        Self {
            name,
            state_rewards,
            action_rewards,
            num_actions,
        }
    }

    /// The model's name, unique among the game's reward models (`R{"name"}`
    /// in a Storm property).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// `r(s)`: the reward of every step taken from state `s`, 0 unless the
    /// model gives one.
    pub fn state_reward(&self, s: StateId) -> f64 {
        self.state_rewards
            .binary_search_by_key(&s, |&(t, _)| t)
            .map_or(0.0, |i| self.state_rewards[i].1)
    }

    /// `r(s, u, v)`: the reward of a step from state `s` in which the
    /// defender plays `u` and the adversary `v` (in a POMDP, the adversary's
    /// only action `AdversaryAction(0)`), on top of [`Self::state_reward`];
    /// 0 unless the model gives one, and always 0 for a triple the game does
    /// not define ([`super::Posg::transition`] is empty there). `None` when
    /// `u` or `v` is not an action of its player.
    pub fn action_reward(
        &self,
        s: StateId,
        DefenderAction(u): DefenderAction,
        AdversaryAction(v): AdversaryAction,
    ) -> Option<f64> {
        let (nu, nv) = self.num_actions;
        if u >= nu || v >= nv {
            return None;
        }
        let triple = s
            .checked_mul(nu)?
            .checked_add(u)?
            .checked_mul(nv)?
            .checked_add(v)?;
        Some(
            self.action_rewards
                .binary_search_by_key(&triple, |&(t, _)| t)
                .map_or(0.0, |i| self.action_rewards[i].1),
        )
    }

    /// The non-zero state rewards `(s, r(s))`, by increasing state.
    pub fn state_rewards(&self) -> impl Iterator<Item = (StateId, f64)> + '_ {
        self.state_rewards.iter().copied()
    }

    /// The non-zero action rewards `(s, u, v, r(s, u, v))`, in the order of
    /// the triples (state, then defender action, then adversary action).
    pub fn action_rewards(
        &self,
    ) -> impl Iterator<Item = (StateId, DefenderAction, AdversaryAction, f64)> + '_ {
        let (nu, nv) = self.num_actions;
        self.action_rewards.iter().map(move |&(t, r)| {
            (
                t / (nu * nv),
                DefenderAction(t / nv % nu),
                AdversaryAction(t % nv),
                r,
            )
        })
    }

    /// `max_s |r(s)| + max |r(s, u, v)|`: a bound on the magnitude of
    /// the reward of any step, whatever the controllers play.
    pub fn largest_step_reward(&self) -> f64 {
        let largest =
            |rewards: &[(usize, f64)]| rewards.iter().fold(0.0f64, |m, r| m.max(r.1.abs()));
        largest(&self.state_rewards) + largest(&self.action_rewards)
    }

    /// Whether some state reward is not 0.
    pub(crate) fn has_state_rewards(&self) -> bool {
        !self.state_rewards.is_empty()
    }

    /// The non-zero action rewards by triple index, increasing.
    pub(crate) fn action_rewards_by_triple(&self) -> &[(usize, f64)] {
        &self.action_rewards
    }
}

/// The entries of `rewards` whose reward is not 0, in their order, the
/// room of the others given back.
fn non_zero<K>(mut rewards: Vec<(K, f64)>) -> Vec<(K, f64)> {
    rewards.retain(|&(_, r)| r != 0.0);
    rewards.shrink_to_fit();
    rewards
}

/// Whether `name` can name a reward model: not empty, without whitespace
/// or `"` (what both a DRN `@reward_models` line and a Storm property's
/// `R{"name"}` can hold).
pub(crate) fn is_valid_reward_name(name: &str) -> bool {
    !name.is_empty() && !name.chars().any(|c| c.is_whitespace() || c == '"')
}

/// The error message for a reward model name that
/// [`is_valid_reward_name`] refuses.
pub(crate) fn invalid_reward_name(name: &str) -> String {
    format!("`{name}` is not a valid reward model name (not empty, without whitespace or `\"`)")
}
