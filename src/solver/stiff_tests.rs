//! Stiff chains with memory against exact rational arithmetic (method.md
//! section 8): whatever the solver returns lies within its error bound of
//! the exact solution of the system it was given, or is an error.

use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{Signed, ToPrimitive, Zero};
use proptest::prelude::*;
use proptest::strategy::ValueTree;

use super::{LinearSolver, SolverError, SolverMethod, SolverSettings, SparsePattern};

/// A chain's transient system as the library builds it: off-diagonal
/// `-Q`, row sums `exits` (the probabilities of leaving `T`) and `b`.
#[derive(Debug)]
struct Chain {
    pattern: SparsePattern,
    values: Vec<f64>,
    exits: Vec<f64>,
    b: Vec<f64>,
}

/// `base` lazy states, each split into `nodes` states by a memory that
/// moves uniformly among `nodes` nodes (as a `uniform:K` controller does):
/// from `(s, g)` to `(s', g')` with probability `P(s' | s) / nodes`.
/// `moves[s]` lists `(s', P(s' | s))` for `s' != s` among the base states,
/// `goal[s]` and `fail[s]` the probabilities of leaving to the target and
/// to the zero set; the rest stays in `s`.
fn with_memory(moves: &[Vec<(usize, f64)>], goal: &[f64], fail: &[f64], nodes: usize) -> Chain {
    let base = moves.len();
    let n = base * nodes;
    let (mut row_offsets, mut columns, mut values) = (vec![0], Vec::new(), Vec::new());
    let (mut exits, mut b) = (Vec::new(), Vec::new());
    for s in 0..base {
        let leave: f64 = moves[s].iter().map(|&(_, p)| p).sum::<f64>() + goal[s] + fail[s];
        let stay = 1.0 - leave;
        for g in 0..nodes {
            let row = s * nodes + g;
            let mut entries: Vec<(usize, f64)> = vec![(row, 0.0)];
            for h in 0..nodes {
                if h != g {
                    entries.push((s * nodes + h, -(stay / nodes as f64)));
                }
            }
            for &(t, p) in &moves[s] {
                for h in 0..nodes {
                    entries.push((t * nodes + h, -(p / nodes as f64)));
                }
            }
            entries.sort_by_key(|&(c, _)| c);
            for (c, v) in entries {
                columns.push(c);
                values.push(v);
            }
            row_offsets.push(columns.len());
            // Each of the `nodes` successors of a leaving move is written
            // as the GMC writes it, then summed.
            let split = |p: f64| (0..nodes).map(|_| p / nodes as f64).sum::<f64>();
            exits.push(split(goal[s]) + split(fail[s]));
            b.push(split(goal[s]));
        }
    }
    Chain {
        pattern: SparsePattern {
            n,
            row_offsets,
            columns,
        },
        values,
        exits,
        b,
    }
}

fn exact(value: f64) -> BigRational {
    BigRational::from_float(value).expect("finite")
}

/// The exact solution of the chain's system, in rationals (dense
/// Gaussian elimination; the diagonal is the exit plus the off-diagonal
/// magnitudes, exactly).
#[allow(clippy::needless_range_loop)] // rows k and i of one matrix at once
fn exact_solution(chain: &Chain) -> Vec<BigRational> {
    let n = chain.pattern.n;
    let mut a = vec![vec![BigRational::zero(); n + 1]; n];
    for (row, entries) in a.iter_mut().enumerate() {
        let mut diagonal = exact(chain.exits[row]);
        for k in chain.pattern.row_range(row) {
            let column = chain.pattern.columns[k];
            if column != row {
                entries[column] = exact(chain.values[k]);
                diagonal -= exact(chain.values[k]);
            }
        }
        entries[row] = diagonal;
        entries[n] = exact(chain.b[row]);
    }
    for k in 0..n {
        let pivot = a[k][k].clone();
        for i in k + 1..n {
            if a[i][k].is_zero() {
                continue;
            }
            let factor = &a[i][k] / &pivot;
            for j in k..=n {
                let update = &factor * &a[k][j];
                a[i][j] -= update;
            }
        }
    }
    let mut x = vec![BigRational::zero(); n];
    for k in (0..n).rev() {
        let mut sum = a[k][n].clone();
        for j in k + 1..n {
            sum -= &a[k][j] * &x[j];
        }
        x[k] = sum / &a[k][k];
    }
    x
}

/// `|x - exact|` as a double, rounded up by a relative `2^-50`.
fn distance(x: f64, exact_value: &BigRational) -> f64 {
    let difference = (exact(x) - exact_value).abs();
    difference.to_f64().expect("finite") * (1.0 + 2f64.powi(-50))
}

/// Solves the chain with `method` in double precision (no exact
/// fallback) and checks every entry against the exact solution: within the
/// reported bound, or an error saying the bound could not be proved.
/// Returns whether it was solved.
fn solved_within_bound(chain: &Chain, method: SolverMethod) -> bool {
    let settings = SolverSettings {
        method,
        exact_limit: 0,
        ..SolverSettings::default()
    };
    solved_within_bound_by(chain, &settings)
}

/// [`solved_within_bound`] with `settings`.
fn solved_within_bound_by(chain: &Chain, settings: &SolverSettings) -> bool {
    let method = settings.method;
    let mut solver = LinearSolver::new(chain.pattern.clone(), settings).unwrap();
    let factorised = solver.factorize_with(|values, exits| {
        values.copy_from_slice(&chain.values);
        exits.copy_from_slice(&chain.exits);
    });
    match factorised {
        // ILU(0) subtracts: a nearly closed block can cancel a pivot to 0.
        // That is a clear error of BiCGSTAB as set (`auto` turns to LU).
        Err(SolverError::Singular(_)) if method == SolverMethod::Krylov => return false,
        other => other.unwrap(),
    }
    let mut x = vec![0.0; chain.pattern.n];
    match solver.solve(&chain.b, &mut x) {
        Ok(report) => {
            let bound = report.error_bound.expect("a forward solve is bounded");
            assert!(bound <= settings.tolerance);
            for (i, exact_value) in exact_solution(chain).iter().enumerate() {
                let error = distance(x[i], exact_value);
                assert!(
                    error <= bound,
                    "{method:?}: x[{i}] = {} is {error:e} from the exact value, above its \
                     bound {bound:e}",
                    x[i]
                );
            }
            true
        }
        Err(
            SolverError::Unbounded { .. }
            | SolverError::TooLargeForExact { .. }
            | SolverError::Inaccurate { .. }
            | SolverError::NotConverged { .. },
        ) => false,
        Err(other) => panic!("{method:?}: {other}"),
    }
}

/// A chain (found by the property test below) on which ILU(0) meets a
/// zero pivot: BiCGSTAB as set says so, `auto` starting with BiCGSTAB
/// turns to LU and solves it within its bound (exactly: it is too stiff
/// for double precision).
#[test]
fn a_zero_ilu_pivot_hands_auto_over_to_lu() {
    let moves = [vec![(1, 1e-7)], vec![(0, 1e-12)], vec![(0, 1e-6)], vec![]];
    let chain = with_memory(&moves, &[0.0, 0.0, 0.0, 1e-6], &[1e-13, 0.0, 0.0, 0.0], 3);
    let forced = SolverSettings {
        method: SolverMethod::Krylov,
        ..SolverSettings::default()
    };
    let mut krylov = LinearSolver::new(chain.pattern.clone(), &forced).unwrap();
    let refused = krylov.factorize_with(|values, exits| {
        values.copy_from_slice(&chain.values);
        exits.copy_from_slice(&chain.exits);
    });
    assert!(
        matches!(refused, Err(SolverError::Singular(_))),
        "{refused:?}"
    );
    // Too stiff for double precision: the exact fallback proves it.
    let auto = SolverSettings {
        lu_limit: 0,
        ..SolverSettings::default()
    };
    assert!(solved_within_bound_by(&chain, &auto));
}

#[test]
fn a_lazy_state_split_by_memory_keeps_its_escape() {
    // The 3-state chain (value 1/3) with 1, 2 and 3 memory nodes:
    // elimination by subtraction lost the block's escape of 3e-13.
    for nodes in 1..=3 {
        let chain = with_memory(&[vec![]], &[1e-13], &[2e-13], nodes);
        let mut solver =
            LinearSolver::new(chain.pattern.clone(), &SolverSettings::default()).unwrap();
        solver
            .factorize_with(|values, exits| {
                values.copy_from_slice(&chain.values);
                exits.copy_from_slice(&chain.exits);
            })
            .unwrap();
        let mut x = vec![0.0; chain.pattern.n];
        let report = solver.solve(&chain.b, &mut x).unwrap();
        for xi in x {
            assert!((xi - 1.0 / 3.0).abs() < 1e-15, "{nodes} nodes: {xi}");
        }
        assert!(report.error_bound.unwrap() < 1e-15);
        assert!(solved_within_bound(&chain, SolverMethod::Lu));
    }
}

#[test]
fn a_slowly_mixing_pair_is_proved_by_refinement_in_extended_precision() {
    // Two states swapping with probability 0.3, one leaving to the target
    // and one to the zero set with 1e-10 each: x is near 1/2 and the chain
    // spends ~5e9 steps in T, so even the exact solution rounded to
    // doubles has a residual (~1e-17) that the bound magnifies above the
    // tolerance; carrying x as a double-double proves it in double
    // arithmetic, without the exact fallback.
    for nodes in 1..=2 {
        let chain = with_memory(
            &[vec![(1, 0.3)], vec![(0, 0.3)]],
            &[1e-10, 0.0],
            &[0.0, 1e-10],
            nodes,
        );
        let expected_time = 1.0 / 1e-10;
        assert!(expected_time * f64::EPSILON / 2.0 > SolverSettings::default().tolerance);
        for method in [SolverMethod::Lu, SolverMethod::Auto] {
            assert!(
                solved_within_bound(&chain, method),
                "{nodes} nodes, {method:?}: refused"
            );
        }
    }
}

/// A lazy chain before memory: each state's moves `(to, probability)`, its
/// probabilities of reaching the target and the zero set, and the number
/// of memory nodes that split it.
type LazyChain = (Vec<Vec<(usize, f64)>>, Vec<f64>, Vec<f64>, usize);

/// A random lazy chain: `base` states, each moving to a few others with
/// probabilities of `10^-escape` scale, and leaving to the target or the
/// zero set as rarely.
fn stiff_chain() -> impl Strategy<Value = LazyChain> {
    (2usize..6, 1usize..=3).prop_flat_map(|(base, nodes)| {
        let scale = || (6i32..=15, 1.0f64..9.0).prop_map(|(e, m)| m * 10f64.powi(-e));
        let moves =
            proptest::collection::vec(proptest::collection::vec((0..base, scale()), 0..3), base);
        let leaving = proptest::collection::vec(
            (
                proptest::bool::weighted(0.6),
                scale(),
                proptest::bool::weighted(0.6),
                scale(),
            ),
            base,
        );
        (moves, leaving, Just(nodes)).prop_map(|(moves, leaving, nodes)| {
            let moves: Vec<Vec<(usize, f64)>> = moves
                .into_iter()
                .enumerate()
                .map(|(s, row)| {
                    let mut row: Vec<(usize, f64)> =
                        row.into_iter().filter(|&(t, _)| t != s).collect();
                    row.sort_by_key(|&(t, _)| t);
                    row.dedup_by_key(|&mut (t, _)| t);
                    row
                })
                .collect();
            // The last state always escapes, so that T is transient.
            let count = leaving.len();
            let goal = leaving
                .iter()
                .enumerate()
                .map(|(s, &(g, p, _, _))| if g || s + 1 == count { p } else { 0.0 })
                .collect();
            let fail = leaving
                .iter()
                .map(|&(_, _, f, p)| if f { p } else { 0.0 })
                .collect();
            (moves, goal, fail, nodes)
        })
    })
}

/// Every state reaches a state that leaves `T` (else the system is singular).
fn transient(moves: &[Vec<(usize, f64)>], goal: &[f64], fail: &[f64]) -> bool {
    let base = moves.len();
    let mut leaves: Vec<bool> = (0..base).map(|s| goal[s] + fail[s] > 0.0).collect();
    for _ in 0..base {
        for s in 0..base {
            if moves[s].iter().any(|&(t, _)| leaves[t]) {
                leaves[s] = true;
            }
        }
    }
    leaves.iter().all(|&l| l)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn random_stiff_chains_with_memory_are_never_outside_their_bound(
        (moves, goal, fail, nodes) in stiff_chain()
    ) {
        prop_assume!(transient(&moves, &goal, &fail));
        let chain = with_memory(&moves, &goal, &fail, nodes);
        for method in [SolverMethod::Lu, SolverMethod::Krylov] {
            solved_within_bound(&chain, method);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]
    #[test]
    fn random_stiff_chains_are_solved_exactly_where_double_precision_cannot_prove_them(
        (moves, goal, fail, nodes) in stiff_chain()
    ) {
        prop_assume!(transient(&moves, &goal, &fail));
        let chain = with_memory(&moves, &goal, &fail, nodes);
        let reference = exact_solution(&chain);
        let exact = super::exact::solve_exactly(
            &chain.pattern, &chain.values, &chain.exits, &chain.b,
            &super::exact::ExactBudget::unlimited(),
        )
        .unwrap();
        for (i, exact_value) in reference.iter().enumerate() {
            prop_assert_eq!(exact.x[i], exact_value.to_f64().unwrap(), "x[{}]", i);
            prop_assert!(distance(exact.x[i], exact_value) <= exact.error_bound);
        }
        prop_assert!(exact.error_bound <= 1e-16);
        // With the fallback (the default settings), nothing is refused
        // (BiCGSTAB as set may still stop before converging).
        for method in [SolverMethod::Lu, SolverMethod::Auto] {
            let settings = SolverSettings { method, ..SolverSettings::default() };
            prop_assert!(solved_within_bound_by(&chain, &settings), "{:?} refused", method);
        }
    }
}

#[test]
fn most_random_stiff_chains_are_solved_not_refused() {
    // Of the chains above, those that LU solves must be most: a solver that
    // refused everything would pass the property test.
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let (mut tried, mut solved) = (0, 0);
    while tried < 100 {
        let (moves, goal, fail, nodes) = stiff_chain().new_tree(&mut runner).unwrap().current();
        if !transient(&moves, &goal, &fail) {
            continue;
        }
        tried += 1;
        solved += usize::from(solved_within_bound(
            &with_memory(&moves, &goal, &fail, nodes),
            SolverMethod::Lu,
        ));
    }
    assert!(solved >= 90, "only {solved} of {tried} solved");
}

#[test]
fn the_exact_solution_is_exact() {
    // Independent check of the reference: a 2-state chain by hand.
    let chain = with_memory(&[vec![(1, 0.25)], vec![]], &[0.25, 0.5], &[0.5, 0.5], 1);
    let x = exact_solution(&chain);
    // x1 = 0.5; x0 = (0.25 + 0.25 x1) / 1 = 0.375.
    assert_eq!(x[1], BigRational::new(BigInt::from(1), BigInt::from(2)));
    assert_eq!(x[0], BigRational::new(BigInt::from(3), BigInt::from(8)));
}

/// Issue 57's case: a 60-state lazy walk (58 transient states) whose
/// escape probabilities are full-precision random doubles of about
/// `1e-15`, split by a 3-node memory: 174 unknowns, beyond double
/// precision. The exact solve gives the same doubles as the reference
/// elimination in rationals, and the solver reports them with a bound
/// below `1e-16`.
#[test]
fn a_stiff_walk_with_full_precision_escapes_is_solved_exactly() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(57);
    let walk = 58;
    let mut draw = || 1e-15 * (0.5 + rng.random::<f64>());
    let escapes: Vec<(f64, f64)> = (0..walk).map(|_| (draw(), draw())).collect();
    let moves: Vec<Vec<(usize, f64)>> = (0..walk)
        .map(|s| {
            let (left, right) = escapes[s];
            let mut row = Vec::new();
            if s > 0 {
                row.push((s - 1, left));
            }
            if s + 1 < walk {
                row.push((s + 1, right));
            }
            row
        })
        .collect();
    let goal: Vec<f64> = (0..walk)
        .map(|s| if s + 1 == walk { escapes[s].1 } else { 0.0 })
        .collect();
    let fail: Vec<f64> = (0..walk)
        .map(|s| if s == 0 { escapes[s].0 } else { 0.0 })
        .collect();
    let chain = with_memory(&moves, &goal, &fail, 3);
    assert_eq!(chain.pattern.n, 174);
    // Double precision alone cannot prove it.
    assert!(!solved_within_bound(&chain, SolverMethod::Lu));
    let reference = super::exact::solve_by_rational_elimination(
        &chain.pattern,
        &chain.values,
        &chain.exits,
        &chain.b,
        usize::MAX,
    )
    .unwrap();
    let exact = super::exact::solve_exactly(
        &chain.pattern,
        &chain.values,
        &chain.exits,
        &chain.b,
        &super::exact::ExactBudget::for_limit(super::exact::DEFAULT_EXACT_LIMIT),
    )
    .unwrap();
    assert_eq!(exact.x, reference.x);
    assert!(exact.error_bound <= reference.error_bound * (1.0 + 1e-12));
    assert!(exact.error_bound > 0.0 && exact.error_bound < 1e-16);
    // Through the solver, with the default settings.
    let mut solver = LinearSolver::new(chain.pattern.clone(), &SolverSettings::default()).unwrap();
    solver
        .factorize_with(|values, exits| {
            values.copy_from_slice(&chain.values);
            exits.copy_from_slice(&chain.exits);
        })
        .unwrap();
    let mut x = vec![0.0; chain.pattern.n];
    let report = solver.solve(&chain.b, &mut x).unwrap();
    assert_eq!(x, reference.x);
    assert_eq!(report.error_bound, Some(exact.error_bound));
    assert!(solver.reason().contains("exact"), "{}", solver.reason());
    // A work budget too small for it is a refusal naming the budget.
    let refused = super::exact::solve_exactly(
        &chain.pattern,
        &chain.values,
        &chain.exits,
        &chain.b,
        &super::exact::ExactBudget {
            entries: usize::MAX,
            work: 1_000_000,
        },
    );
    assert!(
        matches!(
            refused,
            Err(super::exact::ExactRefusal::TooMuchWork { limit: 1_000_000, bits }) if bits > 0
        ),
        "{refused:?}"
    );
}

/// Random full-precision systems, not only chains: dense-ish random
/// off-diagonal entries of either sign, positive exits, `b` of either sign.
fn random_system() -> impl Strategy<Value = Chain> {
    (1usize..7).prop_flat_map(|n| {
        let entry = (any::<bool>(), -40i32..2, 1.0f64..2.0).prop_map(|(present, e, m)| {
            if present { -m * 2f64.powi(e) } else { 0.0 }
        });
        (
            proptest::collection::vec(entry, n * n),
            proptest::collection::vec((-60i32..2, 1.0f64..2.0), n),
            proptest::collection::vec(-2.0f64..2.0, n),
        )
            .prop_map(move |(entries, exits, b)| {
                let mut row_offsets = vec![0];
                let mut columns = Vec::new();
                let mut values = Vec::new();
                for i in 0..n {
                    for j in 0..n {
                        if i == j || entries[i * n + j] != 0.0 {
                            columns.push(j);
                            values.push(if i == j { 0.0 } else { entries[i * n + j] });
                        }
                    }
                    row_offsets.push(columns.len());
                }
                Chain {
                    pattern: SparsePattern {
                        n,
                        row_offsets,
                        columns,
                    },
                    values,
                    exits: exits.into_iter().map(|(e, m)| m * 2f64.powi(e)).collect(),
                    b,
                }
            })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn random_systems_are_solved_as_by_rational_elimination(chain in random_system()) {
        let reference = exact_solution(&chain);
        let solution = super::exact::solve_exactly(
            &chain.pattern, &chain.values, &chain.exits, &chain.b,
            &super::exact::ExactBudget::unlimited(),
        )
        .unwrap();
        let old = super::exact::solve_by_rational_elimination(
            &chain.pattern, &chain.values, &chain.exits, &chain.b, usize::MAX,
        )
        .unwrap();
        prop_assert_eq!(&solution.x, &old.x);
        for (i, exact_value) in reference.iter().enumerate() {
            let error = (exact(solution.x[i]) - exact_value).abs();
            prop_assert!(distance(solution.x[i], exact_value) <= solution.error_bound * (1.0 + 1e-14));
            // Nearest: no neighbouring double is closer.
            for neighbour in [-1.0, 1.0].map(|sign| super::exact::next_double(solution.x[i], sign)) {
                prop_assert!((exact(neighbour) - exact_value).abs() >= error, "x[{}]", i);
            }
        }
        prop_assert!(solution.error_bound <= old.error_bound * (1.0 + 1e-12) + f64::from_bits(2));
    }
}
