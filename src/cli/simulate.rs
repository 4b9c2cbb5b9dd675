//! `posg-fsc simulate`: a Monte Carlo estimate of the value, to check `eval`.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use posg_fsc::value::evaluate_controllers;
use posg_fsc::value::{DEFAULT_TOLERANCE, SolverSettings};
use posg_fsc::value::{Estimate, SimulationSettings, simulate};
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
    /// Number of sampled runs; each ends when it enters a recurrence class.
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
    estimate: Estimate,
    exact_value: f64,
    exact_within_interval: bool,
    seconds: f64,
}

/// Runs `simulate`.
pub fn run(args: SimulateArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let game = common::read_game_for(&args.game, &args.objective)?;
    let (dra, formula) = common::objective(&args.objective, &game)?;
    let (defender, adversary) = common::controllers(&args.controllers, &game)?;
    let (evaluator, evaluation) = evaluate_controllers(
        &game,
        &dra,
        &defender,
        &adversary,
        &SolverSettings::default(),
    )?;
    let exact = evaluation.value;
    let settings = SimulationSettings {
        runs: args.runs,
        seed: args.seed,
    };
    anyhow::ensure!(settings.runs > 0, "--runs must be at least 1");
    let estimate = simulate(&game, &dra, &defender, &adversary, &evaluator, settings)?;
    let within =
        estimate.lower - DEFAULT_TOLERANCE <= exact && exact <= estimate.upper + DEFAULT_TOLERANCE;
    if !within {
        eprintln!(
            "note: the exact value {exact} lies outside the {}% interval [{}, {}]: such an \
             interval misses the exact value in about one seed of {}; another --seed or more \
             --runs tells chance from a fault",
            estimate.confidence * 100.0,
            estimate.lower,
            estimate.upper,
            (1.0 / (1.0 - estimate.confidence)).round()
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
