//! Output directories end to end (issue 13): results appear whole or not at
//! all, a non-empty `--out` is refused without `--force`, a failing run
//! leaves the old results as they were, and two runs cannot share one `--out`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

const GRID: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/valid/grid-3x2.posg.json"
);

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("posg-fsc-out-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn posg_fsc(args: &[&str], out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn solve_args(extra: &[&'static str]) -> Vec<&'static str> {
    let mut args = vec![
        "solve",
        GRID,
        "--ltl",
        "!unsafe U goal",
        "--structures",
        "full",
    ];
    if !extra.contains(&"--max-iterations") {
        args.extend(["--max-iterations", "4"]);
    }
    args.extend_from_slice(extra);
    args
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The directory's files and their contents, sorted by name.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&path).unwrap())
        })
        .collect();
    files.sort();
    files
}

#[test]
fn existing_files_are_kept_without_force_and_replaced_whole_with_it() {
    let base = scratch("force");
    let out = base.join("chain");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let args = ["export-gmc", GRID];
    let refused = posg_fsc(&args, &out);
    assert!(!refused.status.success());
    assert!(stderr(&refused).contains("--force"), "{}", stderr(&refused));
    assert!(stderr(&refused).contains(out.to_str().unwrap()));
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    assert!(!out.join("chain.tra").exists());
    let forced = posg_fsc(&["export-gmc", GRID, "--force"], &out);
    assert!(forced.status.success(), "{}", stderr(&forced));
    let names: Vec<String> = snapshot(&out).into_iter().map(|(n, _)| n).collect();
    assert_eq!(
        names,
        ["chain.drn", "chain.lab", "chain.sta", "chain.tra"],
        "never a mixture"
    );
    let leftovers = std::fs::read_dir(&base).unwrap().count();
    assert_eq!(leftovers, 1, "no staging directory or lock file is left");
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn a_failing_run_leaves_the_old_results_intact() {
    let base = scratch("failing");
    let out = base.join("run");
    let first = posg_fsc(&solve_args(&[]), &out);
    assert!(first.status.success(), "{}", stderr(&first));
    let before = snapshot(&out);
    assert!(
        before
            .iter()
            .any(|(n, c)| n == "curve.csv" && !c.is_empty())
    );
    // No solve is that accurate: the optimiser's first evaluation fails.
    let failing = posg_fsc(
        &solve_args(&["--force", "--solver-tolerance", "1e-30"]),
        &out,
    );
    assert!(!failing.status.success());
    assert!(
        stderr(&failing).contains("tolerance 1e-30"),
        "{}",
        stderr(&failing)
    );
    assert_eq!(snapshot(&out), before, "the old results are untouched");
    assert_eq!(std::fs::read_dir(&base).unwrap().count(), 1);
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn two_concurrent_runs_into_one_directory_one_refuses() {
    let base = scratch("concurrent");
    let out = base.join("run");
    let first = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(solve_args(&[
            "--max-iterations",
            "100000000",
            "--time-budget",
            "3",
        ]))
        .arg("--out")
        .arg(&out)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let lock = base.join(".run.lock");
    let start = Instant::now();
    while !lock.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no lock taken");
        std::thread::sleep(Duration::from_millis(5));
    }
    let second = posg_fsc(&solve_args(&[]), &out);
    assert!(!second.status.success());
    assert!(
        stderr(&second).contains("another run"),
        "{}",
        stderr(&second)
    );
    let first = first.wait_with_output().unwrap();
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(out.join("summary.json").exists());
    assert!(!lock.exists());
    std::fs::remove_dir_all(&base).unwrap();
}

/// `solve --lu-limit` reaches the settings recorded in summary.json (which
/// name it only when it is not the default, so older summaries stay as they
/// were), and `--tolerance` and its old name `--solver-tolerance` are one option.
#[test]
fn solve_takes_lu_limit_and_both_names_of_the_tolerance() {
    let base = scratch("solver-options");
    let settings = |extra: &[&'static str], name: &str| {
        let out = base.join(name);
        let run = posg_fsc(&solve_args(extra), &out);
        assert!(run.status.success(), "{}", stderr(&run));
        let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
        let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
        summary["settings"].clone()
    };
    let new = settings(&["--lu-limit", "7", "--tolerance", "1e-8"], "new");
    assert_eq!(new["lu_limit"], 7);
    assert_eq!(new["solver_tolerance"], 1e-8);
    let old = settings(&["--solver-tolerance", "1e-8"], "old");
    assert_eq!(old.get("lu_limit"), None, "{old}");
    assert_eq!(old["solver_tolerance"], 1e-8);
    std::fs::remove_dir_all(&base).unwrap();
}
