//! Local search over the supports of the defender on the certified lower bound
//! (method.md section 6, "Local search on the supports").
//!
//! The certified lower bound is not continuous where a choice leaves the
//! support: on an objective that must hold forever (a safety objective,
//! PAYNT's `Pmin=? [F "goal"]`), a choice kept at probability `exp(-2c)`
//! is taken infinitely often, and the all-seeing adversary makes it fatal,
//! while the controller without it may be safe. Softmax controllers cannot
//! reach that boundary, and their rounding reaches only the nearest
//! deterministic controller. This search starts at the best candidate and
//! changes one block `(g, o)` at a time, dropping a choice or playing one
//! enabled `(next node, action)` pair, keeping every change that raises the
//! certified lower bound (first improvement). The moves with the largest
//! first-order gains by the bound's gradient are tried first (guided
//! steps), the sweeps over every move only where those fail (passing over,
//! unsolved, the moves in blocks the adversary's best response does not
//! meet and the moves the analysis of the current defender refutes, which
//! cannot raise the bound). Where a sweep
//! over all blocks changes nothing and a node is unused, it tries memory:
//! one choice is sent to a copy of its next node (a change of no value by
//! itself), and climbs go on from there. It stops when neither raises the
//! bound, or when its effort is spent. Restarts from seeded random
//! memoryless defenders run in parallel rounds, more of them where climbs
//! end early; then kicks (iterated local search) climb from the best end
//! point with a few of its blocks redrawn. The search is reproducible for
//! a seed unless a deadline cuts it.

use std::cell::{Cell, OnceCell, RefCell};
use std::collections::HashMap;
use std::hash::{DefaultHasher, Hasher};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::automaton::Dra;
use crate::certify::gradient::LowerBoundGradients;
use crate::certify::refutation::Refuter;
use crate::certify::{
    Analysis, CertifyError, lower_value_or_trivial_within, product_states, ranked_lower_bound,
};
use crate::controller::{Choice, Fsc, Role, Support};
use crate::game::{AdversaryAction, DefenderAction, Posg};
use crate::optimise::{Cancel, Certifier};
use crate::solver::SolverSettings;

/// A move counts as an improvement only when the bound rises by more
/// than this (bounds are accurate to the solver's tolerance, 1e-9).
const IMPROVEMENT: f64 = 1e-8;

/// A defender where a climb ended, with its lower bound `L`.
#[derive(Debug, Clone)]
pub struct Climbed {
    /// The defender.
    pub defender: Fsc,
    /// Its lower bound `L`: as the climbs rank it inside the search
    /// ([`Landscape::bound`]); certified, without the exact rational solve
    /// (the trivial 0 where that is needed), where [`climb_with_restarts`]
    /// returns it.
    pub bound: f64,
}

/// How long the search goes on: each climb until its bound evaluations
/// have counted products of `work` states in all (at least one evaluation
/// beyond the start's; a move passed over counts as evaluated), every
/// climb until `deadline` (with a time budget) or until `cancel` is set,
/// and the rounds of restarts and kicks until a climb reaches `enough`.
#[derive(Debug, Clone, Copy)]
pub struct Effort<'c> {
    /// The product states (reachable, summed over evaluations) one climb
    /// may count.
    pub work: usize,
    /// When every climb ends, whatever it has evaluated.
    pub deadline: Option<Instant>,
    /// A bound that ends the restarts and the kicks: no defender certifies
    /// more than an upper bound, so one within the gap tolerance of it is
    /// enough (`f64::INFINITY`: none known).
    pub enough: f64,
    /// The run's cancellation (Ctrl-C, a callback): every climb ends at
    /// once when it is set, as at the deadline.
    pub cancel: Option<&'c Cancel>,
}

impl Effort<'_> {
    /// Whether the deadline (if any) has passed or the run was cancelled.
    fn past_deadline(&self) -> bool {
        self.deadline.is_some_and(|end| Instant::now() >= end)
            || self.cancel.is_some_and(Cancel::is_cancelled)
    }
}

/// A defender's ranked bound ([`Landscape::bound`]), the states of its
/// product, and the blocks its adversary's best response meets (every
/// block where the product mixes too slowly to say).
#[derive(Debug, Clone)]
struct Judged {
    /// The ranked bound.
    bound: f64,
    /// The reachable states of the product (the work of judging it).
    states: usize,
    /// Per block, whether the adversary's best response meets it.
    met: Arc<[bool]>,
}

/// The defenders the climbs of the searches sharing a [`SearchMemo`] have
/// judged ([`Landscape::judge`]), the product sizes of those they passed
/// over ([`Landscape::pass_over`]), and where their climbs ended, shared
/// by the climbs that run in parallel.
/// The climbs come back to defenders judged before: a kick that climbs
/// back to the end point it left sweeps that point's moves again, and a
/// move that overrides a split's redirected choice gives a defender one
/// move from the split's origin. With 2 nodes, 97% of the evaluations
/// were repeats on PAYNT's dice-and-coin, 29% on grid-walls, 12% on
/// attacker-one-defender (stop 45, every move judged).
#[derive(Default)]
struct Evaluations {
    /// The defenders judged.
    known: Mutex<HashMap<EvaluationKey, Judged>>,
    /// The product states of the defenders passed over and not judged.
    sizes: Mutex<HashMap<EvaluationKey, usize>>,
    /// Where each climb ([`climb`]) ended and the work it spent, by its
    /// start (every block, [`EvaluationKey::whole`]) and its effort's
    /// work: the structures of a run draw the same random starts and,
    /// from the same best end point, the same kicks, and a climb from a
    /// start already climbed would only go the same way again (its
    /// evaluations found in the memo, its gradients and refutations not).
    climbs: Mutex<HashMap<(EvaluationKey, usize), (Climbed, usize)>>,
}

impl Evaluations {
    /// What was recorded for `key`, if it was judged.
    fn get(&self, key: &EvaluationKey) -> Option<Judged> {
        lock(&self.known).get(key).cloned()
    }

    /// Records what `key` was judged (two climbs may judge the same key at
    /// once: they find the same numbers).
    fn insert(&self, key: EvaluationKey, judged: Judged) {
        let bits = judged.bound.to_bits();
        let before = lock(&self.known).insert(key, judged);
        debug_assert!(before.is_none_or(|b| b.bound.to_bits() == bits));
    }

    /// The states of `key`'s product, where it was judged or passed over.
    fn states(&self, key: &EvaluationKey) -> Option<usize> {
        let judged = lock(&self.known).get(key).map(|judged| judged.states);
        judged.or_else(|| lock(&self.sizes).get(key).copied())
    }

    /// Records the states of a passed-over defender's product.
    fn insert_states(&self, key: EvaluationKey, states: usize) {
        lock(&self.sizes).insert(key, states);
    }

    /// Where the climb from `start` with `work` ended, if one did.
    fn climbed(&self, start: &(EvaluationKey, usize)) -> Option<(Climbed, usize)> {
        lock(&self.climbs).get(start).cloned()
    }

    /// Records where the climb from `start` with `work` ended.
    fn insert_climb(&self, start: (EvaluationKey, usize), end: (Climbed, usize)) {
        lock(&self.climbs).insert(start, end);
    }
}

/// What the local searches on one game and automaton have evaluated
/// ([`climb_with_restarts`]): the structures of one run share it, so that
/// a defender one search judged costs another no solve, and a climb one
/// made from a start costs another nothing (the searches' universe,
/// every enabled pair of the game's defender, is the same for every
/// structure with the same number of nodes). Sharing changes no search:
/// a defender found in it is charged as where it is solved (up to the
/// corner cases of [`sweep`]: whether a move is passed over or judged
/// then depends on what the other searches judged first, and the two
/// differ where a judgment fails to solve or crosses [`IMPROVEMENT`] by
/// numerical error alone).
#[derive(Default, Clone)]
pub struct SearchMemo(Arc<Evaluations>);

/// One of the maps of [`Evaluations`], locked, whether or not a climb
/// panicked while holding it (its entries are complete: each is inserted
/// whole).
fn lock<T>(map: &Mutex<T>) -> MutexGuard<'_, T> {
    map.lock().unwrap_or_else(PoisonError::into_inner)
}

/// What determines a defender's bound among the defenders of the searches
/// sharing a [`SearchMemo`] (on one game and automaton): its number of
/// nodes, its initial distribution (the probabilities' bits) and its
/// blocks in use ([`DefenderSteps::blocks_in_use`]), each as its index, its number of
/// choices and its choices (next node, action, the probability's bits).
/// Blocks out of use are never played, so defenders that differ only
/// there have the same product.
///
/// The key is a 128-bit digest of that sequence of words (two SipHash-1-3
/// hashes of it under different prefixes), not the words themselves: on a
/// 96x96 grid one defender's words take megabytes, and the memo of a run
/// held hundreds of them (about 180 MB at its peak). Two different
/// defenders share a digest with probability about `n^2 / 2^129` for `n`
/// keys; even then only the search's path changes, never a reported
/// number: a structure scores the defender it returns again from the
/// defender itself (its final candidates' certified lower bounds).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct EvaluationKey([u64; 2]);

impl EvaluationKey {
    /// The key of `defender` in the game of `steps`.
    fn of(steps: &DefenderSteps<'_>, defender: &Fsc) -> Self {
        Self::with_blocks(defender, &steps.blocks_in_use(defender))
    }

    /// The key of `defender` with every block, in use or not: what a climb
    /// from it does depends on the blocks its moves bring into use.
    fn whole(defender: &Fsc) -> Self {
        Self::with_blocks(defender, &vec![true; defender.blocks.len()])
    }

    /// The key of `defender` with the blocks `b` where `blocks[b]`.
    fn with_blocks(defender: &Fsc, blocks: &[bool]) -> Self {
        let mut digest = KeyDigest::new();
        digest.word(defender.num_nodes() as u64);
        for p in defender.initial() {
            digest.word(p.to_bits());
        }
        for (b, block) in defender
            .blocks
            .iter()
            .enumerate()
            .filter(|&(b, _)| blocks[b])
        {
            digest.word(b as u64);
            digest.word(block.len() as u64);
            for choice in block {
                digest.word(((choice.next as u64) << 32) | choice.action as u64);
                digest.word(choice.probability.to_bits());
            }
        }
        digest.finish()
    }
}

/// Two SipHash-1-3 states (the standard library's fixed-key hasher) fed
/// the same words after different one-word prefixes: together a 128-bit
/// digest of the words ([`EvaluationKey`]).
struct KeyDigest([DefaultHasher; 2]);

impl KeyDigest {
    /// The digest of no words yet.
    fn new() -> Self {
        Self([0_u64, 1].map(|prefix| {
            let mut hasher = DefaultHasher::new();
            hasher.write_u64(prefix);
            hasher
        }))
    }

    /// Feeds one word.
    fn word(&mut self, word: u64) {
        for hasher in &mut self.0 {
            hasher.write_u64(word);
        }
    }

    /// The key of the words fed.
    fn finish(&self) -> EvaluationKey {
        EvaluationKey(self.0.each_ref().map(Hasher::finish))
    }
}

/// What the climbs of one search share: the game, the automaton of
/// `!phi`, every enabled `(next node, action)` pair of each block (as
/// blocks, `universe`, and as a support), each climb's effort, and the
/// bounds evaluated so far.
struct Search<'a> {
    game: &'a Posg,
    /// The game's defender steps, for the blocks in use of the defenders
    /// the search keys.
    steps: DefenderSteps<'a>,
    not_phi: &'a Dra,
    /// The run's linear solver, which the search's rankings and proofs
    /// refine ([`ranking_settings`], [`proving_settings`]).
    solver: SolverSettings,
    universe: &'a Fsc,
    support: Support,
    effort: Effort<'a>,
    known: Arc<Evaluations>,
    /// Whether the sweeps pass over the moves the adversary's best
    /// response does not meet ([`sweep`]); off only where a test judges
    /// every move to compare.
    pass_over_unmet: bool,
    /// Whether the sweeps pass over the moves a [`Refuter`] refutes
    /// ([`sweep`]); off only where a test judges every move to compare.
    pass_over_refuted: bool,
}

impl<'a> Search<'a> {
    /// The search over the defenders whose blocks play `universe`'s
    /// pairs, each climb with `effort`, nothing evaluated yet.
    #[cfg(test)]
    fn new(game: &'a Posg, not_phi: &'a Dra, universe: &'a Fsc, effort: Effort<'a>) -> Self {
        let solver = SolverSettings::default();
        Self::sharing(
            (game, not_phi, solver),
            universe,
            effort,
            &SearchMemo::default(),
        )
    }

    /// The search over the defenders whose blocks play `universe`'s pairs,
    /// each climb with `effort`, knowing what the searches sharing `memo`
    /// evaluated, its bounds solved by `solver`.
    fn sharing(
        (game, not_phi, solver): (&'a Posg, &'a Dra, SolverSettings),
        universe: &'a Fsc,
        effort: Effort<'a>,
        memo: &SearchMemo,
    ) -> Self {
        Self {
            game,
            steps: DefenderSteps::new(game),
            not_phi,
            solver,
            universe,
            support: Support::of(universe),
            effort,
            known: Arc::clone(&memo.0),
            pass_over_unmet: true,
            pass_over_refuted: true,
        }
    }

    /// The enabled pairs of block `b`.
    fn pairs(&self, b: usize) -> &[Choice] {
        &self.universe.blocks[b]
    }
}

/// One climb of a [`Search`]: the bounds it has evaluated so far and the
/// product states they solved.
struct Landscape<'a> {
    search: &'a Search<'a>,
    evaluated: Cell<usize>,
    spent: Cell<usize>,
    /// The analysis of the defender the climb solved last, with its key:
    /// after an improving move, the new current defender's, from which
    /// its [`Refuter`] starts without solving it again.
    last_solved: RefCell<Option<(EvaluationKey, Analysis)>>,
}

impl<'a> Landscape<'a> {
    /// A climb of `search` that has evaluated nothing yet.
    fn new(search: &'a Search<'a>) -> Self {
        Self {
            search,
            evaluated: Cell::new(0),
            spent: Cell::new(0),
            last_solved: RefCell::new(None),
        }
    }

    /// Whether the climb has spent its effort.
    fn exhausted(&self) -> bool {
        let effort = &self.search.effort;
        (self.evaluated.get() >= 2 && self.spent.get() >= effort.work) || effort.past_deadline()
    }

    /// The lower bound of `defender` as the climb ranks it: the value of
    /// the adversary's best response found by policy iteration, without
    /// the exact rational solve or the optimality certificate
    /// ([`ranking_settings`]; 0 where the product mixes too slowly). A
    /// defender the search has evaluated before ([`Evaluations`]) costs no
    /// solve, but counts its product's states as spent all the same, so
    /// that the climbs go as they would without the memo.
    fn bound(&self, defender: &Fsc) -> Result<f64, CertifyError> {
        self.bound_keyed(EvaluationKey::of(&self.search.steps, defender), defender)
    }

    /// [`Self::bound`] of `defender`, whose key is `key`.
    fn bound_keyed(&self, key: EvaluationKey, defender: &Fsc) -> Result<f64, CertifyError> {
        self.evaluated.set(self.evaluated.get() + 1);
        let judged = self.judge_keyed(key, defender)?;
        self.spent.set(self.spent.get() + judged.states);
        Ok(judged.bound)
    }

    /// What the search knows of `defender` ([`Judged`]), solved where it
    /// has not judged it before; not counted as the climb's work.
    fn judge(&self, defender: &Fsc) -> Result<Judged, CertifyError> {
        self.judge_keyed(EvaluationKey::of(&self.search.steps, defender), defender)
    }

    /// [`Self::judge`] of `defender`, whose key is `key`.
    fn judge_keyed(&self, key: EvaluationKey, defender: &Fsc) -> Result<Judged, CertifyError> {
        if let Some(known) = self.search.known.get(&key) {
            return Ok(known);
        }
        let judged = self.evaluate(&key, defender)?;
        self.search.known.insert(key, judged.clone());
        Ok(judged)
    }

    /// A [`Refuter`] of the moves of `defender`, where the search refutes
    /// moves and the product can be analysed (`None` where it cannot: its
    /// moves are judged, and a judgment reports a failure that is not
    /// numerical); not counted as the climb's work.
    fn refuter(&self, defender: &Fsc) -> Option<Refuter<'_>> {
        let Search {
            game,
            not_phi,
            solver,
            ..
        } = *self.search;
        if !self.search.pass_over_refuted {
            return None;
        }
        let key = EvaluationKey::of(&self.search.steps, defender);
        match self.last_solved.take() {
            Some((solved, analysis)) if solved == key => {
                Some(Refuter::from_analysis(game, not_phi, analysis))
            }
            _ => Refuter::new(game, not_phi, defender, &ranking_settings(&solver)).ok(),
        }
    }

    /// [`Self::judge`] solved: the ranked bound of `defender` with its
    /// product's states and the blocks the adversary's best response meets
    /// ([`ranked_lower_bound`]); a product that could not be proved
    /// counts as large as the game, with every block met.
    fn evaluate(&self, key: &EvaluationKey, defender: &Fsc) -> Result<Judged, CertifyError> {
        let Search {
            game,
            not_phi,
            solver,
            ..
        } = *self.search;
        match ranked_lower_bound(game, not_phi, defender, &ranking_settings(&solver)) {
            Ok(ranked) => {
                let judged = Judged {
                    bound: ranked.value,
                    states: ranked.analysis.states.len(),
                    met: ranked.blocks.into(),
                };
                let solved = (*key, ranked.analysis);
                self.last_solved.replace(Some(solved));
                Ok(judged)
            }
            Err(error) if error.is_numerical() => Ok(Judged {
                bound: 0.0,
                states: game.num_states(),
                met: vec![true; defender.blocks.len()].into(),
            }),
            Err(error) => Err(error),
        }
    }

    /// Counts `candidates` as judged by [`Self::first_improvement`] without
    /// solving them, each as the work of its product's states (built, not
    /// analysed, where the search has not met it before), until the
    /// effort is spent: for moves that cannot raise the bound, so that the
    /// climb spends its effort, and goes on, as where it judges them.
    fn pass_over(&self, candidates: impl Iterator<Item = Fsc>) -> Result<(), CertifyError> {
        for candidate in candidates {
            if self.exhausted() {
                return Ok(());
            }
            self.pass_over_one(
                EvaluationKey::of(&self.search.steps, &candidate),
                &candidate,
            )?;
        }
        Ok(())
    }

    /// Counts `candidate`, whose key is `key`, as judged without solving
    /// it ([`Self::pass_over`]).
    fn pass_over_one(&self, key: EvaluationKey, candidate: &Fsc) -> Result<(), CertifyError> {
        let Search { game, not_phi, .. } = *self.search;
        self.evaluated.set(self.evaluated.get() + 1);
        let states = match self.search.known.states(&key) {
            Some(states) => states,
            None => {
                let states = product_states(game, not_phi, candidate, Role::Defender)?;
                self.search.known.insert_states(key, states);
                states
            }
        };
        self.spent.set(self.spent.get() + states);
        Ok(())
    }

    /// The first-order gains of the moves of `current` (blocks in use
    /// only) by the lower bound's gradient over every enabled pair
    /// ([`LowerBoundGradients::at_over`]): `(gain, block, choices)` for
    /// each move whose gain is known and above [`IMPROVEMENT`], the
    /// largest first. Empty where the gradient cannot be computed (a
    /// product too stiff for it): the sweeps go on without it.
    fn promising_moves(
        &self,
        current: &Fsc,
    ) -> Result<Vec<(f64, usize, Vec<Choice>)>, CertifyError> {
        self.evaluated.set(self.evaluated.get() + 1);
        let search = self.search;
        let mut gradients = LowerBoundGradients::new(
            search.game,
            search.not_phi,
            ranking_settings(&search.solver),
        );
        let gradient = gradients.at_over(current, &search.support);
        self.spent
            .set(self.spent.get().saturating_add(gradients.work() as usize));
        let entries = match gradient {
            Ok(gradient) => gradient.entries,
            Err(error) if error.is_numerical() => return Ok(Vec::new()),
            Err(error) => return Err(error),
        };
        let in_use = search.steps.blocks_in_use(current);
        let mut moves = Vec::new();
        for b in (0..current.blocks.len()).filter(|&b| in_use[b]) {
            let rate = |choices: &[Choice]| block_rate(&search.support, &entries, b, choices);
            let now = rate(&current.blocks[b]);
            for choices in block_moves(&current.blocks[b], search.pairs(b)) {
                let gain = rate(&choices) - now;
                if gain > IMPROVEMENT {
                    moves.push((gain, b, choices));
                }
            }
        }
        moves.sort_by(|a, b| b.0.total_cmp(&a.0));
        Ok(moves)
    }

    /// The first of `candidates` that certifies more than `bound` by
    /// [`IMPROVEMENT`]; `None` when none does or the effort is spent. A
    /// candidate the search has not judged and `refuted` says cannot
    /// raise the bound is passed over ([`Self::pass_over`]).
    fn first_improvement(
        &self,
        candidates: impl Iterator<Item = Fsc>,
        bound: f64,
        refuted: impl Fn(&Fsc) -> bool,
    ) -> Result<Option<Climbed>, CertifyError> {
        for candidate in candidates {
            if self.exhausted() {
                return Ok(None);
            }
            let key = EvaluationKey::of(&self.search.steps, &candidate);
            if self.search.known.get(&key).is_none() && refuted(&candidate) {
                self.pass_over_one(key, &candidate)?;
                continue;
            }
            let value = self.bound_keyed(key, &candidate)?;
            if value > bound + IMPROVEMENT {
                return Ok(Some(Climbed {
                    defender: candidate,
                    bound: value,
                }));
            }
        }
        Ok(None)
    }
}

/// The solver settings of the climbs' evaluations: without the exact
/// rational solve and without the optimality certificate, since a climb
/// only ranks its candidates; the search's end point is proved with
/// [`proving_settings`], and certified in full afterwards as a candidate.
fn ranking_settings(solver: &SolverSettings) -> SolverSettings {
    SolverSettings {
        prove_optimum: false,
        ..proving_settings(solver)
    }
}

/// The solver settings of the bound the search returns: `solver`'s,
/// proved, but without the exact rational solve (the trivial 0 where
/// double and extended precision cannot prove it).
fn proving_settings(solver: &SolverSettings) -> SolverSettings {
    SolverSettings {
        exact_limit: 0,
        ..*solver
    }
}

/// `sum_k mu(k) dL/dmu(k)` over the `choices` of block `b`, each choice's
/// entry found in `universe` (NaN where its derivative is unknown).
fn block_rate(universe: &Support, entries: &[f64], b: usize, choices: &[Choice]) -> f64 {
    choices
        .iter()
        .map(|choice| {
            let entry = universe
                .block_by_index(b)
                .find(|&k| universe.entry(k) == (choice.next, choice.action));
            choice.probability * entry.map_or(f64::NAN, |k| entries[k])
        })
        .sum()
}

/// The most moves a guided step ([`guided_step`]) evaluates.
const GUIDED_CANDIDATES: usize = 8;

/// Hill-climbs from the defender `start` on the certified lower bound (the
/// trivial 0 where a product mixes too slowly to certify): the moves in a
/// block `(g, o)` are dropping one of its choices (the others
/// renormalised) and playing one enabled `(next node, action)` pair of
/// the game's defender with probability 1; where no such move raises the
/// bound and a node is unused, the splits of [`splits`] followed by such
/// moves. Single-block moves are tried in the order of their first-order
/// gains first ([`guided_step`]). Stops where no move raises the bound,
/// or when the climb has spent its effort (the search's, per climb).
/// Returns the end point and the work spent (the product states of its
/// evaluations, solved or passed over).
fn climb(search: &Search<'_>, start: &Fsc) -> Result<(Climbed, usize), CertifyError> {
    let landscape = Landscape::new(search);
    let mut current = climb_by_single_moves(
        &landscape,
        Climbed {
            bound: landscape.bound(start)?,
            defender: start.clone(),
        },
    )?;
    while let Some(better) = first_improving_split(&landscape, &current)? {
        current = better;
    }
    Ok((current, landscape.spent.get()))
}

/// [`climb`] from `start`, or where the searches sharing the memo
/// climbed from it before with the same work ([`Evaluations`]); a climb
/// that ends after the deadline is not recorded (the deadline may have
/// cut it short).
fn climb_remembered(search: &Search<'_>, start: &Fsc) -> Result<(Climbed, usize), CertifyError> {
    let key = (EvaluationKey::whole(start), search.effort.work);
    if let Some(end) = search.known.climbed(&key) {
        return Ok(end);
    }
    let end = climb(search, start)?;
    if !search.effort.past_deadline() {
        search.known.insert_climb(key, end.clone());
    }
    Ok(end)
}

/// The first split of `current` ([`splits`]) from which single-block
/// moves climb above its bound, where they end; `None` when none does (or
/// the effort is spent). The splits where a guided step ([`guided_step`])
/// finds a first move are climbed first: a split changes no value, and
/// the first-order gains of its copy's moves show where the copy pays,
/// for the cost of one gradient, where a sweep evaluates every move. The
/// others are climbed by sweeps after them, since the gradient is blind
/// to end components and vanishes where the adversary wins surely.
fn first_improving_split(
    landscape: &Landscape<'_>,
    current: &Climbed,
) -> Result<Option<Climbed>, CertifyError> {
    // The split changes no value: it starts where `current` is.
    let from = |split| Climbed {
        defender: split,
        bound: current.bound,
    };
    let improves = |end: &Climbed| end.bound > current.bound + IMPROVEMENT;
    for split in splits(&landscape.search.steps, &current.defender) {
        // Checked before the next split is built: each is a copy of the
        // whole defender, and a spent effort stays spent.
        if landscape.exhausted() {
            return Ok(None);
        }
        if let Some(first) = guided_step(landscape, &from(split))? {
            let end = climb_by_single_moves(landscape, first)?;
            if improves(&end) {
                return Ok(Some(end));
            }
        }
    }
    for split in splits(&landscape.search.steps, &current.defender) {
        if landscape.exhausted() {
            break;
        }
        let end = climb_by_single_moves(landscape, from(split))?;
        if improves(&end) {
            return Ok(Some(end));
        }
    }
    Ok(None)
}

/// Single-block moves from `from` until none raises the bound: guided
/// steps ([`guided_step`]) while they find one, then a sweep over every
/// move ([`sweep`], which passes over those that cannot raise the bound),
/// until a sweep changes nothing.
fn climb_by_single_moves(
    landscape: &Landscape<'_>,
    from: Climbed,
) -> Result<Climbed, CertifyError> {
    let mut current = from;
    loop {
        if let Some(better) = guided_step(landscape, &current)? {
            current = better;
        } else if let Some(better) = sweep(landscape, &current)? {
            current = better;
        } else {
            return Ok(current);
        }
    }
}

/// The first of the [`GUIDED_CANDIDATES`] moves of `current` with the
/// largest first-order gains ([`Landscape::promising_moves`]) that raises
/// the bound; `None` when none does (or the effort is spent). A move's
/// gain against the adversary's current best response is not its gain
/// against the next one, nor does it see an end component the move makes
/// or breaks, so the sweeps still judge every move that can raise the
/// bound where this finds none.
fn guided_step(
    landscape: &Landscape<'_>,
    current: &Climbed,
) -> Result<Option<Climbed>, CertifyError> {
    if landscape.exhausted() {
        return Ok(None);
    }
    let moves = landscape.promising_moves(&current.defender)?;
    let candidates = moves
        .into_iter()
        .take(GUIDED_CANDIDATES)
        .map(|(_, b, choices)| with_block(&current.defender, b, choices));
    landscape.first_improvement(candidates, current.bound, |_| false)
}

/// One sweep of single-block moves over the blocks in use, each block
/// taking its first improving move; `None` when no block changed (or the
/// effort was spent before any did). The moves in a block the adversary's
/// best response to the current defender does not meet
/// ([`crate::certify::ranked_lower_bound`]), and the moves the analysis of
/// the current defender refutes ([`Refuter`], built when a move first
/// asks), cannot raise the bound (beyond the ranking's numerical error),
/// and are passed over
/// ([`Landscape::pass_over`]): counted as judged, not solved, so that the
/// climb goes as where it judges them (unless a judged move would have
/// crossed [`IMPROVEMENT`] by that error, or failed to solve and been
/// charged as large as the game). The current defender's blocks met come
/// from its judgment ([`Landscape::judge`]), a solve that counts no work
/// where the climb has not judged it (a split, whose value is its
/// origin's).
fn sweep(landscape: &Landscape<'_>, from: &Climbed) -> Result<Option<Climbed>, CertifyError> {
    if landscape.exhausted() {
        return Ok(None);
    }
    let mut current = from.clone();
    let mut changed = false;
    let mut in_use = landscape.search.steps.blocks_in_use(&current.defender);
    let mut met = landscape.judge(&current.defender)?.met;
    // Built when a move first asks, once per current defender.
    let mut refuter = OnceCell::new();
    for b in 0..current.defender.blocks.len() {
        if !in_use[b] {
            continue;
        }
        let defender = &current.defender;
        let moves = block_moves(&defender.blocks[b], landscape.search.pairs(b))
            .map(|choices| with_block(defender, b, choices));
        let refuted = |candidate: &Fsc| {
            let refuter = refuter.get_or_init(|| landscape.refuter(&current.defender));
            refuter.as_ref().is_some_and(|r| r.refutes(candidate, b))
        };
        if !met[b] && landscape.search.pass_over_unmet {
            landscape.pass_over(moves)?;
        } else if let Some(better) = landscape.first_improvement(moves, current.bound, refuted)? {
            current = better;
            changed = true;
            in_use = landscape.search.steps.blocks_in_use(&current.defender);
            met = landscape.judge(&current.defender)?.met;
            refuter = OnceCell::new();
        }
        if landscape.exhausted() {
            break;
        }
    }
    Ok(changed.then_some(current))
}

/// The splits of `fsc` where it has an unused node `h` (no block of `h`
/// in use): for each choice `(g', u)` of a block in use, `fsc` with that
/// choice sent to `h` instead and `h` a copy of node `g'` (blocks and next
/// nodes), which changes no value. Empty where every node is in use.
fn splits<'a>(steps: &DefenderSteps<'_>, fsc: &'a Fsc) -> impl Iterator<Item = Fsc> + 'a {
    let in_use = steps.blocks_in_use(fsc);
    let observations = fsc.num_observations();
    let spare =
        (0..fsc.num_nodes()).find(|&h| (0..observations).all(|o| !in_use[h * observations + o]));
    let choices_in_use: Vec<(usize, usize)> = (0..in_use.len())
        .filter(|&b| in_use[b])
        .flat_map(|b| (0..fsc.blocks[b].len()).map(move |i| (b, i)))
        .collect();
    spare
        .map(|spare| (spare, choices_in_use))
        .into_iter()
        .flat_map(move |(spare, choices)| {
            choices
                .into_iter()
                .map(move |(b, i)| split(fsc, b, i, spare))
        })
}

/// `fsc` with choice `i` of block `b` sent to node `spare`, which becomes
/// a copy of that choice's next node.
fn split(fsc: &Fsc, b: usize, i: usize, spare: usize) -> Fsc {
    let observations = fsc.num_observations();
    let copied = fsc.blocks[b][i].next;
    let mut split = fsc.clone();
    for o in 0..observations {
        split.blocks[spare * observations + o] = fsc.blocks[copied * observations + o].clone();
    }
    split.blocks[b][i].next = spare;
    split
}

/// The blocks one move away from `block`: each choice dropped (if the
/// block has several), then each of `pairs` alone.
fn block_moves<'a>(
    block: &'a [Choice],
    pairs: &'a [Choice],
) -> impl Iterator<Item = Vec<Choice>> + 'a {
    let drops = (0..block.len())
        .filter(move |_| block.len() > 1)
        .map(move |dropped| {
            let kept = block.iter().enumerate().filter(|&(i, _)| i != dropped);
            let total: f64 = kept.clone().map(|(_, c)| c.probability).sum();
            kept.map(|(_, c)| Choice {
                probability: c.probability / total,
                logit: None,
                ..*c
            })
            .collect()
        });
    drops.chain(single_moves(block, pairs))
}

/// `block` replaced by one of `pairs` with probability 1, for each pair but
/// the one the block already plays alone.
fn single_moves<'a>(
    block: &'a [Choice],
    pairs: &'a [Choice],
) -> impl Iterator<Item = Vec<Choice>> + 'a {
    pairs
        .iter()
        .filter(move |pair| {
            !(block.len() == 1 && (block[0].next, block[0].action) == (pair.next, pair.action))
        })
        .map(|pair| vec![certain(pair)])
}

/// `pair` played with probability 1.
fn certain(pair: &Choice) -> Choice {
    Choice {
        probability: 1.0,
        logit: None,
        ..*pair
    }
}

/// The restarts of a round that `restarts` climbs of `work` each can pay
/// for, where every climb judges at least two defenders
/// ([`Landscape::exhausted`]) whose products are about as large as the start's
/// (`start_states`, asked for only where it matters): all of them unless
/// two judgments of the start's product cost more than `work`, then one
/// per two such judgments of the round's budget `restarts * work`, at least
/// one. On PAYNT's drone-2-8-1 (a 500,094-state product, each judgment
/// tens of seconds) the 16 restarts of two structures ran for more than
/// ten minutes after the race.
fn affordable_restarts(
    restarts: usize,
    work: usize,
    start_states: impl FnOnce() -> Result<usize, CertifyError>,
) -> Result<usize, CertifyError> {
    if restarts <= 1 {
        return Ok(restarts);
    }
    let per_climb = start_states()?.saturating_mul(2);
    if per_climb <= work {
        return Ok(restarts);
    }
    Ok((restarts.saturating_mul(work) / per_climb).clamp(1, restarts))
}

/// The most rounds of restarts [`climb_with_restarts`] runs.
const MAX_RESTART_ROUNDS: usize = 4;

/// Further rounds of restarts run while the climbs have spent less than
/// one round at full effort divided by this.
const ROUNDS_BUDGET_DIVISOR: usize = 4;

/// The climbs of one round of kicks ([`climb_with_restarts`]).
const KICKS_PER_ROUND: usize = 4;

/// A kick redraws one in this many of the blocks in use ([`kicked`]).
const KICK_DIVISOR: usize = 8;

/// A kick redraws at least this many blocks (where that many are in use).
const MIN_KICKED_BLOCKS: usize = 2;

/// [`climb`] from each of `starts` (deterministic defenders of one size,
/// at least one) and from random memoryless deterministic defenders (each
/// block `(g, o)` one enabled pair `(g, u)`, `u` uniformly drawn from a
/// stream seeded by `rng`; the climb adds memory), each until it ends or
/// spends `effort`; then from kicks of the best end point (iterated local
/// search). The restarts run in rounds of `restarts` climbs in parallel
/// (the first also climbs from `starts`); another round
/// follows while the climbs so far have spent less than a
/// [`ROUNDS_BUDGET_DIVISOR`]-th of one round at full effort (`restarts`
/// times `effort.work`), up to [`MAX_RESTART_ROUNDS`] rounds: where climbs
/// end early at local optima (small products), more of them run. The kicks
/// run in rounds of [`KICKS_PER_ROUND`] climbs in parallel, each from the
/// best end point so far with some of its blocks redrawn ([`kicked`]),
/// until they have spent as much work as the restarts (none without
/// restarts, nor where the best end point's bound is 0: a kick from a
/// defender that certifies nothing is one more random start; the last
/// round may overshoot). Both end once a climb reaches `effort.enough`,
/// and at the deadline. Returns the end point with the highest bound (the
/// first such, in the order `starts`, then the climbs as drawn), with its
/// certified lower bound. The rounds depend on counts and bounds only, so
/// the search is reproducible for a seed unless a deadline cuts it; what
/// the searches sharing `memo` evaluated costs it no solve.
pub fn climb_with_restarts(
    certifier: Certifier<'_>,
    starts: &[Fsc],
    restarts: usize,
    rng: &mut ChaCha8Rng,
    effort: Effort<'_>,
    memo: &SearchMemo,
) -> Result<Climbed, CertifyError> {
    let start = starts
        .first()
        .expect("a search climbs from at least one start");
    let Certifier {
        game,
        not_phi,
        solver,
        ..
    } = certifier;
    let universe = Fsc::uniform_enabled(Role::Defender, start.num_nodes(), game.defender());
    let restarts = affordable_restarts(restarts, effort.work, || {
        product_states(game, not_phi, start, Role::Defender)
    })?;
    let mut rounds = Rounds {
        search: Search::sharing((game, not_phi, solver), &universe, effort, memo),
        best: None,
        spent: 0,
    };
    let budget = restarts.saturating_mul(effort.work) / ROUNDS_BUDGET_DIVISOR;
    let mut froms = starts.to_vec();
    for _ in 0..MAX_RESTART_ROUNDS {
        froms.extend(draws(restarts, rng, |stream| {
            random_memoryless(start, &universe, stream)
        }));
        rounds.climb_from(std::mem::take(&mut froms))?;
        if restarts == 0 || rounds.spent >= budget || rounds.finished() {
            break;
        }
    }
    let restarts_spent = rounds.spent;
    while restarts > 0 && rounds.spent - restarts_spent < restarts_spent && !rounds.finished() {
        let Some(best) = rounds.best.as_ref().filter(|best| best.bound > 0.0) else {
            break;
        };
        let in_use = rounds.search.steps.blocks_in_use(&best.defender);
        let kicks = draws(KICKS_PER_ROUND, rng, |stream| {
            kicked(&best.defender, &in_use, &universe, stream)
        });
        rounds.climb_from(kicks)?;
    }
    let best = rounds.best.expect("the search climbs from the start");
    Ok(Climbed {
        bound: proved_bound(game, not_phi, &best.defender, &solver)?,
        defender: best.defender,
    })
}

/// `count` defenders made by `make`, each from its own stream seeded by
/// `rng`.
fn draws(count: usize, rng: &mut ChaCha8Rng, make: impl Fn(&mut ChaCha8Rng) -> Fsc) -> Vec<Fsc> {
    (0..count)
        .map(|_| make(&mut ChaCha8Rng::seed_from_u64(rng.random())))
        .collect()
}

/// The rounds of parallel climbs of [`climb_with_restarts`]: the best end
/// point so far and the work all climbs have spent.
struct Rounds<'a> {
    search: Search<'a>,
    best: Option<Climbed>,
    spent: usize,
}

impl Rounds<'_> {
    /// Climbs from each of `froms` in parallel, keeping the first end
    /// point with the highest bound.
    fn climb_from(&mut self, froms: Vec<Fsc>) -> Result<(), CertifyError> {
        let ends = froms
            .par_iter()
            .map(|from| climb_remembered(&self.search, from))
            .collect::<Result<Vec<_>, _>>()?;
        for end in ends {
            self.keep(end);
        }
        Ok(())
    }

    /// Counts the work of a climb and keeps its end point where it is the
    /// first with the highest bound.
    fn keep(&mut self, (end, work): (Climbed, usize)) {
        self.spent = self.spent.saturating_add(work);
        if self.best.as_ref().is_none_or(|b| end.bound > b.bound) {
            self.best = Some(end);
        }
    }

    /// Whether the deadline has passed or a climb reached `effort.enough`.
    fn finished(&self) -> bool {
        let found_enough = self
            .best
            .as_ref()
            .is_some_and(|b| b.bound >= self.search.effort.enough);
        self.search.effort.past_deadline() || found_enough
    }
}

/// `fsc` with one in [`KICK_DIVISOR`] of its blocks in use (`in_use`, by
/// [`DefenderSteps::blocks_in_use`]; at least [`MIN_KICKED_BLOCKS`]), drawn from `rng`
/// without repetition, each playing one of `universe`'s enabled pairs
/// `(next node, action)` with probability 1, drawn uniformly: a jump out
/// of a climb's end point's basin that keeps most of what the climb found.
fn kicked(fsc: &Fsc, in_use: &[bool], universe: &Fsc, rng: &mut ChaCha8Rng) -> Fsc {
    let in_use: Vec<usize> = in_use
        .iter()
        .enumerate()
        .filter_map(|(b, &used)| used.then_some(b))
        .collect();
    let count = (in_use.len() / KICK_DIVISOR)
        .max(MIN_KICKED_BLOCKS)
        .min(in_use.len());
    let mut jumped = fsc.clone();
    for i in rand::seq::index::sample(rng, in_use.len(), count) {
        let pairs = &universe.blocks[in_use[i]];
        jumped.blocks[in_use[i]] = vec![certain(&pairs[rng.random_range(0..pairs.len())])];
    }
    jumped
}

/// The certified lower bound of `defender` with [`proving_settings`], or
/// the trivial 0 where it cannot be proved so.
fn proved_bound(
    game: &Posg,
    not_phi: &Dra,
    defender: &Fsc,
    solver: &SolverSettings,
) -> Result<f64, CertifyError> {
    lower_value_or_trivial_within(game, not_phi, defender, &proving_settings(solver))
}

/// `shape` (nodes, initial distribution) with each block `(g, o)` playing
/// one of `universe`'s pairs `(g, u)` with probability 1, drawn uniformly
/// from `rng`.
fn random_memoryless(shape: &Fsc, universe: &Fsc, rng: &mut ChaCha8Rng) -> Fsc {
    let mut random = shape.clone();
    let observations = random.num_observations();
    for (b, (block, pairs)) in random.blocks.iter_mut().zip(&universe.blocks).enumerate() {
        let stay: Vec<&Choice> = pairs
            .iter()
            .filter(|p| p.next == b / observations)
            .collect();
        *block = vec![certain(stay[rng.random_range(0..stay.len())])];
    }
    random
}

/// Where the defender's action `u` can lead in `game` from each state `s`,
/// whatever the adversary plays: the distinct successors of `(s, u, v)`
/// over every adversary action `v`, once per game (the blocks in use of
/// every defender a search keys are found on it).
struct DefenderSteps<'a> {
    game: &'a Posg,
    /// The successors of `(s, u)` are
    /// `successors[offsets[s |U| + u]..offsets[s |U| + u + 1]]`, increasing.
    offsets: Vec<usize>,
    successors: Vec<usize>,
}

impl<'a> DefenderSteps<'a> {
    /// The steps of `game`'s defender.
    fn new(game: &'a Posg) -> Self {
        let (actions, adversary_actions) = (
            game.defender().num_actions(),
            game.adversary().num_actions(),
        );
        let mut offsets = Vec::with_capacity(game.num_states() * actions + 1);
        offsets.push(0);
        let mut successors = Vec::new();
        let mut reached = Vec::new();
        for s in 0..game.num_states() {
            for u in 0..actions {
                reached.clear();
                for v in 0..adversary_actions {
                    let moves = game.transition(s, DefenderAction(u), AdversaryAction(v));
                    reached.extend(moves.iter().map(|&(t, _)| t));
                }
                reached.sort_unstable();
                reached.dedup();
                successors.extend_from_slice(&reached);
                offsets.push(successors.len());
            }
        }
        Self {
            game,
            offsets,
            successors,
        }
    }

    /// The successors of `(s, u)`.
    fn from(&self, s: usize, u: usize) -> &[usize] {
        let i = s * self.game.defender().num_actions() + u;
        &self.successors[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Which blocks `(g, o)` of the defender `fsc` can be used against any
    /// adversary: those of the pairs `(s, g)` reachable from the initial
    /// states and nodes, where `o` is an observation of `s`. A move in any
    /// other block changes no value.
    fn blocks_in_use(&self, fsc: &Fsc) -> Vec<bool> {
        let game = self.game;
        let nodes = fsc.num_nodes();
        let observations = fsc.num_observations();
        let mut seen = vec![false; game.num_states() * nodes];
        let mut blocks = vec![false; nodes * observations];
        let mut stack: Vec<(usize, usize)> = Vec::new();
        let mut visit = |s: usize, g: usize, stack: &mut Vec<(usize, usize)>| {
            if !std::mem::replace(&mut seen[s * nodes + g], true) {
                stack.push((s, g));
            }
        };
        for &(s, _) in game.initial() {
            for (g, _) in fsc.initial().iter().enumerate().filter(|(_, p)| **p > 0.0) {
                visit(s, g, &mut stack);
            }
        }
        while let Some((s, g)) = stack.pop() {
            for &(o, _) in game.defender().observation_distribution(s) {
                blocks[g * observations + o] = true;
                for choice in fsc.choices(g, o) {
                    for &t in self.from(s, choice.action) {
                        visit(t, choice.next, &mut stack);
                    }
                }
            }
        }
        blocks
    }
}

/// `fsc` with block `b` replaced by `choices`.
fn with_block(fsc: &Fsc, b: usize, choices: Vec<Choice>) -> Fsc {
    let mut changed = fsc.clone();
    changed.blocks[b] = choices;
    changed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::lower_value_or_trivial;
    use crate::game::file::from_json_str;
    use crate::game::grid::GridSpec;
    use crate::optimise::truncated;
    use crate::pipeline::Automata;

    /// Which blocks `(g, o)` of the defender `fsc` can be used in `game`
    /// against any adversary ([`DefenderSteps::blocks_in_use`]).
    fn blocks_in_use(game: &Posg, fsc: &Fsc) -> Vec<bool> {
        DefenderSteps::new(game).blocks_in_use(fsc)
    }

    const UNLIMITED: Effort<'static> = Effort {
        work: usize::MAX,
        deadline: None,
        enough: f64::INFINITY,
        cancel: None,
    };

    fn grid_4x4() -> Posg {
        GridSpec {
            width: 4,
            height: 4,
            unsafe_cells: vec![5, 10],
            goal_cells: vec![15],
            ..GridSpec::default()
        }
        .build()
        .unwrap()
    }

    fn not_phi(formula: &str) -> Dra {
        Automata::from_ltl(formula).unwrap().not_phi.unwrap()
    }

    /// What a search certifies with: `game`, `not_phi` (also in the place
    /// of phi, which the search does not use) and the default solver.
    fn certifier<'a>(game: &'a Posg, not_phi: &'a Dra) -> Certifier<'a> {
        Certifier {
            game,
            phi: not_phi,
            not_phi,
            solver: SolverSettings::default(),
        }
    }

    /// Every block on its first enabled pair (next node 0): node 0 only is
    /// in use, and every node plays the same actions.
    fn first_pairs(game: &Posg, nodes: usize) -> Fsc {
        let uniform = Fsc::uniform_enabled(Role::Defender, nodes, game.defender());
        truncated(&uniform, f64::INFINITY).unwrap()
    }

    /// From the worst deterministic start on a 4x4 grid, the climb raises
    /// the bound and ends at a deterministic controller that no single
    /// change certifies higher.
    #[test]
    fn the_climb_ends_at_a_deterministic_local_optimum_of_the_bound() {
        let game = grid_4x4();
        let not_phi = not_phi("!unsafe U goal");
        let start = first_pairs(&game, 1);
        let before = lower_value_or_trivial(&game, &not_phi, &start).unwrap();
        let universe = Fsc::uniform_enabled(Role::Defender, 1, game.defender());
        let search = Search::new(&game, &not_phi, &universe, UNLIMITED);
        let found = climb(&search, &start).unwrap().0;
        let reached = lower_value_or_trivial(&game, &not_phi, &found.defender).unwrap();
        assert!(
            (reached - found.bound).abs() < 1e-12,
            "{reached} {}",
            found.bound
        );
        assert!(reached > before + 0.1, "{before} -> {reached}");
        assert!(found.defender.blocks.iter().all(|block| block.len() == 1));
        for (b, pairs) in universe.blocks.iter().enumerate() {
            for choices in block_moves(&found.defender.blocks[b], pairs) {
                let neighbour = with_block(&found.defender, b, choices);
                let value = lower_value_or_trivial(&game, &not_phi, &neighbour).unwrap();
                assert!(value <= reached + IMPROVEMENT, "block {b}: {value}");
            }
        }
    }

    /// The cue game (tests/stopping.rs): the defender sees the adversary's
    /// cue once and must later answer L after A, R after B. From two nodes
    /// that both answer L, with node 1 unused, no single-block change
    /// raises the bound 0 (a second node in use still answers L); the
    /// memory move (after B, a copy of node 0 that answers R) wins surely,
    /// and the search with 0 and 2 restarts reaches it too.
    #[test]
    fn memory_moves_add_the_memory_a_single_change_cannot() {
        let game = from_json_str(REMEMBER_THE_CUE, "cue.posg.json").unwrap();
        let not_phi = not_phi("F goal");
        let start = first_pairs(&game, 2);
        let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let search = Search::new(&game, &not_phi, &universe, UNLIMITED);
        let landscape = Landscape::new(&search);
        let from = Climbed {
            bound: landscape.bound(&start).unwrap(),
            defender: start.clone(),
        };
        assert_eq!(from.bound, 0.0);
        assert!(sweep(&landscape, &from).unwrap().is_none());
        let found = climb(&search, &start).unwrap().0;
        assert!((found.bound - 1.0).abs() < 1e-9, "{}", found.bound);
        let in_use = blocks_in_use(&game, &found.defender);
        assert!(
            in_use[game.defender().num_observations()..]
                .iter()
                .any(|&used| used)
        );
        for restarts in [0, 2] {
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            let searched = climb_with_restarts(
                certifier(&game, &not_phi),
                std::slice::from_ref(&start),
                restarts,
                &mut rng,
                UNLIMITED,
                &SearchMemo::default(),
            )
            .unwrap();
            assert!((searched.bound - 1.0).abs() < 1e-9, "{}", searched.bound);
        }
    }

    /// Every restart is paid for on small products; on a product whose two
    /// judgments cost more than a climb's work, one restart per two such
    /// judgments of the round's budget, at least one, and the product is
    /// not counted where one restart or none is asked for.
    #[test]
    fn restarts_are_cut_to_what_the_budget_pays_for_on_large_products() {
        let count = |states: usize| move || Ok::<_, CertifyError>(states);
        assert_eq!(affordable_restarts(16, 120_000, count(4_000)).unwrap(), 16);
        assert_eq!(affordable_restarts(16, 120_000, count(60_000)).unwrap(), 16);
        assert_eq!(affordable_restarts(16, 120_000, count(60_001)).unwrap(), 15);
        assert_eq!(affordable_restarts(16, 120_000, count(500_094)).unwrap(), 1);
        assert_eq!(
            affordable_restarts(16, 120_000, count(10_000_000)).unwrap(),
            1
        );
        let never = || -> Result<usize, CertifyError> { panic!("counted") };
        assert_eq!(affordable_restarts(1, 120_000, never).unwrap(), 1);
        assert_eq!(affordable_restarts(0, 120_000, never).unwrap(), 0);
    }

    /// Defenders that differ only in blocks out of use share their memo
    /// key (their products are the same); a change in a block in use
    /// makes another, and so does another number of nodes with the same
    /// blocks in use (the structures of a run may differ in it, and share
    /// the memo).
    #[test]
    fn the_memo_keys_defenders_by_their_blocks_in_use() {
        let game = grid_4x4();
        let start = first_pairs(&game, 2);
        let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let in_use = blocks_in_use(&game, &start);
        let observations = start.num_observations();
        let (unused, used) = (observations, 0);
        assert!(!in_use[unused] && in_use[used]);
        let other_pair = |b: usize| {
            let pair = universe.blocks[b]
                .iter()
                .find(|p| {
                    (p.next, p.action) != (start.blocks[b][0].next, start.blocks[b][0].action)
                })
                .expect("a block with a second pair");
            vec![certain(pair)]
        };
        let steps = DefenderSteps::new(&game);
        let key = |fsc: &Fsc| EvaluationKey::of(&steps, fsc);
        assert_eq!(
            key(&with_block(&start, unused, other_pair(unused))),
            key(&start)
        );
        assert_ne!(
            key(&with_block(&start, used, other_pair(used))),
            key(&start)
        );
        let one_node = first_pairs(&game, 1);
        assert_eq!(
            one_node.blocks[..observations],
            start.blocks[..observations]
        );
        assert_ne!(key(&one_node), key(&start));
    }

    /// A climb that finds every bound in the memo goes as the climb that
    /// filled it: the same end point, bound and work.
    #[test]
    fn a_climb_through_the_memo_goes_as_the_first() {
        let game = grid_4x4();
        let not_phi = not_phi("!unsafe U goal");
        let start = first_pairs(&game, 2);
        let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let search = Search::new(&game, &not_phi, &universe, UNLIMITED);
        let (first, first_work) = climb(&search, &start).unwrap();
        let known = lock(&search.known.known).len();
        let (again, again_work) = climb(&search, &start).unwrap();
        assert_eq!(
            lock(&search.known.known).len(),
            known,
            "the second climb solved something"
        );
        assert_eq!(again.defender, first.defender);
        assert_eq!(again.bound.to_bits(), first.bound.to_bits());
        assert_eq!(again_work, first_work);
    }

    /// PAYNT's attacker-one-defender (player 0 keeps the attacker from
    /// the goal, `Pmin=? [F "goal"]`), its universe with `nodes` nodes,
    /// and `!phi`.
    fn attacker_one_defender(nodes: usize) -> (Posg, Fsc, Dra) {
        let game = crate::game::drn::read(std::path::Path::new(
            "tests/data/paynt/attacker-one-defender.drn",
        ))
        .unwrap()
        .game;
        let universe = Fsc::uniform_enabled(Role::Defender, nodes, game.defender());
        (game, universe, not_phi("G !goal"))
    }

    /// No move in a block the adversary's best response does not meet
    /// raises the lower bound: on PAYNT's attacker-one-defender with 2
    /// nodes, from kicks of the uniform defender, some blocks in use are
    /// not met, every move there is judged and none rises above the bound
    /// (beyond the ranking's error), and some move in a block met does.
    #[test]
    fn no_move_in_a_block_the_adversary_does_not_meet_raises_the_bound() {
        let (game, universe, not_phi) = attacker_one_defender(2);
        let settings = ranking_settings(&SolverSettings::default());
        let judged = |fsc: &Fsc| ranked_lower_bound(&game, &not_phi, fsc, &settings).unwrap();
        let (mut unmet_moves, mut raised_where_met) = (0, 0);
        let uniform_in_use = blocks_in_use(&game, &universe);
        for seed in 0..3 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let defender = kicked(&universe, &uniform_in_use, &universe, &mut rng);
            let before = judged(&defender);
            let in_use = blocks_in_use(&game, &defender);
            assert!(before.blocks.iter().zip(&in_use).all(|(&m, &u)| !m || u));
            for b in (0..in_use.len()).filter(|&b| in_use[b]) {
                for choices in block_moves(&defender.blocks[b], &universe.blocks[b]) {
                    let after = judged(&with_block(&defender, b, choices)).value;
                    if before.blocks[b] {
                        raised_where_met += usize::from(after > before.value + IMPROVEMENT);
                    } else {
                        assert!(
                            after <= before.value + 1e-9,
                            "seed {seed} block {b}: {} -> {after}",
                            before.value
                        );
                        unmet_moves += 1;
                    }
                }
            }
        }
        assert!(
            unmet_moves > 0 && raised_where_met > 0,
            "{unmet_moves} {raised_where_met}"
        );
    }

    /// The blocks met are those of the adversary's optimal play while it
    /// can still win: from s0 it goes left (to `a`, where `bad` follows
    /// with 0.9) rather than right (to `b`, 0.5); `a` shows either of two
    /// observations, both met; `b` (off the optimal play) and `safe`
    /// (reached, but the adversary wins nothing from it) are not met;
    /// `bad` (the accepting end component) is.
    #[test]
    fn the_blocks_met_are_those_of_the_adversarys_optimal_play_while_it_can_win() {
        let game = from_json_str(
            r#"{"posg": 1, "states": ["s0", "a", "b", "safe", "bad"], "initial": {"s0": 1.0},
                "labels": {"bad": ["bad"]},
                "defender": {"actions": ["go", "dash"],
                    "observations": ["o0", "oa", "ox", "ob", "os", "obad"], "observe": {
                    "s0": {"o0": 1.0}, "a": {"oa": 0.5, "ox": 0.5}, "b": {"ob": 1.0},
                    "safe": {"os": 1.0}, "bad": {"obad": 1.0}}},
                "adversary": {"actions": ["left", "right"], "observe": "full"},
                "transitions": [
                    {"state": "s0", "defender": "*", "adversary": "left", "next": {"a": 1.0}},
                    {"state": "s0", "defender": "*", "adversary": "right", "next": {"b": 1.0}},
                    {"state": "a", "defender": "*", "adversary": "*",
                     "next": {"bad": 0.9, "safe": 0.1}},
                    {"state": "b", "defender": "*", "adversary": "*",
                     "next": {"bad": 0.5, "safe": 0.5}},
                    {"state": "safe", "defender": "*", "adversary": "*", "next": {"safe": 1.0}},
                    {"state": "bad", "defender": "*", "adversary": "*", "next": {"bad": 1.0}}
                ]}"#,
            "blocks-met.posg.json",
        )
        .unwrap();
        let not_phi = not_phi("G !bad");
        let defender = Fsc::uniform_enabled(Role::Defender, 1, game.defender());
        let ranked = ranked_lower_bound(
            &game,
            &not_phi,
            &defender,
            &ranking_settings(&SolverSettings::default()),
        )
        .unwrap();
        assert!((ranked.value - 0.1).abs() < 1e-12, "{}", ranked.value);
        let state = |name: &str| game.states().iter().position(|s| s == name).unwrap();
        let met_at = |name: &str| -> Vec<bool> {
            game.defender()
                .observation_distribution(state(name))
                .iter()
                .map(|&(o, _)| ranked.blocks[o])
                .collect()
        };
        for (name, met) in [
            ("s0", true),
            ("a", true),
            ("b", false),
            ("safe", false),
            ("bad", true),
        ] {
            let at = met_at(name);
            assert!(
                !at.is_empty() && at.iter().all(|&m| m == met),
                "{name}: {at:?}"
            );
        }
        assert_eq!(met_at("a").len(), 2);
    }

    /// Passing over moves changes no climb: on PAYNT's
    /// attacker-one-defender with 2 nodes, from random memoryless starts
    /// and with a work budget that ends some climbs early, climbs that
    /// pass over the moves the adversary does not meet, and those that
    /// also pass over the moves a refuter refutes, end at the same
    /// defenders with the same bounds and the same work as climbs that
    /// judge every move, each solving fewer products.
    #[test]
    fn passing_over_moves_changes_no_climb() {
        let (game, universe, not_phi) = attacker_one_defender(2);
        let start = first_pairs(&game, 2);
        let effort = Effort {
            work: 20_000,
            ..UNLIMITED
        };
        let search = |unmet: bool, refuted: bool| Search {
            pass_over_unmet: unmet,
            pass_over_refuted: refuted,
            ..Search::new(&game, &not_phi, &universe, effort)
        };
        let searches = [
            search(true, true),
            search(true, false),
            search(false, false),
        ];
        let mut ended_early = 0;
        for seed in 0..4 {
            let from = random_memoryless(&start, &universe, &mut ChaCha8Rng::seed_from_u64(seed));
            let climbs: Vec<_> = searches.iter().map(|s| climb(s, &from).unwrap()).collect();
            let (judged, judged_work) = &climbs[2];
            for (passed, passed_work) in &climbs[..2] {
                assert_eq!(passed.defender, judged.defender, "seed {seed}");
                assert_eq!(
                    passed.bound.to_bits(),
                    judged.bound.to_bits(),
                    "seed {seed}"
                );
                assert_eq!(passed_work, judged_work, "seed {seed}");
            }
            ended_early += usize::from(*judged_work >= effort.work);
        }
        assert!(ended_early > 0, "no climb spent its effort");
        let solved = searches
            .each_ref()
            .map(|search| lock(&search.known.known).len());
        assert!(
            solved[0] < solved[1] && solved[1] < solved[2],
            "products solved: {solved:?}"
        );
    }

    /// Searches sharing a memo go as they go alone: on the 4x4 grid, a
    /// search from another start after one that filled the memo ends
    /// where it ends with a memo of its own, with the same bound, solving
    /// fewer products.
    #[test]
    fn a_search_sharing_a_memo_goes_as_alone() {
        let game = grid_4x4();
        let not_phi = not_phi("!unsafe U goal");
        let first = first_pairs(&game, 2);
        let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let other = random_memoryless(&first, &universe, &mut ChaCha8Rng::seed_from_u64(9));
        let search = |start: &Fsc, memo: &SearchMemo| {
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            climb_with_restarts(
                certifier(&game, &not_phi),
                std::slice::from_ref(start),
                3,
                &mut rng,
                UNLIMITED,
                memo,
            )
            .unwrap()
        };
        let solved = |memo: &SearchMemo| lock(&memo.0.known).len();
        let shared = SearchMemo::default();
        search(&first, &shared);
        let before = solved(&shared);
        let sharing = search(&other, &shared);
        let own = SearchMemo::default();
        let alone = search(&other, &own);
        assert_eq!(sharing.defender, alone.defender);
        assert_eq!(sharing.bound.to_bits(), alone.bound.to_bits());
        assert!(
            solved(&shared) - before < solved(&own),
            "{} solved sharing, {} alone",
            solved(&shared) - before,
            solved(&own)
        );
    }

    /// A climb the searches sharing a memo made is not made again: on the
    /// 4x4 grid, the same search repeated on the memo, its evaluations
    /// forgotten, ends where it ended without judging a single defender.
    #[test]
    fn a_search_repeated_on_a_memo_climbs_nothing_again() {
        let game = grid_4x4();
        let not_phi = not_phi("!unsafe U goal");
        let start = first_pairs(&game, 2);
        let memo = SearchMemo::default();
        let search = || {
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            climb_with_restarts(
                certifier(&game, &not_phi),
                std::slice::from_ref(&start),
                3,
                &mut rng,
                UNLIMITED,
                &memo,
            )
            .unwrap()
        };
        let first = search();
        assert!(lock(&memo.0.climbs).len() > 1, "the restarts are recorded");
        lock(&memo.0.known).clear();
        lock(&memo.0.sizes).clear();
        let again = search();
        assert_eq!(again.defender, first.defender);
        assert_eq!(again.bound.to_bits(), first.bound.to_bits());
        assert!(lock(&memo.0.known).is_empty(), "a climb was made again");
        assert!(lock(&memo.0.sizes).is_empty(), "a climb was made again");
    }

    /// The restarts keep the best end point and are reproducible: on the
    /// 4x4 grid from the worst start they certify at least what the climb
    /// from that start reaches, the same defender for the same seed, and a
    /// deterministic one; the bound returned is certified.
    #[test]
    fn restarts_keep_the_best_end_point_and_are_reproducible() {
        let game = grid_4x4();
        let not_phi = not_phi("!unsafe U goal");
        let start = first_pairs(&game, 2);
        let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let search = Search::new(&game, &not_phi, &universe, UNLIMITED);
        let alone = climb(&search, &start).unwrap().0;
        let restarted = || {
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            climb_with_restarts(
                certifier(&game, &not_phi),
                std::slice::from_ref(&start),
                3,
                &mut rng,
                UNLIMITED,
                &SearchMemo::default(),
            )
            .unwrap()
        };
        let best = restarted();
        // The returned bound is proved, the climb's only ranked: the proof
        // may widen it by rounding.
        assert!(
            best.bound >= alone.bound - 1e-12,
            "{} below {}",
            best.bound,
            alone.bound
        );
        // It is the certified bound, not the climb's ranking above it.
        let certified = crate::certify::lower_bound(&game, &not_phi, &best.defender).unwrap();
        assert!(
            best.bound <= certified.value,
            "{} above {}",
            best.bound,
            certified.value
        );
        assert_eq!(best.defender, restarted().defender);
        assert!(best.defender.blocks.iter().all(|block| block.len() == 1));
    }

    /// A kick redraws `max(in use / 8, 2)` blocks in use, each to one
    /// enabled pair played surely (a redraw may land on the pair the block
    /// plays), and leaves every other block as it was; the same stream
    /// kicks alike. On the 4x4 grid (16 observations) the least count, 2;
    /// on PAYNT's attacker-one-defender with 2 nodes, one in 8.
    #[test]
    fn a_kick_redraws_one_in_8_blocks_in_use_and_keeps_the_rest() {
        let (aod, universe, _) = attacker_one_defender(2);
        let aod_fsc = {
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            let mut fsc = first_pairs(&aod, 2);
            // Both nodes in use: node 0 moves to node 1 on every observation.
            for block in fsc.blocks.iter_mut().take(fsc.num_observations) {
                block[0].next = 1;
            }
            for b in fsc.num_observations..fsc.blocks.len() {
                let pairs = &universe.blocks[b];
                fsc.blocks[b] = vec![certain(&pairs[rng.random_range(0..pairs.len())])];
            }
            fsc
        };
        for (game, fsc, expected) in [
            (grid_4x4(), first_pairs(&grid_4x4(), 2), 2),
            (aod, aod_fsc, 4),
        ] {
            let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
            let in_use = blocks_in_use(&game, &fsc);
            let used = in_use.iter().filter(|&&u| u).count();
            assert_eq!(
                (used / KICK_DIVISOR).max(MIN_KICKED_BLOCKS),
                expected,
                "{used} in use"
            );
            let kick = |seed| {
                kicked(
                    &fsc,
                    &in_use,
                    &universe,
                    &mut ChaCha8Rng::seed_from_u64(seed),
                )
            };
            let mut most = 0;
            for seed in 0..20 {
                let jumped = kick(seed);
                let changed: Vec<usize> = (0..fsc.blocks.len())
                    .filter(|&b| jumped.blocks[b] != fsc.blocks[b])
                    .collect();
                assert!(changed.len() <= expected, "{changed:?}");
                most = most.max(changed.len());
                for &b in &changed {
                    assert!(in_use[b], "block {b} is not in use");
                    let [choice] = jumped.blocks[b].as_slice() else {
                        panic!("block {b}: {:?}", jumped.blocks[b]);
                    };
                    assert_eq!(choice.probability, 1.0);
                    assert!(
                        universe.blocks[b].iter().any(|pair| {
                            (pair.next, pair.action) == (choice.next, choice.action)
                        })
                    );
                }
                assert_eq!(jumped, kick(seed));
            }
            assert_eq!(most, expected);
        }
    }

    /// The cue game of tests/stopping.rs.
    const REMEMBER_THE_CUE: &str =
        include_str!("../../tests/data/valid/remember-the-cue.posg.json");
}
