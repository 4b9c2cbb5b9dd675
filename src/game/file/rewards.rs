//! The `rewards` of a game file (formats.md section 1): reward model name ->
//! `states` (state -> reward) and `actions` (entries `{state, defender,
//! adversary, reward}` with the wildcards and the most-specific-entry rule
//! of `transitions`), read into [`RewardModel`]s and written back without
//! wildcards, zeros left out.

use serde::{Deserialize, Serialize};

use super::{
    Builder, Keyed, Located, Name, UniqueMap, Unresolved, resolve_triple, triple_required,
};
use crate::game::rewards::{RewardModel, invalid_reward_name, is_valid_reward_name};
use crate::game::{ModelError, Posg};

/// One reward model of `rewards`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRewardModel<'a> {
    /// State -> `r(s)`; states left out have 0.
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    states: Option<UniqueMap<f64, Name<'a>>>,
    /// `r(s, u, v)` by entries like those of `transitions`; triples no
    /// entry covers have 0.
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    actions: Option<Vec<RawActionReward<'a>>>,
}

/// One entry of a reward model's `actions`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawActionReward<'a> {
    #[serde(borrow)]
    state: Name<'a>,
    #[serde(borrow)]
    defender: Name<'a>,
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    adversary: Option<Name<'a>>,
    reward: f64,
}

impl Builder<'_, '_> {
    /// The reward models of `raw` (the file's `rewards`, if any) for the
    /// game built so far, in the order of the file.
    pub(super) fn rewards(
        &self,
        raw: Option<&UniqueMap<RawRewardModel, Name>>,
        game: &Posg,
    ) -> Result<Vec<RewardModel>, ModelError> {
        let at = self.at("rewards");
        let num_actions = (game.defender.num_actions(), game.adversary.num_actions());
        let models = raw.map_or(&[][..], |m| m.0.as_slice());
        models
            .iter()
            .map(|(name, model)| {
                let here = at.key(name);
                if !is_valid_reward_name(name) {
                    return Err(here.error(invalid_reward_name(name)));
                }
                let states = self.state_rewards(model.states.as_ref(), &here.key("states"))?;
                let actions = model.actions.as_deref().unwrap_or_default();
                let actions = self.action_rewards(actions, &here.key("actions"), game)?;
                Ok(RewardModel::new(
                    name.to_string(),
                    states,
                    actions,
                    num_actions,
                ))
            })
            .collect()
    }

    /// `r(s)` for every state (none without `states`).
    fn state_rewards(
        &self,
        raw: Option<&UniqueMap<f64, Name>>,
        at: &Located,
    ) -> Result<Vec<f64>, ModelError> {
        let Some(map) = raw else {
            return Ok(Vec::new());
        };
        let mut rewards = vec![0.0; self.raw.states.len()];
        for (state, reward) in &map.0 {
            let s = self
                .state(state)
                .ok_or_else(|| at.key(state).error(format!("unknown state `{}`", &**state)))?;
            rewards[s] = *reward;
        }
        Ok(rewards)
    }

    /// `r(s, u, v)` by triple index for the triples the game defines, as
    /// the most specific entry of `raw` gives it (0 where none does).
    fn action_rewards(
        &self,
        raw: &[RawActionReward],
        at: &Located,
        game: &Posg,
    ) -> Result<Vec<(usize, f64)>, ModelError> {
        let mut keys = Vec::with_capacity(raw.len());
        for (i, entry) in raw.iter().enumerate() {
            let adversary = entry.adversary.as_deref();
            let key = self.transition_key(
                &entry.state,
                &entry.defender,
                adversary,
                &|| at.index(i),
                game,
            )?;
            keys.push((key, i));
        }
        let keyed = Keyed::new(keys, game.num_states());
        let (nu, nv) = (game.defender.num_actions(), game.adversary.num_actions());
        let mut rewards = Vec::new();
        for s in (0..game.num_states()).filter(|&s| !keyed.of_state(s).is_empty()) {
            for u in 0..nu {
                for v in (0..nv).filter(|&v| triple_required(game, s, u, v)) {
                    match resolve_triple(&keyed, s, u, v) {
                        Ok(i) => rewards.push(((s * nu + u) * nv + v, raw[i].reward)),
                        Err(Unresolved::Uncovered) => {}
                        Err(e) => return Err(at.error(e.describe(at.path(), game, s, u, v))),
                    }
                }
            }
        }
        Ok(rewards)
    }
}

/// The game's reward models as `rewards` (none when it has none).
pub(super) fn raw_rewards(game: &Posg) -> Option<UniqueMap<RawRewardModel<'_>, Name<'_>>> {
    let models = game
        .rewards
        .iter()
        .map(|model| (Name::from(model.name()), raw_reward_model(model, game)))
        .collect::<Vec<_>>();
    (!models.is_empty()).then_some(UniqueMap(models))
}

/// One reward model: its non-zero rewards, one action entry per triple.
fn raw_reward_model<'a>(model: &RewardModel, game: &'a Posg) -> RawRewardModel<'a> {
    let states: Vec<(Name, f64)> = model
        .state_rewards()
        .map(|(s, r)| (Name::from(game.states[s].as_str()), r))
        .collect();
    let actions: Vec<RawActionReward> = model
        .action_rewards()
        .map(|(s, u, v, reward)| RawActionReward {
            state: Name::from(game.states[s].as_str()),
            defender: Name::from(game.defender.actions[u.0].as_str()),
            adversary: game
                .has_adversary
                .then(|| Name::from(game.adversary.actions[v.0].as_str())),
            reward,
        })
        .collect();
    RawRewardModel {
        states: (!states.is_empty()).then_some(UniqueMap(states)),
        actions: (!actions.is_empty()).then_some(actions),
    }
}
