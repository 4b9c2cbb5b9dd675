//! `posg-fsc prune` end to end: the controller files it writes read back
//! and evaluate to the value recorded in `structures.json`.

use std::path::Path;
use std::process::Command;

use posg_fsc::controller::{Role, Support, file};
use posg_fsc::game::Posg;
use posg_fsc::value::Evaluator;
use posg_fsc::value::SolverSettings;
use serde_json::Value;

/// `risky` reaches `u` from `s0` when the adversary pushes; `go` is safe.
const RISKY: &str = r#"{
  "posg": 1, "states": ["s0", "s1", "u"], "initial": {"s0": 1.0},
  "labels": {"u": ["unsafe"]},
  "defender": {"actions": ["go", "risky"], "observe": "full"},
  "adversary": {"actions": ["calm", "push"], "observe": "full"},
  "transitions": [
    {"state": "s0", "defender": "go", "adversary": "*", "next": {"s1": 1.0}},
    {"state": "s0", "defender": "risky", "adversary": "calm", "next": {"s1": 1.0}},
    {"state": "s0", "defender": "risky", "adversary": "push", "next": {"s1": 0.5, "u": 0.5}},
    {"state": "s1", "defender": "*", "adversary": "*", "next": {"s0": 1.0}},
    {"state": "u", "defender": "*", "adversary": "*", "next": {"u": 1.0}}
  ]
}"#;

fn prune_cli(dir: &Path, extra: &[&str]) -> Value {
    let game = dir.join("risky.posg.json");
    std::fs::write(&game, RISKY).unwrap();
    let out = dir.join("out");
    let status = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .arg("prune")
        .arg(&game)
        .args([
            "--ltl",
            "G !unsafe",
            "--def-nodes",
            "2",
            "--adv-nodes",
            "1",
            "--out",
        ])
        .arg(&out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(out.join("structures.json")).unwrap()).unwrap()
}

fn value_of(game: &Posg, dir: &Path, structure: &Value) -> f64 {
    let read = |key: &str, role| {
        file::read(
            &dir.join("out").join(structure[key].as_str().unwrap()),
            game,
            role,
        )
        .unwrap()
    };
    let (def, adv) = (
        read("defender", Role::Defender),
        read("adversary", Role::Adversary),
    );
    let dra = posg_fsc::ltl::translate(&posg_fsc::ltl::parse("G !unsafe").unwrap()).unwrap();
    let mut ev = Evaluator::new(
        game,
        &dra,
        &Support::of(&def),
        &Support::of(&adv),
        &SolverSettings::default(),
    )
    .unwrap();
    ev.evaluate(
        &Support::probabilities_of(&def),
        &Support::probabilities_of(&adv),
    )
    .unwrap()
    .value
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir =
        std::env::temp_dir().join(format!("posg-fsc-prune-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn prune_writes_evaluable_structures_with_their_values() {
    let dir = scratch("default");
    let summary = prune_cli(&dir, &[]);
    let game = posg_fsc::game::file::from_json_str(RISKY, "risky.posg.json").unwrap();
    assert_eq!(summary["initial_value"], 0.0);
    assert_eq!(summary["adversary_pruned"], false);
    let structures = summary["structures"].as_array().unwrap();
    assert_eq!(structures.len(), 1);
    let recorded = structures[0]["value"].as_f64().unwrap();
    assert!((recorded - 1.0).abs() < 1e-12, "{recorded}");
    assert!((value_of(&game, &dir, &structures[0]) - recorded).abs() < 1e-12);
    let produced_by = &structures[0]["produced_by"][0];
    assert_eq!(
        produced_by["removed_defender"], 4,
        "(g', risky | g, s0) for g, g' in {{0, 1}}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn adversary_pruning_is_recorded_in_the_output() {
    let dir = scratch("adversary");
    let summary = prune_cli(&dir, &["--prune-adversary"]);
    assert_eq!(summary["adversary_pruned"], true);
    assert!(
        summary["note"]
            .as_str()
            .unwrap()
            .contains("not max-min guarantees")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
