//! # tissue-bvh: axis-aligned bounding-box hierarchies (geometry only, no physics)
//!
//! ## Brief overview
//! - [`Bvh`]: a flat array of 32-byte [`BvhNode`]s with `u32` indices, children adjacent, over any
//!   [`Primitives`] (a set whose members each give an [`Aabb`]). [`Bvh::build`] works top-down
//!   with the thesis's equal-area split ([`Split::EqualArea`], SPEC A.3) or a binned SAH
//!   ([`Split::Sah`]) down to [`BuildOptions::leaf_size`]; [`BuildOptions::margin`] fattens the
//!   leaf boxes for contact anticipation.
//! - [`Bvh::refit`]: boxes follow the moved primitives with the thesis's semantics (a leaf takes a
//!   new box only if it differs, an inner node recomputes only if a child changed) and returns a
//!   [`RefitReport`] with the number of changed nodes and the [`Bvh::cost`] figure a caller
//!   compares with [`Bvh::build_cost`] to decide on [`Bvh::rebuild`].
//! - Queries, all taking a [`BvhWorkspace`] so that nothing allocates in a simulation step:
//!   [`Bvh::overlapping_leaves`] / [`Bvh::overlapping_primitives`] (box), [`Bvh::closest_point`]
//!   (point, [`ClosestPoint`]), [`Bvh::cast_ray`] ([`Ray`], [`RayIntersect`]) and
//!   [`Bvh::leaf_pairs`] between two hierarchies.
//! - [`Triangles`]: the triangles of a mesh at given positions (weight = area), the primitives the
//!   rest of tissue builds hierarchies over. [`Bvh::assert_well_formed`] checks every invariant.
//!
//! Units are those of the positions (cm in tissue); positions are `f32` ([`glam::Vec3A`] in the
//! hot arrays, [`glam::Vec3`] in the boxes). Builds and refits of hierarchies over 16 k primitives
//! or more split their work over rayon's threads (feature `parallel`, on by default); the result
//! is the same, bit for bit, on any number of threads.
//!
//! ```
//! use glam::Vec3A;
//! use tissue_bvh::{Aabb, BuildOptions, Bvh, BvhWorkspace, Triangles};
//!
//! let mesh = tissue_mesh::grid(33, 1.0)?; // 2048 triangles in z = 0
//! let mut positions: Vec<Vec3A> = mesh.positions().iter().map(|&p| p.into()).collect();
//! let mut bvh = Bvh::build(&Triangles::from_mesh(&mesh, &positions)?, &BuildOptions::default())?;
//! bvh.assert_well_formed(&Triangles::from_mesh(&mesh, &positions)?);
//!
//! // Lift one vertex and refit: only the boxes on its leaves' paths to the root change.
//! positions[0].z += 0.1;
//! let tris = Triangles::from_mesh(&mesh, &positions)?;
//! let report = bvh.refit(&tris)?;
//! assert!(report.nodes_changed > 0 && (report.nodes_changed as usize) < bvh.node_count());
//! bvh.assert_well_formed(&tris);
//!
//! let mut ws = BvhWorkspace::new();
//! let mut hits = Vec::new();
//! let probe = Aabb::new(glam::Vec3::splat(-0.01), glam::Vec3::splat(0.01));
//! bvh.overlapping_primitives(&tris, &probe, 0.0, &mut ws, &mut hits);
//! assert!(!hits.is_empty());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]

mod aabb;
mod bvh;
mod bvh_build;
mod bvh_pairs;
mod bvh_refit;
mod bvh_traverse;
mod error;
mod geometry;
mod primitives;
mod workspace;

#[doc(hidden)]
pub mod scenes;

pub use aabb::Aabb;
pub use bvh::{BuildOptions, Bvh, BvhNode, Split};
pub use bvh_build::{BuildWorkspace, MAX_PRIMITIVES};
pub use bvh_refit::RefitReport;
pub use bvh_traverse::{PointHit, RayHit};
pub use error::BvhError;
pub use geometry::{closest_point_on_triangle, closest_point_on_triangle_f64, ray_triangle};
pub use primitives::{ClosestPoint, Primitives, Ray, RayIntersect, Triangles};
pub use workspace::BvhWorkspace;
