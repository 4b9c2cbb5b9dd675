//! `posg-fsc certify` end to end: both bounds printed as JSON and the
//! attack written to a file, on a game whose bounds are known on paper.

use std::process::Command;

use serde_json::Value;

const BLOCKABLE_GOAL: &str = r#"{
  "posg": 1, "states": ["s0", "s1"], "initial": {"s0": 1.0}, "labels": {"s1": ["goal"]},
  "defender": {"actions": ["go"], "observe": "full"},
  "adversary": {"actions": ["pass", "block"], "observe": "full"},
  "transitions": [
    {"state": "s0", "defender": "go", "adversary": "pass", "next": {"s1": 0.5, "s0": 0.5}},
    {"state": "s0", "defender": "go", "adversary": "block", "next": {"s0": 1.0}},
    {"state": "s1", "defender": "*", "adversary": "*", "next": {"s1": 1.0}}
  ]
}"#;

#[test]
fn certify_prints_both_bounds_and_writes_the_attack() {
    let dir = std::env::temp_dir().join(format!("posg-fsc-certify-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let game = dir.join("blockable.posg.json");
    let attack = dir.join("attack.json");
    std::fs::write(&game, BLOCKABLE_GOAL).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .arg("certify")
        .arg(&game)
        .args([
            "--ltl",
            "F goal",
            "--defender",
            "uniform:1",
            "--adversary",
            "uniform:1",
        ])
        .arg("--attack")
        .arg(&attack)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["lower"]["value"], 0.0);
    assert_eq!(report["upper"]["value"], 1.0);
    let strategy: Value = serde_json::from_str(&std::fs::read_to_string(&attack).unwrap()).unwrap();
    assert_eq!(strategy["player"], "adversary");
    let s0 = strategy["rules"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["state"] == "s0")
        .unwrap();
    assert_eq!(s0["action"], "block");
    std::fs::remove_dir_all(&dir).unwrap();
}
