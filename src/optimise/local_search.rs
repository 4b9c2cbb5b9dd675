//! Local search over the supports of the defender on the certified lower bound
//! (method.md section 6, "Deterministic local search").
//!
//! The certified lower bound is not continuous where a choice leaves the
//! support: on an objective that must hold forever (a safety objective,
//! PAYNT's `Pmin=? [F "goal"]`), a choice kept at probability `exp(-2c)`
//! is taken infinitely often, and the all-seeing adversary makes it fatal,
//! while the controller without it may be safe. Softmax controllers cannot
//! reach that boundary, and their rounding reaches only the nearest
//! deterministic controller. This search starts at the best candidate and
//! changes one block `(g, o)` at a time, dropping a choice or playing one
//! enabled `(next node, action)` pair, keeping every change that raises the
//! certified lower bound (first improvement), until a sweep over all blocks
//! changes nothing or the deadline passes.

use std::time::Instant;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::automaton::Dra;
use crate::certify::{CertifyError, lower_value_or_trivial};
use crate::controller::{Choice, Fsc, Role};
use crate::game::{AdversaryAction, DefenderAction, Posg};

/// A move counts as an improvement only when the bound rises by more
/// than this (bounds are accurate to the solver's tolerance, 1e-9).
const IMPROVEMENT: f64 = 1e-8;

/// Hill-climbs from the defender `start` on the certified lower bound (the
/// trivial 0 where a product mixes too slowly to certify): the moves in a
/// block `(g, o)` are dropping one of its choices (the others
/// renormalised) and playing one enabled `(next node, action)` pair of
/// `game`'s defender with probability 1. Stops after a sweep over all
/// blocks without a change or at `deadline`; returns where it stopped.
pub fn climb(
    game: &Posg,
    not_phi: &Dra,
    start: &Fsc,
    deadline: Option<Instant>,
) -> Result<Fsc, CertifyError> {
    let universe = Fsc::uniform_enabled(Role::Defender, start.num_nodes(), game.defender());
    let mut current = start.clone();
    let mut bound = lower_value_or_trivial(game, not_phi, &current)?;
    let past = || deadline.is_some_and(|end| Instant::now() >= end);
    let mut visited = visited_blocks(game, &current);
    'sweeps: loop {
        let mut changed = false;
        for b in 0..current.blocks.len() {
            if !visited[b] {
                continue;
            }
            let mut better = None;
            for candidate in moves(&current, b, &universe.blocks[b]) {
                if past() {
                    break 'sweeps;
                }
                let value = lower_value_or_trivial(game, not_phi, &candidate)?;
                if value > bound + IMPROVEMENT {
                    better = Some((candidate, value));
                    break;
                }
            }
            if let Some((candidate, value)) = better {
                (current, bound, changed) = (candidate, value, true);
                visited = visited_blocks(game, &current);
            }
        }
        if !changed {
            break;
        }
    }
    Ok(current)
}

/// The controllers one move away from `fsc` in block `b`: each choice
/// dropped (if the block has several), then each of `pairs` alone (unless
/// the block is already that pair alone).
fn moves<'a>(fsc: &'a Fsc, b: usize, pairs: &'a [Choice]) -> impl Iterator<Item = Fsc> + 'a {
    let block = &fsc.blocks[b];
    let drops = (0..block.len())
        .filter(move |_| block.len() > 1)
        .map(move |dropped| {
            let kept = block.iter().enumerate().filter(|&(i, _)| i != dropped);
            let total: f64 = kept.clone().map(|(_, c)| c.probability).sum();
            let renormalised = kept
                .map(|(_, c)| Choice {
                    probability: c.probability / total,
                    logit: None,
                    ..*c
                })
                .collect();
            with_block(fsc, b, renormalised)
        });
    let singles = pairs
        .iter()
        .filter(move |pair| {
            !(block.len() == 1 && (block[0].next, block[0].action) == (pair.next, pair.action))
        })
        .map(move |pair| {
            let single = Choice {
                probability: 1.0,
                logit: None,
                ..*pair
            };
            with_block(fsc, b, vec![single])
        });
    drops.chain(singles)
}

/// [`climb`] from `start` for at most half the time to `deadline`, then
/// from random memoryless deterministic defenders (each block `(g, o)` one
/// enabled pair `(g, u)`, `u` uniformly drawn from `rng`; the climb adds
/// memory) until `deadline`; returns the end point with the highest
/// certified lower bound.
pub fn climb_with_restarts(
    game: &Posg,
    not_phi: &Dra,
    start: &Fsc,
    rng: &mut ChaCha8Rng,
    deadline: Instant,
) -> Result<Fsc, CertifyError> {
    let universe = Fsc::uniform_enabled(Role::Defender, start.num_nodes(), game.defender());
    let now = Instant::now();
    let halfway = now + deadline.saturating_duration_since(now) / 2;
    let mut best = climb(game, not_phi, start, Some(halfway))?;
    let mut best_bound = lower_value_or_trivial(game, not_phi, &best)?;
    while Instant::now() < deadline {
        let mut random = start.clone();
        // Memoryless draws: every block keeps its node (the climb adds memory).
        let observations = random.num_observations();
        for (b, (block, pairs)) in random.blocks.iter_mut().zip(&universe.blocks).enumerate() {
            let stay: Vec<&Choice> = pairs
                .iter()
                .filter(|p| p.next == b / observations)
                .collect();
            let pair = *stay[rng.random_range(0..stay.len())];
            *block = vec![Choice {
                probability: 1.0,
                logit: None,
                ..pair
            }];
        }
        let end = climb(game, not_phi, &random, Some(deadline))?;
        let bound = lower_value_or_trivial(game, not_phi, &end)?;
        if bound > best_bound {
            (best, best_bound) = (end, bound);
        }
    }
    Ok(best)
}

/// Which blocks `(g, o)` of the defender `fsc` can be used in `game`
/// against any adversary: those of the pairs `(s, g)` reachable from the
/// initial states and nodes, where `o` is an observation of `s`. A move in
/// any other block changes no value.
fn visited_blocks(game: &Posg, fsc: &Fsc) -> Vec<bool> {
    let nodes = fsc.num_nodes();
    let observations = fsc.num_observations();
    let mut seen = vec![false; game.num_states() * nodes];
    let mut blocks = vec![false; nodes * observations];
    let mut stack: Vec<(usize, usize)> = Vec::new();
    let mut visit = |s: usize, g: usize, stack: &mut Vec<(usize, usize)>| {
        if !std::mem::replace(&mut seen[s * nodes + g], true) {
            stack.push((s, g));
        }
    };
    for &(s, _) in game.initial() {
        for (g, _) in fsc.initial().iter().enumerate().filter(|(_, p)| **p > 0.0) {
            visit(s, g, &mut stack);
        }
    }
    let adversary_actions = game.adversary().num_actions();
    while let Some((s, g)) = stack.pop() {
        for &(o, _) in game.defender().observation_distribution(s) {
            blocks[g * observations + o] = true;
            for choice in fsc.choices(g, o) {
                for v in 0..adversary_actions {
                    let moves =
                        game.transition(s, DefenderAction(choice.action), AdversaryAction(v));
                    for &(t, _) in moves {
                        visit(t, choice.next, &mut stack);
                    }
                }
            }
        }
    }
    blocks
}

/// `fsc` with block `b` replaced by `choices`.
fn with_block(fsc: &Fsc, b: usize, choices: Vec<Choice>) -> Fsc {
    let mut changed = fsc.clone();
    changed.blocks[b] = choices;
    changed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::game::grid::GridSpec;
    use crate::optimise::truncated;
    use crate::pipeline::Automata;

    /// From the worst deterministic start (every block on the first enabled
    /// pair) on a 4x4 grid, the climb raises the bound and ends at a
    /// deterministic controller that no single change certifies higher.
    #[test]
    fn the_climb_ends_at_a_deterministic_local_optimum_of_the_bound() {
        let game = GridSpec {
            width: 4,
            height: 4,
            unsafe_cells: vec![5, 10],
            goal_cells: vec![15],
            ..GridSpec::default()
        }
        .build()
        .unwrap();
        let not_phi = Automata::from_ltl("!unsafe U goal")
            .unwrap()
            .not_phi
            .unwrap();
        let uniform = Fsc::uniform_enabled(Role::Defender, 1, game.defender());
        let start = truncated(&uniform, f64::INFINITY).unwrap();
        let before = lower_value_or_trivial(&game, &not_phi, &start).unwrap();
        let found = climb(&game, &not_phi, &start, None).unwrap();
        let reached = lower_value_or_trivial(&game, &not_phi, &found).unwrap();
        assert!(reached > before + 0.1, "{before} -> {reached}");
        assert!(found.blocks.iter().all(|block| block.len() == 1));
        for (b, pairs) in uniform.blocks.iter().enumerate() {
            for neighbour in moves(&found, b, pairs) {
                let value = lower_value_or_trivial(&game, &not_phi, &neighbour).unwrap();
                assert!(value <= reached + IMPROVEMENT, "block {b}: {value}");
            }
        }
    }

    /// The restarts keep the best end point: on the 4x4 grid from the worst
    /// start it certifies at least what the climb from that start reaches,
    /// and it is deterministic (restarts are memoryless, the climb may add
    /// memory; here the controller has 2 nodes).
    #[test]
    fn restarts_keep_the_best_end_point() {
        use rand::SeedableRng;
        let game = GridSpec {
            width: 4,
            height: 4,
            unsafe_cells: vec![5, 10],
            goal_cells: vec![15],
            ..GridSpec::default()
        }
        .build()
        .unwrap();
        let not_phi = Automata::from_ltl("!unsafe U goal")
            .unwrap()
            .not_phi
            .unwrap();
        let uniform = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let start = truncated(&uniform, f64::INFINITY).unwrap();
        let climbed = climb(&game, &not_phi, &start, None).unwrap();
        let alone = lower_value_or_trivial(&game, &not_phi, &climbed).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let deadline = Instant::now() + std::time::Duration::from_millis(300);
        let best = climb_with_restarts(&game, &not_phi, &start, &mut rng, deadline).unwrap();
        let reached = lower_value_or_trivial(&game, &not_phi, &best).unwrap();
        assert!(reached >= alone - 1e-12, "{reached} below {alone}");
        assert!(best.blocks.iter().all(|block| block.len() == 1));
    }
}
