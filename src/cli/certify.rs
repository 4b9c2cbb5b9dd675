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
use posg_fsc::certify::belief::{BeliefBound, belief_bound_above};
use posg_fsc::certify::strategy::StrategyFile;
use posg_fsc::certify::{Bound, check_consistent, lower_bound_within, upper_bound_within};
use posg_fsc::controller::Role;
use posg_fsc::controller::file::resolve;
use posg_fsc::game::Posg;
use serde::Serialize;

use super::common::{self, ObjectiveArgs, Provenance};

/// Arguments of `certify`.
#[derive(Debug, Args)]
pub struct CertifyArgs {
    /// The game (`*.posg.json`).
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
    lower: BoundSummary,
    upper: Option<BoundSummary>,
    /// A one-player game's belief bound (method.md section 6): no defender
    /// of any memory does better.
    belief: Option<BeliefBound>,
}

/// A bound without its strategy.
#[derive(Serialize)]
struct BoundSummary {
    value: f64,
    mdp_states: usize,
    seconds: f64,
    residual: f64,
    /// A bound on the error of `value` (method.md section 8).
    error_bound: f64,
}

impl From<&Bound> for BoundSummary {
    fn from(bound: &Bound) -> Self {
        Self {
            value: bound.value,
            mdp_states: bound.mdp_states,
            seconds: bound.seconds,
            residual: bound.residual,
            error_bound: bound.error_bound,
        }
    }
}

/// Computes and prints the bounds.
pub fn run(args: CertifyArgs) -> anyhow::Result<()> {
    let game = common::read_game_for(&args.game, &args.objective)?;
    let (phi_dra, formula) = common::objective(&args.objective, &game)?;
    let not_phi_dra =
        common::negated_objective(&args.objective, args.negated_automaton.as_deref(), &game)?;
    let defender = resolve(&args.defender, &game, Role::Defender)?;
    let settings = args.solver.settings();
    let lower = lower_bound_within(&game, &not_phi_dra, &defender, &settings)?;
    let strategy = |path: Option<&Path>, dra: &Dra, bound: &Bound, nodes: usize| {
        write_strategy(path, &game, dra, bound, nodes, &formula)
    };
    strategy(
        args.attack.as_deref(),
        &not_phi_dra,
        &lower,
        defender.num_nodes(),
    )?;
    let upper = match &args.adversary {
        Some(spec) => {
            let adversary = resolve(spec, &game, Role::Adversary)?;
            let upper = upper_bound_within(&game, &phi_dra, &adversary, &settings)?;
            check_consistent(&lower, &upper)?;
            strategy(
                args.response.as_deref(),
                &phi_dra,
                &upper,
                adversary.num_nodes(),
            )?;
            Some(upper)
        }
        None => None,
    };
    // The belief bound holds for every defender, this one included.
    let belief = belief_bound_above(&game, &phi_dra, &lower, &settings)?;
    common::print_json(&Report {
        provenance: Provenance::current(),
        game: args.game.display().to_string(),
        formula,
        lower: (&lower).into(),
        upper: upper.as_ref().map(BoundSummary::from),
        belief,
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
