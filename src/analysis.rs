//! Recurrence analysis of the global Markov chain (method.md section 1).
//!
//! For a fixed support structure the graph of the GMC is fixed, and so are:
//!
//! * its bottom strongly connected components (BSCCs), the recurrence classes;
//! * the phi-feasible ones (the paper's Definition 4.3): a BSCC `R` is
//!   feasible iff for some Rabin pair `i` it meets `K_i` and misses `L_i`;
//!   the paper's Algorithm 2 gives `Good_k`, the states of `R` in the `K_i` of
//!   every such pair;
//! * `B`, the union of feasible BSCCs; `Z`, the states that cannot reach `B`;
//!   `T`, every other reachable state.
//!
//! The value is 1 on `B`, 0 on `Z` and solves `(I - Q) x = b` on `T`. As a
//! qualitative precomputation (standard in probabilistic model checkers),
//! the states of `T` that cannot reach `Z` are classified [`StateClass::Sure`]:
//! their value is exactly 1 for every probability on the supports, so they
//! join `B` in the linear system, which makes it smaller and their values
//! exact rather than `1 - 1e-15`.

use serde::Serialize;

use crate::automaton::Dra;
use crate::graph::{
    CsrGraph, backward_reachable, bottom_components, reverse_csr, strongly_connected_components,
};
use crate::product::Gmc;

/// The class of a GMC state with respect to the target set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum StateClass {
    /// In a phi-feasible BSCC: the formula holds with probability 1 from here.
    Target,
    /// Cannot reach a phi-feasible BSCC: probability 0.
    Zero,
    /// Not in a feasible BSCC, but cannot reach a `Zero` state: every run
    /// from here reaches a feasible BSCC, so the probability is exactly 1.
    Sure,
    /// Transient and can reach a phi-feasible BSCC: solved for.
    Transient,
}

/// One recurrence class (BSCC) of the GMC.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Bscc {
    /// Its states (GMC indices, increasing).
    pub states: Vec<usize>,
    /// The Rabin pairs `i` through which it is phi-feasible (meets `K_i`,
    /// misses `L_i`); empty if it is not feasible.
    pub feasible_pairs: Vec<usize>,
    /// Algorithm 2's `Good_k`: its states whose automaton state is in `K_i`
    /// for a feasible pair `i`.
    pub good: Vec<usize>,
}

impl Bscc {
    /// Whether the class is phi-feasible.
    pub fn is_feasible(&self) -> bool {
        !self.feasible_pairs.is_empty()
    }
}

/// The recurrence classes of a GMC and the partition `B`, `Z`, `T`.
#[derive(Debug, Clone)]
pub struct Recurrence {
    /// All BSCCs, in reverse topological order of the component graph.
    pub bsccs: Vec<Bscc>,
    /// The class of every GMC state.
    pub classes: Vec<StateClass>,
    /// The transient states `T` (without the [`StateClass::Sure`] ones) in
    /// increasing GMC order: the unknowns of the linear system.
    pub transient: Vec<usize>,
    /// For each GMC state, its position in `transient` (or `u32::MAX`).
    pub transient_index: Vec<u32>,
}

impl Recurrence {
    /// Analyses the sparsity pattern of `gmc` against the Rabin pairs of `dra`
    /// (the automaton the GMC was built with). `O(states + transitions)`.
    pub fn analyse(gmc: &Gmc, dra: &Dra) -> Self {
        let graph = gmc.graph();
        let components = strongly_connected_components(&graph);
        let bottom = bottom_components(&graph, &components);
        let mut bsccs = Vec::new();
        let mut in_target = vec![false; gmc.num_states()];
        for (c, states) in components.members().into_iter().enumerate() {
            if !bottom[c] {
                continue;
            }
            let bscc = classify(gmc, dra, states);
            if bscc.is_feasible() {
                for &m in &bscc.states {
                    in_target[m] = true;
                }
            }
            bsccs.push(bscc);
        }
        let (offsets, targets) = reverse_csr(&graph);
        let reaches = backward_reachable(
            &CsrGraph {
                offsets: &offsets,
                targets: &targets,
            },
            &in_target,
        );
        let zero: Vec<bool> = reaches.iter().map(|&r| !r).collect();
        let reaches_zero = backward_reachable(
            &CsrGraph {
                offsets: &offsets,
                targets: &targets,
            },
            &zero,
        );
        let classes: Vec<StateClass> = (0..gmc.num_states())
            .map(|m| match (in_target[m], reaches[m], reaches_zero[m]) {
                (true, _, _) => StateClass::Target,
                (false, false, _) => StateClass::Zero,
                (false, true, false) => StateClass::Sure,
                (false, true, true) => StateClass::Transient,
            })
            .collect();
        let transient: Vec<usize> = (0..classes.len())
            .filter(|&m| classes[m] == StateClass::Transient)
            .collect();
        let mut transient_index = vec![u32::MAX; classes.len()];
        for (i, &m) in transient.iter().enumerate() {
            transient_index[m] = i as u32;
        }
        Self {
            bsccs,
            classes,
            transient,
            transient_index,
        }
    }

    /// The phi-feasible BSCCs.
    pub fn feasible(&self) -> impl Iterator<Item = &Bscc> {
        self.bsccs.iter().filter(|b| b.is_feasible())
    }
}

fn classify(gmc: &Gmc, dra: &Dra, states: Vec<usize>) -> Bscc {
    let automaton_states = |m: &usize| gmc.state(*m).q as usize;
    let feasible_pairs: Vec<usize> = dra
        .pairs()
        .iter()
        .enumerate()
        .filter(|(_, pair)| {
            states.iter().map(automaton_states).any(|q| pair.inf[q])
                && !states.iter().map(automaton_states).any(|q| pair.fin[q])
        })
        .map(|(i, _)| i)
        .collect();
    let good = states
        .iter()
        .copied()
        .filter(|m| {
            feasible_pairs
                .iter()
                .any(|&i| dra.pairs()[i].inf[automaton_states(m)])
        })
        .collect();
    Bscc {
        states,
        feasible_pairs,
        good,
    }
}
