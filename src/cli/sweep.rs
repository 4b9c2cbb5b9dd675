//! `posg-fsc sweep`: `solve` for every pair of controller sizes (the
//! adversary sizes in parallel, the defender sizes in increasing order, each
//! warm-started from the next smaller one), with a table and a plot of the
//! worst-case estimates; with `--shard K/N` one slice of it, with
//! `--slurm` the Slurm scripts that run every slice; `sweep-merge` joins
//! the slices (docs/formats.md section 9).

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use rayon::prelude::*;

use super::shard::{self, Shard, ShardRecord, SweepPlan};
use super::slurm::{self, SlurmSweep};
use posg_fsc::game::Posg;
use posg_fsc::limits;
use posg_fsc::ltl::props::Property;
use posg_fsc::optimise::Settings;
use posg_fsc::output::sweep::{SweepRow, sweep_table};
use posg_fsc::output::{OutputDirectory, Title, create_dir, write_file};
use posg_fsc::pipeline::{self, Automata, Chain};

use super::common::{self, ObjectiveArgs, PlotArgs, SolverArgs, print_text};
use super::progress::{OutputArgs, ProgressMode, Reporter, SweepProgress};
use super::solve::{SIZE_OPTIONS, load, settings, solve_into};

/// Arguments of `sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
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
    /// appear there whole when the run ends; with --shard, each pair
    /// appears whole when it is done; docs/formats.md section 9).
    #[arg(long)]
    out: PathBuf,
    /// Replace a non-empty --out whole (without it, a non-empty --out is
    /// refused); with --shard, recompute the shard's complete chains too.
    #[arg(long, conflicts_with = "slurm")]
    force: bool,
    /// Run only shard K of N (`K/N`, 1 <= K <= N): the adversary sizes at
    /// positions K, K+N, K+2N, ... of --adv-nodes, each with all its
    /// defender sizes; every size pair goes into --out atomically, and
    /// `posg-fsc sweep-merge DIR` writes sweep.csv and sweep.svg once all
    /// shards are done. A rerun completes what a failed run left out.
    #[arg(long, conflicts_with = "slurm")]
    shard: Option<Shard>,
    /// Run nothing: write --out/sweep.sbatch, a Slurm array job whose task K
    /// runs --shard K/N, and --out/sweep-merge.sbatch, and print how to
    /// submit them.
    #[arg(long)]
    slurm: bool,
    /// With --slurm: an extra `#SBATCH` line (e.g. --slurm-option=--partition=short); repeatable.
    #[arg(long, requires = "slurm", allow_hyphen_values = true)]
    slurm_option: Vec<String>,
    /// With --slurm: N, the number of shards (array tasks); default one per adversary size.
    #[arg(long, requires = "slurm")]
    shards: Option<usize>,
    #[command(flatten)]
    settings: Settings,
    #[command(flatten)]
    solver: SolverArgs,
    #[command(flatten)]
    output: OutputArgs,
    #[command(flatten)]
    plot: PlotArgs,
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

/// Arguments of `sweep-merge`.
#[derive(Debug, Args)]
pub struct SweepMergeArgs {
    /// The --out of the `sweep --shard K/N` runs.
    dir: PathBuf,
    #[command(flatten)]
    plot: PlotArgs,
}

/// The loaded inputs every chain of a sweep shares.
struct Inputs<'a> {
    game: &'a Posg,
    automata: &'a Automata,
    settings: &'a Settings,
    defender_sizes: &'a [usize],
    seconds_axis: bool,
    plot: PlotArgs,
    /// The query of `--props`, restated in each pair's `summary.json`.
    query: Option<&'a Property>,
}

/// Where a chain writes its pairs.
#[derive(Clone, Copy)]
enum PairPlace<'a> {
    /// Into the staging directory of the whole (unsharded) sweep.
    Inside(&'a Path),
    /// Each pair into its own atomic directory under a sharded sweep's
    /// directory, with its row in [`shard::ROW_FILE`].
    Own(&'a Path),
}

/// Runs `sweep`: the adversary sizes in parallel; for each, the defender
/// sizes in increasing order, each warm-started from the best defender of
/// the next smaller size and kept at least as good as it
/// ([`Job::warm_started`]), so the results
/// are monotone in the defender's size by construction. With `--shard K/N`
/// only the chains (adversary sizes) of shard K; with `--slurm` nothing
/// runs: the Slurm scripts are written ([`posg_fsc::output::shard`]).
pub fn run(args: SweepArgs) -> anyhow::Result<()> {
    let settings = settings(&args.settings, &args.solver)?;
    let (game, automata) = load(&args.game, &args.objective)?;
    let property = args.objective.property()?;
    let description = &automata.description;
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
            let sizes = pipeline::Sizes {
                defender: n,
                adversary: m,
            };
            sizes.check(&game, SIZE_OPTIONS)?;
        }
    }
    let mut defender_sizes = args.def_nodes.0.clone();
    defender_sizes.sort_unstable();
    defender_sizes.dedup();
    let inputs = Inputs {
        game: &game,
        automata: &automata,
        settings: &settings,
        defender_sizes: &defender_sizes,
        seconds_axis: args.output.seconds_axis,
        plot: args.plot,
        query: property.as_ref(),
    };
    let adversary_sizes = distinct_in_order(&args.adv_nodes.0);
    let title = Title {
        main: format!("{}: {}", game.name().unwrap_or("game"), description),
        detail: format!(
            "best structure per size pair, game of {} states, {} iterations at most",
            game.num_states(),
            settings.max_iterations
        ),
    };
    let shards = match (args.shard, args.slurm) {
        (Some(shard), _) => Some(shard.count),
        (None, true) => Some(args.shards.unwrap_or(adversary_sizes.len())),
        (None, false) => None,
    };
    let Some(shards) = shards else {
        return run_whole(&args, &inputs, &adversary_sizes, &title);
    };
    if shards == 0 || shards > adversary_sizes.len() {
        anyhow::bail!(
            "{shards} shards: the sweep has {} chains (one per adversary size: a chain runs the \
             defender sizes in increasing order, each warm-started from the previous), so N \
             must be between 1 and {}",
            adversary_sizes.len(),
            adversary_sizes.len()
        );
    }
    let game_bytes =
        std::fs::read(&args.game).with_context(|| format!("reading {}", args.game.display()))?;
    let plan = SweepPlan {
        crate_version: env!("CARGO_PKG_VERSION").into(),
        game_fingerprint: shard::fingerprint(&game_bytes),
        game_name: game.name().map(str::to_string),
        objective: description.clone(),
        settings: serde_json::to_value(&settings)?,
        defender_sizes: defender_sizes.clone(),
        adversary_sizes,
        shards,
        title_main: title.main,
        title_detail: title.detail,
    };
    match args.shard {
        Some(shard) => run_shard(&args, &inputs, &plan, shard),
        None => write_slurm(&args, &plan),
    }
}

/// The sizes without repetitions, in their first order.
fn distinct_in_order(sizes: &[usize]) -> Vec<usize> {
    let mut seen = Vec::new();
    for &m in sizes {
        if !seen.contains(&m) {
            seen.push(m);
        }
    }
    seen
}

/// The unsharded sweep: every chain, into one atomic directory.
fn run_whole(
    args: &SweepArgs,
    inputs: &Inputs,
    adversary_sizes: &[usize],
    title: &Title,
) -> anyhow::Result<()> {
    let out = OutputDirectory::create(&args.out, args.force)?;
    let progress = SweepProgress::new(
        ProgressMode::detect(&args.output),
        inputs.defender_sizes.len() * adversary_sizes.len(),
    );
    let rows = run_chains(
        inputs,
        adversary_sizes,
        PairPlace::Inside(out.path()),
        &progress,
    )?;
    progress.finish();
    let format = args.plot.format;
    shard::write_sweep(out.path(), &rows, title, args.plot)?;
    out.commit()?;
    print_text(&format!(
        "wrote sweep.csv and sweep.{format} ({} size pairs) to {}\n{MONOTONE}\n",
        rows.len(),
        args.out.display()
    ))
}

/// What every sweep prints about the warm starts.
const MONOTONE: &str = "each defender size was warm-started from the best defender of the next \
     smaller size and kept at least as good as it (a k-node controller embeds into k+1 nodes), \
     so the results are monotone in the defender's size by construction (by certified lower \
     bound with an LTL formula, else by worst-case estimate)";

/// The chains of `adversary_sizes` in parallel; their rows in order.
fn run_chains(
    inputs: &Inputs,
    adversary_sizes: &[usize],
    place: PairPlace,
    progress: &SweepProgress,
) -> anyhow::Result<Vec<SweepRow>> {
    Ok(adversary_sizes
        .par_iter()
        .map(|&m| run_chain(inputs, m, place, progress))
        .collect::<anyhow::Result<Vec<Vec<SweepRow>>>>()?
        .into_iter()
        .flatten()
        .collect())
}

/// One chain: adversary size `m`, the defender sizes in increasing order,
/// each warm-started from the best defender of the previous size.
fn run_chain(
    inputs: &Inputs,
    m: usize,
    place: PairPlace,
    progress: &SweepProgress,
) -> anyhow::Result<Vec<SweepRow>> {
    let mut chain = Chain::new(inputs.game, inputs.automata, inputs.settings, m);
    let mut rows = Vec::new();
    for &n in inputs.defender_sizes {
        let name = shard::pair_directory_name(n, m);
        let (own, out) = match place {
            PairPlace::Inside(root) => (None, root.join(&name)),
            PairPlace::Own(dir) => {
                let own = OutputDirectory::create(&dir.join(&name), true)?;
                let path = own.path().to_path_buf();
                (Some(own), path)
            }
        };
        let reporter = progress.pair_reporter(n, m);
        let outcome = solve_into(
            chain.job(n)?,
            &out,
            reporter.as_ref().map(Reporter::progress),
            inputs.seconds_axis,
            inputs.plot,
            inputs.query,
        )
        .with_context(|| format!("defender {n} nodes, adversary {m} nodes"))?;
        drop(reporter);
        let row = chain.row(n, &outcome);
        progress.finished(n, m, row.worst_case);
        if let Some(own) = own {
            let table = sweep_table(std::slice::from_ref(&row))
                .with_context(|| format!("writing {}", out.join(shard::ROW_FILE).display()))?;
            write_file(&out.join(shard::ROW_FILE), table)?;
            own.commit()?;
        }
        rows.push(row);
    }
    Ok(rows)
}

/// Whether every pair of the chain `m` is in `dir` (renamed into place whole).
fn chain_complete(dir: &Path, plan: &SweepPlan, m: usize) -> bool {
    plan.defender_sizes.iter().all(|&n| {
        dir.join(shard::pair_directory_name(n, m))
            .join(shard::ROW_FILE)
            .is_file()
    })
}

/// `--shard K/N`: records the shard, then runs its chains that are not
/// complete yet (all of them with --force), each pair into its own atomic
/// directory.
fn run_shard(
    args: &SweepArgs,
    inputs: &Inputs,
    plan: &SweepPlan,
    shard: Shard,
) -> anyhow::Result<()> {
    let record = ShardRecord {
        written_by: format!("shard {shard}"),
        command_line: common::command_line(),
        plan: plan.clone(),
    };
    shard::begin(
        &args.out,
        &shard::shard_record_path(&args.out, shard),
        &record,
    )?;
    let chains = plan.chains_of(shard);
    let (done, todo): (Vec<usize>, Vec<usize>) = chains
        .iter()
        .partition(|&&m| !args.force && chain_complete(&args.out, plan, m));
    let progress = SweepProgress::new(
        ProgressMode::detect(&args.output),
        inputs.defender_sizes.len() * todo.len(),
    );
    let rows = run_chains(inputs, &todo, PairPlace::Own(&args.out), &progress)?;
    progress.finish();
    let kept = if done.is_empty() {
        String::new()
    } else {
        format!(
            "; adversary sizes {done:?} were complete already and kept (--force recomputes them)"
        )
    };
    print_text(&format!(
        "shard {shard}: wrote {} size pairs (adversary sizes {todo:?}) to {}{kept}\n\
         when all {} shards are done: posg-fsc sweep-merge {}\n{MONOTONE}\n",
        rows.len(),
        args.out.display(),
        shard.count,
        args.out.display()
    ))
}

/// The arguments of this run without the options of `--slurm` itself; an
/// error if one is not UTF-8 (it could not be written into the job script).
fn arguments_for_shards() -> anyhow::Result<Vec<String>> {
    let mut kept = Vec::new();
    let arguments: Vec<String> = std::env::args_os()
        .skip(1)
        .map(|argument| {
            argument.into_string().map_err(|argument| {
                anyhow::anyhow!(
                    "the argument {argument:?} is not UTF-8, so it cannot be written into \
                     sweep.sbatch; rename the file or directory it names"
                )
            })
        })
        .collect::<anyhow::Result<_>>()?;
    let mut arguments = arguments.into_iter();
    while let Some(argument) = arguments.next() {
        match argument.as_str() {
            "--slurm" => {}
            "--slurm-option" | "--shards" => {
                arguments.next();
            }
            a if a.starts_with("--slurm-option=") || a.starts_with("--shards=") => {}
            _ => kept.push(argument),
        }
    }
    Ok(kept)
}

/// `--slurm`: records the plan and writes `sweep.sbatch` and
/// `sweep-merge.sbatch`; prints how to submit them.
fn write_slurm(args: &SweepArgs, plan: &SweepPlan) -> anyhow::Result<()> {
    for option in &args.slurm_option {
        slurm::check_option(option).map_err(anyhow::Error::msg)?;
    }
    let command_line = common::command_line();
    let record = ShardRecord {
        written_by: "--slurm".into(),
        command_line: command_line.clone(),
        plan: plan.clone(),
    };
    shard::begin(&args.out, &shard::slurm_record_path(&args.out), &record)?;
    create_dir(&args.out.join(slurm::LOG_DIRECTORY))?;
    let working_directory = std::env::current_dir().context("the current directory")?;
    let out = std::path::absolute(&args.out)
        .with_context(|| format!("the absolute path of {}", args.out.display()))?;
    let program = std::env::current_exe().context("the path of posg-fsc itself")?;
    let sweep_arguments = arguments_for_shards()?;
    let job = SlurmSweep {
        program: &program,
        working_directory: &working_directory,
        sweep_arguments: &sweep_arguments,
        out: &out,
        shards: plan.shards,
        plot: args.plot,
        options: &args.slurm_option,
        command_line: &command_line,
    };
    let (array, merge) = (out.join("sweep.sbatch"), out.join("sweep-merge.sbatch"));
    shard::write_atomically(&array, slurm::array_script(&job).as_bytes())?;
    shard::write_atomically(&merge, slurm::merge_script(&job).as_bytes())?;
    print_text(&format!(
        "wrote {} (an array job of {} shards) and {}; submit both with\n{}",
        array.display(),
        plan.shards,
        merge.display(),
        slurm::submit_commands(&array, &merge)
    ))
}

/// Runs `sweep-merge`.
pub fn run_merge(args: SweepMergeArgs) -> anyhow::Result<()> {
    let format = args.plot.format;
    let merged = shard::merge(&args.dir, args.plot)?;
    print_text(&format!(
        "wrote sweep.csv and sweep.{format} ({} size pairs from {} shards) to {}\n",
        merged.rows.len(),
        merged.plan.shards,
        args.dir.display()
    ))
}
