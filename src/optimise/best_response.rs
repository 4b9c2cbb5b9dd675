//! The adversary's best response to a fixed defender (method.md section 4):
//! `min over phi_adv of V(phi_def, phi_adv)` by L-BFGS from several starts.
//!
//! argmin's gradient solvers have no box constraints, so the minimisation
//! runs in the unconstrained coordinates `z` of `phi = c tanh(z)`
//! ([`Reparametrisation`], method.md section 3). The solver is
//! `LBFGS::new(MoreThuenteLineSearch::new(), m)`. The lowest value found over
//! all starts is the defender's worst-case estimate: an upper bound on the
//! true minimum over adversaries of this size and support.
//!
//! Near the box's faces the adversary's chain can mix so slowly that its
//! linear system cannot be solved to the tolerance (method.md section 8).
//! A start that runs into such a point is dropped (its estimate would not
//! be trustworthy), never reported as a number; if every start is dropped
//! the check fails with the solver's error.

use std::cell::RefCell;

use argmin::core::{CostFunction, Error, Executor, Gradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::objective::Objective;
use super::reparam::Reparametrisation;
use super::{OptimiseError, Settings};
use crate::value::ValueError;

/// The outcome of one best-response check.
#[derive(Debug, Clone, PartialEq)]
pub struct BestResponse {
    /// The lowest value found: the defender's worst-case estimate.
    pub value: f64,
    /// The adversary logits that reach it.
    pub adversary: Vec<f64>,
}

/// Random starts draw `z` uniformly from `[-START_RANGE, START_RANGE]`,
/// that is `phi` in `(-0.76 c, 0.76 c)`.
const START_RANGE: f64 = 1.0;

/// Where a best-response minimisation starts: at given adversaries
/// (warm starts: the current adversary, the last best response found) and
/// from `restarts` random points.
#[derive(Debug, Clone, Copy)]
pub struct Starts<'a> {
    /// Adversary logits to start from (at least one).
    pub at: &'a [&'a [f64]],
    /// Random starts besides them.
    pub restarts: usize,
}

/// Minimises `V` over the adversary's logits with the defender's fixed at
/// `defender`, from each of `starts`, each with at most
/// `settings.best_response_iterations` L-BFGS iterations.
pub fn best_response(
    objective: &mut Objective,
    defender: &[f64],
    starts: Starts<'_>,
    settings: &Settings,
    rng: &mut ChaCha8Rng,
) -> Result<BestResponse, OptimiseError> {
    let map = Reparametrisation::new(settings.logit_bound);
    let mut best: Option<BestResponse> = None;
    let mut dropped = None;
    let mut keep = |found: Result<BestResponse, OptimiseError>| match found {
        Ok(found) => {
            if best.as_ref().is_none_or(|b| found.value < b.value) {
                best = Some(found);
            }
            Ok(())
        }
        Err(error @ OptimiseError::Value(ValueError::Solver(_))) => {
            dropped = Some(error);
            Ok(())
        }
        Err(error) => Err(error),
    };
    let parameters = starts.at.first().map_or(0, |logits| logits.len());
    for logits in starts.at {
        keep(minimise_from(
            objective,
            defender,
            map.to_z(logits),
            settings,
        ))?;
    }
    for _ in 0..starts.restarts {
        let start = (0..parameters)
            .map(|_| rng.random_range(-START_RANGE..=START_RANGE))
            .collect();
        keep(minimise_from(objective, defender, start, settings))?;
    }
    match (best, dropped) {
        (Some(best), _) => Ok(best),
        (None, Some(error)) => Err(error),
        (None, None) => Err(OptimiseError::BestResponse(
            "no start to minimise from".into(),
        )),
    }
}

fn minimise_from(
    objective: &mut Objective,
    defender: &[f64],
    start: Vec<f64>,
    settings: &Settings,
) -> Result<BestResponse, OptimiseError> {
    let map = Reparametrisation::new(settings.logit_bound);
    let start_value = objective.value(defender, &map.to_phi(&start))?;
    if start.is_empty() {
        return Ok(BestResponse {
            value: start_value,
            adversary: Vec::new(),
        });
    }
    let problem = AdversaryProblem {
        objective: RefCell::new(objective),
        defender,
        map,
    };
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), settings.lbfgs_memory);
    let result = Executor::new(problem, solver)
        .configure(|state| {
            state
                .param(start.clone())
                .max_iters(settings.best_response_iterations)
        })
        .run()
        .map_err(|e| match e.downcast::<crate::value::ValueError>() {
            Ok(value_error) => OptimiseError::Value(value_error),
            Err(other) => OptimiseError::BestResponse(other.to_string()),
        })?;
    let state = result.state();
    match state.get_best_param() {
        Some(z) if state.get_best_cost() < start_value => Ok(BestResponse {
            value: state.get_best_cost(),
            adversary: map.to_phi(z),
        }),
        _ => Ok(BestResponse {
            value: start_value,
            adversary: map.to_phi(&start),
        }),
    }
}

/// argmin's view of `z -> V(phi_def, c tanh(z))`.
struct AdversaryProblem<'a> {
    objective: RefCell<&'a mut Objective>,
    defender: &'a [f64],
    map: Reparametrisation,
}

impl CostFunction for AdversaryProblem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, z: &Vec<f64>) -> Result<f64, Error> {
        let phi = self.map.to_phi(z);
        Ok(self
            .objective
            .borrow_mut()
            .point(self.defender, &phi)?
            .value)
    }
}

impl Gradient for AdversaryProblem<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, z: &Vec<f64>) -> Result<Vec<f64>, Error> {
        let phi = self.map.to_phi(z);
        let point = self.objective.borrow_mut().point(self.defender, &phi)?;
        Ok(self.map.chain_rule(z, &point.adversary))
    }
}
