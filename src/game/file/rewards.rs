//! The `rewards` of a game file (formats.md section 1): reward model name ->
//! `states` (state -> reward) and `actions` (entries `{state, defender,
//! adversary, reward}` with the wildcards and the most-specific-entry rule
//! of `transitions`), read into [`RewardModel`]s and written back without
//! wildcards, zeros left out.

use serde::{Deserialize, Serialize};

use super::{
    Builder, Keyed, Located, Name, UniqueMap, Unresolved, WILDCARD, resolve_triple, triple_required,
};
use crate::game::rewards::{RewardModel, invalid_reward_name, is_valid_reward_name};
use crate::game::{ModelError, Posg};
use crate::limits;

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

/// One reward model of `rewards` read but not expanded: its name, its
/// non-zero state rewards, its `actions` and their keys.
struct Read<'r, 'a> {
    name: &'r str,
    states: Vec<(usize, f64)>,
    actions: &'r [RawActionReward<'a>],
    keys: Vec<(Key, usize)>,
}

/// The key of an entry of `actions`: `(state, defender action or
/// WILDCARD, adversary action or WILDCARD)`.
type Key = (usize, u32, u32);

impl Builder<'_, '_> {
    /// The reward models of `raw` (the file's `rewards`, if any) for the
    /// game built so far, in the order of the file. The rewards they would
    /// hold, wildcards expanded, are counted against
    /// [`limits::MAX_REWARD_ENTRIES`] before any is expanded.
    pub(super) fn rewards(
        &self,
        raw: Option<&UniqueMap<RawRewardModel, Name>>,
        game: &Posg,
    ) -> Result<Vec<RewardModel>, ModelError> {
        let at = self.at("rewards");
        let models = raw.map_or(&[][..], |m| m.0.as_slice());
        let mut read = Vec::with_capacity(models.len());
        let mut total: u128 = 0;
        for (name, model) in models {
            let here = at.key(name);
            if !is_valid_reward_name(name) {
                return Err(here.error(invalid_reward_name(name)));
            }
            let states = self.state_rewards(model.states.as_ref(), &here.key("states"))?;
            let actions = model.actions.as_deref().unwrap_or_default();
            let keys = self.action_keys(actions, &here.key("actions"), game)?;
            total += states.len() as u128 + expansion_bound(&keys, game);
            if let Some(message) = limits::exceeded(
                "the reward models with their wildcards expanded",
                total,
                limits::MAX_REWARD_ENTRIES,
                "rewards or more",
                "MAX_REWARD_ENTRIES",
            ) {
                return Err(here.error(message));
            }
            read.push(Read {
                name,
                states,
                actions,
                keys,
            });
        }
        let num_actions = (game.defender.num_actions(), game.adversary.num_actions());
        read.into_iter()
            .map(|model| {
                let here = at.key(model.name).key("actions");
                let actions = action_rewards(model.actions, model.keys, &here, game)?;
                Ok(RewardModel::new(
                    model.name.to_string(),
                    model.states,
                    actions,
                    num_actions,
                ))
            })
            .collect()
    }

    /// The non-zero `r(s)` by increasing state (none without `states`).
    fn state_rewards(
        &self,
        raw: Option<&UniqueMap<f64, Name>>,
        at: &Located,
    ) -> Result<Vec<(usize, f64)>, ModelError> {
        let Some(map) = raw else {
            return Ok(Vec::new());
        };
        let mut rewards = Vec::new();
        for (state, reward) in &map.0 {
            let s = self
                .state(state)
                .ok_or_else(|| at.key(state).error(format!("unknown state `{}`", &**state)))?;
            if *reward != 0.0 {
                rewards.push((s, *reward));
            }
        }
        rewards.sort_unstable_by_key(|&(s, _)| s);
        Ok(rewards)
    }

    /// The key of each entry of `raw` with its position, sorted.
    fn action_keys(
        &self,
        raw: &[RawActionReward],
        at: &Located,
        game: &Posg,
    ) -> Result<Vec<(Key, usize)>, ModelError> {
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
        keys.sort_unstable();
        Ok(keys)
    }
}

/// The most triples the entries with `keys` can give a reward: those each
/// covers (a wildcard covers every action of its player), at most every
/// triple of the game.
fn expansion_bound(keys: &[(Key, usize)], game: &Posg) -> u128 {
    let (nu, nv) = (game.defender.num_actions(), game.adversary.num_actions());
    let covered = |key: u32, n: usize| if key == WILDCARD { n as u128 } else { 1 };
    let sum: u128 = keys
        .iter()
        .map(|&((_, u, v), _)| covered(u, nu) * covered(v, nv))
        .sum();
    sum.min(game.num_states() as u128 * nu as u128 * nv as u128)
}

/// `r(s, u, v)` by triple index for the triples the game defines, as the
/// most specific entry of `raw` (whose sorted `keys` these are) gives it (0
/// where none does): only the states the entries name are visited.
fn action_rewards(
    raw: &[RawActionReward],
    keys: Vec<(Key, usize)>,
    at: &Located,
    game: &Posg,
) -> Result<Vec<(usize, f64)>, ModelError> {
    let mut states: Vec<usize> = keys.iter().map(|&((s, _, _), _)| s).collect();
    states.dedup();
    // Keyed by the position of each state among `states`, so that its
    // table is as long as the entries, not as the game.
    let compact = keys
        .into_iter()
        .map(|((s, u, v), i)| {
            let c = states.binary_search(&s).expect("every state is listed");
            ((c, u, v), i)
        })
        .collect();
    let keyed = Keyed::new(compact, states.len());
    let (nu, nv) = (game.defender.num_actions(), game.adversary.num_actions());
    let mut rewards = Vec::new();
    for (c, &s) in states.iter().enumerate() {
        for u in 0..nu {
            for v in (0..nv).filter(|&v| triple_required(game, s, u, v)) {
                match resolve_triple(&keyed, c, u, v) {
                    Ok(i) if raw[i].reward != 0.0 => {
                        rewards.push(((s * nu + u) * nv + v, raw[i].reward));
                    }
                    Ok(_) | Err(Unresolved::Uncovered) => {}
                    Err(e) => return Err(at.error(e.describe(at.path(), game, s, u, v))),
                }
            }
        }
    }
    Ok(rewards)
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
