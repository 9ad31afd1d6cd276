//! Particles as flat arrays: position, velocity, force, mass and inverse mass.

use glam::{DVec3, Vec3, Vec3A};

use crate::MssError;

/// The particles of a mass–spring system, one array per attribute (structure of arrays).
///
/// Invariants: every array has [`Particles::len`] entries; masses are positive and finite;
/// `inverse_mass[i]` is `1 / mass[i]`, or `0` for a fixed particle (which forces do not move).
#[derive(Debug, Clone, PartialEq)]
pub struct Particles {
    pub(crate) position: Vec<Vec3A>,
    pub(crate) velocity: Vec<Vec3A>,
    pub(crate) force: Vec<Vec3A>,
    pub(crate) mass: Vec<f32>,
    pub(crate) inverse_mass: Vec<f32>,
}

impl Particles {
    /// Particles at rest at `positions` with the given masses (g). All start free.
    pub fn new(positions: &[Vec3], masses: &[f32]) -> Result<Self, MssError> {
        if masses.len() != positions.len() {
            return Err(MssError::LengthMismatch {
                what: "masses",
                got: masses.len(),
                expected: positions.len(),
            });
        }
        if positions.len() >= u32::MAX as usize {
            return Err(MssError::InvalidParameter {
                name: "particle count",
                value: positions.len() as f64,
                expected: "fewer than 2^32 - 1",
            });
        }
        for (i, (p, &m)) in positions.iter().zip(masses).enumerate() {
            if !p.is_finite() {
                return Err(MssError::InvalidParticle {
                    particle: i as u32,
                    what: format!("position {p} is not finite"),
                });
            }
            if !(m.is_finite() && m > 0.0) {
                return Err(MssError::InvalidParticle {
                    particle: i as u32,
                    what: format!("mass {m} must be positive and finite"),
                });
            }
        }
        Ok(Particles {
            position: positions.iter().map(|&p| Vec3A::from(p)).collect(),
            velocity: vec![Vec3A::ZERO; positions.len()],
            force: vec![Vec3A::ZERO; positions.len()],
            mass: masses.to_vec(),
            inverse_mass: masses.iter().map(|m| 1.0 / m).collect(),
        })
    }

    /// Fixes particle `i`: forces no longer move it (its inverse mass becomes 0) and its velocity
    /// is set to zero. Its mass still counts for the centre of mass.
    pub fn fix(&mut self, i: u32) -> Result<(), MssError> {
        let n = self.len();
        let (Some(w), Some(v)) = (
            self.inverse_mass.get_mut(i as usize),
            self.velocity.get_mut(i as usize),
        ) else {
            return Err(MssError::InvalidParticle {
                particle: i,
                what: format!("cannot fix it: the system has {n} particles"),
            });
        };
        *w = 0.0;
        *v = Vec3A::ZERO;
        Ok(())
    }

    /// Releases particle `i`: forces move it again (its inverse mass is `1/mass` again). Its
    /// velocity is kept.
    pub fn release(&mut self, i: u32) -> Result<(), MssError> {
        let n = self.len();
        let (Some(w), Some(&m)) = (
            self.inverse_mass.get_mut(i as usize),
            self.mass.get(i as usize),
        ) else {
            return Err(MssError::InvalidParticle {
                particle: i,
                what: format!("cannot release it: the system has {n} particles"),
            });
        };
        *w = 1.0 / m;
        Ok(())
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// `true` when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Whether particle `i` is fixed.
    ///
    /// # Panics
    /// If `i` is out of range.
    pub fn is_fixed(&self, i: u32) -> bool {
        self.inverse_mass[i as usize] == 0.0
    }

    /// Positions (cm).
    pub fn positions(&self) -> &[Vec3A] {
        &self.position
    }

    /// Positions, to move particles between steps (e.g. the thesis's initial lift). Non-finite
    /// values put here are caught by the next step as [`MssError::Diverged`].
    pub fn positions_mut(&mut self) -> &mut [Vec3A] {
        &mut self.position
    }

    /// Velocities (cm/s).
    pub fn velocities(&self) -> &[Vec3A] {
        &self.velocity
    }

    /// Velocities, e.g. for collision impulses between the velocity and position updates.
    pub fn velocities_mut(&mut self) -> &mut [Vec3A] {
        &mut self.velocity
    }

    /// Positions (mutable), velocities (mutable) and inverse masses at once, for code such as
    /// collision response that moves particles while reading which are fixed.
    pub fn state_mut(&mut self) -> (&mut [Vec3A], &mut [Vec3A], &[f32]) {
        (&mut self.position, &mut self.velocity, &self.inverse_mass)
    }

    /// Positions and the forces of the current evaluation (mutable), for forces a caller adds
    /// between [`crate::MassSpringSystem::compute_forces`] and the velocity update.
    pub fn positions_and_forces_mut(&mut self) -> (&[Vec3A], &mut [Vec3A]) {
        (&self.position, &mut self.force)
    }

    /// Forces of the last force evaluation (g·cm/s²).
    pub fn forces(&self) -> &[Vec3A] {
        &self.force
    }

    /// Masses (g).
    pub fn masses(&self) -> &[f32] {
        &self.mass
    }

    /// Inverse masses (1/g); 0 for fixed particles.
    pub fn inverse_masses(&self) -> &[f32] {
        &self.inverse_mass
    }

    /// Total linear momentum `Σ mᵢ vᵢ` of the free particles, in `f64`.
    pub fn momentum(&self) -> DVec3 {
        self.velocity
            .iter()
            .zip(&self.mass)
            .zip(&self.inverse_mass)
            .filter(|(_, &w)| w > 0.0)
            .map(|((v, &m), _)| Vec3::from(*v).as_dvec3() * f64::from(m))
            .sum()
    }

    /// Kinetic energy `½ Σ mᵢ |vᵢ|²` of the free particles, in `f64`.
    pub fn kinetic_energy(&self) -> f64 {
        self.velocity
            .iter()
            .zip(&self.mass)
            .zip(&self.inverse_mass)
            .filter(|(_, &w)| w > 0.0)
            .map(|((v, &m), _)| 0.5 * f64::from(m) * Vec3::from(*v).as_dvec3().length_squared())
            .sum()
    }
}
