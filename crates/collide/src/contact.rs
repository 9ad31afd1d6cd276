//! What detection reports: one contact per (edge of one surface, triangle of the other).

use glam::Vec3;

use crate::CollideError;

/// The two surfaces of a colliding pair. In the thesis's scenario A is the tissue region (the
/// large surface, with a hierarchy) and B the implant (small: a hierarchy or a voxel grid).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Side {
    /// The first surface of the pair.
    A,
    /// The second surface of the pair.
    B,
}

impl Side {
    /// The other side.
    pub fn other(self) -> Side {
        match self {
            Side::A => Side::B,
            Side::B => Side::A,
        }
    }
}

/// An edge of one surface touching or passing through a triangle of the other.
///
/// The contact point on the edge is `(1 − s)·x[edge_particles[0]] + s·x[edge_particles[1]]`; on the
/// triangle `Σ barycentric[i]·x[triangle_particles[i]]`. The impulse and the position correction
/// act on these five particles with these weights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// The surface the edge belongs to; the triangle belongs to the other one.
    pub edge_side: Side,
    /// Index of the edge in its surface's [`crate::Surface::edges`].
    pub edge: u32,
    /// The edge's two particles (smaller index first).
    pub edge_particles: [u32; 2],
    /// Parameter of the contact point along the edge, in `[0, 1]`.
    pub s: f32,
    /// Index of the triangle in the other surface.
    pub triangle: u32,
    /// The triangle's three particles.
    pub triangle_particles: [u32; 3],
    /// Barycentric coordinates of the contact point on the triangle (each in `[0, 1]`, sum 1).
    pub barycentric: [f32; 3],
    /// Unit vector along which the edge must move relative to the triangle to separate from it.
    pub normal: Vec3,
    /// Penetration estimate (cm). `> 0`: the edge passes through the triangle, and moving it by
    /// `depth` along `normal` takes it wholly to one side of the triangle's plane. `≤ 0`: they do
    /// not cross; `−depth` is their distance (at most the contact tolerance).
    pub depth: f32,
}

impl Contact {
    /// `true` when the edge passes through the triangle (`depth > 0`).
    pub fn is_crossing(&self) -> bool {
        self.depth > 0.0
    }

    /// The key contacts are sorted by: (edge side, edge, triangle). Unique within a detection.
    pub fn key(&self) -> (Side, u32, u32) {
        (self.edge_side, self.edge, self.triangle)
    }
}

/// What counts as a contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// An edge and a triangle closer than this (cm) are in contact even if they do not cross, so
    /// that the response can stop them before they do (contact anticipation). `≥ 0`; 0 reports only
    /// crossing and touching pairs.
    pub tolerance: f32,
    /// Set when both surfaces index one particle array (e.g. two layers of one mass–spring
    /// system): an edge and a triangle that share a particle are neighbours, never a contact.
    pub shared_particles: bool,
}

impl Default for ContactParams {
    /// Tolerance 0, separate particle arrays.
    fn default() -> Self {
        ContactParams {
            tolerance: 0.0,
            shared_particles: false,
        }
    }
}

impl ContactParams {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`CollideError::InvalidParameter`] for a negative or non-finite tolerance.
    pub fn validate(&self) -> Result<(), CollideError> {
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(CollideError::InvalidParameter {
                name: "tolerance",
                value: self.tolerance,
                expected: "finite and at least 0 (cm)",
            });
        }
        Ok(())
    }
}

/// Counts from one detection, for logs and benches.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DetectStats {
    /// Broad-phase candidates: leaf pairs (BVH vs BVH) or (cell, leaf) pairs (BVH vs voxels).
    pub candidates: u32,
    /// Triangle pairs whose boxes overlap (grown by the tolerance), each tested once.
    pub triangle_pairs: u32,
    /// Edge–triangle tests run.
    pub edge_tests: u32,
    /// Contacts found.
    pub contacts: u32,
}
