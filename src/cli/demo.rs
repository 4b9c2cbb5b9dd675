//! `posg-fsc demo`: the main job on the seed paper's 3x2 grid, explained.
//!
//! 1. `solve` for `!unsafe U goal` (2-node defender, 1-node adversary):
//!    worst-case estimate, certified bracket, output files.
//! 2. `GF goal & G !unsafe`, the paper's formula: zero under full supports,
//!    no structure from Algorithm 1, and a hand-made 2-node controller whose
//!    guarantee against every adversary `certify` proves.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use posg_fsc::automaton::Dra;
use posg_fsc::certify::{lower_bound, upper_bound};
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::game::grid::GridSpec;
use posg_fsc::optimise::{self, Settings, Structure};
use posg_fsc::prune::{PruneSettings, prune};
use posg_fsc::solver::SolverSettings;
use posg_fsc::value::evaluate_controllers;

use super::solve::{SolveJob, run_job};

/// Arguments of `demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Where to write the solve's files.
    #[arg(long, default_value = "posg-fsc-demo")]
    out: PathBuf,
}

fn translate(formula: &str) -> anyhow::Result<(Dra, Dra)> {
    let phi = posg_fsc::ltl::parse(formula)?;
    Ok((
        posg_fsc::ltl::translate(&phi)?,
        posg_fsc::ltl::translate(&phi.negate())?,
    ))
}

/// Runs the demo.
pub fn run(args: DemoArgs) -> anyhow::Result<()> {
    let game = GridSpec::default().build()?;
    let mut out = String::new();
    writeln!(
        out,
        "posg-fsc demo: the seed paper's grid, 3 x 2 cells, start s0, unsafe s4, goal s5\n"
    )?;
    writeln!(out, "    s0  s1  s2")?;
    writeln!(out, "    s3  s4! s5*      (! unsafe, * goal)\n")?;
    writeln!(
        out,
        "The defender moves R/L/U/D; a move succeeds with probability 0.8 (0.6 when"
    )?;
    writeln!(
        out,
        "the adversary attacks) and otherwise slips to a neighbouring cell; moving"
    )?;
    writeln!(
        out,
        "into a wall stays put. Each player sees its true cell with probability 0.8"
    )?;
    writeln!(
        out,
        "(defender) or 0.6 (adversary), otherwise a random neighbour's name.\n"
    )?;
    solve_reach_avoid(&game, &args.out, &mut out)?;
    recurrence(&game, &mut out)?;
    super::common::print_text(&out)
}

fn solve_reach_avoid(game: &Posg, dir: &std::path::Path, out: &mut String) -> anyhow::Result<()> {
    let formula = "!unsafe U goal";
    let (dra, negated) = translate(formula)?;
    let settings = Settings::default();
    let start = Structure::full(game, 2, 1, settings.optimise_initial);
    let job = SolveJob {
        game,
        dra: &dra,
        negated_dra: Some(&negated),
        objective: formula,
        candidates: optimise::candidate_structures(game, &dra, Some(&negated), start, &settings)?,
        settings: &settings,
        out: dir,
        progress: super::progress::ProgressMode::Quiet,
        floor: None,
        seconds_axis: false,
    };
    let (solution, certified) = run_job(&job)?;
    let best = solution.best();
    let defender = Fsc::uniform(
        Role::Defender,
        2,
        game.defender().num_observations(),
        game.defender().num_actions(),
    );
    let adversary = Fsc::uniform(
        Role::Adversary,
        1,
        game.adversary().num_observations(),
        game.adversary().num_actions(),
    );
    let uniform = value(game, &dra, &defender, &adversary)?;
    writeln!(
        out,
        "1. solve '{formula}' (reach the goal before touching s4), defender 2 nodes,"
    )?;
    writeln!(
        out,
        "   adversary 1 node, {} iterations of alternating gradient ascent-descent:",
        best.report.iterations
    )?;
    writeln!(
        out,
        "   worst-case estimate {:.4}: the best adversary of that size found against the",
        best.report.worst_case
    )?;
    writeln!(
        out,
        "   tuned defender (uniform controllers give {uniform:.4})."
    )?;
    if let Some(bracket) = certified {
        writeln!(
            out,
            "   certified: the tuned defender achieves at least {:.4} against EVERY adversary",
            bracket.certified_lower
        )?;
        writeln!(
            out,
            "   (any size, full observation, any memory), and no defender of any size can get"
        )?;
        writeln!(
            out,
            "   more than {:.4} against the adversary found.",
            bracket.upper_bound
        )?;
    }
    writeln!(
        out,
        "   Files in {}/: curve.csv and curve.svg (convergence), defender.fsc.json and",
        dir.display()
    )?;
    writeln!(
        out,
        "   adversary.fsc.json (the controllers, with logits), summary.json (settings).\n"
    )?;
    Ok(())
}

fn recurrence(game: &Posg, out: &mut String) -> anyhow::Result<()> {
    let formula = "GF goal & G !unsafe";
    let (dra, negated) = translate(formula)?;
    let uniform = |role: Role, nodes: usize| {
        let player = if role == Role::Defender {
            game.defender()
        } else {
            game.adversary()
        };
        Fsc::uniform(role, nodes, player.num_observations(), player.num_actions())
    };
    let (defender, adversary) = (uniform(Role::Defender, 2), uniform(Role::Adversary, 1));
    let full = value(game, &dra, &defender, &adversary)?;
    let report = prune(game, &dra, &defender, &adversary, &PruneSettings::default())?;
    writeln!(out, "2. The paper's formula '{formula}'.")?;
    writeln!(
        out,
        "   With every action possible in every node its value is exactly {full}: the"
    )?;
    writeln!(
        out,
        "   defender eventually slips into s4, whatever the probabilities, so gradients"
    )?;
    writeln!(
        out,
        "   are zero. Algorithm 1 (`posg-fsc prune`) keeps {} structures here: near s4",
        report.structures.len()
    )?;
    writeln!(
        out,
        "   only wall moves are safe and the noisy observations mix cells that need"
    )?;
    writeln!(
        out,
        "   different wall moves, so pruning stops before any Good state is recurrent."
    )?;
    let park = park_on_goal(game)?;
    let parked = value(game, &dra, &park, &adversary)?;
    let lower = lower_bound(game, &negated, &park)?.value;
    let upper = upper_bound(game, &dra, &adversary)?.value;
    writeln!(
        out,
        "   A hand-made 2-node defender (go R, R, D to s5, then switch node and push"
    )?;
    writeln!(
        out,
        "   into the wall forever) has value {parked:.4} against the uniform adversary and is"
    )?;
    writeln!(
        out,
        "   certified to get at least {lower:.4} against every adversary; against the uniform"
    )?;
    writeln!(
        out,
        "   adversary no defender gets more than {upper:.4}. Positive values exist; finding"
    )?;
    writeln!(
        out,
        "   the support that reaches them is what pruning is for.\n"
    )?;
    writeln!(
        out,
        "Next: `posg-fsc solve --help`, `posg-fsc certify --help`, `posg-fsc example grid --help`."
    )?;
    Ok(())
}

fn value(game: &Posg, dra: &Dra, defender: &Fsc, adversary: &Fsc) -> anyhow::Result<f64> {
    Ok(
        evaluate_controllers(game, dra, defender, adversary, &SolverSettings::default())?
            .1
            .value,
    )
}

/// Node 0 walks s0 -R-> s1 -R-> s2 -D-> s5 by observation and moves to node 1
/// on observing s5; node 1 plays R (a wall at s5 and s2) forever.
fn park_on_goal(game: &Posg) -> anyhow::Result<Fsc> {
    let player = game.defender();
    let action = |name: &str| {
        player
            .actions()
            .iter()
            .position(|a| a == name)
            .expect("grid action")
    };
    let walk = |observation: &str| match observation {
        "s2" | "s5" => "D",
        "s3" => "U",
        _ => "R",
    };
    let mut blocks = Vec::new();
    for node in 0..2 {
        for observation in player.observations() {
            let (next, name) = match (node, observation.as_str()) {
                (0, "s5") => (1, "R"),
                (0, o) => (0, walk(o)),
                _ => (1, "R"),
            };
            blocks.push(vec![Choice {
                next,
                action: action(name),
                probability: 1.0,
                logit: None,
            }]);
        }
    }
    Ok(Fsc::new(
        Role::Defender,
        2,
        player.num_observations(),
        player.num_actions(),
        vec![1.0, 0.0],
        blocks,
    )?)
}
