//! The HOA parser: tokens to the header and the `State:` blocks as written.
//!
//! Contract: [`parse`] reads `HOA: v1` or `HOA: v1.1`, the header items up to
//! `--BODY--`, the `State:` blocks up to `--END--`, and requires nothing after
//! it. It checks what the grammar alone decides: the version, required and
//! repeated header items, unknown upper-case items, the number of
//! propositions (at most [`MAX_PROPOSITIONS`]) and of acceptance sets (at most
//! the bits of a [`MarkSet`]), acceptance set numbers below the declared
//! count, aliases defined before use, the nesting depth, and no alternation.
//! Labels stay unevaluated ([`Label`]); state and AP indices are checked by
//! [`super::build`]. Every error is a [`HoaError::Syntax`] at the offending
//! token.

use super::HoaError;
use super::lex::{Pos, Token, error_at};
use crate::automaton::MAX_PROPOSITIONS;
use crate::automaton::emerson_lei::{Acceptance, MarkSet};

/// How deeply parentheses and negations may nest in labels and acceptance
/// conditions (deeper input is refused instead of exhausting the stack).
const MAX_NESTING: usize = 64;

/// The versions of the format the reader accepts.
const SUPPORTED_VERSIONS: [&str; 2] = ["v1", "v1.1"];

/// The header, the `State:` blocks and the position of `--END--` that
/// `tokens` (as [`super::lex::tokenize`] returns them) describe.
pub(super) fn parse(tokens: Vec<(Token, Pos)>) -> Result<(Header, Vec<RawState>, Pos), HoaError> {
    let mut parser = Parser { tokens, next: 0 };
    let header = parser.header()?;
    let (states, end) = parser.body(header.num_marks)?;
    parser.end()?;
    Ok((header, states, end))
}

/// A label expression as written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum Label {
    Constant(bool),
    Proposition(u64, Pos),
    Alias(String, Pos),
    Not(Box<Label>),
    And(Vec<Label>),
    Or(Vec<Label>),
}

/// The header items read so far.
#[derive(Debug, Default)]
struct HeaderItems {
    states: Option<(u64, Pos)>,
    start: Option<(u64, Pos)>,
    propositions: Vec<String>,
    aliases: Vec<(String, Label)>,
    acceptance: Option<(u32, Acceptance)>,
}

/// A complete header.
#[derive(Debug)]
pub(super) struct Header {
    /// `States:`, if given.
    pub(super) states: Option<(u64, Pos)>,
    /// `Start:`.
    pub(super) start: (u64, Pos),
    /// `AP:`.
    pub(super) propositions: Vec<String>,
    /// `Alias:` items in order.
    pub(super) aliases: Vec<(String, Label)>,
    /// The `n` of `Acceptance: n ...`.
    pub(super) num_marks: u32,
    /// The condition of `Acceptance: n ...`.
    pub(super) acceptance: Acceptance,
    /// Where `--BODY--` is.
    pub(super) body: Pos,
}

impl HeaderItems {
    /// The header, once `--BODY--` at `body` is reached.
    fn finish(self, body: Pos) -> Result<Header, HoaError> {
        let Some((num_marks, acceptance)) = self.acceptance else {
            return error_at(body, "missing `Acceptance:` header item");
        };
        let Some(start) = self.start else {
            return error_at(
                body,
                "missing `Start:` header item: exactly one initial state is required",
            );
        };
        Ok(Header {
            states: self.states,
            start,
            propositions: self.propositions,
            aliases: self.aliases,
            num_marks,
            acceptance,
            body,
        })
    }
}

/// A `State:` block as written.
#[derive(Debug)]
pub(super) struct RawState {
    pub(super) pos: Pos,
    pub(super) id: u64,
    pub(super) label: Option<Label>,
    pub(super) marks: MarkSet,
    pub(super) edges: Vec<RawEdge>,
}

/// An edge as written.
#[derive(Debug)]
pub(super) struct RawEdge {
    pub(super) pos: Pos,
    pub(super) label: Option<Label>,
    pub(super) target: (u64, Pos),
    pub(super) marks: MarkSet,
}

/// A recursive-descent parser over the tokens.
struct Parser {
    tokens: Vec<(Token, Pos)>,
    next: usize,
}

impl Parser {
    /// The next token.
    fn peek(&self) -> &Token {
        &self.tokens[self.next].0
    }

    /// The position of the next token.
    fn pos(&self) -> Pos {
        self.tokens[self.next].1
    }

    /// Consumes the next token (the final [`Token::Eof`] stays).
    fn advance(&mut self) -> (Token, Pos) {
        let token = self.tokens[self.next].clone();
        if self.next + 1 < self.tokens.len() {
            self.next += 1;
        }
        token
    }

    /// An error at the next token saying what was expected instead.
    fn expected<T>(&self, what: &str) -> Result<T, HoaError> {
        error_at(
            self.pos(),
            format!("expected {what}, found {}", self.peek().describe()),
        )
    }

    /// Consumes the punctuation `c` or fails.
    fn punct(&mut self, c: char) -> Result<(), HoaError> {
        if *self.peek() != Token::Punct(c) {
            return self.expected(&format!("`{c}`"));
        }
        self.advance();
        Ok(())
    }

    /// Consumes the punctuation `c` if it is next.
    fn eat(&mut self, c: char) -> bool {
        let found = *self.peek() == Token::Punct(c);
        if found {
            self.advance();
        }
        found
    }

    /// Consumes an integer or fails, naming `what` was expected.
    fn integer(&mut self, what: &str) -> Result<(u64, Pos), HoaError> {
        match *self.peek() {
            Token::Int(n) => Ok((n, self.advance().1)),
            _ => self.expected(what),
        }
    }

    /// The header up to and including `--BODY--`.
    fn header(&mut self) -> Result<Header, HoaError> {
        if *self.peek() != Token::Header("HOA".into()) {
            return self.expected("`HOA: v1`");
        }
        self.advance();
        if !matches!(self.peek(), Token::Ident(version) if SUPPORTED_VERSIONS.contains(&version.as_str()))
        {
            return self.expected("version `v1` or `v1.1`");
        }
        self.advance();
        let mut items = HeaderItems::default();
        loop {
            let (token, pos) = self.advance();
            match token {
                Token::Header(name) => self.header_item(&mut items, &name, pos)?,
                Token::Body => return items.finish(pos),
                other => {
                    return error_at(
                        pos,
                        format!(
                            "expected a header item or `--BODY--`, found {}",
                            other.describe()
                        ),
                    );
                }
            }
        }
    }

    /// The values of the header item `name:` at `pos`.
    fn header_item(
        &mut self,
        header: &mut HeaderItems,
        name: &str,
        pos: Pos,
    ) -> Result<(), HoaError> {
        match name {
            "States" => {
                if header.states.is_some() {
                    return error_at(pos, "second `States:` item");
                }
                header.states = Some(self.integer("the number of states")?);
            }
            "Start" => self.start(header, pos)?,
            "AP" => self.propositions(header, pos)?,
            "Alias" => self.alias(header)?,
            "Acceptance" => {
                if header.acceptance.is_some() {
                    return error_at(pos, "second `Acceptance:` item");
                }
                header.acceptance = Some(self.acceptance()?);
            }
            "HOA" => return error_at(pos, "second `HOA:` item"),
            other if other.starts_with(|c: char| c.is_ascii_uppercase()) => {
                return error_at(
                    pos,
                    format!(
                        "unsupported header item `{other}:` (items starting with an \
                         upper-case letter may change the automaton's meaning)"
                    ),
                );
            }
            _ => self.skip_values(),
        }
        Ok(())
    }

    /// Skips the values of an informative header item.
    fn skip_values(&mut self) {
        while !matches!(
            self.peek(),
            Token::Header(_) | Token::Body | Token::End | Token::Abort | Token::Eof
        ) {
            self.advance();
        }
    }

    /// `Start: q`.
    fn start(&mut self, header: &mut HeaderItems, pos: Pos) -> Result<(), HoaError> {
        if header.start.is_some() {
            return error_at(
                pos,
                "second `Start:` item: exactly one initial state is supported",
            );
        }
        header.start = Some(self.integer("the initial state")?);
        if *self.peek() == Token::Punct('&') {
            return error_at(
                self.pos(),
                "conjunctions of initial states (alternation) are not supported",
            );
        }
        Ok(())
    }

    /// `AP: n "p_0" ... "p_{n-1}"`.
    fn propositions(&mut self, header: &mut HeaderItems, pos: Pos) -> Result<(), HoaError> {
        if !header.propositions.is_empty() {
            return error_at(pos, "second `AP:` item");
        }
        let (count, count_pos) = self.integer("the number of atomic propositions")?;
        if count > MAX_PROPOSITIONS as u64 {
            return error_at(
                count_pos,
                format!("{count} atomic propositions; at most {MAX_PROPOSITIONS} are supported"),
            );
        }
        while let Token::Str(name) = self.peek().clone() {
            if header.propositions.contains(&name) {
                return error_at(
                    self.pos(),
                    format!("atomic proposition {name:?} named twice"),
                );
            }
            header.propositions.push(name);
            self.advance();
        }
        if header.propositions.len() as u64 != count {
            return self.expected(&format!(
                "{count} quoted proposition names after `AP: {count}`"
            ));
        }
        Ok(())
    }

    /// `Alias: @name label`.
    fn alias(&mut self, header: &mut HeaderItems) -> Result<(), HoaError> {
        let Token::Alias(name) = self.peek().clone() else {
            return self.expected("an alias name such as `@a`");
        };
        let pos = self.advance().1;
        if header.aliases.iter().any(|(known, _)| *known == name) {
            return error_at(pos, format!("alias `@{name}` defined twice"));
        }
        let label = self.label(0)?;
        check_aliases(&label, &header.aliases)?;
        header.aliases.push((name, label));
        Ok(())
    }

    /// A label expression: `|` of `&` of negated atoms.
    fn label(&mut self, depth: usize) -> Result<Label, HoaError> {
        let mut parts = vec![self.label_conjunction(depth)?];
        while self.eat('|') {
            parts.push(self.label_conjunction(depth)?);
        }
        Ok(single_or(parts, Label::Or))
    }

    /// A conjunction of label atoms.
    fn label_conjunction(&mut self, depth: usize) -> Result<Label, HoaError> {
        let mut parts = vec![self.label_atom(depth)?];
        while self.eat('&') {
            parts.push(self.label_atom(depth)?);
        }
        Ok(single_or(parts, Label::And))
    }

    /// `t`, `f`, an AP index, an alias, `!atom` or `(label)`.
    fn label_atom(&mut self, depth: usize) -> Result<Label, HoaError> {
        if depth >= MAX_NESTING {
            return error_at(self.pos(), "label nested too deeply");
        }
        let what = "a label: `t`, `f`, an AP index, an alias, `!` or `(`";
        let (token, pos) = (self.peek().clone(), self.pos());
        let label = match token {
            Token::Ident(name) if name == "t" || name == "f" => Label::Constant(name == "t"),
            Token::Int(index) => Label::Proposition(index, pos),
            Token::Alias(name) => Label::Alias(name, pos),
            Token::Punct('!') => {
                self.advance();
                return Ok(Label::Not(Box::new(self.label_atom(depth + 1)?)));
            }
            Token::Punct('(') => {
                self.advance();
                let inner = self.label(depth + 1)?;
                self.punct(')')?;
                return Ok(inner);
            }
            _ => return self.expected(what),
        };
        self.advance();
        Ok(label)
    }

    /// `Acceptance: n condition`.
    fn acceptance(&mut self) -> Result<(u32, Acceptance), HoaError> {
        let (count, pos) = self.integer("the number of acceptance sets")?;
        if count > u64::from(MarkSet::BITS) {
            return error_at(
                pos,
                format!(
                    "{count} acceptance sets; at most {} are supported",
                    MarkSet::BITS
                ),
            );
        }
        let count = count as u32;
        Ok((count, self.condition(count, 0)?))
    }

    /// An acceptance condition: `|` of `&` of atoms.
    fn condition(&mut self, count: u32, depth: usize) -> Result<Acceptance, HoaError> {
        let mut parts = vec![self.condition_conjunction(count, depth)?];
        while self.eat('|') {
            parts.push(self.condition_conjunction(count, depth)?);
        }
        Ok(single_or(parts, Acceptance::Or))
    }

    /// A conjunction of acceptance atoms.
    fn condition_conjunction(&mut self, count: u32, depth: usize) -> Result<Acceptance, HoaError> {
        let mut parts = vec![self.condition_atom(count, depth)?];
        while self.eat('&') {
            parts.push(self.condition_atom(count, depth)?);
        }
        Ok(single_or(parts, Acceptance::And))
    }

    /// `t`, `f`, `Fin([!]m)`, `Inf([!]m)` or `(condition)`.
    fn condition_atom(&mut self, count: u32, depth: usize) -> Result<Acceptance, HoaError> {
        if depth >= MAX_NESTING {
            return error_at(self.pos(), "acceptance condition nested too deeply");
        }
        let what = "an acceptance condition: `t`, `f`, `Fin(...)`, `Inf(...)` or `(`";
        match self.peek().clone() {
            Token::Ident(name) if name == "t" || name == "f" => {
                self.advance();
                Ok(Acceptance::Constant(name == "t"))
            }
            Token::Ident(name) if name == "Fin" || name == "Inf" => {
                self.advance();
                self.punct('(')?;
                let complemented = self.eat('!');
                let (mark, pos) = self.integer("an acceptance set number")?;
                if mark >= u64::from(count) {
                    return error_at(pos, mark_range_message(mark, count));
                }
                self.punct(')')?;
                let mark = mark as u32;
                Ok(if name == "Fin" {
                    Acceptance::Fin { mark, complemented }
                } else {
                    Acceptance::Inf { mark, complemented }
                })
            }
            Token::Punct('(') => {
                self.advance();
                let inner = self.condition(count, depth + 1)?;
                self.punct(')')?;
                Ok(inner)
            }
            _ => self.expected(what),
        }
    }

    /// The body after `--BODY--`, up to and including `--END--`, whose
    /// position is returned too; marks must be below `count`.
    fn body(&mut self, count: u32) -> Result<(Vec<RawState>, Pos), HoaError> {
        let mut states = Vec::new();
        loop {
            match self.peek() {
                Token::Header(name) if name == "State" => {
                    let pos = self.advance().1;
                    states.push(self.state(pos, count)?);
                }
                Token::End => return Ok((states, self.advance().1)),
                Token::Abort => {
                    return error_at(
                        self.pos(),
                        "the producer aborted the automaton (`--ABORT--`)",
                    );
                }
                _ => return self.expected("`State:` or `--END--`"),
            }
        }
    }

    /// A `State:` line (after `State:` at `pos`) and its edges.
    fn state(&mut self, pos: Pos, count: u32) -> Result<RawState, HoaError> {
        let label = self.optional_label()?;
        let (id, _) = self.integer("a state number")?;
        if let Token::Str(_) = self.peek() {
            self.advance();
        }
        let marks = self.optional_marks(count)?;
        let mut edges = Vec::new();
        while matches!(self.peek(), Token::Int(_) | Token::Punct('[')) {
            let edge_pos = self.pos();
            let label = self.optional_label()?;
            let target = self.integer("a target state")?;
            if *self.peek() == Token::Punct('&') {
                return error_at(
                    self.pos(),
                    "conjunctions of target states (alternation) are not supported",
                );
            }
            let marks = self.optional_marks(count)?;
            edges.push(RawEdge {
                pos: edge_pos,
                label,
                target,
                marks,
            });
        }
        Ok(RawState {
            pos,
            id,
            label,
            marks,
            edges,
        })
    }

    /// `[label]` if present.
    fn optional_label(&mut self) -> Result<Option<Label>, HoaError> {
        if !self.eat('[') {
            return Ok(None);
        }
        let label = self.label(0)?;
        self.punct(']')?;
        Ok(Some(label))
    }

    /// `{m ...}` if present, each mark below `count`.
    fn optional_marks(&mut self, count: u32) -> Result<MarkSet, HoaError> {
        let mut marks: MarkSet = 0;
        if !self.eat('{') {
            return Ok(marks);
        }
        while !self.eat('}') {
            let (mark, pos) = self.integer("an acceptance set number or `}`")?;
            if mark >= u64::from(count) {
                return error_at(pos, mark_range_message(mark, count));
            }
            marks |= 1 << mark;
        }
        Ok(marks)
    }

    /// Nothing may follow `--END--`.
    fn end(&mut self) -> Result<(), HoaError> {
        match self.peek() {
            Token::Eof => Ok(()),
            _ => self.expected("end of input after `--END--`"),
        }
    }
}

/// The error message for an acceptance set number past the declared count.
fn mark_range_message(mark: u64, count: u32) -> String {
    format!("acceptance set {mark} out of range: `Acceptance: {count}` declares sets 0..{count}")
}

/// `parts[0]` if there is one part, else `combine(parts)`.
fn single_or<T>(mut parts: Vec<T>, combine: impl Fn(Vec<T>) -> T) -> T {
    if parts.len() == 1 {
        parts.remove(0)
    } else {
        combine(parts)
    }
}

/// Fails if `label` uses an alias not among `known` (aliases may use only
/// aliases defined before them, so they cannot be cyclic).
fn check_aliases(label: &Label, known: &[(String, Label)]) -> Result<(), HoaError> {
    match label {
        Label::Alias(name, pos) if !known.iter().any(|(k, _)| k == name) => {
            error_at(*pos, format!("unknown alias `@{name}`"))
        }
        Label::Not(inner) => check_aliases(inner, known),
        Label::And(parts) | Label::Or(parts) => {
            parts.iter().try_for_each(|p| check_aliases(p, known))
        }
        _ => Ok(()),
    }
}
