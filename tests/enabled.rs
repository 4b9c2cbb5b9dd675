//! Actions enabled per observation (formats.md section 6): the game file's
//! `enabled` map, controllers that must respect it, the GMC, pruning and the
//! certified bounds, checked on hand-made games and against the dense
//! reference computation on random games with random `enabled` maps.

mod common;

use posg_fsc::certify::{lower_bound, upper_bound};
use posg_fsc::controller::file::{from_json_str as fsc_from_json, resolve};
use posg_fsc::controller::{Choice, Fsc, Role, Support};
use posg_fsc::game::file::{from_json_str, to_json_string};
use posg_fsc::game::{AdversaryAction, DefenderAction, Posg};
use posg_fsc::ltl;
use posg_fsc::optimise::{Structure, warm_started};
use posg_fsc::prune::{PruneSettings, prune};
use posg_fsc::value::Gmc;
use posg_fsc::value::SolverSettings;
use posg_fsc::value::evaluate_controllers;
use proptest::prelude::*;
use serde_json::{Value, json};

fn game(value: &Value) -> Posg {
    from_json_str(&value.to_string(), "enabled.posg.json").unwrap()
}

fn game_error(value: &Value) -> String {
    from_json_str(&value.to_string(), "enabled.posg.json")
        .unwrap_err()
        .to_string()
}

fn value(game: &Posg, formula: &str, def: &Fsc, adv: &Fsc) -> f64 {
    let dra = ltl::translate(&ltl::parse(formula).unwrap()).unwrap();
    evaluate_controllers(game, &dra, def, adv, &SolverSettings::default())
        .unwrap()
        .1
        .value
}

fn bounds(game: &Posg, formula: &str, def: &Fsc, adv: &Fsc) -> (f64, f64) {
    let phi = ltl::parse(formula).unwrap();
    let dra = ltl::translate(&phi).unwrap();
    let not_dra = ltl::translate(&phi.negate()).unwrap();
    (
        lower_bound(game, &not_dra, def).unwrap().value,
        upper_bound(game, &dra, adv).unwrap().value,
    )
}

/// A corridor `c0 -> c1 -> goal` that the defender walks with `step`; in
/// `c0` (observation `dark`) only `step` and `wait` are enabled, and `jump`
/// (which would reach the goal at once, or fall into the pit) only in `c1`
/// (observation `lit`). No entry exists for `jump` in `c0`: none is needed.
fn corridor() -> Value {
    json!({
        "posg": 1, "states": ["c0", "c1", "goal", "pit"], "initial": {"c0": 1.0},
        "labels": {"goal": ["goal"], "pit": ["unsafe"]},
        "defender": {
            "actions": ["step", "wait", "jump"],
            "observations": ["dark", "lit", "end"],
            "observe": {"c0": {"dark": 1.0}, "c1": {"lit": 1.0}, "goal": {"end": 1.0}, "pit": {"end": 1.0}},
            "enabled": {"dark": ["step", "wait"], "end": ["wait"]}
        },
        "transitions": [
            {"state": "c0", "defender": "step", "next": {"c1": 1.0}},
            {"state": "c0", "defender": "wait", "next": {"c0": 1.0}},
            {"state": "c1", "defender": "step", "next": {"goal": 0.5, "c0": 0.5}},
            {"state": "c1", "defender": "wait", "next": {"c1": 1.0}},
            {"state": "c1", "defender": "jump", "next": {"goal": 0.5, "pit": 0.5}},
            {"state": "goal", "defender": "wait", "next": {"goal": 1.0}},
            {"state": "pit", "defender": "wait", "next": {"pit": 1.0}}
        ]
    })
}

#[test]
fn the_enabled_map_is_read_into_the_player() {
    let g = game(&corridor());
    let def = g.defender();
    assert!(def.restricts_actions());
    let (dark, lit, end) = (0, 1, 2);
    let (step, wait, jump) = (0, 1, 2);
    assert!(def.action_enabled(dark, step) && def.action_enabled(dark, wait));
    assert!(!def.action_enabled(dark, jump));
    assert!(
        (0..3).all(|u| def.action_enabled(lit, u)),
        "lit is not listed: all enabled"
    );
    assert_eq!(def.enabled_actions(end).collect::<Vec<_>>(), vec![wait]);
    assert!(!def.action_enabled_in_state(0, jump));
    assert!(def.action_enabled_in_state(1, jump));
    assert!(
        g.transition(0, DefenderAction(jump), AdversaryAction(0))
            .is_empty()
    );
    assert_eq!(
        g.transition(1, DefenderAction(jump), AdversaryAction(0))
            .len(),
        2
    );
    assert!(!g.adversary().restricts_actions());
}

#[test]
fn a_game_without_enabled_restricts_nothing() {
    let mut value = corridor();
    value["defender"].as_object_mut().unwrap().remove("enabled");
    let error = game_error(&value);
    assert!(
        error.contains("no entry covers (state `c0`, defender `jump`"),
        "{error}"
    );
}

#[test]
fn an_enabled_map_that_enables_everything_equals_none() {
    let mut value = corridor();
    value["defender"]["enabled"] = json!({"lit": ["jump", "wait", "step"]});
    value["transitions"].as_array_mut().unwrap().extend([
        json!({"state": "c0", "defender": "jump", "next": {"c0": 1.0}}),
        json!({"state": "goal", "defender": "*", "next": {"goal": 1.0}}),
        json!({"state": "pit", "defender": "*", "next": {"pit": 1.0}}),
    ]);
    let g = game(&value);
    assert!(!g.defender().restricts_actions());
}

#[test]
fn a_missing_entry_for_an_enabled_action_is_still_an_error() {
    let mut value = corridor();
    value["transitions"].as_array_mut().unwrap().remove(4);
    let error = game_error(&value);
    assert!(
        error.contains(
            "enabled.posg.json: transitions: no entry covers (state `c1`, defender `jump`"
        ),
        "{error}"
    );
}

#[test]
fn bad_enabled_maps_are_errors_with_their_json_path() {
    let cases = [
        (
            json!({"nowhere": ["step"]}),
            "defender.enabled.nowhere: unknown observation `nowhere`",
        ),
        (
            json!({"dark": ["fly"]}),
            "defender.enabled.dark[0]: unknown action `fly`",
        ),
        (
            json!({"dark": []}),
            "defender.enabled.dark: an observation needs at least one enabled action",
        ),
        (
            json!({"dark": ["step", "step"]}),
            "defender.enabled.dark[1]: action `step` listed twice",
        ),
        (json!(["step"]), "defender.enabled: invalid type"),
    ];
    for (enabled, expected) in cases {
        let mut value = corridor();
        value["defender"]["enabled"] = enabled;
        let error = game_error(&value);
        assert!(
            error.contains(expected),
            "expected `{expected}` in `{error}`"
        );
    }
}

#[test]
fn writing_and_reading_keeps_the_enabled_map() {
    let g = game(&corridor());
    let text = to_json_string(&g);
    let written: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        written["defender"]["enabled"],
        json!({"dark": ["step", "wait"], "end": ["wait"]})
    );
    assert_eq!(written["transitions"].as_array().unwrap().len(), 7);
    assert_eq!(from_json_str(&text, "again.posg.json").unwrap(), g);
}

#[test]
fn a_controller_that_plays_a_disabled_action_is_an_error() {
    let g = game(&corridor());
    let controller = json!({
        "fsc": 1, "player": "defender", "nodes": 1, "initial": [1.0],
        "rules": [
            {"node": 0, "observation": "dark", "choices": [{"next": 0, "action": "jump", "p": 0.5},
                                                          {"next": 0, "action": "step", "p": 0.5}]}
        ],
        "default": "uniform"
    });
    let error = fsc_from_json(&controller.to_string(), "d.fsc.json", &g, Role::Defender)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("d.fsc.json: rules[0].choices[0].action: action `jump` is not enabled under observation `dark`"),
        "{error}"
    );
}

#[test]
fn a_disabled_action_with_probability_zero_is_allowed() {
    let g = game(&corridor());
    let controller = json!({
        "fsc": 1, "player": "defender", "nodes": 1, "initial": [1.0],
        "rules": [
            {"node": 0, "observation": "dark", "choices": [{"next": 0, "action": "jump", "p": 0.0},
                                                          {"next": 0, "action": "step", "p": 1.0}]}
        ],
        "default": "uniform"
    });
    let fsc = fsc_from_json(&controller.to_string(), "d.fsc.json", &g, Role::Defender).unwrap();
    assert_eq!(fsc.choices(0, 0).len(), 1);
}

#[test]
fn uniform_controllers_are_uniform_over_enabled_actions_only() {
    let g = game(&corridor());
    let fsc = resolve("uniform:2", &g, Role::Defender).unwrap();
    let dark = fsc.choices(1, 0);
    assert_eq!(dark.len(), 4, "2 nodes x {{step, wait}}");
    assert!(dark.iter().all(|c| c.probability == 0.25 && c.action != 2));
    assert_eq!(fsc.choices(0, 1).len(), 6, "lit enables all three");
    assert!(fsc.choices(0, 2).iter().all(|c| c.action == 1));
    let controller = json!({
        "fsc": 1, "player": "defender", "nodes": 2, "initial": [1.0, 0.0],
        "rules": [], "default": "uniform"
    });
    let defaulted =
        fsc_from_json(&controller.to_string(), "d.fsc.json", &g, Role::Defender).unwrap();
    assert_eq!(defaulted, fsc);
}

/// A warm start (a sweep's next size) embeds the smaller defender into the
/// full structure's enabled pairs only: it fits the player, block by block
/// on the full structure's support (it mixed over every action before).
#[test]
fn a_warm_start_embeds_into_the_enabled_actions_only() {
    let g = game(&corridor());
    let smaller = resolve("uniform:1", &g, Role::Defender).unwrap();
    let full = Structure::full(&g, 2, 1, false);
    let started = warm_started(full.clone(), &smaller, false).unwrap();
    let (defender, support) = (started.warm.as_ref().unwrap(), &full.defender);
    assert_eq!(defender.check_fits(g.defender()), Ok(()));
    let pairs = |choices: &[Choice]| -> Vec<(usize, usize)> {
        choices.iter().map(|c| (c.next, c.action)).collect()
    };
    for (h, o) in (0..2).flat_map(|h| (0..3).map(move |o| (h, o))) {
        let block = defender.choices(h, o);
        assert_eq!(
            pairs(block),
            pairs(support.choices(h, o)),
            "block ({h}, {o})"
        );
        let total: f64 = block.iter().map(|c| c.probability).sum();
        assert!(
            (total - 1.0).abs() < 1e-12,
            "block ({h}, {o}) sums to {total}"
        );
    }
    // A structure without a pair the smaller defender plays is refused:
    // node 0 under `dark` without `step` (action 0).
    let blocks = (0..2)
        .flat_map(|h| (0..3).map(move |o| (h, o)))
        .map(|(h, o)| {
            let mut block = support.choices(h, o).to_vec();
            if (h, o) == (0, 0) {
                block.retain(|c| c.action != 0);
                let p = 1.0 / block.len() as f64;
                block.iter_mut().for_each(|c| c.probability = p);
            }
            block
        })
        .collect();
    let narrow = Fsc::new(Role::Defender, 2, 3, 3, vec![1.0, 0.0], blocks).unwrap();
    let error = warm_started(
        Structure {
            defender: narrow,
            ..full
        },
        &smaller,
        false,
    )
    .unwrap_err()
    .to_string();
    assert!(error.contains("outside the structure's support"), "{error}");
}

#[test]
fn the_value_of_the_uniform_controller_counts_enabled_actions_only() {
    // uniform:1: in c0 step/wait with 1/2 each, in c1 step/wait/jump with 1/3:
    // x0 = x0/2 + x1/2, so x0 = x1; x1 = (1/2 + x0/2)/3 + x1/3 + (1/2)/3,
    // so x1/2 = 1/3 and x1 = 2/3. (Uniform over all three actions in c0
    // would be undefined: `jump` has no transition there.)
    let g = game(&corridor());
    let def = resolve("uniform:1", &g, Role::Defender).unwrap();
    let adv = resolve("uniform:1", &g, Role::Adversary).unwrap();
    let v = value(&g, "F goal", &def, &adv);
    assert!((v - 2.0 / 3.0).abs() < 1e-12, "{v}");
}

#[test]
fn the_gmc_refuses_a_support_with_a_disabled_action() {
    let g = game(&corridor());
    let blocks = (0..3)
        .map(|_| {
            vec![Choice {
                next: 0,
                action: 2,
                probability: 1.0,
                logit: None,
            }]
        })
        .collect();
    let jumper = Fsc::new(Role::Defender, 1, 3, 3, vec![1.0], blocks).unwrap();
    let adv = resolve("uniform:1", &g, Role::Adversary).unwrap();
    let dra = ltl::translate(&ltl::parse("F goal").unwrap()).unwrap();
    let error = Gmc::build(&g, &dra, &Support::of(&jumper), &Support::of(&adv))
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("plays action `jump` in node 0 under observation `dark`"),
        "{error}"
    );
    let not_dra = ltl::translate(&ltl::parse("!F goal").unwrap()).unwrap();
    let error = lower_bound(&g, &not_dra, &jumper).unwrap_err().to_string();
    assert!(error.contains("does not enable"), "{error}");
}

/// s0 is left for the goal only if the adversary lets the defender pass. The
/// adversary's observation of s0 is `calm` (probability 1 - p) or `storm`
/// (p); `block` is enabled under `storm` only.
fn blockable(p_storm: f64) -> Value {
    let observe = if p_storm > 0.0 {
        json!({"calm": 1.0 - p_storm, "storm": p_storm})
    } else {
        json!({"calm": 1.0})
    };
    json!({
        "posg": 1, "states": ["s0", "s1"], "initial": {"s0": 1.0},
        "labels": {"s1": ["goal"]},
        "defender": {"actions": ["go"], "observe": "full"},
        "adversary": {
            "actions": ["pass", "block"], "observations": ["calm", "storm"],
            "observe": {"s0": observe, "s1": {"calm": 1.0}},
            "enabled": {"calm": ["pass"]}
        },
        "transitions": [
            {"state": "s0", "defender": "go", "adversary": "pass", "next": {"s1": 0.5, "s0": 0.5}},
            {"state": "s0", "defender": "go", "adversary": "block", "next": {"s0": 1.0}},
            {"state": "s1", "defender": "*", "adversary": "*", "next": {"s1": 1.0}}
        ]
    })
}

#[test]
fn the_certification_adversary_plays_only_actions_some_observation_enables() {
    // Never stormy: `block` is enabled under no observation of s0, so even
    // the all-seeing adversary of the lower bound cannot play it.
    let g = game(&blockable(0.0));
    let def = resolve("uniform:1", &g, Role::Defender).unwrap();
    let adv = resolve("uniform:1", &g, Role::Adversary).unwrap();
    assert_eq!(bounds(&g, "F goal", &def, &adv), (1.0, 1.0));
    assert!((value(&g, "F goal", &def, &adv) - 1.0).abs() < 1e-12);
}

#[test]
fn a_state_whose_observations_enable_different_actions_gives_the_union() {
    // Stormy with probability 0.1: an FSC adversary can block only after
    // seeing `storm`, so its best value is: it blocks whenever it may, and
    // from s0 the defender passes with 0.9 * 0.5 per step: P(F goal) = 1.
    // The certification adversary, which sees the state but not its own
    // observation, may play `block` in s0 at every step (method.md section 6
    // as documented in `certify`): lower bound 0, a sound bracket.
    let g = game(&blockable(0.1));
    let def = resolve("uniform:1", &g, Role::Defender).unwrap();
    let blocker = fsc_from_json(
        &json!({"fsc": 1, "player": "adversary", "nodes": 1, "initial": [1.0], "rules": [
            {"node": 0, "observation": "calm", "choices": [{"next": 0, "action": "pass", "p": 1.0}]},
            {"node": 0, "observation": "storm", "choices": [{"next": 0, "action": "block", "p": 1.0}]}
        ]})
        .to_string(),
        "blocker.fsc.json",
        &g,
        Role::Adversary,
    )
    .unwrap();
    assert!((value(&g, "F goal", &def, &blocker) - 1.0).abs() < 1e-12);
    let (lower, upper) = bounds(&g, "F goal", &def, &blocker);
    assert_eq!(lower, 0.0);
    assert!((upper - 1.0).abs() < 1e-12);
}

#[test]
fn pruning_keeps_only_enabled_actions_and_needs_no_entry_for_disabled_ones() {
    let g = game(&corridor());
    let dra = ltl::translate(&ltl::parse("F goal & G !unsafe").unwrap()).unwrap();
    let def = resolve("uniform:1", &g, Role::Defender).unwrap();
    let adv = resolve("uniform:1", &g, Role::Adversary).unwrap();
    let report = prune(&g, &dra, &def, &adv, &PruneSettings::default()).unwrap();
    assert!(!report.structures.is_empty());
    for structure in &report.structures {
        structure.defender.check_fits(g.defender()).unwrap();
        let v = value(
            &g,
            "F goal & G !unsafe",
            &structure.defender,
            &structure.adversary,
        );
        assert!(
            v > 0.0,
            "a kept structure has a feasible recurrent set: {v}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(1),
        ..ProptestConfig::with_cases(150)
    })]

    /// On random games with random `enabled` maps (and no transition entries
    /// for triples no observation enables), random controllers on enabled
    /// actions: the GMC's value equals the dense reference computation, lies
    /// in the certified bracket, and pruning keeps enabled actions only.
    #[test]
    fn random_games_with_enabled_maps(seed in any::<u64>()) {
        let text = common::random::game_json_with_enabled(seed);
        let g = from_json_str(&text, "random.posg.json").unwrap();
        let reread = from_json_str(&to_json_string(&g), "again.posg.json").unwrap();
        prop_assert_eq!(&reread, &g);
        let dra = common::random::dra(seed);
        let def = common::random::controller(seed, &g, Role::Defender);
        let adv = common::random::controller(seed ^ 1, &g, Role::Adversary);
        let ours = evaluate_controllers(&g, &dra, &def, &adv, &SolverSettings::default())
            .unwrap()
            .1
            .value;
        let reference = common::reference_value(&g, &dra, &def, &adv);
        prop_assert!((ours - reference).abs() < 1e-9, "{} vs {}", ours, reference);
        let formula = ["F goal", "G !unsafe", "GF goal & G !unsafe", "!unsafe U goal"][(seed % 4) as usize];
        let phi_value = value(&g, formula, &def, &adv);
        let (lower, upper) = bounds(&g, formula, &def, &adv);
        prop_assert!(lower <= phi_value + 1e-9 && phi_value <= upper + 1e-9,
            "{}: {} <= {} <= {}", formula, lower, phi_value, upper);
        let full_def = Fsc::uniform_enabled(Role::Defender, 1, g.defender());
        let full_adv = Fsc::uniform_enabled(Role::Adversary, 1, g.adversary());
        let report = prune(&g, &dra, &full_def, &full_adv, &PruneSettings { paper_literal: seed % 2 == 0, prune_adversary: seed % 3 == 0 }).unwrap();
        for structure in &report.structures {
            prop_assert!(structure.defender.check_fits(g.defender()).is_ok());
            prop_assert!(structure.adversary.check_fits(g.adversary()).is_ok());
        }
    }
}

#[test]
fn random_games_with_enabled_maps_restrict_actions_and_drop_entries() {
    let (mut restricting, mut dropping, mut disabled_in_a_state) = (0, 0, 0);
    for seed in 0..200 {
        let full: Value = serde_json::from_str(&common::random::game_json(seed)).unwrap();
        let text = common::random::game_json_with_enabled(seed);
        let reduced: Value = serde_json::from_str(&text).unwrap();
        let g = from_json_str(&text, "random.posg.json").unwrap();
        restricting +=
            usize::from(g.defender().restricts_actions() || g.adversary().restricts_actions());
        dropping += usize::from(
            reduced["transitions"].as_array().unwrap().len()
                < full["transitions"].as_array().unwrap().len(),
        );
        let def = g.defender();
        disabled_in_a_state += usize::from(
            (0..g.num_states())
                .any(|s| (0..def.num_actions()).any(|u| !def.action_enabled_in_state(s, u))),
        );
    }
    assert!(
        restricting > 100 && dropping > 50 && disabled_in_a_state > 50,
        "{restricting} restricting, {dropping} dropping, {disabled_in_a_state} with a disabled action"
    );
}
