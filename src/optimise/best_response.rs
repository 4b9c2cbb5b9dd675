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
//!
//! A search with a deadline (the final best responses of a run with a time
//! budget) starts no random restart after it and stops each L-BFGS run
//! there: its value is still the lowest found, a weaker estimate.

use std::cell::RefCell;
use std::time::{Duration, Instant};

use argmin::core::{CostFunction, Error, Executor, Gradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

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
/// from `restarts` random points, and when it must end.
#[derive(Debug, Clone, Copy)]
pub struct Starts<'a> {
    /// Adversary logits to start from (at least one).
    pub at: &'a [&'a [f64]],
    /// Random starts besides them.
    pub restarts: usize,
    /// When the search ends (`None`: after every start's iterations): no
    /// random restart begins after it, and each L-BFGS run stops there
    /// (a warm start still gets its value at the start).
    pub deadline: Option<Instant>,
}

impl<'a> Starts<'a> {
    /// The warm starts `at` and `restarts` random ones, without a deadline.
    pub fn new(at: &'a [&'a [f64]], restarts: usize) -> Self {
        Self {
            at,
            restarts,
            deadline: None,
        }
    }

    /// These starts, ending at `deadline` if given.
    pub fn until(self, deadline: Option<Instant>) -> Self {
        Self { deadline, ..self }
    }

    fn past_deadline(&self) -> bool {
        self.deadline.is_some_and(|end| Instant::now() >= end)
    }
}

/// Minimises `V` over the adversary's logits with the defender's fixed at
/// `defender`, from each of `starts`, each with at most
/// `settings.best_response_iterations` L-BFGS iterations and within the
/// starts' deadline.
pub fn best_response(
    objective: &mut Objective,
    defender: &[f64],
    starts: Starts<'_>,
    settings: &Settings,
    rng: &mut ChaCha8Rng,
) -> Result<BestResponse, OptimiseError> {
    let points = start_points(&starts, settings, rng);
    let found = points.into_iter().map(|(warm, start)| {
        (warm || !starts.past_deadline())
            .then(|| minimise_from(objective, defender, start, settings, starts.deadline))
    });
    lowest(found)
}

/// A final best response (method.md section 4: the returned defender's, or
/// every start's without a certifier): [`best_response`] with the starts
/// minimised in parallel (rayon), each on its own objective from
/// `objective` (the same GMC, of `gmc_states` states), and each start's
/// L-BFGS iterations capped by [`Settings::final_best_response_iterations`].
/// Where the cap does not bind, the same value as [`best_response`] for
/// the same random stream, on as many cores as there are starts.
pub fn final_best_response<F>(
    objective: F,
    gmc_states: usize,
    defender: &[f64],
    starts: Starts<'_>,
    settings: &Settings,
    rng: &mut ChaCha8Rng,
) -> Result<BestResponse, OptimiseError>
where
    F: Fn() -> Result<Objective, OptimiseError> + Sync,
{
    let count = starts.at.len() + starts.restarts;
    let settings = &Settings {
        best_response_iterations: settings.final_best_response_iterations(gmc_states, count),
        ..settings.clone()
    };
    let points = start_points(&starts, settings, rng);
    let found = points
        .into_par_iter()
        .map(|(warm, start)| {
            (warm || !starts.past_deadline()).then(|| {
                minimise_from(
                    &mut objective()?,
                    defender,
                    start,
                    settings,
                    starts.deadline,
                )
            })
        })
        .collect::<Vec<_>>();
    lowest(found)
}

/// The starts in the coordinates `z`, each marked whether it is warm: the
/// warm ones first, then `starts.restarts` random ones drawn from `rng`
/// (none after the deadline; a random start drawn is still skipped when
/// the deadline has passed by the time it would run).
fn start_points(
    starts: &Starts<'_>,
    settings: &Settings,
    rng: &mut ChaCha8Rng,
) -> Vec<(bool, Vec<f64>)> {
    let map = Reparametrisation::new(settings.logit_bound);
    let parameters = starts.at.first().map_or(0, |logits| logits.len());
    let warm = starts.at.iter().map(|logits| (true, map.to_z(logits)));
    // A random start is drawn only before the deadline.
    let random: Vec<_> = (0..starts.restarts)
        .take_while(|_| !starts.past_deadline())
        .map(|_| {
            let z = (0..parameters)
                .map(|_| rng.random_range(-START_RANGE..=START_RANGE))
                .collect();
            (false, z)
        })
        .collect();
    warm.chain(random).collect()
}

/// The lowest of the starts' results, in order (`None`: a random start
/// not run, past the deadline); a start whose system could not be solved
/// to the tolerance is dropped, and its error returned only when every
/// start is; any other error ends the search there.
fn lowest(
    found: impl IntoIterator<Item = Option<Result<BestResponse, OptimiseError>>>,
) -> Result<BestResponse, OptimiseError> {
    let mut best: Option<BestResponse> = None;
    let mut dropped = None;
    for result in found.into_iter().flatten() {
        match result {
            Ok(found) => {
                if best.as_ref().is_none_or(|b| found.value < b.value) {
                    best = Some(found);
                }
            }
            Err(error @ OptimiseError::Value(ValueError::Solver(_))) => dropped = Some(error),
            Err(error) => return Err(error),
        }
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
    deadline: Option<Instant>,
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
    let mut executor = Executor::new(problem, solver).configure(|state| {
        state
            .param(start.clone())
            .max_iters(settings.best_response_iterations)
    });
    if let Some(end) = deadline {
        let left = end.saturating_duration_since(Instant::now());
        executor = executor.timeout(left.max(Duration::from_nanos(1)));
    }
    let result = executor
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

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;
    use crate::controller::{Fsc, Role};
    use crate::game::grid::GridSpec;
    use crate::optimise::Softmax;
    use crate::pipeline::Automata;

    /// The paper's 3x2 grid with 1-node controllers on full supports, and
    /// the uniform logits of both.
    fn paper_grid() -> (Objective, Vec<f64>, Vec<f64>) {
        paper_grid_for("GF goal & G !unsafe")
    }

    /// [`paper_grid`] for the objective `formula`.
    fn paper_grid_for(formula: &str) -> (Objective, Vec<f64>, Vec<f64>) {
        let game = GridSpec::default().build().unwrap();
        let dra = Automata::from_ltl(formula).unwrap().phi;
        let settings = Settings::default();
        let softmax = |role, player| Softmax::new(&Fsc::uniform_enabled(role, 1, player), false);
        let objective = Objective::new(
            &game,
            &dra,
            softmax(Role::Defender, game.defender()),
            softmax(Role::Adversary, game.adversary()),
            &settings.solver_settings(),
        )
        .unwrap();
        let defender = objective
            .defender()
            .logits_of_template(settings.logit_bound);
        let adversary = objective
            .adversary()
            .logits_of_template(settings.logit_bound);
        (objective, defender, adversary)
    }

    /// On a GMC too small for the cap, the final (parallel) search
    /// minimises from the same starts as the sequential one (the same
    /// stream drawn in the same order) and keeps the same lowest start: the
    /// same value and adversary, below the warm start's value.
    #[test]
    fn the_parallel_search_finds_what_the_sequential_one_finds() {
        let formula = "!unsafe U goal";
        let (mut objective, defender, adversary) = paper_grid_for(formula);
        let settings = Settings::default();
        let warm = [adversary.as_slice()];
        let starts = Starts::new(&warm, 3);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let sequential = best_response(&mut objective, &defender, starts, &settings, &mut rng);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let fresh = || Ok(paper_grid_for(formula).0);
        let states = objective.gmc_size().states;
        let parallel = final_best_response(fresh, states, &defender, starts, &settings, &mut rng);
        let (sequential, parallel) = (sequential.unwrap(), parallel.unwrap());
        assert_eq!(sequential, parallel);
        let at_start = objective.value(&defender, &adversary).unwrap();
        assert!(
            parallel.value < at_start,
            "{} not below {at_start}",
            parallel.value
        );
    }

    /// Past the deadline no random restart begins (the random stream is
    /// left as it was) and the warm start keeps at most its start's value;
    /// without one, the restarts draw from the stream.
    #[test]
    fn past_its_deadline_a_search_starts_no_restart_but_keeps_its_warm_start() {
        let (mut objective, defender, adversary) = paper_grid();
        let settings = Settings::default();
        let warm = [adversary.as_slice()];
        let at_start = objective.value(&defender, &adversary).unwrap();
        let untouched = ChaCha8Rng::seed_from_u64(3);
        let mut rng = untouched.clone();
        let late = Starts::new(&warm, 50).until(Some(Instant::now()));
        let found = best_response(&mut objective, &defender, late, &settings, &mut rng).unwrap();
        assert_eq!(rng, untouched, "a restart drew from the stream");
        assert!(found.value <= at_start, "{} above {at_start}", found.value);
        let unhurried = Starts::new(&warm, 1);
        best_response(&mut objective, &defender, unhurried, &settings, &mut rng).unwrap();
        assert_ne!(rng, untouched, "the restart did not run");
    }
}
