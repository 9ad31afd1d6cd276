//! # tissue-implant: the implant-insertion scenario of the thesis (SPEC A.5)
//!
//! ## Brief overview
//! - [`TissueLayers`]: the two-layer mass–spring model of a skin region (layer 1 the region,
//!   layer 2 offset inward by the placement depth, springs between the layers against
//!   compression and shear, zero-length anchors on layer 2, the boundary fixed).
//!
//! Pure scenario logic on top of `tissue-mesh`, `tissue-mss`, `tissue-bvh` and `tissue-collide`:
//! no threads, no terminal, no file I/O. Units: cm, g, s.
#![forbid(unsafe_code)]
#![warn(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::print_stdout,
    clippy::print_stderr
)]

mod error;
mod layers;

pub use error::ImplantError;
pub use layers::{LayerParams, TissueLayers};
