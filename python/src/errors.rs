//! The Python exceptions of `posg_fsc` and the conversion of every library
//! error into one of them, with the message the command line prints
//! ([`posg_fsc::output::error_message`]: the error and its causes, each
//! once, joined by `: `).
//!
//! ```text
//! posg_fsc.Error                  every error of the library
//! ├── GameFormatError             a game or controller that is malformed or does not fit
//! ├── FormulaError                an LTL formula or HOA automaton that cannot be read or translated
//! ├── NumericalError              a linear system that cannot be solved to its tolerance
//! └── SettingsError (ValueError)  a setting or size out of range
//! ```

use posg_fsc::certify::{CertifyError, MdpError};
use posg_fsc::game::ModelError;
use posg_fsc::optimise::OptimiseError;
use posg_fsc::pipeline::PipelineError;
use posg_fsc::synthesis::SynthesisError;
use posg_fsc::value::{ProductError, ValueError};
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyType};

pyo3::create_exception!(
    posg_fsc,
    Error,
    PyException,
    "Base class of every error posg_fsc raises; the message is the one the \
     command line prints."
);
pyo3::create_exception!(
    posg_fsc,
    GameFormatError,
    Error,
    "A game or controller that is malformed (the message names the file and \
     the JSON path or line) or does not fit the game."
);
pyo3::create_exception!(
    posg_fsc,
    FormulaError,
    Error,
    "An LTL formula that cannot be parsed (the message names the position) or \
     translated, or an automaton that cannot be read."
);
pyo3::create_exception!(
    posg_fsc,
    NumericalError,
    Error,
    "A linear system that cannot be solved to its tolerance, or certified \
     bounds that contradict each other: the number is not trusted."
);

/// `SettingsError`, made at import by [`define_settings_error`]: a Python
/// class deriving from both `Error` and the built-in `ValueError`.
static SETTINGS_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// Defines `SettingsError(Error, ValueError)` (pyo3's exceptions have one
/// base class) and adds every exception class to the module.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = module.py();
    module.add("Error", py.get_type::<Error>())?;
    module.add("GameFormatError", py.get_type::<GameFormatError>())?;
    module.add("FormulaError", py.get_type::<FormulaError>())?;
    module.add("NumericalError", py.get_type::<NumericalError>())?;
    module.add("SettingsError", define_settings_error(py)?)?;
    Ok(())
}

fn define_settings_error(py: Python<'_>) -> PyResult<Bound<'_, PyType>> {
    let class = SETTINGS_ERROR.get_or_try_init(py, || {
        let namespace = PyDict::new(py);
        namespace.set_item("Error", py.get_type::<Error>())?;
        py.run(
            c"class SettingsError(Error, ValueError):\n    \
              \"\"\"A setting, size or other argument out of range (also a ValueError).\"\"\"\n    \
              __module__ = 'posg_fsc'\n",
            Some(&namespace),
            None,
        )?;
        let class = namespace.get_item("SettingsError")?.ok_or_else(|| {
            pyo3::exceptions::PyRuntimeError::new_err("SettingsError was not defined")
        })?;
        Ok::<_, PyErr>(class.cast_into::<PyType>()?.unbind())
    })?;
    Ok(class.bind(py).clone())
}

/// Which exception class an error becomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// [`GameFormatError`].
    Game,
    /// [`FormulaError`].
    Formula,
    /// [`NumericalError`].
    Numerical,
    /// `SettingsError`.
    Settings,
    /// [`Error`].
    Other,
}

/// The exception of `kind` with `message`.
pub fn raise(kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    match kind {
        Kind::Game => GameFormatError::new_err(message),
        Kind::Formula => FormulaError::new_err(message),
        Kind::Numerical => NumericalError::new_err(message),
        Kind::Other => Error::new_err(message),
        Kind::Settings => Python::attach(|py| match define_settings_error(py) {
            Ok(class) => PyErr::from_type(class, message),
            Err(error) => error,
        }),
    }
}

/// A library error as the exception of its [`Kind`], with the message
/// `posg-fsc` prints for it.
pub fn convert<E>(error: E) -> PyErr
where
    E: Classify + std::error::Error + Send + Sync + 'static,
{
    let kind = error.kind();
    raise(kind, posg_fsc::output::error_message(&error))
}

/// Runs `work` without the GIL; its error becomes the exception of its
/// [`Kind`], and a panic (a bug) `posg_fsc.Error`: no panic reaches Python.
pub fn compute<T, E>(py: Python<'_>, work: impl FnOnce() -> Result<T, E> + Send) -> PyResult<T>
where
    T: Send,
    E: Classify + std::error::Error + Send + Sync + 'static,
{
    compute_result(py, work)?.map_err(convert)
}

/// [`compute`] with `work`'s error returned as it is, for a caller that
/// reports some errors its own way; only a panic is an exception here.
pub fn compute_result<T, E>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, E> + Send,
) -> PyResult<Result<T, E>>
where
    T: Send,
    E: Send,
{
    py.detach(|| std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)))
        .map_err(|panic| panicked(panic.as_ref()))
}

/// A panic's payload as `posg_fsc.Error`.
pub fn panicked(panic: &(dyn std::any::Any + Send)) -> PyErr {
    let what = panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_default();
    raise(
        Kind::Other,
        format!("internal error (a panic): {what}; please report it"),
    )
}

/// A library error's exception class.
pub trait Classify {
    /// The class.
    fn kind(&self) -> Kind;
}

impl Classify for ModelError {
    fn kind(&self) -> Kind {
        Kind::Game
    }
}

impl Classify for posg_fsc::ltl::ParseError {
    fn kind(&self) -> Kind {
        Kind::Formula
    }
}

impl Classify for posg_fsc::ltl::TranslateError {
    fn kind(&self) -> Kind {
        Kind::Formula
    }
}

impl Classify for posg_fsc::automaton::HoaError {
    fn kind(&self) -> Kind {
        Kind::Formula
    }
}

impl Classify for ValueError {
    fn kind(&self) -> Kind {
        match self {
            ValueError::Solver(_) => Kind::Numerical,
            ValueError::Product(ProductError::Mismatch { .. }) => Kind::Game,
            ValueError::Product(_) | ValueError::InfiniteReward => Kind::Other,
        }
    }
}

impl Classify for posg_fsc::value::SimulationError {
    fn kind(&self) -> Kind {
        match self {
            posg_fsc::value::SimulationError::Value(error) => error.kind(),
            _ => Kind::Other,
        }
    }
}

impl Classify for CertifyError {
    fn kind(&self) -> Kind {
        match self {
            CertifyError::Mismatch { .. } => Kind::Game,
            CertifyError::Mdp(MdpError::Malformed(_)) | CertifyError::Budget(_) => Kind::Other,
            CertifyError::Mdp(_) | CertifyError::Inconsistent { .. } => Kind::Numerical,
        }
    }
}

impl Classify for SynthesisError {
    fn kind(&self) -> Kind {
        match self {
            SynthesisError::Settings { .. } => Kind::Settings,
            SynthesisError::Model(error) => error.kind(),
            SynthesisError::Certify(error) => error.kind(),
            _ => Kind::Other,
        }
    }
}

impl Classify for OptimiseError {
    fn kind(&self) -> Kind {
        match self {
            OptimiseError::Settings { .. } => Kind::Settings,
            OptimiseError::Model(error) => error.kind(),
            OptimiseError::Value(error) => error.kind(),
            OptimiseError::Synthesis(error) => error.kind(),
            OptimiseError::Certify(error) => error.kind(),
            _ => Kind::Other,
        }
    }
}

impl Classify for PipelineError {
    fn kind(&self) -> Kind {
        match self {
            PipelineError::Parse(_)
            | PipelineError::Translate(_)
            | PipelineError::TranslateNegation(_)
            | PipelineError::Propositions(_) => Kind::Formula,
            PipelineError::Model(error) => error.kind(),
            PipelineError::Optimise(error) => error.kind(),
            PipelineError::Certify(error) => error.kind(),
            _ => Kind::Other,
        }
    }
}

impl Classify for posg_fsc::output::OutputError {
    fn kind(&self) -> Kind {
        Kind::Other
    }
}
