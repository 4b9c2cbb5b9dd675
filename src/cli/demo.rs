//! `posg-fsc demo`: the main job on the seed paper's 3x2 grid, explained.

use std::fmt::Write as _;

use clap::Args;
use posg_fsc::controller::{Fsc, Role, Support};
use posg_fsc::game::Posg;
use posg_fsc::game::grid::GridSpec;
use posg_fsc::solver::DEFAULT_TOLERANCE;
use posg_fsc::value::Evaluator;

/// Arguments of `demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {}

const FORMULAS: [(&str, &str); 2] = [
    ("!unsafe U goal", "reach the goal without touching the unsafe cell first"),
    ("GF goal & G !unsafe", "visit the goal again and again and never the unsafe cell"),
];

/// Runs the demo.
pub fn run(_args: DemoArgs) -> anyhow::Result<()> {
    let game = GridSpec::default().build()?;
    let mut out = String::new();
    writeln!(out, "posg-fsc demo: the seed paper's grid, 3 x 2 cells, start s0, unsafe s4, goal s5\n")?;
    writeln!(out, "    s0  s1  s2")?;
    writeln!(out, "    s3  s4! s5*      (! unsafe, * goal)\n")?;
    writeln!(out, "The defender moves R/L/U/D and sees its cell correctly with probability 0.8;")?;
    writeln!(out, "the adversary attacks (A) or not (NA), which lowers the chance that a move")?;
    writeln!(out, "succeeds from 0.8 to 0.6, and sees the cell with probability 0.6.\n")?;
    writeln!(out, "Exact probability that the run satisfies each formula when both players")?;
    writeln!(out, "use uniform controllers (every (next node, action) pair equally likely):\n")?;
    writeln!(out, "  {:<22} {:>10} {:>10}   GMC states", "formula", "K = 1", "K = 2")?;
    for (formula, meaning) in FORMULAS {
        let dra = posg_fsc::ltl::translate(&posg_fsc::ltl::parse(formula)?)?;
        let (one, states_one) = uniform_value(&game, &dra, 1)?;
        let (two, states_two) = uniform_value(&game, &dra, 2)?;
        writeln!(out, "  {formula:<22} {one:>10.6} {two:>10.6}   {states_one} / {states_two}   ({meaning})")?;
    }
    writeln!(out, "\nK is the number of nodes of both controllers. The second value is exactly 0:")?;
    writeln!(out, "with every action possible in every node, the defender eventually steps into")?;
    writeln!(out, "s4 with probability 1, whatever the probabilities. Only removing actions from")?;
    writeln!(out, "the controllers' supports (the paper's Algorithm 1, `posg-fsc prune`) can make")?;
    writeln!(out, "it positive. Try `posg-fsc eval --help` and `posg-fsc example grid --help`.")?;
    super::common::print_text(&out)
}

fn uniform_value(game: &Posg, dra: &posg_fsc::automaton::Dra, nodes: usize) -> anyhow::Result<(f64, usize)> {
    let defender =
        Fsc::uniform(Role::Defender, nodes, game.defender().num_observations(), game.defender().num_actions());
    let adversary =
        Fsc::uniform(Role::Adversary, nodes, game.adversary().num_observations(), game.adversary().num_actions());
    let mut evaluator =
        Evaluator::new(game, dra, &Support::of(&defender), &Support::of(&adversary), DEFAULT_TOLERANCE)?;
    let value =
        evaluator.evaluate(&Support::probabilities_of(&defender), &Support::probabilities_of(&adversary))?.value;
    Ok((value, evaluator.gmc().num_states()))
}
