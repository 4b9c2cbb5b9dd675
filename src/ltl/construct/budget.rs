//! The time budget of a translation: a deadline for the current thread,
//! set by [`crate::ltl::translate_within`] and checked by every exploration.

use std::cell::Cell;
use std::time::Instant;

thread_local! {
    static DEADLINE: Cell<Option<Instant>> = const { Cell::new(None) };
    static SECONDS: Cell<f64> = const { Cell::new(f64::INFINITY) };
}

/// Sets the deadline (and the budget it came from) while alive;
/// restores the previous ones on drop.
pub(crate) struct Deadline(Option<Instant>, f64);

impl Deadline {
    pub(crate) fn set(deadline: Option<Instant>, seconds: f64) -> Self {
        Self(
            DEADLINE.with(|d| d.replace(deadline)),
            SECONDS.with(|s| s.replace(seconds)),
        )
    }
}

impl Drop for Deadline {
    fn drop(&mut self) {
        DEADLINE.with(|d| d.set(self.0));
        SECONDS.with(|s| s.set(self.1));
    }
}

/// The current budget in words.
pub(crate) fn describe() -> String {
    format!(
        "{} s, {} states and {} edges per automaton",
        SECONDS.with(|s| s.get()),
        super::MAX_STATES,
        crate::limits::MAX_AUTOMATON_EDGES
    )
}

/// Whether the current thread's deadline has passed.
pub(crate) fn out_of_time() -> bool {
    DEADLINE
        .with(|d| d.get())
        .is_some_and(|deadline| Instant::now() > deadline)
}
