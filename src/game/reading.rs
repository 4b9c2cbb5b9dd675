//! What every reader and writer of the crate's files shares: text and
//! bytes read whole (a UTF-8 byte order mark skipped), JSON parsed with the
//! path of every error ([`Located`]), probabilities and distributions
//! checked and renormalised within [`super::DISTRIBUTION_TOLERANCE`], the
//! rules for names and propositions, and the game facts the JSON and the
//! binary readers both check (formats.md sections 1, 6 and 11).

use std::borrow::Borrow;
use std::hash::Hash;
use std::path::Path;

use rustc_hash::FxHashMap;
use serde::Deserialize;

use super::{ModelError, Player, Posg};

/// The only format version this crate reads and writes (`"posg": 1`).
pub const FORMAT_VERSION: u64 = 1;

/// Reads a whole file, without a leading byte-order mark
/// ([`without_bom`]); an I/O failure becomes a [`ModelError`] on the file.
pub(crate) fn read_text(path: &Path, file_name: &str) -> Result<String, ModelError> {
    let mut text = std::fs::read_to_string(path)
        .map_err(|e| ModelError::new(file_name, format!("cannot read the file: {e}")))?;
    if text.starts_with(BOM) {
        text.drain(..BOM.len_utf8());
    }
    Ok(text)
}

/// The UTF-8 byte-order mark that some editors write at the start of a file.
const BOM: char = '\u{feff}';

/// `text` without a leading byte-order mark: every text reader (game,
/// controller, strategy, DRN, props, HOA) skips one (formats.md, top).
pub(crate) fn without_bom(text: &str) -> &str {
    text.strip_prefix(BOM).unwrap_or(text)
}

/// [`without_bom`] on the bytes of a file.
pub(crate) fn bytes_without_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(bytes)
}

/// Writes a whole file; an I/O failure becomes a [`ModelError`] on the file.
pub(crate) fn write_text(path: &Path, text: &str) -> Result<(), ModelError> {
    write_bytes(path, text.as_bytes())
}

/// [`write_text`] for bytes.
pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), ModelError> {
    std::fs::write(path, bytes).map_err(|e| {
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
    let text = without_bom(text);
    match serde_json::from_str(text) {
        Ok(value) => Ok(value),
        Err(_) => parse_tracking_paths(text, file_name),
    }
}

/// [`parse`] with the JSON path of every value tracked, for its error message.
pub(super) fn parse_tracking_paths<'de, T: Deserialize<'de>>(
    text: &'de str,
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
pub(super) fn is_probability(p: f64) -> bool {
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
pub(super) fn normalisation(
    total: f64,
    len: usize,
    at: &Located,
) -> Result<Option<f64>, ModelError> {
    let shown = (total * 1e9).round() / 1e9 + 0.0;
    super::check_total(total, shown, "probabilities").map_err(|message| at.error(message))?;
    Ok(super::rescale_by(total, len))
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

/// The single action and observation of the adversary of a POMDP.
pub(super) const POMDP_SYMBOL: &str = "_";

/// Whether the game must define `T(. | s, u, v)`: some observation of `s`
/// enables `u` for the defender and some enables `v` for the adversary
/// (formats.md section 6). Other triples keep no entries.
pub(super) fn triple_required(game: &Posg, s: usize, u: usize, v: usize) -> bool {
    game.defender.action_enabled_in_state(s, u) && game.adversary.action_enabled_in_state(s, v)
}

/// What is wrong with `label` as the label of an action of a player with
/// `actions`, whose other labels are the keys of `earlier` (each with its
/// action; formats.md section 6): empty or with whitespace (no DRN label
/// is), a valid name (an action is named by such a label itself, so only
/// the labels that are not names are given), or the label of another
/// action; `None` when nothing is.
pub(super) fn action_label_problem<N: AsRef<str>, L: Borrow<str> + Eq + Hash>(
    actions: &[N],
    earlier: &FxHashMap<L, usize>,
    label: &str,
) -> Option<String> {
    if label.is_empty() || label.chars().any(char::is_whitespace) {
        return Some(format!(
            "label `{label}` is empty or has whitespace, which no DRN label has"
        ));
    }
    if is_valid_name(label) {
        return Some(format!(
            "label `{label}` is a valid action name; labels are given only for actions \
             renamed from a label that is not a name"
        ));
    }
    earlier.get(label).map(|&u| {
        format!(
            "label `{label}` is also the label of action `{}`",
            actions[u].as_ref()
        )
    })
}

/// Checks names against `[A-Za-z0-9_.:-]+` and for uniqueness; returns name -> index.
pub(super) fn index_names<'n, N: AsRef<str>>(
    names: &'n [N],
    at: &Located,
    kind: &str,
) -> Result<FxHashMap<&'n str, usize>, ModelError> {
    let mut index = FxHashMap::with_capacity_and_hasher(names.len(), Default::default());
    for (i, name) in names.iter().enumerate() {
        let name = name.as_ref();
        if !is_valid_name(name) {
            return Err(at.index(i).error(format!(
                "`{name}` is not a valid {kind} name (expected [A-Za-z0-9_.:-]+)"
            )));
        }
        if let Some(first) = index.insert(name, i) {
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
        action_labels: Vec::new(),
    }
}

/// How to make a game of a model in a peer tool's format, for errors.
const EXPORT_DRN: &str = "posg-fsc reads games as JSON (docs/formats.md section 1), \
     their binary form (section 11) or Storm's DRN (section 6); export the model as DRN \
     with `storm --prism MODEL --buildfull --exportbuild MODEL.drn` (JANI: `--jani`), or \
     with stormpy's `stormpy.io.export_to_drn(model, PATH)`";

/// The error for a file that is not a game but a PRISM or JANI model or a
/// property file, recognised by how it begins; `None` for anything else.
pub(super) fn foreign_format(text: &str, file_name: &str) -> Option<ModelError> {
    let first_word = |text: &str| {
        (text.lines())
            .map(str::trim)
            .find(|line| !line.is_empty() && !line.starts_with("//"))
            .and_then(|line| line.split(|c: char| !c.is_ascii_alphanumeric()).next())
            .map(str::to_string)
    };
    let text = without_bom(text);
    let what = if text.trim_start().starts_with('{') {
        text.contains("\"jani-version\"")
            .then_some("a JANI model")?
    } else {
        let word = first_word(text)?;
        let prism = [
            "pomdp",
            "mdp",
            "dtmc",
            "ctmc",
            "smg",
            "csg",
            "pta",
            "probabilistic",
            "nondeterministic",
            "stochastic",
            "module",
            "const",
            "formula",
            "observables",
            "player",
            "global",
        ];
        let query = [
            "P", "Pmax", "Pmin", "R", "Rmax", "Rmin", "T", "Tmax", "Tmin", "filter",
        ];
        let property = text.trim_start().starts_with("<<") || query.contains(&word.as_str());
        if prism.contains(&word.as_str()) {
            "a PRISM model"
        } else if property {
            return Some(ModelError::new(
                file_name,
                "this is a property file, not a game: a query goes with `--props FILE` \
                 beside the game",
            ));
        } else {
            return None;
        }
    };
    Some(ModelError::new(
        file_name,
        format!("this is {what}, not a game: {EXPORT_DRN}"),
    ))
}
