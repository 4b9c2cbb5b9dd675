//! The partially observable stochastic game (POSG) with labelled states:
//! the paper's `SG = (S, U_def, U_adv, T, O_def, O_adv, O_def, O_adv, AP, L)`.
//!
//! [`Posg`] is the validated in-memory model; [`file`](mod@file) reads and writes it as
//! `*.posg.json` (formats.md section 1) and, through [`binary`], in the
//! optional binary form `*.posg.bin` (formats.md section 11), [`drn`] imports Storm's explicit DRN
//! models (formats.md section 6) and [`grid`] builds the seed paper's grid
//! family. Every distribution held here has positive entries only (a zero
//! is "no edge") that sum to one exactly up to rounding. A game may carry
//! named [`rewards`] models, which expected-reward objectives use (method.md
//! section 9) and LTL objectives do not.

pub mod binary;
pub mod drn;
pub mod file;
pub mod grid;
pub(crate) mod reading;
pub mod rewards;

pub use rewards::RewardModel;

use thiserror::Error;

/// Index of a game state in `0..num_states()`.
pub type StateId = usize;

/// Why a game or controller could not be built.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{path}: {message}")]
pub struct ModelError {
    /// Where the problem is: a file name and JSON path (e.g.
    /// `grid.posg.json: transitions[17].next.s9`) or a description.
    pub path: String,
    /// What is wrong.
    pub message: String,
}

impl ModelError {
    /// An error at `path` saying `message`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// How far from 1 the probabilities of a distribution in an input file
/// (game, controller, DRN model) may sum (formats.md section 1: "sums to 1
/// within 1e-6"); a distribution within it is renormalised exactly.
pub const DISTRIBUTION_TOLERANCE: f64 = 1e-6;

/// Checks that the probabilities of a distribution, whose sum is `total`,
/// sum to 1 within [`DISTRIBUTION_TOLERANCE`]. The error reads
/// `"{subject} sum to {shown}, not 1 (tolerance 1e-6)"`, with `shown` the
/// total as the caller displays it (the total itself, or a rounded form).
pub(crate) fn check_total(total: f64, shown: f64, subject: &str) -> Result<(), String> {
    if (total - 1.0).abs() > DISTRIBUTION_TOLERANCE {
        return Err(format!(
            "{subject} sum to {shown}, not 1 (tolerance {DISTRIBUTION_TOLERANCE:e})"
        ));
    }
    Ok(())
}

/// What weights summing to `total` (already checked by [`check_total`])
/// are divided by to sum to 1: `None` when `total` is 1 up to the rounding
/// of adding `len` numbers (the weights are then kept bit for bit, so that
/// writing and reading a model gives back the same numbers).
pub(crate) fn rescale_by(total: f64, len: usize) -> Option<f64> {
    ((total - 1.0).abs() > len as f64 * f64::EPSILON).then_some(total)
}

/// A defender action `u in U_def`: an index into the defender's
/// [`Player::actions`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DefenderAction(pub usize);

/// An adversary action `v in U_adv`: an index into the adversary's
/// [`Player::actions`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct AdversaryAction(pub usize);

/// A sparse probability distribution: `(outcome, probability)` pairs with
/// distinct outcomes and positive probabilities summing to 1.
pub type Distribution = Vec<(usize, f64)>;

/// Removes the outcomes of probability zero from `out[start..]`, the
/// distribution being built at the end of a flat buffer.
pub(crate) fn drop_zero_outcomes(out: &mut Vec<(usize, f64)>, start: usize) {
    let mut kept = start;
    for i in start..out.len() {
        if out[i].1 > 0.0 {
            out[kept] = out[i];
            kept += 1;
        }
    }
    out.truncate(kept);
}

/// One player's side of the game: actions `U_*`, observations `O_*`, the
/// observation function `O_*(o | s)` and the actions enabled under each
/// observation (formats.md section 6; by default every action).
#[derive(Debug, Clone, PartialEq)]
pub struct Player {
    pub(crate) actions: Vec<String>,
    pub(crate) observations: Vec<String>,
    pub(crate) full_observation: bool,
    pub(crate) observe: Vec<Distribution>,
    /// `enabled[o * |U| + u]`: whether action `u` is enabled under
    /// observation `o`; empty when every action is enabled everywhere.
    pub(crate) enabled: Vec<bool>,
    /// `(u, label)`: the label as written of each action `u` whose name
    /// differs from it (a renamed DRN label, formats.md section 6), by
    /// increasing `u`; empty when every action is named as written.
    pub(crate) action_labels: Vec<(usize, String)>,
}

impl Player {
    /// The action names `U_*`.
    pub fn actions(&self) -> &[String] {
        &self.actions
    }

    /// The observation names `O_*`.
    pub fn observations(&self) -> &[String] {
        &self.observations
    }

    /// The label of `action` as written in the model the game came from:
    /// its name, unless that label is not a valid name and was renamed on
    /// import (a DRN label such as SAYNT's `(init)` is the action `_init_`,
    /// formats.md section 6). Files and controllers use the name. `None`
    /// when `action` is not one of the player's actions.
    pub fn action_label(&self, action: usize) -> Option<&str> {
        match self
            .action_labels
            .binary_search_by_key(&action, |&(u, _)| u)
        {
            Ok(i) => Some(&self.action_labels[i].1),
            Err(_) => self.actions.get(action).map(String::as_str),
        }
    }

    /// Each action's label as the model wrote it ([`Player::action_label`]):
    /// the names pictures show (`(init)`, `(unlabelled #0)`, `north`).
    pub fn action_labels(&self) -> Vec<String> {
        (0..self.actions.len())
            .map(|u| self.action_label(u).unwrap_or_default().to_string())
            .collect()
    }

    /// `|U_*|`.
    pub fn num_actions(&self) -> usize {
        self.actions.len()
    }

    /// `|O_*|`.
    pub fn num_observations(&self) -> usize {
        self.observations.len()
    }

    /// Whether the player observes the state exactly (`"observe": "full"`).
    pub fn observes_fully(&self) -> bool {
        self.full_observation
    }

    /// `O_*(. | s)` as `(observation, probability)` pairs with positive probability.
    pub fn observation_distribution(&self, s: StateId) -> &[(usize, f64)] {
        &self.observe[s]
    }

    /// Whether the player may play `action` after seeing `observation`
    /// (formats.md section 6): a controller gives positive probability
    /// `mu(g', u | g, o)` only to actions `u` enabled under `o`.
    pub fn action_enabled(&self, observation: usize, action: usize) -> bool {
        self.enabled.is_empty() || self.enabled[observation * self.actions.len() + action]
    }

    /// The actions enabled under `observation`, in increasing order.
    pub fn enabled_actions(&self, observation: usize) -> impl Iterator<Item = usize> + '_ {
        (0..self.actions.len()).filter(move |&u| self.action_enabled(observation, u))
    }

    /// Whether some observation `o` with `O_*(o | s) > 0` enables `action`:
    /// the actions the player can play in state `s`, the ones whose
    /// transitions the game must define, and the ones a fully observing
    /// player of the certified bounds may use (method.md section 6).
    pub fn action_enabled_in_state(&self, s: StateId, action: usize) -> bool {
        self.enabled.is_empty()
            || self.observe[s]
                .iter()
                .any(|&(o, _)| self.action_enabled(o, action))
    }

    /// Whether some action is disabled under some observation (the game
    /// file has a non-trivial `enabled` map for this player).
    pub fn restricts_actions(&self) -> bool {
        !self.enabled.is_empty()
    }

    /// A player with these actions and observations, every action enabled,
    /// in a game without states (to read a controller file on its own).
    pub(crate) fn named(actions: Vec<String>, observations: Vec<String>) -> Self {
        Self {
            actions,
            observations,
            full_observation: false,
            observe: Vec::new(),
            enabled: Vec::new(),
            action_labels: Vec::new(),
        }
    }
}

/// A POSG with labelled states and an initial distribution.
#[derive(Debug, Clone, PartialEq)]
pub struct Posg {
    pub(crate) name: Option<String>,
    pub(crate) states: Vec<String>,
    pub(crate) initial: Distribution,
    pub(crate) propositions: Vec<String>,
    pub(crate) labels: Vec<Vec<usize>>,
    pub(crate) defender: Player,
    pub(crate) adversary: Player,
    pub(crate) has_adversary: bool,
    /// `T(. | s, u, v)` for triple index `(s * |U_def| + u) * |U_adv| + v`:
    /// entries `transition_offsets[t]..transition_offsets[t + 1]` of `transition_entries`.
    pub(crate) transition_offsets: Vec<usize>,
    pub(crate) transition_entries: Vec<(StateId, f64)>,
    /// The reward models, in the order of the file; names are unique.
    pub(crate) rewards: Vec<RewardModel>,
}

impl Posg {
    /// The game's name, if any.
    pub fn name(&self) -> Option<&str> {
        self.name.as_deref()
    }

    /// `|S|`.
    pub fn num_states(&self) -> usize {
        self.states.len()
    }

    /// The state names.
    pub fn states(&self) -> &[String] {
        &self.states
    }

    /// The index of the state named `name` (a scan of the names: to look
    /// up many, [`Self::state_indices`]).
    pub fn state_index(&self, name: &str) -> Option<StateId> {
        self.states.iter().position(|s| s == name)
    }

    /// Each state's index by its name.
    pub fn state_indices(&self) -> rustc_hash::FxHashMap<&str, StateId> {
        (self.states.iter())
            .enumerate()
            .map(|(s, name)| (name.as_str(), s))
            .collect()
    }

    /// The initial distribution over states, positive entries only.
    pub fn initial(&self) -> &[(StateId, f64)] {
        &self.initial
    }

    /// The atomic propositions `AP` (sorted, the union of all labels).
    pub fn propositions(&self) -> &[String] {
        &self.propositions
    }

    /// The game's proposition closest to `name` by edit distance, if one is
    /// within two edits (and closer than `name` is long): the hint for a
    /// misspelt proposition.
    pub fn closest_proposition(&self, name: &str) -> Option<&str> {
        closest(name, self.propositions.iter().map(String::as_str))
    }

    /// `L(s)` as indices into [`Posg::propositions`].
    pub fn label(&self, s: StateId) -> &[usize] {
        &self.labels[s]
    }

    /// `L(s)` as names.
    pub fn label_names(&self, s: StateId) -> impl Iterator<Item = &str> {
        self.labels[s]
            .iter()
            .map(|&p| self.propositions[p].as_str())
    }

    /// The defender.
    pub fn defender(&self) -> &Player {
        &self.defender
    }

    /// The adversary; for a POMDP (no adversary in the file) a player with one
    /// action `_` and one observation `_`.
    pub fn adversary(&self) -> &Player {
        &self.adversary
    }

    /// Whether the file named an adversary (false: the game is a POMDP).
    pub fn has_adversary(&self) -> bool {
        self.has_adversary
    }

    /// `T(. | s, u, v)` as `(successor, probability)` pairs with positive
    /// probability. Empty when `u` or `v` is enabled under no observation of
    /// `s` ([`Player::action_enabled_in_state`]): no controller plays it there.
    /// The two actions have their own index types, so that the defender's and
    /// the adversary's action cannot be swapped by mistake.
    pub fn transition(
        &self,
        s: StateId,
        DefenderAction(u): DefenderAction,
        AdversaryAction(v): AdversaryAction,
    ) -> &[(StateId, f64)] {
        let t = (s * self.defender.num_actions() + u) * self.adversary.num_actions() + v;
        &self.transition_entries[self.transition_offsets[t]..self.transition_offsets[t + 1]]
    }

    /// The game's reward models (state and action rewards, formats.md
    /// section 1), in the order of the file; none for most games.
    pub fn reward_models(&self) -> &[RewardModel] {
        &self.rewards
    }

    /// The names of the reward models, in the order of the file.
    pub fn reward_model_names(&self) -> impl Iterator<Item = &str> {
        self.rewards.iter().map(RewardModel::name)
    }

    /// The reward model named `name` (`R{"name"}` in a Storm property), if
    /// the game has one.
    pub fn reward_model(&self, name: &str) -> Option<&RewardModel> {
        self.rewards.iter().find(|r| r.name() == name)
    }
}

/// The candidate closest to `name` by edit distance, if one is within two
/// edits (and closer than `name` is long; the first of equals): the hint
/// for a misspelt name ("did you mean ...?").
pub fn closest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (edit_distance(name, c), c))
        .filter(|&(d, _)| d <= 2 && d < name.chars().count())
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// The Levenshtein distance between two names (insertions, deletions and
/// substitutions of characters).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitution = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitution.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod edit_tests {
    use super::edit_distance;

    #[test]
    fn edit_distances_of_misspellings() {
        assert_eq!(edit_distance("goal", "goal"), 0);
        assert_eq!(edit_distance("gaol", "goal"), 2);
        assert_eq!(edit_distance("goals", "goal"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("unsafe", "unsave"), 1);
    }
}
