//! The quasi-static solver: the tissue layers and the second body (the expander, or the plane
//! press's sphere) solved for their static equilibrium directly, instead of stepped to rest.
//!
//! **The model** is the explicit run's, term for term: both layers' Van Gelder springs, the
//! slab's vertical springs and shear, layer 2's anchors, layer 1's bending hinges, the
//! expander's shell springs, eq. (5) and its fill's pressure (`K·(V₀ − V)/V₀`, which holds the
//! volume to `p/K`), the fixed boundary and base. Only the contacts change form: the explicit
//! run stops approaching particles with impulses; here they are forces of a penalty that acts
//! within the contact distance `d₀`, both ways round:
//! - a layer-2 particle closer than `d₀` to the expander's dome (signed along the dome's
//!   normal interpolated from its vertex normals) is pushed out, the dome triangle's corners
//!   pushed back by the same force split by barycentric weights;
//! - an expander particle closer than `d₀` below layer 2 likewise;
//! - layer 1 closer than the thickness guard to layer 2 along layer 2's normal likewise
//!   (the explicit run's [`TissueLayers::hold_thickness`]).
//!
//! `k_c` is [`StaticParams::contact_stiffness`] times the particle's own stiffness (the
//! Laplacian's diagonal); the penalty `k_c·(d₀ − s)²/d₀` starts smoothly at `d₀`.
//!
//! **The solve** is Newton's method without assembling the Hessian: each step solves
//! `H dx = r` by conjugate gradients, `H` the model's Hessian at the current positions (every
//! spring's `k d dᵀ + k·max(0, 1 − l₀/l)(I − d dᵀ)`, the anchors, the slab's shear across the
//! normal, the hinges' Gauss–Newton `2k g gᵀ`, eq. (5)'s rank-one term, the fill's
//! `K/V₀ ∇V ∇Vᵀ − p ∇²V` (its pressure's geometric term is what lets 100 cm³ converge), the
//! contacts' `k n nᵀ` on their relative normal motion), preconditioned by the springs'
//! Laplacian with the anchors, shear, hinges and eq. (5) on its diagonal, factored once per
//! phase ([`tissue_mss::statics`], sparse Cholesky on faer: the local/global matrix of Liu et
//! al. 2013). A step whose residual norm grew is halved (down to 1/16) from the last accepted
//! point.
//!
//! **Load steps**: the expander fills from flat in [`StaticParams::load_steps`] steps with its
//! dome held where the fill has got to, each solved to [`StaticParams::load_tolerance`]; then it
//! is released to its own forces and everything is solved to [`StaticParams::tolerance`].
//!
//! **Status**: where it converges it agrees with the explicit run (Table 2: gain within 0.8 %,
//! volume difference within 1 %), but it does not yet converge reliably when the contacts
//! carry the expander's full pressure: Table 2 at 100 cm³ settles in a few hundred iterations
//! with layer-2 edges through the expander by 0.04 cm, 150 cm³ stagnates near 10⁻². The slab's
//! shear force, taken across layer 2's current normal, has a Jacobian this symmetric Newton
//! step leaves out (the normal's dependence on the neighbours), of the springs' order. It is
//! therefore not the default: docs/validation.md has the figures.
//!
//! **Stop**: on the residual, not a step count. The residual is the largest net force on a
//! free particle divided by the force that would move that particle by one mean edge against
//! its own stiffness (`P`'s diagonal × the mean layer-2 edge): a dimensionless step, so one
//! tolerance serves every mesh. It is reported with the force itself (N).

use glam::{DVec3, Vec3A};
use tissue_bvh::{closest_point_on_triangle, BuildOptions, Bvh, BvhWorkspace, Triangles};
use tissue_mss::{Preconditioner, StiffnessBuilder};

use crate::contact_run::{ContactRun, StepSummary};
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
    /// 54 iterations; stiffer contacts hold the larger volumes' layer 2 off the expander
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
    /// Layer 2's vertex normals (scratch).
    inner_normals: Vec<DVec3>,
}

impl Hessian {
    fn apply(&self, contacts: &[Contact], free: &[bool], v: &[DVec3], out: &mut [DVec3]) {
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
    ws: BvhWorkspace,
    hessian: Hessian,
    free: Vec<bool>,
    /// The contacts' stiffness on the preconditioner's diagonal.
    extra: Vec<(u32, f64)>,
    /// Conjugate-gradient vectors.
    cg: [Vec<DVec3>; 5],
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

/// The shortest step the line search tries, as a fraction of the Newton step.
const MIN_STEP: f64 = 1.0 / 16.0;

/// The conjugate-gradient iterations of one step, at most.
const CG_ITERATIONS: u32 = 200;

/// A step's linear solve stops when its residual has fallen by this factor.
const CG_FORCING: f64 = 0.05;

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
        Ok(Surfaces {
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
        // Layer 2 against the dome.
        let n = self.layers.rest(Layer::Inner).vertex_count() as u32;
        for r in 0..n {
            let p = TissueLayers::particle(Layer::Inner, r);
            if tissue_w[p as usize] == 0.0 {
                continue;
            }
            let x = tissue_p[p as usize];
            let Some((tri, bary, normal, gap)) =
                surfaces.dome_contact(&dome, body_p, x, reach, &mut s.ws)
            else {
                continue;
            };
            if gap >= d0 {
                continue;
            }
            let (f, k) = penalty(kc * s.diagonal[p as usize], d0, gap);
            let normal = normal.as_dvec3();
            let mut contact = Contact {
                particles: [p, 0, 0, 0],
                c: [1.0, 0.0, 0.0, 0.0],
                normal,
                k,
            };
            s.r[p as usize] += normal * f;
            for (i, (&v, &w)) in tri.iter().zip(&bary).enumerate() {
                if body_free && body_w[v as usize] > 0.0 {
                    s.r[t + v as usize] -= normal * (f * f64::from(w));
                    contact.particles[i + 1] = t as u32 + v;
                    contact.c[i + 1] = -f64::from(w);
                }
            }
            s.contacts.push(contact);
            contacts += 1;
        }
        // The dome's free particles against layer 2.
        if body_free {
            for (v, &x) in body_p.iter().enumerate() {
                if body_w[v] == 0.0 {
                    continue;
                }
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
                let (normal, gap) = (face, (q - x).dot(face));
                if gap >= d0 {
                    continue;
                }
                let (f, k) = penalty(kc * s.diagonal[t + v], d0, gap);
                let normal = normal.as_dvec3();
                let mut contact = Contact {
                    particles: [0, 0, 0, (t + v) as u32],
                    c: [0.0, 0.0, 0.0, -1.0],
                    normal,
                    k,
                };
                s.r[t + v] -= normal * f;
                for (i, (&p, &w)) in tri.iter().zip(&bary).enumerate() {
                    if tissue_w[p as usize] > 0.0 {
                        s.r[p as usize] += normal * (f * f64::from(w));
                        contact.particles[i] = p;
                        contact.c[i] = f64::from(w);
                    }
                }
                s.contacts.push(contact);
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
            let kt = (k * (1.0 - f64::from(rest) / l)).max(0.0);
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
        phase.pre.refactor(&s.extra).map_err(ImplantError::Model)?;
        let [res, z, p, ap, w] = &mut s.cg;
        let (hessian, contacts, free) = (&s.hessian, &s.contacts, &s.free);
        let dot = |a: &[DVec3], b: &[DVec3]| a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum::<f64>();
        let fill: &[(u32, DVec3)] = &hessian.fill;
        let alpha = hessian.fill_k;
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
        let precondition = |pre: &mut Preconditioner, r: &[DVec3], out: &mut [DVec3]| {
            pre.solve(r, out);
            if !fill.is_empty() {
                let gz: f64 = fill.iter().map(|&(p, g)| g.dot(out[p as usize])).sum();
                let scale = alpha * gz / (1.0 + alpha * wg);
                for (o, wi) in out.iter_mut().zip(w.iter()) {
                    *o -= *wi * scale;
                }
            }
        };
        s.dx.iter_mut().for_each(|d| *d = DVec3::ZERO);
        res.copy_from_slice(&s.r);
        let r0 = dot(res, res).sqrt();
        precondition(&mut phase.pre, res, z);
        p.copy_from_slice(z);
        let mut rz = dot(res, z);
        let mut iterations = 0;
        while iterations < CG_ITERATIONS {
            hessian.apply(contacts, free, p, ap);
            let pap = dot(p, ap);
            if pap.is_nan() || pap <= 0.0 {
                break;
            }
            let a = rz / pap;
            for ((d, r), (pi, api)) in
                s.dx.iter_mut()
                    .zip(res.iter_mut())
                    .zip(p.iter().zip(ap.iter()))
            {
                *d += *pi * a;
                *r -= *api * a;
            }
            iterations += 1;
            if dot(res, res).sqrt() <= CG_FORCING * r0 {
                break;
            }
            precondition(&mut phase.pre, res, z);
            let rz_new = dot(res, z);
            let beta = rz_new / rz;
            rz = rz_new;
            for (pi, zi) in p.iter_mut().zip(z.iter()) {
                *pi = *zi + *pi * beta;
            }
        }
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
            ws: BvhWorkspace::default(),
            hessian: Hessian::default(),
            free: vec![false; t + m],
            extra: Vec::new(),
            cg: std::array::from_fn(|_| vec![DVec3::ZERO; t + m]),
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
