//! Property files of Storm, PRISM and PAYNT (`sketch.props`): the one
//! query they hold, as the defender's objective (formats.md section 6).
//!
//! A file holds one query `<<P>> Pmax=? [ PATH ]` or `<<P>> Pmin=? [ PATH ]`,
//! or an expected-reward query `<<P>> R{"r"}min=? [ F T ]` (also `Rmax`, and
//! `Rmin`/`Rmax` without a name for a model's only reward model),
//! optionally named (`"name": ...`) and ended by `;` as Storm writes it,
//! with `//` comments and blank lines around it. `<<P>>` names the player
//! who optimises (the defender of a turn-based game read from DRN);
//! without it the query is a POMDP's or an MDP's. `PATH` is any LTL path
//! formula the parser of [`super::parse`] accepts (labels in double
//! quotes, as Storm writes them: `F "goal"`, `G !"crash" & F "goal"`).
//! `Pmax` makes `PATH` the defender's objective; `Pmin` makes its
//! complement the objective (`F "goal"` becomes `G !goal`), since
//! minimising the probability of `PATH` is maximising that of `!PATH`. A
//! reward query asks for the expected total reward of reward model `r`
//! accumulated until the first state satisfying the state formula `T` (a
//! Boolean combination of labels), minimised (`Rmin`, a cost) or maximised
//! (`Rmax`) by the defender (method.md section 9).
//! Everything else (time queries, bounds such as `P>=0.5`, reward paths
//! other than `F T`, several queries, constants, bounded operators such as
//! `F<=10`) is an error naming the line and column ([`parse_props`]), and
//! the file too ([`from_props_str`], as the command line reports it).

use thiserror::Error;

use super::{Formula, parse};
use crate::game::ModelError;

/// The query of a property file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Property {
    /// The optimising player `P` of `<<P>>`, if the query names one.
    pub player: Option<u64>,
    /// `true` for `Pmax` and `Rmax`, `false` for `Pmin` and `Rmin`.
    pub maximise: bool,
    /// What is asked: a probability or an expected reward.
    pub query: Query,
    /// The query as written, without its name and its `;` (`Pmax=? [F
    /// "goal"]`), for reports that restate it.
    pub text: String,
    /// The 1-based line of the query.
    pub line: usize,
    /// The 1-based column (in characters) where the query starts after its
    /// name: that of `<<P>>` when it names a player.
    pub column: usize,
}

/// What a property file asks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Query {
    /// `Pmax=? [ PATH ]` or `Pmin=? [ PATH ]`.
    Probability {
        /// The path formula as written.
        path: Formula,
        /// The formula whose probability the defender maximises: `path`
        /// for `Pmax`, its complement for `Pmin`.
        objective: Formula,
    },
    /// `R{"r"}min=? [ F T ]` or `R{"r"}max=? [ F T ]`: the expected total
    /// reward until `T` (method.md section 9).
    Reward(RewardQuery),
}

/// An expected-reward query `R{"model"}min=? [ F target ]` (or `max`):
/// the expected total reward of the reward model accumulated until the
/// first state satisfying `target` (method.md section 9).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RewardQuery {
    /// The reward model's name; `None` for `Rmin`/`Rmax`, which need a
    /// game with exactly one reward model.
    pub model: Option<String>,
    /// The state formula `T` (a Boolean combination of labels).
    pub target: Formula,
}

impl RewardQuery {
    /// The path formula `F T` whose automaton tracks whether `T` was
    /// reached (its accepting states are the target of the reward).
    pub fn reach_target(&self) -> Formula {
        Formula::Finally(Box::new(self.target.clone()))
    }
}

impl Property {
    /// The formula whose probability the defender maximises, for a
    /// probability query; `None` for a reward query.
    pub fn probability_objective(&self) -> Option<&Formula> {
        match &self.query {
            Query::Probability { objective, .. } => Some(objective),
            Query::Reward(_) => None,
        }
    }

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

/// `["name":] [<<P>>] P(max|min)=? [ PATH ] [;]` or `["name":] [<<P>>]
/// R[{"r"}](max|min)=? [ F T ] [;]` on one line.
fn query(text: &str, line: usize) -> Result<Property, PropsError> {
    let mut cursor = Cursor { text, at: 0, line };
    skip_name(&mut cursor)?;
    cursor.skip_blanks();
    let column = cursor.column();
    let query_start = cursor.at;
    let player = coalition(&mut cursor)?;
    cursor.skip_blanks();
    let (operator, maximise) = operator(&mut cursor)?;
    let (path, path_column) = bracketed_path(&mut cursor, &operator)?;
    let query_end = cursor.at;
    cursor.eat(";");
    cursor.skip_blanks();
    if !cursor.rest().is_empty() {
        return Err(cursor.error(format!("unexpected {} after the query", cursor.found())));
    }
    let query = match operator {
        Operator::Probability => {
            let objective = if maximise {
                path.clone()
            } else {
                complement(&path)
            };
            Query::Probability { path, objective }
        }
        Operator::Reward { model } => Query::Reward(RewardQuery {
            model,
            target: reward_target(path).map_err(|message| PropsError {
                line,
                column: path_column,
                message,
            })?,
        }),
    };
    Ok(Property {
        player,
        maximise,
        query,
        text: text[query_start..query_end].trim().to_string(),
        line,
        column,
    })
}

/// The operator of a query: `P` or `R` with its reward model.
enum Operator {
    Probability,
    Reward { model: Option<String> },
}

impl std::fmt::Display for Operator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Operator::Probability => write!(f, "P"),
            Operator::Reward { model: None } => write!(f, "R"),
            Operator::Reward { model: Some(name) } => write!(f, "R{{\"{name}\"}}"),
        }
    }
}

/// `Pmax=?`, `Pmin=?`, `R{"r"}max=?`, `R{"r"}min=?`, `Rmax=?` or `Rmin=?`,
/// and whether it maximises.
fn operator(cursor: &mut Cursor) -> Result<(Operator, bool), PropsError> {
    let operator = if cursor.rest().starts_with('P') {
        Operator::Probability
    } else if cursor.rest().starts_with("R{") || cursor.rest().starts_with("Rm") {
        let start = cursor.column();
        cursor.at += 1;
        let model = reward_model_name(cursor).map_err(|message| PropsError {
            line: cursor.line,
            column: start,
            message,
        })?;
        Operator::Reward { model }
    } else {
        return Err(unsupported_query(cursor));
    };
    let after = match &operator {
        Operator::Probability => 1,
        Operator::Reward { .. } => 0,
    };
    let rest = &cursor.rest()[after..];
    let maximise = if rest.starts_with("max=?") {
        true
    } else if rest.starts_with("min=?") {
        false
    } else {
        return Err(unsupported_query(cursor));
    };
    cursor.at += after + "max=?".len();
    Ok((operator, maximise))
}

/// After `R`: an optional `{"name"}`.
fn reward_model_name(cursor: &mut Cursor) -> Result<Option<String>, String> {
    if !cursor.rest().starts_with('{') {
        return Ok(None);
    }
    let inside = &cursor.rest()[1..];
    let close = inside
        .find('}')
        .ok_or("unterminated reward model name: expected `}`")?;
    let name = inside[..close].trim();
    let name = name
        .strip_prefix('"')
        .and_then(|n| n.strip_suffix('"'))
        .filter(|n| !n.is_empty() && !n.contains('"'))
        .ok_or_else(|| {
            format!("the reward model in `R{{{name}}}` must be a name in double quotes, as `R{{\"steps\"}}`")
        })?;
    cursor.at += close + 2;
    Ok(Some(name.to_string()))
}

/// `[ PATH ]` after the operator: the parsed path and the column where it
/// starts.
fn bracketed_path(
    cursor: &mut Cursor,
    operator: &Operator,
) -> Result<(Formula, usize), PropsError> {
    cursor.skip_blanks();
    let open = cursor.column();
    if !cursor.eat("[") {
        return Err(cursor.error(format!(
            "expected `[` and a path formula after {operator}max=? or {operator}min=?, found {}",
            cursor.found()
        )));
    }
    let (text, line) = (cursor.text, cursor.line);
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
    let path_column = text[..inner_start].chars().count() + 1 + indent(path_text);
    if let Operator::Reward { .. } = operator {
        if let Some(message) = unsupported_reward_path(path_text.trim()) {
            return Err(PropsError {
                line,
                column: path_column,
                message,
            });
        }
    }
    let (formula_text, reward_target) = match operator {
        Operator::Reward { .. } => match reward_path(path_text) {
            Some(target) => (target, true),
            None => (path_text, false),
        },
        Operator::Probability => (path_text, false),
    };
    let formula_start = inner_start + (path_text.len() - formula_text.len());
    let formula = parse(formula_text).map_err(|e| PropsError {
        line,
        column: text[..formula_start].chars().count() + e.column,
        message: format!("in the path formula: {}", e.message),
    })?;
    let path = match reward_target {
        true => Formula::Finally(Box::new(formula)),
        false => formula,
    };
    cursor.at = close + 1;
    Ok((path, path_column))
}

/// The message for a reward path of Storm's that is not a total reward
/// until a target (`C`, `C<=k`, `I=k`, `LRA`, `F<=k`), or `None`.
fn unsupported_reward_path(path: &str) -> Option<String> {
    let word: String = path
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric())
        .collect();
    let what = match word.as_str() {
        "C" => "a cumulative reward `C`",
        "I" => "an instantaneous reward `I=k`",
        "LRA" | "S" => "a long-run average reward",
        "F" if path[1..].trim_start().starts_with(['<', '>', '[']) => {
            "a step-bounded reward `F<=k`"
        }
        _ => return None,
    };
    Some(format!(
        "{what} is not supported: a reward query asks for the total reward until a target, `F T`"
    ))
}

/// The target `T` of a reward path `F T`, which must be a state formula.
fn reward_target(path: Formula) -> Result<Formula, String> {
    match path {
        Formula::Finally(target) if is_state_formula(&target) => Ok(*target),
        other => Err(format!(
            "a reward query asks for the total reward until a target, `F T` with `T` a Boolean \
             combination of labels (as `F \"goal\"`); found `{other}`"
        )),
    }
}

/// A reward path `F T` read as PRISM and Storm read it: `F` applies to the
/// whole state formula that follows (`F "goal" & !"crash"` is `F ("goal" &
/// !"crash")`), where LTL's precedence would bind `F` to `"goal"` alone.
/// `None` when the path does not start with `F`.
fn reward_path(path_text: &str) -> Option<&str> {
    let trimmed = path_text.trim_start();
    let rest = trimmed.strip_prefix('F')?;
    rest.starts_with(|c: char| c.is_whitespace() || matches!(c, '(' | '"' | '!'))
        .then_some(rest)
}

/// Whether `f` has no temporal operator: its truth is decided by one state.
fn is_state_formula(f: &Formula) -> bool {
    match f {
        Formula::True | Formula::False | Formula::Prop(_) => true,
        Formula::Not(g) => is_state_formula(g),
        Formula::And(gs) | Formula::Or(gs) => gs.iter().all(is_state_formula),
        Formula::Implies(f, g) | Formula::Equiv(f, g) | Formula::Xor(f, g) => {
            is_state_formula(f) && is_state_formula(g)
        }
        _ => false,
    }
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

/// The error for a query other than `Pmax=?`, `Pmin=?`, `R{"r"}max=?` and
/// `R{"r"}min=?`.
fn unsupported_query(cursor: &Cursor) -> PropsError {
    let rest = cursor.rest();
    let message = if rest.starts_with('T') {
        format!(
            "{} is a time query; posg-fsc solves `Pmax=? [ PATH ]`, `Pmin=? [ PATH ]` and the \
             expected-reward queries `R{{\"r\"}}min=? [ F T ]` and `R{{\"r\"}}max=? [ F T ]` \
             (a time query is a reward query with reward 1 per step)",
            cursor.found()
        )
    } else if rest.starts_with('R') {
        format!(
            "{}: only the reward queries `R{{\"r\"}}min=?` and `R{{\"r\"}}max=?` (or `Rmin=?` \
             and `Rmax=?`) can be solved (not a bound or an unoptimised `R=?`)",
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
            "expected a query `Pmax=? [ PATH ]`, `Pmin=? [ PATH ]` or `R{{\"r\"}}min=? [ F T ]`, \
             found {}",
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
