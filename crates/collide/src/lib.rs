//! # tissue-collide: collisions between two tissue surfaces (no implants, no mass–spring model)
//!
//! ## Brief overview
//! - [`Surface`]: a colliding surface's triangles and unique edges (the springs), each edge owned
//!   by one of its triangles; [`Surface::view`] pairs it with the step's positions.
//! - Detection (SPEC A.4) returns the same sorted [`Contact`] set three ways:
//!   [`detect_bvh_bvh`] (both surfaces in a [`tissue_bvh::Bvh`]), [`detect_bvh_voxels`] (the
//!   smaller surface in a [`VoxelGrid`] of uniform cells listing the triangles that overlap them
//!   by an exact triangle–box test) and [`detect_brute_force`] (the oracle). The narrow phase is
//!   [`edge_triangle`]: an edge of one surface against a triangle of the other, both directions.
//! - Response: [`impulse`] is eqs. (8)–(10) generalised to points inside an edge and a triangle
//!   (barycentric weights, inverse masses, restitution, Coulomb friction), applied by
//!   [`apply_impulses`]; [`correct_positions`] pushes edges left through a triangle back out.
//! - [`Collider`]: all of it for one pair of surfaces across steps (hierarchies refit, grid
//!   re-binned, workspace reused): [`Collider::detect`], [`Collider::apply_impulses`],
//!   [`Collider::separate`].
//!
//! Particle state is flat arrays as the mass–spring crate stores it: positions and velocities
//! `&[glam::Vec3A]`, inverse masses `&[f32]` with 0 for a fixed particle ([`Bodies`]). Units:
//! cm, g, s (velocities cm/s, impulses g·cm/s). Nothing allocates in a step once the buffers have
//! grown; each phase is a `tracing` span.
//!
//! ```
//! use glam::Vec3A;
//! use tissue_collide::{Bodies, Collider, ColliderOptions, ResponseParams, Snapshot};
//!
//! // A fixed 1 cm plane (A) and a sphere of radius 0.25 cm (B) whose top is 0.01 cm below it,
//! // moving up at 10 cm/s; the step is 2 ms.
//! let plane = tissue_mesh::grid(33, 1.0)?;
//! let sphere = tissue_mesh::uv_sphere(16, 15, 0.25)?;
//! let mut pos_a: Vec<Vec3A> = plane.positions().iter().map(|&p| p.into()).collect();
//! let down = Vec3A::new(0.0, 0.0, -0.26);
//! let mut pos_b: Vec<Vec3A> = sphere.positions().iter().map(|&p| Vec3A::from(p) + down).collect();
//! let (inv_a, inv_b) = (vec![0.0; pos_a.len()], vec![1.0; pos_b.len()]);
//! let mut vel_a = vec![Vec3A::ZERO; pos_a.len()];
//! let mut vel_b = vec![Vec3A::new(0.0, 0.0, 10.0); pos_b.len()];
//! let h = 0.002;
//! let mut collider = Collider::new(&plane, &sphere, &ColliderOptions::default())?;
//! let params = ResponseParams::default();
//!
//! // Phase 3 (collisions): nothing touches yet, so no impulse.
//! assert!(collider.detect(&pos_a, &pos_b)?.is_empty());
//! collider.apply_impulses(&mut Bodies::two(&mut vel_a, &inv_a, &mut vel_b, &inv_b), &params)?;
//! // Phase 4 (positions): the sphere moves 0.02 cm up, 0.01 cm through the plane.
//! let (prev_a, prev_b) = (pos_a.clone(), pos_b.clone());
//! for (x, v) in pos_b.iter_mut().zip(&vel_b) {
//!     *x += *v * h;
//! }
//! assert!(collider.detect(&pos_a, &pos_b)?.iter().any(|c| c.is_crossing()));
//! // Then no sphere edge may be left through the plane: the sphere's cap is pushed back below.
//! let report = collider.separate(
//!     &mut Bodies::two(&mut pos_a, &inv_a, &mut pos_b, &inv_b),
//!     Some(Snapshot { a: &prev_a, b: &prev_b }),
//!     &params,
//! )?;
//! assert_eq!(report.remaining, 0);
//! assert!(pos_b.iter().all(|p| p.z <= 1e-3));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]

mod bodies;
mod collider;
mod contact;
mod correct;
mod detect;
mod edge_triangle;
mod error;
mod impulse;
mod narrow;
mod surface;
mod tri_box;
mod voxel;
mod workspace;

pub use bodies::{Bodies, Particles};
pub use collider::{BroadPhase, Collider, ColliderOptions, SeparationReport, UpdateReport};
pub use contact::{Contact, ContactParams, DetectStats, Side};
pub use correct::{correct_positions, CorrectionReport, Snapshot};
pub use detect::{detect_brute_force, detect_bvh_bvh, detect_bvh_voxels};
pub use edge_triangle::{edge_triangle, EdgeTriangleHit};
pub use error::CollideError;
pub use impulse::{
    apply_impulses, impulse, Impulse, ImpulseReport, ImpulseWorkspace, ResponseParams,
};
pub use surface::{Surface, SurfaceView, NOT_OWNED};
pub use tri_box::triangle_overlaps_box;
pub use voxel::{VoxelGrid, MAX_CELLS};
pub use workspace::DetectWorkspace;
