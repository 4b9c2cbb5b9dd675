//! `Game.from_arrays`: a game from numpy arrays (a transition array, the
//! observations, labels, rewards), checked in the arrays' own terms
//! (`transitions[3, 1]` sums to 0.9) and then read as the JSON game it
//! describes (docs/formats.md section 1), so that every rule of the format
//! holds for it too.

use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::{Map, Value, json};

use crate::errors::{Kind, compute, raise};

/// How far from 1 a row may sum (the game format's tolerance).
const TOLERANCE: f64 = posg_fsc::game::DISTRIBUTION_TOLERANCE;

/// A dense array of doubles with its shape, from anything numpy reads.
struct Dense {
    shape: Vec<usize>,
    values: Vec<f64>,
}

impl Dense {
    /// `value` as a float64 array (numpy's `asarray`), named `name` in
    /// errors.
    fn of(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Self> {
        let numpy = value.py().import("numpy")?;
        let array = numpy
            .call_method1("asarray", (value, "float64"))
            .map_err(|e| settings(format!("{name}: not an array of numbers ({e})")))?;
        let array = array.cast_into::<PyArrayDyn<f64>>()?;
        let shape = array.shape().to_vec();
        let values = array.to_vec().or_else(|_| {
            let copy = numpy.call_method1("ascontiguousarray", (&array,))?;
            copy.cast_into::<PyArrayDyn<f64>>()?
                .to_vec()
                .map_err(PyErr::from)
        })?;
        if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
            return Err(settings(format!(
                "{name}: holds {bad}; every entry must be finite"
            )));
        }
        Ok(Self { shape, values })
    }
}

/// A `SettingsError` (the arrays are the caller's arguments).
fn settings(message: String) -> PyErr {
    raise(Kind::Settings, message)
}

/// The names of `count` things: `given` (checked for its length) or
/// `prefix0`, `prefix1`, ...
fn names(
    keyword: &str,
    given: Option<Vec<String>>,
    count: usize,
    prefix: &str,
) -> PyResult<Vec<String>> {
    match given {
        Some(names) if names.len() != count => Err(settings(format!(
            "{keyword}: {} names for {count} entries",
            names.len()
        ))),
        Some(names) => Ok(names),
        None => Ok((0..count).map(|i| format!("{prefix}{i}")).collect()),
    }
}

/// One player's arrays: its actions and what it observes.
pub struct PlayerArrays<'py> {
    /// Action names (default `a0`, `a1`, ...).
    pub actions: Option<Vec<String>>,
    /// `None`: the player sees the state; a vector of observation indices
    /// per state; or a `(states, observations)` array of probabilities.
    pub observations: Option<Bound<'py, PyAny>>,
    /// Observation names (default `o0`, `o1`, ...).
    pub observation_names: Option<Vec<String>>,
}

/// Everything `Game.from_arrays` takes.
pub struct GameArrays<'py> {
    pub transitions: Bound<'py, PyAny>,
    pub initial: Bound<'py, PyAny>,
    pub states: Option<Vec<String>>,
    pub labels: Option<Bound<'py, PyDict>>,
    pub rewards: Option<Bound<'py, PyDict>>,
    pub defender: PlayerArrays<'py>,
    pub adversary: PlayerArrays<'py>,
    pub name: Option<String>,
}

/// The game the arrays describe.
pub fn game(arrays: GameArrays<'_>) -> PyResult<posg_fsc::game::Posg> {
    let py = arrays.transitions.py();
    let t = Dense::of("transitions", &arrays.transitions)?;
    let (n, a, b) = match t.shape[..] {
        [n, a, n2] if n == n2 => (n, a, None),
        [n, a, b, n2] if n == n2 => (n, a, Some(b)),
        _ => {
            return Err(settings(format!(
                "transitions: shape {:?}; expected (states, actions, states) or (states, \
                 defender actions, adversary actions, states)",
                t.shape
            )));
        }
    };
    if n == 0 || a == 0 || b == Some(0) {
        return Err(settings("transitions: no states or no actions".into()));
    }
    let states = names("states", arrays.states, n, "s")?;
    let defender_actions = names("actions", arrays.defender.actions.clone(), a, "a")?;
    let adversary_actions = match b {
        Some(b) => Some(names(
            "adversary_actions",
            arrays.adversary.actions.clone(),
            b,
            "b",
        )?),
        None => None,
    };
    let width = b.unwrap_or(1);
    let row = |s: usize, u: usize, v: usize| {
        let at = ((s * a + u) * width + v) * n;
        &t.values[at..at + n]
    };
    let index = |s: usize, u: usize, v: usize| match b {
        Some(_) => format!("[{s}, {u}, {v}]"),
        None => format!("[{s}, {u}]"),
    };
    // Which (u, v) each state offers: rows with mass.
    let mut offered_def = vec![vec![false; a]; n];
    let mut offered_adv = vec![vec![false; width]; n];
    let pairs = (0..a).flat_map(|u| (0..width).map(move |v| (u, v)));
    for (s, state) in states.iter().enumerate() {
        for (u, v) in pairs.clone() {
            let r = row(s, u, v);
            if let Some(p) = r.iter().find(|&&p| p < 0.0) {
                return Err(settings(format!(
                    "transitions{}: holds the negative probability {p}",
                    index(s, u, v)
                )));
            }
            if r.iter().sum::<f64>() > 0.0 {
                offered_def[s][u] = true;
                offered_adv[s][v] = true;
            }
        }
        if !offered_def[s].contains(&true) {
            return Err(settings(format!(
                "transitions[{s}]: state {state} has no action (every row is zero); give it a \
                 self-loop"
            )));
        }
    }
    let mut transitions = Vec::new();
    for s in 0..n {
        for u in (0..a).filter(|&u| offered_def[s][u]) {
            for v in (0..width).filter(|&v| offered_adv[s][v]) {
                let r = row(s, u, v);
                let total: f64 = r.iter().sum();
                if (total - 1.0).abs() > TOLERANCE {
                    let whose = match &adversary_actions {
                        Some(adv) => format!(
                            "state {}, defender action {}, adversary action {}",
                            states[s], defender_actions[u], adv[v]
                        ),
                        None => format!("state {}, action {}", states[s], defender_actions[u]),
                    };
                    let why = match (total, b) {
                        (0.0, Some(_)) => {
                            "; both actions are offered in this state (by \
                                           other rows), so every pair of them needs a \
                                           distribution"
                        }
                        _ => "; a row of zeros leaves the action out of the state",
                    };
                    return Err(settings(format!(
                        "transitions{} ({whose}) sums to {total}, not 1{why}",
                        index(s, u, v)
                    )));
                }
                let next: Map<String, Value> = (r.iter().enumerate())
                    .filter(|&(_, &p)| p > 0.0)
                    .map(|(s2, &p)| (states[s2].clone(), json!(p)))
                    .collect();
                let mut entry = json!({
                    "state": states[s],
                    "defender": defender_actions[u],
                    "next": next,
                });
                if let Some(adv) = &adversary_actions {
                    entry["adversary"] = json!(adv[v]);
                }
                transitions.push(entry);
            }
        }
    }
    let mut game = json!({
        "posg": 1,
        "states": states,
        "initial": initial(&arrays.initial, &states)?,
        "defender": player(
            "",
            &arrays.defender,
            &states,
            &defender_actions,
            &offered_def,
        )?,
        "transitions": transitions,
    });
    if let Some(adv) = &adversary_actions {
        game["adversary"] = player("adversary_", &arrays.adversary, &states, adv, &offered_adv)?;
    }
    if let Some(name) = arrays.name {
        game["name"] = json!(name);
    }
    if let Some(labels) = &arrays.labels {
        game["labels"] = labelled(labels, &states)?;
    }
    if let Some(rewards) = &arrays.rewards {
        let shape = (n, a, b);
        let names = (
            &states[..],
            &defender_actions[..],
            adversary_actions.as_deref(),
        );
        game["rewards"] = reward_models(rewards, shape, names)?;
    }
    let text = game.to_string();
    compute(py, || {
        posg_fsc::game::file::from_json_str(&text, "Game.from_arrays")
    })
}

/// `initial`: a state index, or a distribution over the states.
fn initial(value: &Bound<'_, PyAny>, states: &[String]) -> PyResult<Value> {
    if let Ok(s) = value.extract::<usize>() {
        return match states.get(s) {
            Some(state) => Ok(json!({ state: 1.0 })),
            None => Err(settings(format!(
                "initial: state {s} is out of range ({} states)",
                states.len()
            ))),
        };
    }
    let d = Dense::of("initial", value)?;
    if d.shape != [states.len()] {
        return Err(settings(format!(
            "initial: shape {:?}; expected a state index or ({},)",
            d.shape,
            states.len()
        )));
    }
    let total: f64 = d.values.iter().sum();
    if (total - 1.0).abs() > TOLERANCE || d.values.iter().any(|&p| p < 0.0) {
        return Err(settings(format!(
            "initial: not a distribution (sums to {total})"
        )));
    }
    Ok(Value::Object(
        (d.values.iter().enumerate())
            .filter(|&(_, &p)| p > 0.0)
            .map(|(s, &p)| (states[s].clone(), json!(p)))
            .collect(),
    ))
}

/// A player of the JSON game: its actions, observation function and the
/// actions each observation enables (those its states offer, which must
/// agree); `prefix` is `adversary_` for the adversary's keywords.
fn player(
    prefix: &str,
    arrays: &PlayerArrays<'_>,
    states: &[String],
    actions: &[String],
    offered: &[Vec<bool>],
) -> PyResult<Value> {
    let keyword = format!("{prefix}observations");
    let Some(given) = &arrays.observations else {
        let enabled = enabled_map(states.iter().cloned().zip(offered), actions);
        return Ok(json!({"actions": actions, "observe": "full", "enabled": enabled}));
    };
    let d = Dense::of(&keyword, given)?;
    let n = states.len();
    // O(o | s) as (state, observation, probability) with positive mass.
    let (count, emitted): (usize, Vec<(usize, usize, f64)>) = match d.shape[..] {
        [len] if len == n => {
            let mut emitted = Vec::with_capacity(n);
            // No more observations than names, or than states without names.
            let limit = arrays.observation_names.as_ref().map_or(n, Vec::len);
            for (s, &o) in d.values.iter().enumerate() {
                if o < 0.0 || o.fract() != 0.0 || o >= limit as f64 {
                    return Err(settings(format!(
                        "{keyword}[{s}]: {o} is not an observation index (0..{limit})"
                    )));
                }
                emitted.push((s, o as usize, 1.0));
            }
            let used = emitted.iter().map(|&(_, o, _)| o + 1).max().unwrap_or(1);
            let count = arrays.observation_names.as_ref().map_or(used, Vec::len);
            if used > count {
                return Err(settings(format!(
                    "{keyword}: observation index {} but {count} {prefix}observation_names",
                    used - 1
                )));
            }
            (count, emitted)
        }
        [len, count] if len == n => {
            let mut emitted = Vec::new();
            for (s, state) in states.iter().enumerate() {
                let r = &d.values[s * count..(s + 1) * count];
                let total: f64 = r.iter().sum();
                if (total - 1.0).abs() > TOLERANCE || r.iter().any(|&p| p < 0.0) {
                    return Err(settings(format!(
                        "{keyword}[{s}] (state {state}): not a distribution (sums to {total})"
                    )));
                }
                emitted.extend((0..count).filter(|&o| r[o] > 0.0).map(|o| (s, o, r[o])));
            }
            (count, emitted)
        }
        _ => {
            return Err(settings(format!(
                "{keyword}: shape {:?}; expected ({n},) observation indices or ({n}, \
                 observations) probabilities",
                d.shape
            )));
        }
    };
    let observations = names(
        &format!("{prefix}observation_names"),
        arrays.observation_names.clone(),
        count,
        "o",
    )?;
    // The actions an observation enables: those of every state emitting it.
    let mut enabled: Vec<Option<(usize, &Vec<bool>)>> = vec![None; count];
    let mut observe: Map<String, Value> = Map::new();
    for &(s, o, p) in &emitted {
        match enabled[o] {
            Some((first, offers)) if offers != &offered[s] => {
                return Err(settings(format!(
                    "{keyword}: states {} and {} share the observation {} but offer different \
                     actions (rows of zeros in transitions); a player must have the same \
                     actions wherever it sees the same",
                    states[first], states[s], observations[o]
                )));
            }
            Some(_) => {}
            None => enabled[o] = Some((s, &offered[s])),
        }
        let row = observe
            .entry(states[s].clone())
            .or_insert_with(|| Value::Object(Map::new()));
        row[observations[o].as_str()] = json!(p);
    }
    let seen = (0..count).filter_map(|o| Some((observations[o].clone(), enabled[o]?.1)));
    Ok(json!({
        "actions": actions,
        "observations": observations,
        "observe": observe,
        "enabled": enabled_map(seen, actions),
    }))
}

/// `enabled` of the JSON game: for each observation whose states do not
/// offer every action, the actions they offer.
fn enabled_map<'a>(
    offers: impl Iterator<Item = (String, &'a Vec<bool>)>,
    actions: &[String],
) -> Value {
    Value::Object(
        offers
            .filter(|(_, offered)| offered.contains(&false))
            .map(|(observation, offered)| {
                let names: Vec<&String> = (actions.iter().zip(offered.iter()))
                    .filter(|&(_, &on)| on)
                    .map(|(name, _)| name)
                    .collect();
                (observation, json!(names))
            })
            .collect(),
    )
}

/// `labels` of the JSON game from `{proposition: states}` (state indices,
/// or a boolean array over the states).
fn labelled(labels: &Bound<'_, PyDict>, states: &[String]) -> PyResult<Value> {
    let mut of_state: Map<String, Value> = Map::new();
    for (proposition, value) in labels.iter() {
        let proposition: String = proposition.extract()?;
        let keyword = format!("labels[{proposition:?}]");
        let d = Dense::of(&keyword, &value)?;
        let boolean = is_boolean(&value)?;
        if boolean && d.shape != [states.len()] {
            return Err(settings(format!(
                "{keyword}: a boolean array of shape {:?}; expected one entry per state ({})",
                d.shape,
                states.len()
            )));
        }
        let marked: Vec<usize> = if boolean {
            (d.values.iter().enumerate())
                .filter(|&(_, &x)| x != 0.0)
                .map(|(s, _)| s)
                .collect()
        } else {
            let mut marked = Vec::with_capacity(d.values.len());
            for &s in &d.values {
                if s < 0.0 || s.fract() != 0.0 || s as usize >= states.len() {
                    return Err(settings(format!(
                        "{keyword}: {s} is not a state index (0..{})",
                        states.len()
                    )));
                }
                marked.push(s as usize);
            }
            marked
        };
        for s in marked {
            let entry = of_state
                .entry(states[s].clone())
                .or_insert_with(|| json!([]));
            if let Value::Array(list) = entry {
                list.push(json!(proposition));
            }
        }
    }
    Ok(Value::Object(of_state))
}

/// Whether `value` is a boolean array (numpy's `bool_` dtype or a list of
/// bools).
fn is_boolean(value: &Bound<'_, PyAny>) -> PyResult<bool> {
    let numpy = value.py().import("numpy")?;
    let array = numpy.call_method1("asarray", (value,))?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    Ok(kind == "b")
}

/// `rewards` of the JSON game from `{name: array}`: `(states,)` state
/// rewards, or `(states, actions)` (`(states, defender actions, adversary
/// actions)` in a game) action rewards.
fn reward_models(
    rewards: &Bound<'_, PyDict>,
    (n, a, b): (usize, usize, Option<usize>),
    (states, defender, adversary): (&[String], &[String], Option<&[String]>),
) -> PyResult<Value> {
    let mut models: Map<String, Value> = Map::new();
    for (name, value) in rewards.iter() {
        let name: String = name.extract()?;
        let keyword = format!("rewards[{name:?}]");
        let d = Dense::of(&keyword, &value)?;
        let nonzero = |at: usize| d.values[at] != 0.0;
        let model = match (&d.shape[..], b) {
            ([len], _) if *len == n => {
                let states: Map<String, Value> = (0..n)
                    .filter(|&s| nonzero(s))
                    .map(|s| (states[s].clone(), json!(d.values[s])))
                    .collect();
                json!({ "states": states })
            }
            ([len, width], None) if *len == n && *width == a => {
                let actions: Vec<Value> = (0..n * a)
                    .filter(|&i| nonzero(i))
                    .map(|i| {
                        json!({"state": states[i / a], "defender": defender[i % a], "reward": d.values[i]})
                    })
                    .collect();
                json!({ "actions": actions })
            }
            ([len, width, depth], Some(b)) if *len == n && *width == a && *depth == b => {
                let adversary = adversary.unwrap_or_default();
                let actions: Vec<Value> = (0..n * a * b)
                    .filter(|&i| nonzero(i))
                    .map(|i| {
                        json!({
                            "state": states[i / (a * b)],
                            "defender": defender[i / b % a],
                            "adversary": adversary[i % b],
                            "reward": d.values[i],
                        })
                    })
                    .collect();
                json!({ "actions": actions })
            }
            (shape, _) => {
                return Err(settings(format!(
                    "{keyword}: shape {shape:?}; expected ({n},) state rewards or the shape of \
                     transitions without its last axis (action rewards)"
                )));
            }
        };
        models.insert(name, model);
    }
    Ok(Value::Object(models))
}
