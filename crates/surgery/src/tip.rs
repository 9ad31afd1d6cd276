//! The cut's ends on the surface: a second, "tip" split of the surface triangle in which the
//! swept polygon's boundary crosses the surface.
//!
//! After the first split (module `split`), a crossed boundary triangle `A B C` holds an edge
//! `E–E2` on the blade's plane (both its crossing points split). When `E` lies in the swept
//! polygon and `E2` outside it (the polygon's boundary — the blade's front, or where the cut
//! started — crosses the surface between them), that edge is split again at the **tip** `P`
//! where it leaves the polygon (found by bisection on [`crate::split`]'s `CutPlane::contains`;
//! both ends lie on the plane, so `P` does too), and every tet around it is bisected once more
//! (the same ordered bisection, a second pass after the first split is applied). The triangle
//! `A B C` is then in 5 boundary pieces: the triangle and the quad piece on the two sides of
//! `E–E2` each halved at `P` (4 pieces around `P`), and the quad's other piece. The tets around
//! `P–E2` (beyond the tip) join the cut's front for this sweep: their faces stay glued, so `P`
//! keeps one node while `E` is duplicated, and the surface opening ends exactly at `P`. A later
//! sweep that covers `P–E2` opens them as any other faces on the plane (`P` becomes an ordinary
//! wall node).
//!
//! Rules: the edge must have tets on both sides of the plane (an edge of an opening already
//! made has only one side: it is not split again), exactly two nodes of the boundary triangle
//! on the plane (a wall lying in the plane is not a crossed triangle), and `P` at least
//! [`TIP_MARGIN`] of the edge from either end; the pieces must meet the same quality bound as
//! the first split's ([`crate::MIN_RATIO`], [`crate::MIN_PIECE_FRACTION`],
//! [`crate::MAX_SPLIT_DEPTH`], pieces tiling the parent in rest space). Otherwise the tip is not
//! inserted and the cut ends there as without it (at a tet boundary).

use glam::DVec3;
use tissue_mesh::NO_TET;
use tissue_pbd::SoftBody;

use crate::geometry::FxMap as HashMap;
use crate::split::MAX_SPLIT_DEPTH;
use crate::split::{bisect, sorted2, split_edges_of, CutPlane, EdgeCut, SplitOutcome};
use crate::state::face_nodes;
use crate::{SplitTriangle, Surgery, SurgeryError};

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
        let (o, n) = (plane.origin, plane.normal);
        let (new_lo, new_hi) = (out.first_node, out.end_node);
        let (side, reach) = (&self.side, &self.node_reach);
        // On the plane: the first split's new nodes, and nodes snapped or lying on it (within
        // rounding: nodes made on it by an earlier sweep are a few ulps off).
        let on_plane = |v: u32| {
            (new_lo..new_hi).contains(&v)
                || side
                    .get(v as usize)
                    .is_some_and(|&d| d.abs() <= ON_PLANE * reach[v as usize] as f64)
        };
        let pos = |body: &SoftBody, v: u32| body.positions()[v as usize].as_dvec3();
        // Boundary triangles with exactly two nodes on the plane: their edge on it.
        let mut on: Vec<[u32; 2]> = Vec::new();
        let tets = body.tets();
        for t in candidates.iter().copied().chain(out.first_tet..out.end_tet) {
            for j in 0..4 {
                if self.neighbours[t as usize][j] != NO_TET {
                    continue;
                }
                let f = face_nodes(&tets[t as usize], j);
                let p: Vec<u32> = f.iter().copied().filter(|&v| on_plane(v)).collect();
                if p.len() == 2 {
                    on.push(sorted2(p[0], p[1]));
                }
            }
        }
        if on.is_empty() {
            return Ok(Vec::new());
        }
        on.sort_unstable();
        on.dedup();
        let side_of = |body: &SoftBody, t: u32| {
            let c = body.tets()[t as usize]
                .iter()
                .map(|&v| pos(body, v))
                .sum::<DVec3>()
                * 0.25;
            n.dot(c - o)
        };
        // Edge → (parameter of the tip from e[0], the end outside the polygon).
        let mut edges: HashMap<[u32; 2], EdgeCut> = HashMap::default();
        let mut outer: HashMap<[u32; 2], u32> = HashMap::default();
        for e in on {
            let (x0, x1) = (pos(body, e[0]), pos(body, e[1]));
            let (in0, in1) = (plane.contains(x0), plane.contains(x1));
            if in0 == in1 {
                continue;
            }
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            // `lo` inside, `hi` outside (parameters from the inside end).
            let (a, b) = if in0 { (x0, x1) } else { (x1, x0) };
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if plane.contains(a + (b - a) * mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let t = 0.5 * (lo + hi);
            if !(TIP_MARGIN..=1.0 - TIP_MARGIN).contains(&t) {
                continue;
            }
            let (mut plus, mut minus) = (false, false);
            for u in self.tets_around(&e) {
                let d = side_of(body, u);
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
                    node: u32::MAX,
                },
            );
            outer.insert(e, if in0 { e[1] } else { e[0] });
        }
        if edges.is_empty() {
            return Ok(Vec::new());
        }
        // Plan as the first split does (see `split_along`): a tet whose pieces fail the bound
        // gives up its tip edges, and the rest is planned again.
        let first = body.node_count() as u32;
        let mut pieces: Vec<[u32; 4]> = Vec::new();
        let mut plan: Vec<(u32, std::ops::Range<usize>)> = Vec::new();
        let mut new_rest: Vec<DVec3> = Vec::new();
        let mut order: Vec<[u32; 2]> = Vec::new();
        let mut local: Vec<([u32; 2], u32)> = Vec::new();
        loop {
            order.clear();
            order.extend(edges.iter().filter(|(_, c)| c.valid).map(|(e, _)| *e));
            order.sort_unstable();
            if order.is_empty() {
                return Ok(Vec::new());
            }
            new_rest.clear();
            for (k, e) in order.iter().enumerate() {
                if let Some(c) = edges.get_mut(e) {
                    c.node = first + k as u32;
                    let (r0, r1) = (self.rest[e[0] as usize], self.rest[e[1] as usize]);
                    new_rest.push(r0 + (r1 - r0) * c.s);
                }
            }
            let mut affected: Vec<u32> = order.iter().flat_map(|e| self.tets_around(e)).collect();
            affected.sort_unstable();
            affected.dedup();
            let rest_of = |v: u32| -> DVec3 {
                if v >= first {
                    new_rest[(v - first) as usize]
                } else {
                    self.rest[v as usize]
                }
            };
            pieces.clear();
            plan.clear();
            let mut failed: Vec<[u32; 2]> = Vec::new();
            for &t in &affected {
                let tet = body.tets()[t as usize];
                split_edges_of(tet, &edges, &mut local);
                let start = pieces.len();
                bisect(tet, &local, &mut pieces);
                let good = self.pieces_meet_bound(tet, &pieces[start..], rest_of)
                    && self.depth[t as usize] < MAX_SPLIT_DEPTH;
                if good {
                    plan.push((t, start..pieces.len()));
                } else {
                    pieces.truncate(start);
                    failed.extend(local.iter().map(|l| l.0));
                }
            }
            if failed.is_empty() {
                break;
            }
            for e in failed {
                if let Some(c) = edges.get_mut(&e) {
                    c.valid = false;
                }
            }
        }
        tracing::debug!(tips = order.len(), tets = plan.len(), "tips split");
        let mut second = SplitOutcome::default();
        self.apply_split(body, &edges, &order, &new_rest, &plan, &pieces, &mut second)?;
        // Merge into the first split's outcome: nodes and tets were appended right after its.
        out.end_node = second.end_node;
        out.end_tet = second.end_tet;
        for t in second.split {
            if t < out.first_tet && !out.split.contains(&t) {
                out.split.push(t);
            }
        }
        merge_surface(&mut out.surface, second.surface);
        Ok(order
            .iter()
            .enumerate()
            .map(|(k, e)| sorted2(first + k as u32, outer[e]))
            .collect())
    }
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
