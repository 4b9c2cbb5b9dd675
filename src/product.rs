//! The global Markov chain (GMC): the product of a game, a deterministic
//! Rabin automaton and one finite-state controller per player
//! (formats.md section 3, the paper's equation for `T^{phi,C_def,C_adv}`):
//!
//! ```text
//! P((s',q',g',h') | (s,q,g,h)) = sum_{u,v} A_def(g',u | s,g) A_adv(h',v | s,h) T(s' | s,u,v)
//!                                 when q' = delta(q, L(s')), and 0 otherwise,
//! A_*(g',u | s,g) = sum_o O_*(o | s) mu_*(g',u | g,o),
//! ```
//!
//! with initial distribution `p0(s, delta(q_0, L(s)), g, h) = init(s) init_def(g) init_adv(h)`.
//!
//! [`Gmc::build`] explores the states reachable under the controllers'
//! *supports* and stores the chain in compressed sparse rows: an edge exists
//! iff some term of the sum is positive under the supports, so the pattern
//! depends on the supports only. [`Gmc::refill`] then writes the numbers for
//! new probabilities into the same arrays, in parallel over chunks of rows
//! (each row is computed alone, so the numbers do not depend on the number
//! of threads): the optimiser does this thousands of times. The cost of both
//! is linear in the number of terms of the sum.

use rayon::prelude::*;
use rustc_hash::FxHashMap;
use thiserror::Error;

use crate::automaton::{Dra, Letter};
use crate::controller::{Probabilities, Support};
use crate::game::{Player, Posg};
use crate::graph::CsrGraph;
use crate::solver::FlushDenormals;

/// The fewest rows with nonzero adjoint weight for which
/// [`Gmc::add_adjoint_gradient`] runs in parallel.
pub const PARALLEL_GRADIENT_ROWS: usize = 4096;

/// The number of row chunks of the parallel gradient pass: fixed, so that
/// the sum does not depend on the number of threads.
pub const GRADIENT_CHUNKS: usize = 4;

/// Gradient entries per task when the chunks' buffers are added up.
const REDUCTION_BLOCK: usize = 1 << 14;

/// A state `(s, q, g, h)` of the GMC: game state, automaton state, defender
/// node, adversary node.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GmcState {
    /// Game state `s`.
    pub s: u32,
    /// Automaton state `q`.
    pub q: u32,
    /// Defender node `g`.
    pub g: u32,
    /// Adversary node `h`.
    pub h: u32,
}

/// Why the GMC could not be built.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ProductError {
    /// A controller does not fit the game.
    #[error("the {player} controller {problem}")]
    Mismatch {
        /// `defender` or `adversary`.
        player: &'static str,
        /// What does not fit.
        problem: String,
    },
    /// The chain has more states than 32-bit indices allow.
    #[error("the global Markov chain exceeds 2^32 - 1 states")]
    TooLarge,
    /// The chain exceeds the resource budget ([`crate::limits`]).
    #[error("the global Markov chain: {0}")]
    Budget(String),
}

/// One player's action mixture `A(g', u | s, g) = sum_o O(o | s) mu(g', u | g, o)`
/// on a fixed support: for each `(s, g)` the distinct supported `(g', u)`,
/// each with the terms `(support entry k, O(o | s))` that sum to it.
#[derive(Debug, Clone)]
struct Mixture {
    num_nodes: usize,
    offsets: Vec<usize>,
    entries: Vec<(u32, u32)>,
    term_offsets: Vec<usize>,
    terms: Vec<(u32, f64)>,
    values: Vec<f64>,
}

/// A mixture entry `(g', u)`.
type MixtureKey = (u32, u32);
/// A term `(support entry k, O(o | s))` of a mixture entry.
type MixtureTerm = (u32, f64);

impl Mixture {
    fn build(player: &Player, support: &Support, num_states: usize) -> Self {
        let num_nodes = support.num_nodes();
        let mut offsets = vec![0];
        let mut entries = Vec::new();
        let mut term_offsets = vec![0];
        let mut terms = Vec::new();
        let mut pending: Vec<(MixtureKey, Vec<MixtureTerm>)> = Vec::new();
        for s in 0..num_states {
            for g in 0..num_nodes {
                pending.clear();
                for &(o, weight) in player.observation_distribution(s) {
                    for k in support.block(g, o) {
                        let (next, action) = support.entry(k);
                        let key = (next as u32, action as u32);
                        let term = (k as u32, weight);
                        match pending.iter_mut().find(|(e, _)| *e == key) {
                            Some((_, list)) => list.push(term),
                            None => pending.push((key, vec![term])),
                        }
                    }
                }
                pending.sort_by_key(|(key, _)| *key);
                for (key, list) in &pending {
                    entries.push(*key);
                    terms.extend_from_slice(list);
                    term_offsets.push(terms.len());
                }
                offsets.push(entries.len());
            }
        }
        let values = vec![0.0; entries.len()];
        Self {
            num_nodes,
            offsets,
            entries,
            term_offsets,
            terms,
            values,
        }
    }

    fn refill(&mut self, mu: &[f64]) {
        for (j, value) in self.values.iter_mut().enumerate() {
            *value = self.terms[self.term_offsets[j]..self.term_offsets[j + 1]]
                .iter()
                .map(|&(k, weight)| weight * mu[k as usize])
                .sum();
        }
    }

    fn at(&self, s: usize, g: usize) -> std::ops::Range<usize> {
        let i = s * self.num_nodes + g;
        self.offsets[i]..self.offsets[i + 1]
    }

    fn terms_of(&self, j: usize) -> &[(u32, f64)] {
        &self.terms[self.term_offsets[j]..self.term_offsets[j + 1]]
    }
}

/// Game-level tables: for each state `s`, its possible successors over all
/// action pairs (numbered locally `0..`), the transitions rewritten to those
/// local numbers, and the automaton letter `L(s)`.
#[derive(Debug, Clone)]
struct GameTables {
    num_defender_actions: usize,
    num_adversary_actions: usize,
    successor_offsets: Vec<usize>,
    successors: Vec<u32>,
    transition_offsets: Vec<usize>,
    local_transitions: Vec<(u32, f64)>,
    letters: Vec<Letter>,
}

impl GameTables {
    fn build(game: &Posg, dra: &Dra) -> Self {
        let (nu, nv) = (
            game.defender().num_actions(),
            game.adversary().num_actions(),
        );
        let mut successor_offsets = vec![0];
        let mut successors = Vec::new();
        let mut local_transitions = Vec::with_capacity(game.transition_entries.len());
        for s in 0..game.num_states() {
            let start = successors.len();
            for (u, v) in (0..nu).flat_map(|u| (0..nv).map(move |v| (u, v))) {
                successors.extend(game.transition(s, u, v).iter().map(|&(t, _)| t as u32));
            }
            successors[start..].sort_unstable();
            let mut unique = start;
            for i in start..successors.len() {
                if i == start || successors[i] != successors[unique - 1] {
                    successors[unique] = successors[i];
                    unique += 1;
                }
            }
            successors.truncate(unique);
            let local = &successors[start..];
            for (u, v) in (0..nu).flat_map(|u| (0..nv).map(move |v| (u, v))) {
                local_transitions.extend(game.transition(s, u, v).iter().map(|&(t, p)| {
                    let index = local
                        .binary_search(&(t as u32))
                        .expect("successor is in the union");
                    (index as u32, p)
                }));
            }
            successor_offsets.push(successors.len());
        }
        let letters = (0..game.num_states())
            .map(|s| dra.letter_of(game.label_names(s)))
            .collect();
        Self {
            num_defender_actions: nu,
            num_adversary_actions: nv,
            successor_offsets,
            successors,
            transition_offsets: game.transition_offsets.clone(),
            local_transitions,
            letters,
        }
    }

    fn successors(&self, s: usize) -> &[u32] {
        &self.successors[self.successor_offsets[s]..self.successor_offsets[s + 1]]
    }

    fn transition(&self, s: usize, u: usize, v: usize) -> &[(u32, f64)] {
        let t = (s * self.num_defender_actions + u) * self.num_adversary_actions + v;
        &self.local_transitions[self.transition_offsets[t]..self.transition_offsets[t + 1]]
    }
}

/// Scratch vectors of [`Gmc::row_derivatives`] (one per thread): the
/// values `x` of a row's successors by cell, and the derivatives of the
/// row with respect to each of its mixture entries.
#[derive(Debug, Clone, Default)]
pub struct RowWorkspace {
    x_cell: Vec<f64>,
    d_def: Vec<f64>,
    d_adv: Vec<f64>,
}

/// One chunk of rows of the parallel gradient pass: its partial gradients
/// and its row scratch.
#[derive(Debug, Clone)]
struct GradientChunk {
    defender: Vec<f64>,
    adversary: Vec<f64>,
    rows: RowWorkspace,
}

/// The buffers of [`Gmc::add_adjoint_gradient`], kept between calls: the
/// rows with nonzero adjoint weight, the row scratch of the sequential
/// pass and one [`GradientChunk`] per chunk of the parallel pass.
#[derive(Debug, Clone, Default)]
struct GradientWorkspace {
    rows: Vec<u32>,
    sequential: RowWorkspace,
    chunks: Vec<GradientChunk>,
}

/// The reachable global Markov chain in compressed sparse row form.
///
/// Row `m` holds `P(. | m)`; within a row the columns are sorted. Each
/// stored entry also remembers its *cell* `(local s', g', h')`, which lets
/// [`Gmc::refill`] and the gradient pass find an entry without searching.
#[derive(Debug, Clone)]
pub struct Gmc {
    tables: GameTables,
    defender: Mixture,
    adversary: Mixture,
    states: Vec<GmcState>,
    index: FxHashMap<GmcState, u32>,
    row_offsets: Vec<usize>,
    columns: Vec<u32>,
    cells: Vec<u32>,
    values: Vec<f64>,
    initial_states: Vec<u32>,
    initial_probabilities: Vec<f64>,
    game_initial: Vec<f64>,
    max_cells: usize,
    gradient_workspace: GradientWorkspace,
}

/// Rows refilled by one parallel task of [`Gmc::refill`].
const REFILL_CHUNK_ROWS: usize = 8192;

impl Gmc {
    /// Explores the GMC reachable from the initial distribution under the
    /// controllers' supports and stores its sparsity pattern. The numbers are
    /// zero until [`Gmc::refill`] is called.
    pub fn build(
        game: &Posg,
        dra: &Dra,
        defender: &Support,
        adversary: &Support,
    ) -> Result<Self, ProductError> {
        check_support("defender", game.defender(), defender)?;
        check_support("adversary", game.adversary(), adversary)?;
        let tables = GameTables::build(game, dra);
        let defender_mixture = Mixture::build(game.defender(), defender, game.num_states());
        let adversary_mixture = Mixture::build(game.adversary(), adversary, game.num_states());
        let (num_g, num_h) = (defender.num_nodes(), adversary.num_nodes());
        let max_successors = (0..game.num_states())
            .map(|s| tables.successors(s).len())
            .max()
            .unwrap_or(0);
        let cells = [max_successors, num_g, num_h]
            .into_iter()
            .fold(1u128, |product, n| product.saturating_mul(n as u128));
        if let Some(message) = crate::limits::exceeded(
            "one row (successor states x defender nodes x adversary nodes)",
            cells,
            crate::limits::MAX_CHAIN_TRANSITIONS,
            "transitions",
            "MAX_CHAIN_TRANSITIONS",
        ) {
            return Err(ProductError::Budget(message));
        }
        let max_cells = max_successors * num_g * num_h;
        let mut game_initial = vec![0.0; game.num_states()];
        for &(s, p) in game.initial() {
            game_initial[s] = p;
        }
        let mut gmc = Self {
            tables,
            defender: defender_mixture,
            adversary: adversary_mixture,
            states: Vec::new(),
            index: FxHashMap::default(),
            row_offsets: vec![0],
            columns: Vec::new(),
            cells: Vec::new(),
            values: Vec::new(),
            initial_states: Vec::new(),
            initial_probabilities: Vec::new(),
            game_initial,
            max_cells,
            gradient_workspace: GradientWorkspace::default(),
        };
        for &(s, _) in game.initial() {
            let q = dra.successor(dra.initial(), gmc.tables.letters[s]) as u32;
            for g in defender.initial_nodes() {
                for h in adversary.initial_nodes() {
                    let state = GmcState {
                        s: s as u32,
                        q,
                        g: g as u32,
                        h: h as u32,
                    };
                    let m = gmc.intern(state)?;
                    gmc.initial_states.push(m);
                }
            }
        }
        gmc.explore(dra)?;
        gmc.values = vec![0.0; gmc.columns.len()];
        gmc.initial_probabilities = vec![0.0; gmc.initial_states.len()];
        Ok(gmc)
    }

    fn intern(&mut self, state: GmcState) -> Result<u32, ProductError> {
        if let Some(&m) = self.index.get(&state) {
            return Ok(m);
        }
        let m = u32::try_from(self.states.len()).map_err(|_| ProductError::TooLarge)?;
        self.states.push(state);
        self.index.insert(state, m);
        Ok(m)
    }

    fn explore(&mut self, dra: &Dra) -> Result<(), ProductError> {
        let mut cell_seen = vec![false; self.max_cells];
        let mut row_cells: Vec<u32> = Vec::new();
        let mut row: Vec<(u32, u32)> = Vec::new();
        let mut m = 0;
        while m < self.states.len() {
            let state = self.states[m];
            row_cells.clear();
            self.for_each_term(state, |cell, _, _, _| {
                if !cell_seen[cell] {
                    cell_seen[cell] = true;
                    row_cells.push(cell as u32);
                }
            });
            row.clear();
            for &cell in &row_cells {
                cell_seen[cell as usize] = false;
                let target = self.cell_state(state, cell as usize, dra);
                row.push((self.intern(target)?, cell));
            }
            row.sort_unstable();
            if let Some(message) = crate::limits::exceeded(
                "the reachable transitions",
                (self.columns.len() + row.len()) as u128,
                crate::limits::MAX_CHAIN_TRANSITIONS,
                "transitions or more",
                "MAX_CHAIN_TRANSITIONS",
            ) {
                return Err(ProductError::Budget(message));
            }
            self.columns.extend(row.iter().map(|&(column, _)| column));
            self.cells.extend(row.iter().map(|&(_, cell)| cell));
            self.row_offsets.push(self.columns.len());
            m += 1;
        }
        Ok(())
    }

    /// The GMC state of `cell = (local s', g', h')` in the row of `state`.
    fn cell_state(&self, state: GmcState, cell: usize, dra: &Dra) -> GmcState {
        let (num_g, num_h) = (self.defender.num_nodes, self.adversary.num_nodes);
        let h = cell % num_h;
        let g = (cell / num_h) % num_g;
        let local = cell / (num_h * num_g);
        let s = self.tables.successors(state.s as usize)[local];
        let q = dra.successor(state.q as usize, self.tables.letters[s as usize]) as u32;
        GmcState {
            s,
            q,
            g: g as u32,
            h: h as u32,
        }
    }

    /// Calls `visit(cell, j, l, T(s' | s, u, v))` for every term of the sum
    /// defining row `state`: defender mixture entry `j = (g', u)`, adversary
    /// mixture entry `l = (h', v)`, successor `s'` (in `cell`).
    #[inline]
    fn for_each_term(&self, state: GmcState, mut visit: impl FnMut(usize, usize, usize, f64)) {
        let (s, num_h) = (state.s as usize, self.adversary.num_nodes);
        let num_g = self.defender.num_nodes;
        for j in self.defender.at(s, state.g as usize) {
            let (g_next, u) = self.defender.entries[j];
            for l in self.adversary.at(s, state.h as usize) {
                let (h_next, v) = self.adversary.entries[l];
                for &(local, p) in self.tables.transition(s, u as usize, v as usize) {
                    let cell = (local as usize * num_g + g_next as usize) * num_h + h_next as usize;
                    visit(cell, j, l, p);
                }
            }
        }
    }

    /// Writes the transition probabilities and the initial distribution for
    /// new controller probabilities (on the supports the chain was built with).
    pub fn refill(&mut self, defender: &Probabilities, adversary: &Probabilities) {
        self.defender.refill(&defender.entries);
        self.adversary.refill(&adversary.entries);
        let mut values = std::mem::take(&mut self.values);
        let mut chunks = Vec::with_capacity(self.states.len().div_ceil(REFILL_CHUNK_ROWS));
        let mut rest = values.as_mut_slice();
        for first in (0..self.states.len()).step_by(REFILL_CHUNK_ROWS) {
            let rows = first..(first + REFILL_CHUNK_ROWS).min(self.states.len());
            let entries = self.row_offsets[rows.end] - self.row_offsets[rows.start];
            let (chunk, tail) = rest.split_at_mut(entries);
            chunks.push((rows, chunk));
            rest = tail;
        }
        chunks
            .into_par_iter()
            .for_each(|(rows, chunk)| self.refill_rows(rows, chunk));
        self.values = values;
        for (i, &m) in self.initial_states.iter().enumerate() {
            let state = self.states[m as usize];
            self.initial_probabilities[i] = self.game_initial[state.s as usize]
                * defender.initial[state.g as usize]
                * adversary.initial[state.h as usize];
        }
    }

    /// Writes the probabilities of `rows` into `values`, the slice of the
    /// value array that starts at the first entry of `rows`.
    fn refill_rows(&self, rows: std::ops::Range<usize>, values: &mut [f64]) {
        let _flush = FlushDenormals::on_this_thread();
        let mut scratch = vec![0.0; self.max_cells];
        let base = self.row_offsets[rows.start];
        let (defender_mixture, adversary_mixture) = (&self.defender.values, &self.adversary.values);
        for m in rows {
            self.for_each_term(self.states[m], |cell, j, l, p| {
                scratch[cell] += defender_mixture[j] * adversary_mixture[l] * p;
            });
            for k in self.row_range(m) {
                let cell = self.cells[k] as usize;
                values[k - base] = scratch[cell];
                scratch[cell] = 0.0;
            }
        }
    }

    /// The number of states.
    pub fn num_states(&self) -> usize {
        self.states.len()
    }

    /// The number of transitions (stored entries).
    pub fn num_transitions(&self) -> usize {
        self.columns.len()
    }

    /// State `m` as `(s, q, g, h)`.
    pub fn state(&self, m: usize) -> GmcState {
        self.states[m]
    }

    /// The index of a reachable state.
    pub fn index_of(&self, state: GmcState) -> Option<usize> {
        self.index.get(&state).map(|&m| m as usize)
    }

    /// Row `m`: successor indices (sorted) and their probabilities.
    pub fn row(&self, m: usize) -> (&[u32], &[f64]) {
        let range = self.row_offsets[m]..self.row_offsets[m + 1];
        (&self.columns[range.clone()], &self.values[range])
    }

    /// The range of stored entries of row `m` (indices into the value array).
    pub fn row_range(&self, m: usize) -> std::ops::Range<usize> {
        self.row_offsets[m]..self.row_offsets[m + 1]
    }

    /// All transition probabilities, row after row.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The sparsity pattern as a graph (edge iff positive probability under
    /// the supports).
    pub fn graph(&self) -> CsrGraph<'_> {
        CsrGraph {
            offsets: &self.row_offsets,
            targets: &self.columns,
        }
    }

    /// The initial distribution `p0` as `(state, probability)` pairs; a state
    /// may appear once only.
    pub fn initial(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.initial_states
            .iter()
            .zip(&self.initial_probabilities)
            .map(|(&m, &p)| (m as usize, p))
    }

    /// A scratch space for [`Gmc::row_derivatives`], sized for this chain.
    pub fn row_workspace(&self) -> RowWorkspace {
        RowWorkspace {
            x_cell: vec![0.0; self.max_cells],
            d_def: Vec::new(),
            d_adv: Vec::new(),
        }
    }

    /// The partial derivatives of row `m`'s expectation of `x` with respect
    /// to the controller probabilities (method.md section 2):
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
    /// probability appears in row `m` (every other `r_k(m)` is zero), using
    /// the numbers of the last [`Gmc::refill`]. `x` is indexed by GMC state.
    pub fn row_derivatives(
        &self,
        m: usize,
        x: &[f64],
        work: &mut RowWorkspace,
        mut defender: impl FnMut(usize, f64),
        mut adversary: impl FnMut(usize, f64),
    ) {
        let state = self.states[m];
        for k in self.row_range(m) {
            work.x_cell[self.cells[k] as usize] = x[self.columns[k] as usize];
        }
        let def_range = self.defender.at(state.s as usize, state.g as usize);
        let adv_range = self.adversary.at(state.s as usize, state.h as usize);
        work.d_def.clear();
        work.d_def.resize(def_range.len(), 0.0);
        work.d_adv.clear();
        work.d_adv.resize(adv_range.len(), 0.0);
        let (def_start, adv_start) = (def_range.start, adv_range.start);
        let (defender_mixture, adversary_mixture) = (&self.defender.values, &self.adversary.values);
        let (x_cell, d_def, d_adv) = (&work.x_cell, &mut work.d_def, &mut work.d_adv);
        self.for_each_term(state, |cell, j, l, p| {
            let w = p * x_cell[cell];
            d_def[j - def_start] += adversary_mixture[l] * w;
            d_adv[l - adv_start] += defender_mixture[j] * w;
        });
        for (offset, j) in def_range.enumerate() {
            for &(k, weight) in self.defender.terms_of(j) {
                defender(k as usize, weight * d_def[offset]);
            }
        }
        for (offset, l) in adv_range.enumerate() {
            for &(k, weight) in self.adversary.terms_of(l) {
                adversary(k as usize, weight * d_adv[offset]);
            }
        }
    }

    /// The adjoint gradient pass of method.md section 2. With `x` the value
    /// vector on all states and `y` the adjoint weights (zero outside `T`),
    /// adds to `gradient_defender[k]` and `gradient_adversary[k]`
    ///
    /// ```text
    /// grad_k = sum_m y(m) r_k(m),   r_k(m) = sum_m' dP(m' | m)/d mu_k x(m')
    /// ```
    ///
    /// ([`Gmc::row_derivatives`]): the partial derivatives of
    /// `sum_m y(m) sum_m' P(m' | m) x(m')` with respect to `mu_def` and `mu_adv`.
    ///
    /// Above [`PARALLEL_GRADIENT_ROWS`] rows with `y(m) != 0`, the rows are
    /// split into [`GRADIENT_CHUNKS`] contiguous chunks handled in parallel
    /// (rayon), each summing into its own buffers, which are then added in
    /// chunk order. The chunks do not depend on the number of threads, so
    /// the result is bitwise reproducible; it differs from a sequential sum
    /// only by the order of summation. The buffers are kept in the GMC and
    /// reused: after the first call the pass allocates nothing.
    pub fn add_adjoint_gradient(
        &mut self,
        x: &[f64],
        y: &[f64],
        gradient_defender: &mut [f64],
        gradient_adversary: &mut [f64],
    ) {
        let mut workspace = std::mem::take(&mut self.gradient_workspace);
        workspace.rows.clear();
        workspace
            .rows
            .extend((0..y.len()).filter(|&m| y[m] != 0.0).map(|m| m as u32));
        if workspace.rows.len() < PARALLEL_GRADIENT_ROWS {
            let work = &mut workspace.sequential;
            work.x_cell.resize(self.max_cells, 0.0);
            for &m in &workspace.rows {
                let y_m = y[m as usize];
                self.row_derivatives(
                    m as usize,
                    x,
                    work,
                    |k, r| gradient_defender[k] += y_m * r,
                    |k, r| gradient_adversary[k] += y_m * r,
                );
            }
        } else {
            self.parallel_adjoint_gradient(
                &mut workspace,
                x,
                y,
                gradient_defender,
                gradient_adversary,
            );
        }
        self.gradient_workspace = workspace;
    }

    fn parallel_adjoint_gradient(
        &self,
        workspace: &mut GradientWorkspace,
        x: &[f64],
        y: &[f64],
        gradient_defender: &mut [f64],
        gradient_adversary: &mut [f64],
    ) {
        let (num_def, num_adv) = (gradient_defender.len(), gradient_adversary.len());
        workspace
            .chunks
            .resize_with(GRADIENT_CHUNKS, || GradientChunk {
                defender: Vec::new(),
                adversary: Vec::new(),
                rows: RowWorkspace::default(),
            });
        let rows = &workspace.rows;
        let per_chunk = rows.len().div_ceil(GRADIENT_CHUNKS);
        workspace
            .chunks
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, chunk)| {
                let _flush = FlushDenormals::on_this_thread();
                chunk.defender.clear();
                chunk.defender.resize(num_def, 0.0);
                chunk.adversary.clear();
                chunk.adversary.resize(num_adv, 0.0);
                chunk.rows.x_cell.resize(self.max_cells, 0.0);
                let mine =
                    &rows[(c * per_chunk).min(rows.len())..((c + 1) * per_chunk).min(rows.len())];
                let (defender, adversary) = (&mut chunk.defender, &mut chunk.adversary);
                for &m in mine {
                    let y_m = y[m as usize];
                    self.row_derivatives(
                        m as usize,
                        x,
                        &mut chunk.rows,
                        |k, r| defender[k] += y_m * r,
                        |k, r| adversary[k] += y_m * r,
                    );
                }
            });
        let chunks = &workspace.chunks;
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

    /// Adds to `initial_defender[g]` and `initial_adversary[h]` the partial
    /// derivatives of `V = sum_m p0(m) x(m)` with respect to the initial node
    /// probabilities: `dV/d init_def(g) = sum_{s,h} init(s) init_adv(h) x(s, q0(s), g, h)`.
    pub fn add_initial_gradient(
        &self,
        x: &[f64],
        defender: &Probabilities,
        adversary: &Probabilities,
        initial_defender: &mut [f64],
        initial_adversary: &mut [f64],
    ) {
        for &m in &self.initial_states {
            let state = self.states[m as usize];
            let (s, g, h) = (state.s as usize, state.g as usize, state.h as usize);
            let base = self.game_initial[s] * x[m as usize];
            initial_defender[g] += base * adversary.initial[h];
            initial_adversary[h] += base * defender.initial[g];
        }
    }
}

fn check_support(
    player: &'static str,
    game_player: &Player,
    support: &Support,
) -> Result<(), ProductError> {
    let mismatch = |problem: String| ProductError::Mismatch { player, problem };
    if support.num_observations() != game_player.num_observations() {
        return Err(mismatch(format!(
            "has {} observations, the game's {player} has {}",
            support.num_observations(),
            game_player.num_observations()
        )));
    }
    if (0..support.num_entries()).any(|k| support.entry(k).1 >= game_player.num_actions()) {
        return Err(mismatch(format!(
            "uses an action the game's {player} does not have"
        )));
    }
    for g in 0..support.num_nodes() {
        for o in 0..support.num_observations() {
            if let Some(k) = support
                .block(g, o)
                .find(|&k| !game_player.action_enabled(o, support.entry(k).1))
            {
                return Err(mismatch(format!(
                    "plays action `{}` in node {g} under observation `{}`, which does not enable it",
                    game_player.actions()[support.entry(k).1],
                    game_player.observations()[o]
                )));
            }
        }
    }
    if support.initial_nodes().next().is_none() {
        return Err(mismatch(
            "has no initial node with positive probability".into(),
        ));
    }
    Ok(())
}
