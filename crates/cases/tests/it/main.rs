//! tissue-cases' integration tests (one binary, one module per area). Helpers outside the
//! tests unwrap and panic as the tests do.
#![allow(clippy::unwrap_used, clippy::panic)]

mod archive;
mod common;
mod compare;
mod concurrency;
mod crash;
mod erase;
mod migrations;
mod roundtrip;
mod validation;
