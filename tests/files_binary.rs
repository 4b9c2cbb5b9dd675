//! The optional binary game form `*.posg.bin` (formats.md section 11): JSON
//! -> binary -> read gives the identical `Posg` (grids, random games with
//! and without `enabled` maps, POMDPs); truncated, corrupt and inconsistent
//! files are errors naming the file, never panics; the commands read a
//! `.posg.bin` file as they read its JSON.

mod common;

use std::process::Command;

use posg_fsc::game::binary::{MAGIC, from_bytes, is_binary, to_bytes};
use posg_fsc::game::file::{from_json_str, read, to_json_string};
use posg_fsc::game::grid::{GridSpec, ObservationModel};
use posg_fsc::game::{AdversaryAction, DefenderAction, ModelError, Posg};
use proptest::prelude::*;

const FILE: &str = "t.posg.bin";

fn grid(observation: ObservationModel) -> Posg {
    GridSpec {
        width: 4,
        height: 3,
        observation,
        ..GridSpec::default()
    }
    .build()
    .unwrap()
}

/// The game read back from its JSON text, then from its binary form.
fn through_json_and_binary(game: &Posg) -> (Posg, Posg) {
    let from_json = from_json_str(&to_json_string(game), "t.posg.json").unwrap();
    let from_binary = from_bytes(&to_bytes(&from_json), FILE).unwrap();
    (from_json, from_binary)
}

fn error_of(bytes: &[u8]) -> ModelError {
    from_bytes(bytes, FILE).expect_err("the file should be rejected")
}

/// A two-state POMDP without a name, fully observed.
fn small_pomdp() -> Posg {
    from_json_str(
        r#"{"posg": 1, "states": ["a", "b"], "initial": {"a": 1.0},
            "labels": {"b": ["goal"]},
            "defender": {"actions": ["go"], "observe": "full"},
            "transitions": [{"state": "a", "defender": "go", "next": {"b": 0.25, "a": 0.75}},
                            {"state": "b", "defender": "go", "next": {"b": 1.0}}]}"#,
        "small.posg.json",
    )
    .unwrap()
}

#[test]
fn grids_read_back_identically() {
    for model in [ObservationModel::Neighbourhood, ObservationModel::Blind] {
        let (json, binary) = through_json_and_binary(&grid(model));
        assert_eq!(binary, json);
        assert_eq!(to_json_string(&binary), to_json_string(&json));
    }
}

#[test]
fn the_written_bytes_follow_the_documented_layout() {
    let bytes = to_bytes(&small_pomdp());
    let mut expected = MAGIC.to_vec();
    expected.extend(1u32.to_le_bytes()); // version
    expected.push(0); // no name
    expected.extend(2u32.to_le_bytes()); // two states
    for name in ["a", "b"] {
        expected.extend(1u32.to_le_bytes());
        expected.extend(name.as_bytes());
    }
    expected.extend(1u32.to_le_bytes()); // initial: one entry
    expected.extend(0u32.to_le_bytes());
    expected.extend(1.0f64.to_le_bytes());
    expected.extend(1u32.to_le_bytes()); // one proposition
    expected.extend(4u32.to_le_bytes());
    expected.extend(b"goal");
    expected.extend(0u32.to_le_bytes()); // L(a) = {}
    expected.extend(1u32.to_le_bytes()); // L(b) = {goal}
    expected.extend(0u32.to_le_bytes());
    expected.push(0); // no adversary
    expected.extend(1u32.to_le_bytes()); // defender: one action
    expected.extend(2u32.to_le_bytes());
    expected.extend(b"go");
    expected.extend(2u32.to_le_bytes()); // observations a, b
    for name in ["a", "b"] {
        expected.extend(1u32.to_le_bytes());
        expected.extend(name.as_bytes());
    }
    expected.push(1); // full observation
    expected.push(0); // every action enabled
    // T(. | a, go, _) sorted by successor, then T(. | b, go, _).
    for next in [vec![(0u32, 0.75f64), (1, 0.25)], vec![(1, 1.0)]] {
        expected.extend((next.len() as u32).to_le_bytes());
        for (s, q) in next {
            expected.extend(s.to_le_bytes());
            expected.extend(f64::to_le_bytes(q));
        }
    }
    assert_eq!(bytes, expected);
    assert_eq!(from_bytes(&bytes, FILE).unwrap(), small_pomdp());
}

#[test]
fn read_tells_the_forms_apart_by_the_magic_bytes() {
    let dir = std::env::temp_dir().join(format!("posg-fsc-binary-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let game = grid(ObservationModel::Neighbourhood);
    let path = dir.join("g.posg.bin");
    posg_fsc::game::binary::write(&path, &game).unwrap();
    assert!(is_binary(&std::fs::read(&path).unwrap()));
    assert_eq!(read(&path).unwrap(), through_json_and_binary(&game).0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_truncation_is_an_error_naming_the_file() {
    let bytes = to_bytes(&grid(ObservationModel::Blind));
    for len in 0..bytes.len() {
        let error = error_of(&bytes[..len]);
        assert!(error.path.starts_with(FILE), "{error}");
        if len >= MAGIC.len() {
            assert!(error.message.contains("ends early"), "{len}: {error}");
        }
    }
}

#[test]
fn trailing_bytes_and_other_versions_are_errors() {
    let mut bytes = to_bytes(&small_pomdp());
    bytes.push(0);
    assert!(error_of(&bytes).message.contains("1 bytes after the end"));
    let mut bytes = to_bytes(&small_pomdp());
    bytes[8] = 3;
    let error = error_of(&bytes);
    assert_eq!(error.path, format!("{FILE}: posg"));
    assert!(
        error
            .message
            .contains("unsupported format version 3 (expected 1 or 2)")
    );
}

/// The offset of the last transition's probability (the final 8 bytes).
fn last_probability(bytes: &[u8]) -> usize {
    bytes.len() - 8
}

#[test]
fn bad_distributions_are_errors_at_their_triple() {
    let good = to_bytes(&small_pomdp());
    let at = last_probability(&good);
    let mut bytes = good.clone();
    bytes[at..].copy_from_slice(&0.5f64.to_le_bytes());
    let error = error_of(&bytes);
    assert_eq!(error.path, format!("{FILE}: transitions[1]"));
    assert!(error.message.contains("sum to 0.5, not 1"), "{error}");
    bytes[at..].copy_from_slice(&f64::NAN.to_le_bytes());
    assert!(error_of(&bytes).message.contains("not in [0, 1]"));
    // The successor index of the last entry: out of range.
    bytes = good.clone();
    bytes[at - 4..at].copy_from_slice(&7u32.to_le_bytes());
    let error = error_of(&bytes);
    assert!(error.message.contains("state 7 out of range"), "{error}");
    // Within the tolerance: renormalised exactly as the JSON reader does.
    bytes = good;
    bytes[at..].copy_from_slice(&(1.0f64 - 1e-9).to_le_bytes());
    let game = from_bytes(&bytes, FILE).unwrap();
    assert_eq!(
        game.transition(1, DefenderAction(0), AdversaryAction(0)),
        &[(1, 1.0)]
    );
}

#[test]
fn huge_counts_are_errors_without_allocating() {
    let mut bytes = to_bytes(&small_pomdp());
    // The number of states.
    bytes[13..17].copy_from_slice(&u32::MAX.to_le_bytes());
    let error = error_of(&bytes);
    assert_eq!(error.path, format!("{FILE}: states"));
    assert!(
        error.message.contains("4294967295 items announced"),
        "{error}"
    );
}

#[test]
fn a_distribution_for_a_disabled_triple_is_an_error() {
    let game = from_json_str(&common::random::game_json_with_enabled(3), "e.posg.json").unwrap();
    let (nu, nv) = (
        game.defender().num_actions(),
        game.adversary().num_actions(),
    );
    let triple = |t: usize| {
        let (s, u, v) = (t / (nu * nv), t / nv % nu, t % nv);
        game.transition(s, DefenderAction(u), AdversaryAction(v))
    };
    let triples = game.num_states() * nu * nv;
    let t = (0..triples)
        .find(|&t| triple(t).is_empty())
        .expect("seed 3 disables some action");
    // The transitions end the file: re-encode them with {s0: 1} at `t`.
    let section: usize = (0..triples).map(|t| 4 + 12 * triple(t).len()).sum();
    let bytes = to_bytes(&game);
    let mut corrupt = bytes[..bytes.len() - section].to_vec();
    for i in 0..triples {
        let d = if i == t {
            vec![(0, 1.0)]
        } else {
            triple(i).to_vec()
        };
        corrupt.extend((d.len() as u32).to_le_bytes());
        for (o, p) in d {
            corrupt.extend((o as u32).to_le_bytes());
            corrupt.extend(p.to_le_bytes());
        }
    }
    let error = error_of(&corrupt);
    assert_eq!(error.path, format!("{FILE}: transitions[{t}]"));
    assert!(
        error
            .message
            .contains("no observation of the state enables"),
        "{error}"
    );
}

#[test]
fn the_commands_read_the_binary_form_like_the_json() {
    let dir = std::env::temp_dir().join(format!("posg-fsc-binary-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |args: &[&str]| {
        let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        String::from_utf8(output.stdout).unwrap()
    };
    let grid = [
        "example", "grid", "--width", "5", "--height", "4", "--goal", "s19",
    ];
    run(&[&grid[..], &["--out", "g.posg.json"]].concat());
    run(&[&grid[..], &["--binary", "--out", "g.posg.bin"]].concat());
    let check = |file: &str| run(&["check", file]);
    assert_eq!(check("g.posg.bin"), check("g.posg.json"));
    let eval = |file: &str| {
        let out = run(&[
            "eval",
            file,
            "--ltl",
            "!unsafe U goal",
            "--defender",
            "uniform:2",
        ]);
        let report: serde_json::Value = serde_json::from_str(&out).unwrap();
        report["value"].as_f64().unwrap()
    };
    assert_eq!(eval("g.posg.bin").to_bits(), eval("g.posg.json").to_bits());
    std::fs::remove_dir_all(&dir).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(11),
        ..ProptestConfig::with_cases(256)
    })]

    #[test]
    fn random_games_read_back_identically(seed in 0u64..1_000_000, enabled in any::<bool>()) {
        let text = if enabled {
            common::random::game_json_with_enabled(seed)
        } else {
            common::random::game_json(seed)
        };
        let game = from_json_str(&text, "r.posg.json").unwrap();
        prop_assert_eq!(from_bytes(&to_bytes(&game), FILE).unwrap(), game);
    }

    #[test]
    fn corrupt_bytes_never_panic(seed in 0u64..1000, at in 0usize..100_000, byte in any::<u8>()) {
        let game = from_json_str(&common::random::game_json_with_enabled(seed), "r.posg.json").unwrap();
        let mut bytes = to_bytes(&game);
        let i = at % bytes.len();
        bytes[i] = byte;
        if let Ok(read) = from_bytes(&bytes, FILE) {
            // A change the checks cannot see (a name's letter, a
            // probability's last bits) still gives a valid game.
            prop_assert!(from_bytes(&to_bytes(&read), FILE).is_ok());
        }
    }
}
