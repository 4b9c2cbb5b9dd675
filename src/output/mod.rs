//! Writers of the optimiser's output, all [`Observer`]s or plain functions
//! of finished results:
//!
//! * [`CurveCsv`]: `curve.csv`, one row per outer iteration;
//! * [`CurvePlot`]: `curve.svg`, the value and the worst-case estimate
//!   against the iteration;
//! * [`Progress`]: a progress bar on stderr (the caller creates it only when
//!   stderr is a terminal);
//! * [`plot_sweep`]: `sweep.svg`, the worst-case value against the defender's
//!   size, one line per adversary size;
//! * [`dot::controller_dot`]: a Graphviz picture of a controller.

pub mod dot;
mod plot;

pub use plot::{CurvePlot, SweepPoint, plot_sweep};

use std::fs::File;
use std::path::Path;

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use crate::optimise::{IterationRecord, Observer, ObserverError};

/// Writes one CSV row per [`IterationRecord`]: `iteration, seconds, value,
/// defender_gradient_norm, adversary_gradient_norm, defender_step,
/// adversary_step, worst_case, certified_lower, upper_bound` (the last three
/// empty where no check ran; the last two also when no automaton for !phi
/// was given).
pub struct CurveCsv {
    writer: csv::Writer<File>,
    error: Option<csv::Error>,
}

impl CurveCsv {
    /// Creates (truncates) the file at `path`.
    pub fn create(path: &Path) -> Result<Self, csv::Error> {
        Ok(Self {
            writer: csv::Writer::from_path(path)?,
            error: None,
        })
    }
}

impl Observer for CurveCsv {
    fn observe(&mut self, record: &IterationRecord) {
        if self.error.is_none() {
            self.error = self.writer.serialize(record).err();
        }
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        match self.error.take() {
            Some(error) => Err(error.into()),
            None => Ok(self.writer.flush()?),
        }
    }
}

/// A progress bar over the outer iterations showing the value and the last
/// worst-case estimate.
pub struct Progress {
    bar: ProgressBar,
    worst_case: Option<f64>,
}

impl Progress {
    /// A bar of `iterations` steps labelled `label`, drawn on stderr below
    /// the other bars of `bars` (one per structure optimised in parallel).
    pub fn new(bars: &MultiProgress, label: &str, iterations: usize) -> Self {
        let bar = bars.add(ProgressBar::new(iterations as u64));
        let style =
            ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(label.to_string());
        Self {
            bar,
            worst_case: None,
        }
    }
}

impl Observer for Progress {
    fn observe(&mut self, record: &IterationRecord) {
        self.worst_case = record.worst_case.or(self.worst_case);
        let worst = self
            .worst_case
            .map_or("-".to_string(), |w| format!("{w:.6}"));
        self.bar.set_position(record.iteration as u64 + 1);
        self.bar
            .set_message(format!("value {:.6}, worst case {worst}", record.value));
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        self.bar.finish();
        Ok(())
    }
}
