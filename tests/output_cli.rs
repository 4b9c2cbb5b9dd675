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
        "!unsafe U goal",
        "--def-nodes",
        "2",
        "--out",
        &out,
        // 30 iterations: no local search, stall or gap rule ends it sooner
        // (on `F goal & G !unsafe` the full support's value is 0, and the
        // loop stops at once: zero-on-support).
        "--max-iterations",
        "30",
        "--no-local-search",
        "--gap-tolerance",
        "0",
        "--stall-checks",
        "0",
        "--no-grow",
        "--structures",
        "full",
        "--seconds-axis",
    ]);
    let svg = read(dir.join("out/curve.svg"));
    let texts = texts(&svg);
    for text in [
        "grid-3x2: !unsafe U goal",
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
        stderr.contains("2 nodes, full: returns its defender from ")
            && stderr.contains(
                " after 30 iterations (its race: iteration limit reached: 30 iterations)"
            )
            && stderr.contains("; best certified ["),
        "{stderr}"
    );
}

/// Issue 59: a line at once for each event, and the status (what each
/// structure does, the best certified bracket) whenever nothing else was
/// said for `--progress-every` seconds; every line stamped with the run's
/// clock, which never runs backwards.
#[test]
fn progress_lines_say_what_runs_and_the_best_bracket_on_one_clock() {
    let dir = scratch("lines");
    let example = posg_fsc(&[
        "example",
        "grid",
        "--width",
        "6",
        "--height",
        "6",
        "--unsafe",
        "none",
        "--goal",
        "s35",
        "--random-unsafe",
        "4",
        "--seed",
        "1",
    ]);
    let game = dir.join("grid6.json");
    std::fs::write(&game, example.stdout).unwrap();
    let out = dir.join("out").display().to_string();
    let output = posg_fsc(&[
        "solve",
        &game.display().to_string(),
        "--ltl",
        "F goal & G !unsafe",
        "--out",
        &out,
        "--max-iterations",
        "300",
        "--stall-checks",
        "0",
        "--gap-tolerance",
        "0",
        "--no-local-search",
        "--structures",
        "full,sat",
        "--def-nodes",
        "2",
        "--progress-every",
        "1e-9",
    ]);
    assert!(output.status.success());
    let stderr = String::from_utf8(output.stderr).unwrap();
    let stamped: Vec<(f64, &str)> = (stderr.lines())
        .filter_map(|line| {
            let (stamp, text) = line.strip_prefix('[')?.split_once(" s] ")?;
            Some((stamp.parse().ok()?, text))
        })
        .collect();
    assert!(stamped.len() >= 4, "{stderr}");
    assert!(
        stamped.windows(2).all(|pair| pair[0].0 <= pair[1].0),
        "one clock: {stderr}"
    );
    let status = |text: &str| text.starts_with("1 of 2 nodes: ") || text.starts_with("2 nodes: ");
    assert!(
        stamped
            .iter()
            .any(|(_, text)| status(text) && text.contains(" racing (iteration ")),
        "a status line during the race: {stderr}"
    );
    assert!(
        (stamped.iter())
            .any(|(_, text)| text.starts_with("2 nodes: done in ") && text.contains("certified [")),
        "the size's result: {stderr}"
    );
    assert!(
        !stderr.contains("(at most "),
        "no cap the run may not reach: {stderr}"
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
        "cell and colour:",
        "certified lower bound",
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
    let estimates = texts.iter().filter(|t| t.starts_with("est. ")).count();
    let uppers = texts.iter().filter(|t| t.starts_with("ub ")).count();
    assert_eq!(
        (estimates, uppers),
        (4, 4),
        "one labelled cell per size pair"
    );
    let table = read(dir.join("out/sweep.csv"));
    let lower = table.lines().nth(1).unwrap().split(',').nth(10).unwrap();
    let lower: f64 = lower.parse().unwrap_or_else(|_| panic!("{table}"));
    assert!(
        texts
            .iter()
            .any(|t| t == &format!("{lower:.3}") || t.starts_with(&format!("{lower:.3}"))),
        "the first pair's certified lower bound {lower} is written in its cell: {texts:?}"
    );
    assert!(
        svg.matches("<rect").count() > 100,
        "the colour bar is a gradient"
    );
}

/// `"key": number` of a JSON text (the first occurrence).
fn json_number(text: &str, key: &str) -> f64 {
    let rest = text.split(&format!("\"{key}\": ")).nth(1).unwrap();
    let end = rest.find([',', '\n', '}']).unwrap();
    rest[..end].trim().parse().unwrap()
}

#[test]
fn curve_svg_draws_the_certified_bracket_solve_returns_with_distinct_tick_labels() {
    let dir = scratch("bracket");
    let game = grid(&dir);
    let out = dir.join("out").display().to_string();
    let output = posg_fsc(&[
        "solve",
        &game,
        "--ltl",
        "GF goal & G !unsafe",
        "--def-nodes",
        "2",
        "--out",
        &out,
        "--max-iterations",
        "200",
    ]);
    let summary = read(dir.join("out/summary.json"));
    let certified = summary.split("\"certified\": ").nth(1).unwrap();
    let (lower, upper) = (
        json_number(certified, "certified_lower"),
        json_number(certified, "upper_bound"),
    );
    let bracket = format!("[{lower:.6}, {upper:.6}]");
    let stdout = String::from_utf8(output.stdout).unwrap();
    assert!(
        stdout.contains(&format!("at least {lower:.6}")),
        "solve prints the bracket: {stdout}"
    );
    let svg = read(dir.join("out/curve.svg"));
    let texts = texts(&svg);
    assert!(
        texts.iter().any(|t| t == &bracket),
        "curve.svg lacks the returned bracket {bracket}: {texts:?}"
    );
    // The y tick labels: numbers with a decimal point, all different.
    let ticks: Vec<&String> = texts
        .iter()
        .filter(|t| t.contains('.') && t.parse::<f64>().is_ok())
        .collect();
    assert!(ticks.len() >= 3, "{texts:?}");
    let mut distinct = ticks.clone();
    distinct.sort();
    distinct.dedup();
    assert_eq!(
        distinct.len(),
        ticks.len(),
        "repeated tick labels: {ticks:?}"
    );
    let lines = String::from_utf8(output.stderr).unwrap();
    assert!(lines.contains("Won: "), "{lines}");
    assert!(!lines.contains("keeps 1 structures"), "{lines}");
}

#[test]
fn solve_writes_png_plots_with_format_png() {
    let dir = scratch("png");
    let game = grid(&dir);
    let out = dir.join("out").display().to_string();
    posg_fsc(&[
        "solve",
        &game,
        "--ltl",
        "F goal",
        "--def-nodes",
        "1",
        "--out",
        &out,
        "--max-iterations",
        "10",
        "--structures",
        "full",
        "--format",
        "png",
        "--size",
        "1000x600",
        "--dpi",
        "200",
    ]);
    let png = std::fs::read(dir.join("out/curve.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // The header chunk's width and height, big-endian.
    let dimension = |at: usize| u32::from_be_bytes(png[at..at + 4].try_into().unwrap());
    assert_eq!((dimension(16), dimension(20)), (1000, 600));
    // The pHYs chunk: 200 dots per inch are 7874 per metre.
    let phys = png.windows(4).position(|w| w == b"pHYs").unwrap();
    assert_eq!(dimension(phys + 4), 7874);
    assert!(!dir.join("out/curve.svg").exists());
    let summary = read(dir.join("out/summary.json"));
    assert!(summary.contains("\"curve.png\""), "{summary}");
}

#[test]
fn solve_help_shows_the_common_options_first_and_the_others_under_headings() {
    let output = posg_fsc(&["solve", "--help"]);
    let help = String::from_utf8(output.stdout).unwrap();
    // From "Options:" to the next heading (a line at the margin ending in ':').
    let common = help.split("\nOptions:\n").nth(1).unwrap();
    let end = common
        .match_indices('\n')
        .map(|(i, _)| i)
        .find(|&i| {
            let line = common[i + 1..].lines().next().unwrap_or("");
            !line.starts_with(' ') && line.ends_with(':')
        })
        .unwrap();
    let common = &common[..end];
    for option in [
        "--ltl",
        "--def-nodes",
        "--out",
        "--seed",
        "--starts",
        "--format",
    ] {
        assert!(
            common.contains(option),
            "{option} not among the first options:\n{help}"
        );
    }
    assert!(!common.contains("--lbfgs-memory"), "{help}");
    let position = |heading: &str| {
        help.find(&format!("\n{heading}:\n"))
            .unwrap_or_else(|| panic!("no heading {heading}:\n{help}"))
    };
    assert!(position("Options") < position("Stopping"));
    assert!(position("Stopping") < position("Linear solver"));
    assert!(
        !help.contains("Other options:"),
        "every option has its heading:\n{help}"
    );
}
