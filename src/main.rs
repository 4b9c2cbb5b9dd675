//! The `posg-fsc` command line: a thin layer over the `posg_fsc` library.
//! Each subcommand lives in its own module under `cli/`.

mod cli;

use std::process::ExitCode;

/// mimalloc: about 30% less CPU than the system allocator on the local
/// search, whose bound evaluations allocate and free many small graphs
/// (measured in results/README.md, stop 41); the default feature
/// `mimalloc`.
#[cfg(feature = "mimalloc")]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// mimalloc's option `destroy_on_exit` (index 22 of `mi_option_e`, kept
/// stable across mimalloc 2 and 3 by its deprecated placeholders).
#[cfg(feature = "mimalloc")]
const MI_OPTION_DESTROY_ON_EXIT: libmimalloc_sys::mi_option_t = 22;

/// Skips mimalloc's teardown at exit (`destroy_on_exit` = 2: its process
/// exit handler returns at once): it would free every heap and hand the
/// memory back to the operating system piecewise, work the kernel does at
/// once when the process ends. On PRISM's grid-avoid-4-0 that teardown
/// was about 0.4 ms of an 11 ms run, and on a virtual machine the pages
/// it returned made the runs that followed 3-5 times slower when they
/// came back cold (results/README.md, stop 54). Not where the user asked
/// mimalloc for statistics or messages at exit (`MIMALLOC_SHOW_STATS`,
/// `MIMALLOC_VERBOSE`, which the teardown prints) or set
/// `MIMALLOC_DESTROY_ON_EXIT` themselves.
#[cfg(feature = "mimalloc")]
fn skip_allocator_teardown() {
    use libmimalloc_sys::{mi_option_get, mi_option_is_enabled, mi_option_set};
    use libmimalloc_sys::{mi_option_show_stats, mi_option_verbose};
    // SAFETY: reads and sets mimalloc's integer options (no allocation, no
    // pointer; an index out of range is ignored); this runs before any
    // other thread.
    unsafe {
        let asked = mi_option_is_enabled(mi_option_show_stats)
            || mi_option_is_enabled(mi_option_verbose)
            || mi_option_get(MI_OPTION_DESTROY_ON_EXIT) != 0;
        if !asked {
            mi_option_set(MI_OPTION_DESTROY_ON_EXIT, 2);
        }
    }
}

fn main() -> ExitCode {
    #[cfg(feature = "mimalloc")]
    skip_allocator_teardown();
    let args = cli::parse();
    cli::interrupt::install();
    let result = cli::run(args);
    match result {
        Ok(()) if cli::interrupt::received() => ExitCode::from(cli::interrupt::INTERRUPTED),
        Ok(()) => ExitCode::SUCCESS,
        Err(error) if is_broken_pipe(&error) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", posg_fsc::output::error_message(error.as_ref()));
            if cli::interrupt::received() {
                ExitCode::from(cli::interrupt::INTERRUPTED)
            } else {
                ExitCode::from(2)
            }
        }
    }
}

/// Whether the error is stdout's reader having gone away (`| head`).
fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error
        .downcast_ref::<std::io::Error>()
        .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
}

#[cfg(test)]
mod tests {
    use posg_fsc::output::error_message;

    #[derive(Debug, thiserror::Error)]
    #[error("the inner cause")]
    struct Inner;

    #[derive(Debug, thiserror::Error)]
    #[error("embedding: {0}")]
    struct Embedding(#[from] Inner);

    #[derive(Debug, thiserror::Error)]
    #[error("not embedding")]
    struct Wrapping(#[source] Inner);

    #[test]
    fn each_cause_is_printed_once() {
        let embedded = anyhow::Error::from(Embedding(Inner)).context("reading a.drn");
        assert_eq!(
            error_message(embedded.as_ref()),
            "reading a.drn: embedding: the inner cause"
        );
        let wrapped = anyhow::Error::from(Wrapping(Inner));
        assert_eq!(
            error_message(wrapped.as_ref()),
            "not embedding: the inner cause"
        );
    }
}
