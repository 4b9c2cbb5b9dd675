//! Monte Carlo estimation of the value, independent of the GMC's numbers.
//!
//! Each run samples formats.md section 3 step by step from the game and the
//! controllers themselves (initial state and nodes, both observations, both
//! controllers' choices, the successor state) and tracks the automaton. It
//! ends when it enters a bottom strongly connected component of the GMC;
//! that component's phi-feasibility decides the run (with probability 1 the
//! trace satisfies phi iff the run's BSCC is feasible). A run also ends at a
//! decided state, whose automaton state decides phi whatever follows
//! ([`crate::product::Gmc::verdict`]). The estimate carries a 95% Wilson
//! score interval. [`simulate_reward`] samples the total reward of each run
//! until its target instead (method.md section 9), with a normal
//! approximation interval.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use thiserror::Error;

use crate::automaton::Dra;
use crate::controller::Support;
use crate::controller::{Choice, Fsc};
use crate::game::{AdversaryAction, DefenderAction, Posg, RewardModel};
use crate::product::GmcState;
use crate::value::{
    DEFAULT_TOLERANCE, Evaluator, SolverSettings, ValueError, evaluate_controllers,
};

/// Why a simulation failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SimulationError {
    /// A run left the GMC that was built for these controllers (the
    /// controllers are not the ones the GMC was built with).
    #[error("run {run} reached a state outside the global Markov chain")]
    OutsideChain {
        /// The run's number.
        run: u64,
    },
    /// The expected reward is infinite: some runs never reach the target.
    #[error(
        "the expected reward is infinite (the target is missed with positive probability, \
         method.md section 9): there is no mean to estimate"
    )]
    InfiniteReward,
    /// The exact value to check the estimate against could not be computed.
    #[error(transparent)]
    Value(#[from] ValueError),
    /// A run did not reach a BSCC or a decided state within the step limit.
    #[error("run {run} did not reach a recurrence class (or the target) within {limit} steps")]
    StepLimit {
        /// The run's number.
        run: u64,
        /// The limit.
        limit: u64,
    },
}

/// A Monte Carlo estimate of the value with a 95% confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Estimate {
    /// Number of runs.
    pub runs: u64,
    /// Runs that ended in a phi-feasible BSCC or a decided state where phi holds.
    pub successes: u64,
    /// `successes / runs`.
    pub mean: f64,
    /// Lower end of the 95% Wilson score interval.
    pub lower: f64,
    /// Upper end of the 95% Wilson score interval.
    pub upper: f64,
    /// The interval's confidence, [`CONFIDENCE`]: over seeds, it misses
    /// the exact value about once in twenty.
    pub confidence: f64,
}

/// The confidence of [`Estimate`]'s interval.
pub const CONFIDENCE: f64 = 0.95;

impl Estimate {
    fn wilson(runs: u64, successes: u64) -> Self {
        let n = runs as f64;
        let p = successes as f64 / n;
        let z = Z_95;
        let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
        let half = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / (1.0 + z * z / n);
        Self {
            runs,
            successes,
            mean: p,
            lower: (centre - half).max(0.0),
            upper: (centre + half).min(1.0),
            confidence: CONFIDENCE,
        }
    }
}

/// The step limit per run.
pub const STEP_LIMIT: u64 = 10_000_000;

/// How many runs to sample, and from which seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct SimulationSettings {
    /// Number of runs.
    pub runs: u64,
    /// Seed of the ChaCha8 generator.
    pub seed: u64,
}

/// Estimates the value of `(defender, adversary)` by sampled runs.
/// `evaluator` must have been built for `dra` and these controllers' supports;
/// only its graph analysis is used, never its numbers.
pub fn simulate(
    game: &Posg,
    dra: &Dra,
    defender: &Fsc,
    adversary: &Fsc,
    evaluator: &Evaluator,
    settings: SimulationSettings,
) -> Result<Estimate, SimulationError> {
    let (gmc, recurrence) = (evaluator.gmc(), evaluator.recurrence());
    let mut bscc_of = vec![None; gmc.num_states()];
    for bscc in &recurrence.bsccs {
        for &m in &bscc.states {
            bscc_of[m] = Some(bscc.is_feasible());
        }
    }
    let mut sampler = Sampler::new(game, dra, defender, adversary, evaluator, settings.seed);
    let mut successes = 0;
    for run in 0..settings.runs {
        let feasible = sampler.run(run, |m| bscc_of[m].or(gmc.verdict(m)), |_, _, _| {})?;
        successes += u64::from(feasible);
    }
    Ok(Estimate::wilson(settings.runs, successes))
}

/// A Monte Carlo estimate of an expected reward (method.md section 9) with
/// a 95% normal-approximation interval, `mean +- 1.96 s / sqrt(runs)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RewardEstimate {
    /// Number of runs.
    pub runs: u64,
    /// The mean total reward of the runs until the target.
    pub mean: f64,
    /// The runs' sample standard deviation `s`.
    pub standard_deviation: f64,
    /// Lower end of the interval.
    pub lower: f64,
    /// Upper end of the interval.
    pub upper: f64,
    /// The interval's confidence, [`CONFIDENCE`] (asymptotically: rewards
    /// with heavy tails make it optimistic for few runs).
    pub confidence: f64,
}

/// Estimates the expected total reward of `rewards` until the target of
/// `target` (the automaton of `F T`) by sampled runs, each ending at its
/// first state where `T` has held. `evaluator` must have been built by
/// [`Evaluator::for_expected_reward`] for these controllers' supports, and
/// the value must be finite ([`SimulationError::InfiniteReward`] otherwise:
/// some runs would never end).
pub fn simulate_reward(
    game: &Posg,
    target: &Dra,
    rewards: &RewardModel,
    defender: &Fsc,
    adversary: &Fsc,
    evaluator: &Evaluator,
    settings: SimulationSettings,
) -> Result<RewardEstimate, SimulationError> {
    if evaluator.is_infinite() {
        return Err(SimulationError::InfiniteReward);
    }
    let gmc = evaluator.gmc();
    let mut sampler = Sampler::new(game, target, defender, adversary, evaluator, settings.seed);
    let (mut sum, mut sum_of_squares) = (0.0, 0.0);
    for run in 0..settings.runs {
        let mut total = 0.0;
        let reached = |m| (gmc.verdict(m) == Some(true)).then_some(());
        sampler.run(run, reached, |s, u, v| {
            let action = rewards.action_reward(s, DefenderAction(u), AdversaryAction(v));
            total += rewards.state_reward(s) + action.unwrap_or(0.0);
        })?;
        sum += total;
        sum_of_squares += total * total;
    }
    let n = settings.runs as f64;
    let mean = sum / n;
    let variance = if settings.runs > 1 {
        ((sum_of_squares - n * mean * mean) / (n - 1.0)).max(0.0)
    } else {
        0.0
    };
    let standard_deviation = variance.sqrt();
    let half = Z_95 * standard_deviation / n.sqrt();
    Ok(RewardEstimate {
        runs: settings.runs,
        mean,
        standard_deviation,
        lower: mean - half,
        upper: mean + half,
        confidence: CONFIDENCE,
    })
}

/// The 97.5% quantile of the standard normal distribution.
const Z_95: f64 = 1.959_963_984_540_054;

/// Samples runs of the GMC from the game and the controllers themselves.
struct Sampler<'a> {
    game: &'a Posg,
    dra: &'a Dra,
    defender: &'a Fsc,
    adversary: &'a Fsc,
    evaluator: &'a Evaluator,
    letters: Vec<u32>,
    rng: ChaCha8Rng,
}

impl<'a> Sampler<'a> {
    fn new(
        game: &'a Posg,
        dra: &'a Dra,
        defender: &'a Fsc,
        adversary: &'a Fsc,
        evaluator: &'a Evaluator,
        seed: u64,
    ) -> Self {
        Self {
            game,
            dra,
            defender,
            adversary,
            evaluator,
            letters: dra.state_letters(game),
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// One run from the initial distribution until `ended(m)` gives its
    /// outcome at the GMC state `m`; `stepped(s, u, v)` sees each step's
    /// game state and actions.
    fn run<T>(
        &mut self,
        run: u64,
        ended: impl Fn(usize) -> Option<T>,
        mut stepped: impl FnMut(usize, usize, usize),
    ) -> Result<T, SimulationError> {
        let (game, dra, rng) = (self.game, self.dra, &mut self.rng);
        let s = sample(rng, game.initial().iter().map(|&(s, p)| (s, p)));
        let g = sample(rng, self.defender.initial().iter().copied().enumerate());
        let h = sample(rng, self.adversary.initial().iter().copied().enumerate());
        let q = dra.successor(dra.initial(), self.letters[s]);
        let mut state = GmcState {
            s: s as u32,
            q: q as u32,
            g: g as u32,
            h: h as u32,
        };
        let gmc = self.evaluator.gmc();
        let mut steps = 0;
        loop {
            let m = gmc
                .index_of(state)
                .ok_or(SimulationError::OutsideChain { run })?;
            if let Some(outcome) = ended(m) {
                return Ok(outcome);
            }
            steps += 1;
            if steps > STEP_LIMIT {
                return Err(SimulationError::StepLimit {
                    run,
                    limit: STEP_LIMIT,
                });
            }
            let (next, u, v) = self.step(state);
            stepped(state.s as usize, u, v);
            state = next;
        }
    }

    /// One step of formats.md section 3 from `state`: the next state and
    /// the actions played.
    fn step(&mut self, state: GmcState) -> (GmcState, usize, usize) {
        let (game, rng) = (self.game, &mut self.rng);
        let s = state.s as usize;
        let o = sample(
            rng,
            game.defender().observation_distribution(s).iter().copied(),
        );
        let o_adv = sample(
            rng,
            game.adversary().observation_distribution(s).iter().copied(),
        );
        let def = choose(rng, self.defender.choices(state.g as usize, o));
        let adv = choose(rng, self.adversary.choices(state.h as usize, o_adv));
        let next = sample(
            rng,
            game.transition(s, DefenderAction(def.action), AdversaryAction(adv.action))
                .iter()
                .copied(),
        );
        let q = self.dra.successor(state.q as usize, self.letters[next]);
        let next = GmcState {
            s: next as u32,
            q: q as u32,
            g: def.next as u32,
            h: adv.next as u32,
        };
        (next, def.action, adv.action)
    }
}

fn choose<'a>(rng: &mut ChaCha8Rng, choices: &'a [Choice]) -> &'a Choice {
    let k = sample(rng, choices.iter().map(|c| c.probability).enumerate());
    &choices[k]
}

/// Draws an outcome from `(outcome, probability)` pairs summing to 1.
fn sample(rng: &mut ChaCha8Rng, outcomes: impl Iterator<Item = (usize, f64)>) -> usize {
    let mut threshold: f64 = rng.random();
    let mut last = 0;
    for (outcome, p) in outcomes {
        if p <= 0.0 {
            continue;
        }
        last = outcome;
        if threshold < p {
            return outcome;
        }
        threshold -= p;
    }
    last
}

/// What a simulation estimates: the probability of the formula of `Dra`
/// (its value, method.md section 1), or the expected total reward of
/// `rewards` until the target of the automaton of `F T` (section 9).
#[derive(Debug, Clone, Copy)]
pub enum Simulated<'a> {
    /// `P(trace |= phi)`.
    Probability(&'a Dra),
    /// The expected reward until the target.
    Reward {
        /// The automaton of `F T`.
        target: &'a Dra,
        /// The reward model.
        rewards: &'a RewardModel,
    },
}

/// The estimate of a probability or of an expected reward.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(untagged)]
pub enum EstimateReport {
    /// Of a probability (a Wilson interval).
    Probability(Estimate),
    /// Of an expected reward (a normal-approximation interval).
    Reward(RewardEstimate),
}

impl EstimateReport {
    /// The runs' mean.
    pub fn mean(&self) -> f64 {
        match self {
            Self::Probability(e) => e.mean,
            Self::Reward(e) => e.mean,
        }
    }

    /// `(lower, upper, confidence)` of the interval.
    pub fn interval(&self) -> (f64, f64, f64) {
        match self {
            Self::Probability(e) => (e.lower, e.upper, e.confidence),
            Self::Reward(e) => (e.lower, e.upper, e.confidence),
        }
    }
}

/// A simulation checked against the exact value (`posg-fsc simulate`,
/// Python's `simulate`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SimulationCheck {
    /// The runs and the seed.
    pub settings: SimulationSettings,
    /// The estimate with its interval.
    pub estimate: EstimateReport,
    /// The value computed exactly (method.md sections 1 and 9).
    pub exact_value: f64,
    /// Whether the interval, widened by the solver's tolerance, holds the
    /// exact value: false about once in twenty seeds by chance
    /// ([`SimulationCheck::miss_note`]).
    pub exact_within_interval: bool,
}

impl SimulationCheck {
    /// Where the interval misses the exact value: a sentence saying what
    /// that means (`seed` and `runs` name the settings as the caller's face
    /// spells them).
    pub fn miss_note(&self, seed: &str, runs: &str) -> Option<String> {
        if self.exact_within_interval {
            return None;
        }
        let (lower, upper, confidence) = self.estimate.interval();
        Some(format!(
            "the exact value {} lies outside the {}% interval [{lower}, {upper}]: such an \
             interval misses the exact value in about one seed of {}; another {seed} or more \
             {runs} tells chance from a fault",
            self.exact_value,
            confidence * 100.0,
            (1.0 / (1.0 - confidence)).round()
        ))
    }
}

/// Estimates `simulated` for the controller pair by `settings.runs`
/// sampled runs ([`simulate`], [`simulate_reward`]) and checks the estimate
/// against the exact value.
pub fn simulate_and_check(
    game: &Posg,
    simulated: Simulated,
    (defender, adversary): (&Fsc, &Fsc),
    settings: SimulationSettings,
) -> Result<SimulationCheck, SimulationError> {
    let solver = SolverSettings::default();
    let (exact, estimate) = match simulated {
        Simulated::Reward { target, rewards } => {
            let (def, adv) = (Support::of(defender), Support::of(adversary));
            let mut evaluator =
                Evaluator::for_expected_reward(game, target, rewards, &def, &adv, &solver)?;
            let probabilities = |fsc: &Fsc| Support::probabilities_of(fsc);
            let exact =
                (evaluator.evaluate(&probabilities(defender), &probabilities(adversary))?).value;
            let estimate = simulate_reward(
                game, target, rewards, defender, adversary, &evaluator, settings,
            )?;
            (exact, EstimateReport::Reward(estimate))
        }
        Simulated::Probability(dra) => {
            let (evaluator, evaluation) =
                evaluate_controllers(game, dra, defender, adversary, &solver)?;
            let estimate = simulate(game, dra, defender, adversary, &evaluator, settings)?;
            (evaluation.value, EstimateReport::Probability(estimate))
        }
    };
    let (lower, upper, _) = estimate.interval();
    let slack = DEFAULT_TOLERANCE * (1.0 + exact.abs());
    Ok(SimulationCheck {
        settings,
        estimate,
        exact_value: exact,
        exact_within_interval: lower - slack <= exact && exact <= upper + slack,
    })
}
