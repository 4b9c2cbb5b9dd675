//! A property file's query restated in its own terms (docs/formats.md
//! sections 6 and 9): `eval`'s and `summary.json`'s `query`, Python's
//! `Evaluation.query` and `SolveResult.query`; `simulate`'s estimate
//! ([`QueryEstimate`]). A `Pmin=? [PATH]` query is
//! solved as the probability of the complement of `PATH`; restated, its
//! value is 1 minus that probability, and its certified bracket turns over.

use serde::Serialize;

use crate::certify::Bracket;
use crate::ltl::props::{Property, Query};
use crate::value::{Evaluation, SimulationCheck, number_or_inf};

/// A query with its value, as the query asks it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QueryValue {
    /// The query as written (`Pmin=? [F "goal"]`).
    pub text: String,
    /// Its value (`"inf"` in JSON for an infinite expected reward): of the
    /// controllers evaluated, or the returned defender's worst-case
    /// estimate.
    #[serde(serialize_with = "number_or_inf")]
    pub value: f64,
    /// A bound on `|value - exact value|` (docs/method.md section 8).
    pub error_bound: f64,
    /// For a solved query, `[lo, hi]`: for a maximised probability, `lo`
    /// is what the returned defender guarantees against every adversary
    /// and `hi` bounds what any defender can guarantee; for a minimised
    /// one, `hi` is the guarantee (the probability stays below it) and
    /// `lo` the bound (docs/method.md section 6).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub certified: Option<[f64; 2]>,
    /// For a reward query, the probability of reaching its target.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_probability: Option<f64>,
}

impl QueryValue {
    /// The query of `property` for the evaluation of its objective
    /// ([`Property::probability_objective`], or the expected reward) and,
    /// for a reward query, the probability of reaching its target.
    pub fn evaluated(
        property: &Property,
        evaluation: &Evaluation,
        target_probability: Option<f64>,
    ) -> Self {
        Self {
            text: property.text.clone(),
            value: restated(property, evaluation.value),
            error_bound: evaluation.error_bound,
            certified: None,
            target_probability,
        }
    }

    /// The query of `property` solved: the returned defender's worst-case
    /// estimate of its objective's probability, its error bound and
    /// certified bracket.
    pub fn solved(
        property: &Property,
        worst_case: f64,
        error_bound: f64,
        bracket: Option<Bracket>,
    ) -> Self {
        let certified = bracket.map(|b| {
            let (lo, hi) = (
                restated(property, b.certified_lower),
                restated(property, b.upper_bound),
            );
            [lo.min(hi), lo.max(hi)]
        });
        Self {
            text: property.text.clone(),
            value: restated(property, worst_case),
            error_bound,
            certified,
            target_probability: None,
        }
    }
}

impl QueryValue {
    /// The expected-reward query of `property` solved: the returned
    /// defender's expected reward `value`, exact within `error_bound`;
    /// where it is finite, its target is reached with probability 1.
    pub fn rewarded(property: &Property, value: f64, error_bound: f64) -> Self {
        Self {
            text: property.text.clone(),
            value,
            error_bound,
            certified: None,
            target_probability: value.is_finite().then_some(1.0),
        }
    }
}

/// A query estimated by simulation (`simulate --props`, Python's
/// `simulate(props=...)`), as the query asks it: for `Pmin=? [PATH]`, the
/// runs' estimate of the probability of `PATH` itself, not of the
/// complement the tool optimises.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QueryEstimate {
    /// The query as written.
    pub text: String,
    /// The runs' mean.
    pub mean: f64,
    /// The interval around it, `[lower, upper]`.
    pub interval: [f64; 2],
    /// The interval's confidence level.
    pub confidence: f64,
    /// The value computed exactly (`"inf"` in JSON for an infinite
    /// expected reward).
    #[serde(serialize_with = "number_or_inf")]
    pub exact_value: f64,
}

impl QueryEstimate {
    /// The query of `property` for the simulation `check` of its objective.
    pub fn simulated(property: &Property, check: &SimulationCheck) -> Self {
        let (lower, upper, confidence) = check.estimate.interval();
        let (lower, upper) = (restated(property, lower), restated(property, upper));
        Self {
            text: property.text.clone(),
            mean: restated(property, check.estimate.mean()),
            interval: [lower.min(upper), lower.max(upper)],
            confidence,
            exact_value: restated(property, check.exact_value),
        }
    }
}

/// `value` of the objective as a value of the query: `1 - value` for
/// `Pmin`, whose objective is the complement of its path.
fn restated(property: &Property, value: f64) -> f64 {
    match (&property.query, property.maximise) {
        (Query::Probability { .. }, false) => 1.0 - value,
        _ => value,
    }
}
