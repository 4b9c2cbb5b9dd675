//! `posg-fsc eval --gradient` end to end, on a game whose value and
//! gradient are known on paper.

use std::ffi::OsStr;
use std::path::PathBuf;
use std::process::Command;

use serde_json::Value;

/// From s0 the adversary lets the defender through to the goal s1 (pass)
/// or into the trap s2 (attack), each with probability 1/2, else s0 again.
/// With `a = mu_adv(pass)`, `b = mu_adv(attack)` and `g = mu_def(go)`:
/// `x = g (a/2 + (a + b) x/2)`, so at `a = b = 1/2`, `g = 1`: `x = 1/2`,
/// `dx/da = 3/2`, `dx/db = 1/2`, `dx/dg = 1`.
const PASS_OR_TRAP: &str = r#"{
  "posg": 1, "states": ["s0", "s1", "s2"], "initial": {"s0": 1.0}, "labels": {"s1": ["goal"]},
  "defender": {"actions": ["go"], "observe": "full"},
  "adversary": {"actions": ["pass", "attack"], "observe": "full"},
  "transitions": [
    {"state": "s0", "defender": "go", "adversary": "pass", "next": {"s1": 0.5, "s0": 0.5}},
    {"state": "s0", "defender": "go", "adversary": "attack", "next": {"s2": 0.5, "s0": 0.5}},
    {"state": "s1", "defender": "*", "adversary": "*", "next": {"s1": 1.0}},
    {"state": "s2", "defender": "*", "adversary": "*", "next": {"s2": 1.0}}
  ]
}"#;

/// A fresh directory `posg-fsc-NAME-PID` under the temporary directory,
/// holding `PASS_OR_TRAP` as `pass-or-trap.posg.json`: the directory and
/// the game's path.
fn pass_or_trap(name: &str) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!("posg-fsc-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let game = dir.join("pass-or-trap.posg.json");
    std::fs::write(&game, PASS_OR_TRAP).unwrap();
    (dir, game)
}

/// The JSON `posg-fsc ARGS` prints, after checking that it succeeded.
fn posg_fsc_json(args: &[&OsStr]) -> Value {
    let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

fn close(value: &Value, expected: f64) -> bool {
    (value.as_f64().unwrap() - expected).abs() < 1e-12
}

#[test]
fn eval_with_gradient_reports_the_norms_of_the_adjoint_gradient() {
    let (dir, game) = pass_or_trap("eval");
    let report = posg_fsc_json(&[
        "eval".as_ref(),
        game.as_os_str(),
        "--ltl".as_ref(),
        "F goal".as_ref(),
        "--gradient".as_ref(),
    ]);
    assert!(close(&report["value"], 0.5), "{report}");
    let gradient = &report["gradient"];
    // One block per state (full observation): only s0's entries move the value.
    assert_eq!(gradient["defender_parameters"], 3);
    assert_eq!(gradient["adversary_parameters"], 6);
    assert!(close(&gradient["defender_norm"], 1.0), "{gradient}");
    assert!(
        close(&gradient["adversary_norm"], 2.5f64.sqrt()),
        "{gradient}"
    );
    assert!(close(&gradient["adversary_max_abs"], 1.5), "{gradient}");
    assert!(gradient["adjoint_residual"].as_f64().unwrap() < 1e-12);
    assert!(report["phase_seconds"]["value_and_gradient"].is_number());
    assert!(report["phase_seconds"]["factorise_and_solve"].is_null());
    assert_eq!(report["solver"], "lu");
    assert_eq!(
        report["solver_reason"], "auto: lu, 1 unknowns, at most the LU limit 500000",
        "{report}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `simulate` says what its interval means: the JSON carries its
/// confidence, and a run whose interval misses the exact value says on
/// stderr that a 95% interval does so about once in twenty.
#[test]
fn simulate_explains_an_interval_that_misses_the_exact_value() {
    let (dir, game) = pass_or_trap("simulate");
    let (mut missed, mut met) = (0, 0);
    for seed in 0..200 {
        if missed > 0 && met > 0 {
            break;
        }
        let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
            .arg("simulate")
            .arg(&game)
            .args([
                "--ltl",
                "F goal",
                "--runs",
                "30",
                "--seed",
                &seed.to_string(),
            ])
            .output()
            .unwrap();
        assert!(output.status.success());
        let report: Value = serde_json::from_slice(&output.stdout).unwrap();
        assert_eq!(report["estimate"]["confidence"], 0.95);
        let stderr = String::from_utf8_lossy(&output.stderr);
        let within = report["exact_within_interval"].as_bool().unwrap();
        assert_eq!(
            stderr.contains("lies outside the 95% interval") && stderr.contains("one seed of 20"),
            !within,
            "seed {seed}: {stderr}"
        );
        if within { met += 1 } else { missed += 1 }
    }
    assert!(missed > 0 && met > 0, "missed {missed}, met {met}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `simulate --props` restates a `Pmin=? [F "goal"]` query in its own
/// terms: the tool samples the complement `G !goal`, and `query` gives the
/// probability of `F goal` itself (here 1/2, with an interval that turns
/// over with it), beside the complement's estimate.
#[test]
fn simulate_restates_a_pmin_query_as_the_probability_of_its_path() {
    let (dir, game) = pass_or_trap("simulate-pmin");
    let props = dir.join("pmin.props");
    std::fs::write(&props, "Pmin=? [F \"goal\"]\n").unwrap();
    let report = posg_fsc_json(&[
        "simulate".as_ref(),
        game.as_os_str(),
        "--props".as_ref(),
        props.as_os_str(),
        "--runs".as_ref(),
        "400".as_ref(),
        "--seed".as_ref(),
        "3".as_ref(),
    ]);
    let query = &report["query"];
    assert_eq!(query["text"], "Pmin=? [F \"goal\"]");
    assert!(close(&query["exact_value"], 0.5), "{query}");
    assert!(close(&report["exact_value"], 0.5), "{report}");
    let complement = report["estimate"]["mean"].as_f64().unwrap();
    // (This seed's estimate is not 1/2, so restating shows.)
    assert!((complement - 0.5).abs() > 1e-3, "{report}");
    assert!(close(&query["mean"], 1.0 - complement), "{report}");
    let [lower, upper] = [0, 1].map(|i| query["interval"][i].as_f64().unwrap());
    let [c_lower, c_upper] = ["lower", "upper"].map(|k| report["estimate"][k].as_f64().unwrap());
    assert!((lower - (1.0 - c_upper)).abs() < 1e-12, "{report}");
    assert!((upper - (1.0 - c_lower)).abs() < 1e-12, "{report}");
    assert!(
        lower < upper && lower < 0.5 + 0.1 && upper > 0.5 - 0.1,
        "{query}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--props` takes the query itself, recognised by its `=?`, as Python's
/// props= does: the same value as from a file, and a mistake in it is
/// cited as `--props` with its position.
#[test]
fn props_take_a_query_written_inline_as_a_file_would() {
    let (dir, game) = pass_or_trap("inline-props");
    let query = "Pmax=? [F \"goal\"]";
    let file = dir.join("q.props");
    std::fs::write(&file, query).unwrap();
    let eval = |props: &OsStr| {
        posg_fsc_json(&[
            "eval".as_ref(),
            game.as_os_str(),
            "--props".as_ref(),
            props,
            "--adversary".as_ref(),
            "uniform:1".as_ref(),
        ])
    };
    let inline = eval(query.as_ref());
    let from_file = eval(file.as_os_str());
    assert!(close(&inline["query"]["value"], 0.5), "{inline}");
    assert_eq!(inline["query"], from_file["query"]);
    let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args([
            "eval".as_ref(),
            game.as_os_str(),
            "--props".as_ref(),
            "Pmax=? [F (\"goal\"]".as_ref(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(stderr.contains("--props: line 1, column"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}
