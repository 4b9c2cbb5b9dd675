//! `posg_fsc.certify`, `posg_fsc.support` and `posg_fsc.translate`: the
//! certified bounds (docs/method.md section 6), support synthesis by SAT
//! (section 7) and the LTL translation, as the commands of the same names.

use posg_fsc::certify::certificate;
use posg_fsc::certify::reward::reward_certificate;
use posg_fsc::controller::Role;
use posg_fsc::ltl;
use posg_fsc::synthesis::{self, Mode};
use posg_fsc::value::SolverSettings;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::controller::Controller;
use crate::convert::{serialised, settings_from_json, size, to_json};
use crate::errors::{Kind, compute, convert, raise};
use crate::game::Game;
use crate::objective::{self, Asked};

/// The certified bounds of `posg-fsc certify` (docs/method.md section 6):
/// `lower`, the defender's guaranteed probability of the formula against
/// every adversary (of any size, observation and memory), and, when an
/// adversary is given, `upper`, the best probability any defender achieves
/// against it. Each is a dict with `value`, `mdp_states`, `seconds`,
/// `residual` and `error_bound`; `upper` is `None` without an adversary.
/// `belief`, on a one-player game (a POMDP), is the belief bound: `value`
/// (no defender of any memory does better), `beliefs` and `complete`
/// (every belief explored); `None` on a game with an adversary, or where
/// the bound cannot be had (docs/method.md section 6).
/// Controllers are `Controller`s, paths or `"uniform:K"`.
///
/// With an expected-reward query (`props='R{"r"}min=? [F "goal"]'`, or
/// `Rmax`; docs/method.md section 9) the dict is the reward's certificate,
/// as `posg-fsc certify` prints it: `query`, `minimise`, `guaranteed` (the
/// cost the defender never exceeds, or the reward it always gets, against
/// every adversary), `best_possible` (with an adversary: the cost no
/// defender gets below, or the reward none exceeds, against it; else
/// `None`), and the brackets behind them, `worst_case` and `best_response`.
#[pyfunction]
#[pyo3(signature = (game, ltl = None, defender = None, adversary = None, *, props = None))]
pub fn certify<'py>(
    py: Python<'py>,
    game: &Bound<'py, Game>,
    ltl: Option<&str>,
    defender: Option<&Bound<'py, PyAny>>,
    adversary: Option<&Bound<'py, PyAny>>,
    props: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let asked = Asked::from_keywords(ltl, props)?;
    let defender = defender.ok_or_else(|| {
        raise(
            Kind::Settings,
            "certify needs the defender's controller: defender= (a Controller, a path or \"uniform:K\")",
        )
    })?;
    let posg = &game.get().inner;
    let defender = Controller::resolve("defender", Some(defender), posg, Role::Defender)?;
    let adversary = adversary
        .map(|a| Controller::resolve("adversary", Some(a), posg, Role::Adversary))
        .transpose()?;
    if let (Some(query), Some(property)) = (asked.reward(), asked.property()) {
        let reward = objective::reward(py, posg, query, property.maximise, false)?;
        let certificate = compute(py, || {
            let objective = (&reward.target, &reward.rewards, reward.minimise);
            let adversaries: Vec<_> = adversary.iter().collect();
            let settings = SolverSettings::default();
            reward_certificate(posg, objective, &defender, &adversaries, &settings)
        })?;
        let report = PyDict::new(py);
        report.set_item("query", &reward.description)?;
        report.update(
            serialised(py, &certificate)?
                .cast_into::<PyDict>()?
                .as_mapping(),
        )?;
        return Ok(report);
    }
    let ltl = &asked.formula("certify")?;
    let objective = objective::automata(py, posg, ltl, false, true)?;
    let not_phi = objective
        .not_phi
        .as_ref()
        .expect("the negation was asked for");
    let certificate = compute(py, || {
        let automata = (&objective.phi, not_phi);
        let settings = SolverSettings::default();
        certificate(posg, automata, &defender, adversary.as_ref(), &settings)
    })?;
    let report = PyDict::new(py);
    report.set_item("formula", ltl)?;
    report.update(
        serialised(py, &certificate.report())?
            .cast_into::<PyDict>()?
            .as_mapping(),
    )?;
    Ok(report)
}

/// A defender support of `def_nodes` nodes that wins with positive
/// probability (or almost surely, `almost_sure=True`) against every
/// adversary, found by SAT and made inclusion-maximal (docs/method.md
/// section 7), as `posg-fsc support`. Returns the fields of `support.json`
/// (`found`, `mode`, `certified_lower`, `support_entries`, `exact`,
/// `reason`, `confirmation`, `sat`) and `defender`, the uniform controller
/// on the support found (or `None`). `settings` are the synthesis options
/// (`engine`, `rank_bound`, `clause_budget`, `synthesis_time_budget`, ...).
#[pyfunction]
#[pyo3(signature = (game, ltl = None, def_nodes = None, almost_sure = false, *, props = None, **settings))]
pub fn support<'py>(
    py: Python<'py>,
    game: &Bound<'py, Game>,
    ltl: Option<&str>,
    def_nodes: Option<&Bound<'py, PyAny>>,
    almost_sure: bool,
    props: Option<&Bound<'py, PyAny>>,
    settings: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let ltl = &Asked::from_keywords(ltl, props)?.formula("support")?;
    let mut json = serde_json::Map::new();
    if let Some(settings) = settings {
        for (key, value) in settings.iter() {
            let key: String = key.extract()?;
            let key = match key.as_str() {
                "synthesis_time_budget" => "time_budget".to_string(),
                "mode" => {
                    return Err(pyo3::exceptions::PyTypeError::new_err(
                        "support() got an unexpected keyword argument 'mode' (use almost_sure=True)",
                    ));
                }
                _ => key,
            };
            let value = to_json(&key, &value)?;
            json.insert(key, value);
        }
    }
    let mut settings: synthesis::Settings =
        settings_from_json("support", serde_json::Value::Object(json))?;
    settings.mode = if almost_sure {
        Mode::AlmostSure
    } else {
        Mode::Positive
    };
    settings.validate().map_err(convert)?;
    let posg = &game.get().inner;
    let nodes = def_nodes.map_or(Ok(1), |n| size("def_nodes", n))?;
    let player = posg.defender();
    posg_fsc::controller::Fsc::check_uniform_size(
        "def_nodes",
        nodes,
        player.num_observations(),
        player.num_actions(),
    )
    .map_err(|e| raise(Kind::Settings, e.to_string()))?;
    let objective = objective::automata(py, posg, ltl, false, true)?;
    let not_phi = objective
        .not_phi
        .as_ref()
        .expect("the negation was asked for");
    let found = compute(py, || {
        synthesis::synthesise(
            posg,
            &objective.phi,
            not_phi,
            nodes,
            &settings,
            &SolverSettings::default(),
        )
    })?;
    let report = PyDict::new(py);
    report.set_item("found", found.defender.is_some())?;
    report.set_item("mode", found.mode.name())?;
    report.set_item("defender_nodes", nodes)?;
    report.set_item("certified_lower", found.certified_lower)?;
    report.set_item("support_entries", found.support_entries())?;
    report.set_item("exact", found.exact)?;
    report.set_item("reason", &found.reason)?;
    report.set_item("confirmation", serialised(py, &found.confirmation)?)?;
    report.set_item("sat", serialised(py, &found.statistics)?)?;
    report.set_item("settings", serialised(py, &settings)?)?;
    report.set_item(
        "defender",
        found
            .defender
            .map(|fsc| Py::new(py, Controller::new(fsc, posg)))
            .transpose()?,
    )?;
    Ok(report)
}

/// The deterministic Rabin automaton of an LTL formula (Spot's syntax) in
/// the HOA format, as `posg-fsc translate --hoa` prints it.
#[pyfunction]
pub fn translate(py: Python<'_>, ltl: &str) -> PyResult<String> {
    let formula = ltl::parse(ltl)
        .map_err(|error| raise(Kind::Formula, format!("cannot parse the formula: {error}")))?;
    let dra = py.detach(|| ltl::translate(&formula)).map_err(|error| {
        raise(
            Kind::Formula,
            format!("cannot translate the formula: {error}"),
        )
    })?;
    Ok(posg_fsc::automaton::write_hoa(
        &dra,
        Some(&formula.to_string()),
    ))
}
