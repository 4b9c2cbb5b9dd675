//! `posg-fsc dot`: a Graphviz picture of a controller (docs/formats.md
//! section 10).

use std::path::PathBuf;

use clap::Args;
use posg_fsc::controller::file::{read_either, read_standalone};
use posg_fsc::output::dot::{DEFAULT_THRESHOLD, controller_dot};

use super::common::{self, print_text};

/// Arguments of `dot`.
#[derive(Debug, Args)]
pub struct DotArgs {
    /// The controller (`*.fsc.json`).
    controller: PathBuf,
    /// The game it belongs to: checks the controller against it (needed
    /// when the file's `default` is `uniform`).
    #[arg(long)]
    game: Option<PathBuf>,
    /// Choices with a smaller probability are hidden (their number is shown).
    #[arg(long, default_value_t = DEFAULT_THRESHOLD, value_parser = threshold)]
    threshold: f64,
    /// Write the picture here instead of to standard output (render it with
    /// `dot -Tsvg FILE.dot -o FILE.svg`).
    #[arg(long, value_name = "FILE.dot")]
    out: Option<PathBuf>,
}

fn threshold(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(t) if (0.0..=1.0).contains(&t) => Ok(t),
        _ => Err(format!("'{text}' is not a probability in [0, 1]")),
    }
}

/// Draws the controller.
pub fn run(args: DotArgs) -> anyhow::Result<()> {
    let name = args.controller.display().to_string();
    let text = match &args.game {
        Some(game_path) => {
            let game = common::read_game(game_path)?;
            let fsc = read_either(&args.controller, &game)?;
            let player = fsc.role().player(&game);
            let title = format!("{name}: {} nodes", fsc.num_nodes());
            controller_dot(
                &fsc,
                player.observations(),
                player.actions(),
                &title,
                args.threshold,
            )
        }
        None => {
            let file = read_standalone(&args.controller)?;
            let title = format!("{name}: {} nodes", file.fsc.num_nodes());
            controller_dot(
                &file.fsc,
                &file.observations,
                &file.actions,
                &title,
                args.threshold,
            )
        }
    };
    match &args.out {
        Some(path) => std::fs::write(path, text)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display())),
        None => print_text(&text),
    }
}
