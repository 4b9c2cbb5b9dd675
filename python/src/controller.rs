//! `posg_fsc.Controller`: a finite-state controller ([`Fsc`]) of one
//! player of a game, its file (docs/formats.md section 2) and its
//! probabilities as a numpy array.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::ndarray::{Array1, Array4};
use numpy::{IntoPyArray, PyArray1, PyArray4, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::Posg;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

use crate::convert::size;
use crate::errors::{Kind, compute, convert, raise};
use crate::game::Game;

/// A finite-state controller (FSC) of one player: in node `g`, on
/// observation `o`, it moves to node `g'` and plays action `u` with
/// probability `mu(g', u | g, o)`, starting from the `initial` node
/// distribution.
///
/// `probabilities` is a numpy array with axes `(node, observation,
/// next_node, action)`: `probabilities[g, o, g2, u] = mu(g2, u | g, o)`,
/// observations and actions in the order of the game's
/// `defender_observations`/`defender_actions` (or the adversary's); each
/// `probabilities[g, o]` sums to 1, and zero entries are outside the
/// support. A controller belongs to its game.
#[pyclass(module = "posg_fsc", name = "Controller", frozen)]
pub struct Controller {
    pub(crate) fsc: Fsc,
    pub(crate) game: Arc<Posg>,
}

impl Controller {
    /// `fsc` of `game`.
    pub(crate) fn new(fsc: Fsc, game: &Arc<Posg>) -> Self {
        Self {
            fsc,
            game: Arc::clone(game),
        }
    }

    /// A controller argument: a `Controller` of `game`, a file path or
    /// `"uniform:K"` (as the command line's `--defender`), for `role`.
    pub(crate) fn resolve(
        name: &str,
        value: Option<&Bound<'_, PyAny>>,
        game: &Arc<Posg>,
        role: Role,
    ) -> PyResult<Fsc> {
        let Some(value) = value else {
            return Ok(Fsc::uniform_enabled(role, 1, role.player(game)));
        };
        if let Ok(controller) = value.cast::<Controller>() {
            let controller = controller.get();
            if !Arc::ptr_eq(&controller.game, game) && *controller.game != **game {
                return Err(PyValueError::new_err(format!(
                    "{name} is a controller of another game"
                )));
            }
            if controller.fsc.role() != role {
                return Err(PyValueError::new_err(format!(
                    "{name} is a controller of the {}, not of the {}",
                    controller.fsc.role().name(),
                    role.name()
                )));
            }
            return Ok(controller.fsc.clone());
        }
        if let Ok(spec) = value.extract::<PathBuf>() {
            let spec = spec.to_string_lossy().into_owned();
            return posg_fsc::controller::file::resolve(&spec, game, role).map_err(convert);
        }
        Err(PyTypeError::new_err(format!(
            "{name} must be a Controller, a path or \"uniform:K\", not {}",
            value.get_type().name()?
        )))
    }

    fn player(&self) -> &posg_fsc::game::Player {
        self.fsc.role().player(&self.game)
    }

    /// The dense array `(node, observation, next_node, action)` of values
    /// given per support entry (in the controller's block order).
    pub(crate) fn dense(fsc: &Fsc, per_entry: &[f64]) -> Array4<f64> {
        let (nodes, observations, actions) =
            (fsc.num_nodes(), fsc.num_observations(), fsc.num_actions());
        let mut dense = Array4::zeros((nodes, observations, nodes, actions));
        let mut values = per_entry.iter();
        for g in 0..nodes {
            for o in 0..observations {
                for choice in fsc.choices(g, o) {
                    dense[[g, o, choice.next, choice.action]] = *values.next().unwrap_or(&0.0);
                }
            }
        }
        dense
    }
}

#[pymethods]
impl Controller {
    /// Reads a controller file (docs/formats.md section 2) for `game`; the
    /// player is the file's `player` field. Raises `GameFormatError` naming
    /// the file and JSON path of the first problem.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf, game: &Bound<'_, Game>) -> PyResult<Self> {
        let game = &game.get().inner;
        compute(py, || posg_fsc::controller::file::read_either(&path, game))
            .map(|fsc| Self::new(fsc, game))
    }

    /// Parses a controller of `role` (`"defender"` or `"adversary"`) in
    /// `game` from JSON text (docs/formats.md section 2).
    #[staticmethod]
    #[pyo3(signature = (text, game, role, name = "<string>"))]
    fn from_json(text: &str, game: &Bound<'_, Game>, role: &str, name: &str) -> PyResult<Self> {
        let role = crate::convert::role("role", role)?;
        let game = &game.get().inner;
        posg_fsc::controller::file::from_json_str(text, name, game, role)
            .map(|fsc| Self::new(fsc, game))
            .map_err(convert)
    }

    /// The controller of `nodes` nodes for `role` that starts in node 0 and
    /// is uniform over all `(next node, enabled action)` pairs in every
    /// block (the command line's `uniform:K`).
    #[staticmethod]
    fn uniform(game: &Bound<'_, Game>, role: &str, nodes: &Bound<'_, PyAny>) -> PyResult<Self> {
        let role = crate::convert::role("role", role)?;
        let nodes = size("nodes", nodes)?;
        let game = &game.get().inner;
        let player = role.player(game);
        Fsc::check_uniform_size(
            "nodes",
            nodes,
            player.num_observations(),
            player.num_actions(),
        )
        .map_err(|e| raise(Kind::Settings, e.to_string()))?;
        Ok(Self::new(Fsc::uniform_enabled(role, nodes, player), game))
    }

    /// The controller of `role` in `game` with the given probabilities: an
    /// array (or nested lists) with axes `(node, observation, next_node,
    /// action)` as `Controller.probabilities`, and the initial node
    /// distribution (default: node 0). Zero entries are outside the
    /// support; each `probabilities[g, o]` and the initial distribution
    /// must sum to 1 within 1e-6 (the tolerance of docs/formats.md
    /// section 1) and are then rescaled to sum to 1 exactly; a row further
    /// off raises `GameFormatError` naming the node, the observation (its
    /// index) and the sum.
    #[staticmethod]
    #[pyo3(signature = (game, role, probabilities, initial = None))]
    fn from_probabilities(
        py: Python<'_>,
        game: &Bound<'_, Game>,
        role: &str,
        probabilities: &Bound<'_, PyAny>,
        initial: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let role = crate::convert::role("role", role)?;
        let game = &game.get().inner;
        let player = role.player(game);
        let array = float_array(py, "probabilities", probabilities)?;
        let shape = array.shape().to_vec();
        let (observations, actions) = (player.num_observations(), player.num_actions());
        if shape.len() != 4
            || shape[0] == 0
            || shape[2] != shape[0]
            || shape[1] != observations
            || shape[3] != actions
        {
            return Err(PyValueError::new_err(format!(
                "probabilities has shape {shape:?}; the {} needs (nodes, {observations}, nodes, \
                 {actions}): axes (node, observation, next_node, action)",
                role.name()
            )));
        }
        let nodes = shape[0];
        let values = array.to_vec()?;
        let initial = match initial {
            None => (0..nodes).map(|g| if g == 0 { 1.0 } else { 0.0 }).collect(),
            Some(value) => {
                let initial = float_array(py, "initial", value)?;
                if initial.shape() != [nodes] {
                    return Err(PyValueError::new_err(format!(
                        "initial has shape {:?}; expected ({nodes},)",
                        initial.shape()
                    )));
                }
                initial.to_vec()?
            }
        };
        let blocks = values
            .chunks(nodes * actions)
            .map(|block| {
                block
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| **p != 0.0)
                    .map(|(k, &probability)| Choice {
                        next: k / actions,
                        action: k % actions,
                        probability,
                        logit: None,
                    })
                    .collect()
            })
            .collect();
        let fsc = Fsc::new(role, nodes, observations, actions, initial, blocks).map_err(convert)?;
        fsc.check_fits(player)
            .map_err(|problem| raise(Kind::Game, format!("probabilities: {problem}")))?;
        Ok(Self::new(fsc, game))
    }

    /// The controller as JSON text (docs/formats.md section 2) naming the
    /// game's observations and actions.
    fn to_json(&self) -> String {
        posg_fsc::controller::file::to_json_string(&self.fsc, &self.game)
    }

    /// Writes the controller file (`*.fsc.json`, docs/formats.md section 2).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        compute(py, || {
            posg_fsc::controller::file::write(&path, &self.fsc, &self.game)
        })
    }

    /// `"defender"` or `"adversary"`.
    #[getter]
    fn role(&self) -> &'static str {
        self.fsc.role().name()
    }

    /// The number of nodes.
    #[getter]
    fn nodes(&self) -> usize {
        self.fsc.num_nodes()
    }

    /// The player's observations, in the order of axis 1 of `probabilities`.
    #[getter]
    fn observations(&self) -> Vec<String> {
        self.player().observations().to_vec()
    }

    /// The player's actions, in the order of axis 3 of `probabilities`.
    #[getter]
    fn actions(&self) -> Vec<String> {
        self.player().actions().to_vec()
    }

    /// `mu(g', u | g, o)` as a float64 array with axes `(node, observation,
    /// next_node, action)`; zero outside the support. A new array each time.
    #[getter]
    fn probabilities<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray4<f64>> {
        let per_entry: Vec<f64> = (0..self.fsc.num_nodes())
            .flat_map(|g| (0..self.fsc.num_observations()).map(move |o| (g, o)))
            .flat_map(|(g, o)| self.fsc.choices(g, o).iter().map(|c| c.probability))
            .collect();
        Self::dense(&self.fsc, &per_entry).into_pyarray(py)
    }

    /// The initial node distribution, a float64 array of shape `(nodes,)`.
    #[getter]
    fn initial<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Array1::from(self.fsc.initial().to_vec()).into_pyarray(py)
    }

    /// The number of supported entries `(g, o, g', u)`.
    #[getter]
    fn support_size(&self) -> usize {
        (0..self.fsc.num_nodes())
            .flat_map(|g| (0..self.fsc.num_observations()).map(move |o| (g, o)))
            .map(|(g, o)| self.fsc.choices(g, o).len())
            .sum()
    }

    fn __repr__(&self) -> String {
        format!(
            "Controller(role={:?}, nodes={}, support_size={})",
            self.fsc.role().name(),
            self.fsc.num_nodes(),
            self.support_size()
        )
    }
}

/// `value` as a float64 numpy array (lists and arrays of any number type).
fn float_array<'py>(
    py: Python<'py>,
    name: &str,
    value: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let numpy = py.import("numpy")?;
    let array = numpy
        .call_method1("asarray", (value, "float64"))
        .map_err(|e| PyTypeError::new_err(format!("{name} must be an array of numbers: {e}")))?;
    let array = array
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be an array of numbers")))?;
    // A C-contiguous copy, so that `to_vec` reads in axis order.
    let array = numpy
        .call_method1("ascontiguousarray", (array,))?
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be an array of numbers")))?;
    Ok(array)
}
