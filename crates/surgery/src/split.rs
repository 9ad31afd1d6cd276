//! The geometric part of a cut: nodes snapped onto the blade's plane, tet edges the plane
//! crosses split, and the tets around them subdivided conformingly, so that the faces the
//! separation step then opens lie **on** the blade's plane.
//!
//! For one sweep (the cut surface: a planar polygon, see [`crate::BladeSweep`]), with `d(v)`
//! the signed distance of node `v` to the plane (current positions):
//! 1. **Snapping.** A free node with `0 < |d| < SNAP_FRACTION × its shortest rest edge` whose
//!    projection lies in the polygon moves onto the plane (current and previous position and
//!    rest position shifted by `−d n`) if every tet around it keeps a positive current volume,
//!    a rest volume at or above the input's smallest and a rest radius ratio at or above
//!    `min(MIN_RATIO, its ratio before)`; its tets' rest volumes and its edges' rest lengths
//!    are then rebuilt ([`tissue_pbd::SoftBody::reshape_tet`],
//!    [`tissue_pbd::SoftBody::reset_distance_constraint`]). A node that was near but is not
//!    snapped is *near*: no edge at it is split.
//! 2. **Edges.** An edge whose ends lie strictly on opposite sides is *valid* when neither end
//!    is near and its crossing point lies in the polygon.
//! 3. **Tets.** A straddling tet is split when all its crossing edges are valid; an edge is
//!    split when all tets around it are split (repeated to a fixed point, so no tet has a
//!    hanging node), and a tet whose pieces would fall below the quality bound
//!    ([`MIN_RATIO`], the input's smallest rest volume) or not sum to its rest volume is not
//!    split (and the fixed point is run again). Split edges get one node each (shared by all
//!    tets around the edge), interpolated in current and rest space at the crossing.
//! 4. **Subdivision**, by the signs of the four nodes (`+`, `−`, `0` on the plane): one
//!    crossing edge (`+ − 0 0`) → 2 tets; a triangle and a pyramid (`+ − − 0`) → 1 + 2; a tet
//!    and a prism (`+ − − −`) → 1 + 3; two prisms (`+ + − −`) → 3 + 3. Quads are split along
//!    the diagonal from their smallest global node index (prisms as in Dompierre et al. 1999),
//!    so two tets sharing a quad split it the same way. Each piece is oriented positively in
//!    rest space. The split tet's record is reused for its first piece, the others appended;
//!    volume constraints get their rest values from the rest positions, new edges distance
//!    constraints with their rest lengths, a split edge's constraint moves onto its first half;
//!    masses of the touched nodes are rebuilt from their tets (eq. (1)).
//! 5. Tets the sweep reaches but does not cross completely (a crossing point outside the
//!    polygon: the cut's front and sides) are left whole and **glued** (the separation step
//!    does not open their faces); a later sweep that covers them splits them. A tet that could
//!    not be split for quality or a near node is left to the face separation (the staircase).
//! 6. **Tips** (module `tip`): where the polygon's boundary crosses a crossed surface
//!    triangle, the triangle's far crossing edge is dropped from the plan and the tip inserted
//!    inside the triangle by a face split of the piece on it (four-way, planned before the
//!    split is applied); where that is refused, after the split is applied, the triangle's
//!    edge on the plane is split again at the tip and the tets around it bisected once more
//!    (the fallback). Either way the tets beyond the tip join the front, so the opening on the
//!    surface ends at the tip.
//!
//! The plan (steps 1–4, and the four-way tips) is made completely before anything is applied:
//! a [`SplitPlan`] (module `plan`), whose new nodes are typed [`NewNode`]s until
//! [`Surgery::apply_split`] (module `apply`) appends them to the body.

use glam::{DVec3, Vec3};
use tissue_pbd::SoftBody;

use crate::geometry::radius_ratio;
use crate::geometry::FxMap as HashMap;
use crate::plan::{EdgeCut, NewNode, NodeRef, SplitEdge, SplitPlan, TetSplit};
use crate::state::face_nodes;
use crate::tip::{split_face, FourWayTip};
use crate::{SplitTriangle, Surgery, SurgeryError};

/// A node closer to the blade's plane than this fraction of its shortest rest edge is snapped
/// onto the plane (or, if that would spoil a tet, no edge at it is split).
pub const SNAP_FRACTION: f64 = 0.25;

/// Smallest rest radius ratio `3 r_in / r_circ` of a tet created by a split, and of a tet a
/// snap reshapes unless it was already worse.
pub const MIN_RATIO: f64 = 0.02;

/// The cut's ends snap to tet boundaries: a crossing point at most this fraction of its
/// edge's length outside the swept polygon counts as inside (so a cut may end up to this much
/// beyond the blade, and the tets at its front are split whole or not at all).
pub const FRONT_SNAP: f64 = 0.75;

/// Two crossing points of one edge in different sweeps are the same cut when their parameters
/// along the edge differ by at most this.
const COVERED_SLACK: f64 = 0.1;

/// Covered crossing points remembered at most (then forgotten all at once).
const COVERED_CAP: usize = 1 << 16;

/// Smallest rest volume of a tet created or reshaped by a cut, as a fraction of the input
/// mesh's smallest rest volume.
pub const MIN_VOLUME_FRACTION: f64 = 1e-3;

/// Smallest rest volume of a piece a split creates, as a fraction of the input's median tet:
/// with [`MAX_SPLIT_DEPTH`] it bounds how fine repeated cuts through one place refine the mesh.
pub const MIN_PIECE_FRACTION: f64 = 0.01;

/// A tet made by this many splits in a row is not split again (a later cut through it
/// separates along its faces, as where a split is refused for quality).
pub const MAX_SPLIT_DEPTH: u8 = 3;

/// A cut wall whose normal is this close to the blade's (|cos|) counts as parallel to it.
const WALL_PARALLEL: f64 = 0.9;

/// A cut wall farther than this fraction of its node's reach (1.5 × its longest rest edge) off
/// the blade's plane is an earlier cut's, not this one continued: the tets at its nodes are not
/// split (they separate along their faces, see `split`).
const WALL_OFFSET: f64 = 1e-3;

/// What one sweep's split did.
#[derive(Debug, Default)]
pub(crate) struct SplitOutcome {
    /// New nodes on split edges: `first..end`.
    pub first_node: u32,
    pub end_node: u32,
    /// Tets split (their records now hold the first piece) and tets appended.
    pub split: Vec<u32>,
    pub first_tet: u32,
    pub end_tet: u32,
    /// Nodes snapped onto the plane.
    pub snapped: Vec<u32>,
    /// Boundary triangles split into pieces.
    pub surface: Vec<SplitTriangle>,
    /// Straddling tets left whole because the sweep did not cross them completely (sorted):
    /// their faces stay glued this sweep.
    pub front: Vec<u32>,
    /// The four-way tips' nodes (module `tip`), within `first_node..end_node`.
    pub four_way: std::ops::Range<u32>,
}

/// The plane and polygon of one sweep.
pub(crate) struct CutPlane<'a> {
    pub origin: DVec3,
    pub normal: DVec3,
    pub surface: &'a [[DVec3; 3]; 8],
}

impl CutPlane<'_> {
    /// Whether point `p` of the plane lies in the polygon (one of the eight triangles).
    pub fn contains(&self, p: DVec3) -> bool {
        let n = self.normal;
        self.surface.iter().any(|[a, b, c]| {
            let (ab, bc, ca) = (
                (*b - *a).cross(p - *a).dot(n),
                (*c - *b).cross(p - *b).dot(n),
                (*a - *c).cross(p - *c).dot(n),
            );
            (ab >= 0.0 && bc >= 0.0 && ca >= 0.0) || (ab <= 0.0 && bc <= 0.0 && ca <= 0.0)
        })
    }
}

impl CutPlane<'_> {
    /// Distance from point `p` of the plane to the polygon (0 inside).
    pub fn distance(&self, p: DVec3) -> f64 {
        if self.contains(p) {
            return 0.0;
        }
        let seg = |a: DVec3, b: DVec3| {
            let ab = b - a;
            let l = ab.length_squared();
            let t = if l > 0.0 {
                ((p - a).dot(ab) / l).clamp(0.0, 1.0)
            } else {
                0.0
            };
            p.distance(a + ab * t)
        };
        self.surface
            .iter()
            .map(|[a, b, c]| seg(*a, *b).min(seg(*b, *c)).min(seg(*c, *a)))
            .fold(f64::INFINITY, f64::min)
    }
}

pub(crate) fn six_volume([a, b, c, d]: [DVec3; 4]) -> f64 {
    (b - a).cross(c - a).dot(d - a)
}

pub(crate) fn sorted2(a: u32, b: u32) -> [u32; 2] {
    [a.min(b), a.max(b)]
}

/// The pieces of tet `t` when its edges in `split` (sorted edge → node on it, in the global
/// order of the sorted edges) are bisected in that order: the first split edge of `t` is
/// bisected (the tet into the two tets through its node and the opposite edge), then each half
/// the same way with the later edges. Since a face's triangulation then depends only on the
/// order of its own edges, which is global, two tets sharing a face split it alike (no
/// hanging node); replacing an end of an edge by a point strictly inside it keeps the
/// orientation. Once every crossing edge of `t` is split, no piece holds nodes of both sides.
pub(crate) fn bisect<N: Copy + PartialEq + From<u32>>(
    t: [N; 4],
    split: &[([u32; 2], N)],
    out: &mut Vec<[N; 4]>,
) {
    for (k, (e, m)) in split.iter().enumerate() {
        let (e0, e1) = (N::from(e[0]), N::from(e[1]));
        if let (Some(i), Some(j)) = (
            t.iter().position(|&v| v == e0),
            t.iter().position(|&v| v == e1),
        ) {
            let (mut lo, mut hi) = (t, t);
            lo[j] = *m;
            hi[i] = *m;
            bisect(lo, &split[k + 1..], out);
            bisect(hi, &split[k + 1..], out);
            return;
        }
    }
    out.push(t);
}

/// Tet `tet`'s edges planned for a split (valid in `edges`), sorted, each with its new node:
/// the input of [`bisect`]. `local` is cleared first.
pub(crate) fn split_edges_of(
    tet: [u32; 4],
    edges: &HashMap<[u32; 2], EdgeCut>,
    local: &mut Vec<([u32; 2], NodeRef)>,
) {
    local.clear();
    for a in 0..4 {
        for b in a + 1..4 {
            let e = sorted2(tet[a], tet[b]);
            if let Some(node) = edges.get(&e).filter(|c| c.valid).and_then(|c| c.node) {
                local.push((e, NodeRef::New(node)));
            }
        }
    }
    local.sort_unstable();
}

impl Surgery {
    /// Steps 1–4 of the module docs for one sweep, as phases: snap the nodes near the plane,
    /// find the tets a wall blocks and the crossing edges, plan the split (quality rounds, then
    /// the four-way tips), apply it, then the fallback tips. `candidates` are the tets that
    /// straddle the plane near the polygon (sorted).
    pub(crate) fn split_along(
        &mut self,
        body: &mut SoftBody,
        plane: &CutPlane<'_>,
        candidates: &[u32],
    ) -> Result<SplitOutcome, SurgeryError> {
        let _span = tracing::debug_span!("split").entered();
        let mut out = SplitOutcome {
            first_node: body.node_count() as u32,
            end_node: body.node_count() as u32,
            first_tet: body.tets().len() as u32,
            end_tet: body.tets().len() as u32,
            ..Default::default()
        };
        if candidates.is_empty() {
            return Ok(out);
        }
        let (o, n) = (plane.origin, plane.normal);
        let mut nodes: Vec<u32> = candidates
            .iter()
            .flat_map(|&t| body.tets()[t as usize])
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        // Signed distances of the nodes from the plane: those `straddling_tets` left in
        // `side` (the same expression), recomputed if it did not run for this body.
        let mut dist = std::mem::take(&mut self.scratch.side);
        if dist.len() != body.node_count() {
            dist.clear();
            dist.extend(body.positions().iter().map(|p| n.dot(p.as_dvec3() - o)));
        }
        let near = self.snap_nodes(body, plane, &nodes, &mut dist, &mut out.snapped)?;
        let blocked = self.blocked_by_walls(body, plane, candidates);
        let mut edges = self.crossing_edges(body, plane, candidates, &dist, &near);
        self.scratch.side = dist;
        let first = body.node_count() as u32;
        let plan = self.plan_tets(body, plane, &mut edges, &blocked)?;
        let first_tip = first + plan.edges.len() as u32;
        out.four_way = first_tip..first_tip + plan.tips.len() as u32;
        self.remember_covered(&edges);
        let outside: Vec<[u32; 2]> = edges
            .iter()
            .filter(|(_, c)| !c.inside)
            .map(|(e, _)| *e)
            .collect();
        if !plan.tets.is_empty() {
            self.apply_split(body, &plan, &mut out)?;
        }
        for (k, tip) in plan.tips.iter().enumerate() {
            let e = edges
                .get(&tip.ab)
                .filter(|c| c.valid)
                .and_then(|c| c.node)
                .map_or(u32::MAX, |e| NodeRef::New(e).resolve(first));
            self.open_tip_wall(body, tip, e, first_tip + k as u32);
        }
        // The tips on the surface (module `tip`): the edges beyond them join the front.
        let beyond = self.split_tips(body, plane, candidates, &mut out)?;
        // The front: tets (after the split) on a crossing edge outside the polygon.
        out.front = self.tets_around_edges(body.tets(), &[outside, beyond].concat());
        Ok(out)
    }

    /// Step 1, snapping: each of `nodes` (sorted) closer to the plane than [`SNAP_FRACTION`]
    /// of its shortest rest edge moves onto it (current, previous and rest position) when every
    /// tet around it allows it ([`Surgery::snap_keeps_quality`]); its tets' rest shapes, its
    /// edges' rest lengths and the masses are then rebuilt. Returns the nodes that were close
    /// but could not be snapped (sorted): no edge at them is split. `dist` (the nodes' signed
    /// distances) is kept up to date; `snapped` gets the snapped nodes.
    fn snap_nodes(
        &mut self,
        body: &mut SoftBody,
        plane: &CutPlane<'_>,
        nodes: &[u32],
        dist: &mut [f64],
        snapped: &mut Vec<u32>,
    ) -> Result<Vec<u32>, SurgeryError> {
        let n = plane.normal;
        let mut near: Vec<u32> = Vec::new();
        let mut reshaped: Vec<u32> = Vec::new();
        for &v in nodes {
            let d = dist[v as usize];
            // `node_reach` is 1.5 × the longest rest edge: far nodes are skipped cheaply.
            if d == 0.0 || d.abs() >= SNAP_FRACTION * self.node_reach[v as usize] as f64 / 1.5 {
                continue;
            }
            if self.has_short_edge(body, v, d) {
                continue;
            }
            let moved_rest = self.rest[v as usize] - d * n;
            if !self.snap_keeps_quality(body, plane, v, d, moved_rest) {
                near.push(v);
                continue;
            }
            let shift = (-d * n).as_vec3();
            let (xv, pv, vv) = (
                Vec3::from(body.positions()[v as usize]),
                Vec3::from(body.previous_positions()[v as usize]),
                Vec3::from(body.velocities()[v as usize]),
            );
            body.set_node_state(v, xv + shift, pv + shift, vv)?;
            body.set_rest_position(v, moved_rest.as_vec3())?;
            self.rest[v as usize] = moved_rest;
            dist[v as usize] = 0.0;
            snapped.push(v);
            reshaped.extend_from_slice(&self.node_tets[v as usize]);
        }
        if !snapped.is_empty() {
            self.reshape_snapped(body, snapped, reshaped)?;
        }
        near.sort_unstable();
        Ok(near)
    }

    /// Whether some rest edge at node `v` is shorter than `|d| / SNAP_FRACTION` (`d` its
    /// distance from the plane): such a node is not snapped (nor counted as near).
    fn has_short_edge(&self, body: &SoftBody, v: u32, d: f64) -> bool {
        let tets = body.tets();
        let (rv, limit) = (self.rest[v as usize], d.abs() / SNAP_FRACTION);
        self.node_tets[v as usize].iter().any(|&t| {
            tets[t as usize]
                .iter()
                .any(|&u| u != v && rv.distance(self.rest[u as usize]) <= limit)
        })
    }

    /// Whether node `v` (at distance `d` from the plane, `moved_rest` its rest position on
    /// it) may snap: it is free, its projection lies in the polygon, and every tet around it
    /// keeps a positive current volume, a rest volume at or above the floor and a radius ratio
    /// at or above `min(MIN_RATIO, its ratio before)`.
    fn snap_keeps_quality(
        &self,
        body: &SoftBody,
        plane: &CutPlane<'_>,
        v: u32,
        d: f64,
        moved_rest: DVec3,
    ) -> bool {
        let pos = |v: u32| body.positions()[v as usize].as_dvec3();
        let tets = body.tets();
        let target = pos(v) - d * plane.normal;
        let free = body.inverse_masses()[v as usize] > 0.0;
        free && plane.contains(target)
            && self.node_tets[v as usize].iter().all(|&t| {
                let tet = tets[t as usize];
                let before = tet.map(|u| self.rest[u as usize]);
                let after = tet.map(|u| {
                    if u == v {
                        moved_rest
                    } else {
                        self.rest[u as usize]
                    }
                });
                let now = tet.map(|u| if u == v { target } else { pos(u) });
                let vol = six_volume(after) / 6.0;
                six_volume(now) > 0.0
                    && vol >= self.volume_floor()
                    && radius_ratio(after) >= MIN_RATIO.min(radius_ratio(before))
            })
    }

    /// After snapping: the rest shapes of the `reshaped` tets (the snapped nodes' tets, with
    /// repeats), the rest lengths of the snapped nodes' edges and their tets' nodes' masses.
    fn reshape_snapped(
        &mut self,
        body: &mut SoftBody,
        snapped: &[u32],
        mut reshaped: Vec<u32>,
    ) -> Result<(), SurgeryError> {
        reshaped.sort_unstable();
        reshaped.dedup();
        for &t in &reshaped {
            let tet = body.tets()[t as usize];
            body.reshape_tet(t as usize, tet, tet.map(|u| self.rest[u as usize]))?;
        }
        let mut edges: Vec<[u32; 2]> = Vec::new();
        for &v in snapped {
            for &t in &self.node_tets[v as usize] {
                for &u in &body.tets()[t as usize] {
                    if u != v {
                        edges.push(sorted2(u, v));
                    }
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        for e in edges {
            if let Some(&c) = self.edge_constraint.get(&e) {
                let l = self.rest[e[0] as usize].distance(self.rest[e[1] as usize]);
                body.reset_distance_constraint(c as usize, e, l as f32)?;
            }
        }
        self.rebuild_masses(body, &reshaped)
    }

    /// Tets at a node of a cut wall nearly parallel to the blade (sorted): the blade runs in
    /// or next to a gap already opened (the tissue moved a little since the sweep that cut
    /// it); splitting them again would shave a thin slab off the wall, and the slab, glued to
    /// both sides, would bridge the cut. They are not split: their faces open as where a split
    /// is refused, so the new wall steps onto the old one within one tet.
    fn blocked_by_walls(
        &self,
        body: &SoftBody,
        plane: &CutPlane<'_>,
        candidates: &[u32],
    ) -> Vec<u32> {
        let (o, n) = (plane.origin, plane.normal);
        let pos = |v: u32| body.positions()[v as usize].as_dvec3();
        let mut blocked: Vec<u32> = Vec::new();
        let walls = candidates.iter().flat_map(|&t| {
            let bits = self.wall[t as usize];
            (0..4u8)
                .filter(move |j| bits >> j & 1 == 1)
                .map(move |j| (t, j))
        });
        for (t, j) in walls {
            let f = face_nodes(&body.tets()[t as usize], j as usize).map(pos);
            let normal = (f[1] - f[0]).cross(f[2] - f[0]).normalize_or_zero();
            if normal.dot(n).abs() > WALL_PARALLEL {
                blocked.push(t);
                // A wall off the plane (not the same cut continued): its neighbourhood too.
                let nodes = face_nodes(&body.tets()[t as usize], j as usize);
                let off = f.iter().map(|p| n.dot(*p - o).abs()).fold(0.0, f64::max);
                if off > WALL_OFFSET * self.node_reach[nodes[0] as usize] as f64 {
                    for &v in &nodes {
                        blocked.extend_from_slice(&self.node_tets[v as usize]);
                    }
                }
            }
        }
        blocked.sort_unstable();
        blocked.dedup();
        blocked
    }

    /// Step 2, the crossing edges of the `candidates`: each edge with ends strictly on both
    /// sides (signs of `dist`), its crossing point inside the polygon (within [`FRONT_SNAP`] of
    /// its length, or covered by an earlier sweep) and valid when neither end is `near`
    /// (sorted). Then a tet whose centroid lies over the polygon is cut whole: its crossing
    /// points outside the polygon count as inside (the cut's end snaps to the tet's far side),
    /// so a body that moved between sweeps does not leave partly covered tets behind for good.
    fn crossing_edges(
        &self,
        body: &SoftBody,
        plane: &CutPlane<'_>,
        candidates: &[u32],
        dist: &[f64],
        near: &[u32],
    ) -> HashMap<[u32; 2], EdgeCut> {
        let (o, n) = (plane.origin, plane.normal);
        let pos = |v: u32| body.positions()[v as usize].as_dvec3();
        let is_near = |v: u32| near.binary_search(&v).is_ok();
        let sign = |v: u32| -> i8 {
            let d = dist[v as usize];
            if d > 0.0 {
                1
            } else if d < 0.0 {
                -1
            } else {
                0
            }
        };
        let mut edges: HashMap<[u32; 2], EdgeCut> = HashMap::default();
        let mut crossed: Vec<u32> = Vec::new();
        for &t in candidates {
            let tet = body.tets()[t as usize];
            let mut any = false;
            for a in 0..4 {
                for b in a + 1..4 {
                    let (p, q) = (tet[a], tet[b]);
                    if sign(p) * sign(q) >= 0 {
                        continue;
                    }
                    any = true;
                    let e = sorted2(p, q);
                    edges.entry(e).or_insert_with(|| {
                        let (d0, d1) = (dist[e[0] as usize], dist[e[1] as usize]);
                        let s = d0 / (d0 - d1);
                        let (x0, x1) = (pos(e[0]), pos(e[1]));
                        let reach = FRONT_SNAP * x0.distance(x1);
                        let inside = plane.distance(x0 + (x1 - x0) * s) <= reach
                            || self
                                .covered
                                .get(&e)
                                .is_some_and(|&s0| (s0 - s).abs() <= COVERED_SLACK);
                        EdgeCut {
                            s,
                            inside,
                            valid: inside && !is_near(e[0]) && !is_near(e[1]),
                            node: None,
                        }
                    });
                }
            }
            if any {
                crossed.push(t);
            }
        }
        for &t in &crossed {
            let tet = body.tets()[t as usize];
            let c = tet.iter().map(|&v| pos(v)).sum::<DVec3>() * 0.25;
            if !plane.contains(c - n * n.dot(c - o)) {
                continue;
            }
            for a in 0..4 {
                for b in a + 1..4 {
                    let e = sorted2(tet[a], tet[b]);
                    if let Some(c) = edges.get_mut(&e) {
                        c.inside = true;
                        c.valid = !is_near(e[0]) && !is_near(e[1]);
                    }
                }
            }
        }
        edges
    }

    /// Steps 3–4, the plan: the valid crossing edges get new nodes, the tets around them are
    /// judged until none fails the quality bound ([`Surgery::quality_rounds`]), the four-way
    /// tips are planned on the result (module `tip`), and the pieces are made.
    ///
    /// The quality of a tet's pieces depends on which of its edges are split and on rest
    /// positions, not on the new nodes' numbers: while judging, the new node of candidate edge
    /// `i` is `NewNode(i)` (then the tips'); the final plan numbers only the edges kept.
    fn plan_tets(
        &mut self,
        body: &SoftBody,
        plane: &CutPlane<'_>,
        edges: &mut HashMap<[u32; 2], EdgeCut>,
        blocked: &[u32],
    ) -> Result<SplitPlan, SurgeryError> {
        let mut candidate_edges: Vec<[u32; 2]> = edges
            .iter()
            .filter(|(_, c)| c.valid)
            .map(|(e, _)| *e)
            .collect();
        candidate_edges.sort_unstable();
        let mut candidate_rest: Vec<DVec3> = Vec::with_capacity(candidate_edges.len());
        for (i, e) in candidate_edges.iter().enumerate() {
            let c = edges.get_mut(e).ok_or(SurgeryError::Defect {
                element: "edge",
                index: e[0] as usize,
                what: "split edge lost its record",
            })?;
            c.node = Some(NewNode(i as u32));
            let (r0, r1) = (self.rest[e[0] as usize], self.rest[e[1] as usize]);
            candidate_rest.push(r0 + (r1 - r0) * c.s);
        }
        let mut affected =
            self.quality_rounds(body, edges, &candidate_edges, &candidate_rest, blocked);
        let tips = self.plan_four_way_tips(
            body,
            plane,
            &mut affected,
            edges,
            &candidate_edges,
            &candidate_rest,
        );
        self.final_plan(
            body,
            edges,
            &candidate_edges,
            &candidate_rest,
            &affected,
            tips,
        )
    }

    /// The quality rounds of the plan: each tet around a candidate edge is bisected under the
    /// valid edges (new nodes `NewNode(i)` for `candidate_edges[i]`, at `candidate_rest[i]`);
    /// a tet whose pieces would fall below the bound or not tile it in rest space, that is at
    /// [`MAX_SPLIT_DEPTH`] or `blocked`, gives up its split edges, and the tets around the edges
    /// given up are judged again until none fails. Returns the tets still split (sorted).
    fn quality_rounds(
        &self,
        body: &SoftBody,
        edges: &mut HashMap<[u32; 2], EdgeCut>,
        candidate_edges: &[[u32; 2]],
        candidate_rest: &[DVec3],
        blocked: &[u32],
    ) -> Vec<u32> {
        let rest_of = |v: NodeRef| -> DVec3 {
            match v {
                NodeRef::Body(v) => self.rest[v as usize],
                NodeRef::New(NewNode(i)) => candidate_rest[i as usize],
            }
        };
        let mut local: Vec<([u32; 2], NodeRef)> = Vec::new();
        let mut scratch: Vec<[NodeRef; 4]> = Vec::new();
        // Whether tet `t`'s pieces under the valid edges meet the bound; `local` is left with
        // its valid edges.
        let mut judge = |t: u32, edges: &HashMap<[u32; 2], EdgeCut>, local: &mut Vec<_>| {
            let tet = body.tets()[t as usize];
            split_edges_of(tet, edges, local);
            scratch.clear();
            bisect(tet.map(NodeRef::Body), local, &mut scratch);
            self.pieces_meet_bound(tet.map(NodeRef::Body), &scratch, rest_of)
                && (local.is_empty()
                    || (self.depth[t as usize] < MAX_SPLIT_DEPTH
                        && blocked.binary_search(&t).is_err()))
        };
        let mut affected = self.tets_around_edges(body.tets(), candidate_edges);
        let mut to_judge = affected.clone();
        loop {
            let mut failed: Vec<[u32; 2]> = Vec::new();
            for &t in &to_judge {
                if !judge(t, edges, &mut local) {
                    failed.extend(local.iter().map(|l| l.0));
                }
            }
            if failed.is_empty() {
                return affected;
            }
            failed.sort_unstable();
            failed.dedup();
            for e in &failed {
                if let Some(c) = edges.get_mut(e) {
                    c.valid = false;
                }
            }
            // Judged again: the tets around the edges given up that still split an edge.
            to_judge = self.tets_around_edges(body.tets(), &failed);
            let mut has_valid = |t: u32| {
                split_edges_of(body.tets()[t as usize], edges, &mut local);
                !local.is_empty()
            };
            to_judge.retain(|&t| has_valid(t));
            affected.retain(|&t| has_valid(t));
        }
    }

    /// The plan once the edges and tips hold: the split edges still valid get their new nodes
    /// in order (`NewNode(0..)`), the tips' points after them, and each `affected` tet its
    /// pieces (a four-way tip's piece on `A E C` split at its point, module `tip`).
    fn final_plan(
        &self,
        body: &SoftBody,
        edges: &mut HashMap<[u32; 2], EdgeCut>,
        candidate_edges: &[[u32; 2]],
        candidate_rest: &[DVec3],
        affected: &[u32],
        tips: Vec<FourWayTip>,
    ) -> Result<SplitPlan, SurgeryError> {
        let mut plan = SplitPlan::default();
        for (i, e) in candidate_edges.iter().enumerate() {
            if let Some(c) = edges.get_mut(e).filter(|c| c.valid) {
                c.node = Some(NewNode(plan.edges.len() as u32));
                plan.edges.push(SplitEdge { ends: *e, s: c.s });
                plan.new_rest.push(candidate_rest[i]);
            }
        }
        for tip in &tips {
            plan.new_rest.push(tip.point.rest(&self.rest));
        }
        plan.tips = tips;
        plan.tets.reserve(affected.len());
        let mut local: Vec<([u32; 2], NodeRef)> = Vec::new();
        for &t in affected {
            let tet = body.tets()[t as usize];
            split_edges_of(tet, edges, &mut local);
            let start = plan.pieces.len();
            bisect(tet.map(NodeRef::Body), &local, &mut plan.pieces);
            for (k, tip) in plan.tips.iter().enumerate().filter(|(_, tip)| tip.tet == t) {
                let e = edges.get(&tip.ab).filter(|c| c.valid).and_then(|c| c.node);
                let mut own = plan.pieces.split_off(start);
                let face = e.map(|e| [tip.a.into(), e.into(), tip.c.into()]);
                let p = NodeRef::New(plan.tip_node(k));
                if face.and_then(|f| split_face(&mut own, f, p)).is_none() {
                    return Err(SurgeryError::Defect {
                        element: "tet",
                        index: t as usize,
                        what: "a four-way tip's face is in none of its pieces",
                    });
                }
                plan.pieces.append(&mut own);
            }
            plan.tets.push(TetSplit {
                tet: t,
                pieces: start..plan.pieces.len(),
            });
        }
        Ok(plan)
    }

    /// Crossing points this sweep covered on edges it did not split: a later sweep in about
    /// the same place finds them covered (a cut continued over many steps).
    fn remember_covered(&mut self, edges: &HashMap<[u32; 2], EdgeCut>) {
        if self.covered.len() > COVERED_CAP {
            self.covered.clear();
        }
        for (e, c) in edges {
            if c.inside && !c.valid {
                self.covered.insert(*e, c.s);
            } else if c.valid {
                self.covered.remove(e);
            }
        }
    }

    /// Smallest rest volume a cut may create (cm³): [`MIN_VOLUME_FRACTION`] of the input's.
    pub(crate) fn volume_floor(&self) -> f64 {
        MIN_VOLUME_FRACTION * self.min_rest_volume as f64
    }

    /// Smallest rest volume of a piece a split creates (cm³): [`MIN_PIECE_FRACTION`] of the
    /// input's median tet, and at least [`Surgery::volume_floor`].
    pub(crate) fn piece_floor(&self) -> f64 {
        (MIN_PIECE_FRACTION * self.median_rest_volume).max(self.volume_floor())
    }

    /// Whether the `pieces` of `tet` (rest corners by `rest_of`) meet a split's bound: each
    /// piece's rest volume ≥ [`Surgery::piece_floor`] and radius ratio ≥ [`MIN_RATIO`], and
    /// together they tile the tet in rest space (volumes summing to its own within 10⁻⁹).
    pub(crate) fn pieces_meet_bound<N: Copy>(
        &self,
        tet: [N; 4],
        pieces: &[[N; 4]],
        rest_of: impl Fn(N) -> DVec3,
    ) -> bool {
        let parent = six_volume(tet.map(&rest_of));
        let mut sum = 0.0;
        pieces.iter().all(|p| {
            let r = p.map(&rest_of);
            let v = six_volume(r);
            sum += v;
            v / 6.0 >= self.piece_floor() && radius_ratio(r) >= MIN_RATIO
        }) && (sum - parent).abs() <= 1e-9 * parent.abs()
    }

    /// The tets around an edge (`tets` the body's: a tet of the first end's list holds the
    /// other end).
    pub(crate) fn tets_around<'a>(
        &'a self,
        tets: &'a [[u32; 4]],
        e: &'a [u32; 2],
    ) -> impl Iterator<Item = u32> + 'a {
        self.node_tets[e[0] as usize]
            .iter()
            .copied()
            .filter(move |&t| tets[t as usize].contains(&e[1]))
    }

    /// The tets around any of `edges`, sorted, each once.
    pub(crate) fn tets_around_edges(&self, tets: &[[u32; 4]], edges: &[[u32; 2]]) -> Vec<u32> {
        let mut around: Vec<u32> = edges
            .iter()
            .flat_map(|e| self.tets_around(tets, e))
            .collect();
        around.sort_unstable();
        around.dedup();
        around
    }

    /// Masses of the nodes of `tets` from their tets' rest volumes (eq. (1)).
    pub(crate) fn rebuild_masses(
        &self,
        body: &mut SoftBody,
        tets: &[u32],
    ) -> Result<(), SurgeryError> {
        let mut nodes: Vec<u32> = tets.iter().flat_map(|&t| body.tets()[t as usize]).collect();
        nodes.sort_unstable();
        nodes.dedup();
        let density = body.density() as f64;
        for v in nodes {
            let m: f64 = self.node_tets[v as usize]
                .iter()
                .map(|&t| density * body.tet_rest_volumes()[t as usize] as f64 / 4.0)
                .sum();
            body.set_node_mass(v, m as f32)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every sign pattern of the unit tet, with every crossing edge split: the pieces tile the
    /// tet (their volumes sum to its volume), none is flat or inverted, and none holds nodes of
    /// both sides.
    #[test]
    fn every_sign_pattern_tiles_the_tet_and_separates_the_sides() {
        let base = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        for code in 0..81u32 {
            let s: [i8; 4] = [0, 1, 2, 3].map(|k| ((code / 3u32.pow(k)) % 3) as i8 - 1);
            let mut x = base.to_vec();
            let mut split: Vec<([u32; 2], u32)> = Vec::new();
            for a in 0..4u32 {
                for b in a + 1..4 {
                    if s[a as usize] * s[b as usize] < 0 {
                        split.push(([a, b], x.len() as u32));
                        x.push(base[a as usize] * 0.4 + base[b as usize] * 0.6);
                    }
                }
            }
            let mut out = Vec::new();
            bisect([0, 1, 2, 3], &split, &mut out);
            let v: f64 = out
                .iter()
                .map(|t| six_volume(t.map(|i| x[i as usize])))
                .sum();
            assert!((v - 1.0).abs() < 1e-12, "{s:?}: {v}");
            for t in &out {
                assert!(six_volume(t.map(|i| x[i as usize])) > 1e-6, "{s:?}: {t:?}");
                let sides: Vec<i8> = t
                    .iter()
                    .filter(|&&i| i < 4)
                    .map(|&i| s[i as usize])
                    .collect();
                assert!(!(sides.contains(&1) && sides.contains(&-1)), "{s:?}: {t:?}");
            }
        }
    }

    /// Two tets sharing the face 0 1 2, any subset of its edges split: both sides triangulate
    /// the face the same way.
    #[test]
    fn neighbours_split_a_shared_face_alike() {
        let edges = [([0, 1], 5), ([1, 2], 6), ([0, 2], 7)];
        for mask in 1..8u32 {
            let split: Vec<([u32; 2], u32)> = (0..3)
                .filter(|k| mask & (1 << k) != 0)
                .map(|k| edges[k])
                .collect();
            let mut sorted = split.clone();
            sorted.sort_unstable();
            let on_face = |t: &[u32; 4]| -> Vec<[u32; 3]> {
                (0..4)
                    .map(|j| {
                        let mut f = face_nodes(t, j);
                        f.sort_unstable();
                        f
                    })
                    .filter(|f| f.iter().all(|&v| v != 3 && v != 4))
                    .collect()
            };
            let faces = |t: [u32; 4]| {
                let mut out = Vec::new();
                bisect(t, &sorted, &mut out);
                let mut f: Vec<[u32; 3]> = out.iter().flat_map(on_face).collect();
                f.sort_unstable();
                f
            };
            assert_eq!(faces([0, 1, 2, 3]), faces([0, 2, 1, 4]), "mask {mask}");
        }
    }
}
