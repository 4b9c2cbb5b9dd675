//! Certified bounds for an expected reward until a target (method.md
//! section 9, "the worst case over adversaries").
//!
//! As for a probability (section 6), one player's controller is fixed and
//! the other sees `(s, q, node)` and remembers everything: the product
//! MDP of section 6 (`certify::product`) with the automaton of `F T`, whose states where `T`
//! has held are the target. Its action `w` in `(s, q, g)` earns
//!
//! ```text
//! r(s) + sum_f a_fixed(f | s, g) r(s, f, w)   (r(s, w, f) when the defender is free),
//! ```
//!
//! the reward of the GMC's step (section 9) with the free player's action
//! drawn as `w`. `mdp::optimal_total_reward` brackets the free
//! player's optimum, infinite where Storm's convention makes it so:
//!
//! * **What a defender guarantees** ([`RewardCertificate::guaranteed`]):
//!   the adversary maximises a cost (`Rmin`) or minimises a reward
//!   (`Rmax`). No adversary of any size, observation or memory makes a
//!   cost higher than the bracket's top, or a reward lower than its
//!   bottom.
//! * **What any defender can get** ([`RewardCertificate::best_possible`],
//!   with an adversary's controller): the defender that sees the state
//!   minimises the cost (maximises the reward) against it, so no FSC
//!   defender gets a cost below the bracket's bottom (a reward above its
//!   top) against every adversary.

use std::time::Instant;

use serde::Serialize;

use super::{CertifyError, MdpError, Product};
use crate::automaton::Dra;
use crate::controller::{Fsc, Mixture, Role, Support};
use crate::game::{AdversaryAction, DefenderAction, Posg, RewardModel};
use crate::mdp::{Optimum, optimal_total_reward};
use crate::solver::SolverSettings;
use crate::value::number_or_inf;

/// The bracket of the optimal expected reward of the player who sees the
/// state, against a fixed controller of the other (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RewardBound {
    /// A lower bound on the optimum (`"inf"` in JSON where it is infinite).
    #[serde(serialize_with = "number_or_inf")]
    pub lower: f64,
    /// An upper bound on the optimum (`"inf"` where it is infinite).
    #[serde(serialize_with = "number_or_inf")]
    pub upper: f64,
    /// The reachable product MDP states.
    pub mdp_states: usize,
    /// Wall-clock seconds to build and solve the MDP.
    pub seconds: f64,
}

/// The optimum of the player who sees the state (the one `fixed` is not),
/// optimising the expected reward of `rewards` until the target of
/// `target` (the automaton of `F T`) as `optimum` says, against
/// `controller` playing for `fixed`; its policy evaluations solved by
/// `settings`.
pub fn optimal_response(
    game: &Posg,
    (target, rewards): (&Dra, &RewardModel),
    (controller, fixed): (&Fsc, Role),
    optimum: Optimum,
    settings: &SolverSettings,
) -> Result<RewardBound, CertifyError> {
    let clock = Instant::now();
    let product = Product::build(game, target, controller, fixed)?;
    let reached = reached_target(game, target, &product);
    let step_rewards = step_rewards(game, rewards, controller, fixed, &product);
    let optimal = optimal_total_reward(&product.mdp, &reached, &step_rewards, optimum, settings)?;
    let (lower, upper) = optimal.of_initial(&product.initial);
    Ok(RewardBound {
        lower,
        upper,
        mdp_states: product.mdp.num_states(),
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The product states where `T` has held: their automaton state is decided
/// true (the accepting sink of `F T`).
fn reached_target(game: &Posg, target: &Dra, product: &Product) -> Vec<bool> {
    let mut letters = target.state_letters(game);
    letters.sort_unstable();
    letters.dedup();
    let decided = target.decided_states(&letters);
    product
        .states()
        .iter()
        .map(|&(_, q, _)| decided[q] == Some(true))
        .collect()
}

/// Each product action's reward (module documentation), in the order of
/// the MDP's actions: state after state, the free player's actions of
/// `product.free_actions`.
fn step_rewards(
    game: &Posg,
    rewards: &RewardModel,
    controller: &Fsc,
    fixed: Role,
    product: &Product,
) -> Vec<f64> {
    let support = Support::of(controller);
    let mut mixture = Mixture::build(fixed.player(game), &support, game.num_states());
    mixture.refill(&Support::probabilities_of(controller).entries);
    let probabilities = mixture.values();
    let reward = |s: usize, f: usize, w: usize| {
        let (u, v) = match fixed {
            Role::Defender => (f, w),
            Role::Adversary => (w, f),
        };
        (rewards.action_reward(s, DefenderAction(u), AdversaryAction(v))).unwrap_or(0.0)
    };
    let mut step = Vec::with_capacity(product.mdp.num_state_actions());
    for &(s, _, g) in product.states() {
        for &w in &product.free_actions[s] {
            let drawn: f64 = mixture
                .at(s, g)
                .map(|j| probabilities[j] * reward(s, mixture.entry(j).1 as usize, w))
                .sum();
            step.push(rewards.state_reward(s) + drawn);
        }
    }
    step
}

/// What a defender guarantees for an expected reward against every
/// adversary and, with an adversary's controller, what any defender can
/// get against it (module documentation): `certify`'s report for a reward
/// query.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RewardCertificate {
    /// Whether the defender minimises the expected reward (`Rmin`).
    pub minimise: bool,
    /// The defender's certified value: the expected cost stays at most
    /// this (`Rmin`), the expected reward at least this (`Rmax`), whatever
    /// the adversary (`"inf"` in JSON where it is infinite).
    #[serde(serialize_with = "number_or_inf")]
    pub guaranteed: f64,
    /// With an adversary: no defender controller gets a cost below this
    /// (`Rmin`) or a reward above it (`Rmax`) against every adversary.
    #[serde(serialize_with = "option_number_or_inf")]
    pub best_possible: Option<f64>,
    /// The adversary's optimum against the defender.
    pub worst_case: RewardBound,
    /// The optimum of the defender that sees the state against the given
    /// adversary that bounds it best (the tightest [`Self::best_possible`]).
    pub best_response: Option<RewardBound>,
}

/// [`number_or_inf`] for an optional value (`null` for none).
fn option_number_or_inf<S: serde::Serializer>(
    value: &Option<f64>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    match value {
        Some(value) => number_or_inf(value, serializer),
        None => serializer.serialize_none(),
    }
}

/// The [`RewardCertificate`] of `defender` (and of the best bound over
/// `adversaries`, when any are given) for the expected reward of `rewards`
/// until the target of `target`, minimised or maximised by the defender.
/// An adversary against which the defender's minimum is refused
/// ([`MdpError::RewardCycle`]) or cannot be solved to the tolerance
/// ([`CertifyError::is_numerical`]) bounds nothing and is passed over. A
/// guarantee better than the best possible is an error
/// ([`CertifyError::Inconsistent`]): exact numbers never are.
pub fn reward_certificate(
    game: &Posg,
    (target, rewards, minimise): (&Dra, &RewardModel, bool),
    defender: &Fsc,
    adversaries: &[&Fsc],
    settings: &SolverSettings,
) -> Result<RewardCertificate, CertifyError> {
    let (adversary_optimum, defender_optimum) = match minimise {
        true => (Optimum::Max, Optimum::Min),
        false => (Optimum::Min, Optimum::Max),
    };
    let objective = (target, rewards);
    let worst_case = optimal_response(
        game,
        objective,
        (defender, Role::Defender),
        adversary_optimum,
        settings,
    )?;
    let possible = |b: &RewardBound| match minimise {
        true => b.lower,
        false => -b.upper,
    };
    let mut best_response: Option<RewardBound> = None;
    for adversary in adversaries {
        let fixed = (*adversary, Role::Adversary);
        let bound = match optimal_response(game, objective, fixed, defender_optimum, settings) {
            Ok(bound) => bound,
            // A minimum this analysis refuses, or cannot solve to the
            // tolerance, bounds nothing: that adversary is passed over.
            Err(error) if error.is_numerical() => continue,
            Err(CertifyError::Mdp(MdpError::RewardCycle(_))) => continue,
            Err(error) => return Err(error),
        };
        if best_response.is_none_or(|best| possible(&bound) > possible(&best)) {
            best_response = Some(bound);
        }
    }
    let guaranteed = match minimise {
        true => worst_case.upper,
        false => worst_case.lower,
    };
    let best_possible = best_response.map(|b| match minimise {
        true => b.lower,
        false => b.upper,
    });
    if let Some(best) = best_possible {
        let better = match minimise {
            true => guaranteed < best,
            false => guaranteed > best,
        };
        if better {
            return Err(CertifyError::Inconsistent {
                lower: guaranteed.min(best),
                upper: guaranteed.max(best),
                lower_error: 0.0,
                upper_error: 0.0,
            });
        }
    }
    let certificate = RewardCertificate {
        minimise,
        guaranteed,
        best_possible,
        worst_case,
        best_response,
    };
    Ok(certificate)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::Choice;
    use crate::game::file::from_json_str;
    use crate::ltl;

    /// A corridor `0 -> 1 -> 2` where the defender walks (`go`, cost 1 per
    /// step) and the adversary may push it back from 1 to 0 (`push`, cost
    /// 2 added on that step) or `wait`; 2 is the goal.
    const CORRIDOR: &str = r#"{
      "posg": 1,
      "states": ["s0", "s1", "s2"],
      "initial": {"s0": 1.0},
      "labels": {"s2": ["goal"]},
      "defender": {"actions": ["go"], "observations": ["o"],
                   "observe": {"s0": {"o": 1.0}, "s1": {"o": 1.0}, "s2": {"o": 1.0}}},
      "adversary": {"actions": ["wait", "push"], "observations": ["o"],
                    "observe": {"s0": {"o": 1.0}, "s1": {"o": 1.0}, "s2": {"o": 1.0}}},
      "transitions": [
        {"state": "s0", "defender": "go", "adversary": "*", "next": {"s1": 1.0}},
        {"state": "s1", "defender": "go", "adversary": "wait", "next": {"s2": 1.0}},
        {"state": "s1", "defender": "go", "adversary": "push", "next": {"s0": 0.5, "s2": 0.5}},
        {"state": "s2", "defender": "go", "adversary": "*", "next": {"s2": 1.0}}
      ],
      "rewards": {"cost": {"states": {"s0": 1.0, "s1": 1.0},
                           "actions": [{"state": "s1", "defender": "go", "adversary": "push", "reward": 2.0}]}}
    }"#;

    /// The corridor's certificate of its only defender, the cost minimised
    /// or not, with the adversary that always plays `action` as the one
    /// the defender that sees the state responds to.
    fn corridor_certificate(minimise: bool, action: usize) -> RewardCertificate {
        let game = from_json_str(CORRIDOR, "corridor.posg.json").unwrap();
        let target = ltl::translate(&ltl::parse("F goal").unwrap()).unwrap();
        let rewards = game.reward_model("cost").unwrap().clone();
        let defender = Fsc::uniform(Role::Defender, 1, 1, 1);
        let adversary = always(Role::Adversary, action);
        reward_certificate(
            &game,
            (&target, &rewards, minimise),
            &defender,
            &[&adversary],
            &SolverSettings::default(),
        )
        .unwrap()
    }

    /// The 1-node controller of one observation and two actions that
    /// always plays `action`.
    fn always(role: Role, action: usize) -> Fsc {
        let choice = Choice {
            next: 0,
            action,
            probability: 1.0,
            logit: None,
        };
        Fsc::new(role, 1, 1, 2, vec![1.0], vec![vec![choice]]).unwrap()
    }

    /// On paper, with the adversary pushing: `x1 = 3 + x0 / 2`, `x0 = 1 +
    /// x1`, so `x0 = 8`; waiting gives `x0 = 2`. The worst case of the
    /// only defender is 8, and the defender that sees the state against
    /// the waiting adversary gets 2 (it has one action).
    #[test]
    fn the_worst_case_cost_of_a_corridor_is_the_one_on_paper() {
        let certificate = corridor_certificate(true, 0);
        assert!(
            (certificate.guaranteed - 8.0).abs() < 1e-9,
            "{certificate:?}"
        );
        assert!(certificate.worst_case.lower <= 8.0 && 8.0 <= certificate.worst_case.upper);
        let best = certificate.best_possible.unwrap();
        assert!((best - 2.0).abs() < 1e-9 && best <= 2.0, "{certificate:?}");
    }

    /// Maximised, the same numbers turn over: the adversary minimises the
    /// reward by waiting (2), so the defender guarantees 2 and no defender
    /// gets more than 8 against a pushing adversary.
    #[test]
    fn a_maximised_reward_turns_the_bracket_over() {
        let certificate = corridor_certificate(false, 1);
        assert!(
            (certificate.guaranteed - 2.0).abs() < 1e-9,
            "{certificate:?}"
        );
        assert!(certificate.guaranteed <= 2.0);
        assert!((certificate.best_possible.unwrap() - 8.0).abs() < 1e-9);
    }
}
