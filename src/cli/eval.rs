//! `posg-fsc eval`: the exact value of a controller pair, and with
//! `--gradient` its adjoint gradient (method.md section 2).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use posg_fsc::controller::Support;
use posg_fsc::game::Posg;
use posg_fsc::pipeline::QueryValue;
use posg_fsc::value::Gmc;
use posg_fsc::value::Recurrence;
use posg_fsc::value::{EvaluationReport, Evaluator, Exploration, Gradient};
use serde::Serialize;

use super::common::{self, ControllerArgs, ObjectiveArgs, Provenance};

/// Arguments of `eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The game: a `*.posg.json` file (docs/formats.md section 1), its
    /// binary form, or a model in Storm's DRN format (section 6).
    pub game: PathBuf,
    #[command(flatten)]
    pub objective: ObjectiveArgs,
    #[command(flatten)]
    pub controllers: ControllerArgs,
    /// Also list every recurrence class (BSCC) with its members (s, q, g, h),
    /// whether it is phi-feasible and through which Rabin pairs, and its Good
    /// set (the paper's Algorithm 2). The GMC is then explored in full,
    /// beyond the states whose automaton state already decides the formula.
    #[arg(long)]
    pub explain: bool,
    #[command(flatten)]
    pub solver: common::SolverArgs,
    /// Also compute the gradient of the value with respect to every
    /// controller probability of both players by the adjoint method (one
    /// more solve, transposed, and one pass over the GMC), and report its
    /// size, its norms and the adjoint solve's residual under `gradient`
    /// (the gradient itself is not printed); the time of value and gradient
    /// is the phase `value_and_gradient`, instead of `factorise_and_solve`.
    #[arg(long)]
    pub gradient: bool,
}

#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    provenance: Provenance,
    formula: String,
    /// The query of `--props` restated in its own terms.
    #[serde(skip_serializing_if = "Option::is_none")]
    query: Option<QueryValue>,
    /// With `--explain` the GMC is explored beyond the decided states.
    #[serde(flatten)]
    evaluation: EvaluationReport,
    seconds: f64,
    phase_seconds: PhaseSeconds,
    #[serde(skip_serializing_if = "Option::is_none")]
    gradient: Option<GradientReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    recurrence_classes: Option<Vec<ClassReport>>,
}

/// The adjoint gradient `dV/d mu` of both players (with `--gradient`).
#[derive(Serialize)]
struct GradientReport {
    /// Defender support entries `mu_def(g', u | g, o)`.
    defender_parameters: usize,
    /// Adversary support entries `mu_adv(h', v | h, o')`.
    adversary_parameters: usize,
    /// Euclidean norm of `dV/d mu_def`.
    defender_norm: f64,
    /// Euclidean norm of `dV/d mu_adv`.
    adversary_norm: f64,
    /// Largest `|dV/d mu_def|`.
    defender_max_abs: f64,
    /// Largest `|dV/d mu_adv|`.
    adversary_max_abs: f64,
    /// `max_i |((I - Q)^T y - p0)_i|` of the adjoint solve.
    adjoint_residual: f64,
    /// BiCGSTAB iterations of the adjoint solve (0 for LU).
    adjoint_iterations: usize,
}

impl GradientReport {
    fn new(gradient: &Gradient) -> Self {
        let norm = |g: &[f64]| g.iter().map(|v| v * v).sum::<f64>().sqrt();
        let max_abs = |g: &[f64]| g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        Self {
            defender_parameters: gradient.defender.len(),
            adversary_parameters: gradient.adversary.len(),
            defender_norm: norm(&gradient.defender),
            adversary_norm: norm(&gradient.adversary),
            defender_max_abs: max_abs(&gradient.defender),
            adversary_max_abs: max_abs(&gradient.adversary),
            adjoint_residual: gradient.adjoint_residual,
            adjoint_iterations: gradient.adjoint_iterations,
        }
    }
}

/// Wall-clock seconds of each phase.
#[derive(Serialize)]
struct PhaseSeconds {
    read_game: f64,
    automaton: f64,
    controllers: f64,
    build_and_analyse: f64,
    /// Without `--gradient`: the value (refill, factorisation, one solve).
    #[serde(skip_serializing_if = "Option::is_none")]
    factorise_and_solve: Option<f64>,
    /// With `--gradient`: the value and the gradient (refill,
    /// factorisation, two solves, one pass over the GMC).
    #[serde(skip_serializing_if = "Option::is_none")]
    value_and_gradient: Option<f64>,
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
    let game = common::read_game_for(&args.game, &args.objective)?;
    let read_game = lap.seconds();
    let reward = args.objective.reward_objective(&game)?;
    if reward.is_some() && args.explain {
        anyhow::bail!(
            "--explain lists the recurrence classes of a probability objective; drop it for an \
             expected-reward query"
        );
    }
    let (dra, formula) = match &reward {
        Some(reward) => (reward.target.clone(), reward.description.clone()),
        None => common::objective(&args.objective, &game)?,
    };
    let automaton = lap.seconds();
    let (defender, adversary) = common::controllers(&args.controllers, &game)?;
    // The supports and probabilities are all that is needed of the
    // controllers: free them (tens of MB for `uniform:K` at 1e5 states)
    // before the chain is built, which reuses their memory.
    let (def_support, adv_support) = (Support::of(&defender), Support::of(&adversary));
    let (def_probabilities, adv_probabilities) = (
        Support::probabilities_of(&defender),
        Support::probabilities_of(&adversary),
    );
    drop((defender, adversary));
    let controllers = lap.seconds();
    let exploration = if args.explain {
        Exploration::Full
    } else {
        Exploration::UntilDecided
    };
    let settings = args.solver.settings();
    let mut evaluator = match &reward {
        Some(reward) => Evaluator::for_expected_reward(
            &game,
            &dra,
            &reward.rewards,
            &def_support,
            &adv_support,
            &settings,
        )?,
        None => Evaluator::with_exploration(
            &game,
            &dra,
            &def_support,
            &adv_support,
            &settings,
            exploration,
        )?,
    };
    // Where the expected reward is infinite, the probability of reaching
    // the target says by how much it is missed.
    let target_probability = match &reward {
        Some(reward) => Some(reward.target_probability(
            &game,
            &evaluator,
            (&def_support, &adv_support),
            (&def_probabilities, &adv_probabilities),
            &settings,
        )?),
        None => None,
    };
    let build_and_analyse = lap.seconds();
    // The evaluator owns all it needs: free the game (tens of MB at 1e6 GMC
    // states) before the factorisation, the step of peak memory, unless
    // --explain names its states.
    let game = args.explain.then_some(game);
    let (evaluation, gradient) = if args.gradient {
        let (evaluation, gradient) =
            evaluator.evaluate_with_gradient(&def_probabilities, &adv_probabilities)?;
        (evaluation, Some(gradient))
    } else {
        let evaluation = evaluator.evaluate(&def_probabilities, &adv_probabilities)?;
        (evaluation, None)
    };
    let solve_seconds = lap.seconds();
    let phase_seconds = PhaseSeconds {
        read_game,
        automaton,
        controllers,
        build_and_analyse,
        factorise_and_solve: gradient.is_none().then_some(solve_seconds),
        value_and_gradient: gradient.is_some().then_some(solve_seconds),
    };
    let recurrence = evaluator.recurrence();
    let query = args
        .objective
        .property()?
        .map(|property| QueryValue::evaluated(&property, &evaluation, target_probability));
    let report = Report {
        provenance: Provenance::current(),
        formula,
        query,
        evaluation: evaluator.report(&evaluation),
        seconds: common::seconds_since(start),
        phase_seconds,
        gradient: gradient.as_ref().map(GradientReport::new),
        recurrence_classes: game
            .as_ref()
            .map(|game| explain(game, evaluator.gmc(), recurrence)),
    };
    common::print_json(&report)?;
    // The process ends here: leave the chain and the factors (hundreds of
    // MB at 10^6 GMC states) to the operating system rather than freeing
    // them piece by piece.
    std::mem::forget(evaluator);
    Ok(())
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
