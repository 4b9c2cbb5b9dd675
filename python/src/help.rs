//! The settings `solve` and `sweep` take as keywords, with their defaults
//! and meanings, for `help()` and `posg_fsc.settings()`: the meanings are
//! the documentation of the fields of the library's `Settings` (the same
//! text the command line's `--help` shows), read from the library's source
//! when the binding is compiled, so that they cannot drift apart.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::Value;

use crate::convert::to_python;

/// The source of the optimiser's settings.
const OPTIMISER: &str = include_str!("../../src/optimise/settings.rs");
/// The source of the support synthesis' settings (the `sat` structures).
const SYNTHESIS: &str = include_str!("../../src/synthesis/mod.rs");

/// One setting: its keyword, the field it sets and its meaning.
pub struct Setting {
    /// The keyword (`tolerance` for the field `solver_tolerance`,
    /// `synthesis_time_budget` for the synthesis' `time_budget`).
    pub keyword: String,
    /// The field's name in its struct.
    pub field: String,
    /// Whether the field is the synthesis' (inside the optimiser's
    /// `synthesis`).
    pub synthesis: bool,
    /// The field's documentation, on one line.
    pub meaning: String,
}

/// The documented `pub` fields of `pub struct Settings` in `source`:
/// `(name, documentation)`.
fn fields(source: &str) -> Vec<(String, String)> {
    let Some(start) = source.find("pub struct Settings {") else {
        return Vec::new();
    };
    let body = &source[start..];
    let body = &body[..body.find("\n}").unwrap_or(body.len())];
    let mut fields = Vec::new();
    let mut doc: Vec<&str> = Vec::new();
    for line in body.lines().skip(1).map(str::trim) {
        if let Some(text) = line.strip_prefix("///") {
            doc.push(text.trim());
        } else if let Some(field) = line.strip_prefix("pub ") {
            let name = field.split(':').next().unwrap_or("").trim();
            fields.push((name.to_string(), doc.join(" ")));
            doc.clear();
        }
    }
    fields
}

/// Every setting `solve` and `sweep` take, the optimiser's then the
/// synthesis' (not its `mode`, which the `sat` source chooses itself; not
/// `synthesis`, whose fields are keywords of their own).
pub fn settings() -> Vec<Setting> {
    let optimiser = of(
        OPTIMISER,
        false,
        "synthesis",
        ("solver_tolerance", "tolerance"),
    );
    let synthesis = of(
        SYNTHESIS,
        true,
        "mode",
        ("time_budget", "synthesis_time_budget"),
    );
    optimiser.chain(synthesis).collect()
}

/// The settings of the struct in `source` (the synthesis' with
/// `synthesis`), without the field `left_out`, the field `renamed.0`
/// under the keyword `renamed.1`.
fn of(
    source: &str,
    synthesis: bool,
    left_out: &str,
    renamed: (&'static str, &'static str),
) -> impl Iterator<Item = Setting> {
    let left_out = left_out.to_string();
    fields(source)
        .into_iter()
        .filter(move |(name, _)| *name != left_out)
        .map(move |(field, meaning)| Setting {
            keyword: if field == renamed.0 {
                renamed.1.to_string()
            } else {
                field.clone()
            },
            field,
            synthesis,
            meaning,
        })
}

/// Each setting's default, as JSON (`None` where the default is not
/// written, as `lu_limit`'s).
fn default_of(setting: &Setting) -> Option<Value> {
    let optimiser = serde_json::to_value(posg_fsc::optimise::Settings::default()).ok()?;
    let owner = if setting.synthesis {
        optimiser.get("synthesis")?
    } else {
        &optimiser
    };
    let written = owner.get(&setting.field).cloned();
    // `summary.json` leaves out the LU limit where it is the default.
    written.or_else(|| {
        (setting.field == "lu_limit").then(|| Value::from(posg_fsc::value::DEFAULT_LU_LIMIT))
    })
}

/// Every setting of `solve` and `sweep` as a dict: `keyword`, `default`
/// and `meaning` (the command line's help text of the option). `help()` of
/// `posg_fsc.solve` and `posg_fsc.sweep` lists them too.
#[pyfunction(name = "settings")]
pub fn settings_list(py: Python<'_>) -> PyResult<Py<PyList>> {
    let list = PyList::empty(py);
    for setting in settings() {
        let entry = PyDict::new(py);
        entry.set_item("keyword", &setting.keyword)?;
        let default = match default_of(&setting) {
            Some(value) => to_python(py, &value)?.unbind(),
            None => py.None(),
        };
        entry.set_item("default", default)?;
        entry.set_item("meaning", &setting.meaning)?;
        list.append(entry)?;
    }
    Ok(list.unbind())
}
