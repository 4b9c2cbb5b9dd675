//! A bounded, seeded mutation fuzzer over the inputs (issue 13): games,
//! controllers, HOA automata and LTL formulas, mutated byte- and
//! token-wise from valid seeds. Every mutant must give a value or an error
//! that names the input (file name, JSON path, line or column), never a
//! panic and never an aborted allocation (the budgets of
//! `posg_fsc::limits` stop those before they happen). A few seconds in all.

use std::panic::{AssertUnwindSafe, catch_unwind};

use posg_fsc::controller::Role;
use posg_fsc::ltl::TranslationBudget;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

const GRID: &str = include_str!("data/valid/grid-3x2.posg.json");
const HOA: &[&str] = &[
    include_str!("data/ltl/examples/fg_stable.dra.hoa"),
    include_str!("data/ltl/examples/gfa_and_gfb.dgra.hoa"),
    include_str!("data/ltl/examples/spot_fga_or_gfb.dpa.hoa"),
];
const FORMULAS: &[&str] = &[
    "GF goal & G !unsafe",
    "G(a -> F b) & G(c -> F d)",
    "(F a) U (b W c)",
    "!(a xor b xor c) <-> X X d",
    "FG a | GF b R c",
];

/// Tokens that stress the readers: huge, negative, non-finite and
/// fractional numbers, wildcards, brackets, operators.
const TOKENS: &[&str] = &[
    "1e308",
    "-1",
    "0",
    "4294967296",
    "18446744073709551616",
    "NaN",
    "\"*\"",
    "\"\"",
    "null",
    "[]",
    "{}",
    ",",
    ":",
    "0.5",
    "1e-300",
    "999999999",
    "(",
    ")",
    "U",
    "X",
    "!",
    "^",
    "<->",
    "\"s0\"",
    "\"uniform\"",
    "Acceptance:",
    "States: 1000000",
    "AP: 16",
    "--BODY--",
];

/// One random edit of `text`: delete, duplicate or swap a span, or insert
/// or substitute a token.
fn mutate(text: &str, rng: &mut StdRng) -> String {
    let chars: Vec<char> = text.chars().collect();
    let n = chars.len().max(1);
    let at = rng.random_range(0..n);
    let span = rng.random_range(1..=8.min(n));
    let end = (at + span).min(chars.len());
    let token: Vec<char> = TOKENS[rng.random_range(0..TOKENS.len())].chars().collect();
    let mut out: Vec<char> = Vec::with_capacity(chars.len() + 32);
    match rng.random_range(0..5) {
        0 => {
            out.extend(&chars[..at.min(chars.len())]);
            out.extend(&chars[end..]);
        }
        1 => {
            out.extend(&chars[..end]);
            out.extend(&chars[at.min(chars.len())..end]);
            out.extend(&chars[end..]);
        }
        2 => {
            out.extend(&chars[..at.min(chars.len())]);
            out.extend(&token);
            out.extend(&chars[at.min(chars.len())..]);
        }
        3 => {
            out.extend(&chars[..at.min(chars.len())]);
            out.extend(&token);
            out.extend(&chars[end..]);
        }
        _ => {
            let other = rng.random_range(0..n);
            out.extend(&chars);
            let last = out.len().saturating_sub(1);
            if !out.is_empty() {
                out.swap(at.min(last), other.min(last));
            }
        }
    }
    out.into_iter().collect()
}

/// Mutants of `seed` with 1 to 3 edits each.
fn mutants(seed: &str, count: usize, stream: u64) -> Vec<String> {
    let mut rng = StdRng::seed_from_u64(0x5eed_0000 + stream);
    (0..count)
        .map(|_| {
            let edits = rng.random_range(1..=3);
            (0..edits).fold(seed.to_string(), |text, _| mutate(&text, &mut rng))
        })
        .collect()
}

/// Runs `check` on every mutant, failing on a panic with the mutant shown.
fn without_panics(inputs: &[String], check: impl Fn(&str)) {
    for input in inputs {
        if catch_unwind(AssertUnwindSafe(|| check(input))).is_err() {
            panic!("panic on the input:\n{input}");
        }
    }
}

#[test]
fn mutated_games_are_read_or_refused_with_the_file_and_path() {
    without_panics(&mutants(GRID, 1500, 1), |text| {
        if let Err(error) = posg_fsc::game::file::from_json_str(text, "fuzz.posg.json") {
            assert!(error.to_string().contains("fuzz.posg.json"), "{error}");
        }
    });
}

#[test]
fn mutated_controllers_are_read_or_refused_with_the_file_and_path() {
    let game = posg_fsc::game::file::from_json_str(GRID, "grid.posg.json").unwrap();
    let valid = posg_fsc::controller::file::resolve("uniform:2", &game, Role::Defender).unwrap();
    let text = posg_fsc::controller::file::to_json_string(&valid, &game);
    without_panics(&mutants(&text, 1500, 2), |text| {
        let read =
            posg_fsc::controller::file::from_json_str(text, "fuzz.fsc.json", &game, Role::Defender);
        if let Err(error) = read {
            assert!(error.to_string().contains("fuzz.fsc.json"), "{error}");
        }
    });
}

#[test]
fn mutated_automata_are_read_or_refused_with_a_position() {
    for (k, seed) in HOA.iter().enumerate() {
        without_panics(&mutants(seed, 500, 10 + k as u64), |text| {
            if let Err(error) = posg_fsc::automaton::read_hoa_dra(text) {
                let message = error.to_string();
                let located = message.contains("line ")
                    || message.contains("automaton")
                    || message.contains("propositions");
                assert!(located, "{message}");
            }
        });
    }
}

#[test]
fn mutated_formulas_are_translated_or_refused_with_a_column_or_subformula() {
    let budget = TranslationBudget { seconds: 0.5 };
    for (k, seed) in FORMULAS.iter().enumerate() {
        without_panics(
            &mutants(seed, 60, 20 + k as u64),
            |text| match posg_fsc::ltl::parse(text) {
                Err(error) => assert!(error.to_string().contains("column"), "{error}"),
                Ok(formula) => {
                    let _ = posg_fsc::ltl::translate_within(&formula, &budget);
                }
            },
        );
    }
}

#[test]
fn a_very_long_left_nested_chain_neither_overflows_nor_hangs() {
    let chain = vec!["a"; 25_000].join(" ^ ");
    let formula = posg_fsc::ltl::parse(&chain).unwrap();
    let dra = posg_fsc::ltl::translate(&formula).unwrap();
    // An even number of `a`: false, a single rejecting state.
    assert!(!dra.accepts_lasso(&[], &[1]) && !dra.accepts_lasso(&[], &[0]));
    let nested = vec!["F a"; 25_000].join(" ^ ");
    let error = posg_fsc::ltl::translate(&posg_fsc::ltl::parse(&nested).unwrap()).unwrap_err();
    assert!(error.to_string().contains("xor"), "{error}");
    let implications = vec!["a"; 25_000].join(" -> ");
    let error = posg_fsc::ltl::parse(&implications).unwrap_err();
    assert!(error.to_string().contains("column"), "{error}");
}
