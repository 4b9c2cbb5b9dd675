//! Subcommands. Each module defines `XArgs` (what the user typed, validated
//! by clap) and `run(XArgs) -> anyhow::Result<()>`, which builds the library's
//! objects from those arguments and prints or writes the results.

mod demo;
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
    /// Translate an LTL formula into a deterministic Rabin automaton.
    Translate(translate::TranslateArgs),
}

/// Runs the subcommand the user chose.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo(args) => demo::run(args),
        Command::Translate(args) => translate::run(args),
    }
}
