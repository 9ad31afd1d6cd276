//! Self-collision of a body's surface (issue 35): vertex–triangle proximity with a thickness,
//! found with a [`tissue_bvh::Bvh`] over the surface's triangles, projected inside the solver's
//! iterations as unilateral position constraints with Coulomb friction.
//!
//! ## The surface
//! The faces used by one tet only (the boundary of the current tets, so the faces a cut opens
//! are in it: a cut duplicates nodes and gives the two walls distinct faces), wound outward
//! ([`tissue_mesh::TET_FACES`] on positively oriented tets). Rebuilt, with its hierarchy, after
//! any topology edit (`duplicate_nodes`, `set_tet_nodes`, `add_tet`: that step allocates);
//! otherwise the hierarchy over the triangles' swept boxes is refit every step.
//!
//! ## Thickness and detection
//! `h` = [`SelfCollision::thickness_fraction`] × the mean rest length of the surface's edges
//! (fixed when the surface is first built, kept through cuts; 0.25 by default, i.e. 1 mm on a
//! mesh of 4 mm edges). A vertex gets a contact with a triangle for the substep when its
//! predicted position lies within `h + h` (thickness plus an equal detection band) in front of
//! the triangle's plane or behind it, over the triangle (the vertex within a 45° cone about the
//! normal through its closest point on the triangle, `LATERAL`), and it started the substep at most `h` behind
//! the triangle (so only a vertex coming from the triangle's outer side is held there).
//!
//! ## Exclusion (rest neighbours)
//! A vertex is never held against a triangle that has it as a corner or a corner sharing a tet
//! with it (its one-ring in the tet mesh: the surface fan around it, the fan's neighbours across
//! short edges of an irregular mesh, the far side of a one-tet-thick wall), nor against one
//! within `1.5 h` of it at rest (a sliver's far corner), except when the two coincided at rest:
//! the two walls of a cut, whose nodes were duplicated in place and share no tet, do collide.
//! A vertex is not held against a triangle it starts the substep *behind* if it was within `2h`
//! of it at rest (a vertex just below a sharp convex edge is behind the faces across the edge);
//! one that starts behind a triangle it was farther from at rest came through it, and is pushed
//! back out (see `h'` below). Pairs farther apart at rest (a crease folding the surface into
//! itself three edges away, a flap laid on its base, a wound's walls) are held apart. A body at
//! rest has no active self-contact (`tests/it/selfcol.rs`, the bunny).
//!
//! ## Constraint
//! With the triangle's corners `a, b, c`, the barycentric weights `(u, v, w)` of the closest
//! point and the triangle's outward unit normal `n` at the start of the substep (both fixed for
//! the substep), `C = n·(p − (u a + v b + w c)) − h' ≥ 0` with `h' = min(h, d₀ + 0.1 h)`, `d₀`
//! the vertex's distance in front of that point at the start of the substep: a vertex that
//! starts nearer than `h` is pushed back by at most a tenth of `h` per substep (no energy
//! injected by the thickness). Projected as XPBD with compliance 0
//! (a hard constraint, as the tool and collider contacts): with `W = w_p + u² w_a + v² w_b +
//! w² w_c`, `Δλ = −C/W`, `Δp = w_p Δλ n`, `Δa = −u w_a Δλ n`, …, which conserves momentum.
//! Friction as the contacts' (Macklin et al. 2014, `contact.rs`), on the displacement of the
//! vertex relative to the triangle's point since the substep's start, tangential part: removed
//! while it and the friction already applied stay within `μ_s` times the normal correction,
//! otherwise reduced by what `μ_k` times it allows.
//!
//! ## Place in the step and determinism
//! Broad phase once per step, in its first substep (the hierarchy refit over boxes swept over
//! the whole step: the first substep's motion extrapolated over the step's substeps, grown by
//! the detection reach `2h`; one query per surface vertex; rest neighbours dropped),
//! narrow phase (the tests above) on those pairs in every substep, after the tool and collider
//! contacts; projected in every
//! iteration after the body's own constraints (material, sutures, floor) and before the tool
//! and collider contacts, which thus have the last word (tools, pins and the tray hold). Serial,
//! in a fixed order (surface vertices in increasing index, triangles in the hierarchy's order):
//! the same for any thread count (`tests/it/selfcol.rs`). No allocation in a step after the
//! one that builds the surface (the buffers are reserved then: at most eight contacts per
//! surface vertex and substep, the rest dropped and counted, `tests/no_allocation.rs`).
//!
//! Edge–edge proximity is not handled (a known gap: two edges can cross between vertices held
//! apart when the thickness is small against the edges).

use glam::{Vec3A, Vec4, Vec4Swizzles};
use tissue_bvh::{closest_point_on_triangle, Aabb, BuildOptions, Bvh, BvhWorkspace};
use tissue_mesh::TET_FACES;

use crate::{PbdError, PbdParam, SoftBody};

/// A body's self-collision settings ([`SoftBody::set_self_collision`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfCollision {
    /// Thickness `h` kept between a surface vertex and the surface, as a fraction of the mean
    /// rest length of the surface's edges, `> 0` and `≤ 1`.
    pub thickness_fraction: f32,
    /// Static friction coefficient `μ_s ≥ 0` between surface and surface.
    pub static_friction: f32,
    /// Kinetic friction coefficient `μ_k ≥ 0`.
    pub kinetic_friction: f32,
}

impl Default for SelfCollision {
    /// Thickness a quarter of the mean surface edge, `μ_s = 0.3`, `μ_k = 0.2` (wet tissue on
    /// wet tissue slides more easily than on steel).
    fn default() -> Self {
        Self {
            thickness_fraction: 0.25,
            static_friction: 0.3,
            kinetic_friction: 0.2,
        }
    }
}

impl SelfCollision {
    fn validate(&self) -> Result<(), PbdError> {
        let f = self.thickness_fraction;
        if !(f.is_finite() && f > 0.0 && f <= 1.0) {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::Margin,
                value: f as f64,
                expected: "self-collision thickness fraction: finite, > 0 and ≤ 1",
            });
        }
        for (param, v) in [
            (PbdParam::StaticFriction, self.static_friction),
            (PbdParam::KineticFriction, self.kinetic_friction),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(PbdError::InvalidParameter {
                    param,
                    value: v as f64,
                    expected: "finite and ≥ 0",
                });
            }
        }
        Ok(())
    }
}

/// A vertex–triangle pair of the step's broad phase, not a rest neighbour.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    vertex: u32,
    triangle: u32,
    ring: bool,
    rest_distance: f32,
}

/// One vertex–triangle contact of the current substep.
#[derive(Debug, Clone, Copy)]
struct SelfContact {
    /// Solver slots: the vertex, then the triangle's corners.
    slots: [u32; 4],
    /// Caller's node indices, same order (for the start positions).
    nodes: [u32; 4],
    bary: [f32; 3],
    normal: Vec3A,
    /// The distance kept this substep (cm): `h`, or less for a vertex that started nearer
    /// (`RECOVERY` below).
    target: f32,
    /// Normal and friction corrections accumulated over the iterations (cm).
    normal_correction: f32,
    friction_correction: f32,
}

/// The self-collision state of a body.
#[derive(Debug, Clone, Default)]
pub(crate) struct SelfState {
    pub(crate) config: Option<SelfCollision>,
    /// The surface must be rebuilt (a topology edit, or just switched on).
    pub(crate) stale: bool,
    /// Thickness `h` (cm), once known.
    thickness: Option<f32>,
    triangles: Vec<[u32; 3]>,
    /// Surface vertices, increasing.
    vertices: Vec<u32>,
    /// Per surface vertex, the nodes sharing a tet with it (sorted): `neighbours[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    neighbours: Vec<u32>,
    boxes: Vec<Aabb>,
    bvh: Option<Bvh>,
    ws: BvhWorkspace,
    candidates: Vec<u32>,
    /// The step's broad-phase pairs (`MAX_PAIRS_PER_VERTEX` per surface vertex at most).
    pairs: Vec<Candidate>,
    /// Broad-phase pairs found past `pairs`' capacity this step (not tested).
    dropped_pairs: usize,
    contacts: Vec<SelfContact>,
    /// Contacts found past the buffer's capacity this substep (not projected).
    dropped: usize,
}

impl SelfState {
    /// Rebuilds the surface, its neighbour lists and (at the next generation) its hierarchy.
    /// Allocates.
    fn rebuild(&mut self, tets: &[[u32; 4]], rest: &[Vec3A]) {
        let _span = tracing::debug_span!("self_collision_surface", tets = tets.len()).entered();
        // Faces keyed by their sorted nodes; those seen once are the boundary.
        let mut faces: Vec<([u32; 3], [u32; 3])> = Vec::with_capacity(tets.len() * 4);
        for t in tets {
            if t[0] == t[1]
                || t[0] == t[2]
                || t[0] == t[3]
                || t[1] == t[2]
                || t[1] == t[3]
                || t[2] == t[3]
            {
                continue;
            }
            for f in TET_FACES {
                let tri = [t[f[0]], t[f[1]], t[f[2]]];
                let mut key = tri;
                key.sort_unstable();
                faces.push((key, tri));
            }
        }
        faces.sort_unstable_by_key(|f| f.0);
        self.triangles.clear();
        let mut i = 0;
        while i < faces.len() {
            let mut j = i + 1;
            while j < faces.len() && faces[j].0 == faces[i].0 {
                j += 1;
            }
            if j == i + 1 {
                self.triangles.push(faces[i].1);
            }
            i = j;
        }
        self.vertices = self.triangles.iter().flatten().copied().collect();
        self.vertices.sort_unstable();
        self.vertices.dedup();
        // Tet one-rings of the surface vertices.
        let mut pairs: Vec<[u32; 2]> = Vec::new();
        for t in tets {
            for &a in t {
                if self.vertices.binary_search(&a).is_ok() {
                    for &b in t {
                        if b != a {
                            pairs.push([a, b]);
                        }
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        self.start.clear();
        self.neighbours.clear();
        let mut k = 0;
        for &v in &self.vertices {
            self.start.push(self.neighbours.len() as u32);
            while k < pairs.len() && pairs[k][0] < v {
                k += 1;
            }
            while k < pairs.len() && pairs[k][0] == v {
                self.neighbours.push(pairs[k][1]);
                k += 1;
            }
        }
        self.start.push(self.neighbours.len() as u32);
        if self.thickness.is_none() {
            let (mut sum, mut n) = (0.0f64, 0usize);
            for t in &self.triangles {
                for e in 0..3 {
                    let (a, b) = (t[e] as usize, t[(e + 1) % 3] as usize);
                    if let (Some(pa), Some(pb)) = (rest.get(a), rest.get(b)) {
                        sum += pa.distance(*pb) as f64;
                        n += 1;
                    }
                }
            }
            let fraction = self.config.map_or(0.25, |c| c.thickness_fraction);
            if n > 0 {
                self.thickness = Some((sum / n as f64) as f32 * fraction);
            }
        }
        self.boxes.clear();
        self.boxes
            .resize(self.triangles.len(), Aabb::from_point(Vec3A::ZERO));
        self.bvh = None;
        self.contacts.clear();
        // The step's buffers at their largest, so that no step allocates (`MAX_CONTACTS_PER_VERTEX`).
        let most = MAX_CONTACTS_PER_VERTEX * self.vertices.len();
        self.contacts
            .reserve(most.saturating_sub(self.contacts.len()));
        self.candidates
            .reserve(self.triangles.len().saturating_sub(self.candidates.len()));
        self.pairs.clear();
        self.pairs
            .reserve(MAX_PAIRS_PER_VERTEX * self.vertices.len());
        self.stale = false;
    }

    /// The tet one-ring of surface vertex `k`.
    fn ring(&self, k: usize) -> &[u32] {
        &self.neighbours[self.start[k] as usize..self.start[k + 1] as usize]
    }

    /// How the surface vertex `k` (node `v`) stands to triangle `t`: `None` when it must not be
    /// held against it, else `Some((ring, d))`: whether a corner of `t` shares a tet with `v`
    /// (always `false`: such triangles are excluded), and their rest distance `d` (`rest`: rest
    /// positions). Excluded: `t` has `v` as a corner, or a corner sharing a tet with `v` (its
    /// tet one-ring: on an irregular mesh a short edge puts a fan neighbour's far side within
    /// `h`); `t` was within `1.5 h` of `v` at rest (rest neighbours further out, a sliver's far
    /// corner) unless they coincided at rest (`d < 10⁻⁴ h`: the two walls of a cut, made from
    /// one place).
    fn relation(
        &self,
        k: usize,
        v: u32,
        t: [u32; 3],
        rest: &[Vec3A],
        h: f32,
    ) -> Option<(bool, f32)> {
        if t.contains(&v) {
            return None;
        }
        let ring = self.ring(k);
        let near = t.iter().any(|c| ring.binary_search(c).is_ok());
        if near {
            return None;
        }
        let at = |i: u32| rest.get(i as usize).copied().unwrap_or(Vec3A::ZERO);
        let (q, _) = closest_point_on_triangle(at(v), at(t[0]), at(t[1]), at(t[2]));
        let d = q.distance(at(v));
        if d >= REST_NEIGHBOUR * h {
            return Some((near, d));
        }
        if d < TWIN * h && !near {
            return Some((false, d));
        }
        None
    }
}

/// Pairs nearer than this many `h` at rest are rest neighbours (excluded).
const REST_NEIGHBOUR: f32 = 1.5;

/// Pairs nearer than this many `h` at rest coincided at rest: the two walls of a cut.
const TWIN: f32 = 1e-4;

/// At most this many contacts per surface vertex and substep on average: the contact buffer is
/// reserved for them when the surface is built, and a substep's contacts past it are dropped
/// (counted by [`SoftBody::self_contacts_dropped`], never projected), so that a
/// step never allocates. A vertex has one to three contacts where a surface rests on another.
const MAX_CONTACTS_PER_VERTEX: usize = 8;

/// How far the vertex may be off the normal through its closest point on the triangle, as a
/// fraction of its distance along the normal (1: a 45° cone around the normal over the
/// triangle's edges): held by the triangles it lies over or just beside (a vertex of one grid
/// over the edges of another must not slip through), never by a triangle beside it in its own
/// plane (a flattened surface, such as an organ's base on the tray, is not in contact with
/// itself).
const LATERAL: f32 = 1.0;

/// At most this many broad-phase pairs per surface vertex and step on average (reserved when
/// the surface is built; past it, pairs are dropped and counted).
const MAX_PAIRS_PER_VERTEX: usize = 64;

/// The fraction of `h` by which a vertex nearer than `h` to a triangle (or behind it) at the
/// start of a substep is pushed back per substep: the gap is restored over a few substeps
/// instead of in one (a push of `h` in one substep of `Δt/9` would be a velocity of `9h/Δt`,
/// 51 cm/s for `h` = 0.57 mm at 10 ms, energy the contact would inject).
const RECOVERY: f32 = 0.1;

fn point(q: &[Vec4], s: u32) -> Vec3A {
    Vec3A::from(q[s as usize].xyz())
}

impl SoftBody {
    /// Switches self-collision of the body's surface on (with these settings) or off (`None`).
    /// Off by default. See the module `selfcol` in the crate's source for the model; the
    /// thickness is fixed from the rest surface when it is first switched on.
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] for a thickness fraction outside `(0, 1]` or a negative
    /// friction coefficient.
    pub fn set_self_collision(&mut self, settings: Option<SelfCollision>) -> Result<(), PbdError> {
        if let Some(s) = &settings {
            s.validate()?;
        }
        if settings.map(|s| s.thickness_fraction)
            != self.self_collision.config.map(|s| s.thickness_fraction)
        {
            self.self_collision.thickness = None;
        }
        self.self_collision.config = settings;
        self.self_collision.stale = true;
        self.self_collision.contacts.clear();
        Ok(())
    }

    /// The self-collision settings, if it is on.
    pub fn self_collision(&self) -> Option<SelfCollision> {
        self.self_collision.config
    }

    /// The self-collision thickness `h` in use (cm), once the surface was built (the first step
    /// with self-collision on).
    pub fn self_collision_thickness(&self) -> Option<f32> {
        self.self_collision
            .config
            .and(self.self_collision.thickness)
    }

    /// The number of vertex–triangle self-contacts of the last substep, and how many of them
    /// the iterations had to push (the others stayed clear by themselves).
    pub fn self_contact_counts(&self) -> (usize, usize) {
        let c = &self.self_collision.contacts;
        (
            c.len(),
            c.iter().filter(|c| c.normal_correction > 0.0).count(),
        )
    }

    /// Self-contacts found in the last substep past the buffer's capacity (eight per surface
    /// vertex), plus the step's broad-phase pairs past theirs (64 per surface vertex),
    /// hence not tested or projected: 0 unless the surface is badly tangled.
    pub fn self_contacts_dropped(&self) -> usize {
        self.self_collision.dropped + self.self_collision.dropped_pairs
    }

    /// The surface's triangles as self-collision sees them (the faces used by one tet only,
    /// wound outward; caller's node indices). Computes them (allocates).
    pub fn surface_triangles(&self) -> Vec<[u32; 3]> {
        let mut s = SelfState::default();
        s.rebuild(&self.tets, &self.edits.rest_x);
        s.triangles
    }

    /// Generates this substep's self-contacts from the start positions `x` and the predictions
    /// in `q` (after the prediction, step.rs).
    pub(crate) fn generate_self_contacts(&mut self, first: bool) {
        if self.self_collision.config.is_none() {
            return;
        }
        let _span = tracing::trace_span!("self_contacts").entered();
        let st = &mut self.self_collision;
        if st.stale {
            st.rebuild(&self.tets, &self.edits.rest_x);
        }
        st.contacts.clear();
        st.dropped = 0;
        let Some(h) = st.thickness else {
            return;
        };
        if st.triangles.is_empty() {
            return;
        }
        let reach = 2.0 * h;
        let (x, q, rank) = (&self.x, &self.q, &self.rank);
        let predicted = |i: u32| point(q, rank[i as usize]);
        if first || st.bvh.is_none() {
            // The broad phase, once per step: every (vertex, triangle) whose boxes over the
            // whole step (the first substep's motion extrapolated over the step's substeps,
            // the triangle's grown by the detection reach `2h`) overlap, rest neighbours left
            // out.
            let ahead = self.settings.substeps.max(1) as f32;
            let far = |i: u32| {
                let x0 = x[i as usize];
                x0 + (predicted(i) - x0) * ahead
            };
            for (b, t) in st.boxes.iter_mut().zip(&st.triangles) {
                let [a0, a1, a2] = t.map(|i| x[i as usize]);
                let [b0, b1, b2] = t.map(far);
                *b = Aabb::from_triangle(a0, a1, a2)
                    .union(&Aabb::from_triangle(b0, b1, b2))
                    .expanded(reach);
            }
            let ok = match &mut st.bvh {
                Some(bvh) => bvh.refit(st.boxes.as_slice()).is_ok(),
                None => false,
            };
            if !ok {
                match Bvh::build(st.boxes.as_slice(), &BuildOptions::default()) {
                    Ok(bvh) => st.bvh = Some(bvh),
                    Err(_) => {
                        // Non-finite positions: the step reports the divergence.
                        st.bvh = None;
                        return;
                    }
                }
            }
            let Some(bvh) = &st.bvh else {
                return;
            };
            st.pairs.clear();
            st.dropped_pairs = 0;
            for (k, &v) in st.vertices.iter().enumerate() {
                let probe = Aabb::from_segment(x[v as usize], far(v));
                bvh.overlapping_primitives(
                    st.boxes.as_slice(),
                    &probe,
                    0.0,
                    &mut st.ws,
                    &mut st.candidates,
                );
                for &ti in &st.candidates {
                    let t = st.triangles[ti as usize];
                    let Some((ring, rest_distance)) = st.relation(k, v, t, &self.edits.rest_x, h)
                    else {
                        continue;
                    };
                    if st.pairs.len() == st.pairs.capacity() {
                        st.dropped_pairs += 1;
                        continue;
                    }
                    st.pairs.push(Candidate {
                        vertex: v,
                        triangle: ti,
                        ring,
                        rest_distance,
                    });
                }
            }
        }
        // The narrow phase, every substep, on the step's candidates.
        for c in &st.pairs {
            let (v, t) = (c.vertex, st.triangles[c.triangle as usize]);
            let (xv, pv) = (x[v as usize], predicted(v));
            let [a0, a1, a2] = t.map(|i| x[i as usize]);
            let n = (a1 - a0).cross(a2 - a0);
            let len = n.length();
            if len <= 0.0 || !len.is_finite() {
                continue;
            }
            let n = n / len;
            // Started on the outer side (at most h behind the plane).
            let (q0, _) = closest_point_on_triangle(xv, a0, a1, a2);
            if n.dot(xv - q0) < -h {
                continue;
            }
            let [b0, b1, b2] = t.map(predicted);
            let (q1, bary) = closest_point_on_triangle(pv, b0, b1, b2);
            let d = pv - q1;
            let along = n.dot(d);
            if along >= h + reach || along < -reach - h {
                continue;
            }
            if (d - n * along).length() > LATERAL * along.abs() {
                continue;
            }
            let slots = [v, t[0], t[1], t[2]].map(|i| rank[i as usize]);
            if slots.iter().all(|&s| q[s as usize].w <= 0.0) {
                continue;
            }
            if st.contacts.len() == st.contacts.capacity() {
                st.dropped += 1;
                continue;
            }
            let start = n.dot(xv - (a0 * bary[0] + a1 * bary[1] + a2 * bary[2]));
            let rest_distance = c.rest_distance;
            if start < 0.0 && (c.ring || (rest_distance >= TWIN * h && rest_distance < 2.0 * h)) {
                // Behind a tet neighbour's face (inside a thin wall, not through it), or
                // behind a face it was near at rest (beside a sharp convex edge): the
                // material's business. Only a vertex that came through from afar is pushed
                // back out.
                continue;
            }
            st.contacts.push(SelfContact {
                slots,
                nodes: [v, t[0], t[1], t[2]],
                bary,
                normal: n,
                target: h.min(start + RECOVERY * h),
                normal_correction: 0.0,
                friction_correction: 0.0,
            });
        }
    }

    /// Projects the self-contacts once (one iteration), in order.
    pub(crate) fn project_self_contacts(&mut self) {
        let Some(config) = self.self_collision.config else {
            return;
        };
        let (q, x) = (&mut self.q, &self.x);
        for c in &mut self.self_collision.contacts {
            let [sv, sa, sb, sc] = c.slots;
            let [u, v, w] = c.bary;
            let (wv, wa, wb, wc) = (
                q[sv as usize].w,
                q[sa as usize].w,
                q[sb as usize].w,
                q[sc as usize].w,
            );
            let big_w = wv + u * u * wa + v * v * wb + w * w * wc;
            if big_w <= 0.0 {
                continue;
            }
            let n = c.normal;
            let (pv, pa, pb, pc) = (point(q, sv), point(q, sa), point(q, sb), point(q, sc));
            let s = pa * u + pb * v + pc * w;
            let cval = n.dot(pv - s) - c.target;
            let mut pv = pv;
            let (mut pa, mut pb, mut pc) = (pa, pb, pc);
            if cval < 0.0 {
                let l = -cval / big_w;
                pv += n * (wv * l);
                pa -= n * (u * wa * l);
                pb -= n * (v * wb * l);
                pc -= n * (w * wc * l);
                c.normal_correction -= cval;
            }
            if c.normal_correction > 0.0 {
                // Friction on the relative tangential displacement since the substep's start.
                let [nv, na, nb, nc] = c.nodes.map(|i| x[i as usize]);
                let rel = (pv - nv) - ((pa - na) * u + (pb - nb) * v + (pc - nc) * w);
                let t = rel - n * n.dot(rel);
                let tl = t.length();
                if tl > 0.0 {
                    let d = c.normal_correction;
                    let remove = if tl + c.friction_correction <= config.static_friction * d {
                        tl
                    } else {
                        tl.min((config.kinetic_friction * d - c.friction_correction).max(0.0))
                    };
                    if remove > 0.0 {
                        let l = remove / (tl * big_w);
                        pv -= t * (wv * l);
                        pa += t * (u * wa * l);
                        pb += t * (v * wb * l);
                        pc += t * (w * wc * l);
                        c.friction_correction += remove;
                    }
                }
            }
            for (s, p) in [(sv, pv), (sa, pa), (sb, pb), (sc, pc)] {
                let wq = q[s as usize].w;
                q[s as usize] = p.extend(wq);
            }
        }
    }
}
