//! `posg-fsc support`: a defender support that wins positively or almost
//! surely against the certification adversary, by SAT (method.md section
//! 7), or a proof that none of that size exists.
//!
//! Writes `support.json` (formats.md section 5) and, when a support is
//! found, `defender.fsc.json` (uniform on the maximised support) into the
//! output directory, and one summary line on stderr.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use posg_fsc::controller;
use posg_fsc::output::{OutputDirectory, write_file};
use posg_fsc::synthesis::{self, Confirmation, Mode, SatStatistics, Settings, Synthesis};
use posg_fsc::value::SolverSettings;
use serde::Serialize;

use super::common::{self, ObjectiveArgs, Provenance};

/// Arguments of `support`.
#[derive(Debug, Args)]
pub struct SupportArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
    game: PathBuf,
    #[command(flatten)]
    objective: ObjectiveArgs,
    /// With --automaton: a deterministic automaton for !phi (HOA), for the
    /// certification of the support found (with --ltl, !phi is translated).
    #[arg(long, value_name = "FILE.hoa", requires = "automaton")]
    negated_automaton: Option<PathBuf>,
    /// Defender FSC size (nodes).
    #[arg(long, default_value_t = 1)]
    def_nodes: usize,
    /// Ask for almost-sure winning (certified lower bound 1) instead of
    /// positive winning (certified lower bound > 0).
    #[arg(long)]
    almost_sure: bool,
    /// Directory for support.json and defender.fsc.json (created if
    /// missing, written atomically).
    #[arg(long)]
    out: PathBuf,
    /// Replace a non-empty --out whole (without it, a non-empty --out is refused).
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    settings: Settings,
    /// Also write the SAT instance (before maximisation) in DIMACS CNF here.
    #[arg(long, value_name = "FILE.cnf")]
    dimacs: Option<PathBuf>,
}

/// `support.json` (formats.md section 5).
#[derive(Debug, Serialize)]
struct SupportFile<'a> {
    found: bool,
    mode: Mode,
    defender_nodes: usize,
    defender: Option<&'static str>,
    certified_lower: Option<f64>,
    support_entries: usize,
    /// Whether `found: false` is a proof (one usable Rabin pair, exact rank bound).
    exact: bool,
    reason: &'a str,
    /// How the certificate formula confirmed the support (lazy engine).
    confirmation: Confirmation,
    sat: Option<SatStatistics>,
    game: String,
    objective: &'a str,
    settings: &'a Settings,
    #[serde(flatten)]
    provenance: Provenance,
}

/// Runs `support`.
pub fn run(args: SupportArgs) -> anyhow::Result<()> {
    let mode = if args.almost_sure {
        Mode::AlmostSure
    } else {
        Mode::Positive
    };
    let settings = Settings {
        mode,
        ..args.settings.clone()
    };
    settings.validate()?;
    let game = common::read_game_for(&args.game, &args.objective)?;
    let defender = game.defender();
    controller::Fsc::check_uniform_size(
        "--def-nodes",
        args.def_nodes,
        defender.num_observations(),
        defender.num_actions(),
    )?;
    let out = OutputDirectory::create(&args.out, args.force)?;
    let (dra, objective) = common::objective(&args.objective, &game)?;
    let negated =
        common::negated_objective(&args.objective, args.negated_automaton.as_deref(), &game)?;
    if let Some(path) = &args.dimacs {
        let mut file = std::io::BufWriter::new(
            std::fs::File::create(path)
                .with_context(|| format!("cannot create {}", path.display()))?,
        );
        synthesis::write_dimacs(&game, &dra, args.def_nodes, &settings, &mut file)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let result = synthesis::synthesise(
        &game,
        &dra,
        &negated,
        args.def_nodes,
        &settings,
        &SolverSettings::default(),
    )?;
    if let Some(defender) = &result.defender {
        let path = out.join("defender.fsc.json");
        controller::file::write(&path, defender, &game)?;
    }
    let file = SupportFile {
        found: result.defender.is_some(),
        mode,
        defender_nodes: args.def_nodes,
        defender: result.defender.as_ref().map(|_| "defender.fsc.json"),
        certified_lower: result.certified_lower,
        support_entries: result.support_entries(),
        exact: result.exact,
        reason: &result.reason,
        confirmation: result.confirmation,
        sat: result.statistics,
        game: args.game.display().to_string(),
        objective: &objective,
        settings: &settings,
        provenance: Provenance::current(),
    };
    write_file(
        &out.join("support.json"),
        serde_json::to_string_pretty(&file)? + "\n",
    )?;
    out.commit()?;
    eprintln!("{}", summary_line(&result));
    Ok(())
}

/// One line for a person: found or not, the bound, the instance's size and time.
fn summary_line(synthesis: &Synthesis) -> String {
    let outcome = match synthesis.certified_lower {
        Some(lower) => format!(
            "{}; certified lower bound {lower:.6} ({} support entries)",
            synthesis.reason,
            synthesis.support_entries()
        ),
        None => synthesis.reason.clone(),
    };
    match &synthesis.statistics {
        Some(sat) => format!(
            "{outcome}; SAT: {} variables, {} clauses, {} calls, {} lemmas, {:.2} s",
            sat.variables, sat.clauses, sat.calls, sat.lemmas, sat.seconds
        ),
        None => outcome,
    }
}
