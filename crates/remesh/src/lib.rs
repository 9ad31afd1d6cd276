//! # tissue-remesh: isotropic remeshing and hole filling of skin patches (geometry only)
//!
//! ## Brief overview
//! - [`remesh`] turns a surface patch (a photogrammetric scan region: fine and noisy, or coarse
//!   and uneven) into a simulation mesh of near-uniform edges of a target length `L`
//!   ([`RemeshOptions::target_edge`]), optionally projecting onto a moving-least-squares
//!   smoothing of the input ([`RemeshOptions::smoothing_radius`]) so that noise below that scale
//!   is removed. It returns the mesh and [`RemeshStats`] (counts, [`MeshQuality`]).
//! - [`fill_holes`] closes every boundary loop up to a given diameter with a fair patch of
//!   well-shaped triangles and reports the larger ones ([`Hole`], [`HoleFill`]).
//! - [`MeshQuality::measure`]: edge-length band fractions and angle figures of any surface.
//! - Errors: one [`RemeshError`] enum.
//!
//! Units are whatever the mesh is in (tissue uses cm). Positions are `f32` ([`glam::Vec3`]),
//! sums (areas, centroids, fits) `f64`.
//!
//! ## The remeshing algorithm
//! Botsch & Kobbelt (2004), "A remeshing approach to multiresolution modeling". With
//! `hi = 4/3·L`, `lo = 4/5·L`, each iteration runs five phases (each a `tracing` span):
//! 1. **split** every edge longer than `hi` at its midpoint (sweeps until none is left);
//! 2. **collapse** edges shorter than `lo`, shortest first (a priority queue), unless the
//!    collapse would make an edge longer than `hi`, turn a changed triangle by more than about
//!    78°, break the link condition, leave a vertex with too few neighbours or pull a boundary
//!    vertex off the boundary. A boundary edge collapses along the boundary (to its midpoint), an
//!    interior edge with one boundary end onto that end, an interior edge between two boundary
//!    vertices never;
//! 3. **flip** interior edges where that brings valences towards 6 (4 on the boundary), unless a
//!    new triangle would fold;
//! 4. **relax** tangentially: an interior vertex moves to the area-weighted centroid of its
//!    triangles within its tangent plane; a boundary vertex to the midpoint of its two boundary
//!    neighbours along the boundary;
//! 5. **project** interior vertices onto the reference surface (closest point of the input, or
//!    the MLS plane fit), boundary vertices onto the input's boundary polylines.
//!
//! Invariants of the result: a valid [`tissue_mesh::TriMesh`]; the same components, boundary
//! loops and Euler characteristic as the input (every operation preserves them); the input's
//! orientation; boundary vertices on the input's boundary, interior vertices on the reference
//! surface. Vertices where two boundary loops touch (and unreferenced ones) are kept fixed
//! (unreferenced ones are dropped from the output). Deterministic: the same input gives the same
//! output bit for bit (single-threaded, no hash-map order).
//!
//! ```
//! use tissue_remesh::{remesh, RemeshOptions};
//!
//! // A 4 × 4 plane of 0.1-spaced grid lines, remeshed to edges of about 0.5.
//! let plane = tissue_mesh::grid(41, 4.0)?;
//! let out = remesh(&plane, &RemeshOptions::new(0.5))?;
//! assert!(out.mesh.triangle_count() < plane.triangle_count() / 10);
//! assert_eq!(out.mesh.topology().boundary_loops().len(), 1);
//! assert_eq!(out.mesh.euler_characteristic(), plane.euler_characteristic());
//! assert!(out.stats.quality.edges_in_wide_band > 0.85);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]
#![warn(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::print_stdout,
    clippy::print_stderr
)]

mod edit;
mod error;
mod holes;
mod quality;
mod reference;
mod remesh;

#[doc(hidden)]
pub mod scenes;

pub use error::RemeshError;
pub use holes::{fill_holes, Hole, HoleFill};
pub use quality::MeshQuality;
pub use remesh::{remesh, RemeshOptions, RemeshStats, Remeshed, MAX_TRIANGLES};
