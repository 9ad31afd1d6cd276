//! The quasi-static solver: the tissue layers and the second body (the expander, or the plane
//! press's sphere) solved for their static equilibrium directly, instead of stepped to rest.
//!
//! **The model** is the explicit run's, term for term: both layers' Van Gelder springs, the
//! slab's vertical springs and shear, layer 2's anchors, layer 1's bending hinges, the
//! expander's shell springs, eq. (5) and its fill's pressure (`K·(V₀ − V)/V₀`, which holds the
//! volume to `p/K`), the fixed boundary and base. Only the contacts change form: the explicit
//! run stops approaching particles with impulses; here they are forces of a penalty that acts
//! within the contact distance `d₀`, both ways round:
//! - layer 2 against the expander's dome: its particles, and points at ¼, ½ and ¾ of its
//!   edges near the dome (an edge between two particles outside the dome can still cross its
//!   bulge, as Table 2's 150 cm³ showed), each closer than `d₀` to the dome (signed along the
//!   dome's normal interpolated from its vertex normals) pushed out, the dome triangle's
//!   corners pushed back by the same force split by barycentric weights;
//! - an expander particle closer than `d₀` below layer 2 likewise;
//! - layer 1 closer than the thickness guard to layer 2 along layer 2's normal likewise
//!   (the explicit run's [`TissueLayers::hold_thickness`]).
//!
//! `k_c` is [`StaticParams::contact_stiffness`] times the particle's own stiffness (the
//! Laplacian's diagonal); the penalty `k_c·(d₀ − s)²/d₀` starts smoothly at `d₀`.
//!
//! **The solve** is Newton's method without assembling the Jacobian: each step solves
//! `J dx = r` by restarted GMRES (`crate::krylov`: the Jacobian is not symmetric), `J` the
//! model's at the current positions: every spring's `k d dᵀ + k (1 − l₀/l)(I − d dᵀ)` (a
//! compressed spring's negative transverse stiffness kept: dropping it stalled 100 cm³), the
//! anchors, the slab's shear across layer 2's normal with the normal's turn under layer 2's
//! motion (`k (dn (n·s) + n (dn·s))`, not symmetric), the hinges' Gauss–Newton `2k g gᵀ`,
//! eq. (5)'s rank-one term, the fill's `K/V₀ ∇V ∇Vᵀ − p ∇²V`, and each contact's exact local
//! Jacobian (central differences of its force in `f64`: the force turns with the dome's
//! normal as a particle slides over it, a stiffness `f/R` the normal term alone leaves out).
//! It is preconditioned by the springs' Laplacian with the anchors, shear, hinges and eq. (5)
//! on its diagonal, factored once per phase ([`tissue_mss::statics`], sparse Cholesky on faer:
//! the local/global matrix of Liu et al. 2013), the contacts' stiffness added to its diagonal
//! (refactored each step), the fill's rank-one term by Sherman–Morrison. A step whose residual
//! norm grew is halved (down to 1/16) from the last accepted point.
//!
//! **Load steps**: the expander fills from flat in [`StaticParams::load_steps`] steps with its
//! dome held where the fill has got to, each solved to [`StaticParams::load_tolerance`]; then it
//! is released to its own forces and everything is solved to [`StaticParams::tolerance`].
//!
//! **Status**: where it converges it agrees with the explicit run (Table 2: gain within 0.3 %,
//! volume difference within 0.5 %, nothing through the expander), but the penalty contacts
//! make the residual non-smooth where they switch, and the iterations grow with the contact
//! count: Table 2 at 100 cm³ settles in about 240 iterations, 150 cm³ does not settle within
//! 3 000, and on the 129² plane 100 cm³ takes 930. It is therefore not the default:
//! docs/validation.md has the figures.
//!
//! **Stop**: on the residual, not a step count. The residual is the largest net force on a
//! free particle divided by the force that would move that particle by one mean edge against
//! its own stiffness (`P`'s diagonal × the mean layer-2 edge): a dimensionless step, so one
//! tolerance serves every mesh. It is reported with the force itself (N).

use glam::{DMat3, DVec3, Vec3A};
use tissue_bvh::{
    closest_point_on_triangle, closest_point_on_triangle_f64, BuildOptions, Bvh, BvhWorkspace,
    Triangles,
};
use tissue_mss::{Preconditioner, StiffnessBuilder};

use crate::contact_run::{ContactRun, StepSummary};
use crate::krylov::Gmres;
use crate::{ImplantError, Layer, Param, TissueLayers};

/// How the quasi-static solver converges and stops.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticParams {
    /// The final tolerance: the largest net force on a free particle, as a fraction of the
    /// force that moves it by one mean edge against its own stiffness (module docs).
    pub tolerance: f64,
    /// The tolerance of the intermediate load steps.
    pub load_tolerance: f64,
    /// Load steps of the fill (at least 1).
    pub load_steps: u32,
    /// Iterations allowed in all (the solver's step limit).
    pub max_iterations: u64,
    /// A contact's stiffness as a multiple of the particle's own (the matrix's diagonal).
    pub contact_stiffness: f64,
}

impl Default for StaticParams {
    /// A final tolerance of 10⁻⁴ (the net force on any particle would move it by a ten
    /// thousandth of an edge against its own stiffness), 10⁻² on the way, 6 load steps, at
    /// most 3 000 iterations, contacts twice as stiff as the particle (on Table 2 at 50 cm³:
    /// 43 iterations; stiffer contacts hold the larger volumes' layer 2 off the expander
    /// better but converge worse: see the module's status).
    fn default() -> Self {
        StaticParams {
            tolerance: 1e-4,
            load_tolerance: 1e-2,
            load_steps: 6,
            max_iterations: 3_000,
            contact_stiffness: 2.0,
        }
    }
}

impl StaticParams {
    pub(crate) fn check(&self) -> Result<(), ImplantError> {
        let bad = |param: Param, value: f64, expected: &str| {
            Err(ImplantError::InvalidParameter {
                param,
                value,
                expected: expected.into(),
            })
        };
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad(Param::Tolerance, self.tolerance, "positive and finite");
        }
        if !(self.load_tolerance.is_finite() && self.load_tolerance > 0.0) {
            return bad(Param::Tolerance, self.load_tolerance, "positive and finite");
        }
        if self.load_steps == 0 {
            return bad(Param::LoadSteps, 0.0, "at least 1");
        }
        if !(self.contact_stiffness.is_finite() && self.contact_stiffness > 0.0) {
            return bad(
                Param::ContactStiffness,
                self.contact_stiffness,
                "positive and finite",
            );
        }
        Ok(())
    }
}

/// What a quasi-static solve did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticReport {
    /// Local/global iterations over all load steps.
    pub iterations: u64,
    /// The final residual (module docs), dimensionless.
    pub residual: f64,
    /// The largest net force on a free particle at the end (N).
    pub residual_n: f64,
    /// Whether the final tolerance was met.
    pub converged: bool,
}

/// One contact's stiffness: the relative normal displacement `δ = n·Σ cᵢ xᵢ` of its (up to
/// four) particles is held by `k` (g/s²); a fixed particle has `cᵢ = 0`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Contact {
    pub(crate) particles: [u32; 4],
    pub(crate) c: [f64; 4],
    pub(crate) normal: DVec3,
    pub(crate) k: f64,
}

impl Contact {
    /// `out += k (Σ cᵢ n·vᵢ) cⱼ n` for every particle `j`: the contact's Hessian times `v`.
    fn apply(&self, v: &[DVec3], out: &mut [DVec3]) {
        let delta: f64 = self
            .particles
            .iter()
            .zip(&self.c)
            .map(|(&p, &c)| c * self.normal.dot(v[p as usize]))
            .sum();
        for (&p, &c) in self.particles.iter().zip(&self.c) {
            if c != 0.0 {
                out[p as usize] += self.normal * (self.k * delta * c);
            }
        }
    }
}

/// A penalty contact between a point and a triangle, with its exact local Jacobian: the
/// point `x = u₀ y₀ + u₁ y₁` (a particle, `u = (1, 0)`, or a layer-2 edge's midpoint) meets
/// the force `±f(s)·n`, spread on its particles by `u`, the triangle's corners `∓f(s)·n·wᵢ`,
/// `n` the triangle's normal interpolated from its (held) vertex normals at the closest point
/// `q`, `s = ±(x − q)·n` the gap, `f` the [`penalty`]. The contacts carry the expander's
/// pressure, so their force turns with `n` as the point slides over the curved dome: a
/// stiffness of the order `f/R` that `k n nᵀ` leaves out. `m = −∂F/∂y` (the point's two
/// particles, then the corners; 3×3 blocks) is taken by central differences in `f64` of that
/// force.
#[derive(Clone, Copy)]
struct ContactBlock {
    /// The point's two particles, then the triangle's.
    particles: [u32; 5],
    /// Whether each entry is free and carries weight (rows and columns of the others are left
    /// out).
    live: [bool; 5],
    m: [[DMat3; 5]; 5],
    /// The penalty's normal stiffness and the entries' weights (for the preconditioner).
    k: f64,
    c: [f64; 5],
}

/// A point–triangle contact's geometry: `y = [y₀, y₁, a, b, c]`, the point `u₀ y₀ + u₁ y₁`,
/// the triangle's held vertex normals, and the side: `+1` for a point held above the
/// triangle (along `n`), `−1` below.
#[derive(Clone, Copy)]
struct PointTriangle {
    y: [DVec3; 5],
    u: [f64; 2],
    normals: [DVec3; 3],
    side: f64,
}

impl PointTriangle {
    /// The forces on the five entries ([`ContactBlock`]).
    fn forces(&self, y: &[DVec3; 5], k: f64, d0: f64) -> [DVec3; 5] {
        let x = y[0] * self.u[0] + y[1] * self.u[1];
        let (q, w) = closest_point_on_triangle_f64(x, y[2], y[3], y[4]);
        let n = (self.normals[0] * w[0] + self.normals[1] * w[1] + self.normals[2] * w[2])
            .normalize_or_zero();
        let gap = self.side * (x - q).dot(n);
        let depth = (d0 - gap).max(0.0);
        let f = n * (self.side * k * depth * depth / d0);
        [
            f * self.u[0],
            f * self.u[1],
            -f * w[0],
            -f * w[1],
            -f * w[2],
        ]
    }
}

impl ContactBlock {
    /// The block of `geometry` with the penalty `(k, d₀)`; `live` as in the struct,
    /// `stiffness` the penalty's normal stiffness at the gap and `weights` the closest point's
    /// barycentric weights (for the preconditioner).
    fn new(
        particles: [u32; 5],
        live: [bool; 5],
        geometry: &PointTriangle,
        (k, d0): (f64, f64),
        stiffness: f64,
        weights: [f64; 3],
    ) -> Self {
        let h = 1e-4 * d0;
        let mut m = [[DMat3::ZERO; 5]; 5];
        for j in 0..5 {
            if !live[j] {
                continue;
            }
            for axis in 0..3 {
                let (mut plus, mut minus) = (geometry.y, geometry.y);
                plus[j][axis] += h;
                minus[j][axis] -= h;
                let fp = geometry.forces(&plus, k, d0);
                let fm = geometry.forces(&minus, k, d0);
                for i in 0..5 {
                    *m[i][j].col_mut(axis) = (fm[i] - fp[i]) / (2.0 * h);
                }
            }
        }
        let u = geometry.u;
        ContactBlock {
            particles,
            live,
            m,
            k: stiffness,
            c: [u[0], u[1], -weights[0], -weights[1], -weights[2]],
        }
    }

    /// `out += m v` on the live entries.
    fn apply(&self, v: &[DVec3], out: &mut [DVec3]) {
        for i in 0..5 {
            if !self.live[i] {
                continue;
            }
            let mut sum = DVec3::ZERO;
            for j in 0..5 {
                if self.live[j] {
                    sum += self.m[i][j] * v[self.particles[j] as usize];
                }
            }
            out[self.particles[i] as usize] += sum;
        }
    }
}

/// Adds a point–triangle contact's forces to the residual `s.r` (on its live entries) and
/// its block to `s.blocks`.
fn push_contact(
    s: &mut Scratch,
    particles: [u32; 5],
    live: [bool; 5],
    geometry: &PointTriangle,
    (k, d0): (f64, f64),
    gap: f32,
    bary: [f32; 3],
) {
    let forces = geometry.forces(&geometry.y, k, d0);
    for ((&q, &l), f) in particles.iter().zip(&live).zip(forces) {
        if l {
            s.r[q as usize] += f;
        }
    }
    let (_, stiffness) = penalty(k, d0 as f32, gap);
    s.blocks.push(ContactBlock::new(
        particles,
        live,
        geometry,
        (k, d0),
        stiffness,
        bary.map(f64::from),
    ));
}

/// The model's Hessian at the current positions, applied without assembling it (the
/// operator of a step's conjugate gradients): every spring's `k d dᵀ + k·max(0, 1 − l₀/l)
/// (I − d dᵀ)` (positive semidefinite: a compressed spring's negative part dropped), the
/// anchors' `k I`, the slab's shear `k (I − n nᵀ)`, the hinges' Gauss–Newton `2k g gᵀ`,
/// eq. (5)'s rank-one term, the fill's `K/V₀ ∇V ∇Vᵀ − p ∇²V`, and the contacts.
#[derive(Default)]
struct Hessian {
    /// `(a, b, d, k, k_t)`.
    springs: Vec<(u32, u32, DVec3, f64, f64)>,
    anchors: Vec<(u32, f64)>,
    /// `(outer, inner, n, k)`.
    shear: Vec<(u32, u32, DVec3, f64)>,
    /// `(particles, gradient, 2k)`.
    hinges: Vec<([u32; 4], [DVec3; 4], f64)>,
    /// eq. (5): `(particle, cᵢuᵢ)`, `k_v/3`, `C k_v`.
    radial: Vec<(u32, DVec3)>,
    radial_k: (f64, f64),
    /// The fill: `(particle, ∇ᵢV)`, `K/V₀`.
    fill: Vec<(u32, DVec3)>,
    fill_k: f64,
    /// The fill's surface (particle indices), its positions relative to its first vertex, and
    /// its pressure: the geometric term `−p ∇²V` of the fill's Hessian.
    fill_triangles: Vec<[u32; 3]>,
    fill_positions: Vec<DVec3>,
    fill_pressure: f64,
    /// Layer 2's vertex normals, unnormalised (the shear's `n` is this normalised).
    inner_normals: Vec<DVec3>,
    /// Layer 2's triangles (region vertices) and positions, and the slab vectors `x₁ − x₂`:
    /// the shear force's dependence on layer 2's normal, `k (dn (n·s) + n (dn·s))`, whose
    /// `dn` is the normal's change under a displacement of layer 2 (not symmetric).
    inner_triangles: Vec<[u32; 3]>,
    inner_positions: Vec<DVec3>,
    slab: Vec<DVec3>,
}

impl Hessian {
    /// `out = H v`; `dn` is scratch of one entry per region vertex.
    fn apply(
        &self,
        contacts: &[Contact],
        free: &[bool],
        v: &[DVec3],
        out: &mut [DVec3],
        dn: &mut [DVec3],
    ) {
        out.iter_mut().for_each(|o| *o = DVec3::ZERO);
        for &(a, b, d, k, kt) in &self.springs {
            let dv = v[b as usize] - v[a as usize];
            let along = d.dot(dv);
            let f = d * (k * along) + (dv - d * along) * kt;
            out[a as usize] -= f;
            out[b as usize] += f;
        }
        for &(p, k) in &self.anchors {
            out[p as usize] += v[p as usize] * k;
        }
        for &(o, i, n, k) in &self.shear {
            let dv = v[o as usize] - v[i as usize];
            let f = (dv - n * n.dot(dv)) * k;
            out[o as usize] += f;
            out[i as usize] -= f;
        }
        if !self.inner_triangles.is_empty() {
            // The normal's turn: dN = Σ (dvb − dva) × (c − a) + (b − a) × (dvc − dva) over
            // the triangles around each vertex, dn = (I − n nᵀ) dN / |N|.
            dn.iter_mut().for_each(|d| *d = DVec3::ZERO);
            for tri in &self.inner_triangles {
                let [a, b, c] = tri.map(|r| self.inner_positions[r as usize]);
                let [va, vb, vc] = tri.map(|r| v[TissueLayers::particle(Layer::Inner, r) as usize]);
                let d = (vb - va).cross(c - a) + (b - a).cross(vc - va);
                for &r in tri {
                    dn[r as usize] += d;
                }
            }
            for (r, &(o, i, n, k)) in self.shear.iter().enumerate() {
                let len = self.inner_normals[r].length();
                if k == 0.0 || len <= 0.0 {
                    continue;
                }
                let d = (dn[r] - n * n.dot(dn[r])) / len;
                let s = self.slab[r];
                let g = (d * n.dot(s) + n * d.dot(s)) * k;
                out[o as usize] -= g;
                out[i as usize] += g;
            }
        }
        for (particles, grad, k) in &self.hinges {
            let s: f64 = particles
                .iter()
                .zip(grad)
                .map(|(&p, g)| g.dot(v[p as usize]))
                .sum();
            for (&p, g) in particles.iter().zip(grad) {
                out[p as usize] += *g * (k * s);
            }
        }
        if !self.radial.is_empty() {
            let (k3, kc) = self.radial_k;
            let s: f64 = self.radial.iter().map(|(p, w)| w.dot(v[*p as usize])).sum();
            for &(p, w) in &self.radial {
                out[p as usize] += w * (k3 * s) + w * (kc * w.dot(v[p as usize]));
            }
        }
        if !self.fill.is_empty() {
            let s: f64 = self.fill.iter().map(|(p, g)| g.dot(v[*p as usize])).sum();
            for &(p, g) in &self.fill {
                out[p as usize] += g * (self.fill_k * s);
            }
            {
                let scale = -self.fill_pressure / 6.0;
                for t in &self.fill_triangles {
                    let [a, b, c] = t.map(|p| self.fill_positions[p as usize]);
                    let [va, vb, vc] = t.map(|p| v[p as usize]);
                    out[t[0] as usize] += (vb.cross(c) + b.cross(vc)) * scale;
                    out[t[1] as usize] += (vc.cross(a) + c.cross(va)) * scale;
                    out[t[2] as usize] += (va.cross(b) + a.cross(vb)) * scale;
                }
            }
        }
        for c in contacts {
            c.apply(v, out);
        }
        for (o, &f) in out.iter_mut().zip(free) {
            if !f {
                *o = DVec3::ZERO;
            }
        }
    }
}

/// Particles `0..tissue` are the layers', `tissue..` the body's.
struct Scratch {
    tissue: usize,
    r: Vec<DVec3>,
    dx: Vec<DVec3>,
    grad: Vec<Vec3A>,
    x: Vec<f64>,
    g: Vec<f64>,
    diagonal: Vec<f64>,
    contacts: Vec<Contact>,
    blocks: Vec<ContactBlock>,
    /// Whether each layer-2 vertex found the dome within reach (its edges are sampled).
    near: Vec<bool>,
    ws: BvhWorkspace,
    hessian: Hessian,
    free: Vec<bool>,
    /// The contacts' stiffness on the preconditioner's diagonal.
    extra: Vec<(u32, f64)>,
    /// The linear solver's workspace, the fill's Sherman–Morrison vector, scratch.
    gmres: Gmres,
    w: Vec<DVec3>,
    z: Vec<DVec3>,
    dn: Vec<DVec3>,
}

/// One phase of the solve: which body particles are free, and the factored matrix for them.
struct Phase {
    pre: Preconditioner,
    body_free: bool,
}

/// The triangles of the body's dome (every triangle with a free vertex of the body) and of
/// layer 2 (in tissue particle indices).
struct Surfaces {
    dome: Vec<[u32; 3]>,
    dome_bvh: Bvh,
    inner: Vec<[u32; 3]>,
    inner_bvh: Bvh,
    /// Area-weighted vertex normals of the body (per body particle) and of layer 2 (per
    /// region vertex), at the current positions.
    dome_normals: Vec<Vec3A>,
    inner_normals: Vec<Vec3A>,
    /// The body's dome particles (free once the body is released), held below layer 2.
    points: Vec<u32>,
    /// Layer 2's vertex count and edges (region vertices).
    near_len: usize,
    inner_edges: Vec<[u32; 2]>,
}

/// `out[v]` = the area-weighted normal of `triangles` at vertex `v / stride` (unnormalised).
fn vertex_normals(triangles: &[[u32; 3]], positions: &[Vec3A], stride: u32, out: &mut [Vec3A]) {
    out.iter_mut().for_each(|n| *n = Vec3A::ZERO);
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let n = (b - a).cross(c - a);
        for &v in t {
            if let Some(o) = out.get_mut((v / stride) as usize) {
                *o += n;
            }
        }
    }
}

/// Where layer 2's edges near the dome are sampled (fractions from one end).
const EDGE_SAMPLES: [f64; 3] = [0.25, 0.5, 0.75];

/// The shortest step the line search tries, as a fraction of the Newton step.
const MIN_STEP: f64 = 1.0 / 16.0;

/// The Krylov iterations of one step's linear solve, at most.
const KRYLOV_ITERATIONS: u32 = 60;

/// The Krylov space of one GMRES cycle.
const GMRES_RESTART: usize = 30;

/// A step's linear solve stops when its residual has fallen by this factor.
const FORCING: f64 = 0.05;

/// The contact penalty's force and stiffness at `gap` (cm) for a contact of stiffness `k`
/// acting within `d0`: `f = k·(d₀ − s)²/d₀`, smooth where it starts (its stiffness
/// `2k(d₀ − s)/d₀` rises from zero at `s = d₀` to `2k` at contact), so that particles near
/// the contact distance do not switch a stiff force on and off between iterations.
fn penalty(k: f64, d0: f32, gap: f32) -> (f64, f64) {
    let (d0, gap) = (f64::from(d0), f64::from(gap));
    let depth = (d0 - gap).max(0.0);
    (k * depth * depth / d0, 2.0 * k * depth / d0)
}

impl Surfaces {
    /// The dome point closest to `x` within `reach`: its triangle, barycentric weights, the
    /// dome's normal there (interpolated from its vertex normals: continuous across edges, so a
    /// particle sliding over the dome sees no jump in its contact's direction) and `x`'s gap
    /// along it. Needs `dome_bvh` refitted and `dome_normals` computed at `body`.
    fn dome_contact(
        &self,
        dome: &Triangles<'_>,
        body: &[Vec3A],
        x: Vec3A,
        reach: f32,
        ws: &mut BvhWorkspace,
    ) -> Option<([u32; 3], [f32; 3], Vec3A, f32)> {
        let hit = self.dome_bvh.closest_point(dome, x, reach, ws)?;
        let tri = self.dome[hit.primitive as usize];
        let [a, b, c] = tri.map(|v| body[v as usize]);
        let (q, bary) = closest_point_on_triangle(x, a, b, c);
        let normal = (0..3)
            .map(|i| self.dome_normals[tri[i] as usize] * bary[i])
            .sum::<Vec3A>()
            .normalize_or_zero();
        Some((tri, bary, normal, (x - q).dot(normal)))
    }
}

fn search(source: tissue_bvh::BvhError) -> ImplantError {
    ImplantError::Search {
        surface: crate::SearchedSurface::RegionInnerLayer,
        source,
    }
}

impl ContactRun {
    /// The constant part of the matrix: the springs, anchors, slab shear, hinges and eq. (5).
    fn stiffness(&self, body_free: bool) -> (StiffnessBuilder, Vec<f64>) {
        let tissue = self.layers.system();
        let t = tissue.particles().len();
        let m = self.body.particles().len();
        let tissue_inv = tissue.particles().inverse_masses();
        let body_inv = self.body.particles().inverse_masses();
        let fixed = |p: u32| {
            let p = p as usize;
            if p < t {
                tissue_inv[p] == 0.0
            } else {
                !body_free || body_inv[p - t] == 0.0
            }
        };
        let mut b = StiffnessBuilder::new(t + m, fixed);
        let mut diagonal = vec![0.0f64; t + m];
        let mut spring = |b: &mut StiffnessBuilder, a: u32, c: u32, k: f64| {
            b.spring(a, c, k);
            diagonal[a as usize] += k;
            diagonal[c as usize] += k;
        };
        for s in tissue.springs() {
            spring(&mut b, s.a, s.b, f64::from(s.k));
        }
        for (r, &k) in self.layers.shear.iter().enumerate() {
            let outer = TissueLayers::particle(Layer::Outer, r as u32);
            spring(&mut b, outer, outer + 1, f64::from(k));
        }
        for s in self.body.springs() {
            spring(&mut b, s.a + t as u32, s.b + t as u32, f64::from(s.k));
        }
        for (p, k) in tissue.anchor_stiffnesses() {
            b.diagonal(p, f64::from(k));
            diagonal[p as usize] += f64::from(k);
        }
        for v in self.body.volume_preservations() {
            for (p, k) in v.diagonal_stiffness() {
                b.diagonal(p + t as u32, k);
                diagonal[p as usize + t] += k;
            }
        }
        let positions = tissue.particles().positions();
        for h in &self.layers.hinges {
            let x = h.particles.map(|i| positions[i as usize]);
            let Some((_, grad)) = crate::bending::angle_and_gradient(x) else {
                continue;
            };
            let reference = grad[2].normalize_or_zero();
            let c = grad.map(|g| f64::from(g.dot(reference)));
            b.coupling(&h.particles, &c, 2.0 * f64::from(h.k));
            for (&p, &ci) in h.particles.iter().zip(&c) {
                diagonal[p as usize] += 2.0 * f64::from(h.k) * ci * ci;
            }
        }
        (b, diagonal)
    }

    fn surfaces(&self) -> Result<Surfaces, ImplantError> {
        let dome: Vec<[u32; 3]> = self
            .body_triangles
            .iter()
            .copied()
            .filter(|t| t.iter().any(|&v| self.dome_vertex[v as usize]))
            .collect();
        let inner: Vec<[u32; 3]> = self
            .layers
            .rest(Layer::Inner)
            .triangles()
            .iter()
            .map(|t| t.map(|r| TissueLayers::particle(Layer::Inner, r)))
            .collect();
        let body_p = self.body.particles().positions();
        let tissue_p = self.layers.system().particles().positions();
        let options = BuildOptions::default();
        let dome_bvh = Bvh::build(&Triangles::new(body_p, &dome).map_err(search)?, &options)
            .map_err(search)?;
        let inner_bvh = Bvh::build(&Triangles::new(tissue_p, &inner).map_err(search)?, &options)
            .map_err(search)?;
        let points: Vec<u32> = (0..body_p.len() as u32)
            .filter(|&v| self.dome_vertex[v as usize])
            .collect();
        let inner_mesh = self.layers.rest(Layer::Inner);
        Ok(Surfaces {
            near_len: inner_mesh.vertex_count(),
            inner_edges: inner_mesh.topology().edges().to_vec(),
            points,
            dome,
            dome_bvh,
            inner,
            inner_bvh,
            dome_normals: vec![Vec3A::ZERO; body_p.len()],
            inner_normals: vec![Vec3A::ZERO; self.layers.rest(Layer::Inner).vertex_count()],
        })
    }

    /// The net force on every particle at the current positions, contacts included, into
    /// `s.r` (zero on fixed particles); the active contacts' stiffness into `s.contacts`.
    /// Returns `(contacts, thinned)`.
    fn residual(
        &mut self,
        surfaces: &mut Surfaces,
        s: &mut Scratch,
        params: &StaticParams,
        body_free: bool,
    ) -> Result<(u32, u32), ImplantError> {
        let _span = tracing::trace_span!("static_residual").entered();
        let t = s.tissue;
        self.layers.compute_forces();
        self.body.compute_forces();
        let tissue = self.layers.system().particles();
        let body = self.body.particles();
        for (i, (f, &w)) in tissue
            .forces()
            .iter()
            .zip(tissue.inverse_masses())
            .enumerate()
        {
            s.r[i] = if w > 0.0 { f.as_dvec3() } else { DVec3::ZERO };
        }
        for (v, (f, &w)) in body.forces().iter().zip(body.inverse_masses()).enumerate() {
            s.r[t + v] = if body_free && w > 0.0 {
                f.as_dvec3()
            } else {
                DVec3::ZERO
            };
        }
        s.contacts.clear();
        s.blocks.clear();
        let d0 = self.contact_distance;
        let reach = d0 + self.static_reach;
        let tissue_p = tissue.positions();
        let body_p = body.positions();
        let tissue_w = tissue.inverse_masses();
        let body_w = body.inverse_masses();
        surfaces
            .dome_bvh
            .refit(&Triangles::new(body_p, &surfaces.dome).map_err(search)?)
            .map_err(search)?;
        surfaces
            .inner_bvh
            .refit(&Triangles::new(tissue_p, &surfaces.inner).map_err(search)?)
            .map_err(search)?;
        vertex_normals(&surfaces.dome, body_p, 1, &mut surfaces.dome_normals);
        vertex_normals(&surfaces.inner, tissue_p, 2, &mut surfaces.inner_normals);
        let dome = Triangles::new(body_p, &surfaces.dome).map_err(search)?;
        let inner = Triangles::new(tissue_p, &surfaces.inner).map_err(search)?;
        let mut contacts = 0u32;
        let kc = params.contact_stiffness;
        // Layer 2 against the dome: its particles, then the midpoints of its edges near the
        // dome (an edge can cross the dome's bulge between two particles that lie outside).
        let d0f = f64::from(d0);
        let dome_normals = |tri: [u32; 3]| {
            tri.map(|v| {
                surfaces.dome_normals[v as usize]
                    .as_dvec3()
                    .normalize_or_zero()
            })
        };
        let body_live = |v: u32| body_free && body_w[v as usize] > 0.0;
        s.near.iter_mut().for_each(|n| *n = false);
        let points = (0..surfaces.near_len as u32).map(|r| ([r, r], 1.0)).chain(
            surfaces
                .inner_edges
                .iter()
                .flat_map(|&e| EDGE_SAMPLES.map(|f| (e, f))),
        );
        for ([ra, rb], along) in points {
            let edge = ra != rb;
            if edge && !(s.near[ra as usize] || s.near[rb as usize]) {
                continue;
            }
            let (pa, pb) = (
                TissueLayers::particle(Layer::Inner, ra),
                TissueLayers::particle(Layer::Inner, rb),
            );
            let (la, lb) = (tissue_w[pa as usize] > 0.0, tissue_w[pb as usize] > 0.0);
            if !(la || lb) {
                continue;
            }
            let u = [along, 1.0 - along];
            let x = tissue_p[pa as usize] * u[0] as f32 + tissue_p[pb as usize] * u[1] as f32;
            let Some((tri, bary, _, gap)) =
                surfaces.dome_contact(&dome, body_p, x, reach, &mut s.ws)
            else {
                continue;
            };
            if !edge {
                s.near[ra as usize] = true;
            }
            if gap >= d0 {
                continue;
            }
            let geometry = PointTriangle {
                y: [
                    tissue_p[pa as usize].as_dvec3(),
                    tissue_p[pb as usize].as_dvec3(),
                    body_p[tri[0] as usize].as_dvec3(),
                    body_p[tri[1] as usize].as_dvec3(),
                    body_p[tri[2] as usize].as_dvec3(),
                ],
                u,
                normals: dome_normals(tri),
                side: 1.0,
            };
            let k = kc * s.diagonal[pa as usize].max(s.diagonal[pb as usize]);
            let particles = [
                pa,
                pb,
                t as u32 + tri[0],
                t as u32 + tri[1],
                t as u32 + tri[2],
            ];
            let live = [
                la,
                lb && edge,
                body_live(tri[0]),
                body_live(tri[1]),
                body_live(tri[2]),
            ];
            push_contact(s, particles, live, &geometry, (k, d0f), gap, bary);
            contacts += 1;
        }
        // The body's free particles against layer 2.
        if body_free {
            for &v in &surfaces.points {
                if body_w[v as usize] == 0.0 {
                    continue;
                }
                let x = body_p[v as usize];
                let Some(hit) = surfaces
                    .inner_bvh
                    .closest_point(&inner, x, reach, &mut s.ws)
                else {
                    continue;
                };
                let tri = surfaces.inner[hit.primitive as usize];
                let [a, b, c] = tri.map(|p| tissue_p[p as usize]);
                let (q, bary) = closest_point_on_triangle(x, a, b, c);
                let face = (0..3)
                    .map(|i| surfaces.inner_normals[tri[i] as usize / 2] * bary[i])
                    .sum::<Vec3A>()
                    .normalize_or_zero();
                // The body lies below layer 2 (layer 2's normal points out of the body).
                let gap = (q - x).dot(face);
                if gap >= d0 {
                    continue;
                }
                let geometry = PointTriangle {
                    y: [
                        x.as_dvec3(),
                        x.as_dvec3(),
                        a.as_dvec3(),
                        b.as_dvec3(),
                        c.as_dvec3(),
                    ],
                    u: [1.0, 0.0],
                    normals: tri.map(|p| {
                        surfaces.inner_normals[p as usize / 2]
                            .as_dvec3()
                            .normalize_or_zero()
                    }),
                    side: -1.0,
                };
                let k = kc * s.diagonal[t + v as usize];
                let particles = [t as u32 + v, t as u32 + v, tri[0], tri[1], tri[2]];
                let live = tri.map(|p| tissue_w[p as usize] > 0.0);
                let live = [true, false, live[0], live[1], live[2]];
                push_contact(s, particles, live, &geometry, (k, d0f), gap, bary);
                contacts += 1;
            }
        }
        // Layer 1 held off layer 2.
        let thinned = self
            .layers
            .thickness_forces(kc, &s.diagonal, &mut s.r, &mut s.contacts);
        Ok((contacts, thinned))
    }

    /// The load step's predictor: every free layer-2 particle closer than the contact distance
    /// to the body (or inside it) is moved out along the body's normal to the contact
    /// distance, and its layer-1 partner with it, so that a step starts with the tissue on the
    /// body instead of through it. From inside a sphere the closest point is the radial one, so
    /// the press's sheet keeps its order.
    fn project_out(&mut self, surfaces: &mut Surfaces) -> Result<(), ImplantError> {
        let d0 = self.contact_distance;
        let reach = d0 + self.static_reach;
        let body_p = self.body.particles().positions();
        surfaces
            .dome_bvh
            .refit(&Triangles::new(body_p, &surfaces.dome).map_err(search)?)
            .map_err(search)?;
        vertex_normals(&surfaces.dome, body_p, 1, &mut surfaces.dome_normals);
        let dome = Triangles::new(body_p, &surfaces.dome).map_err(search)?;
        let mut ws = BvhWorkspace::default();
        let n = self.layers.rest(Layer::Inner).vertex_count() as u32;
        let tissue = self.layers.system_mut().particles_mut();
        let (position, _, inverse_mass) = tissue.state_mut();
        for r in 0..n {
            let p = TissueLayers::particle(Layer::Inner, r) as usize;
            if inverse_mass[p] == 0.0 {
                continue;
            }
            let Some((_, _, normal, gap)) =
                surfaces.dome_contact(&dome, body_p, position[p], reach, &mut ws)
            else {
                continue;
            };
            if gap < d0 {
                let shift = normal * (d0 - gap);
                position[p] += shift;
                let outer = TissueLayers::particle(Layer::Outer, r) as usize;
                if inverse_mass[outer] > 0.0 {
                    position[outer] += shift;
                }
            }
        }
        Ok(())
    }

    /// Solves the current load for its equilibrium to `tolerance` (module docs), starting from
    /// the current positions; `iterations` counts on across calls. Returns whether it
    /// converged and the last residual (dimensionless, and in g·cm/s²).
    #[allow(clippy::too_many_arguments)]
    fn solve_load(
        &mut self,
        phase: &mut Phase,
        surfaces: &mut Surfaces,
        s: &mut Scratch,
        params: &StaticParams,
        tolerance: f64,
        iterations: &mut u64,
        mut progress: impl FnMut(u64, StepSummary) -> Result<(), ImplantError>,
    ) -> Result<(bool, f64, f64), ImplantError> {
        let body_free = phase.body_free;
        let t = s.tissue;
        let mean_edge = f64::from(self.mean_edge);
        // The line search: the last accepted point's residual norm, and the step's length.
        let mut accepted: Option<f64> = None;
        let mut alpha = 1.0f64;
        loop {
            let (contacts, thinned) = self.residual(surfaces, s, params, body_free)?;
            let (mut worst, mut worst_n, mut norm) = (0.0f64, 0.0f64, 0.0f64);
            let mut worst_at = 0usize;
            for (idx, (r, &d)) in s.r.iter().zip(&s.diagonal).enumerate() {
                let f = r.length();
                if !f.is_finite() {
                    return Err(ImplantError::Diverged {
                        step: *iterations,
                        particle: 0,
                        what: "quasi-static residual",
                    });
                }
                if d > 0.0 {
                    norm += (f / (d * mean_edge)).powi(2);
                }
                if d > 0.0 && f / (d * mean_edge) > worst {
                    worst = f / (d * mean_edge);
                    worst_at = idx;
                }
                worst_n = worst_n.max(f);
            }
            tracing::trace!(
                iteration = *iterations,
                body_free,
                residual = worst,
                force = worst_n,
                contacts,
                thinned,
                worst_at,
                "quasi-static iteration"
            );
            if worst <= tolerance {
                return Ok((true, worst, worst_n));
            }
            if *iterations >= params.max_iterations {
                return Ok((false, worst, worst_n));
            }
            let backtrack = accepted.is_some_and(|a| norm > a) && alpha > MIN_STEP;
            if backtrack {
                // Back along the last step, from the accepted point.
                alpha *= 0.5;
                for (i, d) in s.dx.iter().enumerate() {
                    let from = DVec3::from_slice(&s.g[3 * i..3 * i + 3]);
                    s.x[3 * i..3 * i + 3].copy_from_slice(&(from + *d * alpha).to_array());
                }
            } else {
                accepted = Some(norm);
                alpha = 1.0;
                self.newton_step(phase, s)?;
                // x and G(x) = x + dx, flat; `g` keeps the accepted point for a backtrack.
                let tissue_p = self.layers.system().particles().positions();
                let body_p = self.body.particles().positions();
                for (i, p) in tissue_p.iter().chain(body_p).enumerate() {
                    let p = p.as_dvec3();
                    let d = s.dx[i];
                    s.g[3 * i..3 * i + 3].copy_from_slice(&p.to_array());
                    s.x[3 * i..3 * i + 3].copy_from_slice(&(p + d).to_array());
                }
            }
            let mut moved = 0.0f64;
            {
                let tissue = self.layers.system_mut().particles_mut();
                let (pos, _, inv) = tissue.state_mut();
                for (i, (p, &w)) in pos.iter_mut().zip(inv).enumerate() {
                    if w > 0.0 {
                        let new = Vec3A::new(
                            s.x[3 * i] as f32,
                            s.x[3 * i + 1] as f32,
                            s.x[3 * i + 2] as f32,
                        );
                        moved += f64::from(new.distance(*p));
                        *p = new;
                    }
                }
            }
            if body_free {
                let body = self.body.particles_mut();
                let (pos, _, inv) = body.state_mut();
                for (v, (p, &w)) in pos.iter_mut().zip(inv).enumerate() {
                    let i = t + v;
                    if w > 0.0 {
                        let new = Vec3A::new(
                            s.x[3 * i] as f32,
                            s.x[3 * i + 1] as f32,
                            s.x[3 * i + 2] as f32,
                        );
                        moved += f64::from(new.distance(*p));
                        *p = new;
                    }
                }
            }
            let step = *iterations;
            *iterations += 1;
            progress(
                step,
                StepSummary {
                    step,
                    displacement: moved,
                    contacts,
                    remaining_crossings: 0,
                    thinned,
                },
            )?;
        }
    }

    /// The Hessian at the current positions into `s.hessian`, and which particles are free.
    fn hessian(&self, body_free: bool, s: &mut Scratch) {
        let t = s.tissue;
        let h = &mut s.hessian;
        let tissue = self.layers.system();
        let tp = tissue.particles().positions();
        let bp = self.body.particles().positions();
        let position = |p: u32| {
            if (p as usize) < t {
                tp[p as usize].as_dvec3()
            } else {
                bp[p as usize - t].as_dvec3()
            }
        };
        let weights = tissue
            .particles()
            .inverse_masses()
            .iter()
            .chain(self.body.particles().inverse_masses());
        for (f, &w) in s.free.iter_mut().zip(weights) {
            *f = w > 0.0;
        }
        if !body_free {
            s.free[t..].iter_mut().for_each(|f| *f = false);
        }
        h.springs.clear();
        let body_springs = self
            .body
            .springs()
            .iter()
            .map(|sp| (sp.a + t as u32, sp.b + t as u32, sp.rest, sp.k));
        for (a, b, rest, k) in tissue
            .springs()
            .iter()
            .map(|sp| (sp.a, sp.b, sp.rest, sp.k))
            .chain(body_springs)
        {
            let d = position(b) - position(a);
            let l = d.length();
            let k = f64::from(k);
            if l <= 0.0 {
                h.springs.push((a, b, DVec3::ZERO, 0.0, k));
                continue;
            }
            let kt = k * (1.0 - f64::from(rest) / l);
            h.springs.push((a, b, d / l, k, kt));
        }
        if h.anchors.is_empty() {
            h.anchors
                .extend(tissue.anchor_stiffnesses().map(|(p, k)| (p, f64::from(k))));
        }
        h.shear.clear();
        let inner = self.layers.rest(Layer::Inner);
        let normals = &mut h.inner_normals;
        normals.clear();
        normals.resize(inner.vertex_count(), DVec3::ZERO);
        for tri in inner.triangles() {
            let [a, b, c] = tri.map(|r| position(TissueLayers::particle(Layer::Inner, r)));
            let n = (b - a).cross(c - a);
            for &r in tri {
                normals[r as usize] += n;
            }
        }
        for (r, (&k, n)) in self
            .layers
            .shear
            .iter()
            .zip(h.inner_normals.iter())
            .enumerate()
        {
            let outer = TissueLayers::particle(Layer::Outer, r as u32);
            h.shear
                .push((outer, outer + 1, n.normalize_or_zero(), f64::from(k)));
        }
        if h.inner_triangles.is_empty() {
            h.inner_triangles.extend_from_slice(inner.triangles());
        }
        h.inner_positions.clear();
        h.slab.clear();
        for r in 0..inner.vertex_count() as u32 {
            let o = position(TissueLayers::particle(Layer::Outer, r));
            let i = position(TissueLayers::particle(Layer::Inner, r));
            h.inner_positions.push(i);
            h.slab.push(o - i);
        }
        h.hinges.clear();
        for hinge in &self.layers.hinges {
            let x = hinge.particles.map(|i| tp[i as usize]);
            if let Some((_, grad)) = crate::bending::angle_and_gradient(x) {
                h.hinges.push((
                    hinge.particles,
                    grad.map(|g| g.as_dvec3()),
                    2.0 * f64::from(hinge.k),
                ));
            }
        }
        h.radial.clear();
        h.fill.clear();
        if body_free {
            let body = self.body.particles();
            if let Some(v) = self.body.volume_preservations().first() {
                v.weighted_directions(body.positions(), body.masses(), &mut h.radial);
                for (p, _) in h.radial.iter_mut() {
                    *p += t as u32;
                }
                let (kv, c) = v.constants();
                h.radial_k = (kv / 3.0, c * kv);
            }
            if let Some(pressure) = self.body.volume_pressures().first() {
                h.fill_triangles.clear();
                h.fill_triangles.extend(
                    pressure
                        .triangles()
                        .iter()
                        .map(|tri| tri.map(|v| v + t as u32)),
                );
                let origin = body
                    .positions()
                    .first()
                    .map_or(DVec3::ZERO, |p| p.as_dvec3());
                h.fill_positions.clear();
                h.fill_positions.extend((0..t).map(|_| DVec3::ZERO));
                h.fill_positions
                    .extend(body.positions().iter().map(|p| p.as_dvec3() - origin));
                h.fill_pressure = pressure.pressure(body.positions());
                s.grad.iter_mut().for_each(|g| *g = Vec3A::ZERO);
                pressure.add_gradient(body.positions(), &mut s.grad);
                h.fill_k = pressure.bulk_modulus() / pressure.rest_volume();
                h.fill.extend(
                    s.grad
                        .iter()
                        .enumerate()
                        .map(|(v, g)| ((v + t) as u32, g.as_dvec3())),
                );
            }
        }
    }

    /// `s.dx ≈ A⁻¹ s.r` by conjugate gradients preconditioned with `P⁻¹`: `A = P + the
    /// contacts' Hessian (anisotropic, `k n nᵀ` on their relative normal displacement) + the
    /// fill's `α ∇V ∇Vᵀ`` (module docs). Returns the iterations.
    fn newton_step(&self, phase: &mut Phase, s: &mut Scratch) -> Result<u32, ImplantError> {
        self.hessian(phase.body_free, s);
        // The preconditioner: the Laplacian with every contact's stiffness on its particles'
        // diagonals (refactored), and the fill's rank-one term by Sherman–Morrison.
        s.extra.clear();
        for c in &s.contacts {
            for (&p, &ci) in c.particles.iter().zip(&c.c) {
                if ci != 0.0 {
                    s.extra.push((p, c.k * ci * ci));
                }
            }
        }
        for b in &s.blocks {
            for ((&p, &ci), &live) in b.particles.iter().zip(&b.c).zip(&b.live) {
                if live && ci != 0.0 {
                    s.extra.push((p, b.k * ci * ci));
                }
            }
        }

        phase.pre.refactor(&s.extra).map_err(ImplantError::Model)?;
        let (hessian, contacts, blocks, free) = (&s.hessian, &s.contacts, &s.blocks, &s.free);
        let fill: &[(u32, DVec3)] = &hessian.fill;
        let alpha = hessian.fill_k;
        let (w, z) = (&mut s.w, &mut s.z);
        let mut wg = 0.0;
        if !fill.is_empty() {
            z.iter_mut().for_each(|v| *v = DVec3::ZERO);
            for &(p, g) in fill {
                if free[p as usize] {
                    z[p as usize] = g;
                }
            }
            phase.pre.solve(z, w);
            wg = fill.iter().map(|&(p, g)| g.dot(w[p as usize])).sum();
        }
        let w: &[DVec3] = w;
        let pre = &mut phase.pre;
        let precondition = |r: &[DVec3], out: &mut [DVec3]| {
            pre.solve(r, out);
            if !fill.is_empty() {
                let gz: f64 = fill.iter().map(|&(p, g)| g.dot(out[p as usize])).sum();
                let scale = alpha * gz / (1.0 + alpha * wg);
                for (o, wi) in out.iter_mut().zip(w.iter()) {
                    *o -= *wi * scale;
                }
            }
        };
        let dn = &mut s.dn;
        let apply = |v: &[DVec3], out: &mut [DVec3]| {
            hessian.apply(contacts, free, v, out, dn);
            for b in blocks {
                b.apply(v, out);
            }
        };
        let (iterations, relative) = s.gmres.solve(
            apply,
            precondition,
            &s.r,
            &mut s.dx,
            FORCING,
            KRYLOV_ITERATIONS,
        );
        tracing::trace!(iterations, relative, "newton step's linear solve");
        Ok(iterations)
    }

    /// Solves the run for its static equilibrium (module docs): the body's kinematic phase
    /// ([`ContactRun::fill_body`]) in load steps, then, if `release`, the body free under its
    /// own forces. `progress` is called after every iteration with the iteration count.
    ///
    /// # Errors
    /// [`ImplantError::Diverged`] for a non-finite residual, [`ImplantError::Model`] when the
    /// matrix has no factor, search errors, and whatever `progress` returns.
    pub(crate) fn solve_static(
        &mut self,
        params: &StaticParams,
        release: bool,
        mut progress: impl FnMut(u64, StepSummary) -> Result<(), ImplantError>,
    ) -> Result<StaticReport, ImplantError> {
        let _span = tracing::info_span!("quasi_static").entered();
        params.check()?;
        let t = self.layers.system().particles().len();
        let m = self.body.particles().len();
        let mut surfaces = self.surfaces()?;
        let fill = self.fill.take();
        let mut iterations = 0u64;
        let new_scratch = |diagonal: Vec<f64>| Scratch {
            tissue: t,
            r: vec![DVec3::ZERO; t + m],
            dx: vec![DVec3::ZERO; t + m],
            grad: vec![Vec3A::ZERO; m],
            x: vec![0.0; 3 * (t + m)],
            g: vec![0.0; 3 * (t + m)],
            diagonal,
            contacts: Vec::new(),
            blocks: Vec::new(),
            near: vec![false; t / 2],
            ws: BvhWorkspace::default(),
            hessian: Hessian::default(),
            free: vec![false; t + m],
            extra: Vec::new(),
            gmres: Gmres::new(t + m, GMRES_RESTART),
            w: vec![DVec3::ZERO; t + m],
            z: vec![DVec3::ZERO; t + m],
            dn: vec![DVec3::ZERO; t / 2],
        };
        let mut last = (false, f64::INFINITY, f64::INFINITY);
        if let Some(fill) = fill {
            let (builder, diagonal) = self.stiffness(false);
            let mut phase = Phase {
                pre: builder.build().map_err(ImplantError::Model)?,
                body_free: false,
            };
            let mut s = new_scratch(diagonal);
            let start: Vec<Vec3A> = fill
                .particles
                .iter()
                .map(|&i| self.body.particles().positions()[i as usize])
                .collect();
            let steps = params.load_steps;
            // How far one load step moves the body: contacts must be found that deep.
            self.static_reach = start
                .iter()
                .zip(&fill.end)
                .map(|(a, b)| a.distance(*b))
                .fold(0.0f32, f32::max)
                / steps as f32;
            for j in 1..=steps {
                let f = j as f32 / steps as f32;
                {
                    let pos = self.body.particles_mut().positions_mut();
                    for ((&i, &a), &b) in fill.particles.iter().zip(&start).zip(&fill.end) {
                        pos[i as usize] = a + (b - a) * f;
                    }
                }
                self.project_out(&mut surfaces)?;
                let tolerance = if j == steps && !release {
                    params.tolerance
                } else {
                    params.load_tolerance
                };
                last = self.solve_load(
                    &mut phase,
                    &mut surfaces,
                    &mut s,
                    params,
                    tolerance,
                    &mut iterations,
                    &mut progress,
                )?;
            }
            let particles = self.body.particles_mut();
            for &i in &fill.particles {
                particles.velocities_mut()[i as usize] = Vec3A::ZERO;
                if release {
                    particles.release(i)?;
                }
            }
        }
        if release {
            self.static_reach = 4.0 * self.contact_distance;
            let (builder, diagonal) = self.stiffness(true);
            let mut phase = Phase {
                pre: builder.build().map_err(ImplantError::Model)?,
                body_free: true,
            };
            let mut s = new_scratch(diagonal);
            last = self.solve_load(
                &mut phase,
                &mut surfaces,
                &mut s,
                params,
                params.tolerance,
                &mut iterations,
                &mut progress,
            )?;
        }
        self.settled = last.0;
        self.steps += iterations;
        let report = StaticReport {
            iterations,
            residual: last.1,
            residual_n: last.2 * 1e-5,
            converged: last.0,
        };
        tracing::debug!(?report, "quasi-static solve");
        Ok(report)
    }
}
