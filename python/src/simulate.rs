//! `posg_fsc.simulate`: a Monte Carlo estimate of a controller pair's value
//! checked against the exact value, as `posg-fsc simulate` reports it
//! ([`posg_fsc::value::simulate_and_check`]).

use std::time::Instant;

use posg_fsc::controller::Role;
use posg_fsc::pipeline::QueryEstimate;
use posg_fsc::value::{Simulated, SimulationSettings, simulate_and_check};
use pyo3::prelude::*;

use crate::controller::Controller;
use crate::convert::serialised;
use crate::errors::{Kind, compute, raise};
use crate::game::Game;
use crate::objective::{self, Asked};

/// Estimates the value of a controller pair by `runs` sampled runs (seeded
/// by `seed`), as `posg-fsc simulate` does, and checks it against the
/// exact value: a probability with a 95% Wilson interval, or for an
/// expected-reward query of `props=` the mean total reward until the
/// target with a 95% normal-approximation interval (docs/method.md
/// section 9). `defender` and `adversary` are Controllers, paths or
/// `"uniform:K"` (default `"uniform:1"`). Returns a dict with the names of
/// the command's JSON: `formula`, `settings`, `estimate` (`mean`, `lower`,
/// `upper`, `confidence`, ...), `exact_value`, `exact_within_interval`,
/// `seconds`, and with `props=` the `query` restated in its own terms
/// (`text`, `mean`, `interval`, `confidence`, `exact_value`: a `Pmin`
/// query's own probability, not its complement's). Such an interval
/// misses the exact value in about one seed of twenty: where it does, a
/// `UserWarning` says so.
#[pyfunction]
#[pyo3(signature = (game, ltl = None, *, props = None, defender = None, adversary = None, runs = 10_000, seed = 0, allow_unused_propositions = false))]
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    game: &Bound<'_, Game>,
    ltl: Option<&str>,
    props: Option<&Bound<'_, PyAny>>,
    defender: Option<&Bound<'_, PyAny>>,
    adversary: Option<&Bound<'_, PyAny>>,
    runs: u64,
    seed: u64,
    allow_unused_propositions: bool,
) -> PyResult<Py<PyAny>> {
    let clock = Instant::now();
    if runs == 0 {
        return Err(raise(Kind::Settings, "runs must be at least 1"));
    }
    let asked = Asked::from_keywords(ltl, props)?;
    let posg = &game.get().inner;
    let defender = Controller::resolve("defender", defender, posg, Role::Defender)?;
    let adversary = Controller::resolve("adversary", adversary, posg, Role::Adversary)?;
    let pair = (&defender, &adversary);
    let settings = SimulationSettings { runs, seed };
    let allow = allow_unused_propositions;
    let (formula, check) = match asked.reward() {
        Some(query) => {
            let maximise = asked.property().is_some_and(|p| p.maximise);
            let objective = objective::reward(py, posg, query, maximise, allow)?;
            let simulated = Simulated::Reward {
                target: &objective.target,
                rewards: &objective.rewards,
            };
            let check = compute(py, || simulate_and_check(posg, simulated, pair, settings))?;
            (objective.description.clone(), check)
        }
        None => {
            let formula = asked.formula("simulate")?;
            let automata = objective::automata(py, posg, &formula, allow, false)?;
            let simulated = Simulated::Probability(&automata.phi);
            let check = compute(py, || simulate_and_check(posg, simulated, pair, settings))?;
            (formula, check)
        }
    };
    if let Some(note) = check.miss_note("seed=", "runs=") {
        let warning = py.get_type::<pyo3::exceptions::PyUserWarning>();
        PyErr::warn(py, &warning, &std::ffi::CString::new(note)?, 1)?;
    }
    let report = serialised(py, &check)?;
    report.set_item("formula", formula)?;
    if let Some(property) = asked.property() {
        let query = QueryEstimate::simulated(property, &check);
        report.set_item("query", serialised(py, &query)?)?;
    }
    report.set_item("seconds", clock.elapsed().as_secs_f64())?;
    Ok(report.unbind())
}
