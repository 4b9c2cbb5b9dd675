//! The parser: Spot's precedence and associativity, printing and re-parsing,
//! and error messages with their columns.

use posg_fsc::ltl::{self, Formula};

fn p(text: &str) -> Formula {
    ltl::parse(text).unwrap_or_else(|e| panic!("{text}: {e}"))
}

#[test]
fn precedence_follows_spot() {
    let same = [
        // & binds tighter than xor, which binds tighter than |.
        ("a | b & c", "a | (b & c)"),
        ("a & b | c", "(a & b) | c"),
        ("a xor b | c", "(a xor b) | c"),
        ("a | b ^ c", "a | (b xor c)"),
        ("a xor b & c", "a xor (b & c)"),
        // -> and <-> are loosest and right-associative.
        ("a -> b -> c", "a -> (b -> c)"),
        ("a <-> b -> c", "a <-> (b -> c)"),
        ("a -> b | c", "a -> (b | c)"),
        ("a => b <=> c", "a -> (b <-> c)"),
        // U W R M bind tighter than &, and are right-associative.
        ("a & b U c", "a & (b U c)"),
        ("a U b U c", "a U (b U c)"),
        ("a W b R c M d", "a W (b R (c M d))"),
        // Prefix operators bind tightest.
        ("F a U b", "(F a) U b"),
        ("!a U b", "(!a) U b"),
        ("X a & b", "(X a) & b"),
        ("G F a", "G (F a)"),
        ("GFa", "G (F a)"),
        ("Fp0 -> (!p1 U p0)", "(F p0) -> ((!p1) U p0)"),
        ("[]<> a", "G F a"),
        ("~a /\\ b \\/ c", "(!a & b) | c"),
        ("a && b || c", "(a & b) | c"),
        ("1 U 0", "true U false"),
        ("\"x y\" & b", "\"x y\" & b"),
        // | and & associate to the left (and are flattened); xor to the left.
        ("a | b | c", "a | b | c"),
        ("a xor b xor c", "(a xor b) xor c"),
    ];
    for (text, expected) in same {
        assert_eq!(p(text), p(expected), "{text}");
    }
    assert_eq!(
        p("a & b U c"),
        Formula::And(vec![
            Formula::prop("a"),
            Formula::Until(Box::new(Formula::prop("b")), Box::new(Formula::prop("c")))
        ])
    );
}

#[test]
fn display_parses_back_to_the_same_formula() {
    let texts = [
        "GF goal & G !unsafe",
        "a -> b -> c",
        "(a -> b) -> c",
        "!(a U b) R X (c W \"d e\")",
        "a xor (b <-> c) M true",
        "G((p0 & !p1 & Fp1) -> (!p2 U p1))",
        "\"true\" | \"xor\" | x_1",
    ];
    for text in texts {
        let formula = p(text);
        assert_eq!(
            p(&formula.to_string()),
            formula,
            "{text} printed as {formula}"
        );
    }
}

#[test]
fn propositions_are_sorted_and_unique() {
    assert_eq!(p("b U (a & X b) | \"c\"").propositions(), ["a", "b", "c"]);
    assert!(p("G true").propositions().is_empty());
}

#[test]
fn negate_removes_double_negation() {
    assert_eq!(p("!a").negate(), p("a"));
    assert_eq!(p("a U b").negate(), p("!(a U b)"));
    assert_eq!(p("true").negate(), Formula::False);
}

#[test]
fn malformed_formulas_report_column_and_expectation() {
    let cases = [
        (
            "",
            1,
            "expected a formula (constant, proposition, unary operator or '('), found end of formula",
        ),
        (
            "a &",
            4,
            "expected a formula (constant, proposition, unary operator or '('), found end of formula",
        ),
        (
            "(a | b",
            7,
            "expected ')' or a binary operator, found end of formula",
        ),
        (
            "a b",
            3,
            "expected a binary operator or end of formula, found proposition 'b'",
        ),
        (
            "a)",
            2,
            "expected a binary operator or end of formula, found ')'",
        ),
        (
            "Ab",
            1,
            "unexpected character 'A': expected an operator, a constant or a proposition ([a-z_][a-z0-9_]* or double-quoted)",
        ),
        (
            "a & \"b",
            5,
            "unterminated quoted proposition: expected '\"'",
        ),
        ("\"\" U a", 1, "empty quoted proposition: expected a name"),
        (
            "a U 2",
            5,
            "unexpected number '2': expected '0', '1' or a proposition",
        ),
        (
            "G -> a",
            3,
            "expected a formula (constant, proposition, unary operator or '('), found '->'",
        ),
        (
            "a U U b",
            5,
            "expected a formula (constant, proposition, unary operator or '('), found 'U'",
        ),
        (
            "()",
            2,
            "expected a formula (constant, proposition, unary operator or '('), found ')'",
        ),
        (
            "a # b",
            3,
            "unexpected character '#': expected an operator, a constant or a proposition ([a-z_][a-z0-9_]* or double-quoted)",
        ),
        (
            "F(a xor)",
            8,
            "expected a formula (constant, proposition, unary operator or '('), found ')'",
        ),
    ];
    for (text, column, message) in cases {
        let error = ltl::parse(text).expect_err(text);
        assert_eq!(
            (error.column, error.message.as_str()),
            (column, message),
            "{text}"
        );
        assert_eq!(error.to_string(), format!("column {column}: {message}"));
    }
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let text = format!("{}a", "!".repeat(5000));
    assert!(
        ltl::parse(&text)
            .unwrap_err()
            .message
            .contains("nested deeper")
    );
}

#[test]
fn the_nesting_limit_counts_the_parentheses_it_names() {
    // Fuzzing found "nested deeper than 1000" at 333 parentheses: each
    // parenthesis counted three levels of the parser.
    let nested = |depth: usize| format!("{}a{}", "(".repeat(depth), ")".repeat(depth));
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(move || {
            assert!(ltl::parse(&nested(999)).is_ok());
            let error = ltl::parse(&nested(1001)).unwrap_err();
            assert!(error.message.contains("nested deeper than 1000"), "{error}");
        })
        .unwrap()
        .join()
        .unwrap();
}
