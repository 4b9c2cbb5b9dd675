//! The library's main job, end to end: what `posg-fsc solve`, `sweep` and
//! `demo` run.
//!
//! Given a game, the objective's automata ([`Automata`]: phi, and !phi for
//! the certified bounds), controller sizes and the optimiser's
//! [`Settings`], [`solve`]
//!
//! 1. gathers the support structures of the sources asked for
//!    (`candidate_structures`: the full support, support
//!    synthesis by SAT, the paper's Algorithm 1; method.md sections 5 and 7);
//! 2. optimises on each of them in parallel (the max-min loop or the
//!    single-player ascent, method.md section 4), each reporting to the
//!    observers the caller passes in;
//! 3. keeps the structure with the best certified lower bound (else the
//!    best worst-case estimate), at least as good as a smaller size's result
//!    when one is given ([`Job::floor`], [`optimise::keep_better`]);
//! 4. certifies the best defender's bracket (method.md section 6): its lower
//!    bound against every adversary and the smallest game upper bound over
//!    the best responses found;
//!
//! and returns an [`Outcome`]: the controllers, every structure's report
//! and curve, why each other structure or source lost, the bracket and the
//! timings. [`directory`] writes an outcome as a `solve` directory
//! (docs/formats.md section 9). The pipeline prints nothing: progress goes
//! to the observers, warnings into the outcome.

pub mod directory;
pub mod progress;
mod propositions;
mod query;
mod reward;
mod sweep;

pub use propositions::{PropositionCheck, check_propositions, check_target_propositions};
pub use query::{QueryEstimate, QueryValue};
pub use reward::RewardObjective;
pub use sweep::Chain;

use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

use serde::Serialize;
use thiserror::Error;

use crate::automaton::Dra;
use crate::certify::belief::UpperBoundsOnce;
use crate::certify::{self, Bracket, CertifyError};
use crate::controller::Fsc;
use crate::game::{ModelError, Posg};
use crate::ltl::{self, TranslateError};
use crate::optimise::{
    self, Cancel, IterationRecord, Observer, OptimiseError, Settings, Solution, SourceNote,
    Structure, StructureOutcome, StructureSource,
};
use crate::output::OutputError;

/// The objective as automata: a deterministic automaton for phi, and one
/// for !phi when the certified bracket (method.md section 6) is wanted.
#[derive(Debug, Clone)]
pub struct Automata {
    /// A deterministic automaton for phi: the value is `P(trace |= phi)`.
    pub phi: Dra,
    /// A deterministic automaton for !phi, needed by the certified lower
    /// bound and by the `sat` source of structures; `None`: no bracket.
    pub not_phi: Option<Dra>,
    /// How the objective was given (the formula, or the automaton's file),
    /// for titles and `summary.json`.
    pub description: String,
}

impl Automata {
    /// The automata of the LTL formula `text` (Spot's syntax) and of its
    /// negation, translated without a time budget.
    pub fn from_ltl(text: &str) -> Result<Self, PipelineError> {
        let formula = ltl::parse(text)?;
        Ok(Self {
            phi: ltl::translate(&formula)?,
            not_phi: Some(ltl::translate(&formula.negate())?),
            description: text.to_string(),
        })
    }

    /// The objective of every face (`--ltl`/`--props` on the command
    /// line, `ltl=` in Python): the automata of the LTL formula `text` and,
    /// when `negation`, of its negation (for the certified bracket), each
    /// translated within `budget`, with the formula's propositions checked
    /// against `game`'s labels ([`check_propositions`], whose `allow` is
    /// `allow_unused`). Returns the automata and the check's warnings, for
    /// the face to show; a proposition check that fails is
    /// [`PipelineError::Propositions`], with its warnings too.
    pub fn for_game(
        game: &Posg,
        text: &str,
        budget: &ltl::TranslationBudget,
        negation: bool,
        allow_unused: bool,
    ) -> Result<(Self, Vec<String>), PipelineError> {
        let formula = ltl::parse(text)?;
        let phi = ltl::translate_within(&formula, budget)?;
        let check = check_propositions(&phi, game, text, allow_unused);
        if check.error.is_some() {
            return Err(PipelineError::Propositions(check));
        }
        let not_phi = match negation {
            true => Some(
                ltl::translate_within(&formula.negate(), budget)
                    .map_err(PipelineError::TranslateNegation)?,
            ),
            false => None,
        };
        let automata = Self {
            phi,
            not_phi,
            description: text.to_string(),
        };
        Ok((automata, check.warnings))
    }
}

/// Controller sizes: the defender's and the adversary's number of nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sizes {
    /// The defender's nodes (at least 1).
    pub defender: usize,
    /// The adversary's nodes (at least 1; exactly 1 for a game without an adversary).
    pub adversary: usize,
}

impl Sizes {
    /// Checks the sizes against `game`: at least one node each, uniform
    /// controllers of these sizes within the resource budget
    /// ([`crate::limits`]), and one adversary node for a game without an
    /// adversary (a POMDP). `names` are how the caller spells the two
    /// sizes (`--def-nodes`, `--adv-nodes` on the command line), which the
    /// error names.
    pub fn check(&self, game: &Posg, names: [&str; 2]) -> Result<(), ModelError> {
        let [defender_name, adversary_name] = names;
        for (name, nodes, player) in [
            (defender_name, self.defender, game.defender()),
            (adversary_name, self.adversary, game.adversary()),
        ] {
            let (observations, actions) = (player.num_observations(), player.num_actions());
            Fsc::check_uniform_size(name, nodes, observations, actions)?;
        }
        if !game.has_adversary() && self.adversary != 1 {
            return Err(ModelError::new(
                format!("{adversary_name} {}", self.adversary),
                format!(
                    "the game has no adversary (it is a POMDP), whose controller has exactly \
                     one node; drop {adversary_name}"
                ),
            ));
        }
        Ok(())
    }
}

/// One run of the pipeline: what [`run`] optimises.
#[derive(Debug, Clone)]
pub struct Job<'a> {
    /// The game.
    pub game: &'a Posg,
    /// The objective.
    pub automata: &'a Automata,
    /// The starting structure: [`Structure::full`] of the sizes, or the
    /// user's controllers (then named `from-files`), or a warm start.
    pub start: Structure,
    /// The best outcome of a smaller defender size (a sweep): the result is
    /// kept at least as good ([`optimise::keep_better`]).
    pub floor: Option<&'a StructureOutcome>,
    /// The optimiser's settings.
    pub settings: &'a Settings,
    /// Stops the optimisation early when set (by a clone held elsewhere):
    /// the job then certifies and returns the best defender seen so far.
    pub cancel: Cancel,
}

impl<'a> Job<'a> {
    /// The job starting from the full support structure of `sizes`
    /// ([`Structure::full`]); checks the sizes and the settings.
    pub fn full(
        game: &'a Posg,
        automata: &'a Automata,
        sizes: Sizes,
        settings: &'a Settings,
    ) -> Result<Self, PipelineError> {
        settings.validate()?;
        sizes.check(game, ["the defender's size", "the adversary's size"])?;
        Ok(Self {
            game,
            automata,
            start: Structure::full(
                game,
                sizes.defender,
                sizes.adversary,
                settings.optimise_initial,
            ),
            floor: None,
            settings,
            cancel: Cancel::new(),
        })
    }

    /// Whether [`run`] grows the defender from 1 node: where the settings ask
    /// for it ([`Settings::grow_defender`]), the defender has more than one
    /// node, and the job starts from the full support structure with no
    /// floor of its own (not from the user's controllers, not a warm start).
    pub fn grows(&self) -> bool {
        self.settings.grow_defender
            && self.floor.is_none()
            && self.start.name == "full"
            && self.start.defender.num_nodes() > 1
    }

    /// The job warm-started from `smaller`, the best outcome of a smaller
    /// defender size ([`optimise::warm_started`]), and kept at least as good.
    pub fn warm_started(self, smaller: &'a StructureOutcome) -> Result<Self, PipelineError> {
        let start = optimise::warm_started(
            self.start,
            &smaller.defender,
            self.settings.optimise_initial,
        )?;
        Ok(Self {
            start,
            floor: Some(smaller),
            ..self
        })
    }
}

/// What an observer factory is told about the structure it will observe.
#[derive(Debug, Clone, Copy)]
pub struct Slot<'a> {
    /// The structure's position among the structures tried.
    pub index: usize,
    /// How many structures are tried.
    pub count: usize,
    /// The structure.
    pub structure: &'a Structure,
    /// The defender's size in this run: a grown run ([`Settings::grow_defender`])
    /// optimises every smaller size first.
    pub defender_nodes: usize,
}

/// A step of a run that concerns no one structure, announced to
/// [`Watch::step`] as it begins (or, for [`Step::SizeDone`], as it ends).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Step {
    /// Gathering the candidate structures of a defender size (the informed
    /// projection, support synthesis by SAT, the paper's Algorithm 1;
    /// method.md sections 5 and 7): `defender_nodes` of `final_nodes`.
    Supports {
        /// The size whose structures are gathered.
        defender_nodes: usize,
        /// The job's own size (a grown run optimises every size up to it).
        final_nodes: usize,
    },
    /// One source's search for structures begins (after
    /// [`Step::Supports`]).
    Source(StructureSource),
    /// Certifying the best defender of a size (method.md section 6).
    Certifying {
        /// The size whose best defender is certified.
        defender_nodes: usize,
    },
    /// A size's result is known.
    SizeDone(SizeResult),
}

/// What watches a run ([`run`]): an observer for each structure's
/// optimisation, and the steps between them ([`observing`] makes one of
/// an observer factory, [`Unwatched`] watches nothing,
/// [`progress::Progress::watching`] adds a progress board).
pub trait Watch: Sync {
    /// The observer of the structure in `slot`.
    fn structure(&self, slot: Slot) -> Box<dyn Observer + Send>;

    /// Called as each [`Step`] begins.
    fn step(&self, _step: &Step) {}
}

/// The watch that observes nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Unwatched;

impl Watch for Unwatched {
    fn structure(&self, _slot: Slot) -> Box<dyn Observer + Send> {
        Box::new(())
    }
}

/// The watch that gives each structure the observer `observer(slot)`
/// makes and ignores the steps.
pub fn observing<F>(observer: F) -> Observing<F>
where
    F: Fn(Slot) -> Box<dyn Observer + Send> + Sync,
{
    Observing(observer)
}

/// The watch [`observing`] makes.
#[derive(Debug, Clone, Copy)]
pub struct Observing<F>(F);

impl<F> Watch for Observing<F>
where
    F: Fn(Slot) -> Box<dyn Observer + Send> + Sync,
{
    fn structure(&self, slot: Slot) -> Box<dyn Observer + Send> {
        (self.0)(slot)
    }
}

/// One defender size of a run ([`Outcome::sizes`]): a grown run
/// ([`Settings::grow_defender`]) has one per size from 1 node up, each
/// warm-started from and at least as good as the one before.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SizeResult {
    /// The defender's nodes.
    pub defender_nodes: usize,
    /// The best defender's certified bracket at this size (as
    /// [`Outcome::certified`]).
    pub certified: Option<Bracket>,
    /// Its worst-case estimate.
    pub worst_case: f64,
    /// Wall-clock seconds of this size's run.
    pub seconds: f64,
    /// Seconds into this size's run when some structure first certified a
    /// lower bound above 0 (its curve's first such record); `None` if none did.
    pub first_positive_seconds: Option<f64>,
}

/// One structure's curve: the records its observers received, every
/// start's, in the order they arrived.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// The structure's name.
    pub structure: String,
    /// One record per outer iteration of each start.
    pub records: Vec<IterationRecord>,
}

/// What the pipeline found.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Every structure's outcome (controllers and report) and the best one.
    pub solution: Solution,
    /// What each source of structures found, proved or why it gave none.
    pub sources: Vec<SourceNote>,
    /// One curve per structure tried, in the order tried (a structure
    /// dropped for numerical trouble keeps the records it had).
    pub curves: Vec<Curve>,
    /// The best defender's certified bracket: its lower bound against every
    /// adversary, and the smallest game upper bound over the best responses
    /// found (method.md section 6); `None` without an automaton for !phi or
    /// when the defender could not be certified.
    pub certified: Option<Bracket>,
    /// Why `certified` is `None` although an automaton for !phi was given:
    /// the best defender's product mixes too slowly for its bound to be
    /// solved to the tolerance (method.md section 8).
    pub certification_error: Option<String>,
    /// Why the best structure won, then why each other structure or source
    /// lost (one sentence each).
    pub structure_choice: Vec<String>,
    /// Every defender size optimised, smallest first, the job's own last.
    pub sizes: Vec<SizeResult>,
    /// Wall-clock seconds of the whole job.
    pub seconds: f64,
    /// Seconds of support synthesis (the `sat` source).
    pub synthesis_seconds: f64,
}

impl Outcome {
    /// The best structure's outcome.
    pub fn best(&self) -> &StructureOutcome {
        self.solution.best()
    }

    /// The query of `property` restated for the returned defender: its
    /// worst-case estimate, error bound and certified bracket in the
    /// query's terms ([`QueryValue::solved`]).
    pub fn query(&self, property: &crate::ltl::props::Property) -> QueryValue {
        let report = &self.best().report;
        QueryValue::solved(
            property,
            report.worst_case,
            report.error_bound,
            self.certified,
        )
    }
}

/// Why the pipeline could not finish.
#[derive(Debug, Error)]
pub enum PipelineError {
    /// The formula could not be parsed.
    #[error(transparent)]
    Parse(#[from] ltl::ParseError),
    /// The formula could not be translated into an automaton.
    #[error(transparent)]
    Translate(#[from] TranslateError),
    /// The formula's negation (for the certified bracket) could not be
    /// translated into an automaton.
    #[error("translating !phi: {0}")]
    TranslateNegation(TranslateError),
    /// A size or a controller does not fit the game.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Optimisation failed.
    #[error(transparent)]
    Optimise(#[from] OptimiseError),
    /// The best defender's bracket could not be computed.
    #[error(transparent)]
    Certify(#[from] CertifyError),
    /// An output file could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A report could not be written as JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// The objective's propositions label no state of the game and make it
    /// unsatisfiable ([`check_propositions`]): the check, whose `error` is
    /// the message and whose `warnings` name each such proposition.
    #[error("{}", .0.error.as_deref().unwrap_or("the objective's propositions label no state"))]
    Propositions(PropositionCheck),
}

/// The main job from the full support structure: optimise a defender of
/// `sizes.defender` nodes against adversaries of `sizes.adversary` nodes on
/// the structures of `settings.structures`, keep the best, certify it
/// ([`run`] of [`Job::full`]). `observers` makes each structure's observer.
///
/// ```
/// use posg_fsc::game::grid::GridSpec;
/// use posg_fsc::optimise::Settings;
/// use posg_fsc::pipeline::{self, Automata, Sizes};
///
/// let game = GridSpec::default().build().unwrap(); // the seed paper's 3x2 grid
/// let automata = Automata::from_ltl("!unsafe U goal").unwrap();
/// let settings = Settings { max_iterations: 20, starts: 1, ..Settings::default() };
/// let sizes = Sizes { defender: 1, adversary: 1 };
/// let outcome = pipeline::solve(&game, &automata, sizes, &settings, pipeline::Unwatched).unwrap();
/// let bracket = outcome.certified.expect("a formula gives a certified bracket");
/// assert!(bracket.certified_lower <= bracket.upper_bound);
/// assert!(bracket.certified_lower <= outcome.best().report.worst_case + 1e-9);
/// assert_eq!(outcome.curves.len(), outcome.solution.structures.len());
/// ```
pub fn solve(
    game: &Posg,
    automata: &Automata,
    sizes: Sizes,
    settings: &Settings,
    watch: impl Watch,
) -> Result<Outcome, PipelineError> {
    run(Job::full(game, automata, sizes, settings)?, watch)
}

/// Runs `job`: gathers the structures, optimises on each (each reporting to
/// the observer `watch` makes for its slot, every step announced to
/// `watch`), keeps the best (at least as good as `job.floor`),
/// certifies its bracket. Where the job grows ([`Job::grows`]), every
/// smaller defender size runs first, from 1 node up, each warm-started from
/// and floored by the one before ([`Job::warm_started`]): the result then
/// certifies at least what any smaller size would under the same settings
/// (method.md section 4, "Memory that never hurts").
pub fn run(job: Job, watch: impl Watch) -> Result<Outcome, PipelineError> {
    if !job.grows() {
        let nodes = job.start.defender.num_nodes();
        return run_size(job, &watch, nodes);
    }
    let clock = Instant::now();
    let nodes = job.start.defender.num_nodes();
    let adversary = job.start.adversary.num_nodes();
    let mut sizes = Vec::with_capacity(nodes);
    let mut smaller: Option<Outcome> = None;
    for k in 1..=nodes {
        if let Some(previous) = smaller.as_mut() {
            if let Some(reason) = why_growth_stops(previous, &job) {
                pad_defenders(previous, nodes, reason)?;
                break;
            }
        }
        let sized = Job::full(
            job.game,
            job.automata,
            Sizes {
                defender: k,
                adversary,
            },
            job.settings,
        )?;
        let sized = Job {
            cancel: job.cancel.clone(),
            ..sized
        };
        let sized = match &smaller {
            Some(previous) => sized.warm_started(previous.best())?,
            None => sized,
        };
        let mut outcome = run_size(sized, &watch, nodes)?;
        if let Some(previous) = &smaller {
            keep_kept_curve(&mut outcome, previous);
        }
        sizes.extend(smaller.take().map(|o| o.sizes).unwrap_or_default());
        sizes.append(&mut outcome.sizes);
        outcome.sizes = std::mem::take(&mut sizes);
        smaller = Some(outcome);
    }
    let mut outcome = smaller.ok_or(OptimiseError::NoStructure)?;
    outcome.seconds = clock.elapsed().as_secs_f64();
    Ok(outcome)
}

/// Where `outcome` kept the result of the smaller size `previous` (named
/// `from-<k>-nodes`, [`optimise::keep_better`]), adds that result's curve
/// under that name, so that the returned defender has its curve.
fn keep_kept_curve(outcome: &mut Outcome, previous: &Outcome) {
    let kept = &outcome.best().report.name;
    let previous_best = &previous.best().report.name;
    if kept != &format!("from-{}-nodes", previous.best().defender.num_nodes()) {
        return;
    }
    if let Some(curve) = previous
        .curves
        .iter()
        .find(|c| &c.structure == previous_best)
    {
        outcome.curves.push(Curve {
            structure: kept.clone(),
            records: curve.records.clone(),
        });
    }
}

/// Why a grown run stops at the size of `outcome`, if it does: its
/// certified gap to the game upper bound is closed (no defender of any size
/// certifies more), or the job was cancelled.
fn why_growth_stops(outcome: &Outcome, job: &Job) -> Option<&'static str> {
    if job.cancel.is_cancelled() {
        return Some("the run was cancelled");
    }
    outcome
        .certified
        .filter(|b| job.settings.gap_closed(b.certified_lower, b.upper_bound))
        .map(|_| "its certified gap to the game upper bound was closed: no larger defender certifies more")
}

/// Every structure's defender of `outcome` padded to `nodes` nodes with the
/// same behaviour ([`optimise::pad`]): the result of a grown run that stopped
/// at a smaller size for `reason`, at the job's size.
fn pad_defenders(outcome: &mut Outcome, nodes: usize, reason: &str) -> Result<(), PipelineError> {
    for structure in &mut outcome.solution.structures {
        structure.defender = optimise::pad(&structure.defender, nodes)?;
    }
    let stopped_at = outcome.sizes.last().map_or(0, |s| s.defender_nodes);
    outcome.structure_choice.push(format!(
        "Grown from 1 node, stopped at {}: {reason}; its defender is padded to {nodes} nodes \
         with the same behaviour.",
        crate::output::counted(stopped_at, "node")
    ));
    Ok(())
}

/// [`run`] at the job's size alone; `final_nodes` is the size a grown run
/// ends at (the job's own when it does not grow), which [`Step::Supports`]
/// tells the watch.
fn run_size(job: Job, watch: &impl Watch, final_nodes: usize) -> Result<Outcome, PipelineError> {
    let clock = Instant::now();
    let Job {
        game,
        automata,
        start,
        floor,
        settings,
        cancel,
    } = job;
    let (phi, not_phi) = (&automata.phi, automata.not_phi.as_ref());
    let belief = UpperBoundsOnce::new(game, phi, settings.solver_settings());
    let defender_nodes = start.defender.num_nodes();
    watch.step(&Step::Supports {
        defender_nodes,
        final_nodes,
    });
    let announce = |source| watch.step(&Step::Source(source));
    let candidates = optimise::candidate_structures(
        game,
        (phi, not_phi),
        start,
        (settings, &belief),
        &announce,
    )?;
    let count = candidates.structures.len();
    let records: Vec<Arc<Mutex<Vec<IterationRecord>>>> =
        (0..count).map(|_| Arc::default()).collect();
    let mut solution = optimise::optimise_structures(
        game,
        (phi, not_phi),
        &candidates.structures,
        settings,
        |index, structure| {
            let given = watch.structure(Slot {
                index,
                count,
                structure,
                defender_nodes: structure.defender.num_nodes(),
            });
            let recorder = Recorder(Arc::clone(&records[index]));
            Box::new(vec![given, Box::new(recorder)]) as Box<dyn Observer + Send>
        },
        &cancel,
        &belief,
    )?;
    if let Some(floor) = floor {
        let nodes = solution.best().defender.num_nodes();
        optimise::keep_better(&mut solution, floor, nodes)?;
    }
    watch.step(&Step::Certifying { defender_nodes });
    let (certified, certification_error) = certify_best(game, automata, &solution)?;
    let curves: Vec<Curve> = candidates
        .structures
        .iter()
        .zip(records)
        .map(|(structure, records)| Curve {
            structure: structure.name.clone(),
            records: std::mem::take(&mut *records.lock().unwrap_or_else(PoisonError::into_inner)),
        })
        .collect();
    let best = solution.best();
    let size = SizeResult {
        defender_nodes: best.defender.num_nodes(),
        certified,
        worst_case: best.report.worst_case,
        seconds: clock.elapsed().as_secs_f64(),
        first_positive_seconds: first_positive_seconds(&curves),
    };
    watch.step(&Step::SizeDone(size));
    let sizes = vec![size];
    Ok(Outcome {
        sizes,
        structure_choice: structure_choice(&solution, &candidates.notes),
        synthesis_seconds: candidates
            .notes
            .iter()
            .filter(|n| n.source == StructureSource::Sat)
            .map(|n| n.seconds)
            .sum(),
        solution,
        sources: candidates.notes,
        curves,
        certified,
        certification_error,
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The best defender's bracket against the adversaries of every structure
/// (the smallest upper bound over them and the structures' own), or why a
/// slowly mixing product has none.
fn certify_best(
    game: &Posg,
    automata: &Automata,
    solution: &Solution,
) -> Result<(Option<Bracket>, Option<String>), PipelineError> {
    let Some(not_phi) = &automata.not_phi else {
        return Ok((None, None));
    };
    let adversaries = solution.structures.iter().map(|s| &s.adversary);
    let bracket = match certify::bracket(
        game,
        &automata.phi,
        not_phi,
        &solution.best().defender,
        adversaries,
    ) {
        Ok(bracket) => bracket,
        Err(error) if error.is_numerical() => return Ok((None, Some(error.to_string()))),
        Err(error) => return Err(error.into()),
    };
    let upper_bound = solution
        .structures
        .iter()
        .filter_map(|s| s.report.upper_bound)
        .fold(bracket.upper_bound, f64::min);
    Ok((
        Some(Bracket {
            upper_bound,
            ..bracket
        }),
        None,
    ))
}

/// Why the best structure won, then why each other structure or source
/// lost (one sentence each).
fn structure_choice(solution: &Solution, notes: &[SourceNote]) -> Vec<String> {
    let best = solution.best();
    let tried: Vec<String> = solution
        .structures
        .iter()
        .map(|s| optimise::described(&s.report.name))
        .chain(
            solution
                .failed
                .iter()
                .map(|(name, _)| optimise::described(name)),
        )
        .collect();
    let measure = match best.report.certified_lower {
        Some(lower) => format!("certified at {lower:.6} against every adversary"),
        None => format!(
            "estimated at {:.6} against the best responses found (no certificate: the \
             objective came as an automaton)",
            best.report.worst_case
        ),
    };
    let tried = match tried.len() {
        1 => "Tried one structure".to_string(),
        k => format!("Tried {k} structures: {}", tried.join("; ")),
    };
    [
        format!("{tried}."),
        format!(
            "Won: {}: its best defender is {measure}.",
            optimise::described(&best.report.name)
        ),
    ]
    .into_iter()
    .chain(optimise::why_others_lost(
        &solution.structures,
        solution.best,
        notes,
        &solution.failed,
    ))
    .collect()
}

/// The earliest `seconds` of a record certifying a lower bound above 0 in
/// any of `curves`.
fn first_positive_seconds(curves: &[Curve]) -> Option<f64> {
    (curves.iter())
        .flat_map(|c| &c.records)
        .filter(|r| r.certified_lower.is_some_and(|l| l > 0.0))
        .map(|r| r.seconds)
        .reduce(f64::min)
}

/// An observer keeping every record in a shared list.
struct Recorder(Arc<Mutex<Vec<IterationRecord>>>);

impl Observer for Recorder {
    fn observe(&mut self, record: &IterationRecord) {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(*record);
    }
}
