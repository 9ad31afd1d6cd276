//! The integration tests of `tissue-implant` in one binary, a module per area (each module's own
//! doc says what it covers). Tests that must be alone in their process (allocation
//! counters, timing bounds) keep their own binaries beside `it/`.

mod expansion;
mod head;
mod insertion;
mod layers;
mod outcome;
mod plane_press;
mod planning;
mod quasi_static;
mod region;
mod shape;
mod table2;
