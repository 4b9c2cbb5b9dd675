//! Reading and writing automata in the Hanoi Omega-Automata format, HOA v1
//! and v1.1.
//!
//! [`parse_hoa`] reads a deterministic, complete automaton with an arbitrary
//! Emerson-Lei acceptance condition into an [`EmersonLeiAutomaton`];
//! [`read_hoa_dra`] also converts it to a state-based Rabin automaton.
//! [`write_hoa`] prints a [`Dra`] with state-based `Rabin n` acceptance.
//!
//! What the reader accepts:
//!
//! * header items `HOA: v1` or `HOA: v1.1` (Spot 2.12 writes v1.1 with
//!   `-H1.1`), `States:`, `Start:` (exactly one, a single state), `AP:`,
//!   `Alias:`, `Acceptance:` (`t`, `f`, `Fin(m)`, `Fin(!m)`, `Inf(m)`,
//!   `Inf(!m)`, `&`, `|`, parentheses), and the informative items
//!   `acc-name:`, `name:`, `tool:` and `properties:`, which are skipped like
//!   every other header item whose name starts with a lower-case letter
//!   (tool-specific ones such as `spot.highlight.edges:` or
//!   `controllable-AP:` included: names, like aliases, may contain `.` and
//!   `-`, as in Spot); the format says an item starting with an upper-case
//!   letter may change the meaning of the automaton, so an unknown one is an
//!   error, as is any other version;
//! * a body of `State:` lines (optional label, state number, optional quoted
//!   name, optional marks `{...}`), each followed by its edges: an optional
//!   label `[...]` over AP indices, `t`, `f`, `!`, `&`, `|`, parentheses and
//!   aliases, one target state and optional marks. A state label stands for
//!   the same label on all outgoing edges, and state marks for the same marks
//!   on all outgoing edges. Edges without labels are implicit: the `i`-th
//!   edge of a state reads the letter whose bits are those of `i` (AP 0 is
//!   the least significant bit);
//! * nested `/* ... */` comments anywhere between tokens, and quoted strings
//!   in which a backslash escapes the next character.
//!
//! The automaton must be deterministic and complete: the reader enumerates
//! all `2^|AP|` letters of every state and reports two edges on one letter
//! as nondeterminism, and a letter without an edge (or a state without a
//! `State:` block) as incompleteness. It adds no rejecting sink, because a
//! missing edge more often signals a translation mistake than an intent.
//! Errors carry the line and column (both from 1) of the offending token.
//!
//! The reader runs in three steps, one file each: `lex.rs` turns the text
//! into tokens with positions, `parse.rs` turns the tokens into a header and
//! the `State:` blocks as written, and `build.rs` evaluates the labels and
//! fills the transition table. `write.rs` is the writer.

mod build;
mod lex;
mod parse;
mod write;

use thiserror::Error;

use super::emerson_lei::{EmersonLeiAutomaton, to_state_based_rabin};
use super::{AutomatonError, Dra};

pub use write::write_hoa;

/// Why a HOA text could not be read.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum HoaError {
    /// The text is not a HOA v1 or v1.1 automaton of the kind this crate reads.
    #[error("line {line}, column {column}: {message}")]
    Syntax {
        /// The line of the offending token, from 1.
        line: usize,
        /// The column (in characters) of the offending token, from 1.
        column: usize,
        /// What was wrong or expected.
        message: String,
    },
    /// The automaton was read but could not be converted to a Rabin automaton.
    #[error("{0}")]
    Automaton(#[from] AutomatonError),
}

/// Reads a deterministic, complete HOA v1 or v1.1 automaton (see the
/// module documentation for what is supported); a leading byte-order mark
/// is skipped.
pub fn parse_hoa(text: &str) -> Result<EmersonLeiAutomaton, HoaError> {
    let tokens = lex::tokenize(crate::game::reading::without_bom(text))?;
    let (header, states, end) = parse::parse(tokens)?;
    build::build(&header, &states, end)
}

/// Reads a HOA v1 or v1.1 automaton with [`parse_hoa`] and converts it with
/// [`to_state_based_rabin`].
pub fn read_hoa_dra(text: &str) -> Result<Dra, HoaError> {
    Ok(to_state_based_rabin(&parse_hoa(text)?)?)
}
