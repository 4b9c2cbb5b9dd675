//! Strategy files of the certified bounds (docs/formats.md section 7): the
//! free player's optimal memoryless strategy on the product of the game, a
//! deterministic Rabin automaton and the fixed player's controller, as
//! [`crate::certify`] computes it, written so that it can be read back,
//! checked against the game and, when the free player observes the state,
//! turned into a controller.
//!
//! A [`StrategyFile`] holds the rules `(s, q, node) -> action` with the free
//! player's value in each product state, the value from the initial
//! distribution, and the automaton's transitions on the labels of the game's
//! states, so that nothing else is needed to replay it.
//!
//! [`StrategyFile::to_fsc`] builds a controller for the free player with one
//! node per automaton state: node `n` on observation `o` (the state `s` it
//! reveals) moves to node `q = delta(n, L(s))` and plays the rule's action
//! for `(s, q)`, starting in the automaton's initial state. That replays the
//! strategy exactly when the free player observes every state exactly
//! (`"observe": "full"`, or one observation per state and one state per
//! observation) and the strategy does not depend on the fixed player's node
//! (always so when the fixed controller has one node). Played against the
//! fixed controller it attains the bound: `eval` gives the certified lower
//! bound with the attack, the upper bound with the response.

use std::path::Path;

use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

use crate::automaton::Dra;
use crate::certify::{Bound, StrategyRule};
use crate::controller::{Choice, Fsc, Role};
use crate::game::reading::{Located, parse, read_text, write_text};
use crate::game::{ModelError, Player, Posg};

/// The only format version this crate reads and writes (`"strategy": 1`).
pub const FORMAT_VERSION: u64 = 1;

/// What the free player maximises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// `P(phi)`: the defender's response to a fixed adversary (upper bound).
    Phi,
    /// `P(!phi)`: the adversary's attack on a fixed defender (lower bound).
    NotPhi,
}

/// The automaton of the product, restricted to the letters the game's
/// states carry: `successors[q][i] = delta(q, letters[i])`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AutomatonTable {
    /// `|Q|`.
    pub states: usize,
    /// `q_0`.
    pub initial: usize,
    /// The distinct labels `L(s)` of the game's states, each a sorted list
    /// of propositions.
    pub letters: Vec<Vec<String>>,
    /// `delta(q, letters[i])` for each `q` and `i`.
    pub successors: Vec<Vec<usize>>,
}

/// A strategy file (docs/formats.md section 7).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrategyFile {
    /// The format version, [`FORMAT_VERSION`].
    pub strategy: u64,
    /// The free player, who plays the strategy.
    pub player: Role,
    /// What it maximises.
    pub objective: Objective,
    /// The formula (or automaton file) as the user gave it.
    pub formula: String,
    /// The free player's value from the initial distribution: `1 -` the
    /// certified lower bound for an attack, the upper bound for a response.
    pub free_player_value: f64,
    /// The number of nodes of the fixed player's controller.
    pub fixed_nodes: usize,
    /// The automaton of the product.
    pub automaton: AutomatonTable,
    /// One rule per reachable product state `(s, q, node)`.
    pub rules: Vec<StrategyRule>,
    /// The command line that wrote the file.
    pub command: Vec<String>,
    /// The version of posg-fsc that wrote it.
    pub version: String,
}

impl StrategyFile {
    /// The file for `bound`, computed on the product of `game`, `dra` and a
    /// fixed controller with `fixed_nodes` nodes; `formula` and `command`
    /// record where it came from.
    pub fn new(
        game: &Posg,
        dra: &Dra,
        bound: &Bound,
        fixed_nodes: usize,
        formula: &str,
        command: Vec<String>,
    ) -> Self {
        let player = bound.strategy.player;
        Self {
            strategy: FORMAT_VERSION,
            player,
            objective: match player {
                Role::Adversary => Objective::NotPhi,
                Role::Defender => Objective::Phi,
            },
            formula: formula.to_string(),
            free_player_value: bound.strategy.value,
            fixed_nodes,
            automaton: AutomatonTable::of(game, dra),
            rules: bound.strategy.rules.clone(),
            command,
            version: env!("CARGO_PKG_VERSION").to_string(),
        }
    }

    /// The file as pretty-printed JSON.
    pub fn to_json_string(&self) -> String {
        serde_json::to_string_pretty(self).expect("a strategy always serialises") + "\n"
    }

    /// Writes the file to `path`.
    pub fn write(&self, path: &Path) -> Result<(), ModelError> {
        write_text(path, &self.to_json_string())
    }

    /// Reads the strategy file at `path` and checks it against `game`
    /// ([`StrategyFile::from_json_str`]).
    pub fn read(path: &Path, game: &Posg) -> Result<Self, ModelError> {
        let file_name = path.display().to_string();
        let text = read_text(path, &file_name)?;
        Self::from_json_str(&text, &file_name, game)
    }

    /// Parses a strategy file and checks it against `game`: every rule names
    /// a state of the game, an automaton state, a node of the fixed
    /// controller and an action the free player may play in that state
    /// ([`Player::action_enabled_in_state`]); every product state has one
    /// rule; values lie in `[0, 1]`; the automaton table covers the labels
    /// of the game's states. Errors name `FILE: JSON.path`.
    pub fn from_json_str(text: &str, file_name: &str, game: &Posg) -> Result<Self, ModelError> {
        let file: Self = parse(text, file_name)?;
        file.check(game, &Located::new(file_name, ""))?;
        Ok(file)
    }

    fn check(&self, game: &Posg, at: &Located) -> Result<(), ModelError> {
        if self.strategy != FORMAT_VERSION {
            return Err(at.key("strategy").error(format!(
                "unsupported format version {} (expected {FORMAT_VERSION})",
                self.strategy
            )));
        }
        check_value(self.free_player_value, &at.key("free_player_value"))?;
        self.automaton.check(&at.key("automaton"))?;
        self.automaton.letters_of(game, &at.key("automaton"))?;
        let player = self.player.player(game);
        let mut seen: FxHashMap<(usize, usize, usize), usize> = FxHashMap::default();
        let states = game.state_indices();
        for (i, rule) in self.rules.iter().enumerate() {
            let here = at.key("rules").index(i);
            let (s, _) = self.resolve(rule, &states, player, &here)?;
            check_value(rule.free_player_value, &here.key("free_player_value"))?;
            if let Some(first) = seen.insert((s, rule.automaton_state, rule.node), i) {
                return Err(here.error(format!(
                    "a second rule for state `{}`, automaton state {}, node {} (the first is rules[{first}])",
                    rule.state, rule.automaton_state, rule.node
                )));
            }
        }
        Ok(())
    }

    /// A rule's game state and action as indices, checked.
    /// `states` is the game's [`Posg::state_indices`].
    fn resolve(
        &self,
        rule: &StrategyRule,
        states: &FxHashMap<&str, usize>,
        player: &Player,
        at: &Located,
    ) -> Result<(usize, usize), ModelError> {
        let &s = states.get(rule.state.as_str()).ok_or_else(|| {
            at.key("state")
                .error(format!("unknown state `{}`", rule.state))
        })?;
        if rule.automaton_state >= self.automaton.states {
            return Err(at.key("automaton_state").error(format!(
                "automaton state {} is out of range (the automaton has {})",
                rule.automaton_state, self.automaton.states
            )));
        }
        if rule.node >= self.fixed_nodes {
            return Err(at.key("node").error(format!(
                "node {} is out of range (the fixed controller has {})",
                rule.node, self.fixed_nodes
            )));
        }
        let u = player
            .actions()
            .iter()
            .position(|a| *a == rule.action)
            .ok_or_else(|| {
                at.key("action").error(format!(
                    "unknown action `{}` of the {}",
                    rule.action,
                    self.player.name()
                ))
            })?;
        if !player.action_enabled_in_state(s, u) {
            return Err(at.key("action").error(format!(
                "action `{}` is enabled under no observation of state `{}`",
                rule.action, rule.state
            )));
        }
        Ok((s, u))
    }

    /// The free player's controller that replays the strategy (module
    /// documentation), or why it cannot: the free player does not observe
    /// every state exactly, or the strategy depends on the fixed player's
    /// node. `self` must have been checked against `game` (as [`read`]
    /// does).
    ///
    /// [`read`]: StrategyFile::read
    pub fn to_fsc(&self, game: &Posg) -> Result<Fsc, String> {
        let player = self.player.player(game);
        let observed_state = observed_states(game, player, self.player)?;
        let at = Located::new("strategy", "");
        let letters = self
            .automaton
            .letters_of(game, &at)
            .map_err(|e| e.to_string())?;
        let mut action_at: FxHashMap<(usize, usize), (usize, &StrategyRule)> = FxHashMap::default();
        let states = game.state_indices();
        for rule in &self.rules {
            let (s, u) = self
                .resolve(rule, &states, player, &at)
                .map_err(|e| e.to_string())?;
            match action_at.insert((s, rule.automaton_state), (u, rule)) {
                Some((other, first)) if other != u => {
                    return Err(format!(
                        "the strategy depends on the fixed player's node: in state `{}`, automaton \
                         state {}, it plays `{}` at node {} and `{}` at node {}",
                        rule.state,
                        rule.automaton_state,
                        first.action,
                        first.node,
                        rule.action,
                        rule.node
                    ));
                }
                _ => {}
            }
        }
        let nodes = self.automaton.states;
        let num_observations = player.num_observations();
        let mut blocks = Vec::with_capacity(nodes * num_observations);
        for n in 0..nodes {
            for (o, state) in observed_state.iter().enumerate() {
                let (next, action) = match *state {
                    Some(s) => {
                        let q = self.automaton.successors[n][letters[s]];
                        let action = match action_at.get(&(s, q)) {
                            Some(&(u, _)) => u,
                            None => first_enabled(player, o),
                        };
                        (q, action)
                    }
                    None => (n, first_enabled(player, o)),
                };
                blocks.push(vec![Choice {
                    next,
                    action,
                    probability: 1.0,
                    logit: None,
                }]);
            }
        }
        let mut initial = vec![0.0; nodes];
        initial[self.automaton.initial] = 1.0;
        Fsc::new(
            self.player,
            nodes,
            num_observations,
            player.num_actions(),
            initial,
            blocks,
        )
        .map_err(|e| e.to_string())
    }
}

impl AutomatonTable {
    /// `dra`'s transitions on the labels of `game`'s states.
    pub fn of(game: &Posg, dra: &Dra) -> Self {
        let mut letters: Vec<Vec<String>> = (0..game.num_states())
            .map(|s| game.label_names(s).map(str::to_string).collect())
            .collect();
        letters.sort();
        letters.dedup();
        let successors = (0..dra.num_states())
            .map(|q| {
                letters
                    .iter()
                    .map(|l| dra.successor(q, dra.letter_of(l.iter().map(String::as_str))))
                    .collect()
            })
            .collect();
        Self {
            states: dra.num_states(),
            initial: dra.initial(),
            letters,
            successors,
        }
    }

    fn check(&self, at: &Located) -> Result<(), ModelError> {
        if self.initial >= self.states {
            return Err(at.key("initial").error(format!(
                "automaton state {} is out of range (the automaton has {})",
                self.initial, self.states
            )));
        }
        if self.successors.len() != self.states {
            return Err(at.key("successors").error(format!(
                "{} rows for {} automaton states",
                self.successors.len(),
                self.states
            )));
        }
        for (q, row) in self.successors.iter().enumerate() {
            let here = at.key("successors").index(q);
            if row.len() != self.letters.len() {
                return Err(here.error(format!(
                    "{} successors for {} letters",
                    row.len(),
                    self.letters.len()
                )));
            }
            if let Some(i) = row.iter().position(|&q2| q2 >= self.states) {
                return Err(here.index(i).error(format!(
                    "automaton state {} is out of range (the automaton has {})",
                    row[i], self.states
                )));
            }
        }
        Ok(())
    }

    /// The index in `letters` of each game state's label.
    fn letters_of(&self, game: &Posg, at: &Located) -> Result<Vec<usize>, ModelError> {
        (0..game.num_states())
            .map(|s| {
                let label: Vec<&str> = game.label_names(s).collect();
                self.letters
                    .iter()
                    .position(|l| l.iter().map(String::as_str).eq(label.iter().copied()))
                    .ok_or_else(|| {
                        at.key("letters").error(format!(
                            "no entry for the label {label:?} of state `{}`: the strategy was made \
                             for a game with other labels",
                            game.states()[s]
                        ))
                    })
            })
            .collect()
    }
}

/// For each observation of `player` (the free player `role`), the one state
/// it reveals, or `None` if no state has it; an error when some state has
/// several observations or some observation several states.
fn observed_states(game: &Posg, player: &Player, role: Role) -> Result<Vec<Option<usize>>, String> {
    let mut state_of = vec![None; player.num_observations()];
    for s in 0..game.num_states() {
        let &[(o, _)] = player.observation_distribution(s) else {
            return Err(format!(
                "the {} does not observe the state exactly: state `{}` has several observations",
                role.name(),
                game.states()[s]
            ));
        };
        if let Some(other) = state_of[o].replace(s) {
            return Err(format!(
                "the {} does not observe the state exactly: states `{}` and `{}` share observation `{}`",
                role.name(),
                game.states()[other],
                game.states()[s],
                player.observations()[o]
            ));
        }
    }
    Ok(state_of)
}

/// The first action enabled under observation `o` (for blocks the strategy
/// never reaches).
fn first_enabled(player: &Player, o: usize) -> usize {
    player
        .enabled_actions(o)
        .next()
        .expect("every observation enables some action")
}

fn check_value(value: f64, at: &Located) -> Result<(), ModelError> {
    if value.is_finite() && (0.0..=1.0).contains(&value) {
        Ok(())
    } else {
        Err(at.error(format!("value {value} is not in [0, 1]")))
    }
}
