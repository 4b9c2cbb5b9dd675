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
