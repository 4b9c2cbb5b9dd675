//! The objective of every function: an LTL formula (Spot's syntax) and its
//! automata, built as the command line builds them (`--ltl`).

use posg_fsc::automaton::Dra;
use posg_fsc::game::Posg;
use posg_fsc::ltl::{self, TranslationBudget};
use posg_fsc::pipeline::Automata;
use pyo3::prelude::*;

use crate::errors::{Kind, compute, raise};

/// The automata for phi (and !phi when asked for) of a formula.
pub struct Objective {
    /// A deterministic Rabin automaton for phi.
    pub phi: Dra,
    /// One for !phi, when asked for.
    pub not_phi: Option<Dra>,
    /// The formula as given.
    pub text: String,
}

impl Objective {
    /// Parses and translates `text` (and its negation when `negation`),
    /// without the GIL, within the command line's default translation
    /// budget. A parse error reads as the command line's: `in the formula
    /// '...': ...`. A proposition that labels no state of `game` is a
    /// Python warning, and an error when it makes the objective
    /// unsatisfiable, unless `allow_unused`
    /// ([`posg_fsc::pipeline::check_propositions`]).
    pub fn from_ltl(
        py: Python<'_>,
        game: &Posg,
        text: &str,
        allow_unused: bool,
        negation: bool,
    ) -> PyResult<Self> {
        let formula = ltl::parse(text)
            .map_err(|error| raise(Kind::Formula, format!("in the formula '{text}': {error}")))?;
        let budget = TranslationBudget {
            seconds: ltl::DEFAULT_TRANSLATION_SECONDS,
        };
        let (phi, not_phi) = compute(py, || {
            let phi = ltl::translate_within(&formula, &budget)?;
            let not_phi = match negation {
                true => Some(ltl::translate_within(&formula.negate(), &budget)?),
                false => None,
            };
            Ok::<_, ltl::TranslateError>((phi, not_phi))
        })?;
        let check = posg_fsc::pipeline::check_propositions(&phi, game, text, allow_unused);
        for warning in &check.warnings {
            let warning = std::ffi::CString::new(warning.as_str())?;
            PyErr::warn(
                py,
                &py.get_type::<pyo3::exceptions::PyUserWarning>(),
                &warning,
                1,
            )?;
        }
        if let Some(error) = check.error {
            return Err(raise(Kind::Formula, error));
        }
        Ok(Self {
            phi,
            not_phi,
            text: text.to_string(),
        })
    }

    /// The pipeline's automata (with !phi: the certified bracket).
    pub fn automata(self) -> Automata {
        Automata {
            phi: self.phi,
            not_phi: self.not_phi,
            description: self.text,
        }
    }
}
