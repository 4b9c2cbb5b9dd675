//! `posg-fsc import-drn`: a POMDP, MDP, DTMC, or a turn-based game (SMG,
//! POSMG), in Storm's explicit DRN format as a game file (docs/formats.md
//! section 6).

use std::path::PathBuf;

use clap::Args;
use posg_fsc::game::drn::DrnOptions;

use super::common::{self, print_text};

/// Arguments of `import-drn`.
#[derive(Debug, Args)]
pub struct ImportDrnArgs {
    /// The model in Storm's DRN format (`storm --prism M.prism --buildfull
    /// --exportbuild M.drn`, stormpy's `export_to_drn`, or PRISM-games' and
    /// PAYNT's `@type: SMG`/`POSMG` files).
    model: PathBuf,
    /// Write the game here instead of to standard output.
    #[arg(long, value_name = "GAME.posg.json")]
    out: Option<PathBuf>,
    /// In a turn-based game (SMG, POSMG): the player `<P>` who is the
    /// defender; the other player is the adversary [default: 0, or the
    /// player of --props].
    #[arg(long, value_name = "P")]
    defender_player: Option<u64>,
    /// A property file whose query `<<P>> Pmax=? [...]` names the defender
    /// (the same file `solve --props` reads).
    #[arg(long, value_name = "FILE.props")]
    props: Option<PathBuf>,
}

/// Reads the model, prints on stderr how it renamed action labels that are
/// not names, and writes the game.
pub fn run(args: ImportDrnArgs) -> anyhow::Result<()> {
    let options = options(&args)?;
    let import = posg_fsc::game::drn::read_with(&args.model, &options)?;
    for warning in &import.warnings {
        eprintln!("warning: {warning}");
    }
    match &args.out {
        Some(path) => Ok(posg_fsc::game::file::write(path, &import.game)?),
        None => print_text(&(posg_fsc::game::file::to_json_string(&import.game) + "\n")),
    }
}

/// The import options: `--defender-player`, or the player of the `--props`
/// query (then errors about it name the query); the two must agree.
fn options(args: &ImportDrnArgs) -> anyhow::Result<DrnOptions> {
    let property = args.props.as_deref().map(common::read_props).transpose()?;
    let from_props = common::drn_options(args.props.as_deref().zip(property.as_ref()));
    match (args.defender_player, from_props.defender_player) {
        (Some(given), Some(named)) if given != named => anyhow::bail!(
            "--defender-player {given} disagrees with the query of {}, which optimises for \
             player {named}",
            from_props
                .defender_source
                .as_deref()
                .expect("a player from --props")
        ),
        (Some(given), None) => Ok(DrnOptions {
            defender_player: Some(given),
            defender_source: None,
        }),
        _ => Ok(from_props),
    }
}
