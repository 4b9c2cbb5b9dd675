//! The optimiser carries the result (method.md section 4): more defender
//! memory never certifies less, the informed starting point sees the goal
//! on a grid where the full and SAT supports start at 0, and the curve's
//! records end at the defender the run returns.

mod common;

use posg_fsc::game::file::from_json_str;
use posg_fsc::game::grid::{GridSpec, RandomUnsafe};
use posg_fsc::optimise::{RecordSource, Settings, Status, Structure, StructureSource};
use posg_fsc::pipeline::{self, Automata, Sizes};
use posg_fsc::value::evaluate_controllers;

/// Few iterations and starts, so that many random games run quickly.
fn quick_settings(grow_defender: bool) -> Settings {
    Settings {
        max_iterations: 15,
        starts: 2,
        local_search_restarts: 1,
        grow_defender,
        ..Settings::default()
    }
}

fn certified(
    game: &posg_fsc::game::Posg,
    automata: &Automata,
    nodes: usize,
    settings: &Settings,
) -> Option<f64> {
    let sizes = Sizes {
        defender: nodes,
        adversary: 1,
    };
    let outcome = pipeline::solve(game, automata, sizes, settings, pipeline::Unwatched).unwrap();
    assert_eq!(outcome.best().defender.num_nodes(), nodes);
    outcome.certified.map(|b| b.certified_lower)
}

/// Issue 62's grid family: `side` x `side`, the goal in the last cell and
/// a tenth of the cells unsafe at random (seed 1).
fn issue_grid(side: usize) -> posg_fsc::game::Posg {
    GridSpec {
        width: side,
        height: side,
        unsafe_cells: Vec::new(),
        goal_cells: vec![side * side - 1],
        random_unsafe: Some(RandomUnsafe {
            count: side * side / 10,
            seed: 1,
        }),
        ..GridSpec::default()
    }
    .build()
    .unwrap()
}

#[test]
fn a_larger_defender_certifies_at_least_what_a_smaller_one_does_on_random_games() {
    let settings = quick_settings(true);
    let mut compared = 0;
    for seed in 0..12 {
        let game = from_json_str(&common::random::game_json(seed), "random.posg.json").unwrap();
        for formula in ["!unsafe U goal", "GF goal & G !unsafe"] {
            let automata = Automata::from_ltl(formula).unwrap();
            let lower: Vec<Option<f64>> = (1..=3)
                .map(|k| certified(&game, &automata, k, &settings))
                .collect();
            for k in 1..lower.len() {
                if let (Some(smaller), Some(larger)) = (lower[k - 1], lower[k]) {
                    assert!(
                        larger >= smaller,
                        "seed {seed}, {formula}: {} nodes certify {larger}, {k} certify {smaller}",
                        k + 1
                    );
                    compared += 1;
                }
            }
        }
    }
    assert!(compared >= 20, "only {compared} pairs were certified");
}

#[test]
fn a_grown_run_reports_every_size_and_returns_the_size_asked() {
    let game = GridSpec::default().build().unwrap();
    let automata = Automata::from_ltl("GF goal & G !unsafe").unwrap();
    let settings = Settings {
        gap_tolerance: 0.0,
        ..quick_settings(true)
    };
    let sizes = Sizes {
        defender: 3,
        adversary: 1,
    };
    let outcome = pipeline::solve(&game, &automata, sizes, &settings, pipeline::Unwatched).unwrap();
    let nodes: Vec<usize> = outcome.sizes.iter().map(|s| s.defender_nodes).collect();
    assert_eq!(nodes, [1, 2, 3]);
    assert_eq!(outcome.best().defender.num_nodes(), 3);
    let lower: Vec<f64> = (outcome.sizes.iter())
        .map(|s| s.certified.unwrap().certified_lower)
        .collect();
    assert!(lower.windows(2).all(|w| w[1] >= w[0]), "{lower:?}");
    assert_eq!(outcome.certified, outcome.sizes[2].certified);
}

#[test]
fn the_informed_start_sees_the_goal_on_a_48_by_48_grid() {
    let game = issue_grid(48);
    let automata = Automata::from_ltl("GF goal & G !unsafe").unwrap();
    let solver = Settings::default().solver_settings();
    // The full support's value is exactly 0 there (every action is
    // possible, so an unsafe cell is reached almost surely).
    let full = Structure::full(&game, 2, 1, false);
    let (_, at_full) = evaluate_controllers(
        &game,
        &automata.phi,
        &full.defender,
        &full.adversary,
        &solver,
    )
    .unwrap();
    assert_eq!(at_full.value, 0.0);
    let settings = Settings {
        structures: vec![StructureSource::Informed],
        max_iterations: 1,
        starts: 1,
        round: false,
        local_search: false,
        restarts: 0,
        grow_defender: false,
        ..Settings::default()
    };
    let sizes = Sizes {
        defender: 2,
        adversary: 1,
    };
    let outcome = pipeline::solve(&game, &automata, sizes, &settings, pipeline::Unwatched).unwrap();
    let curve = (outcome.curves.iter())
        .find(|c| c.structure == "informed")
        .expect("an informed structure");
    let first = curve.records[0];
    assert_eq!(first.iteration, 0);
    assert!(
        first.value > 0.05,
        "the informed start's value is {}",
        first.value
    );
}

/// The records of the kept start of the structure a run returned, and the
/// summary's certified lower bound.
fn returned_curve(game: &posg_fsc::game::Posg, formula: &str, settings: &Settings) {
    let automata = Automata::from_ltl(formula).unwrap();
    let sizes = Sizes {
        defender: 1,
        adversary: 1,
    };
    let outcome = pipeline::solve(game, &automata, sizes, settings, pipeline::Unwatched).unwrap();
    let best = outcome.best();
    let curve = (outcome.curves.iter())
        .find(|c| c.structure == best.report.name)
        .unwrap();
    let certified = outcome.certified.unwrap().certified_lower;
    let largest = (curve.records.iter())
        .filter_map(|r| r.certified_lower)
        .fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(largest, certified);
    let last = curve.records.last().unwrap();
    assert!(last.returned);
    assert_eq!(last.certified_lower, Some(certified));
    assert_eq!(
        curve.records.iter().filter(|r| r.returned).count(),
        1,
        "one returned record"
    );
}

#[test]
fn the_curve_ends_at_the_returned_certified_value_on_the_papers_grid() {
    let game = GridSpec::default().build().unwrap();
    // On the paper's grid the returned defender comes from the local
    // search (the loop stops after its first iteration at about 0.29).
    let settings = Settings {
        structures: vec![StructureSource::Full],
        ..quick_settings(false)
    };
    let automata = Automata::from_ltl("!unsafe U goal").unwrap();
    let sizes = Sizes {
        defender: 1,
        adversary: 1,
    };
    let outcome = pipeline::solve(&game, &automata, sizes, &settings, pipeline::Unwatched).unwrap();
    let last = outcome.curves[0].records.last().unwrap();
    assert_eq!(last.source, RecordSource::LocalSearch);
    returned_curve(&game, "!unsafe U goal", &settings);
}

#[test]
fn the_curve_ends_at_the_returned_certified_value_on_random_games() {
    for seed in 0..6 {
        let game = from_json_str(&common::random::game_json(seed), "random.posg.json").unwrap();
        returned_curve(&game, "GF goal & G !unsafe", &quick_settings(false));
    }
}

#[test]
fn a_support_on_which_the_value_is_identically_zero_stops_the_loop_at_once() {
    let game = issue_grid(12);
    let settings = Settings {
        structures: vec![StructureSource::Full],
        max_iterations: 64,
        starts: 1,
        ..quick_settings(false)
    };
    let sizes = Sizes {
        defender: 1,
        adversary: 1,
    };
    let status_and_iterations = |formula: &str| -> Vec<(String, Status, usize)> {
        let automata = Automata::from_ltl(formula).unwrap();
        let outcome =
            pipeline::solve(&game, &automata, sizes, &settings, pipeline::Unwatched).unwrap();
        (outcome.solution.structures.iter())
            .map(|s| (s.report.name.clone(), s.report.status, s.report.iterations))
            .collect()
    };
    // Every action possible: an unsafe cell is reached almost surely, so
    // no phi-feasible BSCC is reachable on the full support.
    let safe = status_and_iterations("GF goal & G !unsafe");
    let full = &safe[0];
    assert_eq!((full.1, full.2), (Status::ZeroOnSupport, 1), "{safe:?}");
    // Reaching the goal first is possible on the full support: it runs.
    let reach = status_and_iterations("!unsafe U goal");
    assert!(
        reach
            .iter()
            .all(|(_, status, _)| *status != Status::ZeroOnSupport),
        "{reach:?}"
    );
}
