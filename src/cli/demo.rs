//! `posg-fsc demo`: the main job on the seed paper's 3x2 grid, explained.
//!
//! 1. `solve` for `!unsafe U goal` (2-node defender, 1-node adversary):
//!    worst-case estimate, certified bracket, output files.
//! 2. `GF goal & G !unsafe`, the paper's formula: zero under full supports
//!    and no structure from Algorithm 1; support synthesis by SAT proves
//!    that no 2-node support wins almost surely and finds one that wins
//!    with positive probability; `solve` with its defaults tunes it and
//!    certifies the result (beside a hand-made controller's guarantee).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use posg_fsc::automaton::Dra;
use posg_fsc::certify::lower_bound;
use posg_fsc::controller::{Choice, Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::game::grid::GridSpec;
use posg_fsc::optimise::Settings;
use posg_fsc::output::{OutputDirectory, PlotFormat, PlotSize};
use posg_fsc::pipeline::{Automata, Job, Outcome, Sizes};
use posg_fsc::prune::{PruneSettings, prune};
use posg_fsc::synthesis::{self, Mode, synthesise};
use posg_fsc::value::SolverSettings;
use posg_fsc::value::evaluate_controllers;

use super::common::PlotArgs;
use super::solve::solve_into;

/// Arguments of `demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Where to write the solves' files (`reach-avoid/` and `paper/`; an
    /// earlier demo's directory is replaced).
    #[arg(long, default_value = "posg-fsc-demo")]
    out: PathBuf,
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
    let directory = OutputDirectory::create(&args.out, true)?;
    let place = |name: &str| Place {
        staging: directory.join(name),
        shown: args.out.join(name),
    };
    solve_reach_avoid(&game, &place("reach-avoid"), &mut out)?;
    recurrence(&game, &place("paper"), &mut out)?;
    directory.commit()?;
    super::common::print_text(&out)
}

/// `solve` with its defaults, 2 defender nodes against 1 adversary node,
/// quietly, into `place`.
fn solve_with_defaults(game: &Posg, automata: &Automata, place: &Place) -> anyhow::Result<Outcome> {
    let settings = Settings::default();
    let sizes = Sizes {
        defender: 2,
        adversary: 1,
    };
    let job = Job::full(game, automata, sizes, &settings)?;
    solve_into(
        job,
        &place.staging,
        None,
        false,
        PlotArgs {
            format: PlotFormat::Svg,
            size: PlotSize::default(),
            dpi: PlotSize::DEFAULT_DPI,
        },
        None,
    )
}

/// Where a solve writes (inside the demo's staging directory) and where its
/// files will be once the demo has finished.
struct Place {
    staging: PathBuf,
    shown: PathBuf,
}

fn solve_reach_avoid(game: &Posg, place: &Place, out: &mut String) -> anyhow::Result<()> {
    let formula = "!unsafe U goal";
    let automata = Automata::from_ltl(formula)?;
    let dra = &automata.phi;
    let outcome = solve_with_defaults(game, &automata, place)?;
    let (best, certified) = (outcome.best(), outcome.certified);
    let defender = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
    let adversary = Fsc::uniform_enabled(Role::Adversary, 1, game.adversary());
    let uniform = value(game, dra, &defender, &adversary)?;
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
        "   Files in {}/: curve.csv and curve.svg (convergence),",
        place.shown.display()
    )?;
    writeln!(
        out,
        "   defender.fsc.json and adversary.fsc.json (the controllers, with logits),"
    )?;
    writeln!(out, "   summary.json (settings).\n")?;
    Ok(())
}

fn recurrence(game: &Posg, place: &Place, out: &mut String) -> anyhow::Result<()> {
    let formula = "GF goal & G !unsafe";
    let automata = Automata::from_ltl(formula)?;
    let (dra, negated) = (
        &automata.phi,
        automata.not_phi.as_ref().expect("a formula's negation"),
    );
    let defender = Fsc::uniform_enabled(Role::Defender, 2, game.defender());
    let adversary = Fsc::uniform_enabled(Role::Adversary, 1, game.adversary());
    let full = value(game, dra, &defender, &adversary)?;
    let report = prune(game, dra, &defender, &adversary, &PruneSettings::default())?;
    writeln!(
        out,
        "2. The paper's formula '{formula}', defender 2 nodes, adversary 1 node."
    )?;
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
        "   are zero. Algorithm 1 (`posg-fsc prune`) keeps {} structures: near s4 the",
        report.structures.len()
    )?;
    writeln!(
        out,
        "   noisy observations mix cells that need different safe moves."
    )?;
    synthesis_story(game, dra, negated, out)?;
    tuned_story(game, &automata, place, out)?;
    let park = park_on_goal(game)?;
    let lower = lower_bound(game, negated, &park)?.value;
    writeln!(
        out,
        "   For comparison, a hand-made 2-node defender (go R, R, D to s5, then switch"
    )?;
    writeln!(
        out,
        "   node and push into the wall forever) is certified at {lower:.4}.\n"
    )?;
    let program = this_program();
    writeln!(
        out,
        "Next: `{program} solve --help`, `{program} support --help`,\n\
         `{program} example grid --help` (`cargo install --path .` in the clone puts\n\
         `posg-fsc` on your PATH)."
    )?;
    Ok(())
}

/// How to call this program from the current directory: `posg-fsc` when
/// it is on the PATH (or cannot be told), else its path relative to the
/// current directory (`target/release/posg-fsc` after `cargo run
/// --release`), else its absolute path.
fn this_program() -> String {
    let Ok(exe) = std::env::current_exe() else {
        return "posg-fsc".into();
    };
    let on_path = std::env::var_os("PATH").is_some_and(|paths| {
        std::env::split_paths(&paths).any(|dir| Some(dir.as_path()) == exe.parent())
    });
    if on_path {
        return "posg-fsc".into();
    }
    let relative = std::env::current_dir()
        .ok()
        .and_then(|dir| exe.strip_prefix(dir).ok().map(Path::to_path_buf));
    match relative {
        Some(path) => path.display().to_string(),
        None => exe.display().to_string(),
    }
}

/// Support synthesis (method.md section 7) for 2 defender nodes, both modes.
fn synthesis_story(game: &Posg, dra: &Dra, negated: &Dra, out: &mut String) -> anyhow::Result<()> {
    let run = |mode| {
        let settings = synthesis::Settings {
            mode,
            ..synthesis::Settings::default()
        };
        synthesise(game, dra, negated, 2, &settings, &SolverSettings::default())
    };
    let almost_sure = run(Mode::AlmostSure)?;
    let positive = run(Mode::Positive)?;
    writeln!(
        out,
        "   Support synthesis by SAT (`posg-fsc support`) decides which supports win:"
    )?;
    let effort = |s: &synthesis::Synthesis| {
        s.statistics.as_ref().map_or_else(String::new, |stats| {
            format!(
                "{} SAT calls, {} lemmas, {:.1} ms",
                stats.calls,
                stats.lemmas,
                stats.seconds * 1e3
            )
        })
    };
    match &almost_sure.defender {
        None => writeln!(
            out,
            "   - no 2-node support wins almost surely against every adversary (proved:\n     {});",
            effort(&almost_sure)
        )?,
        Some(_) => writeln!(
            out,
            "   - a 2-node support wins almost surely ({});",
            effort(&almost_sure)
        )?,
    }
    match (&positive.defender, positive.certified_lower) {
        (Some(support), Some(lower)) => {
            writeln!(
                out,
                "   - a 2-node support of {} (node, observation, next node, action) entries wins\n     \
                 with positive probability: uniform on it, certified at {lower:.4}\n     ({}).",
                positive.support_entries(),
                effort(&positive)
            )?;
            writeln!(
                out,
                "     It starts in node 0 and allows every choice except:"
            )?;
            for line in restrictions(game, support) {
                writeln!(out, "       {line}")?;
            }
        }
        _ => writeln!(out, "   - {} ({}).", positive.reason, effort(&positive))?,
    }
    Ok(())
}

/// `solve` with its defaults on the paper's formula: the SAT support is one
/// of the structures it optimises on.
fn tuned_story(
    game: &Posg,
    automata: &Automata,
    place: &Place,
    out: &mut String,
) -> anyhow::Result<()> {
    let outcome = solve_with_defaults(game, automata, place)?;
    let (best, certified) = (outcome.best(), outcome.certified);
    writeln!(
        out,
        "   `solve` with its defaults optimises on every structure found (full, SAT,"
    )?;
    writeln!(
        out,
        "   Algorithm 1) and keeps the best certified one: here `{}`,\n   tuned in {:.1} s.",
        best.report.name, best.report.seconds
    )?;
    if let Some(bracket) = certified {
        writeln!(
            out,
            "   Certified: at least {:.4} against EVERY adversary; no defender gets more",
            bracket.certified_lower
        )?;
        writeln!(
            out,
            "   than {:.4} against the adversary found. Its rules, as\n   observation:action->next node:",
            bracket.upper_bound
        )?;
    }
    for line in rules(game, &best.defender) {
        writeln!(out, "     {line}")?;
    }
    writeln!(
        out,
        "   Files in {}/ (defender.dot is a picture: `dot -Tsvg`).",
        place.shown.display()
    )?;
    Ok(())
}

/// The choices `(next node, action)` a support keeps in node `node` under
/// each of `observations`.
struct Restriction<'a> {
    node: usize,
    choices: Vec<(usize, usize)>,
    observations: Vec<&'a str>,
}

/// The blocks `(g, o)` of a support that do not allow every `(next node,
/// enabled action)`, blocks with the same choices merged: `node g at o1,
/// o2: A or B, to node(s) ...`.
fn restrictions(game: &Posg, support: &Fsc) -> Vec<String> {
    let player = game.defender();
    let mut groups: Vec<Restriction> = Vec::new();
    for g in 0..support.num_nodes() {
        for (o, observation) in player.observations().iter().enumerate() {
            let enabled = player.enabled_actions(o).count();
            let mut choices: Vec<(usize, usize)> = support
                .choices(g, o)
                .iter()
                .map(|c| (c.next, c.action))
                .collect();
            if choices.len() == support.num_nodes() * enabled {
                continue;
            }
            choices.sort_unstable();
            match groups
                .iter_mut()
                .find(|r| r.node == g && r.choices == choices)
            {
                Some(group) => group.observations.push(observation),
                None => groups.push(Restriction {
                    node: g,
                    choices,
                    observations: vec![observation],
                }),
            }
        }
    }
    groups
        .into_iter()
        .map(
            |Restriction {
                 node: g,
                 choices,
                 observations,
             }| {
                let mut actions: Vec<usize> = choices.iter().map(|&(_, u)| u).collect();
                actions.sort_unstable();
                actions.dedup();
                let mut nexts: Vec<usize> = choices.iter().map(|&(n, _)| n).collect();
                nexts.dedup();
                let names = |items: &[usize], name: &dyn Fn(usize) -> String| {
                    items
                        .iter()
                        .map(|&i| name(i))
                        .collect::<Vec<_>>()
                        .join(" or ")
                };
                format!(
                    "node {g} at {}: only {}, to node {}",
                    observations.join(", "),
                    names(&actions, &|u| player.actions()[u].clone()),
                    names(&nexts, &|n| n.to_string())
                )
            },
        )
        .collect()
}

/// One line per node: each observation's most likely choice,
/// `obs:action->next` (with its probability when below 0.99).
fn rules(game: &Posg, fsc: &Fsc) -> Vec<String> {
    let player = game.defender();
    (0..fsc.num_nodes())
        .map(|g| {
            let choices: Vec<String> = (0..fsc.num_observations())
                .map(|o| {
                    let best = fsc
                        .choices(g, o)
                        .iter()
                        .max_by(|a, b| a.probability.total_cmp(&b.probability));
                    let best = best.expect("every block of a controller has a choice");
                    let probability = if best.probability < 0.99 {
                        format!(" ({:.2})", best.probability)
                    } else {
                        String::new()
                    };
                    format!(
                        "{}:{}->{}{probability}",
                        player.observations()[o],
                        player.actions()[best.action],
                        best.next
                    )
                })
                .collect();
            format!("node {g}: {}", choices.join("  "))
        })
        .collect()
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
