//! Reading and writing games as `*.posg.json` (formats.md section 1).
//!
//! Reading is two passes. [`serde_path_to_error`] first parses the text into
//! plain serde types that mirror the file (`RawGame` and friends): unknown
//! fields, duplicate keys and wrong JSON types fail here, with the JSON path
//! of the offending value. The second pass checks what JSON cannot say (names,
//! distributions, the actions `enabled` per observation, the coverage of every
//! `(s, u_def, u_adv)` triple whose actions some observation of `s` enables by
//! the `"*"` wildcards) and builds the [`Posg`]. Every error is a [`ModelError`]
//! whose path is `FILE: JSON.path`, e.g. `grid.posg.json: transitions[17].next.s9`.
//!
//! The helpers shared with the controller files (`parse`, `Located`,
//! `distribution`) live here too.

use std::fmt;
use std::marker::PhantomData;
use std::path::Path;

use crate::limits;
use rustc_hash::{FxHashMap, FxHashSet};
use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, Visitor};
use serde::ser::{SerializeMap, Serializer};
use serde::{Deserialize, Serialize};

use super::{AdversaryAction, DefenderAction, Distribution, ModelError, Player, Posg};

/// The only format version this crate reads and writes (`"posg": 1`).
pub const FORMAT_VERSION: u64 = 1;

/// Reads and validates the game file at `path` (formats.md section 1).
pub fn read(path: &Path) -> Result<Posg, ModelError> {
    let file_name = path.display().to_string();
    let text = read_text(path, &file_name)?;
    from_json_str(&text, &file_name)
}

/// Parses and validates a game from JSON `text` (formats.md section 1);
/// `file_name` prefixes the path of every error.
pub fn from_json_str(text: &str, file_name: &str) -> Result<Posg, ModelError> {
    let raw: RawGame = parse(text, file_name)?;
    Builder::new(file_name).build(raw)
}

/// The game as pretty-printed JSON that [`from_json_str`] reads back to an
/// equal [`Posg`]: one transition entry per `(s, u_def, u_adv)` triple whose
/// actions are enabled in `s` (no wildcards), `"observe": "full"` for fully
/// observing players, `enabled` only for observations that disable some
/// action, no adversary for a POMDP, the name and labels kept.
pub fn to_json_string(game: &Posg) -> String {
    let raw = RawGame::from_game(game);
    serde_json::to_string_pretty(&raw).expect("a game always serialises")
}

/// Writes the game to `path` as [`to_json_string`] does.
pub fn write(path: &Path, game: &Posg) -> Result<(), ModelError> {
    write_text(path, &to_json_string(game))
}

/// Reads a whole file; an I/O failure becomes a [`ModelError`] on the file.
pub(crate) fn read_text(path: &Path, file_name: &str) -> Result<String, ModelError> {
    std::fs::read_to_string(path)
        .map_err(|e| ModelError::new(file_name, format!("cannot read the file: {e}")))
}

/// Writes a whole file; an I/O failure becomes a [`ModelError`] on the file.
pub(crate) fn write_text(path: &Path, text: &str) -> Result<(), ModelError> {
    std::fs::write(path, text).map_err(|e| {
        ModelError::new(
            path.display().to_string(),
            format!("cannot write the file: {e}"),
        )
    })
}

/// Parses `text` into `T`, turning syntax, type, unknown-field and
/// duplicate-key errors into a [`ModelError`] at `FILE: JSON.path`.
///
/// The text is parsed once without tracking JSON paths (parser speed); only
/// when that fails is it parsed again with [`serde_path_to_error`], whose
/// error names the path. Both parses accept exactly the same texts.
pub(crate) fn parse<T: for<'de> Deserialize<'de>>(
    text: &str,
    file_name: &str,
) -> Result<T, ModelError> {
    match serde_json::from_str(text) {
        Ok(value) => Ok(value),
        Err(_) => parse_tracking_paths(text, file_name),
    }
}

/// [`parse`] with the JSON path of every value tracked, for its error message.
fn parse_tracking_paths<T: for<'de> Deserialize<'de>>(
    text: &str,
    file_name: &str,
) -> Result<T, ModelError> {
    let mut json = serde_json::Deserializer::from_str(text);
    let value = serde_path_to_error::deserialize(&mut json).map_err(|e| {
        let path = e.path().to_string();
        let at = Located::new(file_name, if path == "." { "" } else { &path });
        at.error(e.into_inner().to_string())
    })?;
    json.end()
        .map_err(|e| ModelError::new(file_name, e.to_string()))?;
    Ok(value)
}

/// A position in a file: the file name and a JSON path, for error messages.
#[derive(Debug, Clone)]
pub(crate) struct Located<'a> {
    file_name: &'a str,
    path: String,
}

impl<'a> Located<'a> {
    /// The position `path` (empty: the whole file) in `file_name`.
    pub(crate) fn new(file_name: &'a str, path: &str) -> Self {
        Self {
            file_name,
            path: path.to_string(),
        }
    }

    /// The member `key` of the object here.
    pub(crate) fn key(&self, key: &str) -> Self {
        let path = if self.path.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.path)
        };
        Self::new(self.file_name, &path)
    }

    /// The element `index` of the array here.
    pub(crate) fn index(&self, index: usize) -> Self {
        Self::new(self.file_name, &format!("{}[{index}]", self.path))
    }

    /// The JSON path alone (e.g. `transitions[3]`).
    pub(crate) fn path(&self) -> &str {
        &self.path
    }

    /// The error `message` at this position.
    pub(crate) fn error(&self, message: impl Into<String>) -> ModelError {
        let path = if self.path.is_empty() {
            self.file_name.to_string()
        } else {
            format!("{}: {}", self.file_name, self.path)
        };
        ModelError::new(path, message)
    }
}

/// Whether `p` is a probability: finite and in [0, 1].
fn is_probability(p: f64) -> bool {
    p.is_finite() && (0.0..=1.0).contains(&p)
}

/// Checks one probability of a distribution (finite, in [0, 1]).
pub(crate) fn check_probability(p: f64, at: &Located) -> Result<(), ModelError> {
    if is_probability(p) {
        Ok(())
    } else {
        Err(at.error(format!("probability {p} is not in [0, 1]")))
    }
}

/// Checks that probabilities (already checked one by one) sum to 1 within
/// [`super::DISTRIBUTION_TOLERANCE`] and renormalises them (formats.md section 1). Weights that already sum
/// to 1 up to floating-point rounding are kept bit for bit, so that writing
/// and reading a model gives back the same numbers.
pub(crate) fn normalise(weights: &mut [f64], at: &Located) -> Result<(), ModelError> {
    let total: f64 = weights.iter().sum();
    if let Some(total) = normalisation(total, weights.len(), at)? {
        weights.iter_mut().for_each(|w| *w /= total);
    }
    Ok(())
}

/// The check of [`normalise`] on the sum `total` of `len` weights: an error
/// when it is not 1 within [`super::DISTRIBUTION_TOLERANCE`], `Some(total)` when the weights must be
/// divided by it, `None` when they sum to 1 up to rounding (kept bit for bit).
fn normalisation(total: f64, len: usize, at: &Located) -> Result<Option<f64>, ModelError> {
    let shown = (total * 1e9).round() / 1e9 + 0.0;
    super::check_total(total, shown, "probabilities").map_err(|message| at.error(message))?;
    Ok(((total - 1.0).abs() > len as f64 * f64::EPSILON).then_some(total))
}

/// The distribution written as the object at `at` over outcomes found by
/// `index` (`kind` names them in errors, e.g. "state"): checked, renormalised,
/// zero entries dropped, sorted by outcome (so the order of keys in the file
/// does not matter). Positions in `at` are built only for an error message.
pub(crate) fn distribution(
    map: &UniqueMap<f64>,
    at: &Located,
    kind: &str,
    index: impl Fn(&str) -> Option<usize>,
) -> Result<Distribution, ModelError> {
    let mut d: Distribution = Vec::with_capacity(map.0.len());
    for &(ref name, p) in &map.0 {
        let outcome =
            index(name).ok_or_else(|| at.key(name).error(format!("unknown {kind} `{name}`")))?;
        if !is_probability(p) {
            check_probability(p, &at.key(name))?;
        }
        d.push((outcome, p));
    }
    let total: f64 = d.iter().map(|&(_, p)| p).sum();
    if let Some(total) = normalisation(total, d.len(), at)? {
        d.iter_mut().for_each(|(_, p)| *p /= total);
    }
    d.retain(|&(_, p)| p > 0.0);
    d.sort_unstable_by_key(|&(o, _)| o);
    Ok(d)
}

/// Whether `name` is a valid state, action or observation name: `[A-Za-z0-9_.:-]+`.
pub(crate) fn is_valid_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"_.:-".contains(&b))
}

/// Whether `name` is a valid atomic proposition: `[a-z_][a-z0-9_]*`.
pub(crate) fn is_valid_proposition(name: &str) -> bool {
    let mut bytes = name.bytes();
    bytes
        .next()
        .is_some_and(|b| b.is_ascii_lowercase() || b == b'_')
        && bytes.all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_')
}

/// A JSON object as its members in file order, read with duplicate keys
/// rejected (serde_json alone would silently keep the last one).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct UniqueMap<V>(pub(crate) Vec<(String, V)>);

impl<'de, V: Deserialize<'de>> Deserialize<'de> for UniqueMap<V> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_map(UniqueMapVisitor(PhantomData))
    }
}

impl<V: Serialize> Serialize for UniqueMap<V> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (key, value) in &self.0 {
            map.serialize_entry(key, value)?;
        }
        map.end()
    }
}

struct UniqueMapVisitor<V>(PhantomData<V>);

impl<'de, V: Deserialize<'de>> Visitor<'de> for UniqueMapVisitor<V> {
    type Value = UniqueMap<V>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON object")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut entries = Vec::new();
        let mut seen = None;
        while let Some(key) = map.next_key::<String>()? {
            if is_repeated(&entries, &mut seen, &key) {
                map.next_value_seed(Duplicate)?;
            }
            entries.push((key, map.next_value()?));
        }
        Ok(UniqueMap(entries))
    }
}

/// Objects with at most this many members are checked for a repeated key by
/// comparing with each earlier one (no allocation); larger ones by a set.
const SMALL_OBJECT: usize = 16;

/// Whether `key` is already among the keys of `entries`; `seen` holds those
/// keys as a set once the object outgrows [`SMALL_OBJECT`].
fn is_repeated<V>(
    entries: &[(String, V)],
    seen: &mut Option<FxHashSet<String>>,
    key: &str,
) -> bool {
    if let Some(set) = seen {
        return !set.insert(key.to_string());
    }
    let repeated = entries.iter().any(|(k, _)| k == key);
    if entries.len() >= SMALL_OBJECT {
        let keys = entries.iter().map(|(k, _)| k.clone());
        *seen = Some(keys.chain(std::iter::once(key.to_string())).collect());
    }
    repeated
}

/// The value of a repeated key: always an error, raised from inside the value
/// so that its JSON path ends with the key.
struct Duplicate;

impl<'de> DeserializeSeed<'de> for Duplicate {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
        deserializer.deserialize_ignored_any(self)
    }
}

impl<'de> Visitor<'de> for Duplicate {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a key that appears once")
    }

    fn visit_unit<E: de::Error>(self) -> Result<(), E> {
        Err(E::custom("duplicate key"))
    }
}

/// The top-level object of a `*.posg.json` file.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawGame {
    posg: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    states: Vec<String>,
    initial: UniqueMap<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    labels: Option<UniqueMap<Vec<String>>>,
    defender: RawPlayer,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    adversary: Option<RawPlayer>,
    transitions: Vec<RawTransition>,
}

/// `defender` or `adversary`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawPlayer {
    actions: Vec<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    observations: Option<Vec<String>>,
    observe: RawObserve,
    /// Observation -> the actions enabled under it (formats.md section 6).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    enabled: Option<UniqueMap<Vec<String>>>,
}

/// `observe`: `"full"` or state -> distribution over observations.
#[derive(Debug)]
enum RawObserve {
    Full,
    Map(UniqueMap<UniqueMap<f64>>),
}

impl<'de> Deserialize<'de> for RawObserve {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(ObserveVisitor)
    }
}

impl Serialize for RawObserve {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            RawObserve::Full => serializer.serialize_str("full"),
            RawObserve::Map(map) => map.serialize(serializer),
        }
    }
}

struct ObserveVisitor;

impl<'de> Visitor<'de> for ObserveVisitor {
    type Value = RawObserve;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("\"full\" or an object state -> distribution over observations")
    }

    fn visit_str<E: de::Error>(self, value: &str) -> Result<RawObserve, E> {
        if value == "full" {
            Ok(RawObserve::Full)
        } else {
            Err(E::invalid_value(de::Unexpected::Str(value), &self))
        }
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<RawObserve, A::Error> {
        UniqueMapVisitor(PhantomData)
            .visit_map(map)
            .map(RawObserve::Map)
    }
}

/// One entry of `transitions`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawTransition {
    state: String,
    defender: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    adversary: Option<String>,
    next: UniqueMap<f64>,
}

/// The wildcard action `"*"`.
const ANY: &str = "*";

/// The single action and observation of the adversary of a POMDP.
const POMDP_SYMBOL: &str = "_";

/// A wildcard in a transition key.
const WILDCARD: u32 = u32::MAX;

/// Checks a raw game and builds the [`Posg`].
struct Builder<'a> {
    file_name: &'a str,
    states: FxHashMap<String, usize>,
}

impl<'a> Builder<'a> {
    fn new(file_name: &'a str) -> Self {
        Self {
            file_name,
            states: FxHashMap::default(),
        }
    }

    fn at(&self, path: &str) -> Located<'a> {
        Located::new(self.file_name, path)
    }

    fn build(mut self, raw: RawGame) -> Result<Posg, ModelError> {
        if raw.posg != FORMAT_VERSION {
            return Err(self.at("posg").error(format!(
                "unsupported format version {} (expected {FORMAT_VERSION})",
                raw.posg
            )));
        }
        self.states = index_names(&raw.states, &self.at("states"), "state")?;
        let initial = distribution(&raw.initial, &self.at("initial"), "state", |n| {
            self.state(n)
        })?;
        let (propositions, labels) = self.labels(raw.labels.as_ref(), raw.states.len())?;
        let defender = self.player(&raw.defender, &self.at("defender"), &raw.states)?;
        let adversary = match &raw.adversary {
            Some(a) => self.player(a, &self.at("adversary"), &raw.states)?,
            None => pomdp_adversary(raw.states.len()),
        };
        let mut game = Posg {
            name: raw.name,
            states: raw.states,
            initial,
            propositions,
            labels,
            defender,
            adversary,
            has_adversary: raw.adversary.is_some(),
            transition_offsets: Vec::new(),
            transition_entries: Vec::new(),
        };
        self.transitions(&raw.transitions, &mut game)?;
        Ok(game)
    }

    fn state(&self, name: &str) -> Option<usize> {
        self.states.get(name).copied()
    }

    /// The sorted propositions and each state's label as indices into them.
    #[allow(clippy::type_complexity)]
    fn labels(
        &self,
        raw: Option<&UniqueMap<Vec<String>>>,
        num_states: usize,
    ) -> Result<(Vec<String>, Vec<Vec<usize>>), ModelError> {
        let at = self.at("labels");
        let mut named: Vec<Vec<&str>> = vec![Vec::new(); num_states];
        for (state, props) in raw.map_or(&[][..], |m| m.0.as_slice()) {
            let here = at.key(state);
            let s = self
                .state(state)
                .ok_or_else(|| here.error(format!("unknown state `{state}`")))?;
            for (i, p) in props.iter().enumerate() {
                if !is_valid_proposition(p) {
                    return Err(here.index(i).error(format!(
                        "`{p}` is not a valid proposition (expected [a-z_][a-z0-9_]*)"
                    )));
                }
                if named[s].contains(&p.as_str()) {
                    return Err(here
                        .index(i)
                        .error(format!("proposition `{p}` listed twice")));
                }
                named[s].push(p);
            }
        }
        let mut propositions: Vec<String> = named.iter().flatten().map(|p| p.to_string()).collect();
        propositions.sort();
        propositions.dedup();
        let labels = named
            .iter()
            .map(|ps| {
                let mut ids: Vec<usize> = ps
                    .iter()
                    .map(|p| {
                        propositions
                            .binary_search_by(|q| q.as_str().cmp(p))
                            .unwrap()
                    })
                    .collect();
                ids.sort_unstable();
                ids
            })
            .collect();
        Ok((propositions, labels))
    }

    fn player(
        &self,
        raw: &RawPlayer,
        at: &Located,
        states: &[String],
    ) -> Result<Player, ModelError> {
        index_names(&raw.actions, &at.key("actions"), "action")?;
        if raw.actions.is_empty() {
            return Err(at
                .key("actions")
                .error("a player needs at least one action"));
        }
        match &raw.observe {
            RawObserve::Full => self.full_player(raw, at, states),
            RawObserve::Map(map) => self.partial_player(raw, map, at, states.len()),
        }
    }

    fn full_player(
        &self,
        raw: &RawPlayer,
        at: &Located,
        states: &[String],
    ) -> Result<Player, ModelError> {
        let observations = raw.observations.clone().unwrap_or_else(|| states.to_vec());
        let here = at.key("observations");
        let index = index_names(&observations, &here, "observation")?;
        let observe = states
            .iter()
            .map(|s| {
                let o = index.get(s).copied().ok_or_else(|| {
                    here.error(format!(
                        "with \"observe\": \"full\" every state is an observation; `{s}` is missing"
                    ))
                })?;
                Ok::<_, ModelError>(vec![(o, 1.0)])
            })
            .collect::<Result<_, _>>()?;
        let enabled = enabled(raw, &observations, &index, at)?;
        Ok(Player {
            actions: raw.actions.clone(),
            observations,
            full_observation: true,
            observe,
            enabled,
        })
    }

    fn partial_player(
        &self,
        raw: &RawPlayer,
        map: &UniqueMap<UniqueMap<f64>>,
        at: &Located,
        num_states: usize,
    ) -> Result<Player, ModelError> {
        let observations = raw
            .observations
            .clone()
            .ok_or_else(|| at.error("`observations` is required unless \"observe\" is \"full\""))?;
        let index = index_names(&observations, &at.key("observations"), "observation")?;
        let here = at.key("observe");
        let mut observe: Vec<Option<Distribution>> = vec![None; num_states];
        for (state, dist) in &map.0 {
            let s = self
                .state(state)
                .ok_or_else(|| here.key(state).error(format!("unknown state `{state}`")))?;
            let d = distribution(dist, &here.key(state), "observation", |o| {
                index.get(o).copied()
            })?;
            observe[s] = Some(d);
        }
        let observe = observe
            .into_iter()
            .enumerate()
            .map(|(s, d)| {
                d.ok_or_else(|| {
                    here.error(format!(
                        "state `{}` has no observation distribution",
                        self.state_name(s)
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
        let enabled = enabled(raw, &observations, &index, at)?;
        Ok(Player {
            actions: raw.actions.clone(),
            observations,
            full_observation: false,
            observe,
            enabled,
        })
    }

    fn state_name(&self, s: usize) -> &str {
        self.states
            .iter()
            .find(|&(_, &i)| i == s)
            .map_or("?", |(n, _)| n.as_str())
    }

    /// Resolves the wildcards of `transitions` into one distribution per triple.
    fn transitions(&self, raw: &[RawTransition], game: &mut Posg) -> Result<(), ModelError> {
        let at = self.at("transitions");
        let mut keyed: FxHashMap<(usize, u32, u32), Vec<usize>> = FxHashMap::default();
        let mut nexts = Vec::with_capacity(raw.len());
        for (i, t) in raw.iter().enumerate() {
            let here = at.index(i);
            let key = self.transition_key(t, &here, game)?;
            keyed.entry(key).or_default().push(i);
            nexts.push(distribution(&t.next, &here.key("next"), "state", |n| {
                self.state(n)
            })?);
        }
        let (nu, nv) = (game.defender.num_actions(), game.adversary.num_actions());
        let triples = [game.states.len(), nu, nv]
            .into_iter()
            .fold(1u128, |product, n| product.saturating_mul(n as u128));
        if let Some(message) = limits::exceeded(
            &format!(
                "{} states x {nu} defender actions x {nv} adversary actions",
                game.states.len()
            ),
            triples,
            limits::MAX_TRANSITION_TRIPLES,
            "transition triples",
            "MAX_TRANSITION_TRIPLES",
        ) {
            return Err(at.error(message));
        }
        game.transition_offsets = Vec::with_capacity(game.states.len() * nu * nv + 1);
        game.transition_offsets.push(0);
        for s in 0..game.states.len() {
            for u in 0..nu {
                for v in 0..nv {
                    if triple_required(game, s, u, v) {
                        let entry = resolve_triple(&keyed, s, u, v)
                            .map_err(|m| at.error(m.describe(game, s, u, v)))?;
                        let total =
                            game.transition_entries.len() as u128 + nexts[entry].len() as u128;
                        if let Some(message) = limits::exceeded(
                            "the transitions with their wildcards expanded",
                            total,
                            limits::MAX_TRANSITION_ENTRIES,
                            "entries or more",
                            "MAX_TRANSITION_ENTRIES",
                        ) {
                            return Err(at.error(message));
                        }
                        game.transition_entries.extend_from_slice(&nexts[entry]);
                    }
                    game.transition_offsets.push(game.transition_entries.len());
                }
            }
        }
        Ok(())
    }

    /// `(state, defender action or WILDCARD, adversary action or WILDCARD)`.
    /// In a POMDP the adversary's single action is always taken as named.
    fn transition_key(
        &self,
        t: &RawTransition,
        at: &Located,
        game: &Posg,
    ) -> Result<(usize, u32, u32), ModelError> {
        let s = self.state(&t.state).ok_or_else(|| {
            at.key("state")
                .error(format!("unknown state `{}`", t.state))
        })?;
        let u = action_key(&t.defender, &game.defender, &at.key("defender"))?;
        let v = match (&t.adversary, game.has_adversary) {
            (Some(v), true) => action_key(v, &game.adversary, &at.key("adversary"))?,
            (None, true) => {
                return Err(at.error(
                    "`adversary` is required because the game has an adversary \
                     (use \"*\" for every action)",
                ));
            }
            (Some(v), false) if v != ANY && v != POMDP_SYMBOL => {
                return Err(at.key("adversary").error(format!(
                    "the game has no adversary: `adversary` must be omitted, \"*\" or \"_\", not `{v}`"
                )));
            }
            (_, false) => 0,
        };
        Ok((s, u, v))
    }
}

/// Whether the game must define `T(. | s, u, v)`: some observation of `s`
/// enables `u` for the defender and some enables `v` for the adversary
/// (formats.md section 6). Other triples keep no entries.
fn triple_required(game: &Posg, s: usize, u: usize, v: usize) -> bool {
    game.defender.action_enabled_in_state(s, u) && game.adversary.action_enabled_in_state(s, v)
}

/// The `enabled` map of a player as the dense table of [`Player`]: empty
/// when the map is absent or enables every action everywhere. Every listed
/// observation needs at least one action; actions are listed at most once.
fn enabled(
    raw: &RawPlayer,
    observations: &[String],
    index: &FxHashMap<String, usize>,
    at: &Located,
) -> Result<Vec<bool>, ModelError> {
    let Some(map) = &raw.enabled else {
        return Ok(Vec::new());
    };
    let here = at.key("enabled");
    let num_actions = raw.actions.len();
    let mut table = vec![true; observations.len() * num_actions];
    for (observation, actions) in &map.0 {
        let at_o = here.key(observation);
        let o = *index
            .get(observation)
            .ok_or_else(|| at_o.error(format!("unknown observation `{observation}`")))?;
        if actions.is_empty() {
            return Err(at_o.error("an observation needs at least one enabled action"));
        }
        let row = &mut table[o * num_actions..(o + 1) * num_actions];
        row.fill(false);
        for (i, action) in actions.iter().enumerate() {
            let u = raw
                .actions
                .iter()
                .position(|a| a == action)
                .ok_or_else(|| at_o.index(i).error(format!("unknown action `{action}`")))?;
            if row[u] {
                return Err(at_o
                    .index(i)
                    .error(format!("action `{action}` listed twice")));
            }
            row[u] = true;
        }
    }
    if table.iter().all(|&e| e) {
        table.clear();
    }
    Ok(table)
}

/// A defender or adversary field of a transition: an action index or [`WILDCARD`].
fn action_key(name: &str, player: &Player, at: &Located) -> Result<u32, ModelError> {
    if name == ANY {
        return Ok(WILDCARD);
    }
    player
        .actions
        .iter()
        .position(|a| a == name)
        .map(|u| u as u32)
        .ok_or_else(|| at.error(format!("unknown action `{name}`")))
}

/// Why no single transition entry applies to a triple.
enum Unresolved {
    Uncovered,
    Ambiguous(usize, usize),
}

impl Unresolved {
    fn describe(&self, game: &Posg, s: usize, u: usize, v: usize) -> String {
        let triple = format!(
            "(state `{}`, defender `{}`, adversary `{}`)",
            game.states[s], game.defender.actions[u], game.adversary.actions[v]
        );
        match self {
            Unresolved::Uncovered => format!("no entry covers {triple}"),
            Unresolved::Ambiguous(a, b) => format!(
                "transitions[{a}] and transitions[{b}] both match {triple} \
                 and neither is more specific; add an entry for the triple"
            ),
        }
    }
}

/// The most specific entry for `(s, u, v)`: both actions named, else one, else none.
fn resolve_triple(
    keyed: &FxHashMap<(usize, u32, u32), Vec<usize>>,
    s: usize,
    u: usize,
    v: usize,
) -> Result<usize, Unresolved> {
    let (u, v) = (u as u32, v as u32);
    let levels: [&[(u32, u32)]; 3] = [
        &[(u, v)],
        &[(u, WILDCARD), (WILDCARD, v)],
        &[(WILDCARD, WILDCARD)],
    ];
    for level in levels {
        let mut matches = level
            .iter()
            .filter_map(|&(a, b)| keyed.get(&(s, a, b)))
            .flatten();
        if let Some(&first) = matches.next() {
            return match matches.next() {
                Some(&second) => Err(Unresolved::Ambiguous(first.min(second), first.max(second))),
                None => Ok(first),
            };
        }
    }
    Err(Unresolved::Uncovered)
}

/// Checks names against `[A-Za-z0-9_.:-]+` and for uniqueness; returns name -> index.
fn index_names(
    names: &[String],
    at: &Located,
    kind: &str,
) -> Result<FxHashMap<String, usize>, ModelError> {
    let mut index = FxHashMap::default();
    for (i, name) in names.iter().enumerate() {
        if !is_valid_name(name) {
            return Err(at.index(i).error(format!(
                "`{name}` is not a valid {kind} name (expected [A-Za-z0-9_.:-]+)"
            )));
        }
        if let Some(first) = index.insert(name.clone(), i) {
            return Err(at.index(i).error(format!(
                "{kind} `{name}` already appears at {}[{first}]",
                at.path()
            )));
        }
    }
    Ok(index)
}

/// The adversary of a POMDP: one action `_`, one observation `_`, seen in every state.
pub(crate) fn pomdp_adversary(num_states: usize) -> Player {
    Player {
        actions: vec![POMDP_SYMBOL.to_string()],
        observations: vec![POMDP_SYMBOL.to_string()],
        full_observation: false,
        observe: vec![vec![(0, 1.0)]; num_states],
        enabled: Vec::new(),
    }
}

impl RawGame {
    fn from_game(game: &Posg) -> Self {
        let labels: Vec<(String, Vec<String>)> = (0..game.num_states())
            .filter(|&s| !game.labels[s].is_empty())
            .map(|s| {
                let names = game.label_names(s).map(str::to_string).collect();
                (game.states[s].clone(), names)
            })
            .collect();
        Self {
            posg: FORMAT_VERSION,
            name: game.name.clone(),
            states: game.states.clone(),
            initial: named_distribution(&game.initial, &game.states),
            labels: (!labels.is_empty()).then_some(UniqueMap(labels)),
            defender: RawPlayer::from_player(&game.defender, &game.states),
            adversary: game
                .has_adversary
                .then(|| RawPlayer::from_player(&game.adversary, &game.states)),
            transitions: raw_transitions(game),
        }
    }
}

impl RawPlayer {
    fn from_player(player: &Player, states: &[String]) -> Self {
        let observe = if player.full_observation {
            RawObserve::Full
        } else {
            RawObserve::Map(UniqueMap(
                states
                    .iter()
                    .zip(&player.observe)
                    .map(|(s, d)| (s.clone(), named_distribution(d, &player.observations)))
                    .collect(),
            ))
        };
        let enabled: Vec<(String, Vec<String>)> = (0..player.num_observations())
            .filter(|&o| player.enabled_actions(o).count() < player.num_actions())
            .map(|o| {
                let actions = player
                    .enabled_actions(o)
                    .map(|u| player.actions[u].clone())
                    .collect();
                (player.observations[o].clone(), actions)
            })
            .collect();
        Self {
            actions: player.actions.clone(),
            observations: Some(player.observations.clone()),
            observe,
            enabled: (!enabled.is_empty()).then_some(UniqueMap(enabled)),
        }
    }
}

fn raw_transitions(game: &Posg) -> Vec<RawTransition> {
    let (nu, nv) = (game.defender.num_actions(), game.adversary.num_actions());
    let mut out = Vec::with_capacity(game.num_states() * nu * nv);
    for s in 0..game.num_states() {
        for u in 0..nu {
            for v in (0..nv).filter(|&v| triple_required(game, s, u, v)) {
                out.push(RawTransition {
                    state: game.states[s].clone(),
                    defender: game.defender.actions[u].clone(),
                    adversary: game
                        .has_adversary
                        .then(|| game.adversary.actions[v].clone()),
                    next: named_distribution(
                        game.transition(s, DefenderAction(u), AdversaryAction(v)),
                        &game.states,
                    ),
                });
            }
        }
    }
    out
}

fn named_distribution(d: &[(usize, f64)], names: &[String]) -> UniqueMap<f64> {
    UniqueMap(d.iter().map(|&(i, p)| (names[i].clone(), p)).collect())
}
