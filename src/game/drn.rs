//! Reading Storm's explicit DRN format into a game (formats.md section 6).
//!
//! A DRN file (`storm --prism M.prism --buildfull --exportbuild M.drn`, or
//! stormpy's `export_to_drn`) is a header (`@type`, `@value_type`,
//! `@parameters`, `@reward_models`, `@nr_states`, `@nr_choices`) and, after
//! `@model`, one block per state:
//!
//! ```text
//! state 3 {1} [0.5] goal init      // id, {observation} (POMDP), [rewards], labels
//!     action north [1]             // a choice: its label (or __NOLABEL__), [rewards]
//!         4 : 0.9                  // target : probability
//!         3 : 0.1
//! ```
//!
//! [`from_drn_str`] turns a `POMDP`, `MDP` or `DTMC` into a [`Posg`] without an
//! adversary (a POMDP game), and a turn-based game (`SMG`, `POSMG`: each state
//! carries its player `<p>`) into a concurrent game ([`turn_based`]; the
//! player [`DrnOptions::defender_player`] is the defender): state `k` is named `s{k}`; a POMDP's observation
//! `k` becomes the defender's observation `o{k}` (observed with probability
//! 1), an MDP or DTMC is fully observed; each choice label is an action
//! (renamed when it is not a valid name: [`labels`]; an unlabelled choice,
//! `__NOLABEL__`, is `(unlabelled #i)` by its index in the state), and
//! the `enabled` actions of each observation (or, fully observed, of each
//! state) are the labels of its choices (formats.md section 6), so no
//! transition has to be invented for actions a state does not offer. The
//! states labelled `init` are the initial distribution (uniform if several);
//! the other labels, except `deadlock`, are propositions. State and action
//! rewards become the game's reward models ([`rewards`]). Everything the game
//! format cannot say is an error naming
//! the line: continuous time, parameters and placeholders, intervals, two
//! choices of one state with the same label, a state whose choices differ
//! from those of another state with its observation, a label that is not a
//! proposition name, probabilities that do not sum to 1 within 1e-6.

use std::path::Path;

use rustc_hash::FxHashMap;

use super::reading::{bytes_without_bom, is_valid_proposition, read_text, without_bom};
use super::{Distribution, ModelError, Player, Posg};
use rewards::Arity;

mod labels;
mod rewards;
pub mod turn_based;

/// How a DRN model becomes a game.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DrnOptions {
    /// In a turn-based game (`SMG`, `POSMG`), the player `<p>` who is the
    /// defender (the other player is the adversary); `None` means player 0.
    /// Giving it for a POMDP, MDP or DTMC is an error.
    pub defender_player: Option<u64>,
    /// Where `defender_player` was named, when in a file (a property
    /// file's `<<P>>`: [`crate::ltl::props::Property::position`]): an
    /// error about that player names it, and the DRN file in its message.
    pub defender_source: Option<String>,
}

impl DrnOptions {
    /// The error `message` about the defender player of the DRN file
    /// `file_name`: at [`Self::defender_source`] if known, else at the file.
    fn player_error(&self, file_name: &str, message: String) -> ModelError {
        match &self.defender_source {
            Some(source) => ModelError::new(source, format!("in {file_name}, {message}")),
            None => ModelError::new(file_name, message),
        }
    }
}

/// A game imported from DRN and what changed on the way.
#[derive(Debug, Clone, PartialEq)]
pub struct DrnImport {
    /// The game: no adversary, the defender as the POMDP's agent.
    pub game: Posg,
    /// What the import changed (the names given to action labels that are
    /// not valid names), one sentence each.
    pub warnings: Vec<String>,
}

/// Reads the DRN file at `path` ([`from_drn_str`]); the game is named after
/// the file's stem.
pub fn read(path: &Path) -> Result<DrnImport, ModelError> {
    read_with(path, &DrnOptions::default())
}

/// [`read`] with options (the defender of a turn-based game).
pub fn read_with(path: &Path, options: &DrnOptions) -> Result<DrnImport, ModelError> {
    let file_name = path.display().to_string();
    let text = read_text(path, &file_name)?;
    let name = path
        .file_stem()
        .map(|stem| stem.to_string_lossy().into_owned());
    from_drn_str_with(&text, &file_name, name, options)
}

/// Whether `bytes` look like a DRN file: after a byte-order mark, if any,
/// the first line that is neither empty nor a `//` comment starts with `@`,
/// as every line of a DRN header does (a JSON game starts with `{`, a
/// binary one with its magic). A DRN file that lacks its `@type` line is
/// still one, and its error says so.
pub fn is_drn(bytes: &[u8]) -> bool {
    let bytes = bytes_without_bom(bytes);
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]);
    text.lines()
        .map(str::trim)
        .find(|line| !line.is_empty() && !line.starts_with("//"))
        .is_some_and(|line| line.starts_with('@'))
}

/// Parses a DRN model (module documentation) into a POMDP game named
/// `name`; `file_name` prefixes every error, which names the line.
pub fn from_drn_str(
    text: &str,
    file_name: &str,
    name: Option<String>,
) -> Result<DrnImport, ModelError> {
    from_drn_str_with(text, file_name, name, &DrnOptions::default())
}

/// [`from_drn_str`] with options (the defender of a turn-based game).
pub fn from_drn_str_with(
    text: &str,
    file_name: &str,
    name: Option<String>,
    options: &DrnOptions,
) -> Result<DrnImport, ModelError> {
    let mut lines = Lines::new(without_bom(text), file_name);
    let header = Header::parse(&mut lines)?;
    let mut model = Model::parse(&mut lines, &header)?;
    model.rename_actions();
    let mut warnings = Vec::new();
    if let Some(warning) = labels::renaming_warning(file_name, &model.renamed) {
        warnings.push(warning);
    }
    let game = if header.model_type.is_turn_based() {
        model.into_turn_based_game(&header, name, &lines, options)?
    } else if let Some(player) = options.defender_player {
        return Err(options.player_error(
            file_name,
            format!(
                "a defender player ({player}) applies to turn-based games (SMG, POSMG) only; \
                 this {} has no players",
                header.model_type
            ),
        ));
    } else {
        model.into_game(&header, name, &lines)?
    };
    Ok(DrnImport { game, warnings })
}

/// The model types the importer reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ModelType {
    Dtmc,
    Mdp,
    Pomdp,
    Smg,
    Posmg,
}

impl ModelType {
    /// Whether each state names the player who moves there (`<p>`).
    fn is_turn_based(self) -> bool {
        matches!(self, ModelType::Smg | ModelType::Posmg)
    }

    /// Whether each state carries an observation (`{k}`).
    fn is_partially_observable(self) -> bool {
        matches!(self, ModelType::Pomdp | ModelType::Posmg)
    }
}

impl std::fmt::Display for ModelType {
    /// The name of the type in the file's `@type:` line.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ModelType::Dtmc => "DTMC",
            ModelType::Mdp => "MDP",
            ModelType::Pomdp => "POMDP",
            ModelType::Smg => "SMG",
            ModelType::Posmg => "POSMG",
        })
    }
}

/// Numbered, comment-free lines of the file, for error messages.
struct Lines<'a> {
    file_name: &'a str,
    lines: std::iter::Peekable<std::iter::Enumerate<std::str::Lines<'a>>>,
}

impl<'a> Lines<'a> {
    /// The limit on transition triples ([`crate::limits::transition_triples`])
    /// for `states` states and the players' action counts, checked before
    /// the tables of that size are allocated: an error naming the file.
    fn check_size(&self, states: usize, nu: usize, nv: usize) -> Result<(), ModelError> {
        match crate::limits::transition_triples(states, nu, nv) {
            Some(message) => Err(ModelError::new(self.file_name, message)),
            None => Ok(()),
        }
    }

    fn new(text: &'a str, file_name: &'a str) -> Self {
        Self {
            file_name,
            lines: text.lines().enumerate().peekable(),
        }
    }

    /// The next line that is neither empty nor a `//` comment, trimmed, with
    /// its 1-based number.
    fn next_content(&mut self) -> Option<(usize, &'a str)> {
        for (i, line) in self.lines.by_ref() {
            let line = line.trim();
            if !line.is_empty() && !line.starts_with("//") {
                return Some((i + 1, line));
            }
        }
        None
    }

    /// The next raw line (a header's value, possibly empty), trimmed.
    fn next_raw(&mut self) -> Option<(usize, &'a str)> {
        self.lines.next().map(|(i, line)| (i + 1, line.trim()))
    }

    fn error(&self, line: usize, message: impl Into<String>) -> ModelError {
        ModelError::new(format!("{}: line {line}", self.file_name), message)
    }
}

/// The most states reserved before they are read (`@nr_states` may claim
/// any number).
const MAX_RESERVED_STATES: usize = 1 << 16;

/// The header: everything before `@model`.
#[derive(Debug)]
struct Header {
    model_type: ModelType,
    states: usize,
    choices: Option<usize>,
    /// The lines of the `@nr_states` and `@nr_choices` values (0 if absent).
    count_lines: (usize, usize),
    /// The names on the `@reward_models` line (`None` where it leaves a
    /// model unnamed) and its number (0 if absent).
    reward_models: (Vec<Option<String>>, usize),
}

impl Header {
    fn parse(lines: &mut Lines) -> Result<Self, ModelError> {
        let mut model_type = None;
        let mut states = None;
        let mut choices = None;
        let mut count_lines = (0, 0);
        let mut reward_models = (Vec::new(), 0);
        while let Some((n, line)) = lines.next_content() {
            match line {
                "@model" => {
                    let model_type = model_type.ok_or_else(|| {
                        lines.error(
                            n,
                            "this DRN file's header has no `@type` line (for example \
                             `@type: POMDP`) before `@model`",
                        )
                    })?;
                    let states = states
                        .ok_or_else(|| lines.error(n, "`@nr_states` must come before `@model`"))?;
                    return Ok(Self {
                        model_type,
                        states,
                        choices,
                        count_lines,
                        reward_models,
                    });
                }
                "@parameters" => {
                    let (m, value) = value_line(lines, n, line)?;
                    if !value.is_empty() {
                        return Err(lines.error(
                            m,
                            format!("parametric models cannot be imported (parameters `{value}`)"),
                        ));
                    }
                }
                "@placeholders" => {
                    return Err(lines.error(n, "placeholders (`$name` values) cannot be imported"));
                }
                "@reward_models" => {
                    if reward_models.1 != 0 {
                        return Err(lines.error(
                            n,
                            format!(
                                "a second `@reward_models` line; the first names its reward models at line {}",
                                reward_models.1
                            ),
                        ));
                    }
                    let (m, value) = value_line(lines, n, line)?;
                    let names = rewards::parse_names(value).map_err(|e| lines.error(m, e))?;
                    reward_models = (names, m);
                }
                "@nr_states" => {
                    states = Some(count_line(lines, n, line)?);
                    count_lines.0 = n + 1;
                }
                "@nr_choices" => {
                    choices = Some(count_line(lines, n, line)?);
                    count_lines.1 = n + 1;
                }
                _ => {
                    if let Some(kind) = line.strip_prefix("@type:") {
                        model_type = Some(parse_type(kind.trim(), n, lines)?);
                    } else if let Some(kind) = line.strip_prefix("@value_type:") {
                        let kind = kind.trim();
                        if kind != "double" && kind != "rational" {
                            return Err(lines.error(
                                n,
                                format!(
                                    "value type `{kind}` cannot be imported (only double and rational)"
                                ),
                            ));
                        }
                    } else {
                        return Err(lines.error(n, format!("unexpected header line `{line}`")));
                    }
                }
            }
        }
        Err(ModelError::new(
            lines.file_name,
            "the file ends before `@model`",
        ))
    }
}

/// The line after a header keyword `key` at line `n`.
fn value_line<'a>(
    lines: &mut Lines<'a>,
    n: usize,
    key: &str,
) -> Result<(usize, &'a str), ModelError> {
    lines
        .next_raw()
        .ok_or_else(|| lines.error(n, format!("`{key}` needs a value on the next line")))
}

/// A whole number on the line after `key`.
fn count_line(lines: &mut Lines, n: usize, key: &str) -> Result<usize, ModelError> {
    let (m, value) = value_line(lines, n, key)?;
    value
        .parse()
        .map_err(|_| lines.error(m, format!("`{key}` needs a whole number, not `{value}`")))
}

fn parse_type(kind: &str, n: usize, lines: &Lines) -> Result<ModelType, ModelError> {
    match kind {
        "DTMC" => Ok(ModelType::Dtmc),
        "MDP" => Ok(ModelType::Mdp),
        "POMDP" => Ok(ModelType::Pomdp),
        "SMG" => Ok(ModelType::Smg),
        "POSMG" => Ok(ModelType::Posmg),
        _ => Err(lines.error(
            n,
            format!(
                "model type `{kind}` cannot be imported (only DTMC, MDP, POMDP, SMG and POSMG)"
            ),
        )),
    }
}

/// One choice of a state: its label (as written, then its action name:
/// [`Model::rename_actions`]), the line it starts on, its rewards (one per
/// reward model, or none) and its successors.
#[derive(Debug)]
struct Choice {
    label: String,
    line: usize,
    rewards: Vec<f64>,
    successors: Vec<(usize, f64)>,
}

/// One state: its DRN observation, rewards (one per reward model, or
/// none), labels, line and choices.
#[derive(Debug)]
struct State {
    line: usize,
    observation: Option<u64>,
    /// The player who moves here (`<p>`, SMG and POSMG only).
    player: Option<u64>,
    rewards: Vec<f64>,
    labels: Vec<String>,
    choices: Vec<Choice>,
}

/// The states of the `@model` section, as written.
#[derive(Debug)]
struct Model {
    states: Vec<State>,
    /// How many values a reward annotation carries.
    arity: Arity,
    /// How many non-zero rewards the annotations have so far.
    reward_entries: u128,
    /// `(label, name)` for each choice label that is not a valid action
    /// name, as [`labels::renamed_labels`] names it.
    renamed: Vec<(String, String)>,
}

impl Model {
    fn parse(lines: &mut Lines, header: &Header) -> Result<Self, ModelError> {
        // The declared count is only a hint: room grows with the states
        // actually read, so a huge `@nr_states` allocates nothing.
        let (names, line) = &header.reward_models;
        let mut model = Self {
            states: Vec::with_capacity(header.states.min(MAX_RESERVED_STATES)),
            arity: Arity::of_header(names, *line),
            reward_entries: 0,
            renamed: Vec::new(),
        };
        while let Some((n, line)) = lines.next_content() {
            if let Some(rest) = line.strip_prefix("state ") {
                let state = model.state_line(rest, n, lines, header)?;
                model.states.push(state);
            } else if let Some(rest) = line.strip_prefix("action ") {
                model.action_line(rest, n, lines)?;
            } else {
                model.transition_line(line, n, lines, header)?;
            }
        }
        if model.states.len() != header.states {
            return Err(lines.error(
                header.count_lines.0,
                format!(
                    "@nr_states declares {} states, the model has {}",
                    header.states,
                    model.states.len()
                ),
            ));
        }
        let choices: usize = model.states.iter().map(|s| s.choices.len()).sum();
        if let Some(declared) = header.choices.filter(|&c| c != choices) {
            return Err(lines.error(
                header.count_lines.1,
                format!("@nr_choices declares {declared} choices, the model has {choices}"),
            ));
        }
        Ok(model)
    }

    /// `state ID [{OBSERVATION}] [<PLAYER>] [[REWARDS]] LABELS...`.
    fn state_line(
        &mut self,
        rest: &str,
        n: usize,
        lines: &Lines,
        header: &Header,
    ) -> Result<State, ModelError> {
        let (id, mut rest) = split_word(rest);
        let expected = self.states.len();
        if id.parse::<usize>().ok() != Some(expected) {
            return Err(lines.error(
                n,
                format!("expected state {expected} (states are numbered in order), found `{id}`"),
            ));
        }
        if expected >= header.states {
            return Err(lines.error(
                n,
                format!("more states than @nr_states ({})", header.states),
            ));
        }
        let mut observation = None;
        if header.model_type.is_partially_observable() {
            let (inside, after) = bracketed(rest, '{', '}').ok_or_else(|| {
                lines.error(
                    n,
                    format!(
                        "a {} state needs its observation `{{k}}`",
                        header.model_type
                    ),
                )
            })?;
            observation = Some(inside.trim().parse().map_err(|_| {
                lines.error(n, format!("observation `{inside}` is not a whole number"))
            })?);
            rest = after;
        }
        let mut player = None;
        if header.model_type.is_turn_based() {
            let (id, after) = turn_based::player_annotation(rest, header.model_type)
                .map_err(|m| lines.error(n, m))?;
            player = Some(id);
            rest = after;
        }
        let mut rewards = Vec::new();
        if let Some((inside, after)) = bracketed(rest, '[', ']') {
            rewards = self.reward_annotation(inside, n, lines)?;
            rest = after;
        }
        let labels = parse_labels(rest).map_err(|m| lines.error(n, m))?;
        Ok(State {
            line: n,
            observation,
            player,
            rewards,
            labels,
            choices: Vec::new(),
        })
    }

    /// `action LABEL [[REWARDS]]`: any label without whitespace; Storm's
    /// `__NOLABEL__` is the label `(unlabelled #i)` of the state's `i`-th
    /// choice ([`labels::unlabelled`]).
    fn action_line(&mut self, rest: &str, n: usize, lines: &Lines) -> Result<(), ModelError> {
        let (label, after) = split_word(rest);
        let state = self.states.last();
        let unlabelled = (label == labels::NO_LABEL)
            .then(|| labels::unlabelled(state.map_or(0, |s| s.choices.len())));
        let label = unlabelled.as_deref().unwrap_or(label);
        let mut rewards = Vec::new();
        if let Some((inside, _)) = bracketed(after, '[', ']') {
            rewards = self.reward_annotation(inside, n, lines)?;
        } else if !after.is_empty() {
            return Err(lines.error(n, format!("unexpected `{after}` after the action label")));
        }
        let state = self
            .states
            .last_mut()
            .ok_or_else(|| lines.error(n, "an action before the first state"))?;
        if let Some(first) = state.choices.iter().find(|c| c.label == label) {
            return Err(lines.error(
                n,
                format!(
                    "a second choice labelled `{label}` in this state (the first is at line {}); \
                     give the commands distinct action labels",
                    first.line
                ),
            ));
        }
        state.choices.push(Choice {
            label: label.to_string(),
            line: n,
            rewards,
            successors: Vec::new(),
        });
        Ok(())
    }

    /// `TARGET : PROBABILITY`.
    fn transition_line(
        &mut self,
        line: &str,
        n: usize,
        lines: &Lines,
        header: &Header,
    ) -> Result<(), ModelError> {
        let (target, value) = line.split_once(':').ok_or_else(|| {
            lines.error(
                n,
                format!("expected `target : probability`, found `{line}`"),
            )
        })?;
        let target: usize = target.trim().parse().map_err(|_| {
            lines.error(
                n,
                format!("target `{}` is not a state number", target.trim()),
            )
        })?;
        if target >= header.states {
            return Err(lines.error(
                n,
                format!(
                    "target {target} is not a state (@nr_states is {})",
                    header.states
                ),
            ));
        }
        let p = parse_probability(value.trim()).map_err(|m| lines.error(n, m))?;
        let choice = self
            .states
            .last_mut()
            .and_then(|s| s.choices.last_mut())
            .ok_or_else(|| {
                lines.error(
                    n,
                    "a transition before the first `action` line of its state",
                )
            })?;
        if choice.successors.iter().any(|&(t, _)| t == target) {
            return Err(lines.error(n, format!("target {target} appears twice in this choice")));
        }
        choice.successors.push((target, p));
        Ok(())
    }

    /// The game (module documentation).
    fn into_game(
        self,
        header: &Header,
        name: Option<String>,
        lines: &Lines,
    ) -> Result<Posg, ModelError> {
        let error = |line: usize, message: String| lines.error(line, message);
        let states: Vec<String> = (0..self.states.len()).map(|k| format!("s{k}")).collect();
        let mut actions: Vec<String> = Vec::new();
        let mut action_index: FxHashMap<&str, usize> = FxHashMap::default();
        for choice in self.states.iter().flat_map(|s| &s.choices) {
            action_index.entry(&choice.label).or_insert_with(|| {
                actions.push(choice.label.clone());
                actions.len() - 1
            });
        }
        for state in &self.states {
            if state.choices.is_empty() {
                return Err(error(state.line, "a state without choices".into()));
            }
        }
        lines.check_size(states.len(), actions.len(), 1)?;
        let (observations, observe, observation_of) = self.observations(header.model_type, &states);
        let enabled = self.enabled(
            &observation_of,
            observations.len(),
            &action_index,
            &actions,
            lines,
        )?;
        let (propositions, labels, initial) = self.labels(lines)?;
        let nu = actions.len();
        let mut transition_offsets = Vec::with_capacity(self.states.len() * nu + 1);
        transition_offsets.push(0);
        let mut transition_entries = Vec::new();
        for state in &self.states {
            let mut rows: Vec<Option<&Choice>> = vec![None; nu];
            for choice in &state.choices {
                rows[action_index[choice.label.as_str()]] = Some(choice);
            }
            for row in rows {
                if let Some(choice) = row {
                    let distribution =
                        normalised(&choice.successors).map_err(|m| error(choice.line, m))?;
                    transition_entries.extend(distribution);
                }
                transition_offsets.push(transition_entries.len());
            }
        }
        let rewards = self.reward_models(
            self.reward_model_names(header, lines)?,
            (nu, 1),
            |_, choice| (action_index[choice.label.as_str()], 0),
        );
        let defender = Player {
            action_labels: self.action_labels(&actions),
            actions,
            observations,
            full_observation: header.model_type != ModelType::Pomdp,
            observe,
            enabled,
        };
        Ok(Posg {
            name,
            initial,
            propositions,
            labels,
            adversary: super::reading::pomdp_adversary(states.len()),
            states,
            defender,
            has_adversary: false,
            transition_offsets,
            transition_entries,
            rewards,
        })
    }

    /// The defender's observation names, `O(. | s)` and each state's
    /// observation index: `o{k}` for a POMDP's observation `k` (in
    /// increasing order of `k`), the state names when fully observed.
    fn observations(
        &self,
        model_type: ModelType,
        states: &[String],
    ) -> (Vec<String>, Vec<Distribution>, Vec<usize>) {
        let (names, observation_of) = if model_type == ModelType::Pomdp {
            let mut ids: Vec<u64> = self.states.iter().filter_map(|s| s.observation).collect();
            ids.sort_unstable();
            ids.dedup();
            let of: Vec<usize> = self
                .states
                .iter()
                .map(|s| {
                    let k = s.observation.expect("a POMDP state has an observation");
                    ids.binary_search(&k).expect("every observation is listed")
                })
                .collect();
            (ids.iter().map(|k| format!("o{k}")).collect(), of)
        } else {
            (states.to_vec(), (0..states.len()).collect())
        };
        let observe = observation_of.iter().map(|&o| vec![(o, 1.0)]).collect();
        (names, observe, observation_of)
    }

    /// The dense `enabled` table of [`Player`]: each observation enables the
    /// labels of its states' choices, which must be the same for all its
    /// states (Storm's POMDP semantics). Empty when everything is enabled.
    fn enabled(
        &self,
        observation_of: &[usize],
        num_observations: usize,
        action_index: &FxHashMap<&str, usize>,
        actions: &[String],
        lines: &Lines,
    ) -> Result<Vec<bool>, ModelError> {
        let nu = actions.len();
        let mut table = vec![false; num_observations * nu];
        let mut first_state: Vec<Option<usize>> = vec![None; num_observations];
        for (k, state) in self.states.iter().enumerate() {
            let o = observation_of[k];
            let mut row = vec![false; nu];
            for choice in &state.choices {
                row[action_index[choice.label.as_str()]] = true;
            }
            match first_state[o] {
                None => {
                    table[o * nu..(o + 1) * nu].copy_from_slice(&row);
                    first_state[o] = Some(k);
                }
                Some(first) if table[o * nu..(o + 1) * nu] != row[..] => {
                    let names = |row: &[bool]| self.offered(row, actions);
                    return Err(lines.error(
                        state.line,
                        format!(
                            "state {k} offers {{{}}}, but state {first} (line {}) with the same \
                             observation offers {{{}}}: a POMDP's states with one observation \
                             must offer the same actions",
                            names(&row),
                            self.states[first].line,
                            names(&table[o * nu..(o + 1) * nu])
                        ),
                    ));
                }
                Some(_) => {}
            }
        }
        if table.iter().all(|&e| e) {
            table.clear();
        }
        Ok(table)
    }

    /// The sorted propositions, each state's label and the initial
    /// distribution (uniform over the states labelled `init`).
    #[allow(clippy::type_complexity)]
    fn labels(
        &self,
        lines: &Lines,
    ) -> Result<(Vec<String>, Vec<Vec<usize>>, Distribution), ModelError> {
        let mut propositions: Vec<String> = Vec::new();
        let mut initial_states = Vec::new();
        for (k, state) in self.states.iter().enumerate() {
            for label in &state.labels {
                match label.as_str() {
                    // `init init` labels a state once.
                    "init" if initial_states.last() != Some(&k) => initial_states.push(k),
                    "init" => {}
                    "deadlock" => {}
                    _ if !is_valid_proposition(label) => {
                        return Err(lines.error(
                            state.line,
                            format!(
                                "label `{label}` is not a valid proposition name ([a-z_][a-z0-9_]*)"
                            ),
                        ));
                    }
                    _ => propositions.push(label.clone()),
                }
            }
        }
        propositions.sort();
        propositions.dedup();
        let labels = self
            .states
            .iter()
            .map(|state| {
                let mut ids: Vec<usize> = state
                    .labels
                    .iter()
                    .filter_map(|l| propositions.binary_search(l).ok())
                    .collect();
                ids.sort_unstable();
                ids.dedup();
                ids
            })
            .collect();
        if initial_states.is_empty() {
            return Err(ModelError::new(
                lines.file_name,
                "no state is labelled `init`",
            ));
        }
        let p = 1.0 / initial_states.len() as f64;
        let initial = initial_states.into_iter().map(|s| (s, p)).collect();
        Ok((propositions, labels, initial))
    }
}

/// The first whitespace-separated word and the trimmed rest.
fn split_word(text: &str) -> (&str, &str) {
    let text = text.trim_start();
    match text.find(char::is_whitespace) {
        Some(i) => (&text[..i], text[i..].trim_start()),
        None => (text, ""),
    }
}

/// `OPEN inside CLOSE rest` at the start of `text`: `(inside, rest)`.
fn bracketed(text: &str, open: char, close: char) -> Option<(&str, &str)> {
    let inner = text.trim_start().strip_prefix(open)?;
    let end = inner.find(close)?;
    Some((&inner[..end], inner[end + close.len_utf8()..].trim_start()))
}

/// State labels: words, or names in double quotes.
fn parse_labels(text: &str) -> Result<Vec<String>, String> {
    let mut labels = Vec::new();
    let mut rest = text.trim_start();
    while !rest.is_empty() {
        if let Some(quoted) = rest.strip_prefix('"') {
            let end = quoted
                .find('"')
                .ok_or_else(|| format!("unterminated quoted label in `{text}`"))?;
            labels.push(quoted[..end].to_string());
            rest = quoted[end + 1..].trim_start();
        } else {
            let (word, after) = split_word(rest);
            labels.push(word.to_string());
            rest = after;
        }
    }
    Ok(labels)
}

/// A number written as a decimal (`0.25`, `-1e-3`) or a rational (`1/4`),
/// as DRN writes probabilities and rewards; `None` for anything else.
fn parse_value(text: &str) -> Option<f64> {
    match text.split_once('/') {
        Some((numerator, denominator)) => {
            let numerator: f64 = numerator.trim().parse().ok()?;
            let denominator: f64 = denominator.trim().parse().ok()?;
            Some(numerator / denominator)
        }
        None => text.parse().ok(),
    }
}

/// A probability written as a decimal (`0.25`, `1e-3`) or a rational (`1/4`).
fn parse_probability(text: &str) -> Result<f64, String> {
    let value = parse_value(text).ok_or_else(|| bad_number(text))?;
    if value.is_finite() && (0.0..=1.0).contains(&value) {
        Ok(value)
    } else {
        Err(format!("probability {text} is not in [0, 1]"))
    }
}

fn bad_number(text: &str) -> String {
    format!("`{text}` is not a probability (a decimal or p/q)")
}

/// A choice's successors as a game distribution: sums to 1 within
/// [`super::DISTRIBUTION_TOLERANCE`] (then renormalised), zero entries dropped, sorted by successor.
fn normalised(successors: &[(usize, f64)]) -> Result<Distribution, String> {
    let total: f64 = successors.iter().map(|&(_, p)| p).sum();
    super::check_total(total, total, "the probabilities of this choice")?;
    let renormalise = (total - 1.0).abs() > successors.len() as f64 * f64::EPSILON;
    let mut distribution: Distribution = successors
        .iter()
        .filter(|&&(_, p)| p > 0.0)
        .map(|&(t, p)| (t, if renormalise { p / total } else { p }))
        .collect();
    distribution.sort_unstable_by_key(|&(t, _)| t);
    Ok(distribution)
}
