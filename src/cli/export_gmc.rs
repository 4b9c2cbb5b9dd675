//! `posg-fsc export-gmc`: the labelled Markov chain on (s, g, h) in Storm's
//! DRN format and PRISM's explicit format, for an independent check with
//! Storm or PRISM.

use std::path::PathBuf;

use clap::Args;
use posg_fsc::output::OutputDirectory;
use posg_fsc::output::export::{explicit_chain, write_explicit_chain};
use serde::Serialize;

use super::common::{self, ControllerArgs, Provenance};

/// Arguments of `export-gmc`.
#[derive(Debug, Args)]
pub struct ExportGmcArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
    pub game: PathBuf,
    #[command(flatten)]
    pub controllers: ControllerArgs,
    /// Directory for chain.drn (Storm), chain.tra, chain.lab and chain.sta
    /// (PRISM's explicit format), created if needed. State 0 is a fresh
    /// initial state: check `X phi` there (docs/guide.md, "Check a value
    /// independently with Storm or PRISM").
    #[arg(long)]
    pub out: PathBuf,
    /// Replace a non-empty --out whole (without it, a non-empty --out is refused).
    #[arg(long)]
    pub force: bool,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    provenance: Provenance,
    directory: String,
    states: usize,
    transitions: usize,
    property_hint: &'static str,
}

/// Runs `export-gmc`.
pub fn run(args: ExportGmcArgs) -> anyhow::Result<()> {
    let game = common::read_game(&args.game)?;
    if let Some(reserved) = game
        .propositions()
        .iter()
        .find(|p| *p == "init" || *p == "deadlock")
    {
        anyhow::bail!(
            "the proposition '{reserved}' clashes with a reserved label of the explicit format"
        );
    }
    let (defender, adversary) = common::controllers(&args.controllers, &game)?;
    let out = OutputDirectory::create(&args.out, args.force)?;
    let chain = explicit_chain(&game, &defender, &adversary)?;
    write_explicit_chain(&chain, out.path())?;
    out.commit()?;
    common::print_json(&Report {
        provenance: Provenance::current(),
        directory: args.out.display().to_string(),
        states: chain.summary.states,
        transitions: chain.summary.transitions,
        property_hint: "state 0 is a fresh initial state: the value of phi is P=? [ X phi ] there",
    })
}
