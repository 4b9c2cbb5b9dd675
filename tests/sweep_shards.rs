//! Sharded sweeps (`sweep --shard K/N`, `sweep-merge`, `sweep --slurm`):
//! the merge of the shards equals the unsharded sweep (rows identical apart
//! from the timing column, the same heatmap), missing pairs and shards are
//! named, shards of different settings are refused, a rerun completes a
//! shard that died, and the generated Slurm scripts run the same sweep
//! (executed here with `sh`, no Slurm needed).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("posg-fsc-shards-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(args)
        .output()
        .unwrap()
}

fn succeed(args: &[&str]) -> Output {
    let output = run(args);
    assert!(
        output.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

fn fail(args: &[&str]) -> String {
    let output = run(args);
    assert!(!output.status.success(), "{args:?} succeeded");
    String::from_utf8(output.stderr).unwrap()
}

/// A tiny grid game in `dir`.
fn grid(dir: &Path) -> String {
    let game = dir.join("grid.posg.json").display().to_string();
    succeed(&["example", "grid", "--out", &game]);
    game
}

/// `sweep GAME` with the test's settings (three chains of two pairs,
/// few iterations), then `extra`.
fn sweep(game: &str, out: &Path, extra: &[&str]) -> Output {
    let out = out.display().to_string();
    let mut args = vec![
        "sweep",
        game,
        "--ltl",
        "F goal & G !unsafe",
        "--def-nodes",
        "1..2",
        "--adv-nodes",
        "2,1,3",
        "--max-iterations",
        "4",
        "--quiet",
        "--out",
        &out,
    ];
    args.extend_from_slice(extra);
    run(&args)
}

fn sweep_ok(game: &str, out: &Path, extra: &[&str]) -> Output {
    let output = sweep(game, out, extra);
    assert!(
        output.status.success(),
        "{extra:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

fn merge(dir: &Path) -> Output {
    run(&["sweep-merge", &dir.display().to_string()])
}

/// The rows of `sweep.csv` with the timing column `seconds` removed.
fn rows_without_timing(dir: &Path) -> Vec<Vec<String>> {
    let mut reader = csv::Reader::from_path(dir.join("sweep.csv")).unwrap();
    let headers = reader.headers().unwrap().clone();
    let seconds = headers.iter().position(|h| h == "seconds").unwrap();
    let mut rows = vec![headers.iter().map(str::to_string).collect::<Vec<_>>()];
    for record in reader.records() {
        let record = record.unwrap();
        rows.push(
            record
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != seconds)
                .map(|(_, f)| f.to_string())
                .collect(),
        );
    }
    rows[0].remove(seconds);
    rows
}

fn assert_same_sweep(whole: &Path, merged: &Path) {
    let expected = rows_without_timing(whole);
    assert_eq!(expected.len(), 7, "a header and 3 x 2 size pairs");
    assert_eq!(rows_without_timing(merged), expected);
    assert_eq!(
        std::fs::read_to_string(merged.join("sweep.svg")).unwrap(),
        std::fs::read_to_string(whole.join("sweep.svg")).unwrap()
    );
}

#[test]
fn sharded_and_merged_equals_the_unsharded_sweep() {
    let dir = scratch("equal");
    let game = grid(&dir);
    let (whole, sharded) = (dir.join("whole"), dir.join("sharded"));
    sweep_ok(&game, &whole, &[]);
    // Both shards start at once into a directory that does not exist yet.
    let shards: Vec<_> = ["2/2", "1/2"]
        .into_iter()
        .map(|shard| {
            let (game, out) = (game.clone(), sharded.clone());
            std::thread::spawn(move || sweep(&game, &out, &["--shard", shard]))
        })
        .collect();
    for shard in shards {
        let output = shard.join().unwrap();
        assert!(output.status.success(), "{output:?}");
    }
    let merged = merge(&sharded);
    assert!(merged.status.success(), "{merged:?}");
    assert!(String::from_utf8_lossy(&merged.stdout).contains("6 size pairs from 2 shards"));
    assert_same_sweep(&whole, &sharded);
    let record = std::fs::read_to_string(sharded.join("shards/shard-1-of-2.json")).unwrap();
    let record: serde_json::Value = serde_json::from_str(&record).unwrap();
    assert_eq!(record["written_by"], "shard 1/2");
    assert_eq!(
        record["plan"]["adversary_sizes"],
        serde_json::json!([2, 1, 3])
    );
    assert_eq!(record["plan"]["settings"]["max_iterations"], 4);
    assert!(record["command_line"].as_array().unwrap().len() > 3);
}

#[test]
fn missing_pairs_are_named_and_a_rerun_completes_a_shard_that_died() {
    let dir = scratch("missing");
    let game = grid(&dir);
    let (whole, sharded) = (dir.join("whole"), dir.join("sharded"));
    sweep_ok(&game, &whole, &[]);
    sweep_ok(&game, &sharded, &["--shard", "1/2"]);
    let error = String::from_utf8(merge(&sharded).stderr).unwrap();
    assert!(error.contains("2 of 6 size pairs are missing"), "{error}");
    for pair in ["def1-adv1", "def2-adv1"] {
        assert!(
            error.contains(&format!("{pair} (shard 2/2, never started")),
            "{error}"
        );
    }
    assert!(!sharded.join("sweep.csv").exists());
    sweep_ok(&game, &sharded, &["--shard", "2/2"]);
    // A shard killed while writing def2-adv1: the pair never appeared, its
    // staging directory stays behind.
    std::fs::remove_dir_all(sharded.join("def2-adv1")).unwrap();
    let staging = sharded.join(".def2-adv1.partial-4294967295");
    std::fs::create_dir_all(&staging).unwrap();
    std::fs::write(staging.join("curve.csv"), "iteration,seconds\n0,").unwrap();
    let error = String::from_utf8(merge(&sharded).stderr).unwrap();
    assert!(
        error.contains("1 of 6 size pairs are missing: def2-adv1 (shard 2/2, started but did not finish it: rerun that shard)"),
        "{error}"
    );
    let rerun = sweep_ok(&game, &sharded, &["--shard", "2/2"]);
    assert!(String::from_utf8_lossy(&rerun.stdout).contains("wrote 2 size pairs"));
    let complete = sweep_ok(&game, &sharded, &["--shard", "1/2"]);
    assert!(
        String::from_utf8_lossy(&complete.stdout).contains("were complete already and kept"),
        "a complete shard is not recomputed"
    );
    assert!(merge(&sharded).status.success());
    assert_same_sweep(&whole, &sharded);
}

#[test]
fn shards_of_different_settings_are_refused() {
    let dir = scratch("mismatch");
    let game = grid(&dir);
    let sharded = dir.join("sharded");
    sweep_ok(&game, &sharded, &["--shard", "1/2"]);
    let error =
        String::from_utf8(sweep(&game, &sharded, &["--shard", "2/2", "--seed", "7"]).stderr)
            .unwrap();
    assert!(
        error.contains("shard-1-of-2.json (shard 1/2) was written with different settings"),
        "{error}"
    );
    let error = String::from_utf8(sweep(&game, &sharded, &["--shard", "1/3"]).stderr).unwrap();
    assert!(error.contains("different shards"), "{error}");
    // A record that disagrees, put there by hand: the merge refuses it.
    let first = std::fs::read_to_string(sharded.join("shards/shard-1-of-2.json")).unwrap();
    let second = first
        .replace("shard 1/2", "shard 2/2")
        .replace("\"seed\": 0", "\"seed\": 7");
    assert_ne!(first, second);
    std::fs::write(sharded.join("shards/shard-2-of-2.json"), second).unwrap();
    let error = String::from_utf8(merge(&sharded).stderr).unwrap();
    assert!(
        error.contains("shard-2-of-2.json (shard 2/2) was written with different settings"),
        "{error}"
    );
}

#[test]
fn bad_shards_and_directories_are_refused() {
    let dir = scratch("refused");
    let game = grid(&dir);
    let error =
        String::from_utf8(sweep(&game, &dir.join("a"), &["--shard", "4/4"]).stderr).unwrap();
    assert!(error.contains("the sweep has 3 chains"), "{error}");
    let error =
        String::from_utf8(sweep(&game, &dir.join("a"), &["--shard", "3/2"]).stderr).unwrap();
    assert!(error.contains("1 <= K <= N"), "{error}");
    let whole = dir.join("whole");
    sweep_ok(&game, &whole, &[]);
    let error = String::from_utf8(sweep(&game, &whole, &["--shard", "1/3"]).stderr).unwrap();
    assert!(error.contains("holds no shard records"), "{error}");
    let error = fail(&["sweep-merge", &whole.display().to_string()]);
    assert!(
        error.contains("not the --out of a `sweep --shard K/N` run"),
        "{error}"
    );
    let error = fail(&[
        "sweep",
        &game,
        "--out",
        "x",
        "--slurm-option",
        "--partition=a",
    ]);
    assert!(error.contains("--slurm"), "{error}");
}

#[test]
fn the_slurm_scripts_run_the_same_sweep() {
    let dir = scratch("slurm");
    let game = grid(&dir);
    let (whole, sharded) = (dir.join("whole"), dir.join("sharded"));
    sweep_ok(&game, &whole, &[]);
    let output = sweep_ok(
        &game,
        &sharded,
        &[
            "--slurm",
            "--slurm-option=--partition=short",
            "--slurm-option",
            "--time=0:10:00",
        ],
    );
    assert!(!sharded.join("def1-adv1").exists(), "--slurm runs nothing");
    let stdout = String::from_utf8(output.stdout).unwrap();
    assert!(stdout.contains("an array job of 3 shards"), "{stdout}");
    assert!(stdout.contains("JOBID=$(sbatch --parsable "), "{stdout}");
    assert!(
        stdout.contains("sbatch --dependency=afterok:$JOBID ")
            && stdout.contains("sweep-merge.sbatch"),
        "{stdout}"
    );
    let script = std::fs::read_to_string(sharded.join("sweep.sbatch")).unwrap();
    let lines: Vec<&str> = script.lines().collect();
    assert_eq!(lines[0], "#!/bin/sh");
    for line in [
        "#SBATCH --array=1-3",
        "#SBATCH --partition=short",
        "#SBATCH --time=0:10:00",
        "#SBATCH --job-name=posg-fsc-sweep",
    ] {
        assert!(lines.contains(&line), "{line} missing from\n{script}");
    }
    let exec = lines.last().unwrap();
    assert!(exec.starts_with("exec '/"), "{exec}");
    assert!(exec.contains("'sweep' '"), "{exec}");
    assert!(
        exec.ends_with("--shard \"$SLURM_ARRAY_TASK_ID/3\""),
        "{exec}"
    );
    assert!(
        !exec.contains("--slurm") && !exec.contains("short"),
        "{exec}"
    );
    let first_command = lines.iter().position(|l| !l.starts_with('#')).unwrap();
    assert!(
        lines[first_command..]
            .iter()
            .all(|l| !l.starts_with("#SBATCH")),
        "sbatch reads options only before the first command"
    );
    assert!(
        sharded.join("slurm-logs").is_dir(),
        "Slurm does not create it"
    );
    let merge_script = std::fs::read_to_string(sharded.join("sweep-merge.sbatch")).unwrap();
    assert!(merge_script.contains("#SBATCH --partition=short"));
    assert!(!merge_script.contains("--array"));
    assert!(
        merge_script
            .trim_end()
            .ends_with(&format!("sweep-merge '{}'", sharded.display()))
    );
    // The array tasks and the merge as Slurm would run them.
    for task in ["3", "1", "2"] {
        let status = Command::new("sh")
            .arg(sharded.join("sweep.sbatch"))
            .env("SLURM_ARRAY_TASK_ID", task)
            .output()
            .unwrap();
        assert!(status.status.success(), "task {task}: {status:?}");
    }
    let status = Command::new("sh")
        .arg(sharded.join("sweep-merge.sbatch"))
        .output()
        .unwrap();
    assert!(status.status.success(), "{status:?}");
    assert_same_sweep(&whole, &sharded);
    let record = std::fs::read_to_string(sharded.join("shards/slurm.json")).unwrap();
    assert!(record.contains("\"written_by\": \"--slurm\""));
}
