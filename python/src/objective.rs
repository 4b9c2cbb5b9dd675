//! The objective of every function: an LTL formula (Spot's syntax) and its
//! automata, built by the library as the command line builds them
//! ([`Automata::for_game`]).

use posg_fsc::game::Posg;
use posg_fsc::ltl::{self, TranslationBudget};
use posg_fsc::pipeline::{Automata, PipelineError};
use pyo3::prelude::*;

use crate::errors::{Kind, compute_result, convert, raise};

/// The automata of the formula `text` (and of its negation when
/// `negation`), translated without the GIL within the command line's
/// default translation budget. A parse error reads as the command line's:
/// `in the formula '...': ...`. A proposition that labels no state of
/// `game` is a Python warning, and an error when it makes the objective
/// unsatisfiable, unless `allow_unused`.
pub fn automata(
    py: Python<'_>,
    game: &Posg,
    text: &str,
    allow_unused: bool,
    negation: bool,
) -> PyResult<Automata> {
    let budget = TranslationBudget {
        seconds: ltl::DEFAULT_TRANSLATION_SECONDS,
    };
    let built = compute_result(py, || {
        Automata::for_game(game, text, &budget, negation, allow_unused)
    })?;
    let (automata, warnings) = match built {
        Ok(built) => built,
        Err(PipelineError::Parse(error)) => {
            return Err(raise(
                Kind::Formula,
                format!("in the formula '{text}': {error}"),
            ));
        }
        Err(PipelineError::Propositions(check)) => {
            warn(py, &check.warnings)?;
            let error = check.error.unwrap_or_default();
            return Err(raise(Kind::Formula, error));
        }
        Err(error) => return Err(convert(error)),
    };
    warn(py, &warnings)?;
    Ok(automata)
}

/// Each of `warnings` as a Python `UserWarning`.
fn warn(py: Python<'_>, warnings: &[String]) -> PyResult<()> {
    for warning in warnings {
        let warning = std::ffi::CString::new(warning.as_str())?;
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &warning,
            1,
        )?;
    }
    Ok(())
}
