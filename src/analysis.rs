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
//!
//! A GMC explored [`crate::product::Exploration::UntilDecided`] has leaves,
//! the decided states: they are no BSCC, and their class comes from their
//! verdict ([`Gmc::verdict`]): `Sure` if the formula holds, `Zero` if not.
//! These are the classes the full chain gives them (from such a state
//! every run is accepted, or none is), so `T` and its system are the same.

use serde::Serialize;

use crate::automaton::Dra;
use crate::graph::{Components, CsrGraph, Digraph, strongly_connected_components};
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
    /// (the automaton the GMC was built with). `O(states + transitions)`:
    /// one pass of Tarjan's algorithm and one pass over the components in
    /// its order, in which every edge leaving a component leads to one
    /// already classified.
    pub fn analyse(gmc: &Gmc, dra: &Dra) -> Self {
        let graph = gmc.graph();
        let components = strongly_connected_components(&graph);
        let mut bsccs = Vec::new();
        let verdict = |v: u32| gmc.verdict(v as usize);
        let flags = component_flags(&graph, &components, verdict, |members| {
            let bscc = classify(gmc, dra, members.iter().map(|&v| v as usize).collect());
            let feasible = bscc.is_feasible();
            bsccs.push(bscc);
            feasible
        });
        let classes: Vec<StateClass> = components
            .component
            .iter()
            .map(|&c| flags[c as usize].class())
            .collect();
        Self::with_classes(bsccs, classes)
    }

    /// The partition of the expected reward until a target (method.md
    /// section 9) on a GMC built with the automaton `dra` of `F T`: the
    /// states where `T` was reached (decided, or in a feasible BSCC) are
    /// [`StateClass::Target`], with reward 0 from there; the states that
    /// reach them with probability 1 without being there are the unknowns
    /// ([`StateClass::Transient`]); every other state misses `T` with
    /// positive probability, so its expected reward is infinite (Storm's
    /// convention): [`StateClass::Zero`]. The classes come from
    /// [`Recurrence::analyse`] for `F T`: its `Sure` states that have not
    /// reached `T` are the unknowns, and its `Transient` and `Zero` states
    /// the infinite ones.
    pub fn until_target(gmc: &Gmc, dra: &Dra) -> Self {
        let Self { bsccs, classes, .. } = Self::analyse(gmc, dra);
        let classes: Vec<StateClass> = classes
            .iter()
            .enumerate()
            .map(|(m, &class)| match (class, gmc.verdict(m)) {
                (StateClass::Target, _) | (_, Some(true)) => StateClass::Target,
                (StateClass::Sure, None) => StateClass::Transient,
                _ => StateClass::Zero,
            })
            .collect();
        Self::with_classes(bsccs, classes)
    }

    /// The recurrence with `classes`, its unknowns numbered in GMC order.
    fn with_classes(bsccs: Vec<Bscc>, classes: Vec<StateClass>) -> Self {
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

/// The [`ComponentFlags`] of every component of `graph`, visiting the
/// components in Tarjan's order (successor components first) and asking
/// `feasible` about each bottom component (its vertices, increasing) in
/// that order, except the leaves with a `verdict` (decided states), which
/// reach the target set iff their verdict is `true`.
fn component_flags(
    graph: &CsrGraph<'_>,
    components: &Components,
    verdict: impl Fn(u32) -> Option<bool>,
    mut feasible: impl FnMut(&[u32]) -> bool,
) -> Vec<ComponentFlags> {
    let (offsets, vertices) = components.grouped();
    let mut flags = vec![ComponentFlags::default(); components.count];
    for c in 0..components.count {
        let members = &vertices[offsets[c]..offsets[c + 1]];
        let (mut leaves, mut to_target, mut to_zero) = (false, false, false);
        for &v in members {
            for w in graph.successors(v as usize) {
                let d = components.component[w] as usize;
                if d != c {
                    leaves = true;
                    to_target |= flags[d].reaches_target;
                    to_zero |= flags[d].reaches_zero;
                }
            }
        }
        if !leaves {
            if let Some(holds) = verdict(members[0]) {
                to_target = holds;
            } else {
                to_target = feasible(members);
                flags[c].target = to_target;
            }
        }
        flags[c].reaches_target = to_target;
        flags[c].reaches_zero = !to_target || to_zero;
    }
    flags
}

/// What [`Recurrence::analyse`] knows of a strongly connected component:
/// whether it is a phi-feasible BSCC, can reach one (`B`), or can reach a
/// state that cannot (`Z`). All states of a component share these.
#[derive(Debug, Clone, Copy, Default)]
struct ComponentFlags {
    target: bool,
    reaches_target: bool,
    reaches_zero: bool,
}

impl ComponentFlags {
    fn class(self) -> StateClass {
        match (self.target, self.reaches_target, self.reaches_zero) {
            (true, _, _) => StateClass::Target,
            (false, false, _) => StateClass::Zero,
            (false, true, false) => StateClass::Sure,
            (false, true, true) => StateClass::Transient,
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{backward_reachable, bottom_components, reverse_csr};
    use proptest::prelude::*;

    /// The classes by the definitions: `B` the feasible bottom components
    /// that are no leaf with a verdict, `Z` the vertices that cannot reach
    /// `B` or a leaf whose verdict is `true`, `Sure` those of the rest that
    /// cannot reach `Z` (backward searches on the reverse graph).
    fn reference_classes(
        graph: &CsrGraph<'_>,
        verdict: &dyn Fn(usize) -> Option<bool>,
        feasible: &dyn Fn(&[usize]) -> bool,
    ) -> Vec<StateClass> {
        let components = strongly_connected_components(graph);
        let bottom = bottom_components(graph, &components);
        let members = components.members();
        let n = graph.num_vertices();
        let mut target = vec![false; n];
        for (c, states) in members.iter().enumerate() {
            if bottom[c] && verdict(states[0]).is_none() && feasible(states) {
                for &v in states {
                    target[v] = true;
                }
            }
        }
        let accepting: Vec<bool> = (0..n)
            .map(|v| target[v] || verdict(v) == Some(true))
            .collect();
        let (offsets, targets) = reverse_csr(graph);
        let reverse = CsrGraph {
            offsets: &offsets,
            targets: &targets,
        };
        let reaches = backward_reachable(&reverse, &accepting);
        let zero: Vec<bool> = reaches.iter().map(|&r| !r).collect();
        let reaches_zero = backward_reachable(&reverse, &zero);
        (0..n)
            .map(|v| {
                ComponentFlags {
                    target: target[v],
                    reaches_target: reaches[v],
                    reaches_zero: reaches_zero[v],
                }
                .class()
            })
            .collect()
    }

    proptest! {
        #[test]
        fn one_pass_over_the_components_gives_the_classes_of_the_definitions(
            n in 1usize..14,
            raw in proptest::collection::vec((0usize..14, 0usize..14), 0..40),
            parity in 0usize..2,
            verdicts in proptest::collection::vec(0u8..3, 14),
        ) {
            let mut rows = vec![Vec::new(); n];
            for (a, b) in raw {
                rows[a % n].push((b % n) as u32);
            }
            let mut offsets = vec![0];
            let mut targets = Vec::new();
            for mut row in rows {
                row.sort_unstable();
                row.dedup();
                targets.extend(row);
                offsets.push(targets.len());
            }
            let graph = CsrGraph { offsets: &offsets, targets: &targets };
            let verdict = |v: usize| match verdicts[v] {
                _ if offsets[v + 1] > offsets[v] => None,
                0 => None,
                leaf => Some(leaf == 1),
            };
            let feasible = |states: &[usize]| states[0] % 2 == parity;
            let components = strongly_connected_components(&graph);
            let leaf_verdict = |v: u32| verdict(v as usize);
            let flags = component_flags(&graph, &components, leaf_verdict, |members| {
                let states: Vec<usize> = members.iter().map(|&v| v as usize).collect();
                feasible(&states)
            });
            let classes: Vec<StateClass> = components
                .component
                .iter()
                .map(|&c| flags[c as usize].class())
                .collect();
            prop_assert_eq!(classes, reference_classes(&graph, &verdict, &feasible));
        }
    }
}
