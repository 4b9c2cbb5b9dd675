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
use thiserror::Error;

use crate::automaton::{Dra, Letter};
use crate::controller::{Mixture, Probabilities, Support};
use crate::game::{AdversaryAction, DefenderAction, Player, Posg};
use crate::graph::CsrGraph;
use crate::interner::{Interner, TooManyKeys};
use crate::solver::FlushDenormals;

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
                successors.extend(
                    game.transition(s, DefenderAction(u), AdversaryAction(v))
                        .iter()
                        .map(|&(t, _)| t as u32),
                );
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
                local_transitions.extend(
                    game.transition(s, DefenderAction(u), AdversaryAction(v))
                        .iter()
                        .map(|&(t, p)| {
                            let index = local
                                .binary_search(&(t as u32))
                                .expect("successor is in the union");
                            (index as u32, p)
                        }),
                );
            }
            successor_offsets.push(successors.len());
        }
        let letters = dra.state_letters(game);
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
    states: Interner<GmcState>,
    row_offsets: Vec<usize>,
    columns: Vec<u32>,
    cells: Vec<u32>,
    values: Vec<f64>,
    initial_states: Vec<u32>,
    initial_probabilities: Vec<f64>,
    game_initial: Vec<f64>,
    max_cells: usize,
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
            states: Interner::default(),
            row_offsets: vec![0],
            columns: Vec::new(),
            cells: Vec::new(),
            values: Vec::new(),
            initial_states: Vec::new(),
            initial_probabilities: Vec::new(),
            game_initial,
            max_cells,
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
        self.states
            .intern(state)
            .map_err(|TooManyKeys| ProductError::TooLarge)
    }

    fn explore(&mut self, dra: &Dra) -> Result<(), ProductError> {
        let mut cell_seen = vec![false; self.max_cells];
        let mut row_cells: Vec<u32> = Vec::new();
        let mut row: Vec<(u32, u32)> = Vec::new();
        let mut m = 0;
        while m < self.states.len() {
            let state = self.states.keys()[m];
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
        let (num_g, num_h) = (self.defender.num_nodes(), self.adversary.num_nodes());
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
    pub(crate) fn for_each_term(
        &self,
        state: GmcState,
        mut visit: impl FnMut(usize, usize, usize, f64),
    ) {
        let (s, num_h) = (state.s as usize, self.adversary.num_nodes());
        let num_g = self.defender.num_nodes();
        for j in self.defender.at(s, state.g as usize) {
            let (g_next, u) = self.defender.entry(j);
            for l in self.adversary.at(s, state.h as usize) {
                let (h_next, v) = self.adversary.entry(l);
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
            let state = self.states.keys()[m as usize];
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
        let (defender_mixture, adversary_mixture) =
            (self.defender.values(), self.adversary.values());
        for m in rows {
            self.for_each_term(self.states.keys()[m], |cell, j, l, p| {
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
        self.states.keys()[m]
    }

    /// The index of a reachable state.
    pub fn index_of(&self, state: GmcState) -> Option<usize> {
        self.states.get(&state).map(|m| m as usize)
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

    /// The largest number of cells `(local s', g', h')` of a row: the
    /// length of a dense scratch vector indexed by cell.
    pub(crate) fn max_cells(&self) -> usize {
        self.max_cells
    }

    /// The cell `(local s', g', h')` of each stored entry of row `m`,
    /// aligned with [`Gmc::row`].
    pub(crate) fn row_cells(&self, m: usize) -> &[u32] {
        &self.cells[self.row_range(m)]
    }

    /// The defender's and the adversary's mixtures `A(g', u | s, g)` as of
    /// the last [`Gmc::refill`].
    pub(crate) fn mixtures(&self) -> (&Mixture, &Mixture) {
        (&self.defender, &self.adversary)
    }

    /// The initial states `(s, q0(s), g, h)` and `init(s)` of each, in the
    /// order of [`Gmc::initial`].
    pub(crate) fn initial_states(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.initial_states.iter().map(|&m| {
            let s = self.states.keys()[m as usize].s as usize;
            (m as usize, self.game_initial[s])
        })
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
