//! `posg-fsc import-drn`: a POMDP, MDP or DTMC in Storm's explicit DRN
//! format as a game file (docs/formats.md section 6).

use std::path::PathBuf;

use clap::Args;

use super::common::print_text;

/// Arguments of `import-drn`.
#[derive(Debug, Args)]
pub struct ImportDrnArgs {
    /// The model in Storm's DRN format (`storm --prism M.prism --buildfull
    /// --exportbuild M.drn`, or stormpy's `export_to_drn`).
    model: PathBuf,
    /// Write the game here instead of to standard output.
    #[arg(long, value_name = "GAME.posg.json")]
    out: Option<PathBuf>,
}

/// Reads the model, prints what was dropped on stderr and writes the game.
pub fn run(args: ImportDrnArgs) -> anyhow::Result<()> {
    let import = posg_fsc::game::drn::read(&args.model)?;
    for warning in &import.warnings {
        eprintln!("warning: {warning}");
    }
    match &args.out {
        Some(path) => Ok(posg_fsc::game::file::write(path, &import.game)?),
        None => print_text(&(posg_fsc::game::file::to_json_string(&import.game) + "\n")),
    }
}
