//! Constraint records (public, one `Vec` per kind) and their projection kernels (pure functions
//! on local copies of the node positions).
//!
//! Projection of one constraint `C` (Müller et al.): `Δp_i = −s·w_i·∇_i C`,
//! `s = k·C / Σ_j w_j |∇_j C|²`. XPBD (Macklin et al.) replaces the stiffness by a compliance:
//! `Δλ = (−C − α̃λ) / (Σ_j w_j |∇_j C|² + α̃)`, `Δp_i = w_i ∇_i C Δλ`, `α̃ = α/Δt²`; with `α̃ = 0`
//! it is the PBD projection with `k = 1`. Both conserve linear and angular momentum (the
//! gradients of a translation- and rotation-invariant `C` sum to zero and have zero torque).

use glam::Vec3A;

/// Whether a constraint holds as `C = 0` or as `C ≥ 0` (projected only when `C < 0`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintKind {
    /// `C(p) = 0`.
    Equality,
    /// `C(p) ≥ 0`, projected only when violated.
    Inequality,
}

/// Distance constraint on a tet edge: `C = |p₁ − p₂| − d`, cardinality 2, equality.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DistanceConstraint {
    /// The two nodes.
    pub nodes: [u32; 2],
    /// Rest length `d` (cm).
    pub rest_length: f32,
    /// PBD stiffness `k ∈ [0, 1]`.
    pub stiffness: f32,
    /// XPBD compliance `α ≥ 0` (inverse stiffness, cm/dyn = s²/g).
    pub compliance: f32,
}

/// The classic tet-volume constraint: `C = (1/6)(p₂−p₁)×(p₃−p₁)·(p₄−p₁) − V₀`, cardinality 4,
/// equality.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetVolumeConstraint {
    /// The tet's nodes, positively oriented.
    pub nodes: [u32; 4],
    /// Rest volume `V₀` (cm³).
    pub rest_volume: f32,
    /// PBD stiffness `k ∈ [0, 1]`.
    pub stiffness: f32,
    /// XPBD compliance `α ≥ 0` (cm⁶ per erg).
    pub compliance: f32,
}

/// The slides' volume constraint, one per tetrahedron and vertex (4 per tet):
/// `C = |s − c| − h₀`, `c` the centroid of the opposite face, `h₀` its rest distance to the apex
/// `s`. Cardinality 4, equality.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CentroidVolumeConstraint {
    /// The face opposite the apex.
    pub face: [u32; 3],
    /// The apex `s`.
    pub apex: u32,
    /// Rest distance `h₀` from apex to face centroid (cm).
    pub rest_height: f32,
    /// PBD stiffness `k ∈ [0, 1]`.
    pub stiffness: f32,
    /// XPBD compliance `α ≥ 0` (cm/dyn).
    pub compliance: f32,
}

impl DistanceConstraint {
    /// Number of nodes.
    pub const CARDINALITY: usize = 2;
    /// Equality.
    pub const KIND: ConstraintKind = ConstraintKind::Equality;
    /// `C` at `positions`.
    pub fn value(&self, positions: &[Vec3A]) -> f32 {
        let [a, b] = self.nodes.map(|i| positions[i as usize]);
        (a - b).length() - self.rest_length
    }
}

impl TetVolumeConstraint {
    /// Number of nodes.
    pub const CARDINALITY: usize = 4;
    /// Equality.
    pub const KIND: ConstraintKind = ConstraintKind::Equality;
    /// `C` at `positions`.
    pub fn value(&self, positions: &[Vec3A]) -> f32 {
        let [a, b, c, d] = self.nodes.map(|i| positions[i as usize]);
        (b - a).cross(c - a).dot(d - a) / 6.0 - self.rest_volume
    }
}

impl CentroidVolumeConstraint {
    /// Number of nodes.
    pub const CARDINALITY: usize = 4;
    /// Equality.
    pub const KIND: ConstraintKind = ConstraintKind::Equality;
    /// `C` at `positions`.
    pub fn value(&self, positions: &[Vec3A]) -> f32 {
        let [a, b, c] = self.face.map(|i| positions[i as usize]);
        let s = positions[self.apex as usize];
        (s - (a + b + c) / 3.0).length() - self.rest_height
    }
}

/// The floor: an inequality `C = p·axis − height ≥ 0` per node, cardinality 1. Nodes below it are
/// put back on it (no friction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floor {
    /// The up axis: 0 = x, 1 = y, 2 = z (the bunny of the test meshes is +y up).
    pub axis: usize,
    /// Height of the plane along `axis` (cm).
    pub height: f32,
}

impl Floor {
    /// The floor `y = height`, up = +y.
    pub fn y(height: f32) -> Self {
        Self { axis: 1, height }
    }
    /// Equality or inequality.
    pub const KIND: ConstraintKind = ConstraintKind::Inequality;
}

/// Hot record of a distance constraint: 16 bytes, `param` is `k'` (PBD) or `α̃` (XPBD).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C)]
pub(crate) struct DistanceRow {
    pub nodes: [u32; 2],
    pub rest: f32,
    pub param: f32,
}

/// Hot record of a classic volume constraint: 24 bytes.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C)]
pub(crate) struct TetRow {
    pub nodes: [u32; 4],
    pub rest: f32,
    pub param: f32,
}

/// Hot record of the four centroid constraints of one tet (apex `j` = node `j`): 48 bytes.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C)]
pub(crate) struct CentroidRow {
    pub nodes: [u32; 4],
    pub rest: [f32; 4],
    pub param: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<DistanceRow>() == 16);
const _: () = assert!(std::mem::size_of::<TetRow>() == 24);
const _: () = assert!(std::mem::size_of::<CentroidRow>() == 48);

/// Below this length (cm) a distance or centroid constraint has no usable direction and is
/// skipped for the iteration.
const MIN_LENGTH: f32 = 1e-12;

/// The multiplier step `Δλ` shared by PBD (`α̃ = 0`, `k` = `param`) and XPBD (`α̃` = `param`).
#[inline(always)]
fn delta_lambda<const XPBD: bool>(c: f32, denom: f32, param: f32, lambda: &mut f32) -> f32 {
    if XPBD {
        let dl = (-c - param * *lambda) / (denom + param);
        *lambda += dl;
        dl
    } else {
        -param * c / denom
    }
}

/// Projects one distance constraint on local copies `q` of its nodes.
#[inline(always)]
pub(crate) fn project_distance<const XPBD: bool>(
    q: &mut [Vec3A; 2],
    w: [f32; 2],
    row: &DistanceRow,
    lambda: &mut f32,
) {
    let d = q[0] - q[1];
    let len = d.length();
    let denom = w[0] + w[1];
    if denom <= 0.0 || len < MIN_LENGTH {
        return;
    }
    let n = d / len;
    let dl = delta_lambda::<XPBD>(len - row.rest, denom, row.param, lambda);
    q[0] += (w[0] * dl) * n;
    q[1] -= (w[1] * dl) * n;
}

/// Projects one classic tet-volume constraint on local copies `q` of its nodes.
#[inline(always)]
pub(crate) fn project_tet_volume<const XPBD: bool>(
    q: &mut [Vec3A; 4],
    w: [f32; 4],
    row: &TetRow,
    lambda: &mut f32,
) {
    let (e1, e2, e3) = (q[1] - q[0], q[2] - q[0], q[3] - q[0]);
    let g1 = e2.cross(e3) / 6.0;
    let g2 = e3.cross(e1) / 6.0;
    let g3 = e1.cross(e2) / 6.0;
    let g0 = -(g1 + g2 + g3);
    let c = e3.dot(g3) - row.rest;
    let denom = w[0] * g0.length_squared()
        + w[1] * g1.length_squared()
        + w[2] * g2.length_squared()
        + w[3] * g3.length_squared();
    if denom <= f32::MIN_POSITIVE {
        return;
    }
    let dl = delta_lambda::<XPBD>(c, denom, row.param, lambda);
    q[0] += (w[0] * dl) * g0;
    q[1] += (w[1] * dl) * g1;
    q[2] += (w[2] * dl) * g2;
    q[3] += (w[3] * dl) * g3;
}

/// Projects the four centroid constraints of one tet, apex 0, 1, 2, 3 in turn (Gauss–Seidel), on
/// local copies `q` of its nodes.
///
/// `∇_s C = n`, `∇_{p_i} C = −n/3` (`n = (s−c)/|s−c|`), so `Σ w|∇C|² = w_s + (w₁+w₂+w₃)/9` and,
/// with `g = (s−c)(1 − h₀/|s−c|)k'`, `Δp_i = 3w_i/W'·g`, `Δs = −9w_s/W'·g` where
/// `W' = w₁+w₂+w₃+9w_s`. (The slides print `W = w₁+w₂+w₃+w_s`, which over-corrects by
/// `W'/W`, 3× for equal masses, and diverges for `k' > 2/3`.)
// Not inlined: inlined into the sweep's loop it ran 1.5× slower on the bunny (Zen 5).
#[inline(never)]
pub(crate) fn project_centroid<const XPBD: bool>(
    q: &mut [Vec3A; 4],
    w: [f32; 4],
    row: &CentroidRow,
    lambda: &mut [f32],
) {
    // Unrolled with constant indices so that `q` stays in registers.
    centroid_apex::<XPBD, 0, 1, 2, 3>(q, w, row, lambda);
    centroid_apex::<XPBD, 1, 2, 3, 0>(q, w, row, lambda);
    centroid_apex::<XPBD, 2, 3, 0, 1>(q, w, row, lambda);
    centroid_apex::<XPBD, 3, 0, 1, 2>(q, w, row, lambda);
}

#[inline(always)]
fn centroid_apex<
    const XPBD: bool,
    const J: usize,
    const A: usize,
    const B: usize,
    const C: usize,
>(
    q: &mut [Vec3A; 4],
    w: [f32; 4],
    row: &CentroidRow,
    lambda: &mut [f32],
) {
    let c = (q[A] + q[B] + q[C]) * (1.0 / 3.0);
    let d = q[J] - c;
    let len = d.length();
    let denom = w[J] + (w[A] + w[B] + w[C]) * (1.0 / 9.0);
    if denom <= 0.0 || len < MIN_LENGTH {
        return;
    }
    let dl = delta_lambda::<XPBD>(len - row.rest[J], denom, row.param[J], &mut lambda[J]);
    let step = d * (dl / len);
    q[J] += w[J] * step;
    let face = step * (1.0 / 3.0);
    q[A] -= w[A] * face;
    q[B] -= w[B] * face;
    q[C] -= w[C] * face;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_projection_satisfies_each_constraint_with_unit_stiffness() {
        let w = [1.0, 0.5, 2.0, 0.25];
        let mut q = [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(1.2, 0.1, 0.0),
            Vec3A::new(0.1, 0.9, 0.2),
            Vec3A::new(0.2, 0.1, 1.3),
        ];
        let row = DistanceRow {
            nodes: [0, 1],
            rest: 0.7,
            param: 1.0,
        };
        let mut pair = [q[0], q[1]];
        project_distance::<false>(&mut pair, [w[0], w[1]], &row, &mut 0.0);
        assert!(((pair[0] - pair[1]).length() - 0.7).abs() < 1e-5);

        let row = TetRow {
            nodes: [0, 1, 2, 3],
            rest: 0.1,
            param: 1.0,
        };
        let mut t = q;
        project_tet_volume::<false>(&mut t, w, &row, &mut 0.0);
        let vol = (t[1] - t[0]).cross(t[2] - t[0]).dot(t[3] - t[0]) / 6.0;
        // Linearised: one step lands close, not exactly.
        assert!((vol - 0.1).abs() < 0.02, "{vol}");

        // One centroid constraint (apex 0) alone is exactly satisfied: it is linear along n.
        let row = CentroidRow {
            nodes: [0, 1, 2, 3],
            rest: [0.5; 4],
            param: [1.0, 0.0, 0.0, 0.0],
        };
        project_centroid::<false>(&mut q, w, &row, &mut [0.0; 4]);
        let h = (q[0] - (q[1] + q[2] + q[3]) / 3.0).length();
        assert!((h - 0.5).abs() < 1e-5, "{h}");
    }

    #[test]
    fn centroid_projection_conserves_momentum() {
        let w = [1.0, 0.5, 2.0, 0.25];
        let q0 = [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(1.2, 0.1, 0.0),
            Vec3A::new(0.1, 0.9, 0.2),
            Vec3A::new(0.2, 0.1, 1.3),
        ];
        let mut q = q0;
        let row = CentroidRow {
            nodes: [0, 1, 2, 3],
            rest: [0.3, 0.4, 0.5, 0.6],
            param: [0.7; 4],
        };
        project_centroid::<false>(&mut q, w, &row, &mut [0.0; 4]);
        let mut p = Vec3A::ZERO;
        for i in 0..4 {
            p += (q[i] - q0[i]) / w[i];
        }
        assert!(p.length() < 1e-5, "{p}");
    }
}
