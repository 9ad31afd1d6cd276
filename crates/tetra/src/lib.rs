//! # tissue-tetra: tetrahedral models from closed surfaces
//!
//! ## Brief overview
//! - [`tetrahedralize`] fills a closed, manifold [`tissue_mesh::TriMesh`] with tetrahedra and
//!   returns a [`Tetrahedralization`]: the [`tissue_mesh::TetMesh`], its [`QualityReport`],
//!   the interior spacing used. [`tetrahedralize_triangles`] does the same for raw arrays,
//!   validating them first.
//! - [`TetraOptions`]: interior spacing (default `1.68 ×` the mean surface edge length, about
//!   40 000 tetrahedra for a 10 000-triangle bunny), clearance, sliver thresholds, and
//!   `max_tets`, a limit that bounds the work whatever the surface.
//! - [`estimate_tets`]: the count [`tetrahedralize`] will make, in linear time before any
//!   meshing ([`TetEstimate`]: from the enclosed volume, the area, the surface vertices and the
//!   lattice spacing; within 0.91–1.04× of the mesher on the shipped and test surfaces), and
//!   how far to decimate a surface to stay under a count ([`TetEstimate::triangles_for`]).
//! - [`QualityReport`]: counts, dihedral angles, radius-ratio histogram, volumes, and how many
//!   surface triangles are boundary faces of the tetrahedra; [`QualityReport::of_mesh`] measures
//!   meshes from other tools (TetGen files) the same way. `Display` prints it.
//! - [`TetraError`]: open surface (names a boundary edge), non-manifold edge or vertex,
//!   coincident vertices, inside-out or flat surface, too few points, bad options, more
//!   tetrahedra than `max_tets` (estimated before meshing, or counted: [`TetCount`]), numerical
//!   failure.
//!
//! Pure Rust; the only geometric dependency is `robust` (Shewchuk's adaptive exact predicates).
//!
//! ## Algorithm
//! 1. **Check** the surface (closed, manifold vertices, no coincident vertices, positive
//!    enclosed volume); with `max_tets`, refuse a surface [`estimate_tets`] expects to exceed it.
//! 2. **Interior points**: a body-centred cubic lattice of spacing `a`, kept where it is inside
//!    the surface (exact ray parity), at least `clearance · a` from it and outside the
//!    circumscribed balls of small surface triangles. The BCC lattice's Delaunay tetrahedra are
//!    all congruent (dihedral angles 60° and 90°).
//! 3. **Insert** (Bowyer–Watson): surface vertices and lattice points in a biased randomised
//!    order sorted along a Morton curve in each round, located by a visibility walk, cavities
//!    by exact `insphere` with symbolic perturbation (so cospherical lattice points give no
//!    flat tetrahedra); with `max_tets`, stopped if it outgrows four times the estimate.
//! 4. **Carve**: keep the tetrahedra whose centroid is inside the surface.
//! 5. **Improve**: surface triangles missing because the Delaunay tetrahedralisation chose the
//!    other diagonal of a surface quad are recovered by edge removal; slivers are removed by
//!    edge removal where that raises quality; boundary slivers are peeled where that costs no
//!    surface triangle (near-degenerate ones whatever the cost); anything still flat by
//!    [`tissue_mesh::ZERO_VOLUME_TOLERANCE`] goes.
//! 6. **Quality**: the [`QualityReport`].
//!
//! Each phase is a `tracing` span (`check`, `lattice`, `insert`, `carve`, `recover`,
//! `slivers`, `peel`, `quality`) inside `tetrahedralize`. The library never prints.
//!
//! ## Invariants of the result
//! - Nodes `0..surface.vertex_count()` are the surface's vertices, same order, bit-identical
//!   positions; interior nodes follow. A surface vertex used by no triangle stays as an
//!   unreferenced node.
//! - Every tetrahedron is positively oriented, `(b − a)×(c − a)·(d − a) > 0`, and passes
//!   [`tissue_mesh::TetMesh::new`]'s flatness test (it is a valid `TetMesh`).
//! - The boundary of the tetrahedra follows the surface: each surface triangle is a boundary
//!   face unless recovery failed there (the report counts them; 96 % for the bunny), and the
//!   volume matches the surface's signed volume closely (0.01 % for the bunny; tests hold it
//!   to 2 %).
//! - Deterministic: the same input gives the same mesh.
//!
//! Not guaranteed: that every surface triangle is recovered (this is not a constrained
//! tetrahedralisation), nor a minimum dihedral angle; self-intersecting surfaces are not
//! detected. Units are those of the surface (cm in tissue).
//!
//! ```
//! use tissue_mesh::uv_sphere;
//! use tissue_tetra::{tetrahedralize, TetraOptions};
//!
//! let sphere = uv_sphere(24, 12, 1.0)?; // radius 1 cm, 266 vertices
//! let tets = tetrahedralize(&sphere, &TetraOptions::default())?;
//! let mesh = &tets.mesh;
//! // Surface vertices first, in order.
//! assert_eq!(&mesh.positions()[..sphere.vertex_count()], sphere.positions());
//! // The tets fill the enclosed volume.
//! let enclosed = sphere.signed_volume()?;
//! assert!((mesh.volume() / enclosed - 1.0).abs() < 0.02);
//! assert!(mesh.tet_volumes().iter().all(|&v| v > 0.0));
//! println!("{}", tets.report);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]

mod carve;
mod check;
mod delaunay;
mod error;
mod estimate;
mod improve;
mod inside;
mod lattice;
mod mesher;
mod order;
mod predicates;
mod quality;

pub use error::{TetCount, TetraError};
pub use estimate::{estimate_tets, TetEstimate};
pub use mesher::{tetrahedralize, tetrahedralize_triangles, TetraOptions, Tetrahedralization};
pub use quality::{QualityReport, RADIUS_RATIO_BINS};
