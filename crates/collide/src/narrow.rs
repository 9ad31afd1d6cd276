//! The narrow phase shared by every broad phase: a triangle pair becomes the edge–triangle tests
//! of the edges each triangle owns against the other triangle.

use glam::Vec3A;
use tissue_bvh::Aabb;

use crate::edge_triangle::{edge_against, TrianglePlane};
use crate::surface::NOT_OWNED;
use crate::{Contact, DetectStats, EdgeTriangleHit, Side, SurfaceView};

/// What one chunk of the narrow phase writes: its contacts, counts and scratch. The detection
/// runs one chunk per thread over consecutive candidates and concatenates the chunks' contacts.
#[derive(Debug, Clone, Default)]
pub(crate) struct ChunkState {
    pub out: Vec<Contact>,
    pub stats: DetectStats,
    /// B's triangle planes, prepared on first use in this detection (B is the small surface,
    /// whose triangles meet many of A's).
    pub planes_b: PlaneCache,
    /// The B triangles of the current candidate.
    pub tris_b: Vec<Tri>,
}

/// A triangle as the narrow phase reads it, gathered once per candidate.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Tri {
    pub t: u32,
    pub vertices: [u32; 3],
    pub corners: [Vec3A; 3],
    pub aabb: Aabb,
    /// The edges it owns per side, or [`NOT_OWNED`].
    pub owned: [u32; 3],
    pub owns_any: bool,
}

/// The read-only part of a narrow phase.
#[derive(Clone, Copy)]
struct Ctx<'v> {
    a: SurfaceView<'v>,
    b: SurfaceView<'v>,
    tolerance: f32,
    shared: bool,
}

pub(crate) struct Narrow<'v, 'o> {
    ctx: Ctx<'v>,
    pub state: &'o mut ChunkState,
    /// The last A triangle's plane (the loops pair one A triangle with several B triangles).
    last_a: Option<(u32, TrianglePlane)>,
}

impl<'v, 'o> Narrow<'v, 'o> {
    /// A narrow phase writing into `state` (cleared).
    pub fn new(
        a: &SurfaceView<'v>,
        b: &SurfaceView<'v>,
        tolerance: f32,
        shared: bool,
        state: &'o mut ChunkState,
    ) -> Self {
        state.out.clear();
        state.stats = DetectStats::default();
        state.planes_b.begin(b.surface().triangle_count());
        Narrow {
            ctx: Ctx {
                a: *a,
                b: *b,
                tolerance,
                shared,
            },
            state,
            last_a: None,
        }
    }
}

/// Per-detection cache of triangle planes, valid for the triangles stamped with the current
/// detection's number.
#[derive(Debug, Clone, Default)]
pub(crate) struct PlaneCache {
    planes: Vec<TrianglePlane>,
    stamps: Vec<u32>,
    stamp: u32,
}

impl PlaneCache {
    /// Invalidates every entry, for a surface of `n` triangles.
    pub fn begin(&mut self, n: usize) {
        if self.stamps.len() != n {
            self.stamps.clear();
            self.stamps.resize(n, 0);
            self.planes.resize(n, TrianglePlane::default());
        }
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.fill(0);
            self.stamp = 1;
        }
    }

    #[inline]
    fn get(&mut self, t: u32, corners: [Vec3A; 3]) -> &TrianglePlane {
        let i = t as usize;
        if self.stamps[i] != self.stamp {
            self.stamps[i] = self.stamp;
            self.planes[i] = TrianglePlane::new(corners[0], corners[1], corners[2]);
        }
        &self.planes[i]
    }
}

impl Narrow<'_, '_> {
    /// Gathers triangle `t` of `side`.
    #[inline]
    pub fn tri(&self, side: Side, t: u32) -> Tri {
        let v = if side == Side::A {
            &self.ctx.a
        } else {
            &self.ctx.b
        };
        let corners = v.corners(t);
        let owned = v.surface().owned_edges(t);
        Tri {
            t,
            vertices: v.surface().triangles()[t as usize],
            corners,
            aabb: Aabb::from_triangle(corners[0], corners[1], corners[2]),
            owned,
            owns_any: owned.iter().any(|&e| e != NOT_OWNED),
        }
    }

    /// Gathers B's triangles `ts` into `state.tris_b`.
    #[inline]
    pub fn gather_b(&mut self, ts: &[u32]) {
        self.state.tris_b.clear();
        for &t in ts {
            let tri = self.tri(Side::B, t);
            self.state.tris_b.push(tri);
        }
    }

    /// Tests A's triangle `ta` against each of `state.tris_b` whose box it overlaps (grown by
    /// the tolerance) and that `keep` accepts.
    #[inline]
    pub fn against_gathered(&mut self, ta: &Tri, keep: impl Fn(&Tri) -> bool) {
        let tol = self.ctx.tolerance;
        for k in 0..self.state.tris_b.len() {
            if !ta.aabb.overlaps(&self.state.tris_b[k].aabb, tol) {
                continue;
            }
            let tb = self.state.tris_b[k];
            if keep(&tb) {
                self.triangle_pair(ta, &tb);
            }
        }
    }

    /// Tests the edges `ta` owns against `tb` and the edges `tb` owns against `ta` (their boxes
    /// overlap, grown by the tolerance).
    ///
    /// Each triangle's plane is prepared once (B's once per detection) and its vertices' distances
    /// to the other plane computed once; when all three lie beyond the largest reach any of its
    /// edges could have on one side, none of its edges can touch the other triangle and they are
    /// skipped (the test each would fail first). Every edge test runs [`edge_against`] with
    /// exactly the values [`crate::edge_triangle`] would compute, so the contacts are
    /// bit-identical to the brute-force oracle's.
    #[inline]
    fn triangle_pair(&mut self, ta: &Tri, tb: &Tri) {
        self.state.stats.triangle_pairs += 1;
        if !(ta.owns_any || tb.owns_any) {
            return;
        }
        let plane_a = match &self.last_a {
            Some((t, plane)) if *t == ta.t => *plane,
            _ => {
                let [x, y, z] = ta.corners;
                let plane = TrianglePlane::new(x, y, z);
                self.last_a = Some((ta.t, plane));
                plane
            }
        };
        let ctx = self.ctx;
        let ChunkState {
            out,
            stats,
            planes_b,
            ..
        } = &mut *self.state;
        let plane_b = planes_b.get(tb.t, tb.corners);
        // No edge of either triangle is longer than this, so no edge test uses a larger reach.
        let reach = ctx.tolerance + 1e-6 * plane_a.longest().max(plane_b.longest());
        if ta.owns_any {
            let d = ta.corners.map(|x| plane_b.distance(x));
            if !plane_b.all_beyond(d, reach) {
                owned_edges(&ctx, out, stats, &ctx.a, ta, d, reach, tb, plane_b);
            }
        }
        if tb.owns_any {
            let d = tb.corners.map(|x| plane_a.distance(x));
            if !plane_a.all_beyond(d, reach) {
                owned_edges(&ctx, out, stats, &ctx.b, tb, d, reach, ta, &plane_a);
            }
        }
    }

    /// Edge `e` of `ev` against triangle `t` of `tv`, whose prepared plane is `plane` (the
    /// brute-force path: the same arithmetic as [`crate::edge_triangle`]).
    #[inline]
    pub fn edge(
        &mut self,
        ev: &SurfaceView<'_>,
        e: u32,
        tv: &SurfaceView<'_>,
        t: u32,
        plane: &TrianglePlane,
    ) {
        let [i, j] = ev.surface().edges()[e as usize];
        let tri = tv.surface().triangles()[t as usize];
        if self.ctx.shared && (tri.contains(&i) || tri.contains(&j)) {
            return;
        }
        self.state.stats.edge_tests += 1;
        let pos = ev.positions();
        let (p, q) = (pos[i as usize], pos[j as usize]);
        let hit = edge_against(
            plane,
            p,
            q,
            plane.distance(p),
            plane.distance(q),
            self.ctx.tolerance,
        );
        if let Some(hit) = hit {
            push(&mut self.state.out, ev.side(), e, [i, j], t, tri, hit);
        }
    }
}

/// The owned edges of triangle `te` (of surface `ev`; `d` its corners' distances to `plane`)
/// against triangle `t` (with plane `plane`).
#[allow(clippy::too_many_arguments)]
#[inline]
fn owned_edges(
    ctx: &Ctx<'_>,
    out: &mut Vec<Contact>,
    stats: &mut DetectStats,
    ev: &SurfaceView<'_>,
    te: &Tri,
    d: [f32; 3],
    reach: f32,
    t: &Tri,
    plane: &TrianglePlane,
) {
    let tri_e = te.vertices;
    for (k, &e) in te.owned.iter().enumerate() {
        if e == NOT_OWNED {
            continue;
        }
        // Side k runs tri_e[k] → tri_e[k + 1]; the edge is stored smaller index first.
        let k1 = (k + 1) % 3;
        let (lo, hi) = if tri_e[k] < tri_e[k1] {
            (k, k1)
        } else {
            (k1, k)
        };
        // The first test of `edge_against`, with a reach no smaller than the edge's own.
        if plane.all_beyond([d[lo], d[hi], d[hi]], reach) {
            continue;
        }
        let (i, j) = (tri_e[lo], tri_e[hi]);
        if ctx.shared && (t.vertices.contains(&i) || t.vertices.contains(&j)) {
            continue;
        }
        stats.edge_tests += 1;
        let (p, q) = (te.corners[lo], te.corners[hi]);
        if let Some(hit) = edge_against(plane, p, q, d[lo], d[hi], ctx.tolerance) {
            push(out, ev.side(), e, [i, j], t.t, t.vertices, hit);
        }
    }
}

#[inline]
fn push(
    out: &mut Vec<Contact>,
    side: Side,
    e: u32,
    ij: [u32; 2],
    t: u32,
    tri: [u32; 3],
    hit: EdgeTriangleHit,
) {
    out.push(Contact {
        edge_side: side,
        edge: e,
        edge_particles: ij,
        s: hit.s,
        triangle: t,
        triangle_particles: tri,
        barycentric: hit.barycentric,
        normal: hit.normal.into(),
        depth: hit.depth,
    });
}
