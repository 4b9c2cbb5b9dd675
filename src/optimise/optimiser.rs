//! The driver of every optimisation run (method.md section 4), in argmin's
//! shape: a [`Solver`] takes one outer iteration, either alternating
//! projected gradient ascent-descent (`GradientPlay`, `play.rs`, the
//! max-min loop) or, where the adversary cannot influence the game, an
//! L-BFGS step of the defender (`Ascent`, `ascent.rs`); the [`Optimiser`]
//! (the executor) runs it and owns everything between iterations: the
//! stopping rules, the schedule of best-response checks and their
//! certification, the logit bound's widening, the bookkeeping of the best
//! defender seen, and the [`Observer`], which it alone calls (once per
//! iteration).
//!
//! After iteration `t` (the adversary has responded to `phi_def(t)`):
//!
//! 1. the run is due to stop at `max_iterations` or the time budget;
//! 2. a best-response check (`optimiser/check.rs`) runs at `(phi_def(t), phi_adv(t))`
//!    when `t` is a multiple of `check_every` or the run stops;
//! 3. the observer sees iteration `t`'s record;
//! 4. unless the run stops, the solver's next iteration begins with the
//!    defender's step `phi_def(t+1)`.
//!
//! The single-player solver's checks need no best response (the value
//! is the worst case), rank the current defender only (its iterates do not
//! cycle) and start at the widest logit bound (its coordinates keep it
//! inside); a run stops as [`Status::Converged`] when the solver finds no
//! ascent step. Everything else is the same for both solvers.
//!
//! Alternating gradient play cycles around the saddle of bilinear games
//! such as matching pennies; what converges is the *best defender seen*,
//! helped by the fast adversary time scale and the decaying defender steps.
//! Each check ranks two candidates: the current defender and the suffix
//! average of its probabilities (the average over iterations `2^k..=t`,
//! `2^k <= t` the last power of two; the average of cycling play approaches
//! the saddle point where the iterates circle it). A candidate's score is
//! its certified lower bound when an automaton for !phi is given (method.md
//! section 6), else its best-response value; the result is the
//! best-scoring candidate seen, not the last iterate.
//!
//! Stopping and the logit bound: the run stops when the certified gap
//! (smallest game upper bound minus the best certified lower bound) is at
//! most `gap_tolerance`, or when the best score has gained at most
//! `stall_gain` (relative) over the second half of its checks, once there
//! are `stall_checks` of them ([`stalled`]; with the guarantee ascent, the
//! window's start is ascended too where its raw score would not make the
//! window a stall: [`Optimiser::ascend_window_start`]). A stall while some logit
//! sits on the bound `c` and `c < logit_bound` does not stop the run: `c`
//! doubles (capped at `logit_bound`) and the stall count restarts. So `c`
//! starts small (`initial_logit_bound`, where the softmax is far from
//! saturated and gradients are informative) and widens only where
//! determinism pays, while every supported choice keeps probability at least
//! `exp(-2 logit_bound) / |block|`: the support, and the GMC graph, never
//! change. A start of a race that has a floor (a bound the local search
//! proved before it) is probed against it early and at each window end
//! after ([`FLOOR_PROBE_CHECKS`]), and stops as outpaced where even a
//! short guarantee ascent cannot beat it.

mod check;

pub(super) use check::tighten;

use std::time::Instant;

use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::ascent::Ascent;
use super::objective::Objective;
use super::observer::{IterationRecord, Observer, RecordSource};
use super::play::{GradientPlay, perturbed};
use super::solver::{Iterate, PlayState, Solver, norm};
use super::stopping::{STALL_MAGNITUDE_FLOOR, budget_spent, stalled, window_ends};
use super::{Cancel, Method, OptimiseError, Settings, Status};
use crate::automaton::Dra;
use crate::certify::gradient::LowerBoundGradients;
use crate::certify::{self, CertifyError};
use crate::controller::Fsc;
use crate::game::Posg;
use crate::solver::SolverSettings;
use check::{Check, SuffixAverage};

/// The driver of an optimisation run on one structure: the method (which
/// solver it drives), the objective, the random stream of the
/// best-response checks, the certifier and the iterate `(phi_def, phi_adv)`
/// it starts from (and ends at).
pub struct Optimiser<'a> {
    method: Method,
    objective: Objective,
    certifier: Option<Certifier<'a>>,
    /// The certifier's lower bounds of the structure's defenders, one
    /// support, so one graph analysis for the whole run.
    lower_bounds: Option<LowerBoundGradients<'a>>,
    cancel: Cancel,
    settings: Settings,
    rng: ChaCha8Rng,
    defender: Vec<f64>,
    adversary: Vec<f64>,
    /// A certified lower bound proved outside the run (the local search's,
    /// before the race), which the floor probe judges the start against.
    floor: Option<f64>,
}

/// The best defender seen and its best response.
#[derive(Debug, Clone, PartialEq)]
pub struct Incumbent {
    /// The defender's logits.
    pub defender: Vec<f64>,
    /// The best response found to it.
    pub adversary: Vec<f64>,
    /// Its worst-case estimate (the best-response value).
    pub worst_case: f64,
    /// Its certified lower bound, when an automaton for !phi was given.
    pub certified_lower: Option<f64>,
    /// The iteration it was seen at.
    pub iteration: usize,
}

impl Incumbent {
    /// What candidates are ranked by: the certified lower bound when there
    /// is one, else the worst-case estimate.
    pub fn score(&self) -> f64 {
        self.certified_lower.unwrap_or(self.worst_case)
    }
}

/// Seconds spent in each phase of a run (summed over parallel starts in a
/// structure's report: thread seconds, not wall-clock seconds).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PhaseSeconds {
    /// Gradient steps: value and gradient evaluations and updates.
    pub optimisation: f64,
    /// Best-response checks (L-BFGS against the defender).
    pub best_responses: f64,
    /// Certified bounds (method.md section 6).
    pub certification: f64,
    /// Evaluating the rounded candidates at the end.
    pub rounding: f64,
    /// The guarantee ascent at the end (method.md section 6).
    pub guarantee: f64,
    /// The local search on the supports, before the race and after the
    /// rounding (method.md section 6; wall seconds of its parallel climbs).
    pub local_search: f64,
}

impl PhaseSeconds {
    /// The phase-by-phase sum.
    pub fn add(&mut self, other: &PhaseSeconds) {
        self.optimisation += other.optimisation;
        self.best_responses += other.best_responses;
        self.certification += other.certification;
        self.rounding += other.rounding;
        self.guarantee += other.guarantee;
        self.local_search += other.local_search;
    }
}

/// What a run on one structure ends with.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutcome {
    /// The best defender by score ([`Incumbent::score`]).
    pub best: Incumbent,
    /// The smallest game upper bound over the best responses found (with an
    /// automaton for !phi).
    pub upper_bound: Option<f64>,
    /// The value at the last iterate.
    pub last_value: f64,
    /// Outer iterations run.
    pub iterations: usize,
    /// Best-response checks run.
    pub checks: usize,
    /// Why the run stopped.
    pub status: Status,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Seconds per phase.
    pub phases: PhaseSeconds,
    /// The logit bound `c` at the end.
    pub logit_bound: f64,
    /// The largest residual of any linear solve of the run.
    pub max_residual: f64,
    /// The adversary of the run's last L-BFGS best response (a warm start
    /// for [`Optimiser::settle`]).
    pub last_response: Option<Vec<f64>>,
}

/// What the best-response checks certify with (method.md section 6): the
/// game, deterministic automata for phi and !phi, and the run's linear
/// solver (so a chain beyond the LU's reach is certified by the method the
/// run was given).
#[derive(Debug, Clone, Copy)]
pub struct Certifier<'a> {
    /// The game.
    pub game: &'a Posg,
    /// An automaton for phi (for the game upper bound).
    pub phi: &'a Dra,
    /// An automaton for !phi (for the defender's certified lower bound).
    pub not_phi: &'a Dra,
    /// How the policy evaluations of the bounds are solved.
    pub solver: SolverSettings,
}

impl Certifier<'_> {
    /// The certified lower bound of `defender`, or the trivial 0 where it
    /// cannot be proved ([`certify::lower_value_or_trivial_within`]).
    pub fn lower_or_trivial(&self, defender: &Fsc) -> Result<f64, CertifyError> {
        certify::lower_value_or_trivial_within(self.game, self.not_phi, defender, &self.solver)
    }

    /// The game upper bound of `adversary`, or the trivial 1 where it
    /// cannot be proved ([`certify::upper_value_or_trivial_within`]).
    pub fn upper_or_trivial(&self, adversary: &Fsc) -> Result<f64, CertifyError> {
        certify::upper_value_or_trivial_within(self.game, self.phi, adversary, &self.solver)
    }

    /// The certified lower bound of `defender` ([`certify::lower_bound_within`]).
    pub fn lower(&self, defender: &Fsc) -> Result<certify::Bound, CertifyError> {
        certify::lower_bound_within(self.game, self.not_phi, defender, &self.solver)
    }
}

/// A max-min run in progress ([`Optimiser::begin`]), between the solver's
/// iterations: the solver, the books and the current state.
pub struct Run {
    solver: Box<dyn Solver>,
    books: Bookkeeping,
    /// `None` only after an iteration failed.
    state: Option<PlayState>,
    /// Whether the current state was checked and reported.
    judged: bool,
    clock: Instant,
}

impl Run {
    /// The best score so far (the best certified lower bound, or the best
    /// worst-case estimate without a certifier); `None` before the first
    /// check.
    pub fn best_score(&self) -> Option<f64> {
        self.books.best.as_ref().map(Incumbent::score)
    }

    /// The smallest game upper bound so far (with a certifier).
    pub fn upper_bound(&self) -> Option<f64> {
        self.books.upper_bound
    }

    /// The number of checks since the logit bound last widened.
    pub fn checks_since_widening(&self) -> usize {
        self.books.history.len()
    }
}

/// A logit `phi` presses on the bound `c` when `|phi| >= NEAR_BOUND * c`.
pub const NEAR_BOUND: f64 = 0.95;

/// A start is probed against the floor (the local search's certified
/// lower bound, proved before the race) at each window end after this
/// many checks where its best score, even repeating the window's gain,
/// is below the floor: a short guarantee ascent ([`FLOOR_PROBE_STEPS`])
/// runs from its incumbent, and the start stops as outpaced when the floor
/// still stays out of reach ([`Optimiser::sunk_below_floor`]). Otherwise
/// the probe puts the incumbent back (the caches of the bounds' policy
/// iteration and certificate keep what it computed). At 8 checks the
/// first probe comes at iteration 31 or 63 (every 5th iteration and the
/// window ends are checked), not at the stall rule's 255: on PAYNT's
/// dice-and-coin with 3 nodes the race ends at iteration 64, not 512, with
/// the same certified value. A start that passes a probe is probed again at the next window
/// end (twice as many iterations on): on attacker-one-defender with 1 node
/// one start passed the first probe and then crept below the floor until
/// the stall rule stopped it at iteration 512.
pub const FLOOR_PROBE_CHECKS: usize = 8;

/// The most L-BFGS steps of a probe's guarantee ascent. The probe asks
/// whether the start's basin can reach the floor, not where its peak is:
/// on attacker-one-defender with 3 nodes a full ascent took 56-114 steps
/// and about 1 s per start to climb from 0.009 to 0.016-0.020, against a
/// floor of 0.034. With 19 steps (and 39) every case of the time-to-quality
/// benchmark and PAYNT's models under 400 states certifies what it did
/// with full probe ascents.
pub const FLOOR_PROBE_STEPS: usize = 19;

/// A probe's ascent that ends within this relative distance of the floor
/// has climbed to the floor's own optimum (PAYNT's dice-and-coin2: every
/// start's ascent ends 3e-8 under the local search's bound).
pub const FLOOR_TIE: f64 = 1e-6;

/// What the driver keeps between iterations: the best defender seen, the
/// smallest game upper bound, the best score after each check since the
/// logit bound last widened, the suffix averages the checks rank, and the
/// counters.
struct Bookkeeping {
    best: Option<Incumbent>,
    upper_bound: Option<f64>,
    history: Vec<f64>,
    /// The best score at the end of each suffix-averaging window since the
    /// logit bound last widened.
    window_ends: Vec<f64>,
    /// The incumbent where the last window ended, when the guarantee
    /// ascent did not run there ([`Optimiser::ascend_window_start`]).
    unascended_window_start: Option<Incumbent>,
    defender_average: SuffixAverage,
    adversary_average: SuffixAverage,
    /// The adversary of the last L-BFGS best response (a warm start).
    last_response: Option<Vec<f64>>,
    /// When the checks tighten the game upper bound against the adversaries.
    upper_schedule: check::Backoff,
    /// The last argmax rounding certified, and its certified lower bound.
    last_rounding: Option<(Fsc, f64)>,
    /// When the checks certify a changed argmax rounding.
    rounding_schedule: check::Backoff,
    checks: usize,
    phases: PhaseSeconds,
}

impl Bookkeeping {
    /// Empty books for logits of these sizes; the upper bound's schedule
    /// backs off to at most `upper_interval` checks.
    fn new(defender_parameters: usize, adversary_parameters: usize, upper_interval: usize) -> Self {
        Self {
            best: None,
            upper_bound: None,
            history: Vec::new(),
            window_ends: Vec::new(),
            unascended_window_start: None,
            defender_average: SuffixAverage::new(defender_parameters),
            adversary_average: SuffixAverage::new(adversary_parameters),
            last_response: None,
            upper_schedule: check::Backoff::new(upper_interval),
            last_rounding: None,
            rounding_schedule: check::Backoff::new(check::ROUNDING_BACKOFF_CAP),
            checks: 0,
            phases: PhaseSeconds::default(),
        }
    }

    /// Adds the players' probabilities at iteration `t` to their suffix
    /// averages.
    fn average(&mut self, objective: &Objective, iterate: &Iterate) {
        let t = iterate.iteration;
        let defender = objective.defender().probabilities(&iterate.defender);
        self.defender_average.add(t, &defender.entries);
        let adversary = objective.adversary().probabilities(&iterate.adversary);
        self.adversary_average.add(t, &adversary.entries);
    }
}

impl<'a> Optimiser<'a> {
    /// Starts from the templates' logits plus noise uniform in
    /// `[-initial_spread, initial_spread]` drawn from `rng`, clipped to the
    /// starting logit bound: `c_0 = initial_logit_bound` for the max-min
    /// loop, `logit_bound` for the single-player ascent (whose adversary
    /// keeps its template's logits).
    pub fn new(
        method: Method,
        objective: Objective,
        settings: &Settings,
        mut rng: ChaCha8Rng,
    ) -> Self {
        let bound = starting_bound(method, settings);
        let defender = perturbed(
            objective.defender().logits_of_template(bound),
            settings.initial_spread,
            bound,
            &mut rng,
        );
        let adversary = match method {
            Method::MaxMin => perturbed(
                objective.adversary().logits_of_template(bound),
                settings.initial_spread,
                bound,
                &mut rng,
            ),
            Method::Ascent => objective.adversary().logits_of_template(bound),
        };
        Self {
            method,
            objective,
            certifier: None,
            lower_bounds: None,
            cancel: Cancel::new(),
            settings: settings.clone(),
            rng,
            defender,
            adversary,
            floor: None,
        }
    }

    /// Makes every best-response check also certify its candidates: they
    /// are then ranked by certified lower bound, and the run can stop on the
    /// certified gap.
    pub fn with_certifier(mut self, certifier: Certifier<'a>) -> Self {
        self.certifier = Some(certifier);
        self.lower_bounds = Some(LowerBoundGradients::new(
            certifier.game,
            certifier.not_phi,
            self.settings.solver_settings(),
        ));
        self
    }

    /// Makes the run stop ([`Status::Cancelled`]) at the first iteration
    /// after `cancel` is set.
    pub fn with_cancel(mut self, cancel: &Cancel) -> Self {
        self.cancel = cancel.clone();
        self
    }

    /// The run with `floor`, a certified lower bound proved for a
    /// defender outside the run (the best of the structures' local
    /// searches before the races).
    pub fn with_floor(mut self, floor: Option<f64>) -> Self {
        self.floor = floor;
        self
    }

    /// Whether the score `score`, after gaining `gain` over the window that
    /// ends here, stays below the floor even if it repeats that gain.
    fn below_floor(&self, score: f64, gain: f64) -> bool {
        self.floor.is_some_and(|floor| score + gain < floor)
    }

    /// The floor probe's verdict on a start whose guarantee ascent reached
    /// `ascended` where its own iterates gained `gain` over the window:
    /// sunk when even repeating that gain leaves it below the floor, or
    /// when the ascent ends on the floor itself (within [`FLOOR_TIE`],
    /// relative): it climbs to the optimum the local search has already
    /// proved.
    fn sunk_below_floor(&self, ascended: f64, gain: f64) -> bool {
        let ties = self.floor.is_some_and(|floor| {
            (ascended - floor).abs() <= FLOOR_TIE * floor.abs().max(STALL_MAGNITUDE_FLOOR)
        });
        ties || self.below_floor(ascended, gain)
    }

    /// The objective and the random stream where the run left them.
    pub fn into_parts(self) -> (Objective, ChaCha8Rng) {
        (self.objective, self.rng)
    }

    /// The run at iteration 0 (the adversary has responded to the starting
    /// defender), not yet checked or reported: [`Self::advance`] goes on
    /// until the certified gap closes, progress stalls at the widest logit
    /// bound, `max_iterations` or the time budget, reporting every outer
    /// iteration to its observer; [`Self::finish`] ends it. `started` is
    /// when the structure's optimisation began (before the local search
    /// that precedes the race): the records' seconds and the time budget
    /// count from it.
    pub fn begin(&mut self, started: Instant) -> Result<Run, OptimiseError> {
        let mut solver: Box<dyn Solver> = match self.method {
            Method::MaxMin => Box::new(GradientPlay::new(
                &self.settings,
                self.defender.len(),
                self.adversary.len(),
            )),
            Method::Ascent => Box::new(Ascent::new(&self.settings)),
        };
        let mut books = Bookkeeping::new(
            self.defender.len(),
            self.adversary.len(),
            self.settings.best_response_every,
        );
        let start = Iterate {
            iteration: 0,
            defender: self.defender.clone(),
            adversary: self.adversary.clone(),
            bound: starting_bound(self.method, &self.settings),
            max_residual: 0.0,
        };
        let state = self.timed(&mut books, |objective| solver.init(objective, start))?;
        Ok(Run {
            solver,
            books,
            state: Some(state),
            judged: false,
            clock: started,
        })
    }

    /// Continues `run` through iteration `last` (its checks and records
    /// included) unless it stops first; returns why it stopped, if it did
    /// (then [`Self::finish`] ends it).
    pub fn advance(
        &mut self,
        run: &mut Run,
        last: usize,
        observer: &mut dyn Observer,
    ) -> Result<Option<Status>, OptimiseError> {
        loop {
            let Some(state) = run.state.take() else {
                return Err(OptimiseError::BestResponse(
                    "the run was advanced after it failed".into(),
                ));
            };
            let mut state = if run.judged {
                if state.iterate.iteration >= last {
                    run.state = Some(state);
                    return Ok(None);
                }
                let solver = &mut run.solver;
                self.timed(&mut run.books, |objective| {
                    solver.next_iter(objective, state)
                })?
            } else {
                state
            };
            let seconds = run.clock.elapsed().as_secs_f64();
            let status = self.between_iterations(
                run.solver.as_ref(),
                &mut state,
                &mut run.books,
                seconds,
                observer,
            )?;
            run.state = Some(state);
            run.judged = true;
            if status.is_some() {
                return Ok(status);
            }
        }
    }

    /// Frees what the run keeps between iterations but rebuilds at its
    /// next step anyway: the evaluator's factors ([`Objective::release`]).
    /// For a start of a race, between its rounds: only the starts running
    /// hold factors (on PAYNT's drone-8-2 with 3 nodes, up to 900 MB each).
    pub fn release(&mut self) {
        self.objective.release();
    }

    /// The outcome of `run`, stopped for `status`; the optimiser keeps the
    /// last iterate.
    pub fn finish(&mut self, run: Run, status: Status) -> Result<RunOutcome, OptimiseError> {
        let Run {
            books,
            state,
            clock,
            ..
        } = run;
        let state = state.ok_or(OptimiseError::BestResponse(
            "the run was finished after it failed".into(),
        ))?;
        self.outcome(state, books, status, clock)
    }

    /// One of the solver's iterations, `iteration`, timed as optimisation,
    /// its iterate added to the suffix averages.
    fn timed(
        &mut self,
        books: &mut Bookkeeping,
        iteration: impl FnOnce(&mut Objective) -> Result<PlayState, OptimiseError>,
    ) -> Result<PlayState, OptimiseError> {
        let clock = Instant::now();
        let state = iteration(&mut self.objective)?;
        books.average(&self.objective, &state.iterate);
        books.phases.optimisation += clock.elapsed().as_secs_f64();
        Ok(state)
    }

    /// Everything between the solver's iterations, after iteration `t` and
    /// `seconds` into the run: the stopping rules, the best-response check
    /// when one is due (it may widen the logit bound), and the record to
    /// `observer`. Returns why the run stops, if it does.
    fn between_iterations(
        &mut self,
        solver: &dyn Solver,
        state: &mut PlayState,
        books: &mut Bookkeeping,
        seconds: f64,
        observer: &mut dyn Observer,
    ) -> Result<Option<Status>, OptimiseError> {
        let t = state.iterate.iteration;
        let work = self.objective.work();
        let check_clock = Instant::now();
        let mut status = budget_spent(&self.settings, t, work, seconds, &self.cancel)
            .or_else(|| solver.converged().then_some(Status::Converged))
            .or_else(|| {
                self.objective
                    .identically_zero()
                    .then_some(Status::ZeroOnSupport)
            });
        let check = if self.check_due(state.iterate.iteration, status) {
            let deep = books.checks % self.settings.best_response_every == 0;
            let mut check = self.check(state, books, deep)?;
            let timing = (status, seconds, check_clock);
            status = self.after_check(&mut check, timing, &mut state.iterate, books)?;
            if let Some(bounds) = self.lower_bounds.as_mut() {
                bounds.forget_if_large();
            }
            Some(check)
        } else {
            None
        };
        // Stamped when the record is made: a check's certified numbers carry
        // the time they were known, its guarantee ascent included.
        let recorded = seconds + check_clock.elapsed().as_secs_f64();
        observer.observe(&record(
            solver,
            state,
            recorded,
            check.as_ref(),
            books.upper_bound,
        ));
        Ok(status)
    }

    /// A check is due at multiples of `check_every`, at the end of each
    /// suffix-averaging window (`t + 1` a power of two, where the stall
    /// rule is judged) and when the run stops.
    fn check_due(&self, t: usize, status: Option<Status>) -> bool {
        t % self.settings.check_every == 0 || window_ends(t) || status.is_some()
    }

    /// After a check: records the best score in the stall history; unless
    /// the run already stops (`status`), [`Status::GapClosed`] when the
    /// current defender's rounding closes the gap, else
    /// [`Self::stop_or_widen`] (where a window ends, after
    /// [`Self::ascend_window_start`]).
    fn after_check(
        &mut self,
        check: &mut Check,
        (status, seconds, check_clock): (Option<Status>, f64, Instant),
        iterate: &mut Iterate,
        books: &mut Bookkeeping,
    ) -> Result<Option<Status>, OptimiseError> {
        // The seconds into the run now (an ascent spends the rest of the
        // time budget).
        let now = || seconds + check_clock.elapsed().as_secs_f64();
        let score = books
            .best
            .as_ref()
            .ok_or(OptimiseError::BestResponse(
                "no best-response check ran".into(),
            ))?
            .score();
        let iteration = iterate.iteration;
        let window_start = books.window_ends.last().copied().unwrap_or(0.0);
        let probes_floor = window_ends(iteration)
            && books.history.len() + 1 >= FLOOR_PROBE_CHECKS
            && self.below_floor(score, score - window_start);
        let stall_judged =
            window_ends(iteration) && books.history.len() + 1 >= self.settings.stall_checks;
        // Nothing to ascend where the value is 0 on the whole support.
        let nothing_to_ascend = matches!(
            status,
            Some(Status::TimeBudget | Status::Cancelled | Status::ZeroOnSupport)
        );
        // A probe alone puts the incumbent back where the start goes on.
        let probe_alone = probes_floor && !stall_judged && status.is_none();
        let before_probe = probe_alone.then(|| (books.best.clone(), check.certified_lower));
        let ascends = (stall_judged || probes_floor || status.is_some()) && !nothing_to_ascend;
        if ascends {
            let steps = probe_alone.then_some(FLOOR_PROBE_STEPS);
            if let Some(ascended) = self.ascend_guarantee(iterate, books, now(), steps)? {
                check.certified_lower = Some(ascended);
            }
        }
        let ascended = books.best.as_ref().map_or(score, Incumbent::score);
        let sunk = probes_floor && self.sunk_below_floor(ascended, score - window_start);
        if probes_floor && !sunk {
            if let Some((best, certified_lower)) = before_probe {
                books.best = best;
                check.certified_lower = certified_lower;
            }
        }
        let score = books.best.as_ref().map_or(score, Incumbent::score);
        books.history.push(score);
        if window_ends(iteration) {
            books.window_ends.push(score);
        }
        if status.is_some() {
            return Ok(status);
        }
        if sunk {
            return Ok(Some(Status::Outpaced));
        }
        if check.rounding_closes_gap {
            return Ok(Some(Status::GapClosed));
        }
        if window_ends(iteration) {
            if stall_judged {
                if let Some(raised) = self.ascend_window_start(iterate, books, now())? {
                    check.certified_lower = Some(raised);
                }
            }
            let ascended_here = ascends && !probe_alone && self.ascends_guarantee();
            books.unascended_window_start = (!ascended_here).then(|| books.best.clone()).flatten();
        }
        Ok(self.stop_or_widen(books, iterate))
    }

    /// Where the stall rule judges a window (its end ascended, `seconds`
    /// into the run) whose start was not ascended, its gain from that
    /// start's raw score would not count as a stall, and neither the time
    /// budget nor a closed certified gap stops the run: the guarantee ascent
    /// from the start's incumbent too, so that the window gains one
    /// ascended score over another. The higher of the start's raw score
    /// and its ascent's bound becomes the window's baseline; the ascended
    /// defender becomes the incumbent where it beats the incumbent, and
    /// its certified lower bound is returned. (Without this, a window of
    /// creeping play counts the first ascent's jump as its own progress:
    /// on the 16x16 grid the starts ran 256 more iterations for a relative
    /// gain of 1e-4.)
    fn ascend_window_start(
        &mut self,
        iterate: &Iterate,
        books: &mut Bookkeeping,
        seconds: f64,
    ) -> Result<Option<f64>, OptimiseError> {
        let s = &self.settings;
        let out_of_time = s.time_budget > 0.0 && seconds >= s.time_budget;
        let gap_closed = books
            .best
            .as_ref()
            .and_then(|best| best.certified_lower)
            .zip(books.upper_bound)
            .is_some_and(|(lower, upper)| s.gap_closed(lower, upper));
        // The run stops at this check anyway, or the window is a stall.
        if !self.ascends_guarantee()
            || out_of_time
            || gap_closed
            || stalled(&books.history, &books.window_ends, s)
        {
            return Ok(None);
        }
        let Some(start) = books.unascended_window_start.take() else {
            return Ok(None);
        };
        let Some(ascended) = self.ascend_from(&start, iterate, &mut books.phases, seconds, None)?
        else {
            return Ok(None);
        };
        let n = books.window_ends.len();
        let bound = ascended.score();
        if let Some(baseline) = n.checked_sub(2).map(|i| &mut books.window_ends[i]) {
            *baseline = baseline.max(bound);
        }
        if books
            .best
            .as_ref()
            .is_some_and(|best| best.score() >= bound)
        {
            return Ok(None);
        }
        *books.history.last_mut().expect("pushed by after_check") = bound;
        books.window_ends[n - 1] = bound;
        let certified_lower = ascended.certified_lower;
        books.best = Some(ascended);
        Ok(certified_lower)
    }

    /// [`Status::GapClosed`] when the certified gap is at most
    /// `gap_tolerance`; on a stall, the doubled logit bound when some
    /// defender or adversary logit is within [`NEAR_BOUND`] of it, it is
    /// below `logit_bound` and the run does not ascend the guarantee (whose
    /// ascent goes beyond the loop's bound), else [`Status::Stalled`].
    fn stop_or_widen(&self, books: &mut Bookkeeping, iterate: &mut Iterate) -> Option<Status> {
        let s = &self.settings;
        let incumbent = books.best.as_ref()?;
        if let (Some(lower), Some(upper)) = (incumbent.certified_lower, books.upper_bound) {
            if s.gap_closed(lower, upper) {
                return Some(Status::GapClosed);
            }
        }
        if !(window_ends(iterate.iteration) && stalled(&books.history, &books.window_ends, s)) {
            return None;
        }
        let bound = iterate.bound;
        let on_bound = |logits: &[f64]| logits.iter().any(|phi| phi.abs() >= NEAR_BOUND * bound);
        let widens = bound < s.logit_bound && !self.ascends_guarantee();
        if widens && (on_bound(&iterate.defender) || on_bound(&iterate.adversary)) {
            iterate.bound = (2.0 * bound).min(s.logit_bound);
            books.history.clear();
            // The score at the widening is the next window's baseline, so
            // the next window end judges the widened bound (not the one
            // after it, twice as far).
            books
                .window_ends
                .drain(..books.window_ends.len().saturating_sub(1));
            None
        } else {
            Some(Status::Stalled)
        }
    }

    /// The run's outcome, stopped for `status` at `state` (its incumbent not
    /// yet settled: [`Self::settle`]); the optimiser keeps the last iterate.
    fn outcome(
        &mut self,
        state: PlayState,
        books: Bookkeeping,
        status: Status,
        clock: Instant,
    ) -> Result<RunOutcome, OptimiseError> {
        let best = books.best.ok_or(OptimiseError::BestResponse(
            "no best-response check ran".into(),
        ))?;
        let PlayState { iterate, point, .. } = state;
        self.defender = iterate.defender;
        self.adversary = iterate.adversary;
        Ok(RunOutcome {
            best,
            upper_bound: books.upper_bound,
            last_value: point.value,
            iterations: iterate.iteration + 1,
            checks: books.checks,
            status,
            seconds: clock.elapsed().as_secs_f64(),
            phases: books.phases,
            logit_bound: iterate.bound,
            max_residual: iterate.max_residual,
            last_response: books.last_response,
        })
    }
}

/// Iteration `t`'s record: the value and gradient norms at
/// `(phi_def(t), phi_adv(t))`, the step sizes, the check's numbers when one
/// ran (the upper bound only with a certified lower bound), the logit bound.
fn record(
    solver: &dyn Solver,
    state: &PlayState,
    seconds: f64,
    check: Option<&Check>,
    upper_bound: Option<f64>,
) -> IterationRecord {
    let t = state.iterate.iteration;
    let (defender_step, adversary_step) = solver.steps(t);
    IterationRecord {
        start: 0,
        iteration: t,
        seconds,
        value: state.point.value,
        defender_gradient_norm: norm(&state.point.defender),
        adversary_gradient_norm: state.adversary_gradient_norm,
        defender_step,
        adversary_step,
        worst_case: check.and_then(|c| c.worst_case),
        certified_lower: check.and_then(|c| c.certified_lower),
        upper_bound: upper_bound.filter(|_| check.is_some_and(|c| c.certified_lower.is_some())),
        logit_bound: state.iterate.bound,
        source: RecordSource::Gradient,
        returned: false,
    }
}

/// The logit bound a run starts at: `initial_logit_bound` for the max-min
/// loop (it widens on stalls), `logit_bound` for the single-player ascent.
fn starting_bound(method: Method, settings: &Settings) -> f64 {
    match method {
        Method::MaxMin => settings.initial_logit_bound,
        Method::Ascent => settings.logit_bound,
    }
}
