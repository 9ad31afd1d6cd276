//! # tissue-mss: the mass–spring system of the implant-insertion thesis
//!
//! ## Brief overview
//! - [`Particles`]: flat arrays of position, velocity, force, mass and inverse mass (inverse
//!   mass 0 = fixed).
//! - [`Spring`]: a 16-byte record `{a, b: u32, rest, k}`; [`springs_from_triangles`] makes one per
//!   mesh edge with Van Gelder stiffness; [`Anchor`] is a zero-length spring to a fixed point.
//! - [`MassSpringSystem`]: springs, anchors, gravity, an external field, damping, volume
//!   preservation ([`VolumePreservation`]) and an [`Integrator`]; [`MassSpringSystem::step`] in
//!   the thesis's phase order, [`MassSpringSystem::step_adaptive`] with an [`AdaptiveStep`], and
//!   [`MassSpringSystem::run`] until the [`StopCriterion`] fires.
//! - [`statics`]: a constant stiffness matrix (the springs' Laplacian, anchors, couplings)
//!   assembled by [`StiffnessBuilder`] and factored once by sparse Cholesky (faer) into a
//!   [`Preconditioner`] (`P⁻¹` of three right-hand sides, `P·v`, refactoring with another
//!   diagonal): the global step of a local/global solve and the preconditioner of a Newton–CG
//!   one, for quasi-static solves.
//!
//! It knows nothing of implants, hierarchies or threads (beyond rayon inside a step with the
//! `parallel` feature).
//!
//! ## Units
//! Centimetres, grams, seconds: positions in cm, masses in g, velocities in cm/s, forces in
//! g·cm/s² (dyn), stiffness in g/s² (dyn/cm; 1 N/m = 1000 g/s²), Young's modulus in g/(cm·s²)
//! (= 0.1 Pa).
//!
//! ## Equations (SPEC A.2 numbering)
//! - (1) `mᵢ = M Σ_{t∋i} v_t / (4V)` over tetrahedra ([`masses_from_tets`]; the thesis prints 3V,
//!   which would not sum to M), (2) `mᵢ = M Σ_{t∋i} a_t / (3A)` over triangles
//!   ([`masses_from_triangles`]); `M` = density × volume, or area × thickness × density.
//! - (3) Van Gelder: `k_c = E₂/(1+ν)·2A/c² + E₂ν/(1−ν²)·(a²+b²−c²)/(4A)`, `E₂ = E·t`, summed
//!   over the triangles of an edge ([`van_gelder`]).
//! - (4) Hooke: `fᵢ = k(|x_ij| − l)·x_ij/|x_ij|`, `x_ij = x_j − x_i` ([`spring_force`]; finite
//!   for zero-length springs).
//! - (5) Vassilev–Spanlang volume preservation: `fᵢ = −cᵢ k_v (Δl_tot + C Δlᵢ) uᵢ`
//!   ([`VolumePreservation`]).
//! - (6), (7) explicit Euler `v ← v + f/m·h`, `x ← x + v_old·h`; damping multiplies velocities by
//!   a factor in (0, 1] after the velocity update.
//!
//! ## Determinism
//! With the `parallel` feature, forces and the integration run over fixed particle blocks whose
//! layout depends only on the particle count; forces of block-crossing springs are added
//! serially. Results are bit-identical for any number of threads and with the feature off.
//!
//! ## Example: a mass hanging from a fixed point settles at `mg/k` below the spring's rest length
//! ```
//! use glam::Vec3;
//! use tissue_mss::{MassSpringSystem, Particles, Spring, StopCriterion, StopReason};
//!
//! let mut particles = Particles::new(&[Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0)], &[1.0, 2.0])?;
//! particles.fix(0)?;
//! let k = 4000.0; // g/s²
//! let mut system = MassSpringSystem::new(particles, vec![Spring::new(0, 1, 1.0, k)])?;
//! system.set_gravity(Vec3::new(0.0, 0.0, -981.0))?;
//! system.set_damping(0.99)?;
//! let criterion = StopCriterion { window: 20, tolerance: 1e-3, max_steps: 100_000, floor: 0.0 };
//! let report = system.run(1e-3, &criterion)?;
//! assert_eq!(report.reason, StopReason::Settled);
//! let z = system.particles().positions()[1].z;
//! assert!((z - (-1.0 - 2.0 * 981.0 / k)).abs() < 1e-4);
//! # Ok::<(), tissue_mss::MssError>(())
//! ```
#![forbid(unsafe_code)]

mod adaptive;
mod error;
mod layout;
mod mass;
mod particles;
mod pressure;
#[doc(hidden)]
pub mod scenes;
mod spring;
pub mod statics;
mod stop;
mod system;
mod volume;

pub use adaptive::AdaptiveStep;
pub use error::MssError;
pub use mass::{masses_from_tets, masses_from_triangles, sheet_mass, WATER_DENSITY};
pub use particles::Particles;
pub use pressure::VolumePressure;
pub use spring::{
    spring_force, springs_from_triangles, springs_from_triangles_floored, van_gelder, Anchor,
    SheetMaterial, Spring,
};
pub use statics::{Preconditioner, StiffnessBuilder};
pub use stop::{RunReport, SettleDetector, StopCriterion, StopReason};
pub use system::{Integrator, MassSpringSystem, StepReport};
pub use volume::VolumePreservation;
