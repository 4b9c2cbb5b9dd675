//! Subcommands. Each module defines `XArgs` (what the user typed, validated
//! by clap) and `run(XArgs) -> anyhow::Result<()>`, which builds the library's
//! objects from those arguments and prints or writes the results.

mod certify;
mod check;
mod common;
mod demo;
mod dot;
mod eval;
mod example;
mod export_gmc;
mod help;
mod import_drn;
pub(crate) mod interrupt;
mod progress;
mod prune;
mod shard;
mod simulate;
mod slurm;
pub(crate) mod solve;
mod strategy;
pub(crate) mod support;
mod sweep;
mod translate;

use clap::{Parser, Subcommand};

/// posg-fsc: finite-state controllers for partially observable stochastic
/// games under LTL objectives.
#[derive(Debug, Parser)]
#[command(name = "posg-fsc", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the main job on the seed paper's 3x2 grid and explain the output.
    Demo(demo::DemoArgs),
    /// Write a built-in example game (*.posg.json).
    Example(example::ExampleArgs),
    /// Validate a game file and describe it.
    Check(check::CheckArgs),
    /// Convert a POMDP, MDP, DTMC, SMG or POSMG from Storm's DRN format into a game file
    /// (docs/formats.md section 6).
    ImportDrn(import_drn::ImportDrnArgs),
    /// The exact value of a controller pair, as JSON.
    Eval(eval::EvalArgs),
    /// A Monte Carlo estimate of the value with a 95% confidence interval.
    Simulate(simulate::SimulateArgs),
    /// Export the Markov chain on (s, g, h) for Storm (DRN) and PRISM
    /// (explicit format; docs/formats.md section 8).
    ExportGmc(export_gmc::ExportGmcArgs),
    /// Algorithm 1: prune FSC structures so that a phi-feasible recurrent set exists.
    Prune(prune::PruneArgs),
    /// Certified lower and upper bounds (MDP analysis, docs/method.md section 6).
    Certify(certify::CertifyArgs),
    /// Read a strategy file of `certify --attack/--response` (docs/formats.md
    /// section 7), check it against the game and, where possible, write it as
    /// a controller.
    Strategy(strategy::StrategyArgs),
    /// Optimise a defender FSC against a worst-case adversary FSC (max-min by
    /// alternating projected gradient ascent-descent with best-response
    /// checks) and write curve.csv, curve.svg, defender.fsc.json,
    /// defender.dot, adversary.fsc.json and summary.json.
    Solve(solve::SolveArgs),
    /// A defender support that wins positively or almost surely against every
    /// adversary, found by SAT, or a proof that none of that size exists; writes
    /// support.json and defender.fsc.json.
    Support(support::SupportArgs),
    /// Run `solve` for every pair of controller sizes in parallel and write
    /// sweep.csv and sweep.svg.
    Sweep(sweep::SweepArgs),
    /// Join the shards of `sweep --shard K/N` into sweep.csv and sweep.svg
    /// (naming any size pair that is missing).
    SweepMerge(sweep::SweepMergeArgs),
    /// Translate an LTL formula into a deterministic Rabin automaton.
    Translate(translate::TranslateArgs),
    /// Draw a controller as a Graphviz graph (nodes, and edges labelled
    /// observation / action  probability; docs/formats.md section 10).
    Dot(dot::DotArgs),
}

/// The command line as the user typed it, with `solve --help` and `sweep
/// --help` grouped under headings ([`help`]); exits with clap's message
/// on a usage error.
pub fn parse() -> Cli {
    use clap::{CommandFactory, FromArgMatches};
    let matches = help::with_headings(Cli::command()).get_matches();
    Cli::from_arg_matches(&matches).unwrap_or_else(|error| error.exit())
}

/// Runs the subcommand the user chose.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo(args) => demo::run(args),
        Command::Example(args) => example::run(args),
        Command::Check(args) => check::run(args),
        Command::ImportDrn(args) => import_drn::run(args),
        Command::Eval(args) => eval::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::ExportGmc(args) => export_gmc::run(args),
        Command::Prune(args) => prune::run(args),
        Command::Certify(args) => certify::run(args),
        Command::Strategy(args) => strategy::run(args),
        Command::Solve(args) => solve::run(args),
        Command::Support(args) => support::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::SweepMerge(args) => sweep::run_merge(args),
        Command::Translate(args) => translate::run(args),
        Command::Dot(args) => dot::run(args),
    }
}
