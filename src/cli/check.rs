//! `posg-fsc check`: validate a game file and describe it.

use std::path::PathBuf;

use clap::Args;
use posg_fsc::game::{AdversaryAction, DefenderAction, Posg};

use super::common;

/// Arguments of `check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
    pub game: PathBuf,
}

/// Runs `check`: prints the game's sizes and names, or the first error.
pub fn run(args: CheckArgs) -> anyhow::Result<()> {
    let game = common::read_game(&args.game)?;
    common::print_text(&describe(&game))
}

fn list(names: &[String]) -> String {
    const SHOWN: usize = 12;
    let mut text = names
        .iter()
        .take(SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        text.push_str(&format!(", ... ({} more)", names.len() - SHOWN));
    }
    text
}

fn describe(game: &Posg) -> String {
    let transitions: usize = (0..game.num_states())
        .flat_map(|s| {
            (0..game.defender().num_actions())
                .flat_map(move |u| (0..game.adversary().num_actions()).map(move |v| (s, u, v)))
        })
        .map(|(s, u, v)| {
            game.transition(s, DefenderAction(u), AdversaryAction(v))
                .len()
        })
        .sum();
    let player = |name: &str, p: &posg_fsc::game::Player| {
        let observe = if p.observes_fully() {
            " (full observation)"
        } else {
            ""
        };
        let restricted = (0..p.num_observations())
            .filter(|&o| p.enabled_actions(o).count() < p.num_actions())
            .count();
        let enabled = if restricted > 0 {
            format!("  enabled: {restricted} observations enable only some actions\n")
        } else {
            String::new()
        };
        format!(
            "{name}:\n  actions ({}): {}\n  observations ({}){observe}: {}\n{enabled}",
            p.num_actions(),
            list(p.actions()),
            p.num_observations(),
            list(p.observations())
        )
    };
    let mut text = format!(
        "game {}: valid\nstates ({}): {}\npropositions ({}): {}\n",
        game.name().unwrap_or("(unnamed)"),
        game.num_states(),
        list(game.states()),
        game.propositions().len(),
        list(game.propositions())
    );
    text.push_str(&player("defender", game.defender()));
    if game.has_adversary() {
        text.push_str(&player("adversary", game.adversary()));
    } else {
        text.push_str("adversary: none (a POMDP)\n");
    }
    text.push_str(&format!(
        "transitions: {transitions} (state, defender action, adversary action, successor) entries\n"
    ));
    text
}
