//! The abstract syntax of LTL, its printing in Spot's syntax, negation normal
//! form and simplification.

use std::collections::BTreeSet;
use std::fmt;

/// An LTL formula over atomic propositions named by strings.
///
/// A word `w = w_0 w_1 ...` over `2^AP` satisfies a formula at position `i`
/// as usual: `X f` iff `f` holds at `i + 1`; `f U g` iff `g` holds at some
/// `j >= i` and `f` at all `i <= k < j`; `f W g` iff `f U g` or `G f`;
/// `f R g` iff `!(!f U !g)`; `f M g` iff `!(!f W !g)`; `F f = true U f`;
/// `G f = false R f`.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Formula {
    /// `true`: every word.
    True,
    /// `false`: no word.
    False,
    /// An atomic proposition: holds iff it is in the current letter.
    Prop(String),
    /// `!f`.
    Not(Box<Formula>),
    /// `f_1 & ... & f_n` (`n >= 2`).
    And(Vec<Formula>),
    /// `f_1 | ... | f_n` (`n >= 2`).
    Or(Vec<Formula>),
    /// `f -> g`.
    Implies(Box<Formula>, Box<Formula>),
    /// `f <-> g`.
    Equiv(Box<Formula>, Box<Formula>),
    /// `f xor g`.
    Xor(Box<Formula>, Box<Formula>),
    /// `X f` (next).
    Next(Box<Formula>),
    /// `F f` (eventually).
    Finally(Box<Formula>),
    /// `G f` (always).
    Globally(Box<Formula>),
    /// `f U g` (strong until).
    Until(Box<Formula>, Box<Formula>),
    /// `f W g` (weak until).
    WeakUntil(Box<Formula>, Box<Formula>),
    /// `f R g` (weak release).
    Release(Box<Formula>, Box<Formula>),
    /// `f M g` (strong release).
    StrongRelease(Box<Formula>, Box<Formula>),
}

use Formula::*;

impl Formula {
    /// The atomic proposition named `name`.
    pub fn prop(name: &str) -> Formula {
        Prop(name.to_string())
    }

    /// The names of the atomic propositions occurring in the formula, sorted
    /// and without repetition.
    pub fn propositions(&self) -> Vec<String> {
        let mut names = BTreeSet::new();
        self.collect_propositions(&mut names);
        names.into_iter().map(str::to_string).collect()
    }

    fn collect_propositions<'a>(&'a self, names: &mut BTreeSet<&'a str>) {
        match self {
            True | False => {}
            Prop(name) => {
                names.insert(name);
            }
            Not(f) | Next(f) | Finally(f) | Globally(f) => f.collect_propositions(names),
            And(fs) | Or(fs) => fs.iter().for_each(|f| f.collect_propositions(names)),
            Implies(f, g)
            | Equiv(f, g)
            | Xor(f, g)
            | Until(f, g)
            | WeakUntil(f, g)
            | Release(f, g)
            | StrongRelease(f, g) => {
                f.collect_propositions(names);
                g.collect_propositions(names);
            }
        }
    }

    /// `!self`: a formula satisfied by exactly the words that do not satisfy
    /// `self` (constants are swapped and a double negation is removed).
    pub fn negate(&self) -> Formula {
        match self {
            True => False,
            False => True,
            Not(f) => (**f).clone(),
            f => Not(Box::new(f.clone())),
        }
    }

    /// Whether the top-level operator is binary (printed with parentheses
    /// when nested).
    fn is_binary(&self) -> bool {
        matches!(
            self,
            And(_)
                | Or(_)
                | Implies(..)
                | Equiv(..)
                | Xor(..)
                | Until(..)
                | WeakUntil(..)
                | Release(..)
                | StrongRelease(..)
        )
    }
}

/// Whether `name` can be printed without quotes: it matches
/// `[a-z_][a-z0-9_]*` and is not a keyword.
pub(crate) fn is_bare_name(name: &str) -> bool {
    let mut chars = name.chars();
    matches!(chars.next(), Some('a'..='z' | '_'))
        && chars.all(|c| matches!(c, 'a'..='z' | '0'..='9' | '_'))
        && !matches!(name, "true" | "false" | "xor")
}

struct Operand<'a>(&'a Formula);

impl fmt::Display for Operand<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_binary() {
            write!(f, "({})", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

impl fmt::Display for Formula {
    /// Prints the formula in Spot's syntax; every binary operand is
    /// parenthesised, so the output parses back to the same formula.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let join = |f: &mut fmt::Formatter<'_>, parts: &[Formula], op: &str| {
            for (i, part) in parts.iter().enumerate() {
                if i > 0 {
                    write!(f, " {op} ")?;
                }
                write!(f, "{}", Operand(part))?;
            }
            Ok(())
        };
        let binary = |f: &mut fmt::Formatter<'_>, l: &Formula, op: &str, r: &Formula| {
            write!(f, "{} {op} {}", Operand(l), Operand(r))
        };
        match self {
            True => write!(f, "true"),
            False => write!(f, "false"),
            Prop(name) if is_bare_name(name) => write!(f, "{name}"),
            Prop(name) => write!(f, "\"{name}\""),
            Not(g) => write!(f, "!{}", Operand(g)),
            Next(g) => write!(f, "X {}", Operand(g)),
            Finally(g) => write!(f, "F {}", Operand(g)),
            Globally(g) => write!(f, "G {}", Operand(g)),
            And(parts) => join(f, parts, "&"),
            Or(parts) => join(f, parts, "|"),
            Implies(l, r) => binary(f, l, "->", r),
            Equiv(l, r) => binary(f, l, "<->", r),
            Xor(l, r) => binary(f, l, "xor", r),
            Until(l, r) => binary(f, l, "U", r),
            WeakUntil(l, r) => binary(f, l, "W", r),
            Release(l, r) => binary(f, l, "R", r),
            StrongRelease(l, r) => binary(f, l, "M", r),
        }
    }
}

/// A formula in negation normal form, simplified: negation only on
/// propositions, no `-> <-> xor`, `And`/`Or` flattened, sorted, without
/// duplicates or constants, and at least two operands.
///
/// The constructors below apply simplification rules in the style of Spot's
/// basic rewritings (`F F f = F f`, `G G f = G f`, `X true = true`,
/// `F f | F g = F (f | g)`, `G f & G g = G (f & g)`, `f U false = false`,
/// `F G F f = G F f`, ...); each rule preserves the set of satisfying words.
pub(crate) fn nnf(formula: &Formula, positive: bool) -> Formula {
    let b = |g: &Formula, p: bool| nnf(g, p);
    match (formula, positive) {
        (True, true) | (False, false) => True,
        (True, false) | (False, true) => False,
        (Prop(_), true) => formula.clone(),
        (Prop(_), false) => Not(Box::new(formula.clone())),
        (Not(g), p) => b(g, !p),
        (And(gs), true) | (Or(gs), false) => and(gs.iter().map(|g| b(g, positive)).collect()),
        (Or(gs), true) | (And(gs), false) => or(gs.iter().map(|g| b(g, positive)).collect()),
        (Implies(l, r), true) => or(vec![b(l, false), b(r, true)]),
        (Implies(l, r), false) => and(vec![b(l, true), b(r, false)]),
        (Equiv(l, r), p) | (Xor(l, r), p) => {
            let equiv = matches!(formula, Equiv(..)) == p;
            let (lp, ln, rp, rn) = (b(l, true), b(l, false), b(r, true), b(r, false));
            if equiv {
                or(vec![and(vec![lp, rp]), and(vec![ln, rn])])
            } else {
                or(vec![and(vec![lp, rn]), and(vec![ln, rp])])
            }
        }
        (Next(g), p) => next(b(g, p)),
        (Finally(g), true) | (Globally(g), false) => finally(b(g, positive)),
        (Globally(g), true) | (Finally(g), false) => globally(b(g, positive)),
        (Until(l, r), true) => until(b(l, true), b(r, true)),
        (Until(l, r), false) => release(b(l, false), b(r, false)),
        (WeakUntil(l, r), true) => weak_until(b(l, true), b(r, true)),
        (WeakUntil(l, r), false) => strong_release(b(l, false), b(r, false)),
        (Release(l, r), true) => release(b(l, true), b(r, true)),
        (Release(l, r), false) => until(b(l, false), b(r, false)),
        (StrongRelease(l, r), true) => strong_release(b(l, true), b(r, true)),
        (StrongRelease(l, r), false) => weak_until(b(l, false), b(r, false)),
    }
}

fn junction(parts: Vec<Formula>, conjunction: bool) -> Formula {
    let (unit, zero) = if conjunction {
        (True, False)
    } else {
        (False, True)
    };
    let mut flat = BTreeSet::new();
    for part in parts {
        match part {
            And(inner) if conjunction => flat.extend(inner),
            Or(inner) if !conjunction => flat.extend(inner),
            p if p == unit => {}
            p if p == zero => return zero,
            p => {
                flat.insert(p);
            }
        }
    }
    if flat
        .iter()
        .any(|p| matches!(p, Not(q) if flat.contains(&**q)))
    {
        return zero;
    }
    let mut flat: Vec<Formula> = flat.into_iter().collect();
    match flat.len() {
        0 => unit,
        1 => flat.pop().unwrap_or(unit),
        _ if conjunction => And(flat),
        _ => Or(flat),
    }
}

/// `f_1 & ... & f_n`, simplified.
pub(crate) fn and(parts: Vec<Formula>) -> Formula {
    let merged = merge_temporal(parts, true);
    junction(merged, true)
}

/// `f_1 | ... | f_n`, simplified.
pub(crate) fn or(parts: Vec<Formula>) -> Formula {
    let merged = merge_temporal(parts, false);
    junction(merged, false)
}

/// `G f & G g = G (f & g)`, `X f & X g = X (f & g)`, `F G f & F G g =
/// F G (f & g)` and dually `F f | F g = F (f | g)`, `X f | X g = X (f | g)`,
/// `G F f | G F g = G F (f | g)`: fewer temporal atoms (a conjunction of
/// `n` persistence formulas is one, not `n` independent guesses).
fn merge_temporal(parts: Vec<Formula>, conjunction: bool) -> Vec<Formula> {
    let mut next_parts = Vec::new();
    let mut modal_parts = Vec::new();
    let mut limit_parts = Vec::new();
    let mut rest = Vec::new();
    for part in parts {
        match part {
            Next(g) => next_parts.push(*g),
            Finally(g) if conjunction && matches!(*g, Globally(_)) => match *g {
                Globally(h) => limit_parts.push(*h),
                other => rest.push(Finally(Box::new(other))),
            },
            Globally(g) if !conjunction && matches!(*g, Finally(_)) => match *g {
                Finally(h) => limit_parts.push(*h),
                other => rest.push(Globally(Box::new(other))),
            },
            Globally(g) if conjunction => modal_parts.push(*g),
            Finally(g) if !conjunction => modal_parts.push(*g),
            p => rest.push(p),
        }
    }
    match limit_parts.len() {
        0 => {}
        1 if conjunction => rest.push(Finally(Box::new(Globally(Box::new(limit_parts.remove(0)))))),
        1 => rest.push(Globally(Box::new(Finally(Box::new(limit_parts.remove(0)))))),
        _ => {
            let inner = if conjunction {
                and(limit_parts)
            } else {
                or(limit_parts)
            };
            rest.push(if conjunction {
                finally(globally(inner))
            } else {
                globally(finally(inner))
            });
        }
    }
    let combine = |gs: Vec<Formula>| junction(gs, conjunction);
    if next_parts.len() == 1 {
        rest.push(Next(Box::new(next_parts.remove(0))));
    } else if !next_parts.is_empty() {
        rest.push(next(combine(next_parts)));
    }
    if modal_parts.len() == 1 {
        let g = modal_parts.remove(0);
        rest.push(if conjunction {
            Globally(Box::new(g))
        } else {
            Finally(Box::new(g))
        });
    } else if !modal_parts.is_empty() {
        let g = combine(modal_parts);
        rest.push(if conjunction { globally(g) } else { finally(g) });
    }
    rest
}

/// `X f`, simplified (`X true = true`, `X false = false`).
pub(crate) fn next(f: Formula) -> Formula {
    match f {
        True | False => f,
        f => Next(Box::new(f)),
    }
}

/// Whether `f` is a suspendable "eventually always" or "always eventually"
/// formula whose truth does not depend on any finite prefix.
fn is_prefix_independent(f: &Formula) -> bool {
    match f {
        Finally(g) => matches!(**g, Globally(_)),
        Globally(g) => matches!(**g, Finally(_)),
        And(gs) | Or(gs) => gs.iter().all(is_prefix_independent),
        _ => false,
    }
}

/// `F f`, simplified.
pub(crate) fn finally(f: Formula) -> Formula {
    match f {
        True | False => f,
        Finally(_) => f,
        f if is_prefix_independent(&f) => f,
        Until(_, g) => finally(*g),
        StrongRelease(l, r) => finally(and(vec![*l, *r])),
        Next(g) => next(finally(*g)),
        f => Finally(Box::new(f)),
    }
}

/// `G f`, simplified.
pub(crate) fn globally(f: Formula) -> Formula {
    match f {
        True | False => f,
        Globally(_) => f,
        f if is_prefix_independent(&f) => f,
        Release(_, g) => globally(*g),
        WeakUntil(l, r) => globally(or(vec![*l, *r])),
        Next(g) => next(globally(*g)),
        f => Globally(Box::new(f)),
    }
}

/// Whether `f` propositionally implies `h` because `h` is `f` or `h`'s
/// conjuncts are among `f`'s.
fn implies_conjuncts(f: &Formula, h: &Formula) -> bool {
    let conjuncts = |x: &Formula| match x {
        And(xs) => xs.clone(),
        x => vec![x.clone()],
    };
    let fs = conjuncts(f);
    conjuncts(h).iter().all(|x| fs.contains(x))
}

/// `f U g`, simplified; also `f U (g | G h) = (f U g) | G h` if `f` implies
/// `h` (if `G h` holds at the position where the until is fulfilled, `h`
/// holds from the start), which is `f W g` for `h = f`.
pub(crate) fn until(f: Formula, g: Formula) -> Formula {
    if let Or(gs) = &g
        && let Some(at) = gs
            .iter()
            .position(|x| matches!(x, Globally(h) if implies_conjuncts(&f, h)))
    {
        let mut rest = gs.clone();
        let Globally(h) = rest.remove(at) else {
            unreachable!("matched above")
        };
        let rest = or(rest);
        return if *h == f {
            weak_until(f, rest)
        } else {
            or(vec![until(f, rest), Globally(h)])
        };
    }
    match (f, g) {
        (_, g @ (True | False)) => g,
        (False, g) => g,
        (True, g) => finally(g),
        (f, g) if f == g => f,
        (_, g @ Finally(_)) => g,
        (f, g) => Until(Box::new(f), Box::new(g)),
    }
}

/// `f W g`, simplified.
pub(crate) fn weak_until(f: Formula, g: Formula) -> Formula {
    match (f, g) {
        (_, True) | (True, _) => True,
        (False, g) => g,
        (f, False) => globally(f),
        (f, g) if f == g => f,
        (f, g) => WeakUntil(Box::new(f), Box::new(g)),
    }
}

/// `f R g`, simplified.
pub(crate) fn release(f: Formula, g: Formula) -> Formula {
    match (f, g) {
        (_, g @ (True | False)) => g,
        (True, g) => g,
        (False, g) => globally(g),
        (f, g) if f == g => f,
        (_, g @ Globally(_)) => g,
        (f, g) => Release(Box::new(f), Box::new(g)),
    }
}

/// `f M g`, simplified.
pub(crate) fn strong_release(f: Formula, g: Formula) -> Formula {
    match (f, g) {
        (_, False) | (False, _) => False,
        (True, g) => g,
        (f, True) => finally(f),
        (f, g) if f == g => f,
        (f, g) => StrongRelease(Box::new(f), Box::new(g)),
    }
}

/// Whether an NNF formula is propositional (no temporal operator): its
/// truth depends on the first letter only.
pub(crate) fn is_propositional(f: &Formula) -> bool {
    match f {
        True | False | Prop(_) => true,
        Not(g) => is_propositional(g),
        And(gs) | Or(gs) => gs.iter().all(is_propositional),
        _ => false,
    }
}

/// Whether an NNF formula is syntactically co-safety (no `G`, `R`, `W`):
/// every satisfying word has a finite prefix all of whose extensions satisfy it.
pub(crate) fn is_cosafety(f: &Formula) -> bool {
    match f {
        True | False | Prop(_) => true,
        Not(g) | Next(g) | Finally(g) => is_cosafety(g),
        And(gs) | Or(gs) => gs.iter().all(is_cosafety),
        Until(l, r) | StrongRelease(l, r) => is_cosafety(l) && is_cosafety(r),
        _ => false,
    }
}

/// Whether an NNF formula is syntactically safety (no `F`, `U`, `M`).
pub(crate) fn is_safety(f: &Formula) -> bool {
    match f {
        True | False | Prop(_) => true,
        Not(g) | Next(g) | Globally(g) => is_safety(g),
        And(gs) | Or(gs) => gs.iter().all(is_safety),
        Release(l, r) | WeakUntil(l, r) => is_safety(l) && is_safety(r),
        _ => false,
    }
}

/// Whether an NNF formula is in the syntactic obligation class of Černá and
/// Pelánek (2003), as in Spot: `O ::= S | C | O & O | O | O | X O | O U C |
/// O R S | S W O | C M O` with `S` safety and `C` co-safety, extended by
/// `(!c & O) U (c & O)` for a literal `c` and, dually, `(c | O) R (!c | O)`
/// (not for `W`: `(!c & O) W false` is `G (!c & O)`, a recurrence). Its language is an obligation property, recognised by a weak
/// deterministic automaton.
pub(crate) fn is_obligation(f: &Formula) -> bool {
    is_safety(f)
        || is_cosafety(f)
        || match f {
            Next(g) => is_obligation(g),
            And(gs) | Or(gs) => gs.iter().all(is_obligation),
            Until(l, r) if first_occurrence(l, r, true) => is_obligation(l) && is_obligation(r),
            Release(l, r) if first_occurrence(l, r, false) => is_obligation(l) && is_obligation(r),
            Until(l, r) => is_obligation(l) && is_cosafety(r),
            Release(l, r) => is_obligation(l) && is_safety(r),
            WeakUntil(l, r) => is_safety(l) && is_obligation(r),
            StrongRelease(l, r) => is_cosafety(l) && is_obligation(r),
            _ => false,
        }
}

/// The literals `f` is a conjunction (`conjunctive`) or disjunction of.
fn literals(f: &Formula, conjunctive: bool) -> Vec<&Formula> {
    match f {
        Prop(_) | Not(_) => vec![f],
        And(gs) if conjunctive => gs
            .iter()
            .filter(|g| matches!(g, Prop(_) | Not(_)))
            .collect(),
        Or(gs) if !conjunctive => gs
            .iter()
            .filter(|g| matches!(g, Prop(_) | Not(_)))
            .collect(),
        _ => Vec::new(),
    }
}

/// Whether `l U r` (`until`) has the shape `(!c & ...) U (c & ...)` for a
/// literal `c`, or `l R r` the dual shape `(c | ...) R (!c | ...)`: the
/// position where the right side is awaited is then the first one where `c`
/// holds, and `l U r` (resp. `l R r`) is an obligation property when `l` and
/// `r` are.
fn first_occurrence(l: &Formula, r: &Formula, until: bool) -> bool {
    let left = literals(l, until);
    literals(r, until).into_iter().any(|c| {
        let complement = match c {
            Not(p) => (**p).clone(),
            p => Not(Box::new(p.clone())),
        };
        left.contains(&&complement)
    })
}
