//! Maximum probability of a Rabin condition on an MDP's states.
//!
//! A run satisfies the pairs `{(L_i, K_i)}` iff for some `i` it visits `L_i`
//! finitely often and `K_i` infinitely often. An end component is
//! *accepting* for pair `i` if it avoids `L_i` and meets `K_i`. Then
//! (Baier and Katoen, Section 10.6)
//!
//! ```text
//! sup_sigma P^sigma(Rabin) = sup_sigma P^sigma(reach U),
//! U = union over i of the MECs of the sub-MDP without L_i that meet K_i,
//! ```
//!
//! because the states a run visits infinitely often form an end component
//! almost surely, and inside an accepting end component a strategy can stay
//! forever and visit `K_i` infinitely often. Memoryless deterministic
//! strategies suffice: [`max_rabin_analysis`] plays an optimal
//! reachability strategy outside `U` and, inside, an *in-component
//! attractor*: in each MEC of pair `i`, actions of the component that lead
//! towards `K_i` by a backward search (any action of the component on `K_i`).
//! A state in several components plays for the first pair's. Along a run
//! the pair index played never increases (a component's actions stay in it,
//! and its states play for its pair or an earlier one), so it is eventually
//! constant, say `i`; from then on the run stays in one MEC of pair `i`
//! (no `L_i`) and, from every state, reaches `K_i` or an earlier pair's
//! state within `|C|` steps with probability bounded away from 0: `K_i` is
//! visited infinitely often almost surely.

use crate::automaton::RabinPair;

use super::reachability::{QualitativeReachability, qualitative_reachability};
use super::{EndComponent, Mdp, MdpError, Reachability, max_reachability, maximal_end_components};
use crate::solver::SolverSettings;

/// A maximal end component that is accepting for one Rabin pair.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AcceptingComponent {
    /// The index `i` of the pair `(L_i, K_i)`.
    pub pair: usize,
    /// A MEC of the sub-MDP without `L_i` that meets `K_i`.
    pub component: EndComponent,
}

/// For each pair `i` in order, the MECs of the sub-MDP on the states outside
/// `L_i` (`pair.fin`) that contain a state of `K_i` (`pair.inf`). The pairs
/// are indexed by MDP states.
pub fn accepting_end_components(
    mdp: &Mdp,
    pairs: &[RabinPair],
) -> Result<Vec<AcceptingComponent>, MdpError> {
    let n = mdp.num_states();
    let mut accepting = Vec::new();
    for (i, pair) in pairs.iter().enumerate() {
        if pair.fin.len() != n || pair.inf.len() != n {
            return Err(MdpError::Malformed(format!(
                "Rabin pair {i} does not cover the {n} states"
            )));
        }
        let within: Vec<bool> = pair.fin.iter().map(|&l| !l).collect();
        accepting.extend(
            maximal_end_components(mdp, &within)
                .into_iter()
                .filter(|c| c.states.iter().any(|&s| pair.inf[s]))
                .map(|component| AcceptingComponent { pair: i, component }),
        );
    }
    Ok(accepting)
}

/// `sup_sigma P^sigma_s(Rabin)` for every state, with an optimal memoryless
/// deterministic strategy (see the module documentation), together with the
/// accepting end components ([`accepting_end_components`]) whose union is the
/// reachability target. The values and residual are those of the
/// reachability problem for that union, its linear systems solved by
/// `settings`.
pub fn max_rabin_analysis(
    mdp: &Mdp,
    pairs: &[RabinPair],
    settings: &SolverSettings,
) -> Result<(Reachability, Vec<AcceptingComponent>), MdpError> {
    let accepting = accepting_end_components(mdp, pairs)?;
    let mut result = max_reachability(mdp, &accepting_union(mdp, &accepting), settings)?;
    stay_in_accepting(mdp, pairs, &accepting, &mut result.strategy);
    Ok((result, accepting))
}

/// The qualitative part of [`max_rabin_analysis`] (graph search only, no
/// linear solve): from which states the Rabin condition can be met with
/// positive probability and from which almost surely, with a strategy that
/// wins almost surely from the latter.
pub fn max_rabin_qualitative(
    mdp: &Mdp,
    pairs: &[RabinPair],
) -> Result<(QualitativeReachability, Vec<AcceptingComponent>), MdpError> {
    let accepting = accepting_end_components(mdp, pairs)?;
    let mut result = qualitative_reachability(mdp, &accepting_union(mdp, &accepting))?;
    stay_in_accepting(mdp, pairs, &accepting, &mut result.strategy);
    Ok((result, accepting))
}

/// Whether each state lies in an accepting end component.
pub fn accepting_union(mdp: &Mdp, accepting: &[AcceptingComponent]) -> Vec<bool> {
    let mut target = vec![false; mdp.num_states()];
    for c in accepting {
        for &s in &c.component.states {
            target[s] = true;
        }
    }
    target
}

/// Inside the accepting end components, `strategy` stays in the component
/// and visits its pair's `inf` states ([`stay_and_visit`]).
fn stay_in_accepting(
    mdp: &Mdp,
    pairs: &[RabinPair],
    accepting: &[AcceptingComponent],
    strategy: &mut [usize],
) {
    let mut decided = vec![false; mdp.num_states()];
    let mut position = vec![usize::MAX; mdp.num_states()];
    for c in accepting {
        let inf = &pairs[c.pair].inf;
        stay_and_visit(
            mdp,
            &c.component,
            inf,
            &mut position,
            &mut decided,
            strategy,
        );
    }
}

/// Writes the in-component attractor towards `inf` of `component` into
/// `strategy`, for its states not yet `decided`. `position` is scratch space
/// of one entry per MDP state, `usize::MAX` on entry and on return.
fn stay_and_visit(
    mdp: &Mdp,
    component: &EndComponent,
    inf: &[bool],
    position: &mut [usize],
    decided: &mut [bool],
    strategy: &mut [usize],
) {
    for (i, &s) in component.states.iter().enumerate() {
        position[s] = i;
    }
    let size = component.states.len();
    let mut predecessors: Vec<Vec<(usize, usize)>> = vec![Vec::new(); size];
    for (i, (&s, actions)) in component.states.iter().zip(&component.actions).enumerate() {
        for &a in actions {
            for &(t, _) in mdp.distribution(s, a) {
                predecessors[position[t]].push((i, a));
            }
        }
    }
    let mut found = vec![false; size];
    let mut choice = vec![0; size];
    let mut frontier = Vec::new();
    for (i, &s) in component.states.iter().enumerate() {
        if inf[s] {
            found[i] = true;
            choice[i] = component.actions[i][0];
            frontier.push(i);
        }
    }
    while let Some(j) = frontier.pop() {
        for &(i, a) in &predecessors[j] {
            if !found[i] {
                found[i] = true;
                choice[i] = a;
                frontier.push(i);
            }
        }
    }
    for (i, &s) in component.states.iter().enumerate() {
        position[s] = usize::MAX;
        if !decided[s] {
            decided[s] = true;
            strategy[s] = choice[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::mdp;
    use super::*;

    fn pair(fin: &[usize], inf: &[usize], n: usize) -> RabinPair {
        RabinPair {
            fin: (0..n).map(|s| fin.contains(&s)).collect(),
            inf: (0..n).map(|s| inf.contains(&s)).collect(),
        }
    }

    /// From 0: action 0 enters the cycle 1 -> 2 -> 1 (2 is in K, 1 is not),
    /// action 1 enters 3, which may loop (action 0) or move to 4 (action 1),
    /// an absorbing L state that is also in K.
    fn cycle_or_trap() -> Mdp {
        mdp(&[
            &[&[(1, 0.5), (3, 0.5)], &[(3, 1.0)]],
            &[&[(2, 1.0)], &[(1, 1.0)]],
            &[&[(1, 1.0)]],
            &[&[(3, 1.0)], &[(4, 1.0)]],
            &[&[(4, 1.0)]],
        ])
    }

    #[test]
    fn buchi_inside_a_component_needs_the_right_action() {
        let pairs = [pair(&[4], &[2, 4], 5)];
        let accepting = accepting_end_components(&cycle_or_trap(), &pairs).unwrap();
        let states: Vec<_> = accepting
            .iter()
            .map(|c| c.component.states.clone())
            .collect();
        assert_eq!(states, vec![vec![1, 2]]);
        let result = max_rabin_analysis(&cycle_or_trap(), &pairs, &SolverSettings::default())
            .unwrap()
            .0;
        assert_eq!(result.values, vec![0.5, 1.0, 1.0, 0.0, 0.0]);
        assert_eq!(result.strategy[1], 0, "1 must move on to 2, not idle");
    }

    #[test]
    fn a_second_pair_opens_another_component() {
        let pairs = [pair(&[4], &[2, 4], 5), pair(&[], &[3], 5)];
        let result = max_rabin_analysis(&cycle_or_trap(), &pairs, &SolverSettings::default())
            .unwrap()
            .0;
        assert_eq!(result.values, vec![1.0, 1.0, 1.0, 1.0, 0.0]);
        assert_eq!(result.strategy[3], 0, "3 must stay in K");
    }

    #[test]
    fn pairs_of_the_wrong_size_are_an_error() {
        assert!(accepting_end_components(&cycle_or_trap(), &[pair(&[], &[], 2)]).is_err());
    }
}
