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

/// Exit 0, or 1 or 2 with a one-line cause: no panic, no abort.
fn assert_clean(args: &[&str], output: &Output) {
    let code = output.status.code();
    assert!(
        matches!(code, Some(0..=2)) && !stderr(output).contains("panicked"),
        "{args:?}: exit {code:?}\n{}",
        stderr(output)
    );
}

fn grid(dir: &Path) -> String {
    let game = dir.join("grid.posg.json").display().to_string();
    assert!(posg_fsc(&["example", "grid", "--out", &game]).status.success());
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
        &["sweep", "--time-budget", "1e308", "--def-nodes", "1", "--adv-nodes", "1"],
        &["sweep", "--synthesis-time-budget", "1e308", "--def-nodes", "1", "--adv-nodes", "1"],
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
        let output = posg_fsc(&args);
        assert_eq!(output.status.code(), Some(2), "{args:?}");
        assert!(stderr(&output).contains(flag), "{args:?}: {}", stderr(&output));
    }
}
