//! Issue 12: the optimiser converges and never loses what it had. Matrix
//! games whose max-min value is derived by hand are certified within 1e-3;
//! rounding never returns a worse controller; the support never changes
//! while optimising and the linear systems stay accurate; warm-started
//! sweeps are monotone in the defender's size.

mod common;

use std::process::Command;

use posg_fsc::automaton::Dra;
use posg_fsc::certify::belief::UpperBoundsOnce;
use posg_fsc::certify::lower_bound;
use posg_fsc::controller::{Choice, Fsc, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::optimise::{
    Cancel, IterationRecord, Method, Observer, SearchRecord, Settings, Status, Structure, embed,
    keep_better, optimise_structure, pad, rounded_candidates, score, truncated, warm_started,
};
use posg_fsc::value::SolverSettings;
use posg_fsc::value::evaluate_controllers;
use proptest::prelude::*;

fn game(text: &str) -> Posg {
    from_json_str(text, "test.posg.json").unwrap()
}

/// Automata for `formula` and its negation.
fn automata(formula: &str) -> (Dra, Dra) {
    let parsed = posg_fsc::ltl::parse(formula).unwrap();
    (
        posg_fsc::ltl::translate(&parsed).unwrap(),
        posg_fsc::ltl::translate(&parsed.negate()).unwrap(),
    )
}

/// One state; the defender picks row H or T, the adversary column H or T,
/// and the goal is reached with probability `[[a, b], [c, d]][row][column]`.
fn matrix_game(a: f64, b: f64, c: f64, d: f64) -> Posg {
    let entries = [("H", "H", a), ("H", "T", b), ("T", "H", c), ("T", "T", d)];
    let mut transitions: Vec<String> = entries
        .iter()
        .map(|(u, v, p)| {
            format!(
                r#"{{"state": "s", "defender": "{u}", "adversary": "{v}", "next": {{"goal": {p}, "trap": {}}}}}"#,
                1.0 - p
            )
        })
        .collect();
    for t in ["goal", "trap"] {
        transitions.push(format!(
            r#"{{"state": "{t}", "defender": "*", "adversary": "*", "next": {{"{t}": 1.0}}}}"#
        ));
    }
    game(&format!(
        r#"{{"posg": 1, "states": ["s", "goal", "trap"], "initial": {{"s": 1.0}},
            "labels": {{"goal": ["goal"]}},
            "defender": {{"actions": ["H", "T"], "observe": "full"}},
            "adversary": {{"actions": ["H", "T"], "observe": "full"}},
            "transitions": [{}]}}"#,
        transitions.join(",")
    ))
}

/// A 2x2 matrix game without a saddle in pure strategies has value
/// `(ad - bc) / (a + d - b - c)`, the defender playing H with probability
/// `(d - c) / (a + d - b - c)`.
#[test]
fn solve_certifies_hand_solved_matrix_games_within_1e_3() {
    let (phi, not_phi) = automata("F goal");
    // Matching pennies: value 1/2, H with 1/2; and [[0.9, 0.2], [0.3, 0.6]]:
    // value (0.54 - 0.06) / (1.5 - 0.5) = 0.48, H with 0.3 / 1.0 = 0.3.
    for (matrix, value, heads) in [
        ([1.0, 0.0, 0.0, 1.0], 0.5, 0.5),
        ([0.9, 0.2, 0.3, 0.6], 0.48, 0.3),
    ] {
        let [a, b, c, d] = matrix;
        let g = matrix_game(a, b, c, d);
        let found = common::solve_one_node(&g, &phi, Some(&not_phi), &Settings::default()).unwrap();
        let best = found.best();
        let lower = best.report.certified_lower.unwrap();
        let upper = best.report.upper_bound.unwrap();
        assert!(
            (value - 1e-3..=value + 1e-9).contains(&lower),
            "{matrix:?}: certified {lower}, value {value}"
        );
        assert!(upper >= value - 1e-9, "{matrix:?}: upper bound {upper}");
        let independent = lower_bound(&g, &not_phi, &best.defender).unwrap().value;
        assert!((independent - lower).abs() < 1e-12);
        let p_heads = best
            .defender
            .choices(0, 0)
            .iter()
            .filter(|c| c.action == 0)
            .map(|c| c.probability)
            .sum::<f64>();
        assert!(
            (p_heads - heads).abs() < 0.02,
            "{matrix:?}: H with {p_heads}"
        );
    }
}

#[test]
fn truncation_drops_small_entries_and_argmax_keeps_one_per_block() {
    let choice = |next, action, probability| Choice {
        next,
        action,
        probability,
        logit: None,
    };
    let fsc = Fsc::new(
        Role::Defender,
        1,
        2,
        3,
        vec![1.0],
        vec![
            vec![
                choice(0, 0, 0.999),
                choice(0, 1, 0.0009),
                choice(0, 2, 0.0001),
            ],
            vec![choice(0, 0, 0.5), choice(0, 1, 0.3), choice(0, 2, 0.2)],
        ],
    )
    .unwrap();
    let partial = truncated(&fsc, 1e-2).unwrap();
    assert_eq!(partial.choices(0, 0).len(), 1);
    assert_eq!(partial.choices(0, 0)[0].probability, 1.0);
    assert_eq!(partial.choices(0, 1).len(), 3);
    let names: Vec<String> = rounded_candidates(&fsc)
        .unwrap()
        .into_iter()
        .map(|(name, _)| name)
        .collect();
    // 1e-6 and 1e-4 drop nothing (0.0001 is not below 1e-4): no candidate.
    assert_eq!(names, ["truncated-1e-2", "argmax"]);
    let argmax = truncated(&fsc, f64::INFINITY).unwrap();
    assert!((0..2).all(|o| argmax.choices(0, o).len() == 1 && argmax.choices(0, o)[0].action == 0));
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(12)
    })]

    /// The returned defender scores at least as well as the unrounded one
    /// (certified lower bound, recomputed independently), whichever
    /// candidate wins.
    #[test]
    fn rounding_never_returns_a_worse_controller(seed in any::<u64>()) {
        let g = game(&common::random::game_json(seed));
        let (phi, not_phi) = automata("!unsafe U goal");
        let settings = Settings { seed, max_iterations: 30, restarts: 1, starts: 1, ..Settings::default() };
        let structure = Structure::full(&g, 1 + (seed % 2) as usize, 1, false);
        let outcome = optimise_structure(&g, &phi, Some(&not_phi), &structure, &settings, 0, &mut (), &Cancel::new()).unwrap();
        let report = &outcome.report;
        prop_assert_eq!(&report.candidates[0].name, "unrounded");
        let unrounded = report.candidates[0].score;
        let returned = lower_bound(&g, &not_phi, &outcome.defender).unwrap().value;
        prop_assert!((returned - report.certified_lower.unwrap()).abs() < 1e-12);
        prop_assert!(returned >= unrounded - 1e-12, "returned {} < unrounded {}", returned, unrounded);
        let best_candidate = report.candidates.iter().map(|c| c.score).fold(f64::NEG_INFINITY, f64::max);
        prop_assert!((returned - best_candidate).abs() < 1e-12);
    }
}

const CORRIDOR: &str = r#"{"posg": 1, "states": ["a", "b", "goal", "trap"], "initial": {"a": 1.0},
    "labels": {"goal": ["goal"]},
    "defender": {"actions": ["go", "wait"], "observations": ["o"],
                 "observe": {"a": {"o": 1.0}, "b": {"o": 1.0}, "goal": {"o": 1.0}, "trap": {"o": 1.0}}},
    "transitions": [
      {"state": "a", "defender": "go", "next": {"b": 0.9, "a": 0.1}},
      {"state": "a", "defender": "wait", "next": {"a": 0.5, "trap": 0.5}},
      {"state": "b", "defender": "go", "next": {"goal": 0.9, "b": 0.1}},
      {"state": "b", "defender": "wait", "next": {"b": 0.5, "trap": 0.5}},
      {"state": "goal", "defender": "*", "next": {"goal": 1.0}},
      {"state": "trap", "defender": "*", "next": {"trap": 1.0}}]}"#;

/// A single-player corridor whose optimum is deterministic (always `go`,
/// never `wait`, which risks the trap): the optimiser pushes probabilities
/// towards 0, yet every supported choice keeps probability at least
/// `exp(-2c)/|block|`, the support is the structure's, and every linear
/// solve is accurate.
#[test]
fn the_support_never_changes_and_the_solves_stay_accurate() {
    let g = game(CORRIDOR);
    let (phi, _) = automata("F goal");
    let structure = Structure::full(&g, 2, 1, false);
    for method in [Method::Ascent, Method::MaxMin] {
        let settings = Settings {
            round: false,
            single_player_ascent: method == Method::Ascent,
            ..Settings::default()
        };
        let outcome = optimise_structure(
            &g,
            &phi,
            None,
            &structure,
            &settings,
            0,
            &mut (),
            &Cancel::new(),
        )
        .unwrap();
        assert_eq!(outcome.report.method, method);
        assert_eq!(
            Support::of(&outcome.defender),
            Support::of(&structure.defender)
        );
        let floor = (-2.0 * settings.logit_bound).exp() / 4.0;
        let smallest = Support::probabilities_of(&outcome.defender)
            .entries
            .into_iter()
            .fold(1.0f64, f64::min);
        assert!(smallest >= floor * (1.0 - 1e-9), "{method:?}: {smallest}");
        assert!(
            smallest < 1e-3,
            "{method:?}: the optimum is nearly deterministic, {smallest}"
        );
        assert!(outcome.report.max_residual < 1e-12, "{:?}", outcome.report);
        assert!(
            outcome.report.worst_case > 1.0 - 1e-3,
            "{:?}",
            outcome.report
        );
    }
}

/// Every start's records, in the order they arrived.
#[derive(Clone, Default)]
struct Records(std::sync::Arc<std::sync::Mutex<Vec<IterationRecord>>>);

impl Observer for Records {
    fn observe(&mut self, record: &IterationRecord) {
        self.0.lock().unwrap().push(*record);
    }
}

/// The single-player ascent runs under the max-min loop's driver (issue 25,
/// item 6): every iteration of every start is reported live; a check's
/// worst case is the value itself (the adversary cannot act) and comes at
/// the driver's check iterations; the run ends on the driver's rules, and
/// the work cap stops it like any run.
#[test]
fn the_single_player_ascent_runs_under_the_drivers_checks_and_rules() {
    let g = game(CORRIDOR);
    let (phi, _) = automata("F goal");
    let structure = Structure::full(&g, 2, 1, false);
    let run = |settings: &Settings| {
        let records = Records::default();
        let mut observer = records.clone();
        let outcome = optimise_structure(
            &g,
            &phi,
            None,
            &structure,
            settings,
            0,
            &mut observer,
            &Cancel::new(),
        )
        .unwrap();
        let records = records.0.lock().unwrap().clone();
        (outcome.report, records)
    };
    let settings = Settings::default();
    let (report, records) = run(&settings);
    assert_eq!(report.method, Method::Ascent);
    for start in 0..settings.starts {
        let mine: Vec<&IterationRecord> = (records.iter())
            .filter(|r| r.start == start && !r.returned)
            .collect();
        let iterations: Vec<usize> = mine.iter().map(|r| r.iteration).collect();
        assert_eq!(
            iterations,
            (0..mine.len()).collect::<Vec<_>>(),
            "start {start}"
        );
        let last = mine.len() - 1;
        for record in &mine {
            let t = record.iteration;
            let due = t % settings.check_every == 0 || (t + 1).is_power_of_two() || t == last;
            assert_eq!(
                record.worst_case.is_some(),
                due,
                "start {start}: {record:?}"
            );
            if let Some(worst_case) = record.worst_case {
                assert_eq!(worst_case, record.value, "start {start}: {record:?}");
            }
        }
    }
    // The optimum is deterministic: the logits creep towards the box's
    // face, and ten steps that each gain less than 1e-12 of V end the
    // run as converged long before the stall rule is judged (iteration
    // 255), while the line search still finds steps (the last record's
    // step is positive; where the line search fails it is 0).
    assert_eq!(report.status, Status::Converged, "{report:?}");
    assert!(report.iterations < 255, "{report:?}");
    let still_stepping = (0..settings.starts).filter(|&start| {
        let last = records.iter().rfind(|r| r.start == start).unwrap();
        last.defender_step > 0.0
    });
    assert!(
        still_stepping.count() > 0,
        "no start stopped on negligible gains"
    );
    assert!(report.worst_case > 1.0 - 1e-3, "{report:?}");
    let capped = Settings {
        max_work: (3 * report.gmc.states) as f64,
        ..Settings::default()
    };
    let (report, _) = run(&capped);
    assert_eq!(report.status, Status::WorkBudget, "{report:?}");
    assert!(report.iterations <= 3, "{report:?}");
}

#[test]
fn the_logit_bound_widens_when_progress_stalls_on_it() {
    let g = game(CORRIDOR);
    let (phi, _) = automata("F goal");
    let settings = Settings {
        initial_logit_bound: 1.0,
        initial_spread: 0.5,
        logit_bound: 8.0,
        stall_checks: 5,
        defender_decay: 0.0,
        defender_step: 0.2,
        single_player_ascent: false,
        starts: 1,
        round: false,
        ..Settings::default()
    };
    let structure = Structure::full(&g, 1, 1, false);
    let outcome = optimise_structure(
        &g,
        &phi,
        None,
        &structure,
        &settings,
        0,
        &mut (),
        &Cancel::new(),
    )
    .unwrap();
    assert_eq!(outcome.report.logit_bound, 8.0, "{:?}", outcome.report);
    assert_eq!(outcome.report.status, Status::Stalled);
    // At c = 1 `go` has probability at most e^2 / (1 + e^2) = 0.88.
    let go = outcome
        .defender
        .choices(0, 0)
        .iter()
        .find(|c| c.action == 0)
        .unwrap();
    assert!(go.probability > 0.99, "{go:?}");
}

#[test]
fn padding_keeps_the_value_and_embedding_moves_it_by_at_most_the_mix() {
    // Half the games enable actions per observation (formats.md section 6).
    for seed in 0..12 {
        let g = game(&if seed < 6 {
            common::random::game_json(seed)
        } else {
            common::random::game_json_with_enabled(seed)
        });
        let dra = common::random::dra(seed);
        let def = common::random::controller(seed, &g, Role::Defender);
        let adv = common::random::controller(seed, &g, Role::Adversary);
        let solver = SolverSettings::default();
        let value = |d: &Fsc| {
            evaluate_controllers(&g, &dra, d, &adv, &solver)
                .unwrap()
                .1
                .value
        };
        let n = def.num_nodes() + 1;
        let padded = pad(&def, n).unwrap();
        assert!((value(&padded) - value(&def)).abs() < 1e-12);
        let full = Structure::full(&g, n, 1, false).defender;
        let embedded = embed(&def, &full, 1e-6, false).unwrap();
        assert!(
            (0..n)
                .flat_map(|h| (0..full.num_observations()).map(move |o| (h, o)))
                .all(|(h, o)| embedded.choices(h, o).len() == full.choices(h, o).len())
        );
        assert!((value(&embedded) - value(&def)).abs() < 1e-3);
    }
}

/// Sizes 1..4 warm-started and kept: the certified lower bound never drops.
#[test]
fn a_warm_started_sweep_is_monotone_in_the_defenders_size() {
    let g = game(&common::random::game_json(21));
    let (phi, not_phi) = automata("!unsafe U goal");
    let settings = Settings {
        max_iterations: 40,
        restarts: 1,
        ..Settings::default()
    };
    let mut previous: Option<posg_fsc::optimise::StructureOutcome> = None;
    for n in 1..=4 {
        let mut start = Structure::full(&g, n, 1, false);
        if let Some(smaller) = &previous {
            start = warm_started(start, &smaller.defender, false).unwrap();
        }
        let belief = UpperBoundsOnce::new(&g, &phi, settings.solver_settings());
        let mut solution = posg_fsc::optimise::optimise_structures(
            &g,
            (&phi, Some(&not_phi)),
            &[start],
            &settings,
            |_, _| Box::new(()),
            &posg_fsc::optimise::Cancel::new(),
            &belief,
        )
        .unwrap();
        if let Some(smaller) = &previous {
            keep_better(&mut solution, smaller, n).unwrap();
            assert!(score(&solution.best().report) >= score(&smaller.report));
        }
        assert_eq!(solution.best().defender.num_nodes(), n);
        previous = Some(solution.best().clone());
    }
}

#[test]
fn the_sweep_command_is_monotone_and_says_so() {
    let dir = std::env::temp_dir().join(format!("posg-fsc-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("game.posg.json");
    std::fs::write(&path, common::random::game_json(5)).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .arg("sweep")
        .arg(&path)
        .args([
            "--ltl",
            "!unsafe U goal",
            "--def-nodes",
            "1..3",
            "--adv-nodes",
            "1,2",
        ])
        .args(["--max-iterations", "30", "--restarts", "1", "--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    assert!(output.status.success(), "{output:?}");
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.contains("monotone in the defender's size by construction"),
        "{text}"
    );
    let csv = std::fs::read_to_string(dir.join("out").join("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 6);
    for m in ["1", "2"] {
        let lowers: Vec<f64> = rows
            .iter()
            .filter(|r| r[column("adversary_nodes")] == m)
            .map(|r| r[column("certified_lower")].parse().unwrap())
            .collect();
        assert_eq!(lowers.len(), 3);
        assert!(lowers.windows(2).all(|w| w[1] >= w[0]), "{lowers:?}");
    }
}

/// The local searches' end points before the races, with the index of the
/// structure whose observer got each, in the order they arrived.
#[derive(Clone, Default)]
struct Searches(std::sync::Arc<std::sync::Mutex<Vec<(usize, f64)>>>, usize);

impl Observer for Searches {
    fn observe(&mut self, _record: &IterationRecord) {}

    fn searched(&mut self, record: &SearchRecord) {
        let bound = record.certified_lower;
        self.0.lock().unwrap().push((self.1, bound));
    }
}

/// The structures of a run search before their races one after another,
/// on the first structure's random stream, sharing what they judged: the
/// same structure given twice finds the end point of a run on it alone
/// (stream 0) twice, each reported to its own structure's observer, in
/// the structures' order.
#[test]
fn the_structures_of_a_run_search_one_after_another_alike() {
    let g = posg_fsc::game::grid::GridSpec {
        width: 4,
        height: 4,
        unsafe_cells: vec![5, 10],
        goal_cells: vec![15],
        ..Default::default()
    }
    .build()
    .unwrap();
    let (phi, not_phi) = automata("!unsafe U goal");
    let settings = Settings {
        max_iterations: 20,
        restarts: 1,
        local_search_restarts: 3,
        ..Settings::default()
    };
    let structure = Structure::full(&g, 2, 1, false);
    let alone = Searches::default();
    optimise_structure(
        &g,
        &phi,
        Some(&not_phi),
        &structure,
        &settings,
        0,
        &mut alone.clone(),
        &Cancel::new(),
    )
    .unwrap();
    let both = Searches::default();
    posg_fsc::optimise::optimise_structures(
        &g,
        (&phi, Some(&not_phi)),
        &[structure.clone(), structure],
        &settings,
        |index, _| Box::new(Searches(both.0.clone(), index)),
        &Cancel::new(),
        &UpperBoundsOnce::new(&g, &phi, settings.solver_settings()),
    )
    .unwrap();
    let alone = alone.0.lock().unwrap().clone();
    let both = both.0.lock().unwrap().clone();
    assert_eq!(alone.len(), 1, "{alone:?}");
    assert_eq!(
        both.iter().map(|&(index, _)| index).collect::<Vec<_>>(),
        [0, 1]
    );
    for (_, bound) in &both {
        assert_eq!(bound.to_bits(), alone[0].1.to_bits(), "{both:?} {alone:?}");
    }
}

/// The first iterate's value of every start on `structure`.
fn first_values(g: &Posg, phi: &Dra, structure: &Structure, settings: &Settings) -> Vec<f64> {
    use std::sync::{Arc, Mutex};
    struct First(Arc<Mutex<Vec<(usize, f64)>>>);
    impl Observer for First {
        fn observe(&mut self, record: &IterationRecord) {
            if record.iteration == 0 {
                self.0.lock().unwrap().push((record.start, record.value));
            }
        }
    }
    let seen = Arc::new(Mutex::new(Vec::new()));
    let belief = UpperBoundsOnce::new(g, phi, settings.solver_settings());
    posg_fsc::optimise::optimise_structures(
        g,
        (phi, None),
        std::slice::from_ref(structure),
        settings,
        |_, _| Box::new(First(Arc::clone(&seen))),
        &posg_fsc::optimise::Cancel::new(),
        &belief,
    )
    .unwrap();
    let mut seen = seen.lock().unwrap().clone();
    seen.sort_by_key(|&(start, _)| start);
    seen.into_iter().map(|(_, value)| value).collect()
}

/// A warm start is one more start: the others begin where they would
/// without it, so growing the defender keeps their reach.
#[test]
fn a_warm_start_is_one_more_start_and_leaves_the_others() {
    let g = posg_fsc::game::grid::GridSpec::default().build().unwrap();
    let (phi, _) = automata("!unsafe U goal");
    let settings = Settings {
        max_iterations: 1,
        starts: 3,
        local_search: false,
        round: false,
        structures: vec![posg_fsc::optimise::StructureSource::Full],
        ..Settings::default()
    };
    let uniform = Fsc::uniform_enabled(Role::Defender, 1, g.defender());
    // A deterministic smaller defender (each block's first choice), so that
    // its embedding differs from the uniform starting point.
    let blocks = (0..uniform.num_observations())
        .map(|o| {
            vec![Choice {
                probability: 1.0,
                ..uniform.choices(0, o)[0]
            }]
        })
        .collect();
    let smaller = Fsc::new(
        Role::Defender,
        1,
        uniform.num_observations(),
        uniform.num_actions(),
        vec![1.0],
        blocks,
    )
    .unwrap();
    let cold = Structure::full(&g, 2, 1, false);
    let warm = warm_started(cold.clone(), &smaller, false).unwrap();
    assert_eq!(
        warm.defender, cold.defender,
        "the structure's own start is kept"
    );
    let (from_cold, from_warm) = (
        first_values(&g, &phi, &cold, &settings),
        first_values(&g, &phi, &warm, &settings),
    );
    assert_eq!(from_cold.len(), 3);
    assert_eq!(from_warm.len(), 4);
    assert!(from_cold.iter().all(|&v| v > 0.0), "{from_cold:?}");
    assert_eq!(from_cold[..], from_warm[..3]);
    assert!(
        from_cold.iter().all(|&v| v != from_warm[3]),
        "{from_warm:?}"
    );
}
