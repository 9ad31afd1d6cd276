//! Self-collision of a body's surface (issue 35): vertex–triangle proximity with a thickness,
//! found with a [`tissue_bvh::Bvh`] over the surface's triangles, projected inside the solver's
//! iterations as unilateral position constraints with Coulomb friction.
//!
//! ## The surface
//! The faces used by one tet only (the boundary of the current tets, so the faces a cut opens
//! are in it: a cut duplicates nodes and gives the two walls distinct faces), wound outward
//! ([`tissue_mesh::TET_FACES`] on positively oriented tets). Rebuilt, with its hierarchy, after
//! any topology edit (`duplicate_nodes`, `set_tet_nodes`, `add_tet`) or rest-position edit
//! (`set_rest_position`; that step allocates); otherwise the hierarchy over the triangles'
//! swept boxes is refit when the broad phase's lists are found again (below).
//!
//! ## Thickness and detection
//! `h` = [`SelfCollision::thickness_fraction`] × the mean rest length of the surface's edges
//! (fixed when the surface is first built, kept through cuts; 0.25 by default, i.e. 1 mm on a
//! mesh of 4 mm edges). A vertex gets a contact with a triangle for the substep when its
//! predicted position lies within `h + h` (thickness plus an equal detection band, `BAND`) in
//! front of the triangle's plane or behind it, over the triangle (the vertex within a 45° cone about the
//! normal through its closest point on the triangle, `LATERAL`), and it started the substep at most `h` behind
//! the triangle (so only a vertex coming from the triangle's outer side is held there).
//!
//! ## Exclusion (rest neighbours)
//! A vertex is never held against a triangle that has it as a corner or a corner sharing a tet
//! with it (its one-ring in the tet mesh: the surface fan around it, the fan's neighbours across
//! short edges of an irregular mesh, the far side of a one-tet-thick wall), nor against one
//! within `1.5 h` of it at rest (a sliver's far corner), except when the two coincided at
//! rest: the two walls of a cut, whose nodes were duplicated in place and share no tet, do
//! collide. A vertex is not held against a triangle it starts the substep *behind* if it was
//! within `2h` of it at rest (a vertex just below a sharp convex edge is behind the faces across
//! the edge); one that starts at most `h/10` behind a triangle it was farther from at rest (the
//! slop of the iterations) is pushed back out (see `h'` below), and so is one up to `h` behind
//! a triangle it was held against in the last substep (the iterations let it through); any
//! other is left to the material (`BEHIND`: pushing it across injected energy into a freshly
//! cut, moving surface). Pairs farther apart at rest (a crease folding the surface into itself
//! three edges away, a flap laid on its base, a wound's walls) are held apart. A body at rest
//! has no active self-contact (`tests/it/selfcol.rs`, the bunny).
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
//! ## Place in the step, cost and determinism
//! **Rest relations**, once per surface build: per surface vertex, the sorted list of the
//! triangles it is never held against (above) or was near at rest (within `2h`: not pushed out
//! from behind them), found with a hierarchy over the rest triangles grown by `2h`, by blocks of
//! vertices (in parallel when the steps are). A step looks a pair up in it (a binary search)
//! instead of computing a closest point at rest.
//!
//! **Travels.** Each step, every surface vertex's expected path over it: a segment from its
//! position along its net displacement over the last step (its first substep's motion times
//! the substeps when the surface was just built), grown by a spread of twice its first
//! substep's motion, held as it decays (`SPREAD`, `SPREAD_DECAY`). The net displacement,
//! not the first substep's velocity extrapolated: a jittering vertex's velocity says little of
//! where it will be at the step's end.
//!
//! **Broad phase**, once per step in its first substep: the (vertex, triangle) pairs, rest
//! neighbours left out, whose boxes over the whole step overlap (the vertex's travel; the
//! triangle's corners' travels grown by the detection reach `2h`). Taken from Verlet lists: a
//! *full pass* (the hierarchy refit over the triangles' boxes grown by a further slack `h`, one
//! query per surface vertex with its travel's box grown by `h`; in fact one traversal per
//! `GROUP` = 8 consecutive vertices of a chunk for the union of their boxes, then each
//! vertex's box against the triangles found: the same pairs in the same order; 7–15 % less
//! broad-phase time than a traversal per vertex on the `trainer` run, measured together with
//! a rest-relation lookup since dropped that alone made no difference) keeps every vertex's
//! pairs, and
//! they hold while every surface vertex's travel stays inside its box of that pass grown by `h`
//! (then any pair whose boxes overlap now overlapped then); each step filters them with its own
//! boxes, so the pairs are exactly those of a full pass every step. A last filter keeps the pairs
//! that can come within the narrow phase's reach (`√2 · 2h`, the band and the cone) over the
//! step: their distance at its start, less what their travels can close (the vertex's
//! expected motion against the triangle's corners' mean, plus how far each path can stray
//! from it), about a third of the boxes' pairs on the bunny with a cut. The lists' boxes are kept in
//! a frame that follows the surface's mean translation since the full pass (overlaps do not
//! change when every box moves alike): a body carried or falling as a whole keeps its lists.
//! When a few vertices left their boxes (at most one in 16), an *update* instead: they take new
//! boxes, so do the triangles they are a corner of (then a refit), and the vertices whose box
//! meets a moved triangle's new one (found through the hierarchy: a vertex's box lies in those
//! of its triangles) query again, the others keeping their lists
//! (`tests::updated_lists_give_the_pairs_of_a_full_pass`). A body at rest skips the refit and
//! the queries; a tool pressing on one place re-queries the vertices around it. Lists that did
//! not outlast a step (a body in motion) are found without the slack until one in
//! `BARE_PASSES` = 8 full passes tries the slack again. The queries go by chunks of 128 surface
//! vertices along a Morton curve over their rest positions (a chunk is a patch of the surface),
//! each into its own list (in parallel when the step is).
//!
//! **Narrow phase** (the tests above) on the step's pairs in every substep, after the tool and
//! collider contacts. Each triangle of the step's pairs is read once per substep into a facet
//! (its normal at the substep's start, its predicted box and extent along the normal; the
//! triangles are stored along a Morton curve over their rest centroids, so a chunk's pairs read
//! nearby facets), and the pairs are rejected cheaply from it first (the extent along `n`
//! bounds the distance along it; the cone bounds the distance to the triangle's box). A contact
//! whose four nodes are all pinned or held in the substep (by a tool or collider contact, or
//! predicted at or under the floor) is dropped: it could only fight the holders. Projected
//! in every iteration after the body's own constraints (material, sutures, floor) and before
//! the tool and collider contacts, which thus have the last word (tools, pins and the tray
//! hold). Found by chunks of surface vertices (in parallel when the step is), each into its own
//! contact buffer, and projected serially by increasing vertex, then triangle (its index among
//! the boundary faces sorted by nodes): the same for any thread count and chunking
//! (`tests/it/selfcol.rs`). No allocation in a step after the one that builds the surface (the
//! buffers are reserved then: at most 64 broad-phase pairs per surface vertex and eight
//! contacts per vertex and substep, the rest dropped and counted,
//! `tests/selfcol_allocation.rs`, serial and parallel).
//!
//! **A tangled surface** (one that passed through itself: a violent drag, a solver that could
//! not hold the organ) puts many triangles within reach of every vertex, which vertex–triangle
//! contacts cannot undo (each pushes its vertex back through the nearest wall). When the broad
//! phase finds more pairs past its lists' capacity than 64 a surface vertex (the thick slabs of
//! the tests overflow by 13 a vertex at most; tangles by hundreds to thousands), self-collision is
//! suspended for `SUSPENSION` = 50 steps and then tried again with a full pass
//! ([`SoftBody::self_collision_suspended`], [`SoftBody::self_collision_suspensions`]): the
//! bunny flung by a drag snapped to the tray's corner steps in 4.9 ms (median, serial) instead
//! of 130, as without self-collision. The capacities bound any step's work otherwise.
//!
//! Edge–edge proximity is not handled (a known gap: two edges can cross between vertices held
//! apart when the thickness is small against the edges).

use glam::{Vec3, Vec3A, Vec4, Vec4Swizzles};
use rayon::prelude::*;
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
#[derive(Debug, Clone, Copy, PartialEq)]
struct Candidate {
    vertex: u32,
    /// The vertex's index in `SelfState::vertices`.
    local: u32,
    triangle: u32,
    /// The two were within `2h` at rest without coinciding (`NEAR_AT_REST`).
    near_at_rest: bool,
}

/// A run of surface vertices (consecutive along the Morton curve of `SelfState::order`) whose
/// broad-phase queries and narrow-phase tests are made together (by one thread), with its own
/// scratch, pairs and contacts: `CHUNK` vertices, so that the chunks, and the order of the
/// pairs they give, are the same for any number of threads.
#[derive(Debug, Clone, Default)]
struct Chunk {
    /// Its surface vertices, `SelfState::order[start..end]`.
    start: usize,
    end: usize,
    ws: BvhWorkspace,
    candidates: Vec<u32>,
    /// The pairs of the last full pass, found over boxes grown by the slack (twice
    /// `MAX_PAIRS_PER_VERTEX` per vertex at most, reserved).
    near: Vec<Candidate>,
    /// The next `near` while it is found (its capacity).
    spare: Vec<Candidate>,
    /// This step's pairs (from `near`).
    pairs: Vec<Candidate>,
    /// Pairs found past `near`'s capacity in its last query.
    dropped: usize,
    /// `near` must be found again this step.
    dirty: bool,
    /// This substep's contacts of its vertices (`MAX_CONTACTS_PER_VERTEX` per vertex,
    /// reserved), in the order of its pairs.
    contacts: Vec<SelfContact>,
    /// Contacts found past `contacts`' capacity this substep (not projected).
    contacts_dropped: usize,
}

/// The slack of the broad phase's pairs, in `h` (see `SelfState::swept`): larger keeps them
/// over more steps, and gives the narrow phase more pairs to test.
const SLACK: f32 = 1.0;

/// A full pass instead of an update when more than one surface vertex in this many left its
/// box.
const FULL_PASS: usize = 16;

/// Full passes without slack in a row before one with it again (see `SelfState::slack`).
const BARE_PASSES: u32 = 8;

/// Surface vertices per broad-phase chunk.
const CHUNK: usize = 128;

/// Steps a tangled surface's self-collision is suspended for (0.5 s at the real-time preset)
/// before it is tried again.
const SUSPENSION: u32 = 50;

/// Surface vertices (consecutive in a chunk) per query of the hierarchy in the broad phase.
const GROUP: usize = 8;

/// A contact's place in the projection order: `(vertex, triangle's serial, chunk, index in the
/// chunk's contacts)`.
type Sequenced = (u32, u32, u32, u32);

/// One vertex–triangle contact of the current substep.
#[derive(Debug, Clone, Copy)]
struct SelfContact {
    /// The triangle.
    triangle: u32,
    /// Solver slots: the vertex, then the triangle's corners.
    slots: [u32; 4],
    /// Caller's node indices, same order (for the start positions).
    nodes: [u32; 4],
    bary: [f32; 3],
    /// Inverse masses, same order.
    weights: [f32; 4],
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
    /// The surface vertices (indices into `vertices`) in the chunks' order: along a Morton
    /// curve over their rest positions, so that a chunk is a patch of the surface (its
    /// vertices' pairs read nearby triangles, and a tool dirties few chunks).
    order: Vec<u32>,
    /// Per surface vertex, the nodes sharing a tet with it (sorted): `neighbours[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    neighbours: Vec<u32>,
    /// Per surface vertex, the triangles it must not be held against or was near at rest
    /// (`relation`), sorted, each as `triangle << 1 | near`: `rest[rest_start[k]..rest_start[k + 1]]`.
    /// Computed once per surface build from the rest positions.
    rest_start: Vec<u32>,
    rest: Vec<u32>,
    /// The triangles in surface-vertex indices (`vertices[..]`).
    local: Vec<[u32; 3]>,
    /// Per surface vertex, the box of its segment over the step at the last full broad phase:
    /// the pairs found then hold while every vertex's segment stays in its box grown by
    /// `SLACK h`.
    swept: Vec<Aabb>,
    /// The chunks hold the pairs of a full broad phase over the current surface.
    found: bool,
    /// Per surface vertex: its position at the start of the last step, its expected motion
    /// over this step (its net motion over the last one, or its first substep's motion times
    /// the substeps when the last is not `known`), and the spread of its path about that
    /// (`SPREAD`).
    previous: Vec<Vec3A>,
    known: bool,
    motion: Vec<Vec3A>,
    spread: Vec<f32>,
    /// The mean of the surface vertices' positions at the last full pass: the lists' boxes
    /// (`swept`, `boxes`, the hierarchy) are in a frame moved by the surface's mean translation
    /// since.
    centre: Vec3A,
    /// Per surface vertex, the triangles it is a corner of: `fan[fan_start[k]..fan_start[k + 1]]`.
    fan_start: Vec<u32>,
    fan: Vec<u32>,
    /// The vertices whose pairs are found again in an update, and the scratch of the
    /// hierarchy's queries that find them.
    again: Vec<bool>,
    scratch: BvhWorkspace,
    hits: Vec<u32>,
    /// Per surface vertex, whether its segment left its box this step (scratch).
    moved: Vec<bool>,
    /// Broad phases that updated the lists without a full pass (a statistic for the tests).
    updates: usize,
    /// The slack of the lists (cm): `SLACK h`, or 0 while they do not outlast a step.
    slack: f32,
    /// Steps since the last full pass, and full passes without slack in a row.
    lasted: u32,
    bare: u32,
    /// Surface vertices per chunk, `CHUNK` when 0 (smaller in the tests).
    chunk_size: usize,
    /// `FULL_PASS` when 0 (1 in the tests: updates only).
    full_pass: usize,
    /// The triangles' boxes of the last full pass (grown by reach and slack), with their
    /// hierarchy.
    boxes: Vec<Aabb>,
    bvh: Option<Bvh>,
    /// The triangles' boxes over this step, grown by the reach.
    tight: Vec<Aabb>,
    /// Where the triangles start this step (the pairs' last filter).
    outset: Vec<Outset>,
    /// The triangles in the current substep (scratch of the narrow phase), for those of the
    /// step's pairs (`wanted`).
    facets: Vec<Facet>,
    wanted: Vec<bool>,
    /// Per node, whether a tool or collider contact holds it this substep, or the floor (its
    /// prediction at or under the floor): a self-contact whose nodes are all held or pinned is
    /// dropped (it would fight the holders).
    held: Vec<bool>,
    /// The broad phase's chunks of surface vertices, in order.
    chunks: Vec<Chunk>,
    /// The order in which this substep's contacts are projected: `(vertex, triangle's serial,
    /// chunk, index in the chunk's contacts)`, by increasing vertex and serial, whatever the
    /// chunks and the hierarchy.
    sequence: Vec<Sequenced>,
    /// Per triangle, its index among the boundary faces sorted by their nodes (`serial`): the
    /// triangles themselves are in Morton order.
    serial: Vec<u32>,
    /// Steps left of a suspension (a tangled surface, `SUSPENSION`), whether the current step
    /// is suspended, and how many suspensions so far (a statistic).
    suspended: u32,
    idle: bool,
    suspensions: usize,
    /// The last substep's `sequence` (empty after a surface build).
    last: Vec<Sequenced>,
}

/// The faces used by one tet only (the boundary of `tets`), as the tets wind them; tets with
/// a repeated node are skipped. Allocates.
fn boundary_faces(tets: &[[u32; 4]]) -> Vec<[u32; 3]> {
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
    let mut triangles = Vec::new();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j].0 == faces[i].0 {
            j += 1;
        }
        if j == i + 1 {
            triangles.push(faces[i].1);
        }
        i = j;
    }
    triangles
}

impl SelfState {
    /// Rebuilds the surface, its neighbour lists and (at the next generation) its hierarchy.
    /// Allocates.
    fn rebuild(&mut self, tets: &[[u32; 4]], rest: &[Vec3A], parallel: bool) {
        let _span = tracing::debug_span!("self_collision_surface", tets = tets.len()).entered();
        self.triangles = boundary_faces(tets);
        // Along a Morton curve over their rest centroids (the narrow phase reads the triangles
        // of a patch of the surface together), each with its index in the faces' order.
        let centroid = |t: &[u32; 3]| {
            t.iter()
                .map(|&i| rest.get(i as usize).copied().unwrap_or(Vec3A::ZERO))
                .sum::<Vec3A>()
                / 3.0
        };
        self.serial = morton_order(&self.triangles.iter().map(centroid).collect::<Vec<_>>());
        self.triangles = (self.serial.iter())
            .map(|&t| self.triangles[t as usize])
            .collect();
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
        self.local = self
            .triangles
            .iter()
            .map(|t| t.map(|i| self.vertices.binary_search(&i).unwrap_or(0) as u32))
            .collect();
        let at = |v: u32| rest.get(v as usize).copied().unwrap_or(Vec3A::ZERO);
        self.order = morton_order(&self.vertices.iter().map(|&v| at(v)).collect::<Vec<_>>());
        self.swept.clear();
        self.swept
            .resize(self.vertices.len(), Aabb::from_point(Vec3A::ZERO));
        self.found = false;
        self.suspended = 0;
        self.idle = false;
        self.lasted = 0;
        self.bare = 0;
        self.moved.clear();
        self.moved.resize(self.vertices.len(), false);
        let nv = self.vertices.len();
        self.previous.clear();
        self.previous.resize(nv, Vec3A::ZERO);
        self.known = false;
        self.motion.clear();
        self.motion.resize(nv, Vec3A::ZERO);
        self.spread.clear();
        self.spread.resize(nv, 0.0);
        self.held.clear();
        self.held.resize(rest.len(), false);
        self.boxes.clear();
        self.boxes
            .resize(self.triangles.len(), Aabb::from_point(Vec3A::ZERO));
        self.tight.clone_from(&self.boxes);
        self.outset.clear();
        self.outset.resize(
            self.triangles.len(),
            Outset {
                corners: [Vec3A::ZERO; 3],
                motion: Vec3A::ZERO,
                deviation: 0.0,
            },
        );
        // Each surface vertex's fan of triangles.
        self.fan_start.clear();
        self.fan_start.resize(self.vertices.len() + 1, 0);
        for t in &self.local {
            for &k in t {
                self.fan_start[k as usize + 1] += 1;
            }
        }
        for k in 0..self.vertices.len() {
            self.fan_start[k + 1] += self.fan_start[k];
        }
        let mut fill = self.fan_start.clone();
        self.fan.clear();
        self.fan.resize(3 * self.local.len(), 0);
        for (ti, t) in self.local.iter().enumerate() {
            for &k in t {
                self.fan[fill[k as usize] as usize] = ti as u32;
                fill[k as usize] += 1;
            }
        }
        self.hits = Vec::with_capacity(self.triangles.len());
        self.scratch = BvhWorkspace::new();
        self.again.clear();
        self.again.resize(self.vertices.len(), false);
        self.wanted.clear();
        self.wanted.resize(self.triangles.len(), false);
        self.facets.clear();
        self.facets.resize(self.triangles.len(), Facet::DEGENERATE);
        self.bvh = None;
        self.chunks.clear();
        let chunk = if self.chunk_size > 0 {
            self.chunk_size
        } else {
            CHUNK
        };
        for start in (0..self.vertices.len()).step_by(chunk) {
            let end = (start + chunk).min(self.vertices.len());
            self.chunks.push(Chunk {
                start,
                end,
                ws: BvhWorkspace::new(),
                candidates: Vec::with_capacity(self.triangles.len()),
                near: Vec::with_capacity(2 * MAX_PAIRS_PER_VERTEX * (end - start)),
                spare: Vec::with_capacity(2 * MAX_PAIRS_PER_VERTEX * (end - start)),
                pairs: Vec::with_capacity(MAX_PAIRS_PER_VERTEX * (end - start)),
                dropped: 0,
                dirty: true,
                contacts: Vec::with_capacity(MAX_CONTACTS_PER_VERTEX * (end - start)),
                contacts_dropped: 0,
            });
        }
        self.sequence = Vec::with_capacity(MAX_CONTACTS_PER_VERTEX * self.vertices.len());
        self.last = Vec::with_capacity(MAX_CONTACTS_PER_VERTEX * self.vertices.len());
        self.rest_start.clear();
        self.rest.clear();
        if let Some(h) = self.thickness {
            self.cache_rest_relations(rest, h, parallel);
        }
        self.stale = false;
    }

    /// Fills `rest_start` and `rest` (see the fields) from the rest positions `rest`: for each
    /// surface vertex `v`, the triangles it must never be held against, and those it was near
    /// at rest. Excluded: a triangle with `v` as a corner, or a corner sharing a tet with `v`
    /// (its tet one-ring: on an irregular mesh a short edge puts a fan neighbour's far side
    /// within `h`); one within `1.5 h` of `v` at rest (rest neighbours further out, a sliver's
    /// far corner) unless they coincided at rest (`d < 10⁻⁴ h`: the two walls of a cut, made
    /// from one place). Near at rest: from `1.5 h` to `2 h`. Found with a hierarchy over the
    /// rest triangles grown by `2 h`. Allocates (once per surface build).
    fn cache_rest_relations(&mut self, rest: &[Vec3A], h: f32, parallel: bool) {
        let at = |i: u32| rest.get(i as usize).copied().unwrap_or(Vec3A::ZERO);
        // Node → its surface triangles.
        let n = self
            .triangles
            .iter()
            .flatten()
            .map(|&i| i as usize + 1)
            .max()
            .unwrap_or(0);
        let mut first = vec![0u32; n + 1];
        for &c in self.triangles.iter().flatten() {
            first[c as usize + 1] += 1;
        }
        for i in 0..n {
            first[i + 1] += first[i];
        }
        let mut fill = first.clone();
        let mut incident = vec![0u32; 3 * self.triangles.len()];
        for (ti, t) in self.triangles.iter().enumerate() {
            for &c in t {
                incident[fill[c as usize] as usize] = ti as u32;
                fill[c as usize] += 1;
            }
        }
        let boxes: Vec<Aabb> = self
            .triangles
            .iter()
            .map(|t| Aabb::from_triangle(at(t[0]), at(t[1]), at(t[2])).expanded(NEAR_AT_REST * h))
            .collect();
        let bvh = Bvh::build(boxes.as_slice(), &BuildOptions::default()).ok();
        let this = &*self;
        // One vertex's sorted relations into `list`.
        let relations =
            |k: usize, ws: &mut BvhWorkspace, hits: &mut Vec<u32>, list: &mut Vec<u32>| {
                let v = this.vertices[k];
                let ring = this.ring(k);
                for &r in std::iter::once(&v).chain(ring) {
                    let r = r as usize;
                    if let (Some(&a), Some(&b)) = (first.get(r), first.get(r + 1)) {
                        list.extend(incident[a as usize..b as usize].iter().map(|&t| t << 1));
                    }
                }
                if let Some(bvh) = &bvh {
                    let probe = Aabb::from_point(at(v));
                    bvh.overlapping_primitives(boxes.as_slice(), &probe, 0.0, ws, hits);
                    for &ti in hits.iter() {
                        let t = this.triangles[ti as usize];
                        if t.contains(&v) || t.iter().any(|c| ring.binary_search(c).is_ok()) {
                            continue;
                        }
                        let (q, _) = closest_point_on_triangle(at(v), at(t[0]), at(t[1]), at(t[2]));
                        let d = q.distance(at(v));
                        if d < TWIN * h {
                            // The two walls of a cut: they collide.
                        } else if d < REST_NEIGHBOUR * h {
                            list.push(ti << 1);
                        } else if d < NEAR_AT_REST * h {
                            list.push(ti << 1 | 1);
                        }
                    }
                }
            };
        // By blocks of vertices (in parallel when the steps are), each into its own lists,
        // joined in order.
        let block = |range: std::ops::Range<usize>| {
            let (mut ws, mut hits, mut list) = (BvhWorkspace::new(), Vec::new(), Vec::new());
            let (mut all, mut counts) = (Vec::new(), Vec::with_capacity(range.len()));
            for k in range {
                list.clear();
                relations(k, &mut ws, &mut hits, &mut list);
                list.sort_unstable();
                list.dedup();
                all.extend_from_slice(&list);
                counts.push(list.len() as u32);
            }
            (all, counts)
        };
        let nv = self.vertices.len();
        let ranges: Vec<_> = (0..nv)
            .step_by(RELATIONS_BLOCK)
            .map(|a| a..(a + RELATIONS_BLOCK).min(nv))
            .collect();
        let blocks: Vec<(Vec<u32>, Vec<u32>)> = if parallel {
            ranges.into_par_iter().map(block).collect()
        } else {
            ranges.into_iter().map(block).collect()
        };
        for (all, counts) in blocks {
            let mut start = self.rest.len() as u32;
            for c in counts {
                self.rest_start.push(start);
                start += c;
            }
            self.rest.extend_from_slice(&all);
        }
        self.rest_start.push(self.rest.len() as u32);
    }

    /// The tet one-ring of surface vertex `k`.
    fn ring(&self, k: usize) -> &[u32] {
        &self.neighbours[self.start[k] as usize..self.start[k + 1] as usize]
    }
}

/// How surface vertex `k` stands to triangle `t`, from its cached rest relations `rest`
/// (`SelfState::rest` from `rest_start[k]` to `rest_start[k + 1]`): `None` when it must not be
/// held against it, else whether the two were near at rest (`NEAR_AT_REST`).
fn relation(rest: &[u32], t: u32) -> Option<bool> {
    match rest.binary_search_by_key(&t, |e| e >> 1) {
        Ok(i) => (rest[i] & 1 == 1).then_some(true),
        Err(_) => Some(false),
    }
}

/// Surface vertices per block of the rest relations' computation.
const RELATIONS_BLOCK: usize = 256;

/// Pairs within this many `h` at rest (and not rest neighbours) were near at rest: a vertex
/// that starts a substep behind such a triangle is left to the material (beside a sharp convex
/// edge), not pushed out.
const NEAR_AT_REST: f32 = 2.0;

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

/// A vertex that starts a substep more than this fraction of `h` behind a triangle is not held
/// against it (not pushed back out): only the slop of the solver's iterations (a vertex that
/// crossed by less than a tenth of the thickness) is recovered. Pushed back from up to `h`
/// behind, vertices of a freshly cut, moving surface were driven across the other wall and the
/// surface tangled (the appendix's cut-off: 6 × 10³ – 10⁵ intersecting pairs against 362
/// without self-collision; 192 with this bound; `tissue-scenes` `tests/it/selfcol.rs`). A
/// vertex held against the triangle in the last substep is held still, from up to `h` behind
/// (a contact persists: the iterations let it through, it did not come through from afar).
const BEHIND: f32 = 0.1;

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
        self.self_collision.clear_contacts();
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
        let c = || self.self_collision.contacts();
        (
            c().count(),
            c().filter(|c| c.normal_correction > 0.0).count(),
        )
    }

    /// Self-contacts found in the last substep past the buffer's capacity (eight per surface
    /// vertex), plus the step's broad-phase pairs past theirs (64 per surface vertex),
    /// hence not tested or projected: 0 unless the surface is badly tangled.
    pub fn self_contacts_dropped(&self) -> usize {
        let st = &self.self_collision;
        st.chunks
            .iter()
            .map(|c| c.dropped + c.contacts_dropped)
            .sum::<usize>()
    }

    /// Steps left of the current suspension of self-collision, 0 when it is active (or off).
    /// Self-collision is suspended for 50 steps when the broad phase finds more pairs past its
    /// lists' capacity than 64 a surface vertex: a surface that passed through itself (a tangle a
    /// violent drag or the solver made), which vertex–triangle contacts cannot undo and which
    /// would cost every list in full (130 ms a step on the bunny, whose step takes about 10 ms
    /// with self-collision and 5 without); then it is tried again. [`SoftBody::self_collision_suspensions`] counts them.
    pub fn self_collision_suspended(&self) -> u32 {
        let st = &self.self_collision;
        if st.idle {
            st.suspended + 1
        } else {
            st.suspended
        }
    }

    /// How many times self-collision was suspended for a tangled surface since the body was
    /// made ([`SoftBody::self_collision_suspended`]).
    pub fn self_collision_suspensions(&self) -> usize {
        self.self_collision.suspensions
    }

    /// The surface's triangles as self-collision sees them (the faces used by one tet only,
    /// wound outward; caller's node indices). Computes them (allocates).
    pub fn surface_triangles(&self) -> Vec<[u32; 3]> {
        boundary_faces(&self.tets)
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
            st.rebuild(&self.tets, &self.edits.rest_x, self.settings.parallel);
        }
        // The last substep's contacts, for the contacts that persist (`BEHIND`).
        std::mem::swap(&mut st.sequence, &mut st.last);
        st.clear_contacts();
        let Some(h) = st.thickness else {
            return;
        };
        if st.triangles.is_empty() {
            return;
        }
        if first {
            // A suspension (a tangled surface, below) counts down by steps.
            st.idle = st.suspended > 0;
            st.suspended = st.suspended.saturating_sub(1);
        }
        if st.idle {
            return;
        }
        let (x, q, rank) = (&self.x, &self.q, &self.rank);
        // The nodes held this substep: by the contacts with tools and colliders (generated
        // before these), by the floor.
        st.held.clear();
        st.held.resize(x.len(), false);
        for c in &self.collision.contacts {
            if let Some(h) = st.held.get_mut(c.node as usize) {
                *h = true;
            }
        }
        if let Some(f) = self.floor {
            for &v in &st.vertices {
                if q[rank[v as usize] as usize][f.axis] <= f.height {
                    st.held[v as usize] = true;
                }
            }
        }
        if first || st.bvh.is_none() {
            let ahead = self.settings.substeps.max(1) as f32;
            let parallel = self.settings.parallel;
            let ok = st.broad_phase(x, q, rank, h, ahead, parallel);
            if !ok {
                return;
            }
            let dropped = st.chunks.iter().map(|c| c.dropped).sum::<usize>();
            if dropped > MAX_PAIRS_PER_VERTEX * st.vertices.len() {
                // More pairs past the lists' capacity than 64 a surface vertex: a surface that
                // passed through itself (a tangle, which vertex–triangle contacts cannot undo:
                // they push each vertex back through the nearest wall, and every vertex is
                // near many). Its pairs would cost a full pass and the narrow phase on every
                // list full, 130 ms a step on the bunny tangled by a violent drag, against 5
                // ms without self-collision: suspended for `SUSPENSION` steps instead, then
                // tried again (a full pass, the travels found afresh).
                st.suspended = SUSPENSION;
                st.suspensions += 1;
                st.idle = true;
                st.found = false;
                st.known = false;
                for c in &mut st.chunks {
                    c.pairs.clear();
                }
                return;
            }
        }
        let parallel = self.settings.parallel;
        st.narrow_phase(x, q, rank, h, parallel);
    }
}

impl SelfState {
    /// The broad phase, once per step (in its first substep): every (vertex, triangle) whose
    /// boxes over the whole step overlap (the vertex's travel: its net motion over the last
    /// step, or its first substep's motion times the step's `ahead` substeps after a surface
    /// build, grown by its spread; the triangle's corners' travels grown by the detection reach
    /// `2h`), rest neighbours left out, into the chunks' `pairs`. From the chunks' `near` lists
    /// (Verlet lists), which a full pass (refit and one query per vertex) refills, or an update
    /// (the vertices concerned) amends, only when a vertex's travel left its box of the last
    /// pass grown by `SLACK h` in the frame that follows the surface's mean translation.
    /// `false` for non-finite positions (no pairs: the step reports the divergence).
    fn broad_phase(
        &mut self,
        x: &[Vec3A],
        q: &[Vec4],
        rank: &[u32],
        h: f32,
        ahead: f32,
        parallel: bool,
    ) -> bool {
        let st = self;
        // The slack of the current lists.
        let (reach, mut slack) = (BAND * h, st.slack);
        // Each surface vertex's expected motion over the step and the spread about it.
        for (k, &v) in st.vertices.iter().enumerate() {
            let x0 = x[v as usize];
            let sub = point(q, rank[v as usize]) - x0;
            st.motion[k] = if st.known {
                x0 - st.previous[k]
            } else {
                sub * ahead
            };
            // Held over a few steps as it decays (`SPREAD_DECAY`): a jittering vertex keeps
            // its box, and its lists.
            st.spread[k] = (SPREAD * sub.length()).max(SPREAD_DECAY * st.spread[k]);
            st.previous[k] = x0;
        }
        st.known = true;
        // The surface's mean translation since the last full pass: the lists' boxes are kept
        // in a frame that moves with it (overlaps do not change when every box moves alike),
        // so a body carried or falling as a whole keeps its lists.
        let centre = st
            .vertices
            .iter()
            .fold(Vec3A::ZERO, |c, &v| c + x[v as usize])
            / st.vertices.len().max(1) as f32;
        let shift = centre - st.centre;
        let (motion, spread) = (&st.motion, &st.spread);
        let segment = |k: usize| {
            let x0 = x[st.vertices[k] as usize];
            Aabb::from_segment(x0, x0 + motion[k]).expanded(spread[k])
        };
        // The triangles' boxes over this step, grown by the reach, and where they start.
        for ((b, o), t) in st.tight.iter_mut().zip(&mut st.outset).zip(&st.local) {
            let [r0, r1, r2] = t.map(|k| segment(k as usize));
            *b = r0.union(&r1).union(&r2).expanded(reach);
            let m = t.map(|k| motion[k as usize]);
            let mean = (m[0] + m[1] + m[2]) / 3.0;
            let deviation = (m.iter().map(|&m| m.distance(mean))).fold(0.0f32, f32::max)
                + 3f32.sqrt()
                    * t.map(|k| spread[k as usize])
                        .into_iter()
                        .fold(0.0, f32::max);
            *o = Outset {
                corners: t.map(|k| x[st.vertices[k as usize] as usize]),
                motion: mean,
                deviation,
            };
        }
        // The vertices whose segment left its box of the last pass grown by the slack.
        let mut escaped = 0;
        let framed = |k: usize| {
            let b = segment(k);
            Aabb {
                min: b.min - Vec3::from(shift),
                max: b.max - Vec3::from(shift),
            }
        };
        for (k, (m, r)) in st.moved.iter_mut().zip(&st.swept).enumerate() {
            *m = !r.expanded(slack).contains(&framed(k));
            escaped += usize::from(*m);
        }
        let most = st.vertices.len()
            / if st.full_pass > 0 {
                st.full_pass
            } else {
                FULL_PASS
            };
        let full = !st.found || st.bvh.is_none() || escaped > most;
        st.lasted = st.lasted.saturating_add(1);
        if full {
            // Lists that did not outlast a step (a body in motion): the slack would only cost
            // (larger boxes, more pairs), so none, but tried again every `BARE_PASSES` passes.
            let bare = st.found && st.lasted <= 1 && st.bare < BARE_PASSES;
            st.bare = if bare { st.bare + 1 } else { 0 };
            slack = if bare { 0.0 } else { SLACK * h };
            st.slack = slack;
            st.lasted = 0;
        }
        if full || escaped > 0 {
            // A full pass (boxes grown by the slack, refit, one query per surface vertex), or
            // an update: the escaped vertices take their new boxes, the triangles they are a
            // corner of too, and the vertices that moved or whose box meets a moved triangle's
            // new one query again. Queries by chunks (in parallel when the step is, each chunk
            // into its own list: the same lists on any number of threads).
            st.found = false;
            if full {
                // A new frame: the current positions.
                st.centre = centre;
            }
            let shift = if full { Vec3A::ZERO } else { shift };
            let framed = |k: usize| {
                let b = segment(k);
                Aabb {
                    min: b.min - Vec3::from(shift),
                    max: b.max - Vec3::from(shift),
                }
            };
            for (k, (r, &m)) in st.swept.iter_mut().zip(&st.moved).enumerate() {
                if full || m {
                    *r = framed(k);
                }
            }
            for c in &mut st.chunks {
                c.dirty = full;
            }
            for (b, t) in st.boxes.iter_mut().zip(&st.local) {
                if !full && !t.iter().any(|&k| st.moved[k as usize]) {
                    continue;
                }
                let [r0, r1, r2] = t.map(|k| st.swept[k as usize]);
                *b = r0.union(&r1).union(&r2).expanded(reach + slack);
            }
            if st.bvh.is_none() {
                // Built over this step's boxes without the slack (the hierarchy, and the order
                // of each vertex's triangles, as without the lists), then refit with it.
                st.bvh = Bvh::build(st.tight.as_slice(), &BuildOptions::default()).ok();
            }
            let ok = match &mut st.bvh {
                Some(bvh) => bvh.refit(st.boxes.as_slice()).is_ok(),
                None => false,
            };
            if !ok {
                match Bvh::build(st.boxes.as_slice(), &BuildOptions::default()) {
                    Ok(bvh) => st.bvh = Some(bvh),
                    Err(_) => {
                        st.bvh = None;
                        for c in &mut st.chunks {
                            c.pairs.clear();
                        }
                        return false;
                    }
                }
            }
            let Some(bvh) = &st.bvh else {
                return false;
            };
            // On an update, the vertices whose pairs are found again: those that moved, and
            // those whose box meets a moved triangle's new one. Found per moved vertex `e`,
            // with one query over the union of its triangles' boxes: a vertex whose box meets
            // one of them has a triangle whose box (which holds the vertex's) meets the union.
            if !full {
                let (again, moved, swept, local, boxes) =
                    (&mut st.again, &st.moved, &st.swept, &st.local, &st.boxes);
                again.copy_from_slice(moved);
                let ws = &mut st.scratch;
                for e in (0..moved.len()).filter(|&e| moved[e]) {
                    let fan = &st.fan[st.fan_start[e] as usize..st.fan_start[e + 1] as usize];
                    let union = (fan.iter()).fold(Aabb::EMPTY, |u, &t| u.union(&boxes[t as usize]));
                    bvh.overlapping_primitives(boxes.as_slice(), &union, 0.0, ws, &mut st.hits);
                    for &tj in &st.hits {
                        for k in local[tj as usize] {
                            let k = k as usize;
                            if again[k] {
                                continue;
                            }
                            let probe = swept[k].expanded(slack);
                            if probe.overlaps(&union, 0.0)
                                && fan.iter().any(|&t| probe.overlaps(&boxes[t as usize], 0.0))
                            {
                                again[k] = true;
                            }
                        }
                    }
                }
                for c in &mut st.chunks {
                    c.dirty = st.order[c.start..c.end].iter().any(|&k| again[k as usize]);
                }
            }
            let (vertices, order, again, swept, boxes, rest_start, rest) = (
                &st.vertices,
                &st.order,
                &st.again,
                &st.swept,
                st.boxes.as_slice(),
                &st.rest_start,
                &st.rest,
            );
            let query = |c: &mut Chunk| {
                if !c.dirty {
                    return;
                }
                // The new list in `spare`: a vertex's pairs found again in a full pass or when
                // marked (`again`), else kept. The vertices to query go by groups of `GROUP`
                // along the chunk (a small patch): one traversal for the union of their boxes,
                // then each vertex's box against the triangles found (the hierarchy visits its
                // leaves in one order whatever the box: a vertex's triangles come in the order
                // its own query would give them).
                c.spare.clear();
                c.dropped = 0;
                let mut cursor = 0;
                for group in order[c.start..c.end].chunks(GROUP) {
                    let asked = (group.iter()).filter(|&&k| full || again[k as usize]);
                    let union = asked
                        .clone()
                        .fold(Aabb::EMPTY, |u, &k| u.union(&swept[k as usize]));
                    if asked.count() > 0 {
                        let union = union.expanded(slack);
                        bvh.overlapping_primitives(
                            boxes,
                            &union,
                            0.0,
                            &mut c.ws,
                            &mut c.candidates,
                        );
                    }
                    for &k in group {
                        let k = k as usize;
                        let begin = cursor;
                        while cursor < c.near.len() && c.near[cursor].local == k as u32 {
                            cursor += 1;
                        }
                        let v = vertices[k];
                        if !(full || again[k]) {
                            let keep = (c.spare.capacity() - c.spare.len()).min(cursor - begin);
                            c.spare.extend_from_slice(&c.near[begin..begin + keep]);
                            c.dropped += cursor - begin - keep;
                            continue;
                        }
                        let probe = swept[k].expanded(slack);
                        let rest = &rest[rest_start[k] as usize..rest_start[k + 1] as usize];
                        for &triangle in &c.candidates {
                            if !boxes[triangle as usize].overlaps(&probe, 0.0) {
                                continue;
                            }
                            let Some(near_at_rest) = relation(rest, triangle) else {
                                continue;
                            };
                            if c.spare.len() == c.spare.capacity() {
                                c.dropped += 1;
                                continue;
                            }
                            c.spare.push(Candidate {
                                vertex: v,
                                local: k as u32,
                                triangle,
                                near_at_rest,
                            });
                        }
                    }
                }
                std::mem::swap(&mut c.near, &mut c.spare);
            };
            if parallel {
                st.chunks.par_iter_mut().for_each(query);
            } else {
                st.chunks.iter_mut().for_each(query);
            }
            st.found = true;
            st.updates += usize::from(!full);
        }
        // This step's pairs: the lists' pairs whose boxes over this step overlap, and that
        // can come within the narrow phase's reach over the step: their distance at its start,
        // less how much their motions (each node along its expected motion, off it by its
        // spread) can close it, at most `√(1 + LATERAL²)` times the band.
        let (tight, outset) = (st.tight.as_slice(), st.outset.as_slice());
        let within = (1.0 + LATERAL * LATERAL).sqrt() * BAND * h;
        let filter = |c: &mut Chunk| {
            c.pairs.clear();
            let mut last = (
                u32::MAX,
                Aabb::from_point(Vec3A::ZERO),
                Vec3A::ZERO,
                Vec3A::ZERO,
                0.0,
            );
            for p in &c.near {
                if p.local != last.0 {
                    let k = p.local as usize;
                    let xv = x[st.vertices[k] as usize];
                    last = (p.local, segment(k), xv, motion[k], 3f32.sqrt() * spread[k]);
                }
                let (_, ref bv, xv, mv, sv) = last;
                if !tight[p.triangle as usize].overlaps(bv, 0.0) {
                    continue;
                }
                let o = &outset[p.triangle as usize];
                let [a, b, c0] = o.corners;
                let (cp, _) = closest_point_on_triangle(xv, a, b, c0);
                let closing = (mv - o.motion).length() + o.deviation + sv;
                if cp.distance(xv) - closing <= within {
                    c.pairs.push(*p);
                }
            }
        };
        if parallel {
            st.chunks.par_iter_mut().for_each(filter);
        } else {
            st.chunks.iter_mut().for_each(filter);
        }
        // The triangles the narrow phase reads this step.
        st.wanted.fill(false);
        for p in st.chunks.iter().flat_map(|c| &c.pairs) {
            st.wanted[p.triangle as usize] = true;
        }
        true
    }

    /// The narrow phase, every substep, on the step's pairs: this substep's contacts.
    /// By chunks (in parallel with `parallel`), each into its own buffer: the contacts, in
    /// the chunks' order, are the same for any thread count.
    fn narrow_phase(&mut self, x: &[Vec3A], q: &[Vec4], rank: &[u32], h: f32, parallel: bool) {
        // Each triangle's normal at the substep's start and its predicted box and extent along
        // it, once per triangle instead of once per pair.
        let triangles = self.triangles.as_slice();
        let facet = |((f, t), &wanted): ((&mut Facet, &[u32; 3]), &bool)| {
            if !wanted {
                return;
            }
            let [a0, a1, a2] = t.map(|i| x[i as usize]);
            let n = (a1 - a0).cross(a2 - a0);
            let len = n.length();
            let [b0, b1, b2] = t.map(|i| point(q, rank[i as usize]));
            *f = if len > 0.0 && len.is_finite() {
                let n = n / len;
                let (nb0, nb1, nb2) = (n.dot(b0), n.dot(b1), n.dot(b2));
                let bounds = Aabb::from_triangle(b0, b1, b2);
                Facet {
                    normal: n,
                    min: bounds.min.into(),
                    max: bounds.max.into(),
                    lowest: nb0.min(nb1).min(nb2),
                    highest: nb0.max(nb1).max(nb2),
                }
            } else {
                Facet::DEGENERATE
            };
        };
        if parallel {
            (self.facets.par_iter_mut().zip(triangles.par_iter()))
                .zip(self.wanted.par_iter())
                .with_min_len(FACETS_PER_TASK)
                .for_each(facet);
        } else {
            (self.facets.iter_mut().zip(triangles))
                .zip(&self.wanted)
                .for_each(facet);
        }
        let (facets, held) = (self.facets.as_slice(), self.held.as_slice());
        let history = (self.last.as_slice(), self.serial.as_slice());
        let narrow = |chunk: &mut Chunk| {
            narrow_chunk(chunk, history, triangles, facets, held, x, q, rank, h)
        };
        if parallel {
            self.chunks.par_iter_mut().for_each(narrow);
        } else {
            self.chunks.iter_mut().for_each(narrow);
        }
        self.sequence.clear();
        let serial = &self.serial;
        for (ci, c) in self.chunks.iter().enumerate() {
            self.sequence.extend(
                (c.contacts.iter().enumerate())
                    .map(|(i, s)| (s.nodes[0], serial[s.triangle as usize], ci as u32, i as u32)),
            );
        }
        self.sequence.sort_unstable();
    }

    /// Empties every chunk's contacts.
    fn clear_contacts(&mut self) {
        for c in &mut self.chunks {
            c.contacts.clear();
            c.contacts_dropped = 0;
        }
        self.sequence.clear();
    }

    /// This substep's contacts, in order.
    fn contacts(&self) -> impl Iterator<Item = &SelfContact> {
        self.chunks.iter().flat_map(|c| &c.contacts)
    }
}

/// The detection band in `h`: a vertex gets a contact with a triangle when its prediction lies
/// within `BAND h` of it along its normal, in front or behind (the thickness `h` plus as much
/// again for the iterations' motion within the substep).
const BAND: f32 = 2.0;

/// Where a triangle starts a step, for the broad phase's last filter: its corners, the mean of
/// their expected motions over the step and how far any corner's path can stray from that mean
/// (the largest corner's deviation from it plus the largest corner's spread, `√3` times).
#[derive(Debug, Clone, Copy)]
struct Outset {
    corners: [Vec3A; 3],
    motion: Vec3A,
    deviation: f32,
}

/// The spread of a vertex's path over a step about its expected segment, in lengths of its
/// first substep's motion: a vertex jittering in place (the step's last substep kicks the
/// nodes, the next ones bring them back) moves by up to about twice its first substep's
/// motion and back within a step, whatever its net motion.
const SPREAD: f32 = 2.0;

/// The fraction of a vertex's spread kept into the next step when its first substep moves it
/// less.
const SPREAD_DECAY: f32 = 0.9;

/// The indices of `points` sorted along a Morton (Z-order) curve (10 bits per axis over their
/// bounding box; ties by index).
fn morton_order(points: &[Vec3A]) -> Vec<u32> {
    let bounds = points
        .iter()
        .fold(Aabb::EMPTY, |b, &p| b.union(&Aabb::from_point(p)));
    let (min, size) = (
        Vec3A::from(bounds.min),
        Vec3A::from(bounds.max - bounds.min).max(Vec3A::splat(f32::MIN_POSITIVE)),
    );
    let spread = |x: u32| {
        // 10 bits, two zeros between each.
        let mut x = x & 0x3ff;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    let mut keyed: Vec<(u32, u32)> = points
        .iter()
        .enumerate()
        .map(|(k, &p)| {
            let u = ((p - min) / size * 1023.0).clamp(Vec3A::ZERO, Vec3A::splat(1023.0));
            let code = spread(u.x as u32) | spread(u.y as u32) << 1 | spread(u.z as u32) << 2;
            (code, k as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, k)| k).collect()
}

/// A surface triangle in a substep, for the narrow phase's cheap rejections: its outward unit
/// normal at the substep's start, and the box and extent along that normal of its predicted
/// corners.
#[derive(Debug, Clone, Copy)]
struct Facet {
    normal: Vec3A,
    min: Vec3A,
    max: Vec3A,
    lowest: f32,
    highest: f32,
}

impl Facet {
    /// A triangle without a normal (zero area at the substep's start): no contact.
    const DEGENERATE: Facet = Facet {
        normal: Vec3A::ZERO,
        min: Vec3A::ZERO,
        max: Vec3A::ZERO,
        lowest: 1.0,
        highest: 0.0,
    };
}

/// Triangles per parallel task when the facets are computed.
const FACETS_PER_TASK: usize = 1024;

/// The narrow phase of one chunk: its pairs' tests into its contacts.
#[allow(clippy::too_many_arguments)]
fn narrow_chunk(
    chunk: &mut Chunk,
    (history, serial): (&[Sequenced], &[u32]),
    triangles: &[[u32; 3]],
    facets: &[Facet],
    held: &[bool],
    x: &[Vec3A],
    q: &[Vec4],
    rank: &[u32],
    h: f32,
) {
    let band = BAND * h;
    let predicted = |i: u32| point(q, rank[i as usize]);
    let Chunk {
        pairs,
        contacts,
        contacts_dropped,
        ..
    } = chunk;
    let mut last = (u32::MAX, Vec3A::ZERO);
    for c in pairs.iter() {
        let v = c.vertex;
        if v != last.0 {
            last = (v, predicted(v));
        }
        let (pv, f) = (last.1, &facets[c.triangle as usize]);
        if f.lowest > f.highest {
            // Degenerate at the substep's start.
            continue;
        }
        // Cheap rejections first: the distance `along` tested below lies between `lo` and
        // `hi` (the predicted triangle's extent along `n`); the vertex, within the cone, is
        // at most `√2 |along|` from the triangle, hence from its box.
        let (n, np) = (f.normal, f.normal.dot(pv));
        let (lo, hi) = (np - f.highest, np - f.lowest);
        if lo >= band || hi < -band {
            continue;
        }
        let most = lo.abs().max(hi.abs());
        if (pv - pv.clamp(f.min, f.max)).length_squared() > 2.1 * most * most {
            continue;
        }
        let t = triangles[c.triangle as usize];
        let xv = x[v as usize];
        let [a0, a1, a2] = t.map(|i| x[i as usize]);
        let [b0, b1, b2] = t.map(predicted);
        let (q1, bary) = closest_point_on_triangle(pv, b0, b1, b2);
        let d = pv - q1;
        let along = n.dot(d);
        if along >= band || along < -band {
            continue;
        }
        if (d - n * along).length() > LATERAL * along.abs() {
            continue;
        }
        // Started on the outer side (at most h behind the plane).
        let (q0, _) = closest_point_on_triangle(xv, a0, a1, a2);
        if n.dot(xv - q0) < -h {
            continue;
        }
        let nodes = [v, t[0], t[1], t[2]];
        let slots = nodes.map(|i| rank[i as usize]);
        let weights = slots.map(|s| q[s as usize].w.max(0.0));
        if (weights.iter().zip(&nodes))
            .all(|(&w, &i)| w <= 0.0 || held.get(i as usize).copied().unwrap_or(true))
        {
            // Every node pinned or held this substep: the holders have the last word.
            continue;
        }
        if contacts.len() == contacts.capacity() {
            *contacts_dropped += 1;
            continue;
        }
        let start = n.dot(xv - (a0 * bary[0] + a1 * bary[1] + a2 * bary[2]));
        if start < -BEHIND * h
            && history
                .binary_search_by(|e| (e.0, e.1).cmp(&(v, serial[c.triangle as usize])))
                .is_err()
        {
            // Deeper behind than the solver's slop, and not held against the triangle in the
            // last substep: through already (a sliver of a fresh cut, a tangle) or beside a
            // crease. Pushing it back across injected energy (the appendix's cut-off blew up,
            // 10⁵ intersecting pairs); the material has it. One that was held there is held
            // still (up to `h` behind): the iterations let it through.
            continue;
        }
        if start < 0.0 && c.near_at_rest {
            // Behind a tet neighbour's face (inside a thin wall, not through it), or
            // behind a face it was near at rest (beside a sharp convex edge): the
            // material's business. Only a vertex that came through from afar is pushed
            // back out.
            continue;
        }
        contacts.push(SelfContact {
            triangle: c.triangle,
            slots,
            nodes,
            bary,
            weights,
            normal: n,
            target: h.min(start + RECOVERY * h),
            normal_correction: 0.0,
            friction_correction: 0.0,
        });
    }
}

impl SoftBody {
    /// Projects the self-contacts once (one iteration), in order.
    pub(crate) fn project_self_contacts(&mut self) {
        let Some(config) = self.self_collision.config else {
            return;
        };
        let (q, x) = (&mut self.q, &self.x);
        let st = &mut self.self_collision;
        for &(_, _, ci, i) in &st.sequence {
            let Some(c) = st
                .chunks
                .get_mut(ci as usize)
                .and_then(|c| c.contacts.get_mut(i as usize))
            else {
                continue;
            };
            let [sv, sa, sb, sc] = c.slots;
            let [u, v, w] = c.bary;
            let [wv, wa, wb, wc] = c.weights;
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use glam::Vec3;
    use tissue_mesh::{tet_box, TetMesh};

    use super::*;
    use crate::{ContactParams, Floor, Material, Pose, StepSettings, ToolShape};

    /// The lists updated for the vertices that left their boxes give the pairs of a full pass:
    /// the upper arm of a weightless U-folded slab pressed onto the lower one by a probe (a
    /// few vertices move at a time, and come near vertices that do not), checked after every
    /// step against a full pass on the same positions.
    #[test]
    fn updated_lists_give_the_pairs_of_a_full_pass() {
        let (positions, tets) = tet_box(30, 2, 5, Vec3::new(6.0, 0.4, 1.0))
            .unwrap()
            .into_parts();
        // Bent into a U (tests/it/selfcol.rs): the upper arm 0.8 cm over the lower one.
        let (s0, r) = (-0.5f32, 0.6f32);
        let loop_len = std::f32::consts::PI * r;
        let bent = positions
            .iter()
            .map(|p| {
                let (s, t) = (p.x, p.y);
                if s <= s0 {
                    Vec3::new(s, t, p.z)
                } else if s <= s0 + loop_len {
                    let phi = (s - s0) / r;
                    Vec3::new(s0 + (r - t) * phi.sin(), r - (r - t) * phi.cos(), p.z)
                } else {
                    Vec3::new(s0 - (s - s0 - loop_len), 2.0 * r - t, p.z)
                }
            })
            .collect();
        let mesh = TetMesh::new(bent, tets).unwrap();
        let mut body = SoftBody::new(&mesh, &Material::soft_tissue()).unwrap();
        body.set_settings(StepSettings {
            gravity: Vec3::ZERO,
            ..StepSettings::realtime()
        })
        .unwrap();
        body.set_floor(Some(Floor::y(-0.2))).unwrap();
        body.set_self_collision(Some(SelfCollision::default()))
            .unwrap();
        // Chunks of four vertices (the arms' vertices in different ones; with larger ones the
        // chunks of the moved vertices cover the others here), and updates however many
        // vertices moved.
        body.self_collision.chunk_size = 4;
        body.self_collision.full_pass = 1;
        let probe = ToolShape::Capsule {
            a: Vec3::new(0.0, 0.0, -1.5),
            b: Vec3::new(0.0, 0.0, 1.5),
            radius: 0.2,
        };
        let at = |y: f32| Pose::from_translation(Vec3::new(-1.5, y, 0.0));
        let tool = body
            .add_tool(probe, at(1.8), ContactParams::default())
            .unwrap();
        let ahead = StepSettings::REALTIME_SUBSTEPS as f32;
        let mut checked = 0;
        for s in 1..=100 {
            body.set_tool_pose(tool, at(1.8 - 1.1 * s as f32 / 100.0))
                .unwrap();
            body.step().unwrap();
            let h = body.self_collision.thickness.unwrap();
            let (x, q, rank) = (&body.x, &body.q, &body.rank);
            // A clone with the buffers' capacities (a clone's are its lengths).
            let copy = || {
                let mut st = body.self_collision.clone();
                for c in &mut st.chunks {
                    let n = c.end - c.start;
                    c.near.reserve(2 * MAX_PAIRS_PER_VERTEX * n - c.near.len());
                    c.spare
                        .reserve(2 * MAX_PAIRS_PER_VERTEX * n - c.spare.len());
                    c.pairs.reserve(MAX_PAIRS_PER_VERTEX * n - c.pairs.len());
                }
                st
            };
            let mut updated = copy();
            let before = updated.updates;
            assert!(updated.broad_phase(x, q, rank, h, ahead, false));
            let mut full = copy();
            full.found = false;
            assert!(full.broad_phase(x, q, rank, h, ahead, false));
            let pairs = |st: &SelfState| -> Vec<Candidate> {
                st.chunks.iter().flat_map(|c| c.pairs.clone()).collect()
            };
            assert_eq!(full.chunks.iter().map(|c| c.dropped).sum::<usize>(), 0);
            assert_eq!(pairs(&updated), pairs(&full), "step {s}");
            checked += updated.updates - before;
        }
        assert!(
            checked > 0,
            "no update without a full pass: the test tests nothing"
        );
    }
}
