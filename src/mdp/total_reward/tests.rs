//! The optimum against every deterministic memoryless strategy of random
//! MDPs, and values on paper.

use super::super::tests::mdp;
use super::*;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn settings() -> SolverSettings {
    SolverSettings::default()
}

/// State 0 may go on (action 0: to 1, reward 2) or gamble (action 1:
/// the target 2 or back to 0, half each, reward 1); 1 goes to the
/// target with reward 3 or back to 0 with probability 1/4. On paper,
/// with `x1 = 3 + x0 / 4`: on, `x0 = 2 + x1 = 5 + x0 / 4`, `x0 = 20/3`;
/// gamble, `x0 = 1 + x0 / 2`, `x0 = 2`. The maximum is 20/3 (and
/// `x1 = 14/3`), the minimum 2 (and `x1 = 3.5`).
fn on_or_gamble() -> (Mdp, Vec<bool>, Vec<f64>) {
    let m = mdp(&[
        &[&[(1, 1.0)], &[(2, 0.5), (0, 0.5)]],
        &[&[(2, 0.75), (0, 0.25)]],
        &[&[(2, 1.0)]],
    ]);
    (m, vec![false, false, true], vec![2.0, 1.0, 3.0, 0.0])
}

#[test]
fn the_optima_of_a_small_mdp_are_those_on_paper() {
    let (m, target, rewards) = on_or_gamble();
    let max = optimal_total_reward(&m, &target, &rewards, Optimum::Max, &settings()).unwrap();
    let min = optimal_total_reward(&m, &target, &rewards, Optimum::Min, &settings()).unwrap();
    for (bracket, expected) in [
        ((max.lower[0], max.upper[0]), 20.0 / 3.0),
        ((max.lower[1], max.upper[1]), 14.0 / 3.0),
        ((min.lower[0], min.upper[0]), 2.0),
        ((min.lower[1], min.upper[1]), 3.5),
    ] {
        assert!(
            bracket.0 <= expected && expected <= bracket.1,
            "{bracket:?} {expected}"
        );
        assert!(bracket.1 - bracket.0 < 1e-9, "{bracket:?}");
    }
    assert_eq!((max.strategy[0], min.strategy[0]), (0, 1));
    assert_eq!((max.lower[2], max.upper[2]), (0.0, 0.0));
}

/// State 0 may loop (action 0) or go to the target (action 1). The
/// maximum is infinite (looping misses the target); the minimum is
/// action 1's reward where the loop earns a positive reward or nothing
/// (collapsed: staying forever is not a way out), and refused where it
/// loses (the minimum is `-inf`).
#[test]
fn a_loop_makes_the_maximum_infinite_and_the_minimum_refused_unless_it_costs() {
    let m = mdp(&[&[&[(0, 1.0)], &[(1, 1.0)]], &[&[(1, 1.0)]]]);
    let target = [false, true];
    let max = optimal_total_reward(&m, &target, &[1.0, 5.0, 0.0], Optimum::Max, &settings());
    assert_eq!(
        max.unwrap().of_initial(&[(0, 1.0)]),
        (f64::INFINITY, f64::INFINITY)
    );
    let min = optimal_total_reward(&m, &target, &[1.0, 5.0, 0.0], Optimum::Min, &settings());
    let (low, high) = min.unwrap().of_initial(&[(0, 1.0)]);
    assert!(low <= 5.0 && 5.0 <= high && high - low < 1e-9);
    let free = optimal_total_reward(&m, &target, &[0.0, 5.0, 0.0], Optimum::Min, &settings());
    let free = free.unwrap();
    assert_eq!(free.strategy[0], 1);
    let (low, high) = free.of_initial(&[(0, 1.0)]);
    assert!(low <= 5.0 && 5.0 <= high && high - low < 1e-9);
    let losing = [-1.0, 5.0, 0.0];
    let min = optimal_total_reward(&m, &target, &losing, Optimum::Min, &settings());
    assert!(matches!(min, Err(MdpError::RewardCycle(_))), "{min:?}");
}

/// State 0 moves to 1 for nothing (action 0) or pays 10 for the target
/// (action 1); 1 moves back to 0 for 1 (action 0) or pays 5 for the
/// target (action 1). Every round of the cycle earns 1, though one of
/// its actions earns nothing: the minimum is attained, 5 from both.
#[test]
fn a_free_action_on_a_cycle_that_costs_is_accepted() {
    let m = mdp(&[
        &[&[(1, 1.0)], &[(2, 1.0)]],
        &[&[(0, 1.0)], &[(2, 1.0)]],
        &[&[(2, 1.0)]],
    ]);
    let rewards = [0.0, 10.0, 1.0, 5.0, 0.0];
    let min = optimal_total_reward(
        &m,
        &[false, false, true],
        &rewards,
        Optimum::Min,
        &settings(),
    )
    .unwrap();
    for s in 0..2 {
        assert!(min.lower[s] <= 5.0 && 5.0 <= min.upper[s], "{min:?}");
        assert!(min.upper[s] - min.lower[s] < 1e-9, "{min:?}");
    }
    assert_eq!(min.strategy[..2], [0, 1]);
}

/// A random MDP: `n` states, the last one the target (absorbing), each
/// other with 1 to 3 actions of 1 to 3 successors, and a reward per
/// action drawn from `rewards`.
fn random_mdp(seed: u64, n: usize, rewards: (f64, f64)) -> (Mdp, Vec<bool>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut actions: Vec<Vec<Vec<(usize, f64)>>> = Vec::new();
    for _ in 0..n - 1 {
        let k = rng.random_range(1..=3);
        actions.push(
            (0..k)
                .map(|_| {
                    let successors = rng.random_range(1..=3);
                    let weights: Vec<(usize, f64)> = (0..successors)
                        .map(|_| (rng.random_range(0..n), rng.random_range(1..=4) as f64))
                        .collect();
                    let total: f64 = weights.iter().map(|w| w.1).sum();
                    weights.iter().map(|&(t, w)| (t, w / total)).collect()
                })
                .collect(),
        );
    }
    actions.push(vec![vec![(n - 1, 1.0)]]);
    let borrowed: Vec<Vec<&[(usize, f64)]>> = actions
        .iter()
        .map(|state| state.iter().map(Vec::as_slice).collect())
        .collect();
    let nested: Vec<&[&[(usize, f64)]]> = borrowed.iter().map(Vec::as_slice).collect();
    let m = mdp(&nested);
    let mut target = vec![false; n];
    target[n - 1] = true;
    let r = (0..m.num_state_actions())
        .map(|_| (rng.random_range(rewards.0..rewards.1) * 4.0).round() / 4.0)
        .collect();
    (m, target, r)
}

/// The value of every deterministic memoryless strategy by Gaussian
/// elimination (`+inf` where it misses the target with positive
/// probability), then the optimum per state: independent of the
/// policy iteration and of the graph analyses above.
fn brute_force(m: &Mdp, target: &[bool], rewards: &[f64], optimum: Optimum) -> Vec<f64> {
    let n = m.num_states();
    let mut best = vec![
        match optimum {
            Optimum::Max => f64::NEG_INFINITY,
            Optimum::Min => f64::INFINITY,
        };
        n
    ];
    let mut choice = vec![0; n];
    loop {
        let values = strategy_values(m, target, rewards, &choice);
        for s in 0..n {
            best[s] = match optimum {
                Optimum::Max => best[s].max(values[s]),
                Optimum::Min => best[s].min(values[s]),
            };
        }
        let Some(s) = (0..n).find(|&s| choice[s] + 1 < m.num_actions(s)) else {
            return best;
        };
        choice[s] += 1;
        choice[..s].fill(0);
    }
}

fn strategy_values(m: &Mdp, target: &[bool], rewards: &[f64], choice: &[usize]) -> Vec<f64> {
    let n = m.num_states();
    // The states that reach the target surely: those from which every
    // path that avoids the target can still reach it.
    let mut reaches = target.to_vec();
    loop {
        let before = reaches.clone();
        for s in 0..n {
            reaches[s] |= m
                .distribution(s, choice[s])
                .iter()
                .any(|&(t, _)| reaches[t]);
        }
        if reaches == before {
            break;
        }
    }
    let mut sure: Vec<bool> = reaches.clone();
    loop {
        let before = sure.clone();
        for s in (0..n).filter(|&s| !target[s]) {
            sure[s] &= m.distribution(s, choice[s]).iter().all(|&(t, _)| sure[t]);
        }
        if sure == before {
            break;
        }
    }
    let unknowns: Vec<usize> = (0..n).filter(|&s| sure[s] && !target[s]).collect();
    let k = unknowns.len();
    let mut a = vec![vec![0.0; k + 1]; k];
    for (i, &s) in unknowns.iter().enumerate() {
        a[i][i] += 1.0;
        a[i][k] = rewards[m.global_actions(s).start + choice[s]];
        for &(t, p) in m.distribution(s, choice[s]) {
            if let Some(j) = unknowns.iter().position(|&u| u == t) {
                a[i][j] -= p;
            }
        }
    }
    for col in 0..k {
        let pivot = (col..k)
            .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
            .unwrap();
        a.swap(col, pivot);
        let pivot_row = a[col].clone();
        for (_, entries) in a.iter_mut().enumerate().filter(|&(row, _)| row != col) {
            let factor = entries[col] / pivot_row[col];
            for (entry, &p) in entries[col..].iter_mut().zip(&pivot_row[col..]) {
                *entry -= factor * p;
            }
        }
    }
    let mut values: Vec<f64> = (0..n)
        .map(|s| if target[s] { 0.0 } else { f64::INFINITY })
        .collect();
    for (i, &s) in unknowns.iter().enumerate() {
        values[s] = a[i][k] / a[i][i];
    }
    values
}

fn assert_brackets(result: &TotalReward, expected: &[f64]) {
    for (s, &e) in expected.iter().enumerate() {
        let (low, high) = (result.lower[s], result.upper[s]);
        if e.is_infinite() {
            assert!(
                low.is_infinite() && high.is_infinite(),
                "state {s}: {low} {high} {e}"
            );
        } else {
            let slack = 1e-9 * e.abs().max(1.0);
            assert!(
                low <= e + slack && e <= high + slack,
                "state {s}: [{low}, {high}] {e}"
            );
            assert!(
                high - low <= 1e-7 * e.abs().max(1.0),
                "state {s}: [{low}, {high}]"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn the_maximum_is_the_best_strategy_s(seed in any::<u64>(), n in 2usize..7) {
        let (m, target, rewards) = random_mdp(seed, n, (-2.0, 3.0));
        let result = optimal_total_reward(&m, &target, &rewards, Optimum::Max, &settings()).unwrap();
        assert_brackets(&result, &brute_force(&m, &target, &rewards, Optimum::Max));
    }

    #[test]
    fn the_minimum_of_positive_rewards_is_the_best_strategy_s(seed in any::<u64>(), n in 2usize..7) {
        let (m, target, rewards) = random_mdp(seed, n, (0.25, 3.0));
        let result = optimal_total_reward(&m, &target, &rewards, Optimum::Min, &settings()).unwrap();
        assert_brackets(&result, &brute_force(&m, &target, &rewards, Optimum::Min));
    }

    /// Rewards of 0 a third of the time: the free end components are
    /// collapsed, and nothing is refused.
    #[test]
    fn the_minimum_of_rewards_that_never_lose_is_the_best_strategy_s(seed in any::<u64>(), n in 2usize..7) {
        let (m, target, rewards) = random_mdp(seed, n, (-1.0, 2.0));
        let rewards: Vec<f64> = rewards.iter().map(|r| r.max(0.0)).collect();
        let result = optimal_total_reward(&m, &target, &rewards, Optimum::Min, &settings()).unwrap();
        assert_brackets(&result, &brute_force(&m, &target, &rewards, Optimum::Min));
        let played = strategy_values(&m, &target, &rewards, &result.strategy);
        assert_brackets(&result, &played);
    }

    #[test]
    fn a_minimum_of_either_sign_is_right_or_refused(seed in any::<u64>(), n in 2usize..7) {
        let (m, target, rewards) = random_mdp(seed, n, (-2.0, 3.0));
        match optimal_total_reward(&m, &target, &rewards, Optimum::Min, &settings()) {
            Ok(result) => assert_brackets(&result, &brute_force(&m, &target, &rewards, Optimum::Min)),
            Err(e) => prop_assert!(matches!(e, MdpError::RewardCycle(_)), "{e}"),
        }
    }
}
