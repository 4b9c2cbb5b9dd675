//! Translation budgets and the constructions for the families that used to
//! blow up (issue 13): conjunctions of `GF`, `FG` and `G (a -> F b)` terms,
//! Boolean `xor`/`<->` chains. Every automaton is checked against the
//! direct semantics on random lasso words (`holds_on_lasso`, no shared code
//! with the translation).

use posg_fsc::automaton::{Dra, Letter};
use posg_fsc::ltl::{self, Formula, TranslateError, TranslationBudget};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn parse(text: &str) -> Formula {
    ltl::parse(text).unwrap_or_else(|e| panic!("{text}: {e}"))
}

/// The automaton agrees with the formula on `count` random lassos.
fn agrees_on_random_lassos(formula: &Formula, dra: &Dra, count: usize, seed: u64) {
    let mut rng = StdRng::seed_from_u64(seed);
    let letters = 1u32 << dra.propositions().len();
    for _ in 0..count {
        let prefix: Vec<Letter> = (0..rng.random_range(0..4))
            .map(|_| rng.random_range(0..letters))
            .collect();
        let cycle: Vec<Letter> = (0..rng.random_range(1..6))
            .map(|_| rng.random_range(0..letters))
            .collect();
        let expected = ltl::holds_on_lasso(formula, dra.propositions(), &prefix, &cycle).unwrap();
        assert_eq!(
            dra.accepts_lasso(&prefix, &cycle),
            expected,
            "{formula} on {prefix:?} ({cycle:?})^w"
        );
    }
}

fn conjunction(term: impl Fn(usize) -> String, n: usize) -> String {
    (0..n).map(term).collect::<Vec<_>>().join(" & ")
}

#[test]
fn conjunctions_of_persistence_and_recurrence_terms_are_small_and_right() {
    let cases = [
        (conjunction(|i| format!("FG p{i}"), 10), 2),
        (conjunction(|i| format!("GF p{i}"), 8), 18),
        (conjunction(|i| format!("G(a{i} -> F b{i})"), 4), 64),
    ];
    for (text, most) in cases {
        let formula = parse(&text);
        let dra = ltl::translate(&formula).unwrap_or_else(|e| panic!("{text}: {e}"));
        assert!(
            dra.num_states() <= most,
            "{text}: {} states",
            dra.num_states()
        );
        agrees_on_random_lassos(&formula, &dra, 300, 7);
    }
}

#[test]
fn boolean_chains_are_evaluated_not_expanded() {
    let parity = (0..16)
        .map(|i| format!("a{i}"))
        .collect::<Vec<_>>()
        .join(" ^ ");
    let equivalence = (0..16)
        .map(|i| format!("a{i}"))
        .collect::<Vec<_>>()
        .join(" <-> ");
    for text in [parity, equivalence] {
        let formula = parse(&text);
        let dra = ltl::translate(&formula).unwrap();
        assert!(dra.num_states() <= 3, "{text}: {}", dra.num_states());
        agrees_on_random_lassos(&formula, &dra, 200, 3);
    }
}

#[test]
fn an_exhausted_budget_names_the_subformula() {
    let formula = parse("G(a -> F b) & GF c");
    let error = ltl::translate_within(&formula, &TranslationBudget { seconds: 0.0 }).unwrap_err();
    assert!(matches!(error, TranslateError::Budget { .. }), "{error}");
    let message = error.to_string();
    assert!(
        message.contains("time budget") && message.contains("translating "),
        "{message}"
    );
    let nested = (0..40).map(|_| "F a").collect::<Vec<_>>().join(" <-> ");
    let error = ltl::translate(&parse(&nested)).unwrap_err();
    assert!(error.to_string().contains("<->"), "{error}");
}
