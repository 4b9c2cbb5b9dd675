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

use std::fmt::Write as _;

use thiserror::Error;

use super::emerson_lei::{
    Acceptance, Edge, EmersonLeiAutomaton, MAX_TABLE_ENTRIES, MarkSet, to_state_based_rabin,
};
use super::{AutomatonError, Dra, Letter, MAX_PROPOSITIONS};

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
/// module documentation for what is supported).
pub fn parse_hoa(text: &str) -> Result<EmersonLeiAutomaton, HoaError> {
    let tokens = tokenize(text)?;
    let mut parser = Parser { tokens, next: 0 };
    let header = parser.header()?;
    let (states, end) = parser.body(header.num_marks)?;
    parser.end()?;
    build(&header, &states, end)
}

/// Reads a HOA v1 or v1.1 automaton with [`parse_hoa`] and converts it with
/// [`to_state_based_rabin`].
pub fn read_hoa_dra(text: &str) -> Result<Dra, HoaError> {
    Ok(to_state_based_rabin(&parse_hoa(text)?)?)
}

/// Prints `dra` as HOA v1 with state-based acceptance `Rabin n`: pair `i`
/// becomes `Fin(2i) & Inf(2i+1)`, state `q` carries mark `2i` iff it is in
/// `L_i` and mark `2i + 1` iff it is in `K_i`. Each state has one edge per
/// successor, labelled with an irredundant sum of cubes over AP indices
/// (`t` when one successor takes every letter). `name` becomes the `name:`
/// item.
pub fn write_hoa(dra: &Dra, name: Option<&str>) -> String {
    let mut out = String::from("HOA: v1\n");
    if let Some(name) = name {
        writeln!(out, "name: {}", quoted(name)).expect("writing to a String");
    }
    write_header(&mut out, dra);
    out.push_str("--BODY--\n");
    for q in 0..dra.num_states() {
        write_state(&mut out, dra, q);
    }
    out.push_str("--END--\n");
    out
}

// ---------------------------------------------------------------- writer

/// The `States:` to `properties:` items.
fn write_header(out: &mut String, dra: &Dra) {
    let props = dra.propositions();
    let names: String = props.iter().map(|p| format!(" {}", quoted(p))).collect();
    let n = dra.pairs().len();
    let acceptance = if n == 0 {
        "f".to_string()
    } else {
        (0..n)
            .map(|i| format!("(Fin({})&Inf({}))", 2 * i, 2 * i + 1))
            .collect::<Vec<_>>()
            .join(" | ")
    };
    writeln!(
        out,
        "States: {}\nStart: {}\nAP: {}{names}\nacc-name: Rabin {n}\nAcceptance: {} {acceptance}\n\
         properties: trans-labels explicit-labels state-acc deterministic complete",
        dra.num_states(),
        dra.initial(),
        props.len(),
        2 * n,
    )
    .expect("writing to a String");
}

/// One `State:` line and its edges.
fn write_state(out: &mut String, dra: &Dra, q: usize) {
    let marks: Vec<String> = dra
        .pairs()
        .iter()
        .enumerate()
        .flat_map(|(i, p)| {
            [(p.fin[q], 2 * i), (p.inf[q], 2 * i + 1)]
                .into_iter()
                .filter(|&(member, _)| member)
                .map(|(_, mark)| mark.to_string())
        })
        .collect();
    if marks.is_empty() {
        writeln!(out, "State: {q}").expect("writing to a String");
    } else {
        writeln!(out, "State: {q} {{{}}}", marks.join(" ")).expect("writing to a String");
    }
    let props = dra.propositions().len();
    let letters = 1usize << props;
    let mut targets: Vec<usize> = (0..letters)
        .map(|a| dra.successor(q, a as Letter))
        .collect();
    let table = targets.clone();
    targets.sort_unstable();
    targets.dedup();
    for target in targets {
        let on: Vec<bool> = table.iter().map(|&t| t == target).collect();
        writeln!(out, "[{}] {target}", label_text(&on, props)).expect("writing to a String");
    }
}

/// A HOA string literal.
fn quoted(text: &str) -> String {
    let mut out = String::from("\"");
    for c in text.chars() {
        if c == '"' || c == '\\' {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

/// A product of literals: proposition `i` is constrained iff bit `i` of
/// `care` is set, and then must have the value of bit `i` of `value`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Cube {
    care: Letter,
    value: Letter,
}

/// A label for the letters `a` with `on[a]`, as a sum of cubes.
fn label_text(on: &[bool], props: usize) -> String {
    let cubes = isop(on, on, props);
    if cubes.is_empty() {
        return "f".to_string();
    }
    cubes
        .iter()
        .map(|cube| cube_text(*cube, props))
        .collect::<Vec<_>>()
        .join(" | ")
}

/// A cube as `0&!1&...`, or `t` for the empty cube.
fn cube_text(cube: Cube, props: usize) -> String {
    let literals: Vec<String> = (0..props)
        .filter(|i| cube.care >> i & 1 == 1)
        .map(|i| {
            if cube.value >> i & 1 == 1 {
                i.to_string()
            } else {
                format!("!{i}")
            }
        })
        .collect();
    if literals.is_empty() {
        "t".to_string()
    } else {
        literals.join("&")
    }
}

/// An irredundant sum of cubes covering every letter of `lower` and only
/// letters of `upper` (`lower` implies `upper`), over propositions
/// `0..vars`, by the Minato-Morreale recursion on the top proposition.
fn isop(lower: &[bool], upper: &[bool], vars: usize) -> Vec<Cube> {
    if !lower.contains(&true) {
        return Vec::new();
    }
    if !upper.contains(&false) {
        return vec![Cube { care: 0, value: 0 }];
    }
    let half = lower.len() / 2;
    let x = (vars - 1) as u32;
    let (l0, l1) = lower.split_at(half);
    let (u0, u1) = upper.split_at(half);
    let only0: Vec<bool> = l0.iter().zip(u1).map(|(&l, &u)| l && !u).collect();
    let only1: Vec<bool> = l1.iter().zip(u0).map(|(&l, &u)| l && !u).collect();
    let cubes0 = isop(&only0, u0, vars - 1);
    let cubes1 = isop(&only1, u1, vars - 1);
    let covered0 = cover(&cubes0, half);
    let covered1 = cover(&cubes1, half);
    let rest: Vec<bool> = (0..half)
        .map(|a| (l0[a] && !covered0[a]) || (l1[a] && !covered1[a]))
        .collect();
    let both: Vec<bool> = u0.iter().zip(u1).map(|(&a, &b)| a && b).collect();
    let shared = isop(&rest, &both, vars - 1);
    let with = |value: Letter| {
        move |c: Cube| Cube {
            care: c.care | 1 << x,
            value: c.value | value << x,
        }
    };
    cubes0
        .into_iter()
        .map(with(0))
        .chain(cubes1.into_iter().map(with(1)))
        .chain(shared)
        .collect()
}

/// The letters `0..size` covered by some cube.
fn cover(cubes: &[Cube], size: usize) -> Vec<bool> {
    (0..size as Letter)
        .map(|a| cubes.iter().any(|c| a & c.care == c.value))
        .collect()
}

// ---------------------------------------------------------------- lexer

/// How deeply parentheses and negations may nest in labels and acceptance
/// conditions (deeper input is refused instead of exhausting the stack).
const MAX_NESTING: usize = 64;

/// A line and column, both from 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Pos {
    line: usize,
    column: usize,
}

/// A syntax error at `pos`.
fn error_at<T>(pos: Pos, message: impl Into<String>) -> Result<T, HoaError> {
    Err(HoaError::Syntax {
        line: pos.line,
        column: pos.column,
        message: message.into(),
    })
}

/// A HOA token.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Token {
    /// A header name such as `States:`, without the colon.
    Header(String),
    /// An identifier, including the Booleans `t` and `f`.
    Ident(String),
    /// A non-negative integer.
    Int(u64),
    /// A string literal, unescaped.
    Str(String),
    /// An alias name `@name`, without the `@`.
    Alias(String),
    /// `--BODY--`.
    Body,
    /// `--END--`.
    End,
    /// `--ABORT--`.
    Abort,
    /// One of `! & | ( ) [ ] { }`.
    Punct(char),
    /// The end of the text.
    Eof,
}

impl Token {
    /// The token as an error message names it.
    fn describe(&self) -> String {
        match self {
            Token::Header(name) => format!("header item `{name}:`"),
            Token::Ident(name) => format!("`{name}`"),
            Token::Int(n) => format!("number {n}"),
            Token::Str(text) => format!("string {}", quoted(text)),
            Token::Alias(name) => format!("alias `@{name}`"),
            Token::Body => "`--BODY--`".to_string(),
            Token::End => "`--END--`".to_string(),
            Token::Abort => "`--ABORT--`".to_string(),
            Token::Punct(c) => format!("`{c}`"),
            Token::Eof => "end of input".to_string(),
        }
    }
}

/// A cursor over the characters of the text.
struct Lexer {
    chars: Vec<char>,
    index: usize,
    pos: Pos,
}

impl Lexer {
    /// The next character, if any.
    fn peek(&self) -> Option<char> {
        self.chars.get(self.index).copied()
    }

    /// The character after the next one, if any.
    fn peek_second(&self) -> Option<char> {
        self.chars.get(self.index + 1).copied()
    }

    /// Consumes the next character.
    fn bump(&mut self) -> Option<char> {
        let c = self.peek()?;
        self.index += 1;
        if c == '\n' {
            self.pos.line += 1;
            self.pos.column = 1;
        } else {
            self.pos.column += 1;
        }
        Some(c)
    }

    /// Consumes characters while `accept` holds and returns them.
    fn take_while(&mut self, accept: impl Fn(char) -> bool) -> String {
        let mut taken = String::new();
        while let Some(c) = self.peek().filter(|&c| accept(c)) {
            taken.push(c);
            self.bump();
        }
        taken
    }

    /// Skips white space and (nested) comments.
    fn skip_blanks(&mut self) -> Result<(), HoaError> {
        loop {
            match (self.peek(), self.peek_second()) {
                (Some(c), _) if c.is_whitespace() => {
                    self.bump();
                }
                (Some('/'), Some('*')) => self.skip_comment()?,
                _ => return Ok(()),
            }
        }
    }

    /// Skips one comment starting at `/*`, with nested comments inside.
    fn skip_comment(&mut self) -> Result<(), HoaError> {
        let start = self.pos;
        let mut depth = 0usize;
        loop {
            match (self.peek(), self.peek_second()) {
                (Some('/'), Some('*')) => {
                    depth += 1;
                    self.bump();
                    self.bump();
                }
                (Some('*'), Some('/')) => {
                    depth -= 1;
                    self.bump();
                    self.bump();
                    if depth == 0 {
                        return Ok(());
                    }
                }
                (Some(_), _) => {
                    self.bump();
                }
                (None, _) => return error_at(start, "unterminated comment: expected `*/`"),
            }
        }
    }

    /// Reads the token starting with `c` at `start`.
    fn token(&mut self, c: char, start: Pos) -> Result<Token, HoaError> {
        match c {
            '"' => self.string(start),
            '0'..='9' => self.integer(start),
            '@' => {
                self.bump();
                let name = self.take_while(is_identifier_char);
                if name.is_empty() {
                    return error_at(start, "expected an alias name after `@`");
                }
                Ok(Token::Alias(name))
            }
            '-' => self.separator(start),
            '!' | '&' | '|' | '(' | ')' | '[' | ']' | '{' | '}' => {
                self.bump();
                Ok(Token::Punct(c))
            }
            c if c.is_ascii_alphabetic() || c == '_' => {
                let name = self.take_while(is_identifier_char);
                if self.peek() == Some(':') {
                    self.bump();
                    return Ok(Token::Header(name));
                }
                Ok(Token::Ident(name))
            }
            other => error_at(start, format!("unexpected character {other:?}")),
        }
    }

    /// A string literal; a backslash escapes the next character.
    fn string(&mut self, start: Pos) -> Result<Token, HoaError> {
        self.bump();
        let mut text = String::new();
        loop {
            match self.bump() {
                Some('"') => return Ok(Token::Str(text)),
                Some('\\') => match self.bump() {
                    Some(escaped) => text.push(escaped),
                    None => break,
                },
                Some(c) => text.push(c),
                None => break,
            }
        }
        error_at(start, "unterminated string: expected `\"`")
    }

    /// A non-negative integer.
    fn integer(&mut self, start: Pos) -> Result<Token, HoaError> {
        let digits = self.take_while(|c| c.is_ascii_digit());
        match digits.parse() {
            Ok(n) => Ok(Token::Int(n)),
            Err(_) => error_at(start, format!("number {digits} is too large")),
        }
    }

    /// `--BODY--`, `--END--` or `--ABORT--`.
    fn separator(&mut self, start: Pos) -> Result<Token, HoaError> {
        let word = self.take_while(|c| c == '-' || c.is_ascii_alphabetic());
        match word.as_str() {
            "--BODY--" => Ok(Token::Body),
            "--END--" => Ok(Token::End),
            "--ABORT--" => Ok(Token::Abort),
            _ => error_at(
                start,
                format!("expected `--BODY--`, `--END--` or `--ABORT--`, found `{word}`"),
            ),
        }
    }
}

/// Whether `c` may continue an identifier (a header name, an alias, `v1.1`).
fn is_identifier_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.'
}

/// The versions of the format the reader accepts.
const SUPPORTED_VERSIONS: [&str; 2] = ["v1", "v1.1"];

/// The tokens of `text` with their positions, ending with [`Token::Eof`].
fn tokenize(text: &str) -> Result<Vec<(Token, Pos)>, HoaError> {
    let mut lexer = Lexer {
        chars: text.chars().collect(),
        index: 0,
        pos: Pos { line: 1, column: 1 },
    };
    let mut tokens = Vec::new();
    loop {
        lexer.skip_blanks()?;
        let start = lexer.pos;
        let Some(c) = lexer.peek() else {
            tokens.push((Token::Eof, start));
            return Ok(tokens);
        };
        tokens.push((lexer.token(c, start)?, start));
    }
}

// ---------------------------------------------------------------- parser

/// A label expression as written.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Label {
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
struct Header {
    /// `States:`, if given.
    states: Option<(u64, Pos)>,
    /// `Start:`.
    start: (u64, Pos),
    /// `AP:`.
    propositions: Vec<String>,
    /// `Alias:` items in order.
    aliases: Vec<(String, Label)>,
    /// The `n` of `Acceptance: n ...`.
    num_marks: u32,
    /// The condition of `Acceptance: n ...`.
    acceptance: Acceptance,
    /// Where `--BODY--` is.
    body: Pos,
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
struct RawState {
    pos: Pos,
    id: u64,
    label: Option<Label>,
    marks: MarkSet,
    edges: Vec<RawEdge>,
}

/// An edge as written.
#[derive(Debug)]
struct RawEdge {
    pos: Pos,
    label: Option<Label>,
    target: (u64, Pos),
    marks: MarkSet,
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

// ---------------------------------------------------------------- building

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
fn build(header: &Header, states: &[RawState], end: Pos) -> Result<EmersonLeiAutomaton, HoaError> {
    let (start, start_pos) = header.start;
    let evaluator = Evaluator::new(header)?;
    let num_states = state_count(header, states, start)?;
    if start >= num_states as u64 {
        return error_at(start_pos, format!("initial state {start} out of range"));
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

#[cfg(test)]
mod tests {
    use super::*;

    fn label_of(letters: &[usize], props: usize) -> String {
        let on: Vec<bool> = (0..1 << props).map(|a| letters.contains(&a)).collect();
        label_text(&on, props)
    }

    #[test]
    fn labels_are_compact_sums_of_cubes() {
        assert_eq!(label_of(&[0, 1, 2, 3], 2), "t");
        assert_eq!(label_of(&[], 2), "f");
        assert_eq!(label_of(&[1, 3], 2), "0");
        assert_eq!(label_of(&[0, 2], 2), "!0");
        assert_eq!(label_of(&[1, 2], 2), "0&!1 | !0&1");
        assert_eq!(label_of(&[1, 2, 3], 2), "1 | 0");
        assert_eq!(label_of(&[0], 0), "t");
    }

    #[test]
    fn comments_nest_and_strings_unescape() {
        let tokens =
            tokenize("/* a /* b */ c */ \"x\\\"y\\\\\" @al name: 12 --BODY--").expect("lexes");
        let kinds: Vec<Token> = tokens.into_iter().map(|(t, _)| t).collect();
        assert_eq!(
            kinds,
            [
                Token::Str("x\"y\\".into()),
                Token::Alias("al".into()),
                Token::Header("name".into()),
                Token::Int(12),
                Token::Body,
                Token::Eof,
            ]
        );
    }
}
