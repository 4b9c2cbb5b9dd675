//! A `solve` directory (docs/formats.md section 9): the pipeline's
//! [`Outcome`] as `curve.csv`, `curve.svg`, `defender.fsc.json`,
//! `defender.dot`, `adversary.fsc.json` and `summary.json` (with several
//! structures, each one's curve as `curve-<name>.csv`/`.svg`, the best one's
//! copied to `curve.csv`/`curve.svg`).

use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

use serde::Serialize;

use super::{Automata, Job, Outcome, PipelineError, Slot, run};
use crate::certify::Bracket;
use crate::controller::{self, Fsc};
use crate::game::Posg;
use crate::optimise::{
    IterationRecord, Observer, ObserverError, OptimiseError, Settings, SourceNote, StructureReport,
};
use crate::output::{CurveCsv, CurvePlot, OutputError, Title, create_dir, write_file};

/// The files of a solve directory, as `summary.json` lists them.
pub const FILES: [&str; 6] = [
    "curve.csv",
    "curve.svg",
    "defender.fsc.json",
    "defender.dot",
    "adversary.fsc.json",
    "summary.json",
];

/// Where and how a solve directory is written.
#[derive(Debug, Clone, Copy)]
pub struct SolveDirectory<'a> {
    /// The directory (created if missing; a staging directory of an
    /// [`crate::output::OutputDirectory`], or a subdirectory of one).
    pub path: &'a Path,
    /// Whether `curve.svg` gets a top axis with the seconds elapsed.
    pub seconds_axis: bool,
    /// The command line recorded in `summary.json`.
    pub command_line: &'a [String],
}

impl SolveDirectory<'_> {
    /// Runs `job` ([`run`]) with the curve's CSV writer and
    /// `observers(slot)` as each structure's observers, then draws each
    /// structure's curve and writes the other files.
    pub fn solve<F>(&self, job: Job, observers: F) -> Result<Outcome, PipelineError>
    where
        F: Fn(Slot) -> Box<dyn Observer + Send> + Sync,
    {
        create_dir(self.path)?;
        let (game, automata, settings) = (job.game, job.automata, job.settings);
        let plots = Mutex::new(Vec::new());
        let outcome = run(job, |slot| {
            let stem = curve_stem(slot);
            let title = plot_title(game, automata, slot);
            plots.lock().unwrap_or_else(PoisonError::into_inner).push((
                slot.index,
                self.path.join(format!("{stem}.svg")),
                title,
            ));
            let table = self.path.join(format!("{stem}.csv"));
            let csv: Box<dyn Observer + Send> = match CurveCsv::create(&table) {
                Ok(csv) => Box::new(Named(table, csv)),
                Err(error) => Box::new(Failed(Some(error.into()))),
            };
            Box::new(vec![csv, observers(slot)]) as Box<dyn Observer + Send>
        })?;
        let plots = plots.into_inner().unwrap_or_else(PoisonError::into_inner);
        for (index, path, title) in plots {
            self.draw_curve(&outcome, index, &path, title)?;
        }
        self.write(game, automata, settings, &outcome)?;
        Ok(outcome)
    }

    /// Draws the curve of structure `index` at `path`: the records of its
    /// kept start (of start 0 for a structure dropped for numerical
    /// trouble).
    fn draw_curve(
        &self,
        outcome: &Outcome,
        index: usize,
        path: &Path,
        title: Title,
    ) -> Result<(), PipelineError> {
        let curve = &outcome.curves[index];
        let kept = outcome
            .solution
            .structures
            .iter()
            .find(|s| s.report.name == curve.structure)
            .map_or(0, |s| s.report.best_start);
        let records: Vec<IterationRecord> = curve
            .records
            .iter()
            .filter(|r| r.start == kept)
            .copied()
            .collect();
        CurvePlot::new(path, title)
            .with_seconds_axis(self.seconds_axis)
            .draw(&records)
            .map_err(|e| {
                OptimiseError::Observer(format!("writing {}: {e}", path.display()).into()).into()
            })
    }

    /// Copies the best structure's curve to `curve.csv`/`curve.svg` (with
    /// several structures), writes the controllers, the defender's picture
    /// and `summary.json`.
    fn write(
        &self,
        game: &Posg,
        automata: &Automata,
        settings: &Settings,
        outcome: &Outcome,
    ) -> Result<(), PipelineError> {
        let best = outcome.best();
        let best_curve = |ext: &str| self.path.join(format!("curve-{}.{ext}", best.report.name));
        if outcome.curves.len() > 1 && best_curve("csv").exists() {
            for ext in ["csv", "svg"] {
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
            structures: outcome
                .solution
                .structures
                .iter()
                .map(|s| &s.report)
                .collect(),
            files: FILES,
        };
        write_file(
            &self.path.join("summary.json"),
            serde_json::to_string_pretty(&summary)? + "\n",
        )?;
        Ok(())
    }
}

/// `summary.json` (docs/formats.md section 9).
#[derive(Debug, Serialize)]
struct Summary<'a> {
    command_line: &'a [String],
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
    structures: Vec<&'a StructureReport>,
    files: [&'static str; 6],
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
        player.actions(),
        &title,
        crate::output::dot::DEFAULT_THRESHOLD,
    );
    write_file(path, &text)
}

/// The stem of a structure's curve files: `curve` when it is the only
/// structure, else `curve-<name>`.
fn curve_stem(slot: Slot) -> String {
    if slot.count > 1 {
        format!("curve-{}", slot.structure.name)
    } else {
        "curve".to_string()
    }
}

/// The title of a structure's `curve.svg`: game and objective, then sizes
/// and structure.
fn plot_title(game: &Posg, automata: &Automata, slot: Slot) -> Title {
    let nodes = |n: usize| {
        if n == 1 {
            "1 node".to_string()
        } else {
            format!("{n} nodes")
        }
    };
    let structure = slot.structure;
    let adversary = if game.has_adversary() {
        format!(", adversary {}", nodes(structure.adversary.num_nodes()))
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
            nodes(structure.defender.num_nodes()),
            structure.name,
            game.num_states()
        ),
    }
}

/// An observer writing the file at `.0`, whose failure names that file.
struct Named<O>(PathBuf, O);

impl<O: Observer> Observer for Named<O> {
    fn observe(&mut self, record: &IterationRecord) {
        self.1.observe(record);
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        self.1
            .finish()
            .map_err(|e| format!("writing {}: {e}", self.0.display()).into())
    }
}

/// An observer that could not be created: reports its error at the end.
struct Failed(Option<ObserverError>);

impl Observer for Failed {
    fn observe(&mut self, _record: &IterationRecord) {}

    fn finish(&mut self) -> Result<(), ObserverError> {
        self.0.take().map_or(Ok(()), Err)
    }
}
