//! `posg-fsc demo`, the README's first command: on the paper's formula it
//! must prove that no 2-node support wins almost surely, find one that wins
//! positively, and certify a tuned defender better than the hand-made one.

use std::process::Command;

/// The number after `prefix` in `text` (the first occurrence after `from`).
fn number_after(text: &str, from: &str, prefix: &str) -> f64 {
    let rest = &text[text.find(from).expect(from)..];
    let rest = &rest[rest.find(prefix).expect(prefix) + prefix.len()..];
    let digits: String = rest
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    digits
        .trim_end_matches('.')
        .parse()
        .unwrap_or_else(|_| panic!("a number after {prefix:?}"))
}

#[test]
fn the_demo_finds_and_certifies_a_support_for_the_papers_formula() {
    let dir = std::env::temp_dir().join(format!("posg-fsc-demo-test-{}", std::process::id()));
    let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(["demo", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        text.contains("no 2-node support wins almost surely"),
        "{text}"
    );
    let positive = number_after(&text, "with positive probability", "certified at");
    assert!(positive > 0.0, "{text}");
    assert!(
        text.contains("allows every choice except:\n       node "),
        "{text}"
    );
    let tuned = number_after(&text, "2. The paper's formula", "Certified: at least");
    let upper = number_after(
        &text,
        "2. The paper's formula",
        "no defender gets more\n   than",
    );
    let hand_made = number_after(&text, "hand-made 2-node defender", "certified at");
    assert!(
        tuned > hand_made,
        "tuned {tuned} vs hand-made {hand_made}\n{text}"
    );
    assert!(tuned <= upper + 1e-9, "{text}");
    for file in [
        "reach-avoid/summary.json",
        "paper/summary.json",
        "paper/defender.dot",
    ] {
        assert!(dir.join(file).exists(), "{file} missing");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
