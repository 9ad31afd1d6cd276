//! The integration tests of `tissue-surgery` in one binary, a module per area (each module's own
//! doc says what it covers). Tests that must be alone in their process (allocation
//! counters, timing bounds) keep their own binaries beside `it/`.

#[path = "../common/mod.rs"]
mod common;

mod cut;
mod geometry;
mod robustness;
mod suture;
mod tip;
