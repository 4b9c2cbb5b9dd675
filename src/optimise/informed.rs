//! The `informed` source of structures (method.md section 4, "Starting
//! points that see the goal"): the strategy of an easier game, in which the
//! defender sees the state and the adversary plays the structure's
//! starting controller, projected onto the defender's observations.
//!
//! The easier game's optimum is the fully informed bound
//! ([`crate::certify::upper_bound`]): a memoryless deterministic rule
//! `sigma(s, q, n)` per product state, with its value `v(s, q, n)`. The
//! projection lets every product state vote for its rule's action under
//! each observation it may show, with weight `O(o | s) v(s, q, n)`: states
//! from which the goal cannot be reached cast no vote, and states near it
//! the strongest. Under observation `o` the structure's defender keeps the
//! actions whose votes reach [`INFORMED_SUPPORT_SHARE`] of the leading
//! action's, with probabilities proportional to their votes; every node
//! plays the same actions, stays in its node with probability
//! `1 - INFORMED_NODE_MIX` and moves to each other node with an equal share
//! of the rest (so memory is free to be learned). An observation without a
//! vote keeps the starting structure's block.
//!
//! On the grid family the full support's value is exactly 0 at every
//! interior point (some action always leads into an unsafe cell) and the
//! SAT support's starts at `1e-11` and less, so the gradient has nothing to
//! climb; the informed structure starts where the value is that of the
//! informed strategy played through the observations.

use rustc_hash::FxHashMap;

use super::{OptimiseError, Structure};
use crate::certify::StrategyRule;
use crate::certify::belief::UpperBoundsOnce;
use crate::controller::{Choice, Fsc};
use crate::game::Posg;

/// The least share of the leading action's votes an action needs under an
/// observation to enter the informed support ([`informed`]).
pub const INFORMED_SUPPORT_SHARE: f64 = 0.1;

/// The probability with which the informed defender leaves its node
/// ([`informed`]): small, so that the nodes start apart and the gradient
/// can give them different roles.
pub const INFORMED_NODE_MIX: f64 = 0.05;

/// The informed structure of `start` (module documentation): its defender
/// projected from the fully informed defender's optimal strategy against
/// `start`'s adversary, on `start`'s defender support; the adversary is
/// `start`'s. No structure where the informed defender cannot reach phi at
/// all (its value is 0). Returns the structures and a note.
pub(crate) fn informed(
    game: &Posg,
    start: &Structure,
    bounds: &UpperBoundsOnce<'_>,
) -> Result<(Vec<Structure>, String), OptimiseError> {
    let bound = bounds.informed(&start.adversary)?;
    if bound.value <= 0.0 {
        return Ok((
            Vec::new(),
            "a defender that sees the state cannot satisfy phi against the starting adversary"
                .into(),
        ));
    }
    let votes = observation_votes(game, &bound.strategy.rules)?;
    let defender = projected(&start.defender, &votes)?;
    let note = format!(
        "the fully informed defender's strategy (value {:.6} against the starting adversary) \
         projected onto the observations",
        bound.value
    );
    Ok((
        vec![Structure {
            name: "informed".into(),
            defender,
            adversary: start.adversary.clone(),
            warm: None,
        }],
        note,
    ))
}

/// `votes[o][u]`: the weight of the rules playing `u` in the states that
/// may show observation `o` to the defender, each weighted by `O(o | s)`
/// and its value.
fn observation_votes(game: &Posg, rules: &[StrategyRule]) -> Result<Vec<Vec<f64>>, OptimiseError> {
    let defender = game.defender();
    let action_index: FxHashMap<&str, usize> = (defender.actions().iter())
        .enumerate()
        .map(|(u, name)| (name.as_str(), u))
        .collect();
    let state_index = game.state_indices();
    let mut votes = vec![vec![0.0; defender.num_actions()]; defender.num_observations()];
    for rule in rules.iter().filter(|r| r.free_player_value > 0.0) {
        let (Some(&s), Some(&u)) = (
            state_index.get(rule.state.as_str()),
            action_index.get(rule.action.as_str()),
        ) else {
            return Err(OptimiseError::Settings {
                field: "structures",
                problem: format!(
                    "the informed strategy names state `{}` or action `{}`, which the game lacks",
                    rule.state, rule.action
                ),
            });
        };
        for &(o, p) in defender.observation_distribution(s) {
            votes[o][u] += p * rule.free_player_value;
        }
    }
    Ok(votes)
}

/// The informed defender on `start`'s support: under each observation the
/// actions whose votes reach [`INFORMED_SUPPORT_SHARE`] of the leading
/// one's, with probabilities proportional to their votes and the node
/// kept with probability `1 - INFORMED_NODE_MIX` (module documentation).
fn projected(start: &Fsc, votes: &[Vec<f64>]) -> Result<Fsc, OptimiseError> {
    let nodes = start.num_nodes();
    let blocks = (0..nodes)
        .flat_map(|g| (0..start.num_observations()).map(move |o| (g, o)))
        .map(|(g, o)| projected_block(start.choices(g, o), &votes[o], g, nodes))
        .collect();
    Ok(Fsc::new(
        start.role(),
        nodes,
        start.num_observations(),
        start.num_actions(),
        start.initial().to_vec(),
        blocks,
    )?)
}

/// One block `(g, o)` of [`projected`]: the pairs of `support` whose action
/// has enough of `votes` (else all of `support`, as it is).
fn projected_block(support: &[Choice], votes: &[f64], g: usize, nodes: usize) -> Vec<Choice> {
    let leading = support.iter().map(|c| votes[c.action]).fold(0.0, f64::max);
    let kept: Vec<&Choice> = support
        .iter()
        .filter(|c| leading > 0.0 && votes[c.action] >= INFORMED_SUPPORT_SHARE * leading)
        .collect();
    if kept.is_empty() {
        return support.to_vec();
    }
    let node_weight = |next: usize| match (nodes, next == g) {
        (1, _) => 1.0,
        (_, true) => 1.0 - INFORMED_NODE_MIX,
        (_, false) => INFORMED_NODE_MIX / (nodes - 1) as f64,
    };
    let weights: Vec<f64> = kept
        .iter()
        .map(|c| votes[c.action] * node_weight(c.next))
        .collect();
    let total: f64 = weights.iter().sum();
    kept.iter()
        .zip(weights)
        .map(|(c, w)| Choice {
            next: c.next,
            action: c.action,
            probability: w / total,
            logit: None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::Role;

    fn choice(next: usize, action: usize) -> Choice {
        Choice {
            next,
            action,
            probability: 0.25,
            logit: None,
        }
    }

    #[test]
    fn a_block_keeps_the_actions_with_enough_votes_in_proportion() {
        let support = [choice(0, 0), choice(0, 1), choice(1, 0), choice(1, 1)];
        // Action 1 has a twentieth of action 0's votes: below the share.
        let block = projected_block(&support, &[1.0, 0.05], 0, 2);
        let actions: Vec<(usize, usize)> = block.iter().map(|c| (c.next, c.action)).collect();
        assert_eq!(actions, [(0, 0), (1, 0)]);
        assert!((block[0].probability - (1.0 - INFORMED_NODE_MIX)).abs() < 1e-12);
        assert!((block[1].probability - INFORMED_NODE_MIX).abs() < 1e-12);
        // Both above the share: probabilities follow the votes.
        let block = projected_block(&support[..2], &[3.0, 1.0], 0, 1);
        assert!((block[0].probability - 0.75).abs() < 1e-12);
        assert!((block[1].probability - 0.25).abs() < 1e-12);
    }

    #[test]
    fn a_block_without_votes_keeps_its_support() {
        let support = [choice(0, 0), choice(0, 1)];
        assert_eq!(projected_block(&support, &[0.0, 0.0], 0, 1), support);
    }

    #[test]
    fn the_projection_is_a_controller_on_the_start_support() {
        let start = Fsc::uniform(Role::Defender, 2, 3, 2);
        let votes = vec![vec![1.0, 0.0], vec![0.0, 0.0], vec![0.5, 0.5]];
        let fsc = projected(&start, &votes).unwrap();
        assert_eq!(fsc.choices(1, 0).len(), 2); // action 0 to both nodes
        assert_eq!(fsc.choices(1, 1).len(), 4); // no votes: the start's block
        assert_eq!(fsc.choices(0, 2).len(), 4);
    }
}
