//! Impulse response (SPEC A.4, eqs. 8–10, after Mirtich & Canny), generalised to contact points
//! inside an edge and a triangle.
//!
//! The thesis's two-body impulse `j = −(1+e)(v₂−v₁)·n / (1/m₁ + 1/m₂)`, `v₁ ← v₁ + j·n/m₁`,
//! `v₂ ← v₂ − j·n/m₂` becomes, for the contact point `(1−s)·x_p + s·x_q` of the edge and
//! `u·x_a + v·x_b + w·x_c` of the triangle, with weights `c = (1−s, s, −u, −v, −w)` and inverse
//! masses `w_k`:
//!
//! - relative velocity `v_rel = Σ c_k v_k` (edge point minus triangle point), normal part
//!   `v_n = v_rel·n`; only an approaching contact (`v_n < 0`) gets an impulse;
//! - effective inverse mass `W = Σ c_k² w_k` (eq. 8's `1/m₁ + 1/m₂` when `s` and the barycentric
//!   coordinates pick single particles), `j = −(1+e)·v_n / W`;
//! - `Δv_k = c_k·w_k·j·n` (eqs. 9–10), so `v_n` becomes `−e·v_n` and `Σ m_k Δv_k = j·n·Σ c_k = 0`:
//!   momentum is conserved; a fixed particle (`w_k = 0`) takes nothing;
//! - Coulomb friction: the tangential relative velocity `v_t` is reduced by an impulse
//!   `j_t = min(μ·j, |v_t|/W)` along `−v_t/|v_t|`, distributed the same way.
//!
//! [`impulse`] is that kernel for one contact; [`apply_impulses`] solves all the contacts of a
//! step together (projected Gauss–Seidel on the accumulated impulses), which for an isolated
//! contact is the same impulse.

use glam::Vec3A;

use crate::bodies::contact_particles;
use crate::{Bodies, CollideError, Contact, Side};

/// The velocity changes of one contact's five particles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impulse {
    /// `Δv` of the edge's two particles, then the triangle's three (cm/s).
    pub dv: [Vec3A; 5],
    /// The normal impulse `j` (g·cm/s).
    pub normal: f32,
    /// The friction impulse `j_t` (g·cm/s).
    pub friction: f32,
}

/// The impulse of one contact (see the module docs): `velocities`, `inv_masses` and `weights` of
/// the five particles (edge `(1−s, s)`, triangle `(−u, −v, −w)`), unit `normal` (the direction the
/// edge must move relative to the triangle), restitution `e ∈ [0, 1]`, friction coefficient `μ ≥ 0`.
/// `None` when the contact is not approaching or no particle can move.
pub fn impulse(
    velocities: [Vec3A; 5],
    inv_masses: [f32; 5],
    weights: [f32; 5],
    normal: Vec3A,
    restitution: f32,
    friction: f32,
) -> Option<Impulse> {
    let mut v_rel = Vec3A::ZERO;
    let mut w_eff = 0.0f32;
    for k in 0..5 {
        v_rel += velocities[k] * weights[k];
        w_eff += weights[k] * weights[k] * inv_masses[k];
    }
    let vn = v_rel.dot(normal);
    if !(vn < 0.0 && w_eff > 0.0) {
        return None;
    }
    let j = -(1.0 + restitution) * vn / w_eff;
    let mut dir = normal * j;
    let vt = v_rel - normal * vn;
    let vt_len = vt.length();
    let mut jt = 0.0;
    if friction > 0.0 && vt_len > 0.0 {
        jt = (friction * j).min(vt_len / w_eff);
        dir -= vt * (jt / vt_len);
    }
    let dv = [0, 1, 2, 3, 4].map(|k| dir * (weights[k] * inv_masses[k]));
    Some(Impulse {
        dv,
        normal: j,
        friction: jt,
    })
}

/// Parameters of the response.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResponseParams {
    /// Coefficient of restitution `e ∈ [0, 1]`: 0 stops the approach, 1 reverses it.
    pub restitution: f32,
    /// Coulomb friction coefficient `μ ≥ 0`.
    pub friction: f32,
    /// Passes of [`apply_impulses`] over the contacts (≥ 1): with particles in several contacts,
    /// each pass brings every contact closer to its target.
    pub sweeps: u32,
    /// The gap (cm, ≥ 0) [`crate::correct_positions`] leaves between a corrected edge and the
    /// triangle's plane; a little above 0 so the next detection sees a near contact, not a
    /// crossing.
    pub separation: f32,
    /// Rounds of detect-then-correct in [`crate::Collider::separate`] (≥ 1).
    pub max_iterations: u32,
    /// Warm start, in `[0, 1]`: each contact that was also among the previous call's contacts
    /// (same [`Contact::key`]) starts from this fraction of the impulses it ended with there,
    /// applied before the sweeps (Catto's accumulated impulses). A contact resting under a
    /// steady load then starts near its answer, so the sweeps converge and it does not jitter.
    /// 0 starts every contact from zero.
    pub warm_start: f32,
}

impl Default for ResponseParams {
    /// Inelastic (`e = 0`), frictionless, 8 sweeps, separation 10⁻⁴ cm, 32 correction rounds,
    /// no warm start.
    fn default() -> Self {
        ResponseParams {
            restitution: 0.0,
            friction: 0.0,
            sweeps: 8,
            separation: 1e-4,
            max_iterations: 32,
            warm_start: 0.0,
        }
    }
}

impl ResponseParams {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`CollideError::InvalidParameter`] naming the first parameter out of range.
    pub fn validate(&self) -> Result<(), CollideError> {
        let bad = |name, value, expected| {
            Err(CollideError::InvalidParameter {
                name,
                value,
                expected,
            })
        };
        if !(0.0..=1.0).contains(&self.restitution) {
            return bad("restitution", self.restitution, "in [0, 1]");
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return bad("friction", self.friction, "finite and at least 0");
        }
        if self.sweeps == 0 {
            return bad("sweeps", 0.0, "at least 1");
        }
        if !(self.separation.is_finite() && self.separation >= 0.0) {
            return bad("separation", self.separation, "finite and at least 0 (cm)");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", 0.0, "at least 1");
        }
        if !(0.0..=1.0).contains(&self.warm_start) {
            return bad("warm_start", self.warm_start, "in [0, 1]");
        }
        Ok(())
    }
}

/// What [`apply_impulses`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ImpulseReport {
    /// Contacts left with a positive normal impulse.
    pub active: u32,
    /// Sum of the normal impulses (g·cm/s).
    pub normal_impulse: f32,
}

/// Per-contact scratch of [`apply_impulses`] (accumulated impulses and targets) and the compact
/// copy of the velocities the contacts touch, kept by the caller so that a step allocates nothing
/// once it has grown to the largest contact count.
#[derive(Debug, Clone, Default)]
pub struct ImpulseWorkspace {
    normal: Vec<f32>,
    friction: Vec<Vec3A>,
    target: Vec<f32>,
    prepared: Vec<Prepared>,
    /// Per particle ([`Bodies::key`]): its slot in `velocity`, or `u32::MAX`. All `u32::MAX`
    /// between calls.
    slot: Vec<u32>,
    /// The velocities of the particles the contacts touch, in first-touched order, and whose
    /// they are.
    velocity: Vec<Vec3A>,
    owner: Vec<(Side, u32)>,
    /// The last call's contacts (sorted by key) and the impulses they ended with.
    previous: Vec<((Side, u32, u32), f32, Vec3A)>,
}

/// A contact as the sweeps read it: its particles' slots in the compact velocities, their weights
/// in the relative velocity, the velocity change per unit impulse of each (`weight/m`),
/// `W = Σ weight²/m` and the normal. Only the first `count` entries are used: the particles
/// that can move and have a weight; the fixed ones' part of the relative velocity, constant
/// during the sweeps, is `fixed_part` (a kinematic body's contacts touch two or three
/// particles, not five).
#[derive(Debug, Clone, Copy)]
struct Prepared {
    slot: [u32; 5],
    weight: [f32; 5],
    push: [f32; 5],
    count: u32,
    fixed_part: Vec3A,
    w_eff: f32,
    /// `1/W`, or 0 for a contact no particle of which can move (skipped).
    inv_w_eff: f32,
    normal: Vec3A,
}

impl ImpulseWorkspace {
    /// An empty workspace.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Applies the contacts' impulses to `velocities` (the particles' velocities).
///
/// Every contact that approaches at the start (`v_n⁰ < 0`) must end with `v_n = −e·v_n⁰`; every
/// other contact must not start approaching (`v_n ≥ 0`). With many contacts sharing particles,
/// single impulses applied one after another overshoot (each one, distributed with barycentric
/// weights, also moves the other contacts of its particles), and particles would leave with
/// energy they never had. So the contacts are solved together by projected Gauss–Seidel over
/// `params.sweeps` passes in the detection order: each contact keeps its accumulated normal
/// impulse `λ ≥ 0` and friction impulse `|λ_t| ≤ μ·λ`, and each pass applies the change
/// `Δλ = (target − v_n)/W` (clamped so the accumulated impulse stays admissible) with
/// [`impulse`]'s weights. A contact alone gets exactly [`impulse`] in the first pass and nothing
/// after; momentum is conserved by every change.
///
/// # Errors
/// [`CollideError::ParticleCount`] when an inverse-mass array does not match its velocities,
/// [`CollideError::ParticleOutOfRange`] / [`CollideError::InvalidInverseMass`] naming a
/// contact's particle (checked before any velocity changes), [`CollideError::InvalidParameter`].
pub fn apply_impulses(
    contacts: &[Contact],
    velocities: &mut Bodies<'_>,
    params: &ResponseParams,
    ws: &mut ImpulseWorkspace,
) -> Result<ImpulseReport, CollideError> {
    params.validate()?;
    velocities.check_lengths()?;
    let _span = tracing::trace_span!("impulses", contacts = contacts.len()).entered();
    let n = contacts.len();
    ws.normal.clear();
    ws.normal.resize(n, 0.0);
    ws.friction.clear();
    ws.friction.resize(n, Vec3A::ZERO);
    if let Err(e) = prepare(contacts, velocities, params, ws) {
        release_slots(velocities, ws);
        return Err(e);
    }
    if params.warm_start > 0.0 {
        warm_start(contacts, params, ws);
    }
    // The sweeps run on the compact velocities (a few thousand, cache-resident): the same
    // arithmetic in the same order as on the bodies' arrays.
    let v = &mut ws.velocity;
    for _ in 0..params.sweeps {
        for (k, p) in ws.prepared.iter().enumerate() {
            let inv_w = p.inv_w_eff;
            if inv_w == 0.0 {
                continue;
            }
            let m = p.count as usize;
            let mut v_rel = p.fixed_part;
            for i in 0..m {
                v_rel += v[p.slot[i] as usize] * p.weight[i];
            }
            let n = p.normal;
            let vn = v_rel.dot(n);
            let lambda = (ws.normal[k] + (ws.target[k] - vn) * inv_w).max(0.0);
            let d_lambda = lambda - ws.normal[k];
            ws.normal[k] = lambda;
            let mut j = n * d_lambda;
            if params.friction > 0.0 {
                // The normal impulse does not change the tangential relative velocity.
                let vt = v_rel - n * vn;
                let mut ft = ws.friction[k] - vt * inv_w;
                let limit = params.friction * lambda;
                let len = ft.length();
                if len > limit {
                    ft *= limit / len;
                }
                j += ft - ws.friction[k];
                ws.friction[k] = ft;
            }
            if j != Vec3A::ZERO {
                for i in 0..m {
                    v[p.slot[i] as usize] += j * p.push[i];
                }
            }
        }
    }
    for (&(side, i), &vel) in ws.owner.iter().zip(&ws.velocity) {
        velocities.set(side, i, vel);
    }
    release_slots(velocities, ws);
    ws.previous.clear();
    if params.warm_start > 0.0 {
        ws.previous.extend(
            contacts
                .iter()
                .zip(ws.normal.iter().zip(&ws.friction))
                .map(|(c, (&l, &f))| (c.key(), l, f)),
        );
    }
    Ok(ImpulseReport {
        active: ws.normal.iter().filter(|&&l| l > 0.0).count() as u32,
        normal_impulse: ws.normal.iter().sum(),
    })
}

/// Checks every contact's particles, computes the targets from the velocities before any
/// impulse, and gathers the touched velocities into the workspace's compact copy.
fn prepare(
    contacts: &[Contact],
    velocities: &Bodies<'_>,
    params: &ResponseParams,
    ws: &mut ImpulseWorkspace,
) -> Result<(), CollideError> {
    ws.target.clear();
    ws.prepared.clear();
    ws.velocity.clear();
    ws.owner.clear();
    let count = velocities.particle_count();
    if ws.slot.len() != count {
        ws.slot.clear();
        ws.slot.resize(count, u32::MAX);
    }
    for c in contacts {
        let (v, w, weights) = gather(c, velocities)?;
        let normal = Vec3A::from(c.normal);
        let vn = relative(&v, &weights).dot(normal);
        ws.target.push(if vn < 0.0 {
            -params.restitution * vn
        } else {
            0.0
        });
        let parts = contact_particles(c);
        let w_eff: f32 = (0..5).map(|i| weights[i] * weights[i] * w[i]).sum();
        let mut prepared = Prepared {
            slot: [0; 5],
            weight: [0.0; 5],
            push: [0.0; 5],
            count: 0,
            fixed_part: Vec3A::ZERO,
            w_eff,
            inv_w_eff: if w_eff > 0.0 && w_eff.is_finite() {
                1.0 / w_eff
            } else {
                0.0
            },
            normal,
        };
        for (k, &(side, i, weight)) in parts.iter().enumerate() {
            if weight == 0.0 {
                continue;
            }
            if w[k] == 0.0 {
                prepared.fixed_part += v[k] * weight;
                continue;
            }
            let key = velocities.key(side, i);
            if ws.slot[key] == u32::MAX {
                ws.slot[key] = ws.velocity.len() as u32;
                ws.velocity.push(v[k]);
                ws.owner.push((side, i));
            }
            let m = prepared.count as usize;
            prepared.slot[m] = ws.slot[key];
            prepared.weight[m] = weight;
            prepared.push[m] = weight * w[k];
            prepared.count += 1;
        }
        ws.prepared.push(prepared);
    }
    Ok(())
}

/// Starts each contact that the previous call also had from `warm_start` × the impulses it ended
/// with (both lists are sorted by key), applied to the compact velocities. The friction impulse
/// keeps its direction and stays within the cone; momentum is conserved as by any impulse.
fn warm_start(contacts: &[Contact], params: &ResponseParams, ws: &mut ImpulseWorkspace) {
    let mut prev = ws.previous.iter().peekable();
    for (k, c) in contacts.iter().enumerate() {
        let key = c.key();
        while prev.next_if(|p| p.0 < key).is_some() {}
        let Some(&&(_, lambda, friction)) = prev.peek() else {
            break;
        };
        if lambda.is_nan() || friction.is_nan() {
            continue;
        }
        let p = &ws.prepared[k];
        if prev.peek().map(|p| p.0) != Some(key) || p.w_eff.is_nan() || p.w_eff <= 0.0 {
            continue;
        }
        let lambda = params.warm_start * lambda;
        // Only the part of the old friction impulse that is tangential to the new normal, within
        // the cone.
        let mut ft = friction - p.normal * friction.dot(p.normal);
        ft *= params.warm_start;
        let limit = params.friction * lambda;
        let len = ft.length();
        if len > limit {
            ft *= if len > 0.0 { limit / len } else { 0.0 };
        }
        ws.normal[k] = lambda;
        ws.friction[k] = ft;
        let j = p.normal * lambda + ft;
        if j != Vec3A::ZERO {
            for i in 0..p.count as usize {
                ws.velocity[p.slot[i] as usize] += j * p.push[i];
            }
        }
    }
}

/// Marks every slot free again (the workspace's invariant between calls).
fn release_slots(velocities: &Bodies<'_>, ws: &mut ImpulseWorkspace) {
    for &(side, i) in &ws.owner {
        ws.slot[velocities.key(side, i)] = u32::MAX;
    }
}

/// Velocities, inverse masses and weights of a contact's five particles.
type Gathered = ([Vec3A; 5], [f32; 5], [f32; 5]);

/// [`Gathered`] for contact `c`, checked.
#[inline]
fn gather(c: &Contact, bodies: &Bodies<'_>) -> Result<Gathered, CollideError> {
    let parts = contact_particles(c);
    let mut v = [Vec3A::ZERO; 5];
    let mut w = [0.0; 5];
    let mut weights = [0.0; 5];
    for (k, &(side, i, weight)) in parts.iter().enumerate() {
        (v[k], w[k]) = bodies.get(side, i)?;
        weights[k] = weight;
    }
    Ok((v, w, weights))
}

#[inline]
fn relative(v: &[Vec3A; 5], weights: &[f32; 5]) -> Vec3A {
    (0..5).map(|k| v[k] * weights[k]).sum()
}
