//! The adjoint gradient pass of method.md section 2 on the GMC: with `x`
//! the value vector on all states and `y` the adjoint weights (zero outside
//! `T`),
//!
//! ```text
//! grad_k = sum_m y(m) r_k(m),   r_k(m) = sum_m' dP(m' | m)/d mu_k x(m'),
//! ```
//!
//! the partial derivatives of `sum_m y(m) sum_m' P(m' | m) x(m')` with
//! respect to `mu_def` and `mu_adv`, and the derivatives of
//! `V = sum_m p0(m) x(m)` with respect to the initial node distributions.

use rayon::prelude::*;

use crate::controller::Probabilities;
use crate::product::Gmc;

/// The fewest rows with nonzero adjoint weight for which
/// [`GradientPass::add_adjoint_gradient`] runs in parallel.
pub const PARALLEL_GRADIENT_ROWS: usize = 4096;

/// The number of row chunks of the parallel gradient pass: fixed, so that
/// the sum does not depend on the number of threads.
pub(crate) const GRADIENT_CHUNKS: usize = 4;

/// Gradient entries per task when the chunks' buffers are added up.
const REDUCTION_BLOCK: usize = 1 << 14;

/// Scratch vectors of [`row_derivatives`] (one per thread): the values `x`
/// of a row's successors by cell, and the derivatives of the row with
/// respect to each of its mixture entries.
#[derive(Debug, Clone, Default)]
pub(crate) struct RowWorkspace {
    x_cell: Vec<f64>,
    d_def: Vec<f64>,
    d_adv: Vec<f64>,
}

impl RowWorkspace {
    /// A scratch space for [`row_derivatives`], sized for `gmc`.
    pub(crate) fn for_chain(gmc: &Gmc) -> Self {
        Self {
            x_cell: vec![0.0; gmc.max_cells()],
            d_def: Vec::new(),
            d_adv: Vec::new(),
        }
    }
}

/// One chunk of rows of the parallel gradient pass: its partial gradients
/// and its row scratch.
#[derive(Debug, Clone)]
struct GradientChunk {
    defender: Vec<f64>,
    adversary: Vec<f64>,
    rows: RowWorkspace,
}

/// The adjoint gradient pass with its buffers, kept between calls: the rows
/// with nonzero adjoint weight, the row scratch of the sequential pass and
/// one chunk of partial gradients per chunk of the parallel pass. After the
/// first call on a chain the pass allocates nothing.
#[derive(Debug, Clone, Default)]
pub struct GradientPass {
    rows: Vec<u32>,
    sequential: RowWorkspace,
    chunks: Vec<GradientChunk>,
}

impl GradientPass {
    /// A pass with empty buffers (they grow on the first call).
    pub fn new() -> Self {
        Self::default()
    }

    /// The adjoint gradient pass of method.md section 2. With `x` the value
    /// vector on all states of `gmc` and `y` the adjoint weights (zero
    /// outside `T`), adds to `gradient_defender[k]` and
    /// `gradient_adversary[k]`
    ///
    /// ```text
    /// grad_k = sum_m y(m) r_k(m),   r_k(m) = sum_m' dP(m' | m)/d mu_k x(m')
    /// ```
    ///
    /// (the partial derivatives of `sum_m y(m) sum_m' P(m' | m) x(m')` with
    /// respect to `mu_def` and `mu_adv`), using the numbers of the last
    /// [`Gmc::refill`].
    ///
    /// Above [`PARALLEL_GRADIENT_ROWS`] rows with `y(m) != 0`, the rows are
    /// split into 4 contiguous chunks handled in parallel (rayon), each
    /// summing into its own buffers, which are then added in chunk order.
    /// The chunks do not depend on the number of threads, so the result is
    /// bitwise reproducible; it differs from a sequential sum only by the
    /// order of summation.
    pub fn add_adjoint_gradient(
        &mut self,
        gmc: &Gmc,
        x: &[f64],
        y: &[f64],
        gradient_defender: &mut [f64],
        gradient_adversary: &mut [f64],
    ) {
        self.rows.clear();
        self.rows
            .extend((0..y.len()).filter(|&m| y[m] != 0.0).map(|m| m as u32));
        if self.rows.len() < PARALLEL_GRADIENT_ROWS {
            let work = &mut self.sequential;
            work.x_cell.resize(gmc.max_cells(), 0.0);
            for &m in &self.rows {
                let y_m = y[m as usize];
                row_derivatives(
                    gmc,
                    m as usize,
                    x,
                    work,
                    |k, r| gradient_defender[k] += y_m * r,
                    |k, r| gradient_adversary[k] += y_m * r,
                );
            }
        } else {
            self.parallel_adjoint_gradient(gmc, x, y, gradient_defender, gradient_adversary);
        }
    }

    fn parallel_adjoint_gradient(
        &mut self,
        gmc: &Gmc,
        x: &[f64],
        y: &[f64],
        gradient_defender: &mut [f64],
        gradient_adversary: &mut [f64],
    ) {
        let (num_def, num_adv) = (gradient_defender.len(), gradient_adversary.len());
        self.chunks.resize_with(GRADIENT_CHUNKS, || GradientChunk {
            defender: Vec::new(),
            adversary: Vec::new(),
            rows: RowWorkspace::default(),
        });
        let rows = &self.rows;
        let per_chunk = rows.len().div_ceil(GRADIENT_CHUNKS);
        self.chunks
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, chunk)| {
                chunk.defender.clear();
                chunk.defender.resize(num_def, 0.0);
                chunk.adversary.clear();
                chunk.adversary.resize(num_adv, 0.0);
                chunk.rows.x_cell.resize(gmc.max_cells(), 0.0);
                let mine =
                    &rows[(c * per_chunk).min(rows.len())..((c + 1) * per_chunk).min(rows.len())];
                let (defender, adversary) = (&mut chunk.defender, &mut chunk.adversary);
                for &m in mine {
                    let y_m = y[m as usize];
                    row_derivatives(
                        gmc,
                        m as usize,
                        x,
                        &mut chunk.rows,
                        |k, r| defender[k] += y_m * r,
                        |k, r| adversary[k] += y_m * r,
                    );
                }
            });
        let chunks = &self.chunks;
        let reduce = |gradient: &mut [f64], part: fn(&GradientChunk) -> &[f64]| {
            gradient
                .par_chunks_mut(REDUCTION_BLOCK)
                .enumerate()
                .for_each(|(b, block)| {
                    let start = b * REDUCTION_BLOCK;
                    for (i, g) in block.iter_mut().enumerate() {
                        *g += chunks
                            .iter()
                            .map(|chunk| part(chunk)[start + i])
                            .sum::<f64>();
                    }
                });
        };
        reduce(gradient_defender, |chunk| &chunk.defender);
        reduce(gradient_adversary, |chunk| &chunk.adversary);
    }
}

/// The partial derivatives of row `m`'s expectation of `x` with respect to
/// the controller probabilities (method.md section 2):
///
/// ```text
/// r_k(m) = sum_m' dP(m' | m)/d mu_k x(m').
/// ```
///
/// For a defender support entry `k = (g', u | g, o)` with `m = (s, q, g, h)`,
///
/// ```text
/// r_k(m) = O_def(o|s) sum_{h',v} A_adv(h',v | s,h) sum_{s'} T(s'|s,u,v) x(s', q', g', h'),
/// ```
///
/// and symmetrically for the adversary. Calls `defender(k, r_k(m))` and
/// `adversary(k, r_k(m))` once for every support entry `k` whose
/// probability appears in row `m` (every other `r_k(m)` is zero), using the
/// numbers of the last [`Gmc::refill`]. `x` is indexed by GMC state.
pub(crate) fn row_derivatives(
    gmc: &Gmc,
    m: usize,
    x: &[f64],
    work: &mut RowWorkspace,
    mut defender: impl FnMut(usize, f64),
    mut adversary: impl FnMut(usize, f64),
) {
    let state = gmc.state(m);
    let (columns, _) = gmc.row(m);
    for (&cell, &column) in gmc.row_cells(m).iter().zip(columns) {
        work.x_cell[cell as usize] = x[column as usize];
    }
    let (defender_mixture, adversary_mixture) = gmc.mixtures();
    let def_range = defender_mixture.at(state.s as usize, state.g as usize);
    let adv_range = adversary_mixture.at(state.s as usize, state.h as usize);
    work.d_def.clear();
    work.d_def.resize(def_range.len(), 0.0);
    work.d_adv.clear();
    work.d_adv.resize(adv_range.len(), 0.0);
    let (def_start, adv_start) = (def_range.start, adv_range.start);
    let (def_values, adv_values) = (defender_mixture.values(), adversary_mixture.values());
    let (x_cell, d_def, d_adv) = (&work.x_cell, &mut work.d_def, &mut work.d_adv);
    gmc.for_each_term(state, |cell, j, l, p| {
        let w = p * x_cell[cell];
        d_def[j - def_start] += adv_values[l] * w;
        d_adv[l - adv_start] += def_values[j] * w;
    });
    let (s, g, h) = (state.s as usize, state.g as usize, state.h as usize);
    defender_mixture.for_each_term(s, g, |entry, k, weight| defender(k, weight * d_def[entry]));
    adversary_mixture.for_each_term(s, h, |entry, k, weight| adversary(k, weight * d_adv[entry]));
}

/// Adds to `initial_defender[g]` and `initial_adversary[h]` the partial
/// derivatives of `V = sum_m p0(m) x(m)` with respect to the initial node
/// probabilities: `dV/d init_def(g) = sum_{s,h} init(s) init_adv(h) x(s, q0(s), g, h)`.
pub(crate) fn add_initial_gradient(
    gmc: &Gmc,
    x: &[f64],
    defender: &Probabilities,
    adversary: &Probabilities,
    initial_defender: &mut [f64],
    initial_adversary: &mut [f64],
) {
    for (m, game_initial) in gmc.initial_states() {
        let state = gmc.state(m);
        let (g, h) = (state.g as usize, state.h as usize);
        let base = game_initial * x[m];
        initial_defender[g] += base * adversary.initial[h];
        initial_adversary[h] += base * defender.initial[g];
    }
}
