//! `posg-fsc sweep`: `solve` for every pair of controller sizes (the
//! adversary sizes in parallel, the defender sizes in increasing order, each
//! warm-started from the next smaller one), with a table and a plot of the
//! worst-case estimates.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use rayon::prelude::*;
use serde::Serialize;

use posg_fsc::limits;
use posg_fsc::optimise::{self, Structure, StructureOutcome};
use posg_fsc::output::{OutputDirectory, OutputError, SweepPoint, Title, plot_sweep};

use super::common::{ObjectiveArgs, print_text};
use super::progress::{OutputArgs, ProgressMode, SweepProgress};
use super::solve::{SettingsArgs, SolveJob, check_sizes, load, run_job};

/// Arguments of `sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The game, a `*.posg.json` file (docs/formats.md section 1).
    game: PathBuf,
    #[command(flatten)]
    objective: ObjectiveArgs,
    /// Defender FSC sizes: `A..B` (inclusive), `A,B,C` or `A`.
    #[arg(long, default_value = "1..3", value_parser = parse_sizes)]
    def_nodes: Sizes,
    /// Adversary FSC sizes: `A..B` (inclusive), `A,B,C` or `A`.
    #[arg(long, default_value = "1..2", value_parser = parse_sizes)]
    adv_nodes: Sizes,
    /// Directory for `sweep.csv`, `sweep.svg` and one `solve` directory
    /// `def<N>-adv<M>/` per size pair (written atomically: the results
    /// appear there whole when the run ends).
    #[arg(long)]
    out: PathBuf,
    /// Replace a non-empty --out whole (without it, a non-empty --out is refused).
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    settings: SettingsArgs,
    #[command(flatten)]
    output: OutputArgs,
}

/// A list of positive sizes.
#[derive(Debug, Clone)]
pub struct Sizes(Vec<usize>);

fn parse_sizes(text: &str) -> Result<Sizes, String> {
    let positive = |t: &str| match t.trim().parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!("`{t}` is not a positive integer")),
    };
    let sizes = match text.split_once("..") {
        Some((a, b)) => {
            let (a, b) = (positive(a)?, positive(b)?);
            let count = (b as u128 + 1).saturating_sub(a as u128);
            if let Some(message) = limits::exceeded(
                &format!("the range `{text}`"),
                count,
                limits::MAX_SWEEP_PAIRS,
                "sizes",
                "MAX_SWEEP_PAIRS",
            ) {
                return Err(message);
            }
            (a..=b).collect()
        }
        None => text
            .split(',')
            .map(positive)
            .collect::<Result<Vec<_>, _>>()?,
    };
    if sizes.is_empty() {
        return Err(format!("`{text}` is an empty range"));
    }
    Ok(Sizes(sizes))
}

/// One row of `sweep.csv`: the best structure's numbers for one size pair.
#[derive(Debug, Serialize)]
struct Row {
    defender_nodes: usize,
    adversary_nodes: usize,
    structure: String,
    gmc_states: usize,
    gmc_transitions: usize,
    defender_parameters: usize,
    adversary_parameters: usize,
    last_value: f64,
    worst_case: f64,
    error_bound: f64,
    certified_lower: Option<f64>,
    upper_bound: Option<f64>,
    iterations: usize,
    seconds: f64,
    /// Whether the run started from the best defender of the next smaller size.
    warm_started: bool,
}

/// Runs `sweep`: the adversary sizes in parallel; for each, the defender
/// sizes in increasing order, each warm-started from the best defender of
/// the next smaller size and kept at least as good as it
/// ([`optimise::warm_started`], [`optimise::keep_better`]), so the results
/// are monotone in the defender's size by construction.
pub fn run(args: SweepArgs) -> anyhow::Result<()> {
    let settings = args.settings.settings()?;
    let (game, dra, negated, description) = load(&args.game, &args.objective)?;
    let count = args.def_nodes.0.len() as u128 * args.adv_nodes.0.len() as u128;
    if let Some(message) = limits::exceeded(
        "--def-nodes x --adv-nodes",
        count,
        limits::MAX_SWEEP_PAIRS,
        "size pairs",
        "MAX_SWEEP_PAIRS",
    ) {
        anyhow::bail!(message);
    }
    for &n in &args.def_nodes.0 {
        for &m in &args.adv_nodes.0 {
            check_sizes(&game, n, m)?;
        }
    }
    let out = OutputDirectory::create(&args.out, args.force)?;
    let mut defender_sizes = args.def_nodes.0.clone();
    defender_sizes.sort_unstable();
    defender_sizes.dedup();
    let progress = SweepProgress::new(
        ProgressMode::detect(args.output.quiet),
        defender_sizes.len() * args.adv_nodes.0.len(),
    );
    let rows: Vec<Row> = args
        .adv_nodes
        .0
        .par_iter()
        .map(|&m| {
            let mut rows = Vec::new();
            let mut previous: Option<StructureOutcome> = None;
            for &n in &defender_sizes {
                let out = out.join(format!("def{n}-adv{m}"));
                let mut start = Structure::full(&game, n, m, settings.optimise_initial);
                if let Some(smaller) = &previous {
                    start = optimise::warm_started(
                        start,
                        &smaller.defender,
                        settings.optimise_initial,
                    )?;
                }
                let job = SolveJob {
                    game: &game,
                    dra: &dra,
                    negated_dra: negated.as_ref(),
                    objective: &description,
                    candidates: optimise::candidate_structures(
                        &game,
                        &dra,
                        negated.as_ref(),
                        start,
                        &settings,
                    )?,
                    settings: &settings,
                    out: &out,
                    progress: ProgressMode::Quiet,
                    floor: previous.as_ref(),
                    seconds_axis: args.output.seconds_axis,
                };
                let (solution, certified) = run_job(&job)
                    .with_context(|| format!("defender {n} nodes, adversary {m} nodes"))?;
                let best = solution.best();
                let report = &best.report;
                progress.finished(n, m, report.worst_case);
                rows.push(Row {
                    defender_nodes: n,
                    adversary_nodes: m,
                    structure: report.name.clone(),
                    gmc_states: report.gmc.states,
                    gmc_transitions: report.gmc.transitions,
                    defender_parameters: report.defender_parameters,
                    adversary_parameters: report.adversary_parameters,
                    last_value: report.last_value,
                    worst_case: report.worst_case,
                    error_bound: report.error_bound,
                    certified_lower: certified.map(|b| b.certified_lower),
                    upper_bound: certified.map(|b| b.upper_bound),
                    iterations: report.iterations,
                    seconds: report.seconds,
                    warm_started: previous.is_some(),
                });
                previous = Some(best.clone());
            }
            Ok(rows)
        })
        .collect::<anyhow::Result<Vec<Vec<Row>>>>()?
        .into_iter()
        .flatten()
        .collect();
    progress.finish();
    let table = out.join("sweep.csv");
    let file = std::fs::File::create(&table).map_err(|e| OutputError::io("creating", &table, e))?;
    let mut writer = csv::Writer::from_writer(file);
    for row in &rows {
        writer
            .serialize(row)
            .with_context(|| format!("writing {}", table.display()))?;
    }
    writer
        .flush()
        .map_err(|e| OutputError::io("writing", &table, e))?;
    let points: Vec<SweepPoint> = rows
        .iter()
        .map(|r| SweepPoint {
            defender_nodes: r.defender_nodes,
            adversary_nodes: r.adversary_nodes,
            worst_case: r.worst_case,
            bracket: r.certified_lower.zip(r.upper_bound),
        })
        .collect();
    let title = Title {
        main: format!("{}: {}", game.name().unwrap_or("game"), description),
        detail: format!(
            "best structure per size pair, game of {} states, {} iterations at most",
            game.num_states(),
            settings.max_iterations
        ),
    };
    let plot = out.join("sweep.svg");
    plot_sweep(&plot, &title, &points)
        .map_err(|e| anyhow::anyhow!("writing {}: {e}", plot.display()))?;
    out.commit()?;
    print_text(&format!(
        "wrote sweep.csv and sweep.svg ({} size pairs) to {}\n\
         each defender size was warm-started from the best defender of the next smaller size \
         and kept at least as good as it (a k-node controller embeds into k+1 nodes), so the \
         results are monotone in the defender's size by construction (by certified lower bound \
         with an LTL formula, else by worst-case estimate)\n",
        rows.len(),
        args.out.display()
    ))
}
