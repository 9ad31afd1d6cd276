//! The cut's ends on the surface: the surface triangle in which the swept polygon's boundary
//! (the blade's front, or where the cut started) crosses the surface is split at the **tip**,
//! the point where that boundary crosses it, and the opening on the surface ends there.
//!
//! **Four-way tips** ([`Surgery::plan_four_way_tips`], in the first split's plan, before
//! anything is applied). A crossed boundary triangle `A B C` of a tet `A B C D` to be split,
//! `A` alone on its side of the plane, both `A B` and `A C` planned for a split, the crossing
//! point `E` of `A B` in the polygon and `E2` of `A C` outside it (within `FRONT_SNAP`):
//! the edge `A C` is dropped from the split edges (globally: every tet around it is bisected
//! without it, which keeps the ordered bisection conforming) and marked outside the polygon,
//! so the tets around it after the split — the pieces holding both `A` and `C`, which are the
//! only pieces with nodes of both sides — are the cut's front and stay glued this sweep. `A B
//! C D`'s pieces then include one `(A, E, C, Y)` with its face `A E C` on the boundary
//! triangle and `Y` a new node on the plane (the crossing point of `A D`, `B D` or `C D`, or
//! `D` itself on the plane); for some orders with `D` on `A`'s side one more piece holds `A`
//! and `C` (unit test). The tip `P`, where the polygon's boundary crosses the segment `E–E2`
//! (bisection on `CutPlane::contains`, `E2` a point only), is inserted into `A E C` by a 1→3
//! face split ([`split_face`]): `(A, E, P, Y)`, `(P, E, C, Y)`, `(A, P, C, Y)`. `A B C` is then
//! in exactly 4 boundary pieces `A E P`, `E C P`, `C A P`, `E B C` (one `SplitTriangle`). The
//! wall `E P Y` lies on the plane and is queued to open with the sweep's faces
//! ([`Surgery::open_tip_wall`]: the centroid rule alone can miss it, the polygon's boundary
//! passing through `P`); `(A, P, C, Y)` is in the front, so `P` keeps one node while `E` is
//! duplicated. A later sweep that continues the cut splits `A C` (and the piece) normally; `P`
//! then lies on the crack between `E` and `E2` and becomes an ordinary wall node. `P` is a new
//! node interpolated (current, previous, rest position, velocity) as the weighted sum of `A`,
//! `B`, `C`; masses and constraints are rebuilt by the same `apply_split` as edge nodes.
//!
//! A candidate is refused — `A C` stays split and the triangle goes to the fallback below —
//! when: `P` is within [`FACE_TIP_MARGIN`] (barycentric) of a side of `A E C`; another
//! boundary triangle at `A C` would want a tip (a node on the plane, or its other crossing
//! point split and in the polygon); a face on the plane that the tets around `A C` have with
//! it split but not without it (other than those at `E–E2`, which `E P Y` replaces) would open
//! under the rules of the face separation (its two pieces not at the front and their centroid
//! segment crossing the polygon: the cut runs there, e.g. under a blade whose front leans
//! forward); or a tet around `A C`, bisected without it (with the face split in
//! `A B C D`), would have a piece below the split's bound ([`crate::MIN_RATIO`],
//! [`crate::MIN_PIECE_FRACTION`], tiling the parent in rest space) or no piece on `A E C` with
//! `Y` on the plane. [`Surgery::tip_counts`] counts each way.
//!
//! **Fallback: tips on the crack line** ([`Surgery::split_tips`], after the first split is
//! applied). A crossed boundary triangle `A B C` holding an edge `E–E2` on the plane (both
//! crossing points split, or a node on the plane and a crossing point) with `E` in the polygon
//! and `E2` outside: that edge is split again at the tip `P` where it leaves the polygon, and
//! every tet around it is bisected once more (the same ordered bisection, a second pass). The
//! triangle is then in 5 boundary pieces (4 where the plane enters it through a node): the
//! triangle and the quad piece on the two sides of `E–E2` each halved at `P`, and the quad's
//! other piece. The tets around `P–E2` (beyond the tip) join the cut's front for this sweep:
//! their faces stay glued, so `P` keeps one node while `E` is duplicated.
//!
//! Rules of the fallback: the edge must have tets on both sides of the plane (an edge of an
//! opening already made has only one side: it is not split again), exactly two nodes of the
//! boundary triangle on the plane (a wall lying in the plane is not a crossed triangle), not a
//! four-way tip's, and `P` at least [`TIP_MARGIN`] of the edge from either end; the pieces must
//! meet the same quality bound as the first split's ([`crate::MIN_RATIO`],
//! [`crate::MIN_PIECE_FRACTION`], [`crate::MAX_SPLIT_DEPTH`], pieces tiling the parent in rest
//! space). Otherwise no tip is inserted and the cut ends there as without it (at a tet
//! boundary).

use glam::DVec3;
use tissue_mesh::NO_TET;
use tissue_pbd::SoftBody;

use crate::geometry::FxMap as HashMap;
use crate::plan::{EdgeCut, FacePoint, NewNode, NodeRef, SplitEdge, SplitPlan, TetSplit};
use crate::split::MAX_SPLIT_DEPTH;
use crate::split::{bisect, sorted2, split_edges_of, CutPlane, SplitOutcome};
use crate::state::{face_nodes, FacePair};
use crate::{SplitTriangle, Surgery, SurgeryError};

/// A four-way tip is inserted only where each of its barycentric coordinates in the triangle
/// `A E C` (module docs) is at least this: the tip lies clearly inside that triangle, so the
/// three tets it splits the piece on `A E C` into are each at least this fraction of it and
/// none is flat. Otherwise the tip falls back to the five-way split.
pub const FACE_TIP_MARGIN: f64 = 0.05;

/// How the cuts of a [`Surgery`] ended on the surface, counted per tip since it was made
/// ([`Surgery::tip_counts`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TipCounts {
    /// Boundary triangles split into 4 at a tip inside them.
    pub four_way: u64,
    /// Tips inserted by the second pass on a crossed triangle's edge on the plane (the tip on
    /// the crack line: the triangle in 5 pieces, or in 4 where the plane enters it through a
    /// node on it): the fallback, and every tip with [`crate::SurgerySettings::four_way_tips`]
    /// off.
    pub fallback: u64,
    /// Candidates for a four-way tip refused (each falls back to the five-way split or to no
    /// tip), by reason: the tip too close to the triangle `A E C`'s sides ([`FACE_TIP_MARGIN`]),
    pub refused_margin: u64,
    /// another boundary triangle at `A C` would want a tip of its own,
    pub refused_neighbour: u64,
    /// the tet under the triangle has no piece on `A E C` whose fourth node is on the plane (it
    /// keeps another crossing edge whole: given up by the split's quality rounds, or at a node
    /// near the plane that could not be snapped),
    pub refused_unsplit: u64,
    /// an on-plane face at the crossing point `E2` would open (the edge `A C` is needed),
    pub refused_needed: u64,
    /// or the pieces would fall below the quality bound.
    pub refused_quality: u64,
}

/// A planned four-way tip (module docs): the tet `A B C D` under the boundary triangle `A B C`,
/// its edge `A B` split (its node `E` in the polygon), `A C` not split, and the tip `P` as a
/// weighted sum of `A`, `B`, `C`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FourWayTip {
    pub tet: u32,
    pub a: u32,
    pub c: u32,
    pub ab: [u32; 2],
    pub point: FacePoint,
}

/// Splits the piece of `pieces` holding the face `a e c` (a boundary face) at a point `p`
/// strictly inside that face: the piece `(a, e, c, y)` (in its own order) becomes three, each
/// the piece with one of `a`, `e`, `c` replaced by `p` (so each keeps its orientation, its
/// volume being the piece's times `p`'s barycentric coordinate there). The first replaces the
/// piece in place, the others are appended. Returns `y`, or `None` when no piece holds the
/// face (nothing changed).
pub(crate) fn split_face<N: Copy + PartialEq>(
    pieces: &mut Vec<[N; 4]>,
    face: [N; 3],
    p: N,
) -> Option<N> {
    let i = pieces
        .iter()
        .position(|t| face.iter().all(|v| t.contains(v)))?;
    let piece = pieces[i];
    let y = *piece.iter().find(|v| !face.contains(v))?;
    let with_p = |v: N| piece.map(|u| if u == v { p } else { u });
    pieces[i] = with_p(face[2]);
    pieces.push(with_p(face[0]));
    pieces.push(with_p(face[1]));
    Some(y)
}

/// A tip closer to either end of its edge than this fraction of the edge's length is not
/// inserted (the cut ends at that end, or as without a tip split).
pub const TIP_MARGIN: f64 = 0.15;

/// A node this close to the blade's plane (a fraction of its reach, 1.5 × its longest rest
/// edge) counts as on it for the tip split: a node an earlier sweep made on the same plane.
const ON_PLANE: f64 = 1e-5;

impl Surgery {
    /// The tip split of one sweep (module docs), after the first split was applied: `out` is
    /// the first split's outcome and is extended (nodes, tets, split tets, boundary triangles:
    /// a first-split triangle's pieces split again are replaced by their pieces). Returns the
    /// edges `P–E2` beyond the tips, whose tets are the cut's front.
    pub(crate) fn split_tips(
        &mut self,
        body: &mut SoftBody,
        plane: &CutPlane<'_>,
        candidates: &[u32],
        out: &mut SplitOutcome,
    ) -> Result<Vec<[u32; 2]>, SurgeryError> {
        let on = self.crossed_edges_on_plane(body, candidates, out);
        if on.is_empty() {
            return Ok(Vec::new());
        }
        let (mut edges, outer) = self.tip_edges(body, plane, on);
        if edges.is_empty() {
            return Ok(Vec::new());
        }
        let first = body.node_count() as u32;
        let Some(plan) = self.plan_tip_split(body, &mut edges) else {
            return Ok(Vec::new());
        };
        tracing::debug!(
            tips = plan.edges.len(),
            tets = plan.tets.len(),
            "tips split"
        );
        let mut second = SplitOutcome::default();
        self.apply_split(body, &plan, &mut second)?;
        self.tip_counts.fallback += plan.edges.len() as u64;
        // Merge into the first split's outcome: nodes and tets were appended right after its.
        out.end_node = second.end_node;
        out.end_tet = second.end_tet;
        for t in second.split {
            if t < out.first_tet && !out.split.contains(&t) {
                out.split.push(t);
            }
        }
        merge_surface(&mut out.surface, second.surface);
        Ok(plan
            .edges
            .iter()
            .enumerate()
            .map(|(k, e)| sorted2(first + k as u32, outer[&e.ends]))
            .collect())
    }

    /// The edges on the plane of the crossed boundary triangles: boundary faces of the
    /// `candidates` and of the first split's pieces with exactly two nodes on the plane (the
    /// first split's new nodes, and nodes snapped or lying on it within rounding: nodes made
    /// on it by an earlier sweep are a few ulps off), except a four-way tip's (sorted).
    fn crossed_edges_on_plane(
        &self,
        body: &SoftBody,
        candidates: &[u32],
        out: &SplitOutcome,
    ) -> Vec<[u32; 2]> {
        let (new_lo, new_hi) = (out.first_node, out.end_node);
        let (side, reach) = (&self.scratch.side, &self.node_reach);
        let on_plane = |v: u32| {
            (new_lo..new_hi).contains(&v)
                || side
                    .get(v as usize)
                    .is_some_and(|&d| d.abs() <= ON_PLANE * reach[v as usize] as f64)
        };
        let mut on: Vec<[u32; 2]> = Vec::new();
        let tets = body.tets();
        for t in candidates.iter().copied().chain(out.first_tet..out.end_tet) {
            for j in 0..4 {
                if self.neighbours[t as usize][j] != NO_TET {
                    continue;
                }
                let f = face_nodes(&tets[t as usize], j);
                let p: Vec<u32> = f.iter().copied().filter(|&v| on_plane(v)).collect();
                // A four-way tip's triangles are done.
                if p.len() == 2 && !p.iter().any(|v| out.four_way.contains(v)) {
                    on.push(sorted2(p[0], p[1]));
                }
            }
        }
        on.sort_unstable();
        on.dedup();
        on
    }

    /// The edges of `on` that get a tip: one end in the polygon and the other outside, the
    /// tip (where the edge leaves the polygon, by bisection) at least [`TIP_MARGIN`] from
    /// either end, tets around it on both sides of the plane. Returns them as split edges
    /// (the tip's parameter from the smaller node), and each one's end outside the polygon.
    fn tip_edges(
        &self,
        body: &SoftBody,
        plane: &CutPlane<'_>,
        on: Vec<[u32; 2]>,
    ) -> (HashMap<[u32; 2], EdgeCut>, HashMap<[u32; 2], u32>) {
        let (o, n) = (plane.origin, plane.normal);
        let pos = |v: u32| body.positions()[v as usize].as_dvec3();
        let side_of = |t: u32| {
            let c = body.tets()[t as usize]
                .iter()
                .map(|&v| pos(v))
                .sum::<DVec3>()
                * 0.25;
            n.dot(c - o)
        };
        let mut edges: HashMap<[u32; 2], EdgeCut> = HashMap::default();
        let mut outer: HashMap<[u32; 2], u32> = HashMap::default();
        for e in on {
            let (x0, x1) = (pos(e[0]), pos(e[1]));
            let (in0, in1) = (plane.contains(x0), plane.contains(x1));
            if in0 == in1 {
                continue;
            }
            // `a` inside, `b` outside (parameters from the inside end).
            let (a, b) = if in0 { (x0, x1) } else { (x1, x0) };
            let t = polygon_exit(plane, a, b);
            if !(TIP_MARGIN..=1.0 - TIP_MARGIN).contains(&t) {
                continue;
            }
            let (mut plus, mut minus) = (false, false);
            for u in self.tets_around(body.tets(), &e) {
                let d = side_of(u);
                plus |= d > 0.0;
                minus |= d < 0.0;
            }
            if !(plus && minus) {
                continue;
            }
            let s = if in0 { t } else { 1.0 - t };
            edges.insert(
                e,
                EdgeCut {
                    s,
                    inside: true,
                    valid: true,
                    node: None,
                },
            );
            outer.insert(e, if in0 { e[1] } else { e[0] });
        }
        (edges, outer)
    }

    /// The tip split's plan, as the first split plans (see `split_along`): a tet whose pieces
    /// fail the bound gives up its tip edges, and the rest is planned again. `None` when no
    /// edge is left.
    fn plan_tip_split(
        &self,
        body: &SoftBody,
        edges: &mut HashMap<[u32; 2], EdgeCut>,
    ) -> Option<SplitPlan> {
        let mut plan = SplitPlan::default();
        let mut order: Vec<[u32; 2]> = Vec::new();
        let mut local: Vec<([u32; 2], NodeRef)> = Vec::new();
        loop {
            order.clear();
            order.extend(edges.iter().filter(|(_, c)| c.valid).map(|(e, _)| *e));
            order.sort_unstable();
            if order.is_empty() {
                return None;
            }
            plan.edges.clear();
            plan.new_rest.clear();
            for (k, e) in order.iter().enumerate() {
                if let Some(c) = edges.get_mut(e) {
                    c.node = Some(NewNode(k as u32));
                    let (r0, r1) = (self.rest[e[0] as usize], self.rest[e[1] as usize]);
                    plan.new_rest.push(r0 + (r1 - r0) * c.s);
                    plan.edges.push(SplitEdge { ends: *e, s: c.s });
                }
            }
            let affected = self.tets_around_edges(body.tets(), &order);
            let new_rest = &plan.new_rest;
            let rest_of = |v: NodeRef| -> DVec3 {
                match v {
                    NodeRef::Body(v) => self.rest[v as usize],
                    NodeRef::New(NewNode(k)) => new_rest[k as usize],
                }
            };
            plan.pieces.clear();
            plan.tets.clear();
            let mut failed: Vec<[u32; 2]> = Vec::new();
            for &t in &affected {
                let tet = body.tets()[t as usize];
                split_edges_of(tet, edges, &mut local);
                let start = plan.pieces.len();
                bisect(tet.map(NodeRef::Body), &local, &mut plan.pieces);
                let good =
                    self.pieces_meet_bound(tet.map(NodeRef::Body), &plan.pieces[start..], rest_of)
                        && self.depth[t as usize] < MAX_SPLIT_DEPTH;
                if good {
                    plan.tets.push(TetSplit {
                        tet: t,
                        pieces: start..plan.pieces.len(),
                    });
                } else {
                    plan.pieces.truncate(start);
                    failed.extend(local.iter().map(|l| l.0));
                }
            }
            if failed.is_empty() {
                return Some(plan);
            }
            for e in failed {
                if let Some(c) = edges.get_mut(&e) {
                    c.valid = false;
                }
            }
        }
    }
}

/// Where the segment `a → b` (`a` in the polygon of `plane`, `b` outside) leaves the polygon:
/// its parameter along the segment, by 40 bisections on [`CutPlane::contains`].
fn polygon_exit(plane: &CutPlane<'_>, a: DVec3, b: DVec3) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if plane.contains(a + (b - a) * mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Boundary triangles split again by the tip split: a first-split piece is replaced by its
/// pieces (the triangle is reported once, split into all its pieces); others are added.
fn merge_surface(first: &mut Vec<SplitTriangle>, second: Vec<SplitTriangle>) {
    let key = |f: &[u32; 3]| {
        let mut k = *f;
        k.sort_unstable();
        k
    };
    for s in second {
        let k = key(&s.original);
        let hit = first.iter_mut().find_map(|tri| {
            let i = tri.pieces.iter().position(|p| key(p) == k)?;
            Some((tri, i))
        });
        match hit {
            Some((tri, i)) => {
                tri.pieces.splice(i..=i, s.pieces);
            }
            None => first.push(s),
        }
    }
}

/// A boundary triangle `A B C` that may get a four-way tip (module docs): of tet `tet`, `A`
/// alone on its side, `A B` and `A C` split, `E` on `A B` in the polygon and `E2` on `A C`
/// outside it. Ordered by `A C` first, so that the triangles at one edge `A C` are together.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct TipCandidate {
    ac: [u32; 2],
    tet: u32,
    a: u32,
    b: u32,
    c: u32,
}

/// Why the four-way candidates at one edge `A C` were refused (see [`TipCounts`]).
#[derive(Debug, Clone, Copy)]
enum Refusal {
    Neighbour,
    Margin,
    Needed,
    Unsplit,
    Quality,
}

impl Refusal {
    /// Counts `triangles` candidates refused for this reason.
    fn count(self, counts: &mut TipCounts, triangles: u64) {
        let n = match self {
            Refusal::Neighbour => &mut counts.refused_neighbour,
            Refusal::Margin => &mut counts.refused_margin,
            Refusal::Needed => &mut counts.refused_needed,
            Refusal::Unsplit => &mut counts.refused_unsplit,
            Refusal::Quality => &mut counts.refused_quality,
        };
        *n += triangles;
    }
}

/// What the four-way planning reads of one sweep: the body (current positions), the plane,
/// the nodes' signed distances from it, and the current positions of the candidate edges'
/// crossing points (the new nodes `NewNode(i)` of the plan being judged).
struct TipSweep<'a, 'p> {
    body: &'a SoftBody,
    plane: &'a CutPlane<'p>,
    side: &'a [f64],
    crossings: Vec<DVec3>,
}

impl TipSweep<'_, '_> {
    /// Current position of a node of the plan (`NaN` for a tip's point).
    fn point(&self, v: NodeRef) -> DVec3 {
        match v {
            NodeRef::Body(v) => self.body.positions()[v as usize].as_dvec3(),
            NodeRef::New(NewNode(i)) => self
                .crossings
                .get(i as usize)
                .copied()
                .unwrap_or(DVec3::NAN),
        }
    }

    /// The side of the plane node `v` is on (0: on it).
    fn sign(&self, v: u32) -> i8 {
        match self.side.get(v as usize) {
            Some(&d) if d > 0.0 => 1,
            Some(&d) if d < 0.0 => -1,
            _ => 0,
        }
    }

    /// Whether a node of the plan lies on the plane: a new node, or a node exactly on it.
    fn on_plane(&self, v: NodeRef) -> bool {
        match v {
            NodeRef::New(_) => true,
            NodeRef::Body(v) => self.side.get(v as usize).is_some_and(|&d| d == 0.0),
        }
    }
}

/// The split edge's node of `edges` at `e`, if it is split.
fn split_node(edges: &HashMap<[u32; 2], EdgeCut>, e: [u32; 2]) -> Option<NodeRef> {
    edges
        .get(&e)
        .filter(|c| c.valid)
        .and_then(|c| c.node)
        .map(NodeRef::New)
}

impl Surgery {
    /// The four-way tips of one sweep (module docs), planned on the first split's plan before
    /// it is applied: `edges` holds the split edges after the quality rounds, the new node of
    /// `candidate_edges[i]` being `NewNode(i)` (rest position `candidate_rest[i]`, tip `k`'s
    /// point `NewNode(candidate_edges.len() + k)`), and `affected` the tets to split. For each
    /// accepted tip the edge `A C` is dropped from `edges` (not valid, and not inside: the tets
    /// around it join the cut's front), and tets left with no split edge are removed from
    /// `affected`. A candidate refused keeps `A C` (the tip pass may then split the triangle
    /// into 5).
    pub(crate) fn plan_four_way_tips(
        &mut self,
        body: &SoftBody,
        plane: &CutPlane<'_>,
        affected: &mut Vec<u32>,
        edges: &mut HashMap<[u32; 2], EdgeCut>,
        candidate_edges: &[[u32; 2]],
        candidate_rest: &[DVec3],
    ) -> Vec<FourWayTip> {
        let mut tips: Vec<FourWayTip> = Vec::new();
        if !self.settings.four_way_tips || affected.is_empty() {
            return tips;
        }
        let mut counts = self.tip_counts;
        let pos = |v: u32| body.positions()[v as usize].as_dvec3();
        let sweep = TipSweep {
            body,
            plane,
            side: &self.scratch.side,
            crossings: candidate_edges
                .iter()
                .map(|e| {
                    let s = edges.get(e).map_or(0.0, |c| c.s);
                    pos(e[0]) + (pos(e[1]) - pos(e[0])) * s
                })
                .collect(),
        };
        let found = self.four_way_candidates(&sweep, affected, edges);
        if found.is_empty() {
            return tips;
        }
        let mut local: Vec<([u32; 2], NodeRef)> = Vec::new();
        let mut scratch: Vec<[NodeRef; 4]> = Vec::new();
        for group in found.chunk_by(|x, y| x.ac == y.ac) {
            let triangles = group.len() as u64;
            let taken = self.four_way_group(
                &sweep,
                group,
                edges,
                &mut tips,
                candidate_rest,
                &mut local,
                &mut scratch,
            );
            match taken {
                Ok(()) => counts.four_way += triangles,
                Err(refusal) => refusal.count(&mut counts, triangles),
            }
        }
        if !tips.is_empty() {
            affected.retain(|&t| {
                split_edges_of(body.tets()[t as usize], edges, &mut local);
                !local.is_empty()
            });
        }
        self.tip_counts = counts;
        tips
    }

    /// The candidates (sorted): boundary triangles `A B C` of the `affected` tets, `A` alone on
    /// its side, `A B` and `A C` split, exactly one of the two crossing points in the polygon
    /// (`A B`'s, after renaming).
    fn four_way_candidates(
        &self,
        sweep: &TipSweep<'_, '_>,
        affected: &[u32],
        edges: &HashMap<[u32; 2], EdgeCut>,
    ) -> Vec<TipCandidate> {
        let mut found: Vec<TipCandidate> = Vec::new();
        for &t in affected {
            let nb = self.neighbours[t as usize];
            if !nb.contains(&NO_TET) {
                continue;
            }
            let tet = sweep.body.tets()[t as usize];
            for j in (0..4).filter(|&j| nb[j] == NO_TET) {
                let f = face_nodes(&tet, j);
                let sf = f.map(|v| sweep.sign(v));
                if sf.contains(&0) {
                    continue;
                }
                let Some(i) =
                    (0..3).find(|&i| sf[i] != sf[(i + 1) % 3] && sf[i] != sf[(i + 2) % 3])
                else {
                    continue;
                };
                let (a, u, w) = (f[i], f[(i + 1) % 3], f[(i + 2) % 3]);
                let (Some(nu), Some(nw)) = (
                    split_node(edges, sorted2(a, u)),
                    split_node(edges, sorted2(a, w)),
                ) else {
                    continue;
                };
                let inside = |v: NodeRef| sweep.plane.contains(sweep.point(v));
                let (iu, iw) = (inside(nu), inside(nw));
                if iu == iw {
                    continue;
                }
                let (b, c) = if iu { (u, w) } else { (w, u) };
                found.push(TipCandidate {
                    ac: sorted2(a, c),
                    tet: t,
                    a,
                    b,
                    c,
                });
            }
        }
        found.sort_unstable();
        found
    }

    /// Judges the candidates at one edge `A C` (`group`, sharing it): taken (their tips
    /// appended to `tips`, `A C` dropped from `edges`) or refused, and why. The tets around
    /// `A C` are judged with the tips planned and `A C` dropped; `local` and `scratch` are
    /// scratch.
    #[allow(clippy::too_many_arguments)]
    fn four_way_group(
        &self,
        sweep: &TipSweep<'_, '_>,
        group: &[TipCandidate],
        edges: &mut HashMap<[u32; 2], EdgeCut>,
        tips: &mut Vec<FourWayTip>,
        candidate_rest: &[DVec3],
        local: &mut Vec<([u32; 2], NodeRef)>,
        scratch: &mut Vec<[NodeRef; 4]>,
    ) -> Result<(), Refusal> {
        let ac = group[0].ac;
        let ring: Vec<u32> = self.tets_around(sweep.body.tets(), &ac).collect();
        if !self.only_candidates_at(sweep, group, &ring, edges) {
            return Err(Refusal::Neighbour);
        }
        let (planned, e_nodes, e2) = tip_points(sweep, group, edges).ok_or(Refusal::Margin)?;
        if self.crossing_needed(sweep, &ring, ac, e2, &e_nodes, edges) {
            return Err(Refusal::Needed);
        }
        // Dropped tentatively; the tets around A C judged again with the tips.
        let base = tips.len();
        tips.extend(planned);
        if let Some(c) = edges.get_mut(&ac) {
            c.valid = false;
        }
        let n_edges = sweep.crossings.len();
        let mut failure: Option<Refusal> = None;
        for &u in &ring {
            if !self.four_way_pieces(sweep, u, edges, tips, n_edges, local, scratch) {
                failure = Some(Refusal::Unsplit);
                break;
            }
            let tet = sweep.body.tets()[u as usize].map(NodeRef::Body);
            let rest_of = |v: NodeRef| -> DVec3 { self.rest_with_tips(v, candidate_rest, tips) };
            if !self.pieces_meet_bound(tet, scratch, rest_of) {
                failure = Some(Refusal::Quality);
                break;
            }
        }
        let good = failure.is_none();
        if let Some(c) = edges.get_mut(&ac) {
            c.valid = !good;
            c.inside = !good;
        }
        match failure {
            None => Ok(()),
            Some(refusal) => {
                tips.truncate(base);
                Err(refusal)
            }
        }
    }

    /// Whether every other boundary triangle `A C X` at `A C` (dropping `A C` leaves it
    /// unsplit along it) is one of the `group` or does not want a tip: `X` off the plane, and
    /// its other crossing point, if split, outside the polygon (so both are: the triangle is
    /// beyond the tip). `ring`: the tets around `A C`.
    fn only_candidates_at(
        &self,
        sweep: &TipSweep<'_, '_>,
        group: &[TipCandidate],
        ring: &[u32],
        edges: &HashMap<[u32; 2], EdgeCut>,
    ) -> bool {
        let ac = group[0].ac;
        let beyond = |f: [u32; 3]| {
            let Some(&x) = f.iter().find(|v| !ac.contains(v)) else {
                return false;
            };
            if sweep.sign(x) == 0 {
                return false;
            }
            let other = if sweep.sign(x) == sweep.sign(ac[0]) {
                ac[1]
            } else {
                ac[0]
            };
            split_node(edges, sorted2(x, other))
                .is_none_or(|v| !sweep.plane.contains(sweep.point(v)))
        };
        ring.iter().all(|&u| {
            let tet = sweep.body.tets()[u as usize];
            (0..4).all(|j| {
                let f = face_nodes(&tet, j);
                self.neighbours[u as usize][j] != NO_TET
                    || !(f.contains(&ac[0]) && f.contains(&ac[1]))
                    || group.iter().any(|g| g.tet == u && f.contains(&g.b))
                    || beyond(f)
            })
        })
    }

    /// Queues the wall face `E P Y` of an applied four-way tip (node `p`, `E` node `e`) to
    /// open with this sweep's faces (as a face glued earlier is retried, see `cut`): it lies
    /// on the plane between the piece on `A`'s side and the piece on `C`'s, both inside the
    /// cut (their crossing points are split), but the segment between their centroids crosses
    /// the plane at `(E + P + Y + E2) / 4`, which can lie beyond the polygon's boundary (that
    /// passes through `P`), so the centroid rule alone may leave it glued.
    pub(crate) fn open_tip_wall(&mut self, body: &SoftBody, tip: &FourWayTip, e: u32, p: u32) {
        let tets = body.tets();
        let Some(star) = self.node_tets.get(p as usize) else {
            return;
        };
        let side = |end: u32| {
            star.iter().copied().find_map(|t| {
                let tet = tets[t as usize];
                let j = tet.iter().position(|&v| v == end)?;
                tet.contains(&e).then_some((t, j))
            })
        };
        if let (Some((t, j)), Some((u, k))) = (side(tip.a), side(tip.c)) {
            if self.neighbours[t as usize][j] == u && self.neighbours[u as usize][k] == t {
                self.pending.push(FacePair {
                    t,
                    j: j as u8,
                    u,
                    k: k as u8,
                });
            }
        }
    }

    /// Rest position of node `v` of the plan being judged: a node of the body, a candidate
    /// edge's node (`NewNode(i)`, `i` below `candidate_rest.len()`), or a tip's point (the
    /// tips' new nodes follow the edges').
    fn rest_with_tips(&self, v: NodeRef, candidate_rest: &[DVec3], tips: &[FourWayTip]) -> DVec3 {
        let i = match v {
            NodeRef::Body(v) => return self.rest[v as usize],
            NodeRef::New(NewNode(i)) => i as usize,
        };
        if let Some(&r) = candidate_rest.get(i) {
            return r;
        }
        tips.get(i - candidate_rest.len())
            .map_or(DVec3::NAN, |tip| tip.point.rest(&self.rest))
    }

    /// The pieces of tet `u` (into `scratch`) under the valid `edges` and the planned `tips`
    /// (tip `k`'s point is `NewNode(n_edges + k)`); `false` when a tip's face is in no piece
    /// or its piece's fourth node is off the plane.
    #[allow(clippy::too_many_arguments)]
    fn four_way_pieces(
        &self,
        sweep: &TipSweep<'_, '_>,
        u: u32,
        edges: &HashMap<[u32; 2], EdgeCut>,
        tips: &[FourWayTip],
        n_edges: usize,
        local: &mut Vec<([u32; 2], NodeRef)>,
        scratch: &mut Vec<[NodeRef; 4]>,
    ) -> bool {
        let tet = sweep.body.tets()[u as usize];
        split_edges_of(tet, edges, local);
        scratch.clear();
        bisect(tet.map(NodeRef::Body), local, scratch);
        for (k, tip) in tips.iter().enumerate().filter(|(_, tip)| tip.tet == u) {
            let Some(e) = split_node(edges, tip.ab) else {
                return false;
            };
            let p = NodeRef::New(NewNode((n_edges + k) as u32));
            let Some(y) = split_face(scratch, [tip.a.into(), e, tip.c.into()], p) else {
                return false;
            };
            if !sweep.on_plane(y) {
                return false;
            }
        }
        true
    }

    /// Whether the tets `ring` around `A C` need it split: a face on the plane between two of a
    /// ring tet's pieces with `A C` split that is not one without it (lost with `E2`: the
    /// pieces holding both `A` and `C` straddle it), other than the faces at `E–E2` (`e2`
    /// and one of `e_nodes`, which the tip replaces by `E P Y`), would open — neither of its
    /// two pieces at the cut's front (holding both ends of a crossing edge outside the
    /// polygon), and the segment between their centroids crossing the polygon. Such a face is
    /// part of the cut inside the polygon: `A C` is then not dropped.
    fn crossing_needed(
        &self,
        sweep: &TipSweep<'_, '_>,
        ring: &[u32],
        ac: [u32; 2],
        e2: NodeRef,
        e_nodes: &[NodeRef],
        edges: &HashMap<[u32; 2], EdgeCut>,
    ) -> bool {
        let front = |p: &[NodeRef; 4]| {
            (0..4).any(|i| {
                (i + 1..4).any(|k| match (p[i], p[k]) {
                    (NodeRef::Body(x), NodeRef::Body(y)) => {
                        edges.get(&sorted2(x, y)).is_some_and(|c| !c.inside)
                    }
                    _ => false,
                })
            })
        };
        let centroid = |p: &[NodeRef; 4]| p.iter().map(|&v| sweep.point(v)).sum::<DVec3>() * 0.25;
        let (plane, o, n) = (sweep.plane, sweep.plane.origin, sweep.plane.normal);
        let mut local: Vec<([u32; 2], NodeRef)> = Vec::new();
        let mut pieces: Vec<[NodeRef; 4]> = Vec::new();
        let mut without: Vec<[NodeRef; 4]> = Vec::new();
        let (mut faces, mut kept) = (Vec::new(), Vec::new());
        for &u in ring {
            let tet = sweep.body.tets()[u as usize];
            split_edges_of(tet, edges, &mut local);
            pieces.clear();
            bisect(tet.map(NodeRef::Body), &local, &mut pieces);
            on_plane_faces(sweep, &pieces, &mut faces);
            if faces.is_empty() {
                continue;
            }
            local.retain(|l| l.0 != ac);
            without.clear();
            bisect(tet.map(NodeRef::Body), &local, &mut without);
            on_plane_faces(sweep, &without, &mut kept);
            for f in &faces {
                let at_tip = f.nodes.contains(&e2) && f.nodes.iter().any(|v| e_nodes.contains(v));
                if at_tip || kept.iter().any(|g| g.nodes == f.nodes) {
                    continue;
                }
                let (p, q) = (&pieces[f.i], &pieces[f.k]);
                if front(p) || front(q) {
                    continue;
                }
                let (cp, cq) = (centroid(p), centroid(q));
                let (dp, dq) = (n.dot(cp - o), n.dot(cq - o));
                if (dp > 0.0) == (dq > 0.0) || dp == dq {
                    continue;
                }
                if plane.contains(cp + (cq - cp) * (dp / (dp - dq))) {
                    return true;
                }
            }
        }
        false
    }
}

/// The tips of the candidates at one edge `A C` (all of `group`), where the polygon's
/// boundary crosses `E–E2`, with the nodes `E` of the group and `E2`; `None` when a tip lies
/// within [`FACE_TIP_MARGIN`] (barycentric) of a side of its `A E C`.
fn tip_points(
    sweep: &TipSweep<'_, '_>,
    group: &[TipCandidate],
    edges: &HashMap<[u32; 2], EdgeCut>,
) -> Option<(Vec<FourWayTip>, Vec<NodeRef>, NodeRef)> {
    let mut planned: Vec<FourWayTip> = Vec::new();
    let mut e_nodes: Vec<NodeRef> = Vec::new();
    let mut e2_node = None;
    for g in group {
        let (a, b, c, ac) = (g.a, g.b, g.c, g.ac);
        let ab = sorted2(a, b);
        let (Some(ce), Some(ce2)) = (edges.get(&ab), edges.get(&ac)) else {
            return None;
        };
        let (Some(e), Some(e2)) = (ce.node, ce2.node) else {
            return None;
        };
        let (e, e2) = (NodeRef::New(e), NodeRef::New(e2));
        // Parameters from A along A B and A C.
        let from_a = |e: [u32; 2], s: f64| if e[0] == a { s } else { 1.0 - s };
        let (sb, sc) = (from_a(ab, ce.s), from_a(ac, ce2.s));
        let s = polygon_exit(sweep.plane, sweep.point(e), sweep.point(e2));
        // Barycentric coordinates of P in A E C.
        let bary = [s * (1.0 - sc), 1.0 - s, s * sc];
        if bary.iter().any(|&w| w.is_nan() || w < FACE_TIP_MARGIN) {
            return None;
        }
        e_nodes.push(e);
        e2_node = Some(e2);
        planned.push(FourWayTip {
            tet: g.tet,
            a,
            c,
            ab,
            point: FacePoint {
                nodes: [a, b, c],
                weights: [
                    (1.0 - s) * (1.0 - sb) + s * (1.0 - sc),
                    (1.0 - s) * sb,
                    s * sc,
                ],
            },
        });
    }
    Some((planned, e_nodes, e2_node?))
}

/// A face on the plane shared by pieces `i` and `k` (its nodes sorted).
struct PlaneFace {
    nodes: [NodeRef; 3],
    i: usize,
    k: usize,
}

/// The faces on the plane between two of `pieces`, into `out` (cleared first).
fn on_plane_faces(sweep: &TipSweep<'_, '_>, pieces: &[[NodeRef; 4]], out: &mut Vec<PlaneFace>) {
    out.clear();
    for (i, p) in pieces.iter().enumerate() {
        for (k, q) in pieces.iter().enumerate().skip(i + 1) {
            let mut shared = [NodeRef::Body(0); 3];
            let mut m = 0;
            for v in p.iter().copied().filter(|v| q.contains(v)) {
                if m < 3 {
                    shared[m] = v;
                }
                m += 1;
            }
            if m == 3 && shared.iter().all(|&v| sweep.on_plane(v)) {
                shared.sort_unstable();
                out.push(PlaneFace {
                    nodes: shared,
                    i,
                    k,
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::split::six_volume;

    /// The face-point split on a single tet `A B C D` over every sign pattern with the
    /// boundary face `A B C` crossed (A alone on its side, D on either side or on the plane),
    /// both sides of the plane, every assignment of node numbers (so every global order of the
    /// bisection): with every crossing edge but `A C` split and the tip `P` at the middle of
    /// `E–E2`, the pieces tile the tet (volumes sum to its own), none is flat or inverted,
    /// the face `A B C` is in exactly 4 triangles tiling it (`P` joined to `A`, `E`, `C`),
    /// `E`, `P` and `Y` lie on the plane with `E P Y` a face of two pieces, and only pieces
    /// holding both `A` and `C` hold nodes of both sides (`(A, P, C, Y)`, and for some orders a
    /// second one).
    #[test]
    fn the_face_point_split_tiles_the_tet_and_puts_the_tip_wall_on_the_plane() {
        let base = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let mut checked = 0;
        for perm in 0..24usize {
            // Node k sits at base position `at[k]`.
            let mut at = [0usize; 4];
            let mut free: Vec<usize> = (0..4).collect();
            let mut code = perm;
            for (k, slot) in at.iter_mut().enumerate() {
                let r = 4 - k;
                *slot = free.remove(code % r);
                code /= r;
            }
            // The tet in positive order: the nodes at positions 0, 1, 2, 3.
            let tet: [u32; 4] =
                [0, 1, 2, 3].map(|p| at.iter().position(|&q| q == p).unwrap() as u32);
            let d = tet[3];
            for lone in 0..3 {
                for swap in [false, true] {
                    for d_value in [0.7, -0.6, 0.0] {
                        for flip in [1.0, -1.0] {
                            let a = tet[lone];
                            let (mut b, mut c) = (tet[(lone + 1) % 3], tet[(lone + 2) % 3]);
                            if swap {
                                std::mem::swap(&mut b, &mut c);
                            }
                            let mut f = [0.0f64; 4];
                            f[a as usize] = flip;
                            f[b as usize] = -0.8 * flip;
                            f[c as usize] = -1.3 * flip;
                            f[d as usize] = d_value * flip;
                            check_face_split(&base, &at, tet, [a, b, c, d], f);
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(checked, 24 * 3 * 2 * 3 * 2);
    }

    fn check_face_split(
        base: &[DVec3; 4],
        at: &[usize; 4],
        tet: [u32; 4],
        [a, b, c, _d]: [u32; 4],
        f: [f64; 4],
    ) {
        let mut x: Vec<DVec3> = (0..4).map(|k| base[at[k]]).collect();
        // The plane: where the affine function with values `f` at the nodes vanishes.
        let value = |p: DVec3| {
            let l = [1.0 - p.x - p.y - p.z, p.x, p.y, p.z];
            (0..4).map(|k| l[at[k]] * f[k]).sum::<f64>()
        };
        let crossing = |x: &[DVec3], e: [u32; 2]| {
            let (f0, f1) = (f[e[0] as usize], f[e[1] as usize]);
            x[e[0] as usize] + (x[e[1] as usize] - x[e[0] as usize]) * (f0 / (f0 - f1))
        };
        let ac = sorted2(a, c);
        let mut split: Vec<([u32; 2], u32)> = Vec::new();
        for i in 0..4u32 {
            for j in i + 1..4 {
                if f[i as usize] * f[j as usize] < 0.0 && [i, j] != ac {
                    let p = crossing(&x, [i, j]);
                    split.push(([i, j], x.len() as u32));
                    x.push(p);
                }
            }
        }
        let ab = sorted2(a, b);
        let e = split.iter().find(|s| s.0 == ab).map(|s| s.1).unwrap();
        let tip = (x[e as usize] + crossing(&x, ac)) * 0.5;
        let p = x.len() as u32;
        x.push(tip);
        let mut pieces = Vec::new();
        bisect(tet, &split, &mut pieces);
        let y = split_face(&mut pieces, [a, e, c], p).expect("a piece holds A E C");
        let ctx = format!("tet {tet:?} f {f:?}: {pieces:?}");
        check_tiling_and_tip_wall(&x, &pieces, [e, p, y], value, &ctx);
        check_face_in_four(&x, &pieces, [a, e, c], p, &ctx);
        check_only_front_straddles(&pieces, f, [a, c, p, y], &ctx);
    }

    /// The pieces tile the unit tet (volume 1/6 × 6), none flat or inverted; `E`, `P`, `Y`
    /// lie on the plane (`value` zero) and `E P Y` is a face of two pieces.
    fn check_tiling_and_tip_wall(
        x: &[DVec3],
        pieces: &[[u32; 4]],
        [e, p, y]: [u32; 3],
        value: impl Fn(DVec3) -> f64,
        ctx: &str,
    ) {
        // Tiling, orientation.
        let volume: f64 = pieces
            .iter()
            .map(|t| six_volume(t.map(|i| x[i as usize])))
            .sum();
        assert!((volume - 1.0).abs() < 1e-12, "{ctx}: volume {volume}");
        for t in pieces {
            assert!(six_volume(t.map(|i| x[i as usize])) > 1e-6, "{ctx}: {t:?}");
        }
        // E, P, Y on the plane, and the wall E P Y a face of two pieces.
        for v in [e, p, y] {
            assert!(
                value(x[v as usize]).abs() < 1e-12,
                "{ctx}: node {v} off the plane"
            );
        }
        let wall = pieces
            .iter()
            .filter(|t| [e, p, y].iter().all(|v| t.contains(v)))
            .count();
        assert_eq!(wall, 2, "{ctx}");
    }

    /// The face `A B C` (z = 0) is in 4 triangles tiling it, `P` joined to exactly `A`, `E`,
    /// `C`.
    fn check_face_in_four(
        x: &[DVec3],
        pieces: &[[u32; 4]],
        [a, e, c]: [u32; 3],
        p: u32,
        ctx: &str,
    ) {
        // The face A B C (opposite D, base position 3: z = 0) in 4 triangles tiling it.
        let on_face = |v: u32| x[v as usize].z.abs() < 1e-12;
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        for t in pieces {
            for j in 0..4 {
                let tri = face_nodes(t, j);
                if tri.iter().all(|&v| on_face(v)) {
                    triangles.push(tri);
                }
            }
        }
        assert_eq!(triangles.len(), 4, "{ctx}: {triangles:?}");
        let area: f64 = triangles
            .iter()
            .map(|t| {
                let [q, r, s] = t.map(|v| x[v as usize]);
                0.5 * (r - q).cross(s - q).length()
            })
            .sum();
        assert!((area - 0.5).abs() < 1e-12, "{ctx}: area {area}");
        let mut joined: Vec<u32> = triangles
            .iter()
            .filter(|t| t.contains(&p))
            .flatten()
            .copied()
            .filter(|&v| v != p)
            .collect();
        joined.sort_unstable();
        joined.dedup();
        let mut want = vec![a, e, c];
        want.sort_unstable();
        assert_eq!(joined, want, "{ctx}");
    }

    /// Only pieces on the unsplit edge `A C` hold nodes of both sides (`f`: the nodes' signs),
    /// at most two, one of them `(A, P, C, Y)`.
    fn check_only_front_straddles(
        pieces: &[[u32; 4]],
        f: [f64; 4],
        [a, c, p, y]: [u32; 4],
        ctx: &str,
    ) {
        // Only pieces on the unsplit edge A C straddle (the front, `tets_around(A C)`): (A, P,
        // C, Y) and, for some orders where D is on A's side, a second one (A, F, C, G).
        let mut straddling = 0;
        for t in pieces {
            let sides: Vec<f64> = t
                .iter()
                .filter(|&&v| v < 4)
                .map(|&v| f[v as usize])
                .collect();
            let both = sides.iter().any(|&s| s > 0.0) && sides.iter().any(|&s| s < 0.0);
            assert_eq!(both, t.contains(&a) && t.contains(&c), "{ctx}: {t:?}");
            straddling += usize::from(both);
        }
        assert!(straddling <= 2, "{ctx}");
        let apcy = pieces
            .iter()
            .filter(|t| [a, p, c, y].iter().all(|v| t.contains(v)));
        assert_eq!(apcy.count(), 1, "{ctx}");
    }
}
