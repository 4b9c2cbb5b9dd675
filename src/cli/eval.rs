//! `posg-fsc eval`: the exact value of a controller pair.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use posg_fsc::analysis::Recurrence;
use posg_fsc::controller::Support;
use posg_fsc::game::Posg;
use posg_fsc::product::Gmc;
use posg_fsc::value::Evaluator;
use serde::Serialize;

use super::common::{self, ControllerArgs, ObjectiveArgs, Provenance};

/// Arguments of `eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The game (*.posg.json).
    pub game: PathBuf,
    #[command(flatten)]
    pub objective: ObjectiveArgs,
    #[command(flatten)]
    pub controllers: ControllerArgs,
    /// Also list every recurrence class (BSCC) with its members (s, q, g, h),
    /// whether it is phi-feasible and through which Rabin pairs, and its Good
    /// set (the paper's Algorithm 2).
    #[arg(long)]
    pub explain: bool,
    #[command(flatten)]
    pub solver: common::SolverArgs,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    provenance: Provenance,
    formula: String,
    value: f64,
    gmc_states: usize,
    gmc_transitions: usize,
    bsccs: usize,
    feasible_bsccs: usize,
    transient_states: usize,
    solver: &'static str,
    residual: f64,
    solver_iterations: usize,
    seconds: f64,
    phase_seconds: PhaseSeconds,
    #[serde(skip_serializing_if = "Option::is_none")]
    recurrence_classes: Option<Vec<ClassReport>>,
}

/// Wall-clock seconds of each phase.
#[derive(Serialize)]
struct PhaseSeconds {
    read_game: f64,
    automaton: f64,
    controllers: f64,
    build_and_analyse: f64,
    factorise_and_solve: f64,
}

/// One BSCC described by its members' names.
#[derive(Serialize)]
struct ClassReport {
    size: usize,
    feasible: bool,
    feasible_pairs: Vec<usize>,
    members: Vec<String>,
    good: Vec<String>,
}

/// Runs `eval`.
pub fn run(args: EvalArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let mut lap = Lap(Instant::now());
    let game = common::read_game(&args.game)?;
    let read_game = lap.seconds();
    let (dra, formula) = common::objective(&args.objective, &game)?;
    let automaton = lap.seconds();
    let (defender, adversary) = common::controllers(&args.controllers, &game)?;
    let controllers = lap.seconds();
    let mut evaluator = Evaluator::new(
        &game,
        &dra,
        &Support::of(&defender),
        &Support::of(&adversary),
        &args.solver.settings(),
    )?;
    let build_and_analyse = lap.seconds();
    let evaluation = evaluator.evaluate(
        &Support::probabilities_of(&defender),
        &Support::probabilities_of(&adversary),
    )?;
    let phase_seconds = PhaseSeconds {
        read_game,
        automaton,
        controllers,
        build_and_analyse,
        factorise_and_solve: lap.seconds(),
    };
    let recurrence = evaluator.recurrence();
    let report = Report {
        provenance: Provenance::current(),
        formula,
        value: evaluation.value,
        gmc_states: evaluator.gmc().num_states(),
        gmc_transitions: evaluator.gmc().num_transitions(),
        bsccs: recurrence.bsccs.len(),
        feasible_bsccs: recurrence.feasible().count(),
        transient_states: recurrence.transient.len(),
        solver: evaluator.solver_method().name(),
        residual: evaluation.residual,
        solver_iterations: evaluation.iterations,
        seconds: common::seconds_since(start),
        phase_seconds,
        recurrence_classes: args
            .explain
            .then(|| explain(&game, evaluator.gmc(), recurrence)),
    };
    common::print_json(&report)
}

fn explain(game: &Posg, gmc: &Gmc, recurrence: &Recurrence) -> Vec<ClassReport> {
    let name = |m: &usize| {
        let state = gmc.state(*m);
        format!(
            "({}, q{}, g{}, h{})",
            game.states()[state.s as usize],
            state.q,
            state.g,
            state.h
        )
    };
    recurrence
        .bsccs
        .iter()
        .map(|bscc| ClassReport {
            size: bscc.states.len(),
            feasible: bscc.is_feasible(),
            feasible_pairs: bscc.feasible_pairs.clone(),
            members: bscc.states.iter().map(name).collect(),
            good: bscc.good.iter().map(name).collect(),
        })
        .collect()
}

/// Seconds since the previous lap.
struct Lap(Instant);

impl Lap {
    fn seconds(&mut self) -> f64 {
        let now = Instant::now();
        let elapsed = now.duration_since(self.0).as_secs_f64();
        self.0 = now;
        elapsed
    }
}
