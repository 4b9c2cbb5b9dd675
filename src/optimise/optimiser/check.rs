//! The driver's best-response check at `(phi_def(t), phi_adv(t))` and its
//! certification hooks (method.md sections 4 and 6): two candidates (the
//! current defender and the suffix average of its probabilities) each get
//! a best response and, with a [`super::Certifier`], a certified lower bound; the
//! game upper bound is tightened against the adversary's suffix average
//! and the best response to the current defender.

use std::time::Instant;

use super::super::best_response::best_response;
use super::super::play::{Iterate, PlayState};
use super::super::rounding::truncated;
use super::{Bookkeeping, Incumbent, OptimiseError, Optimiser, PhaseSeconds};
use crate::certify::{lower_value_or_trivial, upper_value_or_trivial};

/// The numbers of one best-response check that the iteration record shows.
pub(super) struct Check {
    /// The best-response value of the current defender.
    pub worst_case: f64,
    /// The current defender's certified lower bound (with a certifier).
    pub certified_lower: Option<f64>,
    /// The argmax rounding of the current defender certifies within
    /// `gap_tolerance` of the upper bound (it is then the incumbent, and
    /// the final rounding keeps the rounded controller).
    pub rounding_closes_gap: bool,
}

impl Optimiser<'_> {
    /// The best-response check at iteration `t`: the current defender and
    /// the suffix average of the defender's probabilities (as logits within
    /// the bound `c`) each get a best response and, with a certifier, a
    /// certified lower bound; either replaces the incumbent when its score
    /// is higher. With a certifier the game upper bound is also taken
    /// against the suffix average of the adversary's probabilities (where
    /// cycling play circles a mixed saddle point, the average approaches
    /// it) and against the best response to the current defender. Returns
    /// the current defender's numbers.
    pub(super) fn check(
        &mut self,
        state: &PlayState,
        books: &mut Bookkeeping,
    ) -> Result<Check, OptimiseError> {
        books.checks += 1;
        let iterate = &state.iterate;
        let averaged = self.averaged_defender(iterate, &books.defender_average);
        self.certify_against_average_adversary(iterate, books)?;
        let rounding_closes_gap =
            self.rounding_closes_gap(iterate, books.upper_bound, &mut books.phases)?;
        let mut current = None;
        for (i, candidate) in [iterate.defender.clone(), averaged].into_iter().enumerate() {
            let incumbent = self.judge(candidate, i == 0, iterate, books)?;
            current.get_or_insert(Check {
                worst_case: incumbent.worst_case,
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

    /// The defender's logits (within the bound `c`) whose probabilities are
    /// the suffix average `average`.
    fn averaged_defender(&self, iterate: &Iterate, average: &SuffixAverage) -> Vec<f64> {
        let softmax = self.objective.defender();
        let mut averaged = softmax.probabilities(&iterate.defender);
        averaged.entries.clone_from(&average.mean);
        softmax.logits_of(&averaged, iterate.bound)
    }

    /// With a certifier: tightens the game upper bound with the adversary
    /// whose probabilities are the adversary's suffix average (as logits
    /// within `logit_bound`).
    fn certify_against_average_adversary(
        &self,
        iterate: &Iterate,
        books: &mut Bookkeeping,
    ) -> Result<(), OptimiseError> {
        let Some(certifier) = self.certifier else {
            return Ok(());
        };
        let clock = Instant::now();
        let softmax = self.objective.adversary();
        let mut mu = softmax.probabilities(&iterate.adversary);
        mu.entries.clone_from(&books.adversary_average.mean);
        let logits = softmax.logits_of(&mu, self.settings.logit_bound);
        let adversary = softmax.controller(&logits)?;
        let upper = upper_value_or_trivial(certifier.game, certifier.phi, &adversary)?;
        tighten(&mut books.upper_bound, upper);
        books.phases.certification += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// One candidate defender of the check at iteration `t`: its best
    /// response (from the current adversary) and, with a certifier, its
    /// certified lower bound; for the current defender (`current`) the game
    /// upper bound is also tightened with the best response found.
    fn judge(
        &mut self,
        candidate: Vec<f64>,
        current: bool,
        iterate: &Iterate,
        books: &mut Bookkeeping,
    ) -> Result<Incumbent, OptimiseError> {
        let clock = Instant::now();
        let found = best_response(
            &mut self.objective,
            &candidate,
            &iterate.adversary,
            &self.settings,
            &mut self.rng,
        )?;
        books.phases.best_responses += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let certified_lower = match self.certifier {
            Some(certifier) => {
                let defender = self.objective.defender().controller(&candidate)?;
                let lower = lower_value_or_trivial(certifier.game, certifier.not_phi, &defender)?;
                if current {
                    let adversary = self.objective.adversary().controller(&found.adversary)?;
                    let upper = upper_value_or_trivial(certifier.game, certifier.phi, &adversary)?;
                    tighten(&mut books.upper_bound, upper);
                }
                Some(lower)
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
