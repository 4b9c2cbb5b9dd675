//! Cost of the exact fallback solve ([`posg_fsc::value::exact`], method.md
//! section 8) on stiff chains whose probabilities are full-precision
//! doubles: lazy walks of `WALK` transient states, each moving left and
//! right with random probabilities of about `1e-15` (random doubles, all
//! 53 bits used), split into blocks by a memory of `NODES` nodes that moves
//! uniformly (as a `uniform:NODES` controller does). The leftmost state
//! leaves to the zero set, the rightmost to the target.
//!
//! `cargo run --release --example exact_fallback -- chain WALK NODES SEED
//! [old]` prints one CSV row: walk, nodes, seed, unknowns, seconds of the
//! exact solve, its error bound and the largest value, then (with `old`)
//! the seconds of the reference elimination in rationals
//! (`solve_by_rational_elimination`) and whether both give the same
//! doubles.
//! `experiments/exact-fallback/run.py` collects the rows.
//!
//! `cargo run --release --example exact_fallback -- eval WALK NODES SEED`
//! builds the same walk as a game (the transition probabilities written
//! as JSON numbers that round-trip) and prints the seconds of `eval`
//! (default settings) against a `uniform:NODES` defender, the value, its
//! error bound and the solver's reason, then (with `old`) the seconds of
//! the reference elimination on the same matrix (with the exits as
//! right-hand side, which the evaluator does not expose). The case of
//! issue 57 is `eval 58 3 SEED [old]` (a 60-state walk: 58 transient
//! states, 174 unknowns).

use std::time::Instant;

use posg_fsc::controller::Role;
use posg_fsc::value::{SolverSettings, SparsePattern, evaluate_controllers, exact};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The probabilities of moving left and right of each of `walk` states.
fn escapes(walk: usize, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut draw = || 1e-15 * (0.5 + rng.random::<f64>());
    (0..walk).map(|_| (draw(), draw())).collect()
}

/// The transient system `(pattern, off-diagonal values, exits, b)` of the
/// walk split by `nodes` memory nodes, as the library builds it.
fn chain(walk: usize, nodes: usize, seed: u64) -> (SparsePattern, Vec<f64>, Vec<f64>, Vec<f64>) {
    let moves = escapes(walk, seed);
    let n = walk * nodes;
    let (mut row_offsets, mut columns, mut values) = (vec![0], Vec::new(), Vec::new());
    let (mut exits, mut b) = (Vec::new(), Vec::new());
    let share = |p: f64| p / nodes as f64;
    for (s, &(left, right)) in moves.iter().enumerate() {
        let stay = 1.0 - left - right;
        for g in 0..nodes {
            let mut entries = vec![(s * nodes + g, 0.0)];
            for h in (0..nodes).filter(|&h| h != g) {
                entries.push((s * nodes + h, -share(stay)));
            }
            for (t, p) in [(s.wrapping_sub(1), left), (s + 1, right)] {
                if t < walk {
                    entries.extend((0..nodes).map(|h| (t * nodes + h, -share(p))));
                }
            }
            entries.sort_by_key(|&(c, _)| c);
            columns.extend(entries.iter().map(|&(c, _)| c));
            values.extend(entries.iter().map(|&(_, v)| v));
            row_offsets.push(columns.len());
            let split = |p: f64| (0..nodes).map(|_| share(p)).sum::<f64>();
            let (fail, goal) = (
                if s == 0 { left } else { 0.0 },
                if s + 1 == walk { right } else { 0.0 },
            );
            exits.push(split(fail) + split(goal));
            b.push(split(goal));
        }
    }
    let pattern = SparsePattern {
        n,
        row_offsets,
        columns,
    };
    (pattern, values, exits, b)
}

/// The walk as a game file: `walk` transient states between `fail` and
/// `goal`, starting in the middle.
fn walk_json(walk: usize, seed: u64) -> String {
    let moves = escapes(walk, seed);
    let name = |i: usize| match i {
        0 => "fail".to_string(),
        i if i == walk + 1 => "goal".to_string(),
        i => format!("w{i}"),
    };
    let states: Vec<String> = (0..walk + 2).map(|i| format!("\"{}\"", name(i))).collect();
    let mut transitions = vec![
        r#"{"state": "fail", "defender": "*", "next": {"fail": 1.0}}"#.to_string(),
        r#"{"state": "goal", "defender": "*", "next": {"goal": 1.0}}"#.to_string(),
    ];
    for (s, &(left, right)) in moves.iter().enumerate() {
        let i = s + 1;
        transitions.push(format!(
            r#"{{"state": "{}", "defender": "*", "next": {{"{}": {:?}, "{}": {left:?}, "{}": {right:?}}}}}"#,
            name(i),
            name(i),
            1.0 - left - right,
            name(i - 1),
            name(i + 1)
        ));
    }
    format!(
        r#"{{"posg": 1, "states": [{}], "initial": {{"{}": 1.0}}, "labels": {{"goal": ["goal"]}},
           "defender": {{"actions": ["go"], "observe": "full"}}, "transitions": [{}]}}"#,
        states.join(", "),
        name(walk.div_ceil(2)),
        transitions.join(",\n")
    )
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: exact_fallback (chain WALK NODES SEED [old] | eval WALK NODES SEED [old])";
    let number = |i: usize| -> usize { args.get(i).and_then(|a| a.parse().ok()).expect(usage) };
    let (walk, nodes, seed) = (number(1), number(2), number(3) as u64);
    match args[0].as_str() {
        "chain" => {
            let (pattern, values, exits, b) = chain(walk, nodes, seed);
            let start = Instant::now();
            let solution = exact::solve_exactly(
                &pattern,
                &values,
                &exits,
                &b,
                &exact::ExactBudget::unlimited(),
            )
            .expect("a transient chain is solved");
            let seconds = start.elapsed().as_secs_f64();
            let largest = solution.x.iter().copied().fold(0.0, f64::max);
            print!(
                "{walk},{nodes},{seed},{},{seconds:.4},{:e},{largest:e}",
                pattern.n, solution.error_bound
            );
            if args.get(4).map(String::as_str) == Some("old") {
                let start = Instant::now();
                let old =
                    exact::solve_by_rational_elimination(&pattern, &values, &exits, &b, usize::MAX)
                        .expect("a transient chain is solved");
                let old_seconds = start.elapsed().as_secs_f64();
                print!(",{old_seconds:.4},{}", old.x == solution.x);
            } else {
                print!(",,");
            }
            println!();
        }
        "eval" => {
            let game = posg_fsc::game::file::from_json_str(&walk_json(walk, seed), "walk")
                .expect("the walk is a game");
            let dra = posg_fsc::ltl::translate(&posg_fsc::ltl::parse("F goal").unwrap()).unwrap();
            let uniform = |role, k: usize| {
                posg_fsc::controller::file::resolve(&format!("uniform:{k}"), &game, role).unwrap()
            };
            let (defender, adversary) =
                (uniform(Role::Defender, nodes), uniform(Role::Adversary, 1));
            let start = Instant::now();
            let outcome = evaluate_controllers(
                &game,
                &dra,
                &defender,
                &adversary,
                &SolverSettings::default(),
            );
            let seconds = start.elapsed().as_secs_f64();
            match outcome {
                Ok((evaluator, evaluation)) => {
                    print!(
                        "{walk},{nodes},{seed},{},{seconds:.4},{:e},{:e},{}",
                        evaluator.system().0.n,
                        evaluation.value,
                        evaluation.error_bound,
                        evaluator.solver_reason()
                    );
                    if args.get(4).map(String::as_str) == Some("old") {
                        // The same matrix with the exits as right-hand side
                        // (the evaluator does not expose its `b`).
                        let (pattern, values) = evaluator.system();
                        let exits = evaluator.exits();
                        let start = Instant::now();
                        let old = exact::solve_by_rational_elimination(
                            pattern,
                            values,
                            exits,
                            exits,
                            usize::MAX,
                        );
                        print!(",{:.4},{}", start.elapsed().as_secs_f64(), old.is_ok());
                    }
                    println!();
                }
                Err(error) => println!("{walk},{nodes},{seed},,{seconds:.4},,,{error}"),
            }
        }
        _ => panic!("{usage}"),
    }
}
