//! HOA v1 input and output: the example automata in `tests/data/ltl/examples`,
//! round trips through the writer, and malformed inputs.

use posg_fsc::automaton::Edge;
use posg_fsc::automaton::{
    Acceptance, EmersonLeiAutomaton, HoaError, Letter, minimise, parse_hoa, read_hoa_dra,
    to_state_based_rabin, write_hoa,
};
use proptest::prelude::*;

/// The text of an example file from `tests/data/ltl/examples`.
fn example(name: &str) -> String {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ltl/examples/");
    std::fs::read_to_string(format!("{dir}{name}")).expect("example file present")
}

/// A lasso word `prefix cycle^omega` and whether it should be accepted.
type Case = (&'static [Letter], &'static [Letter], bool);

/// Checks `cases` on the automaton in `text`, on its state-based Rabin
/// conversion, on the minimised conversion and on the written and re-read
/// minimised conversion.
fn check_language(text: &str, cases: &[Case]) {
    let aut = parse_hoa(text).expect("example parses");
    let dra = to_state_based_rabin(&aut).expect("example converts");
    let small = minimise(&dra);
    let reread = read_hoa_dra(&write_hoa(&small, Some("reread"))).expect("output re-reads");
    for &(prefix, cycle, expected) in cases {
        let word = format!("{prefix:?} {cycle:?}^omega");
        assert_eq!(aut.accepts_lasso(prefix, cycle), expected, "HOA, {word}");
        assert_eq!(dra.accepts_lasso(prefix, cycle), expected, "Rabin, {word}");
        assert_eq!(
            small.accepts_lasso(prefix, cycle),
            expected,
            "minimised, {word}"
        );
        assert_eq!(
            reread.accepts_lasso(prefix, cycle),
            expected,
            "re-read, {word}"
        );
    }
}

const A: Letter = 1;
const B: Letter = 2;
const AB: Letter = 3;
const NONE: Letter = 0;

#[test]
fn fg_stable_accepts_eventually_always_s() {
    let text = example("fg_stable.dra.hoa");
    check_language(
        &text,
        &[
            (&[], &[1], true),
            (&[0, 0, 1, 0], &[1], true),
            (&[], &[1, 0], false),
            (&[], &[0], false),
            (&[1, 1], &[1, 1, 0], false),
        ],
    );
    let aut = parse_hoa(&text).expect("parses");
    assert_eq!(aut.propositions(), ["s"]);
    let dra = to_state_based_rabin(&aut).expect("converts");
    assert_eq!(minimise(&dra).num_states(), 3, "initial, L and K states");
}

/// Lasso words separating `GF a & GF b` from its neighbours.
const GFA_AND_GFB: &[Case] = &[
    (&[], &[AB], true),
    (&[], &[A, B], true),
    (&[NONE, B], &[A, NONE, NONE, B], true),
    (&[], &[A], false),
    (&[], &[B], false),
    (&[AB, AB], &[NONE], false),
    (&[], &[A, NONE, A], false),
];

#[test]
fn gfa_and_gfb_generalised_rabin() {
    check_language(&example("gfa_and_gfb.dgra.hoa"), GFA_AND_GFB);
}

#[test]
fn gfa_and_gfb_rabin() {
    check_language(&example("gfa_and_gfb.dra.hoa"), GFA_AND_GFB);
}

#[test]
fn gfa_and_g_not_b() {
    check_language(
        &example("gfa_and_gnotb.dra.hoa"),
        &[
            (&[], &[A], true),
            (&[NONE], &[A, NONE], true),
            (&[], &[NONE], false),
            (&[B], &[A], false),
            (&[], &[A, AB], false),
            (&[A, A, A], &[A, B, A], false),
        ],
    );
}

#[test]
fn spot_parity_f_ga_or_gfb() {
    check_language(
        &example("spot_fga_or_gfb.dpa.hoa"),
        &[
            (&[], &[A], true),
            (&[NONE, B], &[A], true),
            (&[], &[B], true),
            (&[], &[NONE, NONE, B], true),
            (&[], &[AB, NONE], true),
            (&[], &[NONE], false),
            (&[], &[A, NONE], false),
            (&[B, B], &[A, A, NONE], false),
        ],
    );
}

#[test]
fn written_rabin_automaton_has_the_documented_form() {
    let dra = minimise(&read_hoa_dra(&example("fg_stable.dra.hoa")).expect("reads"));
    let text = write_hoa(&dra, Some("FG \"s\""));
    let expected_lines = [
        "HOA: v1",
        "name: \"FG \\\"s\\\"\"",
        "States: 3",
        "Start: 0",
        "AP: 1 \"s\"",
        "acc-name: Rabin 1",
        "Acceptance: 2 (Fin(0)&Inf(1))",
        "properties: trans-labels explicit-labels state-acc deterministic complete",
        "--BODY--",
    ];
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[..expected_lines.len()], expected_lines, "{text}");
    assert_eq!(lines.last(), Some(&"--END--"));
    assert!(text.contains("[0] ") && text.contains("[!0] "), "{text}");
}

#[test]
fn written_labels_merge_letters_by_target() {
    let text = example("gfa_and_gnotb.dra.hoa");
    let written = write_hoa(&minimise(&read_hoa_dra(&text).expect("reads")), None);
    assert!(!written.contains("\nname:"));
    assert!(
        written.contains("[t] "),
        "the sink takes every letter: {written}"
    );
    assert!(written.contains("[1] "), "b leads to the sink: {written}");
}

#[test]
fn automaton_without_pairs_is_written_with_false_acceptance() {
    let text = "HOA: v1 States: 1 Start: 0 AP: 0 Acceptance: 0 f --BODY-- State: 0 [t] 0 --END--";
    let dra = read_hoa_dra(text).expect("reads");
    assert!(dra.pairs().is_empty());
    let written = write_hoa(&dra, None);
    assert!(
        written.contains("acc-name: Rabin 0\nAcceptance: 0 f\n"),
        "{written}"
    );
    assert!(written.contains("State: 0\n[t] 0\n"), "{written}");
    let reread = read_hoa_dra(&written).expect("re-reads");
    assert!(!reread.accepts_lasso(&[], &[0]));
}

#[test]
fn syntax_features_are_understood() {
    let text = r#"HOA: v1 /* a /* nested */ comment */
name: "with \"escapes\" \\ inside"
tool: "hand" "1.0"
Start: 0
AP: 2 "s" "x y"
Alias: @s 0
Alias: @both @s & 1
acc-name: Rabin 1
Acceptance: 2 (Fin(0) & Inf(1)) | (f & Inf(!0))
properties: trans-labels explicit-labels trans-acc
spot-extra-item: 1 "two" three @four
--BODY--
State: 0 "start" {1}
[!@s] 1
[@s & !1 | @both] 0
State: 1
0 {0}
1
0
0 {0}
--END--
"#;
    let aut = parse_hoa(text).expect("parses");
    assert_eq!(aut.num_states(), 2);
    assert_eq!(aut.propositions(), ["s", "x y"]);
    assert_eq!(
        aut.edge(0, 1),
        Edge {
            target: 0,
            marks: 2
        }
    );
    assert_eq!(
        aut.edge(0, 3),
        Edge {
            target: 0,
            marks: 2
        }
    );
    assert_eq!(
        aut.edge(0, 2),
        Edge {
            target: 1,
            marks: 2
        }
    );
    assert_eq!(
        aut.edge(1, 0),
        Edge {
            target: 0,
            marks: 1
        }
    );
    assert_eq!(
        aut.edge(1, 1),
        Edge {
            target: 1,
            marks: 0
        }
    );
    assert_eq!(
        aut.edge(1, 3),
        Edge {
            target: 0,
            marks: 1
        }
    );
    assert_eq!(
        aut.acceptance(),
        &Acceptance::Or(vec![
            Acceptance::And(vec![
                Acceptance::Fin {
                    mark: 0,
                    complemented: false
                },
                Acceptance::Inf {
                    mark: 1,
                    complemented: false
                },
            ]),
            Acceptance::And(vec![
                Acceptance::Constant(false),
                Acceptance::Inf {
                    mark: 0,
                    complemented: true
                },
            ]),
        ])
    );
}

#[test]
fn state_labels_apply_to_all_edges() {
    let text =
        "HOA: v1 Start: 0 AP: 1 \"s\" Acceptance: 1 Inf(0)\n--BODY--\nState: [t] 0 {0}\n0\n--END--";
    let aut = parse_hoa(text).expect("parses");
    assert!(aut.accepts_lasso(&[], &[0, 1]));
}

/// The error for `text`, as its message.
fn error_of(text: &str) -> String {
    match parse_hoa(text) {
        Ok(_) => panic!("accepted malformed input:\n{text}"),
        Err(error) => error.to_string(),
    }
}

/// A one-state automaton over `s` with `body` as its state's edges and
/// `header` as extra header items.
fn one_state(header: &str, body: &str) -> String {
    format!(
        "HOA: v1\nStates: 1\nStart: 0\nAP: 1 \"s\"\n{header}Acceptance: 2 Fin(0) & Inf(1)\n\
         --BODY--\nState: 0\n{body}\n--END--\n"
    )
}

#[test]
fn malformed_inputs_are_reported_with_their_position() {
    let cases: Vec<(String, &str)> = vec![
        (
            String::new(),
            "line 1, column 1: expected `HOA: v1`, found end of input",
        ),
        (
            "HOA: v2".into(),
            "line 1, column 6: expected version `v1` or `v1.1`, found `v2`",
        ),
        (
            "HOA: v1\nAP: 0\nAcceptance: 0 t\n--BODY--\nState: 0 [t] 0\n--END--".into(),
            "line 4, column 1: missing `Start:` header item: exactly one initial state is required",
        ),
        (
            one_state("", "[0] 0 {1}\n[t] 0"),
            "line 9, column 1: nondeterministic: state 0 has a second edge on letter s",
        ),
        (
            one_state("", "[0] 0 {1}"),
            "line 7, column 1: incomplete automaton: state 0 has no edge on letter !s",
        ),
        (
            one_state("", "[0] 0\n[!1] 0"),
            "line 9, column 3: AP index 1 out of range: `AP:` declares 1 propositions",
        ),
        (
            one_state("", "[@x] 0\n[!0] 0"),
            "line 8, column 2: unknown alias `@x`",
        ),
        (
            one_state("", "[t] 0 /* never /* closed */"),
            "line 8, column 7: unterminated comment: expected `*/`",
        ),
        (
            "HOA: v1\nStart: 0\nAcceptance: 2 Fin(0) & | Inf(1)\n--BODY--\n--END--".into(),
            "line 3, column 24: expected an acceptance condition: `t`, `f`, `Fin(...)`, \
             `Inf(...)` or `(`, found `|`",
        ),
        (
            "HOA: v1\nStart: 0\nAcceptance: 2 Fin(2)\n--BODY--\n--END--".into(),
            "line 3, column 19: acceptance set 2 out of range: `Acceptance: 2` declares sets 0..2",
        ),
        (
            one_state("", "[t] 0 {0 2}"),
            "line 8, column 10: acceptance set 2 out of range: `Acceptance: 2` declares sets 0..2",
        ),
        (
            "HOA: v1\nStart: 0 & 1\nAcceptance: 0 t\n--BODY--\n--END--".into(),
            "line 2, column 10: conjunctions of initial states (alternation) are not supported",
        ),
        (
            "HOA: v1\nStart: 0\nStart: 1\nAcceptance: 0 t\n--BODY--\n--END--".into(),
            "line 3, column 1: second `Start:` item: exactly one initial state is supported",
        ),
        (
            one_state("Tool: \"x\"\n", "[t] 0"),
            "line 5, column 1: unsupported header item `Tool:` (items starting with an \
             upper-case letter may change the automaton's meaning)",
        ),
        (
            one_state("name: \"open\n", "[t] 0"),
            "line 5, column 7: unterminated string: expected `\"`",
        ),
        (
            one_state("", "[t] 3"),
            "line 8, column 5: state 3 out of range: `States: 1`",
        ),
        (
            one_state("", "0\n0\n0"),
            "line 10, column 1: more implicit edges than the 2 letters",
        ),
        (
            one_state("", "[0] 0\n0"),
            "line 9, column 1: a state's edges must be all labelled or all unlabelled",
        ),
        (
            one_state("", "[t] 0 & 0"),
            "line 8, column 7: conjunctions of target states (alternation) are not supported",
        ),
        (
            one_state("Alias: @a @b\nAlias: @b 0\n", "[t] 0"),
            "line 5, column 11: unknown alias `@b`",
        ),
        (
            one_state("", "[t] 0").replace("--END--", "--ABORT--"),
            "line 9, column 1: the producer aborted the automaton (`--ABORT--`)",
        ),
        (
            format!("{}State: 1 [t] 0", one_state("", "[t] 0")),
            "line 10, column 1: expected end of input after `--END--`, found header item `State:`",
        ),
        (
            "HOA: v1\nStates: 2\nStart: 0\nAcceptance: 0 t\n--BODY--\nState: 0 [t] 1\n--END--"
                .into(),
            "line 7, column 1: incomplete automaton: state 1 has no edge on letter t (there are \
             no propositions)",
        ),
        (
            one_state("", &format!("[{}0] 0", "!".repeat(100_000))),
            "line 8, column 66: label nested too deeply",
        ),
        (
            "HOA: v1\nAP: 17".into(),
            "line 2, column 5: 17 atomic propositions; at most 16 are supported",
        ),
        (
            "HOA: v1\nAP: 2 \"a\"\n".into(),
            "line 3, column 1: expected 2 quoted proposition names after `AP: 2`, found end of input",
        ),
        (
            "HOA: v1\nStates: 99999999999999999999".into(),
            "line 2, column 9: number 99999999999999999999 is too large",
        ),
    ];
    for (text, message) in &cases {
        assert_eq!(error_of(text), *message, "input:\n{text}");
    }
}

#[test]
fn errors_carry_line_and_column_fields() {
    let text = one_state("", "[0] 0 {1}\n[t] 0");
    match parse_hoa(&text) {
        Err(HoaError::Syntax { line, column, .. }) => assert_eq!((line, column), (9, 1)),
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

/// A random deterministic complete automaton with up to 4 states, 2
/// propositions, 3 marks and a random acceptance formula.
fn automaton() -> impl Strategy<Value = EmersonLeiAutomaton> {
    let atom = prop_oneof![
        any::<bool>().prop_map(Acceptance::Constant),
        (0u32..3, any::<bool>())
            .prop_map(|(mark, complemented)| Acceptance::Fin { mark, complemented }),
        (0u32..3, any::<bool>())
            .prop_map(|(mark, complemented)| Acceptance::Inf { mark, complemented }),
    ];
    let acceptance = atom.prop_recursive(3, 12, 3, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 1..4).prop_map(Acceptance::And),
            prop::collection::vec(inner, 1..4).prop_map(Acceptance::Or),
        ]
    });
    (1usize..5, 0usize..3).prop_flat_map(move |(states, props)| {
        (
            0..states,
            prop::collection::vec((0..states as u32, 0u64..8), states << props),
            acceptance.clone(),
        )
            .prop_map(move |(initial, edges, acceptance)| {
                let edges = edges
                    .into_iter()
                    .map(|(target, marks)| Edge { target, marks })
                    .collect();
                let names = (0..props).map(|i| format!("p {i}")).collect();
                EmersonLeiAutomaton::new(names, states, initial, edges, 3, acceptance)
                    .expect("well-formed random automaton")
            })
    })
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(300)
    })]

    #[test]
    fn write_then_read_preserves_the_language(
        aut in automaton(),
        words in prop::collection::vec(
            (prop::collection::vec(0u32..4, 0..7), prop::collection::vec(0u32..4, 1..7)),
            1..24,
        ),
    ) {
        let dra = to_state_based_rabin(&aut).expect("converts");
        let text = write_hoa(&dra, Some("random"));
        let reread = read_hoa_dra(&text).expect("written automaton re-reads");
        let as_written = parse_hoa(&text).expect("written automaton parses");
        let small = minimise(&reread);
        let mask = (1 << aut.propositions().len()) - 1;
        for (prefix, cycle) in &words {
            let u: Vec<Letter> = prefix.iter().map(|a| a & mask).collect();
            let v: Vec<Letter> = cycle.iter().map(|a| a & mask).collect();
            let expected = aut.accepts_lasso(&u, &v);
            prop_assert_eq!(as_written.accepts_lasso(&u, &v), expected);
            prop_assert_eq!(reread.accepts_lasso(&u, &v), expected);
            prop_assert_eq!(small.accepts_lasso(&u, &v), expected);
        }
    }

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
        let _ = parse_hoa(&text);
    }

    #[test]
    fn damaged_examples_never_panic(
        file in 0usize..5,
        position in 0usize..400,
        replacement in "[ -~]{0,3}",
    ) {
        let names = [
            "fg_stable.dra.hoa",
            "gfa_and_gfb.dgra.hoa",
            "gfa_and_gfb.dra.hoa",
            "gfa_and_gnotb.dra.hoa",
            "spot_fga_or_gfb.dpa.hoa",
        ];
        let text = example(names[file]);
        let cut = position.min(text.len());
        let damaged = format!("{}{replacement}{}", &text[..cut], &text[(cut + 1).min(text.len())..]);
        let _ = read_hoa_dra(&damaged);
    }
}

/// `G F a` as Spot 2.12 writes it with `ltl2tgba -D -G -H1.1 'GF a'`, plus
/// the other tool-specific items Spot may write.
const SPOT_V1_1: &str = r#"HOA: v1.1
name: "G F a"
States: 1
Start: 0
AP: 1 "a"
acc-name: Buchi
Acceptance: 1 Inf(0)
properties: trans-labels explicit-labels trans-acc complete
properties: deterministic stutter-invariant !weak
controllable-AP: 0
spot.highlight.edges: 1 1 2 2
spot.highlight.states: 0 3
spot.state-player: 0
Alias: @a.1 0
--BODY--
State: 0
[@a.1] 0 {0}
[!0] 0
--END--
"#;

#[test]
fn hoa_v1_1_with_dotted_and_tool_specific_items_is_read() {
    let aut = parse_hoa(SPOT_V1_1).expect("HOA v1.1 is read");
    assert!(aut.accepts_lasso(&[], &[0, 1]), "a infinitely often");
    assert!(!aut.accepts_lasso(&[1], &[0]), "a finitely often");
    let dra = read_hoa_dra(SPOT_V1_1).expect("and converted");
    let v1 = read_hoa_dra(&SPOT_V1_1.replace("HOA: v1.1", "HOA: v1")).unwrap();
    assert_eq!(dra, v1);
}

#[test]
fn hoa_items_that_may_change_the_meaning_are_still_errors() {
    let cases = [
        (
            SPOT_V1_1.replace("HOA: v1.1", "HOA: v1.2"),
            "line 1, column 6: expected version `v1` or `v1.1`, found `v1.2`",
        ),
        (
            SPOT_V1_1.replace("spot.state-player: 0", "Spot.state-player: 0"),
            "line 13, column 1: unsupported header item `Spot.state-player:`",
        ),
        (
            SPOT_V1_1.replace("Start: 0", "Start: 0 & 0"),
            "conjunctions of initial states (alternation) are not supported",
        ),
    ];
    for (text, expected) in cases {
        let error = error_of(&text);
        assert!(
            error.contains(expected),
            "expected `{expected}` in `{error}`"
        );
    }
}
