//! tissue-cases' integration tests (one binary, one module per area).

mod archive;
mod common;
mod compare;
mod concurrency;
mod crash;
mod erase;
mod migrations;
mod roundtrip;
mod validation;
