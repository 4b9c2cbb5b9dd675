//! The portfolio of max-min starts on one structure, run as a race
//! (method.md section 4). The starts advance in parallel in lockstep
//! rounds that end where the suffix-averaging windows end (iterations
//! `2^k - 1`, where every start checks). After each round a start that
//! has run `stall_checks` checks since its logit bound last widened is
//! stopped as [`Status::Outpaced`] when another start's best score exceeds
//! its own best plus what it gained over the round (the second half of its
//! run): repeating that progress, which would take as many iterations as
//! it has run so far, would still leave it behind. Once one start has
//! closed the certified gap (its own, or the best score against the
//! smallest game upper bound of any start: every start's upper bound
//! bounds the same game value), the others are stopped as outpaced too:
//! none can certify more than `gap_tolerance` above it; a lower bound
//! proved before the race (the local search's) counts as a best score
//! here; where an upper bound was proved before the race (a single
//! player's, whose starts have none of their own), a start meeting it
//! ends the race as well. Decisions are taken
//! between rounds on numbers at the same iteration of every start, so
//! they, and every start's iterations, do not depend on thread timing: a
//! seeded run is reproducible.

use std::time::Instant;

use rayon::prelude::*;

use super::optimiser::{Optimiser, Run, RunOutcome};
use super::{Observer, OptimiseError, Settings, Status};

/// One start in the race: its optimiser, its run in progress, the
/// observer its records go to, why it stopped (once it has), and its best
/// score at the end of the last round.
pub(super) struct Racer<'a, O> {
    optimiser: Optimiser<'a>,
    run: Run,
    observer: O,
    stopped: Option<Status>,
    round_best: Option<f64>,
}

impl<'a, O: Observer + Send> Racer<'a, O> {
    /// The start of `optimiser`, reporting to `observer`; `started` is when
    /// the structure's optimisation began ([`Optimiser::begin`]).
    pub fn new(
        mut optimiser: Optimiser<'a>,
        observer: O,
        started: Instant,
    ) -> Result<Self, OptimiseError> {
        let run = optimiser.begin(started)?;
        Ok(Self {
            optimiser,
            run,
            observer,
            stopped: None,
            round_best: None,
        })
    }

    /// Continues through iteration `last` unless the run stops first, then
    /// frees the factors it would rebuild anyway ([`Optimiser::release`]):
    /// between rounds, only the starts that run hold them.
    fn advance(&mut self, last: usize) -> Result<(), OptimiseError> {
        self.stopped = self
            .optimiser
            .advance(&mut self.run, last, &mut self.observer)?;
        self.optimiser.release();
        Ok(())
    }

    /// The run's outcome, and the optimiser (with its objective and random
    /// stream where the run left them).
    fn finish(mut self) -> Result<(Optimiser<'a>, RunOutcome), OptimiseError> {
        let status = self.stopped.unwrap_or(Status::MaxIterations);
        let outcome = self.optimiser.finish(self.run, status)?;
        Ok((self.optimiser, outcome))
    }

    /// Whether the start still runs.
    fn running(&self) -> bool {
        self.stopped.is_none()
    }
}

/// A best score this close to the ceiling (the upper bound proved before
/// the race) has met it: no defender does better, beyond the values'
/// accuracy (the solver's tolerance, 1e-9). Only a met ceiling ends a
/// single player's race: a start within `gap_tolerance` of it still
/// climbs to it (on PRISM's grid-avoid-4-0 with 1 node, stopping within
/// `gap_tolerance` reported 0.928530 for the optimum 0.928571), where its
/// converging steps cost little.
pub const CEILING_MET: f64 = 1e-8;

/// Runs every start (an error in place of a start that failed to begin
/// or failed later) until each stops; returns each start's optimiser and
/// outcome, or its error. `floor` is a certified lower bound already
/// proved for a defender outside the race (the best of the local
/// searches of every structure, run before the races): once it is within `gap_tolerance` of a start's upper bound, the
/// race is over. `ceiling` is an upper bound on every defender's score
/// proved before the race (a single player's, whose starts check no
/// upper bound of their own): once a start's best score meets it
/// ([`CEILING_MET`]), the race is over too.
pub(super) fn race<'a, O: Observer + Send>(
    mut racers: Vec<Result<Racer<'a, O>, OptimiseError>>,
    settings: &Settings,
    (floor, ceiling): (Option<f64>, Option<f64>),
) -> Vec<Result<(Optimiser<'a>, RunOutcome), OptimiseError>> {
    let mut last = 0usize;
    while racers
        .iter()
        .any(|entry| entry.as_ref().is_ok_and(Racer::running))
    {
        racers.par_iter_mut().for_each(|entry| {
            let failed = match entry {
                Ok(racer) if racer.running() => racer.advance(last).err(),
                _ => None,
            };
            if let Some(error) = failed {
                *entry = Err(error);
            }
        });
        stop_the_outpaced(&mut racers, settings, (floor, ceiling));
        last = last.saturating_mul(2).saturating_add(1);
    }
    racers
        .into_par_iter()
        .map(|entry| entry.and_then(Racer::finish))
        .collect()
}

/// After a round: stops each running start outpaced by the best score of
/// any start, or by a closed gap (module documentation; `floor` counts as
/// a score) or a met `ceiling` (a start that met it has closed the gap),
/// and records each start's best score.
fn stop_the_outpaced<O>(
    racers: &mut [Result<Racer<'_, O>, OptimiseError>],
    settings: &Settings,
    (floor, ceiling): (Option<f64>, Option<f64>),
) {
    // A start that met the ceiling has closed the gap.
    let meets_ceiling = |score: f64| ceiling.is_some_and(|c| c - score <= CEILING_MET);
    for racer in racers.iter_mut().filter_map(|entry| entry.as_mut().ok()) {
        if racer.stopped.is_none() && racer.run.best_score().is_some_and(meets_ceiling) {
            racer.stopped = Some(Status::GapClosed);
        }
    }
    let started = || racers.iter().filter_map(|entry| entry.as_ref().ok());
    let leader = started()
        .filter_map(|racer| racer.run.best_score())
        .chain(floor)
        .reduce(f64::max);
    let upper = started()
        .filter_map(|racer| racer.run.upper_bound())
        .reduce(f64::min);
    // The leader also covers a start that stopped (converged) at the ceiling.
    let gap_closed = started().any(|racer| racer.stopped == Some(Status::GapClosed))
        || leader.is_some_and(meets_ceiling)
        || leader
            .zip(upper)
            .is_some_and(|(lower, upper)| settings.gap_closed(lower, upper));
    for racer in racers.iter_mut().filter_map(|entry| entry.as_mut().ok()) {
        let best = racer.run.best_score();
        if gap_closed && racer.stopped.is_none() {
            racer.stopped = Some(Status::Outpaced);
        }
        if let (Some(best), Some(before), Some(leader), None) =
            (best, racer.round_best, leader, racer.stopped)
        {
            if outpaced(
                best,
                best - before,
                leader,
                racer.run.checks_since_widening(),
                settings,
            ) {
                racer.stopped = Some(Status::Outpaced);
            }
        }
        racer.round_best = best;
    }
}

/// Whether a start whose best score is `best`, after gaining `gain` over
/// the last round with `checks` checks since its logit bound last widened,
/// is outpaced by the best score `leader` of any start.
fn outpaced(best: f64, gain: f64, leader: f64, checks: usize, settings: &Settings) -> bool {
    settings.stall_checks > 0 && checks >= settings.stall_checks && best + gain < leader
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_start_is_outpaced_only_when_repeating_its_last_gain_leaves_it_behind() {
        let settings = Settings::default();
        let enough = settings.stall_checks;
        assert!(outpaced(0.60, 0.01, 0.65, enough, &settings));
        assert!(
            !outpaced(0.60, 0.05, 0.65, enough, &settings),
            "it may catch up"
        );
        assert!(
            !outpaced(0.65, 0.0, 0.65, enough, &settings),
            "the leader itself"
        );
        assert!(
            !outpaced(0.60, 0.0, 0.65, enough - 1, &settings),
            "too soon after widening"
        );
        let never = Settings {
            stall_checks: 0,
            ..Settings::default()
        };
        assert!(!outpaced(0.0, 0.0, 1.0, enough, &never), "stall rule off");
    }
}
