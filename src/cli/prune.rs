//! `posg-fsc prune`: the paper's Algorithm 1 on a game and an LTL formula.
//!
//! Writes, into `--out`, one pair of controller files per kept structure
//! (`structure-K.defender.fsc.json`, `structure-K.adversary.fsc.json`,
//! uniform over the kept support, ready for `eval`) and `structures.json`:
//! for each structure the SCCs and Rabin pairs that produced it, `|Bad|`,
//! `|Good|`, the number of removed entries and the exact value of the
//! uniform controllers; then every attempt and every stop at line 9's guard.

use std::path::{Path, PathBuf};

use clap::Args;
use serde_json::{Value, json};

use posg_fsc::automaton::Dra;
use posg_fsc::controller::{Fsc, Role, file};
use posg_fsc::game::Posg;
use posg_fsc::output::{OutputDirectory, write_file};
use posg_fsc::prune::{Attempt, LastOptionStop, PruneReport, PruneSettings, prune};
use posg_fsc::value::GmcState;
use posg_fsc::value::SolverSettings;
use posg_fsc::value::evaluate_controllers;

use super::common::{ObjectiveArgs, Provenance, objective, read_game_for};

/// Arguments of `prune`.
#[derive(Debug, Args)]
pub struct PruneArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
    game: PathBuf,
    #[command(flatten)]
    objective: ObjectiveArgs,
    /// Defender FSC size; the initial structure is the full support.
    #[arg(long, default_value_t = 1, conflicts_with = "defender")]
    def_nodes: usize,
    /// Adversary FSC size; the initial structure is the full support.
    #[arg(long, default_value_t = 1, conflicts_with = "adversary")]
    adv_nodes: usize,
    /// Initial defender structure: the support of this controller file (or `uniform:K`).
    #[arg(long)]
    defender: Option<String>,
    /// Initial adversary structure: the support of this controller file (or `uniform:K`).
    #[arg(long)]
    adversary: Option<String>,
    /// Lines 14-16 as printed: remove the action under the observation for all nodes.
    #[arg(long)]
    paper_literal: bool,
    /// Run lines 18-23, which prune the adversary (off: a max-min guarantee
    /// must not restrict the adversary).
    #[arg(long)]
    prune_adversary: bool,
    /// The output directory (created if missing, written atomically).
    #[arg(long)]
    out: PathBuf,
    /// Replace a non-empty --out whole (without it, a non-empty --out is refused).
    #[arg(long)]
    force: bool,
}

/// Runs Algorithm 1 and writes the structures and `structures.json`.
pub fn run(args: PruneArgs) -> anyhow::Result<()> {
    let game = read_game_for(&args.game, &args.objective)?;
    let (dra, objective_text) = objective(&args.objective, &game)?;
    let defender = initial_structure(
        &game,
        Role::Defender,
        args.defender.as_deref(),
        args.def_nodes,
    )?;
    let adversary = initial_structure(
        &game,
        Role::Adversary,
        args.adversary.as_deref(),
        args.adv_nodes,
    )?;
    let settings = PruneSettings {
        paper_literal: args.paper_literal,
        prune_adversary: args.prune_adversary,
    };
    let out = OutputDirectory::create(&args.out, args.force)?;
    let report = prune(&game, &dra, &defender, &adversary, &settings)?;
    let mut structures = Vec::new();
    for (k, structure) in report.structures.iter().enumerate() {
        let names = write_structure(
            out.path(),
            k,
            &game,
            &structure.defender,
            &structure.adversary,
        )?;
        let value = uniform_value(&game, &dra, &structure.defender, &structure.adversary)?;
        println!("structure {k}: value of the uniform controllers {value}");
        structures.push(json!({
            "defender": names.0,
            "adversary": names.1,
            "value": value,
            "witness": describe(&game, structure.witness),
            "produced_by": structure.attempts.iter().map(|&a| attempt_json(&report.attempts[a])).collect::<Vec<_>>(),
        }));
    }
    let summary = json!({
        "provenance": Provenance::current(),
        "game": args.game.display().to_string(),
        "objective": objective_text,
        "automaton": {"states": dra.num_states(), "pairs": dra.pairs().len()},
        "defender_nodes": defender.num_nodes(),
        "adversary_nodes": adversary.num_nodes(),
        "initial_defender": args.defender.clone().unwrap_or_else(|| "full support".into()),
        "initial_adversary": args.adversary.clone().unwrap_or_else(|| "full support".into()),
        "initial_value": uniform_value(&game, &dra, &defender, &adversary)?,
        "settings": settings,
        "adversary_pruned": settings.prune_adversary,
        "note": note(&settings),
        "gmc_states": report.gmc_states,
        "sccs": report.sccs,
        "skipped_empty_good": report.skipped,
        "structures": structures,
        "attempts": report.attempts.iter().map(attempt_json).collect::<Vec<_>>(),
        "stops": stops_json(&game, &report),
    });
    write_file(
        &out.join("structures.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    out.commit()?;
    print_summary(&report);
    Ok(())
}

/// The initial structure of one player: a controller file's support, or the
/// full support on `nodes` nodes starting in node 0.
fn initial_structure(
    game: &Posg,
    role: Role,
    spec: Option<&str>,
    nodes: usize,
) -> anyhow::Result<Fsc> {
    let spec = spec.map_or_else(|| format!("uniform:{nodes}"), str::to_string);
    Ok(file::resolve(&spec, game, role)?)
}

fn write_structure(
    out: &Path,
    k: usize,
    game: &Posg,
    defender: &Fsc,
    adversary: &Fsc,
) -> anyhow::Result<(String, String)> {
    let names = (
        format!("structure-{k}.defender.fsc.json"),
        format!("structure-{k}.adversary.fsc.json"),
    );
    file::write(&out.join(&names.0), defender, game)?;
    file::write(&out.join(&names.1), adversary, game)?;
    Ok(names)
}

/// The exact value of a controller pair.
fn uniform_value(game: &Posg, dra: &Dra, defender: &Fsc, adversary: &Fsc) -> anyhow::Result<f64> {
    Ok(
        evaluate_controllers(game, dra, defender, adversary, &SolverSettings::default())?
            .1
            .value,
    )
}

fn note(settings: &PruneSettings) -> &'static str {
    if settings.prune_adversary {
        "the adversary's support was pruned (lines 18-23): values are not max-min guarantees against the full adversary"
    } else {
        "the adversary keeps its full initial support"
    }
}

fn describe(game: &Posg, m: GmcState) -> String {
    format!(
        "({}, q{}, g{}, h{})",
        game.states()[m.s as usize],
        m.q,
        m.g,
        m.h
    )
}

fn attempt_json(a: &Attempt) -> Value {
    json!({
        "scc": a.scc, "scc_size": a.scc_size, "pair": a.pair, "bad": a.bad, "good": a.good,
        "removed_defender": a.removed_defender, "removed_adversary": a.removed_adversary,
        "stopped": a.stop.is_some(), "structure": a.structure,
    })
}

fn stops_json(game: &Posg, report: &PruneReport) -> Vec<Value> {
    report.stops().map(|(a, s)| stop_json(game, a, s)).collect()
}

fn stop_json(game: &Posg, a: &Attempt, s: &LastOptionStop) -> Value {
    let player = s.player.player(game);
    json!({
        "scc": a.scc, "pair": a.pair,
        "bad_state": describe(game, s.bad_state),
        "player": s.player,
        "node": s.node,
        "observation": player.observations()[s.observation],
        "last_entry": {"next": s.entry.0, "action": player.actions()[s.entry.1]},
    })
}

fn print_summary(report: &PruneReport) {
    println!(
        "GMC: {} states, {} SCCs; {} (SCC, pair) attempts, {} skipped (empty Good)",
        report.gmc_states,
        report.sccs,
        report.attempts.len(),
        report.skipped
    );
    println!("kept structures: {}", report.structures.len());
    for (a, s) in report.stops() {
        println!(
            "stopped: SCC {} pair {}: the {:?} block (node {}, observation {}) would lose its last option",
            a.scc, a.pair, s.player, s.node, s.observation
        );
    }
    if report.settings.prune_adversary {
        println!("note: the adversary was pruned (--prune-adversary)");
    }
}
