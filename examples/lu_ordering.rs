//! Fill and time of faer's sparse LU of `I - Q` (method.md, the transient
//! system) under different fill-reducing column orderings, on a grid of the
//! paper's family (unsafe cell `s(w+1)`, goal the last cell, `!unsafe U
//! goal`, 2-node uniform controllers for both players). Issue 15's question:
//! does another ordering than faer's default (COLAMD) cut the fill?
//!
//! `cargo run --release --example lu_ordering -- SIDE ORDERING FACTORISATION`
//! prints one CSV row (`experiments/lu-ordering/run.py` collects them):
//!
//! * ORDERING: `colamd` (faer's, on the columns of `A`), `amd` (approximate
//!   minimum degree on `A + A^T`), `natural` (the GMC's state order), `auto`
//!   (only with `multifrontal`: the order [`LuSolver`] picks, the cheaper of
//!   AMD and nested dissection on the compressed graph of `A + A^T`);
//! * FACTORISATION: `faer` (faer's own symbolic analysis: always COLAMD),
//!   `supernodal` (faer's supernodal LU with the given column order: its
//!   structure is the Cholesky factor of `A^T A`, a bound for any row
//!   pivoting), `simplicial` (faer's left-looking LU: the fill it actually
//!   produces), `multifrontal` (posg-fsc's own [`LuSolver`]: multifrontal,
//!   no pivoting, on the pattern of `A + A^T`).
//!
//! Fill: the exact `nnz(L) + nnz(U)` for `simplicial`; the entries
//! `multifrontal` stores (dense supernode blocks counted whole,
//! [`LuSolver::factor_entries`]); for `supernodal` and `faer` the sum of
//! the column counts of the `A^T A` Cholesky factor that the supernodal
//! structure is built from (`L` and `U` each hold about that many
//! entries); and the memory the numeric factorisation added.

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::reborrow::IntoConst;
use faer::sparse::linalg::lu::{NumericLu, factorize_symbolic_lu, simplicial, supernodal};
use faer::sparse::linalg::{SymbolicSupernodalParams, amd, colamd, qr};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};
use posg_fsc::controller::{Fsc, Role, Support};
use posg_fsc::game::grid::GridSpec;
use posg_fsc::value::{Evaluator, LuSolver, SolverMethod, SolverSettings, SparsePattern};

/// `A = I - Q` row-wise: `n` rows, row offsets, column indices, values.
struct System {
    n: usize,
    row_offsets: Vec<usize>,
    columns: Vec<usize>,
    values: Vec<f64>,
}

/// One measurement: seconds of each phase, fill and memory.
struct Row {
    ordering_seconds: f64,
    symbolic_seconds: f64,
    numeric_seconds: f64,
    solve_seconds: f64,
    fill: usize,
    numeric_mib: f64,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: lu_ordering SIDE colamd|amd|natural supernodal|simplicial, SIDE colamd faer or SIDE auto multifrontal";
    let (Some(side), Some(ordering), Some(factorisation)) = (
        args.get(1).and_then(|s| s.parse::<usize>().ok()),
        args.get(2),
        args.get(3),
    ) else {
        eprintln!("{usage}");
        std::process::exit(2);
    };
    let system = transient_system(side);
    let (pattern, values) = (&system, &system.values);
    let b: Vec<f64> = (0..pattern.n).map(|i| 1.0 + (i % 7) as f64).collect();
    let a = SymbolicSparseColMatRef::new_checked(
        pattern.n,
        pattern.n,
        &pattern.row_offsets,
        None,
        &pattern.columns,
    );
    let a = SparseColMatRef::new(a, values);
    let mut x = b.clone();
    let row = match (ordering.as_str(), factorisation.as_str()) {
        ("colamd", "faer") => faer_default(a, &mut x),
        ("auto", "multifrontal") => multifrontal_lu(&system, &mut x),
        (ordering, "supernodal" | "simplicial") => {
            let start = Instant::now();
            let (perm, inverse) = column_order(a, ordering).unwrap_or_else(|| {
                eprintln!("{usage}");
                std::process::exit(2);
            });
            let ordering_seconds = start.elapsed().as_secs_f64();
            let order = PermRef::new_checked(&perm, &inverse, pattern.n);
            let mut row = if factorisation == "supernodal" {
                supernodal_lu(a, order, &mut x)
            } else {
                simplicial_lu(a, order, &mut x)
            };
            row.ordering_seconds = ordering_seconds;
            row
        }
        _ => {
            eprintln!("{usage}");
            std::process::exit(2);
        }
    };
    let residual = relative_residual(&system, &x, &b);
    println!(
        "{side}x{side},{},{},{ordering},{factorisation},{:.3},{:.3},{:.3},{:.3},{},{:.0},{:e}",
        pattern.n,
        pattern.columns.len(),
        row.ordering_seconds,
        row.symbolic_seconds,
        row.numeric_seconds,
        row.solve_seconds,
        row.fill,
        row.numeric_mib,
        residual,
    );
}

/// `I - Q` of the grid's GMC (uniform controllers), row-wise. The numbers
/// are filled before the solve, so one BiCGSTAB iteration (not converged)
/// is enough to get them.
fn transient_system(side: usize) -> System {
    let game = GridSpec::square(side).build().expect("a valid grid");
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

/// posg-fsc's own LU ([`LuSolver`]): its own ordering of `A + A^T`,
/// multifrontal, no pivoting; the analysis (ordering included) is the
/// symbolic time.
fn multifrontal_lu(system: &System, x: &mut [f64]) -> Row {
    let pattern = SparsePattern {
        n: system.n,
        row_offsets: system.row_offsets.clone(),
        columns: system.columns.clone(),
    };
    let before = resident_mib();
    let start = Instant::now();
    let mut lu = LuSolver::new(pattern, 1.0).expect("an analysis");
    let symbolic_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    lu.factorize(&system.values).expect("a factorisation");
    let numeric_seconds = start.elapsed().as_secs_f64();
    let numeric_mib = resident_mib() - before;
    let b = x.to_vec();
    let start = Instant::now();
    lu.solve(&b, x).expect("a solve");
    Row {
        ordering_seconds: 0.0,
        symbolic_seconds,
        numeric_seconds,
        solve_seconds: start.elapsed().as_secs_f64(),
        fill: lu.factor_entries(),
        numeric_mib,
    }
}

/// The column order `(perm, inverse)` named `ordering`, of faer's matrix
/// (the CSC view of `A`'s rows, that is `A^T`).
fn column_order(
    a: SparseColMatRef<'_, usize, f64>,
    ordering: &str,
) -> Option<(Vec<usize>, Vec<usize>)> {
    let n = a.ncols();
    let nnz = a.compute_nnz();
    let mut perm = vec![0; n];
    let mut inverse = vec![0; n];
    match ordering {
        "natural" => {
            perm = (0..n).collect();
            inverse = (0..n).collect();
        }
        "amd" => {
            let mut memory = MemBuffer::new(amd::order_maybe_unsorted_scratch::<usize>(n, nnz));
            amd::order_maybe_unsorted(
                &mut perm,
                &mut inverse,
                a.symbolic(),
                amd::Control::default(),
                MemStack::new(&mut memory),
            )
            .expect("an AMD order");
        }
        "colamd" => {
            let mut memory = MemBuffer::new(colamd::order_scratch::<usize>(n, n, nnz));
            colamd::order(
                &mut perm,
                &mut inverse,
                a.symbolic(),
                colamd::Control::default(),
                MemStack::new(&mut memory),
            )
            .expect("a COLAMD order");
        }
        _ => return None,
    }
    Some((perm, inverse))
}

/// faer's own symbolic and numeric LU (COLAMD), then `A x = b` (faer's
/// transposed solve).
fn faer_default(a: SparseColMatRef<'_, usize, f64>, x: &mut [f64]) -> Row {
    let n = a.ncols();
    let start = Instant::now();
    let symbolic = factorize_symbolic_lu(a.symbolic(), Default::default()).expect("a symbolic LU");
    let symbolic_done = Instant::now();
    let before = resident_mib();
    let mut numeric = NumericLu::new();
    let mut workspace =
        MemBuffer::new(symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()));
    let lu = symbolic
        .factorize_numeric_lu(
            &mut numeric,
            a,
            Par::Seq,
            MemStack::new(&mut workspace),
            Default::default(),
        )
        .expect("a numeric LU");
    let numeric_done = Instant::now();
    let numeric_mib = resident_mib() - before;
    let mut solve = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
    lu.solve_transpose_in_place_with_conj(
        Conj::No,
        MatMut::from_column_major_slice_mut(x, n, 1),
        Par::Seq,
        MemStack::new(&mut solve),
    );
    let (col_counts, _) = ata_structure(a, lu.col_perm());
    Row {
        ordering_seconds: 0.0,
        symbolic_seconds: (symbolic_done - start).as_secs_f64(),
        numeric_seconds: (numeric_done - symbolic_done).as_secs_f64(),
        solve_seconds: numeric_done.elapsed().as_secs_f64(),
        fill: col_counts,
        numeric_mib,
    }
}

/// The sum of the `A^T A` Cholesky column counts under `order`, and the
/// time it took.
fn ata_structure(a: SparseColMatRef<'_, usize, f64>, order: PermRef<'_, usize>) -> (usize, f64) {
    let start = Instant::now();
    let n = a.ncols();
    let mut etree = vec![0; n];
    let mut postorder = vec![0; n];
    let mut col_counts = vec![0; n];
    let mut min_col = vec![0; n];
    let nnz = a.compute_nnz();
    let (mut values, mut col_ptr, mut row_idx) = (vec![0.0; nnz], vec![0; n + 1], vec![0; nnz]);
    let mut memory = MemBuffer::new(StackReq::any_of(&[
        qr::col_etree_scratch::<usize>(n, n),
        qr::postorder_scratch::<usize>(n),
        qr::column_counts_aat_scratch::<usize>(n, n),
    ]));
    let a_t = faer::sparse::utils::transpose(
        &mut values,
        &mut col_ptr,
        &mut row_idx,
        a,
        MemStack::new(&mut memory),
    )
    .into_const();
    let tree = qr::col_etree(
        a.symbolic(),
        Some(order),
        &mut etree,
        MemStack::new(&mut memory),
    );
    qr::postorder(&mut postorder, tree, MemStack::new(&mut memory));
    qr::column_counts_ata(
        &mut col_counts,
        &mut min_col,
        a_t.symbolic(),
        Some(order),
        tree,
        &postorder,
        MemStack::new(&mut memory),
    );
    (col_counts.iter().sum(), start.elapsed().as_secs_f64())
}

/// faer's supernodal LU with the column order `order` (its symbolic
/// structure from `A^T A`), then `A x = b`.
fn supernodal_lu(
    a: SparseColMatRef<'_, usize, f64>,
    order: PermRef<'_, usize>,
    x: &mut [f64],
) -> Row {
    let n = a.ncols();
    let nnz = a.compute_nnz();
    let start = Instant::now();
    let (mut values, mut col_ptr, mut row_idx) = (vec![0.0; nnz], vec![0; n + 1], vec![0; nnz]);
    let mut memory = MemBuffer::new(StackReq::any_of(&[
        StackReq::new::<usize>(n),
        qr::col_etree_scratch::<usize>(n, n),
        qr::postorder_scratch::<usize>(n),
        qr::column_counts_aat_scratch::<usize>(n, n),
        supernodal::factorize_supernodal_symbolic_lu_scratch::<usize>(n, n),
    ]));
    let a_t = faer::sparse::utils::transpose(
        &mut values,
        &mut col_ptr,
        &mut row_idx,
        a,
        MemStack::new(&mut memory),
    )
    .into_const();
    let mut etree = vec![0; n];
    let mut postorder = vec![0; n];
    let mut col_counts = vec![0; n];
    let mut min_col = vec![0; n];
    let tree = qr::col_etree(
        a.symbolic(),
        Some(order),
        &mut etree,
        MemStack::new(&mut memory),
    );
    qr::postorder(&mut postorder, tree, MemStack::new(&mut memory));
    qr::column_counts_ata(
        &mut col_counts,
        &mut min_col,
        a_t.symbolic(),
        Some(order),
        tree,
        &postorder,
        MemStack::new(&mut memory),
    );
    let symbolic = supernodal::factorize_supernodal_symbolic_lu(
        a.symbolic(),
        Some(order),
        &min_col,
        tree,
        &col_counts,
        MemStack::new(&mut memory),
        SymbolicSupernodalParams::default(),
    )
    .expect("a symbolic LU");
    let symbolic_done = Instant::now();
    let before = resident_mib();
    let mut lu = supernodal::SupernodalLu::<usize, f64>::new();
    let (mut row_perm, mut row_inverse) = (vec![0; n], vec![0; n]);
    let mut workspace = MemBuffer::new(supernodal::factorize_supernodal_numeric_lu_scratch::<
        usize,
        f64,
    >(&symbolic, Default::default()));
    supernodal::factorize_supernodal_numeric_lu(
        &mut row_perm,
        &mut row_inverse,
        &mut lu,
        a,
        a_t,
        order,
        &symbolic,
        Par::Seq,
        MemStack::new(&mut workspace),
        Default::default(),
    )
    .expect("a numeric LU");
    let numeric_done = Instant::now();
    let numeric_mib = resident_mib() - before;
    let mut solve = MemBuffer::new(supernodal::solve_transpose_in_place_scratch::<usize, f64>(
        n,
        1,
        Par::Seq,
    ));
    lu.solve_transpose_in_place_with_conj(
        PermRef::new_checked(&row_perm, &row_inverse, n),
        order,
        Conj::No,
        MatMut::from_column_major_slice_mut(x, n, 1),
        Par::Seq,
        MemStack::new(&mut solve),
    );
    Row {
        ordering_seconds: 0.0,
        symbolic_seconds: (symbolic_done - start).as_secs_f64(),
        numeric_seconds: (numeric_done - symbolic_done).as_secs_f64(),
        solve_seconds: numeric_done.elapsed().as_secs_f64(),
        fill: col_counts.iter().sum(),
        numeric_mib,
    }
}

/// faer's simplicial (left-looking, partial pivoting) LU with the column
/// order `order`, then `A x = b`; its fill is exact.
fn simplicial_lu(
    a: SparseColMatRef<'_, usize, f64>,
    order: PermRef<'_, usize>,
    x: &mut [f64],
) -> Row {
    let n = a.ncols();
    let before = resident_mib();
    let start = Instant::now();
    let mut lu = simplicial::SimplicialLu::<usize, f64>::new();
    let (mut row_perm, mut row_inverse) = (vec![0; n], vec![0; n]);
    let mut workspace = MemBuffer::new(simplicial::factorize_simplicial_numeric_lu_scratch::<
        usize,
        f64,
    >(n, n));
    simplicial::factorize_simplicial_numeric_lu(
        &mut row_perm,
        &mut row_inverse,
        &mut lu,
        a,
        order,
        MemStack::new(&mut workspace),
    )
    .expect("a numeric LU");
    let numeric_done = Instant::now();
    let numeric_mib = resident_mib() - before;
    let mut solve = MemBuffer::new(simplicial::solve_transpose_in_place_scratch::<usize, f64>(
        n,
        1,
        Par::Seq,
    ));
    lu.solve_transpose_in_place_with_conj(
        PermRef::new_checked(&row_perm, &row_inverse, n),
        order,
        Conj::No,
        MatMut::from_column_major_slice_mut(x, n, 1),
        Par::Seq,
        MemStack::new(&mut solve),
    );
    Row {
        ordering_seconds: 0.0,
        symbolic_seconds: 0.0,
        numeric_seconds: (numeric_done - start).as_secs_f64(),
        solve_seconds: numeric_done.elapsed().as_secs_f64(),
        fill: lu.l_factor_unsorted().compute_nnz() + lu.u_factor_unsorted().compute_nnz(),
        numeric_mib,
    }
}

/// `||A x - b||_inf / ||b||_inf`.
fn relative_residual(system: &System, x: &[f64], b: &[f64]) -> f64 {
    let max_abs = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0_f64, |m, e| m.max(e.abs()));
    let residual = max_abs(&mut (0..system.n).map(|row| {
        let range = system.row_offsets[row]..system.row_offsets[row + 1];
        let ax: f64 = system.columns[range.clone()]
            .iter()
            .zip(&system.values[range])
            .map(|(&c, &a)| a * x[c])
            .sum();
        ax - b[row]
    }));
    residual / max_abs(&mut b.iter().copied())
}

/// The resident memory of this process in MiB (Linux; 0 elsewhere).
fn resident_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            status
                .lines()
                .find_map(|line| line.strip_prefix("VmRSS:"))
                .and_then(|kib| kib.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(0.0, |kib| kib / 1024.0)
}
