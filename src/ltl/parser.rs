//! A recursive-descent parser for Spot's LTL syntax.
//!
//! Operators, from the loosest to the tightest binding (as in Spot's
//! grammar): `-> => <-> <=>` (right-associative), `| || \/`, `xor ^`,
//! `& && /\`, `U W R M` (right-associative), then the prefix operators
//! `! ~ X F G [] <>`. `|`, `xor` and `&` associate to the left.

use thiserror::Error;

use super::formula::Formula;

/// Why a text is not an LTL formula.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
#[error("column {column}: {message}")]
pub struct ParseError {
    /// The 1-based column (in characters) where the problem was found.
    pub column: usize,
    /// What was found and what was expected there.
    pub message: String,
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Token {
    Constant(bool),
    Prop(String),
    Not,
    And,
    Or,
    Xor,
    Implies,
    Equiv,
    Next,
    Finally,
    Globally,
    Binary(char),
    Open,
    Close,
    End,
}

impl Token {
    fn describe(&self) -> String {
        match self {
            Token::Constant(value) => format!("constant '{value}'"),
            Token::Prop(name) => format!("proposition '{name}'"),
            Token::Not => "'!'".into(),
            Token::And => "'&'".into(),
            Token::Or => "'|'".into(),
            Token::Xor => "'xor'".into(),
            Token::Implies => "'->'".into(),
            Token::Equiv => "'<->'".into(),
            Token::Next => "'X'".into(),
            Token::Finally => "'F'".into(),
            Token::Globally => "'G'".into(),
            Token::Binary(op) => format!("'{op}'"),
            Token::Open => "'('".into(),
            Token::Close => "')'".into(),
            Token::End => "end of formula".into(),
        }
    }
}

/// Splits `text` into tokens with their 1-based columns.
fn lex(text: &str) -> Result<Vec<(Token, usize)>, ParseError> {
    let chars: Vec<char> = text.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    let error = |column: usize, message: String| Err(ParseError { column, message });
    while i < chars.len() {
        let column = i + 1;
        let c = chars[i];
        let rest: String = chars[i..chars.len().min(i + 3)].iter().collect();
        let symbol = [
            ("<->", Token::Equiv),
            ("<=>", Token::Equiv),
            ("->", Token::Implies),
            ("=>", Token::Implies),
            ("&&", Token::And),
            ("/\\", Token::And),
            ("||", Token::Or),
            ("\\/", Token::Or),
            ("[]", Token::Globally),
            ("<>", Token::Finally),
            ("&", Token::And),
            ("|", Token::Or),
            ("^", Token::Xor),
            ("!", Token::Not),
            ("~", Token::Not),
            ("(", Token::Open),
            (")", Token::Close),
        ]
        .into_iter()
        .find(|(s, _)| rest.starts_with(s));
        if c.is_whitespace() {
            i += 1;
        } else if let Some((s, token)) = symbol {
            tokens.push((token, column));
            i += s.chars().count();
        } else if c == '"' {
            let Some(len) = chars[i + 1..].iter().position(|&d| d == '"') else {
                return error(
                    column,
                    "unterminated quoted proposition: expected '\"'".into(),
                );
            };
            if len == 0 {
                return error(column, "empty quoted proposition: expected a name".into());
            }
            let name: String = chars[i + 1..i + 1 + len].iter().collect();
            tokens.push((Token::Prop(name), column));
            i += len + 2;
        } else if c.is_ascii_lowercase() || c == '_' {
            let len = chars[i..]
                .iter()
                .take_while(|d| d.is_ascii_lowercase() || d.is_ascii_digit() || **d == '_')
                .count();
            let word: String = chars[i..i + len].iter().collect();
            let token = match word.as_str() {
                "true" => Token::Constant(true),
                "false" => Token::Constant(false),
                "xor" => Token::Xor,
                _ => Token::Prop(word),
            };
            tokens.push((token, column));
            i += len;
        } else if c.is_ascii_digit() {
            let len = chars[i..].iter().take_while(|d| d.is_ascii_digit()).count();
            match &chars[i..i + len] {
                ['0'] => tokens.push((Token::Constant(false), column)),
                ['1'] => tokens.push((Token::Constant(true), column)),
                _ => {
                    let number: String = chars[i..i + len].iter().collect();
                    return error(
                        column,
                        format!("unexpected number '{number}': expected '0', '1' or a proposition"),
                    );
                }
            }
            i += len;
        } else {
            let token = match c {
                'X' => Token::Next,
                'F' => Token::Finally,
                'G' => Token::Globally,
                'U' | 'W' | 'R' | 'M' => Token::Binary(c),
                _ => {
                    return error(
                        column,
                        format!(
                            "unexpected character '{c}': expected an operator, a constant or a proposition ([a-z_][a-z0-9_]* or double-quoted)"
                        ),
                    );
                }
            };
            tokens.push((token, column));
            i += 1;
        }
    }
    tokens.push((Token::End, chars.len() + 1));
    Ok(tokens)
}

struct Parser {
    tokens: Vec<(Token, usize)>,
    position: usize,
}

/// The deepest nesting accepted (parentheses, unary operators and the
/// right operands of `->`, `<->`, `U`, `R`, `W`, `M` each count one), so
/// that parsing and every later walk of the formula cannot overflow the
/// stack.
pub const MAX_DEPTH: usize = 1000;

/// `xor` chains with more operands than this become balanced trees.
const BALANCED_XOR: usize = 3;

/// `f_1 xor ... xor f_n` as a balanced tree of depth `ceil(log2 n)`.
fn balanced_xor(mut parts: Vec<Formula>) -> Formula {
    if parts.len() == 1 {
        return parts.remove(0);
    }
    let right = parts.split_off(parts.len() / 2);
    Formula::Xor(Box::new(balanced_xor(parts)), Box::new(balanced_xor(right)))
}

impl Parser {
    fn peek(&self) -> &Token {
        &self.tokens[self.position].0
    }

    fn column(&self) -> usize {
        self.tokens[self.position].1
    }

    fn advance(&mut self) -> Token {
        let token = self.tokens[self.position].0.clone();
        if self.position + 1 < self.tokens.len() {
            self.position += 1;
        }
        token
    }

    fn expected(&self, what: &str) -> ParseError {
        ParseError {
            column: self.column(),
            message: format!("expected {what}, found {}", self.peek().describe()),
        }
    }

    fn check_depth(&self, depth: usize) -> Result<(), ParseError> {
        if depth > MAX_DEPTH {
            Err(ParseError {
                column: self.column(),
                message: format!(
                    "formula nested deeper than {MAX_DEPTH} levels (parentheses and operators): \
                     expected a flatter formula"
                ),
            })
        } else {
            Ok(())
        }
    }

    /// `implication := disjunction ((-> | <->) implication)?`
    fn implication(&mut self, depth: usize) -> Result<Formula, ParseError> {
        self.check_depth(depth)?;
        let left = self.disjunction(depth)?;
        let op = self.peek().clone();
        if !matches!(op, Token::Implies | Token::Equiv) {
            return Ok(left);
        }
        self.advance();
        let right = Box::new(self.implication(depth + 1)?);
        Ok(if op == Token::Implies {
            Formula::Implies(Box::new(left), right)
        } else {
            Formula::Equiv(Box::new(left), right)
        })
    }

    /// `disjunction := exclusive (| exclusive)*`
    fn disjunction(&mut self, depth: usize) -> Result<Formula, ParseError> {
        let mut parts = vec![self.exclusive(depth)?];
        while *self.peek() == Token::Or {
            self.advance();
            parts.push(self.exclusive(depth)?);
        }
        Ok(if parts.len() == 1 {
            parts.remove(0)
        } else {
            Formula::Or(parts)
        })
    }

    /// `exclusive := conjunction (xor conjunction)*`, associating to the
    /// left; a chain longer than [`BALANCED_XOR`] is built as a balanced
    /// tree (`xor` is associative), so that its depth, and the recursion of
    /// everything that walks it, grows with the logarithm of its length.
    fn exclusive(&mut self, depth: usize) -> Result<Formula, ParseError> {
        let mut parts = vec![self.conjunction(depth)?];
        while *self.peek() == Token::Xor {
            self.advance();
            parts.push(self.conjunction(depth)?);
        }
        if parts.len() > BALANCED_XOR {
            return Ok(balanced_xor(parts));
        }
        let mut parts = parts.into_iter();
        let first = parts.next().expect("at least one operand");
        Ok(parts.fold(first, |left, right| {
            Formula::Xor(Box::new(left), Box::new(right))
        }))
    }

    /// `conjunction := temporal (& temporal)*`
    fn conjunction(&mut self, depth: usize) -> Result<Formula, ParseError> {
        let mut parts = vec![self.temporal(depth)?];
        while *self.peek() == Token::And {
            self.advance();
            parts.push(self.temporal(depth)?);
        }
        Ok(if parts.len() == 1 {
            parts.remove(0)
        } else {
            Formula::And(parts)
        })
    }

    /// `temporal := unary ((U | W | R | M) temporal)?`
    fn temporal(&mut self, depth: usize) -> Result<Formula, ParseError> {
        self.check_depth(depth)?;
        let left = Box::new(self.unary(depth)?);
        let Token::Binary(op) = *self.peek() else {
            return Ok(*left);
        };
        self.advance();
        let right = Box::new(self.temporal(depth + 1)?);
        Ok(match op {
            'U' => Formula::Until(left, right),
            'W' => Formula::WeakUntil(left, right),
            'R' => Formula::Release(left, right),
            _ => Formula::StrongRelease(left, right),
        })
    }

    /// `unary := (! | X | F | G) unary | constant | proposition | ( implication )`
    fn unary(&mut self, depth: usize) -> Result<Formula, ParseError> {
        self.check_depth(depth)?;
        let wrap: fn(Box<Formula>) -> Formula = match self.peek() {
            Token::Not => Formula::Not,
            Token::Next => Formula::Next,
            Token::Finally => Formula::Finally,
            Token::Globally => Formula::Globally,
            Token::Constant(value) => {
                let value = *value;
                self.advance();
                return Ok(if value { Formula::True } else { Formula::False });
            }
            Token::Prop(name) => {
                let name = name.clone();
                self.advance();
                return Ok(Formula::Prop(name));
            }
            Token::Open => {
                self.advance();
                let inner = self.implication(depth + 1)?;
                if *self.peek() != Token::Close {
                    return Err(self.expected("')' or a binary operator"));
                }
                self.advance();
                return Ok(inner);
            }
            _ => {
                return Err(
                    self.expected("a formula (constant, proposition, unary operator or '(')")
                );
            }
        };
        self.advance();
        Ok(wrap(Box::new(self.unary(depth + 1)?)))
    }
}

/// Parses an LTL formula written in Spot's syntax (see the module docs for
/// the operators and their precedence).
pub fn parse(text: &str) -> Result<Formula, ParseError> {
    let mut parser = Parser {
        tokens: lex(text)?,
        position: 0,
    };
    let formula = parser.implication(0)?;
    if *parser.peek() != Token::End {
        return Err(parser.expected("a binary operator or end of formula"));
    }
    Ok(formula)
}
