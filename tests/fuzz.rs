//! A bounded, seeded mutation fuzzer over the inputs (issues 13 and 57):
//! games in JSON (one with reward models) and in Storm's DRN (POMDPs, one
//! with SAYNT's labels and rewards, turn-based games: POSMG and SMG),
//! controllers, property files, HOA automata and LTL formulas,
//! mutated byte- and token-wise from valid seeds. Every mutant must give a
//! value or an error that names the input (file name, JSON path, line or
//! column), never a panic and never a huge allocation: a global allocator
//! notes each thread's largest request, which must stay below
//! [`MAX_ONE_ALLOCATION`] (the budgets of `posg_fsc::limits` stop large
//! inputs before they are allocated).
//!
//! The corpus `tests/data/fuzz-corpus/` holds the hand-found inputs of
//! issue 57, each replayed through the library with the exact result it
//! must give (and mutated as a seed): a byte-order mark, a DRN file
//! without `@type`, `@nr_states` of 10^12, `<<P>>` naming a player the
//! game lacks and `<<0>>` on a POMDP; and two inputs found while writing
//! this fuzzer: a HOA `States:` count far beyond its body (which allocated
//! a table of that many rows, 400 MB) and a `//` inside a property's
//! quoted name (which was cut as a comment). The 10^6 x 10^6 grid and
//! durations of 1e20 and 1e308 seconds are replayed through the library
//! below; the CLI side of the issue's cases is in `tests/bad_input.rs`,
//! and the parser of durations has its unit tests in `src/seconds.rs`.
//!
//! Under a second in release; `FUZZ_SCALE=N` multiplies the number of
//! mutants for a longer search.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::Write;
use std::panic::{AssertUnwindSafe, catch_unwind};

use posg_fsc::controller::Role;
use posg_fsc::game::ModelError;
use posg_fsc::game::drn::{DrnOptions, from_drn_str, from_drn_str_with};
use posg_fsc::ltl::TranslationBudget;
use posg_fsc::ltl::props::from_props_str;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// The largest single allocation a reader may request for one mutant (a
/// few hundred bytes of text): 64 MiB, far above what a small input needs
/// and far below a table sized by a number the input declares.
const MAX_ONE_ALLOCATION: usize = 64 << 20;

/// A request this large is refused outright (the process aborts, after
/// printing the input), so that a runaway cannot exhaust the machine.
const REFUSED_ALLOCATION: usize = 4 << 30;

/// The system allocator, noting each thread's largest single request.
struct Largest;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
    /// The bytes this thread has requested in all (never decreased).
    static TOTAL: Cell<usize> = const { Cell::new(0) };
    /// The input being checked on this thread (pointer, length), for the
    /// message of a refused allocation.
    static INPUT: Cell<(*const u8, usize)> = const { Cell::new((std::ptr::null(), 0)) };
}

/// Notes a request of `size` bytes; `false` if it is to be refused.
fn note(size: usize) -> bool {
    let _ = LARGEST.try_with(|largest| largest.set(largest.get().max(size)));
    let _ = TOTAL.try_with(|total| total.set(total.get().saturating_add(size)));
    if size < REFUSED_ALLOCATION {
        return true;
    }
    let (at, len) = INPUT.try_with(Cell::get).unwrap_or((std::ptr::null(), 0));
    let mut stderr = std::io::stderr().lock();
    let _ = writeln!(
        stderr,
        "fuzz: refused an allocation of {size} bytes on the input:"
    );
    if !at.is_null() {
        // SAFETY: `without_panics` sets INPUT to a live `&str` for the
        // duration of the check and clears it after.
        let _ = stderr.write_all(unsafe { std::slice::from_raw_parts(at, len) });
    }
    false
}

// SAFETY: every call goes to `System` unchanged, or fails as an allocator
// may (a null pointer).
unsafe impl GlobalAlloc for Largest {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if !note(layout.size()) {
            return std::ptr::null_mut();
        }
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if !note(layout.size()) {
            return std::ptr::null_mut();
        }
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if !note(new_size) {
            return std::ptr::null_mut();
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Largest = Largest;

const GRID: &str = include_str!("data/valid/grid-3x2.posg.json");
/// A game with reward models, wildcards in their `actions`.
const REWARDED: &str = include_str!("data/valid/rewarded-pennies.posg.json");
const HOA: &[&str] = &[
    include_str!("data/ltl/examples/fg_stable.dra.hoa"),
    include_str!("data/ltl/examples/gfa_and_gfb.dgra.hoa"),
    include_str!("data/ltl/examples/spot_fga_or_gfb.dpa.hoa"),
];
const FORMULAS: &[&str] = &[
    "GF goal & G !unsafe",
    "G(a -> F b) & G(c -> F d)",
    "(F a) U (b W c)",
    "!(a xor b xor c) <-> X X d",
    "FG a | GF b R c",
];

/// Tokens that stress the readers: huge, negative, non-finite and
/// fractional numbers, wildcards, brackets, operators.
const TOKENS: &[&str] = &[
    "1e308",
    "-1",
    "0",
    "4294967296",
    "18446744073709551616",
    "NaN",
    "\"*\"",
    "\"\"",
    "null",
    "[]",
    "{}",
    ",",
    ":",
    "0.5",
    "1e-300",
    "999999999",
    "(",
    ")",
    "U",
    "X",
    "!",
    "^",
    "<->",
    "\"s0\"",
    "\"uniform\"",
    "Acceptance:",
    "States: 1000000",
    "AP: 16",
    "--BODY--",
];

/// One random edit of `text`: delete, duplicate or swap a span, or insert
/// or substitute a token.
fn mutate(text: &str, rng: &mut StdRng, tokens: &[&str]) -> String {
    let chars: Vec<char> = text.chars().collect();
    let n = chars.len().max(1);
    let at = rng.random_range(0..n);
    let span = rng.random_range(1..=8.min(n));
    let end = (at + span).min(chars.len());
    let token: Vec<char> = tokens[rng.random_range(0..tokens.len())].chars().collect();
    let mut out: Vec<char> = Vec::with_capacity(chars.len() + 32);
    match rng.random_range(0..5) {
        0 => {
            out.extend(&chars[..at.min(chars.len())]);
            out.extend(&chars[end..]);
        }
        1 => {
            out.extend(&chars[..end]);
            out.extend(&chars[at.min(chars.len())..end]);
            out.extend(&chars[end..]);
        }
        2 => {
            out.extend(&chars[..at.min(chars.len())]);
            out.extend(&token);
            out.extend(&chars[at.min(chars.len())..]);
        }
        3 => {
            out.extend(&chars[..at.min(chars.len())]);
            out.extend(&token);
            out.extend(&chars[end..]);
        }
        _ => {
            let other = rng.random_range(0..n);
            out.extend(&chars);
            let last = out.len().saturating_sub(1);
            if !out.is_empty() {
                out.swap(at.min(last), other.min(last));
            }
        }
    }
    out.into_iter().collect()
}

/// Mutants of `seed` with 1 to 3 edits each, inserting [`TOKENS`].
fn mutants(seed: &str, count: usize, stream: u64) -> impl Iterator<Item = String> {
    mutants_with(seed, count, stream, TOKENS)
}

/// Mutants of `seed` with 1 to 3 edits each, inserting `tokens`: `count`
/// of them, times `FUZZ_SCALE` if set (`FUZZ_SCALE=100 cargo test
/// --release --test fuzz` for a longer search, whose first `count` are
/// those of the default run).
fn mutants_with<'a>(
    seed: &'a str,
    count: usize,
    stream: u64,
    tokens: &'a [&'a str],
) -> impl Iterator<Item = String> + 'a {
    let scale: usize = std::env::var("FUZZ_SCALE").map_or(1, |s| s.parse().expect("FUZZ_SCALE"));
    let mut rng = StdRng::seed_from_u64(0x5eed_0000 + stream);
    (0..count * scale).map(move |_| {
        let edits = rng.random_range(1..=3);
        (0..edits).fold(seed.to_string(), |text, _| mutate(&text, &mut rng, tokens))
    })
}

/// Runs `check` on every mutant, failing on a panic or on an allocation
/// above [`MAX_ONE_ALLOCATION`], with the mutant shown.
fn without_panics(inputs: impl IntoIterator<Item = String>, check: impl Fn(&str)) {
    for input in inputs {
        let input = input.as_str();
        let largest = largest_allocation(input, || {
            if catch_unwind(AssertUnwindSafe(|| check(input))).is_err() {
                panic!("panic on the input:\n{input}");
            }
        });
        assert!(
            largest <= MAX_ONE_ALLOCATION,
            "an allocation of {largest} bytes on the input:\n{input}"
        );
    }
}

/// Runs `run` on `input` and returns the largest single allocation this
/// thread requested meanwhile.
fn largest_allocation(input: &str, run: impl FnOnce()) -> usize {
    /// Clears INPUT when the check ends, even by a panic.
    struct Checking;
    impl Drop for Checking {
        fn drop(&mut self) {
            INPUT.with(|current| current.set((std::ptr::null(), 0)));
        }
    }
    INPUT.with(|current| current.set((input.as_ptr(), input.len())));
    let checking = Checking;
    LARGEST.with(|largest| largest.set(0));
    run();
    drop(checking);
    LARGEST.with(Cell::get)
}

#[test]
fn mutated_games_are_read_or_refused_with_the_file_and_path() {
    for (k, (seed, count)) in [(GRID, 1500), (REWARDED, 600)].into_iter().enumerate() {
        without_panics(mutants(seed, count, 1 + 100 * k as u64), |text| {
            match posg_fsc::game::file::from_json_str(text, "fuzz.posg.json") {
                Ok(game) => assert_valid(&game),
                Err(error) => assert!(error.to_string().contains("fuzz.posg.json"), "{error}"),
            }
        });
    }
}

#[test]
fn mutated_controllers_are_read_or_refused_with_the_file_and_path() {
    let game = posg_fsc::game::file::from_json_str(GRID, "grid.posg.json").unwrap();
    let valid = posg_fsc::controller::file::resolve("uniform:2", &game, Role::Defender).unwrap();
    let text = posg_fsc::controller::file::to_json_string(&valid, &game);
    without_panics(mutants(&text, 1500, 2), |text| {
        let read =
            posg_fsc::controller::file::from_json_str(text, "fuzz.fsc.json", &game, Role::Defender);
        if let Err(error) = read {
            assert!(error.to_string().contains("fuzz.fsc.json"), "{error}");
        }
    });
}

#[test]
fn mutated_automata_are_read_or_refused_with_a_position() {
    let corpus = corpus_file("hoa-states-beyond-the-body.hoa");
    for (k, seed) in HOA.iter().copied().chain([corpus.as_str()]).enumerate() {
        without_panics(mutants(seed, 500, 10 + k as u64), |text| {
            if let Err(error) = posg_fsc::automaton::read_hoa_dra(text) {
                let message = error.to_string();
                let located = message.contains("line ")
                    || message.contains("automaton")
                    || message.contains("propositions");
                assert!(located, "{message}");
            }
        });
    }
}

#[test]
fn mutated_formulas_are_translated_or_refused_with_a_column_or_subformula() {
    let budget = TranslationBudget { seconds: 0.5 };
    for (k, seed) in FORMULAS.iter().enumerate() {
        without_panics(
            mutants(seed, 60, 20 + k as u64),
            |text| match posg_fsc::ltl::parse(text) {
                Err(error) => assert!(error.to_string().contains("column"), "{error}"),
                Ok(formula) => {
                    let _ = posg_fsc::ltl::translate_within(&formula, &budget);
                }
            },
        );
    }
}

#[test]
fn a_very_long_left_nested_chain_neither_overflows_nor_hangs() {
    let chain = vec!["a"; 25_000].join(" ^ ");
    let formula = posg_fsc::ltl::parse(&chain).unwrap();
    let dra = posg_fsc::ltl::translate(&formula).unwrap();
    // An even number of `a`: false, a single rejecting state.
    assert!(!dra.accepts_lasso(&[], &[1]) && !dra.accepts_lasso(&[], &[0]));
    let nested = vec!["F a"; 25_000].join(" ^ ");
    let error = posg_fsc::ltl::translate(&posg_fsc::ltl::parse(&nested).unwrap()).unwrap_err();
    assert!(error.to_string().contains("xor"), "{error}");
    let implications = vec!["a"; 25_000].join(" -> ");
    let error = posg_fsc::ltl::parse(&implications).unwrap_err();
    assert!(error.to_string().contains("column"), "{error}");
}

const COIN: &str = include_str!("data/drn/coin.drn");
const PENNIES: &str = include_str!("data/drn/pennies.drn");
const PAYNT_GAME: &str = include_str!("data/paynt/test-game.drn");
/// SAYNT-style labels `(n)` and two reward models.
const REWARDS: &str = include_str!("data/drn/rewards.drn");

/// Tokens of DRN: header lines, state, action and transition lines, their
/// annotations, and numbers too large for the tables they size.
const DRN_TOKENS: &[&str] = &[
    "@type: SMG",
    "@type: POSMG",
    "@type: MDP",
    "@type: DTMC",
    "@type: CTMC",
    "@value_type: interval",
    "@parameters\np",
    "@placeholders",
    "@reward_models\nr",
    "@reward_models\nr r",
    "@reward_models\n\n",
    "action (init)",
    "(n)",
    "[-0.04]",
    "[1/0]",
    "[inf, 1]",
    ", -1e400",
    "@nr_states\n1000000000000",
    "@nr_choices\n4294967296",
    "@model",
    "\nstate 1 {0} <0> init\n",
    "state 99",
    "\n\taction a\n",
    "action __NOLABEL__",
    "action _",
    "\t\t0 : 1\n",
    "1/0",
    "0/0",
    "1/3",
    "1e308",
    "-0.5",
    "NaN",
    "{",
    "}",
    "<",
    ">",
    "<2>",
    "<18446744073709551616>",
    "{18446744073709551615}",
    "[",
    "]",
    "[1, 2]",
    "\"",
    "init",
    "deadlock",
    "Goal",
    "\n",
    "//",
    "\u{feff}",
    "é",
    "4294967296",
    "0",
    ":",
];

/// The errors about a DRN model as a whole, which name the file but no
/// line: nothing before `@model`, no initial state, a defender player who
/// owns no state or a player given for a model without players.
const DRN_WHOLE_FILE: &[&str] = &[
    "the file ends before `@model`",
    "no state is labelled `init`",
    "the defender, player <",
    "a defender player (1) applies to turn-based games (SMG, POSMG) only; this ",
];

/// Checks that `error`, from reading `text` as the DRN file `file`, names
/// `file` and one of its lines (`FILE: line N`), or is about the model as
/// a whole ([`DRN_WHOLE_FILE`]).
fn assert_drn_error_located(error: &ModelError, text: &str, file: &str) {
    if error.path == file {
        assert!(
            DRN_WHOLE_FILE.iter().any(|m| error.message.starts_with(m)),
            "no line: {error}"
        );
        return;
    }
    let line: usize = error
        .path
        .strip_prefix(file)
        .and_then(|rest| rest.strip_prefix(": line "))
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("not `{file}: line N`: {error}"));
    assert!(
        (1..=text.lines().count()).contains(&line),
        "line {line} is not a line of the file: {error}"
    );
}

/// Checks that a game read from DRN is valid: it is written as JSON and
/// read back (with every check of the game format) unchanged.
fn assert_valid(game: &posg_fsc::game::Posg) {
    let json = posg_fsc::game::file::to_json_string(game);
    let back = posg_fsc::game::file::from_json_str(&json, "back.posg.json")
        .unwrap_or_else(|error| panic!("the game read is not valid: {error}"));
    assert!(&back == game, "the game changed when written and read back");
}

#[test]
fn mutated_drn_models_are_read_or_refused_with_the_file_and_line() {
    let corpus = ["smg.drn", "bom.drn", "no-type.drn", "huge-nr-states.drn"].map(corpus_file);
    let seeds = [
        (COIN, 600),
        (PENNIES, 600),
        (PAYNT_GAME, 600),
        (REWARDS, 600),
    ]
    .into_iter()
    .chain(corpus.iter().map(|text| (text.as_str(), 150)));
    let player_1 = DrnOptions {
        defender_player: Some(1),
        defender_source: None,
    };
    for (k, (seed, count)) in seeds.enumerate() {
        without_panics(
            mutants_with(seed, count, 30 + k as u64, DRN_TOKENS),
            |text| {
                for options in [&DrnOptions::default(), &player_1] {
                    match from_drn_str_with(text, "fuzz.drn", None, options) {
                        Ok(import) => assert_valid(&import.game),
                        Err(error) => assert_drn_error_located(&error, text, "fuzz.drn"),
                    }
                }
            },
        );
    }
}

const PROPS: &[&str] = &[
    "Pmax=? [\"notbad\" U \"goal\"]",
    "<<0>> Pmax=? [F \"goal\"]",
    "Pmin=? [F \"goal\"]",
    "P>=0.5 [G !\"bad\"]",
    "// the defender, player 1, avoids the goal\n\n\"safe\": <<1>> Pmin=? [ F \"goal\" ] // why\n",
];

/// Tokens of property files: coalitions, queries, brackets, comments.
const PROPS_TOKENS: &[&str] = &[
    "<<",
    ">>",
    "<<1>>",
    "<<5>>",
    "<<18446744073709551616>>",
    "Pmax=?",
    "Pmin=?",
    "P=?",
    "R{\"r\"}max=?",
    "T",
    "[",
    "]",
    "\"",
    "\"goal\"",
    ":",
    "//",
    "\n",
    "F<=10",
    "U",
    "G",
    "X",
    "!",
    "&",
    "->",
    "1e308",
    "-1",
    "é",
    "\u{feff}",
    " ",
];

/// Checks that line `line`, column `column` (both 1-based, the column in
/// characters) is in `text`, or just after the end of its line.
fn assert_in_text(text: &str, line: usize, column: usize, what: &str) {
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        (1..=lines.len().max(1)).contains(&line),
        "line {line} is not in the file: {what}"
    );
    let width = lines.get(line - 1).map_or(0, |l| l.chars().count());
    assert!(
        (1..=width + 1).contains(&column),
        "column {column} is not in line {line}: {what}"
    );
}

#[test]
fn mutated_props_are_read_or_refused_with_the_file_line_and_column() {
    let corpus = [
        "comment-in-a-name.props",
        "player-5.props",
        "pomdp-player-0.props",
    ]
    .map(corpus_file);
    let seeds = PROPS
        .iter()
        .copied()
        .chain(corpus.iter().map(String::as_str));
    for (k, seed) in seeds.enumerate() {
        without_panics(
            mutants_with(seed, 400, 40 + k as u64, PROPS_TOKENS),
            |text| match from_props_str(text, "fuzz.props") {
                Err(error) => {
                    let position = error
                        .path
                        .strip_prefix("fuzz.props: line ")
                        .and_then(|rest| rest.split_once(", column "))
                        .and_then(|(l, c)| Some((l.parse().ok()?, c.parse().ok()?)));
                    let (line, column) = position
                        .unwrap_or_else(|| panic!("not `fuzz.props: line L, column C`: {error}"));
                    assert_in_text(text, line, column, &error.to_string());
                }
                Ok(property) => {
                    let at = property.position("fuzz.props");
                    assert_in_text(text, property.line, property.column, &at);
                    assert_query_player(&property, &at);
                }
            },
        );
    }
}

/// Reads the turn-based `pennies.drn` and the POMDP `coin.drn` with the
/// query's player as the CLI does (`<<P>>` the defender, its errors at the
/// query's position): each refusal names that position and the game.
fn assert_query_player(property: &posg_fsc::ltl::props::Property, at: &str) {
    let options = DrnOptions {
        defender_player: property.player,
        defender_source: property.player.map(|_| at.to_string()),
    };
    let pennies = from_drn_str_with(PENNIES, "pennies.drn", None, &options);
    let coin = from_drn_str_with(COIN, "coin.drn", None, &options);
    match property.player {
        None | Some(0 | 1) => assert!(pennies.is_ok(), "{pennies:?}"),
        Some(p) => assert_eq!(
            pennies.unwrap_err().to_string(),
            format!(
                "{at}: in pennies.drn, the defender, player <{p}>, owns no state \
                 (the states belong to <1> and <0>)"
            )
        ),
    }
    match property.player {
        None => assert!(coin.is_ok(), "{coin:?}"),
        Some(p) => assert_eq!(
            coin.unwrap_err().to_string(),
            format!(
                "{at}: in coin.drn, a defender player ({p}) applies to turn-based games \
                 (SMG, POSMG) only; this POMDP has no players"
            )
        ),
    }
}

const CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/fuzz-corpus");

/// The text of the corpus file `name`.
fn corpus_file(name: &str) -> String {
    std::fs::read_to_string(format!("{CORPUS}/{name}")).unwrap()
}

/// One file of the corpus and what replaying it must give.
struct Replay {
    /// The file's name in `tests/data/fuzz-corpus/`.
    file: &'static str,
    /// For a property file, the DRN game (name, text) it is applied to.
    game: Option<(&'static str, &'static str)>,
    /// `Ok(())` (read), or the exact error.
    expected: Result<(), &'static str>,
}

/// The corpus (`tests/data/fuzz-corpus/`), each file with its result.
const REPLAYED: &[Replay] = &[
    Replay {
        file: "bom.drn",
        game: None,
        expected: Ok(()),
    },
    Replay {
        file: "smg.drn",
        game: None,
        expected: Ok(()),
    },
    Replay {
        file: "no-type.drn",
        game: None,
        expected: Err(
            "no-type.drn: line 4: this DRN file's header has no `@type` line \
             (for example `@type: POMDP`) before `@model`",
        ),
    },
    Replay {
        file: "huge-nr-states.drn",
        game: None,
        expected: Err(
            "huge-nr-states.drn: line 4: @nr_states declares 1000000000000 states, \
             the model has 2",
        ),
    },
    Replay {
        file: "hoa-states-beyond-the-body.hoa",
        game: None,
        expected: Err(
            "line 11, column 1: incomplete automaton: state 1 has no edge on letter t \
             (there are no propositions)",
        ),
    },
    Replay {
        file: "comment-in-a-name.props",
        game: Some(("pennies.drn", PENNIES)),
        expected: Ok(()),
    },
    Replay {
        file: "player-5.props",
        game: Some(("pennies.drn", PENNIES)),
        expected: Err(
            "player-5.props: line 2, column 1: in pennies.drn, the defender, player <5>, \
             owns no state (the states belong to <1> and <0>)",
        ),
    },
    Replay {
        file: "pomdp-player-0.props",
        game: Some(("coin.drn", COIN)),
        expected: Err(
            "pomdp-player-0.props: line 1, column 1: in coin.drn, a defender player (0) \
             applies to turn-based games (SMG, POSMG) only; this POMDP has no players",
        ),
    },
];

/// Reads the corpus file `name` (a DRN model, an automaton in HOA, or a
/// property file applied to `game` as the CLI applies `--props`).
fn replay(name: &str, game: Option<(&str, &str)>) -> Result<(), String> {
    let text = corpus_file(name);
    if name.ends_with(".hoa") {
        return posg_fsc::automaton::read_hoa_dra(&text)
            .map(|_| ())
            .map_err(|e| e.to_string());
    }
    let Some((game_name, game)) = game else {
        let import = from_drn_str(&text, name, None).map_err(|e| e.to_string())?;
        assert_valid(&import.game);
        return Ok(());
    };
    let property = from_props_str(&text, name).map_err(|e| e.to_string())?;
    let options = DrnOptions {
        defender_player: property.player,
        defender_source: Some(property.position(name)),
    };
    let import = from_drn_str_with(game, game_name, None, &options).map_err(|e| e.to_string())?;
    assert_valid(&import.game);
    Ok(())
}

#[test]
fn the_corpus_of_hand_found_inputs_gives_its_exact_results() {
    for case in REPLAYED {
        let name = case.file;
        let mut result = Ok(());
        let largest = largest_allocation(name, || result = replay(name, case.game));
        assert_eq!(result, case.expected.map_err(str::to_string), "{name}");
        assert!(largest <= MAX_ONE_ALLOCATION, "{name}: {largest} bytes");
    }
    // The byte-order mark is read as if absent.
    let bom = corpus_file("bom.drn");
    assert!(bom.starts_with('\u{feff}'));
    let with = from_drn_str(&bom, "bom.drn", None).unwrap();
    let without = from_drn_str(&bom['\u{feff}'.len_utf8()..], "bom.drn", None).unwrap();
    assert_eq!(with, without);
    // Every file of the corpus is replayed.
    let mut files: Vec<String> = std::fs::read_dir(CORPUS)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let mut listed: Vec<&str> = REPLAYED.iter().map(|case| case.file).collect();
    listed.sort();
    assert_eq!(files, listed, "a corpus file is not in REPLAYED");
}

/// Issue 57: a 10^6 x 10^6 grid (and sizes whose product overflows) is
/// refused through the library's builder before anything is allocated,
/// with its size and the limit (the CLI's `example grid` in
/// tests/bad_input.rs).
#[test]
fn huge_grids_are_refused_with_their_size_and_the_limit_before_allocation() {
    use posg_fsc::game::grid::GridSpec;
    let cases = [
        (
            1_000_000,
            1_000_000,
            "1000000000000 states",
            "8000000000000",
        ),
        (
            usize::MAX,
            usize::MAX,
            "18446744073709551615 states",
            "147573952589676412920",
        ),
        (
            1 << 32,
            1 << 32,
            "18446744073709551615 states",
            "147573952589676412920",
        ),
        (
            usize::MAX,
            1,
            "18446744073709551615 states",
            "147573952589676412920",
        ),
    ];
    for (width, height, states, triples) in cases {
        let spec = GridSpec {
            width,
            height,
            ..GridSpec::default()
        };
        let mut result = None;
        let largest = largest_allocation("grid", || result = Some(spec.build()));
        let message = result.unwrap().unwrap_err().to_string();
        assert_eq!(
            message,
            format!(
                "grid: a {width}x{height} grid: {states} x 4 defender actions x 2 adversary \
                 actions would need {triples} transition triples, above the budget of 50000000 \
                 (posg_fsc::limits::MAX_TRANSITION_TRIPLES); use a smaller input"
            )
        );
        assert!(largest <= 1 << 20, "{width}x{height}: {largest} bytes");
    }
}

/// Durations as users type them (seeds 1e20 and 1e308 of issue 57, whose
/// conversion to a `Duration` or a deadline panicked): every mutant is a
/// budget whose deadline is computed without a panic, or refused naming
/// the text or the value.
#[test]
fn mutated_durations_are_budgets_or_refused_by_value_never_a_panic() {
    let tokens = [
        "9", "0", "e", "e3", "e30", "e308", "-", ".", "inf", "NaN", " ", "1e19",
    ];
    let now = std::time::Instant::now();
    for (k, seed) in ["1e20", "1e308", "0.5", "18446744073709551616"]
        .iter()
        .enumerate()
    {
        without_panics(mutants_with(seed, 200, 50 + k as u64, &tokens), |text| {
            match posg_fsc::seconds::parse(text) {
                Ok(seconds) => {
                    // Within a few years a deadline; beyond a `Duration`
                    // (2^64 seconds), none: no limit.
                    let deadline = posg_fsc::seconds::deadline(now, seconds);
                    if seconds > 0.0 && seconds < 1e8 {
                        assert!(deadline.is_some(), "{text}");
                    } else if seconds == 0.0 || seconds >= 2f64.powi(64) {
                        assert!(deadline.is_none(), "{text}");
                    }
                }
                Err(message) => assert!(
                    message == format!("'{text}' is not a number of seconds")
                        || message
                            .starts_with("must be a finite, non-negative number of seconds, got "),
                    "{message}"
                ),
            }
        });
    }
}

/// The bytes this thread requests in all while `run` runs.
fn total_allocation(run: impl FnOnce()) -> usize {
    let before = TOTAL.with(Cell::get);
    run();
    TOTAL.with(Cell::get) - before
}

/// A DRN MDP of `states` states, each with one unannotated choice, whose
/// `@reward_models` line is `header`.
fn drn_without_rewards(header: &str, states: usize) -> String {
    let mut text = format!("@type: MDP\n@reward_models\n{header}\n@nr_states\n{states}\n@model\n");
    for k in 0..states {
        let init = if k == 0 { " init" } else { "" };
        text += &format!("state {k}{init}\n\taction a\n\t\t{k} : 1\n");
    }
    text
}

/// Issue 60's review: many reward models without a single non-zero value
/// took a state vector and a choice vector each (10^4 states x 500 models
/// were 120 MB); now they take only the room of their names.
#[test]
fn declared_reward_models_without_values_take_no_room_per_state() {
    let names: Vec<String> = (0..500).map(|i| format!("m{i}")).collect();
    let plain = drn_without_rewards("", 10_000);
    let declared = drn_without_rewards(&names.join(" "), 10_000);
    let read = |text: &str| {
        total_allocation(|| {
            let game = from_drn_str(text, "m.drn", None).unwrap().game;
            assert!(game.reward_models().len() <= 500);
        })
    };
    let (without, with) = (read(&plain), read(&declared));
    assert!(
        with < without + (1 << 20),
        "{with} bytes with 500 empty reward models, {without} without"
    );
}

/// A JSON game of `states` states, one action each, with `models` reward
/// models `{"states": {}}`.
fn json_with_empty_reward_models(states: usize, models: usize) -> String {
    let names: Vec<String> = (0..states).map(|k| format!("\"s{k}\"")).collect();
    let transitions: Vec<String> = (0..states)
        .map(|k| format!("{{\"state\": \"s{k}\", \"defender\": \"*\", \"next\": {{\"s{k}\": 1}}}}"))
        .collect();
    let rewards: Vec<String> = (0..models)
        .map(|i| format!("\"m{i}\": {{\"states\": {{}}, \"actions\": []}}"))
        .collect();
    format!(
        "{{\"posg\": 1, \"states\": [{}], \"initial\": {{\"s0\": 1}}, \
         \"defender\": {{\"actions\": [\"a\"], \"observe\": \"full\"}}, \
         \"transitions\": [{}], \"rewards\": {{{}}}}}",
        names.join(", "),
        transitions.join(", "),
        rewards.join(", ")
    )
}

/// The same from JSON: `"m": {"states": {}}` took a vector of every state.
#[test]
fn empty_json_reward_models_take_no_room_per_state() {
    let read = |text: &str| {
        total_allocation(|| {
            posg_fsc::game::file::from_json_str(text, "m.posg.json").unwrap();
        })
    };
    let without = read(&json_with_empty_reward_models(10_000, 0));
    let with = read(&json_with_empty_reward_models(10_000, 500));
    assert!(
        with < without + (1 << 20),
        "{with} bytes with 500 empty reward models, {without} without"
    );
}

/// A binary game's count of reward models reserved room for that many
/// models (about 10 times the bytes the count needs); a count backed by
/// zeros now fails on the first model's empty name, having reserved little.
#[test]
fn a_binary_count_of_reward_models_reserves_little_room() {
    let text = include_str!("data/drn/rewards.drn");
    let game = from_drn_str(text, "m.drn", None).unwrap().game;
    let bytes = posg_fsc::game::binary::to_bytes(&game);
    let name = [&6u32.to_le_bytes()[..], b"reward"].concat();
    let at = bytes.windows(name.len()).position(|w| w == name).unwrap() - 4;
    let padding = 1 << 20;
    let mut hostile = bytes[..at].to_vec();
    hostile.extend_from_slice(&((padding / 9) as u32).to_le_bytes());
    hostile.resize(hostile.len() + padding, 0);
    let input = String::from_utf8_lossy(&hostile[..at]).into_owned();
    let largest = largest_allocation(&input, || {
        let error = posg_fsc::game::binary::from_bytes(&hostile, "t.posg.bin").unwrap_err();
        assert!(
            error.to_string().starts_with("t.posg.bin: rewards[0]: ``"),
            "{error}"
        );
    });
    // The transitions reserve room by the bytes left (1.3 times them); the
    // models' room was 10 times.
    assert!(largest < 2 * padding, "{largest} bytes in one allocation");
}
