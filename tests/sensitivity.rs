//! Forward sensitivities (one solve per parameter) against the adjoint
//! gradient (one transposed solve and one pass), on random small games and
//! on a grid large enough for the parallel gradient pass.

mod common;

use posg_fsc::controller::{Fsc, Probabilities, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::game::grid::GridSpec;
use posg_fsc::optimise::{Softmax, Structure};
use posg_fsc::value::ForwardSensitivities;
use posg_fsc::value::PARALLEL_GRADIENT_ROWS;
use posg_fsc::value::{DEFAULT_TOLERANCE, SolverMethod, SolverSettings};
use posg_fsc::value::{Evaluator, Gradient};
use proptest::prelude::*;

fn lu() -> SolverSettings {
    SolverSettings {
        method: SolverMethod::Lu,
        ..SolverSettings::default()
    }
}

fn largest(values: &[f64]) -> f64 {
    values.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

fn adjoint(evaluator: &mut Evaluator, def: &Probabilities, adv: &Probabilities) -> Gradient {
    evaluator.evaluate_with_gradient(def, adv).unwrap().1
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(200)
    })]

    #[test]
    fn forward_sensitivities_agree_with_the_adjoint_gradient(seed in any::<u64>()) {
        let game: Posg = from_json_str(&common::random::game_json(seed), "random.posg.json").unwrap();
        let dra = common::random::dra(seed);
        let def = common::random::controller(seed, &game, Role::Defender);
        let adv = common::random::controller(seed, &game, Role::Adversary);
        let (pd, pa) = (Support::probabilities_of(&def), Support::probabilities_of(&adv));
        let mut evaluator =
            Evaluator::new(&game, &dra, &Support::of(&def), &Support::of(&adv), &lu()).unwrap();
        let gradient = adjoint(&mut evaluator, &pd, &pa);
        let mut forward = ForwardSensitivities::new(&evaluator, &pd, &pa, DEFAULT_TOLERANCE).unwrap();
        prop_assert_eq!(forward.num_parameters(), pd.entries.len() + pa.entries.len());
        let reference = forward.gradient().unwrap();
        prop_assert!(reference.residual < 1e-12);
        let scale = 1.0 + largest(&gradient.defender).max(largest(&gradient.adversary));
        for (k, (f, a)) in reference.defender.iter().zip(&gradient.defender).enumerate() {
            prop_assert!((f - a).abs() < 1e-10 * scale, "defender {}: forward {} adjoint {}", k, f, a);
        }
        for (k, (f, a)) in reference.adversary.iter().zip(&gradient.adversary).enumerate() {
            prop_assert!((f - a).abs() < 1e-10 * scale, "adversary {}: forward {} adjoint {}", k, f, a);
        }
    }
}

/// A 40x40 grid of the paper's family with 2-node controllers at
/// non-uniform probabilities: about 19000 GMC states, of which more than
/// [`PARALLEL_GRADIENT_ROWS`] are transient.
fn large_grid() -> (Evaluator, Probabilities, Probabilities) {
    let side = 40;
    let game = GridSpec {
        width: side,
        height: side,
        unsafe_cells: vec![side + 1, 3 * side + 5],
        goal_cells: vec![side * side - 1],
        ..GridSpec::default()
    }
    .build()
    .unwrap();
    let dra = posg_fsc::ltl::translate(&posg_fsc::ltl::parse("!unsafe U goal").unwrap()).unwrap();
    let structure = Structure::full(&game, 2, 2, false);
    let probabilities = |fsc: &Fsc| {
        let softmax = Softmax::new(fsc, false);
        let logits: Vec<f64> = (0..softmax.num_parameters())
            .map(|k| ((k * 7919) % 13) as f64 / 13.0 - 0.5)
            .collect();
        softmax.probabilities(&logits)
    };
    let (pd, pa) = (
        probabilities(&structure.defender),
        probabilities(&structure.adversary),
    );
    let evaluator = Evaluator::new(
        &game,
        &dra,
        &Support::of(&structure.defender),
        &Support::of(&structure.adversary),
        &lu(),
    )
    .unwrap();
    (evaluator, pd, pa)
}

#[test]
fn the_parallel_gradient_pass_agrees_with_forward_sensitivities_and_is_reproducible() {
    let (mut evaluator, pd, pa) = large_grid();
    let gradient = adjoint(&mut evaluator, &pd, &pa);
    assert!(evaluator.recurrence().transient.len() > PARALLEL_GRADIENT_ROWS);
    let mut forward = ForwardSensitivities::new(&evaluator, &pd, &pa, DEFAULT_TOLERANCE).unwrap();
    let scale = largest(&gradient.defender).max(largest(&gradient.adversary));
    assert!(scale > 1e-6, "the gradient is not trivially zero: {scale}");
    let num_defender = pd.entries.len();
    let step = forward.num_parameters() / 40;
    for k in (0..forward.num_parameters()).step_by(step) {
        let (reference, _) = forward.sensitivity(k).unwrap();
        let adjoint = if k < num_defender {
            gradient.defender[k]
        } else {
            gradient.adversary[k - num_defender]
        };
        assert!(
            (reference - adjoint).abs() < 1e-10 * scale,
            "parameter {k}: forward {reference} adjoint {adjoint}"
        );
    }
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let again = pool.install(|| adjoint(&mut evaluator, &pd, &pa));
        assert!(
            again
                .defender
                .iter()
                .zip(&gradient.defender)
                .all(|(a, b)| a.to_bits() == b.to_bits())
                && again
                    .adversary
                    .iter()
                    .zip(&gradient.adversary)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
            "the gradient with {threads} threads differs from the first"
        );
    }
}
