//! Progress reports on stderr for `solve` and `sweep`, kept out of the
//! library: optimiser [`Observer`]s and a sweep tracker that draw indicatif
//! bars on a terminal, print a line every few seconds otherwise (logs, CI,
//! cluster jobs), and stay silent with `--quiet`.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use posg_fsc::optimise::{IterationRecord, Observer, ObserverError, RecordSource, SearchRecord};

/// Output options shared by `solve` and `sweep`.
#[derive(Debug, Clone, Args)]
pub struct OutputArgs {
    /// No progress on stderr (by default: bars on a terminal, otherwise a
    /// line every `--progress-every` seconds with the start, iteration,
    /// estimate, best certified bracket and elapsed time).
    #[arg(long)]
    pub quiet: bool,
    /// Seconds between two progress lines when stderr is not a terminal
    /// (logs, pipes, cluster jobs).
    #[arg(long, default_value_t = 5.0, value_parser = posg_fsc::seconds::parse_positive)]
    pub progress_every: f64,
    /// Label the top of curve.svg with the seconds elapsed.
    #[arg(long)]
    pub seconds_axis: bool,
}

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ProgressMode {
    /// indicatif bars (stderr is a terminal).
    Bars,
    /// A line every so often (stderr is a file or a pipe).
    Lines(Duration),
    /// Nothing.
    Quiet,
}

impl ProgressMode {
    /// Bars on a terminal, lines (every `args.progress_every` seconds)
    /// elsewhere (only the final one when the interval is beyond the
    /// clock), nothing with `--quiet`.
    pub fn detect(args: &OutputArgs) -> Self {
        if args.quiet {
            Self::Quiet
        } else if std::io::stderr().is_terminal() {
            Self::Bars
        } else {
            Self::Lines(posg_fsc::seconds::duration(args.progress_every).unwrap_or(Duration::MAX))
        }
    }
}

/// The numbers a progress report shows, updated from the records of every
/// start as they arrive: the latest record's start, iteration, value and
/// worst case, the furthest iteration of any start, and the best bracket
/// certified so far (the highest lower bound and lowest upper bound of any
/// start).
#[derive(Debug, Clone, Copy, Default)]
struct Latest {
    start: usize,
    iteration: usize,
    furthest: usize,
    value: f64,
    worst_case: Option<f64>,
    lower: Option<f64>,
    upper: Option<f64>,
    seconds: f64,
    /// The part that made the returned defender, once it is known.
    returned: Option<RecordSource>,
}

impl Latest {
    fn update(&mut self, record: &IterationRecord) {
        self.seconds = self.seconds.max(record.seconds);
        self.lower = max_of(self.lower, record.certified_lower);
        self.upper = min_of(self.upper, record.upper_bound);
        if record.returned {
            self.returned = Some(record.source);
            self.worst_case = record.worst_case;
            return;
        }
        self.start = record.start;
        self.iteration = record.iteration;
        self.furthest = self.furthest.max(record.iteration + 1);
        self.value = record.value;
        self.worst_case = record.worst_case.or(self.worst_case);
    }

    /// Counts the bound of the local search before the race as certified.
    fn searched(&mut self, record: &SearchRecord) {
        self.seconds = self.seconds.max(record.seconds);
        self.lower = max_of(self.lower, Some(record.certified_lower));
    }

    /// `start 2 at iteration 140: value 0.61, worst case 0.58; best certified [0.57, 0.70]`.
    fn describe(&self) -> String {
        let worst = self.worst_case.map_or("-".into(), |w| format!("{w:.6}"));
        let bracket = match (self.lower, self.upper) {
            (Some(l), Some(u)) => format!("; best certified [{l:.6}, {u:.6}]"),
            _ => String::new(),
        };
        if let Some(source) = self.returned {
            let source = serde_json::to_value(source).ok();
            let source = source.as_ref().and_then(|s| s.as_str()).unwrap_or("?");
            return format!(
                "returned the {source} defender after {}: worst case {worst}{bracket}",
                posg_fsc::output::counted(self.furthest, "iteration")
            );
        }
        format!(
            "start {} at iteration {}: value {:.6}, worst case {worst}{bracket}",
            self.start,
            self.iteration + 1,
            self.value
        )
    }
}

/// `local search before the race: certified 0.81, done at 0.4 s` (since
/// the run began: the structures search one after another).
fn searched_line(record: &SearchRecord) -> String {
    format!(
        "local search before the race: certified {:.6}, done at {:.1} s",
        record.certified_lower, record.seconds
    )
}

/// The larger of two optional numbers (either when the other is `None`).
fn max_of(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    }
}

/// The smaller of two optional numbers (either when the other is `None`).
fn min_of(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
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
        (ProgressMode::Lines(interval), _) => {
            Some(Box::new(LineProgress::new(label, iterations, interval)))
        }
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
        self.bar.set_position(self.latest.furthest as u64);
        self.bar.set_message(self.latest.describe());
    }

    fn searched(&mut self, record: &SearchRecord) {
        self.latest.searched(record);
        self.bar.set_message(searched_line(record));
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        self.bar.finish();
        Ok(())
    }
}

/// A line on stderr every `interval` and at the end (unless the last
/// line already showed every record).
struct LineProgress {
    label: String,
    iterations: usize,
    interval: Duration,
    last_line: Instant,
    latest: Latest,
    /// Whether a record arrived since the last line.
    unprinted: bool,
}

impl LineProgress {
    fn new(label: &str, iterations: usize, interval: Duration) -> Self {
        Self {
            label: label.to_string(),
            iterations,
            interval,
            last_line: Instant::now(),
            latest: Latest::default(),
            unprinted: false,
        }
    }

    fn print(&mut self) {
        self.unprinted = false;
        self.last_line = Instant::now();
        let cap = match self.latest.returned {
            None => format!(" (at most {} iterations)", self.iterations),
            Some(_) => String::new(),
        };
        eprintln!(
            "[{}] {}{cap}; {:.1} s",
            self.label,
            self.latest.describe(),
            self.latest.seconds
        );
    }
}

impl Observer for LineProgress {
    fn observe(&mut self, record: &IterationRecord) {
        if record.returned {
            // The last iterations' line, then the returned defender's, at once.
            if self.unprinted {
                self.print();
            }
            self.latest.update(record);
            self.print();
            return;
        }
        self.latest.update(record);
        self.unprinted = true;
        if self.last_line.elapsed() >= self.interval {
            self.print();
        }
    }

    fn searched(&mut self, record: &SearchRecord) {
        self.latest.searched(record);
        eprintln!("[{}] {}", self.label, searched_line(record));
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        if self.unprinted {
            self.print();
        }
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
            (None, ProgressMode::Lines(_)) => {
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
