//! # tissue-pbd: position-based dynamics for the surgical trainer
//!
//! ## Brief overview
//! - [`SoftBody`]: a tetrahedral body as flat node arrays (positions, previous positions,
//!   velocities, masses, inverse masses; inverse mass 0 = pinned) and constraints stored flat by
//!   kind: [`DistanceConstraint`] per unique tet edge, and per [`Material::volume`] either
//!   [`TetVolumeConstraint`] (classic, one per tet), [`CentroidVolumeConstraint`] (the slides',
//!   four per tet) or none. Pins, kinematic attachments, a static [`Floor`].
//! - [`StepSettings`] / [`Solver`]: `Δt`, `K` Gauss–Seidel iterations, PBD with raw or linearised
//!   stiffness (`k' = 1 − (1 − k)^{1/K}`), or XPBD (compliance `α`, `α̃ = α/Δt²`), gravity,
//!   rigid-mode damping, serial or parallel projection (same result).
//! - [`PbdError`]: bad input, naming the element.
//!
//! ## Units
//! Centimetres, grams, seconds (as `tissue-mss`): gravity −981 cm/s², density g/cm³, XPBD
//! compliance in `[C]²/erg` (cm/dyn for distances).
//!
//! ## Step (SPEC Part B, Müller et al.)
//! `v += Δt·w·f_ext`; `p = x + Δt·v`; `K` × project (distance, volume, floor); `v = (p − x)/Δt`;
//! `x = p`; rigid-mode damping `vᵢ += k_damp (v_cm + ω × rᵢ − vᵢ)`. Projection
//! `Δpᵢ = −s wᵢ ∇ᵢC`, `s = C / Σⱼ wⱼ|∇ⱼC|²` (scaled by `k` or `k'`), which conserves linear and
//! angular momentum. The centroid constraint uses this general projection: its weight sum is
//! `W' = w₁+w₂+w₃+9w_s`, not the slides' `w₁+w₂+w₃+w_s` (which over-corrects 3× for equal
//! masses; see [`CentroidVolumeConstraint`]).
//!
//! ## Invariants and determinism
//! - Architecture Invariant: a step allocates nothing; every buffer is made in the constructor.
//! - Solver order (module `partition`), fixed by the mesh alone, never by the thread count: at
//!   construction the nodes are renumbered by recursive coordinate bisection, and a binary tree
//!   of blocks is laid over the renumbered nodes: each block a contiguous node range, its
//!   children its two halves, leaves of at most 1280 nodes (a leaf's positions fit in L1). Each
//!   constraint belongs to the deepest block holding all its nodes. The public API keeps the
//!   caller's node order: a step predicts straight into a solver-order buffer and copies the
//!   result back; node indices in records and errors are the caller's.
//! - Within a block the constraints are greedily coloured and stored colour by colour, in
//!   batches of eight projected at once (one constraint per `f32` lane, two `Vec4`s per value).
//!   The lanes of a batch share no node, and a colour's last batch is filled up with copies of
//!   its lane 0, which compute and write back exactly what lane 0 does; so projecting a batch is
//!   projecting its constraints one after another.
//! - One iteration is one Gauss–Seidel sweep in a fixed order: the blocks in post order (left
//!   subtree, right subtree, then the block's own constraints: distances, then volumes), then the
//!   floor. It is not the mesh order a naive Gauss–Seidel would use (it converges about as fast;
//!   results differ at float level from other orders) and it depends on the node positions and
//!   count given.
//! - The parallel mode runs the two subtrees of a block at the same time (`rayon::join` on
//!   disjoint `split_at_mut` slices of the nodes and multipliers: one fork–join tree per
//!   iteration, no copies, no write-back). The root block's own constraints (about 3 % of the
//!   bunny's) and the floor are the serial part of an iteration. Every node sees the same
//!   projections, in the same order, on the same values as in the serial sweep, so **serial and
//!   parallel are bit-identical, for any thread count** (`tests/parallel.rs`: 1, 2, 3 threads).
//! - While the root's own constraints are projected, a second worker, if one is free, spins on a
//!   flag instead of going to sleep, so that the next iteration's fork does not wait for a
//!   thread to wake up (it yields to the OS after a few thousand spins). It touches no data.
//! - No I/O; meshes come in as [`tissue_mesh::TetMesh`] or raw arrays.
//!
//! ## Example: a cube resting on a floor keeps its volume
//! ```
//! use glam::Vec3;
//! use tissue_mesh::tet_box;
//! use tissue_pbd::{Floor, Material, SoftBody, StepSettings, VolumeConstraintKind};
//!
//! let mesh = tet_box(3, 3, 3, Vec3::splat(2.0))?;
//! let material = Material { distance_stiffness: 0.5, volume: VolumeConstraintKind::Classic, ..Material::default() };
//! let mut body = SoftBody::new(&mesh, &material)?;
//! body.set_floor(Some(Floor::y(-1.0)))?;
//! body.set_settings(StepSettings { dt: 0.005, iterations: 20, ..StepSettings::default() })?;
//! for _ in 0..40 {
//!     body.step()?;
//! }
//! assert!((body.volume() / body.rest_volume() - 1.0).abs() < 0.02);
//! assert!(body.positions().iter().all(|p| p.y >= -1.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::print_stdout,
    clippy::print_stderr
)]

mod body;
mod colour;
mod constraint;
mod error;
mod partition;
mod settings;
mod step;

pub use body::SoftBody;
pub use constraint::{
    CentroidVolumeConstraint, ConstraintKind, DistanceConstraint, Floor, TetVolumeConstraint,
};
pub use error::PbdError;
pub use settings::{Material, Solver, StepSettings, VolumeConstraintKind};
