//! Material (what the body is made of) and step settings (how it is simulated).

use glam::Vec3;

use crate::PbdError;

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
        }
    }
}

impl Material {
    pub(crate) fn validate(&self) -> Result<(), PbdError> {
        positive("density", self.density)?;
        unit("distance_stiffness", self.distance_stiffness)?;
        unit("volume_stiffness", self.volume_stiffness)?;
        non_negative("distance_compliance", self.distance_compliance)?;
        non_negative("volume_compliance", self.volume_compliance)?;
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
    /// Time step `Δt > 0` (s).
    pub dt: f32,
    /// Gauss–Seidel iterations `K ≥ 1`.
    pub iterations: u32,
    /// Stiffness model.
    pub solver: Solver,
    /// Gravity (cm/s²), applied to every free node.
    pub gravity: Vec3,
    /// Rigid-mode damping `k_damp ∈ [0, 1]` per step: `v_i += k_damp (v_cm + ω × r_i − v_i)`.
    pub damping: f32,
    /// Plain velocity damping `c ∈ [0, 1]` per step, `v ← (1 − c) v` for every node (also damps
    /// the rigid modes, so it does not conserve momentum; 0 by default).
    pub linear_damping: f32,
    /// Project the blocks of the domain decomposition on rayon's current pool (sibling subtrees
    /// at the same time). Bit-identical to the serial projection (see the crate docs).
    pub parallel: bool,
}

impl Default for StepSettings {
    /// 10 ms, `K = 10`, linearised PBD, gravity −981 cm/s² along y, rigid-mode damping 0.01, no
    /// linear damping, serial.
    fn default() -> Self {
        Self {
            dt: 0.01,
            iterations: 10,
            solver: Solver::PbdLinearised,
            gravity: Vec3::new(0.0, -981.0, 0.0),
            damping: 0.01,
            linear_damping: 0.0,
            parallel: false,
        }
    }
}

impl StepSettings {
    pub(crate) fn validate(&self) -> Result<(), PbdError> {
        positive("dt", self.dt)?;
        if self.iterations == 0 {
            return Err(PbdError::InvalidParameter {
                name: "iterations",
                value: 0.0,
                expected: "at least 1",
            });
        }
        for (name, g) in [
            ("gravity.x", self.gravity.x),
            ("gravity.y", self.gravity.y),
            ("gravity.z", self.gravity.z),
        ] {
            if !g.is_finite() {
                return Err(PbdError::InvalidParameter {
                    name,
                    value: g as f64,
                    expected: "finite",
                });
            }
        }
        unit("damping", self.damping)?;
        unit("linear_damping", self.linear_damping)?;
        Ok(())
    }

    /// The per-constraint scalar of the kernels: `k`, `k'` or `α̃`.
    pub(crate) fn param(&self, stiffness: f32, compliance: f32) -> f32 {
        match self.solver {
            Solver::Pbd => stiffness,
            Solver::PbdLinearised => {
                1.0 - ((1.0 - stiffness as f64).powf(1.0 / self.iterations as f64)) as f32
            }
            Solver::Xpbd => compliance / (self.dt * self.dt),
        }
    }
}

fn positive(name: &'static str, v: f32) -> Result<(), PbdError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(PbdError::InvalidParameter {
            name,
            value: v as f64,
            expected: "finite and > 0",
        })
    }
}

fn non_negative(name: &'static str, v: f32) -> Result<(), PbdError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(PbdError::InvalidParameter {
            name,
            value: v as f64,
            expected: "finite and ≥ 0",
        })
    }
}

fn unit(name: &'static str, v: f32) -> Result<(), PbdError> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(PbdError::InvalidParameter {
            name,
            value: v as f64,
            expected: "in [0, 1]",
        })
    }
}
