//! Action names for DRN choice labels (formats.md section 6).
//!
//! Storm writes any label a model has, without whitespace (SAYNT's models
//! label their choices `(init)`, `(n)`, ...), while action names in a game
//! are `[A-Za-z0-9_.:-]+`. A label that is a name is kept as written; any
//! other label is renamed, deterministically and so that distinct labels
//! keep distinct names: every character outside the name alphabet becomes
//! `_`, and where that name is already taken (by a label of the file that
//! is a name, by a label renamed before it in order of first appearance, or
//! by `_`, the idle action of turn-based games) `.2`, `.3`, ... is appended,
//! the first that is free. The game keeps the label as written
//! ([`crate::game::Player::action_label`]).

use rustc_hash::{FxHashMap, FxHashSet};

use super::Model;
use super::turn_based::IDLE;
use crate::game::reading::is_valid_name;

impl Model {
    /// Gives each choice label that is not a valid name its name
    /// ([`renamed_labels`]), keeping the pairs in [`Model::renamed`].
    pub(super) fn rename_actions(&mut self) {
        let labels = self
            .states
            .iter()
            .flat_map(|s| &s.choices)
            .map(|c| c.label.as_str());
        self.renamed = renamed_labels(labels);
        let names: FxHashMap<&str, &str> = self
            .renamed
            .iter()
            .map(|(label, name)| (label.as_str(), name.as_str()))
            .collect();
        for choice in self.states.iter_mut().flat_map(|s| &mut s.choices) {
            if let Some(name) = names.get(choice.label.as_str()) {
                choice.label = name.to_string();
            }
        }
    }

    /// `(u, label)` for each of `actions` (names) renamed from `label`: a
    /// player's [`crate::game::Player::action_label`]s.
    pub(super) fn action_labels(&self, actions: &[String]) -> Vec<(usize, String)> {
        let labels: FxHashMap<&str, &str> = self
            .renamed
            .iter()
            .map(|(label, name)| (name.as_str(), label.as_str()))
            .collect();
        actions
            .iter()
            .enumerate()
            .filter_map(|(u, name)| labels.get(name.as_str()).map(|l| (u, l.to_string())))
            .collect()
    }
}

impl Model {
    /// The actions a row of `enabled` offers, separated by commas, each as
    /// its label is written in the file: a renamed label followed by its
    /// name, as in `(n) (read as _n_)`.
    pub(super) fn offered(&self, row: &[bool], actions: &[String]) -> String {
        let labels: FxHashMap<&str, &str> = self
            .renamed
            .iter()
            .map(|(label, name)| (name.as_str(), label.as_str()))
            .collect();
        let listed: Vec<String> = (0..actions.len())
            .filter(|&u| row[u])
            .map(|u| match labels.get(actions[u].as_str()) {
                Some(label) => format!("{label} (read as {})", actions[u]),
                None => actions[u].clone(),
            })
            .collect();
        listed.join(", ")
    }
}

/// The labels among `labels` (in file order, repeats allowed) that are not
/// names, each once in order of first appearance, with their names.
pub(super) fn renamed_labels<'a>(
    labels: impl Iterator<Item = &'a str> + Clone,
) -> Vec<(String, String)> {
    let mut taken: FxHashSet<String> = labels
        .clone()
        .filter(|l| is_valid_name(l))
        .map(str::to_string)
        .collect();
    taken.insert(IDLE.to_string());
    let mut seen = FxHashSet::default();
    let mut renamed = Vec::new();
    for label in labels.filter(|l| !is_valid_name(l)) {
        if seen.insert(label) {
            let name = free_name(&restricted(label), &taken);
            taken.insert(name.clone());
            renamed.push((label.to_string(), name));
        }
    }
    renamed
}

/// The label Storm writes for a choice without one.
pub(super) const NO_LABEL: &str = "__NOLABEL__";

/// The label of the `index`-th choice of a state that Storm wrote without
/// one (`__NOLABEL__`): `(unlabelled #index)`, named `unlabelled_index`
/// ([`restricted`]).
pub(super) fn unlabelled(index: usize) -> String {
    format!("(unlabelled #{index})")
}

/// `i` of a label `(unlabelled #i)` ([`unlabelled`]).
fn unlabelled_index(label: &str) -> Option<&str> {
    label
        .strip_prefix("(unlabelled #")
        .and_then(|rest| rest.strip_suffix(')'))
        .filter(|i| !i.is_empty() && i.bytes().all(|b| b.is_ascii_digit()))
}

/// `label` with every character outside `[A-Za-z0-9_.:-]` replaced by `_`;
/// `(unlabelled #i)` ([`unlabelled`]) is `unlabelled_i`.
fn restricted(label: &str) -> String {
    if let Some(index) = unlabelled_index(label) {
        return format!("unlabelled_{index}");
    }
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "_.:-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// `base`, or `base.2`, `base.3`, ...: the first not in `taken`.
fn free_name(base: &str, taken: &FxHashSet<String>) -> String {
    std::iter::once(base.to_string())
        .chain((2..).map(|k| format!("{base}.{k}")))
        .find(|name| !taken.contains(name))
        .expect("some suffix is free")
}

/// The sentence that tells the user the names of renamed labels (at most
/// [`LISTED`] of them, then how many more), if any label the model wrote
/// was renamed (an unlabelled choice's name, `unlabelled_i`, is no news).
pub(super) fn renaming_warning(file_name: &str, renamed: &[(String, String)]) -> Option<String> {
    let written: Vec<&(String, String)> = (renamed.iter())
        .filter(|(label, _)| unlabelled_index(label).is_none())
        .collect();
    if written.is_empty() {
        return None;
    }
    let listed: Vec<String> = (written.iter().take(LISTED))
        .map(|(label, name)| format!("`{label}` is `{name}`"))
        .collect();
    let more = match written.len().saturating_sub(LISTED) {
        0 => String::new(),
        n => format!(" and {n} more"),
    };
    Some(format!(
        "{file_name}: action labels that are not names ([A-Za-z0-9_.:-]+) are renamed: {}{more} \
         (docs/formats.md section 6); controllers name the actions so",
        listed.join(", ")
    ))
}

/// The most renamed labels a warning lists.
const LISTED: usize = 6;

#[cfg(test)]
mod tests {
    use super::renamed_labels;

    fn renamed(labels: &[&str]) -> Vec<(String, String)> {
        renamed_labels(labels.iter().copied())
    }

    fn pairs(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs
            .iter()
            .map(|&(a, b)| (a.to_string(), b.to_string()))
            .collect()
    }

    #[test]
    fn names_are_kept_and_other_labels_get_underscores() {
        assert_eq!(
            renamed(&["(init)", "north", "(n)", "__NOLABEL__", "(n)", "a:b.c-d"]),
            pairs(&[("(init)", "_init_"), ("(n)", "_n_")])
        );
        assert_eq!(renamed(&["é+x"]), pairs(&[("é+x", "__x")]));
    }

    #[test]
    fn a_taken_name_gets_the_first_free_suffix() {
        // `_n_` is a label of the file (even after `(n)`), so `(n)` is
        // `_n_.2`; `[n]` comes next and `{n}` after it; `?` would be `_`,
        // the idle action.
        assert_eq!(
            renamed(&["(n)", "[n]", "_n_", "_n_.3", "{n}", "?"]),
            pairs(&[
                ("(n)", "_n_.2"),
                ("[n]", "_n_.4"),
                ("{n}", "_n_.5"),
                ("?", "_.2")
            ])
        );
    }
}
