//! `posg-fsc solve`: the max-min optimiser on one game, formula and pair of
//! controller sizes, with its output files.
//!
//! The options are the library's [`Settings`] (shared with `sweep`) and the
//! linear solver's [`SolverArgs`] (shared with `eval`); [`solve_into`] runs the library's pipeline
//! ([`posg_fsc::pipeline`]), which writes `curve.csv`, `curve.svg`,
//! `defender.fsc.json`, `defender.dot`, `adversary.fsc.json` and
//! `summary.json` into the output directory, with progress on stderr.

use std::path::{Path, PathBuf};

use std::sync::Arc;
use std::time::Instant;

use clap::Args;

use posg_fsc::controller::{self, Role};
use posg_fsc::game::Posg;
use posg_fsc::ltl::props::Property;
use posg_fsc::optimise::{Cancel, Observer, RewardSolution, Settings};
use posg_fsc::output::OutputDirectory;
use posg_fsc::pipeline::directory::SolveDirectory;
use posg_fsc::pipeline::progress::Progress;
use posg_fsc::pipeline::{Automata, Job, Outcome, QueryValue, RewardObjective, Sizes, Unwatched};

use super::common::{
    ObjectiveArgs, PlotArgs, SolverArgs, formula_automata, objective, print_text, read_game_for,
};
use super::progress::{OutputArgs, ProgressMode, Reporter};

/// Arguments of `solve`.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
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
    /// or `uniform:K` instead of the full uniform structure; use with
    /// `--initial-spread 0` to resume.
    #[arg(long)]
    defender: Option<String>,
    /// Start the adversary from this `*.fsc.json` or `uniform:K` (see `--defender`).
    #[arg(long)]
    adversary: Option<String>,
    #[command(flatten)]
    settings: Settings,
    #[command(flatten)]
    solver: SolverArgs,
    #[command(flatten)]
    output: OutputArgs,
    #[command(flatten)]
    plot: PlotArgs,
}

/// The settings of `solve` and `sweep`: the optimiser's options, with the
/// linear solver's from `solver` (the options `eval` has too), validated.
pub fn settings(settings: &Settings, solver: &SolverArgs) -> anyhow::Result<Settings> {
    let settings = Settings {
        solver: solver.solver,
        solver_tolerance: solver.tolerance,
        lu_limit: solver.lu_limit,
        ..settings.clone()
    };
    settings.validate()?;
    Ok(settings)
}

/// Reads the game and builds the objective's automata (for an LTL formula,
/// its negation's too, for the certified bracket).
pub fn load(game: &Path, args: &ObjectiveArgs) -> anyhow::Result<(Posg, Automata)> {
    let game = read_game_for(game, args)?;
    let automata = automata(args, &game)?;
    Ok((game, automata))
}

/// The objective's automata on `game` ([`load`]).
fn automata(args: &ObjectiveArgs, game: &Posg) -> anyhow::Result<Automata> {
    Ok(match &args.formula_text()? {
        Some(text) => formula_automata(args, game, text, true)?,
        None => {
            let (phi, description) = objective(args, game)?;
            Automata {
                phi,
                not_phi: None,
                description,
            }
        }
    })
}

/// Runs `job` into the solve directory `path` (the pipeline with its curve
/// writers, [`SolveDirectory`]), its progress on the board `progress` if
/// given; warns when the best defender has no certificate.
pub fn solve_into(
    job: Job,
    path: &Path,
    progress: Option<&Arc<Progress>>,
    seconds_axis: bool,
    plot: PlotArgs,
    query: Option<&Property>,
) -> anyhow::Result<Outcome> {
    let command_line = super::common::command_line();
    let directory = SolveDirectory {
        path,
        seconds_axis,
        plot_format: Some(plot.format),
        plot_size: plot.picture(),
        command_line: &command_line,
        query,
    };
    let outcome = match progress {
        Some(progress) => directory.solve(job, progress.watching(Unwatched)),
        None => directory.solve(job, Unwatched),
    }?;
    if let Some(error) = &outcome.certification_error {
        eprintln!("warning: the best defender has no certificate: {error}");
    }
    Ok(outcome)
}

/// The options that give the controllers' sizes, as [`Sizes::check`]'s
/// errors name them.
pub const SIZE_OPTIONS: [&str; 2] = ["--def-nodes", "--adv-nodes"];

/// A size option given beside a controller file must match the file.
fn agree(
    option: &str,
    nodes: Option<usize>,
    spec: &str,
    controller: &controller::Fsc,
) -> anyhow::Result<()> {
    match nodes {
        Some(n) if n != controller.num_nodes() => anyhow::bail!(
            "{option} {n} disagrees with {spec}, which has {} nodes; drop {option} (the \
             controller's size is used)",
            controller.num_nodes()
        ),
        _ => Ok(()),
    }
}

/// Runs `solve`.
pub fn run(args: SolveArgs) -> anyhow::Result<()> {
    let settings = settings(&args.settings, &args.solver)?;
    let reporter = Reporter::start(ProgressMode::detect(&args.output), None, Instant::now());
    let progress = reporter.as_ref().map(Reporter::progress);
    if let Some(progress) = progress {
        progress.begin(format!("reading {}", args.game.display()));
    }
    let game = read_game_for(&args.game, &args.objective)?;
    if let Some(reward) = args.objective.reward_objective(&game)? {
        return solve_expected_reward(&args, &game, &reward, &settings, progress);
    }
    if let Some(progress) = progress {
        progress.begin("translating the formula");
    }
    let automata = automata(&args.objective, &game)?;
    let sizes = Sizes {
        defender: args.def_nodes.unwrap_or(1),
        adversary: args.adv_nodes.unwrap_or(1),
    };
    sizes.check(&game, SIZE_OPTIONS)?;
    let mut job = Job::full(&game, &automata, sizes, &settings)?;
    if let Some(spec) = &args.defender {
        job.start.defender = controller::file::resolve(spec, &game, Role::Defender)?;
        job.start.name = "from-files".into();
        agree("--def-nodes", args.def_nodes, spec, &job.start.defender)?;
    }
    if let Some(spec) = &args.adversary {
        job.start.adversary = controller::file::resolve(spec, &game, Role::Adversary)?;
        job.start.name = "from-files".into();
        agree("--adv-nodes", args.adv_nodes, spec, &job.start.adversary)?;
    }
    let out = OutputDirectory::create(&args.out, args.force)?;
    super::interrupt::stop_gracefully(&job.cancel);
    let format = args.plot.format;
    let property = args.objective.property()?;
    let seconds_axis = args.output.seconds_axis;
    let outcome = solve_into(
        job,
        out.path(),
        progress,
        seconds_axis,
        args.plot,
        property.as_ref(),
    )?;
    drop(reporter);
    out.commit()?;
    if super::interrupt::received() {
        eprintln!("interrupted: the results below are those of the defender found before it");
    }
    for line in &outcome.structure_choice {
        eprintln!("{line}");
    }
    let report = &outcome.best().report;
    let bracket = outcome.certified.map_or_else(
        || {
            if automata.not_phi.is_some() {
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
            // Where the belief bound set the upper bound, it bounds every
            // controller, not only the adversaries tried.
            let belief = (report.belief_bound)
                .filter(|belief| belief.value <= b.upper_bound)
                .map_or(String::new(), |belief| {
                    let explored = if belief.complete {
                        ", every belief explored"
                    } else {
                        ""
                    };
                    format!(" (the belief bound{explored}: no defender of any memory does better)")
                });
            format!(
                "; certified: at least {:.6} against every adversary, game value at most \
                 {:.6}{belief}",
                b.certified_lower, b.upper_bound
            )
        },
    );
    if let Some(property) = &property {
        print_text(&restated_query(property, &outcome.query(property)))?;
    }
    print_text(&format!(
        "structure {}: worst-case estimate {:.6} (last iterate value {:.6}) after {} \
         ({}, {}; best of {}; {} defender), {:.1} s; \
         GMC {} states{bracket}\nwrote curve.csv, curve.{format}, defender.fsc.json, defender.dot, \
         adversary.fsc.json, summary.json to {}\n",
        report.name,
        report.worst_case,
        report.last_value,
        posg_fsc::output::counted(report.iterations, "iteration"),
        serde_json::to_value(report.method)?.as_str().unwrap_or("?"),
        serde_json::to_value(report.status)?.as_str().unwrap_or("?"),
        posg_fsc::output::counted(report.starts.len(), "start"),
        report.rounding,
        report.seconds,
        report.gmc.states,
        args.out.display()
    ))
}

/// The text line of a property file's query solved: its value, and its
/// certified bracket in its own terms (for `Pmin`, the returned defender's
/// guarantee is the bracket's upper end).
fn restated_query(property: &Property, query: &QueryValue) -> String {
    let certified = query.certified.map_or(String::new(), |[lo, hi]| {
        if property.maximise {
            format!(
                "; certified: at least {lo:.6} against every adversary, and no defender \
                 guarantees more than {hi:.6}"
            )
        } else {
            format!(
                "; certified: at most {hi:.6} against every adversary, and no defender \
                 guarantees less than {lo:.6}"
            )
        }
    });
    format!(
        "query {}: {:.6} (worst-case estimate of the returned defender){certified}\n",
        query.text, query.value
    )
}

/// What the value of an expected-reward solve means, in words: on a game
/// without adversary the returned defender's exact expected reward, on a
/// game with one its certified guarantee against every adversary; then the
/// bound no defender beats (against the adversaries found, or seeing the
/// state of a game without adversary).
fn reward_words(game: &Posg, solution: &RewardSolution) -> String {
    let width = solution.error_bound;
    let Some(certificate) = &solution.certificate else {
        return format!("the returned defender's expected reward, exact within {width:.1e}");
    };
    let (guarantee, beyond) = match certificate.minimise {
        true => ("at most", "below"),
        false => ("at least", "above"),
    };
    let (what, against) = match game.has_adversary() {
        true => (
            format!(
                "what the returned defender guarantees against every adversary: {guarantee} \
                 this, certified within {width:.1e}"
            ),
            "against the adversaries found",
        ),
        false => (
            format!("the returned defender's expected reward, exact within {width:.1e}"),
            "even seeing the state",
        ),
    };
    match certificate.best_possible {
        // A bound that rounds to 0 at the digits shown reads 0, not -0.
        Some(best) => {
            let shown = if best.abs() < 5e-7 { 0.0 } else { best };
            format!("{what}; no defender gets {beyond} {shown:.6} {against}")
        }
        None => what,
    }
}

/// `solve` of an expected-reward query (docs/method.md section 9): the
/// defender of `--def-nodes` nodes optimised (against adversaries of
/// `--adv-nodes` nodes in the gradient play of a game with an adversary),
/// into the solve directory.
fn solve_expected_reward(
    args: &SolveArgs,
    game: &Posg,
    reward: &RewardObjective,
    settings: &Settings,
    progress: Option<&Arc<Progress>>,
) -> anyhow::Result<()> {
    if let Some(option) = [
        ("--defender", &args.defender),
        ("--adversary", &args.adversary),
    ]
    .iter()
    .find_map(|(option, given)| given.as_ref().map(|_| option))
    {
        anyhow::bail!(
            "{option}: starting controllers are not taken for an expected-reward query yet; \
             drop it (docs/method.md section 9)"
        );
    }
    let nodes = args.def_nodes.unwrap_or(1);
    let sizes = Sizes {
        defender: nodes,
        adversary: args.adv_nodes.unwrap_or(1),
    };
    sizes.check(game, SIZE_OPTIONS)?;
    let out = OutputDirectory::create(&args.out, args.force)?;
    let cancel = Cancel::new();
    super::interrupt::stop_gracefully(&cancel);
    let observer: Box<dyn Observer + Send> = match progress {
        Some(progress) => Box::new(progress.observer("full", nodes, reward.minimise)),
        None => Box::new(()),
    };
    let command_line = super::common::command_line();
    let property = args.objective.property()?;
    let directory = SolveDirectory {
        path: out.path(),
        seconds_axis: args.output.seconds_axis,
        plot_format: Some(args.plot.format),
        plot_size: args.plot.picture(),
        command_line: &command_line,
        query: property.as_ref(),
    };
    let solution = directory.solve_expected_reward(
        game,
        reward,
        (nodes, sizes.adversary),
        settings,
        &cancel,
        observer,
    )?;
    out.commit()?;
    if super::interrupt::received() {
        eprintln!("interrupted: the results below are those of the defender found before it");
    }
    let query = property.as_ref().map_or(&reward.description, |p| &p.text);
    for dropped in &solution.dropped_starts {
        eprintln!("warning: dropped for numerical trouble: {dropped}");
    }
    let best = (solution.starts.iter()).find(|start| start.start == solution.best_start);
    let what = reward_words(game, &solution);
    let how = match best {
        Some(best) => format!(
            "{:.6} ({what}; {}, best of {}, {} of start {})",
            solution.value,
            posg_fsc::output::counted(nodes, "node"),
            posg_fsc::output::counted(solution.starts.len(), "start"),
            posg_fsc::output::counted(best.iterations, "iteration"),
            solution.best_start,
        ),
        None => "inf (the uniform defender misses the target with positive probability, and \
                 an infinite reward is the most there is)"
            .to_string(),
    };
    print_text(&format!(
        "{query}: {how}, {:.1} s\nwrote curve.csv, curve.{}, defender.fsc.json, defender.dot, summary.json \
         to {}\n",
        solution.seconds,
        args.plot.format,
        args.out.display()
    ))
}
