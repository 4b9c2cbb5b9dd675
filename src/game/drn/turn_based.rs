//! Turn-based games from DRN (`@type: SMG` and `@type: POSMG`, as PRISM-games
//! and PAYNT write them) as concurrent games (formats.md section 6).
//!
//! Each state `state N {o} <p>` belongs to player `p`, who alone chooses
//! among its choices. The defender is the player [`DrnOptions::defender_player`]
//! (default 0), the adversary the other one; a third player is an error.
//! Nothing is invented: in a state of one player the other has exactly one
//! enabled action, the no-op [`IDLE`], so `T(s, u, _)` (defender's state) or
//! `T(s, _, v)` (adversary's state) is the choice's distribution, and no other
//! triple is needed.
//!
//! Observations follow PAYNT's semantics of a POSMG: the defender sees the
//! DRN observation `o{k}` of its own states, and one shared observation
//! [`OPPONENT_MOVES`] in every state of the adversary (the DRN's observations
//! of those states would tell the defender more than PAYNT's optimising
//! player learns). The adversary sees the state. In an SMG both see the
//! state.

use rustc_hash::FxHashMap;

use super::{Choice, DrnOptions, Header, Lines, Model, ModelType, bracketed, normalised};
use crate::game::{ModelError, Player, Posg};

/// The action of the player who does not move in a state.
pub const IDLE: &str = "_";

/// The defender's observation in every state of the adversary (POSMG).
pub const OPPONENT_MOVES: &str = "opponent";

/// `<PLAYER> rest` at the start of `text`: the player and the rest.
pub(super) fn player_annotation(text: &str, kind: ModelType) -> Result<(u64, &str), String> {
    let (inside, after) = bracketed(text, '<', '>').ok_or_else(|| {
        if text.trim_start().starts_with('<') {
            format!("unterminated player annotation in `{text}`: expected `<p>`")
        } else {
            format!(
                "a state of a turn-based game ({kind}) needs its player `<p>` after the state \
                 number{}",
                if kind == ModelType::Posmg {
                    " and observation"
                } else {
                    ""
                }
            )
        }
    })?;
    let player = inside
        .trim()
        .parse()
        .map_err(|_| format!("player `{inside}` is not a whole number"))?;
    Ok((player, after))
}

/// Who moves in each state: the defender (`true`) or the adversary.
struct Turns {
    defender_moves: Vec<bool>,
}

impl Model {
    /// The concurrent game of a turn-based model (module documentation).
    pub(super) fn into_turn_based_game(
        self,
        header: &Header,
        name: Option<String>,
        lines: &Lines,
        options: &DrnOptions,
    ) -> Result<Posg, ModelError> {
        for state in &self.states {
            if state.choices.is_empty() {
                return Err(lines.error(state.line, "a state without choices"));
            }
        }
        let turns = self.turns(options, lines)?;
        let defender_actions = self.actions_of(&turns, true, lines)?;
        let adversary_actions = self.actions_of(&turns, false, lines)?;
        lines.check_size(
            self.states.len(),
            defender_actions.len(),
            adversary_actions.len(),
        )?;
        let states: Vec<String> = (0..self.states.len()).map(|k| format!("s{k}")).collect();
        let defender = if header.model_type == ModelType::Posmg {
            self.partially_observing_defender(&turns, defender_actions, lines)?
        } else {
            self.fully_observing(&turns, true, defender_actions, &states)
        };
        let adversary = self.fully_observing(&turns, false, adversary_actions, &states);
        let (transition_offsets, transition_entries) =
            self.transitions(&turns, &defender, &adversary, lines)?;
        let (propositions, labels, initial) = self.labels(lines)?;
        let rewards = self.reward_models(
            self.reward_model_names(header, lines)?,
            (defender.num_actions(), adversary.num_actions()),
            |k, choice| joint_action(&turns, k, choice, &defender, &adversary),
        );
        Ok(Posg {
            name,
            states,
            initial,
            propositions,
            labels,
            defender,
            adversary,
            has_adversary: true,
            transition_offsets,
            transition_entries,
            rewards,
        })
    }

    /// Who moves where; an error for a third player, or a defender that
    /// owns no state.
    fn turns(&self, options: &DrnOptions, lines: &Lines) -> Result<Turns, ModelError> {
        let defender = options.defender_player.unwrap_or(0);
        let mut players: Vec<(u64, usize)> = Vec::new();
        for state in &self.states {
            let player = state.player.expect("a turn-based state has a player");
            if players.iter().any(|&(p, _)| p == player) {
                continue;
            }
            if players.len() == 2 {
                return Err(lines.error(
                    state.line,
                    format!(
                        "a third player <{player}> (players <{}> and <{}> own earlier states): a \
                         game has two players, the defender and the adversary",
                        players[0].0, players[1].0
                    ),
                ));
            }
            players.push((player, state.line));
        }
        if !players.iter().any(|&(p, _)| p == defender) {
            let owners: Vec<String> = players.iter().map(|(p, _)| format!("<{p}>")).collect();
            return Err(options.player_error(
                lines.file_name,
                format!(
                    "the defender, player <{defender}>, owns no state (the states belong to {})",
                    owners.join(" and ")
                ),
            ));
        }
        Ok(Turns {
            defender_moves: self
                .states
                .iter()
                .map(|s| s.player == Some(defender))
                .collect(),
        })
    }

    /// One player's actions: the labels of its states' choices in order of
    /// first appearance, then [`IDLE`] if the other player owns some state.
    fn actions_of(
        &self,
        turns: &Turns,
        defender: bool,
        lines: &Lines,
    ) -> Result<Vec<String>, ModelError> {
        let mut actions: Vec<String> = Vec::new();
        let mut idles = false;
        for (k, state) in self.states.iter().enumerate() {
            if turns.defender_moves[k] != defender {
                idles = true;
                continue;
            }
            for choice in &state.choices {
                if choice.label == IDLE {
                    return Err(lines.error(
                        choice.line,
                        format!(
                            "the action label `{IDLE}` is reserved for the player who does not \
                             move in a state of a turn-based game; rename the command"
                        ),
                    ));
                }
                if !actions.contains(&choice.label) {
                    actions.push(choice.label.clone());
                }
            }
        }
        if idles {
            actions.push(IDLE.to_string());
        }
        Ok(actions)
    }

    /// The labels of state `k`'s choices as a row over `actions`, or only
    /// [`IDLE`] where the player does not move.
    fn enabled_row(&self, k: usize, moves: bool, actions: &[String]) -> Vec<bool> {
        let mut row = vec![false; actions.len()];
        if moves {
            for choice in &self.states[k].choices {
                row[position(actions, &choice.label)] = true;
            }
        } else {
            row[position(actions, IDLE)] = true;
        }
        row
    }

    /// A player who sees the state: its observations are the state names,
    /// each enabling the labels of the state's choices where it moves and
    /// [`IDLE`] elsewhere.
    fn fully_observing(
        &self,
        turns: &Turns,
        defender: bool,
        actions: Vec<String>,
        states: &[String],
    ) -> Player {
        let mut enabled = Vec::with_capacity(states.len() * actions.len());
        for k in 0..states.len() {
            enabled.extend(self.enabled_row(k, turns.defender_moves[k] == defender, &actions));
        }
        if enabled.iter().all(|&e| e) {
            enabled.clear();
        }
        Player {
            action_labels: self.action_labels(&actions),
            actions,
            observations: states.to_vec(),
            full_observation: true,
            observe: (0..states.len()).map(|k| vec![(k, 1.0)]).collect(),
            enabled,
        }
    }

    /// The defender of a POSMG: `o{k}` for the DRN observation `k` of its own
    /// states (in increasing order of `k`), each enabling the labels of those
    /// states' choices, which must agree; [`OPPONENT_MOVES`], enabling only
    /// [`IDLE`], in every state of the adversary.
    fn partially_observing_defender(
        &self,
        turns: &Turns,
        actions: Vec<String>,
        lines: &Lines,
    ) -> Result<Player, ModelError> {
        let mut ids: Vec<u64> = (0..self.states.len())
            .filter(|&k| turns.defender_moves[k])
            .filter_map(|k| self.states[k].observation)
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let mut observations: Vec<String> = ids.iter().map(|k| format!("o{k}")).collect();
        let opponent = turns.defender_moves.contains(&false).then(|| {
            observations.push(OPPONENT_MOVES.to_string());
            observations.len() - 1
        });
        let nu = actions.len();
        let mut enabled = vec![false; observations.len() * nu];
        let mut first_state: FxHashMap<usize, usize> = FxHashMap::default();
        let mut observe = Vec::with_capacity(self.states.len());
        for (k, state) in self.states.iter().enumerate() {
            let moves = turns.defender_moves[k];
            let o = match (moves, opponent) {
                (false, Some(o)) => o,
                _ => {
                    let id = state.observation.expect("a POSMG state has an observation");
                    ids.binary_search(&id).expect("every observation is listed")
                }
            };
            observe.push(vec![(o, 1.0)]);
            let row = self.enabled_row(k, moves, &actions);
            match first_state.get(&o) {
                None => {
                    enabled[o * nu..(o + 1) * nu].copy_from_slice(&row);
                    first_state.insert(o, k);
                }
                Some(&first) if enabled[o * nu..(o + 1) * nu] != row[..] => {
                    return Err(lines.error(
                        state.line,
                        format!(
                            "state {k} offers {{{}}}, but state {first} (line {}) with the same \
                             observation offers {{{}}}: the defender's states with one \
                             observation must offer the same actions",
                            self.offered(&row, &actions),
                            self.states[first].line,
                            self.offered(&enabled[o * nu..(o + 1) * nu], &actions)
                        ),
                    ));
                }
                Some(_) => {}
            }
        }
        if enabled.iter().all(|&e| e) {
            enabled.clear();
        }
        Ok(Player {
            action_labels: self.action_labels(&actions),
            actions,
            observations,
            full_observation: false,
            observe,
            enabled,
        })
    }

    /// `T(. | s, u, v)` for every triple: the choice's distribution where
    /// the mover plays one of its labels and the other player [`IDLE`],
    /// nothing elsewhere.
    #[allow(clippy::type_complexity)]
    fn transitions(
        &self,
        turns: &Turns,
        defender: &Player,
        adversary: &Player,
        lines: &Lines,
    ) -> Result<(Vec<usize>, Vec<(usize, f64)>), ModelError> {
        let (nu, nv) = (defender.num_actions(), adversary.num_actions());
        let mut offsets = Vec::with_capacity(self.states.len() * nu * nv + 1);
        offsets.push(0);
        let mut entries = Vec::new();
        for (k, state) in self.states.iter().enumerate() {
            let mut rows: Vec<Option<&Choice>> = vec![None; nu * nv];
            for choice in &state.choices {
                let (u, v) = joint_action(turns, k, choice, defender, adversary);
                rows[u * nv + v] = Some(choice);
            }
            for row in rows {
                if let Some(choice) = row {
                    let distribution =
                        normalised(&choice.successors).map_err(|m| lines.error(choice.line, m))?;
                    entries.extend(distribution);
                }
                offsets.push(entries.len());
            }
        }
        Ok((offsets, entries))
    }
}

/// The actions `(u, v)` the game plays for `choice` of state `k`: the
/// choice's label for the player who moves there, [`IDLE`] for the other.
fn joint_action(
    turns: &Turns,
    k: usize,
    choice: &Choice,
    defender: &Player,
    adversary: &Player,
) -> (usize, usize) {
    if turns.defender_moves[k] {
        (
            position(&defender.actions, &choice.label),
            position(&adversary.actions, IDLE),
        )
    } else {
        (
            position(&defender.actions, IDLE),
            position(&adversary.actions, &choice.label),
        )
    }
}

/// The index of `name` in `actions`, which lists it.
fn position(actions: &[String], name: &str) -> usize {
    actions
        .iter()
        .position(|a| a == name)
        .expect("the player's actions list every label of its states")
}
