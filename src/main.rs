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

fn main() -> ExitCode {
    let args = cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) if is_broken_pipe(&error) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::from(2)
        }
    }
}

/// Whether the error is stdout's reader having gone away (`| head`).
fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error
        .downcast_ref::<std::io::Error>()
        .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
}
