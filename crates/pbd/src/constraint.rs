//! Constraint records (public, one `Vec` per kind) and their projection kernels: pure functions
//! on local copies of the nodes of [`LANES`] constraints at once (structure of arrays, one
//! constraint per `f32` lane; the nodes carry their inverse mass in `w`), gathered and scattered
//! with 4×4 transposes.
//!
//! Projection of one constraint `C` (Müller et al.): `Δp_i = −s·w_i·∇_i C`,
//! `s = k·C / Σ_j w_j |∇_j C|²`. XPBD (Macklin et al.) replaces the stiffness by a compliance:
//! `Δλ = (−C − α̃λ) / (Σ_j w_j |∇_j C|² + α̃)`, `Δp_i = w_i ∇_i C Δλ`, `α̃ = α/Δt²`; with `α̃ = 0`
//! it is the PBD projection with `k = 1`. Both conserve linear and angular momentum (the
//! gradients of a translation- and rotation-invariant `C` sum to zero and have zero torque).

use glam::{BVec4A, Mat3, Mat4, Vec3A, Vec4};

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

/// The stable neo-Hookean constraint pair of one tet (Macklin & Müller 2021, "A constraint-based
/// formulation of stable neo-Hookean materials"), for [`crate::Material::elastic`]: with the
/// deformation gradient `F = D_s D_m⁻¹` (`D_s = [x₁−x₀, x₂−x₀, x₃−x₀]`, `D_m` the same of the rest
/// positions), the hydrostatic constraint `C_H = det F − γ` (compliance `α_H = 1/(λ V₀)`) and the
/// deviatoric constraint `C_D = √(tr FᵀF)` (compliance `α_D = 1/(μ V₀)`). Their XPBD energy
/// `C_H²/(2α_H) + C_D²/(2α_D) = V₀ [λ/2 (J − γ)² + μ/2 I_C]` is `V₀ Ψ` of the stable
/// neo-Hookean density `Ψ = μ/2 (I_C − 3) + λ/2 (J − γ)²` up to a constant; with `γ = 1 + μ/λ`
/// its gradient vanishes at `F = I` (the rest state is stress-free, though neither constraint is
/// zero there: `C_H = −μ/λ`, `C_D = √3`). Here `λ` is the energy's parameter, `λ_Lamé + μ`, so
/// that small strains follow linear elasticity with the Lamé `λ_Lamé`, `μ` (see
/// [`crate::Elastic::lame`]). Cardinality 4, two equalities, solved together per tet (a 2×2 XPBD
/// system).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeoHookeanConstraint {
    /// The tet's nodes, positively oriented.
    pub nodes: [u32; 4],
    /// Rest volume `V₀` (cm³).
    pub rest_volume: f32,
    /// `D_m⁻¹`, the inverse of the rest edge matrix (1/cm).
    pub inverse_rest_edges: Mat3,
    /// `γ = 1 + μ/λ`.
    pub gamma: f32,
    /// `α_H = 1/(λ V₀)` (1/erg).
    pub hydrostatic_compliance: f32,
    /// `α_D = 1/(μ V₀)` (1/erg).
    pub deviatoric_compliance: f32,
}

impl NeoHookeanConstraint {
    /// Number of nodes.
    pub const CARDINALITY: usize = 4;
    /// Equalities.
    pub const KIND: ConstraintKind = ConstraintKind::Equality;

    /// `F = D_s D_m⁻¹` at `positions`.
    pub fn deformation_gradient(&self, positions: &[Vec3A]) -> Mat3 {
        let [a, b, c, d] = self.nodes.map(|i| glam::Vec3::from(positions[i as usize]));
        Mat3::from_cols(b - a, c - a, d - a) * self.inverse_rest_edges
    }

    /// `[C_H, C_D]` at `positions`.
    pub fn values(&self, positions: &[Vec3A]) -> [f32; 2] {
        let f = self.deformation_gradient(positions);
        let ic = f.x_axis.length_squared() + f.y_axis.length_squared() + f.z_axis.length_squared();
        [f.determinant() - self.gamma, ic.sqrt()]
    }

    /// `[∇C_H, ∇C_D]` at `positions`, each the gradients with respect to the four nodes:
    /// `∂C/∂x_i = (∂C/∂F) D_m⁻ᵀ` column `i − 1` (`i = 1, 2, 3`), `∂C/∂x₀ = −Σ` of those, with
    /// `∂C_H/∂F = cof F = [f₁×f₂, f₂×f₀, f₀×f₁]` and `∂C_D/∂F = F / C_D` (`f_j` the columns of
    /// `F`).
    pub fn gradients(&self, positions: &[Vec3A]) -> [[Vec3A; 4]; 2] {
        let f = self.deformation_gradient(positions);
        let ic = f.x_axis.length_squared() + f.y_axis.length_squared() + f.z_axis.length_squared();
        let cof = Mat3::from_cols(
            f.y_axis.cross(f.z_axis),
            f.z_axis.cross(f.x_axis),
            f.x_axis.cross(f.y_axis),
        );
        let bt = self.inverse_rest_edges.transpose();
        [cof * bt, f * bt * (1.0 / ic.sqrt())].map(|g| {
            let (g1, g2, g3) = (g.x_axis, g.y_axis, g.z_axis);
            [-(g1 + g2 + g3), g1, g2, g3].map(Vec3A::from)
        })
    }
}

impl NeoHookeanConstraint {
    /// The pair of tet `nodes` with rest positions `rest` (cm, positively oriented) for the
    /// energy parameters `(μ, λ)` (dyn/cm², [`crate::Elastic::energy_parameters`]); `None` when
    /// the rest shape is flat, inverted or not finite.
    pub fn new(nodes: [u32; 4], rest: [glam::DVec3; 4], mu: f64, lambda: f64) -> Option<Self> {
        let [a, b, c, d] = rest;
        let dm = glam::DMat3::from_cols(b - a, c - a, d - a);
        let det = dm.determinant();
        let volume = det / 6.0;
        if !(volume.is_finite() && volume > 0.0 && (volume as f32) > 0.0) {
            return None;
        }
        let inv = dm.inverse();
        if !inv.is_finite() {
            return None;
        }
        Some(Self {
            nodes,
            rest_volume: volume as f32,
            inverse_rest_edges: inv.as_mat3(),
            gamma: (1.0 + mu / lambda) as f32,
            hydrostatic_compliance: (1.0 / (lambda * volume)) as f32,
            deviatoric_compliance: (1.0 / (mu * volume)) as f32,
        })
    }

    /// The kernels' parameters `[α̃_H, α̃_D] = α/h²` for substeps of `h` (s).
    pub(crate) fn params(&self, h: f32) -> [f32; 2] {
        let h2 = (h as f64) * (h as f64);
        [
            (self.hydrostatic_compliance as f64 / h2) as f32,
            (self.deviatoric_compliance as f64 / h2) as f32,
        ]
    }
}

/// Writes lane `l` of a neo-Hookean batch: the local node indices `s`, the record's rest data
/// and the parameters `param` (`[α̃_H, α̃_D]`).
pub(crate) fn set_neo_hookean_lane(
    b: &mut NeoHookeanBatch,
    l: usize,
    s: [u32; 4],
    c: &NeoHookeanConstraint,
    param: [f32; 2],
) {
    let set = |f: &mut F, v: f32| f.0[l / 4][l % 4] = v;
    for (ids, &n) in b.nodes.iter_mut().zip(&s) {
        ids[l] = n;
    }
    for r in 0..3 {
        for col in 0..3 {
            set(&mut b.dm_inv[3 * r + col], c.inverse_rest_edges.col(col)[r]);
        }
    }
    set(&mut b.gamma, c.gamma);
    set(&mut b.param[0], param[0]);
    set(&mut b.param[1], param[1]);
}

/// A neo-Hookean batch whose every lane is `c` on local nodes `s` (a new dynamic batch).
pub(crate) fn neo_hookean_batch(
    s: [u32; 4],
    c: &NeoHookeanConstraint,
    param: [f32; 2],
) -> NeoHookeanBatch {
    let mut b = NeoHookeanBatch {
        nodes: [[0; LANES]; 4],
        dm_inv: [F::ZERO; 9],
        gamma: F::ZERO,
        param: [F::ZERO; 2],
    };
    for l in 0..LANES {
        set_neo_hookean_lane(&mut b, l, s, c, param);
    }
    b
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

/// `Vec4`s per lane group: a batch holds [`LANES`] `= 4·M` constraints, one per `f32` lane. Two
/// `Vec4`s per value let the CPU overlap two independent chains of SSE operations.
pub(crate) const M: usize = 2;
/// Constraints per batch.
pub(crate) const LANES: usize = 4 * M;

/// One `f32` per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct F(pub [Vec4; M]);

/// One boolean per lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Mask([BVec4A; M]);

macro_rules! lanewise {
    ($trait:ident, $fn:ident, $op:tt) => {
        impl std::ops::$trait for F {
            type Output = F;
            #[inline(always)]
            fn $fn(self, o: F) -> F {
                let mut r = self.0;
                for (r, o) in r.iter_mut().zip(o.0) {
                    *r $op o;
                }
                F(r)
            }
        }
    };
}
lanewise!(Add, add, +=);
lanewise!(Sub, sub, -=);
lanewise!(Mul, mul, *=);
lanewise!(Div, div, /=);

impl std::ops::Neg for F {
    type Output = F;
    #[inline(always)]
    fn neg(self) -> F {
        let mut r = self.0;
        for r in &mut r {
            *r = -*r;
        }
        F(r)
    }
}

impl std::ops::BitAnd for Mask {
    type Output = Mask;
    #[inline(always)]
    fn bitand(self, o: Mask) -> Mask {
        let mut r = self.0;
        for (r, o) in r.iter_mut().zip(o.0) {
            *r &= o;
        }
        Mask(r)
    }
}

impl F {
    pub(crate) const ZERO: F = F([Vec4::ZERO; M]);
    #[cfg(test)]
    pub(crate) const ONE: F = F([Vec4::ONE; M]);
    #[inline(always)]
    pub(crate) fn splat(v: f32) -> F {
        F([Vec4::splat(v); M])
    }
    /// The lanes from an array.
    pub(crate) fn from_lanes(a: [f32; LANES]) -> F {
        F(std::array::from_fn(|m| {
            Vec4::new(a[4 * m], a[4 * m + 1], a[4 * m + 2], a[4 * m + 3])
        }))
    }
    /// Lane `i`.
    #[cfg(test)]
    pub(crate) fn lane(self, i: usize) -> f32 {
        self.0[i / 4][i % 4]
    }
    #[inline(always)]
    fn sqrt(self) -> F {
        let mut r = self.0;
        for r in &mut r {
            *r = Vec4::new(r.x.sqrt(), r.y.sqrt(), r.z.sqrt(), r.w.sqrt());
        }
        F(r)
    }
    #[inline(always)]
    fn cmpgt(self, o: F) -> Mask {
        let mut r = [BVec4A::FALSE; M];
        for (r, (a, b)) in r.iter_mut().zip(self.0.into_iter().zip(o.0)) {
            *r = a.cmpgt(b);
        }
        Mask(r)
    }
    #[inline(always)]
    fn cmpge(self, o: F) -> Mask {
        let mut r = [BVec4A::FALSE; M];
        for (r, (a, b)) in r.iter_mut().zip(self.0.into_iter().zip(o.0)) {
            *r = a.cmpge(b);
        }
        Mask(r)
    }
    /// `if mask { a } else { b }` per lane.
    #[inline(always)]
    fn select(mask: Mask, a: F, b: F) -> F {
        let mut r = b.0;
        for ((r, m), a) in r.iter_mut().zip(mask.0).zip(a.0) {
            *r = Vec4::select(m, a, *r);
        }
        F(r)
    }
}

/// [`LANES`] constraints of one kind projected at once, one per lane (structure of arrays). The
/// lanes of a batch share no node (they come from one colour of one block); a colour whose size
/// is not a multiple of [`LANES`] fills its last batch with copies of that batch's lane 0, which
/// compute exactly what lane 0 computes and write the same values back.
///
/// `nodes[k][lane]`: node `k` of the lane's constraint, an index into the node range of the
/// batch's block. `param` is `k`, `k'` or `α̃` per lane (see [`crate::StepSettings`]).
#[derive(Debug, Clone, Copy)]
#[repr(C)]
pub(crate) struct DistanceBatch {
    pub nodes: [[u32; LANES]; 2],
    pub rest: F,
    pub param: F,
}

/// Classic volume constraints: rest volumes `V₀`.
#[derive(Debug, Clone, Copy)]
#[repr(C)]
pub(crate) struct TetBatch {
    pub nodes: [[u32; LANES]; 4],
    pub rest: F,
    pub param: F,
}

/// The centroid constraints of [`LANES`] tets, `rest[j]`/`param[j]` for apex `j` = node `j`.
#[derive(Debug, Clone, Copy)]
#[repr(C)]
pub(crate) struct CentroidBatch {
    pub nodes: [[u32; LANES]; 4],
    pub rest: [F; 4],
    pub param: [F; 4],
}

/// Stable neo-Hookean constraint pairs of [`LANES`] tets: `D_m⁻¹` row-major (`dm_inv[3r + c]`),
/// `γ`, and the parameters `α̃_H`, `α̃_D` (`α/h²`).
#[derive(Debug, Clone, Copy)]
#[repr(C)]
pub(crate) struct NeoHookeanBatch {
    pub nodes: [[u32; LANES]; 4],
    pub dm_inv: [F; 9],
    pub gamma: F,
    pub param: [F; 2],
}

const _: () = assert!(std::mem::size_of::<DistanceBatch>() == 16 * LANES);
const _: () = assert!(std::mem::size_of::<TetBatch>() == 24 * LANES);
const _: () = assert!(std::mem::size_of::<CentroidBatch>() == 48 * LANES);

/// [`LANES`] points, one per lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct P4 {
    pub x: F,
    pub y: F,
    pub z: F,
}

impl P4 {
    pub(crate) const ZERO: Self = Self {
        x: F::ZERO,
        y: F::ZERO,
        z: F::ZERO,
    };
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    #[inline(always)]
    fn scale(self, s: F) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    fn dot(self, o: Self) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Self {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }
}

/// Loads the nodes `ids` (xyz = position, w = inverse mass) into lanes.
#[inline(always)]
pub(crate) fn gather(p: &[Vec4], ids: &[u32; LANES]) -> (P4, F) {
    let (mut q, mut w) = (P4::ZERO, F::ZERO);
    for m in 0..M {
        let t = Mat4::from_cols(
            p[ids[4 * m] as usize],
            p[ids[4 * m + 1] as usize],
            p[ids[4 * m + 2] as usize],
            p[ids[4 * m + 3] as usize],
        )
        .transpose();
        q.x.0[m] = t.x_axis;
        q.y.0[m] = t.y_axis;
        q.z.0[m] = t.z_axis;
        w.0[m] = t.w_axis;
    }
    (q, w)
}

/// Stores lanes back to the nodes `ids` (in lane order; duplicate lanes hold equal values).
#[inline(always)]
pub(crate) fn scatter(p: &mut [Vec4], ids: &[u32; LANES], q: P4, w: F) {
    for m in 0..M {
        let t = Mat4::from_cols(q.x.0[m], q.y.0[m], q.z.0[m], w.0[m]).transpose();
        p[ids[4 * m] as usize] = t.x_axis;
        p[ids[4 * m + 1] as usize] = t.y_axis;
        p[ids[4 * m + 2] as usize] = t.z_axis;
        p[ids[4 * m + 3] as usize] = t.w_axis;
    }
}

/// Below this length (cm) a distance or centroid constraint has no usable direction and is
/// skipped for the iteration.
const MIN_LENGTH: f32 = 1e-12;

/// The step `s` along the direction `∇C · scale` that the kernel moves along, 0 in the lanes not
/// `valid`: PBD `s = −k·C / (Σw|∇C|² · scale)`, XPBD `Δλ = (−C − α̃λ) / (Σw|∇C|² + α̃)`,
/// `s = Δλ / scale` (`scale`: the length `|d|` for a distance direction `d`, 6 for the volume's
/// six-fold gradients).
#[inline(always)]
fn step<const XPBD: bool>(c: F, denom: F, scale: F, param: F, valid: Mask, lambda: &mut F) -> F {
    let s = if XPBD {
        let dl = (-c - param * *lambda) / (denom + param);
        *lambda = F::select(valid, *lambda + dl, *lambda);
        dl / scale
    } else {
        -(param * c) / (denom * scale)
    };
    F::select(valid, s, F::ZERO)
}

/// Projects a batch of distance constraints (`C = |p₁ − p₂| − d`) on their gathered nodes.
#[inline(always)]
pub(crate) fn project_distance<const XPBD: bool>(
    q: &mut [P4; 2],
    w: &[F; 2],
    b: &DistanceBatch,
    lambda: &mut [F],
) {
    let d = q[0].sub(q[1]);
    let len = d.dot(d).sqrt();
    let denom = w[0] + w[1];
    let valid = denom.cmpgt(F::ZERO) & len.cmpge(F::splat(MIN_LENGTH));
    let s = step::<XPBD>(len - b.rest, denom, len, b.param, valid, &mut lambda[0]);
    q[0] = q[0].add(d.scale(w[0] * s));
    q[1] = q[1].sub(d.scale(w[1] * s));
}

/// Projects a batch of classic tet-volume constraints on their gathered nodes.
#[inline(always)]
pub(crate) fn project_tet_volume<const XPBD: bool>(
    q: &mut [P4; 4],
    w: &[F; 4],
    b: &TetBatch,
    lambda: &mut [F],
) {
    let (e1, e2, e3) = (q[1].sub(q[0]), q[2].sub(q[0]), q[3].sub(q[0]));
    // Six times the gradients: ∇ᵢC = gᵢ/6 (i = 1, 2, 3), ∇₀C = −g₀/6.
    let g1 = e2.cross(e3);
    let g2 = e3.cross(e1);
    let g3 = e1.cross(e2);
    let g0 = g1.add(g2).add(g3);
    let c = e3.dot(g3) * F::splat(1.0 / 6.0) - b.rest;
    let denom = (w[0] * g0.dot(g0) + w[1] * g1.dot(g1) + w[2] * g2.dot(g2) + w[3] * g3.dot(g3))
        * F::splat(1.0 / 36.0);
    let valid = denom.cmpgt(F::splat(f32::MIN_POSITIVE));
    let s = step::<XPBD>(c, denom, F::splat(6.0), b.param, valid, &mut lambda[0]);
    q[0] = q[0].sub(g0.scale(w[0] * s));
    q[1] = q[1].add(g1.scale(w[1] * s));
    q[2] = q[2].add(g2.scale(w[2] * s));
    q[3] = q[3].add(g3.scale(w[3] * s));
}

/// Projects the four centroid constraints of each tet of a batch, apex 0, 1, 2, 3 in turn
/// (Gauss–Seidel), on their gathered nodes.
///
/// `∇_s C = n`, `∇_{p_i} C = −n/3` (`n = (s−c)/|s−c|`), so `Σ w|∇C|² = w_s + (w₁+w₂+w₃)/9` and,
/// with `g = (s−c)(1 − h₀/|s−c|)k'`, `Δp_i = 3w_i/W'·g`, `Δs = −9w_s/W'·g` where
/// `W' = w₁+w₂+w₃+9w_s`. (The slides print `W = w₁+w₂+w₃+w_s`, which over-corrects by
/// `W'/W`, 3× for equal masses, and diverges for `k' > 2/3`.)
#[inline(always)]
pub(crate) fn project_centroid<const XPBD: bool>(
    q: &mut [P4; 4],
    w: &[F; 4],
    b: &CentroidBatch,
    lambda: &mut [F],
) {
    // Unrolled with constant indices so that `q` stays in registers.
    centroid_apex::<XPBD, 0, 1, 2, 3>(q, w, b, lambda);
    centroid_apex::<XPBD, 1, 2, 3, 0>(q, w, b, lambda);
    centroid_apex::<XPBD, 2, 3, 0, 1>(q, w, b, lambda);
    centroid_apex::<XPBD, 3, 0, 1, 2>(q, w, b, lambda);
}

#[inline(always)]
fn centroid_apex<
    const XPBD: bool,
    const J: usize,
    const A: usize,
    const B: usize,
    const C: usize,
>(
    q: &mut [P4; 4],
    w: &[F; 4],
    b: &CentroidBatch,
    lambda: &mut [F],
) {
    let third = F::splat(1.0 / 3.0);
    let d = q[J].sub(q[A].add(q[B]).add(q[C]).scale(third));
    let len = d.dot(d).sqrt();
    let denom = w[J] + (w[A] + w[B] + w[C]) * F::splat(1.0 / 9.0);
    let valid = denom.cmpgt(F::ZERO) & len.cmpge(F::splat(MIN_LENGTH));
    let s = step::<XPBD>(
        len - b.rest[J],
        denom,
        len,
        b.param[J],
        valid,
        &mut lambda[J],
    );
    let step = d.scale(s);
    q[J] = q[J].add(step.scale(w[J]));
    let face = step.scale(third);
    q[A] = q[A].sub(face.scale(w[A]));
    q[B] = q[B].sub(face.scale(w[B]));
    q[C] = q[C].sub(face.scale(w[C]));
}

/// Projects a batch of stable neo-Hookean constraint pairs (see [`NeoHookeanConstraint`]) on
/// their gathered nodes: both constraints of a tet at once, by the linearised XPBD system
/// `(keep · ∇C M⁻¹ ∇Cᵀ + α̃) Δλ = −C − α̃ λ` of the pair (2×2, solved exactly; `keep = 1 − β`,
/// `β` the step's [`crate::StepSettings::over_relaxation`]), then
/// `Δx_i = w_i (∇_i C_H Δλ_H + ∇_i C_D Δλ_D)`. At rest (`F = I`) `∇C_D = ∇C_H/√3` and the
/// solution moves nothing: the coupled solve keeps the rest state still where projecting the two
/// one after the other would not (each alone is far from zero there). Lanes with `C_D` below
/// [`MIN_LENGTH`] (a collapsed, switched-off tet) are skipped. Multipliers `lambda[0]` (`C_H`),
/// `lambda[1]` (`C_D`). Always XPBD.
#[inline(always)]
pub(crate) fn project_neo_hookean(
    q: &mut [P4; 4],
    w: &[F; 4],
    b: &NeoHookeanBatch,
    lambda: &mut [F],
    one_minus_beta: F,
) {
    let e = [q[1].sub(q[0]), q[2].sub(q[0]), q[3].sub(q[0])];
    let m = &b.dm_inv;
    // F's columns: f_c = Σ_r e_r B[r][c].
    // (Spelled out: `array::from_fn` is not inlined here.)
    let column = |c: usize| {
        e[0].scale(m[c])
            .add(e[1].scale(m[3 + c]))
            .add(e[2].scale(m[6 + c]))
    };
    let f = [column(0), column(1), column(2)];
    let ic = f[0].dot(f[0]) + f[1].dot(f[1]) + f[2].dot(f[2]);
    let cd = ic.sqrt();
    let cof = [f[1].cross(f[2]), f[2].cross(f[0]), f[0].cross(f[1])];
    let ch = f[0].dot(cof[0]) - b.gamma;
    let valid = cd.cmpge(F::splat(MIN_LENGTH));
    let inv_cd = F::select(valid, F::splat(1.0) / cd, F::ZERO);
    // Gradients at nodes 1..3: g_r = Σ_c P_c B[r][c]; node 0 the negative sum.
    let grad = |p: &[P4; 3], r: usize| {
        p[0].scale(m[3 * r])
            .add(p[1].scale(m[3 * r + 1]))
            .add(p[2].scale(m[3 * r + 2]))
    };
    let gh = [grad(&cof, 0), grad(&cof, 1), grad(&cof, 2)];
    let gd = [
        grad(&f, 0).scale(inv_cd),
        grad(&f, 1).scale(inv_cd),
        grad(&f, 2).scale(inv_cd),
    ];
    let gh0 = gh[0].add(gh[1]).add(gh[2]);
    let gd0 = gd[0].add(gd[1]).add(gd[2]);
    let (mut hh, mut dd, mut hd) = (
        w[0] * gh0.dot(gh0),
        w[0] * gd0.dot(gd0),
        w[0] * gh0.dot(gd0),
    );
    for k in 0..3 {
        hh = hh + w[k + 1] * gh[k].dot(gh[k]);
        dd = dd + w[k + 1] * gd[k].dot(gd[k]);
        hd = hd + w[k + 1] * gh[k].dot(gd[k]);
    }
    let [ah, ad] = b.param;
    // Over-relaxation (StepSettings::over_relaxation): `A` scaled by one factor per tet (so
    // that the rest state stays still), `(K + (1 − β) α̃)/(K + α̃)` of its stiffer constraint.
    // (The stiffer has the larger `K/α̃`: compared without dividing.)
    let h_stiffer = (hh * ad).cmpgt(dd * ah);
    let (k, a) = (F::select(h_stiffer, hh, dd), F::select(h_stiffer, ah, ad));
    let keep = (k + one_minus_beta * a) / (k + a);
    let (hh, dd, hd) = (hh * keep, dd * keep, hd * keep);
    let rh = -ch - ah * lambda[0];
    let rd = -cd - ad * lambda[1];
    // det = (hh + α̃_H)(dd + α̃_D) − hd², its Gram part hh·dd − hd² ≥ 0 kept so in rounding.
    let gram = hh * dd - hd * hd;
    let gram = F::select(gram.cmpgt(F::ZERO), gram, F::ZERO);
    let det = gram + ah * dd + ad * hh + ah * ad;
    let valid = valid & det.cmpgt(F::splat(f32::MIN_POSITIVE));
    let inv = F::select(valid, F::splat(1.0) / det, F::ZERO);
    let dlh = F::select(valid, ((dd + ad) * rh - hd * rd) * inv, F::ZERO);
    let dld = F::select(valid, ((hh + ah) * rd - hd * rh) * inv, F::ZERO);
    lambda[0] = lambda[0] + dlh;
    lambda[1] = lambda[1] + dld;
    q[0] = q[0].sub(gh0.scale(w[0] * dlh).add(gd0.scale(w[0] * dld)));
    for k in 0..3 {
        q[k + 1] = q[k + 1].add(gh[k].scale(w[k + 1] * dlh).add(gd[k].scale(w[k + 1] * dld)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lane 0 holds the constraint; the other lanes copy it (as padding does).
    fn lanes<const N: usize>(q: [Vec3A; N], w: [f32; N]) -> ([P4; N], [F; N]) {
        (
            q.map(|p| P4 {
                x: F::splat(p.x),
                y: F::splat(p.y),
                z: F::splat(p.z),
            }),
            w.map(F::splat),
        )
    }

    fn lane0<const N: usize>(q: &[P4; N]) -> [Vec3A; N] {
        q.map(|p| Vec3A::new(p.x.lane(0), p.y.lane(0), p.z.lane(0)))
    }

    const W: [f32; 4] = [1.0, 0.5, 2.0, 0.25];
    const Q: [Vec3A; 4] = [
        Vec3A::new(0.0, 0.0, 0.0),
        Vec3A::new(1.2, 0.1, 0.0),
        Vec3A::new(0.1, 0.9, 0.2),
        Vec3A::new(0.2, 0.1, 1.3),
    ];

    #[test]
    fn one_projection_satisfies_each_constraint_with_unit_stiffness() {
        let b = DistanceBatch {
            nodes: [[0; LANES]; 2],
            rest: F::splat(0.7),
            param: F::ONE,
        };
        let (mut q, w) = lanes([Q[0], Q[1]], [W[0], W[1]]);
        project_distance::<false>(&mut q, &w, &b, &mut [F::ZERO]);
        let pair = lane0(&q);
        assert!(((pair[0] - pair[1]).length() - 0.7).abs() < 1e-5);

        let b = TetBatch {
            nodes: [[0; LANES]; 4],
            rest: F::splat(0.1),
            param: F::ONE,
        };
        let (mut q, w) = lanes(Q, W);
        project_tet_volume::<false>(&mut q, &w, &b, &mut [F::ZERO]);
        let t = lane0(&q);
        let vol = (t[1] - t[0]).cross(t[2] - t[0]).dot(t[3] - t[0]) / 6.0;
        // Linearised: one step lands close, not exactly.
        assert!((vol - 0.1).abs() < 0.02, "{vol}");

        // One centroid constraint (apex 0) alone is exactly satisfied: it is linear along n.
        let b = CentroidBatch {
            nodes: [[0; LANES]; 4],
            rest: [F::splat(0.5); 4],
            param: [F::ONE, F::ZERO, F::ZERO, F::ZERO],
        };
        let (mut q, w) = lanes(Q, W);
        project_centroid::<false>(&mut q, &w, &b, &mut [F::ZERO; 4]);
        let q = lane0(&q);
        let h = (q[0] - (q[1] + q[2] + q[3]) / 3.0).length();
        assert!((h - 0.5).abs() < 1e-5, "{h}");
    }

    #[test]
    fn centroid_projection_conserves_momentum() {
        let b = CentroidBatch {
            nodes: [[0; LANES]; 4],
            rest: [0.3, 0.4, 0.5, 0.6].map(F::splat),
            param: [F::splat(0.7); 4],
        };
        let (mut q, w) = lanes(Q, W);
        project_centroid::<false>(&mut q, &w, &b, &mut [F::ZERO; 4]);
        let q = lane0(&q);
        let mut p = Vec3A::ZERO;
        for i in 0..4 {
            p += (q[i] - Q[i]) / W[i];
        }
        assert!(p.length() < 1e-5, "{p}");
    }

    #[test]
    fn lanes_are_independent_and_gather_scatter_round_trip() {
        // Different distance constraints in one batch give, lane by lane, what each gives alone
        // (the padding invariant: a lane's result depends on its lane only).
        let p: Vec<Vec4> = (0..2 * LANES)
            .map(|i| {
                Vec4::new(
                    i as f32 * 0.3,
                    (i * i) as f32 * 0.1,
                    1.0 - i as f32,
                    0.5 + i as f32,
                )
            })
            .collect();
        let nodes: [[u32; LANES]; 2] =
            [0, 1].map(|k| std::array::from_fn(|lane| (2 * lane + k) as u32));
        let b = DistanceBatch {
            nodes,
            rest: F::from_lanes(std::array::from_fn(|l| 0.1 * (l + 1) as f32)),
            param: F::from_lanes(std::array::from_fn(|l| 1.0 - 0.1 * l as f32)),
        };
        let project = |p: &mut Vec<Vec4>, b: &DistanceBatch| {
            let (a, wa) = gather(p, &b.nodes[0]);
            let (c, wc) = gather(p, &b.nodes[1]);
            let mut q = [a, c];
            project_distance::<false>(&mut q, &[wa, wc], b, &mut [F::ZERO]);
            scatter(p, &b.nodes[0], q[0], wa);
            scatter(p, &b.nodes[1], q[1], wc);
        };
        let mut all = p.clone();
        project(&mut all, &b);
        for lane in 0..LANES {
            let one = DistanceBatch {
                nodes: [[nodes[0][lane]; LANES], [nodes[1][lane]; LANES]],
                rest: F::splat(b.rest.lane(lane)),
                param: F::splat(b.param.lane(lane)),
            };
            let mut alone = p.clone();
            project(&mut alone, &one);
            for ids in &nodes {
                let n = ids[lane] as usize;
                assert_eq!(alone[n].to_array(), all[n].to_array());
                assert_eq!(all[n].w, p[n].w, "inverse mass kept");
            }
            assert_ne!(all[nodes[0][lane] as usize], p[nodes[0][lane] as usize]);
        }
    }
}
