//! Reading and writing controllers as `*.fsc.json` (formats.md section 2),
//! and the command-line shorthand `uniform:K`.
//!
//! A controller file names observations and actions; they are resolved
//! against the player of the game it is used with, so reading needs the game
//! and the [`Role`]. Errors are [`ModelError`]s at `FILE: JSON.path`, as for
//! game files ([`crate::game::file`]).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{Choice, Fsc, Role};
use crate::game::reading::{Located, check_probability, normalise, parse, read_text, write_text};
use crate::game::{ModelError, Player, Posg};

/// The only format version this crate reads and writes (`"fsc": 1`).
pub const FORMAT_VERSION: u64 = 1;

/// Reads and validates the controller file at `path` for `role` in `game`
/// (formats.md section 2).
pub fn read(path: &Path, game: &Posg, role: Role) -> Result<Fsc, ModelError> {
    let file_name = path.display().to_string();
    let text = read_text(path, &file_name)?;
    from_json_str(&text, &file_name, game, role)
}

/// Parses and validates a controller for `role` in `game` from JSON `text`
/// (formats.md section 2); `file_name` prefixes the path of every error.
pub fn from_json_str(
    text: &str,
    file_name: &str,
    game: &Posg,
    role: Role,
) -> Result<Fsc, ModelError> {
    let raw: RawFsc = parse(text, file_name)?;
    build(raw, &Located::new(file_name, ""), role.player(game), role)
}

/// Reads the controller file at `path` for whichever player of `game` its
/// `player` field names (formats.md section 2).
pub fn read_either(path: &Path, game: &Posg) -> Result<Fsc, ModelError> {
    let file_name = path.display().to_string();
    let text = read_text(path, &file_name)?;
    let raw: RawFsc = parse(&text, &file_name)?;
    let role = raw.player;
    build(raw, &Located::new(&file_name, ""), role.player(game), role)
}

/// A controller read without its game, with the observation and action
/// names its file uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Standalone {
    /// The controller, over the observations and actions below.
    pub fsc: Fsc,
    /// The observations the rules name, in order of first appearance.
    pub observations: Vec<String>,
    /// The actions the choices name, in order of first appearance.
    pub actions: Vec<String>,
}

/// Reads the controller file at `path` without its game (for pictures):
/// the player's observations and actions are taken to be those the file
/// names. A file with `"default": "uniform"` needs its game (the actions of
/// the missing rules are not in the file), so it is an error here.
pub fn read_standalone(path: &Path) -> Result<Standalone, ModelError> {
    let file_name = path.display().to_string();
    let text = read_text(path, &file_name)?;
    let raw: RawFsc = parse(&text, &file_name)?;
    let at = Located::new(&file_name, "");
    if raw.default == MissingRule::Uniform {
        return Err(at.key("default").error(
            "with \"default\": \"uniform\" the controller can only be read with its game (--game)",
        ));
    }
    let mut observations: Vec<String> = Vec::new();
    let mut actions: Vec<String> = Vec::new();
    for rule in &raw.rules {
        if !observations.contains(&rule.observation) {
            observations.push(rule.observation.clone());
        }
        for c in &rule.choices {
            if !actions.contains(&c.action) {
                actions.push(c.action.clone());
            }
        }
    }
    let player = Player::named(actions.clone(), observations.clone());
    let role = raw.player;
    let fsc = build(raw, &at, &player, role)?;
    Ok(Standalone {
        fsc,
        observations,
        actions,
    })
}

/// The controller as pretty-printed JSON naming `game`'s observations and
/// actions: one rule per (node, observation), `"default": "error"`, the
/// `logit` of every choice that has one.
pub fn to_json_string(fsc: &Fsc, game: &Posg) -> String {
    let raw = RawFsc::from_fsc(fsc, fsc.role.player(game));
    serde_json::to_string_pretty(&raw).expect("a controller always serialises")
}

/// Writes the controller to `path` as [`to_json_string`] does.
pub fn write(path: &Path, fsc: &Fsc, game: &Posg) -> Result<(), ModelError> {
    write_text(path, &to_json_string(fsc, game))
}

/// The controller a command-line argument names: `uniform:K` is
/// [`Fsc::uniform_enabled`] with `K >= 1` nodes (uniform over the enabled
/// actions); anything else is a file path read with [`read`]. For a POMDP
/// the adversary's `uniform:1` is the trivial controller.
pub fn resolve(spec: &str, game: &Posg, role: Role) -> Result<Fsc, ModelError> {
    let Some(size) = spec.strip_prefix("uniform:") else {
        return read(Path::new(spec), game, role);
    };
    let nodes = size
        .parse::<usize>()
        .ok()
        .filter(|&k| k >= 1)
        .ok_or_else(|| {
            ModelError::new(
                spec,
                format!("`uniform:K` needs a whole number K >= 1, not `{size}`"),
            )
        })?;
    let p = role.player(game);
    Fsc::check_uniform_size(spec, nodes, p.num_observations(), p.num_actions())?;
    if role == Role::Adversary && !game.has_adversary() && nodes != 1 {
        return Err(ModelError::new(
            spec,
            "the game has no adversary (it is a POMDP), whose controller is the trivial \
             `uniform:1`; drop --adversary",
        ));
    }
    Ok(Fsc::uniform_enabled(role, nodes, p))
}

/// The top-level object of a `*.fsc.json` file.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawFsc {
    fsc: u64,
    player: Role,
    nodes: usize,
    initial: Vec<f64>,
    rules: Vec<RawRule>,
    #[serde(default)]
    default: MissingRule,
}

/// What a (node, observation) pair without a rule means.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
enum MissingRule {
    #[default]
    Error,
    Uniform,
}

/// One entry of `rules`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawRule {
    node: usize,
    observation: String,
    choices: Vec<RawChoice>,
}

/// One entry of a rule's `choices`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawChoice {
    next: usize,
    action: String,
    p: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    logit: Option<f64>,
}

fn build(raw: RawFsc, at: &Located, player: &Player, role: Role) -> Result<Fsc, ModelError> {
    if raw.fsc != FORMAT_VERSION {
        return Err(at.key("fsc").error(format!(
            "unsupported format version {} (expected {FORMAT_VERSION})",
            raw.fsc
        )));
    }
    if raw.player != role {
        return Err(at.key("player").error(format!(
            "the file's player is `{}`, but a controller for the `{}` is needed",
            raw.player.name(),
            role.name()
        )));
    }
    if raw.nodes == 0 {
        return Err(at
            .key("nodes")
            .error("a controller needs at least one node"));
    }
    let initial = initial(&raw.initial, raw.nodes, &at.key("initial"))?;
    let blocks = blocks(&raw, &at.key("rules"), player).map_err(|mut error| {
        if let Some(foreign) = foreign_names(&raw, player, role) {
            error.message = format!("{}; {foreign}", error.message);
        }
        error
    })?;
    Fsc::new(
        role,
        raw.nodes,
        player.num_observations(),
        player.num_actions(),
        initial,
        blocks,
    )
}

/// Where the rules use more than one observation or action name that
/// `player` does not have (a controller written for another game): a
/// sentence listing them (the first [`LISTED_NAMES`] of each kind, with
/// their count) beside the player's own.
fn foreign_names(raw: &RawFsc, player: &Player, role: Role) -> Option<String> {
    let foreign = |used: &mut dyn Iterator<Item = &str>, own: &[String], kind: &str| {
        let mut seen: Vec<&str> = Vec::new();
        for name in used {
            if index_of(own, name).is_none() && !seen.contains(&name) {
                seen.push(name);
            }
        }
        (!seen.is_empty()).then(|| {
            let own: Vec<&str> = own.iter().map(String::as_str).collect();
            let sentence = format!(
                "{} not the {}'s ({}); its {kind}s are {}",
                crate::output::counted(seen.len(), kind),
                role.name(),
                listed(&seen),
                listed(&own)
            );
            (seen.len(), sentence)
        })
    };
    let observations = &mut raw.rules.iter().map(|r| r.observation.as_str());
    let actions = &mut (raw.rules.iter())
        .flat_map(|r| &r.choices)
        .map(|c| c.action.as_str());
    let problems: Vec<(usize, String)> = [
        foreign(observations, player.observations(), "observation"),
        foreign(actions, player.actions(), "action"),
    ]
    .into_iter()
    .flatten()
    .collect();
    let count: usize = problems.iter().map(|(n, _)| n).sum();
    (count > 1).then(|| {
        let sentences: Vec<String> = problems.into_iter().map(|(_, s)| s).collect();
        format!(
            "the controller does not fit this game (written for another?): {}",
            sentences.join("; ")
        )
    })
}

/// How many names of a kind an error lists.
const LISTED_NAMES: usize = 5;

/// `a, b, c, d, e and 12 more`.
fn listed(names: &[&str]) -> String {
    let shown: Vec<String> = (names.iter().take(LISTED_NAMES))
        .map(|n| format!("`{n}`"))
        .collect();
    match names.len().saturating_sub(LISTED_NAMES) {
        0 => shown.join(", "),
        more => format!("{} and {more} more", shown.join(", ")),
    }
}

fn initial(raw: &[f64], nodes: usize, at: &Located) -> Result<Vec<f64>, ModelError> {
    if raw.len() != nodes {
        return Err(at.error(format!(
            "{} entries for {nodes} nodes (one probability per node is needed)",
            raw.len()
        )));
    }
    for (g, &p) in raw.iter().enumerate() {
        check_probability(p, &at.index(g))?;
    }
    let mut initial = raw.to_vec();
    normalise(&mut initial, at)?;
    Ok(initial)
}

/// One block per (node, observation), in the order `g * |O| + o`.
fn blocks(raw: &RawFsc, at: &Located, player: &Player) -> Result<Vec<Vec<Choice>>, ModelError> {
    let num_obs = player.num_observations();
    if let Some(message) = crate::limits::exceeded(
        &format!("{} nodes x {num_obs} observations", raw.nodes),
        raw.nodes as u128 * num_obs as u128,
        crate::limits::MAX_CONTROLLER_CHOICES,
        "rules",
        "MAX_CONTROLLER_CHOICES",
    ) {
        return Err(at.error(message));
    }
    let mut blocks: Vec<Option<Vec<Choice>>> = vec![None; raw.nodes * num_obs];
    for (i, rule) in raw.rules.iter().enumerate() {
        let here = at.index(i);
        let (g, o) = rule_key(rule, raw.nodes, &here, player)?;
        if blocks[g * num_obs + o].is_some() {
            return Err(here.error(format!(
                "a second rule for node {g}, observation `{}`",
                rule.observation
            )));
        }
        blocks[g * num_obs + o] = Some(choices(rule, o, raw.nodes, &here.key("choices"), player)?);
    }
    let missing = blocks.iter().filter(|b| b.is_none()).count();
    if missing > 0 && raw.default == MissingRule::Uniform {
        let choices =
            (missing as u128).saturating_mul(raw.nodes as u128 * player.num_actions() as u128);
        if let Some(message) = crate::limits::exceeded(
            &format!(
                "{missing} uniform rules of {} choices each",
                raw.nodes * player.num_actions()
            ),
            choices,
            crate::limits::MAX_CONTROLLER_CHOICES,
            "choices",
            "MAX_CONTROLLER_CHOICES",
        ) {
            return Err(at.error(message));
        }
    }
    blocks
        .into_iter()
        .enumerate()
        .map(|(b, block)| match (block, raw.default) {
            (Some(block), _) => Ok(block),
            (None, MissingRule::Uniform) => Ok(uniform_block(raw.nodes, player, b % num_obs)),
            (None, MissingRule::Error) => Err(at.error(format!(
                "no rule for node {}, observation `{}` (and \"default\" is \"error\")",
                b / num_obs,
                player.observations()[b % num_obs]
            ))),
        })
        .collect()
}

/// The block uniform over the pairs `(next node, action)` with the action
/// enabled under observation `o`.
fn uniform_block(nodes: usize, player: &Player, o: usize) -> Vec<Choice> {
    let actions: Vec<usize> = (0..player.num_actions())
        .filter(|&u| player.action_enabled(o, u))
        .collect();
    let probability = 1.0 / (nodes * actions.len()) as f64;
    (0..nodes)
        .flat_map(|next| {
            actions.iter().map(move |&action| Choice {
                next,
                action,
                probability,
                logit: None,
            })
        })
        .collect()
}

/// `(node, observation index)` of a rule.
fn rule_key(
    rule: &RawRule,
    nodes: usize,
    at: &Located,
    player: &Player,
) -> Result<(usize, usize), ModelError> {
    if rule.node >= nodes {
        return Err(at.key("node").error(format!(
            "node {} is out of range (the controller has {nodes} nodes)",
            rule.node
        )));
    }
    let o = index_of(player.observations(), &rule.observation).ok_or_else(|| {
        at.key("observation").error(format!(
            "unknown observation `{}` of the player",
            rule.observation
        ))
    })?;
    Ok((rule.node, o))
}

/// A rule's choices: checked, renormalised, zero-probability choices
/// dropped; a positive probability on an action that the rule's observation
/// does not enable is an error (formats.md section 6).
fn choices(
    rule: &RawRule,
    observation: usize,
    nodes: usize,
    at: &Located,
    player: &Player,
) -> Result<Vec<Choice>, ModelError> {
    let mut choices: Vec<Choice> = Vec::with_capacity(rule.choices.len());
    for (j, c) in rule.choices.iter().enumerate() {
        let here = at.index(j);
        if c.next >= nodes {
            return Err(here.key("next").error(format!(
                "node {} is out of range (the controller has {nodes} nodes)",
                c.next
            )));
        }
        let action = index_of(player.actions(), &c.action).ok_or_else(|| {
            here.key("action")
                .error(format!("unknown action `{}` of the player", c.action))
        })?;
        if let Some(k) = choices
            .iter()
            .position(|d| (d.next, d.action) == (c.next, action))
        {
            return Err(here.error(format!(
                "(next {}, action `{}`) is already listed at {}[{k}]",
                c.next,
                c.action,
                at.path()
            )));
        }
        check_probability(c.p, &here.key("p"))?;
        if c.p > 0.0 && !player.action_enabled(observation, action) {
            return Err(here.key("action").error(format!(
                "action `{}` is not enabled under observation `{}` (the game's `enabled` map)",
                c.action, rule.observation
            )));
        }
        choices.push(Choice {
            next: c.next,
            action,
            probability: c.p,
            logit: c.logit,
        });
    }
    let mut weights: Vec<f64> = choices.iter().map(|c| c.probability).collect();
    normalise(&mut weights, at)?;
    for (c, w) in choices.iter_mut().zip(weights) {
        c.probability = w;
    }
    choices.retain(|c| c.probability > 0.0);
    Ok(choices)
}

fn index_of(names: &[String], name: &str) -> Option<usize> {
    names.iter().position(|n| n == name)
}

impl RawFsc {
    fn from_fsc(fsc: &Fsc, player: &Player) -> Self {
        let rules = (0..fsc.num_nodes)
            .flat_map(|g| (0..fsc.num_observations).map(move |o| (g, o)))
            .map(|(g, o)| RawRule {
                node: g,
                observation: player.observations()[o].clone(),
                choices: fsc
                    .choices(g, o)
                    .iter()
                    .map(|c| RawChoice {
                        next: c.next,
                        action: player.actions()[c.action].clone(),
                        p: c.probability,
                        logit: c.logit,
                    })
                    .collect(),
            })
            .collect();
        Self {
            fsc: FORMAT_VERSION,
            player: fsc.role,
            nodes: fsc.num_nodes,
            initial: fsc.initial.clone(),
            rules,
            default: MissingRule::Error,
        }
    }
}
