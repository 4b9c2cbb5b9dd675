//! `*.posg.json` reading and writing (formats.md section 1): valid files,
//! wildcard precedence, one test per kind of malformed file, round trips and
//! a no-panic fuzz.

use posg_fsc::game::file::{from_json_str, read, to_json_string, write};
use posg_fsc::game::{AdversaryAction, DefenderAction, ModelError, Posg};
use proptest::prelude::*;
use serde_json::{Value, json};

const FILE: &str = "t.posg.json";

/// A two-state game: `a` can move to `b`, `b` is absorbing; the defender sees
/// noisily, the adversary fully.
fn base() -> Value {
    json!({
        "posg": 1,
        "name": "small",
        "states": ["a", "b"],
        "initial": {"a": 1.0},
        "labels": {"b": ["goal"]},
        "defender": {
            "actions": ["go", "stay"],
            "observations": ["x", "y"],
            "observe": {"a": {"x": 0.9, "y": 0.1}, "b": {"y": 1.0}}
        },
        "adversary": {"actions": ["A", "NA"], "observe": "full"},
        "transitions": [
            {"state": "a", "defender": "go", "adversary": "*", "next": {"b": 0.7, "a": 0.3}},
            {"state": "a", "defender": "stay", "adversary": "*", "next": {"a": 1.0}},
            {"state": "b", "defender": "*", "adversary": "*", "next": {"b": 1.0}}
        ]
    })
}

fn load(v: &Value) -> Result<Posg, ModelError> {
    from_json_str(&v.to_string(), FILE)
}

fn error_of(v: &Value) -> ModelError {
    load(v).expect_err("the file should be rejected")
}

fn error_of_text(text: &str) -> ModelError {
    from_json_str(text, FILE).expect_err("the file should be rejected")
}

fn assert_error(e: &ModelError, path: &str, message_part: &str) {
    assert_eq!(e.path, format!("{FILE}: {path}"), "{e}");
    assert!(e.message.contains(message_part), "{e}");
}

#[test]
fn base_game_is_read_with_wildcards_expanded() {
    let g = load(&base()).unwrap();
    assert_eq!(g.name(), Some("small"));
    assert_eq!(g.num_states(), 2);
    assert!(g.has_adversary());
    assert_eq!(
        g.transition(0, DefenderAction(0), AdversaryAction(1)),
        &[(0, 0.3), (1, 0.7)]
    );
    assert_eq!(
        g.transition(1, DefenderAction(1), AdversaryAction(0)),
        &[(1, 1.0)]
    );
    assert_eq!(g.propositions(), ["goal"]);
    assert_eq!(g.label_names(1).collect::<Vec<_>>(), ["goal"]);
    assert_eq!(g.adversary().observations(), ["a", "b"]);
    assert!(g.adversary().observes_fully());
    assert_eq!(g.adversary().observation_distribution(1), &[(1, 1.0)]);
    assert_eq!(g.defender().observation_distribution(1), &[(1, 1.0)]);
}

#[test]
fn most_specific_transition_wins() {
    let mut v = base();
    let t = v["transitions"].as_array_mut().unwrap();
    t.push(json!({"state": "b", "defender": "go", "adversary": "*", "next": {"a": 1.0}}));
    t.push(json!({"state": "b", "defender": "go", "adversary": "A", "next": {"a": 0.5, "b": 0.5}}));
    t.push(
        json!({"state": "b", "defender": "*", "adversary": "NA", "next": {"b": 0.25, "a": 0.75}}),
    );
    // (b, go, NA) is matched by (b, go, *) and (b, *, NA): ambiguous.
    let e = error_of(&v);
    assert_error(
        &e,
        "transitions",
        "transitions[3] and transitions[5] both match",
    );
    assert!(
        e.message
            .contains("(state `b`, defender `go`, adversary `NA`)"),
        "{e}"
    );
    let t = v["transitions"].as_array_mut().unwrap();
    t.push(json!({"state": "b", "defender": "go", "adversary": "NA", "next": {"a": 1.0}}));
    let g = load(&v).unwrap();
    let (go, stay, a, na) = (0, 1, 0, 1);
    assert_eq!(
        g.transition(1, DefenderAction(go), AdversaryAction(a)),
        &[(0, 0.5), (1, 0.5)]
    );
    assert_eq!(
        g.transition(1, DefenderAction(go), AdversaryAction(na)),
        &[(0, 1.0)]
    );
    assert_eq!(
        g.transition(1, DefenderAction(stay), AdversaryAction(na)),
        &[(0, 0.75), (1, 0.25)]
    );
    assert_eq!(
        g.transition(1, DefenderAction(stay), AdversaryAction(a)),
        &[(1, 1.0)]
    );
}

#[test]
fn zero_entries_are_dropped_and_near_one_sums_renormalised() {
    let mut v = base();
    v["transitions"][0]["next"] = json!({"b": 0.6000004, "a": 0.4, "c": 0.0});
    v["states"] = json!(["a", "b", "c"]);
    v["defender"]["observe"]["c"] = json!({"x": 1.0});
    v["transitions"]
        .as_array_mut()
        .unwrap()
        .push(json!({"state": "c", "defender": "*", "adversary": "*", "next": {"c": 1.0}}));
    let g = load(&v).unwrap();
    let row = g.transition(0, DefenderAction(0), AdversaryAction(0));
    assert_eq!(row.len(), 2);
    assert!((row[0].1 + row[1].1 - 1.0).abs() < 1e-15);
}

#[test]
fn pomdp_adversary_field_may_be_omitted_star_or_underscore() {
    let mut v = base();
    v.as_object_mut().unwrap().remove("adversary");
    v["transitions"][0]
        .as_object_mut()
        .unwrap()
        .remove("adversary");
    v["transitions"][1]["adversary"] = json!("_");
    let g = load(&v).unwrap();
    assert!(!g.has_adversary());
    assert_eq!(g.adversary().actions(), ["_"]);
    assert_eq!(g.adversary().observations(), ["_"]);
    assert_eq!(
        g.transition(0, DefenderAction(0), AdversaryAction(0)),
        &[(0, 0.3), (1, 0.7)]
    );
    let text = to_json_string(&g);
    assert!(!text.contains("adversary"), "{text}");
    assert_eq!(from_json_str(&text, FILE).unwrap(), g);
}

#[test]
fn round_trip_through_text_and_disk() {
    let g = load(&base()).unwrap();
    let text = to_json_string(&g);
    assert!(text.contains("\"observe\": \"full\""), "{text}");
    assert_eq!(from_json_str(&text, FILE).unwrap(), g);
    let path =
        std::env::temp_dir().join(format!("posg-fsc-files-{}.posg.json", std::process::id()));
    write(&path, &g).unwrap();
    assert_eq!(read(&path).unwrap(), g);
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn missing_file_is_an_error_naming_it() {
    let e = read(std::path::Path::new("/nonexistent/x.posg.json")).unwrap_err();
    assert_eq!(e.path, "/nonexistent/x.posg.json");
    assert!(e.message.contains("cannot read"), "{e}");
}

#[test]
fn a_file_that_is_not_utf8_is_an_error_naming_it() {
    let path =
        std::env::temp_dir().join(format!("posg-fsc-latin1-{}.posg.json", std::process::id()));
    std::fs::write(&path, b"{\"posg\": 1, \"name\": \"caf\xe9\"}").unwrap();
    let e = read(&path).unwrap_err();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(e.path, path.display().to_string());
    assert_eq!(
        e.message,
        "cannot read the file: stream did not contain valid UTF-8"
    );
}

#[test]
fn shipped_example_files_are_valid() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/valid");
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.to_string_lossy().ends_with(".posg.json") {
            read(&path).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

/// Each `tests/data/malformed/NAME.posg.json` comes with `NAME.expected`:
/// the JSON path of the error on the first line, a part of its message on the second.
#[test]
fn malformed_files_in_data_dir_give_their_expected_error() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/malformed");
    let mut checked = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.display().to_string();
        let Some(stem) = name.strip_suffix(".posg.json") else {
            continue;
        };
        let expected = std::fs::read_to_string(format!("{stem}.expected")).unwrap();
        let (json_path, message) = expected.trim_end().split_once('\n').unwrap();
        let e = read(&path).expect_err(&name);
        assert_eq!(e.path, format!("{name}: {json_path}"));
        assert!(e.message.contains(message), "{e}");
        checked += 1;
    }
    assert!(checked >= 3);
}

mod malformed {
    use super::*;

    #[test]
    fn unknown_top_level_field() {
        let mut v = base();
        v["nmae"] = json!("typo");
        assert_error(&error_of(&v), "nmae", "unknown field `nmae`");
    }

    #[test]
    fn unknown_nested_field() {
        let mut v = base();
        v["transitions"][2]["probability"] = json!(1.0);
        assert_error(
            &error_of(&v),
            "transitions[2].probability",
            "unknown field `probability`",
        );
        let mut v = base();
        v["defender"]["observatons"] = json!([]);
        assert_error(
            &error_of(&v),
            "defender.observatons",
            "unknown field `observatons`",
        );
    }

    #[test]
    fn duplicate_key_in_distribution() {
        let text = base()
            .to_string()
            .replace(r#""b":0.7"#, r#""b":0.35,"b":0.35"#);
        assert!(text.contains(r#""b":0.35,"b":0.35"#));
        assert_error(
            &error_of_text(&text),
            "transitions[0].next.b",
            "duplicate key",
        );
    }

    #[test]
    fn duplicate_key_in_a_large_object() {
        // Objects beyond 16 members are checked by a set, smaller ones by
        // comparison: a repeat is found at every position in both regimes.
        for members in [3, 16, 17, 40] {
            for repeat_of in [0, members / 2, members - 1] {
                let mut v = base();
                let states: Vec<String> = (0..members).map(|i| format!("c{i}")).collect();
                v["states"] = json!(states);
                let entries: Vec<String> = states
                    .iter()
                    .map(|s| format!(r#""{s}":0"#))
                    .chain([format!(r#""c{repeat_of}":1"#)])
                    .collect();
                let text = v.to_string().replacen(
                    r#""initial":{"a":1.0}"#,
                    &format!(r#""initial":{{{}}}"#, entries.join(",")),
                    1,
                );
                assert!(text.contains(r#""c0":0"#));
                assert_error(
                    &error_of_text(&text),
                    &format!("initial.c{repeat_of}"),
                    "duplicate key",
                );
            }
        }
    }

    #[test]
    fn duplicate_key_in_struct() {
        let text = base()
            .to_string()
            .replacen(r#""posg":1"#, r#""posg":1,"posg":1"#, 1);
        let e = error_of_text(&text);
        assert!(e.message.contains("duplicate field `posg`"), "{e}");
    }

    #[test]
    fn bad_version() {
        let mut v = base();
        v["posg"] = json!(2);
        assert_error(
            &error_of(&v),
            "posg",
            "unsupported format version 2 (expected 1)",
        );
    }

    #[test]
    fn unknown_state_in_next() {
        let mut v = base();
        v["transitions"][1]["next"] = json!({"a": 0.5, "s9": 0.5});
        assert_error(
            &error_of(&v),
            "transitions[1].next.s9",
            "unknown state `s9`",
        );
    }

    #[test]
    fn sum_below_one() {
        let mut v = base();
        v["transitions"][0]["next"] = json!({"a": 0.2, "b": 0.7});
        let (state, defender) = (
            &v["transitions"][0]["state"],
            &v["transitions"][0]["defender"],
        );
        let adversary = match &v["transitions"][0]["adversary"] {
            Value::String(a) => format!(", {a}"),
            _ => String::new(),
        };
        // Issue 59: the message names the distribution, not only its path.
        let whose = format!(
            "sum to 0.9, not 1 (tolerance 1e-6), for T(. | {}, {}{adversary})",
            state.as_str().unwrap(),
            defender.as_str().unwrap()
        );
        assert_error(&error_of(&v), "transitions[0].next", &whose);
    }

    #[test]
    fn negative_probability() {
        let mut v = base();
        v["initial"] = json!({"a": 1.1, "b": -0.1});
        assert_error(
            &error_of(&v),
            "initial.a",
            "probability 1.1 is not in [0, 1]",
        );
        v["initial"] = json!({"a": 1.0, "b": -0.1});
        assert_error(
            &error_of(&v),
            "initial.b",
            "probability -0.1 is not in [0, 1]",
        );
    }

    #[test]
    fn probability_as_string() {
        let mut v = base();
        v["defender"]["observe"]["a"]["x"] = json!("NaN");
        assert_error(
            &error_of(&v),
            "defender.observe.a.x",
            "invalid type: string \"NaN\"",
        );
    }

    #[test]
    fn uncovered_triple() {
        let mut v = base();
        v["transitions"][1]["adversary"] = json!("A");
        assert_error(
            &error_of(&v),
            "transitions",
            "no entry covers (state `a`, defender `stay`, adversary `NA`)",
        );
    }

    #[test]
    fn two_identical_entries_are_ambiguous() {
        let mut v = base();
        let again = v["transitions"][2].clone();
        v["transitions"].as_array_mut().unwrap().push(again);
        assert_error(
            &error_of(&v),
            "transitions",
            "transitions[2] and transitions[3] both match",
        );
    }

    #[test]
    fn missing_observe_state() {
        let mut v = base();
        v["defender"]["observe"]
            .as_object_mut()
            .unwrap()
            .remove("b");
        assert_error(
            &error_of(&v),
            "defender.observe",
            "state `b` has no observation distribution",
        );
    }

    #[test]
    fn full_observe_with_wrong_observations() {
        let mut v = base();
        v["adversary"]["observations"] = json!(["a", "c"]);
        assert_error(&error_of(&v), "adversary.observations", "`b` is missing");
    }

    #[test]
    fn observe_string_other_than_full() {
        let mut v = base();
        v["adversary"]["observe"] = json!("partial");
        assert_error(
            &error_of(&v),
            "adversary.observe",
            "expected \"full\" or an object",
        );
    }

    #[test]
    fn partial_observe_needs_observations() {
        let mut v = base();
        v["defender"]
            .as_object_mut()
            .unwrap()
            .remove("observations");
        assert_error(&error_of(&v), "defender", "`observations` is required");
    }

    #[test]
    fn missing_adversary_field_with_adversary() {
        let mut v = base();
        v["transitions"][2]
            .as_object_mut()
            .unwrap()
            .remove("adversary");
        assert_error(&error_of(&v), "transitions[2]", "`adversary` is required");
    }

    #[test]
    fn named_adversary_action_in_pomdp() {
        let mut v = base();
        v.as_object_mut().unwrap().remove("adversary");
        v["transitions"][0]["adversary"] = json!("A");
        assert_error(
            &error_of(&v),
            "transitions[0].adversary",
            "must be omitted, \"*\" or \"_\"",
        );
    }

    #[test]
    fn unknown_action() {
        let mut v = base();
        v["transitions"][1]["defender"] = json!("jump");
        assert_error(
            &error_of(&v),
            "transitions[1].defender",
            "unknown action `jump`",
        );
    }

    #[test]
    fn bad_proposition_name() {
        let mut v = base();
        v["labels"]["b"] = json!(["Goal"]);
        assert_error(
            &error_of(&v),
            "labels.b[0]",
            "`Goal` is not a valid proposition",
        );
    }

    #[test]
    fn bad_state_name() {
        let mut v = base();
        v["states"] = json!(["a", "b c"]);
        assert_error(
            &error_of(&v),
            "states[1]",
            "`b c` is not a valid state name",
        );
    }

    #[test]
    fn duplicate_state_names() {
        let mut v = base();
        v["states"] = json!(["a", "b", "a"]);
        assert_error(
            &error_of(&v),
            "states[2]",
            "state `a` already appears at states[0]",
        );
    }

    #[test]
    fn duplicate_action_names() {
        let mut v = base();
        v["defender"]["actions"] = json!(["go", "go"]);
        assert_error(
            &error_of(&v),
            "defender.actions[1]",
            "action `go` already appears",
        );
    }

    #[test]
    fn missing_required_field() {
        let mut v = base();
        v.as_object_mut().unwrap().remove("initial");
        let e = error_of(&v);
        assert_eq!(e.path, FILE);
        assert!(e.message.contains("missing field `initial`"), "{e}");
    }

    #[test]
    fn syntax_error() {
        let e = error_of_text(r#"{"posg": 1, "states": ["a",]}"#);
        assert!(e.path.starts_with(FILE), "{e}");
        assert!(e.message.contains("line 1"), "{e}");
    }

    #[test]
    fn trailing_text() {
        let text = format!("{} x", base());
        let e = error_of_text(&text);
        assert_eq!(e.path, FILE);
        assert!(e.message.contains("trailing characters"), "{e}");
    }
}

/// Equal games, except that probabilities may differ in the last bits:
/// serde_json without its `float_roundtrip` feature may parse a number one
/// ulp away from the value that was written.
fn assert_same_up_to_rounding(a: &Posg, b: &Posg) {
    let close = |x: &[(usize, f64)], y: &[(usize, f64)]| {
        x.len() == y.len()
            && x.iter()
                .zip(y)
                .all(|(p, q)| p.0 == q.0 && (p.1 - q.1).abs() <= 1e-15)
    };
    assert_eq!(
        (a.name(), a.states(), a.propositions()),
        (b.name(), b.states(), b.propositions())
    );
    assert!(close(a.initial(), b.initial()));
    for (pa, pb) in [(a.defender(), b.defender()), (a.adversary(), b.adversary())] {
        assert_eq!(
            (pa.actions(), pa.observations(), pa.observes_fully()),
            (pb.actions(), pb.observations(), pb.observes_fully())
        );
    }
    for s in 0..a.num_states() {
        assert_eq!(a.label(s), b.label(s));
        assert!(close(
            a.defender().observation_distribution(s),
            b.defender().observation_distribution(s)
        ));
        assert!(close(
            a.adversary().observation_distribution(s),
            b.adversary().observation_distribution(s)
        ));
        for u in 0..a.defender().num_actions() {
            for v in 0..a.adversary().num_actions() {
                assert!(close(
                    a.transition(s, DefenderAction(u), AdversaryAction(v)),
                    b.transition(s, DefenderAction(u), AdversaryAction(v))
                ));
            }
        }
    }
}

/// Changes one byte of a valid file.
fn mutate(text: &str, at: usize, byte: u8) -> String {
    let mut bytes = text.as_bytes().to_vec();
    let i = at % bytes.len();
    bytes[i] = byte;
    String::from_utf8_lossy(&bytes).into_owned()
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(400)
    })]

    #[test]
    fn random_bytes_never_panic(text in "[\\[\\]{}\",:0-9a-z.*_ -]{0,200}") {
        let _ = from_json_str(&text, FILE);
    }

    #[test]
    fn mutated_valid_files_never_panic(at in 0usize..10_000, byte in prop::sample::select(b"{}[]\",:01.-*_ax9eE".to_vec())) {
        let text = base().to_string();
        let _ = from_json_str(&mutate(&text, at, byte), FILE);
    }

    #[test]
    fn any_accepted_game_round_trips(at in 0usize..10_000, byte in prop::sample::select(b"0123456789".to_vec())) {
        let text = mutate(&base().to_string(), at, byte);
        if let Ok(g) = from_json_str(&text, FILE) {
            assert_same_up_to_rounding(&from_json_str(&to_json_string(&g), FILE).unwrap(), &g);
        }
    }
}

/// A PRISM or JANI model or a property file given where a game is expected
/// is named for what it is, with how to export the model as DRN; other
/// text keeps the JSON parser's error.
#[test]
fn models_and_queries_of_the_peer_tools_are_named_with_the_way_to_a_game() {
    let error = |text: &str| from_json_str(text, "m.prism").unwrap_err().to_string();
    let prism = error("// a POMDP\n\npomdp\n\nmodule m\n  x : [0..1];\nendmodule\n");
    assert!(
        prism.starts_with("m.prism: this is a PRISM model, not a game"),
        "{prism}"
    );
    assert!(
        prism.contains("--exportbuild") && prism.contains("export_to_drn"),
        "{prism}"
    );
    let jani = error(r#"{"jani-version": 1, "type": "mdp"}"#);
    assert!(jani.contains("this is a JANI model"), "{jani}");
    for query in [
        "Pmax=? [F \"goal\"]",
        "<<0>> Pmin=? [F \"goal\"]",
        "R{\"steps\"}min=? [F \"goal\"]",
    ] {
        let props = error(query);
        assert!(
            props.contains("this is a property file") && props.contains("--props"),
            "{props}"
        );
    }
    assert_eq!(
        error("garbage"),
        "m.prism: expected value at line 1 column 1"
    );
}
