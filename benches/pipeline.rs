//! The stages of one exact evaluation on grids of the paper's family with
//! 2-node uniform controllers for both players and `!unsafe U goal`:
//! game load (JSON), GMC build, refill, recurrence analysis, preparation
//! (GMC + analysis + symbolic LU), value, value + gradient.
//!
//! Every fixture checks its result before it is timed.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use posg_fsc::automaton::Dra;
use posg_fsc::controller::{Fsc, Probabilities, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::game::grid::{GridSpec, RandomUnsafe};
use posg_fsc::value::Evaluator;
use posg_fsc::value::Gmc;
use posg_fsc::value::Recurrence;
use posg_fsc::value::SolverSettings;

const SIDES: [usize; 3] = [8, 24, 64];

struct Fixture {
    game: Posg,
    dra: Dra,
    supports: (Support, Support),
    probabilities: (Probabilities, Probabilities),
}

fn fixture(side: usize) -> Fixture {
    let cells = side * side;
    let spec = GridSpec {
        width: side,
        height: side,
        unsafe_cells: Vec::new(),
        goal_cells: vec![cells - 1],
        random_unsafe: Some(RandomUnsafe {
            count: cells / 20,
            seed: 1,
        }),
        ..GridSpec::default()
    };
    let game = spec.build().expect("grid");
    let dra = posg_fsc::ltl::translate(&posg_fsc::ltl::parse("!unsafe U goal").unwrap()).unwrap();
    let uniform = |role, player: &posg_fsc::game::Player| {
        Fsc::uniform(role, 2, player.num_observations(), player.num_actions())
    };
    let (def, adv) = (
        uniform(Role::Defender, game.defender()),
        uniform(Role::Adversary, game.adversary()),
    );
    let fixture = Fixture {
        supports: (Support::of(&def), Support::of(&adv)),
        probabilities: (
            Support::probabilities_of(&def),
            Support::probabilities_of(&adv),
        ),
        game,
        dra,
    };
    let mut evaluator = prepare(&fixture);
    let evaluation = evaluator
        .evaluate(&fixture.probabilities.0, &fixture.probabilities.1)
        .unwrap();
    assert!(evaluation.value > 0.0 && evaluation.value < 1.0 && evaluation.residual < 1e-10);
    fixture
}

fn prepare(f: &Fixture) -> Evaluator {
    Evaluator::new(
        &f.game,
        &f.dra,
        &f.supports.0,
        &f.supports.1,
        &SolverSettings::default(),
    )
    .unwrap()
}

fn stages(c: &mut Criterion) {
    let mut group = c.benchmark_group("pipeline");
    group.sample_size(10);
    for side in SIDES {
        let f = fixture(side);
        let states = prepare(&f).gmc().num_states();
        let id =
            |stage: &str| BenchmarkId::new(stage, format!("{side}x{side} ({states} GMC states)"));
        let json = posg_fsc::game::file::to_json_string(&f.game);
        group.bench_function(id("game load"), |b| {
            b.iter(|| posg_fsc::game::file::from_json_str(&json, "grid.posg.json").unwrap())
        });
        group.bench_function(id("gmc build"), |b| {
            b.iter(|| Gmc::build(&f.game, &f.dra, &f.supports.0, &f.supports.1).unwrap())
        });
        let mut gmc = Gmc::build(&f.game, &f.dra, &f.supports.0, &f.supports.1).unwrap();
        group.bench_function(id("refill"), |b| {
            b.iter(|| gmc.refill(&f.probabilities.0, &f.probabilities.1))
        });
        group.bench_function(id("analysis"), |b| {
            b.iter(|| Recurrence::analyse(&gmc, &f.dra))
        });
        group.bench_function(id("prepare"), |b| b.iter(|| prepare(&f)));
        let mut evaluator = prepare(&f);
        group.bench_function(id("value"), |b| {
            b.iter(|| {
                evaluator
                    .evaluate(&f.probabilities.0, &f.probabilities.1)
                    .unwrap()
            })
        });
        group.bench_function(id("value+gradient"), |b| {
            b.iter(|| {
                evaluator
                    .evaluate_with_gradient(&f.probabilities.0, &f.probabilities.1)
                    .unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, stages);
criterion_main!(benches);
