//! Material (what the body is made of) and step settings (how it is simulated).

use glam::Vec3;

use crate::{PbdError, PbdParam};

/// Which volume constraint the body carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VolumeConstraintKind {
    /// Distance constraints only.
    None,
    /// One classic constraint per tet, `C = (1/6)(p₂−p₁)×(p₃−p₁)·(p₄−p₁) − V₀`.
    Classic,
    /// The slides' constraint, 4 per tet: `C = |s − c| − h₀` (see [`crate::CentroidVolumeConstraint`]).
    Centroid,
}

/// A hyperelastic material: stable neo-Hookean (Smith et al. 2018) solved as the constraint
/// pair of Macklin & Müller 2021 ([`crate::NeoHookeanConstraint`]), given by its small-strain
/// constants. Units: kPa (1 kPa = 10⁴ dyn/cm²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elastic {
    /// Young's modulus `E > 0` (kPa). Soft organs are of the order of 1–100 kPa.
    pub young_kpa: f32,
    /// Poisson's ratio `ν ∈ [0, 0.495]`: 0 has no lateral coupling, near 0.5 is nearly
    /// incompressible (tissue: 0.45–0.49). 0.5 itself is refused (`λ` would be infinite).
    pub poisson: f32,
}

impl Elastic {
    /// The largest Poisson's ratio accepted.
    pub const MAX_POISSON: f32 = 0.495;

    /// The Lamé parameters `(μ, λ_Lamé)` in dyn/cm²: `μ = E/(2(1+ν))`,
    /// `λ_Lamé = Eν/((1+ν)(1−2ν))`, `E` in dyn/cm² (`10⁴ × young_kpa`).
    pub fn lame(&self) -> (f64, f64) {
        let e = self.young_kpa as f64 * 1e4;
        let nu = self.poisson as f64;
        (
            e / (2.0 * (1.0 + nu)),
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        )
    }

    /// The stable neo-Hookean energy's parameters `(μ, λ)` in dyn/cm² (`Ψ = μ/2 (I_C − 3) +
    /// λ/2 (J − γ)²`, `γ = 1 + μ/λ`): `λ = λ_Lamé + μ`, which makes its small-strain limit
    /// linear elasticity with [`Elastic::lame`] (Smith et al. 2018, §3.4: linearised at
    /// `F = I`, its stress is `μ(H + Hᵀ) + (λ − μ) tr H · I`). So `ν = 0` is allowed (`λ = μ`).
    pub fn energy_parameters(&self) -> (f64, f64) {
        let (mu, lambda) = self.lame();
        (mu, lambda + mu)
    }

    /// Checks `E` and `ν`.
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] naming the parameter: `young_kpa` not finite and > 0,
    /// `poisson` outside `[0, 0.495]`.
    pub fn validate(&self) -> Result<(), PbdError> {
        if !(self.young_kpa.is_finite() && self.young_kpa > 0.0) {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::YoungModulus,
                value: self.young_kpa as f64,
                expected: "finite and > 0 (kPa; soft tissue is about 1 to 100 kPa): give Young's modulus in kPa",
            });
        }
        if !(0.0..=Self::MAX_POISSON).contains(&self.poisson) {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::PoissonRatio,
                value: self.poisson as f64,
                expected: "in [0, 0.495] (nearly incompressible tissue: 0.45 to 0.49; 0.5 would make λ infinite)",
            });
        }
        Ok(())
    }
}

/// What the body is made of. Units: cm, g, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Density (g/cm³); each node gets a quarter of each of its tets' mass.
    pub density: f32,
    /// PBD stiffness `k ∈ [0, 1]` of the distance constraints.
    pub distance_stiffness: f32,
    /// PBD stiffness `k ∈ [0, 1]` of the volume constraints.
    pub volume_stiffness: f32,
    /// XPBD compliance `α ≥ 0` of the distance constraints (cm/dyn).
    pub distance_compliance: f32,
    /// XPBD compliance `α ≥ 0` of the volume constraints (per `C` unit: cm⁶/erg for
    /// [`VolumeConstraintKind::Classic`], cm/dyn for [`VolumeConstraintKind::Centroid`]).
    pub volume_compliance: f32,
    /// The volume constraint.
    pub volume: VolumeConstraintKind,
    /// Hold each connected piece's total volume with one more constraint per piece (scaled by
    /// `volume_stiffness`), projected after the body's constraints in every iteration: an
    /// incompressible organ (see the crate docs, "Piece volumes").
    pub hold_piece_volumes: bool,
    /// A hyperelastic material: with `Some`, each tet carries a stable neo-Hookean constraint
    /// pair ([`crate::NeoHookeanConstraint`]) instead of the distance and volume constraints,
    /// which are then not projected (the distance records are still built and kept up to date
    /// by cutting, for the edges' bookkeeping; `volume`, the stiffnesses and compliances are
    /// ignored; sutures' links are projected as ever). Needs [`Solver::Xpbd`]
    /// ([`StepSettings::material`]). `None` (the default) keeps the PBD constraints.
    pub elastic: Option<Elastic>,
}

impl Default for Material {
    /// Water density, `k = 1` everywhere, compliance 0 (rigid), the slides' volume constraint.
    fn default() -> Self {
        Self {
            density: 1.0,
            distance_stiffness: 1.0,
            volume_stiffness: 1.0,
            distance_compliance: 0.0,
            volume_compliance: 0.0,
            volume: VolumeConstraintKind::Centroid,
            hold_piece_volumes: false,
            elastic: None,
        }
    }
}

impl Material {
    /// The organ of the real-time preset ([`StepSettings::realtime`]): water density, classic
    /// tet-volume constraints (one per tet, exactly `V − V₀`), one volume constraint per
    /// connected piece (tissue is incompressible: one Gauss–Seidel sweep per substep leaves the
    /// organ's total volume to drift by a few per cent as it settles; the piece's constraint
    /// holds it), `k = 1` and zero compliance everywhere.
    pub fn soft_tissue() -> Self {
        Self {
            density: 1.0,
            distance_stiffness: 1.0,
            volume_stiffness: 1.0,
            distance_compliance: 0.0,
            volume_compliance: 0.0,
            volume: VolumeConstraintKind::Classic,
            hold_piece_volumes: true,
            elastic: None,
        }
    }

    /// The organ of the material scheme ([`StepSettings::material`], `trainer --scheme
    /// material`): density `density` (g/cm³), stable neo-Hookean with Young's modulus
    /// `young_kpa` (kPa) and Poisson's ratio `poisson`, no per-piece volume constraint (the
    /// material's own `λ` holds the volume).
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] for a bad `E`, `ν` or density.
    pub fn elastic(young_kpa: f32, poisson: f32, density: f32) -> Result<Self, PbdError> {
        let m = Self {
            density,
            volume: VolumeConstraintKind::None,
            hold_piece_volumes: false,
            elastic: Some(Elastic { young_kpa, poisson }),
            ..Self::default()
        };
        m.validate()?;
        Ok(m)
    }

    /// The trainer's default organ for the material scheme: 10 kPa, `ν = 0.45`, 1.05 g/cm³
    /// (soft parenchyma; see docs/trainer.md).
    pub fn soft_organ() -> Self {
        Self {
            density: Self::ORGAN_DENSITY,
            volume: VolumeConstraintKind::None,
            hold_piece_volumes: false,
            elastic: Some(Elastic {
                young_kpa: Self::ORGAN_YOUNG_KPA,
                poisson: Self::ORGAN_POISSON,
            }),
            ..Self::default()
        }
    }

    /// [`Material::soft_organ`]'s Young's modulus (kPa).
    pub const ORGAN_YOUNG_KPA: f32 = 10.0;
    /// [`Material::soft_organ`]'s Poisson's ratio.
    pub const ORGAN_POISSON: f32 = 0.45;
    /// [`Material::soft_organ`]'s density (g/cm³).
    pub const ORGAN_DENSITY: f32 = 1.05;

    pub(crate) fn validate(&self) -> Result<(), PbdError> {
        positive(PbdParam::Density, self.density)?;
        unit(PbdParam::DistanceStiffness, self.distance_stiffness)?;
        unit(PbdParam::VolumeStiffness, self.volume_stiffness)?;
        non_negative(PbdParam::DistanceCompliance, self.distance_compliance)?;
        non_negative(PbdParam::VolumeCompliance, self.volume_compliance)?;
        if let Some(e) = &self.elastic {
            e.validate()?;
        }
        Ok(())
    }
}

/// How stiffness enters the projection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solver {
    /// PBD, each projection scaled by the constraint's `k` as given (the result depends on `K`).
    Pbd,
    /// PBD with `k' = 1 − (1 − k)^{1/K}`, so that after `K` iterations the error of an isolated
    /// constraint falls by `(1 − k)` whatever `K`.
    PbdLinearised,
    /// XPBD: compliance `α` per constraint, `α̃ = α/Δt²`, multipliers reset every step. The
    /// stiffness is physical (independent of `K` and `Δt` once the iterations converge).
    Xpbd,
}

/// How one step is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSettings {
    /// Time step `Δt > 0` (s): the time one [`crate::SoftBody::step`] advances.
    pub dt: f32,
    /// Substeps `n ≥ 1` per step: a step is `n` whole PBD steps of `Δt/n` (prediction, contacts,
    /// `K` iterations, velocity update; Macklin et al. 2019, "Small steps in physics
    /// simulation"), with the tools moved along their path a fraction `1/n` per substep.
    pub substeps: u32,
    /// Gauss–Seidel iterations `K ≥ 1` per substep.
    pub iterations: u32,
    /// Stiffness model.
    pub solver: Solver,
    /// Gravity (cm/s²), applied to every free node.
    pub gravity: Vec3,
    /// Rigid-mode damping `k_damp ∈ [0, 1]` per step: `v_i += k_damp (v_cm + ω × r_i − v_i)`
    /// (after the last substep).
    pub damping: f32,
    /// Plain velocity damping `c ∈ [0, 1]` per step, `v ← (1 − c) v` for every node (also damps
    /// the rigid modes, so it does not conserve momentum; 0 by default; with substeps,
    /// `1 − (1 − c)^{1/n}` per substep, the same per step).
    pub linear_damping: f32,
    /// Project the blocks of the domain decomposition on rayon's current pool (sibling subtrees
    /// at the same time). Bit-identical to the serial projection (see the crate docs).
    pub parallel: bool,
    /// Over-relaxation `β ∈ [0, 1]` of an elastic material's pair solve (XPBD). Each tet's
    /// 2 × 2 system `(A + α̃) Δλ = −C − α̃λ` (`A = ∇C M⁻¹ ∇Cᵀ`) is solved with `A` scaled by
    /// `(K + (1 − β) α̃)/(K + α̃)`, `K` and `α̃` those of the tet's stiffer constraint (the
    /// larger `r = K/α̃`; one factor for both, so that the stress-free rest state stays still).
    /// What the iterations converge to (`C + α̃λ = 0`) does not depend on `β`. With one
    /// iteration per substep (λ starting at 0 in every substep) a settled body is softer than
    /// its material by about `r = (hω)²` (`h` the substep, `ω` the mesh's highest
    /// frequencies); the scaling takes `β·r` of that back to first order, so fewer substeps reach
    /// the material. It over-relaxes the Gauss–Seidel update by at most `4/(4 − β)` (at
    /// `r = 1`), and not at all for stiff or sliver tets (`r ≫ 1`), so it stays stable where a
    /// constant over-relaxation factor diverges (one of 1.7 did, on the cut appendix).
    /// Ignored by the other materials.
    pub over_relaxation: f32,
}

impl Default for StepSettings {
    /// 10 ms, one substep, `K = 10`, linearised PBD, gravity −981 cm/s² along y, rigid-mode
    /// damping 0.01, no linear damping, serial. The scheme the solver's tests were written for;
    /// for a real-time organ use [`StepSettings::realtime`].
    fn default() -> Self {
        Self {
            dt: 0.01,
            substeps: 1,
            iterations: 10,
            solver: Solver::PbdLinearised,
            gravity: Vec3::new(0.0, -981.0, 0.0),
            damping: 0.01,
            linear_damping: 0.0,
            parallel: false,
            over_relaxation: 0.0,
        }
    }
}

impl StepSettings {
    /// The trainer's former scheme (`trainer --scheme legacy`): one step of 10 ms per frame,
    /// `K = 10` iterations, linearised PBD, rigid-mode damping 0.05. Kept as a baseline to
    /// compare [`StepSettings::realtime`] against (docs/tuning-log.md).
    pub fn legacy() -> Self {
        Self {
            damping: 0.05,
            ..Self::default()
        }
    }

    /// The real-time preset ("physics defaults that hold"), for the trainer and the
    /// studio at 60 steps/s and below: a 10 ms step as [`StepSettings::REALTIME_SUBSTEPS`]
    /// substeps of one iteration each (small steps, Macklin et al. 2019), linearised PBD (with
    /// [`Material::soft_tissue`]'s `k = 1` the same projection as XPBD with zero compliance, at
    /// a cheaper kernel), rigid-mode damping 0.05 per step. Many small steps hold an organ's
    /// volume under a tool far better than a few iterations of one large step, at about the same
    /// cost per step.
    pub fn realtime() -> Self {
        Self {
            dt: 0.01,
            substeps: Self::REALTIME_SUBSTEPS,
            iterations: 1,
            solver: Solver::PbdLinearised,
            damping: 0.05,
            ..Self::default()
        }
    }

    /// Substeps of [`StepSettings::realtime`].
    pub const REALTIME_SUBSTEPS: u32 = 9;

    /// The material scheme (`trainer --scheme material`, with [`Material::elastic`] or
    /// [`Material::soft_organ`]): a 10 ms step as [`StepSettings::MATERIAL_SUBSTEPS`] XPBD
    /// substeps of one iteration each (small steps, Macklin et al. 2019), the pairs'
    /// [`StepSettings::over_relaxation`] `β = 0.5` (a clamped 4 × 1 × 1 cm beam's tip then
    /// deflects 2.7 % more than the finite-element reference's and moves 2.3 % from 32 to 64
    /// substeps, against 5.3 % and 3.5 % with `β = 0`; a column's compression is 0.991 × and
    /// 0.996 × the analytic one at 32 and 64 substeps; `β = 1` over-corrects the column to
    /// 0.945 ×), and damping with the relaxation time
    /// [`StepSettings::MATERIAL_RELAXATION_TIME`] (see [`StepSettings::with_relaxation_time`]).
    pub fn material() -> Self {
        Self {
            dt: 0.01,
            substeps: Self::MATERIAL_SUBSTEPS,
            iterations: 1,
            solver: Solver::Xpbd,
            over_relaxation: 0.5,
            ..Self::default()
        }
        .with_relaxation_time(Self::MATERIAL_RELAXATION_TIME)
    }

    /// Substeps of [`StepSettings::material`] per 10 ms step: doubling them changes a settled
    /// column's compression by less than 3 % (docs/trainer.md, `tests/it/elastic.rs`).
    pub const MATERIAL_SUBSTEPS: u32 = 32;

    /// The relaxation time `τ` of [`StepSettings::material`] (s).
    pub const MATERIAL_RELAXATION_TIME: f32 = 0.1;

    /// Sets the damping from a relaxation time `τ` (s): the rigid-mode damping per step becomes
    /// `k_damp = 1 − exp(−Δt/τ)`, so that every motion relative to the body's rigid motion
    /// (translation and rotation kept) decays as `exp(−t/τ)` whatever `Δt`: a mass-proportional
    /// (Rayleigh `α_M = 1/τ`) damping force `−ρ (v − v_rigid)/τ` per volume, which conserves
    /// linear and angular momentum. `τ = ∞` (or ≤ 0, not finite) means no damping.
    pub fn with_relaxation_time(self, tau: f32) -> Self {
        let damping = if tau.is_finite() && tau > 0.0 {
            (1.0 - (-(self.dt as f64) / tau as f64).exp()) as f32
        } else {
            0.0
        };
        Self { damping, ..self }
    }

    /// The relaxation time `τ = −Δt / ln(1 − k_damp)` (s) of this rigid-mode damping
    /// (infinite without damping).
    pub fn relaxation_time(&self) -> f32 {
        if self.damping <= 0.0 {
            f32::INFINITY
        } else if self.damping >= 1.0 {
            0.0
        } else {
            (-(self.dt as f64) / (1.0 - self.damping as f64).ln()) as f32
        }
    }

    /// The time one substep advances, `Δt/n` (s).
    pub fn substep_dt(&self) -> f32 {
        self.dt / self.substeps as f32
    }

    pub(crate) fn validate(&self) -> Result<(), PbdError> {
        positive(PbdParam::Dt, self.dt)?;
        if self.substeps == 0 {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::Substeps,
                value: 0.0,
                expected: "at least 1",
            });
        }
        if self.iterations == 0 {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::Iterations,
                value: 0.0,
                expected: "at least 1",
            });
        }
        for (param, g) in [
            (PbdParam::GravityX, self.gravity.x),
            (PbdParam::GravityY, self.gravity.y),
            (PbdParam::GravityZ, self.gravity.z),
        ] {
            if !g.is_finite() {
                return Err(PbdError::InvalidParameter {
                    param,
                    value: g as f64,
                    expected: "finite",
                });
            }
        }
        unit(PbdParam::Damping, self.damping)?;
        unit(PbdParam::LinearDamping, self.linear_damping)?;
        unit(PbdParam::OverRelaxation, self.over_relaxation)?;
        Ok(())
    }

    /// The per-constraint scalar of the kernels: `k`, `k'` (over the `n·K` iterations of a
    /// step) or `α̃ = α/(Δt/n)²`.
    pub(crate) fn param(&self, stiffness: f32, compliance: f32) -> f32 {
        match self.solver {
            Solver::Pbd => stiffness,
            Solver::PbdLinearised => {
                let k = self.iterations as f64 * self.substeps as f64;
                1.0 - ((1.0 - stiffness as f64).powf(1.0 / k)) as f32
            }
            Solver::Xpbd => {
                let h = self.substep_dt();
                compliance / (h * h)
            }
        }
    }

    /// `1 − (1 − c)^{1/n}`: a per-step damping `c` spread over the substeps.
    pub(crate) fn per_substep(&self, c: f32) -> f32 {
        if self.substeps == 1 {
            c
        } else {
            1.0 - ((1.0 - c as f64).powf(1.0 / self.substeps as f64)) as f32
        }
    }
}

fn positive(param: PbdParam, v: f32) -> Result<(), PbdError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(PbdError::InvalidParameter {
            param,
            value: v as f64,
            expected: "finite and > 0",
        })
    }
}

fn non_negative(param: PbdParam, v: f32) -> Result<(), PbdError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(PbdError::InvalidParameter {
            param,
            value: v as f64,
            expected: "finite and ≥ 0",
        })
    }
}

fn unit(param: PbdParam, v: f32) -> Result<(), PbdError> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(PbdError::InvalidParameter {
            param,
            value: v as f64,
            expected: "in [0, 1]",
        })
    }
}
