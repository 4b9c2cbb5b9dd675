//! The Python package `posg_fsc`: a thin binding of the `posg_fsc` library
//! (pyo3, built by maturin from the repository's `pyproject.toml`).
//!
//! It converts types and calls the library's public API, nothing more:
//! games and controllers ([`game`], [`controller`]), the exact value and
//! gradient ([`evaluate`]), the main job and sweeps ([`solve`]), certified
//! bounds, support synthesis and the LTL translation ([`certify`]). Every
//! library error becomes a `posg_fsc.Error` subclass ([`errors`]); the GIL
//! is released while Rust computes. The compiled module is
//! `posg_fsc._native`, re-exported by `python/posg_fsc/__init__.py`; the
//! Python API is documented in `python/posg_fsc/__init__.pyi` (type stubs)
//! and docs/guide.md, section "Python".

mod arrays;
mod certify;
mod controller;
mod convert;
mod errors;
mod evaluate;
mod game;
mod help;
mod objective;
mod reward;
mod simulate;
mod solve;

use pyo3::prelude::*;

/// mimalloc, as in the command line: the library's bound evaluations
/// allocate and free many small graphs.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// posg_fsc: finite-state controllers for partially observable stochastic
/// games under LTL objectives (exact values, adjoint gradients, max-min
/// optimisation against a worst-case adversary, certified bounds).
#[pymodule]
#[pyo3(name = "_native")]
fn posg_fsc_python(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    module.add_class::<game::Game>()?;
    module.add_class::<controller::Controller>()?;
    module.add_class::<evaluate::Evaluation>()?;
    module.add_class::<evaluate::Query>()?;
    module.add_class::<solve::SolveResult>()?;
    module.add_class::<reward::RewardSolveResult>()?;
    module.add_function(wrap_pyfunction!(game::example_grid, module)?)?;
    module.add_function(wrap_pyfunction!(solve::solve, module)?)?;
    module.add_function(wrap_pyfunction!(solve::sweep, module)?)?;
    module.add_function(wrap_pyfunction!(simulate::simulate, module)?)?;
    module.add_function(wrap_pyfunction!(help::settings_list, module)?)?;
    module.add_function(wrap_pyfunction!(certify::certify, module)?)?;
    module.add_function(wrap_pyfunction!(certify::support, module)?)?;
    module.add_function(wrap_pyfunction!(certify::translate, module)?)?;
    errors::register(module)?;
    Ok(())
}
