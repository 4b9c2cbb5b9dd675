//! What a run is doing while it runs, in words: a [`Progress`] board that
//! the run's observers update ([`Progress::watching`] wraps a [`Watch`],
//! [`Progress::observer`] watches a lone optimisation) and that a face
//! reads every so often ([`Progress::due_lines`]; the command line prints
//! the lines on stderr, Python on `sys.stderr`).
//!
//! A line is either an event, at once (a local search before a race ended,
//! a structure returned its defender, a size was certified), or, when no
//! line came for an interval, the status: the step, each structure's
//! phase, and the incumbent certified bracket with where it came from.
//! Every line starts with the seconds since the board was made, so a log
//! shows one clock.

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use super::{Slot, Step, Watch};
use crate::optimise::{IterationRecord, Observer, Phase, RecordSource, SearchRecord};

/// How long a run may stay silent before its first status line.
pub const FIRST_LINE_AFTER: Duration = Duration::from_secs(1);

/// The seconds between two status lines unless the face says otherwise
/// (`--progress-every`, Python's `progress=True`).
pub const DEFAULT_INTERVAL_SECONDS: f64 = 5.0;

/// The board of one run (shared by its observers: hold it in an [`Arc`]).
#[derive(Debug)]
pub struct Progress {
    started: Instant,
    interval: Duration,
    /// Said before every line (a sweep's size pair), if anything.
    label: Option<String>,
    board: Mutex<Board>,
}

/// What the board knows.
#[derive(Debug, Default)]
struct Board {
    /// What the run does outside the structures' optimisation (reading
    /// the game, gathering supports, certifying), if anything.
    step: Option<String>,
    /// The defender size being optimised and the size the run ends at.
    size: Option<(usize, usize)>,
    /// The structures of the size being optimised, by slot index.
    structures: Vec<Option<Optimising>>,
    /// The best certified lower bound so far and where it came from.
    incumbent: Option<Incumbent>,
    /// The smallest game upper bound so far.
    upper: Option<f64>,
    /// The best worst-case estimate so far (shown where nothing is
    /// certified: an objective given as an automaton, a single player
    /// before its final certificate, an expected reward).
    estimate: Option<f64>,
    /// Whether a lower estimate is better (a minimised expected cost).
    minimise: bool,
    /// Event lines not yet handed out.
    events: Vec<String>,
    /// When the last line was handed out.
    last_line: Option<Instant>,
}

/// One structure's optimisation, as far as the board knows it.
#[derive(Debug, Clone)]
struct Optimising {
    name: String,
    phase: Option<Phase>,
    /// The furthest outer iteration any start reached (counted from 1).
    iterations: usize,
    returned: bool,
}

/// The best certified lower bound so far.
#[derive(Debug, Clone)]
struct Incumbent {
    lower: f64,
    structure: String,
    source: RecordSource,
    defender_nodes: usize,
}

impl Progress {
    /// A board made now, whose status line is due when no line came for
    /// `interval` (the first after [`FIRST_LINE_AFTER`]).
    pub fn new(interval: Duration) -> Arc<Self> {
        Self::labelled(interval, None, Instant::now())
    }

    /// A board as [`Progress::new`] whose lines begin with `label` (`defender
    /// 2, adversary 1`), stamped with the seconds since `started` (a
    /// sweep's pairs share the sweep's clock).
    pub fn labelled(interval: Duration, label: Option<String>, started: Instant) -> Arc<Self> {
        Arc::new(Self {
            started,
            interval,
            label,
            board: Mutex::new(Board::default()),
        })
    }

    /// The face's own step (`reading game.drn`), until the run's first.
    pub fn begin(&self, step: impl Into<String>) {
        self.board().step = Some(step.into());
    }

    /// `watch` with this board watching beside it.
    pub fn watching<W: Watch>(self: &Arc<Self>, watch: W) -> Watched<W> {
        Watched {
            progress: Arc::clone(self),
            watch,
        }
    }

    /// An observer of a lone optimisation (no pipeline around it) of the
    /// structure `name` with a defender of `defender_nodes` nodes; with
    /// `minimise`, a lower worst-case estimate is the better (an expected
    /// cost).
    pub fn observer(
        self: &Arc<Self>,
        name: &str,
        defender_nodes: usize,
        minimise: bool,
    ) -> ProgressObserver {
        let mut board = self.board();
        board.minimise = minimise;
        board.size = Some((defender_nodes, defender_nodes));
        board.step = None;
        board.structures = vec![Some(Optimising::new(name))];
        ProgressObserver {
            progress: Arc::clone(self),
            index: 0,
            defender_nodes,
        }
    }

    /// The lines due now: the events since the last call, else the status
    /// line when no line came for the interval (or for
    /// [`FIRST_LINE_AFTER`] at first).
    pub fn due_lines(&self) -> Vec<String> {
        let now = Instant::now();
        let mut board = self.board();
        let mut lines = std::mem::take(&mut board.events);
        let silent_for = match board.last_line {
            Some(last) => (now - last, self.interval),
            None => (now - self.started, FIRST_LINE_AFTER.min(self.interval)),
        };
        if lines.is_empty() && silent_for.0 >= silent_for.1 {
            lines.push(self.stamped(&board.status()));
        }
        if !lines.is_empty() {
            board.last_line = Some(now);
        }
        lines
    }

    /// The event lines since the last call (for a face that shows the
    /// status its own way, a spinner say).
    pub fn events(&self) -> Vec<String> {
        std::mem::take(&mut self.board().events)
    }

    /// The status line now, without its time stamp (for a spinner).
    pub fn status(&self) -> String {
        self.board().status()
    }

    fn board(&self) -> MutexGuard<'_, Board> {
        self.board.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// `text` after the seconds since the board was made.
    fn stamped(&self, text: &str) -> String {
        let label = self
            .label
            .as_ref()
            .map_or(String::new(), |l| format!("{l}: "));
        format!(
            "[{:.1} s] {label}{text}",
            self.started.elapsed().as_secs_f64()
        )
    }

    /// Queues the event `text` with the incumbent bracket after it.
    fn event(&self, board: &mut Board, text: &str) {
        let best = match (&board.incumbent, board.upper) {
            (Some(i), Some(u)) => format!("; best certified [{:.6}, {u:.6}]", i.lower),
            (Some(i), None) => format!("; best certified {:.6}", i.lower),
            (None, _) => String::new(),
        };
        let line = self.stamped(&format!("{text}{best}"));
        board.events.push(line);
    }

    fn step(&self, step: &Step) {
        let mut board = self.board();
        match *step {
            Step::Supports {
                defender_nodes,
                final_nodes,
            } => {
                board.size = Some((defender_nodes, final_nodes));
                board.structures.clear();
                board.step = Some("gathering the supports".into());
            }
            Step::Source(source) => {
                board.step = Some(format!("gathering the supports: {}", source.search()));
            }
            Step::Certifying { .. } => {
                board.step = Some("certifying the best defender".into());
            }
            Step::SizeDone(size) => {
                board.step = None;
                let bracket = match size.certified {
                    Some(b) => {
                        format!("certified [{:.6}, {:.6}]", b.certified_lower, b.upper_bound)
                    }
                    None => format!("worst-case estimate {:.6}", size.worst_case),
                };
                let text = format!(
                    "{}: done in {:.1} s, {bracket}",
                    nodes(size.defender_nodes),
                    size.seconds
                );
                let line = self.stamped(&text);
                board.events.push(line);
            }
        }
    }

    fn slot(self: &Arc<Self>, slot: &Slot) -> ProgressObserver {
        let mut board = self.board();
        board.step = None;
        if board.structures.len() <= slot.index {
            board.structures.resize(slot.index + 1, None);
        }
        board.structures[slot.index] = Some(Optimising::new(&slot.structure.name));
        ProgressObserver {
            progress: Arc::clone(self),
            index: slot.index,
            defender_nodes: slot.defender_nodes,
        }
    }
}

impl Board {
    /// `2 of 3 nodes: full racing (iteration 140), informed local search;
    /// certified [0.53, 0.58] by informed (local search, 1 node)`.
    fn status(&self) -> String {
        let size = match self.size {
            Some((n, of)) if of > n => format!("{n} of {}: ", nodes(of)),
            Some((n, _)) => format!("{}: ", nodes(n)),
            None => String::new(),
        };
        let doing = match &self.step {
            Some(step) => step.clone(),
            None => {
                let each: Vec<String> = (self.structures.iter().flatten())
                    .map(Optimising::describe)
                    .collect();
                if each.is_empty() {
                    "starting".into()
                } else {
                    each.join(", ")
                }
            }
        };
        format!("{size}{doing}; {}", self.bracket())
    }

    /// `certified [0.53, 0.58] by informed (local search, 1 node)`, or the
    /// best estimate where nothing is certified yet.
    fn bracket(&self) -> String {
        let upper = self.upper.map_or(String::new(), |u| format!(", {u:.6}"));
        match &self.incumbent {
            Some(i) => format!(
                "certified [{:.6}{upper}] by {} ({}, {})",
                i.lower,
                i.structure,
                source_words(i.source),
                nodes(i.defender_nodes)
            ),
            None => match self.estimate {
                Some(e) => format!("nothing certified yet; best worst-case estimate {e:.6}"),
                None => "nothing certified yet".into(),
            },
        }
    }

    /// Takes a certified lower bound `lower` of the structure `index`
    /// (at `defender_nodes`) from `source` as the incumbent if it is
    /// higher.
    fn certified(&mut self, lower: f64, index: usize, source: RecordSource, defender_nodes: usize) {
        if self.incumbent.as_ref().is_some_and(|i| i.lower >= lower) {
            return;
        }
        let structure = self.name(index);
        self.incumbent = Some(Incumbent {
            lower,
            structure,
            source,
            defender_nodes,
        });
    }

    fn name(&self, index: usize) -> String {
        (self.structures.get(index).and_then(Option::as_ref))
            .map_or_else(|| "?".into(), |s| s.name.clone())
    }

    fn optimising(&mut self, index: usize) -> Option<&mut Optimising> {
        self.structures.get_mut(index).and_then(Option::as_mut)
    }
}

impl Optimising {
    fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
            phase: None,
            iterations: 0,
            returned: false,
        }
    }

    /// `full racing (iteration 140)`.
    fn describe(&self) -> String {
        let doing = match (&self.phase, self.returned) {
            (_, true) => "done".to_string(),
            (None, _) => "waiting".to_string(),
            (Some(Phase::LocalSearch), _) => "local search".to_string(),
            (Some(Phase::Race), _) => format!("racing (iteration {})", self.iterations),
            (Some(Phase::Finishing { .. }), _) => "rounding and final checks".to_string(),
        };
        format!("{} {doing}", self.name)
    }
}

/// `1 node`, `3 nodes`.
fn nodes(n: usize) -> String {
    crate::output::counted(n, "node")
}

/// What made a record's defender, in words.
fn source_words(source: RecordSource) -> &'static str {
    match source {
        RecordSource::Gradient => "gradient play",
        RecordSource::LocalSearch => "local search",
        RecordSource::Rounding => "rounding",
    }
}

/// A [`Watch`] with a [`Progress`] board watching beside it.
pub struct Watched<W> {
    progress: Arc<Progress>,
    watch: W,
}

impl<W: Watch> Watch for Watched<W> {
    fn structure(&self, slot: Slot) -> Box<dyn Observer + Send> {
        let ours = Box::new(self.progress.slot(&slot));
        Box::new(vec![
            self.watch.structure(slot),
            ours as Box<dyn Observer + Send>,
        ])
    }

    fn step(&self, step: &Step) {
        self.progress.step(step);
        self.watch.step(step);
    }
}

/// The board's observer of one structure.
pub struct ProgressObserver {
    progress: Arc<Progress>,
    index: usize,
    defender_nodes: usize,
}

impl Observer for ProgressObserver {
    fn observe(&mut self, record: &IterationRecord) {
        let mut board = self.progress.board();
        if let Some(lower) = record.certified_lower {
            board.certified(lower, self.index, record.source, self.defender_nodes);
        }
        if let Some(upper) = record.upper_bound {
            board.upper = Some(board.upper.map_or(upper, |u| u.min(upper)));
        }
        if let Some(worst_case) = record.worst_case {
            let better = |e: f64| match board.minimise {
                true => e.min(worst_case),
                false => e.max(worst_case),
            };
            board.estimate = Some(board.estimate.map_or(worst_case, better));
        }
        let Some(structure) = board.optimising(self.index) else {
            return;
        };
        if !record.returned {
            structure.iterations = structure.iterations.max(record.iteration + 1);
            return;
        }
        structure.returned = true;
        let race = match &structure.phase {
            Some(Phase::Finishing { race }) => format!(" (its race: {race})"),
            _ => String::new(),
        };
        let text = format!(
            "{}, {}: returns its defender from {} after {}{race}: worst case {:.6}{}",
            nodes(self.defender_nodes),
            structure.name,
            source_words(record.source),
            crate::output::counted(record.iteration, "iteration"),
            record.value,
            record
                .certified_lower
                .map_or(String::new(), |l| format!(", certified {l:.6}")),
        );
        self.progress.event(&mut board, &text);
    }

    fn searched(&mut self, record: &SearchRecord) {
        let mut board = self.progress.board();
        let source = RecordSource::LocalSearch;
        board.certified(
            record.certified_lower,
            self.index,
            source,
            self.defender_nodes,
        );
        let text = format!(
            "{}, {}: local search before the race certified {:.6}",
            nodes(self.defender_nodes),
            board.name(self.index),
            record.certified_lower
        );
        self.progress.event(&mut board, &text);
    }

    fn phase(&mut self, phase: &Phase) {
        if let Some(structure) = self.progress.board().optimising(self.index) {
            structure.phase = Some(phase.clone());
        }
    }
}
