//! Cost of the adjoint gradient (method.md section 2) on grids of the paper's
//! family with full-support controllers, objective `!unsafe U goal`:
//!
//! * `value`: one exact evaluation (refill, factorisation, one solve);
//! * `value_and_gradient`: value and the logit gradient of both players
//!   (one factorisation, two solves, one pass over the GMC, chain rule);
//! * `finite_differences`: the value plus one more evaluation per defender
//!   and adversary logit (forward differences: one solve per parameter).
//!
//! The claim checked: `value_and_gradient` costs at most 3x `value`, and the
//! ratio `finite_differences / value_and_gradient` grows with the number of
//! parameters. `experiments/gradient-cost/run.py` turns criterion's
//! estimates into `results/gradient-cost.md`.
//!
//! The group `gradient-methods` compares the adjoint gradient with forward
//! sensitivities ([`posg_fsc::value::ForwardSensitivities`]: one factorisation, then one
//! solve per parameter) on grids with about 1e3, 1e4 and 1e5 GMC states
//! (2-node full-support controllers for both players at fixed non-uniform
//! logits, sparse LU for both methods):
//!
//! * `value`: one evaluation (refill, factorisation, one solve);
//! * `adjoint`: value and the gradient of all controller probabilities;
//! * `forward_setup`: LU of `I - Q` and the right-hand sides `r_k` of all
//!   parameters ([`ForwardSensitivities::new`]);
//! * `forward_solve`: one parameter's sensitivity (one solve);
//! * `forward_gradient`: all parameters (only where it takes under a few
//!   seconds: the smallest size).
//!
//! A forward gradient costs `value + forward_setup + K forward_solve`;
//! `experiments/gradient-methods/run.py` writes that and the ratio to the
//! adjoint into `results/gradient-methods.{csv,md}`. Every fixture checks
//! forward against adjoint derivatives before anything is timed.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use posg_fsc::controller::{Probabilities, Support};
use posg_fsc::game::grid::GridSpec;
use posg_fsc::optimise::{Objective, Softmax, Structure};
use posg_fsc::value::Evaluator;
use posg_fsc::value::ForwardSensitivities;
use posg_fsc::value::{DEFAULT_TOLERANCE, SolverMethod, SolverSettings};

/// (grid side, defender nodes, adversary nodes).
const SIZES: [(usize, usize, usize); 3] = [(3, 1, 1), (5, 2, 1), (8, 2, 2)];

/// Grid sides of the `gradient-methods` group: about 1e3, 1e4 and 1e5 GMC states.
const METHOD_SIDES: [usize; 3] = [8, 32, 96];

/// Full-support structures with at most this many parameters are timed
/// for the whole forward gradient, not only per solve.
const FULL_FORWARD_PARAMETERS: usize = 2000;

fn game_and_structure(
    side: usize,
    def: usize,
    adv: usize,
) -> (posg_fsc::game::Posg, posg_fsc::automaton::Dra, Structure) {
    let game = GridSpec::square(side).build().expect("a valid grid");
    let formula = posg_fsc::ltl::parse("!unsafe U goal").expect("a valid formula");
    let dra = posg_fsc::ltl::translate(&formula).expect("a translatable formula");
    let structure = Structure::full(&game, def, adv, false);
    (game, dra, structure)
}

fn logits(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| ((k * 7919) % 13) as f64 / 13.0 - 0.5)
        .collect()
}

fn objective(side: usize, def: usize, adv: usize) -> (Objective, Vec<f64>, Vec<f64>) {
    let (game, dra, structure) = game_and_structure(side, def, adv);
    let objective = Objective::new(
        &game,
        &dra,
        Softmax::new(&structure.defender, false),
        Softmax::new(&structure.adversary, false),
        &SolverSettings::default(),
    )
    .expect("an evaluable structure");
    let phi_def = logits(objective.defender().num_parameters());
    let phi_adv = logits(objective.adversary().num_parameters());
    (objective, phi_def, phi_adv)
}

fn finite_differences(objective: &mut Objective, def: &[f64], adv: &[f64]) -> f64 {
    let h = 1e-6;
    let base = objective.value(def, adv).expect("value");
    let mut total = 0.0;
    let (mut d, mut a) = (def.to_vec(), adv.to_vec());
    for k in 0..d.len() {
        d[k] += h;
        total += (objective.value(&d, &a).expect("value") - base) / h;
        d[k] -= h;
    }
    for k in 0..a.len() {
        a[k] += h;
        total += (objective.value(&d, &a).expect("value") - base) / h;
        a[k] -= h;
    }
    total
}

fn bench(c: &mut Criterion) {
    for (side, def, adv) in SIZES {
        let (mut objective, phi_def, mut phi_adv) = objective(side, def, adv);
        let parameters = phi_def.len() + phi_adv.len();
        let id = format!("{side}x{side}-{def}-{adv}-p{parameters}");
        let mut group = c.benchmark_group("gradient");
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(3))
            .warm_up_time(Duration::from_millis(500));
        group.bench_function(BenchmarkId::new("value", &id), |b| {
            b.iter(|| {
                objective
                    .value(black_box(&phi_def), black_box(&phi_adv))
                    .expect("value")
            })
        });
        group.bench_function(BenchmarkId::new("value_and_gradient", &id), |b| {
            b.iter(|| {
                // A new point every time, so the cache never answers.
                phi_adv[0] = -phi_adv[0];
                objective
                    .point(black_box(&phi_def), black_box(&phi_adv))
                    .expect("point")
            })
        });
        group.bench_function(BenchmarkId::new("finite_differences", &id), |b| {
            b.iter(|| finite_differences(&mut objective, black_box(&phi_def), black_box(&phi_adv)))
        });
        group.finish();
    }
}

/// The evaluator (sparse LU) of a grid with 2-node full-support
/// controllers, and the probabilities at fixed non-uniform logits.
fn method_fixture(side: usize) -> (Evaluator, Probabilities, Probabilities) {
    let (game, dra, structure) = game_and_structure(side, 2, 2);
    let probabilities = |fsc| {
        let softmax = Softmax::new(fsc, false);
        softmax.probabilities(&logits(softmax.num_parameters()))
    };
    let (pd, pa) = (
        probabilities(&structure.defender),
        probabilities(&structure.adversary),
    );
    let settings = SolverSettings {
        method: SolverMethod::Lu,
        ..SolverSettings::default()
    };
    let evaluator = Evaluator::new(
        &game,
        &dra,
        &Support::of(&structure.defender),
        &Support::of(&structure.adversary),
        &settings,
    )
    .expect("an evaluable structure");
    (evaluator, pd, pa)
}

fn methods(c: &mut Criterion) {
    for side in METHOD_SIDES {
        let (mut evaluator, pd, pa) = method_fixture(side);
        let (evaluation, gradient) = evaluator
            .evaluate_with_gradient(&pd, &pa)
            .expect("value and gradient");
        assert!((0.0..=1.0).contains(&evaluation.value) && evaluation.residual < 1e-9);
        let mut forward = ForwardSensitivities::new(&evaluator, &pd, &pa, DEFAULT_TOLERANCE)
            .expect("forward sensitivities");
        let parameters = forward.num_parameters();
        let scale = gradient
            .defender
            .iter()
            .chain(&gradient.adversary)
            .fold(0.0f64, |m, g| m.max(g.abs()));
        for k in (0..parameters).step_by(parameters / 16) {
            let adjoint = if k < pd.entries.len() {
                gradient.defender[k]
            } else {
                gradient.adversary[k - pd.entries.len()]
            };
            let (reference, _) = forward.sensitivity(k).expect("one sensitivity");
            assert!((reference - adjoint).abs() <= 1e-9 * scale, "parameter {k}");
        }
        let id = format!(
            "{side}x{side}-s{}-p{parameters}",
            evaluator.gmc().num_states()
        );
        let mut group = c.benchmark_group("gradient-methods");
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(5))
            .warm_up_time(Duration::from_secs(1));
        group.bench_function(BenchmarkId::new("value", &id), |b| {
            b.iter(|| {
                evaluator
                    .evaluate(black_box(&pd), black_box(&pa))
                    .expect("value")
            })
        });
        group.bench_function(BenchmarkId::new("adjoint", &id), |b| {
            b.iter(|| {
                evaluator
                    .evaluate_with_gradient(black_box(&pd), black_box(&pa))
                    .expect("value and gradient")
            })
        });
        group.bench_function(BenchmarkId::new("forward_setup", &id), |b| {
            b.iter(|| {
                ForwardSensitivities::new(&evaluator, &pd, &pa, DEFAULT_TOLERANCE)
                    .expect("forward sensitivities")
            })
        });
        let mut k = 0;
        group.bench_function(BenchmarkId::new("forward_solve", &id), |b| {
            b.iter(|| {
                k = (k + 7919) % parameters;
                forward.sensitivity(black_box(k)).expect("one sensitivity")
            })
        });
        if parameters <= FULL_FORWARD_PARAMETERS {
            group.bench_function(BenchmarkId::new("forward_gradient", &id), |b| {
                b.iter(|| forward.gradient().expect("forward gradient"))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bench, methods);
criterion_main!(benches);
