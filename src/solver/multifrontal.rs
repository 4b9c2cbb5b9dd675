//! Multifrontal sparse LU of `A = I - Q` without pivoting, on the symmetric
//! pattern of `A + A^T` (method.md section 2, the transient system).
//!
//! `A` is a nonsingular M-matrix whose rows are weakly diagonally dominant
//! (`Q` substochastic), and so is `P A P^T` for any permutation `P`; Gaussian
//! elimination keeps both properties in every Schur complement, so it needs
//! no pivoting and its growth factor is at most 2 (Wilkinson). The factors
//! then have the structure of the Cholesky factor of `P (A + A^T) P^T`:
//! `L` its lower and `U` its upper triangle, which faer's symbolic Cholesky
//! analysis computes, with its (relaxed) supernodes, for the fill-reducing
//! ordering `P` of [`super::ordering`]. A grid-like chain fills far less
//! this way than under a column ordering that must leave room for row
//! pivoting (at 3.3e5 unknowns, 82 M entries in `L` and `U` against faer's
//! COLAMD structure of 157 M, and 0.2 times the factorisation time).
//!
//! The numeric phase is multifrontal: supernode `s` (columns `J_s`, below
//! them the rows `R_s`) owns a dense front on the indices `J_s ∪ R_s`, into
//! which the entries of `P A P^T` whose smaller index lies in `J_s` and the
//! update matrices of its children are added; dense LU of the `J_s` block,
//! two triangular solves and one product leave `L` and `U` for `J_s` and the
//! update matrix `F_RR - L_RJ U_JR` for the parent. The dense work is faer's.
//!
//! A pivot that is zero or not finite (the matrix was not what this module
//! assumes) is a [`SolverError::Singular`], never a wrong number; the caller
//! checks every solution's residual besides.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_unit_lower_triangular_in_place,
};
use faer::perm::PermRef;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};
use faer::{Accum, MatMut, Par, Side};

use super::ordering::{ClassOrder, fill_reducing_order};
use super::{SolverError, SparsePattern};

/// The most rows of a front: the positions in a front are stored as `u32`,
/// so a front holds at most `u32::MAX` entries (65,535 squared is below it,
/// 65,536 squared is not). Such a front alone is 34 GB of doubles.
const LARGEST_FRONT: usize = 65_535;

/// Fronts with at least this many rows use faer's parallel dense kernels.
const PARALLEL_FRONT_ROWS: usize = 512;

/// Diagonal blocks with at most this many columns are factorised by the
/// unblocked loop; larger ones recursively by halves.
const UNBLOCKED_COLUMNS: usize = 16;

/// One supernode: the columns `begin..end` of `P A P^T` and the rows below
/// them, `rows` (sorted, all at least `end`).
#[derive(Debug, Clone)]
struct Supernode {
    begin: usize,
    end: usize,
    /// Range of [`Structure::rows`] holding `R_s`.
    rows: std::ops::Range<usize>,
    /// Offset of the `(|J| + |R|) x |J|` panel `[L_JJ\U_JJ; L_RJ]` in
    /// [`MultifrontalLu::lower`].
    lower_offset: usize,
    /// Offset of the `|J| x |R|` panel `U_JR` in [`MultifrontalLu::upper`].
    upper_offset: usize,
    /// Offset of the `|J| x |J|` pivot block `L_JJ\U_JJ` in
    /// [`MultifrontalLu::pivots`].
    pivot_offset: usize,
    /// Range of [`Structure::assembly`]: the entries of `A` added to the front.
    assembly: std::ops::Range<usize>,
    /// Range of [`Structure::children`].
    children: std::ops::Range<usize>,
    /// Range of [`Structure::relative`]: where each row of `R_s` sits in the
    /// parent's front (empty for a root).
    relative: std::ops::Range<usize>,
}

impl Supernode {
    fn columns(&self) -> usize {
        self.end - self.begin
    }
}

/// The symbolic analysis: ordering, supernodes, and the maps that place the
/// entries of `A` and the children's update matrices in each front.
#[derive(Debug)]
struct Structure {
    n: usize,
    /// `permutation[new] = old`.
    permutation: Vec<usize>,
    supernodes: Vec<Supernode>,
    rows: Vec<usize>,
    /// `(k, position)`: entry `k` of `A`'s values goes to the front's
    /// column-major `position`.
    assembly: Vec<(u32, u32)>,
    children: Vec<usize>,
    relative: Vec<u32>,
    /// The supernodes children first, each subtree contiguous: the update
    /// matrices of a supernode's children are then the top of a stack.
    postorder: Vec<usize>,
    /// The most entries the stack of update matrices holds at once.
    stack_len: usize,
    lower_len: usize,
    upper_len: usize,
    pivots_len: usize,
    /// The most entries of a front's columns `[F_JJ; F_RJ]`.
    largest_left: usize,
    /// The most entries of a front's columns `[F_JR; F_RR]`.
    largest_right: usize,
}

/// LU factors of `P A P^T = L U` (unit lower `L`), stored by supernode.
///
/// [`Self::factorize`] keeps `L` and `U`, for any number of solves in both
/// directions. [`Self::factorize_and_solve`] applies `L^{-1}` to its
/// right-hand sides front by front while it factorises, and keeps of `L`
/// only the pivot blocks that `U^{-1}` needs: `L` below them, the larger
/// part of `L`, is never stored (forward elimination during the
/// factorisation, as in MUMPS), and the factors then serve no other solve.
#[derive(Debug)]
pub(crate) struct MultifrontalLu {
    structure: Structure,
    /// The panels `[L_JJ\U_JJ; L_RJ]`, if `L` is kept.
    lower: Vec<f64>,
    /// The panels `U_JR`.
    upper: Vec<f64>,
    /// The pivot blocks `L_JJ\U_JJ` alone, if `L` is not kept.
    pivots: Vec<f64>,
    /// Whether the last factorisation kept `L` (in [`Self::lower`]).
    lower_kept: bool,
    /// The columns `[F_JJ; F_RJ]` of the front being factorised when `L`
    /// is not kept (otherwise they are assembled in place in
    /// [`Self::lower`]).
    left: Vec<f64>,
    /// The columns `[F_JR; F_RR]` of the front being factorised.
    front: Vec<f64>,
    /// The update matrices waiting for their parents, column-major, in
    /// postorder.
    stack: Vec<f64>,
    /// The exits `e = L^{-1} (A 1)` of the Schur complement so far, in the
    /// elimination order: row `i` of the current Schur complement sums to
    /// `exits[i]` (the probability of leaving the states not yet eliminated).
    exits: Vec<f64>,
    /// For the front being factorised: per pivot row, its exit plus what it
    /// sends to the rows below the pivot block (see [`lu_gth`]).
    beyond: Vec<f64>,
}

impl MultifrontalLu {
    /// Symbolic analysis of `pattern`: ordering, supernodes, assembly maps;
    /// the storage of the factors is allocated by the first factorisation.
    pub(crate) fn new(pattern: &SparsePattern) -> Result<Self, SolverError> {
        let structure = Structure::analyse(pattern)?;
        Ok(Self {
            lower: Vec::new(),
            upper: Vec::new(),
            pivots: Vec::new(),
            lower_kept: false,
            left: Vec::new(),
            front: Vec::new(),
            stack: Vec::new(),
            exits: Vec::with_capacity(structure.n),
            beyond: Vec::new(),
            structure,
        })
    }

    /// Frees the numeric storage (the factors and the fronts' buffers),
    /// keeping the symbolic analysis: the next factorisation allocates it
    /// again. Until then there are no factors to solve with.
    pub(crate) fn release(&mut self) {
        self.lower = Vec::new();
        self.upper = Vec::new();
        self.pivots = Vec::new();
        self.left = Vec::new();
        self.front = Vec::new();
        self.stack = Vec::new();
        self.beyond = Vec::new();
        self.lower_kept = false;
    }

    /// Allocates the factors' storage where [`Self::new`] or
    /// [`Self::release`] left none (zeroed, so touched only when used):
    /// `L`'s panels only where they are kept.
    fn allocate_released(&mut self, keep_lower: bool) {
        let zeroed = |buffer: &mut Vec<f64>, len: usize| {
            if buffer.len() < len {
                *buffer = vec![0.0; len];
            }
        };
        if keep_lower {
            zeroed(&mut self.lower, self.structure.lower_len);
        }
        zeroed(&mut self.upper, self.structure.upper_len);
        zeroed(&mut self.front, self.structure.largest_right);
        self.stack.reserve(self.structure.stack_len);
    }

    /// Entries of `L` and `U` (a pivot block's two triangles share one
    /// square): the structural fill, whether or not `L` is kept.
    pub(crate) fn stored_entries(&self) -> usize {
        self.structure.lower_len + self.structure.upper_len
    }

    /// Floating-point operations of one numeric factorisation, from the
    /// supernodes alone: per front with `c` pivot columns and `r` rows below
    /// them, `2/3 c^3` for the pivot block's LU, `2 r c^2` for the two
    /// triangular solves and `2 r^2 c` for the update matrix.
    pub(crate) fn factorisation_flops(&self) -> f64 {
        self.structure
            .supernodes
            .iter()
            .map(|node| {
                let (c, r) = (node.columns() as f64, node.rows.len() as f64);
                2.0 / 3.0 * c * c * c + 2.0 * r * c * c + 2.0 * r * r * c
            })
            .sum()
    }

    /// Whether the last factorisation kept `L`: the factors then serve
    /// [`Self::solve_many_in_place`] and [`Self::solve_transpose_in_place`].
    pub(crate) fn lower_kept(&self) -> bool {
        self.lower_kept
    }

    /// Numeric factorisation of the matrix with the off-diagonal `values`
    /// (aligned with the pattern's entries; diagonal entries are ignored) and
    /// row sums `exits` (`A 1`, the probabilities of leaving `T`), keeping
    /// `L` and `U`. Each pivot is the sum of what its row still sends to the
    /// states not yet eliminated and of its exit (see [`lu_gth`]).
    pub(crate) fn factorize(&mut self, values: &[f64], exits: &[f64]) -> Result<(), SolverError> {
        self.factorize_fronts::<1>(values, exits, None)
    }

    /// Numeric factorisation with `values` that solves `A x_r = b_r` for
    /// `K` right-hand sides on the way (`x_r` holds `b_r` on entry) and
    /// keeps `U` and the pivot blocks only. Each solution is bit for bit
    /// the one [`Self::factorize`] and [`Self::solve_many_in_place`] give.
    pub(crate) fn factorize_and_solve<const K: usize>(
        &mut self,
        values: &[f64],
        exits: &[f64],
        mut xs: [&mut [f64]; K],
        work: &mut Vec<f64>,
    ) -> Result<(), SolverError> {
        self.permute_many_in(&xs, work);
        self.factorize_fronts::<K>(values, exits, Some(work))?;
        self.upper_solve::<K>(work);
        self.permute_many_out(work, &mut xs);
        Ok(())
    }

    /// The fronts in postorder: assembly, dense factorisation, `U_JR` and
    /// the update matrix. With `forward` (`K` vectors interleaved in the
    /// elimination order), also `x_r <- L^{-1} x_r` front by front, keeping
    /// only the pivot blocks of `L`; without, keeping `L` whole.
    fn factorize_fronts<const K: usize>(
        &mut self,
        values: &[f64],
        exits: &[f64],
        mut forward: Option<&mut [f64]>,
    ) -> Result<(), SolverError> {
        let keep_lower = forward.is_none();
        self.allocate_released(keep_lower);
        if !keep_lower {
            self.pivots.resize(self.structure.pivots_len, 0.0);
            self.left.resize(self.structure.largest_left, 0.0);
        }
        let Self {
            structure,
            lower,
            upper,
            pivots,
            lower_kept,
            left,
            front,
            stack,
            exits: eliminated_exits,
            beyond,
        } = self;
        *lower_kept = false;
        stack.clear();
        eliminated_exits.clear();
        eliminated_exits.extend(structure.permutation.iter().map(|&old| exits[old]));
        for &s in &structure.postorder {
            let node = &structure.supernodes[s];
            let (columns, below) = (node.columns(), node.rows.len());
            let rows = columns + below;
            let left = if keep_lower {
                &mut lower[node.lower_offset..][..rows * columns]
            } else {
                &mut left[..rows * columns]
            };
            let mut front = Front {
                rows,
                left,
                right: &mut front[..rows * below],
            };
            structure.assemble(node, &mut front, values, stack);
            front.beyond_pivot_block(&eliminated_exits[node.begin..node.end], beyond);
            front.factor(beyond).map_err(|column| {
                SolverError::Singular(format!(
                    "zero or non-finite pivot at position {} of the elimination order",
                    node.begin + column
                ))
            })?;
            front.copy_upper(&mut upper[node.upper_offset..][..below * columns]);
            if !node.relative.is_empty() {
                front.push_update(stack);
            }
            let below = &structure.rows[node.rows.clone()];
            forward_through::<1>(node, below, front.left, eliminated_exits);
            if let Some(x) = forward.as_deref_mut() {
                let below = &structure.rows[node.rows.clone()];
                forward_through::<K>(node, below, front.left, x);
                front.copy_pivot_block(&mut pivots[node.pivot_offset..][..columns * columns]);
            }
        }
        *lower_kept = keep_lower;
        Ok(())
    }

    /// Solves `A x_r = b_r` in place for `K` right-hand sides at once
    /// (`x_r` holds `b_r` on entry), reading the factors once. Each
    /// solution gets exactly the operations, in the same order, of a solve
    /// of its own. The factors must keep `L` ([`Self::lower_kept`]).
    pub(crate) fn solve_many_in_place<const K: usize>(
        &self,
        mut xs: [&mut [f64]; K],
        work: &mut Vec<f64>,
    ) {
        debug_assert!(self.lower_kept, "a solve needs L");
        self.permute_many_in(&xs, work);
        self.lower_solve::<K>(work);
        self.upper_solve::<K>(work);
        self.permute_many_out(work, &mut xs);
    }

    /// The `K` vectors `xs` interleaved in the elimination order into `work`.
    fn permute_many_in<const K: usize>(&self, xs: &[&mut [f64]; K], work: &mut Vec<f64>) {
        work.clear();
        work.extend(
            self.structure
                .permutation
                .iter()
                .flat_map(|&old| xs.each_ref().map(|x| x[old])),
        );
    }

    /// The inverse of [`Self::permute_many_in`].
    fn permute_many_out<const K: usize>(&self, work: &[f64], xs: &mut [&mut [f64]; K]) {
        for (&old, values) in self.structure.permutation.iter().zip(work.chunks_exact(K)) {
            for (x, &value) in xs.iter_mut().zip(values) {
                x[old] = value;
            }
        }
    }

    /// Solves `A^T y = c` in place (`y` holds `c` on entry).
    pub(crate) fn solve_transpose_in_place(&self, y: &mut [f64], work: &mut Vec<f64>) {
        debug_assert!(self.lower_kept, "a solve needs L");
        let mut ys = [y];
        self.permute_many_in(&ys, work);
        self.upper_transpose_solve(work);
        self.lower_transpose_solve(work);
        self.permute_many_out(work, &mut ys);
    }

    /// `x_r <- L^{-1} x_r` for the `K` vectors interleaved in `x` (entry
    /// `i` of vector `r` at `i * K + r`), supernodes in postorder, as
    /// [`Self::factorize_and_solve`] meets them.
    fn lower_solve<const K: usize>(&self, x: &mut [f64]) {
        for &s in &self.structure.postorder {
            let node = &self.structure.supernodes[s];
            let below = &self.structure.rows[node.rows.clone()];
            let panel =
                &self.lower[node.lower_offset..][..(node.columns() + below.len()) * node.columns()];
            forward_through::<K>(node, below, panel, x);
        }
    }

    /// The pivot block `L_JJ\U_JJ` of `node`, column-major, and its column
    /// stride: in the panel of `L` if kept, else in [`Self::pivots`].
    fn pivot_block(&self, node: &Supernode) -> (&[f64], usize) {
        let columns = node.columns();
        if self.lower_kept {
            let stride = columns + node.rows.len();
            (&self.lower[node.lower_offset..][..stride * columns], stride)
        } else {
            (
                &self.pivots[node.pivot_offset..][..columns * columns],
                columns,
            )
        }
    }

    /// `x_r <- U^{-1} x_r` for the `K` interleaved vectors in `x`,
    /// supernodes in decreasing order.
    fn upper_solve<const K: usize>(&self, x: &mut [f64]) {
        for node in self.structure.supernodes.iter().rev() {
            let (columns, rows) = (node.columns(), &self.structure.rows[node.rows.clone()]);
            let below = rows.len();
            let (panel, stride) = self.pivot_block(node);
            let upper = &self.upper[node.upper_offset..][..below * columns];
            for (&row, column) in rows.iter().zip(upper.chunks_exact(columns)) {
                let xr: [f64; K] = std::array::from_fn(|r| x[row * K + r]);
                for (i, &u) in (node.begin..node.end).zip(column) {
                    for (target, xr) in x[i * K..][..K].iter_mut().zip(xr) {
                        *target -= u * xr;
                    }
                }
            }
            for j in (0..columns).rev() {
                let column = &panel[j * stride..][..stride];
                let at = (node.begin + j) * K;
                x[at..at + K].iter_mut().for_each(|xj| *xj /= column[j]);
                let xj: [f64; K] = std::array::from_fn(|r| x[at + r]);
                for (i, &u) in (node.begin..node.begin + j).zip(column) {
                    for (target, xj) in x[i * K..][..K].iter_mut().zip(xj) {
                        *target -= u * xj;
                    }
                }
            }
        }
    }

    /// `y <- U^{-T} y`, supernodes in increasing order.
    fn upper_transpose_solve(&self, y: &mut [f64]) {
        for node in &self.structure.supernodes {
            let (columns, rows) = (node.columns(), &self.structure.rows[node.rows.clone()]);
            let below = rows.len();
            let stride = columns + below;
            let panel = &self.lower[node.lower_offset..][..stride * columns];
            let upper = &self.upper[node.upper_offset..][..below * columns];
            for j in 0..columns {
                let column = &panel[j * stride..][..stride];
                let sum: f64 = (0..j).map(|i| column[i] * y[node.begin + i]).sum();
                y[node.begin + j] = (y[node.begin + j] - sum) / column[j];
            }
            for (&row, column) in rows.iter().zip(upper.chunks_exact(columns)) {
                let sum: f64 = column
                    .iter()
                    .zip(&y[node.begin..node.end])
                    .map(|(&u, &yi)| u * yi)
                    .sum();
                y[row] -= sum;
            }
        }
    }

    /// `y <- L^{-T} y`, supernodes in decreasing order.
    fn lower_transpose_solve(&self, y: &mut [f64]) {
        for node in self.structure.supernodes.iter().rev() {
            let (columns, rows) = (node.columns(), &self.structure.rows[node.rows.clone()]);
            let stride = columns + rows.len();
            let panel = &self.lower[node.lower_offset..][..stride * columns];
            for j in (0..columns).rev() {
                let column = &panel[j * stride..][..stride];
                let below: f64 = rows
                    .iter()
                    .zip(&column[columns..])
                    .map(|(&r, &l)| l * y[r])
                    .sum();
                let within: f64 = (j + 1..columns)
                    .map(|i| column[i] * y[node.begin + i])
                    .sum();
                y[node.begin + j] -= below + within;
            }
        }
    }
}

/// `x_r <- L_s^{-1} x_r` for the columns of supernode `node`: with the
/// factorised panel `[L_JJ\U_JJ; L_RJ]` (column-major, `|J| + |R|` rows,
/// `below` the rows `R`), subtracts each column's multiples from the rows
/// below it, for the `K` vectors interleaved in `x`.
fn forward_through<const K: usize>(
    node: &Supernode,
    below: &[usize],
    panel: &[f64],
    x: &mut [f64],
) {
    let columns = node.columns();
    let stride = columns + below.len();
    for j in 0..columns {
        let xj: [f64; K] = std::array::from_fn(|r| x[(node.begin + j) * K + r]);
        let column = &panel[j * stride..][..stride];
        let targets = (node.begin + j + 1..node.end).zip(&column[j + 1..columns]);
        for (row, &l) in targets.chain(below.iter().copied().zip(&column[columns..])) {
            for (target, xj) in x[row * K..][..K].iter_mut().zip(xj) {
                *target -= l * xj;
            }
        }
    }
}

/// The dense front of one supernode, `rows x rows` column-major, split
/// after its pivot columns: `left = [F_JJ; F_RJ]` (where `L` and `U_JJ`
/// stay) and `right = [F_JR; F_RR]`. A position counts through `left` and
/// then `right`, as in one column-major matrix.
struct Front<'a> {
    rows: usize,
    left: &'a mut [f64],
    right: &'a mut [f64],
}

impl Front<'_> {
    fn columns(&self) -> usize {
        self.left.len() / self.rows
    }

    /// The entry at column-major `position`.
    fn at(&mut self, position: usize) -> &mut f64 {
        match position.checked_sub(self.left.len()) {
            Some(right) => &mut self.right[right],
            None => &mut self.left[position],
        }
    }

    /// The column `column` of the front.
    fn column(&mut self, column: usize) -> &mut [f64] {
        let rows = self.rows;
        match column.checked_sub(self.columns()) {
            Some(right) => &mut self.right[right * rows..][..rows],
            None => &mut self.left[column * rows..][..rows],
        }
    }

    /// Adds a child's update matrix (`relative.len()` square, column-major)
    /// at the rows and columns `relative`.
    fn extend_add(&mut self, update: &[f64], relative: &[u32]) {
        let size = relative.len();
        for (&column, source) in relative.iter().zip(update.chunks_exact(size)) {
            let target = self.column(column as usize);
            for (&row, &u) in relative.iter().zip(source) {
                target[row as usize] += u;
            }
        }
    }

    /// `beyond[k] = exits[k] - sum_{r in R} F_kr` for the pivot rows `k`
    /// of an assembled front: what row `k` of the Schur complement sends
    /// out of `T` or to the rows `R` below the pivot block (a sum of
    /// nonnegative terms: `F_kr <= 0`).
    fn beyond_pivot_block(&self, exits: &[f64], beyond: &mut Vec<f64>) {
        beyond.clear();
        beyond.extend_from_slice(exits);
        for column in self.right.chunks_exact(self.rows) {
            for (sum, &entry) in beyond.iter_mut().zip(column) {
                *sum -= entry;
            }
        }
    }

    /// `F_JJ = L U` in place, `F_RJ <- F_RJ U^{-1}`, `F_JR <- L^{-1} F_JR`,
    /// `F_RR <- F_RR - F_RJ F_JR`, the pivots by [`lu_gth`] from `beyond`
    /// ([`Self::beyond_pivot_block`]). Errors with the pivot's column when
    /// a pivot is zero or not finite.
    fn factor(&mut self, beyond: &mut [f64]) -> Result<(), usize> {
        let (rows, columns) = (self.rows, self.columns());
        let par = if rows >= PARALLEL_FRONT_ROWS {
            Par::rayon(0)
        } else {
            Par::Seq
        };
        let left = MatMut::from_column_major_slice_mut(self.left, rows, columns);
        let (mut jj, mut rj) = left.split_at_row_mut(columns);
        lu_gth(jj.rb_mut(), beyond, par)?;
        if rows > columns {
            let right = MatMut::from_column_major_slice_mut(self.right, rows, rows - columns);
            let (mut jr, rr) = right.split_at_row_mut(columns);
            solve_lower_triangular_in_place(jj.rb().transpose(), rj.rb_mut().transpose_mut(), par);
            solve_unit_lower_triangular_in_place(jj.rb(), jr.rb_mut(), par);
            matmul(rr, Accum::Add, rj.rb(), jr.rb(), -1.0, par);
        }
        Ok(())
    }

    /// Copies `U_JR` (`|J| x |R|`, column-major) out of a factorised front.
    fn copy_upper(&self, upper: &mut [f64]) {
        copy_leading_rows(self.right, self.rows, self.columns(), upper);
    }

    /// Copies the pivot block `L_JJ\U_JJ` (`|J| x |J|`, column-major) out
    /// of a factorised front.
    fn copy_pivot_block(&self, pivots: &mut [f64]) {
        copy_leading_rows(self.left, self.rows, self.columns(), pivots);
    }

    /// Pushes the update matrix `F_RR` of a factorised front onto the
    /// stack, column-major.
    fn push_update(&self, stack: &mut Vec<f64>) {
        let columns = self.columns();
        for source in self.right.chunks_exact(self.rows) {
            stack.extend_from_slice(&source[columns..]);
        }
    }
}

/// Copies the first `count` entries of each column of the column-major
/// `source` (columns of `stride` entries) into consecutive columns of
/// `count` entries of `target`.
fn copy_leading_rows(source: &[f64], stride: usize, count: usize, target: &mut [f64]) {
    for (target, source) in target
        .chunks_exact_mut(count)
        .zip(source.chunks_exact(stride))
    {
        target.copy_from_slice(&source[..count]);
    }
}

/// Dense LU without pivoting in place (unit lower `L` below the diagonal,
/// `U` on and above it), recursively by halves, with the pivots of Grassmann,
/// Taksar and Heyman: `a` is a block of `I - Q` (or of a Schur complement)
/// whose off-diagonal entries are at most 0, and `beyond[k]` is what row `k`
/// sends out of the block's columns (to the columns right of it, or out of
/// `T`), at least 0. Each pivot is then formed as `beyond[k] - sum_{j > k}
/// a_kj`, a sum of nonnegative numbers, never as a difference: the diagonal
/// that elimination would compute by subtraction (and which loses every
/// digit in a block that the chain leaves with probability `1e-13`) is not
/// used. Every other operation of elimination adds numbers of one sign, so
/// the factors are accurate entry by entry (O'Cinneide 1993; method.md
/// section 8). `beyond` is consumed. Errors with the column of a zero or
/// non-finite pivot.
fn lu_gth(mut a: MatMut<'_, f64>, beyond: &mut [f64], par: Par) -> Result<(), usize> {
    let n = a.nrows();
    if n <= UNBLOCKED_COLUMNS {
        return gth_unblocked(a, beyond);
    }
    let half = n / 2;
    let (mut a11, mut a12, mut a21, a22) = a.rb_mut().split_at_mut(half, half);
    let (beyond1, beyond2) = beyond.split_at_mut(half);
    let mut beyond11 = beyond1.to_vec();
    for column in 0..a12.ncols() {
        for (sum, row) in beyond11.iter_mut().zip(0..half) {
            *sum -= a12[(row, column)];
        }
    }
    lu_gth(a11.rb_mut(), &mut beyond11, par)?;
    solve_unit_lower_triangular_in_place(a11.rb(), a12.rb_mut(), par);
    solve_lower_triangular_in_place(a11.rb().transpose(), a21.rb_mut().transpose_mut(), par);
    let mut a22 = a22;
    matmul(a22.rb_mut(), Accum::Add, a21.rb(), a12.rb(), -1.0, par);
    // beyond1 <- L11^{-1} beyond1, then beyond2 <- beyond2 - L21 beyond1:
    // the rows of a22 after the first half's eliminations.
    for k in 0..half {
        let carried = beyond1[k];
        for i in k + 1..half {
            beyond1[i] -= a11[(i, k)] * carried;
        }
        for (i, sum) in beyond2.iter_mut().enumerate() {
            *sum -= a21[(i, k)] * carried;
        }
    }
    lu_gth(a22, beyond2, par).map_err(|column| column + half)
}

/// [`lu_gth`] for a small block: one pivot at a time.
fn gth_unblocked(mut a: MatMut<'_, f64>, beyond: &mut [f64]) -> Result<(), usize> {
    let n = a.nrows();
    for k in 0..n {
        let pivot = (k + 1..n).fold(beyond[k], |sum, j| sum - a[(k, j)]);
        if !(pivot > 0.0 && pivot.is_finite()) {
            return Err(k);
        }
        a[(k, k)] = pivot;
        for i in k + 1..n {
            a[(i, k)] /= pivot;
        }
        for j in k + 1..n {
            let akj = a[(k, j)];
            if akj != 0.0 {
                for i in k + 1..n {
                    let l = a[(i, k)];
                    a[(i, j)] -= l * akj;
                }
            }
        }
        for i in k + 1..n {
            beyond[i] -= a[(i, k)] * beyond[k];
        }
    }
    Ok(())
}

impl Structure {
    fn analyse(pattern: &SparsePattern) -> Result<Self, SolverError> {
        let n = pattern.n;
        let order = fill_reducing_order(pattern, LARGEST_FRONT)?;
        let symbolic = cholesky_structure(&order)?;
        let mut structure = Self {
            n,
            permutation: Vec::new(),
            supernodes: Vec::new(),
            rows: Vec::new(),
            assembly: Vec::new(),
            children: Vec::new(),
            relative: Vec::new(),
            postorder: Vec::new(),
            stack_len: 0,
            lower_len: 0,
            upper_len: 0,
            pivots_len: 0,
            largest_left: 0,
            largest_right: 0,
        };
        let expand = |class: usize| order.positions(class..class + 1);
        match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(supernodal) => {
                for s in 0..supernodal.n_supernodes() {
                    let node = supernodal.supernode(s);
                    let columns = order.positions(node.start()..supernodal.supernode_end()[s]);
                    let below = node.pattern().iter().flat_map(|&class| expand(class));
                    structure.push_supernode(columns.start, columns.end, below);
                }
            }
            SymbolicCholeskyRaw::Simplicial(simplicial) => {
                let factor = simplicial.factor();
                for j in 0..order.classes.len() {
                    let below = factor.row_idx_of_col(j).filter(|&i| i > j).flat_map(expand);
                    let columns = expand(j);
                    structure.push_supernode(columns.start, columns.end, below);
                }
            }
        }
        structure.check_front_sizes(LARGEST_FRONT)?;
        structure.permutation = order.permutation;
        structure.link_children()?;
        structure.order_for_the_stack();
        structure.assemble_map(pattern)?;
        Ok(structure)
    }

    /// Refuses fronts of more than `largest_front` rows
    /// ([`SolverError::LuTooLarge`]; [`LARGEST_FRONT`] in an analysis).
    fn check_front_sizes(&self, largest_front: usize) -> Result<(), SolverError> {
        let front = self
            .supernodes
            .iter()
            .map(|node| node.columns() + node.rows.len())
            .max()
            .unwrap_or(0);
        if front <= largest_front {
            Ok(())
        } else {
            Err(SolverError::LuTooLarge {
                unknowns: self.n,
                front,
            })
        }
    }

    /// Appends the supernode of columns `begin..end` with the rows `below`.
    fn push_supernode(&mut self, begin: usize, end: usize, below: impl Iterator<Item = usize>) {
        let first = self.rows.len();
        self.rows.extend(below);
        self.rows[first..].sort_unstable();
        let rows = first..self.rows.len();
        let (columns, below) = (end - begin, rows.len());
        self.largest_left = self.largest_left.max((columns + below) * columns);
        self.largest_right = self.largest_right.max((columns + below) * below);
        self.supernodes.push(Supernode {
            begin,
            end,
            rows,
            lower_offset: self.lower_len,
            upper_offset: self.upper_len,
            pivot_offset: self.pivots_len,
            assembly: 0..0,
            children: 0..0,
            relative: 0..0,
        });
        self.lower_len += (columns + below) * columns;
        self.upper_len += below * columns;
        self.pivots_len += columns * columns;
    }

    /// The supernode owning each column.
    fn owners(&self) -> Vec<usize> {
        let mut owner = vec![0; self.n];
        for (s, node) in self.supernodes.iter().enumerate() {
            owner[node.begin..node.end].fill(s);
        }
        owner
    }

    /// Fills the front of `node` with the entries of `A` it owns and its
    /// children's update matrices, which it pops off the stack.
    fn assemble(
        &self,
        node: &Supernode,
        front: &mut Front<'_>,
        values: &[f64],
        stack: &mut Vec<f64>,
    ) {
        front.left.fill(0.0);
        front.right.fill(0.0);
        for &(k, position) in &self.assembly[node.assembly.clone()] {
            *front.at(position as usize) += values[k as usize];
        }
        let mut top = stack.len();
        for &child in self.children[node.children.clone()].iter().rev() {
            let relative = &self.relative[self.supernodes[child].relative.clone()];
            let size = relative.len() * relative.len();
            top -= size;
            front.extend_add(&stack[top..][..size], relative);
        }
        stack.truncate(top);
    }

    /// Position of `index` among the front indices `J_s ∪ R_s` of `node`.
    fn front_position(&self, node: &Supernode, index: usize) -> Option<usize> {
        if (node.begin..node.end).contains(&index) {
            return Some(index - node.begin);
        }
        self.rows[node.rows.clone()]
            .binary_search(&index)
            .ok()
            .map(|position| node.columns() + position)
    }

    /// Parents (the owner of a supernode's first row below), children lists
    /// and each child's rows' positions in its parent's front.
    fn link_children(&mut self) -> Result<(), SolverError> {
        let owner = self.owners();
        let parents: Vec<Option<usize>> = self
            .supernodes
            .iter()
            .map(|node| self.rows[node.rows.clone()].first().map(|&row| owner[row]))
            .collect();
        let mut counts = vec![0usize; self.supernodes.len() + 1];
        for parent in parents.iter().flatten() {
            counts[parent + 1] += 1;
        }
        for s in 0..self.supernodes.len() {
            counts[s + 1] += counts[s];
        }
        self.children = vec![0; counts[self.supernodes.len()]];
        let mut next = counts.clone();
        for (s, parent) in parents.iter().enumerate() {
            if let Some(parent) = *parent {
                self.children[next[parent]] = s;
                next[parent] += 1;
            }
        }
        for s in 0..self.supernodes.len() {
            self.supernodes[s].children = counts[s]..counts[s + 1];
            let Some(parent) = parents[s] else { continue };
            let first = self.relative.len();
            for k in self.supernodes[s].rows.clone() {
                let position = self
                    .front_position(&self.supernodes[parent], self.rows[k])
                    .ok_or_else(|| {
                        SolverError::Malformed("a supernode's rows miss its parent's front".into())
                    })?;
                self.relative.push(to_u32(position)?);
            }
            self.supernodes[s].relative = first..self.relative.len();
        }
        Ok(())
    }

    /// The postorder of the supernode tree, and the stack it needs.
    fn order_for_the_stack(&mut self) {
        let count = self.supernodes.len();
        let mut postorder = Vec::with_capacity(count);
        let mut pending: Vec<(usize, usize)> = Vec::new();
        for root in (0..count).filter(|&s| self.supernodes[s].relative.is_empty()) {
            pending.push((root, 0));
            while let Some((node, next)) = pending.last_mut() {
                let children = &self.children[self.supernodes[*node].children.clone()];
                if let Some(&child) = children.get(*next) {
                    *next += 1;
                    pending.push((child, 0));
                } else {
                    postorder.push(*node);
                    pending.pop();
                }
            }
        }
        let update_len = |s: usize| self.supernodes[s].relative.len().pow(2);
        let (mut used, mut peak) = (0usize, 0usize);
        for &s in &postorder {
            let children = &self.children[self.supernodes[s].children.clone()];
            used -= children
                .iter()
                .map(|&child| update_len(child))
                .sum::<usize>();
            used += update_len(s);
            peak = peak.max(used);
        }
        self.postorder = postorder;
        self.stack_len = peak;
    }

    /// Where each entry of `P A P^T` goes: into the front of the supernode
    /// owning the smaller of its row and column.
    fn assemble_map(&mut self, pattern: &SparsePattern) -> Result<(), SolverError> {
        let grouped = self.entries_by_owner(pattern)?;
        let mut local = vec![usize::MAX; self.n];
        self.assembly = Vec::with_capacity(grouped.len());
        for node in &self.supernodes {
            let rows = &self.rows[node.rows.clone()];
            for (position, index) in (node.begin..node.end)
                .chain(rows.iter().copied())
                .enumerate()
            {
                local[index] = position;
            }
            let front_rows = node.columns() + rows.len();
            let in_front = |index: usize| {
                let position = local[index];
                let owned = match position.checked_sub(node.columns()) {
                    None => node.begin + position == index,
                    Some(below) => rows.get(below) == Some(&index),
                };
                owned.then_some(position)
            };
            for &(i, j, k) in &grouped[node.assembly.clone()] {
                let missing = || SolverError::Malformed("an entry misses its front".into());
                let row = in_front(i as usize).ok_or_else(missing)?;
                let column = in_front(j as usize).ok_or_else(missing)?;
                self.assembly.push((k, to_u32(row + front_rows * column)?));
            }
        }
        Ok(())
    }

    /// The entries `(i, j, k)` of `P A P^T` (row, column, index into `A`'s
    /// values) grouped by the supernode owning `min(i, j)`; sets each
    /// supernode's [`Supernode::assembly`] range.
    fn entries_by_owner(
        &mut self,
        pattern: &SparsePattern,
    ) -> Result<Vec<(u32, u32, u32)>, SolverError> {
        let owner = self.owners();
        let mut inverse = vec![0; self.n];
        for (new, &old) in self.permutation.iter().enumerate() {
            inverse[old] = new;
        }
        let mut counts = vec![0usize; self.supernodes.len() + 1];
        for row in 0..self.n {
            for &column in &pattern.columns[pattern.row_range(row)] {
                counts[owner[inverse[row].min(inverse[column])] + 1] += 1;
            }
        }
        for s in 0..self.supernodes.len() {
            counts[s + 1] += counts[s];
            self.supernodes[s].assembly = counts[s]..counts[s + 1];
        }
        let mut grouped = vec![(0, 0, 0); pattern.nnz()];
        for row in 0..self.n {
            for k in pattern.row_range(row) {
                let (i, j) = (inverse[row], inverse[pattern.columns[k]]);
                let slot = &mut counts[owner[i.min(j)]];
                grouped[*slot] = (to_u32(i)?, to_u32(j)?, to_u32(k)?);
                *slot += 1;
            }
        }
        Ok(grouped)
    }
}

/// faer's supernodal symbolic Cholesky analysis of the quotient of the
/// pattern of `A + A^T` by classes of indistinguishable vertices, in the
/// class order ([`ClassOrder`]): once each class is expanded to its
/// members, its supernodes are those of `A + A^T`. faer merges adjacent
/// supernodes when the merged one has few explicit zeros, with thresholds
/// on the number of columns (its default relaxation); here a column stands
/// for a class, so the thresholds are divided by the mean class size.
fn cholesky_structure(order: &ClassOrder) -> Result<SymbolicCholesky<usize>, SolverError> {
    let graph = &order.quotient;
    let n = graph.len();
    let mut inverse = vec![0; n];
    for (new, &old) in order.classes.iter().enumerate() {
        inverse[old] = new;
    }
    let (column_offsets, row_indices) = graph.upper();
    let upper = SymbolicSparseColMatRef::new_checked(n, n, &column_offsets, None, &row_indices);
    let class_size = (order.permutation.len() as f64 / n.max(1) as f64)
        .round()
        .max(1.0) as usize;
    let relax: Vec<(usize, f64)> = DEFAULT_RELAXATION
        .iter()
        .map(|&(columns, zeros)| ((columns / class_size).max(1), zeros))
        .chain([(usize::MAX, LARGE_SUPERNODE_ZEROS)])
        .collect();
    let params = CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
        supernodal_params: SymbolicSupernodalParams {
            relax: Some(&relax),
        },
        ..Default::default()
    };
    factorize_symbolic_cholesky(
        upper,
        Side::Upper,
        SymmetricOrdering::Custom(PermRef::new_checked(&order.classes, &inverse, n)),
        params,
    )
    .map_err(|_| SolverError::OutOfMemory)
}

/// faer's default supernode relaxation below its last step: two adjacent
/// supernodes with at most this many columns together are merged if at
/// most this fraction of the merged one's entries are zeros.
const DEFAULT_RELAXATION: [(usize, f64); 3] = [(4, 1.0), (16, 0.8), (48, 0.1)];

/// faer's default fraction of zeros for merging larger supernodes.
const LARGE_SUPERNODE_ZEROS: f64 = 0.05;

fn to_u32(value: usize) -> Result<u32, SolverError> {
    u32::try_from(value)
        .map_err(|_| SolverError::Malformed("the system is too large for 32-bit indices".into()))
}

#[cfg(test)]
mod tests {
    use super::super::test_systems::{grid_walk, random_chain, tridiagonal};
    use super::*;

    #[test]
    fn fronts_beyond_the_index_limit_are_refused_by_size() {
        let (pattern, _) = grid_walk(12);
        let structure = Structure::analyse(&pattern).unwrap();
        let front = structure
            .supernodes
            .iter()
            .map(|node| node.columns() + node.rows.len())
            .max()
            .unwrap();
        assert!(structure.check_front_sizes(front).is_ok());
        assert_eq!(
            structure.check_front_sizes(front - 1),
            Err(SolverError::LuTooLarge {
                unknowns: 144,
                front
            })
        );
        let message = SolverError::LuTooLarge {
            unknowns: 520_190,
            front: 70_000,
        }
        .to_string();
        assert!(
            message.contains("70000 x 70000") && message.contains("39 GB"),
            "{message}"
        );
    }

    /// The row sums of a matrix given with its diagonal.
    fn exits(pattern: &SparsePattern, values: &[f64]) -> Vec<f64> {
        let mut exits = vec![0.0; pattern.n];
        super::super::derive_exits(pattern, values, &mut exits);
        exits
    }

    /// `max_i |(A x - b)_i| / max(1, |x|_inf)` and the same for `A^T y = c`
    /// after both solves (`|A|_inf <= 2`: a relative residual).
    fn residuals(pattern: &SparsePattern, values: &[f64]) -> (f64, f64) {
        let mut lu = MultifrontalLu::new(pattern).unwrap();
        lu.factorize(values, &exits(pattern, values)).unwrap();
        let n = pattern.n;
        let b: Vec<f64> = (0..n).map(|i| 1.0 + (i % 5) as f64).collect();
        let mut work = Vec::new();
        let mut x = b.clone();
        lu.solve_many_in_place([&mut x], &mut work);
        let mut y = b.clone();
        lu.solve_transpose_in_place(&mut y, &mut work);
        let mut product = vec![0.0; n];
        let scale = |v: &[f64]| v.iter().fold(1.0f64, |m, e| m.max(e.abs()));
        (
            pattern.residual(values, &x, &b) / scale(&x),
            pattern.transposed_residual(values, &y, &b, &mut product) / scale(&y),
        )
    }

    #[test]
    fn a_nonsymmetric_chain_is_solved_by_hand() {
        let pattern = SparsePattern {
            n: 3,
            row_offsets: vec![0, 2, 4, 5],
            columns: vec![0, 1, 1, 2, 2],
        };
        let values = [1.0, -0.5, 1.0, -0.25, 1.0];
        let mut lu = MultifrontalLu::new(&pattern).unwrap();
        lu.factorize(&values, &exits(&pattern, &values)).unwrap();
        let mut work = Vec::new();
        let mut x = vec![0.0, 0.0, 1.0];
        lu.solve_many_in_place([&mut x], &mut work);
        assert_eq!(x, [0.125, 0.25, 1.0]);
        let mut y = vec![1.0, 0.0, 0.0];
        lu.solve_transpose_in_place(&mut y, &mut work);
        assert_eq!(y, [1.0, 0.5, 0.125]);
    }

    #[test]
    fn random_chains_are_solved_in_both_directions() {
        for (n, per_row, seed) in [(1, 1, 1), (7, 2, 2), (60, 3, 3), (400, 5, 4), (2000, 4, 5)] {
            let (pattern, values) = random_chain(n, per_row, 0.05, seed);
            let (forward, transposed) = residuals(&pattern, &values);
            assert!(
                forward < 1e-14 && transposed < 1e-14,
                "n {n}: {forward:e} {transposed:e}"
            );
        }
    }

    #[test]
    fn solving_two_right_hand_sides_at_once_gives_each_solve_bit_for_bit() {
        for (pattern, values) in [random_chain(2000, 4, 0.05, 6), grid_walk(40)] {
            let mut lu = MultifrontalLu::new(&pattern).unwrap();
            lu.factorize(&values, &exits(&pattern, &values)).unwrap();
            let n = pattern.n;
            let b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 / 101.0).collect();
            let ones = vec![1.0; n];
            let mut work = Vec::new();
            let (mut x, mut t) = (b.clone(), ones.clone());
            lu.solve_many_in_place([&mut x, &mut t], &mut work);
            let (mut x_alone, mut t_alone) = (b, ones);
            lu.solve_many_in_place([&mut x_alone], &mut work);
            lu.solve_many_in_place([&mut t_alone], &mut work);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&x), bits(&x_alone));
            assert_eq!(bits(&t), bits(&t_alone));
            assert!(
                t.iter().all(|&ti| ti >= 1.0),
                "expected times are at least 1"
            );
        }
    }

    #[test]
    fn solving_during_the_factorisation_matches_solving_after_it_bit_for_bit() {
        // In the first two chains, solving supernode by supernode in
        // increasing order (not the postorder of the factorisation) sums
        // some entries in another order and changes their last bits. The
        // third has fronts of about 700 rows, factorised by the blocked and
        // parallel dense kernels.
        let mut postorder_differs = false;
        let systems = [
            random_chain(600, 2, 0.02, 8),
            random_chain(950, 5, 0.02, 15),
            random_chain(700, 700, 0.01, 6),
            grid_walk(45),
            tridiagonal(300, 0.45),
        ];
        for (pattern, values) in systems {
            let n = pattern.n;
            let b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 / 101.0).collect();
            let mut work = Vec::new();
            let mut lu = MultifrontalLu::new(&pattern).unwrap();
            lu.factorize(&values, &exits(&pattern, &values)).unwrap();
            let (mut x_after, mut t_after) = (b.clone(), vec![1.0; n]);
            lu.solve_many_in_place([&mut x_after, &mut t_after], &mut work);
            let (mut x, mut t) = (b.clone(), vec![1.0; n]);
            lu.factorize_and_solve(
                &values,
                &exits(&pattern, &values),
                [&mut x, &mut t],
                &mut work,
            )
            .unwrap();
            assert!(!lu.lower_kept());
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&x), bits(&x_after));
            assert_eq!(bits(&t), bits(&t_after));
            let mut x_alone = b;
            lu.factorize_and_solve(
                &values,
                &exits(&pattern, &values),
                [&mut x_alone],
                &mut work,
            )
            .unwrap();
            assert_eq!(bits(&x_alone), bits(&x_after));
            let postorder = &lu.structure.postorder;
            postorder_differs |= postorder.iter().enumerate().any(|(i, &s)| i != s);
        }
        assert!(
            postorder_differs,
            "no system tried a postorder unlike 0, 1, ..."
        );
    }

    #[test]
    fn grid_walks_with_large_fronts_are_solved() {
        for side in [2, 9, 70] {
            let (pattern, values) = grid_walk(side);
            let (forward, transposed) = residuals(&pattern, &values);
            assert!(
                forward < 1e-14 && transposed < 1e-14,
                "side {side}: {forward:e} {transposed:e}"
            );
        }
    }

    #[test]
    fn a_dense_chain_uses_the_blocked_and_parallel_kernels() {
        let (pattern, values) = random_chain(700, 700, 0.01, 6);
        let (forward, transposed) = residuals(&pattern, &values);
        assert!(
            forward < 1e-14 && transposed < 1e-14,
            "{forward:e} {transposed:e}"
        );
    }

    #[test]
    fn refactorisation_matches_a_fresh_factorisation() {
        let (pattern, mut values) = tridiagonal(300, 0.4);
        let mut reused = MultifrontalLu::new(&pattern).unwrap();
        reused
            .factorize(&values, &exits(&pattern, &values))
            .unwrap();
        for (k, v) in values.iter_mut().enumerate() {
            if *v != 1.0 {
                *v = -0.3 - 1e-3 * (k % 7) as f64;
            }
        }
        reused
            .factorize(&values, &exits(&pattern, &values))
            .unwrap();
        let mut fresh = MultifrontalLu::new(&pattern).unwrap();
        fresh.factorize(&values, &exits(&pattern, &values)).unwrap();
        assert_eq!(reused.lower, fresh.lower);
        assert_eq!(reused.upper, fresh.upper);
    }

    #[test]
    fn a_zero_pivot_is_an_error() {
        let pattern = SparsePattern {
            n: 2,
            row_offsets: vec![0, 2, 4],
            columns: vec![0, 1, 0, 1],
        };
        let mut lu = MultifrontalLu::new(&pattern).unwrap();
        let error = lu
            .factorize(&[1.0, -1.0, -1.0, 1.0], &[0.0, 0.0])
            .unwrap_err();
        assert!(matches!(error, SolverError::Singular(_)), "{error}");
    }
}
