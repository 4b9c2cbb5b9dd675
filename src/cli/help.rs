//! The headings of `solve --help` and `sweep --help`: the options most runs
//! need come first, under clap's "Options"; the others are grouped under
//! headings by what they tune. The options come from several flattened
//! structures (the library's optimiser and synthesis settings among them),
//! so the headings are set here, on the built command, by option id.

use clap::Command;

/// The options shown first, without a heading (by clap id).
const COMMON: &[&str] = &[
    "ltl",
    "automaton",
    "props",
    "def_nodes",
    "adv_nodes",
    "out",
    "force",
    "seed",
    "starts",
    "max_iterations",
    "max_work",
    "time_budget",
    "structures",
    "quiet",
    "format",
    "shard",
    "slurm",
    "slurm_option",
    "shards",
    "help",
];

/// The other options by heading, in the order the headings are shown; an
/// option in none of them goes under [`OTHER`].
const HEADINGS: &[(&str, &[&str])] = &[
    (
        "Objective",
        &["allow_unused_propositions", "translate_seconds"],
    ),
    (
        "Starting point",
        &[
            "defender",
            "adversary",
            "initial_spread",
            "initial_logit_bound",
            "optimise_initial",
            "grow_defender",
        ],
    ),
    (
        "Optimiser steps",
        &[
            "logit_bound",
            "adversary_steps",
            "defender_step",
            "adversary_step",
            "defender_decay",
            "bold_step_factor",
            "update",
            "optimism",
            "no_single_player_ascent",
            "single_player_ascent",
        ],
    ),
    (
        "Best-response checks",
        &[
            "check_every",
            "best_response_every",
            "restarts",
            "best_response_iterations",
            "lbfgs_memory",
            "guarantee_ascent",
        ],
    ),
    (
        "Stopping",
        &[
            "gap_tolerance",
            "stall_checks",
            "stall_gain",
            "ascent_stall_iterations",
            "stall_tolerance",
        ],
    ),
    (
        "Rounding",
        &[
            "round",
            "local_search",
            "local_search_restarts",
            "local_search_work",
        ],
    ),
    (
        "Support synthesis (--structures sat) and Algorithm 1 (paper)",
        &[
            "engine",
            "rank_bound",
            "rank_encoding",
            "maximise",
            "confirm_certificate",
            "clause_budget",
            "synthesis_time_budget",
            "prune_paper_literal",
            "prune_adversary",
        ],
    ),
    ("Linear solver", &["solver", "lu_limit", "tolerance"]),
    ("Output", &["progress_every", "seconds_axis", "size", "dpi"]),
];

/// The heading of an option in no list (one added later).
const OTHER: &str = "Other options";

/// `command` with the headings set on its `solve` and `sweep` subcommands.
pub fn with_headings(command: Command) -> Command {
    command
        .mut_subcommand("solve", grouped)
        .mut_subcommand("sweep", grouped)
}

/// The heading of the option `id`: `None` for a common one.
fn heading(id: &str) -> Option<&'static str> {
    if COMMON.contains(&id) {
        return None;
    }
    let listed = HEADINGS.iter().find(|(_, ids)| ids.contains(&id));
    Some(listed.map_or(OTHER, |(heading, _)| heading))
}

/// A subcommand with its options under their headings, the headings in
/// the order of [`HEADINGS`].
fn grouped(command: Command) -> Command {
    let ids: Vec<String> = command
        .get_arguments()
        .filter(|a| !a.is_positional())
        .map(|a| a.get_id().to_string())
        .collect();
    let rank = |id: &str| {
        let listed = HEADINGS.iter().position(|(_, ids)| ids.contains(&id));
        match heading(id) {
            None => 0,
            Some(_) => 1 + listed.unwrap_or(HEADINGS.len()),
        }
    };
    let mut order: Vec<(usize, usize, String)> = ids
        .into_iter()
        .enumerate()
        .map(|(position, id)| (rank(&id), position, id))
        .collect();
    order.sort();
    order
        .into_iter()
        .enumerate()
        .fold(command, |command, (display, (_, _, id))| {
            let heading = heading(&id);
            command.mut_arg(id, |arg| arg.help_heading(heading).display_order(display))
        })
}
