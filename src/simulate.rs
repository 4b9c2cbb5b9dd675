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
//! score interval.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use thiserror::Error;

use crate::automaton::Dra;
use crate::controller::{Choice, Fsc};
use crate::game::{AdversaryAction, DefenderAction, Posg};
use crate::product::GmcState;
use crate::value::Evaluator;

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
    /// A run did not reach a BSCC or a decided state within the step limit.
    #[error("run {run} did not reach a recurrence class within {limit} steps")]
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
        let z = 1.959_963_984_540_054_f64;
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
    let letters = dra.state_letters(game);
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let mut successes = 0;
    for run in 0..settings.runs {
        let s = sample(&mut rng, game.initial().iter().map(|&(s, p)| (s, p)));
        let g = sample(&mut rng, defender.initial().iter().copied().enumerate());
        let h = sample(&mut rng, adversary.initial().iter().copied().enumerate());
        let q = dra.successor(dra.initial(), letters[s]);
        let mut state = GmcState {
            s: s as u32,
            q: q as u32,
            g: g as u32,
            h: h as u32,
        };
        let mut steps = 0;
        let feasible = loop {
            let m = gmc
                .index_of(state)
                .ok_or(SimulationError::OutsideChain { run })?;
            if let Some(feasible) = bscc_of[m].or(gmc.verdict(m)) {
                break feasible;
            }
            steps += 1;
            if steps > STEP_LIMIT {
                return Err(SimulationError::StepLimit {
                    run,
                    limit: STEP_LIMIT,
                });
            }
            state = step(&mut rng, game, dra, defender, adversary, &letters, state);
        };
        successes += u64::from(feasible);
    }
    Ok(Estimate::wilson(settings.runs, successes))
}

fn step(
    rng: &mut ChaCha8Rng,
    game: &Posg,
    dra: &Dra,
    defender: &Fsc,
    adversary: &Fsc,
    letters: &[u32],
    state: GmcState,
) -> GmcState {
    let s = state.s as usize;
    let o = sample(
        rng,
        game.defender().observation_distribution(s).iter().copied(),
    );
    let o_adv = sample(
        rng,
        game.adversary().observation_distribution(s).iter().copied(),
    );
    let def = choose(rng, defender.choices(state.g as usize, o));
    let adv = choose(rng, adversary.choices(state.h as usize, o_adv));
    let next = sample(
        rng,
        game.transition(s, DefenderAction(def.action), AdversaryAction(adv.action))
            .iter()
            .copied(),
    );
    let q = dra.successor(state.q as usize, letters[next]);
    GmcState {
        s: next as u32,
        q: q as u32,
        g: def.next as u32,
        h: adv.next as u32,
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
