//! The driver's checks at `(phi_def(t), phi_adv(t))` and their
//! certification hooks (method.md sections 4 and 6). Two candidates are
//! judged, the current defender and the suffix average of its
//! probabilities.
//!
//! With a [`super::Certifier`] the everyday check is cheap: each candidate
//! gets its certified lower bound (one MDP solve), and the game upper bound
//! is tightened against the current adversary and the suffix average of
//! the adversary's probabilities. The candidates' worst-case estimates are
//! then their values against the current adversary (an upper bound on the
//! best response). Every `best_response_every`-th check is *deep*: the
//! current defender also gets an L-BFGS best response, warm-started from
//! the current adversary and the last best response found, which tightens
//! the upper bound further. Without a certifier every check is deep for
//! both candidates, with `restarts` random starts besides the warm ones,
//! since the worst-case estimate is then their score.
//! When the portfolio ends, the kept defender of the start chosen (of
//! every start without a certifier, whose ranking is by worst case) gets a
//! full best response ([`Optimiser::settle`]) with `restarts` random
//! starts besides the warm ones: its reported worst case is always a
//! best-response value.
//!
//! Certification is the costly part of a check (a product MDP built and
//! solved per bound), so a check certifies only what can change the run:
//! - a candidate whose value against an adversary (the current one, or
//!   the best response found) is at most the best certified lower bound is
//!   not certified: its certified lower bound is at most its worst case,
//!   which is at most that value, so it cannot replace the incumbent;
//! - the argmax rounding's lower bound is computed again only when the
//!   rounded controller changed, and then at every check only while it
//!   reaches the incumbent's score, otherwise at intervals that double up
//!   to [`ROUNDING_BACKOFF_CAP`] checks ([`Backoff`]);
//! - the game upper bound is tightened against the adversaries at every
//!   check while that tightens it, otherwise at intervals that double up
//!   to `best_response_every` checks ([`Backoff`]); deep checks and the
//!   end tighten it against the best responses found as before.

use std::time::Instant;

use super::super::FreshObjective;
use super::super::best_response::{BestResponse, Starts, best_response, final_best_response};
use super::super::guarantee::{Guarantee, ascend};
use super::super::rounding::truncated;
use super::super::solver::{Iterate, PlayState};
use super::{
    Bookkeeping, Incumbent, Method, OptimiseError, Optimiser, PhaseSeconds, RunOutcome, Settings,
};
use crate::value::ValueError;

/// The share of `max_work` one guarantee ascent may spend (in the product
/// MDP's states per policy evaluation): on PAYNT's dodge-8 (8,128 states)
/// an unbounded ascent took 124 of a run's 209 CPU seconds.
const GUARANTEE_SHARE_OF_WORK: f64 = 0.25;

/// The numbers of one check that the iteration record shows.
pub(super) struct Check {
    /// The best-response value of the current defender (deep checks only).
    pub worst_case: Option<f64>,
    /// The current defender's certified lower bound (with a certifier,
    /// unless its value showed it cannot beat the incumbent); the ascended
    /// bound where the guarantee ascent then raised the incumbent.
    pub certified_lower: Option<f64>,
    /// The argmax rounding of the current defender certifies within
    /// `gap_tolerance` of the upper bound (it is then the incumbent, and
    /// the final rounding keeps the rounded controller).
    pub rounding_closes_gap: bool,
}

impl Optimiser<'_> {
    /// The check at iteration `t` (deep when `deep`, or always without a
    /// certifier; see the module's documentation): the current defender
    /// and the suffix average of the defender's probabilities (as logits
    /// within the bound `c`) are judged; either replaces the incumbent when
    /// its score is higher. Returns the current defender's numbers.
    pub(super) fn check(
        &mut self,
        state: &PlayState,
        books: &mut Bookkeeping,
        deep: bool,
    ) -> Result<Check, OptimiseError> {
        books.checks += 1;
        let iterate = &state.iterate;
        let upper_tightened = self.certify_against_adversaries(iterate, books)?;
        let rounding_closes_gap = self.rounding_closes_gap(iterate, books, upper_tightened)?;
        let deep = deep || self.certifier.is_none();
        let mut current = None;
        // The single-player ascent does not cycle: its average only lags.
        let candidates = match self.method {
            Method::MaxMin => vec![
                iterate.defender.clone(),
                self.averaged_defender(iterate, &books.defender_average),
            ],
            Method::Ascent => vec![iterate.defender.clone()],
        };
        for (i, candidate) in candidates.into_iter().enumerate() {
            let respond = deep && (i == 0 || self.certifier.is_none());
            let current_closes = i == 0 && rounding_closes_gap;
            let judged = self.judge(candidate, respond, !current_closes, iterate, books)?;
            current.get_or_insert(Check {
                worst_case: respond.then_some(judged.worst_case),
                certified_lower: judged.incumbent.as_ref().and_then(|c| c.certified_lower),
                rounding_closes_gap,
            });
            if let Some(incumbent) = judged.incumbent {
                if current_closes
                    || books
                        .best
                        .as_ref()
                        .is_none_or(|b| incumbent.score() > b.score())
                {
                    books.best = Some(incumbent);
                }
            }
            if current_closes {
                break;
            }
        }
        current.ok_or(OptimiseError::BestResponse("no candidate checked".into()))
    }

    /// Whether the run ascends the certified lower bound at its stall
    /// judgements ([`Self::ascend_guarantee`]): with a certifier and
    /// `guarantee_ascent` on.
    pub(super) fn ascends_guarantee(&self) -> bool {
        self.certifier.is_some() && self.settings.guarantee_ascent
    }

    /// The guarantee ascent (method.md section 6, `guarantee.rs`), `seconds`
    /// into the run (it spends at most the rest of the time budget), where a
    /// suffix-averaging window ends and when the run stops: L-BFGS on the
    /// certified lower bound itself from the incumbent defender. A higher
    /// bound replaces the incumbent (its worst-case estimate: its value
    /// against the current adversary, until [`Self::settle`]), so the
    /// stall rule judges what the run would return if it stopped here. A
    /// start whose product cannot be solved to the tolerance is left as it
    /// is, and so is a better defender whose value against the current
    /// adversary cannot be solved to the tolerance (a nearly deterministic
    /// defender can make the GMC too stiff). At most `steps` L-BFGS steps
    /// where given (a floor probe's short ascent), else the ascent's own
    /// stopping rules. Does nothing without a certifier or with
    /// `guarantee_ascent` off.
    /// Returns the new incumbent's bound when it replaced the incumbent.
    pub(super) fn ascend_guarantee(
        &mut self,
        iterate: &Iterate,
        books: &mut Bookkeeping,
        seconds: f64,
        steps: Option<usize>,
    ) -> Result<Option<f64>, OptimiseError> {
        let Some(best) = books.best.as_ref() else {
            return Ok(None);
        };
        let Some(ascended) = self.ascend_from(best, iterate, &mut books.phases, seconds, steps)?
        else {
            return Ok(None);
        };
        let bound = ascended.certified_lower;
        books.best = Some(ascended);
        Ok(bound)
    }

    /// The guarantee ascent ([`Self::ascend_guarantee`]) from `from`: the
    /// defender it climbed to as an incumbent at `iterate`, where its
    /// certified lower bound exceeds `from`'s score; its seconds added to
    /// `phases`.
    pub(super) fn ascend_from(
        &mut self,
        from: &Incumbent,
        iterate: &Iterate,
        phases: &mut PhaseSeconds,
        seconds: f64,
        steps: Option<usize>,
    ) -> Result<Option<Incumbent>, OptimiseError> {
        if !self.ascends_guarantee() {
            return Ok(None);
        }
        let Some(bounds) = self.lower_bounds.as_mut() else {
            return Ok(None);
        };
        let clock = Instant::now();
        let mut guarantee = Guarantee::new(bounds, self.objective.defender());
        // The ascent spends what is left of the run's time budget.
        let budget = self.settings.time_budget;
        // It stays within twice the loop's logit bound: beyond, nearly
        // deterministic defenders make chains too stiff to certify in
        // double precision, and the exact solves of the final certificate
        // then take minutes (PAYNT's dodge-6-lines-position, 1 node).
        let settings = Settings {
            time_budget: if budget > 0.0 {
                (budget - seconds).max(f64::MIN_POSITIVE)
            } else {
                0.0
            },
            logit_bound: (2.0 * iterate.bound).min(self.settings.logit_bound),
            max_work: self.settings.max_work * GUARANTEE_SHARE_OF_WORK,
            // The ascent stops before its step `t` once `t + 1` reaches
            // `max_iterations` (the driver's budget rule).
            max_iterations: steps.map_or(self.settings.max_iterations, |steps| {
                (steps + 1).min(self.settings.max_iterations)
            }),
            ..self.settings.clone()
        };
        let ascended = ascend(&mut guarantee, &from.defender, &settings, &self.cancel);
        phases.guarantee += clock.elapsed().as_secs_f64();
        let polished = match ascended {
            Ok(ascended) => ascended,
            Err(error) if error.is_numerical() => return Ok(None),
            Err(error) => return Err(error),
        };
        if polished.bound <= from.score() {
            return Ok(None);
        }
        let clock = Instant::now();
        let worst_case = self.objective.value(&polished.defender, &iterate.adversary);
        phases.optimisation += clock.elapsed().as_secs_f64();
        let worst_case = match worst_case {
            Ok(value) => value,
            // Nearly deterministic choices can make the GMC too stiff to
            // solve: such a defender is not kept, so that every number of
            // the run's own stays computable.
            Err(ValueError::Solver(_)) => return Ok(None),
            Err(error) => return Err(error.into()),
        };
        Ok(Some(Incumbent {
            defender: polished.defender,
            adversary: iterate.adversary.clone(),
            worst_case,
            certified_lower: Some(polished.bound),
            iteration: iterate.iteration,
        }))
    }

    /// The incumbent's full best response, once a run without a certifier
    /// has stopped (`outcome`; its score is the worst case itself, which
    /// this can lower): from the adversary it was judged against, the last
    /// best response found and `restarts` random starts
    /// ([`final_best_response`], each start on an objective from `fresh`); its worst case and adversary become
    /// that response's where it is lower. With a time budget it ends at
    /// [`Settings::final_deadline`] of the run that began at `started`.
    /// Where every start runs into a system it cannot solve to the
    /// tolerance, the incumbent keeps its numbers; the single-player
    /// ascent's incumbent has its exact worst case already. (With a
    /// certifier, only the defender a structure returns gets its full best
    /// response, after the rounding.)
    pub fn settle(
        &mut self,
        outcome: &mut RunOutcome,
        started: Instant,
        fresh: &FreshObjective<'_>,
    ) -> Result<(), OptimiseError> {
        if self.method == Method::Ascent {
            return Ok(());
        }
        let best = &outcome.best;
        let restarts = self.settings.final_restarts(false);
        let mut at: Vec<&[f64]> = vec![&best.adversary];
        at.extend(outcome.last_response.as_deref());
        let deadline = self.settings.final_deadline(started, Instant::now());
        let starts = Starts::new(&at, restarts).until(deadline);
        let defender = best.defender.clone();
        let states = self.objective.gmc_size().states;
        let clock = Instant::now();
        let found = final_best_response(
            fresh,
            states,
            &defender,
            starts,
            &self.settings,
            &mut self.rng,
        );
        outcome.phases.best_responses += clock.elapsed().as_secs_f64();
        let found = match found {
            Ok(found) => found,
            // Every start ran into a GMC too stiff to solve (a nearly
            // deterministic defender from the guarantee ascent can cause
            // it): the incumbent keeps the worst-case estimate it has.
            Err(error) if error.is_numerical() => return Ok(()),
            Err(error) => return Err(error),
        };
        let best = &mut outcome.best;
        if found.value <= best.worst_case {
            best.worst_case = found.value;
            best.adversary = found.adversary;
        }
        Ok(())
    }

    /// The defender's logits (within the bound `c`) whose probabilities are
    /// the suffix average `average`.
    fn averaged_defender(&self, iterate: &Iterate, average: &SuffixAverage) -> Vec<f64> {
        let softmax = self.objective.defender();
        let mut averaged = softmax.probabilities(&iterate.defender);
        averaged.entries.clone_from(&average.mean);
        softmax.logits_of(&averaged, iterate.bound)
    }

    /// With a certifier, when the upper bound's [`Backoff`] schedule says
    /// so: tightens the game upper bound with the current adversary and
    /// with the adversary whose probabilities are the adversary's suffix
    /// average (as logits within `logit_bound`; where cycling play circles
    /// a mixed saddle point, the average approaches it). Returns whether
    /// the upper bound went down.
    fn certify_against_adversaries(
        &self,
        iterate: &Iterate,
        books: &mut Bookkeeping,
    ) -> Result<bool, OptimiseError> {
        if self.certifier.is_none() || !books.upper_schedule.due(books.checks) {
            return Ok(false);
        }
        let before = books.upper_bound;
        let softmax = self.objective.adversary();
        let mut mu = softmax.probabilities(&iterate.adversary);
        mu.entries.clone_from(&books.adversary_average.mean);
        let averaged = softmax.logits_of(&mu, self.settings.logit_bound);
        self.tighten_against(
            &iterate.adversary,
            &mut books.upper_bound,
            &mut books.phases,
        )?;
        self.tighten_against(&averaged, &mut books.upper_bound, &mut books.phases)?;
        let tightened = books.upper_bound < before || before.is_none();
        books.upper_schedule.after(books.checks, tightened);
        Ok(tightened)
    }

    /// With a certifier: tightens the game upper bound `upper_bound` with
    /// the adversary of logits `adversary` (the best any defender does
    /// against it), timed as certification in `phases`.
    fn tighten_against(
        &self,
        adversary: &[f64],
        upper_bound: &mut Option<f64>,
        phases: &mut PhaseSeconds,
    ) -> Result<(), OptimiseError> {
        let Some(certifier) = self.certifier else {
            return Ok(());
        };
        let clock = Instant::now();
        let adversary = self.objective.adversary().controller(adversary)?;
        let upper = certifier.upper_or_trivial(&adversary)?;
        tighten(upper_bound, upper);
        phases.certification += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// One candidate defender of the check at iteration `t`: with
    /// `respond`, its best response warm-started from the current
    /// adversary and the last best response found (which then tightens the
    /// game upper bound), else (and always for the single-player ascent,
    /// where it is the best response) its value against the current
    /// adversary;
    /// with a certifier, its certified lower bound, unless `may_skip` and
    /// that value shows it cannot beat the incumbent (module documentation).
    fn judge(
        &mut self,
        candidate: Vec<f64>,
        respond: bool,
        may_skip: bool,
        iterate: &Iterate,
        books: &mut Bookkeeping,
    ) -> Result<Judged, OptimiseError> {
        let found = if respond && self.method == Method::MaxMin {
            let mut at: Vec<&[f64]> = vec![&iterate.adversary];
            at.extend(books.last_response.as_deref());
            // Without a certifier the best-response value is the score, and
            // near a mixed saddle the value is flat around the warm starts:
            // the random restarts keep it honest.
            let restarts = if self.certifier.is_none() {
                self.settings.restarts
            } else {
                0
            };
            let starts = Starts::new(&at, restarts);
            let found = self.respond(&candidate, starts, &mut books.phases)?;
            self.tighten_against(&found.adversary, &mut books.upper_bound, &mut books.phases)?;
            books.last_response = Some(found.adversary.clone());
            found
        } else {
            let clock = Instant::now();
            let value = self.objective.value(&candidate, &iterate.adversary)?;
            books.phases.optimisation += clock.elapsed().as_secs_f64();
            BestResponse {
                value,
                adversary: iterate.adversary.clone(),
            }
        };
        let cannot_beat = self.certifier.is_some()
            && may_skip
            && books
                .best
                .as_ref()
                .is_some_and(|best| found.value <= best.score());
        if cannot_beat {
            return Ok(Judged {
                worst_case: found.value,
                incumbent: None,
            });
        }
        let clock = Instant::now();
        let certified_lower = match self.lower_bounds.as_mut() {
            Some(bounds) => {
                let defender = self.objective.defender().controller(&candidate)?;
                Some(bounds.value_or_trivial(&defender)?)
            }
            None => None,
        };
        books.phases.certification += clock.elapsed().as_secs_f64();
        Ok(Judged {
            worst_case: found.value,
            incumbent: Some(Incumbent {
                defender: candidate,
                adversary: found.adversary,
                worst_case: found.value,
                certified_lower,
                iteration: iterate.iteration,
            }),
        })
    }

    /// The best response to `defender` from `starts`, timed as a
    /// best-response phase.
    fn respond(
        &mut self,
        defender: &[f64],
        starts: Starts<'_>,
        phases: &mut PhaseSeconds,
    ) -> Result<BestResponse, OptimiseError> {
        let clock = Instant::now();
        let found = best_response(
            &mut self.objective,
            defender,
            starts,
            &self.settings,
            &mut self.rng,
        );
        phases.best_responses += clock.elapsed().as_secs_f64();
        found
    }

    /// Whether, with rounding on and a certifier, the argmax rounding of the
    /// current defender certifies within `gap_tolerance` of the upper
    /// bound: a deterministic optimum is then found, though the softmax
    /// iterates would approach it only slowly. The rounding's lower bound
    /// is computed again only when the rounded controller changed; with
    /// neither it nor the upper bound (`upper_tightened`) changed, the
    /// answer is the last one. A changed rounding is certified at every
    /// check while its bound reaches the incumbent's score, otherwise at
    /// intervals that double up to [`ROUNDING_BACKOFF_CAP`] checks: where
    /// the argmax of noisy iterates changes at every check and certifies
    /// far below them (the 16x16 grid), it paid for nothing.
    fn rounding_closes_gap(
        &self,
        iterate: &Iterate,
        books: &mut Bookkeeping,
        upper_tightened: bool,
    ) -> Result<bool, OptimiseError> {
        let (Some(certifier), Some(upper), true) =
            (&self.certifier, books.upper_bound, self.settings.round)
        else {
            return Ok(false);
        };
        let clock = Instant::now();
        let defender = self.objective.defender().controller(&iterate.defender)?;
        let rounded = truncated(&defender, f64::INFINITY)?;
        let lower = match &books.last_rounding {
            Some((last, lower)) if *last == rounded => {
                if !upper_tightened {
                    return Ok(false);
                }
                *lower
            }
            _ if !books.rounding_schedule.due(books.checks) => return Ok(false),
            _ => {
                let lower = certifier.lower_or_trivial(&rounded)?;
                let competitive = books.best.as_ref().is_none_or(|best| lower >= best.score());
                books.rounding_schedule.after(books.checks, competitive);
                books.last_rounding = Some((rounded, lower));
                lower
            }
        };
        books.phases.certification += clock.elapsed().as_secs_f64();
        Ok(self.settings.gap_closed(lower, upper))
    }
}

/// The longest interval, in checks, between certifications of a changed
/// argmax rounding that does not reach the incumbent's score
/// ([`Optimiser::rounding_closes_gap`]): 20 iterations at the default
/// `check_every`.
pub(super) const ROUNDING_BACKOFF_CAP: usize = 4;

/// A candidate after [`Optimiser::judge`]: its value against the adversary
/// it was judged against (a best response when one was computed), and
/// itself as a possible incumbent, `None` when it cannot beat the current
/// one (and was therefore not certified).
struct Judged {
    worst_case: f64,
    incumbent: Option<Incumbent>,
}

/// The schedule of an optional certification (the game upper bound's, a
/// changed argmax rounding's): due at every check while it pays,
/// otherwise at intervals (in checks) that double, up to `cap`, after each
/// check where it did not.
pub(super) struct Backoff {
    interval: usize,
    next: usize,
    cap: usize,
}

impl Backoff {
    /// Due at every check until one does not pay; intervals at most `cap`.
    pub fn new(cap: usize) -> Self {
        Self {
            interval: 1,
            next: 0,
            cap: cap.max(1),
        }
    }

    /// Whether the certification is due at check number `check`.
    pub fn due(&self, check: usize) -> bool {
        check >= self.next
    }

    /// After the certification ran at check number `check`: due again at
    /// the next check when it `paid`, else after twice the last interval.
    pub fn after(&mut self, check: usize, paid: bool) {
        self.interval = if paid {
            1
        } else {
            (2 * self.interval).min(self.cap)
        };
        self.next = check + self.interval;
    }
}

/// The game upper bound tightened with `candidate`: the smaller of the two.
pub(in crate::optimise) fn tighten(upper_bound: &mut Option<f64>, candidate: f64) {
    *upper_bound = Some(upper_bound.map_or(candidate, |u| u.min(candidate)));
}

/// The mean of a player's probabilities over iterations `2^k..=t`.
pub(super) struct SuffixAverage {
    mean: Vec<f64>,
    count: usize,
}

impl SuffixAverage {
    /// The empty average of `n` probabilities.
    pub fn new(n: usize) -> Self {
        Self {
            mean: vec![0.0; n],
            count: 0,
        }
    }

    /// Adds iteration `t`'s probabilities, first restarting at powers of two.
    pub fn add(&mut self, t: usize, mu: &[f64]) {
        if t.is_power_of_two() {
            self.count = 0;
        }
        self.count += 1;
        let weight = 1.0 / self.count as f64;
        for (m, &x) in self.mean.iter_mut().zip(mu) {
            *m += weight * (x - *m);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_suffix_average_restarts_at_powers_of_two() {
        let mut average = SuffixAverage::new(1);
        for (t, mu) in [(0, 10.0), (1, 1.0), (2, 2.0), (3, 4.0)] {
            average.add(t, &[mu]);
        }
        assert_eq!(average.mean, [3.0], "the mean over iterations 2..=3");
        average.add(4, &[7.0]);
        assert_eq!(average.mean, [7.0], "restarted at 4");
    }

    #[test]
    fn the_backoff_doubles_its_interval_until_the_certification_pays() {
        let mut schedule = Backoff::new(4);
        let due: Vec<usize> = (0..20)
            .filter(|&check| {
                let due = schedule.due(check);
                if due {
                    schedule.after(check, false);
                }
                due
            })
            .collect();
        // Never paying: intervals 2, then 4 (the cap).
        assert_eq!(due, [0, 2, 6, 10, 14, 18]);
        let mut schedule = Backoff::new(4);
        let due: Vec<usize> = (0..12)
            .filter(|&check| {
                let due = schedule.due(check);
                if due {
                    schedule.after(check, check == 2);
                }
                due
            })
            .collect();
        // Paying at check 2: due at the next check, then intervals 2, 4.
        assert_eq!(due, [0, 2, 3, 5, 9]);
    }

    #[test]
    fn tightening_keeps_the_smallest_upper_bound() {
        let mut upper = None;
        tighten(&mut upper, 0.8);
        assert_eq!(upper, Some(0.8));
        tighten(&mut upper, 0.9);
        assert_eq!(upper, Some(0.8));
        tighten(&mut upper, 0.5);
        assert_eq!(upper, Some(0.5));
    }
}
