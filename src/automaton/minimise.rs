//! Minimisation of state-based Rabin automata by partition refinement.
//!
//! [`minimise`] keeps the reachable part of a [`Dra`], normalises and prunes
//! its Rabin pairs, and merges states that no letter sequence can tell apart
//! (Moore's algorithm). The quotient is bisimilar to the input, so it accepts
//! the same language. It is not in general the smallest Rabin automaton for
//! the language (that problem is NP-hard), only the smallest one with the
//! same pairs up to bisimulation. [`minimise_with_free_start`] goes one step
//! beyond bisimulation: an initial state that no transition enters is
//! replaced by a state with the same successors.

use rustc_hash::FxHashMap;

use super::{Dra, RabinPair};

/// Returns an automaton accepting the same words as `dra`, with:
///
/// * only the states reachable from the initial state;
/// * every pair `(L, K)` replaced by `(L, K \ L)` (a run visiting `K \ L`
///   infinitely often and `L` finitely often is exactly one satisfying the
///   pair), then pairs with an empty `K` dropped (no run satisfies them) and
///   of equal pairs the first kept;
/// * states merged by partition refinement starting from the partition by
///   membership in every `L_i` and `K_i`, until states of one block have, on
///   every letter, successors in one block.
///
/// States are numbered in breadth-first order from the initial state (state
/// `0`), exploring letters in increasing order, and pairs keep their relative
/// order, so the result depends only on the input.
pub fn minimise(dra: &Dra) -> Dra {
    let reachable = bfs_order(
        dra.num_states(),
        dra.initial(),
        |q, a| dra.successor(q, a as u32),
        letters(dra),
    );
    let restricted = restrict(dra, &reachable);
    let blocks = coarsest_blocks(&restricted);
    quotient(&restricted, &blocks)
}

/// [`minimise`], then, if no transition enters the initial state and some
/// other state has the same successor as it on every letter, that state
/// made initial and the result minimised again.
///
/// A run visits an initial state that no transition enters only once, so
/// that state's membership in the `L_i` and `K_i` does not matter, and
/// starting from a state with the same successors accepts the same words.
/// The result accepts the same words as `dra` but, unlike [`minimise`]'s,
/// need not be bisimilar to it.
pub fn minimise_with_free_start(dra: &Dra) -> Dra {
    let small = minimise(dra);
    let letters = letters(&small);
    let n = small.num_states();
    let small = &small;
    let row = |q: usize| (0..letters).map(move |a| small.successor(q, a as u32));
    let start = small.initial();
    let entered = (0..n).any(|q| row(q).any(|t| t == start));
    let twin = (0..n).find(|&q| q != start && row(q).eq(row(start)));
    match twin {
        Some(q) if !entered => {
            let successors = (0..n).flat_map(|p| row(p).map(|t| t as u32)).collect();
            minimise(&rebuild(small, n, q, successors, small.pairs().to_vec()))
        }
        _ => small.clone(),
    }
}

/// `2^|AP|`.
fn letters(dra: &Dra) -> usize {
    1 << dra.propositions().len()
}

/// The states reachable from `initial`, in breadth-first order with letters
/// explored in increasing order.
fn bfs_order(
    num_states: usize,
    initial: usize,
    successor: impl Fn(usize, usize) -> usize,
    letters: usize,
) -> Vec<usize> {
    let mut seen = vec![false; num_states];
    seen[initial] = true;
    let mut order = vec![initial];
    let mut next = 0;
    while next < order.len() {
        let q = order[next];
        for a in 0..letters {
            let t = successor(q, a);
            if !seen[t] {
                seen[t] = true;
                order.push(t);
            }
        }
        next += 1;
    }
    order
}

/// `dra` on the states `order` (renumbered by their position in it), with
/// its pairs normalised and pruned.
fn restrict(dra: &Dra, order: &[usize]) -> Dra {
    let mut renumber = vec![u32::MAX; dra.num_states()];
    for (new, &old) in order.iter().enumerate() {
        renumber[old] = new as u32;
    }
    let renumber = &renumber;
    let successors = order
        .iter()
        .flat_map(|&q| (0..letters(dra)).map(move |a| renumber[dra.successor(q, a as u32)]))
        .collect();
    let mut pairs: Vec<RabinPair> = Vec::new();
    for pair in dra.pairs() {
        let fin: Vec<bool> = order.iter().map(|&q| pair.fin[q]).collect();
        let inf: Vec<bool> = order.iter().map(|&q| pair.inf[q] && !pair.fin[q]).collect();
        let candidate = RabinPair { fin, inf };
        if candidate.inf.contains(&true) && !pairs.contains(&candidate) {
            pairs.push(candidate);
        }
    }
    rebuild(dra, order.len(), 0, successors, pairs)
}

/// Builds a `Dra` over the propositions of `like` from parts that are
/// consistent by construction.
fn rebuild(
    like: &Dra,
    num_states: usize,
    initial: usize,
    successors: Vec<u32>,
    pairs: Vec<RabinPair>,
) -> Dra {
    Dra::new(
        like.propositions().to_vec(),
        num_states,
        initial,
        successors,
        pairs,
    )
    .expect("minimisation keeps every index in range")
}

/// The block of every state in the coarsest partition that refines the
/// membership in all `L_i` and `K_i` and is stable under every letter
/// (Moore's algorithm). Blocks are numbered by their first state.
fn coarsest_blocks(dra: &Dra) -> Vec<u32> {
    let n = dra.num_states();
    let mut blocks = number_by_signature(n, |q| {
        dra.pairs()
            .iter()
            .flat_map(|p| [u32::from(p.fin[q]), u32::from(p.inf[q])])
            .collect()
    });
    let mut count = block_count(&blocks);
    loop {
        let refined = number_by_signature(n, |q| {
            std::iter::once(blocks[q])
                .chain((0..letters(dra)).map(|a| blocks[dra.successor(q, a as u32)]))
                .collect()
        });
        let refined_count = block_count(&refined);
        blocks = refined;
        if refined_count == count {
            return blocks;
        }
        count = refined_count;
    }
}

/// Numbers the states `0..n` by their signature, in order of first
/// appearance.
fn number_by_signature(n: usize, signature: impl Fn(usize) -> Vec<u32>) -> Vec<u32> {
    let mut ids: FxHashMap<Vec<u32>, u32> = FxHashMap::default();
    (0..n)
        .map(|q| {
            let next = ids.len() as u32;
            *ids.entry(signature(q)).or_insert(next)
        })
        .collect()
}

/// The number of blocks of a numbering from [`number_by_signature`].
fn block_count(blocks: &[u32]) -> u32 {
    blocks.iter().max().map_or(0, |&b| b + 1)
}

/// The quotient of `dra` by `blocks`, renumbered in breadth-first order.
fn quotient(dra: &Dra, blocks: &[u32]) -> Dra {
    let count = block_count(blocks) as usize;
    let mut representative = vec![usize::MAX; count];
    for (q, &b) in blocks.iter().enumerate().rev() {
        representative[b as usize] = q;
    }
    let block_successor =
        |b: usize, a: usize| blocks[dra.successor(representative[b], a as u32)] as usize;
    let order = bfs_order(
        count,
        blocks[dra.initial()] as usize,
        block_successor,
        letters(dra),
    );
    let mut renumber = vec![0u32; count];
    for (new, &b) in order.iter().enumerate() {
        renumber[b] = new as u32;
    }
    let renumber = &renumber;
    let block_successor = &block_successor;
    let successors = order
        .iter()
        .flat_map(|&b| (0..letters(dra)).map(move |a| renumber[block_successor(b, a)]))
        .collect();
    let pairs = dra
        .pairs()
        .iter()
        .map(|p| RabinPair {
            fin: order.iter().map(|&b| p.fin[representative[b]]).collect(),
            inf: order.iter().map(|&b| p.inf[representative[b]]).collect(),
        })
        .collect();
    rebuild(dra, count, 0, successors, pairs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(fin: [bool; 4], inf: [bool; 4]) -> RabinPair {
        RabinPair {
            fin: fin.to_vec(),
            inf: inf.to_vec(),
        }
    }

    /// Four states over no propositions: `0 -> 1 -> 1`, and `2 -> 3 -> 2`
    /// unreachable.
    fn chain(pairs: Vec<RabinPair>) -> Dra {
        Dra::new(vec![], 4, 0, vec![1, 1, 3, 2], pairs).expect("valid")
    }

    #[test]
    fn unreachable_states_go() {
        let dra = chain(vec![pair([false; 4], [false, true, false, false])]);
        let small = minimise(&dra);
        assert_eq!(small.num_states(), 2);
        assert_eq!(small.pairs()[0].inf, [false, true]);
    }

    #[test]
    fn unsatisfiable_and_repeated_pairs_go() {
        let k_inside_l = pair([false, true, false, false], [false, true, false, false]);
        let only_unreachable_k = pair([false; 4], [false, false, true, true]);
        let good = pair([false; 4], [false, true, false, false]);
        let dra = chain(vec![k_inside_l, only_unreachable_k, good.clone(), good]);
        let small = minimise(&dra);
        assert_eq!(small.pairs().len(), 1);
        assert!(small.accepts_lasso(&[], &[0]));
    }

    #[test]
    fn an_initial_state_never_entered_is_replaced_by_its_twin() {
        // 0 -> 1 -> 1 with 1 in K and 0 in L: the run visits 0 once.
        let dra = Dra::new(
            vec![],
            2,
            0,
            vec![1, 1],
            vec![RabinPair {
                fin: vec![true, false],
                inf: vec![false, true],
            }],
        )
        .expect("valid");
        assert_eq!(minimise(&dra).num_states(), 2);
        let small = minimise_with_free_start(&dra);
        assert_eq!(small.num_states(), 1);
        assert!(small.accepts_lasso(&[], &[0]));
    }

    #[test]
    fn without_pairs_everything_merges() {
        let small = minimise(&chain(vec![]));
        assert_eq!(small.num_states(), 1);
        assert!(small.pairs().is_empty());
    }
}
