//! The stopping rules of every loop of the optimiser (method.md section 4):
//! the budgets, the suffix-averaging windows and the stall rules the
//! driver ([`super::Optimiser`]) and the guarantee ascent judge.

use super::{Cancel, Settings, Status};

/// The stall rule measures a window's gain relative to the best score's
/// magnitude, but never relative to less than this: a probability creeping
/// from `1e-8` to `1e-7` has stalled (it gained under `stall_gain` times
/// this), however large its relative climb.
pub const STALL_MAGNITUDE_FLOOR: f64 = 1e-3;

/// The budgets every loop stops on, after iteration `t` (the driver's
/// runs and the guarantee ascent): [`Status::Cancelled`] once `cancel` is
/// set, [`Status::MaxIterations`] after iteration `max_iterations - 1`,
/// [`Status::WorkBudget`] once `work` (states solved) reaches a positive
/// `max_work`, [`Status::TimeBudget`] once `seconds` reach a positive time
/// budget.
pub(super) fn budget_spent(
    s: &Settings,
    t: usize,
    work: f64,
    seconds: f64,
    cancel: &Cancel,
) -> Option<Status> {
    if cancel.is_cancelled() {
        Some(Status::Cancelled)
    } else if t + 1 >= s.max_iterations {
        Some(Status::MaxIterations)
    } else if s.max_work > 0.0 && work >= s.max_work {
        Some(Status::WorkBudget)
    } else if s.time_budget > 0.0 && seconds >= s.time_budget {
        Some(Status::TimeBudget)
    } else {
        None
    }
}

/// Whether iteration `t` ends a suffix-averaging window (`t + 1` is a
/// power of two): the windows are the second halves of the run so far.
pub(super) fn window_ends(t: usize) -> bool {
    (t + 1).is_power_of_two()
}

/// The max-min loop's stall rule, judged where a suffix-averaging window
/// ends: with at least `stall_checks` checks in `history` since the logit
/// bound last widened, whether the best score gained at most `stall_gain`
/// times its magnitude (relative, so that a climb from a small value is
/// not taken for a stall, down to [`STALL_MAGNITUDE_FLOOR`]: gains of a
/// probability below `stall_gain * STALL_MAGNITUDE_FLOOR` do not pay)
/// over the last window, from the previous entry of
/// `window_ends` (the best score at each window's end) to the last. The
/// window is the second half of the run so far, so a run that creeps stops
/// within about twice the iterations of its last real progress; and it
/// counts iterations, not seconds, so a seeded run stops at the same
/// iteration on every machine.
pub(super) fn stalled(history: &[f64], window_ends: &[f64], s: &Settings) -> bool {
    let n = window_ends.len();
    s.stall_checks > 0
        && history.len() >= s.stall_checks
        && n > 1
        && window_ends[n - 1] - window_ends[n - 2]
            <= s.stall_gain * window_ends[n - 1].abs().max(STALL_MAGNITUDE_FLOOR)
}

/// Whether the last entry of `history` exceeds the one `window` entries
/// before by less than `tolerance` times its magnitude (false while the
/// history is shorter than the window).
pub(super) fn gained_little(history: &[f64], window: usize, tolerance: f64) -> bool {
    let n = history.len();
    n > window && history[n - 1] - history[n - 1 - window] <= tolerance * history[n - 1].abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_window_stalls_on_a_small_relative_gain_or_a_negligible_absolute_one() {
        let s = Settings::default();
        let history = vec![0.0; s.stall_checks];
        // 0.5 -> 0.5004: a relative gain of 8e-4 < stall_gain.
        assert!(stalled(&history, &[0.5, 0.5004], &s));
        assert!(!stalled(&history, &[0.5, 0.501], &s));
        // A small probability climbing by 10%: progress.
        assert!(!stalled(&history, &[0.0150, 0.0165], &s));
        // 1e-8 -> 1e-7 climbs tenfold but gains 9e-8 < 1e-3 * 1e-3.
        assert!(stalled(&history, &[1e-8, 1e-7], &s));
        // Too few checks since the last widening, or a single window: no.
        assert!(!stalled(&history[1..], &[1e-8, 1e-7], &s));
        assert!(!stalled(&history, &[1e-7], &s));
    }
}
