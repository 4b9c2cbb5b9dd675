//! Export of the labelled Markov chain on `(s, g, h)` in Storm's DRN format
//! and PRISM's explicit format, so that Storm or PRISM can check a value
//! independently.
//!
//! The chain is the GMC without the automaton: `P((s',g',h') | (s,g,h)) =
//! sum_{u,v} A_def(g',u | s,g) A_adv(h',v | s,h) T(s' | s,u,v)` on the states
//! reachable from the initial distribution, each labelled by `L(s)`.
//! Explicit formats have one initial state, so state 0 is a fresh initial
//! state, labelled `init` and with no proposition, whose transitions carry the
//! initial distribution `init(s) init_def(g) init_adv(h)`. Its trace is
//! `{} L(s_0) L(s_1) ...`: **check `X phi`** on the exported chain to get
//! the value of `phi`.
//!
//! Files: `chain.drn` (Storm's explicit DRN: `@type: DTMC`, one block per
//! state with its labels, `init` on state 0 only, and `(s, g, h)` as a
//! comment; `storm --explicit-drn chain.drn` and stormpy's
//! `build_model_from_drn` read it as it is; Storm refuses a formula over a
//! label no state carries, so when some proposition of the game labels no
//! reachable state, one last, unreachable state with a self-loop carries
//! those propositions), and PRISM's explicit files
//! `chain.tra` (`states transitions`, then `source target probability`
//! lines), `chain.lab` (label declarations, then `state: labels` lines) and
//! `chain.sta` (each state's `(s,g,h)`: the game state's index in the game
//! file's `states` list and the two controller nodes; `-1` for the fresh
//! initial state). All four describe the same chain. `chain.drn` also
//! carries the game's reward models as state rewards: state `(s, g, h)`
//! earns the one-step reward `r(s) + sum_{u,v} a_def(u | s,g) a_adv(v | s,h)
//! r(s, u, v)` of method.md section 9, state 0 earns 0, so that Storm's
//! `R{"r"}=? [F T]` in state 0 is the expected reward posg-fsc computes.

use std::fmt::Write as _;
use std::path::Path;

use crate::automaton::{Dra, RabinPair};
use crate::controller::{Fsc, Support};
use crate::game::Posg;
use crate::output::{OutputError, create_dir, write_file};
use crate::product::{Gmc, ProductError};
use crate::value::RewardVector;

/// Sizes of an exported chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ExportSummary {
    /// States, including the fresh initial state.
    pub states: usize,
    /// Transitions, including those of the fresh initial state.
    pub transitions: usize,
}

/// The files' contents.
pub struct ExplicitChain {
    /// `chain.drn`.
    pub drn: String,
    /// `chain.tra`.
    pub tra: String,
    /// `chain.lab`.
    pub lab: String,
    /// `chain.sta`.
    pub sta: String,
    /// Sizes.
    pub summary: ExportSummary,
}

/// Builds the explicit chain of the game under the two controllers.
pub fn explicit_chain(
    game: &Posg,
    defender: &Fsc,
    adversary: &Fsc,
) -> Result<ExplicitChain, ProductError> {
    let trivial = Dra::new(
        Vec::new(),
        1,
        0,
        vec![0],
        vec![RabinPair {
            fin: vec![false],
            inf: vec![true],
        }],
    )
    .expect("a one-state automaton is well formed");
    let mut gmc = Gmc::build(
        game,
        &trivial,
        &Support::of(defender),
        &Support::of(adversary),
    )?;
    gmc.refill(
        &Support::probabilities_of(defender),
        &Support::probabilities_of(adversary),
    );
    let initial: Vec<(usize, f64)> = gmc.initial().filter(|&(_, p)| p > 0.0).collect();
    let transitions = initial.len() + gmc.num_transitions();
    let states = gmc.num_states() + 1;
    let mut tra = format!("{states} {transitions}\n");
    for &(m, p) in &initial {
        writeln!(tra, "0 {} {p:e}", m + 1).expect("writing to a String");
    }
    for m in 0..gmc.num_states() {
        let (columns, values) = gmc.row(m);
        for (&c, &p) in columns.iter().zip(values) {
            writeln!(tra, "{} {} {p:e}", m + 1, c + 1).expect("writing to a String");
        }
    }
    let mut lab = String::from("0=\"init\" 1=\"deadlock\"");
    for (i, name) in game.propositions().iter().enumerate() {
        write!(lab, " {}=\"{name}\"", i + 2).expect("writing to a String");
    }
    lab.push_str("\n0: 0\n");
    let mut sta = String::from("(s,g,h)\n0:(-1,-1,-1)\n");
    for m in 0..gmc.num_states() {
        let state = gmc.state(m);
        let label = game.label(state.s as usize);
        if !label.is_empty() {
            let ids: Vec<String> = label.iter().map(|p| (p + 2).to_string()).collect();
            writeln!(lab, "{}: {}", m + 1, ids.join(" ")).expect("writing to a String");
        }
        writeln!(sta, "{}:({},{},{})", m + 1, state.s, state.g, state.h)
            .expect("writing to a String");
    }
    let rewards = state_rewards(game, &gmc, defender, adversary);
    Ok(ExplicitChain {
        drn: drn(game, &gmc, &initial, &rewards, states),
        tra,
        lab,
        sta,
        summary: ExportSummary {
            states,
            transitions,
        },
    })
}

/// Per reward model of the game, the one-step reward of every GMC state
/// under the controllers (method.md section 9).
fn state_rewards(game: &Posg, gmc: &Gmc, defender: &Fsc, adversary: &Fsc) -> Vec<Vec<f64>> {
    let all: Vec<usize> = (0..gmc.num_states()).collect();
    let (def_support, adv_support) = (Support::of(defender), Support::of(adversary));
    let (def_mu, adv_mu) = (
        Support::probabilities_of(defender),
        Support::probabilities_of(adversary),
    );
    game.reward_models()
        .iter()
        .map(|model| {
            let vector = RewardVector::new(game, gmc, &all, model, &def_support, &adv_support);
            let mut rewards = vec![0.0; all.len()];
            vector.write(&def_mu, &adv_mu, &mut rewards);
            rewards
        })
        .collect()
}

/// ` [r1, r2]`: the DRN annotation of state `m`'s rewards (state 0's, the
/// fresh initial state's, for `None`), empty without reward models.
fn reward_annotation(rewards: &[Vec<f64>], m: Option<usize>) -> String {
    if rewards.is_empty() {
        return String::new();
    }
    let values: Vec<String> = rewards
        .iter()
        .map(|model| m.map_or(0.0, |m| model[m]))
        .map(|r| format!("{r:e}"))
        .collect();
    format!(" [{}]", values.join(", "))
}

/// Storm's DRN text of the chain: state 0 is the fresh initial state,
/// state `m + 1` the GMC state `m`, each labelled by `L(s)`, with its
/// rewards, and, if some proposition labels no reachable state, an
/// unreachable last state that carries those propositions (module
/// documentation).
fn drn(
    game: &Posg,
    gmc: &Gmc,
    initial: &[(usize, f64)],
    rewards: &[Vec<f64>],
    states: usize,
) -> String {
    let mut reached = vec![false; game.propositions().len()];
    for m in 0..gmc.num_states() {
        for &p in game.label(gmc.state(m).s as usize) {
            reached[p] = true;
        }
    }
    let unreached: Vec<&str> = game
        .propositions()
        .iter()
        .zip(&reached)
        .filter(|&(_, &r)| !r)
        .map(|(name, _)| name.as_str())
        .collect();
    let states = states + usize::from(!unreached.is_empty());
    let names: Vec<&str> = game.reward_model_names().collect();
    let mut text = format!(
        "// Exported by posg-fsc {}: the Markov chain on (s, g, h) under two controllers.\n\
         // State 0 is a fresh initial state: the value of phi is P=? [ X phi ] there.\n\
         @type: DTMC\n@value_type: double\n@parameters\n\n@reward_models\n{}\n\
         @nr_states\n{states}\n@nr_choices\n{states}\n@model\nstate 0{} init\n\taction 0\n",
        env!("CARGO_PKG_VERSION"),
        names.join(" "),
        reward_annotation(rewards, None),
    );
    for &(m, p) in initial {
        writeln!(text, "\t\t{} : {p:e}", m + 1).expect("writing to a String");
    }
    for m in 0..gmc.num_states() {
        let state = gmc.state(m);
        let s = state.s as usize;
        write!(
            text,
            "state {}{}",
            m + 1,
            reward_annotation(rewards, Some(m))
        )
        .expect("writing to a String");
        for name in game.label_names(s) {
            write!(text, " {name}").expect("writing to a String");
        }
        writeln!(
            text,
            "\n//[s={}, g={}, h={}]\n\taction 0",
            game.states()[s],
            state.g,
            state.h
        )
        .expect("writing to a String");
        let (columns, values) = gmc.row(m);
        for (&c, &p) in columns.iter().zip(values) {
            writeln!(text, "\t\t{} : {p:e}", c + 1).expect("writing to a String");
        }
    }
    if !unreached.is_empty() {
        let last = states - 1;
        writeln!(
            text,
            "state {last}{} {}\n// unreachable: declares the propositions no reachable state carries\n\
             \taction 0\n\t\t{last} : 1e0",
            reward_annotation(rewards, None),
            unreached.join(" ")
        )
        .expect("writing to a String");
    }
    text
}

/// Writes `chain.drn`, `chain.tra`, `chain.lab` and `chain.sta` into `dir`
/// (created if needed); an error names the path.
pub fn write_explicit_chain(chain: &ExplicitChain, dir: &Path) -> Result<(), OutputError> {
    create_dir(dir)?;
    write_file(&dir.join("chain.drn"), &chain.drn)?;
    write_file(&dir.join("chain.tra"), &chain.tra)?;
    write_file(&dir.join("chain.lab"), &chain.lab)?;
    write_file(&dir.join("chain.sta"), &chain.sta)
}
