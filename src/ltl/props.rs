//! Property files of Storm, PRISM and PAYNT (`sketch.props`): the one
//! probability query they hold, as the defender's LTL objective
//! (formats.md section 6).
//!
//! A file holds one query `<<P>> Pmax=? [ PATH ]` or `<<P>> Pmin=? [ PATH ]`,
//! optionally named (`"name": ...`) and ended by `;` as Storm writes it,
//! with `//` comments and blank lines around it. `<<P>>` names the player
//! who optimises (the defender of a turn-based game read from DRN);
//! without it the query is a POMDP's or an MDP's. `PATH` is any LTL path
//! formula the parser of [`super::parse`] accepts (labels in double
//! quotes, as Storm writes them: `F "goal"`, `G !"crash" & F "goal"`).
//! `Pmax` makes `PATH` the defender's objective; `Pmin` makes its
//! complement the objective (`F "goal"` becomes `G !goal`), since
//! minimising the probability of `PATH` is maximising that of `!PATH`.
//! Everything else (reward and time queries, bounds such as `P>=0.5`,
//! several queries, constants, bounded operators such as `F<=10`) is an
//! error naming the line and column ([`parse_props`]), and the file too
//! ([`from_props_str`], as the command line reports it).

use thiserror::Error;

use super::{Formula, parse};
use crate::game::ModelError;

/// The query of a property file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Property {
    /// The optimising player `P` of `<<P>>`, if the query names one.
    pub player: Option<u64>,
    /// `true` for `Pmax`, `false` for `Pmin`.
    pub maximise: bool,
    /// The path formula as written.
    pub path: Formula,
    /// The formula whose probability the defender maximises: `path` for
    /// `Pmax`, its complement for `Pmin`.
    pub objective: Formula,
    /// The 1-based line of the query.
    pub line: usize,
    /// The 1-based column (in characters) where the query starts after its
    /// name: that of `<<P>>` when it names a player.
    pub column: usize,
}

impl Property {
    /// Where the query is in the property file `file`, as errors name it:
    /// `FILE: line L, column C`.
    pub fn position(&self, file: &str) -> String {
        format!("{file}: line {}, column {}", self.line, self.column)
    }
}

/// Why a text is not a property file posg-fsc can solve.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
#[error("line {line}, column {column}: {message}")]
pub struct PropsError {
    /// The 1-based line.
    pub line: usize,
    /// The 1-based column (in characters).
    pub column: usize,
    /// What was found and what was expected there.
    pub message: String,
}

/// Reads the one query of a property file (module documentation); a
/// leading byte-order mark is skipped.
pub fn parse_props(text: &str) -> Result<Property, PropsError> {
    let mut found: Option<Property> = None;
    let text = crate::game::reading::without_bom(text);
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = without_comment(raw);
        if content.trim().is_empty() {
            continue;
        }
        if let Some(first) = &found {
            return Err(PropsError {
                line,
                column: 1 + indent(content),
                message: format!(
                    "a second property (the first is on line {}): give a file with one",
                    first.line
                ),
            });
        }
        found = Some(query(content, line)?);
    }
    found.ok_or(PropsError {
        line: 1,
        column: 1,
        message: "the file holds no property (expected `<<P>> Pmax=? [ PATH ]`)".into(),
    })
}

/// `line` up to its `//` comment, if any: a `//` outside double quotes
/// (inside them it belongs to a name or a label).
fn without_comment(line: &str) -> &str {
    let mut quoted = false;
    for (i, c) in line.char_indices() {
        match c {
            '"' => quoted = !quoted,
            '/' if !quoted && line[i + 1..].starts_with('/') => return &line[..i],
            _ => {}
        }
    }
    line
}

/// [`parse_props`] for the property file `file_name`: an error names the
/// file, the line and the column as [`Property::position`] does
/// (`FILE: line L, column C: message`).
pub fn from_props_str(text: &str, file_name: &str) -> Result<Property, ModelError> {
    parse_props(text).map_err(|error| {
        ModelError::new(
            format!("{file_name}: line {}, column {}", error.line, error.column),
            error.message,
        )
    })
}

/// The number of characters before the first non-blank one.
fn indent(text: &str) -> usize {
    text.chars().take_while(|c| c.is_whitespace()).count()
}

/// A cursor over one line, for errors with columns.
struct Cursor<'a> {
    text: &'a str,
    /// The byte offset of the unread part.
    at: usize,
    line: usize,
}

impl<'a> Cursor<'a> {
    fn rest(&self) -> &'a str {
        &self.text[self.at..]
    }

    fn skip_blanks(&mut self) {
        self.at = self.text.len() - self.rest().trim_start().len();
    }

    fn column(&self) -> usize {
        self.text[..self.at].chars().count() + 1
    }

    fn error(&self, message: impl Into<String>) -> PropsError {
        PropsError {
            line: self.line,
            column: self.column(),
            message: message.into(),
        }
    }

    /// Consumes `token` (after blanks) if it is next.
    fn eat(&mut self, token: &str) -> bool {
        self.skip_blanks();
        if self.rest().starts_with(token) {
            self.at += token.len();
            true
        } else {
            false
        }
    }

    /// What comes next, for messages: the next word or character.
    fn found(&self) -> String {
        let rest = self.rest().trim_start();
        match rest.split_whitespace().next() {
            Some(word) => format!("`{word}`"),
            None => "the end of the line".into(),
        }
    }
}

/// `["name":] [<<P>>] P(max|min)=? [ PATH ] [;]` on one line.
fn query(text: &str, line: usize) -> Result<Property, PropsError> {
    let mut cursor = Cursor { text, at: 0, line };
    skip_name(&mut cursor)?;
    cursor.skip_blanks();
    let column = cursor.column();
    let player = coalition(&mut cursor)?;
    cursor.skip_blanks();
    let maximise = if cursor.eat("Pmax=?") {
        true
    } else if cursor.eat("Pmin=?") {
        false
    } else {
        return Err(unsupported_query(&cursor));
    };
    cursor.skip_blanks();
    let open = cursor.column();
    if !cursor.eat("[") {
        return Err(cursor.error(format!(
            "expected `[` and a path formula after P{}=?, found {}",
            if maximise { "max" } else { "min" },
            cursor.found()
        )));
    }
    let inner_start = cursor.at;
    let close = text
        .rfind(']')
        .filter(|&c| c >= inner_start)
        .ok_or_else(|| PropsError {
            line,
            column: open,
            message: "this `[` has no closing `]`".into(),
        })?;
    let path_text = &text[inner_start..close];
    let path = parse(path_text).map_err(|e| PropsError {
        line,
        column: text[..inner_start].chars().count() + e.column,
        message: format!("in the path formula: {}", e.message),
    })?;
    cursor.at = close + 1;
    cursor.eat(";");
    cursor.skip_blanks();
    if !cursor.rest().is_empty() {
        return Err(cursor.error(format!("unexpected {} after the query", cursor.found())));
    }
    let objective = if maximise {
        path.clone()
    } else {
        complement(&path)
    };
    Ok(Property {
        player,
        maximise,
        path,
        objective,
        line,
        column,
    })
}

/// Skips an optional `"name":` prefix.
fn skip_name(cursor: &mut Cursor) -> Result<(), PropsError> {
    cursor.skip_blanks();
    if !cursor.rest().starts_with('"') {
        return Ok(());
    }
    let end = cursor.rest()[1..]
        .find('"')
        .ok_or_else(|| cursor.error("unterminated property name: expected `\"`"))?;
    cursor.at += end + 2;
    if !cursor.eat(":") {
        return Err(cursor.error(format!(
            "expected `:` after the property's name, found {}",
            cursor.found()
        )));
    }
    Ok(())
}

/// An optional `<<P>>` with one player number.
fn coalition(cursor: &mut Cursor) -> Result<Option<u64>, PropsError> {
    if !cursor.eat("<<") {
        return Ok(None);
    }
    cursor.skip_blanks();
    let inside_start = cursor.at;
    let end = cursor
        .rest()
        .find(">>")
        .ok_or_else(|| cursor.error("unterminated coalition: expected `>>`"))?;
    let inside = cursor.rest()[..end].trim();
    let player = inside.parse().map_err(|_| {
        cursor.error(format!(
            "the coalition `<<{inside}>>` must be one player number (a game has two players: \
             the defender, who optimises, and the adversary)"
        ))
    })?;
    cursor.at = inside_start + end + 2;
    Ok(Some(player))
}

/// The error for a query other than `Pmax=?`/`Pmin=?`.
fn unsupported_query(cursor: &Cursor) -> PropsError {
    let rest = cursor.rest();
    let message = if rest.starts_with('R') || rest.starts_with('T') {
        format!(
            "{} is a reward or time query; posg-fsc solves probability queries `Pmax=? [ PATH ]` \
             and `Pmin=? [ PATH ]`",
            cursor.found()
        )
    } else if rest.starts_with('P') {
        format!(
            "{}: only the queries `Pmax=?` and `Pmin=?` can be solved (not a bound or an \
             unoptimised `P=?`)",
            cursor.found()
        )
    } else {
        format!(
            "expected a query `Pmax=? [ PATH ]` or `Pmin=? [ PATH ]`, found {}",
            cursor.found()
        )
    };
    cursor.error(message)
}

/// The complement of a path formula, with the negation pushed through the
/// outer `F`, `G`, `X` and `!` so that it reads as people write it
/// (`!F goal` is `G !goal`).
pub fn complement(formula: &Formula) -> Formula {
    match formula {
        Formula::Finally(f) => Formula::Globally(Box::new(complement(f))),
        Formula::Globally(f) => Formula::Finally(Box::new(complement(f))),
        Formula::Next(f) => Formula::Next(Box::new(complement(f))),
        other => other.negate(),
    }
}
