//! The max-min optimiser (method.md sections 2-4):
//!
//! ```text
//!     max over phi_def in [-c, c]^n   min over phi_adv in [-c, c]^m   V(softmax(phi_def), softmax(phi_adv))
//! ```
//!
//! on fixed support structures. The pieces:
//!
//! * [`Softmax`]: logits per support entry, the softmax and its chain rule
//!   (section 3);
//! * [`Objective`]: one [`crate::value::Evaluator`] per structure, giving the
//!   value and both players' logit gradients by the adjoint method (section 2),
//!   with the last point cached;
//! * [`best_response`]: the adversary's best response by L-BFGS (argmin) in
//!   the coordinates `phi = c tanh(z)`, from several starts;
//! * [`Optimiser`]: alternating projected gradient ascent-descent with a fast
//!   adversary time scale, plain or Adam updates, periodic best-response checks,
//!   keeping the best defender by its worst-case estimate (section 4);
//! * [`optimise_structures`]: the optimiser on several structures in
//!   parallel (rayon), the best worst-case estimate chosen;
//!   [`candidate_structures`] adds the structures pruning keeps (method.md
//!   section 5) to a starting structure; [`solve`] does both from the full
//!   support structure of given sizes.
//!
//! [`Settings`] holds every number; [`Observer`]s receive one
//! [`IterationRecord`] per outer iteration and write all output.

mod best_response;
mod objective;
mod observer;
mod optimiser;
mod settings;
mod softmax;

pub use best_response::{BestResponse, best_response};
pub use objective::{GmcSize, Objective, Point};
pub use observer::{IterationRecord, Observer, ObserverError};
pub use optimiser::{Certifier, Incumbent, Optimiser, RunOutcome};
pub use settings::{Settings, UpdateRule};
pub use softmax::{Softmax, clip};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;

use crate::automaton::Dra;
use crate::controller::{Fsc, Role};
use crate::game::{ModelError, Posg};
use crate::prune::{PruneError, PruneSettings, prune};
use crate::value::ValueError;

/// Why optimisation could not run.
#[derive(Debug, Error)]
pub enum OptimiseError {
    /// A setting is out of range.
    #[error("setting `{field}` {problem}")]
    Settings {
        /// The field's name.
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// A structure's controllers do not fit the game, or a controller could
    /// not be rebuilt from logits.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Algorithm 1 (pruning) failed.
    #[error(transparent)]
    Prune(#[from] PruneError),
    /// A value or gradient could not be computed.
    #[error(transparent)]
    Value(#[from] ValueError),
    /// A certified bound could not be computed.
    #[error(transparent)]
    Certify(#[from] crate::certify::CertifyError),
    /// An observer failed (its output could not be written).
    #[error("output: {0}")]
    Observer(ObserverError),
    /// [`optimise_structures`] was given no structure.
    #[error("no structure to optimise")]
    NoStructure,
    /// The best-response minimisation failed for another reason.
    #[error("best response: {0}")]
    BestResponse(String),
}

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// `max_iterations` outer iterations ran.
    MaxIterations,
    /// The time budget ran out.
    TimeBudget,
    /// The best worst-case estimate stopped improving.
    Stalled,
}

/// A support structure to optimise on: starting controllers whose supports
/// fix the GMC graph (their probabilities, or recorded logits, are the start).
#[derive(Debug, Clone, PartialEq)]
pub struct Structure {
    /// A short name for reports (`full`, `pruned-1`, ...).
    pub name: String,
    /// The defender's starting controller.
    pub defender: Fsc,
    /// The adversary's starting controller.
    pub adversary: Fsc,
}

impl Structure {
    /// The full support structure: every `(g', u)` with `u` enabled under
    /// the block's observation in every block, both
    /// players uniform; each starts in node 0, or (when the initial
    /// distribution is optimised) uniformly over its nodes.
    pub fn full(
        game: &Posg,
        defender_nodes: usize,
        adversary_nodes: usize,
        optimise_initial: bool,
    ) -> Self {
        let make = |role: Role, nodes: usize| {
            let player = match role {
                Role::Defender => game.defender(),
                Role::Adversary => game.adversary(),
            };
            let mut fsc = Fsc::uniform_enabled(role, nodes, player);
            if optimise_initial {
                fsc.initial = vec![1.0 / nodes as f64; nodes];
            }
            fsc
        };
        Self {
            name: "full".into(),
            defender: make(Role::Defender, defender_nodes),
            adversary: make(Role::Adversary, adversary_nodes),
        }
    }
}

/// The numbers of one structure's run, as recorded in `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StructureReport {
    /// The structure's name.
    pub name: String,
    /// The size of its GMC.
    pub gmc: GmcSize,
    /// The number of defender logits.
    pub defender_parameters: usize,
    /// The number of adversary logits.
    pub adversary_parameters: usize,
    /// The seed of this structure's random stream (`seed`, stream = index).
    pub seed: u64,
    /// The best defender's worst-case estimate.
    pub worst_case: f64,
    /// The iteration the best defender was seen at.
    pub best_iteration: usize,
    /// The value at the last iterate.
    pub last_value: f64,
    /// Outer iterations run.
    pub iterations: usize,
    /// Best-response checks run.
    pub checks: usize,
    /// Why the run stopped.
    pub status: Status,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The outcome on one structure: its report and the controllers.
#[derive(Debug, Clone, PartialEq)]
pub struct StructureOutcome {
    /// The numbers.
    pub report: StructureReport,
    /// The best defender by worst-case estimate, with its logits.
    pub defender: Fsc,
    /// The best response found to it, with its logits.
    pub adversary: Fsc,
}

/// The outcomes on all structures and the one with the best worst-case estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// One outcome per structure, in the order given.
    pub structures: Vec<StructureOutcome>,
    /// The index of the best structure (the first of equal estimates).
    pub best: usize,
}

impl Solution {
    /// The best structure's outcome.
    pub fn best(&self) -> &StructureOutcome {
        &self.structures[self.best]
    }
}

/// Optimises on every structure in parallel (rayon), each with its own
/// [`Objective`] and random stream (`settings.seed`, stream = its index),
/// each reporting to the observer `observer(index, structure)` makes;
/// returns every outcome and the best by worst-case estimate. With an
/// automaton `negated` for !phi, every best-response check also certifies
/// (see [`Certifier`]).
pub fn optimise_structures<F>(
    game: &Posg,
    dra: &Dra,
    negated: Option<&Dra>,
    structures: &[Structure],
    settings: &Settings,
    observer: F,
) -> Result<Solution, OptimiseError>
where
    F: Fn(usize, &Structure) -> Box<dyn Observer + Send> + Sync,
{
    settings.validate()?;
    let outcomes = structures
        .par_iter()
        .enumerate()
        .map(|(index, structure)| {
            let mut watcher = observer(index, structure);
            optimise_structure(
                game,
                dra,
                negated,
                structure,
                settings,
                index as u64,
                watcher.as_mut(),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let best = (0..outcomes.len())
        .reduce(|b, i| {
            if outcomes[i].report.worst_case > outcomes[b].report.worst_case {
                i
            } else {
                b
            }
        })
        .ok_or(OptimiseError::BestResponse(
            "no structure to optimise".into(),
        ))?;
    Ok(Solution {
        structures: outcomes,
        best,
    })
}

/// Optimises on one structure with random stream `stream` of `settings.seed`;
/// with an automaton `negated` for !phi the checks also certify ([`Certifier`]).
pub fn optimise_structure(
    game: &Posg,
    dra: &Dra,
    negated: Option<&Dra>,
    structure: &Structure,
    settings: &Settings,
    stream: u64,
    observer: &mut dyn Observer,
) -> Result<StructureOutcome, OptimiseError> {
    settings.validate()?;
    let defender = Softmax::new(&structure.defender, settings.optimise_initial);
    let adversary = Softmax::new(&structure.adversary, settings.optimise_initial);
    let objective = Objective::new(game, dra, defender, adversary, &settings.solver_settings())?;
    let gmc = objective.gmc_size();
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    rng.set_stream(stream);
    let mut optimiser = Optimiser::new(objective, settings, rng);
    if let Some(not_phi) = negated {
        optimiser = optimiser.with_certifier(Certifier {
            game,
            phi: dra,
            not_phi,
        });
    }
    let run = optimiser.run(observer)?;
    observer.finish().map_err(OptimiseError::Observer)?;
    let objective = optimiser.objective();
    Ok(StructureOutcome {
        report: StructureReport {
            name: structure.name.clone(),
            gmc,
            defender_parameters: objective.defender().num_parameters(),
            adversary_parameters: objective.adversary().num_parameters(),
            seed: settings.seed,
            worst_case: run.best.worst_case,
            best_iteration: run.best.iteration,
            last_value: run.last_value,
            iterations: run.iterations,
            checks: run.checks,
            status: run.status,
            seconds: run.seconds,
        },
        defender: objective.defender().controller(&run.best.defender)?,
        adversary: objective.adversary().controller(&run.best.adversary)?,
    })
}

/// The structures to optimise on: `start` and, when `settings.prune`, every
/// structure the paper's Algorithm 1 keeps when started from `start`
/// ([`crate::prune::prune`] with `settings.prune_paper_literal` and
/// `settings.prune_adversary`), named `pruned-1`, `pruned-2`, ...
pub fn candidate_structures(
    game: &Posg,
    dra: &Dra,
    start: Structure,
    settings: &Settings,
) -> Result<Vec<Structure>, OptimiseError> {
    let pruned = if settings.prune {
        let prune_settings = PruneSettings {
            paper_literal: settings.prune_paper_literal,
            prune_adversary: settings.prune_adversary,
        };
        prune(
            game,
            dra,
            &start.defender,
            &start.adversary,
            &prune_settings,
        )?
        .structures
    } else {
        Vec::new()
    };
    let mut structures = vec![start];
    structures.extend(pruned.into_iter().enumerate().map(|(k, kept)| Structure {
        name: format!("pruned-{}", k + 1),
        defender: kept.defender,
        adversary: kept.adversary,
    }));
    Ok(structures)
}

/// The library's main job: optimise a defender of `defender_nodes` nodes
/// against adversaries of `adversary_nodes` nodes on the full support
/// structure ([`Structure::full`]) and on the structures pruning keeps
/// ([`candidate_structures`]), and report the best defender found.
pub fn solve<F>(
    game: &Posg,
    dra: &Dra,
    negated: Option<&Dra>,
    defender_nodes: usize,
    adversary_nodes: usize,
    settings: &Settings,
    observer: F,
) -> Result<Solution, OptimiseError>
where
    F: Fn(usize, &Structure) -> Box<dyn Observer + Send> + Sync,
{
    settings.validate()?;
    if defender_nodes == 0 || adversary_nodes == 0 {
        return Err(
            ModelError::new("controller sizes", "a controller needs at least one node").into(),
        );
    }
    let full = Structure::full(
        game,
        defender_nodes,
        adversary_nodes,
        settings.optimise_initial,
    );
    let structures = candidate_structures(game, dra, full, settings)?;
    optimise_structures(game, dra, negated, &structures, settings, observer)
}
