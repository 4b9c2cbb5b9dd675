//! What `solve` and `sweep` write and report: the plots (titles, the
//! certified band, integer ticks, the heatmap), `defender.dot`, and progress
//! on stderr when it is not a terminal (a line per structure at least, a
//! line per finished size pair), silenced by `--quiet`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("posg-fsc-output-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn posg_fsc(args: &[&str]) -> Output {
    let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

fn grid(dir: &Path) -> String {
    let game = dir.join("grid.posg.json").display().to_string();
    posg_fsc(&["example", "grid", "--out", &game]);
    game
}

/// The trimmed contents of the SVG's `<text>` elements.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let inner = t.split_once('>')?.1;
            Some(inner.split("</text>").next()?.trim().to_string())
        })
        .collect()
}

fn read(path: PathBuf) -> String {
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn solve_writes_a_titled_curve_with_the_certified_band_and_a_controller_picture() {
    let dir = scratch("solve");
    let game = grid(&dir);
    let out = dir.join("out").display().to_string();
    let output = posg_fsc(&[
        "solve",
        &game,
        "--ltl",
        "F goal & G !unsafe",
        "--def-nodes",
        "2",
        "--out",
        &out,
        "--max-iterations",
        "30",
        "--structures",
        "full",
        "--seconds-axis",
    ]);
    let svg = read(dir.join("out/curve.svg"));
    let texts = texts(&svg);
    for text in [
        "grid-3x2: F goal &amp; G !unsafe",
        "defender 2 nodes, adversary 1 node, structure full, game of 6 states",
        "certified bracket",
        "worst-case estimate",
        "seconds",
        "iteration",
        "probability of phi",
        "25",
    ] {
        assert!(
            texts.iter().any(|t| t == text),
            "curve.svg lacks `{text}` in {texts:?}"
        );
    }
    assert!(svg.contains("<polygon"), "the band is a filled polygon");
    assert!(
        !texts.iter().any(|t| t == "25.0"),
        "integer iteration ticks"
    );
    let dot = read(dir.join("out/defender.dot"));
    assert!(
        dot.starts_with("digraph controller {") && dot.contains("n0 -> n1"),
        "{dot}"
    );
    let summary = read(dir.join("out/summary.json"));
    assert!(summary.contains("\"defender.dot\""));
    let stderr = String::from_utf8(output.stderr).unwrap();
    assert!(
        stderr.contains("[full] iteration 30/30: value "),
        "{stderr}"
    );
}

#[test]
fn quiet_solve_and_sweep_report_no_progress() {
    let dir = scratch("quiet");
    let game = grid(&dir);
    let out = dir.join("out").display().to_string();
    let solve = posg_fsc(&[
        "solve",
        &game,
        "--ltl",
        "F goal",
        "--out",
        &out,
        "--max-iterations",
        "5",
        "--quiet",
    ]);
    assert!(!String::from_utf8_lossy(&solve.stderr).contains("iteration"));
    let out = dir.join("sweep").display().to_string();
    let sweep = posg_fsc(&[
        "sweep",
        &game,
        "--ltl",
        "F goal",
        "--def-nodes",
        "1..2",
        "--adv-nodes",
        "1",
        "--out",
        &out,
        "--max-iterations",
        "5",
        "--quiet",
    ]);
    assert!(!String::from_utf8_lossy(&sweep.stderr).contains("sweep"));
}

#[test]
fn sweep_reports_pairs_done_and_draws_a_heatmap() {
    let dir = scratch("sweep");
    let game = grid(&dir);
    let out = dir.join("out").display().to_string();
    let output = posg_fsc(&[
        "sweep",
        &game,
        "--ltl",
        "F goal & G !unsafe",
        "--def-nodes",
        "1,3",
        "--adv-nodes",
        "1..2",
        "--out",
        &out,
        "--max-iterations",
        "10",
    ]);
    let stderr = String::from_utf8(output.stderr).unwrap();
    for done in 1..=4 {
        assert!(
            stderr.contains(&format!("sweep {done}/4 size pairs (defender ")),
            "{stderr}"
        );
    }
    assert!(stderr.contains(" s elapsed, ETA "), "{stderr}");
    let svg = read(dir.join("out/sweep.svg"));
    let texts = texts(&svg);
    for text in [
        "cell: certified lower bound",
        "defender nodes",
        "adversary nodes",
        "1",
        "3",
        "2",
    ] {
        assert!(
            texts.iter().any(|t| t == text),
            "sweep.svg lacks `{text}` in {texts:?}"
        );
    }
    let estimates = texts
        .iter()
        .filter(|t| t.starts_with("est. ") && t.contains(", ub "))
        .count();
    assert_eq!(estimates, 4, "one labelled cell per size pair");
}
