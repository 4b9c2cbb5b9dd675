//! A `solve` directory (docs/formats.md section 9): the pipeline's
//! [`Outcome`] as `curve.csv`, `curve.svg` (or `curve.png`),
//! `defender.fsc.json`, `defender.dot`, `adversary.fsc.json` and
//! `summary.json` (with several structures, each one's curve as
//! `curve-<name>.csv`/`.svg`, the best one's copied to
//! `curve.csv`/`curve.svg`).

use std::path::Path;
use std::sync::{Arc, Mutex, PoisonError};

use serde::Serialize;

use super::{
    Automata, Job, Outcome, PipelineError, QueryValue, Recorder, RewardObjective, SizeResult,
    Watch, run,
};
use crate::certify::Bracket;
use crate::certify::reward::RewardCertificate;
use crate::controller::{self, Fsc};
use crate::game::Posg;
use crate::ltl::props::Property;
use crate::optimise::{
    Cancel, IterationRecord, Observer, RewardSolution, RewardStart, Settings, SourceNote,
    StructureOutcome, StructureReport, optimise_expected_reward,
};
use crate::output::{
    CurveCsv, CurvePlot, OutputError, PROBABILITY_AXIS, PlotFormat, PlotSize, Returned,
    ReturnedValue, Title, counted, create_dir, plot_curve, reward_axis, write_file,
};

/// The files of a solve directory whose plots are in `format` (`None`:
/// no plot), as `summary.json` lists them.
pub fn files(format: Option<PlotFormat>) -> Vec<String> {
    listed(
        format,
        &[
            "defender.fsc.json",
            "defender.dot",
            "adversary.fsc.json",
            "summary.json",
        ],
    )
}

/// The files of an expected-reward solve directory (no adversary's
/// controller), as its `summary.json` lists them.
fn reward_files(format: Option<PlotFormat>) -> Vec<String> {
    listed(
        format,
        &["defender.fsc.json", "defender.dot", "summary.json"],
    )
}

/// `curve.csv`, the curve's picture in `format` if any, then `others`.
fn listed(format: Option<PlotFormat>, others: &[&str]) -> Vec<String> {
    let plot = format.map(|format| format!("curve.{format}"));
    (std::iter::once("curve.csv".to_string()).chain(plot))
        .chain(others.iter().map(|name| name.to_string()))
        .collect()
}

/// Where and how a solve directory is written.
#[derive(Debug, Clone, Copy)]
pub struct SolveDirectory<'a> {
    /// The directory (created if missing; a staging directory of an
    /// [`crate::output::OutputDirectory`], or a subdirectory of one).
    pub path: &'a Path,
    /// Whether `curve.svg` gets a top axis with the seconds elapsed.
    pub seconds_axis: bool,
    /// The plots' file format; `None`: no plot (the CSV tables hold the
    /// same numbers). Drawing needs the cargo feature `plot`.
    pub plot_format: Option<PlotFormat>,
    /// The plots' size.
    pub plot_size: PlotSize,
    /// The command line recorded in `summary.json`.
    pub command_line: &'a [String],
    /// The property file's query the objective came from, if any:
    /// `summary.json` restates it ([`QueryValue::solved`]).
    pub query: Option<&'a Property>,
}

impl SolveDirectory<'_> {
    /// An error, before any run, where a plot is asked for and this build
    /// cannot draw one (without the cargo feature `plot`).
    fn refuse_unbuilt_plots(&self) -> Result<(), OutputError> {
        match self.plot_format.filter(|_| !cfg!(feature = "plot")) {
            Some(format) => Err(OutputError::Plot {
                path: self.path.join(format!("curve.{format}")),
                problem: "this build of posg-fsc draws no plots (cargo feature `plot`); ask \
                          for none"
                    .into(),
            }),
            None => Ok(()),
        }
    }

    /// Runs `job` ([`run`]) under `watch` (each structure's observer and
    /// the run's steps), then writes the curve tables, draws the curves and
    /// writes the other files.
    pub fn solve(&self, job: Job, watch: impl Watch) -> Result<Outcome, PipelineError> {
        self.refuse_unbuilt_plots()?;
        create_dir(self.path)?;
        let (game, automata, settings) = (job.game, job.automata, job.settings);
        let outcome = run(job, watch)?;
        self.write(game, automata, settings, &outcome)?;
        Ok(outcome)
    }

    /// Each structure's curve table: `curve.csv` when it is the only one,
    /// else `curve-<name>.csv` (of the last size a grown run optimised;
    /// `summary.json`'s `sizes` has every size's result).
    fn write_tables(&self, outcome: &Outcome) -> Result<(), PipelineError> {
        let count = outcome.curves.len();
        for curve in &outcome.curves {
            let path = self
                .path
                .join(format!("{}.csv", curve_stem(count, &curve.structure)));
            let mut table = CurveCsv::create(&path)?;
            for record in &curve.records {
                table.observe(record);
            }
            table.finish().map_err(|e| {
                OutputError::io("writing", &path, std::io::Error::other(e.to_string()))
            })?;
        }
        Ok(())
    }

    /// Draws each structure's curve with what it returned (the best one's
    /// with the certified bracket `solve` prints): `curve.svg` with one
    /// structure, else `curve-<name>.svg`.
    fn draw_curves(
        &self,
        game: &Posg,
        automata: &Automata,
        outcome: &Outcome,
    ) -> Result<(), OutputError> {
        let Some(format) = self.plot_format else {
            return Ok(());
        };
        let count = outcome.curves.len();
        for curve in &outcome.curves {
            // None: dropped for numerical trouble, nothing returned.
            let kept = (outcome.solution.structures.iter().enumerate())
                .find(|(_, s)| s.report.name == curve.structure);
            let returned = kept.map(|(index, structure)| {
                let report = &structure.report;
                let certified = if index == outcome.solution.best {
                    outcome.certified
                } else {
                    report.certified_lower.zip(report.upper_bound).map(
                        |(certified_lower, upper_bound)| Bracket {
                            certified_lower,
                            upper_bound,
                        },
                    )
                };
                Returned {
                    worst_case: report.worst_case,
                    certified,
                    kind: ReturnedValue::Estimated,
                }
            });
            // The records of the kept start (start 0's for a structure
            // dropped for numerical trouble).
            let start = kept.map_or(0, |(_, s)| s.report.best_start);
            let records: Vec<IterationRecord> = (curve.records.iter())
                .filter(|r| r.start == start)
                .copied()
                .collect();
            let title = plot_title(game, automata, outcome.best(), &curve.structure);
            let plot = CurvePlot {
                title: &title,
                records: &records,
                returned,
                seconds_axis: self.seconds_axis,
                size: self.plot_size,
                quantity: PROBABILITY_AXIS,
                minimise: false,
            };
            let stem = curve_stem(count, &curve.structure);
            let path = self.path.join(format!("{stem}.{format}"));
            plot_curve(&path, format, &plot)?;
        }
        Ok(())
    }

    /// Draws the curves, copies the best structure's curve to
    /// `curve.csv`/`curve.svg` (with several structures), writes the
    /// controllers, the defender's picture and `summary.json`.
    fn write(
        &self,
        game: &Posg,
        automata: &Automata,
        settings: &Settings,
        outcome: &Outcome,
    ) -> Result<(), PipelineError> {
        self.write_tables(outcome)?;
        self.draw_curves(game, automata, outcome)?;
        let best = outcome.best();
        let best_curve = |ext: &str| self.path.join(format!("curve-{}.{ext}", best.report.name));
        if outcome.curves.len() > 1 && best_curve("csv").exists() {
            let plot = self.plot_format.map(PlotFormat::extension);
            for ext in std::iter::once("csv").chain(plot) {
                let from = best_curve(ext);
                std::fs::copy(&from, self.path.join(format!("curve.{ext}")))
                    .map_err(|e| OutputError::io("copying", &from, e))?;
            }
        }
        controller::file::write(&self.path.join("defender.fsc.json"), &best.defender, game)?;
        write_defender_dot(
            &self.path.join("defender.dot"),
            game,
            automata,
            &best.defender,
        )?;
        controller::file::write(&self.path.join("adversary.fsc.json"), &best.adversary, game)?;
        let summary = Summary {
            command_line: self.command_line,
            crate_version: env!("CARGO_PKG_VERSION"),
            game: game.name(),
            objective: &automata.description,
            query: self.query.map(|property| outcome.query(property)),
            defender_nodes: best.defender.num_nodes(),
            adversary_nodes: best.adversary.num_nodes(),
            settings,
            structure_used: &best.report.name,
            worst_case: best.report.worst_case,
            error_bound: best.report.error_bound,
            certified: outcome.certified,
            certification_error: outcome.certification_error.as_deref(),
            last_value: best.report.last_value,
            seconds: outcome.seconds,
            synthesis_seconds: outcome.synthesis_seconds,
            structure_choice: &outcome.structure_choice,
            sources: &outcome.sources,
            sizes: &outcome.sizes,
            structures: outcome
                .solution
                .structures
                .iter()
                .map(|s| &s.report)
                .collect(),
            files: files(self.plot_format),
        };
        write_file(
            &self.path.join("summary.json"),
            serde_json::to_string_pretty(&summary)? + "\n",
        )?;
        Ok(())
    }
}

impl SolveDirectory<'_> {
    /// Runs the expected-reward optimiser ([`optimise_expected_reward`],
    /// method.md section 9) for a defender of `nodes` nodes (the adversary's
    /// in its gradient play of `adversary_nodes`) with `observer`
    /// beside `curve.csv`, then draws the best start's curve (`curve.svg`,
    /// its value axis named by the reward and its direction) and writes
    /// `defender.fsc.json`, `defender.dot` and `summary.json`.
    pub fn solve_expected_reward(
        &self,
        game: &Posg,
        objective: &RewardObjective,
        (nodes, adversary_nodes): (usize, usize),
        settings: &Settings,
        cancel: &Cancel,
        observer: Box<dyn Observer + Send>,
    ) -> Result<RewardSolution, PipelineError> {
        self.refuse_unbuilt_plots()?;
        create_dir(self.path)?;
        let curve = CurveCsv::create(&self.path.join("curve.csv"))?;
        let records = Arc::new(Mutex::new(Vec::new()));
        let mut observers: Vec<Box<dyn Observer + Send>> = vec![
            Box::new(curve),
            Box::new(Recorder(Arc::clone(&records))),
            observer,
        ];
        let solution = optimise_expected_reward(
            game,
            objective.optimised(),
            (nodes, adversary_nodes),
            settings,
            cancel,
            &mut observers,
        )?;
        drop(observers);
        let records = Arc::into_inner(records)
            .map(|records| records.into_inner().unwrap_or_else(PoisonError::into_inner))
            .unwrap_or_default();
        let description = &objective.description;
        let title = format!(
            "defender for {}: {description} ({nodes} nodes)",
            game.name().unwrap_or("game"),
        );
        controller::file::write(
            &self.path.join("defender.fsc.json"),
            &solution.defender,
            game,
        )?;
        let player = game.defender();
        let dot = crate::output::dot::controller_dot(
            &solution.defender,
            player.observations(),
            &player.action_labels(),
            &title,
            crate::output::dot::DEFAULT_THRESHOLD,
        );
        write_file(&self.path.join("defender.dot"), &dot)?;
        let summary = RewardSummary {
            command_line: self.command_line,
            crate_version: env!("CARGO_PKG_VERSION"),
            game: game.name(),
            objective: description,
            query: self.query.map(|property| {
                QueryValue::rewarded(property, solution.value, solution.error_bound)
            }),
            defender_nodes: nodes,
            settings,
            value: solution.value,
            error_bound: solution.error_bound,
            certificate: solution.certificate.as_ref(),
            best_start: solution.best_start,
            starts: &solution.starts,
            dropped_starts: &solution.dropped_starts,
            seconds: solution.seconds,
            files: reward_files(self.plot_format),
        };
        write_file(
            &self.path.join("summary.json"),
            serde_json::to_string_pretty(&summary)? + "\n",
        )?;
        self.draw_reward_curve(game, objective, nodes, &solution, &records)?;
        Ok(solution)
    }

    /// Draws `curve.svg` of an expected-reward run: the best start's
    /// records and the returned defender's exact value, against the
    /// reward's own axis.
    fn draw_reward_curve(
        &self,
        game: &Posg,
        objective: &RewardObjective,
        nodes: usize,
        solution: &RewardSolution,
        records: &[IterationRecord],
    ) -> Result<(), OutputError> {
        let Some(format) = self.plot_format else {
            return Ok(());
        };
        let records: Vec<IterationRecord> = (records.iter())
            .filter(|r| r.start == solution.best_start)
            .copied()
            .collect();
        let title = Title {
            main: format!(
                "{}: {}",
                game.name().unwrap_or("game"),
                objective.description
            ),
            detail: match solution.starts.len() {
                0 => format!(
                    "defender {}, uniform: the target is missed with positive probability",
                    counted(nodes, "node")
                ),
                starts => format!(
                    "defender {}, best of {}",
                    counted(nodes, "node"),
                    counted(starts, "start")
                ),
            },
        };
        let name = Some(objective.rewards.name()).filter(|name| !name.is_empty());
        let quantity = reward_axis(name, objective.minimise);
        let plot = CurvePlot {
            title: &title,
            records: &records,
            returned: Some(reward_returned(game, solution)),
            seconds_axis: self.seconds_axis,
            size: self.plot_size,
            quantity: &quantity,
            minimise: objective.minimise,
        };
        plot_curve(&self.path.join(format!("curve.{format}")), format, &plot)
    }
}

/// What `curve.svg` shows of an expected-reward run's returned defender: on
/// a game without adversary its exact value; on a game with one, the
/// bracket between what it guarantees and what no defender beats against
/// the adversary found, where both are finite, else its guarantee.
fn reward_returned(game: &Posg, solution: &RewardSolution) -> Returned {
    let Some(certificate) = solution
        .certificate
        .as_ref()
        .filter(|_| game.has_adversary())
    else {
        return Returned {
            worst_case: solution.value,
            certified: None,
            kind: ReturnedValue::Exact,
        };
    };
    let bracket = (certificate.best_possible)
        .filter(|best| best.is_finite() && certificate.guaranteed.is_finite())
        .map(|best| Bracket {
            certified_lower: best.min(certificate.guaranteed),
            upper_bound: best.max(certificate.guaranteed),
        });
    Returned {
        worst_case: certificate.guaranteed,
        certified: bracket,
        kind: ReturnedValue::Guaranteed,
    }
}

/// `summary.json` of an expected-reward objective (docs/formats.md section 9).
#[derive(Debug, Serialize)]
struct RewardSummary<'a> {
    command_line: &'a [String],
    crate_version: &'static str,
    game: Option<&'a str>,
    objective: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    query: Option<QueryValue>,
    defender_nodes: usize,
    settings: &'a Settings,
    /// What the returned defender guarantees: its expected reward,
    /// evaluated exactly, on a game without adversary; its certified worst
    /// case against every adversary on a game with one.
    #[serde(serialize_with = "crate::value::number_or_inf")]
    value: f64,
    /// A bound on `|value - exact value|` (method.md section 8), or the
    /// width of the worst case's certified bracket.
    error_bound: f64,
    /// The returned defender's certificate ([`RewardSolution::certificate`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    certificate: Option<&'a RewardCertificate>,
    best_start: usize,
    starts: &'a [RewardStart],
    /// The starts dropped for numerical trouble, with why.
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    dropped_starts: &'a [String],
    seconds: f64,
    files: Vec<String>,
}

/// `summary.json` (docs/formats.md section 9).
#[derive(Debug, Serialize)]
struct Summary<'a> {
    command_line: &'a [String],
    crate_version: &'static str,
    game: Option<&'a str>,
    objective: &'a str,
    /// The property file's query in its own terms (for `Pmin`, 1 - the
    /// objective's numbers).
    #[serde(skip_serializing_if = "Option::is_none")]
    query: Option<QueryValue>,
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
    /// Why `certified` is absent although the objective came as a formula.
    certification_error: Option<&'a str>,
    last_value: f64,
    seconds: f64,
    /// Seconds of support synthesis (the `sat` source) before optimising.
    synthesis_seconds: f64,
    /// Why `structure_used` won, and why each other structure or source lost.
    structure_choice: &'a [String],
    /// What each source of structures found, proved or why it gave none.
    sources: &'a [SourceNote],
    /// Every defender size optimised (a grown run has one per size from 1
    /// node up), with its certified bracket.
    sizes: &'a [SizeResult],
    structures: Vec<&'a StructureReport>,
    files: Vec<String>,
}

/// The Graphviz picture of the best defender (`dot -Tsvg defender.dot`).
fn write_defender_dot(
    path: &Path,
    game: &Posg,
    automata: &Automata,
    defender: &Fsc,
) -> Result<(), OutputError> {
    let player = game.defender();
    let title = format!(
        "defender for {}: {} ({} nodes)",
        game.name().unwrap_or("game"),
        automata.description,
        defender.num_nodes()
    );
    let text = crate::output::dot::controller_dot(
        defender,
        player.observations(),
        &player.action_labels(),
        &title,
        crate::output::dot::DEFAULT_THRESHOLD,
    );
    write_file(path, &text)
}

/// The file name of a structure's curve without its extension: `curve`
/// when it is the only structure, else `curve-<name>`.
fn curve_stem(count: usize, name: &str) -> String {
    if count > 1 {
        format!("curve-{name}")
    } else {
        "curve".to_string()
    }
}

/// The title of the curve of the structure `name`: game and objective, then
/// the sizes (those of `best`, the same for every structure) and the name.
fn plot_title(game: &Posg, automata: &Automata, best: &StructureOutcome, name: &str) -> Title {
    let nodes = |n: usize| crate::output::counted(n, "node");
    let adversary = if game.has_adversary() {
        format!(", adversary {}", nodes(best.adversary.num_nodes()))
    } else {
        String::new()
    };
    Title {
        main: format!(
            "{}: {}",
            game.name().unwrap_or("game"),
            automata.description
        ),
        detail: format!(
            "defender {}{adversary}, structure {}, game of {} states",
            nodes(best.defender.num_nodes()),
            name,
            game.num_states()
        ),
    }
}
