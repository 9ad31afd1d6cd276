//! Reaction forces on what touches or holds the body (the tool force), for a haptic loop:
//! read after each step, in the library's units (dyn = g·cm/s²; [`DYN_PER_NEWTON`]).
//!
//! - Tools and colliders ([`SoftBody::tool_force`], [`SoftBody::collider_force`]) and the
//!   floor ([`SoftBody::floor_force`]) from their own position corrections: a correction `Δx` of
//!   a node of mass `m` in a (sub)step of length `h` is an impulse `m Δx / h` on the node, so the
//!   force on the source averaged over the step of length `T = Σ h` is
//!   `F = −(1/T) Σ_substeps (1/h) Σ m Δx` (`−Σ m Δx / h²` for a single step), normal and
//!   friction corrections alike (see `contact.rs`).
//! - Pins and attachments ([`SoftBody::holding_force`]) act through the body's own constraints
//!   (the held node has inverse mass 0, so no correction of its own); the force on them follows
//!   from the momentum balance of all the nodes over the step:
//!   `F_hold = M g + (J_contacts + J_floor)/T − (P_end − P_start)/T`, `M` the total mass (the
//!   held nodes' weight included: the grasper carries it), `J` the impulses the contacts and the
//!   floor gave the tissue, `P = Σ m v`.

use glam::{DVec3, Vec3};

use crate::{PbdError, SoftBody};

/// Dynes per newton: the library's forces are in dyn (g·cm/s²); divide by this for newtons.
pub const DYN_PER_NEWTON: f32 = 1e5;

impl SoftBody {
    /// The force the tissue exerted on tool `id` over the last step (dyn, world axes), averaged
    /// over the step: `F = −(1/T) Σ_substeps (1/h) Σ m Δx` over the position corrections `Δx`
    /// its contacts made to nodes of mass `m` (normal and friction parts; module docs of
    /// `force.rs`). It points away from the tissue the tool presses; zero when the tool touched
    /// nothing. Independent of the number of iterations (and substeps) per step; allocation-free.
    /// Divide by [`DYN_PER_NEWTON`] for newtons.
    ///
    /// # Errors
    /// [`PbdError::NoSuchContactSource`].
    pub fn tool_force(&self, id: usize) -> Result<Vec3, PbdError> {
        self.tool(id)?;
        Ok(self
            .collision
            .source_force(self.collision.collider_count() + id))
    }

    /// The force the tissue exerted on collider `id` over the last step (dyn), as
    /// [`SoftBody::tool_force`]. A body resting on a tray presses it with its weight.
    ///
    /// # Errors
    /// [`PbdError::NoSuchContactSource`].
    pub fn collider_force(&self, id: usize) -> Result<Vec3, PbdError> {
        let count = self.collision.collider_count();
        if id >= count {
            return Err(PbdError::NoSuchContactSource {
                what: "collider",
                id,
                count,
            });
        }
        Ok(self.collision.source_force(id))
    }

    /// The force the tissue exerted on the static [`crate::Floor`] over the last step (dyn),
    /// from its corrections as [`SoftBody::tool_force`]; zero without a floor.
    pub fn floor_force(&self) -> Vec3 {
        let (t, j) = (
            self.collision.accounted_time(),
            self.collision.floor_impulse(),
        );
        match self.floor {
            Some(f) if t > 0.0 => {
                let mut v = Vec3::ZERO;
                v[f.axis] = (-j / t) as f32;
                v
            }
            _ => Vec3::ZERO,
        }
    }

    /// The force the tissue exerted over the last step on everything that holds its nodes: the
    /// attachments ([`SoftBody::attach`], e.g. a grasper's jaws, one attachment per grasped
    /// node) and the pins together (dyn). By the momentum balance of all the nodes over the step
    /// of length `T`: `F = M g + (J_contacts + J_floor)/T − (P_end − P_start)/T` (`M` the total
    /// mass, the held nodes' own weight included; `J` the impulses the colliders, tools and floor
    /// gave the tissue, as in [`SoftBody::tool_force`]; `P = Σ m v`). A block hanging at rest from
    /// a grasper pulls it down with its weight.
    ///
    /// Computed only while the body has attachments (zero otherwise, so a body held by pins
    /// alone pays nothing): two passes over the nodes per step. Pins are not separated from
    /// attachments, nor attachments from each other: a held node acts on the tissue only
    /// through the body's constraints (its inverse mass is 0), whose multipliers the solver does
    /// not keep. Plain velocity damping (`linear_damping > 0`) shows up in it as a drag.
    pub fn holding_force(&self) -> Vec3 {
        self.collision.holding
    }

    /// `Σ m v` over all nodes (f64) when the body has attachments (start of a step).
    pub(crate) fn holding_momentum(&self) -> Option<DVec3> {
        if self.attachments.is_empty() {
            return None;
        }
        Some(
            self.mass
                .iter()
                .zip(&self.v)
                .map(|(&m, v)| m as f64 * v.as_dvec3())
                .sum(),
        )
    }

    /// End of a step: the holders' reaction from the momentum `start` had before the step.
    pub(crate) fn finish_holding(&mut self, start: Option<DVec3>) {
        let Some(start) = start else {
            self.collision.holding = Vec3::ZERO;
            return;
        };
        let (mut mass, mut end) = (0.0f64, DVec3::ZERO);
        for (&m, v) in self.mass.iter().zip(&self.v) {
            mass += m as f64;
            end += m as f64 * v.as_dvec3();
        }
        let t = match self.collision.accounted_time() {
            t if t > 0.0 => t,
            _ => self.settings.dt as f64,
        };
        let mut given = self.collision.total_impulse();
        if let Some(f) = self.floor {
            given[f.axis] += self.collision.floor_impulse();
        }
        let force = mass * self.settings.gravity.as_dvec3() + (given - (end - start)) / t;
        self.collision.holding = force.as_vec3();
    }
}
