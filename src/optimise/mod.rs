//! The max-min optimiser (method.md sections 2-4):
//!
//! ```text
//!     max over phi_def in [-c, c]^n   min over phi_adv in [-c, c]^m   V(softmax(phi_def), softmax(phi_adv))
//! ```
//!
//! on fixed support structures. The pieces:
//!
//! * [`Softmax`]: logits per support entry, the softmax and its chain rule
//!   (section 3);
//! * [`Objective`]: one [`crate::value::Evaluator`] per structure, giving the
//!   value and both players' logit gradients by the adjoint method (section 2),
//!   with the last point cached;
//! * `best_response`: the adversary's best response by L-BFGS (argmin) in
//!   the coordinates `phi = c tanh(z)` (`reparam.rs`, section 3), from
//!   several starts;
//! * `Optimiser`: the driver of alternating projected gradient
//!   ascent-descent (section 4). Its solver takes one outer iteration: a
//!   fast adversary time scale, plain or Adam (optionally optimistic)
//!   updates; the driver owns the rest: periodic best-response checks that
//!   also certify, a logit bound that widens when progress stalls on it,
//!   stopping on the certified gap or a stall, the best defender seen, and
//!   the observer;
//! * `Ascent`: the single-player solver under the same driver (the
//!   adversary has one action, so max-min is max): L-BFGS steps on `ln V`
//!   in the same coordinates;
//! * [`rounded_candidates`]: partial and argmax roundings of the result,
//!   each scored exactly on its own support;
//! * [`optimise_structure`]: parallel seeded starts on one structure, the
//!   best certified kept, then rounded; [`optimise_structures`] does it on
//!   several structures (their local searches before the races one after
//!   another, sharing what they judged; the races in parallel, rayon), the
//!   best certified lower bound chosen; `candidate_structures` gathers the
//!   structures of the sources asked for (the starting structure, support
//!   synthesis by SAT, the paper's pruning; identical structures once);
//!   [`crate::pipeline`] does both from the full support structure of
//!   given sizes;
//! * [`embed`], [`pad`], [`warm_started`], [`keep_better`]: warm starts
//!   across defender sizes, results monotone in size by construction.
//!
//! [`Settings`] holds every number; [`Observer`]s receive one
//! [`IterationRecord`] per outer iteration (of the kept start) and write all
//! output.

mod ascent;
mod best_response;
mod cancel;
mod guarantee;
mod informed;
mod local_search;
mod objective;
mod observer;
mod optimiser;
mod play;
mod race;
mod reparam;
mod reward;
mod rounding;
mod settings;
mod softmax;
mod solver;
mod stopping;
mod structures;
mod warm_start;

pub(crate) use best_response::{Starts, final_best_response};
pub use cancel::Cancel;
pub use objective::{GmcSize, Objective, Point};
pub use observer::{IterationRecord, Observer, ObserverError, Phase, RecordSource, SearchRecord};
pub(crate) use optimiser::{Certifier, Optimiser, PhaseSeconds, RunOutcome};
pub use reward::{ExpectedReward, RewardSolution, RewardStart, optimise_expected_reward};
pub use rounding::{TRUNCATION_THRESHOLDS, rounded_candidates, truncated};
pub use settings::{MAX_LOGIT_BOUND, Settings, UpdateRule};
pub use softmax::{Softmax, clip};
pub use structures::{Candidates, Duplicate, SourceNote, StructureSource};
pub(crate) use structures::{
    best_by_certified_lower, candidate_structures, described, why_others_lost,
};
pub use warm_start::{WARM_START_MIX, embed, keep_better, pad, score, warm_started};

use std::sync::{Mutex, PoisonError};
use std::time::Instant;

use race::{Racer, race};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;

use crate::automaton::Dra;
use crate::certify::belief::{BeliefBound, UpperBoundsOnce, check_below_belief};
use crate::controller::{Fsc, Role};
use crate::game::{ModelError, Posg};
use crate::prune::PruneError;
use crate::synthesis::SynthesisError;
use crate::value::ValueError;

/// Why optimisation could not run.
#[derive(Debug, Error)]
pub enum OptimiseError {
    /// A setting is out of range.
    #[error("setting `{field}` {problem}")]
    Settings {
        /// The field's name.
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// A structure's controllers do not fit the game, or a controller could
    /// not be rebuilt from logits.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Algorithm 1 (pruning) failed.
    #[error(transparent)]
    Prune(#[from] PruneError),
    /// A value or gradient could not be computed.
    #[error(transparent)]
    Value(#[from] ValueError),
    /// Support synthesis failed.
    #[error(transparent)]
    Synthesis(#[from] SynthesisError),
    /// A certified bound could not be computed.
    #[error(transparent)]
    Certify(#[from] crate::certify::CertifyError),
    /// An observer failed (its output could not be written).
    #[error("output: {0}")]
    Observer(ObserverError),
    /// [`optimise_structures`] was given no structure.
    #[error("no structure to optimise")]
    NoStructure,
    /// The best-response minimisation failed for another reason.
    #[error("best response: {0}")]
    BestResponse(String),
    /// The objective cannot be optimised on this game yet.
    #[error("{0}")]
    Unsupported(String),
}

impl OptimiseError {
    /// Whether the error is numerical trouble of one candidate (a linear
    /// system that could not be solved to the tolerance, method.md section
    /// 8): a start or structure that runs into it is dropped, with the
    /// reason reported, while the others go on.
    pub fn is_numerical(&self) -> bool {
        match self {
            Self::Value(ValueError::Solver(_)) => true,
            Self::Certify(error) => error.is_numerical(),
            _ => false,
        }
    }
}

/// The items kept by [`keep_solved`] as `(index, item)`, and the dropped
/// ones as `(index, error)`.
type Kept<T> = (Vec<(usize, T)>, Vec<(usize, String)>);

/// Keeps the results of `results` that succeeded; numerical trouble
/// ([`OptimiseError::is_numerical`]) drops an item and is described in the
/// second list as `(index, error)`; any other error, or every item failing,
/// is returned.
fn keep_solved<T>(results: Vec<Result<T, OptimiseError>>) -> Result<Kept<T>, OptimiseError> {
    let (mut kept, mut dropped, mut first) = (Vec::new(), Vec::new(), None);
    for (index, result) in results.into_iter().enumerate() {
        match result {
            Ok(value) => kept.push((index, value)),
            Err(error) if error.is_numerical() => {
                dropped.push((index, error.to_string()));
                first.get_or_insert(error);
            }
            Err(error) => return Err(error),
        }
    }
    match first {
        Some(error) if kept.is_empty() => Err(error),
        _ => Ok((kept, dropped)),
    }
}

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// `max_iterations` outer iterations ran.
    MaxIterations,
    /// The max-min loop or an ascent spent its `max_work` (states solved).
    WorkBudget,
    /// The time budget ran out.
    TimeBudget,
    /// The best score stopped improving (at the widest logit bound).
    Stalled,
    /// The certified gap closed to `gap_tolerance`; or a single player's
    /// value met the upper bound proved before its race (`race.rs`,
    /// `CEILING_MET`).
    GapClosed,
    /// The single-player solver found no ascent step (a stationary point),
    /// or ten consecutive steps each gained less than `1e-12` of the value.
    Converged,
    /// A [`Cancel`] flag asked the run to stop.
    Cancelled,
    /// The structure's GMC reaches no phi-feasible BSCC on its supports:
    /// the value is 0 at every point the loop can reach, and so is every
    /// defender's certified lower bound there, so the loop stops at its
    /// first check (the final rounding and the local search, which change
    /// the support, still run).
    ZeroOnSupport,
    /// Another start of the portfolio (or the local search before the
    /// race) was ahead by more than this one gained over the second half of
    /// its run, or closed the certified gap or met the single player's
    /// upper bound (`race.rs`); or the start's
    /// early probe against the local search's bound found it out of reach
    /// (`optimiser.rs`, `FLOOR_PROBE_CHECKS`).
    Outpaced,
}

impl Status {
    /// Why a run stopped, in words, with the budget of `settings` that
    /// ended it where one did (`work budget spent: 3.5e6 GMC states solved
    /// per start`).
    pub fn explained(self, settings: &Settings) -> String {
        match self {
            Status::MaxIterations => format!(
                "iteration limit reached: {} iterations",
                settings.max_iterations
            ),
            Status::WorkBudget => format!(
                "work budget spent: {:.1e} GMC states solved per start",
                settings.max_work
            ),
            Status::TimeBudget => {
                format!("time budget spent: {} s", settings.time_budget)
            }
            Status::Stalled => "stalled: the best score stopped improving".into(),
            Status::GapClosed => format!("certified gap closed to {:.0e}", settings.gap_tolerance),
            Status::Converged => "converged: no ascent step left".into(),
            Status::Cancelled => "cancelled".into(),
            Status::ZeroOnSupport => {
                "value 0 on the whole support: no phi-feasible recurrent set reachable".into()
            }
            Status::Outpaced => "outpaced by another start or the local search".into(),
        }
    }
}

/// How a structure was optimised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Alternating projected gradient ascent-descent with best-response
    /// checks (method.md section 4).
    MaxMin,
    /// The single-player L-BFGS ascent (`Ascent`) under the same driver:
    /// the adversary has one action, so max-min is max.
    Ascent,
}

/// One start's numbers (every start is recorded, not only the best).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StartReport {
    /// The start's index.
    pub start: usize,
    /// Its random stream of `seed` (`structure stream + (start << 32)`).
    pub stream: u64,
    /// Its best defender's worst-case estimate.
    pub worst_case: f64,
    /// Its best defender's certified lower bound (with an automaton for !phi).
    pub certified_lower: Option<f64>,
    /// Iterations run.
    pub iterations: usize,
    /// Why it stopped.
    pub status: Status,
    /// Its wall-clock seconds.
    pub seconds: f64,
    /// Its logit bound `c` at the end.
    pub logit_bound: f64,
}

/// One candidate of the final rounding and its score.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateReport {
    /// `unrounded`, `truncated-<d>` or `argmax` ([`rounded_candidates`]).
    pub name: String,
    /// Its certified lower bound (with an automaton for !phi), exact value
    /// (single player) or worst-case estimate.
    pub score: f64,
}

/// A support structure to optimise on: starting controllers whose supports
/// fix the GMC graph (their probabilities, or recorded logits, are the start).
#[derive(Debug, Clone, PartialEq)]
pub struct Structure {
    /// A short name for reports (`full`, `pruned-1`, ...).
    pub name: String,
    /// The defender's starting controller.
    pub defender: Fsc,
    /// The adversary's starting controller.
    pub adversary: Fsc,
    /// Where one more start begins (on the same support): the best
    /// defender of the next smaller size embedded, in a grown run
    /// ([`warm_started`]). It races beside the `starts` that begin from
    /// `defender` as a run of this size alone would, and the local search
    /// climbs from both, so growing keeps the fresh starts' reach.
    pub warm: Option<Fsc>,
}

impl Structure {
    /// The full support structure: every `(g', u)` with `u` enabled under
    /// the block's observation in every block, both
    /// players uniform; each starts in node 0, or (when the initial
    /// distribution is optimised) uniformly over its nodes.
    pub fn full(
        game: &Posg,
        defender_nodes: usize,
        adversary_nodes: usize,
        optimise_initial: bool,
    ) -> Self {
        let make = |role: Role, nodes: usize| {
            let player = role.player(game);
            let mut fsc = Fsc::uniform_enabled(role, nodes, player);
            if optimise_initial {
                fsc.initial = vec![1.0 / nodes as f64; nodes];
            }
            fsc
        };
        Self {
            name: "full".into(),
            defender: make(Role::Defender, defender_nodes),
            adversary: make(Role::Adversary, adversary_nodes),
            warm: None,
        }
    }
}

/// The numbers of one structure's run, as recorded in `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StructureReport {
    /// The structure's name.
    pub name: String,
    /// The size of its GMC.
    pub gmc: GmcSize,
    /// The number of defender logits.
    pub defender_parameters: usize,
    /// The number of adversary logits.
    pub adversary_parameters: usize,
    /// The seed of this structure's random streams (`seed`; stream = index
    /// for start 0, see [`StartReport::stream`]).
    pub seed: u64,
    /// The best defender's worst-case estimate.
    pub worst_case: f64,
    /// The iteration the best defender was seen at.
    pub best_iteration: usize,
    /// The value at the last iterate.
    pub last_value: f64,
    /// The largest error bound of the values computed in the run (method.md
    /// section 8): `worst_case` and `last_value` are within it.
    pub error_bound: f64,
    /// Outer iterations run.
    pub iterations: usize,
    /// Best-response checks run.
    pub checks: usize,
    /// Why the run stopped.
    pub status: Status,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// The returned defender's certified lower bound against every
    /// adversary (method.md section 6), when an automaton for !phi was given.
    pub certified_lower: Option<f64>,
    /// The smallest game upper bound over the best responses found (for a
    /// single-player game: the fully observable optimum, or the belief
    /// bound where it is lower), with `certified_lower`.
    pub upper_bound: Option<f64>,
    /// The belief bound of a single-player game (a POMDP; method.md
    /// section 6), where the fully informed optimum left the bracket open:
    /// no defender of any memory does better; `complete` where every
    /// belief was explored.
    pub belief_bound: Option<BeliefBound>,
    /// How the structure was optimised.
    pub method: Method,
    /// Which candidate was returned: `unrounded`, `truncated-<d>` or `argmax`.
    pub rounding: String,
    /// Every rounding candidate scored, the unrounded defender first.
    pub candidates: Vec<CandidateReport>,
    /// Every start's numbers.
    pub starts: Vec<StartReport>,
    /// The start whose defender was kept.
    pub best_start: usize,
    /// The starts dropped because a linear system could not be solved to
    /// the tolerance, with the error.
    pub failed_starts: Vec<String>,
    /// The kept start's logit bound `c` at the end.
    pub logit_bound: f64,
    /// The largest residual of any linear solve of the kept start.
    pub max_residual: f64,
    /// Seconds per phase, summed over the starts (thread seconds).
    pub phases: PhaseSeconds,
}

/// The outcome on one structure: its report and the controllers.
#[derive(Debug, Clone, PartialEq)]
pub struct StructureOutcome {
    /// The numbers.
    pub report: StructureReport,
    /// The returned defender: the best start's best defender or one of its
    /// roundings (then with a smaller support and no logits).
    pub defender: Fsc,
    /// The best response found to it, with its logits.
    pub adversary: Fsc,
}

/// The outcomes on all structures and the one with the best worst-case estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// One outcome per structure that could be optimised, in the order given.
    pub structures: Vec<StructureOutcome>,
    /// The index of the best structure (the first of equal estimates).
    pub best: usize,
    /// The structures dropped for numerical trouble, as `(name, error)`.
    pub failed: Vec<(String, String)>,
}

impl Solution {
    /// The best structure's outcome.
    pub fn best(&self) -> &StructureOutcome {
        &self.structures[self.best]
    }
}

/// Optimises on every structure, each with its own [`Objective`] and
/// random stream (`settings.seed`, stream = its index), each reporting to
/// the observer `observer(index, structure)` makes: first the local
/// searches before the races (`search_supports`), one structure after
/// another, all on the first structure's search stream and sharing one
/// memo (each search then has both cores, and a later one finds most of
/// its climbs judged); then the races in parallel (rayon), timed from the
/// run's start;
/// returns every outcome and the best by certified lower bound
/// (`best_by_certified_lower`). A structure whose linear systems cannot
/// be solved to the tolerance is dropped and named in
/// [`Solution::failed`] (an error only if every structure fails). With an
/// automaton `negated` for !phi, every best-response check also certifies
/// (see `Certifier`); a single-player run takes the belief bound from
/// `belief` (the run's, for `game` and `dra`). Every run stops early once
/// `cancel` is set.
pub fn optimise_structures<F>(
    game: &Posg,
    (dra, negated): (&Dra, Option<&Dra>),
    structures: &[Structure],
    settings: &Settings,
    observer: F,
    cancel: &Cancel,
    belief: &UpperBoundsOnce<'_>,
) -> Result<Solution, OptimiseError>
where
    F: Fn(usize, &Structure) -> Box<dyn Observer + Send> + Sync,
{
    settings.validate()?;
    let run = StructuresRun::new(
        (game, dra, negated),
        (settings, cancel),
        search_stream(0),
        belief,
    );
    let mut watchers: Vec<_> = (structures.iter().enumerate())
        .map(|(index, structure)| observer(index, structure))
        .collect();
    // The searches before the races one structure after another, each
    // with the machine to itself: they search one universe from the same
    // random restarts, so each after the first finds most of its climbs in
    // the memo.
    let presolved: Vec<_> = (structures.iter().zip(&mut watchers))
        .map(|(structure, watcher)| run.presolve(structure, watcher.as_mut()))
        .collect();
    // Every structure's race sees the best bound any search proved: a
    // start that cannot reach it is outpaced on every structure alike.
    let proved = (presolved.iter())
        .filter_map(|p| p.as_ref().ok()?.climbed.as_ref().map(|c| c.bound))
        .reduce(f64::max);
    let outcomes = (structures.par_iter().zip(watchers.par_iter_mut()))
        .zip(presolved)
        .enumerate()
        .map(|(index, ((structure, watcher), presolved))| {
            run.race(
                structure,
                index as u64,
                watcher.as_mut(),
                (presolved?, proved),
            )
        })
        .collect::<Vec<_>>();
    if outcomes.is_empty() {
        return Err(OptimiseError::NoStructure);
    }
    let (kept, dropped) = keep_solved(outcomes)?;
    let outcomes: Vec<StructureOutcome> = kept.into_iter().map(|(_, o)| o).collect();
    let best = best_by_certified_lower(&outcomes).ok_or(OptimiseError::NoStructure)?;
    Ok(Solution {
        structures: outcomes,
        best,
        failed: dropped
            .into_iter()
            .map(|(index, error)| (structures[index].name.clone(), error))
            .collect(),
    })
}

/// Optimises on one structure: `settings.starts` independent starts (one
/// more from [`Structure::warm`] in a grown run) in
/// parallel (rayon), start `i` with random stream `stream + (i << 32)` of
/// `settings.seed`; each runs under the driver (`Optimiser`; the starts
/// race in lockstep rounds and an outpaced start stops, `race.rs`) with
/// gradient play or, when the adversary has one action and
/// `settings.single_player_ascent`, the single-player L-BFGS solver
/// (`Ascent`). The start with the best score
/// (certified lower bound with an automaton `negated` for !phi, else
/// worst-case estimate; the first of equals) is kept; then its rounded candidates
/// ([`rounded_candidates`]) are scored alike and the best of the unrounded
/// defender and its roundings is returned. A start that runs into a linear
/// system it cannot solve to the tolerance is dropped
/// ([`StructureReport::failed_starts`]). Every start streams its records
/// to `observer` as they happen ([`IterationRecord::start`] tells them
/// apart), so the observer sees the starts' records interleaved; its
/// `finish` runs once, after the last start. The starts stop early once
/// `cancel` is set.
#[allow(clippy::too_many_arguments)]
pub fn optimise_structure(
    game: &Posg,
    dra: &Dra,
    negated: Option<&Dra>,
    structure: &Structure,
    settings: &Settings,
    stream: u64,
    observer: &mut (dyn Observer + Send),
    cancel: &Cancel,
) -> Result<StructureOutcome, OptimiseError> {
    settings.validate()?;
    let belief = UpperBoundsOnce::new(game, dra, settings.solver_settings());
    let run = StructuresRun::new(
        (game, dra, negated),
        (settings, cancel),
        search_stream(stream),
        &belief,
    );
    let presolved = run.presolve(structure, observer)?;
    run.race(structure, stream, observer, (presolved, None))
}

/// The random stream of the local search before the race of the structure
/// with random stream `stream` (`stream + (2^32 - 1) 2^32`, apart from its
/// starts'); [`optimise_structures`] gives every structure the first's.
fn search_stream(stream: u64) -> u64 {
    stream.wrapping_add(u64::from(u32::MAX) << 32)
}

/// What the structures of one run share: the game, the automata of phi and
/// (with a certifier) of !phi, the settings, the cancellation, when the
/// run began, the memo and random stream of the local searches before
/// the races ([`search_supports`]), the belief bound, and its value where
/// it was explored before the run (the SAT source's).
struct StructuresRun<'a> {
    game: &'a Posg,
    dra: &'a Dra,
    negated: Option<&'a Dra>,
    settings: &'a Settings,
    cancel: &'a Cancel,
    started: Instant,
    memo: local_search::SearchMemo,
    search_stream: u64,
    belief: &'a UpperBoundsOnce<'a>,
    belief_before: Option<f64>,
}

/// The local search before a structure's race ([`search_supports`]): its
/// end point, if it ran, and its seconds.
struct Presolved {
    climbed: Option<local_search::Climbed>,
    phases: PhaseSeconds,
}

impl<'a> StructuresRun<'a> {
    /// A run on `game` with the automata of phi and (with a certifier)
    /// of !phi, beginning now, nothing searched yet, its searches on
    /// random stream `search_stream`, its belief bound `belief` (of
    /// `game` and `dra`).
    fn new(
        (game, dra, negated): (&'a Posg, &'a Dra, Option<&'a Dra>),
        (settings, cancel): (&'a Settings, &'a Cancel),
        search_stream: u64,
        belief: &'a UpperBoundsOnce<'a>,
    ) -> Self {
        debug_assert!(belief.is_of(game, dra), "the belief bound of another game");
        Self {
            game,
            dra,
            negated,
            settings,
            cancel,
            started: Instant::now(),
            memo: local_search::SearchMemo::default(),
            search_stream,
            belief,
            // Read once, here: a structure's `finalise` may explore it while
            // another structure's race is set up.
            belief_before: belief.known().flatten().map(|b| b.value),
        }
    }

    /// The single-player ascent where the adversary has one action and
    /// the settings ask for it, else the max-min loop.
    fn method(&self) -> Method {
        if self.settings.single_player_ascent && self.game.adversary().num_actions() == 1 {
            Method::Ascent
        } else {
            Method::MaxMin
        }
    }

    /// The certifier, where there is an automaton for !phi.
    fn certifier(&self) -> Option<Certifier<'_>> {
        self.negated.map(|not_phi| Certifier {
            game: self.game,
            phi: self.dra,
            not_phi,
            solver: self.settings.solver_settings(),
        })
    }

    /// The local search on the supports before `structure`'s race, where
    /// the max-min loop runs with a certifier, rounding and the search,
    /// unless the run is cancelled; `observer` gets its end point as it
    /// ends.
    fn presolve(
        &self,
        structure: &Structure,
        observer: &mut (dyn Observer + Send),
    ) -> Result<Presolved, OptimiseError> {
        let settings = self.settings;
        let clock = Instant::now();
        let search = self
            .certifier()
            .filter(|_| self.method() == Method::MaxMin && settings.round && settings.local_search)
            .filter(|_| !self.cancel.is_cancelled());
        let climbed = match search {
            Some(c) => {
                observer.phase(&Phase::LocalSearch);
                search_supports(c, structure, self)?
            }
            None => None,
        };
        // The search's seconds; where it was asked but not run, those of
        // the bounds that showed it had nothing to find are certification.
        let seconds = clock.elapsed().as_secs_f64();
        let searched = climbed.is_some();
        let phases = PhaseSeconds {
            local_search: if searched { seconds } else { 0.0 },
            certification: if search.is_some() && !searched {
                seconds
            } else {
                0.0
            },
            ..PhaseSeconds::default()
        };
        if let Some(climbed) = &climbed {
            observer.searched(&SearchRecord {
                seconds: self.started.elapsed().as_secs_f64(),
                certified_lower: climbed.bound,
            });
        }
        Ok(Presolved { climbed, phases })
    }

    /// `structure`'s race after its search `presolved`, with random stream
    /// `stream` ([`optimise_structure`]); `proved` is the best certified
    /// lower bound the searches of the other structures proved, which the
    /// race's floor includes.
    fn race(
        &self,
        structure: &Structure,
        stream: u64,
        observer: &mut (dyn Observer + Send),
        (presolved, proved): (Presolved, Option<f64>),
    ) -> Result<StructureOutcome, OptimiseError> {
        let StructuresRun {
            game,
            dra,
            settings,
            cancel,
            started: clock,
            ..
        } = *self;
        let method = self.method();
        let certifier = self.certifier();
        let Presolved {
            climbed: presolved,
            phases: presolve,
        } = presolved;
        observer.phase(&Phase::Race);
        let shared = Mutex::new(observer);
        let live = |start| Live {
            start,
            shared: &shared,
        };
        // A grown run's warm start (the last, `settings.starts`) takes the
        // first start's steps whatever its index.
        let start = |start: usize| Start {
            settings: settings.for_start(if start < settings.starts { start } else { 0 }),
            stream: stream + ((start as u64) << 32),
        };
        // The single-player ascent is certified once, at the end (`finalise`):
        // its checks' value is exact already.
        let run_certifier = certifier.filter(|_| method == Method::MaxMin);
        let floor = (presolved.as_ref().map(|climbed| climbed.bound))
            .into_iter()
            .chain(proved)
            .reduce(f64::max);
        // A single player's upper bound before its race (its ceiling): the
        // fully informed optimum, or the belief bound where the SAT source
        // explored it and it is lower.
        let clock_ceiling = Instant::now();
        let informed = match (method, certifier) {
            (Method::Ascent, Some(_)) => {
                Some(self.belief.informed_or_trivial(&structure.adversary)?)
            }
            _ => None,
        };
        let ceiling = informed.map(|u| self.belief_before.map_or(u, |b| b.min(u)));
        let ceiling_seconds = clock_ceiling.elapsed().as_secs_f64();
        let warm = structure.warm.as_ref().map(|defender| Structure {
            defender: defender.clone(),
            warm: None,
            ..structure.clone()
        });
        // A grown run's warm start races beside the starts a run of this
        // size alone would race (the same streams), as one more start.
        let starts = settings.starts + usize::from(warm.is_some());
        let racers = (0..starts)
            .into_par_iter()
            .map(|i| {
                let begins = warm.as_ref().filter(|_| i == settings.starts);
                let begins = begins.unwrap_or(structure);
                let optimiser =
                    start_optimiser((game, dra), (method, run_certifier), begins, &start(i))?;
                Racer::new(
                    optimiser.with_cancel(cancel).with_floor(floor),
                    live(i),
                    clock,
                )
            })
            .collect();
        let mut finished = race(racers, settings, (floor, ceiling));
        if run_certifier.is_none() {
            let fresh = || structure_objective(game, dra, structure, settings);
            settle(&mut finished, clock, &fresh)?;
        }
        let runs = finished
            .into_iter()
            .map(|result| {
                let (optimiser, outcome) = result?;
                let (objective, rng) = optimiser.into_parts();
                Ok(StartRun {
                    outcome,
                    objective,
                    rng,
                })
            })
            .collect::<Vec<_>>();
        let observer = shared.into_inner().unwrap_or_else(PoisonError::into_inner);
        let (runs, failed_starts) = keep_solved(runs)?;
        let (indices, mut runs): (Vec<usize>, Vec<StartRun>) = runs.into_iter().unzip();
        let starts: Vec<StartReport> = runs
            .iter()
            .zip(&indices)
            .map(|(run, &start)| StartReport {
                start,
                stream: stream + ((start as u64) << 32),
                worst_case: run.outcome.best.worst_case,
                certified_lower: run.outcome.best.certified_lower,
                iterations: run.outcome.iterations,
                status: run.outcome.status,
                seconds: run.outcome.seconds,
                logit_bound: run.outcome.logit_bound,
            })
            .collect();
        let best_start = (0..runs.len())
            .reduce(|b, i| {
                if ranks_above(&runs[i].outcome, &runs[b].outcome) {
                    i
                } else {
                    b
                }
            })
            .ok_or(OptimiseError::Settings {
                field: "starts",
                problem: "must be at least 1".into(),
            })?;
        let mut phases = presolve;
        phases.certification += ceiling_seconds;
        for run in &runs {
            phases.add(&run.outcome.phases);
        }
        let upper_bound = runs
            .iter()
            .filter_map(|r| r.outcome.upper_bound)
            .reduce(f64::min);
        let mut run = runs.swap_remove(best_start);
        observer.phase(&Phase::Finishing {
            race: run.outcome.status.explained(settings),
        });
        let chosen = finalise(
            game,
            dra,
            certifier,
            &mut run,
            (upper_bound, presolved, informed),
            settings,
            (method, clock, &self.memo, self.belief, self.cancel),
            &mut phases,
        )?;
        observer.observe(&returned_record(
            &chosen,
            &run.outcome,
            indices[best_start],
            clock.elapsed().as_secs_f64(),
        ));
        observer.finish().map_err(OptimiseError::Observer)?;
        // Whichever candidate closed it, a closed bracket is why the run ended.
        let status = if chosen.bracket_closed(settings) {
            Status::GapClosed
        } else {
            run.outcome.status
        };
        let objective = &run.objective;
        let outcome = &run.outcome;
        Ok(StructureOutcome {
            report: StructureReport {
                name: structure.name.clone(),
                gmc: objective.gmc_size(),
                defender_parameters: objective.defender().num_parameters(),
                adversary_parameters: objective.adversary().num_parameters(),
                seed: settings.seed,
                worst_case: chosen.worst_case,
                best_iteration: outcome.best.iteration,
                last_value: outcome.last_value,
                error_bound: objective.largest_error_bound(),
                iterations: outcome.iterations,
                checks: outcome.checks,
                status,
                seconds: clock.elapsed().as_secs_f64(),
                certified_lower: chosen.certified_lower,
                upper_bound: chosen.upper_bound,
                belief_bound: chosen.belief_bound,
                method,
                rounding: chosen.name,
                candidates: chosen.candidates,
                starts,
                best_start: indices[best_start],
                failed_starts: failed_starts
                    .into_iter()
                    .map(|(start, error)| format!("start {start}: {error}"))
                    .collect(),
                logit_bound: outcome.logit_bound,
                max_residual: outcome.max_residual,
                phases,
            },
            defender: chosen.defender,
            adversary: chosen.adversary,
        })
    }
}

/// The record of the defender a structure's run returns ([`IterationRecord::returned`]):
/// `chosen`, after the kept start `start`'s `outcome`, `seconds` into the run.
fn returned_record(
    chosen: &Chosen,
    outcome: &RunOutcome,
    start: usize,
    seconds: f64,
) -> IterationRecord {
    let source = match chosen.name.as_str() {
        "unrounded" => RecordSource::Gradient,
        "local-search" => RecordSource::LocalSearch,
        _ => RecordSource::Rounding,
    };
    IterationRecord {
        start,
        iteration: outcome.iterations,
        seconds,
        value: chosen.worst_case,
        defender_gradient_norm: 0.0,
        adversary_gradient_norm: 0.0,
        defender_step: 0.0,
        adversary_step: 0.0,
        worst_case: Some(chosen.worst_case),
        certified_lower: chosen.certified_lower,
        upper_bound: chosen
            .upper_bound
            .filter(|_| chosen.certified_lower.is_some()),
        logit_bound: outcome.logit_bound,
        source,
        returned: true,
    }
}

/// The full best responses ([`Optimiser::settle`]) of every finished
/// max-min start without a certifier: the score is then the worst case
/// itself, which settling can lower, and ranks the starts. (With a
/// certifier only the returned defender gets one, in [`finalise`].)
/// `started` is when the structure's run began; `fresh` builds the
/// structure's objective for each of a best response's parallel starts.
fn settle(
    finished: &mut [Result<(Optimiser<'_>, RunOutcome), OptimiseError>],
    started: Instant,
    fresh: &FreshObjective<'_>,
) -> Result<(), OptimiseError> {
    finished.par_iter_mut().try_for_each(|result| match result {
        Ok((optimiser, outcome)) => optimiser.settle(outcome, started, fresh),
        Err(_) => Ok(()),
    })
}

/// The local search on the supports (`local_search.rs`) before the
/// max-min race: from the argmax rounding of the structure's defender (and
/// of its warm start, where it has one) and
/// `local_search_restarts` seeded random memoryless ones, on the run's
/// search stream ([`search_stream`]), sharing the run's memo, each climb
/// bounded by `local_search_work` and, with a time budget, by
/// [`Settings::search_deadline`] of the run (a quarter of the budget);
/// the restarts and kicks end once
/// a climb is within `gap_tolerance` of the upper bound against the
/// structure's starting adversary. Its end point's
/// bound is the race's floor ([`race`]; the best over the structures) and
/// the end point a candidate of the final rounding. `None` where the
/// search's start already certifies within `gap_tolerance` of that upper bound (the race
/// ends at its first check; on PAYNT's pursuit-evasion only randomised
/// defenders win, and the search cost 17 s there).
fn search_supports(
    certifier: Certifier<'_>,
    structure: &Structure,
    run: &StructuresRun<'_>,
) -> Result<Option<local_search::Climbed>, OptimiseError> {
    let settings = run.settings;
    let from = structure.warm.as_ref().unwrap_or(&structure.defender);
    let upper = certifier.upper_or_trivial(&structure.adversary)?;
    let lower = certifier.lower_or_trivial(from)?;
    if settings.gap_closed(lower, upper) {
        return Ok(None);
    }
    // A grown run's search also climbs from where the search of a run of
    // this size alone would start.
    let fresh = structure.warm.as_ref().map(|_| &structure.defender);
    let starts = std::iter::once(from).chain(fresh);
    let starts =
        (starts.map(|d| rounding::truncated(d, f64::INFINITY))).collect::<Result<Vec<_>, _>>()?;
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    rng.set_stream(run.search_stream);
    Ok(Some(local_search::climb_with_restarts(
        certifier,
        &starts,
        settings.local_search_restarts,
        &mut rng,
        local_search::Effort {
            work: settings.local_search_work,
            deadline: settings.search_deadline(run.started),
            enough: upper - settings.gap_tolerance,
            cancel: Some(run.cancel),
        },
        &run.memo,
    )?))
}

/// Whether start outcome `a` is kept before `b`: a start that closed the
/// certified gap first (its argmax rounding, which the final rounding
/// recovers, may certify more than its incumbent's logits), then the
/// higher score.
fn ranks_above(a: &RunOutcome, b: &RunOutcome) -> bool {
    let closed = |o: &RunOutcome| o.status == Status::GapClosed;
    (closed(a), a.best.score()) > (closed(b), b.best.score())
}

/// One start's run and the objective it ran on.
struct StartRun {
    outcome: RunOutcome,
    objective: Objective,
    rng: ChaCha8Rng,
}

/// One start's view of the structure's observer: each record, marked with
/// the start's index, goes to the shared observer as it happens.
struct Live<'a, 'o> {
    start: usize,
    shared: &'a Mutex<&'o mut (dyn Observer + Send)>,
}

impl Observer for Live<'_, '_> {
    fn observe(&mut self, record: &IterationRecord) {
        let record = IterationRecord {
            start: self.start,
            ..*record
        };
        self.shared
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .observe(&record);
    }
}

/// One start's settings ([`Settings::for_start`]) and random stream.
struct Start {
    settings: Settings,
    stream: u64,
}

/// Builds a structure's objective afresh (a GMC and its solver of its
/// own), for work that runs beside the objective a start holds.
pub(crate) type FreshObjective<'a> = dyn Fn() -> Result<Objective, OptimiseError> + Sync + 'a;

/// The objective on `structure`: the value of its defender and adversary
/// softmax maps with `settings`' solver.
fn structure_objective(
    game: &Posg,
    dra: &Dra,
    structure: &Structure,
    settings: &Settings,
) -> Result<Objective, OptimiseError> {
    let defender = Softmax::new(&structure.defender, settings.optimise_initial);
    let adversary = Softmax::new(&structure.adversary, settings.optimise_initial);
    Ok(Objective::new(
        game,
        dra,
        defender,
        adversary,
        &settings.solver_settings(),
    )?)
}

/// A start's objective on `structure` and its seeded random stream.
fn start_objective(
    game: &Posg,
    dra: &Dra,
    structure: &Structure,
    start: &Start,
) -> Result<(Objective, ChaCha8Rng), OptimiseError> {
    let objective = structure_objective(game, dra, structure, &start.settings)?;
    let mut rng = ChaCha8Rng::seed_from_u64(start.settings.seed);
    rng.set_stream(start.stream);
    Ok((objective, rng))
}

/// One start, ready to race: its optimiser (running `method`) on its own
/// objective and random stream, certifying with `certifier` when given.
fn start_optimiser<'a>(
    (game, dra): (&Posg, &Dra),
    (method, certifier): (Method, Option<Certifier<'a>>),
    structure: &Structure,
    start: &Start,
) -> Result<Optimiser<'a>, OptimiseError> {
    let (objective, rng) = start_objective(game, dra, structure, start)?;
    let optimiser = Optimiser::new(method, objective, &start.settings, rng);
    Ok(match certifier {
        Some(certifier) => optimiser.with_certifier(certifier),
        None => optimiser,
    })
}

/// The defender a structure's run returns, after rounding, with its numbers.
struct Chosen {
    name: String,
    defender: Fsc,
    adversary: Fsc,
    worst_case: f64,
    certified_lower: Option<f64>,
    upper_bound: Option<f64>,
    /// The belief bound, where it was computed.
    belief_bound: Option<BeliefBound>,
    candidates: Vec<CandidateReport>,
    /// The score the defender was chosen by.
    score: f64,
    /// Whether `worst_case` is the defender's own (else it still needs a
    /// best response).
    worst_case_known: bool,
}

impl Chosen {
    /// Whether the chosen defender's score closes the certified gap to the
    /// upper bound ([`Settings::gap_closed`]).
    fn bracket_closed(&self, settings: &Settings) -> bool {
        self.upper_bound
            .is_some_and(|upper| settings.gap_closed(self.score, upper))
    }

    /// Records the candidate `name` with its score (and best response, if
    /// `judge` computed one) and takes it when it scores higher than the
    /// chosen defender.
    fn consider(&mut self, name: String, candidate: Fsc, scored: Scored, judge: &Judge<'_>) {
        let (score, found) = scored;
        self.candidates.push(CandidateReport {
            name: name.clone(),
            score,
        });
        if score <= self.score {
            return;
        }
        self.score = score;
        self.name = name;
        self.defender = candidate;
        match found {
            Some((worst_case, adversary)) => {
                self.worst_case = worst_case;
                self.adversary = adversary;
                self.worst_case_known = true;
            }
            None if judge.method == Method::Ascent => {
                self.worst_case = score;
                self.worst_case_known = true;
            }
            None => self.worst_case_known = false,
        }
        self.certified_lower = judge
            .certifier
            .filter(|_| judge.method == Method::MaxMin)
            .map(|_| score);
    }
}

/// A candidate's score, and its best response (value and adversary) when
/// the score is one.
type Scored = (f64, Option<(f64, Fsc)>);

/// Scores the rounded candidates of the run's best defender like the run
/// scored its candidates (single player: the exact value; else the
/// certified lower bound with a certifier, the worst-case estimate
/// without), keeps the best (the unrounded defender wins ties), and
/// completes its numbers: worst-case estimate, certified lower bound and
/// the smallest game upper bound (`informed`: a single player's fully
/// informed bound, with a certifier, which the race's ceiling computed).
/// Its best
/// responses end at the [`Settings::final_deadline`] of the run, begun at
/// `started`; its local search shares the run's `memo` and ends when
/// `cancel` is set; a single player's belief bound comes from the run's
/// `belief`.
#[allow(clippy::too_many_arguments)]
fn finalise(
    game: &Posg,
    dra: &Dra,
    certifier: Option<Certifier<'_>>,
    run: &mut StartRun,
    (upper_bound, presolved, informed): (Option<f64>, Option<local_search::Climbed>, Option<f64>),
    settings: &Settings,
    (method, started, memo, belief, cancel): (
        Method,
        Instant,
        &local_search::SearchMemo,
        &UpperBoundsOnce<'_>,
        &Cancel,
    ),
    phases: &mut PhaseSeconds,
) -> Result<Chosen, OptimiseError> {
    let best = &run.outcome.best;
    let objective = &run.objective;
    let mut warm = vec![best.adversary.clone()];
    warm.extend(run.outcome.last_response.clone());
    let mut chosen = Chosen {
        name: "unrounded".into(),
        defender: objective.defender().controller(&best.defender)?,
        adversary: objective.adversary().controller(&best.adversary)?,
        worst_case: best.worst_case,
        certified_lower: best.certified_lower,
        upper_bound,
        belief_bound: None,
        candidates: vec![CandidateReport {
            name: "unrounded".into(),
            score: best.score(),
        }],
        score: best.score(),
        // The single-player value is exact, and without a certifier every
        // start was settled; a max-min run with a certifier settles the
        // returned defender below.
        worst_case_known: method == Method::Ascent || certifier.is_none(),
    };
    let judge = Judge {
        game,
        dra,
        adversary: objective.adversary().template(),
        warm: &warm,
        gmc_states: objective.gmc_size().states,
        settings,
        deadline: settings.final_deadline(started, Instant::now()),
        method,
        certifier,
    };
    if let Some(informed) = informed {
        // The single player's upper bound (its fully informed value, then,
        // where that leaves the bracket open, the belief bound of a POMDP)
        // first: where the run's value or a rounding already meets it, the
        // local search has nothing to find, and where it runs it stops
        // there.
        let clock = Instant::now();
        chosen.upper_bound = Some(informed);
        if !chosen.bracket_closed(settings) {
            chosen.belief_bound = belief.get()?;
            if let Some(belief) = chosen.belief_bound {
                optimiser::tighten(&mut chosen.upper_bound, belief.value);
            }
        }
        phases.certification += clock.elapsed().as_secs_f64();
    }
    let clock = Instant::now();
    let mut climb_seconds = 0.0;
    if settings.round {
        // The rounded candidates and the end point of the search before
        // the race, then the local search from the best of them (with a
        // certifier; with restarts unless they ran before the race), scored
        // alike.
        let mut candidates = rounded_candidates(&chosen.defender)?;
        let restarts = match &presolved {
            Some(_) => 0,
            None => settings.local_search_restarts,
        };
        let searched = presolved.map(|climbed| climbed.defender);
        candidates.extend(searched.clone().map(|d| ("local-search".to_string(), d)));
        let mut search = certifier.filter(|_| settings.local_search);
        while !candidates.is_empty() {
            for (name, candidate, scored) in
                judge.score_all(std::mem::take(&mut candidates), &mut run.rng)?
            {
                chosen.consider(name, candidate, scored, &judge);
            }
            // A bracket already closed leaves the search nothing to find,
            // and a climb's end point is where it would end again.
            let open =
                !chosen.bracket_closed(settings) && searched.as_ref() != Some(&chosen.defender);
            if let Some(c) = search.take().filter(|_| open) {
                let climbing = Instant::now();
                let found = local_search::climb_with_restarts(
                    c,
                    std::slice::from_ref(&chosen.defender),
                    restarts,
                    &mut run.rng,
                    local_search::Effort {
                        work: settings.local_search_work,
                        deadline: settings.final_deadline(started, Instant::now()),
                        enough: chosen
                            .upper_bound
                            .map_or(f64::INFINITY, |u| u - settings.gap_tolerance),
                        cancel: Some(cancel),
                    },
                    memo,
                )?
                .defender;
                climb_seconds += climbing.elapsed().as_secs_f64();
                if found != chosen.defender {
                    candidates.push(("local-search".into(), found));
                }
            }
        }
    }
    phases.rounding += clock.elapsed().as_secs_f64() - climb_seconds;
    phases.local_search += climb_seconds;
    if !chosen.worst_case_known {
        let clock = Instant::now();
        let responded = settle_chosen(&mut chosen, &judge, &mut run.rng)?;
        phases.best_responses += clock.elapsed().as_secs_f64();
        if let (true, Some(c)) = (responded, certifier) {
            let clock = Instant::now();
            let upper = c.upper_or_trivial(&chosen.adversary)?;
            optimiser::tighten(&mut chosen.upper_bound, upper);
            phases.certification += clock.elapsed().as_secs_f64();
        }
    }
    if let (Method::Ascent, Some(c)) = (method, certifier) {
        let clock = Instant::now();
        chosen.certified_lower = match c.lower(&chosen.defender) {
            Ok(bound) => {
                if let Some(belief) = &chosen.belief_bound {
                    check_below_belief(&bound, belief)?;
                }
                Some(bound.value)
            }
            Err(error) if error.is_numerical() => None,
            Err(error) => return Err(error.into()),
        };
        phases.certification += clock.elapsed().as_secs_f64();
    }
    Ok(chosen)
}

/// The returned defender's full best response (its worst-case estimate,
/// method.md section 4): from the run's adversaries and, unless the
/// certified gap is closed, `restarts` random starts, in parallel; `false`
/// where every start runs into a GMC too stiff to solve. Then the unrounded
/// defender keeps the estimate the run gave it, and a rounded one gets its
/// certified lower bound (the worst case is at least that).
fn settle_chosen(
    chosen: &mut Chosen,
    judge: &Judge<'_>,
    rng: &mut ChaCha8Rng,
) -> Result<bool, OptimiseError> {
    let restarts = judge
        .settings
        .final_restarts(chosen.bracket_closed(judge.settings));
    match judge.best_response(&chosen.defender, restarts, rng) {
        Ok((worst_case, adversary)) => {
            chosen.worst_case = worst_case;
            chosen.adversary = adversary;
            Ok(true)
        }
        Err(error) if error.is_numerical() => {
            if chosen.name != "unrounded" {
                chosen.worst_case = chosen.score;
            }
            Ok(false)
        }
        Err(error) => Err(error),
    }
}

/// Evaluates candidate defenders (with their own supports) against the
/// structure's adversary support.
struct Judge<'a> {
    game: &'a Posg,
    dra: &'a Dra,
    adversary: &'a Fsc,
    /// The run's adversaries (the best defender's, the last best response
    /// found): the first is what candidates are valued against, all of
    /// them warm-start best responses.
    warm: &'a [Vec<f64>],
    /// The states of the structure's GMC (a candidate's own is at most
    /// that), by which a final best response's iterations are capped.
    gmc_states: usize,
    settings: &'a Settings,
    /// When its best responses end (with a time budget).
    deadline: Option<Instant>,
    method: Method,
    certifier: Option<Certifier<'a>>,
}

impl Judge<'_> {
    /// A candidate's score as the run scored its candidates (single player:
    /// the exact value; else the certified lower bound with a certifier,
    /// the best-response value without); `None` when the candidate's GMC is
    /// too stiff to evaluate.
    fn score(
        &self,
        candidate: &Fsc,
        rng: &mut ChaCha8Rng,
    ) -> Result<Option<Scored>, OptimiseError> {
        let scored = match (self.method, self.certifier) {
            (Method::Ascent, _) => self.value(candidate).map(|v| (v, None)),
            (Method::MaxMin, Some(c)) => c
                .lower_or_trivial(candidate)
                .map(|v| (v, None))
                .map_err(OptimiseError::from),
            (Method::MaxMin, None) => self
                .best_response(candidate, self.settings.restarts, rng)
                .map(|found| (found.0, Some(found))),
        };
        match scored {
            Ok(scored) => Ok(Some(scored)),
            Err(OptimiseError::Value(ValueError::Solver(_))) => Ok(None),
            Err(error) => Err(error),
        }
    }

    /// The scores of `candidates` ([`Self::score`]) in parallel (rayon),
    /// each with its own random stream seeded from `rng` in order, and in
    /// their order; those too stiff to evaluate are left out.
    fn score_all(
        &self,
        candidates: Vec<(String, Fsc)>,
        rng: &mut ChaCha8Rng,
    ) -> Result<Vec<(String, Fsc, Scored)>, OptimiseError> {
        let streams: Vec<u64> = candidates.iter().map(|_| rng.random()).collect();
        let scored = candidates
            .into_par_iter()
            .zip(streams)
            .map(|((name, candidate), stream)| {
                let scored = self.score(&candidate, &mut ChaCha8Rng::seed_from_u64(stream))?;
                Ok(scored.map(|scored| (name, candidate, scored)))
            })
            .collect::<Result<Vec<_>, OptimiseError>>()?;
        Ok(scored.into_iter().flatten().collect())
    }

    /// The exact value against the adversary with the run's logits.
    fn value(&self, defender: &Fsc) -> Result<f64, OptimiseError> {
        let mut objective = self.objective(defender)?;
        let logits = objective
            .defender()
            .logits_of_template(self.settings.logit_bound);
        Ok(objective.value(&logits, &self.warm[0])?)
    }

    /// The final best-response value ([`final_best_response`], started
    /// from the run's adversaries and `restarts` random ones) and the
    /// adversary reaching it.
    fn best_response(
        &self,
        defender: &Fsc,
        restarts: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<(f64, Fsc), OptimiseError> {
        let logits = Softmax::new(defender, self.settings.optimise_initial)
            .logits_of_template(self.settings.logit_bound);
        let at: Vec<&[f64]> = self.warm.iter().map(Vec::as_slice).collect();
        let found = final_best_response(
            || self.objective(defender),
            self.gmc_states,
            &logits,
            Starts::new(&at, restarts).until(self.deadline),
            self.settings,
            rng,
        )?;
        let adversary = Softmax::new(self.adversary, self.settings.optimise_initial);
        Ok((found.value, adversary.controller(&found.adversary)?))
    }

    fn objective(&self, defender: &Fsc) -> Result<Objective, OptimiseError> {
        Ok(Objective::new(
            self.game,
            self.dra,
            Softmax::new(defender, self.settings.optimise_initial),
            Softmax::new(self.adversary, self.settings.optimise_initial),
            &self.settings.solver_settings(),
        )?)
    }
}
