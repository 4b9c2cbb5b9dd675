//! `posg_fsc.solve` and `posg_fsc.sweep`: the library's main job
//! ([`posg_fsc::pipeline`]) with its settings from keyword arguments, the
//! iteration records streamed to a Python callback, and Ctrl-C.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use posg_fsc::controller::Role;
use posg_fsc::game::Posg;
use posg_fsc::ltl::props::Property;
use posg_fsc::optimise::{Cancel, IterationRecord, Observer, Settings};
use posg_fsc::output::OutputDirectory;
use posg_fsc::pipeline::directory::SolveDirectory;
use posg_fsc::pipeline::progress::Progress;
use posg_fsc::pipeline::{self, Automata, Chain, Job, Outcome, Sizes, Watch};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::{Map, Value};

use crate::controller::Controller;
use crate::convert::{serialised, settings_from_json, size, sizes, to_json};
use crate::errors::{Kind, convert, panicked, raise};
use crate::evaluate::Query;
use crate::game::Game;
use crate::objective::{self, Asked};

/// Keyword arguments as the JSON of [`Settings`]: each keyword's field
/// ([`crate::help::settings`]: `tolerance` is `solver_tolerance`, the
/// synthesis' fields sit in `synthesis`, its `time_budget` is
/// `synthesis_time_budget`); `structures` may be one comma-separated
/// string. A keyword that is no setting is a TypeError suggesting the
/// closest one.
fn settings_json(function: &str, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Value> {
    let settings = crate::help::settings();
    let mut top = Map::new();
    let mut synthesis = Map::new();
    for (key, value) in kwargs.into_iter().flat_map(|kwargs| kwargs.iter()) {
        let key: String = key.extract()?;
        let Some(setting) = settings.iter().find(|s| s.keyword == key) else {
            return Err(crate::convert::unknown_keyword(function, &key, &settings));
        };
        let mut json = to_json(&key, &value)?;
        if let ("structures", Value::String(list)) = (key.as_str(), &json) {
            json = Value::Array(
                list.split(',')
                    .map(|s| Value::String(s.trim().into()))
                    .collect(),
            );
        }
        let owner = if setting.synthesis {
            &mut synthesis
        } else {
            &mut top
        };
        owner.insert(setting.field.clone(), json);
    }
    if !synthesis.is_empty() {
        top.insert("synthesis".into(), Value::Object(synthesis));
    }
    Ok(Value::Object(top))
}

/// The optimiser's [`Settings`] from keyword arguments: the library's
/// defaults, each keyword (the command line's option name with `_` for
/// `-`) replacing one; validated.
pub fn settings(function: &str, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Settings> {
    let settings: Settings = settings_from_json(function, settings_json(function, kwargs)?)?;
    settings.validate().map_err(convert)?;
    Ok(settings)
}

/// What the observers of one run share: the Python callback, and the first
/// exception (the callback's own, or KeyboardInterrupt) to raise after the
/// run stopped.
pub(crate) struct Run {
    pub(crate) callback: Option<Py<PyAny>>,
    pub(crate) error: Mutex<Option<PyErr>>,
    pub(crate) stop: Cancel,
    /// The board whose lines go to `sys.stderr` while the run runs
    /// (`progress=`).
    pub(crate) progress: Option<Arc<Progress>>,
    /// Set when `sys.stderr` could not be written: progress stops, the run
    /// goes on.
    silenced: AtomicBool,
}

impl Run {
    /// A run calling `callback` with each record, its progress on a board
    /// with a status line every `progress` when given.
    pub(crate) fn new(callback: Option<Py<PyAny>>, progress: Option<Arc<Progress>>) -> Arc<Self> {
        Arc::new(Run {
            callback,
            error: Mutex::new(None),
            stop: Cancel::new(),
            progress,
            silenced: AtomicBool::new(false),
        })
    }

    /// Writes the board's due lines (or, `last`, its last events) to
    /// `sys.stderr`; a stderr that cannot be written (`None` under
    /// pythonw) silences the progress, never the run.
    fn report(&self, py: Python<'_>, last: bool) {
        if self.silenced.load(Ordering::Relaxed) {
            return;
        }
        if self.write_progress(py, last).is_err() {
            self.silenced.store(true, Ordering::Relaxed);
        }
    }

    fn write_progress(&self, py: Python<'_>, last: bool) -> PyResult<()> {
        let Some(progress) = &self.progress else {
            return Ok(());
        };
        let lines = if last {
            progress.events()
        } else {
            progress.due_lines()
        };
        if lines.is_empty() {
            return Ok(());
        }
        let stderr = py.import("sys")?.getattr("stderr")?;
        for line in lines {
            stderr.call_method1("write", (format!("{line}\n"),))?;
        }
        stderr.call_method0("flush")?;
        Ok(())
    }

    fn stopped_by(&self) -> Option<PyErr> {
        self.error
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
    }

    /// Stops the run and keeps `error` to raise (the first one only).
    fn fail(&self, error: PyErr) {
        self.stop.cancel();
        let mut slot = self.error.lock().unwrap_or_else(PoisonError::into_inner);
        if slot.is_none() {
            *slot = Some(error);
        }
    }

    /// One record, on a worker thread: calls the callback with the record
    /// as a dict (plus `structure`); `False` stops the run, an exception
    /// stops it and is raised after it.
    fn observe(&self, structure: &str, record: &IterationRecord) {
        let Some(callback) = &self.callback else {
            return;
        };
        if self.stop.is_cancelled() {
            return;
        }
        Python::attach(|py| {
            let answer = record_dict(py, record).and_then(|dict| {
                dict.set_item("structure", structure)?;
                let answer = callback.call1(py, (dict,))?;
                let answer = answer.bind(py);
                Ok(answer
                    .cast::<pyo3::types::PyBool>()
                    .is_ok_and(|flag| !flag.is_true()))
            });
            match answer {
                Ok(true) => self.stop.cancel(),
                Ok(false) => {}
                Err(error) => self.fail(error),
            }
        });
    }
}

/// An iteration's record as a dict, with the names of `curve.csv`; an
/// infinite expected reward (method.md section 9) is Python's `inf` there,
/// where JSON would have nothing to say it.
pub(crate) fn record_dict<'py>(
    py: Python<'py>,
    record: &IterationRecord,
) -> PyResult<Bound<'py, PyAny>> {
    let dict = serialised(py, record)?;
    for (key, value) in [
        ("value", Some(record.value)),
        ("worst_case", record.worst_case),
    ] {
        if let Some(value) = value.filter(|v| v.is_infinite()) {
            dict.set_item(key, value)?;
        }
    }
    Ok(dict)
}

/// One structure's observer.
pub(crate) struct PythonObserver {
    pub(crate) run: Arc<Run>,
    pub(crate) structure: String,
}

impl Observer for PythonObserver {
    fn observe(&mut self, record: &IterationRecord) {
        self.run.observe(&self.structure, record);
    }
}

/// How often the waiting thread looks for Ctrl-C while a job runs.
pub(crate) const SIGNAL_POLL: Duration = Duration::from_millis(10);

/// Runs `job` on a thread of its own while this (Python's) thread waits
/// without the GIL, checking for Ctrl-C every [`SIGNAL_POLL`] (signals are
/// only seen on the main thread); writes the solve directory `out` as
/// `posg-fsc solve` does when given. Ctrl-C, the callback returning
/// `False` or raising stop the optimiser, which returns what it has; the
/// KeyboardInterrupt or the callback's exception is then raised. A panic
/// in the library becomes `posg_fsc.Error`.
fn run_job(
    py: Python<'_>,
    mut job: Job,
    (callback, progress): (Option<Py<PyAny>>, Option<Arc<Progress>>),
    out: Option<(&PathBuf, bool)>,
    query: Option<&Property>,
) -> PyResult<Outcome> {
    let run = Run::new(callback, progress);
    job.cancel = run.stop.clone();
    let observers = pipeline::observing(|slot| {
        Box::new(PythonObserver {
            run: Arc::clone(&run),
            structure: slot.structure.name.clone(),
        })
    });
    with_signals(py, &run, || match &run.progress {
        Some(progress) => work(job, progress.watching(observers), out, query),
        None => work(job, observers, out, query),
    })
}

/// Runs `work` on a thread of its own while this (Python's) thread waits
/// without the GIL, checking for Ctrl-C every [`SIGNAL_POLL`] (which
/// stops `run`); the error that stopped `run`, if any, is raised after it.
pub(crate) fn with_signals<T: Send>(
    py: Python<'_>,
    run: &Run,
    work: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    let outcome = std::thread::scope(|scope| {
        let worker = scope.spawn(work);
        while !worker.is_finished() {
            py.detach(|| std::thread::sleep(SIGNAL_POLL));
            if let Err(interrupt) = py.check_signals() {
                run.fail(interrupt);
            }
            run.report(py, false);
        }
        worker.join()
    });
    run.report(py, true);
    if let Some(error) = run.stopped_by() {
        return Err(error);
    }
    outcome.unwrap_or_else(|panic| Err(panicked(panic.as_ref())))
}

/// The pipeline, into the solve directory `out` when given.
fn work(
    job: Job,
    watch: impl Watch,
    out: Option<(&PathBuf, bool)>,
    query: Option<&Property>,
) -> PyResult<Outcome> {
    let Some(out) = out else {
        return pipeline::run(job, watch).map_err(convert);
    };
    into_directory(out, query, |directory| directory.solve(job, watch))
}

/// Runs `write` into the solve directory at `path` (a non-empty one
/// replaced with `force`), as `posg_fsc.solve` writes it: no picture, the
/// query of `query` restated; the directory appears once `write` is done.
pub(crate) fn into_directory<T>(
    (path, force): (&PathBuf, bool),
    query: Option<&Property>,
    write: impl FnOnce(&SolveDirectory) -> Result<T, pipeline::PipelineError>,
) -> PyResult<T> {
    let directory = OutputDirectory::create(path, force).map_err(convert)?;
    let command_line = vec!["python".to_string(), "posg_fsc.solve".to_string()];
    let solve = SolveDirectory {
        path: directory.path(),
        seconds_axis: false,
        command_line: &command_line,
        plot_format: None,
        plot_size: Default::default(),
        query,
    };
    let result = write(&solve).map_err(convert)?;
    directory.commit().map_err(convert)?;
    Ok(result)
}

/// The result of `posg_fsc.solve`, with the names of `summary.json`
/// (docs/formats.md section 9).
#[pyclass(module = "posg_fsc", name = "SolveResult", frozen, get_all)]
pub struct SolveResult {
    /// The best defender found.
    pub defender: Py<Controller>,
    /// The best response found to it.
    pub adversary: Py<Controller>,
    /// `{"certified_lower": ..., "upper_bound": ...}`: the defender's value
    /// against every adversary is at least `certified_lower`; no defender
    /// of any size does better than `upper_bound` (docs/method.md section
    /// 6). `None` when the defender could not be certified (see
    /// `certification_error`).
    pub certified: Option<Py<PyDict>>,
    /// Why `certified` is `None`.
    pub certification_error: Option<String>,
    /// The structure whose defender was kept.
    pub structure_used: String,
    /// The best defender's worst-case estimate (best-response value).
    pub worst_case: f64,
    /// The largest error bound of the values computed on the best structure.
    pub error_bound: f64,
    /// The value at the best structure's last iterate.
    pub last_value: f64,
    /// Why the best structure won, then why each other one lost.
    pub structure_choice: Vec<String>,
    /// With `props=`, the query restated in its own terms (for `Pmin`,
    /// the certified bracket's upper end is the defender's guarantee).
    pub query: Option<Query>,
    /// The best structure's convergence curve: one dict per iteration
    /// (`pandas.DataFrame(result.curve)` makes a table).
    pub curve: Py<PyList>,
    /// Every structure's curve, by structure name.
    pub curves: Py<PyDict>,
    /// Every structure's report (as `structures` in `summary.json`).
    pub structures: Py<PyList>,
    /// What each source of structures found (as `sources` in `summary.json`).
    pub sources: Py<PyList>,
    /// The settings used, every field (as `settings` in `summary.json`).
    pub settings: Py<PyDict>,
    /// Wall-clock seconds of the whole job.
    pub seconds: f64,
    /// Seconds of support synthesis (the `sat` source).
    pub synthesis_seconds: f64,
}

#[pymethods]
impl SolveResult {
    fn __repr__(&self) -> String {
        format!(
            "SolveResult(structure_used={:?}, worst_case={:.6}, seconds={:.2})",
            self.structure_used, self.worst_case, self.seconds
        )
    }
}

fn result(
    py: Python<'_>,
    game: &Arc<Posg>,
    settings: &Settings,
    outcome: &Outcome,
    query: Option<&Property>,
) -> PyResult<SolveResult> {
    let best = outcome.best();
    let query = query.map(|property| outcome.query(property));
    let records = |records: &[IterationRecord]| -> PyResult<Bound<'_, PyList>> {
        let list = PyList::empty(py);
        for record in records {
            list.append(record_dict(py, record)?)?;
        }
        Ok(list)
    };
    let curves = PyDict::new(py);
    let mut curve = PyList::empty(py);
    for structure_curve in &outcome.curves {
        let list = records(&structure_curve.records)?;
        if structure_curve.structure == best.report.name {
            curve = list.clone();
        }
        curves.set_item(&structure_curve.structure, list)?;
    }
    let reports: Vec<_> = outcome
        .solution
        .structures
        .iter()
        .map(|s| &s.report)
        .collect();
    Ok(SolveResult {
        query: query.map(Query::from),
        defender: Py::new(py, Controller::new(best.defender.clone(), game))?,
        adversary: Py::new(py, Controller::new(best.adversary.clone(), game))?,
        certified: outcome
            .certified
            .map(|bracket| {
                serialised(py, &bracket)?
                    .cast_into::<PyDict>()
                    .map(Bound::unbind)
                    .map_err(PyErr::from)
            })
            .transpose()?,
        certification_error: outcome.certification_error.clone(),
        structure_used: best.report.name.clone(),
        worst_case: best.report.worst_case,
        error_bound: best.report.error_bound,
        last_value: best.report.last_value,
        structure_choice: outcome.structure_choice.clone(),
        curve: curve.unbind(),
        curves: curves.unbind(),
        structures: serialised(py, &reports)?.cast_into::<PyList>()?.unbind(),
        sources: serialised(py, &outcome.sources)?
            .cast_into::<PyList>()?
            .unbind(),
        settings: serialised(py, settings)?.cast_into::<PyDict>()?.unbind(),
        seconds: outcome.seconds,
        synthesis_seconds: outcome.synthesis_seconds,
    })
}

/// The keywords that give the controllers' sizes, as
/// [`Sizes::check`]'s errors name them.
const SIZE_KEYWORDS: [&str; 2] = ["def_nodes", "adv_nodes"];

/// Checks controller sizes as `posg-fsc solve` does ([`Sizes::check`]).
fn check_sizes(game: &Posg, sizes: Sizes) -> PyResult<()> {
    (sizes.check(game, SIZE_KEYWORDS)).map_err(|e| raise(Kind::Settings, e.to_string()))
}

/// Tunes a defender controller against a worst-case adversary, as
/// `posg-fsc solve` does: on every structure of `structures` (default
/// `full`, `informed`, `sat`, `paper`), alternating projected gradient ascent-descent
/// with best-response checks, the best structure kept and certified.
///
/// `settings` are the command line's options with `_` for `-`
/// (`max_iterations=200`, `starts=1`, `tolerance=1e-9`, ...), with the same
/// defaults; an unknown keyword is a TypeError. `defender`/`adversary`
/// (a Controller, a path or `"uniform:K"`) start the run from those
/// controllers instead of the full uniform structure. `on_iteration(record)`
/// is called with each iteration's record (a dict, with `structure`) from
/// the optimiser's threads; returning `False` stops the run, which returns
/// what it has. `progress=True` writes the command line's progress lines to
/// `sys.stderr` while the run runs: one for each event (a local search
/// ended, a structure returned its defender, a size was certified) and,
/// when nothing happened for 5 seconds (or the seconds given instead of
/// `True`), what each part of the run is doing with the best certified
/// bracket so far. Ctrl-C stops the run too (then KeyboardInterrupt is
/// raised).
/// With `out`, the solve directory (`curve.csv`, `summary.json`, ...) is
/// written there too, without its picture (`force=True` replaces a
/// non-empty one). A proposition that labels no state of the game is a
/// warning, and an error when it makes the formula unsatisfiable, unless
/// `allow_unused_propositions=True`.
#[pyfunction]
#[pyo3(signature = (game, ltl = None, def_nodes = None, adv_nodes = None, *, props = None, defender = None, adversary = None, on_iteration = None, progress = None, out = None, force = false, allow_unused_propositions = false, **settings))]
#[allow(clippy::too_many_arguments)]
pub fn solve(
    py: Python<'_>,
    game: &Bound<'_, Game>,
    ltl: Option<&str>,
    def_nodes: Option<&Bound<'_, PyAny>>,
    adv_nodes: Option<&Bound<'_, PyAny>>,
    props: Option<&Bound<'_, PyAny>>,
    defender: Option<&Bound<'_, PyAny>>,
    adversary: Option<&Bound<'_, PyAny>>,
    on_iteration: Option<Py<PyAny>>,
    progress: Option<&Bound<'_, PyAny>>,
    out: Option<PathBuf>,
    force: bool,
    allow_unused_propositions: bool,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    let asked = Asked::from_keywords(ltl, props)?;
    let settings = self::settings("solve", settings)?;
    let watching = (
        on_iteration,
        progress_interval(progress)?.map(Progress::new),
    );
    if let Some(reward) = asked.reward() {
        if defender.is_some() || adversary.is_some() {
            return Err(raise(
                Kind::Settings,
                "an expected-reward query is optimised from the full supports of def_nodes and \
                 adv_nodes nodes: drop defender= and adversary=",
            ));
        }
        let sizes = Sizes {
            defender: def_nodes.map_or(Ok(1), |n| size("def_nodes", n))?,
            adversary: adv_nodes.map_or(Ok(1), |n| size("adv_nodes", n))?,
        };
        check_sizes(&game.get().inner, sizes)?;
        let request = crate::reward::Request {
            asked: &asked,
            reward,
            nodes: (sizes.defender, sizes.adversary),
            settings: &settings,
            allow_unused: allow_unused_propositions,
        };
        let output = out.as_ref().map(|p| (p, force));
        return crate::reward::solve(py, game, request, watching, output);
    }
    let ltl = &asked.formula("solve")?;
    let posg = &game.get().inner;
    let start_defender = defender
        .map(|d| Controller::resolve("defender", Some(d), posg, Role::Defender))
        .transpose()?;
    let start_adversary = adversary
        .map(|a| Controller::resolve("adversary", Some(a), posg, Role::Adversary))
        .transpose()?;
    let nodes = |name,
                 value: Option<&Bound<'_, PyAny>>,
                 start: &Option<posg_fsc::controller::Fsc>|
     -> PyResult<usize> {
        match (value, start) {
            (Some(value), _) => size(name, value),
            (None, Some(fsc)) => Ok(fsc.num_nodes()),
            (None, None) => Ok(1),
        }
    };
    let sizes = Sizes {
        defender: nodes("def_nodes", def_nodes, &start_defender)?,
        adversary: nodes("adv_nodes", adv_nodes, &start_adversary)?,
    };
    check_sizes(posg, sizes)?;
    let automata = objective::automata(py, posg, ltl, allow_unused_propositions, true)?;
    let mut job = Job::full(posg, &automata, sizes, &settings).map_err(convert)?;
    for (start, fsc, name) in [
        (&mut job.start.defender, start_defender, "def_nodes"),
        (&mut job.start.adversary, start_adversary, "adv_nodes"),
    ] {
        if let Some(fsc) = fsc {
            if fsc.num_nodes() != start.num_nodes() {
                return Err(raise(
                    Kind::Settings,
                    format!(
                        "{name} {} disagrees with the starting controller's {} nodes",
                        start.num_nodes(),
                        fsc.num_nodes()
                    ),
                ));
            }
            *start = fsc;
        }
    }
    if defender.is_some() || adversary.is_some() {
        job.start.name = "from-files".into();
    }
    let out = out.as_ref().map(|p| (p, force));
    let outcome = run_job(py, job, watching, out, asked.property())?;
    let result = result(py, posg, &settings, &outcome, asked.property())?;
    Ok(Py::new(py, result)?.into_any())
}

/// `posg-fsc sweep`: [`solve`] for every pair of sizes, the defender sizes
/// in increasing order, each warm-started from the best defender of the
/// next smaller size and kept at least as good (so results are monotone in
/// the defender's size). `def_nodes` and `adv_nodes` are a size or a list
/// (or range) of sizes. Returns one row per size pair: a dict with the
/// columns of `sweep.csv` (`result` is the row in words) and the pair's `SolveResult` under `solved`.
/// The chains of the adversary sizes run one after the other here.
/// `on_iteration` and `progress` are [`solve`]'s, for each pair.
#[pyfunction]
#[pyo3(signature = (game, ltl = None, def_nodes = None, adv_nodes = None, *, props = None, on_iteration = None, progress = None, allow_unused_propositions = false, **settings))]
#[allow(clippy::too_many_arguments)]
pub fn sweep(
    py: Python<'_>,
    game: &Bound<'_, Game>,
    ltl: Option<&str>,
    def_nodes: Option<&Bound<'_, PyAny>>,
    adv_nodes: Option<&Bound<'_, PyAny>>,
    props: Option<&Bound<'_, PyAny>>,
    on_iteration: Option<Py<PyAny>>,
    progress: Option<&Bound<'_, PyAny>>,
    allow_unused_propositions: bool,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyList>> {
    let progress = progress_interval(progress)?;
    let started = Instant::now();
    let asked = Asked::from_keywords(ltl, props)?;
    let ltl = &asked.formula("sweep")?;
    let settings = self::settings("sweep", settings)?;
    let posg = &game.get().inner;
    let mut defender_sizes = match def_nodes {
        Some(value) => sizes("def_nodes", value)?,
        None => vec![1, 2, 3],
    };
    defender_sizes.sort_unstable();
    defender_sizes.dedup();
    let mut adversary_sizes = match adv_nodes {
        Some(value) => sizes("adv_nodes", value)?,
        None => vec![1, 2],
    };
    adversary_sizes.dedup();
    for &n in &defender_sizes {
        for &m in &adversary_sizes {
            let sizes = Sizes {
                defender: n,
                adversary: m,
            };
            check_sizes(posg, sizes)?;
        }
    }
    let automata: Automata = objective::automata(py, posg, ltl, allow_unused_propositions, true)?;
    let rows = PyList::empty(py);
    let callback = on_iteration;
    for &m in &adversary_sizes {
        let mut chain = Chain::new(posg, &automata, &settings, m);
        for &n in &defender_sizes {
            let job = chain.job(n).map_err(convert)?;
            let callback = callback.as_ref().map(|c| c.clone_ref(py));
            let board = progress.map(|interval| {
                let pair = format!("defender {n}, adversary {m}");
                Progress::labelled(interval, Some(pair), started)
            });
            let outcome = run_job(py, job, (callback, board), None, asked.property())?;
            let row = serialised(py, &chain.row(n, &outcome))?.cast_into::<PyDict>()?;
            row.set_item(
                "solved",
                result(py, posg, &settings, &outcome, asked.property())?,
            )?;
            rows.append(row)?;
        }
    }
    Ok(rows.unbind())
}

/// The status-line interval `progress=` asks for: none for `None` or
/// `False`, [`DEFAULT_PROGRESS_EVERY`] for `True`, else the seconds given.
fn progress_interval(progress: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Duration>> {
    let Some(progress) = progress else {
        return Ok(None);
    };
    if let Ok(flag) = progress.cast::<pyo3::types::PyBool>() {
        return Ok(flag.is_true().then_some(DEFAULT_PROGRESS_EVERY));
    }
    let seconds: f64 = progress.extract().map_err(|_| {
        raise(
            Kind::Settings,
            "progress must be True, False or the seconds between two status lines",
        )
    })?;
    if seconds.is_nan() || seconds <= 0.0 {
        return Err(raise(
            Kind::Settings,
            format!("progress={seconds}: the seconds between two status lines must be positive"),
        ));
    }
    // Beyond the clock: events only, no status line (as the command line).
    Ok(Some(
        posg_fsc::seconds::duration(seconds).unwrap_or(Duration::MAX),
    ))
}

/// The seconds between two status lines with `progress=True`, as the
/// command line's `--progress-every`.
const DEFAULT_PROGRESS_EVERY: Duration =
    Duration::from_secs(posg_fsc::pipeline::progress::DEFAULT_INTERVAL_SECONDS as u64);
