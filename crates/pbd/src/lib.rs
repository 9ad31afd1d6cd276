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
//! - Or a physical material, [`Material::elastic`] ([`Elastic`]: Young's modulus in kPa,
//!   Poisson's ratio, with the density): one stable neo-Hookean constraint pair per tet
//!   ([`NeoHookeanConstraint`], see "Elastic material" below) in place of the distance and
//!   volume constraints, with the preset [`StepSettings::material`].
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
//! compliance in `[C]²/erg` (cm/dyn for distances, 1/erg for the dimensionless neo-Hookean
//! constraints), force in dyn (g·cm/s²), stress and moduli in dyn/cm² (1 kPa = 10⁴ dyn/cm²;
//! [`Elastic::young_kpa`] is in kPa).
//!
//! ## Elastic material (issue 32)
//! With [`Material::elastic`] = `Some(Elastic { young_kpa: E, poisson: ν })` (validated:
//! `E > 0` finite, `0 ≤ ν ≤ 0.495`) and the density `ρ`, every tet carries the stable
//! neo-Hookean energy (Smith et al. 2018) as the constraint pair of Macklin & Müller 2021
//! ([`NeoHookeanConstraint`]):
//! - Lamé parameters `μ = E/(2(1+ν))`, `λ_L = Eν/((1+ν)(1−2ν))` (dyn/cm²), and the energy's
//!   `λ = λ_L + μ` (the energy below linearises to `μ(H+Hᵀ) + (λ − μ) tr H · I` at `F = I + H`,
//!   so this makes small strains linear elasticity with `E`, `ν`; it also makes `ν = 0` usable);
//! - `Ψ(F) = μ/2 (I_C − 3) + λ/2 (J − γ)²`, `γ = 1 + μ/λ`, `F = D_s D_m⁻¹` (`D_s`, `D_m` the
//!   edge matrices `[x₁−x₀, x₂−x₀, x₃−x₀]` now and at rest), `I_C = tr FᵀF`, `J = det F`;
//! - hydrostatic `C_H = det F − γ`, `α_H = 1/(λ V₀)`; deviatoric `C_D = √I_C`,
//!   `α_D = 1/(μ V₀)`: the XPBD energy `C_H²/(2α_H) + C_D²/(2α_D)` is `V₀ Ψ` plus a constant.
//!   `√I_C` (not `√(I_C − 3)`) keeps the gradient finite at rest;
//! - gradients `∂C/∂x_i = (∂C/∂F) D_m⁻ᵀ` column `i−1`, `∂C/∂x₀ = −Σ`, with
//!   `∂C_H/∂F = cof F` and `∂C_D/∂F = F/C_D`;
//! - solved per tet as **one coupled 2×2 XPBD system** (Macklin & Müller §4):
//!   `Σ_j (∇C_i M⁻¹ ∇C_jᵀ + α̃_i δ_ij) Δλ_j = −C_i − α̃_i λ_i` with `α̃ = α/h²` for substeps of
//!   `h`, multipliers accumulated over the iterations of a substep and reset every substep,
//!   `Δx_k = w_k Σ_i ∇_k C_i Δλ_i`. At rest `∇C_D = ∇C_H/√3` and the coupled solution moves
//!   nothing, although `C_H = −μ/λ` and `C_D = √3` there: the rest state is stress-free and
//!   stays still (projected one after the other, the two would pull it apart each substep);
//! - always XPBD: an elastic body refuses another [`Solver`]. Its distance constraints are
//!   still built and kept by edits (cutting uses the edges) but not projected; links (sutures),
//!   the floor, contacts and the per-piece constraint (off in [`Material::elastic`]) are as
//!   ever. The pairs are laid out, coloured, batched and edited exactly as the tets' volume
//!   constraints (the tet batches, `tet_lanes`, dynamic sets), two multipliers per tet.
//! - Convergence: one Gauss–Seidel sweep per substep leaves a body softer than the material by
//!   about `(h ω)²` (`ω ~ c/ℓ`, the wave speed over the tet size); [`StepSettings::material`]'s
//!   32 substeps of 10 ms/32 bring a settled column to 3.7 % of `ρ g L²/(2E)` and change by
//!   2.7 % when doubled (`tests/it/elastic.rs`; docs/trainer.md has the bunny).
//! - Damping ([`StepSettings::with_relaxation_time`]): the rigid-mode damping expressed as a
//!   relaxation time `τ`, `k_damp = 1 − exp(−Δt/τ)`: every motion relative to the body's rigid
//!   motion decays as `exp(−t/τ)` (a mass-proportional damping force `−ρ(v − v_rigid)/τ` per
//!   volume, momentum conserved); `τ` = 0.1 s in the preset.
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
mod intersect;
mod partition;
mod pieces;
mod selfcol;
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
pub use intersect::{
    count_intersecting_pairs, intersecting_pairs, intersecting_pairs_brute_force,
    triangles_intersect,
};
pub use selfcol::SelfCollision;
pub use settings::{Elastic, Material, Solver, StepSettings, VolumeConstraintKind};
pub use tool::{Pose, Tool, ToolShape};
pub use voxel::{ColliderShape, OrientedBox, VoxelCollider, MAX_COLLIDER_CORNERS};
