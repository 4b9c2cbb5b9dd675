//! `*.fsc.json` reading and writing (formats.md section 2) and the
//! `uniform:K` shorthand, on the paper's grid.

use posg_fsc::controller::file::{from_json_str, read, resolve, to_json_string, write};
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::grid::{GridSpec, ObservationModel};
use posg_fsc::game::{ModelError, Posg};
use proptest::prelude::*;
use serde_json::{Value, json};

const FILE: &str = "c.fsc.json";

/// The grid with the two-symbol observations, so a complete controller is short.
fn game() -> Posg {
    GridSpec {
        observation: ObservationModel::Blind,
        ..GridSpec::default()
    }
    .build()
    .unwrap()
}

fn base() -> Value {
    json!({
        "fsc": 1,
        "player": "defender",
        "nodes": 2,
        "initial": [1.0, 0.0],
        "rules": [
            {"node": 0, "observation": "correct",
             "choices": [{"next": 0, "action": "R", "p": 0.7, "logit": 0.85},
                         {"next": 1, "action": "D", "p": 0.3}]},
            {"node": 0, "observation": "wrong", "choices": [{"next": 0, "action": "R", "p": 1.0}]},
            {"node": 1, "observation": "correct", "choices": [{"next": 1, "action": "L", "p": 1.0}]},
            {"node": 1, "observation": "wrong",
             "choices": [{"next": 0, "action": "U", "p": 0.5}, {"next": 1, "action": "U", "p": 0.5},
                         {"next": 1, "action": "D", "p": 0.0}]}
        ],
        "default": "error"
    })
}

fn load(v: &Value) -> Result<Fsc, ModelError> {
    from_json_str(&v.to_string(), FILE, &game(), Role::Defender)
}

fn error_of(v: &Value) -> ModelError {
    load(v).expect_err("the file should be rejected")
}

fn assert_error(e: &ModelError, path: &str, message_part: &str) {
    assert_eq!(e.path, format!("{FILE}: {path}"), "{e}");
    assert!(e.message.contains(message_part), "{e}");
}

#[test]
fn base_controller_is_read() {
    let c = load(&base()).unwrap();
    assert_eq!(c.role(), Role::Defender);
    assert_eq!(c.num_nodes(), 2);
    assert_eq!(c.initial(), &[1.0, 0.0]);
    assert_eq!(
        c.choices(0, 0),
        &[
            Choice {
                next: 0,
                action: 0,
                probability: 0.7,
                logit: Some(0.85)
            },
            Choice {
                next: 1,
                action: 3,
                probability: 0.3,
                logit: None
            },
        ]
    );
    assert_eq!(
        c.choices(1, 1).len(),
        2,
        "the zero-probability choice is not in the support"
    );
}

#[test]
fn default_uniform_fills_missing_rules() {
    let mut v = base();
    v["rules"].as_array_mut().unwrap().truncate(1);
    v["default"] = json!("uniform");
    let c = load(&v).unwrap();
    assert_eq!(c.choices(1, 1).len(), 8);
    assert!(c.choices(1, 1).iter().all(|ch| ch.probability == 0.125));
    assert_eq!(c.choices(0, 0).len(), 2);
}

#[test]
fn default_is_error_when_omitted() {
    let mut v = base();
    v.as_object_mut().unwrap().remove("default");
    assert!(load(&v).is_ok());
    v["rules"].as_array_mut().unwrap().pop();
    assert_error(
        &error_of(&v),
        "rules",
        "no rule for node 1, observation `wrong`",
    );
}

#[test]
fn round_trip_keeps_logits() {
    let g = game();
    let c = load(&base()).unwrap();
    let text = to_json_string(&c, &g);
    assert!(text.contains("\"logit\": 0.85"), "{text}");
    assert_eq!(from_json_str(&text, FILE, &g, Role::Defender).unwrap(), c);
    let path = std::env::temp_dir().join(format!("posg-fsc-files-{}.fsc.json", std::process::id()));
    write(&path, &c, &g).unwrap();
    assert_eq!(read(&path, &g, Role::Defender).unwrap(), c);
    assert_eq!(
        resolve(path.to_str().unwrap(), &g, Role::Defender).unwrap(),
        c
    );
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn uniform_controllers_round_trip_for_both_players() {
    let g = GridSpec::default().build().unwrap();
    for role in [Role::Defender, Role::Adversary] {
        let c = resolve("uniform:3", &g, role).unwrap();
        assert_eq!(c.num_nodes(), 3);
        assert_eq!(
            from_json_str(&to_json_string(&c, &g), FILE, &g, role).unwrap(),
            c
        );
    }
}

#[test]
fn resolve_shorthand() {
    let g = game();
    let c = resolve("uniform:2", &g, Role::Adversary).unwrap();
    assert_eq!(c, Fsc::uniform(Role::Adversary, 2, 2, 2));
    for bad in ["uniform:0", "uniform:", "uniform:x", "uniform:-1"] {
        let e = resolve(bad, &g, Role::Defender).unwrap_err();
        assert_eq!(e.path, bad);
        assert!(e.message.contains("K >= 1"), "{e}");
    }
    let e = resolve("/nonexistent/c.fsc.json", &g, Role::Defender).unwrap_err();
    assert_eq!(e.path, "/nonexistent/c.fsc.json");
}

#[test]
fn pomdp_adversary_uniform_1() {
    let text = r#"{"posg": 1, "states": ["a"], "initial": {"a": 1},
        "defender": {"actions": ["u"], "observe": "full"},
        "transitions": [{"state": "a", "defender": "*", "next": {"a": 1}}]}"#;
    let g = posg_fsc::game::file::from_json_str(text, "p.posg.json").unwrap();
    let c = resolve("uniform:1", &g, Role::Adversary).unwrap();
    assert_eq!(
        c.choices(0, 0),
        &[Choice {
            next: 0,
            action: 0,
            probability: 1.0,
            logit: None
        }]
    );
    let back = from_json_str(&to_json_string(&c, &g), FILE, &g, Role::Adversary).unwrap();
    assert_eq!(back, c);
}

mod malformed {
    use super::*;

    #[test]
    fn wrong_player() {
        let e = from_json_str(&base().to_string(), FILE, &game(), Role::Adversary).unwrap_err();
        assert_error(
            &e,
            "player",
            "the file's player is `defender`, but a controller for the `adversary` is needed",
        );
    }

    #[test]
    fn unknown_player() {
        let mut v = base();
        v["player"] = json!("attacker");
        assert_error(&error_of(&v), "player", "unknown variant `attacker`");
    }

    #[test]
    fn missing_rule_with_default_error() {
        let mut v = base();
        v["rules"].as_array_mut().unwrap().remove(1);
        assert_error(
            &error_of(&v),
            "rules",
            "no rule for node 0, observation `wrong` (and \"default\" is \"error\")",
        );
    }

    #[test]
    fn duplicate_choice() {
        let mut v = base();
        v["rules"][1]["choices"] =
            json!([{"next": 0, "action": "R", "p": 0.5}, {"next": 0, "action": "R", "p": 0.5}]);
        assert_error(
            &error_of(&v),
            "rules[1].choices[1]",
            "(next 0, action `R`) is already listed at rules[1].choices[0]",
        );
    }

    #[test]
    fn duplicate_rule() {
        let mut v = base();
        let again = v["rules"][2].clone();
        v["rules"].as_array_mut().unwrap().push(again);
        assert_error(
            &error_of(&v),
            "rules[4]",
            "a second rule for node 1, observation `correct`",
        );
    }

    #[test]
    fn unknown_action() {
        let mut v = base();
        v["rules"][2]["choices"][0]["action"] = json!("jump");
        assert_error(
            &error_of(&v),
            "rules[2].choices[0].action",
            "unknown action `jump`",
        );
    }

    #[test]
    fn unknown_observation() {
        let mut v = base();
        v["rules"][2]["observation"] = json!("s1");
        assert_error(
            &error_of(&v),
            "rules[2].observation",
            "unknown observation `s1`",
        );
    }

    /// Issue 59: a controller written for another game says so, with the
    /// names that do not fit beside the player's own; one wrong name is a
    /// typo and gets the plain error.
    #[test]
    fn a_controller_of_another_game_names_what_does_not_fit() {
        let mut v = base();
        v["rules"][0]["observation"] = json!("s7");
        v["rules"][1]["observation"] = json!("s8");
        v["rules"][2]["choices"][0]["action"] = json!("jump");
        let error = error_of(&v);
        assert_error(&error, "rules[0].observation", "unknown observation `s7`");
        assert!(
            error.message.contains(
                "the controller does not fit this game (written for another?): 2 observations \
                 not the defender's (`s7`, `s8`); its observations are `correct`, `wrong`; 1 \
                 action not the defender's (`jump`); its actions are "
            ),
            "{error}"
        );
        let mut v = base();
        v["rules"][2]["observation"] = json!("s1");
        assert!(!error_of(&v).message.contains("does not fit"));
    }

    #[test]
    fn node_out_of_range() {
        let mut v = base();
        v["rules"][3]["node"] = json!(2);
        assert_error(
            &error_of(&v),
            "rules[3].node",
            "node 2 is out of range (the controller has 2 nodes)",
        );
        let mut v = base();
        v["rules"][3]["choices"][0]["next"] = json!(5);
        assert_error(
            &error_of(&v),
            "rules[3].choices[0].next",
            "node 5 is out of range",
        );
    }

    #[test]
    fn negative_node_is_a_type_error() {
        let mut v = base();
        v["rules"][0]["node"] = json!(-1);
        assert_error(
            &error_of(&v),
            "rules[0].node",
            "invalid value: integer `-1`",
        );
    }

    #[test]
    fn initial_length_mismatch() {
        let mut v = base();
        v["initial"] = json!([1.0]);
        assert_error(&error_of(&v), "initial", "1 entries for 2 nodes");
    }

    #[test]
    fn initial_not_a_distribution() {
        let mut v = base();
        v["initial"] = json!([0.5, 0.4]);
        assert_error(&error_of(&v), "initial", "sum to 0.9");
        v["initial"] = json!([1.5, -0.5]);
        assert_error(
            &error_of(&v),
            "initial[0]",
            "probability 1.5 is not in [0, 1]",
        );
    }

    #[test]
    fn choices_not_a_distribution() {
        let mut v = base();
        v["rules"][0]["choices"][1]["p"] = json!(0.2);
        assert_error(&error_of(&v), "rules[0].choices", "sum to 0.9");
        let mut v = base();
        v["rules"][1]["choices"] = json!([]);
        assert_error(&error_of(&v), "rules[1].choices", "sum to 0");
    }

    #[test]
    fn zero_nodes() {
        let mut v = base();
        v["nodes"] = json!(0);
        v["initial"] = json!([]);
        v["rules"] = json!([]);
        assert_error(&error_of(&v), "nodes", "at least one node");
    }

    #[test]
    fn unknown_fields() {
        let mut v = base();
        v["size"] = json!(2);
        assert_error(&error_of(&v), "size", "unknown field `size`");
        let mut v = base();
        v["rules"][0]["choices"][0]["prob"] = json!(0.7);
        assert_error(
            &error_of(&v),
            "rules[0].choices[0].prob",
            "unknown field `prob`",
        );
    }

    #[test]
    fn duplicate_key() {
        let text = base()
            .to_string()
            .replacen(r#""nodes":2"#, r#""nodes":2,"nodes":2"#, 1);
        let e = from_json_str(&text, FILE, &game(), Role::Defender).unwrap_err();
        assert!(e.message.contains("duplicate field `nodes`"), "{e}");
    }

    #[test]
    fn bad_version_and_default() {
        let mut v = base();
        v["fsc"] = json!(0);
        assert_error(&error_of(&v), "fsc", "unsupported format version 0");
        let mut v = base();
        v["default"] = json!("random");
        assert_error(&error_of(&v), "default", "unknown variant `random`");
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(300)
    })]

    #[test]
    fn mutated_controller_files_never_panic(at in 0usize..10_000, byte in prop::sample::select(b"{}[]\",:01.-_Rx9".to_vec())) {
        let mut bytes = base().to_string().into_bytes();
        let i = at % bytes.len();
        bytes[i] = byte;
        let _ = from_json_str(&String::from_utf8_lossy(&bytes), FILE, &game(), Role::Defender);
    }
}
