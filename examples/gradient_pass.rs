//! Times the adjoint gradient pass `Gmc::add_adjoint_gradient` alone (15
//! passes, median and minimum) on a `side x side` grid with random unsafe
//! cells, 2-node uniform controllers for both players and `!unsafe U goal`,
//! with adjoint weights `1 + (m mod 7)` on the transient states. The
//! checksum (sum of all partial derivatives) lets two builds be compared.
//!
//! `cargo run --release --example gradient_pass -- 128` (193316 GMC
//! states); `RAYON_NUM_THREADS=1` for one thread.

use posg_fsc::controller::{Fsc, Role, Support};
use posg_fsc::game::grid::{GridSpec, RandomUnsafe};
use posg_fsc::solver::SolverSettings;
use posg_fsc::value::Evaluator;
use std::time::Instant;

fn main() {
    let side: usize = std::env::args().nth(1).map_or(128, |s| s.parse().unwrap());
    let cells = side * side;
    let spec = GridSpec {
        width: side,
        height: side,
        unsafe_cells: vec![],
        goal_cells: vec![cells - 1],
        random_unsafe: Some(RandomUnsafe {
            count: cells / 20,
            seed: 1,
        }),
        ..GridSpec::default()
    };
    let game = spec.build().unwrap();
    let dra = posg_fsc::ltl::translate(&posg_fsc::ltl::parse("!unsafe U goal").unwrap()).unwrap();
    let def = Fsc::uniform(
        Role::Defender,
        2,
        game.defender().num_observations(),
        game.defender().num_actions(),
    );
    let adv = Fsc::uniform(
        Role::Adversary,
        2,
        game.adversary().num_observations(),
        game.adversary().num_actions(),
    );
    let mut ev = Evaluator::new(
        &game,
        &dra,
        &Support::of(&def),
        &Support::of(&adv),
        &SolverSettings::default(),
    )
    .unwrap();
    let (pd, pa) = (
        Support::probabilities_of(&def),
        Support::probabilities_of(&adv),
    );
    ev.evaluate(&pd, &pa).unwrap();
    let x = ev.state_values().to_vec();
    let y: Vec<f64> = (0..x.len())
        .map(|m| {
            if ev.recurrence().transient_index[m] != u32::MAX {
                1.0 + (m % 7) as f64
            } else {
                0.0
            }
        })
        .collect();
    let mut gmc = ev.gmc().clone();
    let (mut gd, mut ga) = (vec![0.0; pd.entries.len()], vec![0.0; pa.entries.len()]);
    let mut times = Vec::new();
    for _ in 0..15 {
        gd.fill(0.0);
        ga.fill(0.0);
        let t = Instant::now();
        gmc.add_adjoint_gradient(&x, &y, &mut gd, &mut ga);
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let sum: f64 = gd.iter().chain(&ga).sum();
    println!(
        "states {} transient {} params {} pass median {:.4} ms min {:.4} ms checksum {:e}",
        gmc.num_states(),
        ev.recurrence().transient.len(),
        gd.len() + ga.len(),
        times[7] * 1e3,
        times[0] * 1e3,
        sum
    );
}
