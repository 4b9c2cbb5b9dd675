//! Progress reports on stderr for `solve` and `sweep`, kept out of the
//! library: optimiser [`Observer`]s and a sweep tracker that draw indicatif
//! bars on a terminal, print a line every few seconds otherwise (logs, CI,
//! cluster jobs), and stay silent with `--quiet`.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use posg_fsc::optimise::{IterationRecord, Observer, ObserverError};

/// Seconds between two progress lines when stderr is not a terminal.
const LINE_INTERVAL: Duration = Duration::from_secs(5);

/// Output options shared by `solve` and `sweep`.
#[derive(Debug, Clone, Args)]
pub struct OutputArgs {
    /// No progress on stderr (by default: bars on a terminal, otherwise a
    /// line every 5 seconds with iteration, estimate, bounds and elapsed time).
    #[arg(long)]
    pub quiet: bool,
    /// Label the top of curve.svg with the seconds elapsed.
    #[arg(long)]
    pub seconds_axis: bool,
}

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProgressMode {
    /// indicatif bars (stderr is a terminal).
    Bars,
    /// A line every [`LINE_INTERVAL`] (stderr is a file or a pipe).
    Lines,
    /// Nothing.
    Quiet,
}

impl ProgressMode {
    /// Bars on a terminal, lines elsewhere, nothing with `--quiet`.
    pub fn detect(quiet: bool) -> Self {
        if quiet {
            Self::Quiet
        } else if std::io::stderr().is_terminal() {
            Self::Bars
        } else {
            Self::Lines
        }
    }
}

/// The numbers a progress report shows, updated from the records.
#[derive(Debug, Clone, Copy, Default)]
struct Latest {
    iteration: usize,
    value: f64,
    worst_case: Option<f64>,
    bracket: Option<(f64, f64)>,
    seconds: f64,
}

impl Latest {
    fn update(&mut self, record: &IterationRecord) {
        self.iteration = record.iteration;
        self.value = record.value;
        self.seconds = record.seconds;
        self.worst_case = record.worst_case.or(self.worst_case);
        if let (Some(lower), Some(upper)) = (record.certified_lower, record.upper_bound) {
            self.bracket = Some((lower, upper));
        }
    }

    /// `value 0.61, worst case 0.58, certified [0.57, 0.70]`.
    fn describe(&self) -> String {
        let worst = self.worst_case.map_or("-".into(), |w| format!("{w:.6}"));
        let bracket = self.bracket.map_or(String::new(), |(l, u)| {
            format!(", certified [{l:.6}, {u:.6}]")
        });
        format!("value {:.6}, worst case {worst}{bracket}", self.value)
    }
}

/// The progress observer of one structure's optimisation, or `None`.
pub fn structure_progress(
    mode: ProgressMode,
    bars: Option<&MultiProgress>,
    label: &str,
    iterations: usize,
) -> Option<Box<dyn Observer + Send>> {
    match (mode, bars) {
        (ProgressMode::Bars, Some(bars)) => {
            Some(Box::new(BarProgress::new(bars, label, iterations)))
        }
        (ProgressMode::Lines, _) => Some(Box::new(LineProgress::new(label, iterations))),
        _ => None,
    }
}

/// A progress bar over the outer iterations.
struct BarProgress {
    bar: ProgressBar,
    latest: Latest,
}

impl BarProgress {
    fn new(bars: &MultiProgress, label: &str, iterations: usize) -> Self {
        let bar = bars.add(ProgressBar::new(iterations as u64));
        let style =
            ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(label.to_string());
        Self {
            bar,
            latest: Latest::default(),
        }
    }
}

impl Observer for BarProgress {
    fn observe(&mut self, record: &IterationRecord) {
        self.latest.update(record);
        self.bar.set_position(record.iteration as u64 + 1);
        self.bar.set_message(self.latest.describe());
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        self.bar.finish();
        Ok(())
    }
}

/// A line on stderr every [`LINE_INTERVAL`] and at the end.
struct LineProgress {
    label: String,
    iterations: usize,
    last_line: Instant,
    latest: Latest,
}

impl LineProgress {
    fn new(label: &str, iterations: usize) -> Self {
        Self {
            label: label.to_string(),
            iterations,
            last_line: Instant::now(),
            latest: Latest::default(),
        }
    }

    fn print(&self) {
        eprintln!(
            "[{}] iteration {}/{}: {}; {:.1} s",
            self.label,
            self.latest.iteration + 1,
            self.iterations,
            self.latest.describe(),
            self.latest.seconds
        );
    }
}

impl Observer for LineProgress {
    fn observe(&mut self, record: &IterationRecord) {
        self.latest.update(record);
        if self.last_line.elapsed() >= LINE_INTERVAL {
            self.print();
            self.last_line = Instant::now();
        }
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        self.print();
        Ok(())
    }
}

/// The size pairs of a sweep done so far: a bar with done / total and an
/// estimated time to go on a terminal, a line per finished pair otherwise.
pub struct SweepProgress {
    mode: ProgressMode,
    total: usize,
    start: Instant,
    done: Mutex<usize>,
    bar: Option<ProgressBar>,
}

impl SweepProgress {
    /// A tracker of `total` size pairs.
    pub fn new(mode: ProgressMode, total: usize) -> Self {
        let bar = (mode == ProgressMode::Bars).then(|| {
            let bar = ProgressBar::new(total as u64);
            let style = ProgressStyle::with_template(
                "sweep [{bar:30}] {pos}/{len} size pairs, {elapsed} elapsed, ETA {eta} {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
            bar.set_style(style);
            bar
        });
        Self {
            mode,
            total,
            start: Instant::now(),
            done: Mutex::new(0),
            bar,
        }
    }

    /// Records that the pair (`defender`, `adversary`) finished with this
    /// worst-case estimate.
    pub fn finished(&self, defender: usize, adversary: usize, worst_case: f64) {
        let done = {
            let mut done = self.done.lock().unwrap_or_else(|e| e.into_inner());
            *done += 1;
            *done
        };
        let summary =
            format!("defender {defender}, adversary {adversary}: worst case {worst_case:.6}");
        match (&self.bar, self.mode) {
            (Some(bar), _) => {
                bar.inc(1);
                bar.set_message(summary);
            }
            (None, ProgressMode::Lines) => {
                let elapsed = self.start.elapsed().as_secs_f64();
                let eta = elapsed / done as f64 * (self.total - done) as f64;
                eprintln!(
                    "sweep {done}/{} size pairs ({summary}); {elapsed:.1} s elapsed, ETA {eta:.0} s",
                    self.total
                );
            }
            _ => {}
        }
    }

    /// Ends the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish();
        }
    }
}
