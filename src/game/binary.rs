//! The optional binary form of a game, `*.posg.bin` (formats.md section 11):
//! the validated [`Posg`] written field by field in little-endian order, so
//! that large generated games are read at memory speed instead of parsed.
//!
//! [`super::file::read`] tells the two forms apart by [`MAGIC`]. Reading
//! checks everything the JSON reader checks (names, distributions, enabled
//! actions, one distribution for exactly the triples the game must define,
//! the size limits) and never trusts a count before the bytes it announces
//! are there: a truncated or corrupt file is a [`ModelError`] naming the
//! file, the part being read and the byte offset, never a panic.
//!
//! A game with action labels or reward models is written as version
//! [`EXTENDED_VERSION`], which appends them after the transitions; every
//! other game is written as version 1, byte for byte as before they existed.

use std::path::Path;

use rustc_hash::{FxHashMap, FxHashSet};

use crate::limits;

use super::reading::{
    FORMAT_VERSION, Located, action_label_problem, check_probability, index_names,
    is_valid_proposition, normalisation, pomdp_adversary, write_bytes,
};
use super::rewards::{RewardModel, invalid_reward_name, is_valid_reward_name};
use super::{Distribution, ModelError, Player, Posg};

/// The first eight bytes of a binary game file.
pub const MAGIC: [u8; 8] = *b"POSGBIN\0";

/// The version of the binary form that follows the transitions with the
/// players' action labels and the reward models (formats.md section 11).
pub const EXTENDED_VERSION: u32 = 2;

/// Whether the game needs [`EXTENDED_VERSION`]: it has reward models, or
/// actions renamed from their labels.
fn is_extended(game: &Posg) -> bool {
    !game.rewards.is_empty()
        || !game.defender.action_labels.is_empty()
        || !game.adversary.action_labels.is_empty()
}

/// Whether `bytes` start with [`MAGIC`] (a JSON text never does).
pub fn is_binary(bytes: &[u8]) -> bool {
    bytes.starts_with(&MAGIC)
}

/// The game in the binary form (formats.md section 11); [`from_bytes`]
/// reads it back to an equal [`Posg`].
pub fn to_bytes(game: &Posg) -> Vec<u8> {
    let entries = game.transition_entries.len();
    let mut out = Writer(Vec::with_capacity(
        64 + 16 * game.transition_offsets.len() + 12 * entries,
    ));
    out.0.extend_from_slice(&MAGIC);
    let extended = is_extended(game);
    out.u32(if extended {
        EXTENDED_VERSION
    } else {
        FORMAT_VERSION as u32
    });
    match &game.name {
        Some(name) => {
            out.u8(1);
            out.string(name);
        }
        None => out.u8(0),
    }
    out.strings(&game.states);
    out.distribution(&game.initial);
    out.strings(&game.propositions);
    for label in &game.labels {
        out.count(label.len());
        label.iter().for_each(|&p| out.u32(p as u32));
    }
    out.u8(u8::from(game.has_adversary));
    out.player(&game.defender);
    if game.has_adversary {
        out.player(&game.adversary);
    }
    for t in game.transition_offsets.windows(2) {
        out.distribution(&game.transition_entries[t[0]..t[1]]);
    }
    if extended {
        out.action_labels(&game.defender);
        if game.has_adversary {
            out.action_labels(&game.adversary);
        }
        out.count(game.rewards.len());
        for model in &game.rewards {
            out.reward_model(model, game.num_states());
        }
    }
    out.0
}

/// Writes the game to `path` in the binary form.
pub fn write(path: &Path, game: &Posg) -> Result<(), ModelError> {
    write_bytes(path, &to_bytes(game))
}

/// Reads and validates a game in the binary form; `file_name` prefixes the
/// path of every error.
pub fn from_bytes(bytes: &[u8], file_name: &str) -> Result<Posg, ModelError> {
    let mut r = Reader {
        bytes,
        pos: 0,
        file_name,
    };
    let at = r.at("");
    if !is_binary(bytes) {
        return Err(at.error("not a binary game (the file does not start with POSGBIN)"));
    }
    r.pos = MAGIC.len();
    let version = r.u32(&at)?;
    if u64::from(version) != FORMAT_VERSION && version != EXTENDED_VERSION {
        return Err(r.at("posg").error(format!(
            "unsupported format version {version} (expected {FORMAT_VERSION} or {EXTENDED_VERSION})"
        )));
    }
    let name = match r.flag(&r.at("name"))? {
        true => Some(r.string(&r.at("name"))?),
        false => None,
    };
    let states = r.strings(&r.at("states"))?;
    index_names(&states, &r.at("states"), "state")?;
    let initial = r.distribution(&r.at("initial"), states.len(), "state")?;
    let (propositions, labels) = r.labels(states.len())?;
    let has_adversary = r.flag(&r.at("adversary"))?;
    let defender = r.player(&r.at("defender"), &states)?;
    let adversary = match has_adversary {
        true => r.player(&r.at("adversary"), &states)?,
        false => pomdp_adversary(states.len()),
    };
    let mut game = Posg {
        name,
        states,
        initial,
        propositions,
        labels,
        defender,
        adversary,
        has_adversary,
        transition_offsets: Vec::new(),
        transition_entries: Vec::new(),
        rewards: Vec::new(),
    };
    r.transitions(&mut game)?;
    if version == EXTENDED_VERSION {
        r.extension(&mut game)?;
    }
    if r.pos != bytes.len() {
        return Err(at.error(format!(
            "{} bytes after the end of the game (byte {})",
            bytes.len() - r.pos,
            r.pos
        )));
    }
    Ok(game)
}

/// Appends the little-endian fields of formats.md section 11.
struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, value: u8) {
        self.0.push(value);
    }

    fn u32(&mut self, value: u32) {
        self.0.extend_from_slice(&value.to_le_bytes());
    }

    /// A count; every count of a valid game fits in a `u32` (limits.rs).
    fn count(&mut self, n: usize) {
        self.u32(u32::try_from(n).expect("counts of a game fit in 32 bits"));
    }

    fn string(&mut self, s: &str) {
        self.count(s.len());
        self.0.extend_from_slice(s.as_bytes());
    }

    fn strings(&mut self, names: &[String]) {
        self.count(names.len());
        names.iter().for_each(|n| self.string(n));
    }

    fn distribution(&mut self, d: &[(usize, f64)]) {
        self.count(d.len());
        for &(outcome, p) in d {
            self.u32(outcome as u32);
            self.0.extend_from_slice(&p.to_le_bytes());
        }
    }

    fn player(&mut self, player: &Player) {
        self.strings(&player.actions);
        self.strings(&player.observations);
        self.u8(u8::from(player.full_observation));
        if !player.full_observation {
            player.observe.iter().for_each(|d| self.distribution(d));
        }
        self.u8(u8::from(!player.enabled.is_empty()));
        self.0.extend(player.enabled.iter().map(|&e| u8::from(e)));
    }

    fn f64(&mut self, value: f64) {
        self.0.extend_from_slice(&value.to_le_bytes());
    }

    fn action_labels(&mut self, player: &Player) {
        self.count(player.action_labels.len());
        for (u, label) in &player.action_labels {
            self.u32(*u as u32);
            self.string(label);
        }
    }

    fn reward_model(&mut self, model: &RewardModel, num_states: usize) {
        self.string(model.name());
        self.u8(u8::from(model.has_state_rewards()));
        if model.has_state_rewards() {
            let mut given = model.state_rewards().peekable();
            for s in 0..num_states {
                let reward = given.next_if(|&(t, _)| t == s).map_or(0.0, |(_, r)| r);
                self.f64(reward);
            }
        }
        let rewards = model.action_rewards_by_triple();
        self.count(rewards.len());
        for &(triple, reward) in rewards {
            self.u32(triple as u32);
            self.f64(reward);
        }
    }
}

/// Reads the fields of formats.md section 11 from `bytes`, checking that
/// every one is there before it is read.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    file_name: &'a str,
}

/// Bytes of one `(outcome, probability)` entry: `u32` and `f64`.
const ENTRY_BYTES: usize = 12;

impl<'a> Reader<'a> {
    fn at(&self, path: &str) -> Located<'a> {
        Located::new(self.file_name, path)
    }

    /// The next `n` bytes; an error at `at` when the file ends first.
    fn take(&mut self, n: usize, at: &Located) -> Result<&'a [u8], ModelError> {
        let remaining = self.bytes.len() - self.pos;
        if n > remaining {
            return Err(at.error(format!(
                "the file ends early: {n} bytes needed at byte {}, {remaining} left",
                self.pos
            )));
        }
        let bytes = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(bytes)
    }

    fn u8(&mut self, at: &Located) -> Result<u8, ModelError> {
        Ok(self.take(1, at)?[0])
    }

    fn flag(&mut self, at: &Located) -> Result<bool, ModelError> {
        match self.u8(at)? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(at.error(format!("byte {} is {b}, expected 0 or 1", self.pos - 1))),
        }
    }

    fn u32(&mut self, at: &Located) -> Result<u32, ModelError> {
        let bytes = self.take(4, at)?;
        Ok(u32::from_le_bytes(bytes.try_into().expect("4 bytes")))
    }

    fn f64(&mut self, at: &Located) -> Result<f64, ModelError> {
        let bytes = self.take(8, at)?;
        Ok(f64::from_le_bytes(bytes.try_into().expect("8 bytes")))
    }

    /// A count of items of at least `item_bytes` bytes each, checked against
    /// the bytes left so that a corrupt count never allocates.
    fn count(&mut self, item_bytes: usize, at: &Located) -> Result<usize, ModelError> {
        let n = self.u32(at)? as usize;
        let remaining = self.bytes.len() - self.pos;
        if n.saturating_mul(item_bytes) > remaining {
            return Err(at.error(format!(
                "the file ends early: {n} items announced at byte {}, only {remaining} bytes left",
                self.pos - 4
            )));
        }
        Ok(n)
    }

    fn string(&mut self, at: &Located) -> Result<String, ModelError> {
        let n = self.count(1, at)?;
        let start = self.pos;
        let bytes = self.take(n, at)?;
        std::str::from_utf8(bytes)
            .map(str::to_string)
            .map_err(|_| at.error(format!("the string at byte {start} is not UTF-8")))
    }

    fn strings(&mut self, at: &Located) -> Result<Vec<String>, ModelError> {
        let n = self.count(4, at)?;
        (0..n).map(|i| self.string(&at.index(i))).collect()
    }

    /// A distribution over `0..num_outcomes` (`kind` names them): outcomes
    /// strictly increasing, probabilities positive, in [0, 1] and summing to
    /// 1 (renormalised as the JSON reader does).
    fn distribution(
        &mut self,
        at: &Located,
        num_outcomes: usize,
        kind: &str,
    ) -> Result<Distribution, ModelError> {
        let mut d = Vec::new();
        if self.distribution_into(at, num_outcomes, kind, &mut d)? == 0 {
            normalisation(0.0, 0, at)?;
        }
        Ok(d)
    }

    /// [`Reader::distribution`] appended to `out`; returns its length. An
    /// empty distribution is left to the caller (no normalisation).
    fn distribution_into(
        &mut self,
        at: &Located,
        num_outcomes: usize,
        kind: &str,
        out: &mut Distribution,
    ) -> Result<usize, ModelError> {
        let n = self.count(ENTRY_BYTES, at)?;
        if n == 0 {
            return Ok(0);
        }
        let bytes = self.take(n * ENTRY_BYTES, at)?;
        let start = out.len();
        out.reserve(n);
        let mut total = 0.0;
        let mut previous = None;
        for entry in bytes.chunks_exact(ENTRY_BYTES) {
            let outcome = u32::from_le_bytes(entry[..4].try_into().expect("4 bytes")) as usize;
            let p = f64::from_le_bytes(entry[4..].try_into().expect("8 bytes"));
            if outcome >= num_outcomes {
                return Err(at.error(format!(
                    "{kind} {outcome} out of range (there are {num_outcomes})"
                )));
            }
            if previous.is_some_and(|q| q >= outcome) {
                return Err(at.error(format!(
                    "{kind}s are not strictly increasing ({kind} {outcome} after {})",
                    previous.unwrap_or(0)
                )));
            }
            check_probability(p, at)?;
            if p == 0.0 {
                return Err(at.error(format!("probability 0 for {kind} {outcome}")));
            }
            previous = Some(outcome);
            total += p;
            out.push((outcome, p));
        }
        if let Some(total) = normalisation(total, n, at)? {
            out[start..].iter_mut().for_each(|(_, p)| *p /= total);
        }
        Ok(n)
    }

    /// The sorted propositions, each labelling some state, and each
    /// state's label as strictly increasing indices into them.
    #[allow(clippy::type_complexity)]
    fn labels(&mut self, num_states: usize) -> Result<(Vec<String>, Vec<Vec<usize>>), ModelError> {
        let at = self.at("labels");
        let at_p = self.at("propositions");
        let propositions = self.strings(&at_p)?;
        for (i, p) in propositions.iter().enumerate() {
            if !is_valid_proposition(p) {
                return Err(at_p.index(i).error(format!(
                    "`{p}` is not a valid proposition (expected [a-z_][a-z0-9_]*)"
                )));
            }
            if i > 0 && propositions[i - 1] >= *p {
                return Err(at_p
                    .index(i)
                    .error("propositions are not sorted and unique"));
            }
        }
        let mut used = vec![false; propositions.len()];
        let mut labels = Vec::with_capacity(num_states.min(self.bytes.len()));
        for s in 0..num_states {
            let label = self
                .label(&at, propositions.len())
                .map_err(|e| at.index(s).error(e.message))?;
            label.iter().for_each(|&p| used[p] = true);
            labels.push(label);
        }
        if let Some(p) = used.iter().position(|&u| !u) {
            return Err(at_p
                .index(p)
                .error(format!("proposition `{}` labels no state", propositions[p])));
        }
        Ok((propositions, labels))
    }

    /// One state's label: strictly increasing indices below `num_propositions`.
    fn label(&mut self, at: &Located, num_propositions: usize) -> Result<Vec<usize>, ModelError> {
        let n = self.count(4, at)?;
        let mut label = Vec::with_capacity(n);
        for _ in 0..n {
            let p = self.u32(at)? as usize;
            if p >= num_propositions || label.last().is_some_and(|&q| q >= p) {
                return Err(at.error(format!(
                    "proposition {p} out of range or not strictly increasing"
                )));
            }
            label.push(p);
        }
        Ok(label)
    }

    fn player(&mut self, at: &Located, states: &[String]) -> Result<Player, ModelError> {
        let actions = self.strings(&at.key("actions"))?;
        index_names(&actions, &at.key("actions"), "action")?;
        if actions.is_empty() {
            return Err(at
                .key("actions")
                .error("a player needs at least one action"));
        }
        let observations = self.strings(&at.key("observations"))?;
        let index = index_names(&observations, &at.key("observations"), "observation")?;
        let full_observation = self.flag(&at.key("observe"))?;
        let here = at.key("observe");
        let observe = if full_observation {
            states
                .iter()
                .map(|s| {
                    let o = index.get(s.as_str()).copied().ok_or_else(|| {
                        here.error(format!(
                            "with full observation every state is an observation; `{s}` is missing"
                        ))
                    })?;
                    Ok(vec![(o, 1.0)])
                })
                .collect::<Result<Vec<_>, ModelError>>()?
        } else {
            let mut observe = Vec::with_capacity(states.len().min(self.bytes.len()));
            for s in 0..states.len() {
                let d = self
                    .distribution(&here, observations.len(), "observation")
                    .map_err(|e| here.index(s).error(e.message))?;
                observe.push(d);
            }
            observe
        };
        let enabled = self.enabled(&at.key("enabled"), observations.len(), actions.len())?;
        Ok(Player {
            actions,
            observations,
            full_observation,
            observe,
            enabled,
            action_labels: Vec::new(),
        })
    }

    /// The dense table of enabled actions: absent (all enabled), or one
    /// byte 0/1 per observation and action with a 1 in every row.
    fn enabled(
        &mut self,
        at: &Located,
        num_observations: usize,
        num_actions: usize,
    ) -> Result<Vec<bool>, ModelError> {
        if !self.flag(at)? {
            return Ok(Vec::new());
        }
        let size = num_observations.saturating_mul(num_actions);
        let start = self.pos;
        let bytes = self.take(size, at)?;
        if let Some(i) = bytes.iter().position(|&b| b > 1) {
            return Err(at.error(format!(
                "byte {} is {}, expected 0 or 1",
                start + i,
                bytes[i]
            )));
        }
        if let Some(o) = bytes.chunks(num_actions).position(|row| !row.contains(&1)) {
            return Err(at
                .index(o)
                .error("an observation needs at least one enabled action"));
        }
        let table: Vec<bool> = bytes.iter().map(|&b| b == 1).collect();
        Ok(if table.iter().all(|&e| e) {
            Vec::new()
        } else {
            table
        })
    }

    /// One distribution per triple `(s, u, v)` in the order of
    /// [`Posg::transition`]: over states when the game must define the
    /// triple, empty otherwise.
    fn transitions(&mut self, game: &mut Posg) -> Result<(), ModelError> {
        let at = self.at("transitions");
        let (ns, nu, nv) = (
            game.states.len(),
            game.defender.num_actions(),
            game.adversary.num_actions(),
        );
        if let Some(message) = limits::transition_triples(ns, nu, nv) {
            return Err(at.error(message));
        }
        let triples = ns * nu * nv;
        if triples.saturating_mul(4) > self.bytes.len() - self.pos {
            return Err(at.error(format!(
                "the file ends early: {triples} triples need at least {} bytes at byte {}",
                triples * 4,
                self.pos
            )));
        }
        let mut offsets = Vec::with_capacity(triples + 1);
        let mut entries = Vec::with_capacity((self.bytes.len() - self.pos) / ENTRY_BYTES);
        offsets.push(0);
        for s in 0..ns {
            for u in 0..nu {
                for v in 0..nv {
                    let t = offsets.len() - 1;
                    let n = self
                        .distribution_into(&at, ns, "state", &mut entries)
                        .map_err(|e| at.index(t).error(e.message))?;
                    let required = super::reading::triple_required(game, s, u, v);
                    if required != (n > 0) {
                        return Err(at.index(t).error(triple_mismatch(game, required, s, u, v)));
                    }
                    if let Some(message) = limits::exceeded(
                        "the transitions",
                        entries.len() as u128,
                        limits::MAX_TRANSITION_ENTRIES,
                        "entries or more",
                        "MAX_TRANSITION_ENTRIES",
                    ) {
                        return Err(at.error(message));
                    }
                    offsets.push(entries.len());
                }
            }
        }
        game.transition_offsets = offsets;
        game.transition_entries = entries;
        Ok(())
    }
}

/// `(state `s`, defender `u`, adversary `v`)` with the names of the game.
fn triple_text(game: &Posg, s: usize, u: usize, v: usize) -> String {
    format!(
        "(state `{}`, defender `{}`, adversary `{}`)",
        game.states[s], game.defender.actions[u], game.adversary.actions[v]
    )
}

/// Why the distribution of triple `(s, u, v)` is wrong: missing for a triple
/// the game must define, or present for one it must not.
fn triple_mismatch(game: &Posg, required: bool, s: usize, u: usize, v: usize) -> String {
    let triple = triple_text(game, s, u, v);
    if required {
        format!("no distribution for {triple}")
    } else {
        format!("a distribution for {triple}, whose actions no observation of the state enables")
    }
}

impl Reader<'_> {
    /// What [`EXTENDED_VERSION`] adds after the transitions: the players'
    /// action labels, then the reward models, each name once.
    fn extension(&mut self, game: &mut Posg) -> Result<(), ModelError> {
        let at = self.at("defender").key("action_labels");
        game.defender.action_labels = self.action_labels(&at, &game.defender.actions)?;
        if game.has_adversary {
            let at = self.at("adversary").key("action_labels");
            game.adversary.action_labels = self.action_labels(&at, &game.adversary.actions)?;
        }
        let at = self.at("rewards");
        let n = self.count(REWARD_MODEL_BYTES, &at)?;
        let mut models: Vec<RewardModel> = Vec::with_capacity(n.min(RESERVED_FROM_COUNT));
        let mut names = FxHashSet::default();
        for i in 0..n {
            let model = self.reward_model(&at.index(i), game)?;
            if !names.insert(model.name().to_string()) {
                return Err(at
                    .index(i)
                    .error(format!("reward model `{}` appears twice", model.name())));
            }
            models.push(model);
        }
        game.rewards = models;
        Ok(())
    }

    /// A player's action labels: `(u, label)` with `u` strictly increasing
    /// below `|actions|`, each label as formats.md section 6 allows.
    fn action_labels(
        &mut self,
        at: &Located,
        actions: &[String],
    ) -> Result<Vec<(usize, String)>, ModelError> {
        let n = self.count(8, at)?;
        let mut labels: Vec<(usize, String)> = Vec::with_capacity(n.min(RESERVED_FROM_COUNT));
        let mut seen: FxHashMap<String, usize> = FxHashMap::default();
        for i in 0..n {
            let here = at.index(i);
            let u = self.u32(&here)? as usize;
            let label = self.string(&here)?;
            if u >= actions.len() || labels.last().is_some_and(|&(p, _)| p >= u) {
                return Err(here.error(format!(
                    "action {u} out of range or not strictly increasing"
                )));
            }
            if let Some(problem) = action_label_problem(actions, &seen, &label) {
                return Err(here.error(problem));
            }
            seen.insert(label.clone(), u);
            labels.push((u, label));
        }
        Ok(labels)
    }

    /// One reward model: its name, its state rewards (a flag, then one
    /// finite `f64` per state) and its action rewards.
    fn reward_model(&mut self, at: &Located, game: &Posg) -> Result<RewardModel, ModelError> {
        let name = self.string(at)?;
        if !is_valid_reward_name(&name) {
            return Err(at.error(invalid_reward_name(&name)));
        }
        let here = self.at("rewards").key(&name);
        let states = match self.flag(&here.key("states"))? {
            true => self.finite_values(game.num_states(), &here.key("states"))?,
            false => Vec::new(),
        };
        let states = states.into_iter().enumerate().filter(|&(_, r)| r != 0.0);
        let actions = self.action_rewards(&here.key("actions"), game)?;
        let num_actions = (game.defender.num_actions(), game.adversary.num_actions());
        Ok(RewardModel::new(
            name,
            states.collect(),
            actions,
            num_actions,
        ))
    }

    /// `n` finite `f64`s (rewards), value `i` at `at[i]`.
    fn finite_values(&mut self, n: usize, at: &Located) -> Result<Vec<f64>, ModelError> {
        let bytes = self.take(n.saturating_mul(8), at)?;
        bytes
            .chunks_exact(8)
            .enumerate()
            .map(|(i, b)| {
                finite(
                    f64::from_le_bytes(b.try_into().expect("8 bytes")),
                    &at.index(i),
                )
            })
            .collect()
    }

    /// A count and that many `(u32 triple, f64 reward)`: triples strictly
    /// increasing, each one the game defines, rewards finite.
    fn action_rewards(
        &mut self,
        at: &Located,
        game: &Posg,
    ) -> Result<Vec<(usize, f64)>, ModelError> {
        let n = self.count(ENTRY_BYTES, at)?;
        let (nu, nv) = (game.defender.num_actions(), game.adversary.num_actions());
        let triples = game.num_states() * nu * nv;
        let mut rewards: Vec<(usize, f64)> = Vec::with_capacity(n);
        for i in 0..n {
            let here = at.index(i);
            let t = self.u32(&here)? as usize;
            let reward = finite(self.f64(&here)?, &here)?;
            if t >= triples || rewards.last().is_some_and(|&(p, _)| p >= t) {
                return Err(here.error(format!(
                    "triple {t} out of range or not strictly increasing"
                )));
            }
            let (s, u, v) = (t / (nu * nv), t / nv % nu, t % nv);
            if !super::reading::triple_required(game, s, u, v) {
                return Err(here.error(format!(
                    "a reward for {}, whose actions no observation of the state enables",
                    triple_text(game, s, u, v)
                )));
            }
            rewards.push((t, reward));
        }
        Ok(rewards)
    }
}

/// The fewest bytes of a reward model: an empty name (`u32`), the state
/// rewards' flag and the action rewards' count.
const REWARD_MODEL_BYTES: usize = 9;

/// The most items room is reserved for from a count the file gives, where
/// an item takes much more memory than its least bytes in the file (a
/// reward model, an action label): more grow as they are read, so a count
/// the file's bytes do not back allocates nothing.
const RESERVED_FROM_COUNT: usize = 16;

/// `value` if it is finite (a reward), else an error at `at`.
fn finite(value: f64, at: &Located) -> Result<f64, ModelError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(at.error(format!("reward {value} is not finite")))
    }
}
