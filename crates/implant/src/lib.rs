//! # tissue-implant: the implant-insertion scenario of the thesis (SPEC A.5)
//!
//! ## Brief overview
//! - [`TissueLayers`]: the two-layer mass–spring model of a skin region (layer 1 the region,
//!   layer 2 offset inward by the placement depth, springs between the layers against
//!   compression and shear, zero-length anchors on layer 2, the boundary fixed).
//!
//! Pure scenario logic on top of `tissue-mesh`, `tissue-mss`, `tissue-bvh` and `tissue-collide`:
//! no threads, no terminal, no file I/O. Units: cm, g, s.
//!
//! ```
//! use tissue_implant::{Layer, LayerParams, TissueLayers};
//!
//! // A flat skin patch of radius 3 cm, its inner layer 1 cm below, lifted 0.5 cm.
//! let region = tissue_mesh::disc(6, 24, 3.0)?;
//! let mut layers = TissueLayers::new(&region, &LayerParams::default())?;
//! layers.lift(0.5)?;
//! let centre = layers.positions(Layer::Outer)[0];
//! assert!((centre.z - 0.5).abs() < 1e-6);
//! # Ok::<(), tissue_implant::ImplantError>(())
//! ```
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
pub use layers::{Layer, LayerParams, TissueLayers};
