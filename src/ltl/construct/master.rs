//! The Master Theorem automaton of Esparza, Křetínský and Sickert, for any
//! NNF formula.
//!
//! Contract: [`master`] returns an automaton with transition-based
//! generalised Rabin acceptance (one disjunct per remaining guess `(X, Y)`)
//! accepting exactly the words of `phi`. It runs in five steps: find the
//! candidates `mu(phi)` and `nu(phi)` ([`fixpoint_candidates`]), enumerate
//! the guesses and the monitors they need ([`enumerate_guesses`]), keep the
//! strongest guesses ([`strongest_guesses`]), number the marks of the
//! monitors they use ([`MarkLayout`]), and explore the product of the
//! `af`-tracker with those monitors ([`explore_product`]). Errors:
//! [`TranslateError::TooManyFixpoints`] when `|mu(phi)| + |nu(phi)|` exceeds
//! [`MAX_GUESS_BITS`], [`TranslateError::TooManyMarks`] when the monitors
//! need more marks than a [`MarkSet`] holds, and
//! [`TranslateError::TooLarge`] and [`TranslateError::OutOfTime`] from the
//! exploration.

use rustc_hash::FxHashMap;

use super::{Disjunct, Tgr, explore};
use crate::automaton::emerson_lei::Edge;
use crate::automaton::{Letter, MarkSet};
use crate::ltl::TranslateError;
use crate::ltl::af::{self, Context, Kind};
use crate::ltl::bdd::{FALSE, Node, TRUE};
use crate::ltl::formula::{self, Formula};

/// One guess `(X, Y)` of the Master Theorem, by the monitors it needs.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Guess {
    /// The co-Büchi monitor of condition (1), if not trivially satisfied.
    safety: Option<usize>,
    /// The Büchi monitors `GF (psi[Y]^mu)` for `psi` in `X` (condition 2).
    recurrent: Vec<usize>,
    /// The co-Büchi monitors `FG (psi[X]_nu)` for `psi` in `Y` (condition 3).
    persistent: Vec<usize>,
}

impl Guess {
    /// Whether every condition `other` asks for is one `self` asks for too.
    fn implies(&self, other: &Guess) -> bool {
        (other.safety.is_none() || other.safety == self.safety)
            && other.recurrent.iter().all(|m| self.recurrent.contains(m))
            && other.persistent.iter().all(|m| self.persistent.contains(m))
    }
}

/// The largest `|mu(phi)| + |nu(phi)|` for which all guesses are enumerated.
const MAX_GUESS_BITS: usize = 16;

/// The position of `item` in `items`, appended if it is new.
fn index_of<T: PartialEq>(items: &mut Vec<T>, item: T) -> usize {
    match items.iter().position(|i| *i == item) {
        Some(i) => i,
        None => {
            items.push(item);
            items.len() - 1
        }
    }
}

/// The automaton of Esparza, Křetínský and Sickert's Master Theorem for any
/// NNF formula `phi`: `w |= phi` iff for some `X ⊆ mu(phi)`, `Y ⊆ nu(phi)`,
/// (1) `w_i |= af(phi, w_0..w_{i-1})[X]_nu` for some `i`, (2) `w |= GF
/// (psi[Y]^mu)` for all `psi` in `X`, and (3) `w |= FG (psi[X]_nu)` for all
/// `psi` in `Y`.
///
/// The state is `(af(phi, u), s_X..., g_c..., f_s...)`:
/// * `s_X` checks the safety formula of (1) and, when it becomes false
///   (a `Fin` mark), restarts from `af(phi, u)[X]_nu`;
/// * `g_c` is the disjunction of `af(c, ...)` over all start positions since
///   the last success; it becomes true (an `Inf` mark) infinitely often iff
///   `GF c`;
/// * `f_s` is the conjunction of `af(s, ...)` over all start positions since
///   the last failure; it fails (a `Fin` mark) finitely often iff `FG s`.
pub(crate) fn master(
    context: &mut Context,
    formula: &Formula,
    letters: usize,
) -> Result<Tgr, TranslateError> {
    let (mu, nu) = fixpoint_candidates(formula)?;
    let root = context.class(formula);
    let (monitors, found) = enumerate_guesses(context, root, &mu, &nu);
    let strongest = strongest_guesses(context, &mu, &nu, found);
    let layout = MarkLayout::of(&strongest)?;
    let disjuncts: Vec<Disjunct> = strongest.iter().map(|g| layout.disjunct(g)).collect();
    let edges = explore_product(context, root, &monitors, &layout, &disjuncts, letters)?;
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks: layout.num_marks() as u32,
        disjuncts,
    })
}

/// The candidates `mu(phi)` and `nu(phi)` of the guesses, or an error when
/// there are more than [`MAX_GUESS_BITS`] of them together.
fn fixpoint_candidates(formula: &Formula) -> Result<(Vec<Formula>, Vec<Formula>), TranslateError> {
    let mu = af::guess_candidates(formula, Kind::Mu);
    let nu = af::guess_candidates(formula, Kind::Nu);
    if mu.len() + nu.len() > MAX_GUESS_BITS {
        return Err(TranslateError::TooManyFixpoints {
            count: mu.len() + nu.len(),
            limit: MAX_GUESS_BITS,
        });
    }
    Ok((mu, nu))
}

/// The monitors the guesses need, each numbered by its first use.
#[derive(Debug, Default)]
struct Monitors {
    /// The set `X` of each co-Büchi monitor of condition (1).
    safety_sets: Vec<Vec<Formula>>,
    /// The initial class `af(phi)[X]_nu` of each monitor of condition (1).
    safety_initial: Vec<Node>,
    /// The class `c` of each Büchi monitor `GF c` of condition (2).
    recurrent: Vec<Node>,
    /// The class `s` of each co-Büchi monitor `FG s` of condition (3).
    persistent: Vec<Node>,
}

impl Monitors {
    /// The guess `(X, Y)` (`X` the members of `mu(phi)` in `x_bits`, `Y`
    /// those of `nu(phi)` in `y_bits`), registering the monitors it needs;
    /// `None` if one of its conditions (2) or (3) is `false`. `start` is
    /// `af(phi)[X]_nu`.
    fn guess(
        &mut self,
        context: &mut Context,
        start: Node,
        (x_bits, x): (u32, &[Formula]),
        (y_bits, y): (u32, &[Formula]),
    ) -> Option<Found> {
        let mut guess = Guess {
            safety: None,
            recurrent: Vec::new(),
            persistent: Vec::new(),
        };
        let mut infinitely_often = Vec::new();
        let mut almost_always = TRUE;
        for psi in x {
            let c = af::mu_under(psi, y);
            match context.class(&c) {
                FALSE => return None,
                TRUE => {}
                class => guess.recurrent.push(index_of(&mut self.recurrent, class)),
            }
            infinitely_often.push(context.class(&recurrence_core(&c)));
        }
        for psi in y {
            let s = af::nu_under(psi, x);
            match context.class(&s) {
                FALSE => return None,
                TRUE => {}
                class => guess.persistent.push(index_of(&mut self.persistent, class)),
            }
            let core = context.class(&persistence_core(&s));
            almost_always = context.bdd.and(almost_always, core);
        }
        if start != TRUE {
            let i = index_of(&mut self.safety_sets, x.to_vec());
            if i == self.safety_initial.len() {
                self.safety_initial.push(start);
            }
            guess.safety = Some(i);
        }
        guess.recurrent.sort_unstable();
        guess.recurrent.dedup();
        guess.persistent.sort_unstable();
        guess.persistent.dedup();
        Some(Found {
            x_bits,
            y_bits,
            infinitely_often,
            almost_always,
            guess,
        })
    }
}

/// Every guess `(X, Y)` over the candidates `mu` and `nu` whose conditions
/// are not `false`, in the order of `(x_bits, y_bits)`, with the monitors
/// they need; `root` is the class of `phi`.
fn enumerate_guesses(
    context: &mut Context,
    root: Node,
    mu: &[Formula],
    nu: &[Formula],
) -> (Monitors, Vec<Found>) {
    let mut monitors = Monitors::default();
    let mut found = Vec::new();
    for x_bits in 0u32..1 << mu.len() {
        let x: Vec<Formula> = select(mu, x_bits);
        let start = context.substitute(root, &|f| af::nu_under(f, &x));
        for y_bits in 0u32..1 << nu.len() {
            let y: Vec<Formula> = select(nu, y_bits);
            found.extend(monitors.guess(context, start, (x_bits, &x), (y_bits, &y)));
        }
    }
    (monitors, found)
}

/// The distinct guesses left when those [`dominates`] finds redundant are
/// dropped, and then those that imply another remaining one.
fn strongest_guesses(
    context: &mut Context,
    mu: &[Formula],
    nu: &[Formula],
    found: Vec<Found>,
) -> Vec<Guess> {
    let dominated: Vec<bool> = (0..found.len())
        .map(|i| {
            (0..found.len()).any(|j| j != i && dominates(context, mu, nu, &found[j], &found[i]))
        })
        .collect();
    let mut guesses: Vec<Guess> = found
        .into_iter()
        .zip(dominated)
        .filter(|(_, d)| !d)
        .map(|(f, _)| f.guess)
        .collect();
    guesses.sort();
    guesses.dedup();
    guesses
        .iter()
        .filter(|g| !guesses.iter().any(|h| h != *g && g.implies(h)))
        .cloned()
        .collect()
}

/// The monitors some remaining guess uses (indices into [`Monitors`]),
/// numbered densely as marks: the safety monitors first, then the recurrent
/// ones, then the persistent ones.
#[derive(Debug)]
struct MarkLayout {
    safety: Vec<usize>,
    recurrent: Vec<usize>,
    persistent: Vec<usize>,
}

impl MarkLayout {
    /// The monitors `guesses` use, or an error when their marks do not fit a
    /// [`MarkSet`].
    fn of(guesses: &[Guess]) -> Result<Self, TranslateError> {
        let layout = MarkLayout {
            safety: used(guesses.iter().filter_map(|g| g.safety)),
            recurrent: used(guesses.iter().flat_map(|g| g.recurrent.iter().copied())),
            persistent: used(guesses.iter().flat_map(|g| g.persistent.iter().copied())),
        };
        if layout.num_marks() > MarkSet::BITS as usize {
            return Err(TranslateError::TooManyMarks {
                count: layout.num_marks(),
                limit: MarkSet::BITS as usize,
            });
        }
        Ok(layout)
    }

    /// The number of marks: one per monitor in use.
    fn num_marks(&self) -> usize {
        self.safety.len() + self.recurrent.len() + self.persistent.len()
    }

    /// The mark of safety monitor `i`.
    fn safety_mark(&self, i: usize) -> u32 {
        self.safety.iter().position(|&j| j == i).unwrap_or(0) as u32
    }

    /// The mark of recurrent monitor `i`.
    fn recurrent_mark(&self, i: usize) -> u32 {
        (self.safety.len() + self.recurrent.iter().position(|&j| j == i).unwrap_or(0)) as u32
    }

    /// The mark of persistent monitor `i`.
    fn persistent_mark(&self, i: usize) -> u32 {
        (self.safety.len()
            + self.recurrent.len()
            + self.persistent.iter().position(|&j| j == i).unwrap_or(0)) as u32
    }

    /// The disjunct of `guess`: `Fin` of its safety and persistent monitors,
    /// `Inf` of each of its recurrent ones.
    fn disjunct(&self, guess: &Guess) -> Disjunct {
        Disjunct {
            fin: guess
                .safety
                .iter()
                .map(|&i| self.safety_mark(i))
                .chain(guess.persistent.iter().map(|&i| self.persistent_mark(i)))
                .fold(0, |m, bit| m | (1 << bit)),
            inf: guess
                .recurrent
                .iter()
                .map(|&i| self.recurrent_mark(i))
                .collect(),
        }
    }
}

/// The edges of the product of the `af`-tracker (from `root`) with the
/// monitors of `layout`, explored from the initial state.
fn explore_product(
    context: &mut Context,
    root: Node,
    monitors: &Monitors,
    layout: &MarkLayout,
    disjuncts: &[Disjunct],
    letters: usize,
) -> Result<Vec<Edge>, TranslateError> {
    let mut product = MonitorProduct::new(root, monitors, layout, disjuncts);
    let initial = product.goals.clone();
    let (_, edges) = explore(initial, letters, |state: &Vec<Node>, letter| {
        product.step(context, state, letter)
    })?;
    Ok(edges)
}

/// The transition function of the product state `(af(phi, u), s_X...,
/// g_c..., f_s...)` (see [`master`]).
struct MonitorProduct {
    /// The initial state; a monitor that succeeds or fails restarts from its
    /// entry here.
    goals: Vec<Node>,
    /// The set `X` of each safety monitor in use, by mark.
    safety_x: Vec<Vec<Formula>>,
    /// The number of safety monitors in use.
    num_safety: usize,
    /// The number of recurrent monitors in use.
    num_recurrent: usize,
    /// Every mark some disjunct has in its `Fin` set.
    fin_all: MarkSet,
    /// Every mark some disjunct has in an `Inf` set.
    inf_all: MarkSet,
    /// `af(phi, u)[X]_nu` by `(af(phi, u), safety mark)`.
    restart_memo: FxHashMap<(Node, usize), Node>,
}

impl MonitorProduct {
    /// The product of the tracker from `root` with the monitors of `layout`.
    fn new(root: Node, monitors: &Monitors, layout: &MarkLayout, disjuncts: &[Disjunct]) -> Self {
        let fin_all: MarkSet = disjuncts.iter().fold(0, |m, d| m | d.fin);
        let inf_all: MarkSet = disjuncts
            .iter()
            .flat_map(|d| d.inf.iter())
            .fold(0, |m, &bit| m | (1 << bit));
        let safety_x: Vec<Vec<Formula>> = layout
            .safety
            .iter()
            .map(|&i| monitors.safety_sets[i].clone())
            .collect();
        let mut goals = vec![root];
        goals.extend(layout.safety.iter().map(|&i| monitors.safety_initial[i]));
        goals.extend(layout.recurrent.iter().map(|&i| monitors.recurrent[i]));
        goals.extend(layout.persistent.iter().map(|&i| monitors.persistent[i]));
        MonitorProduct {
            goals,
            safety_x,
            num_safety: layout.safety.len(),
            num_recurrent: layout.recurrent.len(),
            fin_all,
            inf_all,
            restart_memo: FxHashMap::default(),
        }
    }

    /// The successor of `state` on `letter` and the marks of the transition.
    fn step(
        &mut self,
        context: &mut Context,
        state: &[Node],
        letter: Letter,
    ) -> (Vec<Node>, MarkSet) {
        let main = context.after(state[0], letter);
        if main == FALSE {
            return (vec![FALSE; state.len()], self.fin_all);
        }
        if main == TRUE {
            return (vec![TRUE; state.len()], self.inf_all);
        }
        let mut next = Vec::with_capacity(state.len());
        next.push(main);
        let mut marks: MarkSet = 0;
        for (k, &s) in state.iter().enumerate().skip(1) {
            let moved = context.after(s, letter);
            let (value, marked) = self.monitor_step(context, main, k, moved);
            next.push(value);
            if marked {
                marks |= 1 << (k - 1);
            }
        }
        (next, marks)
    }

    /// The next value of monitor `k` (entry `k` of the state), whose class
    /// moved to `moved`, given the tracker's next class `main`, and whether
    /// the transition carries its mark:
    /// * a safety monitor that becomes false restarts from `main[X]_nu`
    ///   (marked);
    /// * a recurrent monitor that becomes true restarts (marked), otherwise
    ///   it adds a start at this position (`|`);
    /// * a persistent monitor that becomes false restarts (marked),
    ///   otherwise it adds a start at this position (`&`).
    fn monitor_step(
        &mut self,
        context: &mut Context,
        main: Node,
        k: usize,
        moved: Node,
    ) -> (Node, bool) {
        let goal = self.goals[k];
        if k <= self.num_safety {
            if moved == FALSE {
                let x = &self.safety_x[k - 1];
                let restarted = *self
                    .restart_memo
                    .entry((main, k - 1))
                    .or_insert_with(|| context.substitute(main, &|f| af::nu_under(f, x)));
                (restarted, true)
            } else {
                (moved, false)
            }
        } else if k <= self.num_safety + self.num_recurrent {
            if moved == TRUE {
                (goal, true)
            } else {
                (context.bdd.or(moved, goal), false)
            }
        } else if moved == FALSE {
            (goal, true)
        } else {
            (context.bdd.and(moved, goal), false)
        }
    }
}

/// A guess `(X, Y)` (as bit sets over the candidates) with its monitors and
/// what its conditions (2) and (3) say: `GF c` for every class `c` of
/// `infinitely_often`, and `FG almost_always`.
struct Found {
    x_bits: u32,
    y_bits: u32,
    infinitely_often: Vec<Node>,
    almost_always: Node,
    guess: Guess,
}

/// Whether every word satisfying the conditions of guess `stronger` also
/// satisfies those of `weaker`, so that `stronger`'s disjunct is
/// redundant: `X ⊆ X'`, `Y ⊆ Y'` (then condition (1) and the conditions
/// for the common members are monotone), and for every `psi` in `X' \ X`
/// some `GF c` of `stronger` implies `GF (psi[Y']^mu)`, for every `psi` in
/// `Y' \ Y` the `FG s` of `stronger` implies `FG (psi[X']_nu)`; `GF c`
/// implies `GF c'` if `c` propositionally implies `c'`, up to
/// [`recurrence_core`], dually for `FG`.
fn dominates(
    context: &mut Context,
    mu: &[Formula],
    nu: &[Formula],
    weaker: &Found,
    stronger: &Found,
) -> bool {
    if stronger.x_bits & !weaker.x_bits != 0 || stronger.y_bits & !weaker.y_bits != 0 {
        return false;
    }
    let x = select(mu, weaker.x_bits);
    let y = select(nu, weaker.y_bits);
    let implies = |context: &mut Context, a: Node, b: Node| {
        let not_b = context.bdd.not(b);
        context.bdd.and(a, not_b) == FALSE
    };
    for psi in select(mu, weaker.x_bits & !stronger.x_bits) {
        let c = context.class(&recurrence_core(&af::mu_under(&psi, &y)));
        if !stronger
            .infinitely_often
            .iter()
            .any(|&d| implies(context, d, c))
        {
            return false;
        }
    }
    for psi in select(nu, weaker.y_bits & !stronger.y_bits) {
        let s = context.class(&persistence_core(&af::nu_under(&psi, &x)));
        if !implies(context, stronger.almost_always, s) {
            return false;
        }
    }
    true
}

/// A formula `c'` with `GF c' = GF c`: `GF F g = GF X g = GF (f U g) = GF g`,
/// `GF (f M g) = GF (f & g)`, and `GF` distributes over `|`.
fn recurrence_core(c: &Formula) -> Formula {
    match c {
        Formula::Finally(g) | Formula::Next(g) | Formula::Until(_, g) => recurrence_core(g),
        Formula::StrongRelease(f, g) => formula::and(vec![(**f).clone(), (**g).clone()]),
        Formula::Or(gs) => formula::or(gs.iter().map(recurrence_core).collect()),
        other => other.clone(),
    }
}

/// A formula `s'` with `FG s' = FG s`: `FG G g = FG X g = FG (f R g) = FG
/// g`, `FG (f W g) = FG (f | g)`, and `FG` distributes over `&`.
fn persistence_core(s: &Formula) -> Formula {
    match s {
        Formula::Globally(g) | Formula::Next(g) | Formula::Release(_, g) => persistence_core(g),
        Formula::WeakUntil(f, g) => formula::or(vec![(**f).clone(), (**g).clone()]),
        Formula::And(gs) => formula::and(gs.iter().map(persistence_core).collect()),
        other => other.clone(),
    }
}

/// The members of `items` whose bits are set in `bits`.
fn select(items: &[Formula], bits: u32) -> Vec<Formula> {
    items
        .iter()
        .enumerate()
        .filter(|(i, _)| (bits >> i) & 1 == 1)
        .map(|(_, f)| f.clone())
        .collect()
}

/// The distinct indices, in increasing order.
fn used(indices: impl Iterator<Item = usize>) -> Vec<usize> {
    let mut v: Vec<usize> = indices.collect();
    v.sort_unstable();
    v.dedup();
    v
}
