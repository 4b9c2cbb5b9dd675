//! From transition-based generalised Rabin acceptance to a state-based Rabin
//! automaton, and minimisation of the result.
//!
//! 1. Marks move onto states: if every state's outgoing transitions carry
//!    the same marks, a state is labelled by them; otherwise states are split
//!    by the marks of their incoming transition (`(q, M)`), which visits the
//!    same marks infinitely often one step later.
//! 2. A disjunct `Fin(L) & Inf(K_1) & ... & Inf(K_m)` with `m >= 2` gets a
//!    counter `c in 0..m` that a transition advances past every `K_c,
//!    K_{c+1}, ...` it lies in; its Rabin pair is `(L, {states entered by a
//!    transition that completed a round})`.
//! 3. States are merged by partition refinement (Moore): two states are
//!    merged iff they agree on membership in every `L_i` and `K_i` and, for
//!    every letter, their successors are merged; this preserves the language.
//!    A transient initial state is then replaced by a state with the same
//!    successors, if there is one (its own labels are seen only once).

use rustc_hash::FxHashMap;

use super::TranslateError;
use super::construct::{Disjunct, Tgr};
use crate::automaton::{Dra, MarkSet, RabinPair};

/// The state-based Rabin automaton equivalent to `tgr`, minimised.
pub(crate) fn to_dra(tgr: &Tgr, propositions: Vec<String>) -> Result<Dra, TranslateError> {
    let mut tgr = tgr.clone();
    prune_disjuncts(&mut tgr);
    let tgr = &tgr;
    let letters = tgr.letters;
    let n = tgr.num_states();
    let uniform = (0..n).all(|q| {
        let out = &tgr.edges[q * letters..(q + 1) * letters];
        out.iter().all(|e| e.marks == out[0].marks)
    });
    let counted: Vec<usize> = (0..tgr.disjuncts.len())
        .filter(|&i| tgr.disjuncts[i].inf.len() >= 2)
        .collect();
    // A state: (original state, its label, one counter per counted disjunct,
    // whether the entering transition completed a round of each counter).
    type State = (u32, MarkSet, Vec<u8>, Vec<bool>);
    let label_of = |q: usize, incoming: MarkSet| {
        if uniform {
            tgr.edges[q * letters].marks
        } else {
            incoming
        }
    };
    let start: State = (
        tgr.initial as u32,
        label_of(tgr.initial, 0),
        vec![0; counted.len()],
        vec![false; counted.len()],
    );
    let mut index: FxHashMap<State, u32> = FxHashMap::default();
    index.insert(start.clone(), 0);
    let mut states = vec![start];
    let mut successors: Vec<u32> = Vec::new();
    let mut next = 0;
    while next < states.len() {
        let (q, _, counters, _) = states[next].clone();
        for letter in 0..letters {
            let edge = tgr.edges[q as usize * letters + letter];
            // Each counter advances past every Inf set the transition lies
            // in, at most one round at a time.
            let (advanced, completed): (Vec<u8>, Vec<bool>) = counted
                .iter()
                .zip(&counters)
                .map(|(&i, &c)| {
                    let inf = &tgr.disjuncts[i].inf;
                    let mut c = c as usize;
                    while c < inf.len() && (edge.marks >> inf[c]) & 1 == 1 {
                        c += 1;
                    }
                    if c == inf.len() {
                        (0, true)
                    } else {
                        (c as u8, false)
                    }
                })
                .unzip();
            let target: State = (
                edge.target,
                label_of(edge.target as usize, edge.marks),
                advanced,
                completed,
            );
            let fresh = states.len() as u32;
            let id = *index.entry(target.clone()).or_insert_with(|| {
                states.push(target);
                fresh
            });
            successors.push(id);
        }
        if states.len() > super::construct::MAX_STATES {
            return Err(TranslateError::TooLarge {
                limit: super::construct::MAX_STATES,
            });
        }
        next += 1;
    }
    let mut pairs: Vec<RabinPair> = tgr
        .disjuncts
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let counter = counted.iter().position(|&j| j == i);
            RabinPair {
                fin: states
                    .iter()
                    .map(|(_, label, ..)| label & d.fin != 0)
                    .collect(),
                inf: states
                    .iter()
                    .map(|(_, label, _, completed)| match (d.inf.first(), counter) {
                        (None, _) => true,
                        (Some(&m), None) => (label >> m) & 1 == 1,
                        (Some(_), Some(c)) => completed[c],
                    })
                    .collect(),
            }
        })
        .map(|mut p| {
            // A run satisfying the pair visits K \ L infinitely often.
            for (k, &l) in p.inf.iter_mut().zip(&p.fin) {
                *k &= !l;
            }
            p
        })
        .filter(|p| p.inf.iter().any(|&k| k))
        .collect();
    pairs.sort_by(|a, b| (&a.fin, &a.inf).cmp(&(&b.fin, &b.inf)));
    pairs.dedup();
    minimise(states.len(), letters, &successors, &pairs, propositions)
}

/// Drops what no run can use: `Fin` of a mark no transition carries is
/// true, `Inf` of such a mark false; a disjunct implied by another one (it
/// asks for more `Fin` and more `Inf` marks) is redundant.
fn prune_disjuncts(tgr: &mut Tgr) {
    let carried: MarkSet = tgr.edges.iter().fold(0, |m, e| m | e.marks);
    let mut disjuncts: Vec<Disjunct> = tgr
        .disjuncts
        .iter()
        .filter(|d| d.inf.iter().all(|&m| (carried >> m) & 1 == 1))
        .map(|d| Disjunct {
            fin: d.fin & carried,
            inf: d.inf.clone(),
        })
        .collect();
    disjuncts.sort();
    disjuncts.dedup();
    let implies = |d: &Disjunct, e: &Disjunct| {
        d.fin & e.fin == e.fin && e.inf.iter().all(|m| d.inf.contains(m))
    };
    tgr.disjuncts = disjuncts
        .iter()
        .filter(|d| !disjuncts.iter().any(|e| e != *d && implies(d, e)))
        .cloned()
        .collect();
}

/// Moore's partition refinement on a state-based Rabin automaton.
fn minimise(
    n: usize,
    letters: usize,
    successors: &[u32],
    pairs: &[RabinPair],
    propositions: Vec<String>,
) -> Result<Dra, TranslateError> {
    let signature =
        |q: usize| -> Vec<bool> { pairs.iter().flat_map(|p| [p.fin[q], p.inf[q]]).collect() };
    let mut block = renumber((0..n).map(signature).collect::<Vec<_>>());
    loop {
        let keys: Vec<Vec<u32>> = (0..n)
            .map(|q| {
                std::iter::once(block[q])
                    .chain((0..letters).map(|a| block[successors[q * letters + a] as usize]))
                    .collect()
            })
            .collect();
        let refined = renumber(keys);
        let count = |b: &[u32]| b.iter().max().map_or(0, |&m| m + 1);
        if count(&refined) == count(&block) {
            break;
        }
        block = refined;
    }
    // Renumber the blocks reachable from the initial one in BFS order.
    let blocks = block.iter().max().map_or(0, |&m| m as usize + 1);
    let mut representative = vec![usize::MAX; blocks];
    for q in (0..n).rev() {
        representative[block[q] as usize] = q;
    }
    let row = |b: u32| -> Vec<u32> {
        let q = representative[b as usize];
        (0..letters)
            .map(|a| block[successors[q * letters + a] as usize])
            .collect()
    };
    // The initial state is visited once if no transition enters its block:
    // then its own acceptance labels do not matter, and any state with the
    // same successors can start the run instead.
    let initial_row = row(block[0]);
    let entered = (0..blocks as u32).any(|b| row(b).contains(&block[0]));
    let start = if entered {
        block[0]
    } else {
        (0..blocks as u32)
            .find(|&b| b != block[0] && row(b) == initial_row)
            .unwrap_or(block[0])
    };
    let mut order = vec![u32::MAX; blocks];
    let mut queue = vec![start];
    order[start as usize] = 0;
    let mut head = 0;
    while head < queue.len() {
        let q = representative[queue[head] as usize];
        for a in 0..letters {
            let b = block[successors[q * letters + a] as usize];
            if order[b as usize] == u32::MAX {
                order[b as usize] = queue.len() as u32;
                queue.push(b);
            }
        }
        head += 1;
    }
    let mut table = Vec::with_capacity(queue.len() * letters);
    for &b in &queue {
        let q = representative[b as usize];
        table.extend(
            (0..letters).map(|a| order[block[successors[q * letters + a] as usize] as usize]),
        );
    }
    let mut quotient: Vec<RabinPair> = pairs
        .iter()
        .map(|p| RabinPair {
            fin: queue
                .iter()
                .map(|&b| p.fin[representative[b as usize]])
                .collect(),
            inf: queue
                .iter()
                .map(|&b| p.inf[representative[b as usize]])
                .collect(),
        })
        .filter(|p| p.inf.iter().any(|&k| k))
        .collect();
    quotient.sort_by(|a, b| (&a.fin, &a.inf).cmp(&(&b.fin, &b.inf)));
    quotient.dedup();
    Ok(Dra::new(propositions, queue.len(), 0, table, quotient)?)
}

/// Numbers the distinct keys `0, 1, ...` in order of first appearance.
fn renumber<K: std::hash::Hash + Eq>(keys: Vec<K>) -> Vec<u32> {
    let mut ids: FxHashMap<K, u32> = FxHashMap::default();
    keys.into_iter()
        .map(|k| {
            let next = ids.len() as u32;
            *ids.entry(k).or_insert(next)
        })
        .collect()
}
