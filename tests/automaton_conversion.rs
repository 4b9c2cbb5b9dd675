//! The conversion of Emerson-Lei automata to state-based Rabin automata and
//! their minimisation (also with a free start) preserve the language, checked on random automata with
//! random acceptance formulas and random lasso words.

use posg_fsc::automaton::Edge;
use posg_fsc::automaton::minimise_with_free_start;
use posg_fsc::automaton::{
    Acceptance, Dra, EmersonLeiAutomaton, Letter, RabinPair, minimise, to_state_based_rabin,
};
use proptest::prelude::*;

/// An acceptance atom or constant over marks `0..4` (mark 4 is never used).
fn atom() -> impl Strategy<Value = Acceptance> {
    prop_oneof![
        any::<bool>().prop_map(Acceptance::Constant),
        (0u32..5, any::<bool>())
            .prop_map(|(mark, complemented)| Acceptance::Fin { mark, complemented }),
        (0u32..5, any::<bool>())
            .prop_map(|(mark, complemented)| Acceptance::Inf { mark, complemented }),
    ]
}

/// A random acceptance formula of depth at most 3.
fn acceptance() -> impl Strategy<Value = Acceptance> {
    atom().prop_recursive(3, 16, 3, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 1..4).prop_map(Acceptance::And),
            prop::collection::vec(inner, 1..4).prop_map(Acceptance::Or),
        ]
    })
}

/// A random deterministic complete automaton with up to 4 states, 2
/// propositions and 4 marks.
fn automaton() -> impl Strategy<Value = EmersonLeiAutomaton> {
    (1usize..5, 0usize..3).prop_flat_map(|(states, props)| {
        let letters = 1usize << props;
        (
            0..states,
            prop::collection::vec((0..states as u32, 0u64..16), states * letters),
            acceptance(),
        )
            .prop_map(move |(initial, edges, acceptance)| {
                let edges = edges
                    .into_iter()
                    .map(|(target, marks)| Edge { target, marks })
                    .collect();
                let names = (0..props).map(|i| format!("p{i}")).collect();
                EmersonLeiAutomaton::new(names, states, initial, edges, 4, acceptance)
                    .expect("well-formed random automaton")
            })
    })
}

/// Random lasso words `u v^omega` with `|u|, |v| <= 6` over 2 propositions
/// (extra bits are masked off per automaton).
fn lassos() -> impl Strategy<Value = Vec<(Vec<Letter>, Vec<Letter>)>> {
    prop::collection::vec(
        (
            prop::collection::vec(0u32..4, 0..7),
            prop::collection::vec(0u32..4, 1..7),
        ),
        1..24,
    )
}

/// `word` with every letter restricted to the automaton's propositions.
fn masked(word: &[Letter], props: usize) -> Vec<Letter> {
    word.iter().map(|a| a & ((1 << props) - 1)).collect()
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(400)
    })]

    #[test]
    fn conversion_and_minimisation_preserve_the_language(aut in automaton(), words in lassos()) {
        let dra = to_state_based_rabin(&aut).expect("conversion succeeds");
        let small = minimise(&dra);
        prop_assert!(small.num_states() <= dra.num_states());
        let smaller = minimise_with_free_start(&dra);
        prop_assert!(smaller.num_states() <= small.num_states());
        let props = aut.propositions().len();
        for (prefix, cycle) in &words {
            let (u, v) = (masked(prefix, props), masked(cycle, props));
            let expected = aut.accepts_lasso(&u, &v);
            prop_assert_eq!(dra.accepts_lasso(&u, &v), expected, "converted, word {:?} {:?}", u, v);
            prop_assert_eq!(small.accepts_lasso(&u, &v), expected, "minimised, word {:?} {:?}", u, v);
            prop_assert_eq!(smaller.accepts_lasso(&u, &v), expected, "free start, word {:?} {:?}", u, v);
        }
    }

    #[test]
    fn minimisation_is_idempotent(aut in automaton()) {
        let once = minimise(&to_state_based_rabin(&aut).expect("conversion succeeds"));
        prop_assert_eq!(minimise(&once), once);
    }
}

/// `GF a & G !b` as a state-based DRA over `a, b` (bit 0 = a, bit 1 = b)
/// with `copies` interchangeable copies of each of its three states: state
/// `3 k + 0` = "no b, last letter without a", `3 k + 1` = "no b, last letter
/// with a" (in `K`), `3 k + 2` = "b seen" (in `L`). Copy `k` moves to copy
/// `k + 1` (mod `copies`) on every letter.
fn gfa_and_g_not_b(copies: usize) -> Dra {
    let n = 3 * copies;
    let mut successors = Vec::new();
    for q in 0..n {
        let next_copy = 3 * ((q / 3 + 1) % copies);
        for letter in 0..4u32 {
            let role = if q % 3 == 2 || letter & 2 != 0 {
                2
            } else if letter & 1 != 0 {
                1
            } else {
                0
            };
            successors.push((next_copy + role) as u32);
        }
    }
    let pair = RabinPair {
        fin: (0..n).map(|q| q % 3 == 2).collect(),
        inf: (0..n).map(|q| q % 3 == 1).collect(),
    };
    Dra::new(vec!["a".into(), "b".into()], n, 0, successors, vec![pair]).expect("valid DRA")
}

#[test]
fn redundant_copies_of_gfa_and_g_not_b_minimise_to_three_states() {
    let big = gfa_and_g_not_b(4);
    assert_eq!(big.num_states(), 12);
    let small = minimise(&big);
    assert_eq!(small.num_states(), 3);
    assert_eq!(small.pairs().len(), 1);
    let (a, b, none) = (1, 2, 0);
    for dra in [&big, &small] {
        assert!(dra.accepts_lasso(&[], &[a]));
        assert!(dra.accepts_lasso(&[none], &[a, none]));
        assert!(!dra.accepts_lasso(&[], &[none]));
        assert!(!dra.accepts_lasso(&[b], &[a]));
        assert!(!dra.accepts_lasso(&[a, a], &[a, a | b]));
    }
}

#[test]
fn constants_give_one_trivial_pair_or_none() {
    let edges = vec![
        Edge {
            target: 0,
            marks: 0
        };
        2
    ];
    let with = |acceptance| {
        EmersonLeiAutomaton::new(vec!["s".into()], 1, 0, edges.clone(), 0, acceptance)
            .expect("valid automaton")
    };
    let always = to_state_based_rabin(&with(Acceptance::Constant(true))).expect("converts");
    assert_eq!(always.pairs().len(), 1);
    assert!(always.pairs()[0].fin.iter().all(|&f| !f));
    assert!(always.pairs()[0].inf.iter().all(|&k| k));
    let never = to_state_based_rabin(&with(Acceptance::Constant(false))).expect("converts");
    assert!(never.pairs().is_empty());
    assert!(!never.accepts_lasso(&[], &[0]));
}

#[test]
fn acceptance_blowing_up_in_normal_form_is_refused() {
    let disjunction = |i: u32| {
        Acceptance::Or(vec![
            Acceptance::Inf {
                mark: 2 * i,
                complemented: false,
            },
            Acceptance::Inf {
                mark: 2 * i + 1,
                complemented: false,
            },
        ])
    };
    let acceptance = Acceptance::And((0..16).map(disjunction).collect());
    let aut = EmersonLeiAutomaton::new(
        vec![],
        1,
        0,
        vec![Edge {
            target: 0,
            marks: 0,
        }],
        32,
        acceptance,
    )
    .expect("valid automaton");
    let error = to_state_based_rabin(&aut).expect_err("2^16 disjuncts");
    assert!(
        error.to_string().contains("disjunctive normal form"),
        "{error}"
    );
}
