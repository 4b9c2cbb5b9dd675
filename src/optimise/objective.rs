//! [`Objective`]: the value `V(phi_def, phi_adv)` and its logit gradients for
//! one support structure, with the last evaluation cached.
//!
//! One [`Evaluator`] per structure is built once (GMC, recurrence classes,
//! symbolic LU) and reused for every evaluation; each evaluation is the
//! adjoint computation of method.md section 2 followed by the softmax chain
//! rule of section 3. argmin asks for the cost and the gradient of the same
//! point in separate calls: the cache answers the second. For an
//! expected-reward objective (section 9) the value is the expected reward,
//! negated where the defender minimises it, so that the defender always
//! maximises.

use crate::analysis::StateClass;
use crate::automaton::Dra;
use crate::controller::Support;
use crate::game::{Posg, RewardModel};
use crate::solver::SolverSettings;
use crate::value::{Evaluator, ValueError};

use super::softmax::Softmax;

/// The value and both players' logit gradients at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// `V`.
    pub value: f64,
    /// `dV/dphi_def`.
    pub defender: Vec<f64>,
    /// `dV/dphi_adv`.
    pub adversary: Vec<f64>,
    /// The larger residual of the two linear solves (value and adjoint):
    /// `max_i |((I - Q) x - b)_i|` and its transposed counterpart.
    pub residual: f64,
}

/// The value as a function of both players' logits on one structure.
pub struct Objective {
    evaluator: Evaluator,
    /// What the defender maximises: `V` itself (`1`), or `-V` for an
    /// expected reward the defender minimises (`-1`).
    sense: f64,
    /// Whether `V` is a probability (else an expected reward, method.md
    /// section 9).
    probability: bool,
    defender: Softmax,
    adversary: Softmax,
    cache: Option<(Vec<f64>, Vec<f64>, Point)>,
    largest_error_bound: f64,
    /// The GMC states solved so far: its reachable states per evaluation.
    work: f64,
    /// [`Objective::identically_zero`].
    identically_zero: bool,
}

/// The size of a structure's GMC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct GmcSize {
    /// Reachable GMC states, up to the decided states (method.md section
    /// 1, "decided states").
    pub states: usize,
    /// Nonzero transitions.
    pub transitions: usize,
    /// Transient states `|T|`: the order of the linear system.
    pub transient: usize,
    /// States in phi-feasible BSCCs `|B|` before the decided states.
    pub target: usize,
    /// Decided states: their automaton state decides phi whatever follows,
    /// so the exploration stopped there.
    pub decided: usize,
}

impl Objective {
    /// Builds the evaluator for the supports of the two softmax maps.
    pub fn new(
        game: &Posg,
        dra: &Dra,
        defender: Softmax,
        adversary: Softmax,
        solver: &SolverSettings,
    ) -> Result<Self, ValueError> {
        let evaluator = Evaluator::new(
            game,
            dra,
            &Support::of(defender.template()),
            &Support::of(adversary.template()),
            solver,
        )?;
        let classes = &evaluator.recurrence().classes;
        // Every initial state, whatever its probability now: the initial
        // node distribution may be a parameter too.
        let identically_zero =
            (evaluator.gmc().initial()).all(|(m, _)| classes[m] == StateClass::Zero);
        Ok(Self {
            identically_zero,
            evaluator,
            sense: 1.0,
            probability: true,
            defender,
            adversary,
            cache: None,
            largest_error_bound: 0.0,
            work: 0.0,
        })
    }

    /// The expected reward of `rewards` until the target of `target` (the
    /// automaton of `F T`; method.md section 9) on the supports of the two
    /// softmax maps, as the value the defender maximises: `V`, or `-V`
    /// where it `minimises` (a cost). An infinite expected reward on these
    /// supports is [`ValueError::InfiniteReward`]: no point of them has a
    /// finite value to climb.
    pub fn for_expected_reward(
        game: &Posg,
        (target, rewards, minimise): (&Dra, &RewardModel, bool),
        defender: Softmax,
        adversary: Softmax,
        solver: &SolverSettings,
    ) -> Result<Self, ValueError> {
        let evaluator = Evaluator::for_expected_reward(
            game,
            target,
            rewards,
            &Support::of(defender.template()),
            &Support::of(adversary.template()),
            solver,
        )?;
        if evaluator.is_infinite() {
            return Err(ValueError::InfiniteReward);
        }
        Ok(Self {
            identically_zero: false,
            evaluator,
            sense: if minimise { -1.0 } else { 1.0 },
            probability: false,
            defender,
            adversary,
            cache: None,
            largest_error_bound: 0.0,
            work: 0.0,
        })
    }

    /// Whether the value is a probability (else an expected reward,
    /// method.md section 9, which the single-player ascent climbs as it is
    /// rather than in its logarithm).
    pub fn is_probability(&self) -> bool {
        self.probability
    }

    /// `1`, or `-1` where the value is the negated expected reward of a
    /// minimised cost: the factor from the value to the quantity the
    /// objective's value means.
    pub fn sense(&self) -> f64 {
        self.sense
    }

    /// The largest error bound of any value computed so far (method.md
    /// section 8): every value this objective returned is within it of the
    /// exact value.
    pub fn largest_error_bound(&self) -> f64 {
        self.largest_error_bound
    }

    /// The work of the evaluations so far: the GMC's reachable states
    /// times the number of evaluations (cached answers are free), the unit
    /// of [`super::Settings::max_work`].
    pub fn work(&self) -> f64 {
        self.work
    }

    /// The defender's softmax map.
    pub fn defender(&self) -> &Softmax {
        &self.defender
    }

    /// The adversary's softmax map.
    pub fn adversary(&self) -> &Softmax {
        &self.adversary
    }

    /// Whether the value is 0 at every point of the two supports: every
    /// initial GMC state is [`StateClass::Zero`] (method.md section 1),
    /// reaching no phi-feasible BSCC whatever probabilities the supports
    /// carry, so every gradient is 0 as well. Decided once, when the
    /// supports are analysed.
    pub fn identically_zero(&self) -> bool {
        self.identically_zero
    }

    /// Frees the evaluator's factors until the next evaluation
    /// ([`Evaluator::release`]).
    pub fn release(&mut self) {
        self.evaluator.release();
    }

    /// The size of the GMC and of its linear system.
    pub fn gmc_size(&self) -> GmcSize {
        let classes = &self.evaluator.recurrence().classes;
        GmcSize {
            states: self.evaluator.gmc().num_states(),
            transitions: self.evaluator.gmc().num_transitions(),
            transient: self.evaluator.recurrence().transient.len(),
            target: classes.iter().filter(|&&c| c == StateClass::Target).count(),
            decided: self.evaluator.gmc().num_decided(),
        }
    }

    /// `V` alone (one factorisation, one solve); does not touch the cache.
    pub fn value(&mut self, defender: &[f64], adversary: &[f64]) -> Result<f64, ValueError> {
        if let Some((d, a, point)) = &self.cache {
            if d == defender && a == adversary {
                return Ok(point.value);
            }
        }
        let mu_def = self.defender.probabilities(defender);
        let mu_adv = self.adversary.probabilities(adversary);
        self.work += self.evaluator.gmc().num_states() as f64;
        let evaluation = self.evaluator.evaluate(&mu_def, &mu_adv)?;
        self.largest_error_bound = self.largest_error_bound.max(evaluation.error_bound);
        Ok(self.sense * evaluation.value)
    }

    /// `V` and both logit gradients (one factorisation, two solves, one pass
    /// over the GMC, the chain rule), from the cache when the point is the last one.
    pub fn point(&mut self, defender: &[f64], adversary: &[f64]) -> Result<Point, ValueError> {
        if let Some((d, a, point)) = &self.cache {
            if d == defender && a == adversary {
                return Ok(point.clone());
            }
        }
        let mu_def = self.defender.probabilities(defender);
        let mu_adv = self.adversary.probabilities(adversary);
        self.work += self.evaluator.gmc().num_states() as f64;
        let (evaluation, gradient) = self.evaluator.evaluate_with_gradient(&mu_def, &mu_adv)?;
        self.largest_error_bound = self.largest_error_bound.max(evaluation.error_bound);
        let sense = self.sense;
        let signed = |g: Vec<f64>| g.into_iter().map(|d| sense * d).collect();
        let point = Point {
            value: sense * evaluation.value,
            defender: signed(self.defender.chain_rule(
                &mu_def,
                &gradient.defender,
                &gradient.defender_initial,
            )),
            adversary: signed(self.adversary.chain_rule(
                &mu_adv,
                &gradient.adversary,
                &gradient.adversary_initial,
            )),
            residual: evaluation.residual.max(gradient.adjoint_residual),
        };
        self.cache = Some((defender.to_vec(), adversary.to_vec(), point.clone()));
        Ok(point)
    }
}
