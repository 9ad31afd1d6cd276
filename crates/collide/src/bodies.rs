//! The particle state the response changes: flat per-particle arrays, as the mass–spring crate
//! stores them (structure of arrays, inverse mass 0 = fixed particle).

use glam::Vec3A;

use crate::{CollideError, Side};

/// One particle array and its inverse masses: velocities for [`crate::apply_impulses`], positions
/// for [`crate::correct_positions`].
#[derive(Debug)]
pub struct Particles<'a> {
    /// Velocity (cm/s) or position (cm) of each particle.
    pub state: &'a mut [Vec3A],
    /// `1/m` of each particle (1/g); 0 for a fixed particle, which no contact moves.
    pub inv_masses: &'a [f32],
}

/// Where the particles of the two surfaces live.
#[derive(Debug)]
pub enum Bodies<'a> {
    /// Surfaces A and B index two separate arrays (the thesis's region and implant).
    Two {
        /// Surface A's particles.
        a: Particles<'a>,
        /// Surface B's particles.
        b: Particles<'a>,
    },
    /// Both surfaces index one array (two layers of one mass–spring system; detect with
    /// [`crate::ContactParams::shared_particles`]).
    One(Particles<'a>),
}

impl<'a> Bodies<'a> {
    /// Two separate particle arrays.
    pub fn two(
        state_a: &'a mut [Vec3A],
        inv_masses_a: &'a [f32],
        state_b: &'a mut [Vec3A],
        inv_masses_b: &'a [f32],
    ) -> Bodies<'a> {
        Bodies::Two {
            a: Particles {
                state: state_a,
                inv_masses: inv_masses_a,
            },
            b: Particles {
                state: state_b,
                inv_masses: inv_masses_b,
            },
        }
    }

    /// One particle array for both surfaces.
    pub fn one(state: &'a mut [Vec3A], inv_masses: &'a [f32]) -> Bodies<'a> {
        Bodies::One(Particles { state, inv_masses })
    }

    /// The state array of `side` (the shared one for [`Bodies::One`]).
    pub fn state(&self, side: Side) -> &[Vec3A] {
        match (self, side) {
            (Bodies::Two { a, .. }, Side::A) => a.state,
            (Bodies::Two { b, .. }, Side::B) => b.state,
            (Bodies::One(p), _) => p.state,
        }
    }

    fn particles(&self, side: Side) -> &Particles<'a> {
        match (self, side) {
            (Bodies::Two { a, .. }, Side::A) => a,
            (Bodies::Two { b, .. }, Side::B) => b,
            (Bodies::One(p), _) => p,
        }
    }

    /// Checks that each state array has one inverse mass per particle.
    pub(crate) fn check_lengths(&self) -> Result<(), CollideError> {
        for side in [Side::A, Side::B] {
            let p = self.particles(side);
            if p.inv_masses.len() != p.state.len() {
                return Err(CollideError::ParticleCount {
                    side,
                    what: "inverse masses",
                    expected: p.state.len(),
                    got: p.inv_masses.len(),
                });
            }
        }
        Ok(())
    }

    /// State and inverse mass of particle `i` of `side`, checked.
    #[inline]
    pub(crate) fn get(&self, side: Side, i: u32) -> Result<(Vec3A, f32), CollideError> {
        let p = self.particles(side);
        let (Some(&x), Some(&w)) = (p.state.get(i as usize), p.inv_masses.get(i as usize)) else {
            return Err(CollideError::ParticleOutOfRange {
                side,
                particle: i,
                count: p.state.len().min(p.inv_masses.len()),
            });
        };
        if !(w.is_finite() && w >= 0.0) {
            return Err(CollideError::InvalidInverseMass {
                side,
                particle: i,
                value: w,
            });
        }
        Ok((x, w))
    }

    /// How many distinct particles the sides hold together (one array counts once).
    #[inline]
    pub(crate) fn particle_count(&self) -> usize {
        match self {
            Bodies::Two { a, b } => a.state.len() + b.state.len(),
            Bodies::One(p) => p.state.len(),
        }
    }

    /// A dense index of particle `i` of `side` below [`Bodies::particle_count`], the same for
    /// both sides of [`Bodies::One`].
    #[inline]
    pub(crate) fn key(&self, side: Side, i: u32) -> usize {
        match (self, side) {
            (Bodies::Two { a, .. }, Side::B) => a.state.len() + i as usize,
            _ => i as usize,
        }
    }

    /// Sets particle `i` of `side` (checked by a preceding [`Bodies::get`]).
    #[inline]
    pub(crate) fn set(&mut self, side: Side, i: u32, value: Vec3A) {
        let p = match (self, side) {
            (Bodies::Two { a, .. }, Side::A) => a,
            (Bodies::Two { b, .. }, Side::B) => b,
            (Bodies::One(p), _) => p,
        };
        if let Some(x) = p.state.get_mut(i as usize) {
            *x = value;
        }
    }

    /// Adds `delta` to particle `i` of `side` (checked by a preceding [`Bodies::get`]).
    #[inline]
    pub(crate) fn add(&mut self, side: Side, i: u32, delta: Vec3A) {
        let p = match (self, side) {
            (Bodies::Two { a, .. }, Side::A) => a,
            (Bodies::Two { b, .. }, Side::B) => b,
            (Bodies::One(p), _) => p,
        };
        if let Some(x) = p.state.get_mut(i as usize) {
            *x += delta;
        }
    }
}

/// The five particles of a contact with their sides and weights: edge `(1 − s, s)`, triangle
/// `(−u, −v, −w)`. The weighted sum of their velocities is the relative velocity of the contact
/// points (edge minus triangle).
#[inline]
pub(crate) fn contact_particles(c: &crate::Contact) -> [(Side, u32, f32); 5] {
    let (e, t) = (c.edge_side, c.edge_side.other());
    let [u, v, w] = c.barycentric;
    [
        (e, c.edge_particles[0], 1.0 - c.s),
        (e, c.edge_particles[1], c.s),
        (t, c.triangle_particles[0], -u),
        (t, c.triangle_particles[1], -v),
        (t, c.triangle_particles[2], -w),
    ]
}
