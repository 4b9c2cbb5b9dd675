//! `posg-fsc dot`: a Graphviz picture of a controller (docs/formats.md
//! section 10).

use std::path::{Path, PathBuf};

use clap::Args;
use posg_fsc::controller::Role;
use posg_fsc::controller::file::{read_either, read_standalone, resolve};
use posg_fsc::output::dot::{DEFAULT_THRESHOLD, controller_dot};

use super::common::{self, print_text};

/// Arguments of `dot`.
#[derive(Debug, Args)]
pub struct DotArgs {
    /// The controller: a `*.fsc.json` file or `uniform:K` (K nodes, uniform
    /// over all (next node, enabled action) pairs; needs --game).
    controller: String,
    /// The game it belongs to: checks the controller against it (needed
    /// for `uniform:K` and when the file's `default` is `uniform`).
    #[arg(long)]
    game: Option<PathBuf>,
    /// Whose controller `uniform:K` is: `defender` or `adversary` (a file
    /// names its player itself).
    #[arg(long, default_value = "defender", value_parser = role)]
    player: Role,
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

fn role(text: &str) -> Result<Role, String> {
    match text {
        "defender" => Ok(Role::Defender),
        "adversary" => Ok(Role::Adversary),
        _ => Err(format!("'{text}' is not a player: defender or adversary")),
    }
}

/// Draws the controller.
pub fn run(args: DotArgs) -> anyhow::Result<()> {
    let name = &args.controller;
    let uniform = name.starts_with("uniform:");
    let text = match &args.game {
        Some(game_path) => {
            let game = common::read_game(game_path)?;
            let fsc = if uniform {
                resolve(name, &game, args.player)?
            } else {
                read_either(Path::new(name), &game)?
            };
            let player = fsc.role().player(&game);
            let title = format!("{name}: {} nodes", fsc.num_nodes());
            controller_dot(
                &fsc,
                player.observations(),
                &player.action_labels(),
                &title,
                args.threshold,
            )
        }
        None if uniform => anyhow::bail!(
            "{name}: a uniform controller takes its observations and actions from the game; \
             give --game GAME"
        ),
        None => {
            let file = read_standalone(Path::new(name))?;
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
