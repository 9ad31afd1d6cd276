//! The integration tests of `tissue-meshio` in one binary, a module per area (each module's own
//! doc says what it covers). Tests that must be alone in their process (allocation
//! counters, timing bounds) keep their own binaries beside `it/`.

#[path = "../support/bombs.rs"]
mod bombs;
mod fuzz;
mod limits;
mod meshio;
mod tet_formats;
