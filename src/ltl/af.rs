//! The "after" function `af(phi, sigma)` of Esparza, Křetínský and Sickert on
//! propositional equivalence classes of NNF formulas, and the substitutions
//! `phi[X]_nu` and `phi[Y]^mu` of their Master Theorem.
//!
//! A class is a BDD whose variables are *atoms*: propositions and formulas
//! whose top operator is temporal (`X F G U W R M`). `af(phi, sigma)` is the
//! formula that a word `w` must satisfy for `sigma w` to satisfy `phi`:
//! `af(a, sigma)` is `a in sigma`, `af(X f) = f`, `af(F f) = af(f) | F f`,
//! `af(G f) = af(f) & G f`, `af(f U g) = af(g) | (af(f) & f U g)`, the same
//! for `W`, `af(f R g) = af(g) & (af(f) | f R g)`, the same for `M`, and `af`
//! commutes with `&` and `|`.

use rustc_hash::FxHashMap;

use super::bdd::{Bdd, FALSE, Node, TRUE};
use super::formula::{self, Formula};
use super::lasso::Lasso;
use crate::automaton::Letter;

/// Formulas as BDDs over atoms, with memoised `af`.
#[derive(Debug)]
pub(crate) struct Context {
    pub(crate) bdd: Bdd,
    atoms: Vec<Formula>,
    atom_ids: FxHashMap<Formula, u32>,
    propositions: FxHashMap<String, u32>,
    af_memo: FxHashMap<(Node, Letter), Node>,
    atom_af_memo: FxHashMap<(u32, Letter), Node>,
}

impl Context {
    /// A context whose letters are bit sets over `propositions`.
    pub(crate) fn new(propositions: &[String]) -> Self {
        Self {
            bdd: Bdd::new(),
            atoms: Vec::new(),
            atom_ids: FxHashMap::default(),
            propositions: propositions
                .iter()
                .enumerate()
                .map(|(i, p)| (p.clone(), i as u32))
                .collect(),
            af_memo: FxHashMap::default(),
            atom_af_memo: FxHashMap::default(),
        }
    }

    fn atom(&mut self, formula: &Formula) -> Node {
        let next = self.atoms.len() as u32;
        let id = *self.atom_ids.entry(formula.clone()).or_insert(next);
        if id == next {
            self.atoms.push(formula.clone());
        }
        self.bdd.var(id)
    }

    /// The propositions in the bit order of the letters.
    pub(crate) fn propositions(&self) -> Vec<String> {
        let mut named: Vec<(&String, u32)> =
            self.propositions.iter().map(|(p, &i)| (p, i)).collect();
        named.sort_unstable_by_key(|&(_, i)| i);
        named.into_iter().map(|(p, _)| p.clone()).collect()
    }

    /// The class of an NNF formula.
    pub(crate) fn class(&mut self, formula: &Formula) -> Node {
        match formula {
            Formula::True => TRUE,
            Formula::False => FALSE,
            Formula::Not(p) => {
                let p = self.class(p);
                self.bdd.not(p)
            }
            Formula::And(parts) => parts.iter().fold(TRUE, |acc, part| {
                let part = self.class(part);
                self.bdd.and(acc, part)
            }),
            Formula::Or(parts) => parts.iter().fold(FALSE, |acc, part| {
                let part = self.class(part);
                self.bdd.or(acc, part)
            }),
            atom => self.atom(atom),
        }
    }

    /// `af(class, letter)`.
    pub(crate) fn after(&mut self, class: Node, letter: Letter) -> Node {
        if class <= TRUE {
            return class;
        }
        if let Some(&r) = self.af_memo.get(&(class, letter)) {
            return r;
        }
        let substitution = self
            .bdd
            .support(class)
            .into_iter()
            .map(|var| (var, self.atom_after(var, letter)))
            .collect();
        let r = self.bdd.compose(class, &substitution);
        self.af_memo.insert((class, letter), r);
        r
    }

    fn formula_after(&mut self, formula: &Formula, letter: Letter) -> Node {
        let class = self.class(formula);
        self.after(class, letter)
    }

    fn atom_after(&mut self, var: u32, letter: Letter) -> Node {
        if let Some(&r) = self.atom_af_memo.get(&(var, letter)) {
            return r;
        }
        let atom = self.atoms[var as usize].clone();
        let itself = self.bdd.var(var);
        let r = match &atom {
            Formula::Prop(name) => {
                let bit = self.propositions.get(name).copied();
                if bit.is_some_and(|bit| (letter >> bit) & 1 == 1) {
                    TRUE
                } else {
                    FALSE
                }
            }
            Formula::Next(f) => self.class(f),
            Formula::Finally(f) => {
                let now = self.formula_after(f, letter);
                self.bdd.or(now, itself)
            }
            Formula::Globally(f) => {
                let now = self.formula_after(f, letter);
                self.bdd.and(now, itself)
            }
            Formula::Until(f, g) | Formula::WeakUntil(f, g) => {
                let stay = self.formula_after(f, letter);
                let stay = self.bdd.and(stay, itself);
                let now = self.formula_after(g, letter);
                self.bdd.or(now, stay)
            }
            Formula::Release(f, g) | Formula::StrongRelease(f, g) => {
                let stop = self.formula_after(f, letter);
                let stop = self.bdd.or(stop, itself);
                let now = self.formula_after(g, letter);
                self.bdd.and(now, stop)
            }
            _ => itself,
        };
        self.atom_af_memo.insert((var, letter), r);
        r
    }

    /// `class` with every temporal atom `f` replaced by `rewrite(f)`
    /// (propositions are kept).
    pub(crate) fn substitute(
        &mut self,
        class: Node,
        rewrite: &dyn Fn(&Formula) -> Formula,
    ) -> Node {
        let temporal: Vec<u32> = self
            .bdd
            .support(class)
            .into_iter()
            .filter(|&var| !matches!(self.atoms[var as usize], Formula::Prop(_)))
            .collect();
        let substitution = temporal
            .into_iter()
            .map(|var| {
                let rewritten = rewrite(&self.atoms[var as usize]);
                (var, self.class(&rewritten))
            })
            .collect();
        self.bdd.compose(class, &substitution)
    }

    /// Whether the periodic word `cycle^omega` satisfies the formula `class`.
    pub(crate) fn holds_on_cycle(&self, class: Node, cycle: &[Letter]) -> bool {
        let word = Lasso { prefix: &[], cycle };
        let holds = |name: &str, position: usize| {
            self.propositions
                .get(name)
                .is_some_and(|&bit| (cycle[position] >> bit) & 1 == 1)
        };
        let truth: FxHashMap<u32, bool> = self
            .bdd
            .support(class)
            .into_iter()
            .map(|var| (var, word.truth(&self.atoms[var as usize], &holds)[0]))
            .collect();
        self.bdd
            .evaluate(class, |var| truth.get(&var).copied().unwrap_or(false))
    }
}

/// Which kind of fixpoint operator an NNF formula's top operator is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// `F`, `U`, `M`: least fixpoints.
    Mu,
    /// `G`, `R`, `W`: greatest fixpoints.
    Nu,
    /// Anything else.
    Other,
}

pub(crate) fn kind(f: &Formula) -> Kind {
    match f {
        Formula::Finally(_) | Formula::Until(..) | Formula::StrongRelease(..) => Kind::Mu,
        Formula::Globally(_) | Formula::Release(..) | Formula::WeakUntil(..) => Kind::Nu,
        _ => Kind::Other,
    }
}

/// The subformulas of `f` with top operator of the given kind that occur in
/// the scope of an operator of the other fixpoint kind, sorted, without
/// repetition.
///
/// Only these can matter in a guess of the Master Theorem: a mu-subformula
/// outside the scope of every nu-operator is evaluated at finitely many
/// positions of a satisfied obligation, so it can be left out of `X`, and
/// dually for `Y` (Esparza, Křetínský and Sickert, JACM 2020, Section 7).
pub(crate) fn guess_candidates(f: &Formula, wanted: Kind) -> Vec<Formula> {
    fn walk(f: &Formula, wanted: Kind, scoped: bool, out: &mut Vec<Formula>) {
        let k = kind(f);
        if k == wanted && scoped {
            out.push(f.clone());
        }
        let scoped = scoped || (k != wanted && k != Kind::Other);
        match f {
            Formula::Not(g) | Formula::Next(g) | Formula::Finally(g) | Formula::Globally(g) => {
                walk(g, wanted, scoped, out)
            }
            Formula::And(gs) | Formula::Or(gs) => {
                gs.iter().for_each(|g| walk(g, wanted, scoped, out))
            }
            Formula::Implies(g, h)
            | Formula::Equiv(g, h)
            | Formula::Xor(g, h)
            | Formula::Until(g, h)
            | Formula::WeakUntil(g, h)
            | Formula::Release(g, h)
            | Formula::StrongRelease(g, h) => {
                walk(g, wanted, scoped, out);
                walk(h, wanted, scoped, out);
            }
            Formula::True | Formula::False | Formula::Prop(_) => {}
        }
    }
    let mut out = Vec::new();
    walk(f, wanted, false, &mut out);
    out.sort();
    out.dedup();
    out
}

/// `f[X]_nu`: every mu-subformula in `x` is assumed to hold infinitely often
/// (`F g` becomes true, `g U h` becomes `g W h`, `g M h` becomes `g R h`),
/// every other one is replaced by false. The result has no mu-operators.
pub(crate) fn nu_under(f: &Formula, x: &[Formula]) -> Formula {
    let r = |g: &Formula| nu_under(g, x);
    let chosen = || x.binary_search(f).is_ok();
    match f {
        Formula::Finally(_) => {
            if chosen() {
                Formula::True
            } else {
                Formula::False
            }
        }
        Formula::Until(g, h) if chosen() => formula::weak_until(r(g), r(h)),
        Formula::StrongRelease(g, h) if chosen() => formula::release(r(g), r(h)),
        Formula::Until(..) | Formula::StrongRelease(..) => Formula::False,
        _ => map_children(f, &r),
    }
}

/// `f[Y]^mu`: every nu-subformula in `y` is assumed to hold almost always
/// (it becomes true); every other one is strengthened (`G g` becomes false,
/// `g W h` becomes `g U h`, `g R h` becomes `g M h`). The result has no
/// nu-operators.
pub(crate) fn mu_under(f: &Formula, y: &[Formula]) -> Formula {
    let r = |g: &Formula| mu_under(g, y);
    if kind(f) == Kind::Nu && y.binary_search(f).is_ok() {
        return Formula::True;
    }
    match f {
        Formula::Globally(_) => Formula::False,
        Formula::WeakUntil(g, h) => formula::until(r(g), r(h)),
        Formula::Release(g, h) => formula::strong_release(r(g), r(h)),
        _ => map_children(f, &r),
    }
}

/// `f` with its direct subformulas rewritten by `r`, simplified.
fn map_children(f: &Formula, r: &dyn Fn(&Formula) -> Formula) -> Formula {
    match f {
        Formula::And(gs) => formula::and(gs.iter().map(r).collect()),
        Formula::Or(gs) => formula::or(gs.iter().map(r).collect()),
        Formula::Next(g) => formula::next(r(g)),
        Formula::Finally(g) => formula::finally(r(g)),
        Formula::Globally(g) => formula::globally(r(g)),
        Formula::Until(g, h) => formula::until(r(g), r(h)),
        Formula::WeakUntil(g, h) => formula::weak_until(r(g), r(h)),
        Formula::Release(g, h) => formula::release(r(g), r(h)),
        Formula::StrongRelease(g, h) => formula::strong_release(r(g), r(h)),
        other => other.clone(),
    }
}
