//! The refutation of one-block changes of the defender
//! (`posg_fsc::certify::refutation`): no refuted change raises the
//! certified lower bound, on random games, automata and controllers, and
//! on a game made for the condition on bottom components.

mod common;

use common::random;
use posg_fsc::automaton::Dra;
use posg_fsc::certify::lower_bound_within;
use posg_fsc::certify::refutation::Refuter;
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::game::file::from_json_str;
use posg_fsc::value::SolverSettings;

/// The settings the local search ranks its moves with: no exact solve, no
/// optimality certificate.
fn ranking() -> SolverSettings {
    SolverSettings {
        exact_limit: 0,
        prove_optimum: false,
        ..SolverSettings::default()
    }
}

/// The lower bound of `defender`, solved.
fn bound(game: &Posg, not_phi: &Dra, defender: &Fsc) -> f64 {
    lower_bound_within(game, not_phi, defender, &ranking())
        .unwrap()
        .value
}

/// The blocks of `fsc`, `(g, o)` at `g |O| + o`.
fn blocks(fsc: &Fsc) -> Vec<Vec<Choice>> {
    let observations = fsc.num_observations();
    (0..fsc.num_nodes() * observations)
        .map(|b| fsc.choices(b / observations, b % observations).to_vec())
        .collect()
}

/// `defender` with block `b` playing `choices`.
fn with_block(defender: &Fsc, b: usize, choices: Vec<Choice>) -> Fsc {
    let mut changed = blocks(defender);
    changed[b] = choices;
    let (nodes, observations) = (defender.num_nodes(), defender.num_observations());
    let (role, initial) = (defender.role(), defender.initial().to_vec());
    Fsc::new(
        role,
        nodes,
        observations,
        defender.num_actions(),
        initial,
        changed,
    )
    .unwrap()
}

/// `pair` played surely.
fn surely(pair: &Choice) -> Vec<Choice> {
    vec![Choice {
        probability: 1.0,
        logit: None,
        ..*pair
    }]
}

/// The one-block moves of the local search in block `b`: each enabled
/// pair of `universe` played surely, and each choice of `defender`'s
/// block dropped (the others renormalised).
fn moves(defender: &Fsc, universe: &Fsc, b: usize) -> Vec<Vec<Choice>> {
    let block = &blocks(defender)[b];
    let drops = (0..block.len()).filter(|_| block.len() > 1).map(|dropped| {
        let kept: Vec<Choice> = (block.iter().enumerate())
            .filter(|&(i, _)| i != dropped)
            .map(|(_, c)| *c)
            .collect();
        let total: f64 = kept.iter().map(|c| c.probability).sum();
        (kept.into_iter())
            .map(|c| Choice {
                probability: c.probability / total,
                ..c
            })
            .collect()
    });
    let pairs = &blocks(universe)[b];
    pairs.iter().map(surely).chain(drops).collect()
}

/// On random games (noisy observations, exact zeros, 1-3 actions per
/// player), random Rabin automata or those of `!phi` for reachability,
/// until, recurrence, persistence and safe recurrence objectives, and
/// random 2-node defenders (some with an initial distribution over both
/// nodes), no refuted move raises the
/// solved lower bound by more than the rounding of the two solves; the
/// refutation refutes moves, and leaves moves that raise the bound.
#[test]
fn no_refuted_move_raises_the_bound_on_random_games() {
    let formulas = [
        "F goal",
        "!unsafe U goal",
        "GF goal",
        "F G !unsafe",
        "GF goal & G !unsafe",
    ];
    let (mut refuted, mut raising) = (0, 0);
    for seed in 0..150 {
        let game = from_json_str(&random::game_json(seed), "random.posg.json").unwrap();
        let not_phi = match formulas.get(seed as usize % 10) {
            Some(formula) => common::automata(formula).1,
            None => random::dra(seed),
        };
        let defender = random::controller_with_nodes(seed, &game, Role::Defender, 2);
        let universe = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
        let before = bound(&game, &not_phi, &defender);
        let refuter = Refuter::new(&game, &not_phi, &defender, &ranking()).unwrap();
        for b in 0..blocks(&defender).len() {
            for choices in moves(&defender, &universe, b) {
                let changed = with_block(&defender, b, choices);
                let after = bound(&game, &not_phi, &changed);
                if refuter.refutes(&changed, b) {
                    refuted += 1;
                    assert!(
                        after <= before + 1e-9,
                        "seed {seed}, block {b}: {before} -> {after}"
                    );
                } else if after > before + 1e-6 {
                    raising += 1;
                }
            }
        }
    }
    assert!(
        refuted > 1000 && raising > 40,
        "{refuted} refuted, {raising} raising"
    );
}

/// Two states, `x` (labelled `b`) and `y`, each seen as itself; `x`
/// always moves to `y`, and `y` goes back to `x` or stays. The defender
/// wants `F G !b`: going back lets the adversary see `b` forever, staying
/// wins surely.
const LEAVE_THE_LOOP: &str = r#"{"posg": 1,
    "states": ["x", "y"], "initial": {"x": 1.0}, "labels": {"x": ["b"]},
    "defender": {"actions": ["go", "stay"], "observations": ["X", "Y"],
                 "observe": {"x": {"X": 1.0}, "y": {"Y": 1.0}}},
    "adversary": {"actions": ["a"], "observe": "full"},
    "transitions": [
        {"state": "x", "defender": "*", "adversary": "*", "next": {"y": 1.0}},
        {"state": "y", "defender": "go", "adversary": "*", "next": {"x": 1.0}},
        {"state": "y", "defender": "stay", "adversary": "*", "next": {"y": 1.0}}]}"#;

/// The defender that goes back from `y` loses surely. Staying in `y` keeps
/// every value's one-step average (the adversary wins from `y` before and
/// `y` is where it stays), yet wins surely: the new bottom component `{y}`
/// never sees `b`, and the refutation's second condition keeps the move.
/// A move in `x`'s block changes no transition and is refuted.
#[test]
fn a_move_that_closes_a_losing_loop_is_not_refuted() {
    let game = from_json_str(LEAVE_THE_LOOP, "loop.posg.json").unwrap();
    let (_, not_phi) = common::automata("F G !b");
    let universe = Fsc::uniform_enabled(Role::Defender, 1, game.defender());
    let play = |defender: &Fsc, b: usize, action: usize| {
        with_block(defender, b, surely(&blocks(&universe)[b][action]))
    };
    let going = play(&play(&universe, 0, 0), 1, 0);
    assert_eq!(bound(&game, &not_phi, &going), 0.0);
    let refuter = Refuter::new(&game, &not_phi, &going, &ranking()).unwrap();
    let staying = play(&going, 1, 1);
    assert!((bound(&game, &not_phi, &staying) - 1.0).abs() < 1e-12);
    assert!(!refuter.refutes(&staying, 1));
    let idle = play(&going, 0, 1);
    assert_eq!(bound(&game, &not_phi, &idle), 0.0);
    assert!(refuter.refutes(&idle, 0));
}
