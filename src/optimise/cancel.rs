//! [`Cancel`]: a request, from outside a running optimisation, to stop it
//! early (a Python callback returning `False`, Ctrl-C, a caller's own
//! deadline). The optimiser looks at it once per iteration and stops with
//! [`super::Status::Cancelled`], returning the best defender it has seen,
//! certified like any other result.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A shared stop flag: clones share it, any clone may set it, every run
/// holding one stops at its next iteration once it is set.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A flag that is not set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every run holding this flag (or a clone) to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Self::cancel`] was called on this flag or a clone.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clone_sees_the_cancellation() {
        let flag = Cancel::new();
        let clone = flag.clone();
        assert!(!clone.is_cancelled());
        flag.cancel();
        assert!(clone.is_cancelled());
        assert!(!Cancel::new().is_cancelled(), "a new flag is independent");
    }
}
