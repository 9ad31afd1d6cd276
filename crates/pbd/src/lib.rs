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
//! - Domain decomposition (module `partition`), fixed by the mesh alone: at construction the
//!   nodes are renumbered by recursive coordinate bisection, and a binary tree of blocks is laid
//!   over the renumbered nodes (each block a contiguous node range, its children the two halves,
//!   leaves of at most 640 nodes, so a leaf's sweep runs in L1). Each constraint belongs to the
//!   deepest block holding all its nodes; within a block constraints are greedily coloured and
//!   stored colour by colour, in batches of eight that are projected at once (one constraint per
//!   SIMD lane, two `Vec4`s per value; the last batch of a colour is filled up with copies of its
//!   lane 0, which compute and write back exactly what lane 0 does), so projecting a batch is
//!   projecting its eight constraints one after another. The public API keeps the caller's node
//!   order: a step copies the predicted positions into solver order, projects, and copies them
//!   back.
//! - One iteration is one Gauss–Seidel sweep in a fixed order: the blocks in post order (left
//!   subtree, right subtree, then the block's own constraints: distances, then volumes), then the
//!   floor. The parallel mode runs the two subtrees of a block at the same time (`rayon::join`
//!   on disjoint `split_at_mut` slices; one fork–join tree per iteration, no write-back); every
//!   node sees the same projections in the same order as in the serial sweep, so **serial and
//!   parallel are bit-identical, for any thread count**. The price is the order: it is not the
//!   mesh order a naive Gauss–Seidel would use (it converges about as fast; results differ at
//!   float level), and it changes with the node count and positions given.
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
