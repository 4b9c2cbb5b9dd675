//! `posg-fsc simulate`: a Monte Carlo estimate of the value, to check `eval`.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use posg_fsc::controller::Support;
use posg_fsc::value::{DEFAULT_TOLERANCE, Evaluator, SolverSettings, evaluate_controllers};
use posg_fsc::value::{Estimate, RewardEstimate, SimulationSettings, simulate, simulate_reward};
use serde::Serialize;

use super::common::{self, ControllerArgs, ObjectiveArgs, Provenance};

/// Arguments of `simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
    pub game: PathBuf,
    #[command(flatten)]
    pub objective: ObjectiveArgs,
    #[command(flatten)]
    pub controllers: ControllerArgs,
    /// Number of sampled runs; each ends when it enters a recurrence class
    /// (for an expected-reward query of --props, when it reaches the
    /// target: the estimate is then the mean total reward, with a 95%
    /// normal-approximation interval; docs/method.md section 9).
    #[arg(long, default_value_t = 10_000)]
    pub runs: u64,
    /// Seed of the random number generator (ChaCha8).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    provenance: Provenance,
    formula: String,
    settings: SimulationSettings,
    estimate: EstimateReport,
    exact_value: f64,
    exact_within_interval: bool,
    seconds: f64,
}

/// The estimate of a probability or of an expected reward.
#[derive(Serialize)]
#[serde(untagged)]
enum EstimateReport {
    Probability(Estimate),
    Reward(RewardEstimate),
}

impl EstimateReport {
    fn interval(&self) -> (f64, f64, f64) {
        match self {
            Self::Probability(e) => (e.lower, e.upper, e.confidence),
            Self::Reward(e) => (e.lower, e.upper, e.confidence),
        }
    }
}

/// Runs `simulate`.
pub fn run(args: SimulateArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let game = common::read_game_for(&args.game, &args.objective)?;
    let (defender, adversary) = common::controllers(&args.controllers, &game)?;
    let settings = SimulationSettings {
        runs: args.runs,
        seed: args.seed,
    };
    anyhow::ensure!(settings.runs > 0, "--runs must be at least 1");
    let solver = SolverSettings::default();
    let (formula, exact, estimate) = match args.objective.reward_objective(&game)? {
        Some(reward) => {
            let (def, adv) = (Support::of(&defender), Support::of(&adversary));
            let mut evaluator = Evaluator::for_expected_reward(
                &game,
                &reward.target,
                &reward.rewards,
                &def,
                &adv,
                &solver,
            )?;
            let exact = evaluator
                .evaluate(
                    &Support::probabilities_of(&defender),
                    &Support::probabilities_of(&adversary),
                )?
                .value;
            let estimate = simulate_reward(
                &game,
                &reward.target,
                &reward.rewards,
                &defender,
                &adversary,
                &evaluator,
                settings,
            )?;
            (reward.description, exact, EstimateReport::Reward(estimate))
        }
        None => {
            let (dra, formula) = common::objective(&args.objective, &game)?;
            let (evaluator, evaluation) =
                evaluate_controllers(&game, &dra, &defender, &adversary, &solver)?;
            let estimate = simulate(&game, &dra, &defender, &adversary, &evaluator, settings)?;
            (
                formula,
                evaluation.value,
                EstimateReport::Probability(estimate),
            )
        }
    };
    let (lower, upper, confidence) = estimate.interval();
    let slack = DEFAULT_TOLERANCE * (1.0 + exact.abs());
    let within = lower - slack <= exact && exact <= upper + slack;
    if !within {
        eprintln!(
            "note: the exact value {exact} lies outside the {}% interval [{lower}, {upper}]: such \
             an interval misses the exact value in about one seed of {}; another --seed or more \
             --runs tells chance from a fault",
            confidence * 100.0,
            (1.0 / (1.0 - confidence)).round()
        );
    }
    common::print_json(&Report {
        provenance: Provenance::current(),
        formula,
        settings,
        estimate,
        exact_value: exact,
        exact_within_interval: within,
        seconds: common::seconds_since(start),
    })
}
