//! `posg_fsc.solve` of an expected-reward query (docs/method.md section 9):
//! the library's expected-reward optimiser
//! ([`posg_fsc::optimise::optimise_expected_reward`]), into a solve
//! directory when `out=` is given, with the same callback, Ctrl-C and
//! thread handling as a probability objective.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, PoisonError};

use posg_fsc::ltl::props::RewardQuery;
use posg_fsc::optimise::{
    Cancel, IterationRecord, Observer, RewardSolution, Settings, optimise_expected_reward,
};
use posg_fsc::pipeline::QueryValue;
use posg_fsc::pipeline::RewardObjective;
use posg_fsc::pipeline::progress::Progress;
use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::controller::Controller;
use crate::convert::serialised;
use crate::errors::convert;
use crate::evaluate::Query;
use crate::game::Game;
use crate::objective::{self, Asked};
use crate::solve::{PythonObserver, Run, into_directory, record_dict, with_signals};

/// What `solve` was asked for an expected-reward query.
pub struct Request<'a> {
    /// The objective as given (`props=`).
    pub asked: &'a Asked,
    /// Its reward query.
    pub reward: &'a RewardQuery,
    /// The defender's nodes and the adversary's (in the gradient play of a
    /// game with an adversary).
    pub nodes: (usize, usize),
    /// The optimiser's settings.
    pub settings: &'a Settings,
    /// `allow_unused_propositions=`.
    pub allow_unused: bool,
}

/// The result of `posg_fsc.solve` for an expected-reward query, with the
/// names of its `summary.json` (docs/formats.md section 9).
#[pyclass(module = "posg_fsc", name = "RewardSolveResult", frozen, get_all)]
pub struct RewardSolveResult {
    /// The best defender found.
    pub defender: Py<Controller>,
    /// Its expected reward, evaluated exactly (`inf` where it is infinite).
    pub value: f64,
    /// A bound on `|value - exact value|` (docs/method.md section 8).
    pub error_bound: f64,
    /// The query restated in its own terms.
    pub query: Option<Query>,
    /// The start whose defender was returned.
    pub best_start: usize,
    /// Each start's `start`, `value`, `iterations`, `status` and `seconds`.
    pub starts: Py<PyList>,
    /// The starts dropped for numerical trouble, with why.
    pub dropped_starts: Vec<String>,
    /// The returned defender's certificate (a dict as in `summary.json`:
    /// `guaranteed`, the value it holds against every adversary, and
    /// `best_possible`, what no defender beats against the adversaries found,
    /// or seeing the state of a game without adversary; docs/method.md
    /// section 9); `None` only where a game without adversary's product
    /// could not be solved to the tolerance.
    pub certificate: Option<Py<PyAny>>,
    /// Every iteration's record of every start, then the returned one (a
    /// dict each, as the rows of `curve.csv`).
    pub curve: Py<PyList>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

#[pymethods]
impl RewardSolveResult {
    fn __repr__(&self) -> String {
        format!(
            "RewardSolveResult(value={}, error_bound={:e}, seconds={:.2})",
            self.value, self.error_bound, self.seconds
        )
    }
}

/// Every record, kept for the result's `curve`.
#[derive(Clone, Default)]
struct Recorded(Arc<Mutex<Vec<IterationRecord>>>);

impl Observer for Recorded {
    fn observe(&mut self, record: &IterationRecord) {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(*record);
    }
}

/// `solve` of `request` on `game`: `on_iteration` sees each record, `out`
/// (with `force`) receives the solve directory.
pub fn solve(
    py: Python<'_>,
    game: &Bound<'_, Game>,
    request: Request<'_>,
    (on_iteration, progress): (Option<Py<PyAny>>, Option<Arc<Progress>>),
    out: Option<(&PathBuf, bool)>,
) -> PyResult<Py<PyAny>> {
    let posg = &game.get().inner;
    let property = request
        .asked
        .property()
        .expect("a reward query came from props=");
    let objective = objective::reward(
        py,
        posg,
        request.reward,
        property.maximise,
        request.allow_unused,
    )?;
    let run = Run::new(on_iteration, progress);
    let recorded = Recorded::default();
    let mut observers: Vec<Box<dyn Observer + Send>> = vec![
        Box::new(recorded.clone()),
        Box::new(PythonObserver {
            run: Arc::clone(&run),
            structure: "full".into(),
        }),
    ];
    if let Some(progress) = &run.progress {
        let minimise = objective.minimise;
        observers.push(Box::new(progress.observer(
            "full",
            request.nodes.0,
            minimise,
        )));
    }
    let (nodes, settings) = (request.nodes, request.settings);
    let solution = with_signals(py, &run, || {
        optimise(
            posg, &objective, nodes, settings, &run.stop, observers, out, property,
        )
    })?;
    let records = recorded.0.lock().unwrap_or_else(PoisonError::into_inner);
    let curve = PyList::empty(py);
    for record in records.iter() {
        curve.append(record_dict(py, record)?)?;
    }
    let starts = PyList::empty(py);
    for start in &solution.starts {
        starts.append(serialised(py, start)?)?;
    }
    let query = QueryValue::rewarded(property, solution.value, solution.error_bound);
    let result = RewardSolveResult {
        defender: Py::new(py, Controller::new(solution.defender, &game.get().inner))?,
        value: solution.value,
        error_bound: solution.error_bound,
        query: Some(query.into()),
        best_start: solution.best_start,
        starts: starts.unbind(),
        dropped_starts: solution.dropped_starts,
        certificate: solution
            .certificate
            .map(|certificate| serialised(py, &certificate).map(Bound::unbind))
            .transpose()?,
        curve: curve.unbind(),
        seconds: solution.seconds,
    };
    Ok(Py::new(py, result)?.into_any())
}

/// The optimiser, into the solve directory `out` when given.
#[allow(clippy::too_many_arguments)]
fn optimise(
    game: &posg_fsc::game::Posg,
    objective: &RewardObjective,
    nodes: (usize, usize),
    settings: &Settings,
    cancel: &Cancel,
    mut observers: Vec<Box<dyn Observer + Send>>,
    out: Option<(&PathBuf, bool)>,
    property: &posg_fsc::ltl::props::Property,
) -> PyResult<RewardSolution> {
    let Some(out) = out else {
        let expected = objective.optimised();
        return optimise_expected_reward(game, expected, nodes, settings, cancel, &mut observers)
            .map_err(convert);
    };
    into_directory(out, Some(property), |directory| {
        directory.solve_expected_reward(
            game,
            objective,
            nodes,
            settings,
            cancel,
            Box::new(observers),
        )
    })
}
