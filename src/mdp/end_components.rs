//! Maximal end components (MECs).
//!
//! An end component of an MDP is a set of states `C` with, for each `s` in
//! `C`, a non-empty set of actions `A(s)` such that every action in `A(s)`
//! leads into `C` only, and the graph of `C` under those actions is strongly
//! connected. Some strategy can stay in `C` forever and visit all of it
//! infinitely often; conversely, under any strategy, the states visited
//! infinitely often form an end component almost surely (de Alfaro 1997).
//!
//! [`maximal_end_components`] is the iterated SCC decomposition of Baier and
//! Katoen, *Principles of Model Checking*, Algorithm 47: compute the SCCs of
//! the graph of the enabled actions; disable every action that may leave its
//! state's SCC; a state left without an action dies, and every action that
//! may reach it is disabled at once (a backward pass, so that a chain of
//! removals costs one pass rather than one round per link); repeat until
//! no action leaves its SCC. Each round removes an action, so there are at
//! most `|A|` rounds of `O(|S| + |E|)` each; in practice a few.

use crate::graph::{Digraph, strongly_connected_components};

use super::{Mdp, Predecessors};

/// An end component: its states (increasing) and, for each, the actions
/// (local numbers, increasing) that stay inside it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EndComponent {
    /// The states of `C`.
    pub states: Vec<usize>,
    /// `actions[i]` is `A(states[i])`, non-empty.
    pub actions: Vec<Vec<usize>>,
}

/// The graph of an MDP's enabled actions (indexed globally).
struct Enabled<'a> {
    mdp: &'a Mdp,
    enabled: &'a [bool],
}

impl Digraph for Enabled<'_> {
    fn num_vertices(&self) -> usize {
        self.mdp.num_states()
    }

    fn successors(&self, v: usize) -> impl Iterator<Item = usize> + '_ {
        self.mdp
            .global_actions(v)
            .filter(|&a| self.enabled[a])
            .flat_map(|a| self.mdp.global_distribution(a).iter().map(|&(t, _)| t))
    }
}

/// The maximal end components of the sub-MDP on the states with
/// `within[s]` (actions that may leave `within` are not part of it), ordered
/// by their smallest state. Disjoint by construction.
pub fn maximal_end_components(mdp: &Mdp, within: &[bool]) -> Vec<EndComponent> {
    let every_action = vec![true; mdp.num_state_actions()];
    maximal_end_components_using(mdp, within, &every_action)
}

/// [`maximal_end_components`] of the sub-MDP that keeps only the global
/// actions `a` with `actions[a]` (numbered state after state).
pub fn maximal_end_components_using(
    mdp: &Mdp,
    within: &[bool],
    actions: &[bool],
) -> Vec<EndComponent> {
    let mut pruning = Pruning::new(mdp, within, actions);
    loop {
        let component = strongly_connected_components(&Enabled {
            mdp,
            enabled: &pruning.enabled,
        })
        .component;
        let mut changed = false;
        for s in 0..mdp.num_states() {
            if !pruning.alive[s] {
                continue;
            }
            for a in mdp.global_actions(s) {
                let leaves = pruning.enabled[a]
                    && mdp
                        .global_distribution(a)
                        .iter()
                        .any(|&(t, _)| component[t] != component[s]);
                if leaves {
                    pruning.disable(s, a);
                    changed = true;
                }
            }
        }
        pruning.propagate();
        if !changed {
            return collect(mdp, &pruning.alive, &pruning.enabled, &component);
        }
    }
}

/// The states and actions still candidates for an end component. A state
/// dies when its last action is disabled; then every action that may reach
/// it is disabled at once ([`Pruning::propagate`]), so a chain of removals
/// costs one pass instead of one SCC round per link.
struct Pruning<'a> {
    mdp: &'a Mdp,
    predecessors: Predecessors,
    alive: Vec<bool>,
    enabled: Vec<bool>,
    remaining: Vec<usize>,
    dead: Vec<usize>,
}

impl<'a> Pruning<'a> {
    /// The `actions` of the states in `within`, minus those that may leave
    /// it.
    fn new(mdp: &'a Mdp, within: &[bool], actions: &[bool]) -> Self {
        let n = mdp.num_states();
        let mut enabled = vec![false; mdp.num_state_actions()];
        let mut remaining = vec![0; n];
        for s in (0..n).filter(|&s| within[s]) {
            enabled[mdp.global_actions(s)].fill(true);
            remaining[s] = mdp.num_actions(s);
        }
        let mut pruning = Self {
            mdp,
            predecessors: mdp.predecessors(),
            alive: within.to_vec(),
            enabled,
            remaining,
            dead: (0..n).filter(|&s| !within[s]).collect(),
        };
        for s in (0..n).filter(|&s| within[s]) {
            for a in mdp.global_actions(s).filter(|&a| !actions[a]) {
                pruning.disable(s, a);
            }
        }
        pruning.propagate();
        pruning
    }

    /// Disables global action `a` of state `s`; kills `s` if it was its last.
    fn disable(&mut self, s: usize, a: usize) {
        if !self.enabled[a] {
            return;
        }
        self.enabled[a] = false;
        self.remaining[s] -= 1;
        if self.remaining[s] == 0 && self.alive[s] {
            self.alive[s] = false;
            self.dead.push(s);
        }
    }

    /// Disables every action that may reach a dead state, until no state dies.
    fn propagate(&mut self) {
        while let Some(t) = self.dead.pop() {
            for i in 0..self.predecessors.of(t).len() {
                let (s, a) = self.predecessors.of(t)[i];
                self.disable(s, self.mdp.global_actions(s).start + a);
            }
        }
    }
}

/// Groups the surviving states by SCC, in order of their smallest state.
fn collect(mdp: &Mdp, alive: &[bool], enabled: &[bool], component: &[u32]) -> Vec<EndComponent> {
    let mut slot_of_component = vec![usize::MAX; component.len()];
    let mut components: Vec<EndComponent> = Vec::new();
    for s in (0..mdp.num_states()).filter(|&s| alive[s]) {
        let c = component[s] as usize;
        if slot_of_component[c] == usize::MAX {
            slot_of_component[c] = components.len();
            components.push(EndComponent {
                states: Vec::new(),
                actions: Vec::new(),
            });
        }
        let ec = &mut components[slot_of_component[c]];
        ec.states.push(s);
        let first = mdp.global_actions(s).start;
        ec.actions.push(
            mdp.global_actions(s)
                .filter(|&a| enabled[a])
                .map(|a| a - first)
                .collect(),
        );
    }
    components
}

#[cfg(test)]
mod tests {
    use super::super::tests::mdp;
    use super::*;
    use proptest::prelude::*;

    fn states(components: &[EndComponent]) -> Vec<Vec<usize>> {
        components.iter().map(|c| c.states.clone()).collect()
    }

    /// 0 <-> 1 is an end component; 2 must leave towards 3 or 4 and is in
    /// none; 3 is absorbing; 4 can stay with 5 (action 1) but its action 0
    /// goes back to 2.
    fn six_states() -> Mdp {
        mdp(&[
            &[&[(0, 0.5), (1, 0.5)], &[(2, 1.0)]],
            &[&[(0, 1.0)]],
            &[&[(3, 0.5), (4, 0.5)]],
            &[&[(3, 1.0)]],
            &[&[(2, 1.0)], &[(5, 1.0)]],
            &[&[(4, 0.5), (5, 0.5)]],
        ])
    }

    #[test]
    fn hand_made_mdp_has_three_mecs_with_their_actions() {
        let mecs = maximal_end_components(&six_states(), &[true; 6]);
        assert_eq!(
            mecs,
            vec![
                EndComponent {
                    states: vec![0, 1],
                    actions: vec![vec![0], vec![0]]
                },
                EndComponent {
                    states: vec![3],
                    actions: vec![vec![0]]
                },
                EndComponent {
                    states: vec![4, 5],
                    actions: vec![vec![1], vec![0]]
                },
            ]
        );
    }

    #[test]
    fn removing_a_state_splits_or_kills_components() {
        let within = [true, false, true, true, true, false];
        let mecs = maximal_end_components(&six_states(), &within);
        assert_eq!(states(&mecs), vec![vec![3]]);
    }

    #[test]
    fn a_transient_chain_has_no_end_component_but_its_sink() {
        let m = mdp(&[&[&[(1, 1.0)]], &[&[(2, 1.0)]], &[&[(2, 1.0)]]]);
        assert_eq!(
            states(&maximal_end_components(&m, &[true; 3])),
            vec![vec![2]]
        );
    }

    /// Whether `set` (a bit mask) is the state set of some end component:
    /// with all actions that stay in `set`, every state keeps an action and
    /// the graph is strongly connected.
    fn is_end_component(m: &Mdp, set: u32) -> bool {
        let n = m.num_states();
        let inside = |s: usize| set >> s & 1 == 1;
        let members: Vec<usize> = (0..n).filter(|&s| inside(s)).collect();
        let staying = |s: usize| {
            (0..m.num_actions(s))
                .filter(|&a| m.distribution(s, a).iter().all(|&(t, _)| inside(t)))
                .collect::<Vec<_>>()
        };
        if members.iter().any(|&s| staying(s).is_empty()) {
            return false;
        }
        let reach_from = |from: usize| {
            let mut seen = 1u32 << from;
            let mut stack = vec![from];
            while let Some(s) = stack.pop() {
                for a in staying(s) {
                    for &(t, _) in m.distribution(s, a) {
                        if seen >> t & 1 == 0 {
                            seen |= 1 << t;
                            stack.push(t);
                        }
                    }
                }
            }
            seen
        };
        members.iter().all(|&s| reach_from(s) == set)
    }

    fn arbitrary_mdp() -> impl Strategy<Value = Mdp> {
        (1usize..7).prop_flat_map(|n| {
            proptest::collection::vec(
                proptest::collection::vec(proptest::collection::vec(0..n, 1..3), 1..3),
                n,
            )
            .prop_map(|states| {
                let mut builder = super::super::MdpBuilder::new();
                for actions in states {
                    for successors in actions {
                        let p = 1.0 / successors.len() as f64;
                        builder.add_action(successors.into_iter().map(|t| (t, p)));
                    }
                    builder.end_state();
                }
                builder.build().unwrap()
            })
        })
    }

    proptest! {
        #[test]
        fn mecs_are_the_maximal_end_components_by_brute_force(m in arbitrary_mdp()) {
            let n = m.num_states();
            let ecs: Vec<u32> = (1u32..1 << n).filter(|&set| is_end_component(&m, set)).collect();
            let mut maximal: Vec<u32> = ecs
                .iter()
                .copied()
                .filter(|&a| !ecs.iter().any(|&b| b != a && b & a == a))
                .collect();
            maximal.sort_by_key(|set| set.trailing_zeros());
            let found: Vec<u32> = maximal_end_components(&m, &vec![true; n])
                .iter()
                .map(|c| c.states.iter().map(|&s| 1u32 << s).sum())
                .collect();
            prop_assert_eq!(found, maximal);
        }
    }
}
