//! # tissue-fem: a finite-element static reference for hyperelastic tissue
//!
//! The equilibrium of a soft body on linear tetrahedra, solved to a stated tolerance: the
//! reference the position-based trainer (`tissue-pbd`) is compared against (issue 32, item 3).
//!
//! ## Key types
//! - [`ElasticMaterial`]: Young's modulus (kPa), Poisson's ratio, density (g/cm³), validated;
//!   [`ElasticMaterial::lame`] gives `(μ, λ)` in dyn/cm².
//! - [`StableNeoHookean`]: the energy density; [`TetElement`]: one linear tetrahedron's energy,
//!   gradient (12) and Hessian (12×12, optionally projected to positive semidefinite).
//! - [`StaticProblem`]: mesh + material + gravity + supports (clamped nodes, rollers via
//!   [`StaticProblem::fix_axes`], a rigid [`Plane`] floor, a rigid [`Plate`], a
//!   [`SphereIndenter`]), solved by [`StaticProblem::solve`] into a [`StaticSolution`]
//!   (positions, reaction forces) with its [`StaticReport`].
//!
//! ## Units
//! cm, g, s: forces in dyn (1 N = 10⁵ dyn), stresses in dyn/cm² (1 kPa = 10⁴ dyn/cm², see
//! [`KPA`]), energies in erg, gravity 981 cm/s² ([`GRAVITY`]) along `−z` by default.
//!
//! ## Energy
//! Smith, de Goes & Kim (2018), "Stable Neo-Hookean Flesh Simulation", with `I_C = tr(FᵀF)`,
//! `J = det F`:
//!
//! `Ψ(F) = μ'/2 (I_C − 3) + λ'/2 (J − α)² − μ'/2 log(I_C + 1) − Ψ₀`,
//!
//! `μ' = 4μ/3`, `λ' = λ + 5μ/6`, `α = 1 + 3μ'/(4λ') = 1 + μ/λ'`, `Ψ₀` the constant that makes
//! `Ψ(I) = 0`. `α` makes the rest state stress-free; the reparametrisation makes the
//! linearisation at rest exactly Hooke's law `σ = 2μ ε + λ tr(ε) I` with the Lamé constants of
//! `(E, ν)` (at `ν = 0`, `λ = 0` and `λ' = 5μ/6`: no special case). The energy stays finite
//! for inverted elements (`J ≤ 0`). Per element: `F = Σₐ xₐ ⊗ bₐ` with `bₐ` the rest
//! shape-function gradients, energy `V Ψ(F)`, gradient `V P bₐ` with
//! `P = μ'(1 − 1/(I_C + 1)) F + λ'(J − α) cof F`, and the Hessian `V Bᵀ (∂²Ψ/∂F²) B`, where
//! `∂²Ψ/∂F²` (9×9) is projected to positive semidefinite by clamping its negative eigenvalues
//! (Jacobi eigen-decomposition) where the assembled exact tangent is not positive definite, so
//! every Newton direction descends.
//!
//! ## Loads, supports and contact
//! - Gravity: `mᵢ g` on each node, `mᵢ = ρ Σ V/4` over its tetrahedra (lumped).
//! - Clamped (or prescribed) degrees of freedom have no unknown; their reaction is the net force
//!   the rest of the model puts on them, reported in [`StaticSolution::reactions`].
//! - A floor whose normal is a coordinate axis (`Plane::floor`, or `y` up) is a **bound** on
//!   the boundary vertices' coordinate along it: a vertex on the floor that the rest of the body
//!   pushes into it is held there (its degree of freedom taken out of the Newton system), one
//!   that the floor would have to pull is released, one that a step carries through the floor
//!   ends on it (a projected search, Bertsekas 1982). No penetration, and the floor's reaction
//!   is exactly the net force on the held vertices.
//! - A tilted floor, the plate and the sphere are rigid and frictionless and act on the
//!   boundary vertices only, through a **penalty** `½ kᵢ min(gᵢ, 0)²` on the signed gap `gᵢ`
//!   of vertex `i`, with `kᵢ = κ E ℓᵢ` (`ℓᵢ` the cube root of the vertex's lumped volume, `κ =`
//!   [`SolverSettings::contact_stiffness`], default 10³): a thousand times as stiff as the
//!   elastic cube a vertex stands for, so a vertex penetrates `fᵢ / kᵢ`, about 10⁻³ of the
//!   elastic displacement the same force causes (reported as [`StaticReport::max_penetration`]).
//!   The penalty is C¹ and piecewise quadratic, so Newton settles the contact set in a few
//!   iterations. The sphere's (negative) curvature term is left out of the tangent so it stays
//!   positive semidefinite.
//!
//! ## Solver
//! Newton on the total potential energy `Π(x) = Σ V Ψ − Σ mᵢ g·(xᵢ − Xᵢ) + Σ penalties`:
//! tangent assembled into a fixed sparse pattern (lower triangle, free degrees of freedom),
//! factored by faer's sparse Cholesky (symbolic factorisation once per solve, numeric refactor
//! per iteration, `Par::Seq`), with a diagonal shift as fallback when the factorisation fails;
//! backtracking Armijo line search on `Π`. Each iteration tries the exact (unprojected)
//! tangent first and uses it when it is positive definite: the projected one converges only
//! linearly where they differ (compressed elements), and its eigen-decompositions are most of
//! the assembly's cost (on the bunny, 0.38 s against 0.013 s); after a failure the projected
//! one is used until the residual has fallen tenfold. Stop when `‖r‖₂ ≤ tol · scale` over the free degrees
//! of freedom, `scale` the largest of the norms of gravity, contact forces and support
//! reactions (default `tol = 10⁻⁸`, [`SolverSettings::residual_tolerance`]). Loads can be
//! ramped ([`SolverSettings::load_steps`]). Nothing is allocated inside the Newton loop.
//!
//! ## Invariants
//! - `Ψ(I) = 0`, `P(I) = 0`; the small-strain stress is Hooke's (tests in `tests/energy.rs`).
//! - A converged [`StaticSolution`] balances: gravity + contact forces + reactions + elastic
//!   forces = 0 on every node to the stated tolerance, so e.g. the floor's force equals the
//!   weight when the floor alone carries the body.
//! - Validation (cantilever against Euler–Bernoulli, sphere against Hertz, scaling, balance,
//!   tolerance) is in `tests/`.
//!
//! ## Example: a block resting on the floor
//! ```
//! use glam::{DVec3, Vec3};
//! use tissue_fem::{ElasticMaterial, Plane, StaticProblem};
//!
//! // A 2 × 2 × 1 cm block of 2 × 2 × 1 cells, bottom at z = −0.5 cm, on a floor there.
//! let mesh = tissue_mesh::tet_box(2, 2, 1, Vec3::new(2.0, 2.0, 1.0))?;
//! let material = ElasticMaterial { young_kpa: 10.0, poisson: 0.3, density: 1.0 };
//! let mut problem = StaticProblem::new(&mesh, material)?;
//! problem.set_floor(Plane::floor(-0.5))?;
//! // A frictionless floor does not hold the block sideways: hold the bottom centre in x and y
//! // and a bottom node on the x axis in y (rollers, free vertically; by symmetry they carry
//! // no force).
//! let centre = problem.nodes_where(|p| p.z < -0.49 && p.x.abs() < 1e-6 && p.y.abs() < 1e-6);
//! let on_x = problem.nodes_where(|p| p.z < -0.49 && p.x > 0.99 && p.y.abs() < 1e-6);
//! problem.fix_axes(centre[0], [true, true, false])?;
//! problem.fix_axes(on_x[0], [false, true, false])?;
//! let solution = problem.solve()?;
//! assert!(solution.report.converged);
//! // The floor carries the weight, 4 cm³ · 1 g/cm³ · 981 cm/s².
//! let weight = 4.0 * 981.0;
//! assert!((solution.floor_force.z - weight).abs() < 1e-3 * weight);
//! assert!(solution.max_displacement().1.z < 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]

mod energy;
mod material;
mod solver;

pub use energy::{project_psd, StableNeoHookean, TetElement};
pub use material::{ElasticMaterial, FemError, KPA, MAX_POISSON};
pub use solver::{
    Plane, Plate, SolverSettings, SphereIndenter, StaticProblem, StaticReport, StaticSolution,
    GRAVITY,
};
