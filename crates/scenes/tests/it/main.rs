//! The integration tests of `tissue-scenes` in one binary, a module per area (each module's own
//! doc says what it covers).

mod material;
mod moving_body;
mod probe;
mod selfcol;
mod session;
mod shipped;
