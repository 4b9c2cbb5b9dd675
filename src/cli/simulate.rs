//! `posg-fsc simulate`: a Monte Carlo estimate of the value, to check `eval`.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use posg_fsc::pipeline::QueryEstimate;
use posg_fsc::value::{Simulated, SimulationCheck, SimulationSettings, simulate_and_check};
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
    /// The query of `--props` restated in its own terms.
    #[serde(skip_serializing_if = "Option::is_none")]
    query: Option<QueryEstimate>,
    #[serde(flatten)]
    check: SimulationCheck,
    seconds: f64,
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
    let pair = (&defender, &adversary);
    let (formula, check) = match args.objective.reward_objective(&game)? {
        Some(reward) => {
            let simulated = Simulated::Reward {
                target: &reward.target,
                rewards: &reward.rewards,
            };
            let check = simulate_and_check(&game, simulated, pair, settings)?;
            (reward.description, check)
        }
        None => {
            let (dra, formula) = common::objective(&args.objective, &game)?;
            let check = simulate_and_check(&game, Simulated::Probability(&dra), pair, settings)?;
            (formula, check)
        }
    };
    if let Some(note) = check.miss_note("--seed", "--runs") {
        eprintln!("note: {note}");
    }
    let query = (args.objective.property()?).map(|p| QueryEstimate::simulated(&p, &check));
    common::print_json(&Report {
        provenance: Provenance::current(),
        formula,
        query,
        check,
        seconds: common::seconds_since(start),
    })
}
