//! Writers of the optimiser's output, all [`Observer`]s or plain functions
//! of finished results:
//!
//! * [`CurveCsv`]: `curve.csv`, one row per outer iteration;
//! * [`plot_curve`] (cargo feature `plot`): `curve.svg` (or `.png`,
//!   [`PlotFormat`]), the value and the worst-case estimate over the
//!   certified band, against the iteration, with the returned defender's
//!   certified bracket;
//! * [`plot_sweep`] (feature `plot`): `sweep.svg` (or `.png`), a heatmap of
//!   the certified lower bound over defender and adversary sizes;
//! * [`dot::controller_dot`]: a Graphviz picture of a controller;
//! * [`OutputDirectory`]: the directory a command writes its results into,
//!   atomically, under a lock, never mixing old and new results;
//! * [`sweep`]: the rows of `sweep.csv`, one per size pair;
//! * [`counted`]: a count and its noun, as reports print them;
//! * [`error_message`]: an error and its causes, as the CLI and Python
//!   report them.

mod directory;
pub mod dot;
pub mod export;
mod plot;
pub mod sweep;

pub use directory::{
    Abandoned, OutputDirectory, OutputError, abandon_uncommitted, create_dir, write_file,
};
pub use plot::{
    CurvePlot, PROBABILITY_AXIS, PlotFormat, PlotSize, Returned, ReturnedValue, SweepPoint, Title,
    plot_curve, plot_sweep, reward_axis,
};

use std::fs::File;
use std::path::Path;

use crate::optimise::{IterationRecord, Observer, ObserverError};

/// `count` `noun`s, the noun singular for one ("1 iteration", "4
/// starts"), as reports and plot titles print counts.
///
/// ```
/// use posg_fsc::output::counted;
/// assert_eq!(counted(1, "iteration"), "1 iteration");
/// assert_eq!(counted(4, "start"), "4 starts");
/// assert_eq!(counted(0, "node"), "0 nodes");
/// ```
pub fn counted(count: usize, noun: &str) -> String {
    if count == 1 {
        format!("1 {noun}")
    } else {
        format!("{count} {noun}s")
    }
}

/// An error and its causes on one line, each cause once: a cause whose
/// message is already part of the text (an error whose message embeds its
/// source, thiserror's `#[from]` with `{0}`) is not repeated. The CLI
/// prints it after `error: `; Python raises it.
pub fn error_message(error: &(dyn std::error::Error + 'static)) -> String {
    let mut text = error.to_string();
    for cause in std::iter::successors(error.source(), |e| e.source()) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

/// Writes one CSV row per [`IterationRecord`]: `iteration, seconds, value,
/// defender_gradient_norm, adversary_gradient_norm, defender_step,
/// adversary_step, worst_case, certified_lower, upper_bound, logit_bound`
/// (`worst_case`, `certified_lower` and `upper_bound` empty where no check
/// ran; the last two also when no automaton for !phi was given).
pub struct CurveCsv {
    writer: csv::Writer<File>,
    error: Option<csv::Error>,
}

impl CurveCsv {
    /// Creates (truncates) the file at `path`; an error names the path.
    pub fn create(path: &Path) -> Result<Self, OutputError> {
        let file = File::create(path).map_err(|e| OutputError::io("creating", path, e))?;
        Ok(Self {
            writer: csv::Writer::from_writer(file),
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
