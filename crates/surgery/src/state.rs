//! The surgery state kept next to a [`SoftBody`]: tet adjacency across faces (cut faces have
//! none), node → tets, each node's original, the distance constraint of each edge, sutures.

use crate::geometry::FxMap as HashMap;

use glam::DVec3;
use tissue_mesh::{NO_TET, TET_FACES};
use tissue_pbd::{ConstraintSlot, SoftBody};

use crate::geometry::radius_ratio;
use crate::workspace::CutScratch;
use crate::{SurgeryError, SurgerySettings};

/// A suture: a link constraint between two nodes on the two sides of a wound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Suture {
    /// The linked nodes.
    pub nodes: [u32; 2],
    /// The body's distance constraint that links them.
    pub constraint: usize,
    /// Their distance when the suture was placed (cm).
    pub initial_gap: f32,
}

/// Cutting and suturing state for one [`SoftBody`]; every operation takes that body.
///
/// Invariants (kept by every method; [`Surgery::validate`] re-checks them):
/// - `neighbours[t][j]` is the tet across face `j` of tet `t` (the face opposite local node `j`,
///   [`TET_FACES`] order) or [`NO_TET`] when that face is on the boundary (the original surface
///   or a cut wall); the relation is symmetric and neighbours share the face's three nodes;
/// - the boundary faces (those with no neighbour), wound outward, form a closed, manifold,
///   consistently oriented surface when the body's did at construction;
/// - `node_tets[v]` lists the tets using node `v`; `origin[v]` is the node of the original mesh
///   that `v` was split from (itself for original nodes);
/// - `edge_constraint` maps each sorted node pair of a tet edge to the body's live distance
///   constraint on it; tets are never removed: a split tet's record holds its first piece and
///   the others are appended; every tet's rest shape is at or above [`Surgery::quality_bound`];
/// - `rest[v]` is node `v`'s rest position, `depth[t]` how many splits made tet `t`.
#[derive(Debug, Clone)]
pub struct Surgery {
    /// The body this state was made for ([`SoftBody::id`]).
    pub(crate) body: tissue_pbd::BodyId,
    pub(crate) settings: SurgerySettings,
    pub(crate) neighbours: Vec<[u32; 4]>,
    pub(crate) node_tets: Vec<Vec<u32>>,
    pub(crate) origin: Vec<u32>,
    pub(crate) edge_constraint: HashMap<[u32; 2], u32>,
    /// Faces opened by cuts: (tet, local face).
    pub(crate) cut_faces: Vec<(u32, u8)>,
    /// The same per tet: bit `j` set when face `j` is in `cut_faces`.
    pub(crate) wall: Vec<u8>,
    /// Faces crossed by the blade but kept glued (they would have made the surface
    /// non-manifold at the cut's front): (tet, face, neighbour, its face), retried next cut.
    pub(crate) pending: Vec<FacePair>,
    pub(crate) sutures: Vec<Option<Suture>>,
    /// Piece label of each tet (see [`Surgery::tet_components`]).
    pub(crate) tet_component: Vec<u32>,
    pub(crate) component_count: usize,
    /// Per node: 1.5 × its longest rest edge (cm). A tet that straddles the blade's plane has a
    /// node at most this far from it (unless stretched by more than 1.5).
    pub(crate) node_reach: Vec<f32>,
    pub(crate) min_radius_ratio: f64,
    pub(crate) min_rest_volume: f32,
    /// Rest position of each node (cm, `f64`): the body's at construction, then moved by
    /// snapping and interpolated for nodes on split edges (the body's `rest_positions` are
    /// these rounded to `f32`).
    pub(crate) rest: Vec<DVec3>,
    /// Per tet: how many splits made it (0 for the input's tets); pieces (depth > 0) are held
    /// to [`crate::MIN_RATIO`], and a tet at [`crate::MAX_SPLIT_DEPTH`] is not split again.
    pub(crate) depth: Vec<u8>,
    /// Median rest volume of the input's tets (cm³).
    pub(crate) median_rest_volume: f64,
    /// Crossing points (parameter from the smaller node) of edges that a sweep covered but
    /// could not split yet, by sorted edge: a later sweep counts them as inside its polygon.
    pub(crate) covered: HashMap<[u32; 2], f64>,
    /// The cut pipeline's scratch buffers (module `workspace`): no state between cuts.
    pub(crate) scratch: CutScratch,
    /// How the cuts so far ended on the surface (see [`Surgery::tip_counts`]).
    pub(crate) tip_counts: crate::TipCounts,
}

/// An interior face seen from both sides: face `j` of tet `t` against face `k` of tet `u`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct FacePair {
    pub t: u32,
    pub j: u8,
    pub u: u32,
    pub k: u8,
}

/// The face of tet `t` opposite local node `j`, wound outward.
pub(crate) fn face_nodes(t: &[u32; 4], j: usize) -> [u32; 3] {
    TET_FACES[j].map(|i| t[i])
}

fn sorted3(mut f: [u32; 3]) -> [u32; 3] {
    f.sort_unstable();
    f
}

/// Tet adjacency across faces (`NO_TET` on the boundary) of `tets`, by matching faces.
fn face_adjacency(tets: &[[u32; 4]]) -> Vec<[u32; 4]> {
    let mut faces: HashMap<[u32; 3], (u32, u8)> =
        HashMap::with_capacity_and_hasher(tets.len() * 2, Default::default());
    let mut neighbours = vec![[NO_TET; 4]; tets.len()];
    for (t, tet) in tets.iter().enumerate() {
        for j in 0..4 {
            let key = sorted3(face_nodes(tet, j));
            if let Some((u, k)) = faces.remove(&key) {
                neighbours[t][j] = u;
                neighbours[u as usize][k as usize] = t as u32;
            } else {
                faces.insert(key, (t as u32, j as u8));
            }
        }
    }
    neighbours
}

/// Per node, 1.5 × its longest edge (current positions), and the smallest radius ratio of
/// the body's tets.
fn reach_and_quality(body: &SoftBody) -> (Vec<f32>, f64) {
    let x = body.positions();
    let tets = body.tets();
    let mut node_reach = vec![0.0f32; body.node_count()];
    let mut min_ratio = f64::INFINITY;
    for tet in tets {
        let p = tet.map(|i| x[i as usize].as_dvec3());
        for a in 0..4 {
            for b in a + 1..4 {
                let l = p[a].distance(p[b]) as f32;
                for k in [a, b] {
                    let r = &mut node_reach[tet[k] as usize];
                    *r = r.max(1.5 * l);
                }
            }
        }
        min_ratio = min_ratio.min(radius_ratio(p));
    }
    (node_reach, min_ratio)
}

impl Surgery {
    /// The state for `body` as it is (uncut, or as built): face adjacency, edges, quality.
    ///
    /// # Errors
    /// [`SurgeryError::InvalidSetting`] for bad settings.
    pub fn new(body: &SoftBody, settings: SurgerySettings) -> Result<Self, SurgeryError> {
        settings.validate()?;
        let tets = body.tets();
        let n = body.node_count();
        let neighbours = face_adjacency(tets);
        let mut node_tets = vec![Vec::new(); n];
        for (t, tet) in tets.iter().enumerate() {
            for &v in tet {
                node_tets[v as usize].push(t as u32);
            }
        }
        let mut edge_constraint = HashMap::with_capacity_and_hasher(
            body.distance_constraints().len(),
            Default::default(),
        );
        for (c, d) in body.distance_constraints().iter().enumerate() {
            if body.distance_slot(c) != Some(ConstraintSlot::Removed) {
                let [a, b] = d.nodes;
                edge_constraint.insert([a.min(b), a.max(b)], c as u32);
            }
        }
        let (node_reach, min_ratio) = reach_and_quality(body);
        let min_rest_volume = body
            .tet_rest_volumes()
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min);
        let mut s = Self {
            body: body.id(),
            settings,
            neighbours,
            node_tets,
            origin: (0..n as u32).collect(),
            edge_constraint,
            cut_faces: Vec::new(),
            wall: vec![0; tets.len()],
            pending: Vec::new(),
            sutures: Vec::new(),
            tet_component: Vec::new(),
            component_count: 0,
            node_reach,
            min_radius_ratio: min_ratio,
            min_rest_volume,
            rest: body.rest_positions().iter().map(|p| p.as_dvec3()).collect(),
            depth: vec![0; tets.len()],
            median_rest_volume: {
                let mut v: Vec<f32> = body.tet_rest_volumes().to_vec();
                v.sort_unstable_by(f32::total_cmp);
                v.get(v.len() / 2).copied().unwrap_or(0.0) as f64
            },
            covered: HashMap::default(),
            scratch: CutScratch::new(tets.len()),
            tip_counts: crate::TipCounts::default(),
        };
        s.count_components(body);
        Ok(s)
    }

    /// [`SurgeryError::BodyMismatch`] unless `body` is the body this state was made for (by
    /// identity, so a body of the same size built from the same mesh is refused too; a clone
    /// of it keeps its identity) with the nodes and tets this state knows.
    pub(crate) fn check_body(&self, body: &SoftBody) -> Result<(), SurgeryError> {
        if body.id() != self.body {
            return Err(SurgeryError::BodyMismatch {
                what: "body id",
                got: body.id().get() as usize,
                expected: self.body.get() as usize,
            });
        }
        if body.node_count() != self.node_tets.len() {
            return Err(SurgeryError::BodyMismatch {
                what: "nodes",
                got: body.node_count(),
                expected: self.node_tets.len(),
            });
        }
        if body.tets().len() != self.neighbours.len() {
            return Err(SurgeryError::BodyMismatch {
                what: "tets",
                got: body.tets().len(),
                expected: self.neighbours.len(),
            });
        }
        Ok(())
    }

    /// How the cuts so far ended on the surface: tips split into 4 and into 5, and four-way
    /// candidates refused (`docs/surgery.md`, "Tip split").
    pub fn tip_counts(&self) -> crate::TipCounts {
        self.tip_counts
    }

    /// The settings.
    pub fn settings(&self) -> &SurgerySettings {
        &self.settings
    }

    /// The quality bound every tet keeps through any cut: `(smallest rest volume (cm³),
    /// smallest rest radius ratio 3r_in/r_circ)`. The volume is [`crate::MIN_VOLUME_FRACTION`]
    /// of the input mesh's smallest; the ratio is the smaller of the input's smallest and
    /// [`crate::MIN_RATIO`]. Every tet a split creates has a radius ratio of at least
    /// [`crate::MIN_RATIO`] (pieces that would not are not created: that tet stays whole), and
    /// a snap never makes a tet's ratio worse than `min(MIN_RATIO, its ratio before)`.
    /// [`Surgery::validate`] checks both.
    pub fn quality_bound(&self) -> (f32, f64) {
        (
            self.volume_floor() as f32,
            self.min_radius_ratio.min(crate::MIN_RATIO),
        )
    }

    /// Tet adjacency across faces (`NO_TET` on the boundary and across cut walls).
    pub fn neighbours(&self) -> &[[u32; 4]] {
        &self.neighbours
    }

    /// The node of the original mesh each node was split from.
    pub fn origins(&self) -> &[u32] {
        &self.origin
    }

    /// Faces opened by cuts so far, as (tet, local face); both walls of each cut appear.
    pub fn cut_faces(&self) -> &[(u32, u8)] {
        &self.cut_faces
    }

    /// The sutures placed so far (`None` where removed), by id.
    pub fn sutures(&self) -> &[Option<Suture>] {
        &self.sutures
    }

    /// Number of connected pieces (tets sharing nodes).
    pub fn component_count(&self) -> usize {
        self.component_count
    }

    /// Piece label of each tet: the pieces of the input `0, 1, …` (by smallest tet), then each
    /// detached piece the next label, in order of detachment.
    pub fn tet_components(&self) -> &[u32] {
        &self.tet_component
    }

    /// The boundary surface: every tet face without a neighbour (original surface and cut
    /// walls), wound outward, in the body's node numbering.
    pub fn boundary_faces(&self, body: &SoftBody) -> Vec<[u32; 3]> {
        let tets = body.tets();
        let mut out = Vec::new();
        for (t, nb) in self.neighbours.iter().enumerate() {
            for (j, &u) in nb.iter().enumerate() {
                if u == NO_TET {
                    out.push(face_nodes(&tets[t], j));
                }
            }
        }
        out
    }

    /// Labels the pieces (union–find over tets through shared nodes) `0, 1, …` in the order of
    /// their smallest tet.
    pub(crate) fn count_components(&mut self, body: &SoftBody) {
        let (comp, count) = components(body);
        self.tet_component = comp;
        self.component_count = count;
    }

    /// After a cut that may have detached pieces: the pieces again (union–find), each keeping
    /// the label its tets had when it is the first (by smallest tet) with that label, the others
    /// getting new labels. Returns the new pieces' tets (sorted).
    pub(crate) fn relabel_pieces(&mut self, body: &SoftBody) -> Vec<Vec<u32>> {
        let old = std::mem::take(&mut self.tet_component);
        self.count_components(body);
        let fresh = std::mem::take(&mut self.tet_component);
        // fresh label → final label.
        let mut map: Vec<u32> = vec![u32::MAX; self.component_count];
        let mut claimed: HashMap<u32, ()> = HashMap::default();
        let mut next = old.iter().copied().max().map_or(0, |m| m + 1);
        let mut pieces: Vec<Vec<u32>> = Vec::new();
        let mut piece_of: HashMap<u32, usize> = HashMap::default();
        let mut labels = Vec::with_capacity(fresh.len());
        for (t, &f) in fresh.iter().enumerate() {
            if map[f as usize] == u32::MAX {
                if claimed.insert(old[t], ()).is_none() {
                    map[f as usize] = old[t];
                } else {
                    map[f as usize] = next;
                    piece_of.insert(next, pieces.len());
                    pieces.push(Vec::new());
                    next += 1;
                }
            }
            let l = map[f as usize];
            if let Some(&k) = piece_of.get(&l) {
                pieces[k].push(t as u32);
            }
            labels.push(l);
        }
        self.tet_component = labels;
        pieces
    }

    /// Re-checks the invariants against `body`: adjacency symmetric and sharing nodes, the
    /// boundary surface edge-manifold, consistently oriented and vertex-manifold, node → tet
    /// lists right, edge constraints live and on their edge, every tet positive in rest volume
    /// at or above the quality bound and finite. For tests; O(tets).
    ///
    /// # Errors
    /// [`SurgeryError::Defect`] naming the first defect found, or a body mismatch.
    pub fn validate(&self, body: &SoftBody) -> Result<(), SurgeryError> {
        self.check_body(body)?;
        self.check_adjacency(body)?;
        self.check_node_lists(body)?;
        self.check_boundary(body)?;
        self.check_tets(body)?;
        self.check_pieces(body)?;
        self.check_constraints(body)
    }

    /// [`Surgery::validate`]: adjacency symmetric, neighbours sharing the face's nodes.
    fn check_adjacency(&self, body: &SoftBody) -> Result<(), SurgeryError> {
        let tets = body.tets();
        for (t, nb) in self.neighbours.iter().enumerate() {
            for (j, &u) in nb.iter().enumerate() {
                if u == NO_TET {
                    continue;
                }
                let back = self.neighbours[u as usize]
                    .iter()
                    .position(|&w| w as usize == t);
                let Some(k) = back else {
                    return defect("tet", t, "adjacency is not symmetric");
                };
                if sorted3(face_nodes(&tets[t], j)) != sorted3(face_nodes(&tets[u as usize], k)) {
                    return defect("tet", t, "neighbours do not share the face's nodes");
                }
            }
        }
        Ok(())
    }

    /// [`Surgery::validate`]: node → tet lists right and complete, per-node arrays alike.
    fn check_node_lists(&self, body: &SoftBody) -> Result<(), SurgeryError> {
        let tets = body.tets();
        for (v, list) in self.node_tets.iter().enumerate() {
            if list
                .iter()
                .any(|&t| !tets[t as usize].contains(&(v as u32)))
            {
                return defect("node", v, "node → tet list names a tet without the node");
            }
        }
        if self.node_reach.len() != self.node_tets.len()
            || self.origin.len() != self.node_tets.len()
            || self.rest.len() != self.node_tets.len()
        {
            return defect(
                "node",
                self.node_tets.len(),
                "per-node arrays of different lengths",
            );
        }
        if self.node_tets.iter().map(Vec::len).sum::<usize>() != 4 * tets.len() {
            return defect("node", 0, "node → tet lists miss tets");
        }
        Ok(())
    }

    /// [`Surgery::validate`]: the boundary's directed edges pair up exactly, no double face,
    /// and the boundary faces around each vertex make one fan.
    fn check_boundary(&self, body: &SoftBody) -> Result<(), SurgeryError> {
        let faces = self.boundary_faces(body);
        let mut directed: HashMap<[u32; 2], u32> =
            HashMap::with_capacity_and_hasher(faces.len() * 3, Default::default());
        for f in &faces {
            for k in 0..3 {
                *directed.entry([f[k], f[(k + 1) % 3]]).or_default() += 1;
            }
        }
        for (&[a, b], &count) in &directed {
            if count != 1 {
                return defect(
                    "edge",
                    a as usize,
                    "edge used twice in the same direction (non-manifold or mis-oriented)",
                );
            }
            if directed.get(&[b, a]) != Some(&1) {
                return defect(
                    "edge",
                    a as usize,
                    "boundary edge without its opposite (open or non-manifold)",
                );
            }
        }
        let mut seen: HashMap<[u32; 3], ()> =
            HashMap::with_capacity_and_hasher(faces.len(), Default::default());
        for f in &faces {
            if seen.insert(sorted3(*f), ()).is_some() {
                return defect(
                    "vertex",
                    f[0] as usize,
                    "two boundary triangles on the same three nodes (a double face)",
                );
            }
        }
        // Vertex links: the boundary faces around a vertex make one cycle.
        let mut around: Vec<(u32, [u32; 2])> = Vec::with_capacity(faces.len() * 3);
        for f in &faces {
            for k in 0..3 {
                around.push((f[k], [f[(k + 1) % 3], f[(k + 2) % 3]]));
            }
        }
        if let Some(&v) = pinched_vertices(&mut around).first() {
            return defect(
                "vertex",
                v as usize,
                "boundary faces around the vertex do not form one fan (pinched)",
            );
        }
        Ok(())
    }

    /// [`Surgery::validate`]: every tet at or above the quality bound, with finite nodes.
    fn check_tets(&self, body: &SoftBody) -> Result<(), SurgeryError> {
        let x = body.positions();
        let rest = body.tet_rest_volumes();
        for (t, tet) in body.tets().iter().enumerate() {
            if (rest[t] as f64) < self.volume_floor() {
                return defect("tet", t, "rest volume below the quality bound");
            }
            if self.depth.get(t).is_some_and(|&d| d > 0)
                && radius_ratio(tet.map(|i| self.rest[i as usize])) < crate::MIN_RATIO
            {
                return defect("tet", t, "a piece of a split below the radius-ratio bound");
            }
            if tet.iter().any(|&i| !x[i as usize].is_finite()) {
                return defect("tet", t, "non-finite node position");
            }
        }
        Ok(())
    }

    /// [`Surgery::validate`]: tets sharing a node carry one label, and there are as many
    /// labels as pieces.
    fn check_pieces(&self, body: &SoftBody) -> Result<(), SurgeryError> {
        for (v, list) in self.node_tets.iter().enumerate() {
            if let Some(&first) = list.first() {
                let l = self.tet_component[first as usize];
                if list.iter().any(|&t| self.tet_component[t as usize] != l) {
                    return defect(
                        "node",
                        v,
                        "tets sharing the node carry different piece labels",
                    );
                }
            }
        }
        let (_, recounted) = components(body);
        let mut distinct: Vec<u32> = self.tet_component.clone();
        distinct.sort_unstable();
        distinct.dedup();
        if recounted != self.component_count || distinct.len() != self.component_count {
            return defect(
                "tet",
                recounted * 1000 + self.component_count,
                "the piece count is wrong (index: actual × 1000 + counted)",
            );
        }
        Ok(())
    }

    /// [`Surgery::validate`]: every edge's distance constraint live and on its edge.
    fn check_constraints(&self, body: &SoftBody) -> Result<(), SurgeryError> {
        for (&[a, b], &c) in &self.edge_constraint {
            let d = body.distance_constraints()[c as usize];
            let [p, q] = d.nodes;
            if [p.min(q), p.max(q)] != [a, b]
                || body.distance_slot(c as usize) == Some(ConstraintSlot::Removed)
            {
                return defect(
                    "edge",
                    a as usize,
                    "edge's distance constraint is removed or on other nodes",
                );
            }
        }
        Ok(())
    }
}

/// A [`SurgeryError::Defect`] found by [`Surgery::validate`].
fn defect(element: &'static str, index: usize, what: &'static str) -> Result<(), SurgeryError> {
    Err(SurgeryError::Defect {
        element,
        index,
        what,
    })
}

/// The vertices of `around` — (vertex, link edge `(b, c)`), one entry per boundary face at
/// the vertex — whose link edges do not form a single cycle (a pinch), in increasing order;
/// `around` is grouped by vertex on the way (sorted by vertex only: a cycle does not depend
/// on the order of its edges).
pub(crate) fn pinched_vertices(around: &mut [(u32, [u32; 2])]) -> Vec<u32> {
    around.sort_unstable_by_key(|a| a.0);
    let mut link: Vec<[u32; 2]> = Vec::new();
    let mut out = Vec::new();
    for group in around.chunk_by(|a, b| a.0 == b.0) {
        link.clear();
        link.extend(group.iter().map(|g| g.1));
        if !single_cycle(&link) {
            out.push(group[0].0);
        }
    }
    out
}

/// Whether the directed link edges `(b, c)` (one per boundary face around a vertex) form a
/// single cycle.
fn single_cycle(link: &[[u32; 2]]) -> bool {
    if link.is_empty() {
        return true;
    }
    // Each link vertex must start exactly one edge and end exactly one.
    for e in link {
        if link.iter().filter(|f| f[0] == e[0]).count() != 1
            || link.iter().filter(|f| f[1] == e[1]).count() != 1
        {
            return false;
        }
    }
    // Walked back to the start after visiting every edge exactly once.
    let next = |a: u32| link.iter().find(|e| e[0] == a).map(|e| e[1]);
    let start = link[0][0];
    let mut b = start;
    let mut steps = 0;
    loop {
        let Some(n) = next(b) else {
            return false;
        };
        b = n;
        steps += 1;
        if b == start || steps > link.len() {
            break;
        }
    }
    steps == link.len()
}

/// The pieces of `body` (union–find over tets through shared nodes), labelled `0, 1, …` in the
/// order of their smallest tet: each tet's label and the count.
fn components(body: &SoftBody) -> (Vec<u32>, usize) {
    let tets = body.tets();
    let n = body.node_count();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut i: u32) -> u32 {
        while p[i as usize] != i {
            let g = p[p[i as usize] as usize];
            p[i as usize] = g;
            i = g;
        }
        i
    }
    for t in tets {
        let mut r0 = find(&mut parent, t[0]);
        for &v in &t[1..] {
            let r = find(&mut parent, v);
            if r != r0 {
                let (lo, hi) = (r.min(r0), r.max(r0));
                parent[hi as usize] = lo;
                r0 = lo;
            }
        }
    }
    let mut root_comp = vec![u32::MAX; n];
    let mut comp = Vec::with_capacity(tets.len());
    let mut count = 0;
    for t in tets {
        let r = find(&mut parent, t[0]) as usize;
        if root_comp[r] == u32::MAX {
            root_comp[r] = count;
            count += 1;
        }
        comp.push(root_comp[r]);
    }
    (comp, count as usize)
}
