//! The expected-reward optimiser (method.md section 9). On a game without
//! adversary (a POMDP or an MDP): the single-player ascent under the one
//! driver ([`Optimiser`] with [`Method::Ascent`]: L-BFGS on the defender's
//! logits, the same stopping rules and observers as a probability
//! objective), climbing the expected reward itself (negated for a cost,
//! so that the defender always maximises), from `settings.starts` seeded
//! starts in parallel on the full support of the given size. On a game
//! with an adversary: the alternating ascent-descent of method.md section
//! 4 ([`Method::MaxMin`]) on the same objective, with best-response checks
//! for its worst-case estimate. The returned defender is the best start's
//! incumbent or one of its roundings (the softmax keeps every supported
//! choice above `exp(-2c)`; a rounding removes that residue) or a hill
//! climb's end, judged by what it guarantees ([`judged`]): its expected
//! reward evaluated again exactly (within its error bound, method.md
//! section 8) where there is no adversary, and its certified worst case
//! against every adversary ([`crate::certify::reward`]) where there is one.

use std::sync::{Mutex, PoisonError};
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use super::objective::Objective;
use super::observer::{IterationRecord, Observer, RecordSource};
use super::optimiser::Optimiser;
use super::rounding::{rounded_candidates, truncated};
use super::softmax::Softmax;
use super::{Cancel, Method, OptimiseError, Settings, Status, Structure, keep_solved};
use super::{WARM_START_MIX, embed, pad};
use crate::automaton::Dra;
use crate::certify::reward::{RewardCertificate, optimal_response, reward_certificate};
use crate::certify::{CertifyError, MdpError};
use crate::controller::{Choice, Fsc, Role, Support};
use crate::game::{Posg, RewardModel};
use crate::mdp::Optimum;
use crate::synthesis::{Mode, SynthesisError, synthesise};
use crate::value::{Evaluation, Evaluator};

/// An expected-reward objective as the optimiser takes it: the automaton
/// of `F T`, the reward model and whether the defender minimises.
#[derive(Debug, Clone, Copy)]
pub struct ExpectedReward<'a> {
    /// The automaton of `F T`.
    pub target: &'a Dra,
    /// The automaton of `!F T`, for the almost-sure support synthesis of
    /// a cost ([`reward_structure`]).
    pub not_target: &'a Dra,
    /// The reward model.
    pub rewards: &'a RewardModel,
    /// Whether the defender minimises the expected reward (a cost).
    pub minimise: bool,
}

impl ExpectedReward<'_> {
    /// `1` where the defender maximises the expected reward, `-1` where it
    /// minimises it: comparing `sense * value` ranks in the query's
    /// direction.
    pub fn sense(&self) -> f64 {
        if self.minimise { -1.0 } else { 1.0 }
    }
}

/// What one start of the expected-reward optimiser ended with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RewardStart {
    /// The start's index (its random stream; `settings.starts` is the warm
    /// start of a grown run).
    pub start: usize,
    /// The expected reward of the start's best defender.
    pub value: f64,
    /// Its iterations.
    pub iterations: usize,
    /// Why it stopped.
    pub status: Status,
    /// Its wall-clock seconds.
    pub seconds: f64,
}

/// The expected-reward optimiser's result.
#[derive(Debug, Clone)]
pub struct RewardSolution {
    /// The best defender found.
    pub defender: Fsc,
    /// What it guarantees: its expected reward, evaluated
    /// exactly, on a game without adversary; its certified worst case
    /// against every adversary on a game with one (method.md section 9).
    pub value: f64,
    /// A bound on `|value - exact value|` (method.md section 8); on a game
    /// with an adversary, the width of the worst case's certified bracket.
    pub error_bound: f64,
    /// The returned defender's certificate: its worst case against every
    /// adversary (on a game without adversary, its exact value again) and
    /// the bound from the defender that sees the state against the
    /// adversaries found and the uniform one
    /// ([`RewardCertificate::best_possible`]); `None` only on a game without
    /// adversary whose product could not be solved to the tolerance (its
    /// value is exact without it).
    pub certificate: Option<RewardCertificate>,
    /// On a game with an adversary: the starts' adversaries (each the best
    /// response to its start's best defender), which bound what any
    /// defender can get, with the uniform one.
    pub adversaries: Vec<Fsc>,
    /// Each start's result, in start order.
    pub starts: Vec<RewardStart>,
    /// The start whose defender was returned ([`RewardStart::start`]).
    pub best_start: usize,
    /// The starts dropped for numerical trouble, with why.
    pub dropped_starts: Vec<String>,
    /// Wall-clock seconds of the whole run.
    pub seconds: f64,
}

/// Optimises a defender of `nodes` nodes (against adversaries of
/// `adversary_nodes` nodes in the gradient play of a game with an
/// adversary) for `objective` on `game`; every iteration's record goes to
/// `observer` (the expected reward in `value` and `worst_case`, with its
/// sign), then one `returned` record for the defender returned. Stops
/// early when `cancel` is set.
pub fn optimise_expected_reward(
    game: &Posg,
    objective: ExpectedReward<'_>,
    (nodes, adversary_nodes): (usize, usize),
    settings: &Settings,
    cancel: &Cancel,
    observer: &mut (dyn Observer + Send),
) -> Result<RewardSolution, OptimiseError> {
    let started = Instant::now();
    let structure = Structure::full(game, nodes, adversary_nodes, settings.optimise_initial);
    // Whether the target can be missed is a fact of the supports' graph:
    // the evaluator's analysis says it without a solve. For a cost, the
    // sizes race on supports that reach the target ([`reward_structure`]).
    let infinite = !objective.minimise
        && evaluator(
            game,
            objective,
            (&structure.defender, &structure.adversary),
            settings,
        )?
        .is_infinite();
    if infinite && game.has_adversary() {
        return Err(OptimiseError::Unsupported(
            "every pair of controllers on the full supports misses the target with positive \
             probability, so the gradient play has no finite reward to climb; a game with an \
             adversary is optimised for `Rmax` where they reach it (docs/method.md section 9)"
                .into(),
        ));
    }
    let (mut solution, iterations, logit_bound, source) = if infinite {
        let solution = infinite_on_full_support(objective, structure.defender, started)?;
        (solution, 0, settings.logit_bound, RecordSource::Gradient)
    } else {
        observer.phase(&super::Phase::Race);
        let sizes = (nodes, adversary_nodes);
        grown(game, objective, sizes, settings, cancel, observer, started)?
    };
    // The bound of the defender that sees the state against the
    // adversaries found and the uniform one (a game without adversary's
    // only one: the MDP bound); on a game with an adversary the certified
    // worst case is the value returned.
    let uniform = Fsc::uniform_enabled(Role::Adversary, adversary_nodes, game.adversary());
    let tried: Vec<&Fsc> = solution.adversaries.iter().chain([&uniform]).collect();
    let certified = reward_certificate(
        game,
        (objective.target, objective.rewards, objective.minimise),
        &solution.defender,
        &tried,
        &settings.solver_settings(),
    );
    solution.certificate = match certified {
        Ok(certificate) => Some(certificate),
        // On a game without adversary the value is exact without it: a
        // bound that cannot be had is left out.
        Err(error) if !game.has_adversary() && error.is_numerical() => None,
        Err(error) => return Err(error.into()),
    };
    if let Some(certificate) = solution.certificate.filter(|_| game.has_adversary()) {
        solution.value = certificate.guaranteed;
        solution.error_bound =
            bracket_width(certificate.worst_case.lower, certificate.worst_case.upper);
    }
    observer.observe(&IterationRecord {
        start: solution.best_start,
        iteration: iterations,
        seconds: started.elapsed().as_secs_f64(),
        value: solution.value,
        defender_gradient_norm: 0.0,
        adversary_gradient_norm: 0.0,
        defender_step: 0.0,
        adversary_step: 0.0,
        worst_case: Some(solution.value),
        certified_lower: None,
        upper_bound: None,
        logit_bound,
        source,
        returned: true,
    });
    observer.finish().map_err(OptimiseError::Observer)?;
    Ok(solution)
}

/// The race of each defender size from 1 node up to `nodes` (only `nodes`
/// with `settings.grow_defender` off), as the probability objectives grow
/// (method.md section 4, "growth of memory"): each size races its fresh
/// starts and one more, the best smaller defender embedded ([`embed`]),
/// and returns the better of its own result and that smaller defender
/// padded to its size ([`pad`]: the same behaviour, so the same value).
/// A larger defender can play every smaller one, so the value never gets
/// worse with memory. Only the last size's records go to `observer`.
fn grown(
    game: &Posg,
    objective: ExpectedReward<'_>,
    (nodes, adversary_nodes): (usize, usize),
    settings: &Settings,
    cancel: &Cancel,
    observer: &mut (dyn Observer + Send),
    started: Instant,
) -> Result<(RewardSolution, usize, f64, RecordSource), OptimiseError> {
    let sense = objective.sense();
    let first = if settings.grow_defender { 1 } else { nodes };
    let mut previous: Option<(RewardSolution, usize, f64, RecordSource)> = None;
    // A cancelled run still passes through every size (each start stops
    // at its first iteration), so the defender returned has `nodes` nodes.
    for size in first..=nodes {
        let mut quiet = ();
        let sink: &mut (dyn Observer + Send) = if size == nodes {
            &mut *observer
        } else {
            &mut quiet
        };
        let structure = match reward_structure(game, objective, (size, adversary_nodes), settings)?
        {
            Ok(structure) => structure,
            // Memory may be what reaching the target needs: a smaller size
            // without an almost-sure support is passed over, and the size
            // asked for keeps the smaller defender found, padded.
            Err(_) if size < nodes => continue,
            Err(reason) => match previous.take() {
                Some((smaller, iterations, logit_bound, source)) => {
                    let padded = RewardSolution {
                        defender: pad(&smaller.defender, size)?,
                        ..smaller
                    };
                    previous = Some((padded, iterations, logit_bound, source));
                    continue;
                }
                None => return Err(OptimiseError::Unsupported(reason)),
            },
        };
        let synthesised = structure.name != "full";
        let warm = match &previous {
            // The synthesised support is proved from its initial node
            // only: the warm start keeps the smaller defender's.
            Some((smaller, ..)) => match embed(
                &smaller.defender,
                &structure.defender,
                WARM_START_MIX,
                settings.optimise_initial && !synthesised,
            ) {
                Ok(warm) => Some(warm),
                // A synthesised support need not hold the smaller
                // defender's pairs: that size races without it (and its
                // result is still compared with the smaller one below).
                Err(_) if synthesised => None,
                Err(error) => return Err(error.into()),
            },
            None => None,
        };
        let mut result = race(
            game, objective, &structure, warm, settings, cancel, sink, started,
        )?;
        if let Some((smaller, ..)) = previous {
            if sense * smaller.value > sense * result.0.value {
                result.0.defender = pad(&smaller.defender, size)?;
                result.0.value = smaller.value;
                result.0.error_bound = smaller.error_bound;
                result.3 = RecordSource::Gradient;
            }
        }
        previous = Some(result);
    }
    previous.ok_or(OptimiseError::NoStructure)
}

/// The seeded starts in parallel on `structure` (and one more from `warm`,
/// a defender on its support, when given), each reporting to `observer` as
/// it goes; the best start's defender or its best rounding or climb, with
/// the iterations of that start, its logit bound and the source of the
/// defender returned.
#[allow(clippy::too_many_arguments)]
fn race(
    game: &Posg,
    objective: ExpectedReward<'_>,
    structure: &Structure,
    warm: Option<Fsc>,
    settings: &Settings,
    cancel: &Cancel,
    observer: &mut (dyn Observer + Send),
    started: Instant,
) -> Result<(RewardSolution, usize, f64, RecordSource), OptimiseError> {
    let shared = Mutex::new(observer);
    let sense = objective.sense();
    let warm = warm.map(|defender| Structure {
        defender,
        warm: None,
        ..structure.clone()
    });
    let starts = settings.starts + usize::from(warm.is_some());
    let results: Vec<Result<StartResult, OptimiseError>> = (0..starts)
        .into_par_iter()
        .map(|start| {
            let mut signed = Signed {
                start,
                sense,
                shared: &shared,
            };
            let begins = warm.as_ref().filter(|_| start == settings.starts);
            run_start(
                game,
                objective,
                begins.unwrap_or(structure),
                settings,
                start,
                cancel,
                &mut signed,
            )
        })
        .collect();
    // A start whose system cannot be solved to the tolerance is dropped, as
    // in the probability race; all of them failing is the error.
    let (kept, dropped) = keep_solved(results)?;
    let runs: Vec<StartResult> = kept.into_iter().map(|(_, run)| run).collect();
    let best = (0..runs.len())
        .max_by(|&a, &b| (sense * runs[a].start.value).total_cmp(&(sense * runs[b].start.value)))
        .ok_or(OptimiseError::NoStructure)?;
    let StartResult {
        defender: looped,
        start: best,
        logit_bound,
        ..
    } = runs[best].clone();
    let (defender, evaluation, source) = rounded(game, objective, looped, settings)?;
    let ((defender, evaluation, source), _) = climb(
        game,
        objective,
        (defender, evaluation, source),
        (settings.max_work, 0.0, settings),
        cancel,
    )?;
    let (defender, evaluation, source) = restarted(
        game,
        objective,
        structure,
        (defender, evaluation, source),
        settings,
        cancel,
    )?;
    let solution = RewardSolution {
        defender,
        value: evaluation.value,
        error_bound: evaluation.error_bound,
        certificate: None,
        adversaries: match game.has_adversary() {
            true => runs.iter().map(|run| run.adversary.clone()).collect(),
            false => Vec::new(),
        },
        starts: runs.iter().map(|run| run.start).collect(),
        best_start: best.start,
        dropped_starts: dropped
            .into_iter()
            .map(|(start, error)| format!("start {start}: {error}"))
            .collect(),
        seconds: started.elapsed().as_secs_f64(),
    };
    Ok((solution, best.iterations, logit_bound, source))
}

/// The structure a size of a cost races on: the full support where every
/// controller of it reaches the target almost surely (on a game with an
/// adversary: where the uniform defender's certified worst case is
/// finite, against every adversary), else the maximised almost-sure
/// support of the SAT synthesis for `F T` (method.md sections 7 and 9: the
/// uniform defender on it reaches `T` with probability 1 against every
/// adversary, which depends only on the support, so every controller the
/// race plays on it has a finite expected cost). `Err(why)` where no
/// support of `size` nodes reaching `T` almost surely was found (every
/// defender of that size then has an infinite cost, where the synthesis
/// proves it). A reward to maximise always races on the full support.
fn reward_structure(
    game: &Posg,
    objective: ExpectedReward<'_>,
    (size, adversary_nodes): (usize, usize),
    settings: &Settings,
) -> Result<Result<Structure, String>, OptimiseError> {
    let full = Structure::full(game, size, adversary_nodes, settings.optimise_initial);
    if !objective.minimise {
        return Ok(Ok(full));
    }
    // An adversary that sees the state may keep the target away where one
    // of the supports' controllers would not.
    let misses = match game.has_adversary() {
        true => judged(game, objective, &full.defender, settings)?
            .0
            .value
            .is_infinite(),
        false => {
            evaluator(game, objective, (&full.defender, &full.adversary), settings)?.is_infinite()
        }
    };
    if !misses {
        return Ok(Ok(full));
    }
    let almost_sure = crate::synthesis::Settings {
        mode: Mode::AlmostSure,
        ..settings.synthesis.clone()
    };
    let nodes = crate::output::counted(size, "node");
    let (target, not_target) = (objective.target, objective.not_target);
    let found = match synthesise(
        game,
        target,
        not_target,
        size,
        &almost_sure,
        &settings.solver_settings(),
    ) {
        Ok(found) => found,
        Err(SynthesisError::TimeBudget { calls, seconds }) => {
            return Ok(Err(format!(
                "every controller of {nodes} on the full support misses the target with \
                 positive probability, and the almost-sure support synthesis gave no answer \
                 within its time budget ({calls} SAT calls, {seconds:.1} s; \
                 --synthesis-time-budget) (docs/method.md sections 7 and 9)"
            )));
        }
        Err(error) => return Err(error.into()),
    };
    Ok(match found.defender {
        Some(defender) => Ok(Structure {
            name: format!("sat-{}", Mode::AlmostSure.name()),
            defender,
            ..full
        }),
        None => Err(format!(
            "every controller of {nodes} on the full support misses the target with positive \
             probability, so its expected cost is infinite, and no support of {nodes} \
             reaching it almost surely was found: {}{} (docs/method.md sections 7 and 9)",
            found.reason,
            if found.exact {
                ""
            } else {
                " (not a proof: the search was cut short)"
            }
        )),
    })
}

/// The result where the full support's expected reward is infinite (the
/// target is missed with positive probability) for `Rmax`: that is the
/// optimum, which the uniform defender attains.
fn infinite_on_full_support(
    objective: ExpectedReward<'_>,
    defender: Fsc,
    started: Instant,
) -> Result<RewardSolution, OptimiseError> {
    debug_assert!(!objective.minimise);
    Ok(RewardSolution {
        defender,
        value: f64::INFINITY,
        error_bound: 0.0,
        certificate: None,
        adversaries: Vec::new(),
        starts: Vec::new(),
        best_start: 0,
        dropped_starts: Vec::new(),
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// What one start of the race ends with.
#[derive(Clone)]
struct StartResult {
    /// Its best defender.
    defender: Fsc,
    /// The adversary of that defender's last best response (the only
    /// adversary of a game without one).
    adversary: Fsc,
    start: RewardStart,
    /// The logit bound it ended with.
    logit_bound: f64,
}

/// One seeded start: the driver running the single-player ascent (the
/// alternating ascent-descent on a game with an adversary) on the
/// structure's objective.
fn run_start(
    game: &Posg,
    objective: ExpectedReward<'_>,
    structure: &Structure,
    settings: &Settings,
    start: usize,
    cancel: &Cancel,
    observer: &mut dyn Observer,
) -> Result<StartResult, OptimiseError> {
    let clock = Instant::now();
    let settings = settings.for_start(start);
    let objective = Objective::for_expected_reward(
        game,
        (objective.target, objective.rewards, objective.minimise),
        Softmax::new(&structure.defender, settings.optimise_initial),
        Softmax::new(&structure.adversary, settings.optimise_initial),
        &settings.solver_settings(),
    )?;
    let sense = objective.sense();
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    rng.set_stream(start as u64);
    let method = match game.has_adversary() {
        true => Method::MaxMin,
        false => Method::Ascent,
    };
    let mut optimiser = Optimiser::new(method, objective, &settings, rng).with_cancel(cancel);
    let mut run = optimiser.begin(clock)?;
    let stopped = optimiser.advance(&mut run, settings.max_iterations, observer)?;
    let outcome = optimiser.finish(run, stopped.unwrap_or(Status::MaxIterations))?;
    let (objective, _) = optimiser.into_parts();
    let defender = objective.defender().controller(&outcome.best.defender)?;
    let adversary = objective.adversary().controller(&outcome.best.adversary)?;
    let start = RewardStart {
        start,
        value: sense * outcome.best.worst_case,
        iterations: outcome.iterations,
        status: outcome.status,
        seconds: clock.elapsed().as_secs_f64(),
    };
    Ok(StartResult {
        defender,
        adversary,
        start,
        logit_bound: outcome.logit_bound,
    })
}

/// The best of `defender` and its roundings ([`rounded_candidates`]: the
/// partial and the argmax roundings, each on its own support) by what it
/// guarantees ([`judged`]; an infinite value counts as the worst cost and
/// the best reward), passing over those it cannot judge ([`passes_over`];
/// the error of the first where none can be). Returns the defender, its
/// judgement and where it came from.
fn rounded(
    game: &Posg,
    objective: ExpectedReward<'_>,
    defender: Fsc,
    settings: &Settings,
) -> Result<(Fsc, Evaluation, RecordSource), OptimiseError> {
    let sense = objective.sense();
    let roundings = rounded_candidates(&defender)?;
    let candidates = std::iter::once((defender, RecordSource::Gradient)).chain(
        roundings
            .into_iter()
            .map(|(_, c)| (c, RecordSource::Rounding)),
    );
    let mut best: Option<(Fsc, Evaluation, RecordSource)> = None;
    let mut first_error = None;
    for (candidate, source) in candidates {
        // An infinite value is the worst cost and the best reward (Storm's
        // convention, method.md section 9): the comparison sees both.
        let evaluation = match judged(game, objective, &candidate, settings) {
            Ok((evaluation, _)) => evaluation,
            Err(error) if passes_over(&error) => {
                first_error.get_or_insert(error);
                continue;
            }
            Err(error) => return Err(error),
        };
        if best
            .as_ref()
            .is_none_or(|b| sense * evaluation.value > sense * b.1.value)
        {
            best = Some((candidate, evaluation, source));
        }
    }
    best.ok_or_else(|| first_error.unwrap_or(OptimiseError::NoStructure))
}

/// The better of `best` and the hill climbs ([`climb`]) from
/// `settings.local_search_restarts` random deterministic controllers on
/// `structure`'s support (each block one of its `(next node, action)`
/// pairs, drawn uniformly; seeded by `settings.seed`, on streams of their
/// own), which together spend at most `settings.local_search_work` of
/// work (each evaluation's GMC states, at least the game's states: an
/// evaluator's tables span the game), and none where one evaluation leaves
/// each restart fewer than [`MIN_EVALUATIONS_PER_RESTART`]; none without
/// `settings.local_search`. The ascent and the climb
/// from its rounding end in one basin; where the optimum needs memory
/// used in a coordinated way (SAYNT's stand-tiger-95: listen, then open,
/// remembering what was heard), the ascent from uniform controllers stops
/// at never opening, and a restart lands elsewhere.
fn restarted(
    game: &Posg,
    objective: ExpectedReward<'_>,
    structure: &Structure,
    mut best: (Fsc, Evaluation, RecordSource),
    settings: &Settings,
    cancel: &Cancel,
) -> Result<(Fsc, Evaluation, RecordSource), OptimiseError> {
    if !settings.local_search {
        return Ok(best);
    }
    let sense = objective.sense();
    let budget = settings.local_search_work as f64;
    // An evaluation costs at least its game's size (the evaluator's tables
    // span every state), however few states the controller reaches.
    let floor = game.num_states() as f64;
    let mut work = 0.0;
    for restart in 0..settings.local_search_restarts {
        if cancel.is_cancelled() || work >= budget {
            break;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
        rng.set_stream(RESTART_STREAMS + restart as u64);
        let start = random_deterministic(&structure.defender, &mut rng);
        let evaluation = match judged(game, objective, &start, settings) {
            Ok((evaluation, spent)) => {
                let spent = spent.max(floor);
                work += spent;
                // Restarts that cannot afford a few evaluations each find
                // nothing: where one evaluation costs that much, stop.
                if spent * (MIN_EVALUATIONS_PER_RESTART * settings.local_search_restarts) as f64
                    > budget
                {
                    break;
                }
                evaluation
            }
            Err(error) if passes_over(&error) => continue,
            Err(error) => return Err(error),
        };
        let ((end, value, _), spent) = climb(
            game,
            objective,
            (start, evaluation, RecordSource::LocalSearch),
            ((budget - work).max(f64::MIN_POSITIVE), floor, settings),
            cancel,
        )?;
        work += spent;
        if sense * (value.value - best.1.value) > value.error_bound + best.1.error_bound {
            best = (end, value, RecordSource::LocalSearch);
        }
    }
    Ok(best)
}

/// The fewest evaluations each of [`restarted`]'s restarts must be able
/// to afford within the shared work budget, else the restarts stop after
/// the first evaluation: on SAYNT's rocks-12 (6,553 states), whose random
/// controllers reach few of them, 16 restarts counted by GMC states alone
/// made about a thousand evaluations, found nothing and took 25 s of CPU
/// beside the 10 s of the run.
const MIN_EVALUATIONS_PER_RESTART: usize = 4;

/// The first random stream of [`restarted`]'s restarts (the starts use
/// streams from 0).
const RESTART_STREAMS: u64 = 1 << 40;

/// A deterministic controller on `support`'s pairs: in each block one of
/// its `(next node, action)` pairs, drawn uniformly by `rng`; the initial
/// distribution is `support`'s.
fn random_deterministic(support: &Fsc, rng: &mut ChaCha8Rng) -> Fsc {
    let mut drawn = support.clone();
    for block in &mut drawn.blocks {
        if block.is_empty() {
            continue;
        }
        let pick = block[rng.random_range(0..block.len())];
        *block = vec![Choice {
            probability: 1.0,
            logit: None,
            ..pick
        }];
    }
    drawn
}

/// Hill-climbing over deterministic controllers from the argmax rounding
/// of `from`'s defender: each pass visits the blocks `(g, o)` in order and,
/// in each, every other `(next node, enabled action)` choice, moving to the
/// first that improves what the defender guarantees ([`judged`]) in the
/// query's direction by more than both values' error bounds; passes repeat
/// until one improves nothing, the judgements' work (each one's explored
/// states, at least `floor`) reaches `budget` (0: no limit) or the run is
/// cancelled.
/// The gradient's optima are often randomised; where a deterministic
/// controller beats them in a basin the ascent did not find, this finds
/// it. Returns the better of `from` and the climb's end, and its work.
fn climb(
    game: &Posg,
    objective: ExpectedReward<'_>,
    from: (Fsc, Evaluation, RecordSource),
    (budget, floor, settings): (f64, f64, &Settings),
    cancel: &Cancel,
) -> Result<((Fsc, Evaluation, RecordSource), f64), OptimiseError> {
    let sense = objective.sense();
    let mut here = truncated(&from.0, f64::INFINITY)?;
    // A deterministic `from` is its own rounding: its evaluation stands.
    let evaluated = if here == from.0 {
        Ok((from.1, 0.0))
    } else {
        judged(game, objective, &here, settings).map(|(value, spent)| (value, spent.max(floor)))
    };
    let (mut value, mut work) = match evaluated {
        Ok(found) => found,
        Err(error) if passes_over(&error) => return Ok((from, 0.0)),
        Err(error) => return Err(error),
    };
    let budget_left = |work: f64| budget <= 0.0 || work < budget;
    let player = game.defender();
    let nodes = here.num_nodes();
    let mut improved = true;
    while improved && budget_left(work) && !cancel.is_cancelled() {
        improved = false;
        for b in 0..here.blocks.len() {
            let o = b % here.num_observations();
            let choices: Vec<(usize, usize)> = (0..nodes)
                .flat_map(|next| player.enabled_actions(o).map(move |u| (next, u)))
                .collect();
            for (next, action) in choices {
                if !budget_left(work) || cancel.is_cancelled() {
                    break;
                }
                let current = &here.blocks[b][0];
                if (current.next, current.action) == (next, action) {
                    continue;
                }
                let mut candidate = here.clone();
                candidate.blocks[b] = vec![Choice {
                    next,
                    action,
                    probability: 1.0,
                    logit: None,
                }];
                let (evaluation, spent) = match judged(game, objective, &candidate, settings) {
                    Ok(found) => found,
                    Err(error) if passes_over(&error) => continue,
                    Err(error) => return Err(error),
                };
                work += spent.max(floor);
                let margin = evaluation.error_bound + value.error_bound;
                if sense * (evaluation.value - value.value) > margin {
                    here = candidate;
                    value = evaluation;
                    improved = true;
                }
            }
        }
    }
    if sense * (value.value - from.1.value) > value.error_bound + from.1.error_bound {
        Ok(((here, value, RecordSource::LocalSearch), work))
    } else {
        Ok((from, work))
    }
}

/// What `defender` guarantees, and the states its computation explored
/// (the unit of `settings.max_work`): on a game without adversary its
/// expected reward, evaluated exactly on its own support (GMC states); on
/// a game with one, its certified worst case against every adversary
/// ([`optimal_response`], product MDP states), with the width of that
/// bracket as its error bound.
fn judged(
    game: &Posg,
    objective: ExpectedReward<'_>,
    defender: &Fsc,
    settings: &Settings,
) -> Result<(Evaluation, f64), OptimiseError> {
    if game.has_adversary() {
        let adversary_optimum = match objective.minimise {
            true => Optimum::Max,
            false => Optimum::Min,
        };
        let bound = optimal_response(
            game,
            (objective.target, objective.rewards),
            (defender, Role::Defender),
            adversary_optimum,
            &settings.solver_settings(),
        )?;
        let guaranteed = match objective.minimise {
            true => bound.upper,
            false => bound.lower,
        };
        let evaluation = Evaluation {
            value: guaranteed,
            residual: 0.0,
            iterations: 0,
            error_bound: bracket_width(bound.lower, bound.upper),
        };
        return Ok((evaluation, bound.mdp_states as f64));
    }
    // The game has no adversary: its only controller.
    let adversary = Fsc::uniform_enabled(Role::Adversary, 1, game.adversary());
    let mut evaluator = evaluator(game, objective, (defender, &adversary), settings)?;
    let probabilities = Support::probabilities_of(&adversary);
    let evaluation = evaluator.evaluate(&Support::probabilities_of(defender), &probabilities)?;
    Ok((evaluation, evaluator.gmc().num_states() as f64))
}

/// `upper - lower`, 0 where both are infinite.
fn bracket_width(lower: f64, upper: f64) -> f64 {
    if lower.is_infinite() && upper.is_infinite() {
        0.0
    } else {
        upper - lower
    }
}

/// Whether a candidate's judgement failed in a way that passes over it
/// rather than stopping the run: numerical trouble, or a worst case the
/// analysis does not compute (a minimising adversary with a cycle outside
/// the target that earns nothing or less, method.md section 9).
fn passes_over(error: &OptimiseError) -> bool {
    error.is_numerical()
        || matches!(
            error,
            OptimiseError::Certify(CertifyError::Mdp(MdpError::RewardCycle(_)))
        )
}

/// The evaluator of `objective` on the supports of the two controllers.
fn evaluator(
    game: &Posg,
    objective: ExpectedReward<'_>,
    (defender, adversary): (&Fsc, &Fsc),
    settings: &Settings,
) -> Result<Evaluator, OptimiseError> {
    Ok(Evaluator::for_expected_reward(
        game,
        objective.target,
        objective.rewards,
        &Support::of(defender),
        &Support::of(adversary),
        &settings.solver_settings(),
    )?)
}

/// One start's view of the shared observer: each record, marked with the
/// start's index and with the expected reward's sign restored (the driver
/// maximises `-V` for a cost), goes to the observer as it happens.
struct Signed<'a, 'o> {
    start: usize,
    sense: f64,
    shared: &'a Mutex<&'o mut (dyn Observer + Send)>,
}

impl Observer for Signed<'_, '_> {
    fn observe(&mut self, record: &IterationRecord) {
        let record = IterationRecord {
            start: self.start,
            value: self.sense * record.value,
            worst_case: record.worst_case.map(|w| self.sense * w),
            ..*record
        };
        self.shared
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .observe(&record);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::Role;
    use crate::game::grid::GridSpec;

    /// A restart's start plays one pair of its structure's block in every
    /// block, with probability 1, and the same seed and stream draw the
    /// same controller.
    #[test]
    fn a_random_deterministic_start_plays_one_supported_pair_per_block() {
        let game = GridSpec::default().build().unwrap();
        let support = Fsc::uniform_enabled(Role::Defender, 3, game.defender());
        let draw = |stream: u64| {
            let mut rng = ChaCha8Rng::seed_from_u64(7);
            rng.set_stream(stream);
            random_deterministic(&support, &mut rng)
        };
        let drawn = draw(RESTART_STREAMS);
        assert_eq!(drawn, draw(RESTART_STREAMS));
        assert_ne!(drawn, draw(RESTART_STREAMS + 1));
        for (block, pool) in drawn.blocks.iter().zip(&support.blocks) {
            assert_eq!(block.len(), 1);
            assert_eq!(block[0].probability, 1.0);
            assert!(
                pool.iter()
                    .any(|c| (c.next, c.action) == (block[0].next, block[0].action))
            );
        }
        assert_eq!(drawn.initial, support.initial);
    }
}
