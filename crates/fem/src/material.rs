//! The linear-elastic constants of a tissue and the errors of this crate.

use thiserror::Error;

/// One kilopascal in dyn/cm² (the unit of stress in cm–g–s).
pub const KPA: f64 = 1.0e4;

/// The largest Poisson ratio accepted: beyond it the bulk modulus grows without bound and linear
/// tetrahedra lock (a nearly incompressible tissue needs a mixed formulation this crate does not
/// have).
pub const MAX_POISSON: f64 = 0.495;

/// What went wrong, and what to do about it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FemError {
    /// A material constant is out of range.
    #[error("material: {what}; {fix}")]
    Material {
        /// The offending constant and its value.
        what: String,
        /// How to fix it.
        fix: &'static str,
    },
    /// A parameter of the problem (a node index, a position, a tolerance, …) is unusable.
    #[error("problem: {what}; {fix}")]
    Problem {
        /// The offending parameter and its value.
        what: String,
        /// How to fix it.
        fix: &'static str,
    },
    /// A rest tetrahedron is flat or inverted (its rest shape matrix has no inverse).
    #[error(
        "tetrahedron {tet} is degenerate at rest (6·volume = {six_volume:e}); rebuild the mesh"
    )]
    DegenerateTet {
        /// The tetrahedron's index.
        tet: usize,
        /// Six times its signed rest volume (cm³).
        six_volume: f64,
    },
    /// The tangent stiffness has no Cholesky factor even after the diagonal shifts.
    #[error(
        "the stiffness matrix could not be factored ({what}); the body is probably free to move \
         rigidly: clamp or hold (fix_axes) enough nodes"
    )]
    Factorisation {
        /// faer's message.
        what: String,
    },
}

/// An isotropic linear-elastic material at small strain, the constants the stable neo-Hookean
/// energy is fitted to.
///
/// Invariants after [`ElasticMaterial::validate`] (which [`crate::StaticProblem::new`] calls):
/// `young_kpa` finite and > 0, `0 ≤ poisson ≤` [`MAX_POISSON`], `density` finite and > 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticMaterial {
    /// Young's modulus E, kPa (1 kPa = 1e4 dyn/cm²).
    pub young_kpa: f64,
    /// Poisson's ratio ν, dimensionless.
    pub poisson: f64,
    /// Density ρ, g/cm³.
    pub density: f64,
}

impl ElasticMaterial {
    /// Checks the constants (see the type's invariants).
    ///
    /// # Errors
    /// [`FemError::Material`] naming the constant, its value and the accepted range.
    pub fn validate(&self) -> Result<(), FemError> {
        if !(self.young_kpa.is_finite() && self.young_kpa > 0.0) {
            return Err(FemError::Material {
                what: format!("Young's modulus young_kpa = {} kPa", self.young_kpa),
                fix: "give a finite positive value in kPa (soft tissue: about 1 to 100 kPa)",
            });
        }
        if !(self.poisson.is_finite() && (0.0..=MAX_POISSON).contains(&self.poisson)) {
            return Err(FemError::Material {
                what: format!("Poisson's ratio poisson = {}", self.poisson),
                fix: "give a value in [0, 0.495]; nearly incompressible tissue (0.5) would lock \
                      linear tetrahedra, use 0.45–0.49 instead",
            });
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return Err(FemError::Material {
                what: format!("density = {} g/cm³", self.density),
                fix: "give a finite positive value in g/cm³ (soft tissue: about 1.0 to 1.1)",
            });
        }
        Ok(())
    }

    /// Young's modulus in dyn/cm².
    pub fn young(&self) -> f64 {
        self.young_kpa * KPA
    }

    /// The Lamé constants `(μ, λ)` in dyn/cm²: `μ = E / (2(1 + ν))`,
    /// `λ = E ν / ((1 + ν)(1 − 2ν))` (`λ = 0` at `ν = 0`).
    pub fn lame(&self) -> (f64, f64) {
        let e = self.young();
        let nu = self.poisson;
        (
            e / (2.0 * (1.0 + nu)),
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        )
    }
}
