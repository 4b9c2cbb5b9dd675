//! The rewards of a DRN model (formats.md section 6): the names on the
//! `@reward_models` line and the annotations `[r1, r2, ...]` of state and
//! action lines, value `i` of each annotation belonging to model `i`.
//!
//! Storm writes one value per reward model on every state and action line
//! (0 where a model has no state or no action rewards); PRISM writes `[]`,
//! which gives every model 0, as does a line without an annotation. Every
//! other annotation carries as many values as `@reward_models` names
//! models; when that line names none (Storm writes an unnamed PRISM reward
//! structure so), all annotations carry the same number `k` and the models
//! are `rew0`, ..., `rew{k-1}`, as Storm's own parser names reward models
//! the header leaves unnamed.

use super::{Choice, Model, parse_value};
use crate::game::rewards::{RewardModel, invalid_reward_name, is_valid_reward_name};

/// The names on the `@reward_models` line: whitespace-separated, each a
/// valid reward model name, none twice.
pub(super) fn parse_names(line: &str) -> Result<Vec<String>, String> {
    let mut names: Vec<String> = Vec::new();
    for name in line.split_whitespace() {
        if !is_valid_reward_name(name) {
            return Err(invalid_reward_name(name));
        }
        if names.iter().any(|n| n == name) {
            return Err(format!("reward model `{name}` is named twice"));
        }
        names.push(name.to_string());
    }
    Ok(names)
}

/// How many values a non-empty reward annotation must carry, and where
/// that was fixed.
#[derive(Debug)]
pub(super) enum Arity {
    /// `@reward_models`, at `line`, names `count` models.
    Declared { count: usize, line: usize },
    /// `@reward_models` names none; the first annotation, at `line`, had
    /// `count` values.
    Seen { count: usize, line: usize },
    /// `@reward_models` names none and no annotation has a value yet.
    Open,
}

impl Arity {
    /// The arity of a file whose `@reward_models` line (at `line`) names
    /// `names`.
    pub(super) fn of_header(names: &[String], line: usize) -> Self {
        match names.len() {
            0 => Arity::Open,
            count => Arity::Declared { count, line },
        }
    }

    /// The values of the annotation `[inside]` at line `n`: none for `[]`,
    /// else one per reward model, each a decimal or `p/q`, finite, of
    /// either sign.
    pub(super) fn annotation(&mut self, inside: &str, n: usize) -> Result<Vec<f64>, String> {
        if inside.trim().is_empty() {
            return Ok(Vec::new());
        }
        let values: Vec<f64> = inside
            .split(',')
            .map(|v| parse_reward(v.trim()))
            .collect::<Result<_, _>>()?;
        let k = values.len();
        let rewards = |count: usize| match count {
            1 => "1 value".to_string(),
            _ => format!("{count} values"),
        };
        match *self {
            Arity::Open => *self = Arity::Seen { count: k, line: n },
            Arity::Declared { count, line } if count != k => {
                return Err(format!(
                    "the reward annotation `[{inside}]` has {}, but `@reward_models` (line \
                     {line}) names {count} reward model{}",
                    rewards(k),
                    if count == 1 { "" } else { "s" }
                ));
            }
            Arity::Seen { count, line } if count != k => {
                return Err(format!(
                    "the reward annotation `[{inside}]` has {}, but the one at line {line} has {} \
                     (and `@reward_models` names no model)",
                    rewards(k),
                    rewards(count)
                ));
            }
            _ => {}
        }
        Ok(values)
    }

    /// The names of the reward models: those of `@reward_models`, or
    /// `rew0`, `rew1`, ... for the values the annotations carry.
    pub(super) fn names(&self, declared: &[String]) -> Vec<String> {
        match *self {
            Arity::Declared { .. } => declared.to_vec(),
            Arity::Seen { count, .. } => (0..count).map(|i| format!("rew{i}")).collect(),
            Arity::Open => Vec::new(),
        }
    }
}

/// A reward: a decimal or `p/q`, finite.
fn parse_reward(text: &str) -> Result<f64, String> {
    let value = parse_value(text)
        .ok_or_else(|| format!("reward `{text}` is not a number (a decimal or p/q)"))?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!("reward `{text}` is not finite"))
    }
}

impl Model {
    /// The reward models `names` (value `i` of each annotation is model
    /// `i`'s) of a game whose players have `num_actions` = `(|U_def|,
    /// |U_adv|)` actions, where `triple(k, choice)` is the pair of actions
    /// the game plays for a choice of state `k`.
    pub(super) fn reward_models(
        &self,
        names: Vec<String>,
        num_actions: (usize, usize),
        triple: impl Fn(usize, &Choice) -> (usize, usize),
    ) -> Vec<RewardModel> {
        let (nu, nv) = num_actions;
        names
            .into_iter()
            .enumerate()
            .map(|(i, name)| {
                let states = self.states.iter().map(|s| value(&s.rewards, i)).collect();
                let mut actions = Vec::new();
                for (k, state) in self.states.iter().enumerate() {
                    for choice in &state.choices {
                        let (u, v) = triple(k, choice);
                        actions.push(((k * nu + u) * nv + v, value(&choice.rewards, i)));
                    }
                }
                actions.sort_unstable_by_key(|&(t, _)| t);
                RewardModel::new(name, states, actions, num_actions)
            })
            .collect()
    }
}

/// Value `i` of an annotation; 0 for `[]` or no annotation.
fn value(rewards: &[f64], i: usize) -> f64 {
    rewards.get(i).copied().unwrap_or(0.0)
}
