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
