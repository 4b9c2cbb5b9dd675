//! Ctrl-C and SIGTERM on the command line (issue 57): `solve` stops at the
//! first signal with the best defender it has, certified and written whole
//! to `--out`, and exits with 130; a second signal, or a signal to another
//! command, stops at once and leaves `--out` as it was. Nothing is left
//! beside the target either way (no staging directory, no lock).
#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// How long a stopped command may take to exit here: the target is a
/// second, this leaves room for a loaded test machine; an uninterrupted
/// run lasts far longer (no iteration, work or stall limit).
const STOPS_WITHIN: Duration = Duration::from_secs(20);

fn posg_fsc() -> Command {
    Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("posg-fsc-int-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A 10x10 grid with ten random unsafe cells, in `dir`.
fn grid(dir: &Path) -> PathBuf {
    let game = dir.join("grid.posg.json");
    let status = posg_fsc()
        .args([
            "example", "grid", "--width", "10", "--height", "10", "--unsafe", "none",
        ])
        .args([
            "--goal",
            "s99",
            "--random-unsafe",
            "10",
            "--seed",
            "1",
            "--out",
        ])
        .arg(&game)
        .status()
        .unwrap();
    assert!(status.success());
    game
}

/// `solve`'s sizes, one of them.
const SOLVE: &[&str] = &["--def-nodes", "2", "--no-grow"];

/// `command` on `game` into `out` that only a signal ends.
fn endless(command: &str, game: &Path, out: &Path, extra: &[&str]) -> Child {
    posg_fsc()
        .arg(command)
        .arg(game)
        // A support with a positive value (on `GF goal & G !unsafe` the full
        // support's is 0 and the loop stops at once), no local search.
        .args([
            "--ltl",
            "!unsafe U goal",
            "--adv-nodes",
            "1",
            "--no-local-search",
        ])
        .args(["--structures", "full", "--starts", "1"])
        .args([
            "--max-iterations",
            "100000000",
            "--max-work",
            "0",
            "--stall-checks",
            "0",
        ])
        .args(["--gap-tolerance", "0"])
        .args(extra)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits until the run has begun writing (its staging directory exists
/// beside `out`) and a little more, so that the signal meets the optimiser.
fn wait_until_running(out: &Path, child: &mut Child) {
    let started = Instant::now();
    let parent = out.parent().unwrap();
    loop {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before the signal"
        );
        let staging = std::fs::read_dir(parent).unwrap().any(|e| {
            e.unwrap()
                .file_name()
                .to_string_lossy()
                .contains(".partial-")
        });
        if staging {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the run never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(1500));
}

fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([format!("-{name}"), child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// Waits for `child` to exit; its exit code, stderr and how long it took.
fn finish(mut child: Child, signalled: Instant) -> (Option<i32>, String, Duration) {
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if signalled.elapsed() > STOPS_WITHIN {
            let _ = child.kill();
            panic!("still running {STOPS_WITHIN:?} after the signal");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let took = signalled.elapsed();
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    (output.status.code(), stderr, took)
}

/// Runs `command` on `game` into `out` until it is running, sends it
/// `signals` in order, and waits for it: its exit code, stderr and how
/// long it took after the first signal.
fn interrupted(
    (command, extra): (&str, &[&str]),
    game: &Path,
    out: &Path,
    signals: &[&str],
) -> (Option<i32>, String, Duration) {
    let mut child = endless(command, game, out, extra);
    wait_until_running(out, &mut child);
    let signalled = Instant::now();
    for name in signals {
        signal(&child, name);
    }
    finish(child, signalled)
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn a_first_ctrl_c_writes_the_best_defender_so_far_and_exits_130() {
    let dir = scratch("graceful");
    let game = grid(&dir);
    let out = dir.join("run");
    let (code, stderr, took) = interrupted(("solve", SOLVE), &game, &out, &["INT"]);
    assert_eq!(code, Some(130), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    eprintln!("stopped {took:?} after the signal");
    assert_eq!(names(&dir), ["grid.posg.json", "run"]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let structure = &summary["structures"][0];
    assert_eq!(structure["status"], "cancelled", "{structure}");
    let certified = summary["certified"]["certified_lower"].as_f64().unwrap();
    assert!(certified >= 0.0);
    for file in [
        "curve.csv",
        "defender.fsc.json",
        "adversary.fsc.json",
        "defender.dot",
    ] {
        assert!(out.join(file).is_file(), "{file} missing");
    }
}

#[test]
fn sigterm_stops_solve_as_ctrl_c_does() {
    let dir = scratch("term");
    let game = grid(&dir);
    let out = dir.join("run");
    let (code, stderr, _) = interrupted(("solve", SOLVE), &game, &out, &["TERM"]);
    assert_eq!(code, Some(130), "{stderr}");
    assert!(out.join("summary.json").is_file());
}

#[test]
fn a_second_signal_quits_at_once_and_leaves_out_untouched() {
    let dir = scratch("twice");
    let game = grid(&dir);
    let out = dir.join("run");
    // Old results in --out, which the run would replace whole at its end
    // (--force), stay as they were.
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("old.txt"), "earlier results").unwrap();
    let replacing: &[&str] = &["--def-nodes", "2", "--no-grow", "--force"];
    // Two different signals, sent at once: the kernel merges a second
    // SIGINT that arrives while the first is still pending (on a loaded
    // machine it did), where a person's second Ctrl-C comes later.
    let (code, stderr, _) = interrupted(("solve", replacing), &game, &out, &["INT", "TERM"]);
    assert_eq!(code, Some(130), "{stderr}");
    assert!(stderr.contains("nothing written"), "{stderr}");
    assert_eq!(names(&dir), ["grid.posg.json", "run"]);
    assert_eq!(names(&out), ["old.txt"]);
}

#[test]
fn ctrl_c_stops_a_sweep_at_once_leaving_out_untouched() {
    let dir = scratch("sweep");
    let game = grid(&dir);
    let out = dir.join("sweep");
    let sizes: &[&str] = &["--def-nodes", "1..3"];
    let (code, stderr, _) = interrupted(("sweep", sizes), &game, &out, &["INT"]);
    assert_eq!(code, Some(130), "{stderr}");
    assert_eq!(names(&dir), ["grid.posg.json"]);
}
