//! # tissue-mesh: triangle and tetrahedral meshes (pure data and geometry, no I/O)
//!
//! ## Brief overview
//! - [`TriMesh`]: a triangle surface built through a validating constructor. Every defect a
//!   user's file can have is a [`MeshError`] naming the element; [`diagnose`] lists all of them.
//! - [`Topology`]: unique edges, vertex→triangles and edge→triangles adjacency, ordered boundary
//!   loops, connected components.
//! - [`TetMesh`]: a validated tetrahedral mesh with face adjacency and its outward boundary
//!   surface; [`diagnose_tets`] lists every defect.
//! - [`Aabb`]: an axis-aligned box; [`TriMesh::bounding_box`], areas, normals, centroid and
//!   [`TriMesh::signed_volume`] are measures of a surface, [`volume_between`] the thesis's volume
//!   difference of two surfaces that share a boundary.
//! - Generators: [`grid`], [`uv_sphere`], [`subdivided_cube`], [`disc`], [`tet_box`].
//!
//! Units are whatever the positions are in; the rest of tissue uses centimetres. Positions are
//! stored as `f32` ([`glam::Vec3`]); every sum over a mesh (area, volume, centroid) is
//! accumulated in `f64`. Indices are `u32`.
//!
//! ```
//! use glam::Vec3;
//! use tissue_mesh::TriMesh;
//!
//! // A unit square of two triangles, normal +z.
//! let square = TriMesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
//!     vec![[0, 1, 2], [0, 2, 3]],
//! )?;
//! assert_eq!(square.topology().edges().len(), 5);
//! assert_eq!(square.topology().boundary_loops(), &[vec![0, 1, 2, 3]]);
//! # Ok::<(), tissue_mesh::MeshError>(())
//! ```

#![forbid(unsafe_code)]

mod aabb;
mod error;
mod generate;
mod measure;
mod tetmesh;
mod topology;
mod trimesh;

pub use aabb::Aabb;
pub use error::MeshError;
pub use generate::{disc, grid, subdivided_cube, tet_box, uv_sphere};
pub use measure::{volume_between, BOUNDARY_TOLERANCE};
pub use tetmesh::{diagnose_tets, TetMesh, NO_TET, TET_FACES, ZERO_VOLUME_TOLERANCE};
pub use topology::{Topology, NO_TRIANGLE};
pub use trimesh::{diagnose, TriMesh, ZERO_AREA_TOLERANCE};
