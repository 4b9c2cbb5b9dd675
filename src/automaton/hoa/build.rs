//! The HOA builder: the parsed header and `State:` blocks to an
//! [`EmersonLeiAutomaton`].
//!
//! Contract: [`build`] evaluates every label (aliases in order, AP indices
//! below `|AP|`) to its set of letters, enters each edge on its letters and
//! returns the complete, deterministic transition table with the header's
//! propositions, initial state and acceptance condition. Errors
//! ([`HoaError::Syntax`] at the offending state or edge): a state or AP index
//! out of range, a state defined twice, labelled and unlabelled edges mixed,
//! a labelled state with labelled edges, more implicit edges than letters, two
//! edges on one letter (nondeterminism), a letter without an edge
//! (incompleteness: also a state without a `State:` block, found before the
//! table is allocated), and a table larger than `MAX_TABLE_ENTRIES`;
//! [`HoaError::Automaton`] if [`EmersonLeiAutomaton::new`] refuses the result.

use super::HoaError;
use super::lex::{Pos, error_at};
use super::parse::{Header, Label, RawState};
use crate::automaton::emerson_lei::{Edge, EmersonLeiAutomaton, MAX_TABLE_ENTRIES};

/// The letters of `2^AP` a label holds on, by letter.
type LetterSet = Vec<bool>;

/// Evaluates labels over the letters of the automaton.
struct Evaluator<'a> {
    propositions: &'a [String],
    aliases: Vec<(&'a str, LetterSet)>,
}

impl<'a> Evaluator<'a> {
    /// Evaluates the header's aliases in order.
    fn new(header: &'a Header) -> Result<Self, HoaError> {
        let mut evaluator = Evaluator {
            propositions: &header.propositions,
            aliases: Vec::new(),
        };
        for (name, label) in &header.aliases {
            let letters = evaluator.letters(label)?;
            evaluator.aliases.push((name, letters));
        }
        Ok(evaluator)
    }

    /// `2^|AP|`.
    fn num_letters(&self) -> usize {
        1 << self.propositions.len()
    }

    /// The letters on which `label` holds.
    fn letters(&self, label: &Label) -> Result<LetterSet, HoaError> {
        let n = self.num_letters();
        Ok(match label {
            Label::Constant(value) => vec![*value; n],
            Label::Proposition(index, pos) => {
                if *index >= self.propositions.len() as u64 {
                    return error_at(
                        *pos,
                        format!(
                            "AP index {index} out of range: `AP:` declares {} propositions",
                            self.propositions.len()
                        ),
                    );
                }
                (0..n).map(|a| (a >> index) & 1 == 1).collect()
            }
            Label::Alias(name, pos) => match self.aliases.iter().find(|(k, _)| k == name) {
                Some((_, letters)) => letters.clone(),
                None => return error_at(*pos, format!("unknown alias `@{name}`")),
            },
            Label::Not(inner) => self.letters(inner)?.into_iter().map(|b| !b).collect(),
            Label::And(parts) => self.combine(parts, true, |a, b| a && b)?,
            Label::Or(parts) => self.combine(parts, false, |a, b| a || b)?,
        })
    }

    /// Folds the letter sets of `parts` with `op`, starting from `unit`.
    fn combine(
        &self,
        parts: &[Label],
        unit: bool,
        op: impl Fn(bool, bool) -> bool,
    ) -> Result<LetterSet, HoaError> {
        parts
            .iter()
            .try_fold(vec![unit; self.num_letters()], |acc, part| {
                let letters = self.letters(part)?;
                Ok(acc
                    .into_iter()
                    .zip(letters)
                    .map(|(a, b)| op(a, b))
                    .collect())
            })
    }

    /// A letter as `a&!b` over the proposition names.
    fn letter_text(&self, letter: usize) -> String {
        if self.propositions.is_empty() {
            return "t (there are no propositions)".to_string();
        }
        self.propositions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if (letter >> i) & 1 == 1 {
                    p.clone()
                } else {
                    format!("!{p}")
                }
            })
            .collect::<Vec<_>>()
            .join("&")
    }
}

/// The automaton the parsed header and states describe; `end` is the
/// position of `--END--`.
pub(super) fn build(
    header: &Header,
    states: &[RawState],
    end: Pos,
) -> Result<EmersonLeiAutomaton, HoaError> {
    let (start, start_pos) = header.start;
    let evaluator = Evaluator::new(header)?;
    let num_states = state_count(header, states, start)?;
    if start >= num_states as u64 {
        return error_at(start_pos, format!("initial state {start} out of range"));
    }
    // The states are checked before the table is allocated: a `States:`
    // count far beyond the body (`States: 16777216` over one state) would
    // otherwise allocate a table of that many rows.
    for state in states {
        state_index(state.id, state.pos, num_states)?;
    }
    if let Some(q) = first_undefined(states, num_states) {
        return error_at(
            end,
            format!(
                "incomplete automaton: state {q} has no edge on letter {}",
                evaluator.letter_text(0)
            ),
        );
    }
    let letters = evaluator.num_letters();
    let mut table: Vec<Option<Edge>> = vec![None; num_states * letters];
    let mut defined = vec![false; num_states];
    for state in states {
        let q = state_index(state.id, state.pos, num_states)?;
        if defined[q] {
            return error_at(state.pos, format!("state {q} is defined twice"));
        }
        defined[q] = true;
        fill_state(
            &evaluator,
            state,
            num_states,
            &mut table[q * letters..(q + 1) * letters],
        )?;
    }
    let edges = complete_table(&evaluator, states, &table, end)?;
    Ok(EmersonLeiAutomaton::new(
        header.propositions.clone(),
        num_states,
        start as usize,
        edges,
        header.num_marks,
        header.acceptance.clone(),
    )?)
}

/// The number of states: `States:` if given, else one more than the largest
/// state number used. Fails if the transition table would be too large.
fn state_count(header: &Header, states: &[RawState], start: u64) -> Result<usize, HoaError> {
    let (count, pos) = header.states.unwrap_or_else(|| {
        let largest = states
            .iter()
            .flat_map(|s| std::iter::once(s.id).chain(s.edges.iter().map(|e| e.target.0)))
            .chain(std::iter::once(start))
            .max()
            .unwrap_or(0);
        (largest.saturating_add(1), header.body)
    });
    let letters = 1u64 << header.propositions.len();
    if count.saturating_mul(letters) > MAX_TABLE_ENTRIES as u64 {
        return error_at(
            pos,
            format!(
                "{count} states over {letters} letters exceed the supported table size \
                 of {MAX_TABLE_ENTRIES} transitions"
            ),
        );
    }
    Ok(count as usize)
}

/// The first state below `num_states` without a `State:` block, if the
/// body has fewer blocks than states (such a state has no edges).
fn first_undefined(states: &[RawState], num_states: usize) -> Option<u64> {
    if states.len() >= num_states {
        return None;
    }
    let mut ids: Vec<u64> = states.iter().map(|s| s.id).collect();
    ids.sort_unstable();
    ids.dedup();
    (0..).find(|q| ids.binary_search(q).is_err())
}

/// `id` as a state index below `num_states`.
fn state_index(id: u64, pos: Pos, num_states: usize) -> Result<usize, HoaError> {
    if id >= num_states as u64 {
        return error_at(
            pos,
            format!("state {id} out of range: `States: {num_states}`"),
        );
    }
    Ok(id as usize)
}

/// Enters the edges of `state` into its row of the table, failing on
/// nondeterminism.
fn fill_state(
    evaluator: &Evaluator,
    state: &RawState,
    num_states: usize,
    row: &mut [Option<Edge>],
) -> Result<(), HoaError> {
    let labelled = state.edges.iter().filter(|e| e.label.is_some()).count();
    if let Some(edge) = state
        .edges
        .iter()
        .find(|e| e.label.is_some() != (labelled > 0))
    {
        return error_at(
            edge.pos,
            "a state's edges must be all labelled or all unlabelled",
        );
    }
    if state.label.is_some() && labelled > 0 {
        return error_at(state.pos, "a state with a label must have unlabelled edges");
    }
    let state_letters = state
        .label
        .as_ref()
        .map(|l| evaluator.letters(l))
        .transpose()?;
    for (i, edge) in state.edges.iter().enumerate() {
        let letters = match (&edge.label, &state_letters) {
            (Some(label), _) => evaluator.letters(label)?,
            (None, Some(letters)) => letters.clone(),
            (None, None) => implicit_letter(i, row.len(), edge.pos)?,
        };
        let target = state_index(edge.target.0, edge.target.1, num_states)? as u32;
        let entry = Edge {
            target,
            marks: edge.marks | state.marks,
        };
        for (letter, _) in letters.iter().enumerate().filter(|&(_, &on)| on) {
            if row[letter].is_some() {
                return error_at(
                    edge.pos,
                    format!(
                        "nondeterministic: state {} has a second edge on letter {}",
                        state.id,
                        evaluator.letter_text(letter)
                    ),
                );
            }
            row[letter] = Some(entry);
        }
    }
    Ok(())
}

/// The letter set of the `i`-th implicit edge of a state.
fn implicit_letter(i: usize, letters: usize, pos: Pos) -> Result<LetterSet, HoaError> {
    if i >= letters {
        return error_at(
            pos,
            format!("more implicit edges than the {letters} letters"),
        );
    }
    Ok((0..letters).map(|a| a == i).collect())
}

/// The filled table, or the first state and letter without an edge.
fn complete_table(
    evaluator: &Evaluator,
    states: &[RawState],
    table: &[Option<Edge>],
    end: Pos,
) -> Result<Vec<Edge>, HoaError> {
    let letters = evaluator.num_letters();
    let missing = table.iter().position(Option::is_none);
    let Some(index) = missing else {
        return Ok(table.iter().flatten().copied().collect());
    };
    let (q, letter) = (index / letters, index % letters);
    let pos = states
        .iter()
        .find(|s| s.id == q as u64)
        .map_or(end, |s| s.pos);
    error_at(
        pos,
        format!(
            "incomplete automaton: state {q} has no edge on letter {}",
            evaluator.letter_text(letter)
        ),
    )
}
