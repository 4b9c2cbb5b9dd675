//! Graphviz pictures of controllers: the text of a hand-made controller's
//! picture, controller files read without their game, and `posg-fsc dot`.

use std::process::Command;

use posg_fsc::controller::file::read_standalone;
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::output::dot::controller_dot;

fn choice(next: usize, action: usize, probability: f64) -> Choice {
    Choice {
        next,
        action,
        probability,
        logit: None,
    }
}

/// Two nodes, observations {dark, lit}, actions {stay, go}; node 0 on
/// `dark` stays with 0.995 and goes to node 1 with 0.005.
fn two_nodes() -> Fsc {
    let blocks = vec![
        vec![choice(0, 0, 0.995), choice(1, 1, 0.005)],
        vec![choice(1, 1, 0.25), choice(0, 0, 0.75)],
        vec![choice(1, 0, 1.0)],
        vec![choice(0, 1, 1.0)],
    ];
    Fsc::new(Role::Defender, 2, 2, 2, vec![0.5, 0.5], blocks).unwrap()
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

#[test]
fn the_picture_has_the_nodes_the_start_and_one_labelled_edge_per_node_pair() {
    let dot = controller_dot(
        &two_nodes(),
        &names(&["dark", "lit"]),
        &names(&["stay", "go"]),
        "a \"quoted\" title",
        0.01,
    );
    let expected_lines = [
        "digraph controller {",
        "  label=\"a \\\"quoted\\\" title\";",
        "  n0 [label=\"0\"];",
        "  n1 [label=\"1\"];",
        "  start -> n0 [label=\"0.5\"];",
        "  start -> n1 [label=\"0.5\"];",
        "  n0 -> n0 [label=\"dark / stay  0.995\\llit / stay  0.75\\l\"];",
        "  n0 -> n1 [label=\"lit / go  0.25\\l(1 below 0.01)\\l\"];",
        "  n1 -> n0 [label=\"lit / go  1\\l\"];",
        "  n1 -> n1 [label=\"dark / stay  1\\l\"];",
        "}",
    ];
    for line in expected_lines {
        assert!(dot.lines().any(|l| l == line), "missing `{line}` in\n{dot}");
    }
    assert_eq!(dot.matches(" -> ").count(), 6);
}

#[test]
fn an_edge_with_only_hidden_choices_is_dashed() {
    let blocks = vec![
        vec![choice(0, 0, 0.999), choice(1, 0, 0.001)],
        vec![choice(1, 0, 1.0)],
    ];
    let fsc = Fsc::new(Role::Adversary, 2, 1, 1, vec![1.0, 0.0], blocks).unwrap();
    let dot = controller_dot(&fsc, &names(&["o"]), &names(&["a"]), "t", 0.01);
    assert!(
        dot.contains("  n0 -> n1 [label=\"(1 below 0.01)\\l\", style=dashed];"),
        "{dot}"
    );
    assert!(!dot.contains("start -> n1"), "node 1 is not initial");
}

fn write_temp(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("posg-fsc-dot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

const CONTROLLER: &str = r#"{"fsc": 1, "player": "adversary", "nodes": 1, "initial": [1.0],
  "rules": [{"node": 0, "observation": "calm", "choices": [{"next": 0, "action": "pass", "p": 1.0}]},
            {"node": 0, "observation": "storm", "choices": [{"next": 0, "action": "block", "p": 0.6},
                                                            {"next": 0, "action": "pass", "p": 0.4}]}]}"#;

#[test]
fn a_controller_file_is_read_without_its_game_with_the_names_it_uses() {
    let path = write_temp("adv.fsc.json", CONTROLLER);
    let file = read_standalone(&path).unwrap();
    assert_eq!(file.observations, ["calm", "storm"]);
    assert_eq!(file.actions, ["pass", "block"]);
    assert_eq!(file.fsc.role(), Role::Adversary);
    assert_eq!(file.fsc.choices(0, 1).len(), 2);
    let uniform = write_temp(
        "uniform.fsc.json",
        &CONTROLLER.replace("\"rules\"", "\"default\": \"uniform\", \"rules\""),
    );
    let error = read_standalone(&uniform).unwrap_err().to_string();
    assert!(error.contains("uniform.fsc.json: default: with \"default\": \"uniform\" the controller can only be read with its game"), "{error}");
}

#[test]
fn posg_fsc_dot_draws_a_controller_file() {
    let path = write_temp("cli.fsc.json", CONTROLLER);
    let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .arg("dot")
        .arg(&path)
        .args(["--threshold", "0.5"])
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let dot = String::from_utf8(output.stdout).unwrap();
    assert!(
        dot.contains(
            "n0 -> n0 [label=\"calm / pass  1\\lstorm / block  0.6\\l(1 below 0.5)\\l\"];"
        ),
        "{dot}"
    );
}

fn dot_command(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .arg("dot")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn posg_fsc_dot_draws_a_uniform_controller_of_a_game() {
    let game = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/valid/grid-3x2.posg.json"
    );
    let output = dot_command(&["uniform:2", "--game", game]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let dot = String::from_utf8(output.stdout).unwrap();
    assert!(dot.contains("label=\"uniform:2: 2 nodes\";"), "{dot}");
    for line in [
        "  n0 [label=\"0\"];",
        "  n1 [label=\"1\"];",
        "  start -> n0 [label=\"1\"];",
    ] {
        assert!(dot.lines().any(|l| l == line), "missing `{line}` in\n{dot}");
    }
    // Every node pair has an edge: the uniform controller may go anywhere.
    for edge in ["n0 -> n0", "n0 -> n1", "n1 -> n0", "n1 -> n1"] {
        assert!(dot.contains(edge), "missing {edge} in\n{dot}");
    }
    let adversary = dot_command(&["uniform:1", "--game", game, "--player", "adversary"]);
    assert!(adversary.status.success());
    let defender = String::from_utf8(dot_command(&["uniform:1", "--game", game]).stdout).unwrap();
    assert_ne!(String::from_utf8(adversary.stdout).unwrap(), defender);
}

#[test]
fn posg_fsc_dot_of_a_uniform_controller_without_its_game_says_to_give_it() {
    let output = dot_command(&["uniform:2"]);
    assert!(!output.status.success());
    let error = String::from_utf8_lossy(&output.stderr);
    assert!(
        error.contains("uniform:2") && error.contains("--game GAME"),
        "{error}"
    );
    let bad = dot_command(&["uniform:0", "--game", "x.posg.json"]);
    assert!(!bad.status.success());
}

/// Issue 59: a 16x16 grid's defender had edges with 100+ label lines. An
/// edge with more than `MAX_EDGE_LINES` choices shows one line per action
/// and probability, the largest groups first, at most `MAX_EDGE_LINES`.
#[test]
fn an_edge_with_many_choices_groups_them_by_action_and_probability() {
    let observations = 40;
    // Observation o: action 0 with 1 for o < 20; else action 1 with a
    // probability of its own (0.5 + o / 100), the rest hidden below 0.01.
    let blocks = (0..observations)
        .map(|o| match o {
            o if o < 20 => vec![choice(0, 0, 1.0)],
            o => {
                let p = 0.5 + o as f64 / 100.0;
                vec![choice(0, 1, p), choice(0, 0, 1.0 - p)]
            }
        })
        .collect();
    let fsc = Fsc::new(Role::Defender, 1, observations, 2, vec![1.0], blocks).unwrap();
    let names: Vec<String> = (0..observations).map(|o| format!("o{o}")).collect();
    let dot = controller_dot(&fsc, &names, &self::names(&["a", "b"]), "t", 0.01);
    let edge = dot.lines().find(|l| l.starts_with("  n0 -> n0")).unwrap();
    let label = edge.split("label=\"").nth(1).unwrap();
    let lines: Vec<&str> = label.split("\\l").filter(|l| !l.starts_with('"')).collect();
    assert_eq!(lines.len(), posg_fsc::output::dot::MAX_EDGE_LINES, "{edge}");
    assert_eq!(lines[0], "a  1: o0, o1, o2, o3 and 16 more", "{edge}");
    assert_eq!(lines[1], "b  0.7: o20", "{edge}");
    // The 40 single-choice groups (b with p, a with 1 - p) after the
    // first: 10 shown, 30 folded.
    assert_eq!(lines[11], "(30 more choices)", "{edge}");
    // Choices below the threshold take the last of the 12 lines.
    let dot = controller_dot(&fsc, &names, &self::names(&["a", "b"]), "t", 0.2);
    let edge = dot.lines().find(|l| l.starts_with("  n0 -> n0")).unwrap();
    let label = edge.split("label=\"").nth(1).unwrap();
    let lines: Vec<&str> = label.split("\\l").filter(|l| !l.starts_with('"')).collect();
    assert_eq!(lines.len(), posg_fsc::output::dot::MAX_EDGE_LINES, "{edge}");
    assert!(lines[11].ends_with(" below 0.2)"), "{edge}");
}
