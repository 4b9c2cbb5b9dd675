//! Rewards in the model (issue 60, formats.md sections 1, 6 and 11): DRN
//! state and action rewards of both signs are read with their exact values
//! into named reward models; every action label Storm writes is read (SAYNT's
//! `(init)`, `(n)`), renamed where it is not a name and kept as written; the
//! JSON and binary game formats carry both and give them back unchanged; each
//! bad input is an error naming the file and the line or JSON path.

use std::path::Path;

use posg_fsc::controller::Role;
use posg_fsc::controller::file::{from_json_str as fsc_from_json, to_json_string as fsc_to_json};
use posg_fsc::game::binary::{EXTENDED_VERSION, from_bytes, to_bytes};
use posg_fsc::game::drn::{DrnImport, from_drn_str, read as read_drn};
use posg_fsc::game::file::{from_json_str, read, to_json_string};
use posg_fsc::game::{AdversaryAction, DefenderAction, ModelError, Posg, RewardModel};
use posg_fsc::output::dot::controller_dot;
use serde_json::{Value, json};

/// `tests/data/drn/rewards.drn`: SAYNT-style labels, two reward models.
fn saynt_style() -> DrnImport {
    read_drn(Path::new("tests/data/drn/rewards.drn")).unwrap()
}

fn drn_error(text: &str) -> String {
    from_drn_str(text, "m.drn", None).unwrap_err().to_string()
}

/// `r(s, u)` of a POMDP (the adversary's only action).
fn action_reward(model: &RewardModel, s: usize, u: usize) -> f64 {
    model
        .action_reward(s, DefenderAction(u), AdversaryAction(0))
        .unwrap()
}

#[test]
fn drn_state_and_action_rewards_are_read_with_their_exact_values() {
    let game = saynt_style().game;
    assert_eq!(
        game.reward_model_names().collect::<Vec<_>>(),
        ["reward", "cost"]
    );
    let reward = game.reward_model("reward").unwrap();
    let cost = game.reward_model("cost").unwrap();
    assert!(game.reward_model("steps").is_none());
    assert_eq!(reward.name(), "reward");
    assert_eq!(
        (0..4).map(|s| reward.state_reward(s)).collect::<Vec<_>>(),
        [0.0, -0.04, 0.25, 0.0]
    );
    assert_eq!(
        (0..4).map(|s| cost.state_reward(s)).collect::<Vec<_>>(),
        [0.0, 2.0, -0.25, 0.0]
    );
    // Actions in order of first appearance: `(init)`, `(n)`, `(s)`, `n`.
    let expected_reward = [(0, 0, 0.0), (1, 1, -1.0), (1, 2, 1.0), (2, 1, 0.0)];
    for (s, u, r) in expected_reward
        .into_iter()
        .chain([(2, 2, -0.5), (3, 3, 1e-3)])
    {
        assert_eq!(action_reward(reward, s, u), r, "reward ({s}, {u})");
    }
    let expected_cost = [(0, 0, 1.0 / 3.0), (1, 1, 0.5), (1, 2, 0.0), (3, 3, -7.0)];
    for (s, u, r) in expected_cost {
        assert_eq!(action_reward(cost, s, u), r, "cost ({s}, {u})");
    }
    // A triple the game does not define (`n` is not enabled in s0) has 0.
    assert_eq!(action_reward(cost, 0, 3), 0.0);
    assert_eq!(
        cost.state_rewards().collect::<Vec<_>>(),
        [(1, 2.0), (2, -0.25)]
    );
    assert_eq!(
        cost.action_rewards().collect::<Vec<_>>(),
        [
            (0, DefenderAction(0), AdversaryAction(0), 1.0 / 3.0),
            (1, DefenderAction(1), AdversaryAction(0), 0.5),
            (3, DefenderAction(3), AdversaryAction(0), -7.0)
        ]
    );
}

#[test]
fn saynt_labels_are_read_renamed_and_kept_as_written() {
    let import = saynt_style();
    let defender = import.game.defender();
    assert_eq!(defender.actions(), ["_init_", "_n_", "_s_", "n"]);
    let written: Vec<&str> = (0..4).map(|u| defender.action_label(u).unwrap()).collect();
    assert_eq!(written, ["(init)", "(n)", "(s)", "n"]);
    assert_eq!(
        import.warnings,
        [
            "tests/data/drn/rewards.drn: action labels that are not names ([A-Za-z0-9_.:-]+) are \
          renamed: `(init)` is `_init_`, `(n)` is `_n_`, `(s)` is `_s_` (docs/formats.md \
          section 6); controllers name the actions so"
        ]
    );
    // Observation o1 (s1 and s2) enables `(n)` and `(s)`.
    assert_eq!(defender.enabled_actions(1).collect::<Vec<_>>(), [1, 2]);
}

#[test]
fn labels_that_differ_only_outside_the_name_alphabet_stay_distinct() {
    let text = "@type: MDP\n@nr_states\n1\n@model\nstate 0 init\n\taction (n)\n\t\t0 : 1\n\
                \taction [n]\n\t\t0 : 1\n\taction _n_\n\t\t0 : 1\n\taction __NOLABEL__\n\t\t0 : 1\n";
    let import = from_drn_str(text, "m.drn", None).unwrap();
    let defender = import.game.defender();
    assert_eq!(
        defender.actions(),
        ["_n_.2", "_n_.3", "_n_", "unlabelled_3"]
    );
    let written: Vec<&str> = (0..4).map(|u| defender.action_label(u).unwrap()).collect();
    assert_eq!(written, ["(n)", "[n]", "_n_", "(unlabelled #3)"]);
    assert_eq!(defender.action_labels(), written);
    // Two choices of one state with the same label are still an error.
    let twice = text.replace("[n]", "(n)");
    assert!(
        drn_error(&twice).contains("m.drn: line 8: a second choice labelled `(n)` in this state"),
        "{}",
        drn_error(&twice)
    );
}

#[test]
fn controllers_and_pictures_name_a_renamed_action_by_its_name() {
    let game = saynt_style().game;
    let controller = |action: &str| {
        let text = json!({"fsc": 1, "player": "defender", "nodes": 1, "initial": [1.0],
            "rules": [{"node": 0, "observation": "o1",
                       "choices": [{"next": 0, "action": action, "p": 1.0}]}],
            "default": "uniform"});
        fsc_from_json(&text.to_string(), "c.fsc.json", &game, Role::Defender)
    };
    let fsc = controller("_n_").unwrap();
    let written = fsc_to_json(&fsc, &game);
    assert!(
        written.contains("\"_n_\"") && !written.contains("(n)"),
        "{written}"
    );
    let dot = controller_dot(
        &fsc,
        game.defender().observations(),
        game.defender().actions(),
        "t",
        0.01,
    );
    assert!(dot.contains("o1 / _n_"), "{dot}");
    let error = controller("(n)").unwrap_err().to_string();
    assert!(error.contains("(n)"), "{error}");
}

#[test]
fn turn_based_rewards_belong_to_the_movers_action_against_the_idle_one() {
    let text = "@type: SMG\n@reward_models\nr\n@nr_states\n2\n@nr_choices\n3\n@model\n\
                state 0 <0> [1.5] init\n\taction (a) [-2]\n\t\t1 : 1\n\taction b [3]\n\t\t0 : 1\n\
                state 1 <1> [-1]\n\taction (c) [4]\n\t\t1 : 1\n";
    let game = from_drn_str(text, "m.drn", None).unwrap().game;
    let r = game.reward_model("r").unwrap();
    assert_eq!(game.defender().actions(), ["_a_", "b", "_"]);
    assert_eq!(game.adversary().actions(), ["_c_", "_"]);
    assert_eq!(game.adversary().action_label(0), Some("(c)"));
    assert_eq!(game.adversary().action_label(2), None);
    assert_eq!((r.state_reward(0), r.state_reward(1)), (1.5, -1.0));
    let at = |s, u, v| r.action_reward(s, DefenderAction(u), AdversaryAction(v));
    assert_eq!(
        (at(0, 0, 1), at(0, 1, 1), at(1, 2, 0)),
        (Some(-2.0), Some(3.0), Some(4.0))
    );
    assert_eq!((at(0, 0, 0), at(1, 0, 0)), (Some(0.0), Some(0.0)));
    // An action out of range is no reward, not another triple's.
    assert_eq!((at(0, 3, 0), at(0, 0, 2), at(0, 0, 5)), (None, None, None));
    assert_round_trips(&game);
}

/// A game without a name for reward models: `rew0`, `rew1`; `[]` and a
/// missing annotation are 0 in every model.
#[test]
fn unnamed_reward_models_are_named_as_storm_names_them() {
    let text = "@type: DTMC\n@reward_models\n \n@nr_states\n2\n@model\nstate 0 [1, 2] init\n\
                \taction __NOLABEL__ []\n\t\t1 : 1\nstate 1\n\taction __NOLABEL__ [3, -4]\n\t\t1 : 1\n";
    let game = from_drn_str(text, "m.drn", None).unwrap().game;
    assert_eq!(
        game.reward_model_names().collect::<Vec<_>>(),
        ["rew0", "rew1"]
    );
    let rew1 = game.reward_model("rew1").unwrap();
    assert_eq!((rew1.state_reward(0), rew1.state_reward(1)), (2.0, 0.0));
    assert_eq!(
        (action_reward(rew1, 0, 0), action_reward(rew1, 1, 0)),
        (0.0, -4.0)
    );
    // PRISM's empty annotations everywhere: no reward model at all.
    let prism = "@type: DTMC\n@reward_models\n\n@nr_states\n1\n@model\nstate 0 [] init\n\
                 \taction __NOLABEL__ []\n\t\t0 : 1\n";
    let game = from_drn_str(prism, "m.drn", None).unwrap().game;
    assert!(game.reward_models().is_empty());
}

/// Reads `game` back from its JSON, from its binary form and from the JSON
/// of that; all equal, and the JSON texts identical.
fn assert_round_trips(game: &Posg) {
    let json = to_json_string(game);
    let from_json = from_json_str(&json, "t.posg.json").unwrap();
    assert_eq!(&from_json, game);
    let bytes = to_bytes(&from_json);
    let from_binary = from_bytes(&bytes, "t.posg.bin").unwrap();
    assert_eq!(&from_binary, game);
    assert_eq!(to_json_string(&from_binary), json);
}

#[test]
fn rewards_and_labels_survive_drn_json_and_binary() {
    let game = saynt_style().game;
    assert_round_trips(&game);
    let json: Value = serde_json::from_str(&to_json_string(&game)).unwrap();
    assert_eq!(
        json["defender"]["action_labels"],
        json!({"_init_": "(init)", "_n_": "(n)", "_s_": "(s)"})
    );
    assert_eq!(
        json["rewards"]["cost"]["states"],
        json!({"s1": 2.0, "s2": -0.25})
    );
    assert_eq!(
        json["rewards"]["reward"]["actions"][0],
        json!({"state": "s1", "defender": "_n_", "reward": -1.0})
    );
    // A game with rewards or labels is written as version 2.
    assert_eq!(to_bytes(&game)[8..12], EXTENDED_VERSION.to_le_bytes());
}

#[test]
fn json_rewards_resolve_wildcards_by_the_most_specific_entry() {
    let game = read(Path::new("tests/data/valid/rewarded-pennies.posg.json")).unwrap();
    let coins = game.reward_model("coins").unwrap();
    let at = |u, v| {
        coins
            .action_reward(0, DefenderAction(u), AdversaryAction(v))
            .unwrap()
    };
    assert_eq!(
        (at(0, 0), at(0, 1), at(1, 0), at(1, 1)),
        (-0.04, -0.04, 0.5, 2.0)
    );
    assert_eq!(coins.state_reward(1), 1.0);
    assert_eq!(coins.state_reward(2), -1.0);
    let steps = game.reward_model("steps").unwrap();
    assert_eq!(steps.state_rewards().collect::<Vec<_>>(), [(0, 1.0)]);
    assert_eq!(steps.action_rewards().count(), 0);
    assert_round_trips(&game);
    // Written back: one entry per triple, the zero state reward left out.
    let json: Value = serde_json::from_str(&to_json_string(&game)).unwrap();
    assert_eq!(
        json["rewards"]["coins"]["actions"]
            .as_array()
            .unwrap()
            .len(),
        4
    );
    assert_eq!(json["rewards"]["steps"], json!({"states": {"s": 1.0}}));
}

/// Games without rewards or action labels are written byte for byte as
/// before rewards existed: `tests/data/unchanged/` holds what the command
/// line of b51cef3 (the commit before them) wrote: `example grid --out`
/// (JSON), `example grid --binary --out` and `import-drn
/// tests/data/drn/coin.drn --out`.
#[test]
fn games_without_rewards_are_written_as_before() {
    let fixture = |name: &str| std::fs::read(format!("tests/data/unchanged/{name}")).unwrap();
    let grid_json = String::from_utf8(fixture("grid-3x2.posg.json")).unwrap();
    let grid = from_json_str(&grid_json, "grid-3x2.posg.json").unwrap();
    assert!(grid.reward_models().is_empty());
    assert_eq!(to_json_string(&grid), grid_json.trim_end());
    assert_eq!(to_bytes(&grid), fixture("grid-3x2.posg.bin"));
    assert_eq!(
        from_bytes(&fixture("grid-3x2.posg.bin"), "grid-3x2.posg.bin").unwrap(),
        grid
    );
    let coin = read_drn(Path::new("tests/data/drn/coin.drn")).unwrap().game;
    let coin_json = String::from_utf8(fixture("coin.posg.json")).unwrap();
    assert_eq!(to_json_string(&coin), coin_json.trim_end());
    assert_eq!(to_bytes(&coin)[8..12], 1u32.to_le_bytes());
    for file in ["grid-3x2", "matching-pennies", "remember-the-cue"] {
        let game = read(Path::new(&format!("tests/data/valid/{file}.posg.json"))).unwrap();
        let json = to_json_string(&game);
        assert!(!json.contains("rewards") && !json.contains("action_labels"));
        assert_eq!(to_bytes(&game)[8..12], 1u32.to_le_bytes(), "{file}");
    }
}

// --- bad input --------------------------------------------------------------

/// The reward model `[rewards]` of `tests/data/drn/rewards.drn` with `from`
/// replaced by `to`.
fn rewards_drn_with(from: &str, to: &str) -> String {
    let text = std::fs::read_to_string("tests/data/drn/rewards.drn").unwrap();
    assert!(text.contains(from), "{from}");
    text.replacen(from, to, 1)
}

#[test]
fn bad_drn_rewards_are_errors_naming_the_line() {
    let cases = [
        (
            rewards_drn_with("[-0.04, 2]", "[-0.04, inf]"),
            "m.drn: line 22: reward `inf` is not finite",
        ),
        (
            rewards_drn_with("[0, 1/3]", "[0, 1/0]"),
            "m.drn: line 19: reward `1/0` is not finite",
        ),
        (
            rewards_drn_with("[1e-3, -7]", "[1e-3, NaN]"),
            "m.drn: line 34: reward `NaN` is not finite",
        ),
        (
            rewards_drn_with("[1, 0]", "[1, zero]"),
            "m.drn: line 25: reward `zero` is not a number (a decimal or p/q)",
        ),
        (
            rewards_drn_with("[-1, 0.5]", "[-1, 0.5, 2]"),
            "m.drn: line 23: the reward annotation `[-1, 0.5, 2]` has 3 values, but the one at \
             line 18 has 2 values",
        ),
        (
            rewards_drn_with("[0.25, -2.5e-1]", "[0.25]"),
            "m.drn: line 28: the reward annotation `[0.25]` has 1 value, but `@reward_models` \
             (line 12) names 2 reward models",
        ),
        (
            rewards_drn_with("reward cost ", "reward cost reward"),
            "m.drn: line 12: reward model `reward` is named twice",
        ),
        (
            rewards_drn_with("@reward_models\n", "@reward_models\nx\n@reward_models\n"),
            "m.drn: line 13: a second `@reward_models` line; the first names its reward models \
             at line 12",
        ),
        (
            rewards_drn_with("reward cost ", "rew1 "),
            "m.drn: line 12: reward model 1, unnamed here, would be named `rew1`, which \
             `@reward_models` gives another model",
        ),
        (
            rewards_drn_with("reward cost ", "reward \"cost\""),
            "m.drn: line 12: `\"cost\"` is not a valid reward model name (not empty, without \
             whitespace or `\"`)",
        ),
        (
            rewards_drn_with("reward cost \n", "\n").replacen("[0, 1/3]", "[0]", 1),
            "m.drn: line 19: the reward annotation `[0]` has 1 value, but the one at line 18 has \
             2 values",
        ),
    ];
    for (text, expected) in cases {
        let error = drn_error(&text);
        assert_eq!(error, expected);
    }
}

const FILE: &str = "t.posg.json";

/// `tests/data/valid/rewarded-pennies.posg.json` with `change` applied.
fn pennies_with(change: impl FnOnce(&mut Value)) -> Result<Posg, ModelError> {
    let text = std::fs::read_to_string("tests/data/valid/rewarded-pennies.posg.json").unwrap();
    let mut game: Value = serde_json::from_str(&text).unwrap();
    change(&mut game);
    from_json_str(&game.to_string(), FILE)
}

fn assert_json_error<T: std::fmt::Debug>(result: Result<T, ModelError>, path: &str, message: &str) {
    let error = result.expect_err("the game should be refused");
    assert_eq!(error.path, format!("{FILE}: {path}"), "{error}");
    assert!(error.message.starts_with(message), "{error}");
}

#[test]
fn bad_json_rewards_are_errors_naming_the_json_path() {
    assert_json_error(
        pennies_with(|g| g["rewards"]["coins"]["states"]["nowhere"] = json!(1.0)),
        "rewards.coins.states.nowhere",
        "unknown state `nowhere`",
    );
    assert_json_error(
        pennies_with(|g| g["rewards"]["coins"]["actions"][1]["defender"] = json!("X")),
        "rewards.coins.actions[1].defender",
        "unknown action `X`",
    );
    assert_json_error(
        pennies_with(|g| g["rewards"]["coins"]["actions"][2]["state"] = json!("nowhere")),
        "rewards.coins.actions[2].state",
        "unknown state `nowhere`",
    );
    assert_json_error(
        pennies_with(|g| g["rewards"]["coins"]["actions"][0]["adversary"] = json!("H")),
        "rewards.coins.actions",
        "rewards.coins.actions[0] and rewards.coins.actions[1] both match (state `s`, defender \
         `T`, adversary `H`) and neither is more specific",
    );
    assert_json_error(
        pennies_with(|g| g["rewards"]["coins"]["actions"][0]["bonus"] = json!(1.0)),
        "rewards.coins.actions[0].bonus",
        "unknown field `bonus`",
    );
    assert_json_error(
        pennies_with(|g| g["rewards"]["coins"]["actions"][0]["reward"] = json!("1")),
        "rewards.coins.actions[0].reward",
        "invalid type: string \"1\", expected f64",
    );
    assert_json_error(
        pennies_with(|g| g["rewards"]["a b"] = json!({})),
        "rewards.a b",
        "`a b` is not a valid reward model name",
    );
}

#[test]
fn a_json_reward_that_is_not_finite_or_a_repeated_model_is_an_error_naming_its_path() {
    let text = std::fs::read_to_string("tests/data/valid/rewarded-pennies.posg.json").unwrap();
    let huge = text.replacen("\"trap\": -1.0", "\"trap\": -1e400", 1);
    assert_json_error(
        from_json_str(&huge, FILE),
        "rewards.coins.states.trap",
        "number out of range",
    );
    let twice = text.replacen(
        "\"steps\": {\"states\"",
        "\"coins\": {}, \"steps\": {\"states\"",
        1,
    );
    assert_json_error(
        from_json_str(&twice, FILE),
        "rewards.coins",
        "duplicate key",
    );
}

#[test]
fn bad_action_labels_are_errors_naming_the_json_path() {
    let labelled = |labels: Value| {
        pennies_with(|g| g["defender"]["action_labels"] = labels).map(|g| {
            let defender = g.defender();
            (
                defender.action_label(0).unwrap().to_string(),
                defender.action_label(1).unwrap().to_string(),
            )
        })
    };
    assert_eq!(
        labelled(json!({"T": "(t)"})).unwrap(),
        ("H".to_string(), "(t)".to_string())
    );
    assert_json_error(
        labelled(json!({"X": "(x)"})),
        "defender.action_labels.X",
        "unknown action `X`",
    );
    assert_json_error(
        labelled(json!({"H": "T"})),
        "defender.action_labels.H",
        "label `T` is a valid action name; labels are given only for actions renamed from a \
         label that is not a name",
    );
    // A valid name is refused even when no action has it.
    assert_json_error(
        labelled(json!({"H": "heads"})),
        "defender.action_labels.H",
        "label `heads` is a valid action name",
    );
    assert_json_error(
        labelled(json!({"H": "(h)", "T": "(h)"})),
        "defender.action_labels.T",
        "label `(h)` is also the label of action `H`",
    );
    assert_json_error(
        labelled(json!({"H": "a b"})),
        "defender.action_labels.H",
        "label `a b` is empty or has whitespace",
    );
}

/// The binary form of `tests/data/drn/rewards.drn`.
fn saynt_bytes() -> Vec<u8> {
    to_bytes(&saynt_style().game)
}

/// Where the f64 `value` first appears in `bytes`.
fn position_of(bytes: &[u8], value: f64) -> usize {
    bytes
        .windows(8)
        .position(|w| w == value.to_le_bytes())
        .expect("the value is written")
}

#[test]
fn bad_binary_rewards_are_errors_naming_the_part() {
    let bytes = saynt_bytes();
    let mut nan = bytes.clone();
    let at = position_of(&nan, -0.04);
    nan[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let error = from_bytes(&nan, "t.posg.bin").unwrap_err().to_string();
    assert_eq!(
        error,
        "t.posg.bin: rewards.reward.states[1]: reward NaN is not finite"
    );
    let mut infinite = bytes.clone();
    let at = position_of(&infinite, -7.0);
    infinite[at..at + 8].copy_from_slice(&f64::INFINITY.to_le_bytes());
    let error = from_bytes(&infinite, "t.posg.bin").unwrap_err().to_string();
    assert_eq!(
        error,
        "t.posg.bin: rewards.cost.actions[2]: reward inf is not finite"
    );
    // rewarded-pennies' second model renamed as its first: a repeated name.
    let pennies = read(Path::new("tests/data/valid/rewarded-pennies.posg.json")).unwrap();
    let mut twice = to_bytes(&pennies);
    let at = twice.windows(5).rposition(|w| w == b"steps").unwrap();
    twice[at..at + 5].copy_from_slice(b"coins");
    let error = from_bytes(&twice, "t.posg.bin").unwrap_err().to_string();
    assert_eq!(
        error,
        "t.posg.bin: rewards[1]: reward model `coins` appears twice"
    );
    // A reward on a triple the game does not define: `(init)` in s3 (the
    // cost's last action reward names triple 3 * 4 + 3; make it 3 * 4 + 0).
    let mut undefined = bytes.clone();
    let at = position_of(&undefined, -7.0) - 4;
    undefined[at..at + 4].copy_from_slice(&12u32.to_le_bytes());
    let error = from_bytes(&undefined, "t.posg.bin")
        .unwrap_err()
        .to_string();
    assert_eq!(
        error,
        "t.posg.bin: rewards.cost.actions[2]: a reward for (state `s3`, defender `_init_`, \
         adversary `_`), whose actions no observation of the state enables"
    );
}

#[test]
fn truncated_or_corrupt_extended_binaries_are_errors_never_panics() {
    let bytes = saynt_bytes();
    for len in 0..bytes.len() {
        assert!(from_bytes(&bytes[..len], "t.posg.bin").is_err(), "{len}");
    }
    for at in 12..bytes.len() {
        for byte in [0u8, 1, 0x7f, 0xff] {
            let mut corrupt = bytes.clone();
            corrupt[at] = byte;
            if let Ok(game) = from_bytes(&corrupt, "t.posg.bin") {
                assert_round_trips(&game);
            }
        }
    }
}

/// Storm's header line is split at each space or tab: an empty piece, or
/// no piece, leaves a model unnamed, and it is named `rew{i}`; trailing
/// empty pieces are ignored.
#[test]
fn models_the_header_leaves_unnamed_are_named_rew_i() {
    let with_header = |header: &str| {
        let text = format!(
            "@type: DTMC\n@reward_models\n{header}\n@nr_states\n1\n@model\n\
             state 0 [1, 2, 3, 4] init\n\taction __NOLABEL__\n\t\t0 : 1\n"
        );
        let game = from_drn_str(&text, "m.drn", None).unwrap().game;
        game.reward_model_names()
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    assert_eq!(with_header("a  b"), ["a", "rew1", "b", "rew3"]);
    assert_eq!(with_header("a\tb \t "), ["a", "b", "rew2", "rew3"]);
    assert_eq!(with_header(" "), ["rew0", "rew1", "rew2", "rew3"]);
    let game = from_drn_str(
        "@type: DTMC\n@reward_models\na  b\n@nr_states\n1\n@model\nstate 0 init\n\
         \taction __NOLABEL__\n\t\t0 : 1\n",
        "m.drn",
        None,
    )
    .unwrap()
    .game;
    assert_eq!(
        game.reward_model_names().collect::<Vec<_>>(),
        ["a", "rew1", "b"]
    );
}

/// A POMDP whose states with one observation offer different renamed
/// labels: the error shows each label as written, with its name.
#[test]
fn offered_labels_are_shown_as_written_with_their_names() {
    let text = "@type: POMDP\n@nr_states\n2\n@model\nstate 0 {0} init\n\taction (n)\n\t\t1 : 1\n\
                state 1 {0}\n\taction (s)\n\t\t0 : 1\n";
    assert_eq!(
        drn_error(text),
        "m.drn: line 8: state 1 offers {(s) (read as _s_)}, but state 0 (line 5) with the same \
         observation offers {(n) (read as _n_)}: a POMDP's states with one observation must \
         offer the same actions"
    );
    let smg = "@type: POSMG\n@nr_states\n2\n@model\nstate 0 {0} <0> init\n\taction (n)\n\
               \t\t1 : 1\nstate 1 {0} <0>\n\taction s\n\t\t0 : 1\n";
    assert!(
        drn_error(smg).contains(
            "state 1 offers {s}, but state 0 (line 5) with the same \
                                 observation offers {(n) (read as _n_)}"
        ),
        "{}",
        drn_error(smg)
    );
}

/// Wildcard action rewards that would expand to more rewards than
/// `MAX_REWARD_ENTRIES` are refused before any is expanded, naming the
/// model that crosses the budget.
#[test]
fn wildcard_action_rewards_beyond_the_budget_are_refused_before_expansion() {
    let actions: Vec<String> = (0..2000).map(|u| format!("a{u}")).collect();
    let models: serde_json::Map<String, Value> = (0..13)
        .map(|i| {
            let entry = json!({"state": "s", "defender": "*", "adversary": "*", "reward": 1.0});
            (format!("m{i:02}"), json!({"actions": [entry]}))
        })
        .collect();
    let game = json!({
        "posg": 1, "states": ["s"], "initial": {"s": 1.0},
        "defender": {"actions": actions, "observe": "full"},
        "adversary": {"actions": actions, "observe": "full"},
        "transitions": [{"state": "s", "defender": "*", "adversary": "*", "next": {"s": 1.0}}],
        "rewards": models,
    });
    let start = std::time::Instant::now();
    let error = from_json_str(&game.to_string(), FILE)
        .unwrap_err()
        .to_string();
    assert_eq!(
        error,
        "t.posg.json: rewards.m12: the reward models with their wildcards expanded would need \
         52000000 rewards or more, above the budget of 50000000 \
         (posg_fsc::limits::MAX_REWARD_ENTRIES); use a smaller input"
    );
    assert!(start.elapsed().as_secs() < 20, "{:?}", start.elapsed());
}
