//! `posg-fsc solve`: the max-min optimiser on one game, formula and pair of
//! controller sizes, with its output files.
//!
//! [`SettingsArgs`] is what the user typed for [`Settings`] (shared with
//! `sweep`); [`SolveJob`] is the built objects; [`run_job`] optimises and
//! writes `curve.csv`, `curve.svg`, `defender.fsc.json`, `defender.dot`,
//! `adversary.fsc.json` and `summary.json` into the output directory.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use indicatif::MultiProgress;
use serde::Serialize;

use posg_fsc::automaton::Dra;
use posg_fsc::certify::{self, Bracket};
use posg_fsc::controller::{self, Role};
use posg_fsc::game::Posg;
use posg_fsc::optimise::{
    self, Candidates, Observer, Settings, Solution, SourceNote, Structure, StructureOutcome,
    StructureReport, StructureSource, UpdateRule,
};
use posg_fsc::output::{CurveCsv, CurvePlot, OutputDirectory, Title, create_dir, write_file};
use posg_fsc::value::SolverMethod;

use super::common::{ObjectiveArgs, objective, print_text, read_game};
use super::progress::{OutputArgs, ProgressMode, structure_progress};
use super::support::SynthesisArgs;

/// Arguments of `solve`.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// The game, a `*.posg.json` file (docs/formats.md section 1).
    game: PathBuf,
    #[command(flatten)]
    objective: ObjectiveArgs,
    /// Defender FSC size (nodes; default 1, or the size of --defender).
    #[arg(long)]
    def_nodes: Option<usize>,
    /// Adversary FSC size (nodes; default 1, or the size of --adversary).
    #[arg(long)]
    adv_nodes: Option<usize>,
    /// Directory for the output files (created if missing; written
    /// atomically: the results appear there whole when the run ends).
    #[arg(long)]
    out: PathBuf,
    /// Replace a non-empty --out whole (without it, a non-empty --out is refused).
    #[arg(long)]
    force: bool,
    /// Start the defender from this `*.fsc.json` (its support and logits)
    /// instead of the full uniform structure; use with `--initial-spread 0` to resume.
    #[arg(long)]
    defender: Option<PathBuf>,
    /// Start the adversary from this `*.fsc.json` (see `--defender`).
    #[arg(long)]
    adversary: Option<PathBuf>,
    #[command(flatten)]
    settings: SettingsArgs,
    #[command(flatten)]
    output: OutputArgs,
}

/// The optimiser's settings as command-line options (defaults: [`Settings::default`]).
#[derive(Debug, Clone, Args)]
pub struct SettingsArgs {
    /// Seed of every random choice (initial logits, best-response restarts).
    #[arg(long, default_value_t = Settings::default().seed)]
    seed: u64,
    /// Widest logit bound c_max: logits stay in [-c_max, c_max], so every
    /// supported choice keeps probability >= exp(-2 c_max)/|block| and the
    /// GMC graph never changes.
    #[arg(long, default_value_t = Settings::default().logit_bound)]
    logit_bound: f64,
    /// First logit bound c_0 of the max-min loop; it doubles up to
    /// --logit-bound when progress stalls with a logit on the bound.
    #[arg(long, default_value_t = Settings::default().initial_logit_bound)]
    initial_logit_bound: f64,
    /// Initial logits are uniform in [-spread, spread] around the start (0: exactly the start).
    #[arg(long, default_value_t = Settings::default().initial_spread)]
    initial_spread: f64,
    /// Also optimise the initial node distributions.
    #[arg(long)]
    optimise_initial: bool,
    /// Outer iterations (one defender step, or one L-BFGS step for a
    /// single-player game) at most: a cap; runs stop on the certified gap or a stall.
    #[arg(long, default_value_t = Settings::default().max_iterations)]
    max_iterations: usize,
    /// Independent starts per structure, run in parallel; the best certified is kept.
    #[arg(long, default_value_t = Settings::default().starts)]
    starts: usize,
    /// Wall-clock budget per structure in seconds (0: none).
    #[arg(long, default_value_t = Settings::default().time_budget)]
    time_budget: f64,
    /// Adversary descent steps per defender ascent step (the fast time scale).
    #[arg(long, default_value_t = Settings::default().adversary_steps)]
    adversary_steps: usize,
    /// Defender step size at iteration 0.
    #[arg(long, default_value_t = Settings::default().defender_step)]
    defender_step: f64,
    /// Adversary step size (constant).
    #[arg(long, default_value_t = Settings::default().adversary_step)]
    adversary_step: f64,
    /// Defender step decay d: step(t) = defender_step / sqrt(1 + d t).
    #[arg(long, default_value_t = Settings::default().defender_decay)]
    defender_decay: f64,
    /// Update rule of both players: plain gradient steps or Adam.
    #[arg(long, value_enum, default_value = "adam")]
    update: UpdateArg,
    /// Optimism o of both players' steps: d_t + o (d_t - d_{t-1}) (0: plain
    /// alternating play, 1: optimistic gradient).
    #[arg(long, default_value_t = Settings::default().optimism)]
    optimism: f64,
    /// A best-response check every this many iterations (and at the end).
    #[arg(long, default_value_t = Settings::default().check_every)]
    check_every: usize,
    /// Random restarts of each best-response minimisation (besides the current adversary).
    #[arg(long, default_value_t = Settings::default().restarts)]
    restarts: usize,
    /// L-BFGS iterations per best-response start.
    #[arg(long, default_value_t = Settings::default().best_response_iterations)]
    best_response_iterations: u64,
    /// L-BFGS memory.
    #[arg(long, default_value_t = Settings::default().lbfgs_memory)]
    lbfgs_memory: usize,
    /// Stop when the best score (certified lower bound, else worst-case
    /// estimate) gained less than --stall-tolerance over this many checks at
    /// the widest logit bound (0: never).
    #[arg(long, default_value_t = Settings::default().stall_checks)]
    stall_checks: usize,
    /// See --stall-checks.
    #[arg(long, default_value_t = Settings::default().stall_tolerance)]
    stall_tolerance: f64,
    /// The single-player ascent stops when the value gained at most
    /// --stall-tolerance of itself over this many iterations (0: never).
    #[arg(long, default_value_t = Settings::default().ascent_stall_iterations)]
    ascent_stall_iterations: usize,
    /// Stop when the certified gap (game upper bound minus certified lower
    /// bound) is at most this.
    #[arg(long, default_value_t = Settings::default().gap_tolerance)]
    gap_tolerance: f64,
    /// Run the max-min loop with best-response checks on single-player
    /// games too, instead of the L-BFGS ascent.
    #[arg(long)]
    no_single_player_ascent: bool,
    /// Do not evaluate the rounded defenders at the end.
    #[arg(long)]
    no_round: bool,
    /// Largest residual accepted from a linear solve.
    #[arg(long, default_value_t = Settings::default().solver_tolerance, value_parser = super::common::positive_tolerance)]
    solver_tolerance: f64,
    /// `lu` (sparse LU), `krylov` (BiCGSTAB with ILU(0), warm-started from
    /// the previous iteration) or `auto` (LU up to 50000 unknowns).
    #[arg(long, default_value = "auto", value_parser = |text: &str| text.parse::<SolverMethod>())]
    solver: SolverMethod,
    /// The sources of the structures to optimise on: `full` (the full support,
    /// or the --defender/--adversary files), `sat` (a support found by SAT that
    /// wins almost surely, else positively, against every adversary), `paper`
    /// (the paper's Algorithm 1). Identical structures are optimised once; the
    /// best certified lower bound wins.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "full,sat,paper"
    )]
    structures: Vec<StructureArg>,
    #[command(flatten)]
    synthesis: SynthesisArgs,
    /// Pruning: remove action u under observation o for all nodes, as the
    /// paper's lines 14-16 are printed (default: only the offending entries).
    #[arg(long)]
    prune_paper_literal: bool,
    /// Pruning: also restrict the adversary's support (lines 18-22). The
    /// worst-case estimate is then only against the restricted adversary.
    #[arg(long)]
    prune_adversary: bool,
}

/// `--structures`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum StructureArg {
    /// The full support (or the controllers given as files).
    Full,
    /// Support synthesis by SAT.
    Sat,
    /// The paper's Algorithm 1.
    Paper,
}

/// `--update`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum UpdateArg {
    /// phi <- phi +/- eta grad.
    Plain,
    /// Adam with beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8.
    Adam,
}

impl SettingsArgs {
    /// The settings, validated.
    pub fn settings(&self) -> anyhow::Result<Settings> {
        let settings = Settings {
            seed: self.seed,
            logit_bound: self.logit_bound,
            initial_logit_bound: self.initial_logit_bound,
            initial_spread: self.initial_spread,
            optimise_initial: self.optimise_initial,
            max_iterations: self.max_iterations,
            starts: self.starts,
            time_budget: self.time_budget,
            adversary_steps: self.adversary_steps,
            defender_step: self.defender_step,
            adversary_step: self.adversary_step,
            defender_decay: self.defender_decay,
            update: match self.update {
                UpdateArg::Plain => UpdateRule::Plain,
                UpdateArg::Adam => UpdateRule::Adam,
            },
            optimism: self.optimism,
            check_every: self.check_every,
            restarts: self.restarts,
            best_response_iterations: self.best_response_iterations,
            lbfgs_memory: self.lbfgs_memory,
            stall_checks: self.stall_checks,
            stall_tolerance: self.stall_tolerance,
            ascent_stall_iterations: self.ascent_stall_iterations,
            gap_tolerance: self.gap_tolerance,
            single_player_ascent: !self.no_single_player_ascent,
            round: !self.no_round,
            solver_tolerance: self.solver_tolerance,
            solver: self.solver,
            structures: self
                .structures
                .iter()
                .map(|s| match s {
                    StructureArg::Full => StructureSource::Full,
                    StructureArg::Sat => StructureSource::Sat,
                    StructureArg::Paper => StructureSource::Paper,
                })
                .collect(),
            synthesis: self.synthesis.structure_settings()?,
            prune_paper_literal: self.prune_paper_literal,
            prune_adversary: self.prune_adversary,
        };
        settings.validate()?;
        Ok(settings)
    }
}

/// Everything one solve needs, built from the arguments.
pub struct SolveJob<'a> {
    /// The game.
    pub game: &'a Posg,
    /// The DRA of the objective.
    pub dra: &'a Dra,
    /// A DRA of the negated objective, for the certified bracket (none
    /// when the objective came as an automaton).
    pub negated_dra: Option<&'a Dra>,
    /// The objective as the user gave it (formula or automaton file).
    pub objective: &'a str,
    /// The structures to optimise on and what their sources said.
    pub candidates: Candidates,
    /// The optimiser's settings.
    pub settings: &'a Settings,
    /// The directory to write into (a staging directory of an
    /// [`OutputDirectory`], or a subdirectory of one).
    pub out: &'a Path,
    /// The best outcome of a smaller defender size (`sweep`): the result
    /// is kept at least as good ([`optimise::keep_better`]).
    pub floor: Option<&'a StructureOutcome>,
    /// How to show progress on stderr.
    pub progress: ProgressMode,
    /// Whether curve.svg gets a top axis with the seconds elapsed.
    pub seconds_axis: bool,
}

/// `summary.json`.
#[derive(Debug, Serialize)]
struct Summary<'a> {
    command_line: Vec<String>,
    crate_version: &'static str,
    game: Option<&'a str>,
    objective: &'a str,
    defender_nodes: usize,
    adversary_nodes: usize,
    settings: &'a Settings,
    structure_used: &'a str,
    worst_case: f64,
    /// The largest error bound of the values computed on the best structure
    /// (method.md section 8).
    error_bound: f64,
    /// The best defender's guaranteed value against every adversary, and
    /// the smallest game upper bound over the best responses found
    /// (docs/method.md section 6); absent when the objective came as an automaton.
    certified: Option<Bracket>,
    /// Why `certified` is absent although the objective came as a formula:
    /// the best defender's product mixes too slowly for its bound to be
    /// solved to the tolerance (method.md section 8).
    certification_error: Option<String>,
    last_value: f64,
    seconds: f64,
    /// Seconds of support synthesis (the `sat` source) before optimising.
    synthesis_seconds: f64,
    /// Why `structure_used` won: the best certified lower bound, and why
    /// each other structure or source lost.
    structure_choice: Vec<String>,
    /// What each source of structures found, proved or why it gave none.
    sources: &'a [SourceNote],
    structures: Vec<&'a StructureReport>,
    files: [&'static str; 6],
}

/// Reads the game and builds the objective's automaton (and, for an LTL
/// formula, its negation's); returns them with the objective's description.
pub fn load(game: &Path, args: &ObjectiveArgs) -> anyhow::Result<(Posg, Dra, Option<Dra>, String)> {
    let game = read_game(game)?;
    let (dra, description) = objective(args, &game)?;
    let negated = match &args.ltl {
        Some(text) => Some(
            args.translate(&posg_fsc::ltl::parse(text)?.negate())
                .context("translating !phi")?,
        ),
        None => None,
    };
    Ok((game, dra, negated, description))
}

/// Optimises on the job's structures and writes the five output files
/// (the best structure's curve as `curve.csv`/`curve.svg`, the others' as
/// `curve-<name>.csv`/`.svg`). Returns the solution and the best
/// defender's certified bracket.
pub fn run_job(job: &SolveJob) -> anyhow::Result<(Solution, Option<Bracket>)> {
    create_dir(job.out)?;
    let clock = Instant::now();
    let iterations = job.settings.max_iterations;
    let multiple = job.candidates.structures.len() > 1;
    let out = job.out.to_path_buf();
    let bars = (job.progress == ProgressMode::Bars).then(MultiProgress::new);
    let mut solution = optimise::optimise_structures(
        job.game,
        job.dra,
        job.negated_dra,
        &job.candidates.structures,
        job.settings,
        |_, structure| {
            let stem = if multiple {
                format!("curve-{}", structure.name)
            } else {
                "curve".to_string()
            };
            let mut list = observers(&out, &stem, plot_title(job, structure), job.seconds_axis);
            list.extend(structure_progress(
                job.progress,
                bars.as_ref(),
                &structure.name,
                iterations,
            ));
            Box::new(list) as Box<dyn Observer + Send>
        },
    )?;
    if let Some(floor) = job.floor {
        let nodes = solution.best().defender.num_nodes();
        optimise::keep_better(&mut solution, floor, nodes)?;
    }
    let best_curve = |ext: &str| out.join(format!("curve-{}.{ext}", solution.best().report.name));
    if multiple && best_curve("csv").exists() {
        for ext in ["csv", "svg"] {
            let from = best_curve(ext);
            std::fs::copy(&from, out.join(format!("curve.{ext}")))
                .with_context(|| format!("copying {}", from.display()))?;
        }
    }
    let best = solution.best();
    let bracket = job
        .negated_dra
        .map(|negated| {
            let adversaries = solution.structures.iter().map(|s| &s.adversary);
            certify::bracket(job.game, job.dra, negated, &best.defender, adversaries)
        })
        .transpose();
    let (bracket, certification_error) = match bracket {
        Ok(bracket) => (bracket, None),
        Err(error) if error.is_slow_mixing() => {
            eprintln!("warning: the best defender has no certificate: {error}");
            (None, Some(error.to_string()))
        }
        Err(error) => return Err(error.into()),
    };
    let certified = bracket.map(|bracket| Bracket {
        upper_bound: solution
            .structures
            .iter()
            .filter_map(|s| s.report.upper_bound)
            .fold(bracket.upper_bound, f64::min),
        ..bracket
    });
    controller::file::write(&out.join("defender.fsc.json"), &best.defender, job.game)?;
    write_defender_dot(&out.join("defender.dot"), job, &best.defender)?;
    controller::file::write(&out.join("adversary.fsc.json"), &best.adversary, job.game)?;
    let summary = Summary {
        command_line: std::env::args().collect(),
        crate_version: env!("CARGO_PKG_VERSION"),
        game: job.game.name(),
        objective: job.objective,
        defender_nodes: best.defender.num_nodes(),
        adversary_nodes: best.adversary.num_nodes(),
        settings: job.settings,
        structure_used: &best.report.name,
        worst_case: best.report.worst_case,
        error_bound: best.report.error_bound,
        certified,
        certification_error,
        last_value: best.report.last_value,
        seconds: clock.elapsed().as_secs_f64(),
        synthesis_seconds: job
            .candidates
            .notes
            .iter()
            .filter(|n| n.source == StructureSource::Sat)
            .map(|n| n.seconds)
            .sum(),
        structure_choice: structure_choice(&solution, &job.candidates.notes),
        sources: &job.candidates.notes,
        structures: solution.structures.iter().map(|s| &s.report).collect(),
        files: [
            "curve.csv",
            "curve.svg",
            "defender.fsc.json",
            "defender.dot",
            "adversary.fsc.json",
            "summary.json",
        ],
    };
    write_file(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    Ok((solution, certified))
}

/// Why the best structure won, then why each other structure or source
/// lost (one sentence each).
pub fn structure_choice(solution: &Solution, notes: &[SourceNote]) -> Vec<String> {
    let best = solution.best();
    let measure = match best.report.certified_lower {
        Some(lower) => format!("the best certified lower bound, {lower:.6}"),
        None => format!(
            "the best worst-case estimate, {:.6}",
            best.report.worst_case
        ),
    };
    std::iter::once(format!("{} won with {measure}", best.report.name))
        .chain(optimise::why_others_lost(
            &solution.structures,
            solution.best,
            notes,
            &solution.failed,
        ))
        .collect()
}

/// The Graphviz picture of the best defender (`dot -Tsvg defender.dot`).
fn write_defender_dot(
    path: &Path,
    job: &SolveJob,
    defender: &controller::Fsc,
) -> anyhow::Result<()> {
    let player = job.game.defender();
    let title = format!(
        "defender for {}: {} ({} nodes)",
        job.game.name().unwrap_or("game"),
        job.objective,
        defender.num_nodes()
    );
    let text = posg_fsc::output::dot::controller_dot(
        defender,
        player.observations(),
        player.actions(),
        &title,
        posg_fsc::output::dot::DEFAULT_THRESHOLD,
    );
    Ok(write_file(path, &text)?)
}

/// The title of a structure's `curve.svg`: game and objective, then sizes
/// and structure.
fn plot_title(job: &SolveJob, structure: &Structure) -> Title {
    let nodes = |n: usize| {
        if n == 1 {
            "1 node".to_string()
        } else {
            format!("{n} nodes")
        }
    };
    let adversary = if job.game.has_adversary() {
        format!(", adversary {}", nodes(structure.adversary.num_nodes()))
    } else {
        String::new()
    };
    Title {
        main: format!("{}: {}", job.game.name().unwrap_or("game"), job.objective),
        detail: format!(
            "defender {}{adversary}, structure {}, game of {} states",
            nodes(structure.defender.num_nodes()),
            structure.name,
            job.game.num_states()
        ),
    }
}

/// The CSV writer and the plot for `stem`.
fn observers(
    out: &Path,
    stem: &str,
    title: Title,
    seconds_axis: bool,
) -> Vec<Box<dyn Observer + Send>> {
    let mut list: Vec<Box<dyn Observer + Send>> = Vec::new();
    let (table, plot) = (
        out.join(format!("{stem}.csv")),
        out.join(format!("{stem}.svg")),
    );
    match CurveCsv::create(&table) {
        Ok(csv) => list.push(Box::new(Named(table, csv))),
        Err(error) => list.push(Box::new(Failed(Some(error.into())))),
    }
    let curve = CurvePlot::new(&plot, title).with_seconds_axis(seconds_axis);
    list.push(Box::new(Named(plot, curve)));
    list
}

/// An observer writing the file at `.0`, whose failure names that file.
struct Named<O>(PathBuf, O);

impl<O: Observer> Observer for Named<O> {
    fn observe(&mut self, record: &optimise::IterationRecord) {
        self.1.observe(record);
    }

    fn finish(&mut self) -> Result<(), optimise::ObserverError> {
        self.1
            .finish()
            .map_err(|e| format!("writing {}: {e}", self.0.display()).into())
    }
}

/// An observer that could not be created: reports its error at the end.
struct Failed(Option<optimise::ObserverError>);

impl Observer for Failed {
    fn observe(&mut self, _record: &optimise::IterationRecord) {}

    fn finish(&mut self) -> Result<(), optimise::ObserverError> {
        self.0.take().map_or(Ok(()), Err)
    }
}

/// Checks controller sizes given on the command line: at least one node,
/// within the resource budget ([`posg_fsc::limits`]), and one adversary
/// node for a game without an adversary (a POMDP).
pub fn check_sizes(game: &Posg, def_nodes: usize, adv_nodes: usize) -> anyhow::Result<()> {
    let (def, adv) = (game.defender(), game.adversary());
    controller::Fsc::check_uniform_size(
        "--def-nodes",
        def_nodes,
        def.num_observations(),
        def.num_actions(),
    )?;
    controller::Fsc::check_uniform_size(
        "--adv-nodes",
        adv_nodes,
        adv.num_observations(),
        adv.num_actions(),
    )?;
    if !game.has_adversary() && adv_nodes != 1 {
        anyhow::bail!(
            "--adv-nodes {adv_nodes}: the game has no adversary (it is a POMDP), whose controller \
             has exactly one node; drop --adv-nodes"
        );
    }
    Ok(())
}

/// A size option given beside a controller file must match the file.
fn agree(
    option: &str,
    nodes: Option<usize>,
    path: &Path,
    controller: &controller::Fsc,
) -> anyhow::Result<()> {
    match nodes {
        Some(n) if n != controller.num_nodes() => anyhow::bail!(
            "{option} {n} disagrees with {}, which has {} nodes; drop {option} (the file's size is used)",
            path.display(),
            controller.num_nodes()
        ),
        _ => Ok(()),
    }
}

/// Runs `solve`.
pub fn run(args: SolveArgs) -> anyhow::Result<()> {
    let settings = args.settings.settings()?;
    let (game, dra, negated, description) = load(&args.game, &args.objective)?;
    let (def_nodes, adv_nodes) = (args.def_nodes.unwrap_or(1), args.adv_nodes.unwrap_or(1));
    check_sizes(&game, def_nodes, adv_nodes)?;
    let mut structure = Structure::full(&game, def_nodes, adv_nodes, settings.optimise_initial);
    if let Some(path) = &args.defender {
        structure.defender = controller::file::read(path, &game, Role::Defender)?;
        structure.name = "from-files".into();
        agree("--def-nodes", args.def_nodes, path, &structure.defender)?;
    }
    if let Some(path) = &args.adversary {
        structure.adversary = controller::file::read(path, &game, Role::Adversary)?;
        structure.name = "from-files".into();
        agree("--adv-nodes", args.adv_nodes, path, &structure.adversary)?;
    }
    let out = OutputDirectory::create(&args.out, args.force)?;
    let job = SolveJob {
        game: &game,
        dra: &dra,
        negated_dra: negated.as_ref(),
        objective: &description,
        candidates: optimise::candidate_structures(
            &game,
            &dra,
            negated.as_ref(),
            structure,
            &settings,
        )?,
        settings: &settings,
        out: out.path(),
        progress: ProgressMode::detect(args.output.quiet),
        floor: None,
        seconds_axis: args.output.seconds_axis,
    };
    let (solution, certified) = run_job(&job)?;
    let choice = structure_choice(&solution, &job.candidates.notes);
    let certifiable = job.negated_dra.is_some();
    out.commit()?;
    for line in choice {
        eprintln!("{line}");
    }
    let best = solution.best();
    let report = &best.report;
    let bracket = certified.map_or_else(
        || {
            if certifiable {
                "; no certified bracket: the best defender's product mixes too slowly to be \
                 solved to the tolerance (summary.json: certification_error)"
                    .to_string()
            } else {
                "; no certified bracket (the objective came as an automaton: run `posg-fsc \
                 certify --automaton A --negated-automaton N --defender defender.fsc.json`)"
                    .to_string()
            }
        },
        |b| {
            format!(
                "; certified: at least {:.6} against every adversary, game value at most {:.6}",
                b.certified_lower, b.upper_bound
            )
        },
    );
    print_text(&format!(
        "structure {}: worst-case estimate {:.6} (last iterate value {:.6}) after {} iterations \
         ({}, {}; best of {} starts; {} defender), {:.1} s; \
         GMC {} states{bracket}\nwrote curve.csv, curve.svg, defender.fsc.json, defender.dot, adversary.fsc.json, \
         summary.json to {}\n",
        report.name,
        report.worst_case,
        report.last_value,
        report.iterations,
        serde_json::to_value(report.method)?.as_str().unwrap_or("?"),
        serde_json::to_value(report.status)?.as_str().unwrap_or("?"),
        report.starts.len(),
        report.rounding,
        report.seconds,
        report.gmc.states,
        args.out.display()
    ))
}
