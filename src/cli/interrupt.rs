//! Ctrl-C (SIGINT), and SIGTERM and SIGHUP as a batch system sends them.
//!
//! The first signal asks the run that registered a [`Cancel`] (`solve`)
//! to stop: the optimiser returns the best defender it has, which is
//! certified and written whole to `--out` as usual, and the command then
//! exits with 130. A command that registered none (every other), and any
//! second signal, stop at once: every uncommitted output directory is
//! removed ([`abandon_uncommitted`]), so that `--out` is left as it was,
//! and the process exits with 130.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

use posg_fsc::optimise::Cancel;
use posg_fsc::output::abandon_uncommitted;

/// The exit status of a command stopped by a signal (128 + SIGINT's 2).
pub const INTERRUPTED: u8 = 130;

/// Whether a signal has arrived.
static RECEIVED: AtomicBool = AtomicBool::new(false);

/// The run the first signal stops, if one was registered.
static GRACEFUL: Mutex<Option<Cancel>> = Mutex::new(None);

/// Installs the handler; a failure to install it (no signal support)
/// leaves the signals' default action, which also leaves `--out` as it was.
pub fn install() {
    let _ = ctrlc::set_handler(on_signal);
}

/// Lets the first signal stop the run holding `cancel` gracefully.
pub fn stop_gracefully(cancel: &Cancel) {
    *GRACEFUL.lock().unwrap_or_else(|e| e.into_inner()) = Some(cancel.clone());
}

/// Whether a signal has arrived (the command then exits with
/// [`INTERRUPTED`]).
pub fn received() -> bool {
    RECEIVED.load(Ordering::SeqCst)
}

/// The handler (on a thread of its own).
fn on_signal() {
    let first = !RECEIVED.swap(true, Ordering::SeqCst);
    let graceful = GRACEFUL.lock().unwrap_or_else(|e| e.into_inner()).clone();
    match graceful {
        Some(cancel) if first => {
            cancel.cancel();
            eprintln!(
                "interrupted: stopping; the best defender so far is certified and written \
                 (interrupt again to quit at once, writing nothing)"
            );
        }
        _ => {
            let _held = abandon_uncommitted();
            eprintln!("interrupted: stopped, nothing written");
            std::process::exit(i32::from(INTERRUPTED));
        }
    }
}
