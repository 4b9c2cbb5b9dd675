//! The rewards of a DRN model (formats.md section 6): the names on the
//! `@reward_models` line and the annotations `[r1, r2, ...]` of state and
//! action lines, value `i` of each annotation belonging to model `i`.
//!
//! Storm writes one value per reward model on every state and action line
//! (0 where a model has no state or no action rewards), and its header
//! line `name + " "` per model; PRISM writes `[]`, which gives every model
//! 0, as does a line without an annotation. Every other annotation carries
//! the same number of values, at least as many as `@reward_models` names;
//! model `i` is named by piece `i` of that line (split at each space or
//! tab, as Storm's parser splits it), and `rew{i}` where the header gives
//! no name (an empty piece, or none: Storm writes an unnamed PRISM reward
//! structure with an empty name).

use rustc_hash::FxHashSet;

use super::{Choice, Header, Lines, Model, parse_value};
use crate::game::ModelError;
use crate::game::rewards::{RewardModel, invalid_reward_name, is_valid_reward_name};
use crate::limits;

/// The names on the `@reward_models` line, split at each space or tab:
/// `None` for an empty piece (a model the header leaves unnamed), trailing
/// empty pieces dropped; each name a valid reward model name, none twice.
pub(super) fn parse_names(line: &str) -> Result<Vec<Option<String>>, String> {
    let mut seen = FxHashSet::default();
    let mut names = Vec::new();
    for name in line.trim_end_matches([' ', '\t']).split([' ', '\t']) {
        if name.is_empty() {
            names.push(None);
            continue;
        }
        if !is_valid_reward_name(name) {
            return Err(invalid_reward_name(name));
        }
        if !seen.insert(name) {
            return Err(format!("reward model `{name}` is named twice"));
        }
        names.push(Some(name.to_string()));
    }
    if names == [None] {
        names.clear();
    }
    Ok(names)
}

/// How many values a non-empty reward annotation must carry: at least as
/// many as `@reward_models` names, and as many as the first one.
#[derive(Debug)]
pub(super) struct Arity {
    /// How many models `@reward_models` names (with the unnamed ones
    /// between names), and its line.
    declared: (usize, usize),
    /// How many values the first non-empty annotation had, and its line.
    seen: Option<(usize, usize)>,
}

impl Arity {
    /// The arity of a file whose `@reward_models` line (at `line`) names
    /// `names`.
    pub(super) fn of_header(names: &[Option<String>], line: usize) -> Self {
        Self {
            declared: (names.len(), line),
            seen: None,
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
        let (declared, header) = self.declared;
        if k < declared {
            return Err(format!(
                "the reward annotation `[{inside}]` has {}, but `@reward_models` (line \
                 {header}) names {declared} reward model{}",
                rewards(k),
                if declared == 1 { "" } else { "s" }
            ));
        }
        match self.seen {
            None => self.seen = Some((k, n)),
            Some((count, line)) if count != k => {
                return Err(format!(
                    "the reward annotation `[{inside}]` has {}, but the one at line {line} has {}",
                    rewards(k),
                    rewards(count)
                ));
            }
            Some(_) => {}
        }
        Ok(values)
    }

    /// The names of the reward models: those of `@reward_models`, and
    /// `rew{i}` for each model `i` it leaves unnamed; an error when such a
    /// name is one the header gives another model.
    pub(super) fn names(&self, declared: &[Option<String>]) -> Result<Vec<String>, String> {
        let count = self.seen.map_or(self.declared.0, |(k, _)| k);
        let given: FxHashSet<&str> = declared.iter().flatten().map(String::as_str).collect();
        (0..count)
            .map(|i| match declared.get(i) {
                Some(Some(name)) => Ok(name.clone()),
                _ => {
                    let name = format!("rew{i}");
                    match given.contains(name.as_str()) {
                        true => Err(format!(
                            "reward model {i}, unnamed here, would be named `{name}`, which \
                             `@reward_models` gives another model"
                        )),
                        false => Ok(name),
                    }
                }
            })
            .collect()
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
    /// The values of the reward annotation `[inside]` at line `n`
    /// ([`Arity::annotation`]), counted against
    /// [`limits::MAX_REWARD_ENTRIES`].
    pub(super) fn reward_annotation(
        &mut self,
        inside: &str,
        n: usize,
        lines: &Lines,
    ) -> Result<Vec<f64>, ModelError> {
        let values = self
            .arity
            .annotation(inside, n)
            .map_err(|m| lines.error(n, m))?;
        self.reward_entries += values.iter().filter(|&&r| r != 0.0).count() as u128;
        match limits::exceeded(
            "the reward models",
            self.reward_entries,
            limits::MAX_REWARD_ENTRIES,
            "non-zero rewards or more",
            "MAX_REWARD_ENTRIES",
        ) {
            Some(message) => Err(lines.error(n, message)),
            None => Ok(values),
        }
    }

    /// The names of the reward models ([`Arity::names`]); an error names
    /// the `@reward_models` line.
    pub(super) fn reward_model_names(
        &self,
        header: &Header,
        lines: &Lines,
    ) -> Result<Vec<String>, ModelError> {
        let (names, line) = &header.reward_models;
        self.arity.names(names).map_err(|m| lines.error(*line, m))
    }

    /// The reward models `names` (value `i` of each annotation is model
    /// `i`'s) of a game whose players have `num_actions` = `(|U_def|,
    /// |U_adv|)` actions, where `triple(k, choice)` is the pair of actions
    /// the game plays for a choice of state `k` (asked once per choice
    /// with rewards). Only non-zero values take room.
    pub(super) fn reward_models(
        &self,
        names: Vec<String>,
        num_actions: (usize, usize),
        triple: impl Fn(usize, &Choice) -> (usize, usize),
    ) -> Vec<RewardModel> {
        let (nu, nv) = num_actions;
        let mut states: Vec<Vec<(usize, f64)>> = vec![Vec::new(); names.len()];
        let mut actions: Vec<Vec<(usize, f64)>> = vec![Vec::new(); names.len()];
        for (k, state) in self.states.iter().enumerate() {
            push_non_zero(&mut states, k, &state.rewards);
            for choice in state.choices.iter().filter(|c| !c.rewards.is_empty()) {
                let (u, v) = triple(k, choice);
                push_non_zero(&mut actions, (k * nu + u) * nv + v, &choice.rewards);
            }
        }
        names
            .into_iter()
            .zip(states.into_iter().zip(actions))
            .map(|(name, (states, mut actions))| {
                actions.sort_unstable_by_key(|&(t, _)| t);
                RewardModel::new(name, states, actions, num_actions)
            })
            .collect()
    }
}

/// Pushes `(key, r)` onto `models[i]` for each non-zero value `r` of
/// `rewards` at `i`.
fn push_non_zero(models: &mut [Vec<(usize, f64)>], key: usize, rewards: &[f64]) {
    for (model, &r) in models.iter_mut().zip(rewards).filter(|&(_, &r)| r != 0.0) {
        model.push((key, r));
    }
}
