//! The force on a tool between physics steps, for a haptic loop: a local linear model
//! of the last step's contacts, evaluated at the tool's newest position.
//!
//! A haptic device is rendered at 1 kHz or more while the body steps at 60–100 Hz. Holding the
//! last step's force ([`SoftBody::tool_force`]) until the next step feels like a staircase; the
//! model below lets the force follow the tool between steps and meet the next step's force with
//! a small step instead of the whole change.
//!
//! ## The model
//! After each step, [`ContactForceModel::from_body`] keeps, for tool `t`:
//! - `p₀`, the tool's position (its pose's translation) at the end of the step, cm;
//! - `F₀`, the force of the tissue on the tool over the step ([`SoftBody::tool_force`]), N;
//! - per active contact `i` of the tool (one whose normal correction was positive in the last
//!   substep): the tool's outward normal `nᵢ` (towards the tissue) and its load
//!   `fᵢ = mᵢ cᵢ / h²` (N), `mᵢ` the node's mass, `cᵢ` its normal correction in the last substep of
//!   length `h`;
//! - an effective normal stiffness of the tissue `k` (N/cm), shared by the contacts in
//!   proportion to their loads: `kᵢ = k fᵢ / L`, `L = Σ fᵢ`.
//!
//! At a newer position `p`, with `Δp = p − p₀`:
//!
//! `gᵢ = max(0, fᵢ + kᵢ nᵢ·Δp)`,   `F(p) = −Σ gᵢ nᵢ + R · (Σ gᵢ / L)`,   `R = F₀ + Σ fᵢ nᵢ`.
//!
//! Pushing the tool on into the tissue raises each contact's load by its stiffness; pulling it
//! back lowers it until the contact lets go (no contact pulls). `R` is what the per-contact loads
//! do not explain (friction, mostly); it scales with the normal load, as Coulomb friction does,
//! and vanishes with it. At `p = p₀` the model gives exactly `F₀`. Tool rotations between steps
//! are not modelled (the tool's frame is taken as translated only), a contact that begins
//! between two steps is felt from the next step on (at most one step late), and a contact whose
//! normal is across the motion (a shaft's side while the tool is drawn out along its axis) keeps
//! its load until the next step.
//!
//! ## The stiffness
//! [`StiffnessEstimator`] measures `k` as the secant of the normal load against the tool's
//! advance along the mean contact normal `n̄ = Σ fᵢ nᵢ / |Σ fᵢ nᵢ|` over consecutive steps in
//! contact: `k_sec = (L − L_prev) / ((p₀ − p₀_prev)·n̄)` when the tool moved at least
//! [`StiffnessEstimator::MIN_ADVANCE`] along `n̄`, averaged with the previous estimate
//! (`k ← (k + k_sec)/2`, the first taken as is); a non-positive secant (the tissue relaxing
//! while the tool stands still or retreats) keeps the estimate. It starts at 0 (the model then
//! holds the step's force) and is reset when the tool loses contact.

use glam::{Vec3, Vec3A};

use crate::{ContactSource, PbdError, SoftBody, DYN_PER_NEWTON};

/// One contact of the model: the tool's outward normal there and its load.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelContact {
    /// The tool's outward unit normal at the contact (towards the tissue).
    pub normal: Vec3,
    /// The contact's load at the step, N (≥ 0).
    pub load: f32,
}

/// The force on one tool as a function of its position, from one step's contacts (module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ContactForceModel {
    /// The step it was made after ([`SoftBody::step_count`]).
    pub step: u64,
    /// The tool's position at the step, cm.
    pub origin: Vec3,
    /// The force on the tool at the step, N.
    pub force: Vec3,
    /// The active contacts.
    pub contacts: Vec<ModelContact>,
    /// The tissue's effective normal stiffness, N/cm (≥ 0).
    pub stiffness: f32,
}

impl ContactForceModel {
    /// The model of tool `tool` after the last step of `body`, with normal stiffness `stiffness`
    /// (N/cm; e.g. from a [`StiffnessEstimator`]).
    ///
    /// # Errors
    /// [`PbdError::NoSuchContactSource`].
    pub fn from_body(body: &SoftBody, tool: usize, stiffness: f32) -> Result<Self, PbdError> {
        let origin = body.tool(tool)?.pose().translation;
        let force = body.tool_force(tool)? / DYN_PER_NEWTON;
        let h = body.settings().substep_dt();
        let masses = body.masses();
        let contacts = body
            .contacts()
            .iter()
            .filter(|c| c.source == ContactSource::Tool(tool) && c.normal_correction > 0.0)
            .map(|c| ModelContact {
                normal: c.normal.into(),
                load: masses[c.node as usize] * c.normal_correction / (h * h) / DYN_PER_NEWTON,
            })
            .filter(|c| c.load.is_finite() && c.load > 0.0)
            .collect();
        Ok(Self {
            step: body.step_count(),
            origin,
            force,
            contacts,
            stiffness: if stiffness.is_finite() {
                stiffness.max(0.0)
            } else {
                0.0
            },
        })
    }

    /// `L = Σ fᵢ`, N.
    pub fn total_load(&self) -> f32 {
        self.contacts.iter().map(|c| c.load).sum()
    }

    /// The load-weighted mean normal `n̄` (unit; zero without contacts): the direction the tool
    /// presses into the tissue.
    pub fn mean_normal(&self) -> Vec3 {
        self.contacts
            .iter()
            .map(|c| c.normal * c.load)
            .sum::<Vec3>()
            .normalize_or_zero()
    }

    /// The force on the tool at `position` (cm), N: the module's formula. Without contacts,
    /// the step's force (zero in practice: a tool that touched nothing felt nothing).
    pub fn evaluate(&self, position: Vec3) -> Vec3 {
        let total = self.total_load();
        if self.contacts.is_empty() || total <= 0.0 {
            return self.force;
        }
        let dp = Vec3A::from(position - self.origin);
        let (mut normal_part, mut residual, mut loaded) =
            (Vec3A::ZERO, Vec3A::from(self.force), 0.0);
        for c in &self.contacts {
            let n = Vec3A::from(c.normal);
            let k = self.stiffness * c.load / total;
            let g = (c.load + k * n.dot(dp)).max(0.0);
            normal_part -= n * g;
            residual += n * c.load;
            loaded += g;
        }
        (normal_part + residual * (loaded / total)).into()
    }
}

/// The secant estimate of the tissue's normal stiffness under a tool, step by step (module
/// docs).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StiffnessEstimator {
    /// The estimate, N/cm.
    stiffness: f32,
    /// The last step in contact: (position along nothing yet: origin, load, mean normal).
    last: Option<(Vec3, f32, Vec3)>,
}

impl StiffnessEstimator {
    /// The least advance along the mean normal between two steps that makes a secant (cm).
    pub const MIN_ADVANCE: f32 = 1e-4;

    /// The estimate, N/cm.
    pub fn stiffness(&self) -> f32 {
        self.stiffness
    }

    /// Takes the next step's model (its origin, contacts and loads) and returns the updated
    /// estimate (N/cm).
    pub fn update(&mut self, model: &ContactForceModel) -> f32 {
        let load = model.total_load();
        let normal = model.mean_normal();
        if load <= 0.0 || normal == Vec3::ZERO {
            *self = Self::default();
            return 0.0;
        }
        if let Some((origin, last_load, last_normal)) = self.last {
            let n = (normal + last_normal).normalize_or(normal);
            let advance = (model.origin - origin).dot(n);
            if advance.abs() >= Self::MIN_ADVANCE {
                let secant = (load - last_load) / advance;
                if secant.is_finite() && secant > 0.0 {
                    self.stiffness = if self.stiffness > 0.0 {
                        0.5 * (self.stiffness + secant)
                    } else {
                        secant
                    };
                }
            }
        }
        self.last = Some((model.origin, load, normal));
        self.stiffness
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    /// A tool above the tissue: contacts' outward normals point down into it.
    fn pressed(load: f32, stiffness: f32, friction: Vec3) -> ContactForceModel {
        let n = Vec3::NEG_Y;
        ContactForceModel {
            step: 1,
            origin: Vec3::new(0.0, 1.0, 0.0),
            force: Vec3::Y * load + friction,
            contacts: vec![
                ModelContact {
                    normal: n,
                    load: 0.25 * load,
                },
                ModelContact {
                    normal: n,
                    load: 0.75 * load,
                },
            ],
            stiffness,
        }
    }

    #[test]
    fn a_flat_contact_is_a_one_sided_spring_of_the_given_stiffness() {
        // 2 N at the step, 10 N/cm: 0.05 cm deeper is 2.5 N, 0.1 cm back 1 N, 0.3 cm back 0.
        let m = pressed(2.0, 10.0, Vec3::ZERO);
        assert!(close(m.evaluate(m.origin), Vec3::Y * 2.0));
        assert!(close(m.evaluate(m.origin - Vec3::Y * 0.05), Vec3::Y * 2.5));
        assert!(close(m.evaluate(m.origin + Vec3::Y * 0.1), Vec3::Y * 1.0));
        assert!(close(m.evaluate(m.origin + Vec3::Y * 0.3), Vec3::ZERO));
        // Sliding along the surface does not change a flat contact's load.
        assert!(close(m.evaluate(m.origin + Vec3::X * 0.4), Vec3::Y * 2.0));
    }

    #[test]
    fn friction_scales_with_the_normal_load_and_goes_with_it() {
        let friction = Vec3::new(0.4, 0.0, 0.0);
        let m = pressed(2.0, 10.0, friction);
        assert!(close(m.evaluate(m.origin), Vec3::Y * 2.0 + friction));
        // 2.5 N of 2 N: the friction × 1.25.
        let deeper = m.evaluate(m.origin - Vec3::Y * 0.05);
        assert!(close(deeper, Vec3::Y * 2.5 + friction * 1.25), "{deeper}");
        assert!(close(m.evaluate(m.origin + Vec3::Y), Vec3::ZERO));
    }

    #[test]
    fn two_faces_of_a_wedge_add_their_springs() {
        // Contacts at ±45° in the x–y plane, 1 N each, 4 N/cm in all: moving the tool down by d
        // loads each by 2 · d · cos 45°, and their x parts cancel.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let m = ContactForceModel {
            step: 1,
            origin: Vec3::ZERO,
            force: Vec3::Y * 2.0 * s,
            contacts: vec![
                ModelContact {
                    normal: Vec3::new(s, -s, 0.0),
                    load: 1.0,
                },
                ModelContact {
                    normal: Vec3::new(-s, -s, 0.0),
                    load: 1.0,
                },
            ],
            stiffness: 4.0,
        };
        let d = 0.1;
        let g = 1.0 + 2.0 * d * s;
        assert!(close(m.evaluate(Vec3::NEG_Y * d), Vec3::Y * (2.0 * g * s)));
    }

    #[test]
    fn the_estimator_finds_a_linear_springs_stiffness_and_forgets_it_on_release() {
        // A 30 N/cm spring under a tool pressing down from y = 1: load = 30 · depth.
        let mut e = StiffnessEstimator::default();
        let mut k = 0.0;
        for i in 1..=10 {
            let depth = 0.02 * i as f32;
            let mut m = pressed(30.0 * depth, 0.0, Vec3::ZERO);
            m.origin = Vec3::new(0.0, 1.0 - depth, 0.0);
            k = e.update(&m);
        }
        assert!((k - 30.0).abs() < 1e-2, "{k}");
        // Standing still keeps it; losing contact resets it.
        let mut still = pressed(6.0, 0.0, Vec3::ZERO);
        still.origin = Vec3::new(0.0, 0.8, 0.0);
        assert!((e.update(&still) - 30.0).abs() < 1e-2);
        assert_eq!(e.update(&ContactForceModel::default()), 0.0);
    }
}
