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
//!
//! With an expected-reward query (`--props` with `R{"r"}min=? [F T]` or
//! `Rmax`; method.md section 9) it prints the reward's certificate instead:
//! `guaranteed`, the cost the defender never exceeds (the reward it always
//! gets) against every adversary, and with `--adversary`, `best_possible`,
//! the cost no defender gets below (the reward none exceeds) against it;
//! each with the bracket of the optimum behind it.

use std::path::{Path, PathBuf};

use clap::Args;
use posg_fsc::automaton::Dra;
use posg_fsc::certify::reward::{RewardCertificate, reward_certificate};
use posg_fsc::certify::strategy::StrategyFile;
use posg_fsc::certify::{Bound, CertificateReport, certificate};
use posg_fsc::controller::Role;
use posg_fsc::controller::file::resolve;
use posg_fsc::game::Posg;
use posg_fsc::pipeline::RewardObjective;
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

/// The certificate of an expected-reward query.
#[derive(Serialize)]
struct RewardReport {
    #[serde(flatten)]
    provenance: Provenance,
    game: String,
    query: String,
    #[serde(flatten)]
    certificate: RewardCertificate,
}

/// Computes and prints the bounds.
pub fn run(args: CertifyArgs) -> anyhow::Result<()> {
    let game = common::read_game_for(&args.game, &args.objective)?;
    if let Some(reward) = args.objective.reward_objective(&game)? {
        return run_reward(&args, &game, &reward);
    }
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

/// The certificate of the expected-reward query `reward` (module
/// documentation).
fn run_reward(args: &CertifyArgs, game: &Posg, reward: &RewardObjective) -> anyhow::Result<()> {
    if args.attack.is_some() || args.response.is_some() {
        anyhow::bail!(
            "--attack and --response write the strategies of probability queries; an \
             expected-reward query has none written yet"
        );
    }
    let defender = resolve(&args.defender, game, Role::Defender)?;
    let adversary = (args.adversary.as_ref())
        .map(|spec| resolve(spec, game, Role::Adversary))
        .transpose()?;
    let certificate = reward_certificate(
        game,
        (&reward.target, &reward.rewards, reward.minimise),
        &defender,
        &adversary.iter().collect::<Vec<_>>(),
        &args.solver.settings(),
    )?;
    common::print_json(&RewardReport {
        provenance: Provenance::current(),
        game: args.game.display().to_string(),
        query: reward.description.clone(),
        certificate,
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
