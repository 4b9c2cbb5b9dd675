use posg_fsc::controller::{Fsc, Role, Support};
use posg_fsc::game::grid::GridSpec;
use posg_fsc::value::{Evaluator, LuSolver, SolverMethod, SolverSettings, SparsePattern};
use std::time::Instant;
struct System {
    n: usize,
    row_offsets: Vec<usize>,
    columns: Vec<usize>,
    values: Vec<f64>,
}
fn main() {
    let side: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let system = transient_system(side);
    let pattern = SparsePattern {
        n: system.n,
        row_offsets: system.row_offsets.clone(),
        columns: system.columns.clone(),
    };
    let (mut sym, mut num, mut sol) = (f64::MAX, f64::MAX, f64::MAX);
    let mut lu = LuSolver::new(pattern.clone(), 1.0).unwrap();
    for _ in 0..3 {
        let t = Instant::now();
        lu = LuSolver::new(pattern.clone(), 1.0).unwrap();
        sym = sym.min(t.elapsed().as_secs_f64());
    }
    for _ in 0..3 {
        let t = Instant::now();
        lu.factorize(&system.values).unwrap();
        num = num.min(t.elapsed().as_secs_f64());
    }
    let b = vec![1.0; system.n];
    let mut x = vec![0.0; system.n];
    for _ in 0..3 {
        let t = Instant::now();
        lu.solve(&b, &mut x).unwrap();
        sol = sol.min(t.elapsed().as_secs_f64());
    }
    println!(
        "{side}: symbolic {sym:.3} numeric {num:.3} solve {sol:.3} fill {}",
        lu.factor_entries()
    );
}
/// `I - Q` of the grid's GMC (uniform controllers), row-wise. The numbers
/// are filled before the solve, so one BiCGSTAB iteration (not converged)
/// is enough to get them.
fn transient_system(side: usize) -> System {
    let game = GridSpec {
        width: side,
        height: side,
        unsafe_cells: vec![side + 1],
        goal_cells: vec![side * side - 1],
        ..GridSpec::default()
    }
    .build()
    .expect("a valid grid");
    let formula = posg_fsc::ltl::parse("!unsafe U goal").expect("a valid formula");
    let dra = posg_fsc::ltl::translate(&formula).expect("a translatable formula");
    let defender = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
    let adversary = Fsc::uniform_enabled(Role::Adversary, 2, game.adversary());
    let settings = SolverSettings {
        method: SolverMethod::Krylov,
        max_iterations: 1,
        ..SolverSettings::default()
    };
    let mut evaluator = Evaluator::new(
        &game,
        &dra,
        &Support::of(&defender),
        &Support::of(&adversary),
        &settings,
    )
    .expect("an evaluator");
    let _not_converged = evaluator.evaluate(
        &Support::probabilities_of(&defender),
        &Support::probabilities_of(&adversary),
    );
    let (pattern, values) = evaluator.system();
    System {
        n: pattern.n,
        row_offsets: pattern.row_offsets.clone(),
        columns: pattern.columns.clone(),
        values: values.to_vec(),
    }
}
