//! # tissue-python: `import tissue`
//!
//! The native half (`tissue._tissue`) of the Python package `tissue`: a PyO3 extension over the
//! two front doors the other front ends use, `tissue-planner` (planning) and `tissue-scenes` (the
//! trainer), as the C ABI (`tissue-capi`) is. It holds no planning or trainer logic of its own:
//! it turns Python arguments into a [`tissue_planner::JobSpec`] (the JSON the studio and the C
//! ABI take), runs it through [`tissue_planner::PlannedJob::run`], and hands back the report (the
//! JSON contract, `tool` `"python"`) and the deformed patient as NumPy arrays.
//!
//! The pure-Python half (`python/tissue/__init__.py`) holds the documented API (`tissue.plan`,
//! `tissue.sweep`, …, with their keyword arguments), the exception classes
//! (`tissue/_errors.py`) and the type stubs; this crate is what it calls.
//!
//! - [`plan`]: `Patient`, `Plan`, and `_run` (a job's JSON on a patient): the job runs on a
//!   thread of its own with the GIL released; the calling thread waits, taking the GIL every
//!   20 ms to hand the newest progress to the caller's callback and to check for signals
//!   (Ctrl-C cancels the job and raises `KeyboardInterrupt` at once).
//! - [`trainer`]: `Body` (a tissue-scenes `Session` behind a mutex, stepped with the GIL
//!   released) and its contact `Tool`s.
//! - [`errors`]: every library error as one of `tissue._errors`' classes, all subclasses of
//!   `tissue.TissueError`: nothing panics across the boundary (a panic in a job is caught and
//!   raised as a `PlanError` of kind `run`).
//!
//! Units as everywhere in tissue: cm, g, s inside; a patient's positions and displacements in
//! its file's unit; trainer positions in cm, forces in newtons.
//!
//! Building: `pip install ./python` (maturin, `python/pyproject.toml`). No `extension-module`
//! feature: PyO3 0.30 leaves libpython unlinked when maturin sets `PYO3_BUILD_EXTENSION_MODULE`,
//! so the workspace's own `cargo test` and `cargo clippy` build this crate as any other member.

// No `unsafe` here: PyO3's macros allow their own FFI glue, so the workspace's deny holds.
#![forbid(unsafe_code)]

use pyo3::prelude::*;

pub mod arrays;
pub mod errors;
pub mod plan;
pub mod trainer;

/// The library's version (the workspace's), `tissue.__version__`.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The module `tissue._tissue`.
#[pymodule]
fn _tissue(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", VERSION)?;
    m.add(
        "REPORT_SCHEMA_VERSION",
        tissue_planner::report::SCHEMA_VERSION,
    )?;
    m.add_class::<plan::Patient>()?;
    m.add_class::<plan::Plan>()?;
    m.add_function(wrap_pyfunction!(plan::_run, m)?)?;
    m.add_function(wrap_pyfunction!(plan::_request_fields, m)?)?;
    m.add_function(wrap_pyfunction!(plan::_plan_restore, m)?)?;
    m.add_class::<trainer::Body>()?;
    m.add_class::<trainer::Tool>()?;
    Ok(())
}
