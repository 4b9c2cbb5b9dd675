//! Algorithm 2: the states of a phi-feasible recurrent set that must be
//! visited often in steady state.

use crate::analysis::Recurrence;
use crate::automaton::Dra;
use crate::game::Posg;
use crate::product::{Gmc, GmcState};

/// `Good_k` of one phi-feasible recurrence class `R_k`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GoodSet {
    /// The index of `R_k` in [`Recurrence::bsccs`].
    pub bscc: usize,
    /// `|R_k|`.
    pub bscc_size: usize,
    /// The pairs `i` with `(L_i x G_def x G_adv) n R_k` empty (line 3) whose
    /// `K_i` meets `R_k`.
    pub pairs: Vec<usize>,
    /// `Good_k`, increasing in `(s, q, g, h)`.
    pub states: Vec<GmcState>,
}

impl GoodSet {
    /// The members as `(state name, q, g, h)` text, e.g. `(s5, q1, g0, h0)`.
    pub fn describe(&self, game: &Posg) -> Vec<String> {
        self.states
            .iter()
            .map(|m| {
                let name = game.states().get(m.s as usize).map_or("?", String::as_str);
                format!("({name}, q{}, g{}, h{})", m.q, m.g, m.h)
            })
            .collect()
    }
}

/// Algorithm 2 for every phi-feasible BSCC `R_k` of `recurrence` (the
/// analysis of `gmc` against `dra`):
///
/// ```text
/// Good_k = U over i with (L_i x G_def x G_adv) n R_k = {} of (K_i x G_def x G_adv) n R_k   (lines 1-6)
/// ```
///
/// One [`GoodSet`] per feasible class, in the order of [`Recurrence::bsccs`].
pub fn good_sets(gmc: &Gmc, dra: &Dra, recurrence: &Recurrence) -> Vec<GoodSet> {
    recurrence
        .bsccs
        .iter()
        .enumerate()
        .filter(|(_, bscc)| bscc.is_feasible())
        .map(|(k, bscc)| {
            let class: Vec<GmcState> = bscc.states.iter().map(|&m| gmc.state(m)).collect();
            let mut pairs = Vec::new();
            let mut states = Vec::new();
            for (i, pair) in dra.pairs().iter().enumerate() {
                if class.iter().any(|m| pair.fin[m.q as usize]) {
                    continue;
                }
                let before = states.len();
                states.extend(class.iter().filter(|m| pair.inf[m.q as usize]));
                if states.len() > before {
                    pairs.push(i);
                }
            }
            states.sort_unstable();
            states.dedup();
            GoodSet {
                bscc: k,
                bscc_size: class.len(),
                pairs,
                states,
            }
        })
        .collect()
}
