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
use crate::controller::{Mixture, Probabilities, Support};
use crate::game::{AdversaryAction, DefenderAction, Player, Posg};
use crate::graph::CsrGraph;

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

/// How far [`Gmc::build_with`] explores the chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exploration {
    /// Every state reachable from the initial distribution, with its row.
    Full,
    /// Stop at *decided* states, whose automaton state decides the formula
    /// on every word over the game's letters ([`Dra::decided_states`]):
    /// they are kept as leaves without a row, and their value (1 or 0) is
    /// [`Gmc::verdict`]. The states reachable from a decided state are
    /// decided alike, so the value of every other state is unchanged
    /// (method.md section 1, "decided states").
    UntilDecided,
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

    /// The index of `(s, u, v)` in the transition table.
    fn pair_index(&self, s: usize, u: usize, v: usize) -> usize {
        (s * self.num_defender_actions + u) * self.num_adversary_actions + v
    }

    /// For each `(s, u, v)` ([`Self::pair_index`]), the set of local
    /// successors of `T(. | s, u, v)` as a bit mask, or `None` if no state
    /// has at most 64 successors. The masks of a state with more are
    /// incomplete and not to be used.
    fn successor_masks(&self) -> Option<Vec<u64>> {
        let pairs = self.transition_offsets.len() - 1;
        let any_small =
            (0..self.successor_offsets.len() - 1).any(|s| self.successors(s).len() <= 64);
        any_small.then(|| {
            (0..pairs)
                .map(|t| {
                    self.local_transitions
                        [self.transition_offsets[t]..self.transition_offsets[t + 1]]
                        .iter()
                        .filter(|&&(local, _)| local < 64)
                        .fold(0u64, |mask, &(local, _)| mask | (1 << local))
                })
                .collect()
        })
    }

    fn successors(&self, s: usize) -> &[u32] {
        &self.successors[self.successor_offsets[s]..self.successor_offsets[s + 1]]
    }

    fn transition(&self, s: usize, u: usize, v: usize) -> &[(u32, f64)] {
        let t = self.pair_index(s, u, v);
        &self.local_transitions[self.transition_offsets[t]..self.transition_offsets[t + 1]]
    }
}

/// The reachable global Markov chain in compressed sparse row form.
///
/// Row `m` holds `P(. | m)`; within a row the columns are sorted. Each
/// stored entry also remembers its *cell* `(local s', g', h')`, which lets
/// [`Gmc::refill`] and the gradient pass find an entry without searching.
/// Built with [`Exploration::UntilDecided`], the rows of decided states are
/// empty ([`Gmc::verdict`]).
#[derive(Debug, Clone)]
pub struct Gmc {
    tables: GameTables,
    defender: Mixture,
    adversary: Mixture,
    states: StateIndex,
    row_offsets: Vec<usize>,
    columns: Vec<u32>,
    cells: Vec<u32>,
    values: Vec<f64>,
    initial_states: Vec<u32>,
    initial_probabilities: Vec<f64>,
    game_initial: Vec<f64>,
    max_cells: usize,
    decided: Vec<Option<bool>>,
}

/// Rows refilled by one parallel task of [`Gmc::refill`].
const REFILL_CHUNK_ROWS: usize = 8192;

impl Gmc {
    /// Explores the GMC reachable from the initial distribution under the
    /// controllers' supports and stores its sparsity pattern
    /// ([`Exploration::Full`]). The numbers are zero until [`Gmc::refill`]
    /// is called.
    pub fn build(
        game: &Posg,
        dra: &Dra,
        defender: &Support,
        adversary: &Support,
    ) -> Result<Self, ProductError> {
        Self::build_with(game, dra, defender, adversary, Exploration::Full)
    }

    /// [`Gmc::build`], exploring as far as `exploration` says.
    pub fn build_with(
        game: &Posg,
        dra: &Dra,
        defender: &Support,
        adversary: &Support,
        exploration: Exploration,
    ) -> Result<Self, ProductError> {
        check_support("defender", game.defender(), defender)?;
        check_support("adversary", game.adversary(), adversary)?;
        check_mixture_size("defender", game.defender(), defender, game.num_states())?;
        check_mixture_size("adversary", game.adversary(), adversary, game.num_states())?;
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
        // The cells of one row are distinct GMC states.
        if let Some(message) = crate::limits::exceeded(
            "one row (successor states x defender nodes x adversary nodes)",
            cells,
            crate::limits::MAX_GMC_STATES,
            "distinct successor states",
            "MAX_GMC_STATES",
        ) {
            return Err(ProductError::Budget(message));
        }
        let max_cells = max_successors * num_g * num_h;
        let mut game_initial = vec![0.0; game.num_states()];
        for &(s, p) in game.initial() {
            game_initial[s] = p;
        }
        let decided = match exploration {
            Exploration::Full => vec![None; dra.num_states()],
            Exploration::UntilDecided => {
                let mut letters = tables.letters.clone();
                letters.sort_unstable();
                letters.dedup();
                dra.decided_states(&letters)
            }
        };
        let mut gmc = Self {
            tables,
            defender: defender_mixture,
            adversary: adversary_mixture,
            states: StateIndex::new(game.num_states(), dra.num_states(), num_g, num_h),
            row_offsets: vec![0],
            columns: Vec::new(),
            cells: Vec::new(),
            values: Vec::new(),
            initial_states: Vec::new(),
            initial_probabilities: Vec::new(),
            game_initial,
            max_cells,
            decided,
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
        self.states.intern(state)
    }

    fn explore(&mut self, dra: &Dra) -> Result<(), ProductError> {
        let mut pattern = RowPattern {
            successor_masks: self.tables.successor_masks(),
            cell_seen: vec![false; self.max_cells],
            covered: vec![0; self.defender.num_nodes() * self.adversary.num_nodes()],
            cells: Vec::new(),
        };
        let mut row: Vec<(u32, u32)> = Vec::new();
        let mut m = 0;
        while m < self.states.len() {
            let state = self.states.keys()[m];
            if self.decided[state.q as usize].is_some() {
                self.row_offsets.push(self.columns.len());
                m += 1;
                continue;
            }
            let row_cells = self.row_pattern(state, &mut pattern);
            row.clear();
            for &cell in row_cells {
                let target = self.cell_state(state, cell as usize, dra);
                row.push((self.intern(target)?, cell));
            }
            row.sort_unstable();
            if let Some(message) = crate::limits::exceeded(
                &format!(
                    "the global Markov chain (already {} states reached, with {} x {} \
                     controller nodes)",
                    self.states.len(),
                    self.defender.num_nodes(),
                    self.adversary.num_nodes()
                ),
                (self.columns.len() + row.len()) as u128,
                crate::limits::MAX_GMC_TRANSITIONS,
                "transitions or more",
                "MAX_GMC_TRANSITIONS",
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

    /// The distinct cells of row `state`, in the order in which
    /// [`Gmc::for_each_term`] meets them first. A pair of mixture entries
    /// `(g', u)`, `(h', v)` whose successors `T(. | s, u, v)` were all met
    /// with `(g', h')` before adds no cell: its terms are skipped.
    fn row_pattern<'p>(&self, state: GmcState, pattern: &'p mut RowPattern) -> &'p [u32] {
        let RowPattern {
            successor_masks,
            cell_seen,
            covered,
            cells,
        } = pattern;
        for &cell in cells.iter() {
            cell_seen[cell as usize] = false;
        }
        cells.clear();
        covered.fill(0);
        let s = state.s as usize;
        let masks = successor_masks
            .as_deref()
            .filter(|_| self.tables.successors(s).len() <= 64);
        let (num_g, num_h) = (self.defender.num_nodes(), self.adversary.num_nodes());
        for j in self.defender.at(s, state.g as usize) {
            let (g_next, u) = self.defender.entry(j);
            for l in self.adversary.at(s, state.h as usize) {
                let (h_next, v) = self.adversary.entry(l);
                let (u, v) = (u as usize, v as usize);
                if let Some(masks) = masks {
                    let mask = masks[self.tables.pair_index(s, u, v)];
                    let pair = &mut covered[g_next as usize * num_h + h_next as usize];
                    if mask & !*pair == 0 {
                        continue;
                    }
                    *pair |= mask;
                }
                for &(local, _) in self.tables.transition(s, u, v) {
                    let cell = (local as usize * num_g + g_next as usize) * num_h + h_next as usize;
                    if !cell_seen[cell] {
                        cell_seen[cell] = true;
                        cells.push(cell as u32);
                    }
                }
            }
        }
        cells
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
        let mut scratch = vec![0.0; self.max_cells];
        let base = self.row_offsets[rows.start];
        let (defender_mixture, adversary_mixture) =
            (self.defender.values(), self.adversary.values());
        for m in rows {
            if self.row_range(m).is_empty() {
                // A decided state: no row, and no terms to collect.
                continue;
            }
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

    /// `Some(phi holds)` for a state at which the exploration stopped
    /// because its automaton state decides the formula
    /// ([`Exploration::UntilDecided`]): its value is exactly 1 or 0 and its
    /// row is empty. `None` for every state of a full exploration.
    pub fn verdict(&self, m: usize) -> Option<bool> {
        self.decided[self.states.keys()[m].q as usize]
    }

    /// The number of states at which the exploration stopped
    /// ([`Gmc::verdict`]).
    pub fn num_decided(&self) -> usize {
        if self.decided.iter().all(Option::is_none) {
            return 0;
        }
        (0..self.num_states())
            .filter(|&m| self.verdict(m).is_some())
            .count()
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

/// Scratch of [`Gmc::row_pattern`]: the successor masks of the game, the
/// cells met in the current row (as flags and in order of first meeting)
/// and, per node pair `(g', h')`, the local successors met with it (a bit
/// mask).
struct RowPattern {
    successor_masks: Option<Vec<u64>>,
    cell_seen: Vec<bool>,
    covered: Vec<u64>,
    cells: Vec<u32>,
}

/// The GMC states found so far, numbered `0, 1, ...` in order of discovery,
/// and the map from a state to its number. When `|Q| |G| |H|` is small the
/// map is dense: each game state `s` met gets a block of `|Q| |G| |H|`
/// slots holding the numbers of the states `(s, q, g, h)`, which costs 4
/// bytes per slot and no hashing; otherwise it is a hash map.
#[derive(Debug, Clone)]
struct StateIndex {
    keys: Vec<GmcState>,
    lookup: StateLookup,
}

#[derive(Debug, Clone)]
enum StateLookup {
    Blocks(BlockLookup),
    Hashed(FxHashMap<GmcState, u32>),
}

/// The dense map: `slots[block_of[s] + (q |G| + g) |H| + h]` is the number
/// of `(s, q, g, h)`, [`NO_INDEX`] for a state not found (yet) and for the
/// block of a game state not met.
#[derive(Debug, Clone)]
struct BlockLookup {
    num_q: usize,
    num_g: usize,
    num_h: usize,
    block_len: usize,
    block_of: Vec<u32>,
    slots: Vec<u32>,
}

/// An empty slot; also caps the number of states at `2^32 - 1`.
const NO_INDEX: u32 = u32::MAX;

/// The largest block `|Q| |G| |H|` of the dense state map (16 KiB): a game
/// state met costs at most this many slots even if few of its GMC states
/// are reachable.
const MAX_BLOCK_SLOTS: usize = 4096;

impl StateIndex {
    fn new(num_game_states: usize, num_q: usize, num_g: usize, num_h: usize) -> Self {
        let block_len = num_q * num_g * num_h;
        let dense = block_len <= MAX_BLOCK_SLOTS
            && num_game_states
                .checked_mul(block_len)
                .is_some_and(|slots| slots < NO_INDEX as usize);
        let lookup = if dense {
            StateLookup::Blocks(BlockLookup {
                num_q,
                num_g,
                num_h,
                block_len,
                block_of: vec![NO_INDEX; num_game_states],
                slots: Vec::new(),
            })
        } else {
            StateLookup::Hashed(FxHashMap::default())
        };
        Self {
            keys: Vec::new(),
            lookup,
        }
    }

    /// The number of `state`, numbering it next if it is new.
    fn intern(&mut self, state: GmcState) -> Result<u32, ProductError> {
        let next = self.keys.len();
        let slot = match &mut self.lookup {
            StateLookup::Blocks(blocks) => blocks.slot_mut(state),
            StateLookup::Hashed(map) => map.entry(state).or_insert(NO_INDEX),
        };
        if *slot == NO_INDEX {
            if let Some(message) = crate::limits::exceeded(
                "the global Markov chain",
                next as u128 + 1,
                crate::limits::MAX_GMC_STATES,
                "states or more",
                "MAX_GMC_STATES",
            ) {
                return Err(ProductError::Budget(message));
            }
            *slot = u32::try_from(next)
                .ok()
                .filter(|&m| m != NO_INDEX)
                .ok_or(ProductError::TooLarge)?;
            self.keys.push(state);
        }
        Ok(*slot)
    }

    /// The number of `state`, if it has been found.
    fn get(&self, state: &GmcState) -> Option<u32> {
        match &self.lookup {
            StateLookup::Blocks(blocks) => blocks.get(state),
            StateLookup::Hashed(map) => map.get(state).copied(),
        }
    }

    fn len(&self) -> usize {
        self.keys.len()
    }

    fn keys(&self) -> &[GmcState] {
        &self.keys
    }
}

impl BlockLookup {
    fn offset(&self, state: &GmcState) -> usize {
        (state.q as usize * self.num_g + state.g as usize) * self.num_h + state.h as usize
    }

    /// The slot of `state`, giving its game state a block if it has none.
    fn slot_mut(&mut self, state: GmcState) -> &mut u32 {
        let offset = self.offset(&state);
        let start = &mut self.block_of[state.s as usize];
        if *start == NO_INDEX {
            *start = self.slots.len() as u32;
            self.slots
                .resize(self.slots.len() + self.block_len, NO_INDEX);
        }
        &mut self.slots[*start as usize + offset]
    }

    fn get(&self, state: &GmcState) -> Option<u32> {
        let start = *self.block_of.get(state.s as usize)?;
        let in_block = (state.q as usize) < self.num_q
            && (state.g as usize) < self.num_g
            && (state.h as usize) < self.num_h;
        if start == NO_INDEX || !in_block {
            return None;
        }
        let slot = self.slots[start as usize + self.offset(state)];
        (slot != NO_INDEX).then_some(slot)
    }
}

/// Refuses, before allocation, an action mixture of `role` with more terms
/// than [`crate::limits::MAX_MIXTURE_TERMS`] (about game states x
/// controller nodes^2 x actions: the GMC's rows are built from it).
fn check_mixture_size(
    role: &str,
    player: &Player,
    support: &Support,
    num_states: usize,
) -> Result<(), ProductError> {
    let terms = Mixture::count_terms(player, support, num_states) as u128;
    match crate::limits::exceeded(
        &format!(
            "the {role}'s action mixture ({num_states} game states x {} controller nodes \
             x their successor nodes and actions)",
            support.num_nodes()
        ),
        terms,
        crate::limits::MAX_MIXTURE_TERMS,
        "terms",
        "MAX_MIXTURE_TERMS",
    ) {
        Some(message) => Err(ProductError::Budget(message)),
        None => Ok(()),
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
