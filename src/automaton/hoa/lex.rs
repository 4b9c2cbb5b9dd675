//! The HOA lexer: text to tokens with their line and column.
//!
//! Contract: [`tokenize`] returns every token of the text in order, each with
//! the position (line and column from 1) of its first character, and ends
//! with [`Token::Eof`]. White space and nested `/* ... */` comments separate
//! tokens and are dropped; string literals are unescaped (a backslash escapes
//! the next character). Errors ([`HoaError::Syntax`]): an unterminated
//! comment or string, a number too large for `u64`, an `@` without a name, a
//! `--...--` word that is not `--BODY--`, `--END--` or `--ABORT--`, and any
//! other character that starts no token.

use super::HoaError;
use super::write::quoted;

/// A line and column, both from 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Pos {
    line: usize,
    column: usize,
}

/// A syntax error at `pos`.
pub(super) fn error_at<T>(pos: Pos, message: impl Into<String>) -> Result<T, HoaError> {
    Err(HoaError::Syntax {
        line: pos.line,
        column: pos.column,
        message: message.into(),
    })
}

/// A HOA token.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum Token {
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
    pub(super) fn describe(&self) -> String {
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

/// The tokens of `text` with their positions, ending with [`Token::Eof`].
pub(super) fn tokenize(text: &str) -> Result<Vec<(Token, Pos)>, HoaError> {
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

#[cfg(test)]
mod tests {
    use super::*;

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
