//! The integration tests of `tissue-pbd` in one binary, a module per area (each module's own
//! doc says what it covers). Tests that must be alone in their process (allocation
//! counters, timing bounds) keep their own binaries beside `it/`.

#[path = "../common/mod.rs"]
mod common;

mod collision;
mod edit;
mod elastic;
mod errors;
mod force;
mod intersect;
mod parallel;
mod physics;
mod presets;
mod selfcol;
