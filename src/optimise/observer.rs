//! What the optimiser reports while it runs: one [`IterationRecord`] per
//! outer iteration (and a [`SearchRecord`] when a local search before the
//! race ends), handed to an [`Observer`]. Writers of output (the CSV
//! curve, a progress bar) are observers; the loop itself writes nothing.

use serde::Serialize;

/// Which part of the optimiser made a record's defender (method.md
/// section 4, "One engine").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RecordSource {
    /// An iterate of gradient play or of the single-player ascent (at a
    /// check, possibly raised by the guarantee ascent).
    Gradient,
    /// The local search on the supports.
    LocalSearch,
    /// A rounding of the loop's best defender.
    Rounding,
}

/// One outer iteration of the max-min optimiser (method.md section 4), or
/// one quasi-Newton iteration of the single-player ascent (where the
/// adversary fields are 0 and `worst_case` is the exact value); the last
/// record of a structure's run, `returned`, is the defender it returns.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IterationRecord {
    /// The start (of a structure's parallel starts) the record is from:
    /// records of a structure's starts reach its observer interleaved, as
    /// they happen.
    pub start: usize,
    /// The outer iteration `t`, from 0.
    pub iteration: usize,
    /// Wall-clock seconds since the structure's optimisation started, when
    /// the record was made (after iteration `t`'s check, so that a certified
    /// number carries the time it was known).
    pub seconds: f64,
    /// `V(phi_def(t), phi_adv)` after the adversary's steps of iteration `t`.
    pub value: f64,
    /// `|dV/dphi_def|_2` at that point.
    pub defender_gradient_norm: f64,
    /// `|dV/dphi_adv|_2` before the adversary's last step of iteration `t`.
    pub adversary_gradient_norm: f64,
    /// The defender's step size `eta_def(t)`.
    pub defender_step: f64,
    /// The adversary's step size `eta_adv`.
    pub adversary_step: f64,
    /// The best-response value of `phi_def(t)`, when a check ran at `t`.
    pub worst_case: Option<f64>,
    /// When a check ran and an automaton for !phi was given: the certified
    /// lower bound of `phi_def(t)` against every adversary (method.md section
    /// 6); at a check where the guarantee ascent raised the best defender,
    /// the ascended defender's bound instead.
    pub certified_lower: Option<f64>,
    /// With `certified_lower`: the smallest game upper bound over the best
    /// responses found so far (no defender of any size does better).
    pub upper_bound: Option<f64>,
    /// The logit bound `c` in force (method.md section 3): it widens from
    /// `initial_logit_bound` towards `logit_bound` in the max-min loop.
    pub logit_bound: f64,
    /// The part of the optimiser that made this record's defender.
    pub source: RecordSource,
    /// Whether this is the structure's returned defender, after rounding
    /// and local search (one record, the last of the kept start; `iteration`
    /// is then the number of iterations run, `value` its worst-case
    /// estimate, the gradient fields 0): the largest `certified_lower` of a
    /// structure's records is the one it returns.
    pub returned: bool,
}

/// What the local search on the supports before a structure's max-min
/// race found (method.md section 6): the race's floor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SearchRecord {
    /// Wall-clock seconds since the run started (the structures' searches
    /// run one after another, [`super::optimise_structures`]), when the
    /// search ended.
    pub seconds: f64,
    /// The certified lower bound of the search's best end point.
    pub certified_lower: f64,
}

/// A step of a structure's optimisation (method.md section 4), announced
/// to its observer as it begins, so that a progress report can say what a
/// long stretch without records is spent on.
#[derive(Debug, Clone, PartialEq)]
pub enum Phase {
    /// The local search on the supports before the race (method.md
    /// section 6).
    LocalSearch,
    /// The starts' race of gradient play (or of the single-player ascent).
    Race,
    /// The race ended: the rounding, the local search from the rounded
    /// candidates and the returned defender's final best responses and
    /// certificate follow.
    Finishing {
        /// Why the kept start's race ended, in words with the budget that
        /// ended it ([`super::Status::explained`]).
        race: String,
    },
}

/// An observer's failure (an output file could not be written, say).
pub type ObserverError = Box<dyn std::error::Error + Send + Sync>;

/// Receives the optimiser's records as they happen: each start's in
/// iteration order, the starts of a structure interleaved.
pub trait Observer {
    /// Called once per outer iteration.
    fn observe(&mut self, record: &IterationRecord);

    /// Called once when the local search before a max-min race has ended,
    /// before the race's first record.
    fn searched(&mut self, _record: &SearchRecord) {}

    /// Called as each phase of the structure's optimisation begins.
    fn phase(&mut self, _phase: &Phase) {}

    /// Called once after the last record: flushes output and reports the
    /// first failure, which fails the run.
    fn finish(&mut self) -> Result<(), ObserverError> {
        Ok(())
    }
}

/// The observer that ignores everything.
impl Observer for () {
    fn observe(&mut self, _record: &IterationRecord) {}
}

/// Every observer of a list sees every record.
impl Observer for Vec<Box<dyn Observer + Send>> {
    fn observe(&mut self, record: &IterationRecord) {
        for observer in self {
            observer.observe(record);
        }
    }

    fn searched(&mut self, record: &SearchRecord) {
        for observer in self {
            observer.searched(record);
        }
    }

    fn phase(&mut self, phase: &Phase) {
        for observer in self {
            observer.phase(phase);
        }
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        self.iter_mut().try_for_each(|observer| observer.finish())
    }
}
