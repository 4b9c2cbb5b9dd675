//! `posg-fsc strategy`: reads a strategy file of `certify --attack` or
//! `--response` (docs/formats.md section 7), checks it against the game,
//! describes it and, where the free player observes the state, writes it as
//! a controller.

use std::path::PathBuf;

use clap::Args;
use posg_fsc::certify::strategy::StrategyFile;
use serde::Serialize;

use super::common::{self, Provenance};

/// Arguments of `strategy`.
#[derive(Debug, Args)]
pub struct StrategyArgs {
    /// The strategy file (`certify --attack FILE` or `--response FILE`).
    strategy: PathBuf,
    /// The game the strategy was computed on: a `*.posg.json` file
    /// (docs/formats.md section 1), its binary form, or a model in Storm's
    /// DRN format (section 6).
    #[arg(long)]
    game: PathBuf,
    /// Also write the strategy as a controller of the free player (one node
    /// per automaton state). Needs a free player that observes the state
    /// exactly and a strategy that does not depend on the fixed player's
    /// node (always so against a one-node controller).
    #[arg(long, value_name = "FILE.fsc.json")]
    fsc: Option<PathBuf>,
}

#[derive(Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    provenance: Provenance,
    file: String,
    player: posg_fsc::controller::Role,
    objective: posg_fsc::certify::strategy::Objective,
    formula: &'a str,
    free_player_value: f64,
    rules: usize,
    automaton_states: usize,
    fixed_nodes: usize,
    /// The nodes of the controller that replays the strategy, if there is one.
    controller_nodes: Option<usize>,
    /// Why the strategy cannot be written as a controller, if it cannot.
    not_a_controller: Option<String>,
    written: Option<String>,
}

/// Reads, checks and describes the strategy; writes the controller on request.
pub fn run(args: StrategyArgs) -> anyhow::Result<()> {
    let game = common::read_game(&args.game)?;
    let file = StrategyFile::read(&args.strategy, &game)?;
    let fsc = file.to_fsc(&game);
    if let Some(path) = &args.fsc {
        let fsc = fsc
            .as_ref()
            .map_err(|why| anyhow::anyhow!("cannot write the strategy as a controller: {why}"))?;
        posg_fsc::controller::file::write(path, fsc, &game)?;
    }
    common::print_json(&Report {
        provenance: Provenance::current(),
        file: args.strategy.display().to_string(),
        player: file.player,
        objective: file.objective,
        formula: &file.formula,
        free_player_value: file.free_player_value,
        rules: file.rules.len(),
        automaton_states: file.automaton.states,
        fixed_nodes: file.fixed_nodes,
        controller_nodes: fsc.as_ref().ok().map(|f| f.num_nodes()),
        not_a_controller: fsc.err(),
        written: args.fsc.map(|p| p.display().to_string()),
    })
}
