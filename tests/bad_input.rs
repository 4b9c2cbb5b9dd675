//! Issue 57's bad inputs, as a new user types them: each gives exit 0 or
//! a clear error naming its cause, never a panic (exit 101) or an abort
//! (exit 134).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("posg-fsc-bad-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn posg_fsc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The error message of a run that failed cleanly (exit 1 or 2), not by
/// a panic (101) or an abort (134).
fn error_of(output: &Output) -> String {
    let code = output.status.code();
    assert!(
        matches!(code, Some(1 | 2)),
        "exit {code:?}: {}",
        stderr(output)
    );
    stderr(output)
}

fn grid(dir: &Path) -> String {
    let game = dir.join("grid.posg.json").display().to_string();
    assert!(
        posg_fsc(&["example", "grid", "--out", &game])
            .status
            .success()
    );
    game
}

const LTL: &str = "GF goal & G !unsafe";

/// Issue 57: `Duration::from_secs_f64` and `Instant + Duration` panicked on
/// these; a budget beyond the clock now means no limit.
#[test]
fn durations_beyond_the_clock_mean_no_limit() {
    let dir = scratch("durations");
    let game = grid(&dir);
    let cases: [&[&str]; 7] = [
        &["solve", "--progress-every", "1e20"],
        &["solve", "--time-budget", "1e20"],
        &["solve", "--synthesis-time-budget", "1e20"],
        &["solve", "--translate-seconds", "1e308"],
        &[
            "sweep",
            "--time-budget",
            "1e308",
            "--def-nodes",
            "1",
            "--adv-nodes",
            "1",
        ],
        &[
            "sweep",
            "--synthesis-time-budget",
            "1e308",
            "--def-nodes",
            "1",
            "--adv-nodes",
            "1",
        ],
        &["support", "--synthesis-time-budget", "1e20"],
    ];
    for (k, case) in cases.iter().enumerate() {
        let out = dir.join(format!("out{k}")).display().to_string();
        let mut args = case.to_vec();
        args.extend([game.as_str(), "--ltl", LTL, "--out", &out]);
        if case[0] != "support" {
            args.extend(["--max-iterations", "2", "--quiet"]);
        }
        let output = posg_fsc(&args);
        assert!(output.status.success(), "{args:?}: {}", stderr(&output));
    }
}

/// NaN, infinities and negative numbers stay refused, by the option's name.
#[test]
fn unusable_durations_are_refused_by_name() {
    let dir = scratch("bad-durations");
    let game = grid(&dir);
    let out = dir.join("out").display().to_string();
    for (flag, value) in [
        ("--time-budget", "NaN"),
        ("--synthesis-time-budget", "inf"),
        ("--progress-every", "-1"),
        ("--progress-every", "0"),
    ] {
        let option = format!("{flag}={value}");
        let args = ["solve", &game, "--ltl", LTL, "--out", &out, &option];
        let message = error_of(&posg_fsc(&args));
        assert!(message.contains(flag), "{args:?}: {message}");
    }
}

/// Issue 57: a 10^6 x 10^6 grid allocated terabytes and aborted (exit 134);
/// it is refused before anything is allocated, naming the size and the limit.
#[test]
fn a_huge_grid_is_refused_with_its_size_and_the_limit() {
    let dir = scratch("huge-grid");
    let out = dir.join("big.posg.json").display().to_string();
    let args = [
        "example", "grid", "--width", "1000000", "--height", "1000000", "--out", &out,
    ];
    let message = error_of(&posg_fsc(&args));
    assert!(
        message.contains("1000000x1000000")
            && message.contains("8000000000000 transition triples")
            && message.contains("MAX_TRANSITION_TRIPLES"),
        "{message}"
    );
    let library = posg_fsc::game::grid::GridSpec {
        width: 1 << 40,
        height: 1 << 40,
        ..Default::default()
    };
    assert!(
        library
            .build()
            .unwrap_err()
            .to_string()
            .contains("MAX_TRANSITION_TRIPLES")
    );
}

/// An MDP in DRN with `n` states, each with its own action label: `n^2`
/// (state, action) pairs.
fn distinct_labels_drn(n: usize) -> String {
    let mut text = format!("@type: MDP\n@nr_states\n{n}\n@model\n");
    for k in 0..n {
        let init = if k == 0 { " init" } else { "" };
        text += &format!("state {k}{init}\n\taction a{k}\n\t\t{k} : 1\n");
    }
    text
}

/// DRN sizes: a huge `@nr_states` allocates nothing, and a model whose
/// tables (states x actions) exceed the limit is refused before they are
/// allocated (8,000 states with 8,000 labels took 600 MB before).
#[test]
fn drn_sizes_are_checked_before_allocation() {
    let dir = scratch("drn-sizes");
    let wide = dir.join("wide.drn");
    std::fs::write(&wide, distinct_labels_drn(8000)).unwrap();
    let message = error_of(&posg_fsc(&["check", &wide.display().to_string()]));
    assert!(
        message.contains("wide.drn")
            && message.contains("8000 states x 8000 defender actions")
            && message.contains("MAX_TRANSITION_TRIPLES"),
        "{message}"
    );
    let claimed =
        distinct_labels_drn(2).replace("@nr_states\n2", "@nr_states\n1000000000000000000");
    let claims = dir.join("claims.drn");
    std::fs::write(&claims, claimed).unwrap();
    let message = error_of(&posg_fsc(&["check", &claims.display().to_string()]));
    assert!(
        message.contains("declares 1000000000000000000 states, the model has 2"),
        "{message}"
    );
}

const DRN: &str = "tests/data/drn";

/// `text` with a UTF-8 byte-order mark in front, written to `dir/name`.
fn with_bom(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, format!("\u{feff}{text}")).unwrap();
    path.display().to_string()
}

/// Issue 57: a byte-order mark made every text input "expected value at
/// line 1 column 1"; each reader skips it now.
#[test]
fn a_byte_order_mark_is_skipped_by_every_text_reader() {
    let dir = scratch("bom");
    let read = |file: &str| std::fs::read_to_string(file).unwrap();
    let game = with_bom(&dir, "grid.posg.json", &read(&grid(&dir)));
    let drn = with_bom(&dir, "coin.drn", &read(&format!("{DRN}/coin.drn")));
    let props = with_bom(&dir, "coin.props", &read(&format!("{DRN}/coin.props")));
    let hoa = posg_fsc(&["translate", "F goal", "--hoa"]);
    let hoa = with_bom(&dir, "f.hoa", &String::from_utf8(hoa.stdout).unwrap());
    let runs: [&[&str]; 4] = [
        &["check", &game],
        &["check", &drn],
        &["eval", &drn, "--props", &props],
        &["eval", &game, "--automaton", &hoa],
    ];
    for args in runs {
        let output = posg_fsc(args);
        assert!(output.status.success(), "{args:?}: {}", stderr(&output));
    }
    let controller = r#"{"fsc": 1, "player": "defender", "nodes": 1, "initial": [1.0],
        "rules": [], "default": "uniform"}"#;
    let controller = with_bom(&dir, "d.fsc.json", controller);
    let args = ["eval", &game, "--ltl", "F goal", "--defender", &controller];
    let output = posg_fsc(&args);
    assert!(output.status.success(), "{args:?}: {}", stderr(&output));
}

/// Issue 57: a DRN file without its `@type` line was read as JSON
/// ("expected value at line 1 column 1").
#[test]
fn a_drn_file_without_its_type_is_named_as_a_drn_missing_its_header() {
    let dir = scratch("no-type");
    let text = std::fs::read_to_string(format!("{DRN}/coin.drn")).unwrap();
    let path = dir.join("coin.drn");
    std::fs::write(&path, text.replace("@type: POMDP\n", "")).unwrap();
    let message = error_of(&posg_fsc(&["check", &path.display().to_string()]));
    assert!(
        message.contains("coin.drn: line") && message.contains("no `@type` line"),
        "{message}"
    );
}

/// Issue 57: `<<P>>` naming a player the model lacks was an error on the
/// DRN file; it names the props file, line and column of `<<P>>`.
#[test]
fn a_props_player_the_model_lacks_names_the_props_file_line_and_column() {
    let dir = scratch("props-player");
    let seven = dir.join("seven.props");
    std::fs::write(
        &seven,
        "// a player the game lacks\n  <<7>> Pmax=? [F \"goal\"]\n",
    )
    .unwrap();
    let seven = seven.display().to_string();
    for command in ["eval", "import-drn"] {
        let args = [command, "tests/data/drn/pennies.drn", "--props", &seven];
        let message = error_of(&posg_fsc(&args));
        assert!(
            message.contains("seven.props: line 2, column 3: in tests/data/drn/pennies.drn, the defender, player <7>, owns no state"),
            "{args:?}: {message}"
        );
    }
    // A game file fixes its defender: `<<P>>` is ignored, with a warning.
    let game = grid(&dir);
    let output = posg_fsc(&["eval", &game, "--props", &seven]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(stderr(&output).contains("seven.props: line 2, column 3: `<<7>>` is ignored"));
    let zero = dir.join("zero.props");
    std::fs::write(&zero, "<<0>> Pmax=? [F \"goal\"]\n").unwrap();
    let zero = zero.display().to_string();
    let message = error_of(&posg_fsc(&[
        "eval",
        "tests/data/drn/coin.drn",
        "--props",
        &zero,
    ]));
    assert!(
        message.contains("zero.props: line 1, column 1: in tests/data/drn/coin.drn")
            && message.contains("this POMDP has no players"),
        "{message}"
    );
}

/// A one-node defender controller for two observations and two actions
/// whose block for observation 1 is `row`.
fn controller_with_row(row: [f64; 2]) -> Result<posg_fsc::controller::Fsc, String> {
    use posg_fsc::controller::{Choice, Fsc, Role};
    let block = |probabilities: [f64; 2]| {
        (0..2)
            .map(|action| Choice {
                next: 0,
                action,
                probability: probabilities[action],
                logit: None,
            })
            .collect()
    };
    let blocks = vec![block([0.5, 0.5]), block(row)];
    Fsc::new(Role::Defender, 1, 2, 2, vec![1.0], blocks).map_err(|e| e.to_string())
}

/// Issue 57: `Controller.from_probabilities` (Python, through `Fsc::new`)
/// kept a row summing to 1 + 1e-7 as it was: the controller was not a
/// distribution. Within the tolerance (1e-6) it is rescaled; beyond, it is
/// refused with the node, the observation and the sum.
#[test]
fn controller_rows_are_rescaled_within_the_tolerance_and_refused_beyond() {
    let fsc = controller_with_row([0.5, 0.5 + 1e-7]).unwrap();
    let sum: f64 = fsc.choices(0, 1).iter().map(|c| c.probability).sum();
    assert!((sum - 1.0).abs() <= 2.0 * f64::EPSILON, "{sum}");
    assert_eq!(fsc.choices(0, 0)[0].probability, 0.5);
    let message = controller_with_row([0.5, 0.5 + 1e-5]).unwrap_err();
    assert!(
        message.contains("node 0, observation 1")
            && message.contains("sum to 1.00001")
            && message.contains("tolerance 1e-6"),
        "{message}"
    );
}
