//! The grid family (`game::grid`): the paper's 3 x 2 instance checked by hand,
//! row sums, degenerate grids, labels, random unsafe cells and the JSON round trip.

use posg_fsc::game::file::{from_json_str, read, to_json_string};
use posg_fsc::game::grid::{GridSpec, ObservationModel, RandomUnsafe};
use posg_fsc::game::{AdversaryAction, DefenderAction, Posg};

const R: usize = 0;
const L: usize = 1;
const U: usize = 2;
const D: usize = 3;
const A: usize = 0;
const NA: usize = 1;

fn sorted(row: &[(usize, f64)]) -> Vec<(usize, f64)> {
    let mut r = row.to_vec();
    r.sort_by_key(|e| e.0);
    r
}

fn assert_row(game: &Posg, s: usize, u: usize, v: usize, expected: &[(usize, f64)]) {
    let row = sorted(game.transition(s, DefenderAction(u), AdversaryAction(v)));
    assert_eq!(row.len(), expected.len(), "T(.|s{s},{u},{v}) = {row:?}");
    for (&(c, p), &(ec, ep)) in row.iter().zip(expected) {
        assert_eq!(c, ec, "T(.|s{s},{u},{v}) = {row:?}");
        assert!((p - ep).abs() < 1e-12, "T(.|s{s},{u},{v}) = {row:?}");
    }
}

fn assert_rows_sum_to_one(game: &Posg) {
    let (nu, nv) = (
        game.defender().num_actions(),
        game.adversary().num_actions(),
    );
    for s in 0..game.num_states() {
        for u in 0..nu {
            for v in 0..nv {
                let total: f64 = game
                    .transition(s, DefenderAction(u), AdversaryAction(v))
                    .iter()
                    .map(|e| e.1)
                    .sum();
                assert!(
                    (total - 1.0).abs() < 1e-12,
                    "T(.|{s},{u},{v}) sums to {total}"
                );
            }
        }
        for player in [game.defender(), game.adversary()] {
            let total: f64 = player.observation_distribution(s).iter().map(|e| e.1).sum();
            assert!((total - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn paper_instance_shape_and_labels() {
    let g = GridSpec::default().build().unwrap();
    assert_eq!(g.name(), Some("grid-3x2"));
    assert_eq!(g.states(), ["s0", "s1", "s2", "s3", "s4", "s5"]);
    assert_eq!(g.defender().actions(), ["R", "L", "U", "D"]);
    assert_eq!(g.adversary().actions(), ["A", "NA"]);
    assert_eq!(g.initial(), &[(0, 1.0)]);
    assert_eq!(g.propositions(), ["goal", "unsafe"]);
    assert_eq!(g.label_names(4).collect::<Vec<_>>(), ["unsafe"]);
    assert_eq!(g.label_names(5).collect::<Vec<_>>(), ["goal"]);
    assert!(g.label(0).is_empty());
    assert!(g.has_adversary());
    assert_rows_sum_to_one(&g);
}

#[test]
fn paper_instance_transitions_by_hand() {
    let g = GridSpec::default().build().unwrap();
    // Grid:  s0 s1 s2
    //        s3 s4 s5
    assert_row(&g, 0, R, NA, &[(0, 0.1), (1, 0.8), (3, 0.1)]);
    assert_row(&g, 0, R, A, &[(0, 0.2), (1, 0.6), (3, 0.2)]);
    assert_row(&g, 0, L, NA, &[(0, 1.0)]);
    assert_row(&g, 0, U, A, &[(0, 1.0)]);
    // s4 has neighbours s3, s5, s1: D leaves the grid, U goes to s1.
    assert_row(&g, 4, D, A, &[(4, 1.0)]);
    let third = 0.2 / 3.0;
    assert_row(
        &g,
        4,
        U,
        NA,
        &[(1, 0.8), (3, third), (4, third), (5, third)],
    );
    assert_row(
        &g,
        4,
        R,
        A,
        &[(1, 0.4 / 3.0), (3, 0.4 / 3.0), (4, 0.4 / 3.0), (5, 0.6)],
    );
    assert_row(&g, 5, L, NA, &[(2, 0.1), (4, 0.8), (5, 0.1)]);
}

#[test]
fn paper_instance_observations() {
    let g = GridSpec::default().build().unwrap();
    assert_eq!(g.defender().observations(), g.states());
    assert_row_like(
        g.defender().observation_distribution(0),
        &[(0, 0.8), (1, 0.1), (3, 0.1)],
    );
    assert_row_like(
        g.adversary().observation_distribution(0),
        &[(0, 0.6), (1, 0.2), (3, 0.2)],
    );
    assert_row_like(
        g.defender().observation_distribution(4),
        &[(1, 0.2 / 3.0), (3, 0.2 / 3.0), (4, 0.8), (5, 0.2 / 3.0)],
    );
}

fn assert_row_like(row: &[(usize, f64)], expected: &[(usize, f64)]) {
    let row = sorted(row);
    assert_eq!(row.len(), expected.len(), "{row:?}");
    for (&(c, p), &(ec, ep)) in row.iter().zip(expected) {
        assert_eq!(c, ec, "{row:?}");
        assert!((p - ep).abs() < 1e-12, "{row:?}");
    }
}

#[test]
fn blind_observation_model_is_two_symbols() {
    let spec = GridSpec {
        observation: ObservationModel::Blind,
        ..GridSpec::default()
    };
    let g = spec.build().unwrap();
    assert_eq!(g.defender().observations(), ["correct", "wrong"]);
    for s in 0..6 {
        assert_row_like(
            g.defender().observation_distribution(s),
            &[(0, 0.8), (1, 0.2)],
        );
        assert_row_like(
            g.adversary().observation_distribution(s),
            &[(0, 0.6), (1, 0.4)],
        );
    }
}

#[test]
fn one_by_one_grid_stays_put() {
    let spec = GridSpec {
        width: 1,
        height: 1,
        unsafe_cells: vec![],
        goal_cells: vec![0],
        ..GridSpec::default()
    };
    let g = spec.build().unwrap();
    for u in 0..4 {
        for v in 0..2 {
            assert_eq!(
                g.transition(0, DefenderAction(u), AdversaryAction(v)),
                &[(0, 1.0)]
            );
        }
    }
    assert_eq!(g.defender().observation_distribution(0), &[(0, 1.0)]);
}

#[test]
fn one_by_three_grid() {
    let spec = GridSpec {
        width: 1,
        height: 3,
        unsafe_cells: vec![1],
        goal_cells: vec![2],
        ..GridSpec::default()
    };
    let g = spec.build().unwrap();
    assert_rows_sum_to_one(&g);
    // s0 has the single neighbour s1: moving down succeeds or stays.
    assert_row(&g, 0, D, NA, &[(0, 0.2), (1, 0.8)]);
    assert_row(&g, 0, R, NA, &[(0, 1.0)]);
    assert_row(&g, 1, U, A, &[(0, 0.6), (1, 0.2), (2, 0.2)]);
}

#[test]
fn certain_moves_drop_zero_entries() {
    let spec = GridSpec {
        p_na: 1.0,
        defender_p_obs: 1.0,
        ..GridSpec::default()
    };
    let g = spec.build().unwrap();
    assert_eq!(
        g.transition(0, DefenderAction(R), AdversaryAction(NA)),
        &[(1, 1.0)]
    );
    assert_eq!(g.defender().observation_distribution(2), &[(2, 1.0)]);
}

#[test]
fn extra_labels_and_their_checks() {
    let spec = GridSpec {
        extra_labels: vec![("checkpoint".into(), vec![2, 4])],
        ..GridSpec::default()
    };
    let g = spec.build().unwrap();
    assert_eq!(g.propositions(), ["checkpoint", "goal", "unsafe"]);
    assert_eq!(
        g.label_names(4).collect::<Vec<_>>(),
        ["checkpoint", "unsafe"]
    );
    let bad = GridSpec {
        extra_labels: vec![("Bad".into(), vec![1])],
        ..GridSpec::default()
    };
    assert!(
        bad.build()
            .unwrap_err()
            .message
            .contains("not a valid proposition")
    );
    let twice = GridSpec {
        extra_labels: vec![("goal".into(), vec![1])],
        ..GridSpec::default()
    };
    assert!(twice.build().unwrap_err().message.contains("given twice"));
}

#[test]
fn invalid_specs_are_errors() {
    let empty = GridSpec {
        width: 0,
        ..GridSpec::default()
    };
    assert!(empty.build().unwrap_err().message.contains("no cells"));
    let outside = GridSpec {
        goal_cells: vec![6],
        ..GridSpec::default()
    };
    assert_eq!(
        outside.build().unwrap_err().message,
        "goal cell 6 is outside the 6 cells"
    );
    let p = GridSpec {
        p_a: 1.5,
        ..GridSpec::default()
    };
    assert!(p.build().unwrap_err().message.contains("p_a = 1.5"));
    let crowded = GridSpec {
        random_unsafe: Some(RandomUnsafe { count: 4, seed: 1 }),
        ..GridSpec::default()
    };
    assert!(
        crowded
            .build()
            .unwrap_err()
            .message
            .contains("only 3 cells are free")
    );
}

#[test]
fn random_unsafe_cells_are_reproducible_and_avoid_start_and_goal() {
    let spec = GridSpec {
        width: 10,
        height: 10,
        unsafe_cells: vec![],
        goal_cells: vec![99],
        random_unsafe: Some(RandomUnsafe { count: 97, seed: 7 }),
        ..GridSpec::default()
    };
    let a = spec.build().unwrap();
    assert_eq!(a, spec.build().unwrap());
    let unsafe_id = a.propositions().iter().position(|p| p == "unsafe").unwrap();
    let unsafe_cells: Vec<usize> = (0..100)
        .filter(|&s| a.label(s).contains(&unsafe_id))
        .collect();
    assert_eq!(unsafe_cells.len(), 97);
    assert!(!unsafe_cells.contains(&0) && !unsafe_cells.contains(&99));
    let few = GridSpec {
        random_unsafe: Some(RandomUnsafe { count: 5, seed: 7 }),
        ..spec.clone()
    };
    let other = GridSpec {
        random_unsafe: Some(RandomUnsafe { count: 5, seed: 8 }),
        ..spec
    };
    assert_ne!(few.build().unwrap(), other.build().unwrap());
}

#[test]
fn grid_round_trips_through_json() {
    for spec in [
        GridSpec::default(),
        GridSpec {
            observation: ObservationModel::Blind,
            ..GridSpec::default()
        },
        GridSpec {
            width: 7,
            height: 5,
            random_unsafe: Some(RandomUnsafe { count: 6, seed: 3 }),
            ..GridSpec::default()
        },
    ] {
        let g = spec.build().unwrap();
        assert_eq!(
            from_json_str(&to_json_string(&g), "grid.posg.json").unwrap(),
            g
        );
    }
}

#[test]
fn shipped_grid_file_is_the_default_grid() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/valid/grid-3x2.posg.json"
    );
    assert_eq!(
        read(std::path::Path::new(path)).unwrap(),
        GridSpec::default().build().unwrap()
    );
}

/// 512 x 512 cells (the largest size the family is meant for) with random
/// unsafe cells: built directly, in well under a second with optimisations.
#[test]
fn large_grid_builds() {
    let spec = GridSpec {
        width: 512,
        height: 512,
        unsafe_cells: vec![],
        goal_cells: vec![262_143],
        random_unsafe: Some(RandomUnsafe {
            count: 5000,
            seed: 1,
        }),
        ..GridSpec::default()
    };
    let start = std::time::Instant::now();
    let g = spec.build().unwrap();
    eprintln!("512x512 grid built in {:?}", start.elapsed());
    assert_eq!(g.num_states(), 262_144);
    assert_row(&g, 262_143, R, NA, &[(262_143, 1.0)]);
    assert_row(
        &g,
        513,
        L,
        NA,
        &[
            (1, 0.05),
            (512, 0.8),
            (513, 0.05),
            (514, 0.05),
            (1025, 0.05),
        ],
    );
}
