//! Every stage of the pipeline, by stage and by size: grids of the paper's
//! family (unsafe cell `s(w+1)`, goal the last cell), `!unsafe U goal`,
//! uniform controllers, from about 1e3 to 1e6 GMC states.
//!
//! One criterion group per stage, one benchmark per size (`<side>x<side>
//! <nodes>-<nodes> (<states> states)`):
//!
//! * `game load`: the game file's JSON read back ([`from_json_str`]);
//! * `gmc build`: [`Gmc::build`] (exploration and sparsity pattern);
//! * `refill`: [`Gmc::refill`] (new numbers, same pattern);
//! * `analysis`: [`Recurrence::analyse`] (SCCs, BSCCs, phi-feasibility, `B`, `Z`, `T`);
//! * `lu symbolic`, `lu numeric`: sparse LU of `I - Q` ([`LuSolver::new`],
//!   [`LuSolver::factorize`]);
//! * `value`: [`Evaluator::evaluate`] (refill, factorisation, one solve),
//!   with the solver [`SolverMethod::Auto`] picks for the size;
//! * `value+gradient`: [`Evaluator::evaluate_with_gradient`] (two solves and
//!   the adjoint pass);
//! * `gradient pass`: [`GradientPass::add_adjoint_gradient`] alone;
//! * `optimiser iteration`: one alternating projected step of both players
//!   with the public [`Objective`] (value and logit gradients) and
//!   [`clip`]: an adversary descent step, then a defender ascent step, two
//!   value + gradient evaluations, as [`posg_fsc::optimise::Optimiser`]
//!   does with plain updates and one adversary step per iteration;
//! * `certify`: both certified bounds of the uniform pair
//!   ([`lower_bound`] of the defender, [`upper_bound`] of the adversary).
//!
//! `value` and `value+gradient` alternate between the uniform pair and a
//! neighbour one small step away, so where `--solver auto` picks BiCGSTAB
//! (above 50000 unknowns) each solve is warm-started from the other point's
//! solution, as in the optimiser, never from its own.
//!
//! Each fixture checks its result before it is timed: values in `[0, 1]`,
//! residuals within the tolerance, gradients finite, rows of `P` summing to
//! 1, `lower <= V <= upper`.
//!
//! Skipped, and why: the LU stages above 2e5 GMC states (one numeric
//! factorisation takes tens of seconds and up to 12 GB there: the `value`
//! stage uses BiCGSTAB at that size anyway); `certify` above 2e5 states
//! (minutes per sample). A stage whose fixture fails (for instance a solver
//! that does not converge) is reported on stderr and skipped, not timed.
//!
//! `POSG_FSC_BENCH_MAX_STATES=N` leaves out the sizes with more than about
//! `N` GMC states (estimated before building): e.g. `20000` for a run of a
//! few minutes. Sizes above 1e5 states use 10 samples.

use std::hint::black_box;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, criterion_group, criterion_main};
use posg_fsc::automaton::Dra;
use posg_fsc::certify::{lower_bound, upper_bound};
use posg_fsc::controller::{Fsc, Probabilities, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::game::file::{from_json_str, to_json_string};
use posg_fsc::game::grid::GridSpec;
use posg_fsc::optimise::{Objective, Softmax, clip};
use posg_fsc::value::Gmc;
use posg_fsc::value::Recurrence;
use posg_fsc::value::{DEFAULT_TOLERANCE, LuSolver, SolverSettings};
use posg_fsc::value::{Evaluator, GradientPass};

/// (grid side, defender nodes, adversary nodes): about 1.2e3, 1.2e4,
/// 2.8e4, 1.1e5, 2.0e5 and 1.0e6 GMC states.
const SIZES: [(usize, usize, usize); 6] = [
    (10, 2, 2),
    (32, 2, 2),
    (24, 4, 4),
    (96, 2, 2),
    (128, 2, 2),
    (288, 2, 2),
];

/// GMC states per grid cell and pair of nodes, to estimate a size before building it.
const STATES_PER_CELL_AND_NODE_PAIR: usize = 3;

/// Above this many GMC states: no LU stages, no certification, 10 samples.
const LARGE: usize = 200_000;

const FORMULA: &str = "!unsafe U goal";

struct Fixture {
    label: String,
    game: Posg,
    dra: Dra,
    dra_not: Dra,
    controllers: (Fsc, Fsc),
    supports: (Support, Support),
    probabilities: (Probabilities, Probabilities),
    neighbour: (Probabilities, Probabilities),
    states: usize,
}

/// The probabilities after one small step from uniform: every logit moved
/// by up to `0.05` (an optimiser step), so that alternating between the two
/// points warm-starts each solve from a neighbour's solution, not its own.
fn neighbour_of(fsc: &Fsc) -> Probabilities {
    let softmax = Softmax::new(fsc, false);
    let logits: Vec<f64> = (0..softmax.num_parameters())
        .map(|i| 0.05 * ((i * 7919) % 11) as f64 / 10.0)
        .collect();
    softmax.probabilities(&logits)
}

fn fixture(side: usize, def_nodes: usize, adv_nodes: usize) -> Fixture {
    let game = GridSpec::square(side).build().expect("a valid grid");
    let formula = posg_fsc::ltl::parse(FORMULA).expect("a valid formula");
    let dra = posg_fsc::ltl::translate(&formula).expect("a translatable formula");
    let dra_not = posg_fsc::ltl::translate(&formula.negate()).expect("a translatable negation");
    let uniform = |role, nodes, player: &posg_fsc::game::Player| {
        Fsc::uniform(role, nodes, player.num_observations(), player.num_actions())
    };
    let def = uniform(Role::Defender, def_nodes, game.defender());
    let adv = uniform(Role::Adversary, adv_nodes, game.adversary());
    let supports = (Support::of(&def), Support::of(&adv));
    let probabilities = (
        Support::probabilities_of(&def),
        Support::probabilities_of(&adv),
    );
    let neighbour = (neighbour_of(&def), neighbour_of(&adv));
    let states = Gmc::build(&game, &dra, &supports.0, &supports.1)
        .expect("a GMC")
        .num_states();
    Fixture {
        label: format!("{side}x{side} {def_nodes}-{adv_nodes} ({states} states)"),
        game,
        dra,
        dra_not,
        controllers: (def, adv),
        supports,
        probabilities,
        neighbour,
        states,
    }
}

impl Fixture {
    fn evaluator(&self) -> Evaluator {
        Evaluator::new(
            &self.game,
            &self.dra,
            &self.supports.0,
            &self.supports.1,
            &SolverSettings::default(),
        )
        .expect("an evaluator")
    }

    fn gmc(&self) -> Gmc {
        Gmc::build(&self.game, &self.dra, &self.supports.0, &self.supports.1).expect("a GMC")
    }
}

fn max_states() -> usize {
    std::env::var("POSG_FSC_BENCH_MAX_STATES")
        .ok()
        .and_then(|text| text.parse().ok())
        .unwrap_or(usize::MAX)
}

fn finite(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite())
}

/// Reports a stage whose fixture failed instead of timing it.
fn skip(stage: &str, label: &str, why: impl std::fmt::Display) {
    eprintln!("stages: `{stage}` at {label} skipped: {why}");
}

fn configure(group: &mut BenchmarkGroup<'_, WallTime>, states: usize) {
    if states > 50_000 {
        group
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(10));
    } else {
        group
            .sample_size(20)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(3));
    }
}

fn stages(c: &mut Criterion) {
    let cap = max_states();
    for (side, def_nodes, adv_nodes) in SIZES {
        if side * side * def_nodes * adv_nodes * STATES_PER_CELL_AND_NODE_PAIR > cap {
            continue;
        }
        let f = fixture(side, def_nodes, adv_nodes);
        let mut timed = |stage: &str, routine: &mut dyn FnMut()| {
            let mut group = c.benchmark_group(stage);
            configure(&mut group, f.states);
            group.bench_function(BenchmarkId::from_parameter(&f.label), |b| {
                b.iter(&mut *routine)
            });
            group.finish();
        };

        let json = to_json_string(&f.game);
        let loaded = from_json_str(&json, "grid.posg.json").expect("the game reads back");
        assert_eq!(loaded.num_states(), f.game.num_states());
        timed("game load", &mut || {
            black_box(from_json_str(black_box(&json), "grid.posg.json").expect("a game"));
        });

        timed("gmc build", &mut || {
            black_box(f.gmc());
        });

        let mut gmc = f.gmc();
        gmc.refill(&f.probabilities.0, &f.probabilities.1);
        assert!(
            (0..gmc.num_states()).all(|m| (gmc.row(m).1.iter().sum::<f64>() - 1.0).abs() < 1e-12)
        );
        timed("refill", &mut || {
            gmc.refill(black_box(&f.probabilities.0), black_box(&f.probabilities.1))
        });

        let recurrence = Recurrence::analyse(&gmc, &f.dra);
        assert!(recurrence.feasible().count() > 0 && !recurrence.transient.is_empty());
        timed("analysis", &mut || {
            black_box(Recurrence::analyse(&gmc, &f.dra));
        });

        let mut evaluator = f.evaluator();
        let (pd, pa) = (&f.probabilities.0, &f.probabilities.1);
        match evaluator.evaluate(pd, pa) {
            Ok(evaluation) => {
                assert!((0.0..=1.0).contains(&evaluation.value));
                assert!(evaluation.residual <= DEFAULT_TOLERANCE);
                let mut at_neighbour = false;
                timed("value", &mut || {
                    at_neighbour = !at_neighbour;
                    let (d, a) = if at_neighbour {
                        (&f.neighbour.0, &f.neighbour.1)
                    } else {
                        (pd, pa)
                    };
                    black_box(evaluator.evaluate(d, a).expect("a value"));
                });
            }
            Err(error) => skip("value", &f.label, error),
        }

        if f.states <= LARGE {
            let (pattern, values) = evaluator.system();
            let (pattern, values) = (pattern.clone(), values.to_vec());
            let mut lu = LuSolver::new(pattern.clone(), DEFAULT_TOLERANCE).expect("symbolic LU");
            lu.factorize(&values).expect("numeric LU");
            let mut x = vec![0.0; pattern.n];
            let ones = vec![1.0; pattern.n];
            assert!(lu.solve(&ones, &mut x).expect("a solve").residual <= DEFAULT_TOLERANCE);
            timed("lu symbolic", &mut || {
                black_box(LuSolver::new(pattern.clone(), DEFAULT_TOLERANCE).expect("symbolic LU"));
            });
            timed("lu numeric", &mut || {
                lu.factorize(black_box(&values)).expect("numeric LU")
            });
        }

        match evaluator.evaluate_with_gradient(pd, pa) {
            Ok((evaluation, gradient)) => {
                assert!((0.0..=1.0).contains(&evaluation.value));
                assert!(finite(&gradient.defender) && finite(&gradient.adversary));
                assert!(gradient.adjoint_residual <= DEFAULT_TOLERANCE);
                let mut at_neighbour = false;
                timed("value+gradient", &mut || {
                    at_neighbour = !at_neighbour;
                    let (d, a) = if at_neighbour {
                        (&f.neighbour.0, &f.neighbour.1)
                    } else {
                        (pd, pa)
                    };
                    black_box(evaluator.evaluate_with_gradient(d, a).expect("a gradient"));
                });
            }
            Err(error) => skip("value+gradient", &f.label, error),
        }

        // The pass runs on the evaluator's chain, explored up to its decided
        // states, whose state values `x` are.
        let (chain, classes) = (evaluator.gmc(), evaluator.recurrence());
        let x = evaluator.state_values().to_vec();
        let y: Vec<f64> = (0..chain.num_states())
            .map(|m| f64::from(classes.transient_index[m] != u32::MAX))
            .collect();
        let (mut gd, mut ga) = (vec![0.0; pd.entries.len()], vec![0.0; pa.entries.len()]);
        let mut pass = GradientPass::new();
        pass.add_adjoint_gradient(chain, &x, &y, &mut gd, &mut ga);
        assert!(finite(&gd) && finite(&ga));
        timed("gradient pass", &mut || {
            pass.add_adjoint_gradient(chain, &x, &y, &mut gd, &mut ga)
        });
        drop((gmc, evaluator));

        optimiser_iteration(&f, &mut timed);

        if f.states <= LARGE {
            let (def, adv) = &f.controllers;
            let value = f.evaluator().evaluate(pd, pa).map(|e| e.value);
            let lower = lower_bound(&f.game, &f.dra_not, def).map(|b| b.value);
            let upper = upper_bound(&f.game, &f.dra, adv).map(|b| b.value);
            match (value, lower, upper) {
                (Ok(value), Ok(lower), Ok(upper)) => {
                    assert!(lower <= value + 1e-9 && value <= upper + 1e-9);
                    timed("certify", &mut || {
                        black_box(lower_bound(&f.game, &f.dra_not, def).expect("a lower bound"));
                        black_box(upper_bound(&f.game, &f.dra, adv).expect("an upper bound"));
                    });
                }
                (value, lower, upper) => skip(
                    "certify",
                    &f.label,
                    format!("{value:?} {lower:?} {upper:?}"),
                ),
            }
        }
    }
}

/// One alternating projected gradient step of both players (plain
/// updates, step 0.5, logits in [-5, 5]) from logits near uniform.
fn optimiser_iteration(f: &Fixture, timed: &mut impl FnMut(&str, &mut dyn FnMut())) {
    let (step, bound) = (0.5, 5.0);
    let softmax = |fsc| Softmax::new(fsc, false);
    let mut objective = match Objective::new(
        &f.game,
        &f.dra,
        softmax(&f.controllers.0),
        softmax(&f.controllers.1),
        &SolverSettings::default(),
    ) {
        Ok(objective) => objective,
        Err(error) => return skip("optimiser iteration", &f.label, error),
    };
    let mut defender = objective.defender().logits_of_template(bound);
    let mut adversary = objective.adversary().logits_of_template(bound);
    let mut iterate = |objective: &mut Objective| -> Result<f64, posg_fsc::value::ValueError> {
        let point = objective.point(&defender, &adversary)?;
        for (phi, g) in adversary.iter_mut().zip(&point.adversary) {
            *phi -= step * g;
        }
        clip(&mut adversary, bound);
        let point = objective.point(&defender, &adversary)?;
        for (phi, g) in defender.iter_mut().zip(&point.defender) {
            *phi += step * g;
        }
        clip(&mut defender, bound);
        assert!(finite(&point.defender) && finite(&point.adversary));
        Ok(point.value)
    };
    match iterate(&mut objective) {
        Ok(value) => {
            assert!((0.0..=1.0).contains(&value));
            timed("optimiser iteration", &mut || {
                black_box(iterate(&mut objective).expect("an iteration"));
            });
        }
        Err(error) => skip("optimiser iteration", &f.label, error),
    }
}

criterion_group!(benches, stages);
criterion_main!(benches);
