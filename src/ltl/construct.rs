//! The constructions of deterministic automata from NNF formulas:
//!
//! * [`weak`]: for obligation formulas, the automaton of `af`-classes with a
//!   verdict per strongly connected component, and [`weak_agrees`], which
//!   certifies it for formulas that are not syntactically obligations;
//! * [`guarded_globally`]: for `G (l | (chi W r))` with `chi` an obligation,
//!   the breakpoint automaton over copies of the weak automaton of `chi`;
//! * [`wait_then`]: for `G (l | G psi)`, a waiting state in front of an
//!   automaton of `G psi`;
//! * [`union`] and [`with_pending_monitor`]: for `G (l | (psi U (r | G
//!   theta)))`, the union of an automaton of `G (l | (psi U r))` with one of
//!   `(!m | psi) U G theta` read through the past monitor `m`;
//! * [`normalise_marks`] and [`merge_bisimilar`]: language-preserving
//!   simplifications of any of these automata before the state-based
//!   conversion;
//! * [`master`]: for every formula, the product of the `af`-tracker with the
//!   co-Büchi and Büchi monitors of the Master Theorem, with a transition-based
//!   generalised Rabin condition (one disjunct per guess `(X, Y)`).

use rustc_hash::FxHashMap;

use super::TranslateError;
use super::af::{self, Context, Kind};
use super::bdd::{FALSE, Node, TRUE};
use super::formula::{self, Formula};
use crate::automaton::emerson_lei::Edge;
use crate::automaton::{Letter, MarkSet};
use crate::graph::{self, Digraph};

/// One disjunct of a generalised Rabin condition: the transitions carrying a
/// mark of `fin` are taken finitely often and, for every mark of `inf`, the
/// transitions carrying it infinitely often.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Disjunct {
    pub(crate) fin: MarkSet,
    pub(crate) inf: Vec<u32>,
}

/// A deterministic complete automaton with transition-based generalised
/// Rabin acceptance: a run is accepted iff it satisfies some disjunct.
#[derive(Debug, Clone)]
pub(crate) struct Tgr {
    pub(crate) letters: usize,
    pub(crate) initial: usize,
    /// `edges[q * letters + a]`.
    pub(crate) edges: Vec<Edge>,
    pub(crate) num_marks: u32,
    pub(crate) disjuncts: Vec<Disjunct>,
}

impl Tgr {
    pub(crate) fn num_states(&self) -> usize {
        self.edges.len() / self.letters
    }
}

struct Successors<'a>(&'a Tgr);

impl Digraph for Successors<'_> {
    fn num_vertices(&self) -> usize {
        self.0.num_states()
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        self.0.edges[v * self.0.letters..(v + 1) * self.0.letters]
            .iter()
            .map(|e| e.target as usize)
    }
}

/// The largest number of product states built before giving up.
pub(crate) const MAX_STATES: usize = 200_000;

/// The time budget of a translation: a deadline for the current thread,
/// set by [`super::translate_within`] and checked by every exploration.
pub(crate) mod budget {
    use std::cell::Cell;
    use std::time::Instant;

    thread_local! {
        static DEADLINE: Cell<Option<Instant>> = const { Cell::new(None) };
        static SECONDS: Cell<f64> = const { Cell::new(f64::INFINITY) };
    }

    /// Sets the deadline (and the budget it came from) while alive;
    /// restores the previous ones on drop.
    pub(crate) struct Deadline(Option<Instant>, f64);

    impl Deadline {
        pub(crate) fn set(deadline: Option<Instant>, seconds: f64) -> Self {
            Self(
                DEADLINE.with(|d| d.replace(deadline)),
                SECONDS.with(|s| s.replace(seconds)),
            )
        }
    }

    impl Drop for Deadline {
        fn drop(&mut self) {
            DEADLINE.with(|d| d.set(self.0));
            SECONDS.with(|s| s.set(self.1));
        }
    }

    /// The current budget in words.
    pub(crate) fn describe() -> String {
        format!(
            "{} s, {} states and {} edges per automaton",
            SECONDS.with(|s| s.get()),
            super::MAX_STATES,
            crate::limits::MAX_AUTOMATON_EDGES
        )
    }

    /// Whether the current thread's deadline has passed.
    pub(crate) fn out_of_time() -> bool {
        DEADLINE
            .with(|d| d.get())
            .is_some_and(|deadline| Instant::now() > deadline)
    }
}

/// Explores the states reachable from `initial` under `step`, which gives the
/// successor and the marks of a state on a letter.
fn explore<S: Clone + Eq + std::hash::Hash>(
    initial: S,
    letters: usize,
    mut step: impl FnMut(&S, Letter) -> (S, MarkSet),
) -> Result<(Vec<S>, Vec<Edge>), TranslateError> {
    let mut index = FxHashMap::default();
    index.insert(initial.clone(), 0u32);
    let mut states = vec![initial];
    let mut edges = Vec::new();
    let mut next = 0;
    while next < states.len() {
        if budget::out_of_time() {
            return Err(TranslateError::OutOfTime);
        }
        if (states.len() as u128) * (letters as u128) > crate::limits::MAX_AUTOMATON_EDGES {
            return Err(TranslateError::TooLarge { limit: MAX_STATES });
        }
        let state = states[next].clone();
        for letter in 0..letters as Letter {
            let (target, marks) = step(&state, letter);
            let fresh = states.len() as u32;
            let target = *index.entry(target.clone()).or_insert_with(|| {
                states.push(target);
                fresh
            });
            edges.push(Edge { target, marks });
        }
        if states.len() > MAX_STATES {
            return Err(TranslateError::TooLarge { limit: MAX_STATES });
        }
        next += 1;
    }
    Ok((states, edges))
}

/// A shortest non-empty word leading from `from` back to `from` inside the
/// component `members` (`component[q] == comp`), if there is one.
fn cycle_word(tgr: &Tgr, from: usize, component: &[u32]) -> Option<Vec<Letter>> {
    let comp = component[from];
    let mut parent: FxHashMap<usize, (usize, Letter)> = FxHashMap::default();
    let mut queue = std::collections::VecDeque::from([from]);
    while let Some(q) = queue.pop_front() {
        for letter in 0..tgr.letters {
            let target = tgr.edges[q * tgr.letters + letter].target as usize;
            if component[target] != comp {
                continue;
            }
            if target == from {
                let mut word = vec![letter as Letter];
                let mut at = q;
                while at != from {
                    let (before, a) = parent[&at];
                    word.push(a);
                    at = before;
                }
                word.reverse();
                return Some(word);
            }
            if let std::collections::hash_map::Entry::Vacant(e) = parent.entry(target) {
                e.insert((q, letter as Letter));
                queue.push_back(target);
            }
        }
    }
    None
}

/// The weak automaton of an obligation formula: the states are the classes
/// `af(phi, u)`; a strongly connected component is accepting iff the word
/// `v^omega` of any cycle `v` through a state `psi` of it satisfies `psi`.
///
/// Correctness: the language of an obligation formula is recognised by a
/// weak deterministic automaton, and then all cycles through one component
/// of any deterministic automaton whose states determine the residual
/// language agree (Maler and Staiger 1997): so one cycle decides.
pub(crate) fn weak(
    context: &mut Context,
    formula: &Formula,
    letters: usize,
) -> Result<Tgr, TranslateError> {
    weak_with_classes(context, formula, letters).map(|(_, tgr)| tgr)
}

/// [`weak`] together with the class of every state.
fn weak_with_classes(
    context: &mut Context,
    formula: &Formula,
    letters: usize,
) -> Result<(Vec<Node>, Tgr), TranslateError> {
    let root = context.class(formula);
    let (states, edges) = explore(root, letters, |&q, a| (context.after(q, a), 0))?;
    let mut tgr = Tgr {
        letters,
        initial: 0,
        edges,
        num_marks: 1,
        disjuncts: vec![Disjunct {
            fin: 0,
            inf: vec![0],
        }],
    };
    let components = graph::strongly_connected_components(&Successors(&tgr));
    let mut verdict: Vec<Option<bool>> = vec![None; components.count];
    for (q, &class) in states.iter().enumerate() {
        let comp = components.component[q] as usize;
        if verdict[comp].is_none() {
            verdict[comp] = cycle_word(&tgr, q, &components.component)
                .map(|word| context.holds_on_cycle(class, &word));
        }
    }
    for q in 0..states.len() {
        if verdict[components.component[q] as usize] == Some(true) {
            for edge in &mut tgr.edges[q * letters..(q + 1) * letters] {
                edge.marks = 1;
            }
        }
    }
    Ok((states, tgr))
}

/// The deterministic Büchi automaton of `G (l | (chi W r))` for an
/// obligation formula `chi` and propositional formulas `l` and `r` (`G chi`
/// is the case `l = r = false`), by the breakpoint construction of Miyano
/// and Hayashi (1984) on the weak automaton `A` of `chi` ([`weak`]) read as
/// a universal automaton.
///
/// `chi` must hold at position `k` iff `m_k`, where `m_k = !r(w_k) &
/// (!l(w_k) | m_{k-1})` and `m_{-1} = false`: some position `j <= k` violates
/// `l` and `r` holds nowhere in `j..=k`. So the formula holds iff for every
/// `k` with `m_k` the run of `A` on `w_k w_{k+1} ...` ends in an accepting
/// component. A state is a triple `(m, S, O)`: the last `m`, the set `S` of
/// states of the runs started so far (runs that meet merge, runs that reach
/// `true` are dropped, one reaching `false` rejects for good), and the set
/// `O` of the runs still owed a visit to an accepting component since the
/// last breakpoint. On a letter `a`, `S' = delta(S + {chi if m'}, a)` and
/// `O' = delta(O, a)` minus the states of accepting components, where an
/// empty `O` is first refilled with `S + {chi if m'}`. States with `O` empty
/// are the breakpoints and carry the Büchi mark. By König's lemma a run of
/// the product passes infinitely many breakpoints iff no run of `A` stays in
/// non-accepting states forever; in a weak automaton that is iff every run
/// ends in an accepting component.
pub(crate) fn guarded_globally(
    context: &mut Context,
    l: &Formula,
    chi: &Formula,
    r: &Formula,
    letters: usize,
) -> Result<Tgr, TranslateError> {
    let (classes, inner) = weak_with_classes(context, chi, letters)?;
    let (l, r) = (context.class(l), context.class(r));
    let holds: Vec<(bool, bool)> = (0..letters as Letter)
        .map(|a| (context.after(l, a) == TRUE, context.after(r, a) == TRUE))
        .collect();
    let accepting = |q: u32| inner.edges[q as usize * letters].marks != 0;
    let is_class = |q: u32, class: Node| classes[q as usize] == class;
    let delta = |q: u32, a: Letter| inner.edges[q as usize * letters + a as usize].target;
    // The rejecting sink: a run of `A` reached `false`.
    let dead = (false, vec![u32::MAX], vec![u32::MAX]);
    type State = (bool, Vec<u32>, Vec<u32>);
    let (states, mut edges) = explore(
        (false, Vec::new(), Vec::new()),
        letters,
        |(m, s, o): &State, a| {
            if s.first() == Some(&u32::MAX) {
                return (dead.clone(), 0);
            }
            let (l_holds, r_holds) = holds[a as usize];
            let m = !r_holds && (!l_holds || *m);
            let spawned = m.then_some(0);
            let mut moved: Vec<u32> = s
                .iter()
                .copied()
                .chain(spawned)
                .map(|q| delta(q, a))
                .filter(|&q| !is_class(q, TRUE))
                .collect();
            if moved.iter().any(|&q| is_class(q, FALSE)) {
                return (dead.clone(), 0);
            }
            moved.sort_unstable();
            moved.dedup();
            let mut owed: Vec<u32> = if o.is_empty() {
                moved.clone()
            } else {
                o.iter().map(|&q| delta(q, a)).collect()
            };
            owed.retain(|&q| !accepting(q) && !is_class(q, TRUE));
            owed.sort_unstable();
            owed.dedup();
            ((m, moved, owed), 0)
        },
    )?;
    for (q, (_, _, o)) in states.iter().enumerate() {
        if o.is_empty() {
            for edge in &mut edges[q * letters..(q + 1) * letters] {
                edge.marks = 1;
            }
        }
    }
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks: 1,
        disjuncts: vec![Disjunct {
            fin: 0,
            inf: vec![0],
        }],
    })
}

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
    fn implies(&self, other: &Guess) -> bool {
        (other.safety.is_none() || other.safety == self.safety)
            && other.recurrent.iter().all(|m| self.recurrent.contains(m))
            && other.persistent.iter().all(|m| self.persistent.contains(m))
    }
}

/// The largest `|mu(phi)| + |nu(phi)|` for which all guesses are enumerated.
const MAX_GUESS_BITS: usize = 16;

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
    let mu = af::guess_candidates(formula, Kind::Mu);
    let nu = af::guess_candidates(formula, Kind::Nu);
    if mu.len() + nu.len() > MAX_GUESS_BITS {
        return Err(TranslateError::TooManyFixpoints {
            count: mu.len() + nu.len(),
            limit: MAX_GUESS_BITS,
        });
    }
    let root = context.class(formula);
    let mut safety_sets: Vec<Vec<Formula>> = Vec::new();
    let mut safety_initial: Vec<Node> = Vec::new();
    let mut recurrent: Vec<Node> = Vec::new();
    let mut persistent: Vec<Node> = Vec::new();
    let mut found: Vec<Found> = Vec::new();
    for x_bits in 0u32..1 << mu.len() {
        let x: Vec<Formula> = select(&mu, x_bits);
        let start = context.substitute(root, &|f| af::nu_under(f, &x));
        'guess: for y_bits in 0u32..1 << nu.len() {
            let y: Vec<Formula> = select(&nu, y_bits);
            let mut guess = Guess {
                safety: None,
                recurrent: Vec::new(),
                persistent: Vec::new(),
            };
            let mut infinitely_often = Vec::new();
            let mut almost_always = TRUE;
            for psi in &x {
                let c = af::mu_under(psi, &y);
                match context.class(&c) {
                    FALSE => continue 'guess,
                    TRUE => {}
                    class => guess.recurrent.push(index_of(&mut recurrent, class)),
                }
                infinitely_often.push(context.class(&recurrence_core(&c)));
            }
            for psi in &y {
                let s = af::nu_under(psi, &x);
                match context.class(&s) {
                    FALSE => continue 'guess,
                    TRUE => {}
                    class => guess.persistent.push(index_of(&mut persistent, class)),
                }
                let core = context.class(&persistence_core(&s));
                almost_always = context.bdd.and(almost_always, core);
            }
            if start != TRUE {
                let i = index_of(&mut safety_sets, x.clone());
                if i == safety_initial.len() {
                    safety_initial.push(start);
                }
                guess.safety = Some(i);
            }
            guess.recurrent.sort_unstable();
            guess.recurrent.dedup();
            guess.persistent.sort_unstable();
            guess.persistent.dedup();
            found.push(Found {
                x_bits,
                y_bits,
                infinitely_often,
                almost_always,
                guess,
            });
        }
    }
    let dominated: Vec<bool> = (0..found.len())
        .map(|i| {
            (0..found.len()).any(|j| j != i && dominates(context, &mu, &nu, &found[j], &found[i]))
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
    let strongest: Vec<Guess> = guesses
        .iter()
        .filter(|g| !guesses.iter().any(|h| h != *g && g.implies(h)))
        .cloned()
        .collect();
    // Keep only the monitors some remaining guess needs, numbered densely.
    let used_safety: Vec<usize> = used(strongest.iter().filter_map(|g| g.safety));
    let used_recurrent = used(strongest.iter().flat_map(|g| g.recurrent.iter().copied()));
    let used_persistent = used(strongest.iter().flat_map(|g| g.persistent.iter().copied()));
    let num_marks = used_safety.len() + used_recurrent.len() + used_persistent.len();
    if num_marks > MarkSet::BITS as usize {
        return Err(TranslateError::TooManyMarks {
            count: num_marks,
            limit: MarkSet::BITS as usize,
        });
    }
    let safety_mark = |i: usize| used_safety.iter().position(|&j| j == i).unwrap_or(0) as u32;
    let recurrent_mark = |i: usize| {
        (used_safety.len() + used_recurrent.iter().position(|&j| j == i).unwrap_or(0)) as u32
    };
    let persistent_mark = |i: usize| {
        (used_safety.len()
            + used_recurrent.len()
            + used_persistent.iter().position(|&j| j == i).unwrap_or(0)) as u32
    };
    let disjuncts: Vec<Disjunct> = strongest
        .iter()
        .map(|g| Disjunct {
            fin: g
                .safety
                .iter()
                .map(|&i| safety_mark(i))
                .chain(g.persistent.iter().map(|&i| persistent_mark(i)))
                .fold(0, |m, bit| m | (1 << bit)),
            inf: g.recurrent.iter().map(|&i| recurrent_mark(i)).collect(),
        })
        .collect();
    let fin_all: MarkSet = disjuncts.iter().fold(0, |m, d| m | d.fin);
    let inf_all: MarkSet = disjuncts
        .iter()
        .flat_map(|d| d.inf.iter())
        .fold(0, |m, &bit| m | (1 << bit));

    let safety_x: Vec<Vec<Formula>> = used_safety
        .iter()
        .map(|&i| safety_sets[i].clone())
        .collect();
    let mut initial = vec![root];
    initial.extend(used_safety.iter().map(|&i| safety_initial[i]));
    initial.extend(used_recurrent.iter().map(|&i| recurrent[i]));
    initial.extend(used_persistent.iter().map(|&i| persistent[i]));
    let (ns, nr) = (used_safety.len(), used_recurrent.len());
    let goals: Vec<Node> = initial.clone();
    let mut restart_memo: FxHashMap<(Node, usize), Node> = FxHashMap::default();
    let (_, edges) = explore(initial, letters, |state: &Vec<Node>, letter| {
        let main = context.after(state[0], letter);
        if main == FALSE {
            return (vec![FALSE; state.len()], fin_all);
        }
        if main == TRUE {
            return (vec![TRUE; state.len()], inf_all);
        }
        let mut next = Vec::with_capacity(state.len());
        next.push(main);
        let mut marks: MarkSet = 0;
        for (k, &s) in state.iter().enumerate().skip(1) {
            let moved = context.after(s, letter);
            let (value, marked) = if k <= ns {
                if moved == FALSE {
                    let x = &safety_x[k - 1];
                    let restarted = *restart_memo
                        .entry((main, k - 1))
                        .or_insert_with(|| context.substitute(main, &|f| af::nu_under(f, x)));
                    (restarted, true)
                } else {
                    (moved, false)
                }
            } else if k <= ns + nr {
                if moved == TRUE {
                    (goals[k], true)
                } else {
                    (context.bdd.or(moved, goals[k]), false)
                }
            } else if moved == FALSE {
                (goals[k], true)
            } else {
                (context.bdd.and(moved, goals[k]), false)
            };
            next.push(value);
            if marked {
                marks |= 1 << (k - 1);
            }
        }
        (next, marks)
    })?;
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks: num_marks as u32,
        disjuncts,
    })
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

fn select(items: &[Formula], bits: u32) -> Vec<Formula> {
    items
        .iter()
        .enumerate()
        .filter(|(i, _)| (bits >> i) & 1 == 1)
        .map(|(_, f)| f.clone())
        .collect()
}

fn used(indices: impl Iterator<Item = usize>) -> Vec<usize> {
    let mut v: Vec<usize> = indices.collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// Whether some word is accepted by `other` while the run of the weak
/// automaton `weak` on it ends in a component with the given verdict
/// (accepting or not).
///
/// The product of the two deterministic automata is explored; the answer is
/// yes iff for some disjunct `Fin(L) & Inf(K_1) & ... & Inf(K_m)` of `other`
/// a strongly connected part of the product, restricted to states whose weak
/// component has the verdict and to transitions outside `L`, has internal
/// transitions in every `K_j` (then a cycle through all of them is the loop
/// of an accepted lasso, and conversely).
fn meets(weak: &Tgr, verdict: bool, other: &Tgr) -> Result<bool, TranslateError> {
    let letters = weak.letters;
    let (states, edges) = explore(
        (weak.initial as u32, other.initial as u32),
        letters,
        |&(w, o), a| {
            let we = weak.edges[w as usize * letters + a as usize];
            let oe = other.edges[o as usize * letters + a as usize];
            ((we.target, oe.target), oe.marks)
        },
    )?;
    let good: Vec<bool> = states
        .iter()
        .map(|&(w, _)| (weak.edges[w as usize * letters].marks != 0) == verdict)
        .collect();
    for d in &other.disjuncts {
        let allowed =
            |s: usize, e: &Edge| good[s] && good[e.target as usize] && e.marks & d.fin == 0;
        let mut offsets = vec![0];
        let mut targets = Vec::new();
        for s in 0..states.len() {
            targets.extend(
                edges[s * letters..(s + 1) * letters]
                    .iter()
                    .filter(|e| allowed(s, e))
                    .map(|e| e.target),
            );
            offsets.push(targets.len());
        }
        let components = graph::strongly_connected_components(&graph::CsrGraph {
            offsets: &offsets,
            targets: &targets,
        });
        let mut cyclic = vec![false; components.count];
        let mut seen: Vec<MarkSet> = vec![0; components.count];
        for s in 0..states.len() {
            let c = components.component[s] as usize;
            for e in &edges[s * letters..(s + 1) * letters] {
                if allowed(s, e) && components.component[e.target as usize] as usize == c {
                    cyclic[c] = true;
                    seen[c] |= e.marks;
                }
            }
        }
        if (0..components.count)
            .any(|c| cyclic[c] && d.inf.iter().all(|&m| (seen[c] >> m) & 1 == 1))
        {
            return Ok(true);
        }
    }
    Ok(false)
}

/// Whether the weak automaton `weak` accepts exactly the words that
/// `positive` accepts, given an automaton `negative` for the complement.
///
/// This certifies the weak automaton of a formula that is an obligation
/// property without being syntactically one: it must accept no word of the
/// negation and reject no word of the formula.
pub(crate) fn weak_agrees(weak: &Tgr, positive: &Tgr, negative: &Tgr) -> bool {
    matches!(meets(weak, true, negative), Ok(false))
        && matches!(meets(weak, false, positive), Ok(false))
}

/// The automaton of `G (l | G psi)` for a propositional formula `l`, from an
/// automaton `then` of `G psi`.
///
/// `G (l | G psi)` holds iff `l` holds forever or, at the first position
/// where `l` fails, `G psi` holds (then `G psi` holds at every later position
/// too). The automaton waits in a new state while `l` holds, marking its
/// loop with a new mark that a new disjunct `Inf` accepts, and on the first
/// letter violating `l` moves as `then` does from its initial state. That
/// transition is taken at most once, so it carries the waiting mark too
/// (then all transitions of the waiting state carry the same marks).
pub(crate) fn wait_then(context: &mut Context, l: &Formula, then: &Tgr) -> Tgr {
    let letters = then.letters;
    let class = context.class(l);
    let wait_mark = then.num_marks;
    let shifted = |e: &Edge| Edge {
        target: e.target + 1,
        marks: e.marks,
    };
    let mut edges: Vec<Edge> = (0..letters as Letter)
        .map(|a| {
            let target = if context.after(class, a) == TRUE {
                0
            } else {
                then.edges[then.initial * letters + a as usize].target + 1
            };
            Edge {
                target,
                marks: 1 << wait_mark,
            }
        })
        .collect();
    edges.extend(then.edges.iter().map(shifted));
    let mut disjuncts = then.disjuncts.clone();
    disjuncts.push(Disjunct {
        fin: 0,
        inf: vec![wait_mark],
    });
    Tgr {
        letters,
        initial: 0,
        edges,
        num_marks: wait_mark + 1,
        disjuncts,
    }
}

/// The number of marks of the product of `first` and `second` (theirs
/// added up), or an error when a [`MarkSet`] cannot hold them.
fn marks_of_product(first: &Tgr, second: &Tgr) -> Result<u32, TranslateError> {
    let num_marks = first.num_marks + second.num_marks;
    if num_marks > MarkSet::BITS {
        return Err(TranslateError::TooManyMarks {
            count: num_marks as usize,
            limit: MarkSet::BITS as usize,
        });
    }
    Ok(num_marks)
}

/// The edges of the synchronous product of `first` and `second` from their
/// initial states: each edge carries `first`'s marks followed by `second`'s,
/// shifted past `first`'s.
fn product_edges(first: &Tgr, second: &Tgr) -> Result<Vec<Edge>, TranslateError> {
    let (letters, shift) = (first.letters, first.num_marks);
    let shifted = |marks: MarkSet| marks.checked_shl(shift).unwrap_or(0);
    let (_, edges) = explore(
        (first.initial as u32, second.initial as u32),
        letters,
        |&(p, q), a| {
            let e = first.edges[p as usize * letters + a as usize];
            let f = second.edges[q as usize * letters + a as usize];
            ((e.target, f.target), e.marks | shifted(f.marks))
        },
    )?;
    Ok(edges)
}

/// The union of two automata over the same letters: their product, whose
/// marks are those of `first` followed by those of `second` (shifted past
/// `first`'s), accepting a run iff some disjunct of either automaton holds on
/// its component. It accepts exactly the words one of them accepts.
pub(crate) fn union(first: &Tgr, second: &Tgr) -> Result<Tgr, TranslateError> {
    let (letters, shift, num_marks) = (
        first.letters,
        first.num_marks,
        marks_of_product(first, second)?,
    );
    let edges = product_edges(first, second)?;
    let shifted = |marks: MarkSet| marks.checked_shl(shift).unwrap_or(0);
    let disjuncts = first
        .disjuncts
        .iter()
        .cloned()
        .chain(second.disjuncts.iter().map(|d| Disjunct {
            fin: shifted(d.fin),
            inf: d.inf.iter().map(|&m| m + shift).collect(),
        }))
        .collect();
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks,
        disjuncts,
    })
}

/// Removes every disjunct that another one subsumes (its `Fin` marks and
/// its `Inf` marks include the other's: every run it accepts, the other
/// accepts too), and duplicates: the condition accepts the same runs.
pub(crate) fn drop_subsumed_disjuncts(disjuncts: &mut Vec<Disjunct>) {
    for d in disjuncts.iter_mut() {
        d.inf.sort_unstable();
        d.inf.dedup();
    }
    disjuncts.sort();
    disjuncts.dedup();
    let subsumes = |weaker: &Disjunct, stronger: &Disjunct| {
        weaker.fin & !stronger.fin == 0 && weaker.inf.iter().all(|m| stronger.inf.contains(m))
    };
    let kept: Vec<Disjunct> = disjuncts
        .iter()
        .enumerate()
        .filter(|&(i, d)| {
            !disjuncts
                .iter()
                .enumerate()
                .any(|(j, other)| j != i && subsumes(other, d))
        })
        .map(|(_, d)| d.clone())
        .collect();
    *disjuncts = kept;
}

/// The largest number of disjuncts an [`intersection`] may have.
pub(crate) const MAX_PRODUCT_DISJUNCTS: usize = 4096;

/// The product of two automata over the same letters accepting the words
/// both accept: a run satisfies the disjunct pair `(d1, d2)` iff it avoids
/// the `Fin` marks of both and visits every `Inf` mark of both infinitely
/// often, so the condition is the disjunction over all pairs (a generalised
/// Rabin condition again; for conjunctions of `GF`, `FG` and `G (a -> F b)`
/// terms the states multiply, the marks add up and no guess is enumerated).
pub(crate) fn intersection(first: &Tgr, second: &Tgr) -> Result<Tgr, TranslateError> {
    let (letters, shift, num_marks) = (
        first.letters,
        first.num_marks,
        marks_of_product(first, second)?,
    );
    let count = first.disjuncts.len() * second.disjuncts.len();
    if count > MAX_PRODUCT_DISJUNCTS {
        return Err(TranslateError::TooLarge { limit: MAX_STATES });
    }
    let edges = product_edges(first, second)?;
    let shifted = |marks: MarkSet| marks.checked_shl(shift).unwrap_or(0);
    let mut disjuncts = Vec::with_capacity(count);
    for d in &first.disjuncts {
        for e in &second.disjuncts {
            let mut inf = d.inf.clone();
            inf.extend(e.inf.iter().map(|&m| m + shift));
            disjuncts.push(Disjunct {
                fin: d.fin | shifted(e.fin),
                inf,
            });
        }
    }
    drop_subsumed_disjuncts(&mut disjuncts);
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks,
        disjuncts,
    })
}

/// The automaton over `2^AP` accepting the words `w` whose extension `w^m`
/// is accepted by `inner`, an automaton over `2^(AP + {m})` that reads the
/// fresh proposition `m` as the highest letter bit; `w^m` adds `m` at every
/// position `k` with `m_k = !r(w_k) & (!l(w_k) | m_{k-1})`, `m_{-1} = false`,
/// for the propositional formulas `l` and `r` (classes of `context`, whose
/// letters are those over `AP`).
///
/// `m_k` holds iff some position `j <= k` violates `l` and `r` holds
/// nowhere in `j..=k`. The states are pairs of a state of `inner` and
/// `m_{k-1}`; every transition is the one `inner` takes on `w_k` plus `m_k`.
pub(crate) fn with_pending_monitor(
    context: &mut Context,
    l: &Formula,
    r: &Formula,
    inner: &Tgr,
) -> Result<Tgr, TranslateError> {
    let letters = inner.letters / 2;
    let (l, r) = (context.class(l), context.class(r));
    let pending: Vec<bool> = (0..letters as Letter)
        .map(|a| context.after(r, a) != TRUE && context.after(l, a) != TRUE)
        .collect();
    let kept: Vec<bool> = (0..letters as Letter)
        .map(|a| context.after(r, a) != TRUE)
        .collect();
    let (_, edges) = explore((inner.initial as u32, false), letters, |&(q, m), a| {
        let m = pending[a as usize] || (m && kept[a as usize]);
        let extended = a as usize | (usize::from(m) * letters);
        let e = inner.edges[q as usize * inner.letters + extended];
        ((e.target, m), e.marks)
    })?;
    Ok(Tgr {
        letters,
        initial: 0,
        edges,
        num_marks: inner.num_marks,
        disjuncts: inner.disjuncts.clone(),
    })
}

/// `tgr` with bisimilar states merged: the coarsest partition in which two
/// states of a class have, on every letter, the same marks and targets in
/// the same class. Corresponding runs of the two automata see the same
/// marks, so they accept the same words.
pub(crate) fn merge_bisimilar(tgr: &Tgr) -> Tgr {
    let (n, letters) = (tgr.num_states(), tgr.letters);
    let mut class: Vec<u32> = vec![0; n];
    let mut count = 1;
    loop {
        let mut ids: FxHashMap<Vec<(u32, MarkSet)>, u32> = FxHashMap::default();
        let next: Vec<u32> = (0..n)
            .map(|q| {
                let signature: Vec<(u32, MarkSet)> = std::iter::once((class[q], 0))
                    .chain(
                        tgr.edges[q * letters..(q + 1) * letters]
                            .iter()
                            .map(|e| (class[e.target as usize], e.marks)),
                    )
                    .collect();
                let fresh = ids.len() as u32;
                *ids.entry(signature).or_insert(fresh)
            })
            .collect();
        class = next;
        if ids.len() == count {
            break;
        }
        count = ids.len();
    }
    let mut edges = vec![
        Edge {
            target: 0,
            marks: 0
        };
        count * letters
    ];
    for q in 0..n {
        let c = class[q] as usize;
        for (a, e) in tgr.edges[q * letters..(q + 1) * letters].iter().enumerate() {
            edges[c * letters + a] = Edge {
                target: class[e.target as usize],
                marks: e.marks,
            };
        }
    }
    Tgr {
        letters,
        initial: class[tgr.initial] as usize,
        edges,
        num_marks: tgr.num_marks,
        disjuncts: tgr.disjuncts.clone(),
    }
}

/// `tgr` with marks changed where they cannot affect acceptance, so that
/// more states have the same marks on all outgoing transitions:
///
/// * a transition between two strongly connected components is taken at
///   most once by a run, so it gets the marks shared by all transitions of
///   its source inside the source's component, if they share them (no
///   marks if there are none);
/// * an `Inf` mark that no disjunct uses in a `Fin` set is cleared on the
///   transitions of a state `q` if every disjunct using it has a `Fin` mark
///   on every transition of `q` inside its component: a run that takes
///   those transitions infinitely often satisfies none of these disjuncts
///   anyway, and one that takes them finitely often does not depend on them.
pub(crate) fn normalise_marks(tgr: &Tgr) -> Tgr {
    let (n, letters) = (tgr.num_states(), tgr.letters);
    let components = graph::strongly_connected_components(&Successors(tgr));
    let inside =
        |q: usize, e: &Edge| components.component[e.target as usize] == components.component[q];
    let fin_all: MarkSet = tgr.disjuncts.iter().fold(0, |m, d| m | d.fin);
    let mut edges = tgr.edges.clone();
    for q in 0..n {
        let out = &mut edges[q * letters..(q + 1) * letters];
        let mut cleared: MarkSet = 0;
        for m in 0..tgr.num_marks {
            if (fin_all >> m) & 1 == 1 {
                continue;
            }
            let mut users = tgr
                .disjuncts
                .iter()
                .filter(|d| d.inf.contains(&m))
                .peekable();
            if users.peek().is_some()
                && users.all(|d| {
                    out.iter()
                        .filter(|e| inside(q, e))
                        .all(|e| e.marks & d.fin != 0)
                })
            {
                cleared |= 1 << m;
            }
        }
        for e in out.iter_mut() {
            e.marks &= !cleared;
        }
        let mut shared = out.iter().filter(|e| inside(q, e)).map(|e| e.marks);
        let first = shared.next().unwrap_or(0);
        if shared.all(|m| m == first) {
            for e in out.iter_mut() {
                e.marks = first;
            }
        }
    }
    Tgr {
        letters,
        initial: tgr.initial,
        edges,
        num_marks: tgr.num_marks,
        disjuncts: tgr.disjuncts.clone(),
    }
}
