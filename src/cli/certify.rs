//! `posg-fsc certify`: the certified bounds of method.md section 6 for a
//! defender controller and, optionally, an adversary controller.
//!
//! Prints one JSON object: `lower` is the defender's guaranteed probability
//! of the formula against every adversary (of any size, observation and
//! memory); `upper` (null without `--adversary`) is the best probability any
//! defender achieves against the given adversary; `belief` (null but for a
//! one-player game, and where the belief bound has nothing to say) is the
//! best any defender of any memory achieves. The strategies behind them
//! are written to files on request (`--attack`, `--response`; format in
//! docs/formats.md section 7, read back by `posg-fsc strategy`).

use std::path::{Path, PathBuf};

use clap::Args;
use posg_fsc::automaton::Dra;
use posg_fsc::certify::strategy::StrategyFile;
use posg_fsc::certify::{Bound, CertificateReport, certificate};
use posg_fsc::controller::Role;
use posg_fsc::controller::file::resolve;
use posg_fsc::game::Posg;
use serde::Serialize;

use super::common::{self, ObjectiveArgs, Provenance};

/// Arguments of `certify`.
#[derive(Debug, Args)]
pub struct CertifyArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
    game: PathBuf,
    #[command(flatten)]
    objective: ObjectiveArgs,
    #[command(flatten)]
    solver: common::SolverArgs,
    /// With --automaton: a deterministic automaton for !phi (HOA), needed for
    /// the lower bound (with --ltl, !phi is translated).
    #[arg(long, value_name = "FILE.hoa", requires = "automaton")]
    negated_automaton: Option<PathBuf>,
    /// The defender's controller: a `*.fsc.json` file or `uniform:K`.
    #[arg(long)]
    defender: String,
    /// The adversary's controller for the upper bound: a file or `uniform:K`.
    #[arg(long)]
    adversary: Option<String>,
    /// Write the adversary's optimal strategy against the defender here (a
    /// strategy file, docs/formats.md section 7; `posg-fsc strategy` reads it).
    #[arg(long, value_name = "FILE.json")]
    attack: Option<PathBuf>,
    /// Write the defender's optimal strategy against the adversary here (as
    /// --attack).
    #[arg(long, value_name = "FILE.json")]
    response: Option<PathBuf>,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    provenance: Provenance,
    game: String,
    formula: String,
    #[serde(flatten)]
    certificate: CertificateReport,
}

/// Computes and prints the bounds.
pub fn run(args: CertifyArgs) -> anyhow::Result<()> {
    let game = common::read_game_for(&args.game, &args.objective)?;
    let (phi_dra, formula) = common::objective(&args.objective, &game)?;
    let not_phi_dra =
        common::negated_objective(&args.objective, args.negated_automaton.as_deref(), &game)?;
    let defender = resolve(&args.defender, &game, Role::Defender)?;
    let adversary = (args.adversary.as_ref())
        .map(|spec| resolve(spec, &game, Role::Adversary))
        .transpose()?;
    let settings = args.solver.settings();
    let certificate = certificate(
        &game,
        (&phi_dra, &not_phi_dra),
        &defender,
        adversary.as_ref(),
        &settings,
    )?;
    let strategy = |path: Option<&Path>, dra: &Dra, bound: &Bound, nodes: usize| {
        write_strategy(path, &game, dra, bound, nodes, &formula)
    };
    let lower = &certificate.lower;
    strategy(
        args.attack.as_deref(),
        &not_phi_dra,
        lower,
        defender.num_nodes(),
    )?;
    if let (Some(upper), Some(adversary)) = (&certificate.upper, &adversary) {
        strategy(
            args.response.as_deref(),
            &phi_dra,
            upper,
            adversary.num_nodes(),
        )?;
    }
    common::print_json(&Report {
        provenance: Provenance::current(),
        game: args.game.display().to_string(),
        formula: formula.clone(),
        certificate: certificate.report(),
    })
}

/// Writes the strategy of `bound`, computed on the product with `dra` and a
/// controller of `nodes` nodes, when a path was given.
fn write_strategy(
    path: Option<&Path>,
    game: &Posg,
    dra: &Dra,
    bound: &Bound,
    nodes: usize,
    formula: &str,
) -> anyhow::Result<()> {
    if let Some(path) = path {
        let command = Provenance::current().command;
        StrategyFile::new(game, dra, bound, nodes, formula, command).write(path)?;
    }
    Ok(())
}
