//! Progress reports on stderr for `solve` and `sweep`, kept out of the
//! library: a [`Reporter`] that shows the library's [`Progress`] board (a
//! spinner on a terminal, a line every few seconds otherwise: logs, CI,
//! cluster jobs) and a sweep tracker; silent with `--quiet`.

use std::io::IsTerminal;
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use posg_fsc::pipeline::progress::{DEFAULT_INTERVAL_SECONDS, Progress};

/// Output options shared by `solve` and `sweep`.
#[derive(Debug, Clone, Args)]
pub struct OutputArgs {
    /// No progress on stderr (by default: a spinner on a terminal,
    /// otherwise a line at once for each event and, when nothing happened
    /// for `--progress-every` seconds, one with what each part of the run
    /// is doing and the best certified bracket so far).
    #[arg(long)]
    pub quiet: bool,
    /// Seconds between two progress lines when stderr is not a terminal
    /// (logs, pipes, cluster jobs).
    #[arg(long, default_value_t = DEFAULT_INTERVAL_SECONDS, value_parser = posg_fsc::seconds::parse_positive)]
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

/// How often the reporter looks at the board: events appear within this.
const POLL: Duration = Duration::from_millis(100);

/// Prints a run's [`Progress`] on stderr while it runs, from a thread of
/// its own: the board's lines as they are due ([`ProgressMode::Lines`]),
/// or a spinner with the status and the events above it
/// ([`ProgressMode::Bars`]). Dropping it prints what is left and stops.
pub struct Reporter {
    progress: Arc<Progress>,
    stop: Option<mpsc::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl Reporter {
    /// A reporter of a new board (whose lines begin with `label`, if
    /// given, stamped with the seconds since `started`), or `None` in
    /// [`ProgressMode::Quiet`].
    pub fn start(mode: ProgressMode, label: Option<String>, started: Instant) -> Option<Self> {
        let interval = match mode {
            ProgressMode::Quiet => return None,
            ProgressMode::Lines(interval) => interval,
            ProgressMode::Bars => Duration::MAX,
        };
        let progress = Progress::labelled(interval, label, started);
        let (stop, stopped) = mpsc::channel();
        let board = Arc::clone(&progress);
        let thread = std::thread::spawn(move || match mode {
            ProgressMode::Bars => spin(&board, &stopped),
            _ => print_lines(&board, &stopped),
        });
        Some(Self {
            progress,
            stop: Some(stop),
            thread: Some(thread),
        })
    }

    /// The board the run's observers update.
    pub fn progress(&self) -> &Arc<Progress> {
        &self.progress
    }
}

impl Drop for Reporter {
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// Prints the board's due lines until `stopped` says stop (or its sender
/// is gone), then its last events.
fn print_lines(board: &Progress, stopped: &mpsc::Receiver<()>) {
    while let Err(mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(POLL) {
        for line in board.due_lines() {
            eprintln!("{line}");
        }
    }
    for line in board.events() {
        eprintln!("{line}");
    }
}

/// A spinner with the board's status, its events printed above it.
fn spin(board: &Progress, stopped: &mpsc::Receiver<()>) {
    let spinner = ProgressBar::new_spinner();
    spinner.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed}] {wide_msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let show = |spinner: &ProgressBar| {
        for line in board.events() {
            spinner.println(line);
        }
        spinner.set_message(board.status());
    };
    while let Err(mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(POLL) {
        show(&spinner);
        spinner.tick();
    }
    show(&spinner);
    spinner.finish_and_clear();
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

    /// The reporter of the pair (`defender`, `adversary`) while it runs:
    /// its own lines in a log (a terminal shows the sweep's bar alone).
    pub fn pair_reporter(&self, defender: usize, adversary: usize) -> Option<Reporter> {
        match self.mode {
            ProgressMode::Lines(_) => Reporter::start(
                self.mode,
                Some(format!("defender {defender}, adversary {adversary}")),
                self.start,
            ),
            _ => None,
        }
    }

    /// Ends the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish();
        }
    }
}
