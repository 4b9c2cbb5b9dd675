//! Certificates constructed directly for a fixed support: the constructive
//! side of the completeness argument of [`super`], used to confirm a
//! support with the certificate formula by propagation alone.
//!
//! On the product MDP of the game, an automaton for phi and the defender
//! (the adversary choosing), for one Rabin pair `(L, K)`, levels are
//! assigned from 0 upwards. Level `l` gets the greatest set `S` of
//! unassigned states such that, for every `m` in `S` and every action `v`
//! (with "lower" meaning "assigned a level below `l`"):
//!
//! * some successor is lower, or every successor is lower or in `S`;
//! * almost-sure claim: every successor is in the region `R`;
//! * if `m` is in `L`: some successor is lower;
//! * if `m` is not in `K`: some successor is lower, or one in `S` has a
//!   lower rank, ranks inside `S` being the attractor layers towards `K`.
//!
//! The union of two such sets is one, so the greatest exists; it is found
//! by removing violating states until none is left. If any certificate
//! gives a state level `l`, this construction gives it level `l` or lower
//! (induction on `l`: the certificate's states of level `l` not yet
//! assigned form such a set), so the levels found cover every region a
//! certificate can cover. For the almost-sure claim the region `R` starts
//! as every state and shrinks to the states that got a level until it is
//! stable; a certificate's region, inside `R` at the start, stays inside
//! by the same induction.

use crate::mdp::{Mdp, Predecessors};

/// A certificate region with its levels and ranks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Witness {
    /// The level of each state in the region (`None` outside).
    pub level: Vec<Option<usize>>,
    /// The rank of each state in the region (0 on `K` and outside).
    pub rank: Vec<usize>,
}

/// The greatest certificate region of `mdp` for the pair with `fin` (`L`)
/// and `inf` (`K`) per state; `closed` asks for the almost-sure kind.
pub fn construct(mdp: &Mdp, fin: &[bool], inf: &[bool], closed: bool) -> Witness {
    let mut region = vec![true; mdp.num_states()];
    let predecessors = mdp.predecessors();
    loop {
        let witness = assign_levels(
            (mdp, &predecessors),
            fin,
            inf,
            closed.then_some(&region[..]),
        );
        let assigned: Vec<bool> = witness.level.iter().map(Option::is_some).collect();
        if !closed || assigned == region {
            return witness;
        }
        region = assigned;
    }
}

/// The levels and ranks, with every successor required in `region` when
/// one is given.
fn assign_levels(
    (mdp, predecessors): (&Mdp, &Predecessors),
    fin: &[bool],
    inf: &[bool],
    region: Option<&[bool]>,
) -> Witness {
    let n = mdp.num_states();
    let mut level: Vec<Option<usize>> = vec![None; n];
    let mut rank = vec![0; n];
    let mut current = 0;
    loop {
        let mut in_set: Vec<bool> = level.iter().map(Option::is_none).collect();
        loop {
            let mut changed = false;
            for m in 0..n {
                if in_set[m] && !levels_hold(mdp, m, &level, &in_set, fin[m], region) {
                    in_set[m] = false;
                    changed = true;
                }
            }
            changed |= rank_within((mdp, predecessors), &level, &mut in_set, inf, &mut rank);
            if !changed {
                break;
            }
        }
        if !in_set.iter().any(|&s| s) {
            return Witness { level, rank };
        }
        for m in (0..n).filter(|&m| in_set[m]) {
            level[m] = Some(current);
        }
        current += 1;
    }
}

/// The level conditions of `m` against the assigned states (`level`), the
/// candidate set and, when given, the region every successor must be in.
fn levels_hold(
    mdp: &Mdp,
    m: usize,
    level: &[Option<usize>],
    in_set: &[bool],
    fin: bool,
    region: Option<&[bool]>,
) -> bool {
    (0..mdp.num_actions(m)).all(|v| {
        let successors = mdp.distribution(m, v);
        if region.is_some_and(|r| successors.iter().any(|&(t, _)| !r[t])) {
            return false;
        }
        let lower = successors.iter().any(|&(t, _)| level[t].is_some());
        let stays = successors
            .iter()
            .all(|&(t, _)| level[t].is_some() || in_set[t]);
        if fin { lower } else { lower || stays }
    })
}

/// Ranks the candidate set by attractor layers towards `K` (rank 0),
/// where a lower successor also counts; removes the states without a rank
/// and returns whether any was removed. An action is met once a successor
/// has a level or a rank; a candidate is ranked one layer after the layer
/// that meets its last action, found through `predecessors` (linear in the
/// MDP's size, where a scan of every state per layer was quadratic: minutes
/// on PAYNT's drone-2-8-1).
fn rank_within(
    (mdp, predecessors): (&Mdp, &Predecessors),
    level: &[Option<usize>],
    in_set: &mut [bool],
    inf: &[bool],
    rank: &mut [usize],
) -> bool {
    let n = in_set.len();
    let mut ranked: Vec<bool> = (0..n).map(|m| in_set[m] && inf[m]).collect();
    for m in (0..n).filter(|&m| ranked[m]) {
        rank[m] = 0;
    }
    let mut met = vec![false; mdp.num_state_actions()];
    let mut unmet = vec![0usize; n];
    let mut layer_states = Vec::new();
    for m in (0..n).filter(|&m| in_set[m] && !ranked[m]) {
        for (v, action) in mdp.global_actions(m).enumerate() {
            met[action] = mdp
                .distribution(m, v)
                .iter()
                .any(|&(t, _)| level[t].is_some() || (in_set[t] && ranked[t]));
            unmet[m] += usize::from(!met[action]);
        }
        if unmet[m] == 0 {
            layer_states.push(m);
        }
    }
    let mut layer = 1;
    while !layer_states.is_empty() {
        for &m in &layer_states {
            ranked[m] = true;
            rank[m] = layer;
        }
        let mut next = Vec::new();
        for &t in &layer_states {
            for &(m, v) in predecessors.of(t) {
                let action = mdp.global_actions(m).start + v;
                if in_set[m] && !ranked[m] && !met[action] {
                    met[action] = true;
                    unmet[m] -= 1;
                    if unmet[m] == 0 {
                        next.push(m);
                    }
                }
            }
        }
        layer_states = next;
        layer += 1;
    }
    let mut removed = false;
    for m in 0..n {
        if in_set[m] && !ranked[m] {
            in_set[m] = false;
            removed = true;
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mdp::MdpBuilder;

    fn mdp(actions: &[&[&[usize]]]) -> Mdp {
        let mut builder = MdpBuilder::new();
        for state in actions {
            for &successors in *state {
                let p = 1.0 / successors.len() as f64;
                builder.add_action(successors.iter().map(|&t| (t, p)));
            }
            builder.end_state();
        }
        builder.build().unwrap()
    }

    /// `FG a` with a choice: state 0 (a, K) may stay (action 0) or visit 1
    /// (!a, L) once and end in 2 (a, K). Every play wins, through at most
    /// one visit to L: 2 gets level 0, and 0 and 1 level 1 (1 has the
    /// lower successor 2).
    #[test]
    fn a_single_visit_to_l_is_allowed() {
        let m = mdp(&[&[&[0], &[1]], &[&[2]], &[&[2]]]);
        let fin = [false, true, false];
        let inf = [true, false, true];
        let witness = construct(&m, &fin, &inf, true);
        assert_eq!(witness.level, vec![Some(1), Some(1), Some(0)]);
    }

    /// The closed kind may lean on higher levels: 1 (L) must move to 0 (a,
    /// K, absorbing) or 2 (L), and 2 may loop or return to 1. Every play
    /// ends in 0 almost surely, so all three get levels: 0, then 1 (its
    /// successor 0 is lower), then 2 (its successor 1 is lower).
    #[test]
    fn closure_may_rely_on_higher_levels() {
        let m = mdp(&[&[&[0]], &[&[0, 2]], &[&[1, 2]]]);
        let witness = construct(&m, &[false, true, true], &[true, false, false], true);
        assert_eq!(witness.level, vec![Some(0), Some(1), Some(2)]);
    }

    /// A cycle 0 <-> 1 through L (1): the adversary revisits L forever.
    #[test]
    fn an_l_state_on_a_forced_cycle_has_no_level() {
        let m = mdp(&[&[&[1]], &[&[0]]]);
        let witness = construct(&m, &[false, true], &[true, false], false);
        assert_eq!(witness.level, vec![None, None]);
    }

    /// Büchi: in 0 (K) the adversary may stay forever (action 0) or enter
    /// the lottery 1, which ends in 2 (K, absorbing) or 3 (no K, absorbing).
    /// The minimum probability from 0 is 1/2: positive, though the adversary
    /// can keep the play away from the sure region {2} forever; not 1.
    #[test]
    fn an_end_component_the_adversary_may_leave_counts_for_positive() {
        let m = mdp(&[&[&[0], &[1]], &[&[2, 3]], &[&[2]], &[&[3]]]);
        let inf = [true, false, true, false];
        let positive = construct(&m, &[false; 4], &inf, false);
        assert_eq!(positive.level, vec![Some(1), Some(1), Some(0), None]);
        let almost_sure = construct(&m, &[false; 4], &inf, true);
        assert_eq!(almost_sure.level, vec![None, None, Some(0), None]);
    }
}
