//! The objective of every function: an LTL formula (Spot's syntax) or a
//! property file's query, and its automata, built by the library as the
//! command line builds them ([`Automata::for_game`],
//! [`RewardObjective::for_game`]).

use posg_fsc::game::Posg;
use posg_fsc::ltl::props::{self, Property, RewardQuery};
use posg_fsc::ltl::{self, TranslationBudget};
use posg_fsc::pipeline::{Automata, PipelineError, RewardObjective};
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

/// What a function was asked: an LTL formula (`ltl=`) or the query of a
/// property file (`props=`).
pub enum Asked {
    /// `ltl=`: the formula's text.
    Ltl(String),
    /// `props=`: the property file's query.
    Props(Property),
}

impl Asked {
    /// Exactly one of `ltl` and `props`. `props` is a query (`'Pmax=? [F
    /// "goal"]'`, recognised by its `=?`) or the path of a property file
    /// (a `str` or an `os.PathLike`); a query that cannot be read is a
    /// `FormulaError` naming the line and column (and the file).
    pub fn from_keywords(ltl: Option<&str>, props: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        match (ltl, props) {
            (Some(text), None) => Ok(Self::Ltl(text.to_string())),
            (None, Some(props)) => Ok(Self::Props(property(props)?)),
            (Some(_), Some(_)) => Err(raise(
                Kind::Settings,
                "give the objective once: ltl= or props=, not both",
            )),
            (None, None) => Err(raise(
                Kind::Settings,
                "give the objective: ltl='F goal' (an LTL formula) or props='Pmax=? [F \"goal\"]' \
                 (a query or a property file)",
            )),
        }
    }

    /// The expected-reward query of `props=`, if it is one.
    pub fn reward(&self) -> Option<&RewardQuery> {
        match self.property().map(|p| &p.query) {
            Some(posg_fsc::ltl::props::Query::Reward(query)) => Some(query),
            _ => None,
        }
    }

    /// The property file's query, for `props=`.
    pub fn property(&self) -> Option<&Property> {
        match self {
            Self::Props(property) => Some(property),
            Self::Ltl(_) => None,
        }
    }

    /// The LTL formula whose probability the defender maximises: `ltl=`,
    /// or the objective of a `Pmax`/`Pmin` query. `function` takes no
    /// expected-reward query (so far only `evaluate` does): an error says so.
    pub fn formula(&self, function: &str) -> PyResult<String> {
        match self {
            Self::Ltl(text) => Ok(text.clone()),
            Self::Props(property) => match property.probability_objective() {
                Some(objective) => Ok(objective.to_string()),
                None => Err(raise(
                    Kind::Settings,
                    format!(
                        "`{}` is an expected-reward query: Game.evaluate computes its value for \
                         given controllers, certify bounds it against every adversary and solve \
                         optimises it; {function} takes probability queries (Pmax=?, Pmin=?) so \
                         far (docs/method.md section 9)",
                        property.text
                    ),
                )),
            },
        }
    }
}

/// The query of `props`: a query's text, or a property file's path.
fn property(props: &Bound<'_, PyAny>) -> PyResult<Property> {
    let (text, name) = match props.extract::<String>() {
        Ok(text) if text.contains("=?") => (text, "props".to_string()),
        _ => {
            let path: std::path::PathBuf = props.extract().map_err(|_| {
                raise(
                    Kind::Settings,
                    "props must be a query (a str with `=?`, as 'Pmax=? [F \"goal\"]') or the \
                     path of a property file",
                )
            })?;
            let text = std::fs::read_to_string(&path).map_err(|error| {
                raise(
                    Kind::Settings,
                    format!("props: cannot read {}: {error}", path.display()),
                )
            })?;
            (text, path.display().to_string())
        }
    };
    let property = props::from_props_str(&text, &name)
        .map_err(|error| raise(Kind::Formula, error.to_string()))?;
    if let Some(player) = property.player.filter(|&p| p != 0) {
        let warning = format!(
            "{}: `<<{player}>>` is not applied: a Game fixes its defender when it is loaded \
             (Game.from_drn makes player 0 of a turn-based game the defender); for player \
             {player}, write the game with `posg-fsc import-drn --defender-player {player}` and \
             load that file",
            property.position(&name)
        );
        Python::attach(|py| warn(py, &[warning]))?;
    }
    Ok(property)
}

/// The expected-reward objective of `query` on `game` (method.md section
/// 9), minimised unless `maximise`, with the formula's checks of
/// [`automata`]: warnings as Python warnings, errors as `FormulaError`s.
pub fn reward(
    py: Python<'_>,
    game: &Posg,
    query: &RewardQuery,
    maximise: bool,
    allow_unused: bool,
) -> PyResult<RewardObjective> {
    let budget = TranslationBudget {
        seconds: ltl::DEFAULT_TRANSLATION_SECONDS,
    };
    let built = compute_result(py, || {
        RewardObjective::for_game(game, query, !maximise, &budget, allow_unused)
    })?;
    match built {
        Ok((objective, warnings)) => {
            warn(py, &warnings)?;
            Ok(objective)
        }
        Err(PipelineError::Propositions(check)) => {
            warn(py, &check.warnings)?;
            Err(raise(Kind::Formula, check.error.unwrap_or_default()))
        }
        Err(PipelineError::Model(error)) => Err(raise(Kind::Formula, error.to_string())),
        Err(error) => Err(convert(error)),
    }
}
