//! # tissue-pbd: position-based dynamics for the surgical trainer
//!
//! ## Brief overview
//! - [`SoftBody`]: a tetrahedral body as flat node arrays (positions, previous positions,
//!   velocities, masses, inverse masses; inverse mass 0 = pinned) and constraints stored flat by
//!   kind: [`DistanceConstraint`] per unique tet edge, and per [`Material::volume`] either
//!   [`TetVolumeConstraint`] (classic, one per tet), [`CentroidVolumeConstraint`] (the slides',
//!   four per tet) or none; with [`Material::hold_piece_volumes`], one more volume constraint
//!   per connected piece (its tets' total volume, projected on its boundary nodes after the
//!   contacts, the nodes in contact held: Müller et al. 2007 §4.4; a cut that separates a piece
//!   gives it its own). Pins, kinematic attachments, a static [`Floor`].
//! - [`StepSettings`] / [`Solver`]: `Δt`, `K` Gauss–Seidel iterations, PBD with raw or linearised
//!   stiffness (`k' = 1 − (1 − k)^{1/K}`), or XPBD (compliance `α`, `α̃ = α/Δt²`), gravity,
//!   rigid-mode damping, serial or parallel projection (same result).
//! - Contacts (collisions): [`VoxelCollider`], a static collider (tray, table, other
//!   organs) as signed distances on a uniform voxel grid, built from closed [`tissue_mesh::TriMesh`]es
//!   and [`OrientedBox`]es ([`ColliderShape`]); contacts are looked up only in occupied cells.
//!   Kinematic [`Tool`]s of a [`ToolShape`] (a capsule: needle, shaft; a thick triangle: scalpel
//!   blade) moved by the host through their [`Pose`] between steps and swept through the step.
//!   Each step generates one [`Contact`] per node and collider or tool that the node's path
//!   meets, an inequality `n·(p − q) − margin ≥ 0` projected in every iteration after the body's
//!   own constraints, with static and kinetic friction ([`ContactParams`]; Macklin et al. 2014).
//!   Contacts are per node: a tool thinner than the node spacing can pass between nodes.
//! - Reaction forces (the tool force), after each step, in dyn (g·cm/s²; 1 N =
//!   [`DYN_PER_NEWTON`] dyn): [`SoftBody::tool_force`], [`SoftBody::collider_force`] and
//!   [`SoftBody::floor_force`] from the source's own position corrections, averaged over the
//!   step of length `T = Σ h` over its (sub)steps of length `h`:
//!   `F = −(1/T) Σ_substeps (1/h) Σ m Δx` (normal and friction corrections; `−Σ m Δx / h²` for
//!   one step); [`SoftBody::holding_force`] on the attachments and pins together, from the
//!   momentum balance of the nodes (see the method).
//! - Between steps, for a haptic loop: [`ContactForceModel`], the force on a tool as
//!   a local linear model of the last step's contacts (normals, loads, the tissue's normal
//!   stiffness from a [`StiffnessEstimator`]), evaluated at the tool's newest position (N).
//! - Topology edits for cutting and suturing (used by `tissue-surgery`):
//!   [`SoftBody::duplicate_nodes`], [`SoftBody::set_tet_nodes`],
//!   [`SoftBody::add_distance_constraint`], [`SoftBody::add_link_constraint`] (sutures),
//!   [`SoftBody::set_distance_nodes`],
//!   [`SoftBody::remove_distance_constraint`], [`SoftBody::set_node_mass`]; where each record is
//!   projected: [`ConstraintSlot`]; how many were edited: [`SoftBody::dynamic_counts`],
//!   [`SoftBody::serial_dynamic_counts`].
//! - [`PbdError`]: bad input, naming the element.
//!
//! ## Units
//! Centimetres, grams, seconds (as `tissue-mss`): gravity −981 cm/s², density g/cm³, XPBD
//! compliance in `[C]²/erg` (cm/dyn for distances).
//!
//! ## Step (SPEC Part B, Müller et al.)
//! `v += Δt·w·f_ext`; `p = x + Δt·v`; generate contacts; `K` × project (distance, volume, floor,
//! contacts with friction); `v = (p − x)/Δt`;
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
//!   of blocks is laid over the renumbered nodes: each block a contiguous range of solver slots,
//!   its children its two halves, leaves of at most 1280 nodes (a leaf's positions fit in L1),
//!   each followed by as many spare slots for the nodes that edits add near them. Each
//!   constraint belongs to the deepest block holding all its nodes. The public API keeps the
//!   caller's node order: a step predicts straight into a solver-order buffer and copies the
//!   result back; node indices in records and errors are the caller's.
//! - Within a block the constraints are greedily coloured and stored colour by colour, in
//!   batches of eight projected at once (one constraint per `f32` lane, two `Vec4`s per value).
//!   The lanes of a batch share no node, and a colour's last batch is filled up with copies of
//!   its lane 0, which compute and write back exactly what lane 0 does; so projecting a batch is
//!   projecting its constraints one after another.
//! - One iteration is one Gauss–Seidel sweep in a fixed order: the blocks in post order (left
//!   subtree, right subtree, then the block's own constraints: distances, then volumes, then
//!   its dynamic batches of edits: volumes, then distances), then the serial dynamic set and
//!   links of edits, then the floor. It is not the mesh order a naive Gauss–Seidel would use (it converges about as fast;
//!   results differ at float level from other orders) and it depends on the node positions and
//!   count given.
//! - The parallel mode runs the two subtrees of a block at the same time (`rayon::join` on
//!   disjoint `split_at_mut` slices of the nodes and multipliers: one fork–join tree per
//!   iteration, no copies, no write-back). The root block's own constraints (about 3 % of the
//!   bunny's) and the floor are the serial part of an iteration. Every node sees the same
//!   projections, in the same order, on the same values as in the serial sweep, so **serial and
//!   parallel are bit-identical, for any thread count** (`tests/it/parallel.rs`: 1, 2, 3 threads).
//! - While the root's own constraints are projected, a second worker, if one is free, spins on a
//!   flag instead of going to sleep, so that the next iteration's fork does not wait for a
//!   thread to wake up (it yields to the OS after a few thousand spins). It touches no data.
//! - No I/O; meshes come in as [`tissue_mesh::TetMesh`] or raw arrays.
//! - Edits (module `edit`) keep the block tree as built and fit into it: a new node takes a spare
//!   slot of its source's leaf (after the tree's slots, serially projected, only once that leaf
//!   is full); a changed constraint keeps its tree lane when its block holds its new nodes and
//!   no other lane of its batch does, else its lane is switched off in place (its nodes
//!   collapsed onto one, rest 0, parameter off: the kernels skip it exactly) and it joins, like
//!   an added constraint, the *dynamic batches* of the deepest block holding its nodes,
//!   projected right after that block's own tree constraints (in parallel like them); only
//!   constraints on nodes past the tree go to the *serial set*, projected after the tree, then
//!   links such as sutures, last. Serial and parallel stay bit-identical (`tests/it/parallel.rs`
//!   also runs cut bodies). No re-partition: after very many edits the dynamic batches grow.
//! - Contacts are generated and projected serially, in a fixed order (colliders by id, then tools,
//!   nodes in order within each), so they are deterministic and the same in parallel mode. Their
//!   buffer is reserved when a collider or tool is added, so steps stay allocation-free.
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
//!
//! ## Example: a block on a voxel tray, pressed by a probe
//! ```
//! use glam::Vec3;
//! use tissue_mesh::{tet_box, TetMesh};
//! use tissue_pbd::{ContactParams, Material, OrientedBox, Pose, SoftBody, ToolShape, VoxelCollider};
//!
//! // A 4 × 2 × 4 cm block standing on the tray's top, y = 0.
//! let (p, t) = tet_box(8, 4, 8, Vec3::new(4.0, 2.0, 4.0))?.into_parts();
//! let block = TetMesh::new(p.iter().map(|p| *p + Vec3::Y).collect(), t)?;
//! let mut body = SoftBody::new(&block, &Material::default())?;
//! let tray = VoxelCollider::from_box(OrientedBox::tray(0.0, 0.0, 0.0, 20.0, 20.0, 2.0), 0.5)?;
//! body.add_collider(tray, ContactParams::default())?;
//! // A vertical probe of radius 0.3 cm, tip at the pose's origin, pushed 0.5 cm into the top.
//! let probe = ToolShape::Capsule { a: Vec3::ZERO, b: Vec3::new(0.0, 5.0, 0.0), radius: 0.3 };
//! let id = body.add_tool(probe, Pose::from_translation(Vec3::new(0.0, 2.5, 0.0)), ContactParams::default())?;
//! for i in 1..=20 {
//!     body.set_tool_pose(id, Pose::from_translation(Vec3::new(0.0, 2.5 - 0.04 * i as f32, 0.0)))?;
//!     body.step()?;
//! }
//! let tool = body.tool(id)?;
//! assert!(body.positions().iter().all(|p| p.y >= -1e-4 && tool.signed_distance((*p).into()) >= -1e-3));
//! assert!(!body.contacts().is_empty());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]

mod attachment;
mod body;
mod colour;
mod constraint;
mod contact;
mod edit;
mod error;
mod force;
mod geometry;
mod haptic;
mod partition;
mod pieces;
mod settings;
mod step;
mod tool;
mod voxel;

pub use attachment::AttachmentId;
pub use body::{BodyId, SoftBody};
pub use constraint::{
    CentroidVolumeConstraint, ConstraintKind, DistanceConstraint, Floor, NeoHookeanConstraint,
    TetVolumeConstraint,
};
pub use contact::{Contact, ContactParams, ContactSource};
pub use edit::ConstraintSlot;
pub use error::{PbdError, PbdParam};
pub use force::DYN_PER_NEWTON;
pub use haptic::{ContactForceModel, ModelContact, StiffnessEstimator};
pub use settings::{Elastic, Material, Solver, StepSettings, VolumeConstraintKind};
pub use tool::{Pose, Tool, ToolShape};
pub use voxel::{ColliderShape, OrientedBox, VoxelCollider, MAX_COLLIDER_CORNERS};
