//! Alternating projected gradient ascent-descent on one support structure
//! (method.md section 4).
//!
//! Outer iteration `t`:
//!
//! 1. `k_adv` adversary steps `phi_adv <- clip_c(phi_adv - eta_adv d_adv)`;
//! 2. at `(phi_def(t), phi_adv)`: a best-response check when `t` is a
//!    multiple of `check_every` or the run stops;
//! 3. one defender step `phi_def(t+1) = clip_c(phi_def(t) + eta_def(t) d_def)`,
//!    `eta_def(t) = eta_def / sqrt(1 + decay t)`;
//!
//! where `d` is the logit gradient (plain) or Adam's direction, made
//! optimistic (`d_t + optimism (d_t - d_{t-1})`) when `optimism > 0`, and
//! `clip_c` the projection onto `[-c, c]`. Alternating gradient play cycles around
//! the saddle of bilinear games such as matching pennies; what converges is
//! the *best defender seen*, helped by the fast adversary time scale and the
//! decaying defender steps. Each check ranks two candidates: the current
//! defender and the suffix average of its probabilities (the average over
//! iterations `2^k..=t`, `2^k <= t` the last power of two; the average of
//! cycling play approaches the saddle point where the iterates circle it).
//! A candidate's score is its certified lower bound when an automaton for
//! !phi is given (method.md section 6), else its best-response value; the
//! result is the best-scoring candidate seen, not the last iterate.
//!
//! Stopping and the logit bound: the run stops when the certified gap
//! (smallest game upper bound minus the best certified lower bound) is at
//! most `gap_tolerance`, or when the best score has gained less than
//! `stall_tolerance` over `stall_checks` checks. A stall while some logit
//! sits on the bound `c` and `c < logit_bound` does not stop the run: `c`
//! doubles (capped at `logit_bound`) and the stall count restarts. So `c`
//! starts small (`initial_logit_bound`, where the softmax is far from
//! saturated and gradients are informative) and widens only where
//! determinism pays, while every supported choice keeps probability at least
//! `exp(-2 logit_bound) / |block|`: the support, and the GMC graph, never
//! change.

use std::time::Instant;

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::best_response::best_response;
use super::objective::Objective;
use super::observer::{IterationRecord, Observer};
use super::rounding::truncated;
use super::softmax::clip;
use super::{OptimiseError, Settings, Status, UpdateRule};
use crate::automaton::Dra;
use crate::certify::{lower_value_or_trivial, upper_value_or_trivial};
use crate::game::Posg;

/// The optimiser's state on one structure.
pub struct Optimiser<'a> {
    objective: Objective,
    certifier: Option<Certifier<'a>>,
    settings: Settings,
    rng: ChaCha8Rng,
    defender: Vec<f64>,
    adversary: Vec<f64>,
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
}

impl PhaseSeconds {
    /// The phase-by-phase sum.
    pub fn add(&mut self, other: &PhaseSeconds) {
        self.optimisation += other.optimisation;
        self.best_responses += other.best_responses;
        self.certification += other.certification;
        self.rounding += other.rounding;
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
}

/// What the best-response checks certify with (method.md section 6): the
/// game and deterministic automata for phi and !phi.
#[derive(Debug, Clone, Copy)]
pub struct Certifier<'a> {
    /// The game.
    pub game: &'a Posg,
    /// An automaton for phi (for the game upper bound).
    pub phi: &'a Dra,
    /// An automaton for !phi (for the defender's certified lower bound).
    pub not_phi: &'a Dra,
}

/// A logit `phi` presses on the bound `c` when `|phi| >= NEAR_BOUND * c`.
pub const NEAR_BOUND: f64 = 0.95;

/// The numbers of one best-response check that the iteration record shows.
struct Check {
    worst_case: f64,
    certified_lower: Option<f64>,
    /// The argmax rounding of the current defender certifies within
    /// `gap_tolerance` of the upper bound (it is then the incumbent, and
    /// the final rounding keeps the rounded controller).
    rounding_closes_gap: bool,
}

impl<'a> Optimiser<'a> {
    /// Starts from the templates' logits plus noise uniform in
    /// `[-initial_spread, initial_spread]` drawn from `rng`, clipped to
    /// `[-c_0, c_0]` (`c_0 = initial_logit_bound`).
    pub fn new(objective: Objective, settings: &Settings, mut rng: ChaCha8Rng) -> Self {
        let bound = settings.initial_logit_bound;
        let defender = perturbed(
            objective.defender().logits_of_template(bound),
            settings.initial_spread,
            bound,
            &mut rng,
        );
        let adversary = perturbed(
            objective.adversary().logits_of_template(bound),
            settings.initial_spread,
            bound,
            &mut rng,
        );
        Self {
            objective,
            certifier: None,
            settings: settings.clone(),
            rng,
            defender,
            adversary,
        }
    }

    /// Makes every best-response check also certify its candidates: they
    /// are then ranked by certified lower bound, and the run can stop on the
    /// certified gap.
    pub fn with_certifier(mut self, certifier: Certifier<'a>) -> Self {
        self.certifier = Some(certifier);
        self
    }

    /// The objective (its softmax maps turn logits into controllers).
    pub fn objective(&self) -> &Objective {
        &self.objective
    }

    /// The objective and the random stream where the run left them.
    pub fn into_parts(self) -> (Objective, ChaCha8Rng) {
        (self.objective, self.rng)
    }

    /// Runs until the certified gap closes, progress stalls at the widest
    /// logit bound, `max_iterations` or the time budget, reporting every
    /// outer iteration to `observer`.
    pub fn run(&mut self, observer: &mut dyn Observer) -> Result<RunOutcome, OptimiseError> {
        let clock = Instant::now();
        let s = self.settings.clone();
        let mut phases = PhaseSeconds::default();
        let mut defender_update = Update::new(s.update, s.optimism, self.defender.len());
        let mut adversary_update = Update::new(s.update, s.optimism, self.adversary.len());
        let mut best: Option<Incumbent> = None;
        let mut history = Vec::new();
        let mut average = SuffixAverage::new(self.defender.len());
        let mut adversary_average = SuffixAverage::new(self.adversary.len());
        let mut upper_bound = None;
        let mut bound = s.initial_logit_bound;
        let mut max_residual = 0.0f64;
        let mut checks = 0;
        let mut t = 0;
        let (status, last_value) = loop {
            let steps_clock = Instant::now();
            let mut adversary_norm = 0.0;
            for _ in 0..s.adversary_steps {
                let point = self.objective.point(&self.defender, &self.adversary)?;
                max_residual = max_residual.max(point.residual);
                adversary_norm = norm(&point.adversary);
                adversary_update.step(
                    &mut self.adversary,
                    &point.adversary,
                    -s.adversary_step,
                    bound,
                );
            }
            let point = self.objective.point(&self.defender, &self.adversary)?;
            max_residual = max_residual.max(point.residual);
            average.add(
                t,
                &self
                    .objective
                    .defender()
                    .probabilities(&self.defender)
                    .entries,
            );
            adversary_average.add(
                t,
                &self
                    .objective
                    .adversary()
                    .probabilities(&self.adversary)
                    .entries,
            );
            phases.optimisation += steps_clock.elapsed().as_secs_f64();
            let seconds = clock.elapsed().as_secs_f64();
            let mut status = if t + 1 >= s.max_iterations {
                Some(Status::MaxIterations)
            } else if s.time_budget > 0.0 && seconds >= s.time_budget {
                Some(Status::TimeBudget)
            } else {
                None
            };
            let checked = t % s.check_every == 0 || status.is_some();
            let check = if checked {
                checks += 1;
                let check = self.check(
                    &mut best,
                    &mut upper_bound,
                    t,
                    [&average, &adversary_average],
                    bound,
                    &mut phases,
                )?;
                let incumbent = best.as_ref().ok_or(OptimiseError::BestResponse(
                    "no best-response check ran".into(),
                ))?;
                history.push(incumbent.score());
                if status.is_none() && check.rounding_closes_gap {
                    status = Some(Status::GapClosed);
                }
                if status.is_none() {
                    status = self.stop_or_widen(incumbent, upper_bound, &mut history, &mut bound);
                }
                Some(check)
            } else {
                None
            };
            let defender_step = s.defender_step / (1.0 + s.defender_decay * t as f64).sqrt();
            observer.observe(&IterationRecord {
                iteration: t,
                seconds,
                value: point.value,
                defender_gradient_norm: norm(&point.defender),
                adversary_gradient_norm: adversary_norm,
                defender_step,
                adversary_step: s.adversary_step,
                worst_case: check.as_ref().map(|c| c.worst_case),
                certified_lower: check.as_ref().and_then(|c| c.certified_lower),
                upper_bound: upper_bound
                    .filter(|_| check.as_ref().is_some_and(|c| c.certified_lower.is_some())),
                logit_bound: bound,
            });
            if let Some(status) = status {
                break (status, point.value);
            }
            let steps_clock = Instant::now();
            defender_update.step(&mut self.defender, &point.defender, defender_step, bound);
            phases.optimisation += steps_clock.elapsed().as_secs_f64();
            t += 1;
        };
        let best = best.ok_or(OptimiseError::BestResponse(
            "no best-response check ran".into(),
        ))?;
        Ok(RunOutcome {
            best,
            upper_bound,
            last_value,
            iterations: t + 1,
            checks,
            status,
            seconds: clock.elapsed().as_secs_f64(),
            phases,
            logit_bound: bound,
            max_residual,
        })
    }
}

impl Optimiser<'_> {
    /// After a check: [`Status::GapClosed`] when the certified gap is at
    /// most `gap_tolerance`; on a stall, the doubled logit bound when some
    /// defender or adversary logit is within [`NEAR_BOUND`] of it and it is below
    /// `logit_bound`, else [`Status::Stalled`].
    fn stop_or_widen(
        &self,
        incumbent: &Incumbent,
        upper_bound: Option<f64>,
        history: &mut Vec<f64>,
        bound: &mut f64,
    ) -> Option<Status> {
        let s = &self.settings;
        if let (Some(lower), Some(upper)) = (incumbent.certified_lower, upper_bound) {
            if upper - lower <= s.gap_tolerance {
                return Some(Status::GapClosed);
            }
        }
        if !stalled(history, s) {
            return None;
        }
        let on_bound = |logits: &[f64]| logits.iter().any(|phi| phi.abs() >= NEAR_BOUND * *bound);
        if *bound < s.logit_bound && (on_bound(&self.defender) || on_bound(&self.adversary)) {
            *bound = (2.0 * *bound).min(s.logit_bound);
            history.clear();
            None
        } else {
            Some(Status::Stalled)
        }
    }

    /// The best-response check at iteration `t`: the current defender and
    /// the suffix average of the defender's probabilities (as logits within
    /// `bound`) each get a best response and, with a certifier, a certified
    /// lower bound; either replaces the incumbent when its score is higher.
    /// With a certifier the game upper bound is also taken against the
    /// suffix average of the adversary's probabilities (where cycling play
    /// circles a mixed saddle point, the average approaches it) and against
    /// the best response to the current defender. Returns the current
    /// defender's numbers.
    fn check(
        &mut self,
        best: &mut Option<Incumbent>,
        upper_bound: &mut Option<f64>,
        t: usize,
        [average, adversary_average]: [&SuffixAverage; 2],
        bound: f64,
        phases: &mut PhaseSeconds,
    ) -> Result<Check, OptimiseError> {
        let mut averaged = self.objective.defender().probabilities(&self.defender);
        averaged.entries.clone_from(&average.mean);
        let averaged = self.objective.defender().logits_of(&averaged, bound);
        if let Some(certifier) = &self.certifier {
            let clock = Instant::now();
            let mut mu = self.objective.adversary().probabilities(&self.adversary);
            mu.entries.clone_from(&adversary_average.mean);
            let logits = self
                .objective
                .adversary()
                .logits_of(&mu, self.settings.logit_bound);
            let adversary = self.objective.adversary().controller(&logits)?;
            let upper = upper_value_or_trivial(certifier.game, certifier.phi, &adversary)?;
            *upper_bound = Some(upper_bound.map_or(upper, |u: f64| u.min(upper)));
            phases.certification += clock.elapsed().as_secs_f64();
        }
        let rounding_closes_gap = self.rounding_closes_gap(*upper_bound, phases)?;
        let mut current = None;
        for (i, candidate) in [self.defender.clone(), averaged].into_iter().enumerate() {
            let clock = Instant::now();
            let found = best_response(
                &mut self.objective,
                &candidate,
                &self.adversary,
                &self.settings,
                &mut self.rng,
            )?;
            phases.best_responses += clock.elapsed().as_secs_f64();
            let clock = Instant::now();
            let certified_lower = match &self.certifier {
                Some(certifier) => {
                    let defender = self.objective.defender().controller(&candidate)?;
                    let lower =
                        lower_value_or_trivial(certifier.game, certifier.not_phi, &defender)?;
                    if i == 0 {
                        let adversary = self.objective.adversary().controller(&found.adversary)?;
                        let upper =
                            upper_value_or_trivial(certifier.game, certifier.phi, &adversary)?;
                        *upper_bound = Some(upper_bound.map_or(upper, |u: f64| u.min(upper)));
                    }
                    Some(lower)
                }
                None => None,
            };
            phases.certification += clock.elapsed().as_secs_f64();
            let incumbent = Incumbent {
                defender: candidate,
                adversary: found.adversary,
                worst_case: found.value,
                certified_lower,
                iteration: t,
            };
            current.get_or_insert(Check {
                worst_case: found.value,
                certified_lower,
                rounding_closes_gap,
            });
            let current_closes = i == 0 && rounding_closes_gap;
            if current_closes || best.as_ref().is_none_or(|b| incumbent.score() > b.score()) {
                *best = Some(incumbent);
            }
            if current_closes {
                break;
            }
        }
        current.ok_or(OptimiseError::BestResponse("no candidate checked".into()))
    }
}

impl Optimiser<'_> {
    /// Whether, with rounding on and a certifier, the argmax rounding of the
    /// current defender certifies within `gap_tolerance` of `upper_bound`: a
    /// deterministic optimum is then found, though the softmax iterates
    /// would approach it only slowly.
    fn rounding_closes_gap(
        &self,
        upper_bound: Option<f64>,
        phases: &mut PhaseSeconds,
    ) -> Result<bool, OptimiseError> {
        let (Some(certifier), Some(upper), true) =
            (&self.certifier, upper_bound, self.settings.round)
        else {
            return Ok(false);
        };
        let clock = Instant::now();
        let defender = self.objective.defender().controller(&self.defender)?;
        let rounded = truncated(&defender, f64::INFINITY)?;
        let lower = lower_value_or_trivial(certifier.game, certifier.not_phi, &rounded)?;
        phases.certification += clock.elapsed().as_secs_f64();
        Ok(upper - lower <= self.settings.gap_tolerance)
    }
}

/// `logits` plus noise uniform in `[-spread, spread]`, clipped to `[-bound, bound]`.
pub(super) fn perturbed(
    logits: Vec<f64>,
    spread: f64,
    bound: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let mut perturbed: Vec<f64> = logits
        .into_iter()
        .map(|phi| phi + spread * rng.random_range(-1.0..=1.0))
        .collect();
    clip(&mut perturbed, bound);
    perturbed
}

/// The mean of the defender's probabilities over iterations `2^k..=t`.
struct SuffixAverage {
    mean: Vec<f64>,
    count: usize,
}

impl SuffixAverage {
    fn new(n: usize) -> Self {
        Self {
            mean: vec![0.0; n],
            count: 0,
        }
    }

    /// Adds iteration `t`'s probabilities, first restarting at powers of two.
    fn add(&mut self, t: usize, mu: &[f64]) {
        if t.is_power_of_two() {
            self.count = 0;
        }
        self.count += 1;
        let weight = 1.0 / self.count as f64;
        for (m, &x) in self.mean.iter_mut().zip(mu) {
            *m += weight * (x - *m);
        }
    }
}

/// Whether the best score improved by less than `stall_tolerance` times
/// its current magnitude over the last `stall_checks` entries of `history`
/// (relative, so that a climb from a tiny value is not taken for a stall).
pub(super) fn stalled(history: &[f64], s: &Settings) -> bool {
    s.stall_checks > 0 && gained_little(history, s.stall_checks, s.stall_tolerance)
}

/// Whether the last entry of `history` exceeds the one `window` entries
/// before by less than `tolerance` times its magnitude (false while the
/// history is shorter than the window).
pub(super) fn gained_little(history: &[f64], window: usize, tolerance: f64) -> bool {
    let n = history.len();
    n > window && history[n - 1] - history[n - 1 - window] <= tolerance * history[n - 1].abs()
}

pub(super) fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

const ADAM_BETA1: f64 = 0.9;
const ADAM_BETA2: f64 = 0.999;
const ADAM_EPSILON: f64 = 1e-8;

/// One player's update rule and its state (Adam's moment estimates).
struct Update {
    rule: UpdateRule,
    first: Vec<f64>,
    second: Vec<f64>,
    previous: Vec<f64>,
    optimism: f64,
    steps: i32,
}

impl Update {
    fn new(rule: UpdateRule, optimism: f64, n: usize) -> Self {
        Self {
            rule,
            first: vec![0.0; n],
            second: vec![0.0; n],
            previous: vec![0.0; n],
            optimism,
            steps: 0,
        }
    }

    /// `phi <- clip(phi + eta (d_t + optimism (d_t - d_{t-1})))` with `d` the
    /// gradient (plain) or Adam's bias-corrected `m_hat / (sqrt(v_hat) +
    /// epsilon)`; `eta < 0` descends. With `optimism = 1` this is the
    /// optimistic update (Popov 1980; Daskalakis et al. 2018), whose
    /// iterates converge where plain alternating play cycles around a
    /// mixed saddle point.
    fn step(&mut self, phi: &mut [f64], gradient: &[f64], eta: f64, bound: f64) {
        match self.rule {
            UpdateRule::Plain => {
                for (k, (p, &g)) in phi.iter_mut().zip(gradient).enumerate() {
                    *p += eta * (g + self.optimism * (g - self.previous[k]));
                    self.previous[k] = g;
                }
            }
            UpdateRule::Adam => {
                self.steps = self.steps.saturating_add(1);
                let c1 = 1.0 - ADAM_BETA1.powi(self.steps);
                let c2 = 1.0 - ADAM_BETA2.powi(self.steps);
                for (k, (p, &g)) in phi.iter_mut().zip(gradient).enumerate() {
                    self.first[k] = ADAM_BETA1 * self.first[k] + (1.0 - ADAM_BETA1) * g;
                    self.second[k] = ADAM_BETA2 * self.second[k] + (1.0 - ADAM_BETA2) * g * g;
                    let d = (self.first[k] / c1) / ((self.second[k] / c2).sqrt() + ADAM_EPSILON);
                    *p += eta * (d + self.optimism * (d - self.previous[k]));
                    self.previous[k] = d;
                }
            }
        }
        clip(phi, bound);
    }
}
