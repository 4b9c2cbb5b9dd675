//! Alternating projected gradient ascent-descent on one support structure
//! (method.md section 4).
//!
//! Outer iteration `t`:
//!
//! 1. `k_adv` adversary steps `phi_adv <- clip(phi_adv - eta_adv d_adv)`;
//! 2. at `(phi_def(t), phi_adv)`: a best-response check when `t` is a
//!    multiple of `check_every` or the run stops;
//! 3. one defender step `phi_def(t+1) = clip(phi_def(t) + eta_def(t) d_def)`,
//!    `eta_def(t) = eta_def / sqrt(1 + decay t)`;
//!
//! where `d` is the logit gradient (plain) or Adam's direction. Alternating
//! gradient play cycles around the saddle of bilinear games such as matching
//! pennies; what converges is the *best defender seen*, ranked by its
//! best-response value, helped by the fast adversary time scale and the
//! decaying defender steps. Each check ranks two candidates: the current
//! defender and the suffix average of its probabilities (the average over
//! iterations `2^k..=t`, `2^k <= t` the last power of two; the average of
//! cycling play approaches the saddle point where the iterates circle it).
//! The result is the best candidate seen, not the last iterate.

use std::time::Instant;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::best_response::best_response;
use super::objective::Objective;
use super::observer::{IterationRecord, Observer};
use super::softmax::clip;
use super::{OptimiseError, Settings, Status, UpdateRule};
use crate::automaton::Dra;
use crate::certify::{lower_bound, upper_bound};
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
    /// The iteration it was seen at.
    pub iteration: usize,
}

/// What a run on one structure ends with.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutcome {
    /// The best defender by worst-case estimate.
    pub best: Incumbent,
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

impl<'a> Optimiser<'a> {
    /// Starts from the templates' logits plus noise uniform in
    /// `[-initial_spread, initial_spread]` drawn from `rng`, clipped to `[-c, c]`.
    pub fn new(objective: Objective, settings: &Settings, mut rng: ChaCha8Rng) -> Self {
        let mut start = |logits: Vec<f64>| {
            let mut perturbed: Vec<f64> = logits
                .into_iter()
                .map(|phi| phi + settings.initial_spread * rng.random_range(-1.0..=1.0))
                .collect();
            clip(&mut perturbed, settings.logit_bound);
            perturbed
        };
        let defender = start(
            objective
                .defender()
                .logits_of_template(settings.logit_bound),
        );
        let adversary = start(
            objective
                .adversary()
                .logits_of_template(settings.logit_bound),
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

    /// Makes every best-response check also record the current defender's
    /// certified lower bound and the smallest game upper bound over the
    /// adversaries found so far.
    pub fn with_certifier(mut self, certifier: Certifier<'a>) -> Self {
        self.certifier = Some(certifier);
        self
    }

    /// The objective (its softmax maps turn logits into controllers).
    pub fn objective(&self) -> &Objective {
        &self.objective
    }

    /// Runs until `max_iterations`, the time budget or a stall, reporting
    /// every outer iteration to `observer`.
    pub fn run(&mut self, observer: &mut dyn Observer) -> Result<RunOutcome, OptimiseError> {
        let clock = Instant::now();
        let s = self.settings.clone();
        let mut defender_update = Update::new(s.update, self.defender.len());
        let mut adversary_update = Update::new(s.update, self.adversary.len());
        let mut best: Option<Incumbent> = None;
        let mut history = Vec::new();
        let mut average = SuffixAverage::new(self.defender.len());
        let mut upper_bound = None;
        let mut t = 0;
        let (status, last_value) = loop {
            let mut adversary_norm = 0.0;
            for _ in 0..s.adversary_steps {
                let point = self.objective.point(&self.defender, &self.adversary)?;
                adversary_norm = norm(&point.adversary);
                adversary_update.step(
                    &mut self.adversary,
                    &point.adversary,
                    -s.adversary_step,
                    s.logit_bound,
                );
            }
            let point = self.objective.point(&self.defender, &self.adversary)?;
            let seconds = clock.elapsed().as_secs_f64();
            let mut status = if t + 1 >= s.max_iterations {
                Some(Status::MaxIterations)
            } else if s.time_budget > 0.0 && seconds >= s.time_budget {
                Some(Status::TimeBudget)
            } else {
                None
            };
            average.add(
                t,
                &self
                    .objective
                    .defender()
                    .probabilities(&self.defender)
                    .entries,
            );
            let checked = t % s.check_every == 0 || status.is_some();
            let worst_case = if checked {
                let found = self.check(&mut best, t, &average)?;
                history.push(best.as_ref().map_or(found, |b| b.worst_case));
                if status.is_none() && stalled(&history, &s) {
                    status = Some(Status::Stalled);
                }
                Some(found)
            } else {
                None
            };
            let certified_lower = match (&self.certifier, checked) {
                (Some(certifier), true) => {
                    let (lower, upper) = self.certify(certifier, best.as_ref())?;
                    upper_bound = Some(upper_bound.map_or(upper, |u: f64| u.min(upper)));
                    Some(lower)
                }
                _ => None,
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
                worst_case,
                certified_lower,
                upper_bound: upper_bound.filter(|_| certified_lower.is_some()),
            });
            if let Some(status) = status {
                break (status, point.value);
            }
            defender_update.step(
                &mut self.defender,
                &point.defender,
                defender_step,
                s.logit_bound,
            );
            t += 1;
        };
        let best = best.ok_or(OptimiseError::BestResponse(
            "no best-response check ran".into(),
        ))?;
        Ok(RunOutcome {
            best,
            last_value,
            iterations: t + 1,
            checks: history.len(),
            status,
            seconds: clock.elapsed().as_secs_f64(),
        })
    }
}

impl Optimiser<'_> {
    /// The certified lower bound of the current defender and the game upper
    /// bound against the incumbent's best response.
    fn certify(
        &self,
        certifier: &Certifier<'_>,
        best: Option<&Incumbent>,
    ) -> Result<(f64, f64), OptimiseError> {
        let defender = self.objective.defender().controller(&self.defender)?;
        let adversary_logits = best.map_or(&self.adversary, |b| &b.adversary);
        let adversary = self.objective.adversary().controller(adversary_logits)?;
        let lower = lower_bound(certifier.game, certifier.not_phi, &defender)?.value;
        let upper = upper_bound(certifier.game, certifier.phi, &adversary)?.value;
        Ok((lower, upper))
    }

    /// The best-response check at iteration `t`: the worst-case estimates of
    /// the current defender (returned) and of the suffix average; either
    /// replaces the incumbent when it is better.
    fn check(
        &mut self,
        best: &mut Option<Incumbent>,
        t: usize,
        average: &SuffixAverage,
    ) -> Result<f64, OptimiseError> {
        let s = &self.settings;
        let mut averaged = self.objective.defender().probabilities(&self.defender);
        averaged.entries.clone_from(&average.mean);
        let averaged = self
            .objective
            .defender()
            .logits_of(&averaged, s.logit_bound);
        let mut current_value = f64::NAN;
        for (i, candidate) in [self.defender.clone(), averaged].into_iter().enumerate() {
            let found = best_response(
                &mut self.objective,
                &candidate,
                &self.adversary,
                s,
                &mut self.rng,
            )?;
            if i == 0 {
                current_value = found.value;
            }
            if best.as_ref().is_none_or(|b| found.value > b.worst_case) {
                *best = Some(Incumbent {
                    defender: candidate,
                    adversary: found.adversary,
                    worst_case: found.value,
                    iteration: t,
                });
            }
        }
        Ok(current_value)
    }
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

/// Whether the best worst-case estimate improved by less than
/// `stall_tolerance` over the last `stall_checks` checks.
fn stalled(history: &[f64], s: &Settings) -> bool {
    s.stall_checks > 0
        && history.len() > s.stall_checks
        && history[history.len() - 1] - history[history.len() - 1 - s.stall_checks]
            < s.stall_tolerance
}

fn norm(v: &[f64]) -> f64 {
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
    steps: i32,
}

impl Update {
    fn new(rule: UpdateRule, n: usize) -> Self {
        Self {
            rule,
            first: vec![0.0; n],
            second: vec![0.0; n],
            steps: 0,
        }
    }

    /// `phi <- clip(phi + eta d)` with `d` the gradient (plain) or Adam's
    /// bias-corrected `m_hat / (sqrt(v_hat) + epsilon)`; `eta < 0` descends.
    fn step(&mut self, phi: &mut [f64], gradient: &[f64], eta: f64, bound: f64) {
        match self.rule {
            UpdateRule::Plain => {
                for (p, g) in phi.iter_mut().zip(gradient) {
                    *p += eta * g;
                }
            }
            UpdateRule::Adam => {
                self.steps = self.steps.saturating_add(1);
                let c1 = 1.0 - ADAM_BETA1.powi(self.steps);
                let c2 = 1.0 - ADAM_BETA2.powi(self.steps);
                for (k, (p, &g)) in phi.iter_mut().zip(gradient).enumerate() {
                    self.first[k] = ADAM_BETA1 * self.first[k] + (1.0 - ADAM_BETA1) * g;
                    self.second[k] = ADAM_BETA2 * self.second[k] + (1.0 - ADAM_BETA2) * g * g;
                    *p +=
                        eta * (self.first[k] / c1) / ((self.second[k] / c2).sqrt() + ADAM_EPSILON);
                }
            }
        }
        clip(phi, bound);
    }
}
