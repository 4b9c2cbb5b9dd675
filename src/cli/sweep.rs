//! `posg-fsc sweep`: `solve` for every pair of controller sizes, in
//! parallel, with a table and a plot of the worst-case estimates.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use rayon::prelude::*;
use serde::Serialize;

use posg_fsc::optimise::{self, Structure};
use posg_fsc::output::{SweepPoint, Title, plot_sweep};

use super::common::{ObjectiveArgs, print_text};
use super::progress::{OutputArgs, ProgressMode, SweepProgress};
use super::solve::{SettingsArgs, SolveJob, load, run_job};

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
    /// `def<N>-adv<M>/` per size pair.
    #[arg(long)]
    out: PathBuf,
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
        Some((a, b)) => (positive(a)?..=positive(b)?).collect(),
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
    certified_lower: Option<f64>,
    upper_bound: Option<f64>,
    iterations: usize,
    seconds: f64,
}

/// Runs `sweep`.
pub fn run(args: SweepArgs) -> anyhow::Result<()> {
    let settings = args.settings.settings()?;
    let (game, dra, negated, description) = load(&args.game, &args.objective)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let pairs: Vec<(usize, usize)> = args
        .def_nodes
        .0
        .iter()
        .flat_map(|&n| args.adv_nodes.0.iter().map(move |&m| (n, m)))
        .collect();
    let progress = SweepProgress::new(ProgressMode::detect(args.output.quiet), pairs.len());
    let rows = pairs
        .par_iter()
        .map(|&(n, m)| {
            let out = args.out.join(format!("def{n}-adv{m}"));
            let job = SolveJob {
                game: &game,
                dra: &dra,
                negated_dra: negated.as_ref(),
                objective: &description,
                structures: optimise::candidate_structures(
                    &game,
                    &dra,
                    Structure::full(&game, n, m, settings.optimise_initial),
                    &settings,
                )?,
                settings: &settings,
                out: &out,
                progress: ProgressMode::Quiet,
                seconds_axis: args.output.seconds_axis,
            };
            let (solution, certified) = run_job(&job)
                .with_context(|| format!("defender {n} nodes, adversary {m} nodes"))?;
            let report = &solution.best().report;
            progress.finished(n, m, report.worst_case);
            Ok(Row {
                defender_nodes: n,
                adversary_nodes: m,
                structure: report.name.clone(),
                gmc_states: report.gmc.states,
                gmc_transitions: report.gmc.transitions,
                defender_parameters: report.defender_parameters,
                adversary_parameters: report.adversary_parameters,
                last_value: report.last_value,
                worst_case: report.worst_case,
                certified_lower: certified.map(|b| b.certified_lower),
                upper_bound: certified.map(|b| b.upper_bound),
                iterations: report.iterations,
                seconds: report.seconds,
            })
        })
        .collect::<anyhow::Result<Vec<Row>>>()?;
    progress.finish();
    let mut writer = csv::Writer::from_path(args.out.join("sweep.csv"))?;
    for row in &rows {
        writer.serialize(row)?;
    }
    writer.flush()?;
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
    plot_sweep(&args.out.join("sweep.svg"), &title, &points).map_err(|e| anyhow::anyhow!(e))?;
    print_text(&format!(
        "wrote sweep.csv and sweep.svg ({} size pairs) to {}\n",
        rows.len(),
        args.out.display()
    ))
}
