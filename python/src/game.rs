//! `posg_fsc.Game` and `posg_fsc.example_grid`: the library's
//! [`Posg`] (docs/formats.md sections 1, 6 and 11) and the paper's grid
//! family ([`GridSpec`]).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use posg_fsc::game::grid::{GridSpec, ObservationModel, RandomUnsafe};
use posg_fsc::game::{Player, Posg};
use pyo3::exceptions::{PyImportError, PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::convert::{count_of, size};
use crate::errors::{Kind, compute, convert, raise};

/// A partially observable stochastic game (POSG): states labelled with
/// atomic propositions, a defender and an adversary with their actions and
/// observations, and the transition probabilities.
///
/// Read one with `Game.load(path)` (JSON or binary), `Game.from_json(text)`
/// or `Game.from_drn(path)`, or build the paper's grid with
/// `posg_fsc.example_grid(...)`. A game is immutable.
#[pyclass(module = "posg_fsc", name = "Game", frozen)]
pub struct Game {
    pub(crate) inner: Arc<Posg>,
}

impl Game {
    pub(crate) fn new(game: Posg) -> Self {
        Self {
            inner: Arc::new(game),
        }
    }
}

/// Numbers the directories `Game.from_stormpy` exports into, apart within
/// a process.
static EXPORTS: AtomicUsize = AtomicUsize::new(0);

/// A new directory of the temporary directory that only this user may
/// enter (created, never reused: one that exists, a symbolic link planted
/// by another user say, is an error), for `Game.from_stormpy`'s export.
fn private_directory() -> PyResult<PathBuf> {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let path = std::env::temp_dir().join(format!(
        "posg-fsc-stormpy-{}-{}-{nanos}",
        std::process::id(),
        EXPORTS.fetch_add(1, Ordering::Relaxed)
    ));
    let mut builder = std::fs::DirBuilder::new();
    #[cfg(unix)]
    std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
    builder.create(&path)?;
    Ok(path)
}

impl Game {
    /// The game of a DRN import, its warnings (renamed labels) raised as
    /// Python warnings.
    fn imported(py: Python<'_>, import: posg_fsc::game::drn::DrnImport) -> PyResult<Self> {
        for warning in &import.warnings {
            PyErr::warn(
                py,
                &py.get_type::<PyUserWarning>(),
                &std::ffi::CString::new(warning.as_str())?,
                1,
            )?;
        }
        Ok(Self::new(import.game))
    }
}

#[pymethods]
impl Game {
    /// Reads and validates a game file: JSON (docs/formats.md section 1) or
    /// the binary form `*.posg.bin` (section 11). Raises `GameFormatError`
    /// naming the file and the JSON path of the first problem.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        compute(py, || posg_fsc::game::file::read(&path)).map(Self::new)
    }

    /// Parses a game from JSON text (docs/formats.md section 1); `name`
    /// stands for the file in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, name = "<string>"))]
    fn from_json(py: Python<'_>, text: &str, name: &str) -> PyResult<Self> {
        compute(py, || posg_fsc::game::file::from_json_str(text, name)).map(Self::new)
    }

    /// Imports a model from Storm's DRN format, as `posg-fsc import-drn`
    /// does (docs/formats.md section 6): a POMDP, MDP or DTMC as a game
    /// without adversary, an SMG or POSMG (PAYNT's games) as a turn-based
    /// game with one, with its rewards; action labels renamed because they
    /// are not names (SAYNT's `(init)` is `_init_`) are reported as a Python
    /// warning.
    #[staticmethod]
    fn from_drn(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let import = compute(py, || posg_fsc::game::drn::read(&path))?;
        Self::imported(py, import)
    }

    /// A game from a model built by stormpy, the Python face of Storm: a
    /// sparse POMDP, MDP, DTMC, SMG or POSMG (what `stormpy.build_model`,
    /// `build_sparse_model_with_options` or PAYNT return), with its choice
    /// labels, observations and reward models. The model goes through
    /// Storm's own DRN export (`stormpy.io.export_to_drn`) and is read as
    /// `Game.from_drn` reads it; errors name it `stormpy model`. Needs
    /// stormpy.
    #[staticmethod]
    fn from_stormpy(py: Python<'_>, model: &Bound<'_, PyAny>) -> PyResult<Self> {
        let stormpy = py.import("stormpy").map_err(|_| {
            PyImportError::new_err("Game.from_stormpy needs stormpy: pip install stormpy")
        })?;
        let export = (stormpy
            .getattr("io")
            .and_then(|io| io.getattr("export_to_drn")))
        .or_else(|_| stormpy.getattr("export_to_drn"))?;
        let directory = private_directory()?;
        let path = directory.join("model.drn");
        let exported = export.call1((model, path.display().to_string()));
        let text = exported.and_then(|_| Ok(std::fs::read_to_string(&path)?));
        let _ = std::fs::remove_dir_all(&directory);
        let text = text.map_err(|error| {
            raise(
                Kind::Game,
                format!("stormpy could not export this model to DRN: {error}"),
            )
        })?;
        let import = compute(py, || {
            posg_fsc::game::drn::from_drn_str(&text, "stormpy model", None)
        })?;
        Self::imported(py, import)
    }

    /// A game from numpy arrays (or anything numpy reads):
    /// `transitions[s, a, s']` (a POMDP or MDP) or `transitions[s, a, b,
    /// s']` (a game: defender action `a`, adversary action `b`), each row
    /// summing to 1, or all zero to leave the action out of the state;
    /// `initial` a state index (default 0) or a distribution;
    /// `observations` per state an observation index, or a `(states,
    /// observations)` array of probabilities (default: the player sees the
    /// state; `adversary_observations` the same for the adversary); the
    /// states sharing an observation must offer the same actions. `labels`
    /// maps a proposition to the states where it holds (indices, or a
    /// boolean array); `rewards` maps a reward model's name to state
    /// rewards `(states,)` or action rewards (the shape of `transitions`
    /// without its last axis). `states`, `actions`, `observation_names`,
    /// `adversary_actions` and `adversary_observation_names` name them
    /// (default `s0`, `a0`, `o0`, `b0`, ...). A problem is a SettingsError
    /// naming the array and the index (`transitions[3, 1] (state s3, action
    /// a1) sums to 0.9`).
    #[staticmethod]
    #[pyo3(signature = (transitions, initial = None, *, observations = None, labels = None, rewards = None, states = None, actions = None, observation_names = None, adversary_observations = None, adversary_actions = None, adversary_observation_names = None, name = None))]
    #[allow(clippy::too_many_arguments)]
    fn from_arrays<'py>(
        transitions: Bound<'py, PyAny>,
        initial: Option<Bound<'py, PyAny>>,
        observations: Option<Bound<'py, PyAny>>,
        labels: Option<Bound<'py, PyDict>>,
        rewards: Option<Bound<'py, PyDict>>,
        states: Option<Vec<String>>,
        actions: Option<Vec<String>>,
        observation_names: Option<Vec<String>>,
        adversary_observations: Option<Bound<'py, PyAny>>,
        adversary_actions: Option<Vec<String>>,
        adversary_observation_names: Option<Vec<String>>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let py = transitions.py();
        let initial = match initial {
            Some(initial) => initial,
            None => 0usize.into_pyobject(py)?.into_any(),
        };
        let arrays = crate::arrays::GameArrays {
            transitions,
            initial,
            states,
            labels,
            rewards,
            defender: crate::arrays::PlayerArrays {
                actions,
                observations,
                observation_names,
            },
            adversary: crate::arrays::PlayerArrays {
                actions: adversary_actions,
                observations: adversary_observations,
                observation_names: adversary_observation_names,
            },
            name,
        };
        crate::arrays::game(arrays).map(Self::new)
    }

    /// The game as JSON text (docs/formats.md section 1), which
    /// `Game.from_json` reads back to an equal game.
    fn to_json(&self) -> String {
        posg_fsc::game::file::to_json_string(&self.inner)
    }

    /// Writes the game to `path`: JSON, or the binary form when
    /// `binary=True` (docs/formats.md section 11).
    #[pyo3(signature = (path, binary = false))]
    fn save(&self, py: Python<'_>, path: PathBuf, binary: bool) -> PyResult<()> {
        compute(py, || {
            if binary {
                posg_fsc::game::binary::write(&path, &self.inner)
            } else {
                posg_fsc::game::file::write(&path, &self.inner)
            }
        })
    }

    /// The game's name, if it has one.
    #[getter]
    fn name(&self) -> Option<String> {
        self.inner.name().map(str::to_string)
    }

    /// The state names, in index order.
    #[getter]
    fn states(&self) -> Vec<String> {
        self.inner.states().to_vec()
    }

    /// The atomic propositions that label some state.
    #[getter]
    fn propositions(&self) -> Vec<String> {
        self.inner.propositions().to_vec()
    }

    /// The labels: for each state name, the propositions that hold in it.
    #[getter]
    fn labels(&self) -> Vec<(String, Vec<String>)> {
        (0..self.inner.num_states())
            .map(|s| {
                let names = self.inner.label_names(s).map(str::to_string).collect();
                (self.inner.states()[s].clone(), names)
            })
            .collect()
    }

    /// The initial distribution as `(state name, probability)` pairs.
    #[getter]
    fn initial(&self) -> Vec<(String, f64)> {
        self.inner
            .initial()
            .iter()
            .map(|&(s, p)| (self.inner.states()[s].clone(), p))
            .collect()
    }

    /// Whether the game has an adversary (`False` for a POMDP).
    #[getter]
    fn has_adversary(&self) -> bool {
        self.inner.has_adversary()
    }

    /// The defender's actions, in index order (the last axis of a
    /// defender controller's `probabilities`).
    #[getter]
    fn defender_actions(&self) -> Vec<String> {
        self.inner.defender().actions().to_vec()
    }

    /// The defender's observations, in index order (axis 1 of a defender
    /// controller's `probabilities`).
    #[getter]
    fn defender_observations(&self) -> Vec<String> {
        self.inner.defender().observations().to_vec()
    }

    /// The adversary's actions, in index order.
    #[getter]
    fn adversary_actions(&self) -> Vec<String> {
        self.inner.adversary().actions().to_vec()
    }

    /// The adversary's observations, in index order.
    #[getter]
    fn adversary_observations(&self) -> Vec<String> {
        self.inner.adversary().observations().to_vec()
    }

    /// The number of states.
    #[getter]
    fn num_states(&self) -> usize {
        self.inner.num_states()
    }

    /// The exact value of a controller pair (see `posg_fsc.evaluate`).
    #[pyo3(signature = (ltl = None, defender = None, adversary = None, gradient = false, solver = "auto", tolerance = None, lu_limit = None, allow_unused_propositions = false, props = None))]
    #[allow(clippy::too_many_arguments)]
    fn evaluate(
        slf: &Bound<'_, Self>,
        ltl: Option<&str>,
        defender: Option<&Bound<'_, PyAny>>,
        adversary: Option<&Bound<'_, PyAny>>,
        gradient: bool,
        solver: &str,
        tolerance: Option<f64>,
        lu_limit: Option<usize>,
        allow_unused_propositions: bool,
        props: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<crate::evaluate::Evaluation> {
        crate::evaluate::evaluate(
            slf,
            crate::objective::Asked::from_keywords(ltl, props)?,
            defender,
            adversary,
            crate::evaluate::Options {
                gradient,
                solver,
                tolerance,
                lu_limit,
                allow_unused_propositions,
            },
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "Game(name={:?}, states={}, defender: {} actions / {} observations, {})",
            self.inner.name().unwrap_or(""),
            self.inner.num_states(),
            self.inner.defender().num_actions(),
            self.inner.defender().num_observations(),
            adversary_summary(self.inner.adversary(), self.inner.has_adversary())
        )
    }
}

fn adversary_summary(adversary: &Player, present: bool) -> String {
    if present {
        format!(
            "adversary: {} actions / {} observations",
            adversary.num_actions(),
            adversary.num_observations()
        )
    } else {
        "no adversary".to_string()
    }
}

/// Cells as indices or names `s<i>`.
fn cells(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Vec<usize>> {
    if value.is_instance_of::<PyString>() {
        return Err(PyTypeError::new_err(format!(
            "{name} must be a list of cells (indices or names like \"s4\"), not a string"
        )));
    }
    value
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a list of cells")))?
        .map(|item| cell(name, &item?))
        .collect()
}

fn cell(name: &str, value: &Bound<'_, PyAny>) -> PyResult<usize> {
    if let Ok(text) = value.extract::<String>() {
        return text
            .strip_prefix('s')
            .unwrap_or(&text)
            .parse()
            .map_err(|_| {
                PyValueError::new_err(format!(
                    "{name}: '{text}' is not a cell (s<index> or <index>)"
                ))
            });
    }
    let index: i64 = value.extract().map_err(|_| {
        PyTypeError::new_err(format!("{name}: a cell is an index or a name like \"s4\""))
    })?;
    usize::try_from(index)
        .map_err(|_| PyValueError::new_err(format!("{name}: cell {index} is negative")))
}

/// The seed paper's grid family (`posg-fsc example grid`): a `width` x
/// `height` grid (3 x 2), cell `i = x + width * y` named `s{i}`; defender actions
/// R, L, U, D move to the neighbouring cell with probability `p_na` (no
/// attack) or `p_a` (attack), otherwise slip to the cell or a neighbour;
/// adversary actions A and NA. Cells are indices or names like `"s4"`
/// (`unsafe`: `[4]`, `goal`: `[5]`, `initial`: `0` by default);
/// `labels` maps more propositions to their cells; `random_unsafe` adds
/// that many unsafe cells chosen with `seed`. `observation` is
/// `"neighbourhood"` (observe a cell name, the true one with probability
/// `p_obs_*`) or `"blind"` (the paper's two symbols). The defaults are the
/// paper's 3x2 instance.
#[pyfunction]
#[pyo3(signature = (width = None, height = None, r#unsafe = None, goal = None, labels = None, initial = None, p_na = 0.8, p_a = 0.6, p_obs_defender = 0.8, p_obs_adversary = 0.6, observation = "neighbourhood", random_unsafe = None, seed = 0))]
#[allow(clippy::too_many_arguments)]
pub fn example_grid(
    width: Option<&Bound<'_, PyAny>>,
    height: Option<&Bound<'_, PyAny>>,
    r#unsafe: Option<&Bound<'_, PyAny>>,
    goal: Option<&Bound<'_, PyAny>>,
    labels: Option<std::collections::BTreeMap<String, Bound<'_, PyAny>>>,
    initial: Option<&Bound<'_, PyAny>>,
    p_na: f64,
    p_a: f64,
    p_obs_defender: f64,
    p_obs_adversary: f64,
    observation: &str,
    random_unsafe: Option<&Bound<'_, PyAny>>,
    seed: u64,
) -> PyResult<Game> {
    let defaults = GridSpec::default();
    let spec = GridSpec {
        width: width.map_or(Ok(defaults.width), |w| size("width", w))?,
        height: height.map_or(Ok(defaults.height), |h| size("height", h))?,
        unsafe_cells: match r#unsafe {
            Some(value) => cells("unsafe", value)?,
            None => defaults.unsafe_cells,
        },
        goal_cells: match goal {
            Some(value) => cells("goal", value)?,
            None => defaults.goal_cells,
        },
        extra_labels: labels
            .unwrap_or_default()
            .into_iter()
            .map(|(name, value)| Ok((name.clone(), cells(&format!("labels[{name:?}]"), &value)?)))
            .collect::<PyResult<_>>()?,
        initial: match initial {
            Some(value) => cell("initial", value)?,
            None => defaults.initial,
        },
        p_na,
        p_a,
        defender_p_obs: p_obs_defender,
        adversary_p_obs: p_obs_adversary,
        observation: match observation {
            "neighbourhood" => ObservationModel::Neighbourhood,
            "blind" => ObservationModel::Blind,
            other => {
                return Err(PyValueError::new_err(format!(
                    "observation must be \"neighbourhood\" or \"blind\", not {other:?}"
                )));
            }
        },
        random_unsafe: random_unsafe
            .map(|count| count_of("random_unsafe", count))
            .transpose()?
            .map(|count| RandomUnsafe { count, seed }),
    };
    spec.build().map(Game::new).map_err(convert)
}
