//! Conversions between Python objects and the library's serde types: Python
//! values to JSON (keyword arguments to settings), JSON to Python (reports
//! and iteration records to dicts), and the checks of plain arguments
//! (sizes, roles) that name the argument in their error.

use posg_fsc::controller::Role;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyList, PyString, PyTuple};
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::{Map, Value};

/// A Python value as JSON: `None`, `bool`, integers (anything with
/// `__index__`), floats, strings, lists and tuples, dicts with string keys.
/// `name` is the argument's name, for the `TypeError` of anything else.
pub fn to_json(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Value> {
    if value.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(flag) = value.cast::<PyBool>() {
        return Ok(Value::Bool(flag.is_true()));
    }
    if !value.is_instance_of::<PyFloat>() {
        if let Ok(number) = value.extract::<i64>() {
            return Ok(Value::from(number));
        }
        if let Ok(number) = value.extract::<u64>() {
            return Ok(Value::from(number));
        }
    }
    if let Ok(text) = value.cast::<PyString>() {
        return Ok(Value::String(text.to_cow()?.into_owned()));
    }
    if let Ok(number) = value.extract::<f64>() {
        return serde_json::Number::from_f64(number)
            .map(Value::Number)
            .ok_or_else(|| PyValueError::new_err(format!("{name}: {number} is not finite")));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        return value
            .try_iter()?
            .map(|item| to_json(name, &item?))
            .collect::<PyResult<Vec<_>>>()
            .map(Value::Array);
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        let mut map = Map::new();
        for (key, item) in dict.iter() {
            let key: String = key.extract().map_err(|_| {
                PyTypeError::new_err(format!("{name}: dictionary keys must be strings"))
            })?;
            let item = to_json(&format!("{name}.{key}"), &item)?;
            map.insert(key, item);
        }
        return Ok(Value::Object(map));
    }
    Err(PyTypeError::new_err(format!(
        "{name}: a {} cannot be a setting (expected a number, string, bool, list or dict)",
        value.get_type().name()?
    )))
}

/// JSON as Python objects: `null` is `None`, objects are dicts.
pub fn to_python<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(flag) => PyBool::new(py, *flag).to_owned().into_any(),
        Value::Number(number) => match (number.as_u64(), number.as_i64()) {
            (Some(n), _) => n.into_pyobject(py)?.into_any(),
            (None, Some(n)) => n.into_pyobject(py)?.into_any(),
            _ => number
                .as_f64()
                .unwrap_or(f64::NAN)
                .into_pyobject(py)?
                .into_any(),
        },
        Value::String(text) => PyString::new(py, text).into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(to_python(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (key, item) in map {
                dict.set_item(key, to_python(py, item)?)?;
            }
            dict.into_any()
        }
    })
}

/// Any serialisable library value (a report, an iteration record) as
/// Python objects, with the names its JSON files use.
pub fn serialised<'py>(py: Python<'py>, value: &impl Serialize) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_value(value)
        .map_err(|e| crate::errors::raise(crate::errors::Kind::Other, e.to_string()))?;
    to_python(py, &json)
}

/// Deserialises settings from a JSON object: an unknown key or a value of
/// the wrong type is a `TypeError`, a value out of range (a negative count,
/// an unknown name) a `ValueError`; both name the keyword (`function` is
/// the Python function's name, for the message).
pub fn settings_from_json<T: DeserializeOwned>(function: &str, json: Value) -> PyResult<T> {
    serde_path_to_error::deserialize(json).map_err(|error| {
        let path = error.path().to_string();
        let inner = error.into_inner().to_string();
        if let Some(rest) = inner.strip_prefix("unknown field `") {
            let field = rest.split('`').next().unwrap_or(rest);
            let at = if path.contains('.') {
                format!(" (in {path})")
            } else {
                String::new()
            };
            PyTypeError::new_err(format!(
                "{function}() got an unexpected keyword argument '{field}'{at}"
            ))
        } else if inner.starts_with("invalid type") {
            PyTypeError::new_err(format!("{function}() argument '{path}': {inner}"))
        } else {
            PyValueError::new_err(format!("{function}() argument '{path}': {inner}"))
        }
    })
}

/// The TypeError of `function`'s keyword `key`, which is none of its
/// `settings`, suggesting the closest keyword of the settings and of the
/// functions' own.
pub fn unknown_keyword(function: &str, key: &str, settings: &[crate::help::Setting]) -> PyErr {
    let all = (settings.iter().map(|s| s.keyword.as_str())).chain(FUNCTION_KEYWORDS);
    let hint = posg_fsc::game::closest(key, all)
        .map_or(String::new(), |k| format!("; did you mean '{k}'?"));
    PyTypeError::new_err(format!(
        "{function}() got an unexpected keyword argument '{key}'{hint}"
    ))
}

/// The keywords of `solve`, `sweep`, `evaluate` and `certify` that are not
/// settings.
const FUNCTION_KEYWORDS: [&str; 12] = [
    "ltl",
    "props",
    "def_nodes",
    "adv_nodes",
    "defender",
    "adversary",
    "on_iteration",
    "progress",
    "out",
    "force",
    "allow_unused_propositions",
    "gradient",
];

/// A whole number (anything with `__index__`, not a bool or a float);
/// a `TypeError` naming `name` otherwise.
fn whole(name: &str, value: &Bound<'_, PyAny>) -> PyResult<i128> {
    let type_error = || {
        let type_name = value.get_type().name().map(|n| n.to_string());
        PyTypeError::new_err(format!(
            "{name} must be a whole number, not {}",
            type_name.unwrap_or_default()
        ))
    };
    if value.is_instance_of::<PyBool>() || value.is_instance_of::<PyFloat>() {
        return Err(type_error());
    }
    value.extract().map_err(|_| type_error())
}

/// A whole number of at least `least`: a `SettingsError` (a ValueError)
/// naming `name` below it, never an `OverflowError`.
fn at_least(name: &str, value: &Bound<'_, PyAny>, least: i128) -> PyResult<usize> {
    let number = whole(name, value)?;
    if number < least {
        return Err(crate::errors::raise(
            crate::errors::Kind::Settings,
            format!("{name} must be at least {least}, got {number}"),
        ));
    }
    usize::try_from(number)
        .map_err(|_| PyValueError::new_err(format!("{name} {number} is too large")))
}

/// A controller size: a whole number of at least 1.
pub fn size(name: &str, value: &Bound<'_, PyAny>) -> PyResult<usize> {
    at_least(name, value, 1)
}

/// A count: a whole number of at least 0.
pub fn count_of(name: &str, value: &Bound<'_, PyAny>) -> PyResult<usize> {
    at_least(name, value, 0)
}

/// A list of sizes: one size, or a list, tuple or range of them.
pub fn sizes(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Vec<usize>> {
    let listed = value.is_instance_of::<PyList>()
        || value.is_instance_of::<PyTuple>()
        || value.is_instance_of::<pyo3::types::PyRange>();
    if !listed {
        return Ok(vec![size(name, value)?]);
    }
    let list = value
        .try_iter()?
        .enumerate()
        .map(|(i, item)| size(&format!("{name}[{i}]"), &item?))
        .collect::<PyResult<Vec<_>>>()?;
    if list.is_empty() {
        return Err(PyValueError::new_err(format!("{name} is empty")));
    }
    Ok(list)
}

/// A role: `"defender"` or `"adversary"`.
pub fn role(name: &str, value: &str) -> PyResult<Role> {
    match value {
        "defender" => Ok(Role::Defender),
        "adversary" => Ok(Role::Adversary),
        other => Err(PyValueError::new_err(format!(
            "{name} must be \"defender\" or \"adversary\", not {other:?}"
        ))),
    }
}
