//! Regression tests for the findings of issue 26's fuzzing, each named
//! after its finding; each failed before the fix.

use std::process::Command;

use posg_fsc::game::drn::from_drn_str;

fn posg_fsc() -> Command {
    Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
}

#[cfg(unix)]
#[test]
fn fuzz_non_utf8_path_argument_is_an_error_not_a_panic() {
    use std::ffi::OsStr;
    use std::os::unix::ffi::OsStrExt;
    let path = OsStr::from_bytes(b"/nonexistent/\xff\xfe.posg.json");
    for command in ["eval", "certify", "simulate", "export-gmc"] {
        let mut run = posg_fsc();
        run.arg(command).arg(path).args(["--ltl", "F goal"]);
        if command == "certify" {
            run.args(["--defender", "uniform:1"]);
        }
        let output = run.output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_ne!(output.status.code(), Some(101), "{command}: {stderr}");
        assert!(!output.status.success(), "{command}");
        assert!(!stderr.contains("panicked"), "{command}: {stderr}");
    }
}

#[test]
fn fuzz_import_drn_nr_states_of_a_billion_is_an_error_not_an_abort() {
    let text = "@type: DTMC\n@nr_states\n1000000000\n@model\nstate 0 init\n\taction a\n\t\t0 : 1\n";
    let error = from_drn_str(text, "m.drn", None).unwrap_err().to_string();
    assert!(
        error.contains("@nr_states declares 1000000000 states, the model has 1"),
        "{error}"
    );
}

#[test]
fn fuzz_drn_count_mismatches_name_the_line() {
    let text = "@type: DTMC\n@nr_states\n2\n@nr_choices\n3\n@model\nstate 0 init\n\taction a\n\t\t1 : 1\nstate 1\n\taction a\n\t\t1 : 1\n";
    let error = from_drn_str(text, "m.drn", None).unwrap_err().to_string();
    assert!(
        error.contains("m.drn: line 5") && error.contains("@nr_choices"),
        "{error}"
    );
    let text = "@type: DTMC\n@nr_states\n3\n@model\nstate 0 init\n\taction a\n\t\t1 : 1\nstate 1\n\taction a\n\t\t1 : 1\n";
    let error = from_drn_str(text, "m.drn", None).unwrap_err().to_string();
    assert!(
        error.contains("m.drn: line 3") && error.contains("@nr_states"),
        "{error}"
    );
}

#[test]
fn fuzz_drn_init_init_labels_the_state_once() {
    let text = "@type: DTMC\n@nr_states\n2\n@model\nstate 0 init init\n\taction a\n\t\t1 : 1\nstate 1 done\n\taction a\n\t\t1 : 1\n";
    let game = from_drn_str(text, "m.drn", None).unwrap().game;
    assert_eq!(game.initial(), [(0, 1.0)]);
}

#[test]
fn fuzz_certify_honours_tolerance() {
    let chain = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/chains/slow-three.posg.json"
    );
    let output = posg_fsc()
        .args([
            "certify",
            chain,
            "--ltl",
            "F goal",
            "--defender",
            "uniform:2",
        ])
        .args(["--tolerance", "1e-300"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success(),
        "a bound of 1e-300 cannot be proved"
    );
    assert!(
        stderr.contains("tolerance 1e-300") && stderr.contains("policy evaluation"),
        "{stderr}"
    );
}

/// A sharded sweep of one tiny size pair in a fresh directory, and the path
/// of that pair's `row.csv`.
fn one_pair_sharded_sweep(name: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!("posg-fsc-fuzz-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let game = dir.join("grid.posg.json");
    let out = dir.join("sharded");
    let example = posg_fsc()
        .args(["example", "grid", "--out"])
        .arg(&game)
        .output()
        .unwrap();
    assert!(example.status.success(), "{example:?}");
    let sweep = posg_fsc()
        .arg("sweep")
        .arg(&game)
        .args(["--ltl", "F goal & G !unsafe", "--def-nodes", "1"])
        .args(["--adv-nodes", "1", "--max-iterations", "2", "--starts", "1"])
        .args(["--quiet", "--shard", "1/1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(sweep.status.success(), "{sweep:?}");
    let row = out.join("def1-adv1").join("row.csv");
    (out, row)
}

/// `sweep-merge DIR`: its stderr, after asserting that it failed.
fn merge_fails(out: &std::path::Path) -> String {
    let merge = posg_fsc().arg("sweep-merge").arg(out).output().unwrap();
    let stderr = String::from_utf8_lossy(&merge.stderr).into_owned();
    assert!(!merge.status.success(), "merged: {stderr}");
    assert!(!out.join("sweep.csv").exists());
    stderr
}

/// `row.csv` with the field of `column` replaced by `value`.
fn with_field(text: &str, column: &str, value: &str) -> String {
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header = reader.headers().unwrap().clone();
    let i = header.iter().position(|c| c == column).unwrap();
    let record = reader.records().next().unwrap().unwrap();
    let fields = record
        .iter()
        .enumerate()
        .map(|(j, f)| if j == i { value } else { f });
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(&header).unwrap();
    writer.write_record(fields).unwrap();
    String::from_utf8(writer.into_inner().unwrap()).unwrap()
}

#[test]
fn fuzz_sweep_merge_refuses_rows_with_impossible_probabilities() {
    let (out, row) = one_pair_sharded_sweep("row-values");
    let good = std::fs::read_to_string(&row).unwrap();
    let merge = posg_fsc().arg("sweep-merge").arg(&out).output().unwrap();
    assert!(merge.status.success(), "{merge:?}");
    std::fs::remove_file(out.join("sweep.csv")).unwrap();
    let bad = [
        ("worst_case", "1.5"),
        ("certified_lower", "-1"),
        ("last_value", "NaN"),
        ("upper_bound", "inf"),
        ("error_bound", "NaN"),
    ];
    for (column, value) in bad {
        std::fs::write(&row, with_field(&good, column, value)).unwrap();
        let error = merge_fails(&out);
        assert!(
            error.contains("def1-adv1/row.csv: line 2: column `")
                && error.contains(&format!("`{column}`: {value} is not")),
            "{column} = {value}: {error}"
        );
    }
    let crossed = with_field(
        &with_field(&good, "certified_lower", "0.6"),
        "upper_bound",
        "0.5",
    );
    std::fs::write(&row, crossed).unwrap();
    let error = merge_fails(&out);
    assert!(
        error.contains("line 2: column `certified_lower`: 0.6 is above `upper_bound` 0.5"),
        "{error}"
    );
}

#[test]
fn fuzz_sweep_merge_refuses_a_renamed_column() {
    let (out, row) = one_pair_sharded_sweep("row-columns");
    let good = std::fs::read_to_string(&row).unwrap();
    std::fs::write(&row, good.replacen("certified_lower", "certified_low", 1)).unwrap();
    let error = merge_fails(&out);
    assert!(
        error.contains(
            "def1-adv1/row.csv: line 1: column 11 is `certified_low`, expected `certified_lower`"
        ),
        "{error}"
    );
    let (header, rest) = good.split_once('\n').unwrap();
    std::fs::write(&row, format!("{header},extra\n{},1\n", rest.trim_end())).unwrap();
    let error = merge_fails(&out);
    assert!(
        error.contains("line 1: column 17 `extra` is not a column of row.csv"),
        "{error}"
    );
}

/// A scratch directory of this test process.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("posg-fsc-fuzz-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `states` states that each move to every state uniformly, seen by both
/// players as one observation, with one action each.
fn dense_game(dir: &std::path::Path, states: usize) -> std::path::PathBuf {
    let names: Vec<String> = (0..states).map(|i| format!("\"s{i}\"")).collect();
    let observe: Vec<String> = (0..states)
        .map(|i| format!("\"s{i}\": {{\"o\": 1}}"))
        .collect();
    let next: Vec<String> = (0..states)
        .map(|i| format!("\"s{i}\": {:e}", 1.0 / states as f64))
        .collect();
    let player = |action: &str| {
        format!(
            r#"{{"actions": ["{action}"], "observations": ["o"], "observe": {{{}}}}}"#,
            observe.join(", ")
        )
    };
    let next = next.join(", ");
    let transitions: Vec<String> = (0..states)
        .map(|i| {
            format!(r#"{{"state": "s{i}", "defender": "*", "adversary": "*", "next": {{{next}}}}}"#)
        })
        .collect();
    let json = format!(
        r#"{{"posg": 1, "states": [{}], "initial": {{"s0": 1}}, "labels": {{"s1": ["goal"]}},
           "defender": {}, "adversary": {}, "transitions": [{}]}}"#,
        names.join(", "),
        player("a"),
        player("b"),
        transitions.join(",\n")
    );
    let path = dir.join("dense.posg.json");
    std::fs::write(&path, json).unwrap();
    path
}

/// A path of `states` states, each seen as itself, with two defender actions.
fn long_path_game(dir: &std::path::Path, states: usize) -> std::path::PathBuf {
    let names: Vec<String> = (0..states).map(|i| format!("\"s{i}\"")).collect();
    let transitions: Vec<String> = (0..states)
        .map(|i| {
            format!(
                r#"{{"state": "s{i}", "defender": "*", "next": {{"s{}": 1}}}}"#,
                (i + 1).min(states - 1)
            )
        })
        .collect();
    let json = format!(
        r#"{{"posg": 1, "states": [{}], "initial": {{"s0": 1}}, "labels": {{"s{}": ["goal"]}},
           "defender": {{"actions": ["go", "stay"], "observe": "full"}},
           "transitions": [{}]}}"#,
        names.join(", "),
        states - 1,
        transitions.join(",\n")
    );
    let path = dir.join("path.posg.json");
    std::fs::write(&path, json).unwrap();
    path
}

/// Runs posg-fsc with `args`, asserts that it failed cleanly, returns stderr.
fn refused(args: &[&std::ffi::OsStr]) -> String {
    let output = posg_fsc().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    stderr
}

#[test]
fn fuzz_eval_with_huge_uniform_controllers_is_refused_by_the_gmc_budget() {
    // 200 successors x 1000 x 1000 nodes: the action mixtures alone would
    // need 2e8 terms (4 GB), the GMC 2e8 states.
    let dir = scratch("gmc-budget");
    let game = dense_game(&dir, 200);
    let eval = |nodes: &str| {
        refused(&[
            "eval".as_ref(),
            game.as_os_str(),
            "--ltl".as_ref(),
            "F goal".as_ref(),
            "--defender".as_ref(),
            nodes.as_ref(),
            "--adversary".as_ref(),
            nodes.as_ref(),
        ])
    };
    let error = eval("uniform:1000");
    assert!(
        error.contains("the defender's action mixture (200 game states x 1000 controller nodes")
            && error.contains("200000000 terms")
            && error.contains("posg_fsc::limits::MAX_MIXTURE_TERMS"),
        "{error}"
    );
    // 200 x 500 x 500 = 5e7 successors of the first row alone.
    let error = eval("uniform:500");
    assert!(
        error.contains("one row (successor states x defender nodes x adversary nodes)")
            && error.contains("posg_fsc::limits::MAX_GMC_STATES"),
        "{error}"
    );
}

#[test]
fn fuzz_solve_with_many_defender_nodes_is_refused_before_allocation() {
    // 2e5 observations x 2 actions x 6^2 nodes = 1.44e7 choices: the
    // optimiser's starts would need several GB.
    let dir = scratch("solve-budget");
    let game = long_path_game(&dir, 200_000);
    let out = dir.join("out");
    let error = refused(&[
        "solve".as_ref(),
        game.as_os_str(),
        "--ltl".as_ref(),
        "F goal".as_ref(),
        "--def-nodes".as_ref(),
        "6".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert!(
        error.contains("--def-nodes: a full-support controller of 6 nodes (200000 observations, 2 actions) would need 14400000 choices")
            && error.contains("posg_fsc::limits::MAX_CONTROLLER_CHOICES"),
        "{error}"
    );
    assert!(!out.exists(), "nothing is written");
}
