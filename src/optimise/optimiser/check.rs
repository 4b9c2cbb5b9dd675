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
//! When the run ends, the kept defender gets a full best response
//! ([`Optimiser::settle`]) with `restarts` random starts besides the warm
//! ones: its reported worst case is always a best-response value.

use std::time::Instant;

use super::super::best_response::{BestResponse, Starts, best_response};
use super::super::play::{Iterate, PlayState};
use super::super::rounding::truncated;
use super::{Bookkeeping, Incumbent, OptimiseError, Optimiser, PhaseSeconds};
use crate::certify::{lower_value_or_trivial, upper_value_or_trivial};

/// The numbers of one check that the iteration record shows.
pub(super) struct Check {
    /// The best-response value of the current defender (deep checks only).
    pub worst_case: Option<f64>,
    /// The current defender's certified lower bound (with a certifier).
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
        let averaged = self.averaged_defender(iterate, &books.defender_average);
        self.certify_against_adversaries(iterate, books)?;
        let rounding_closes_gap =
            self.rounding_closes_gap(iterate, books.upper_bound, &mut books.phases)?;
        let deep = deep || self.certifier.is_none();
        let mut current = None;
        for (i, candidate) in [iterate.defender.clone(), averaged].into_iter().enumerate() {
            let respond = deep && (i == 0 || self.certifier.is_none());
            let incumbent = self.judge(candidate, respond, iterate, books)?;
            current.get_or_insert(Check {
                worst_case: respond.then_some(incumbent.worst_case),
                certified_lower: incumbent.certified_lower,
                rounding_closes_gap,
            });
            let current_closes = i == 0 && rounding_closes_gap;
            if current_closes
                || books
                    .best
                    .as_ref()
                    .is_none_or(|b| incumbent.score() > b.score())
            {
                books.best = Some(incumbent);
            }
            if current_closes {
                break;
            }
        }
        current.ok_or(OptimiseError::BestResponse("no candidate checked".into()))
    }

    /// The incumbent's full best response, once the run has stopped: from
    /// the adversary it was judged against, the last best response found
    /// and `restarts` random starts; its worst case and adversary become
    /// that response's, which also tightens the game upper bound.
    pub(super) fn settle(&mut self, books: &mut Bookkeeping) -> Result<(), OptimiseError> {
        let Some(best) = books.best.as_ref() else {
            return Err(OptimiseError::BestResponse(
                "no best-response check ran".into(),
            ));
        };
        let mut at: Vec<&[f64]> = vec![&best.adversary];
        at.extend(books.last_response.as_deref());
        let starts = Starts {
            at: &at,
            restarts: self.settings.restarts,
        };
        let found = self.respond(&best.defender, starts, &mut books.phases)?;
        self.tighten_against(&found.adversary, books)?;
        let best = books.best.as_mut().expect("checked above");
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

    /// With a certifier: tightens the game upper bound with the current
    /// adversary and with the adversary whose probabilities are the
    /// adversary's suffix average (as logits within `logit_bound`; where
    /// cycling play circles a mixed saddle point, the average approaches it).
    fn certify_against_adversaries(
        &self,
        iterate: &Iterate,
        books: &mut Bookkeeping,
    ) -> Result<(), OptimiseError> {
        if self.certifier.is_none() {
            return Ok(());
        }
        let softmax = self.objective.adversary();
        let mut mu = softmax.probabilities(&iterate.adversary);
        mu.entries.clone_from(&books.adversary_average.mean);
        let averaged = softmax.logits_of(&mu, self.settings.logit_bound);
        self.tighten_against(&iterate.adversary, books)?;
        self.tighten_against(&averaged, books)
    }

    /// With a certifier: tightens the game upper bound with the adversary
    /// of logits `adversary` (the best any defender does against it).
    fn tighten_against(
        &self,
        adversary: &[f64],
        books: &mut Bookkeeping,
    ) -> Result<(), OptimiseError> {
        let Some(certifier) = self.certifier else {
            return Ok(());
        };
        let clock = Instant::now();
        let adversary = self.objective.adversary().controller(adversary)?;
        let upper = upper_value_or_trivial(certifier.game, certifier.phi, &adversary)?;
        tighten(&mut books.upper_bound, upper);
        books.phases.certification += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// One candidate defender of the check at iteration `t`: with
    /// `respond`, its best response warm-started from the current
    /// adversary and the last best response found (which then tightens the
    /// game upper bound), else its value against the current adversary;
    /// with a certifier, its certified lower bound.
    fn judge(
        &mut self,
        candidate: Vec<f64>,
        respond: bool,
        iterate: &Iterate,
        books: &mut Bookkeeping,
    ) -> Result<Incumbent, OptimiseError> {
        let found = if respond {
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
            let starts = Starts { at: &at, restarts };
            let found = self.respond(&candidate, starts, &mut books.phases)?;
            self.tighten_against(&found.adversary, books)?;
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
        let clock = Instant::now();
        let certified_lower = match self.certifier {
            Some(certifier) => {
                let defender = self.objective.defender().controller(&candidate)?;
                Some(lower_value_or_trivial(
                    certifier.game,
                    certifier.not_phi,
                    &defender,
                )?)
            }
            None => None,
        };
        books.phases.certification += clock.elapsed().as_secs_f64();
        Ok(Incumbent {
            defender: candidate,
            adversary: found.adversary,
            worst_case: found.value,
            certified_lower,
            iteration: iterate.iteration,
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
    /// current defender certifies within `gap_tolerance` of `upper_bound`: a
    /// deterministic optimum is then found, though the softmax iterates
    /// would approach it only slowly.
    fn rounding_closes_gap(
        &self,
        iterate: &Iterate,
        upper_bound: Option<f64>,
        phases: &mut PhaseSeconds,
    ) -> Result<bool, OptimiseError> {
        let (Some(certifier), Some(upper), true) =
            (&self.certifier, upper_bound, self.settings.round)
        else {
            return Ok(false);
        };
        let clock = Instant::now();
        let defender = self.objective.defender().controller(&iterate.defender)?;
        let rounded = truncated(&defender, f64::INFINITY)?;
        let lower = lower_value_or_trivial(certifier.game, certifier.not_phi, &rounded)?;
        phases.certification += clock.elapsed().as_secs_f64();
        Ok(upper - lower <= self.settings.gap_tolerance)
    }
}

/// The game upper bound tightened with `candidate`: the smaller of the two.
fn tighten(upper_bound: &mut Option<f64>, candidate: f64) {
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
