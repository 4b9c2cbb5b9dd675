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

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use posg_fsc::game::grid::GridSpec;
use posg_fsc::optimise::{Objective, Softmax, Structure};
use posg_fsc::solver::SolverSettings;

/// (grid side, defender nodes, adversary nodes).
const SIZES: [(usize, usize, usize); 3] = [(3, 1, 1), (5, 2, 1), (8, 2, 2)];

fn objective(side: usize, def: usize, adv: usize) -> (Objective, Vec<f64>, Vec<f64>) {
    let cells = side * side;
    let spec = GridSpec {
        width: side,
        height: side,
        unsafe_cells: vec![side + 1],
        goal_cells: vec![cells - 1],
        ..GridSpec::default()
    };
    let game = spec.build().expect("a valid grid");
    let formula = posg_fsc::ltl::parse("!unsafe U goal").expect("a valid formula");
    let dra = posg_fsc::ltl::translate(&formula).expect("a translatable formula");
    let structure = Structure::full(&game, def, adv, false);
    let objective = Objective::new(
        &game,
        &dra,
        Softmax::new(&structure.defender, false),
        Softmax::new(&structure.adversary, false),
        &SolverSettings::default(),
    )
    .expect("an evaluable structure");
    let logits = |n: usize| {
        (0..n)
            .map(|k| ((k * 7919) % 13) as f64 / 13.0 - 0.5)
            .collect::<Vec<f64>>()
    };
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

criterion_group!(benches, bench);
criterion_main!(benches);
