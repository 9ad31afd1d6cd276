//! Position correction: after the positions are integrated, no edge may be left through a
//! triangle.
//!
//! For a crossing contact, the edge must return to the side of the triangle it came from: the side
//! where the contact's point of the edge was, relative to the contact's point of the triangle, at
//! the previous positions (the start of the step), when the caller gives them; otherwise the side
//! of its farther endpoint (the smallest move, [`Contact::depth`]). With `n` the triangle's current unit normal signed toward
//! that side, the endpoint on the wrong side (`x`, signed distance `g = n·(x − x_t)` to its
//! closest point `x_t` on the triangle, barycentric `u, v, w`) is moved across by
//! `Δ = separation − g`, with the same mass weighting as the impulse: `W = w_x + u²w_a + v²w_b +
//! w²w_c`, `λ = Δ/W`, `x += w_x·λ·n`, `x_i −= b_i·w_i·λ·n`. The mass-weighted centre of the five
//! particles stays put, fixed particles do not move, and the gap becomes `separation` (exactly, to
//! rounding, for a rigid triangle). Everything is recomputed from the current positions, so a
//! particle in several contacts is moved once, not once per contact; [`crate::Collider::separate`]
//! repeats detection and correction until nothing crosses.

use glam::Vec3A;
use tissue_bvh::closest_point_on_triangle;

use crate::bodies::contact_particles;
use crate::{Bodies, CollideError, Contact, ResponseParams, Side};

/// The particle positions at the start of the step (before integration), one array per surface
/// (the same array twice for surfaces of one particle set).
#[derive(Debug, Clone, Copy)]
pub struct Snapshot<'a> {
    /// Surface A's positions.
    pub a: &'a [Vec3A],
    /// Surface B's positions.
    pub b: &'a [Vec3A],
}

impl Snapshot<'_> {
    fn get(&self, side: Side, i: u32) -> Option<Vec3A> {
        match side {
            Side::A => self.a.get(i as usize).copied(),
            Side::B => self.b.get(i as usize).copied(),
        }
    }
}

/// What [`correct_positions`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CorrectionReport {
    /// Crossing contacts whose edge was moved.
    pub corrected: u32,
    /// Crossing contacts whose five particles are all fixed (nothing can move).
    pub unresolved: u32,
    /// The largest `Δ` applied (cm).
    pub max_correction: f32,
}

/// Moves the particles of every crossing contact back to the side they came from (see the module
/// docs), in order. `positions` holds the particles' positions; `previous` their positions at the
/// start of the step, if known.
///
/// # Errors
/// As [`crate::apply_impulses`] (particles are checked before any position changes).
pub fn correct_positions(
    contacts: &[Contact],
    positions: &mut Bodies<'_>,
    previous: Option<Snapshot<'_>>,
    params: &ResponseParams,
) -> Result<CorrectionReport, CollideError> {
    params.validate()?;
    positions.check_lengths()?;
    let _span = tracing::trace_span!("position_correction", contacts = contacts.len()).entered();
    // Check every particle first, so that an error leaves the positions untouched.
    for c in contacts.iter().filter(|c| c.is_crossing()) {
        for (side, i, _) in contact_particles(c) {
            positions.get(side, i)?;
        }
    }
    let mut report = CorrectionReport::default();
    for c in contacts.iter().filter(|c| c.is_crossing()) {
        let (es, ts) = (c.edge_side, c.edge_side.other());
        let mut ends = [Vec3A::ZERO; 2];
        let mut w_ends = [0.0; 2];
        for k in 0..2 {
            (ends[k], w_ends[k]) = positions.get(es, c.edge_particles[k])?;
        }
        let mut tri = [Vec3A::ZERO; 3];
        let mut w_tri = [0.0; 3];
        for k in 0..3 {
            (tri[k], w_tri[k]) = positions.get(ts, c.triangle_particles[k])?;
        }
        let n = unit_normal(tri).unwrap_or(Vec3A::from(c.normal));
        let d = ends.map(|x| n.dot(x - tri[0]));
        let came_from = previous
            .and_then(|prev| previous_side(c, n, prev))
            .unwrap_or_else(|| if d[0].abs() >= d[1].abs() { d[0] } else { d[1] }.signum());
        let n = n * came_from;
        // The endpoint on the wrong side (the deeper one, if both are).
        let k = if d[0] * came_from <= d[1] * came_from {
            0
        } else {
            1
        };
        let (xt, b) = closest_point_on_triangle(ends[k], tri[0], tri[1], tri[2]);
        let delta = params.separation - n.dot(ends[k] - xt);
        if delta.is_nan() || delta <= 0.0 {
            continue;
        }
        let w_eff =
            w_ends[k] + b[0] * b[0] * w_tri[0] + b[1] * b[1] * w_tri[1] + b[2] * b[2] * w_tri[2];
        if w_eff.is_nan() || w_eff <= 0.0 {
            report.unresolved += 1;
            continue;
        }
        let lambda = delta / w_eff;
        positions.add(es, c.edge_particles[k], n * (w_ends[k] * lambda));
        for i in 0..3 {
            positions.add(ts, c.triangle_particles[i], n * (-b[i] * w_tri[i] * lambda));
        }
        report.corrected += 1;
        report.max_correction = report.max_correction.max(delta);
    }
    Ok(report)
}

/// The unit normal of a triangle, if it has a plane.
fn unit_normal([a, b, c]: [Vec3A; 3]) -> Option<Vec3A> {
    let n = (b - a).cross(c - a);
    let len = n.length();
    (len > 0.0 && len.is_finite()).then(|| n / len)
}

/// `±1`: the side of the triangle the crossing point came from, or `None` if it did not move
/// relative to the triangle (or the data are missing). The contact's two material points, `s`
/// along the edge and the barycentric point of the triangle, coincide now; at the previous
/// positions their offset along `n` (the triangle's current normal) tells which side the edge's
/// point was on. Unlike the side of the whole edge relative to the triangle's infinite plane, this
/// stays right when the edge moved more than a triangle's size in the step.
fn previous_side(c: &Contact, n: Vec3A, prev: Snapshot<'_>) -> Option<f32> {
    let (es, ts) = (c.edge_side, c.edge_side.other());
    let p = prev.get(es, c.edge_particles[0])?;
    let q = prev.get(es, c.edge_particles[1])?;
    let mut xt = Vec3A::ZERO;
    for k in 0..3 {
        xt += prev.get(ts, c.triangle_particles[k])? * c.barycentric[k];
    }
    let g = n.dot(p + (q - p) * c.s - xt);
    (g != 0.0 && g.is_finite()).then(|| g.signum())
}
