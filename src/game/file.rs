//! Reading and writing games as `*.posg.json` (formats.md section 1).
//!
//! Reading is two passes. serde first parses the bytes into plain types that
//! mirror the file (`RawGame` and friends, whose names borrow from the
//! bytes): unknown fields, duplicate keys and wrong JSON types fail here,
//! with the JSON path of the offending value (found by a second parse with
//! [`serde_path_to_error`] only when the first fails). The second pass
//! checks what JSON cannot say (names, distributions, the actions `enabled`
//! per observation, the coverage of every `(s, u_def, u_adv)` triple whose
//! actions some observation of `s` enables by the `"*"` wildcards, the
//! reward models of `rewards`) and builds the [`Posg`], building the JSON
//! path of a value only for an error.
//! Every error is a [`ModelError`] whose path is `FILE: JSON.path`, e.g.
//! `grid.posg.json: transitions[17].next.s9`.
//!
//! The helpers shared with the other readers (`parse`, `Located`, the
//! checks of names and probabilities) live in `super::reading`. [`read`]
//! also reads the optional binary
//! form of [`super::binary`] (formats.md section 11), told apart by its magic bytes.

mod rewards;

use std::borrow::Cow;
use std::fmt;
use std::hash::Hash;
use std::marker::PhantomData;
use std::ops::{Deref, Range};
use std::path::Path;

use crate::limits;
use rustc_hash::{FxHashMap, FxHashSet};
use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, Visitor};
use serde::ser::{SerializeMap, Serializer};
use serde::{Deserialize, Serialize};

pub use super::reading::FORMAT_VERSION;
use super::reading::{
    Located, POMDP_SYMBOL, action_label_problem, bytes_without_bom, check_probability,
    foreign_format, index_names, is_probability, is_valid_proposition, normalisation,
    parse_tracking_paths, pomdp_adversary, triple_required, write_text,
};
use super::{AdversaryAction, DefenderAction, Distribution, ModelError, Player, Posg};
use rewards::{RawRewardModel, raw_rewards};

/// Reads and validates the game file at `path`: JSON (formats.md section 1)
/// or, when the file starts with [`super::binary::MAGIC`], the binary form
/// (formats.md section 11).
pub fn read(path: &Path) -> Result<Posg, ModelError> {
    let file_name = path.display().to_string();
    let bytes = std::fs::read(path)
        .map_err(|e| ModelError::new(&file_name, format!("cannot read the file: {e}")))?;
    if super::binary::is_binary(&bytes) {
        super::binary::from_bytes(&bytes, &file_name)
    } else {
        from_json_slice(&bytes, &file_name)
    }
}

/// Parses and validates a game from JSON `text` (formats.md section 1);
/// `file_name` prefixes the path of every error.
pub fn from_json_str(text: &str, file_name: &str) -> Result<Posg, ModelError> {
    from_json_slice(text.as_bytes(), file_name)
}

/// [`from_json_str`] on the bytes of a file. Bytes that are not UTF-8 give
/// the error of `read_text` ("cannot read the file: ...").
pub fn from_json_slice(bytes: &[u8], file_name: &str) -> Result<Posg, ModelError> {
    let bytes = bytes_without_bom(bytes);
    let raw: RawGame = match serde_json::from_slice(bytes) {
        Ok(raw) => raw,
        Err(_) => {
            let text = std::str::from_utf8(bytes).map_err(|_| {
                let e = std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    "stream did not contain valid UTF-8",
                );
                ModelError::new(file_name, format!("cannot read the file: {e}"))
            })?;
            if let Some(error) = foreign_format(text, file_name) {
                return Err(error);
            }
            parse_tracking_paths(text, file_name)?
        }
    };
    Builder::new(file_name, &raw).build()
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

/// `error` in the distribution of the transition `t`, saying whose it is:
/// `probabilities sum to 0.98, not 1 (...), for T(. | s0, U)`.
fn of_triple(mut error: ModelError, t: &RawTransition) -> ModelError {
    let adversary = t
        .adversary
        .as_ref()
        .map_or(String::new(), |v| format!(", {}", &**v));
    error.message = format!(
        "{}, for T(. | {}, {}{adversary})",
        error.message, &*t.state, &*t.defender
    );
    error
}

/// The distribution written as the object at `at` over outcomes found by
/// `index` (`kind` names them in errors, e.g. "state"): checked, renormalised,
/// zero entries dropped, sorted by outcome (so the order of keys in the file
/// does not matter). Positions in `at` are built only for an error message.
fn distribution<K: AsRef<str>>(
    map: &UniqueMap<f64, K>,
    at: &Located,
    kind: &str,
    index: impl Fn(&str) -> Option<usize>,
) -> Result<Distribution, ModelError> {
    let mut d: Distribution = Vec::with_capacity(map.0.len());
    distribution_into(map, || at.clone(), kind, index, &mut d)?;
    Ok(d)
}

/// [`distribution`] appended to `out`; returns where it lies in `out`. The
/// position `at` is built only for an error message.
fn distribution_into<'f, K: AsRef<str>>(
    map: &UniqueMap<f64, K>,
    at: impl Fn() -> Located<'f>,
    kind: &str,
    index: impl Fn(&str) -> Option<usize>,
    out: &mut Distribution,
) -> Result<Range<usize>, ModelError> {
    let start = out.len();
    let mut total = 0.0;
    for (name, p) in &map.0 {
        let (name, p) = (name.as_ref(), *p);
        let outcome =
            index(name).ok_or_else(|| at().key(name).error(format!("unknown {kind} `{name}`")))?;
        if !is_probability(p) {
            check_probability(p, &at().key(name))?;
        }
        out.push((outcome, p));
        total += p;
    }
    let d = &mut out[start..];
    let rounding_only = (total - 1.0).abs() <= d.len() as f64 * f64::EPSILON;
    if !rounding_only {
        if let Some(total) = normalisation(total, d.len(), &at())? {
            d.iter_mut().for_each(|(_, p)| *p /= total);
        }
    }
    if d.iter().any(|&(_, p)| p <= 0.0) {
        super::drop_zero_outcomes(out, start);
    }
    let d = &mut out[start..];
    if !d.is_sorted_by_key(|&(o, _)| o) {
        d.sort_unstable_by_key(|&(o, _)| o);
    }
    Ok(start..out.len())
}

/// A JSON object as its members in file order, read with duplicate keys
/// rejected (serde_json alone would silently keep the last one). The keys
/// are `K`: owned strings, or [`Name`]s borrowed from the parsed bytes.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct UniqueMap<V, K = String>(pub(crate) Vec<(K, V)>);

/// The key types of a [`UniqueMap`].
pub(crate) trait MapKey: AsRef<str> + Eq + Hash + Clone {}

impl<K: AsRef<str> + Eq + Hash + Clone> MapKey for K {}

impl<'de, V: Deserialize<'de>, K: MapKey + Deserialize<'de>> Deserialize<'de> for UniqueMap<V, K> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_map(UniqueMapVisitor(PhantomData))
    }
}

impl<V: Serialize, K: Serialize> Serialize for UniqueMap<V, K> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (key, value) in &self.0 {
            map.serialize_entry(key, value)?;
        }
        map.end()
    }
}

struct UniqueMapVisitor<V, K>(PhantomData<(V, K)>);

impl<'de, V: Deserialize<'de>, K: MapKey + Deserialize<'de>> Visitor<'de>
    for UniqueMapVisitor<V, K>
{
    type Value = UniqueMap<V, K>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON object")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut entries = Vec::new();
        let mut seen = None;
        while let Some(key) = map.next_key::<K>()? {
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
fn is_repeated<V, K: MapKey>(entries: &[(K, V)], seen: &mut Option<FxHashSet<K>>, key: &K) -> bool {
    if let Some(set) = seen {
        return !set.insert(key.clone());
    }
    let repeated = entries.iter().any(|(k, _)| k == key);
    if entries.len() >= SMALL_OBJECT {
        let keys = entries.iter().map(|(k, _)| k.clone());
        *seen = Some(keys.chain(std::iter::once(key.clone())).collect());
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

/// A JSON string borrowed from the parsed bytes when it has no escapes,
/// else unescaped into an owned string (names, keys and actions).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) struct Name<'a>(Cow<'a, str>);

impl Deref for Name<'_> {
    type Target = str;

    fn deref(&self) -> &str {
        &self.0
    }
}

impl AsRef<str> for Name<'_> {
    fn as_ref(&self) -> &str {
        &self.0
    }
}

impl<'a> From<&'a str> for Name<'a> {
    fn from(name: &'a str) -> Self {
        Name(Cow::Borrowed(name))
    }
}

impl<'de: 'a, 'a> Deserialize<'de> for Name<'a> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_str(NameVisitor)
    }
}

impl Serialize for Name<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&self.0)
    }
}

struct NameVisitor;

impl<'de> Visitor<'de> for NameVisitor {
    type Value = Name<'de>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a string")
    }

    fn visit_borrowed_str<E: de::Error>(self, value: &'de str) -> Result<Name<'de>, E> {
        Ok(Name(Cow::Borrowed(value)))
    }

    fn visit_str<E: de::Error>(self, value: &str) -> Result<Name<'de>, E> {
        Ok(Name(Cow::Owned(value.to_string())))
    }

    fn visit_string<E: de::Error>(self, value: String) -> Result<Name<'de>, E> {
        Ok(Name(Cow::Owned(value)))
    }
}

/// Owned copies of borrowed names.
fn owned(names: &[Name]) -> Vec<String> {
    names.iter().map(|n| n.to_string()).collect()
}

/// Borrowed names of owned strings (for writing).
fn borrowed(names: &[String]) -> Vec<Name<'_>> {
    names.iter().map(|n| Name::from(n.as_str())).collect()
}

/// The top-level object of a `*.posg.json` file.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawGame<'a> {
    posg: u64,
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    name: Option<Name<'a>>,
    #[serde(borrow)]
    states: Vec<Name<'a>>,
    #[serde(borrow)]
    initial: UniqueMap<f64, Name<'a>>,
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    labels: Option<UniqueMap<Vec<Name<'a>>, Name<'a>>>,
    #[serde(borrow)]
    defender: RawPlayer<'a>,
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    adversary: Option<RawPlayer<'a>>,
    #[serde(borrow)]
    transitions: Vec<RawTransition<'a>>,
    /// Reward model name -> its rewards (formats.md section 1).
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    rewards: Option<UniqueMap<RawRewardModel<'a>, Name<'a>>>,
}

/// `defender` or `adversary`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawPlayer<'a> {
    #[serde(borrow)]
    actions: Vec<Name<'a>>,
    /// Action -> its label as written in the model it came from, where
    /// that differs from its name (formats.md section 6).
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    action_labels: Option<UniqueMap<Name<'a>, Name<'a>>>,
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    observations: Option<Vec<Name<'a>>>,
    #[serde(borrow)]
    observe: RawObserve<'a>,
    /// Observation -> the actions enabled under it (formats.md section 6).
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    enabled: Option<UniqueMap<Vec<Name<'a>>, Name<'a>>>,
}

/// A distribution over named outcomes, as a JSON object.
type NamedDistribution<'a> = UniqueMap<f64, Name<'a>>;

/// `observe`: `"full"` or state -> distribution over observations.
#[derive(Debug)]
enum RawObserve<'a> {
    Full,
    Map(UniqueMap<NamedDistribution<'a>, Name<'a>>),
}

impl<'de: 'a, 'a> Deserialize<'de> for RawObserve<'a> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(ObserveVisitor(PhantomData))
    }
}

impl Serialize for RawObserve<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            RawObserve::Full => serializer.serialize_str("full"),
            RawObserve::Map(map) => map.serialize(serializer),
        }
    }
}

struct ObserveVisitor<'a>(PhantomData<&'a ()>);

impl<'de: 'a, 'a> Visitor<'de> for ObserveVisitor<'a> {
    type Value = RawObserve<'a>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("\"full\" or an object state -> distribution over observations")
    }

    fn visit_str<E: de::Error>(self, value: &str) -> Result<RawObserve<'a>, E> {
        if value == "full" {
            Ok(RawObserve::Full)
        } else {
            Err(E::invalid_value(de::Unexpected::Str(value), &self))
        }
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<RawObserve<'a>, A::Error> {
        UniqueMapVisitor(PhantomData)
            .visit_map(map)
            .map(RawObserve::Map)
    }
}

/// One entry of `transitions`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawTransition<'a> {
    #[serde(borrow)]
    state: Name<'a>,
    #[serde(borrow)]
    defender: Name<'a>,
    #[serde(default, skip_serializing_if = "Option::is_none", borrow)]
    adversary: Option<Name<'a>>,
    #[serde(borrow)]
    next: NamedDistribution<'a>,
}

/// The wildcard action `"*"`.
const ANY: &str = "*";

/// A wildcard in a transition key.
const WILDCARD: u32 = u32::MAX;

/// Checks a raw game and builds the [`Posg`]; names are looked up as
/// borrowed strings of `raw`.
struct Builder<'a, 'r> {
    file_name: &'a str,
    raw: &'r RawGame<'r>,
    states: FxHashMap<&'r str, usize>,
}

impl<'a, 'r> Builder<'a, 'r> {
    fn new(file_name: &'a str, raw: &'r RawGame<'r>) -> Self {
        Self {
            file_name,
            raw,
            states: FxHashMap::default(),
        }
    }

    fn at(&self, path: &str) -> Located<'a> {
        Located::new(self.file_name, path)
    }

    fn build(mut self) -> Result<Posg, ModelError> {
        let raw = self.raw;
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
        let defender = self.player(&raw.defender, &self.at("defender"))?;
        let adversary = match &raw.adversary {
            Some(a) => self.player(a, &self.at("adversary"))?,
            None => pomdp_adversary(raw.states.len()),
        };
        let mut game = Posg {
            name: raw.name.as_ref().map(|n| n.to_string()),
            states: owned(&raw.states),
            initial,
            propositions,
            labels,
            defender,
            adversary,
            has_adversary: raw.adversary.is_some(),
            transition_offsets: Vec::new(),
            transition_entries: Vec::new(),
            rewards: Vec::new(),
        };
        self.transitions(&raw.transitions, &mut game)?;
        game.rewards = self.rewards(raw.rewards.as_ref(), &game)?;
        Ok(game)
    }

    fn state(&self, name: &str) -> Option<usize> {
        self.states.get(name).copied()
    }

    /// The sorted propositions and each state's label as indices into them.
    #[allow(clippy::type_complexity)]
    fn labels(
        &self,
        raw: Option<&'r UniqueMap<Vec<Name<'r>>, Name<'r>>>,
        num_states: usize,
    ) -> Result<(Vec<String>, Vec<Vec<usize>>), ModelError> {
        let at = self.at("labels");
        let mut named: Vec<Vec<&str>> = vec![Vec::new(); num_states];
        for (state, props) in raw.map_or(&[][..], |m| m.0.as_slice()) {
            let here = at.key(state);
            let s = self
                .state(state)
                .ok_or_else(|| here.error(format!("unknown state `{}`", &**state)))?;
            for (i, p) in props.iter().enumerate() {
                if !is_valid_proposition(p) {
                    return Err(here.index(i).error(format!(
                        "`{}` is not a valid proposition (expected [a-z_][a-z0-9_]*)",
                        &**p
                    )));
                }
                if named[s].contains(&&**p) {
                    return Err(here
                        .index(i)
                        .error(format!("proposition `{}` listed twice", &**p)));
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

    fn player(&self, raw: &'r RawPlayer<'r>, at: &Located) -> Result<Player, ModelError> {
        index_names(&raw.actions, &at.key("actions"), "action")?;
        if raw.actions.is_empty() {
            return Err(at
                .key("actions")
                .error("a player needs at least one action"));
        }
        match &raw.observe {
            RawObserve::Full => self.full_player(raw, at),
            RawObserve::Map(map) => self.partial_player(raw, map, at),
        }
    }

    fn full_player(&self, raw: &'r RawPlayer<'r>, at: &Located) -> Result<Player, ModelError> {
        let states = &self.raw.states;
        let observations: &[Name] = raw.observations.as_deref().unwrap_or(states);
        let here = at.key("observations");
        let index = index_names(observations, &here, "observation")?;
        let observe = states
            .iter()
            .map(|s| {
                let o = index.get(&**s).copied().ok_or_else(|| {
                    here.error(format!(
                        "with \"observe\": \"full\" every state is an observation; `{}` is missing",
                        &**s
                    ))
                })?;
                Ok::<_, ModelError>(vec![(o, 1.0)])
            })
            .collect::<Result<_, _>>()?;
        let enabled = enabled(raw, observations.len(), &index, at)?;
        Ok(Player {
            actions: owned(&raw.actions),
            action_labels: action_labels(raw, at)?,
            observations: owned(observations),
            full_observation: true,
            observe,
            enabled,
        })
    }

    fn partial_player(
        &self,
        raw: &'r RawPlayer<'r>,
        map: &'r UniqueMap<NamedDistribution<'r>, Name<'r>>,
        at: &Located,
    ) -> Result<Player, ModelError> {
        let num_states = self.raw.states.len();
        let observations = raw
            .observations
            .as_deref()
            .ok_or_else(|| at.error("`observations` is required unless \"observe\" is \"full\""))?;
        let index = index_names(observations, &at.key("observations"), "observation")?;
        let here = at.key("observe");
        let mut observe: Vec<Option<Distribution>> = vec![None; num_states];
        for (state, dist) in &map.0 {
            let s = self.state(state).ok_or_else(|| {
                here.key(state)
                    .error(format!("unknown state `{}`", &**state))
            })?;
            let mut d = Vec::with_capacity(dist.0.len());
            let at_state = || here.key(state);
            distribution_into(
                dist,
                at_state,
                "observation",
                |o| index.get(o).copied(),
                &mut d,
            )?;
            observe[s] = Some(d);
        }
        let observe = observe
            .into_iter()
            .enumerate()
            .map(|(s, d)| {
                d.ok_or_else(|| {
                    here.error(format!(
                        "state `{}` has no observation distribution",
                        &*self.raw.states[s]
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
        let enabled = enabled(raw, observations.len(), &index, at)?;
        Ok(Player {
            actions: owned(&raw.actions),
            action_labels: action_labels(raw, at)?,
            observations: owned(observations),
            full_observation: false,
            observe,
            enabled,
        })
    }

    /// Resolves the wildcards of `transitions` into one distribution per triple.
    fn transitions(&self, raw: &[RawTransition], game: &mut Posg) -> Result<(), ModelError> {
        let at = self.at("transitions");
        let mut keys = Vec::with_capacity(raw.len());
        let mut nexts = Vec::with_capacity(raw.len());
        let mut next_entries = Vec::with_capacity(raw.len() * 4);
        for (i, t) in raw.iter().enumerate() {
            let here = || at.index(i);
            let key =
                self.transition_key(&t.state, &t.defender, t.adversary.as_deref(), &here, game)?;
            keys.push((key, i));
            let next = distribution_into(
                &t.next,
                || here().key("next"),
                "state",
                |n| self.state(n),
                &mut next_entries,
            );
            nexts.push(next.map_err(|error| of_triple(error, t))?);
        }
        let keyed = Keyed::new(keys, game.states.len());
        let (nu, nv) = (game.defender.num_actions(), game.adversary.num_actions());
        if let Some(message) = limits::transition_triples(game.states.len(), nu, nv) {
            return Err(at.error(message));
        }
        game.transition_offsets = Vec::with_capacity(game.states.len() * nu * nv + 1);
        game.transition_offsets.push(0);
        game.transition_entries = Vec::with_capacity(next_entries.len());
        for s in 0..game.states.len() {
            for u in 0..nu {
                for v in 0..nv {
                    if triple_required(game, s, u, v) {
                        let entry = resolve_triple(&keyed, s, u, v)
                            .map_err(|m| at.error(m.describe(at.path(), game, s, u, v)))?;
                        let next = &next_entries[nexts[entry].clone()];
                        let total = game.transition_entries.len() as u128 + next.len() as u128;
                        if let Some(message) = limits::exceeded(
                            "the transitions with their wildcards expanded",
                            total,
                            limits::MAX_TRANSITION_ENTRIES,
                            "entries or more",
                            "MAX_TRANSITION_ENTRIES",
                        ) {
                            return Err(at.error(message));
                        }
                        game.transition_entries.extend_from_slice(next);
                    }
                    game.transition_offsets.push(game.transition_entries.len());
                }
            }
        }
        Ok(())
    }

    /// `(state, defender action or WILDCARD, adversary action or WILDCARD)`
    /// of an entry of `transitions` (or of a reward model's `actions`) with
    /// these fields. In a POMDP the adversary's single action is always
    /// taken as named. The entry's position `at` is built only for an error
    /// message.
    fn transition_key<'f>(
        &self,
        state: &str,
        defender: &str,
        adversary: Option<&str>,
        at: &dyn Fn() -> Located<'f>,
        game: &Posg,
    ) -> Result<(usize, u32, u32), ModelError> {
        let s = self
            .state(state)
            .ok_or_else(|| at().key("state").error(format!("unknown state `{state}`")))?;
        let u = action_key(defender, &game.defender, || at().key("defender"))?;
        let v = match (adversary, game.has_adversary) {
            (Some(v), true) => action_key(v, &game.adversary, || at().key("adversary"))?,
            (None, true) => {
                return Err(at().error(
                    "`adversary` is required because the game has an adversary \
                     (use \"*\" for every action)",
                ));
            }
            (Some(v), false) if v != ANY && v != POMDP_SYMBOL => {
                return Err(at().key("adversary").error(format!(
                    "the game has no adversary: `adversary` must be omitted, \"*\" or \"_\", not `{v}`"
                )));
            }
            (_, false) => 0,
        };
        Ok((s, u, v))
    }
}

/// The entries of `transitions` by key `(state, defender action or
/// WILDCARD, adversary action or WILDCARD)`: sorted by key and then by
/// position in the file, with the range of each state, so that looking up a
/// key is a binary search within its state's few entries.
struct Keyed {
    /// `((s, u, v), i)`: entry `i` of `transitions` has key `(s, u, v)`.
    sorted: Vec<((usize, u32, u32), usize)>,
    /// The entries of state `s` are `sorted[state_offsets[s]..state_offsets[s + 1]]`.
    state_offsets: Vec<usize>,
}

impl Keyed {
    /// `keys` in file order; every state is below `num_states`.
    fn new(mut keys: Vec<((usize, u32, u32), usize)>, num_states: usize) -> Self {
        keys.sort_unstable();
        let mut state_offsets = Vec::with_capacity(num_states + 1);
        state_offsets.push(0);
        let mut next = 0;
        for s in 0..num_states {
            next += keys[next..].partition_point(|&((t, _, _), _)| t == s);
            state_offsets.push(next);
        }
        Self {
            sorted: keys,
            state_offsets,
        }
    }

    /// The entries of state `s`, sorted by key.
    fn of_state(&self, s: usize) -> &[((usize, u32, u32), usize)] {
        &self.sorted[self.state_offsets[s]..self.state_offsets[s + 1]]
    }

    /// The entries with key `(s, a, b)`, in file order.
    fn entries(&self, s: usize, a: u32, b: u32) -> impl Iterator<Item = usize> + '_ {
        let of_state = self.of_state(s);
        let start = of_state.partition_point(|&((_, u, v), _)| (u, v) < (a, b));
        of_state[start..]
            .iter()
            .take_while(move |&&((_, u, v), _)| (u, v) == (a, b))
            .map(|&(_, i)| i)
    }
}

/// The `enabled` map of a player as the dense table of [`Player`]: empty
/// when the map is absent or enables every action everywhere. Every listed
/// observation needs at least one action; actions are listed at most once.
fn enabled(
    raw: &RawPlayer,
    num_observations: usize,
    index: &FxHashMap<&str, usize>,
    at: &Located,
) -> Result<Vec<bool>, ModelError> {
    let Some(map) = &raw.enabled else {
        return Ok(Vec::new());
    };
    let here = at.key("enabled");
    let num_actions = raw.actions.len();
    let mut table = vec![true; num_observations * num_actions];
    for (observation, actions) in &map.0 {
        let at_o = here.key(observation);
        let o = *index
            .get(&**observation)
            .ok_or_else(|| at_o.error(format!("unknown observation `{}`", &**observation)))?;
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
                .ok_or_else(|| {
                    at_o.index(i)
                        .error(format!("unknown action `{}`", &**action))
                })?;
            if row[u] {
                return Err(at_o
                    .index(i)
                    .error(format!("action `{}` listed twice", &**action)));
            }
            row[u] = true;
        }
    }
    if table.iter().all(|&e| e) {
        table.clear();
    }
    Ok(table)
}

/// A player's `action_labels` (formats.md section 6) as [`Player`] holds
/// them: each key an action, each label not empty, without whitespace, not
/// a valid name and different from the other labels.
fn action_labels(raw: &RawPlayer, at: &Located) -> Result<Vec<(usize, String)>, ModelError> {
    let Some(map) = &raw.action_labels else {
        return Ok(Vec::new());
    };
    let here = at.key("action_labels");
    let index: FxHashMap<&str, usize> = raw
        .actions
        .iter()
        .enumerate()
        .map(|(u, a)| (&**a, u))
        .collect();
    let mut labels: Vec<(usize, String)> = Vec::with_capacity(map.0.len());
    let mut seen: FxHashMap<&str, usize> = FxHashMap::default();
    for (action, label) in &map.0 {
        let at_action = here.key(action);
        let u = *index
            .get(&**action)
            .ok_or_else(|| at_action.error(format!("unknown action `{}`", &**action)))?;
        if let Some(problem) = action_label_problem(&raw.actions, &seen, label) {
            return Err(at_action.error(problem));
        }
        seen.insert(label, u);
        labels.push((u, label.to_string()));
    }
    labels.sort_unstable();
    Ok(labels)
}

/// A defender or adversary field of a transition: an action index or
/// [`WILDCARD`]. The position `at` is built only for an error message.
fn action_key<'f>(
    name: &str,
    player: &Player,
    at: impl Fn() -> Located<'f>,
) -> Result<u32, ModelError> {
    if name == ANY {
        return Ok(WILDCARD);
    }
    player
        .actions
        .iter()
        .position(|a| a == name)
        .map(|u| u as u32)
        .ok_or_else(|| at().error(format!("unknown action `{name}`")))
}

/// Why no single transition entry applies to a triple.
enum Unresolved {
    Uncovered,
    Ambiguous(usize, usize),
}

impl Unresolved {
    /// The problem with triple `(s, u, v)` of the entries of the list at
    /// JSON path `list` (`transitions`, or a reward model's `actions`).
    fn describe(&self, list: &str, game: &Posg, s: usize, u: usize, v: usize) -> String {
        let triple = format!(
            "(state `{}`, defender `{}`, adversary `{}`)",
            game.states[s], game.defender.actions[u], game.adversary.actions[v]
        );
        match self {
            Unresolved::Uncovered => format!("no entry covers {triple}"),
            Unresolved::Ambiguous(a, b) => format!(
                "{list}[{a}] and {list}[{b}] both match {triple} \
                 and neither is more specific; add an entry for the triple"
            ),
        }
    }
}

/// The most specific entry for `(s, u, v)`: both actions named, else one, else none.
fn resolve_triple(keyed: &Keyed, s: usize, u: usize, v: usize) -> Result<usize, Unresolved> {
    let (u, v) = (u as u32, v as u32);
    let levels: [&[(u32, u32)]; 3] = [
        &[(u, v)],
        &[(u, WILDCARD), (WILDCARD, v)],
        &[(WILDCARD, WILDCARD)],
    ];
    for level in levels {
        let mut matches = level.iter().flat_map(|&(a, b)| keyed.entries(s, a, b));
        if let Some(first) = matches.next() {
            return match matches.next() {
                Some(second) => Err(Unresolved::Ambiguous(first.min(second), first.max(second))),
                None => Ok(first),
            };
        }
    }
    Err(Unresolved::Uncovered)
}

impl<'a> RawGame<'a> {
    fn from_game(game: &'a Posg) -> Self {
        let labels: Vec<(Name, Vec<Name>)> = (0..game.num_states())
            .filter(|&s| !game.labels[s].is_empty())
            .map(|s| {
                let names = game.label_names(s).map(Name::from).collect();
                (Name::from(game.states[s].as_str()), names)
            })
            .collect();
        Self {
            posg: FORMAT_VERSION,
            name: game.name.as_deref().map(Name::from),
            states: borrowed(&game.states),
            initial: named_distribution(&game.initial, &game.states),
            labels: (!labels.is_empty()).then_some(UniqueMap(labels)),
            defender: RawPlayer::from_player(&game.defender, &game.states),
            adversary: game
                .has_adversary
                .then(|| RawPlayer::from_player(&game.adversary, &game.states)),
            transitions: raw_transitions(game),
            rewards: raw_rewards(game),
        }
    }
}

impl<'a> RawPlayer<'a> {
    fn from_player(player: &'a Player, states: &'a [String]) -> Self {
        let observe = if player.full_observation {
            RawObserve::Full
        } else {
            RawObserve::Map(UniqueMap(
                states
                    .iter()
                    .zip(&player.observe)
                    .map(|(s, d)| {
                        let d = named_distribution(d, &player.observations);
                        (Name::from(s.as_str()), d)
                    })
                    .collect(),
            ))
        };
        let enabled: Vec<(Name, Vec<Name>)> = (0..player.num_observations())
            .filter(|&o| player.enabled_actions(o).count() < player.num_actions())
            .map(|o| {
                let actions = player
                    .enabled_actions(o)
                    .map(|u| Name::from(player.actions[u].as_str()))
                    .collect();
                (Name::from(player.observations[o].as_str()), actions)
            })
            .collect();
        let labels: Vec<(Name, Name)> = player
            .action_labels
            .iter()
            .map(|(u, label)| {
                (
                    Name::from(player.actions[*u].as_str()),
                    Name::from(label.as_str()),
                )
            })
            .collect();
        Self {
            actions: borrowed(&player.actions),
            action_labels: (!labels.is_empty()).then_some(UniqueMap(labels)),
            observations: Some(borrowed(&player.observations)),
            observe,
            enabled: (!enabled.is_empty()).then_some(UniqueMap(enabled)),
        }
    }
}

fn raw_transitions(game: &Posg) -> Vec<RawTransition<'_>> {
    let (nu, nv) = (game.defender.num_actions(), game.adversary.num_actions());
    let mut out = Vec::with_capacity(game.num_states() * nu * nv);
    for s in 0..game.num_states() {
        for u in 0..nu {
            for v in (0..nv).filter(|&v| triple_required(game, s, u, v)) {
                out.push(RawTransition {
                    state: Name::from(game.states[s].as_str()),
                    defender: Name::from(game.defender.actions[u].as_str()),
                    adversary: game
                        .has_adversary
                        .then(|| Name::from(game.adversary.actions[v].as_str())),
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

fn named_distribution<'a>(d: &[(usize, f64)], names: &'a [String]) -> NamedDistribution<'a> {
    UniqueMap(
        d.iter()
            .map(|&(i, p)| (Name::from(names[i].as_str()), p))
            .collect(),
    )
}
