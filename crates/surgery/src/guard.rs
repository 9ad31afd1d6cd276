//! The manifold guard of a cut (step 5 of module `cut`): before anything is committed, each
//! node on a newly opened face gets a split plan (its tets grouped by the faces at it that
//! stay glued), and the boundary the plans would make around the touched nodes is checked.
//! New faces on an edge that would not be manifold, at a vertex whose boundary would be
//! pinched, or with no node split (a zero-width double face) are glued back (and queued to be
//! retried by a later cut), the plans of their nodes redone, and the check repeated.

use tissue_mesh::NO_TET;
use tissue_pbd::SoftBody;

use crate::geometry::FxMap as HashMap;
use crate::state::{face_nodes, pinched_vertices, FacePair};
use crate::Surgery;

/// How one node on a new face splits: its tets (`star`, sorted) grouped into face-connected
/// components through the faces at it that stay glued (`comp`, per star tet), `count` of them.
/// The first component keeps the node, each other one gets a copy.
#[derive(Debug, Clone)]
pub(crate) struct NodePlan {
    pub node: u32,
    pub star: Vec<u32>,
    pub comp: Vec<u32>,
    pub count: u32,
}

impl NodePlan {
    /// Whether the node is split (more than one component).
    pub fn splits(&self) -> bool {
        self.count > 1
    }

    /// Copies the node gets.
    pub fn copies(&self) -> u32 {
        self.count.saturating_sub(1)
    }
}

/// Tentative node labels while a plan is checked: the copies of plan entry `i` numbered from
/// `base[i]`, past the body's nodes, as the commit will number them.
struct Labels<'a> {
    plan: &'a [NodePlan],
    /// Node → its index in `plan` (`u32::MAX` for none).
    entry: &'a [u32],
    base: Vec<u32>,
    node_count: u32,
}

impl<'a> Labels<'a> {
    fn new(plan: &'a [NodePlan], entry: &'a [u32], node_count: u32) -> Self {
        let mut base = Vec::with_capacity(plan.len());
        let mut next = node_count;
        for p in plan {
            base.push(next);
            next += p.copies();
        }
        Self {
            plan,
            entry,
            base,
            node_count,
        }
    }

    /// Node `v`'s index in the plan.
    fn entry(&self, v: u32) -> Option<usize> {
        let i = self.entry.get(v as usize).copied().unwrap_or(u32::MAX);
        (i != u32::MAX).then_some(i as usize)
    }

    /// Whether node `v` is on a new face (has a plan).
    fn touched(&self, v: u32) -> bool {
        self.entry(v).is_some()
    }

    /// The label of node `v` in tet `t` once the plan is committed.
    fn relabel(&self, t: u32, v: u32) -> u32 {
        if let Some(i) = self.entry(v) {
            let p = &self.plan[i];
            if p.splits() {
                if let Ok(s) = p.star.binary_search(&t) {
                    if p.comp[s] > 0 {
                        return self.base[i] + p.comp[s] - 1;
                    }
                }
            }
        }
        v
    }

    /// Back from a label to the node: the node itself or the one it copies.
    fn original(&self, label: u32) -> u32 {
        let i = self.base.partition_point(|&b| b <= label);
        if label < self.node_count || i == 0 {
            label
        } else {
            self.plan[i - 1].node
        }
    }
}

impl Surgery {
    /// The guard: glues back the new `faces` that would leave the boundary non-manifold (see
    /// the module docs) until none does. Returns the nodes' split plans for the faces left
    /// (sorted by node), or `None` when every face was glued back.
    ///
    /// Gluing a face back changes the plan of its three nodes only: the plan is updated, not
    /// rebuilt, between rounds, and the check limited to what those nodes can change.
    pub(crate) fn guard_manifold(
        &mut self,
        body: &SoftBody,
        faces: &mut Vec<FacePair>,
    ) -> Option<Vec<NodePlan>> {
        let mut plan = self.plan_nodes(body, faces);
        let mut changed: Option<Vec<u32>> = None;
        loop {
            let bad = self.check_plan(body, faces, &plan, changed.as_deref());
            if bad.is_empty() {
                return Some(plan);
            }
            let touched = self.glue_back(body, faces, &bad);
            if faces.is_empty() {
                return None;
            }
            let mut on_faces: Vec<u32> = faces
                .iter()
                .flat_map(|f| face_nodes(&body.tets()[f.t as usize], f.j as usize))
                .collect();
            on_faces.sort_unstable();
            on_faces.dedup();
            plan.retain(|p| on_faces.binary_search(&p.node).is_ok());
            for &v in &touched {
                if let Ok(i) = plan.binary_search_by_key(&v, |p| p.node) {
                    plan[i] = self.plan_node(body, v);
                }
            }
            changed = Some(touched);
        }
    }

    /// [`Surgery::defects`] of `plan`, with the node → plan index map and the tet marks of
    /// the workspace (left cleared).
    fn check_plan(
        &mut self,
        body: &SoftBody,
        faces: &[FacePair],
        plan: &[NodePlan],
        changed: Option<&[u32]>,
    ) -> Vec<usize> {
        let mut entry = std::mem::take(&mut self.scratch.plan_entry);
        entry.resize(body.node_count(), u32::MAX);
        for (i, p) in plan.iter().enumerate() {
            entry[p.node as usize] = i as u32;
        }
        let mut seen = std::mem::take(&mut self.scratch.tet_seen);
        let bad = self.defects(body, faces, plan, &entry, &mut seen, changed);
        self.scratch.tet_seen = seen;
        for p in plan {
            entry[p.node as usize] = u32::MAX;
        }
        self.scratch.plan_entry = entry;
        bad
    }

    /// Glues the faces `bad` (indices into `faces`) back, queues them to be retried by a
    /// later cut, and removes them from `faces`. Returns their nodes (sorted).
    fn glue_back(&mut self, body: &SoftBody, faces: &mut Vec<FacePair>, bad: &[usize]) -> Vec<u32> {
        let mut keep = Vec::with_capacity(faces.len());
        let mut touched: Vec<u32> = Vec::new();
        for (i, f) in faces.iter().enumerate() {
            if bad.contains(&i) {
                self.neighbours[f.t as usize][f.j as usize] = f.u;
                self.neighbours[f.u as usize][f.k as usize] = f.t;
                self.pending.push(*f);
                touched.extend(face_nodes(&body.tets()[f.t as usize], f.j as usize));
            } else {
                keep.push(*f);
            }
        }
        *faces = keep;
        touched.sort_unstable();
        touched.dedup();
        touched
    }

    /// For each node on a new face, its split plan (sorted by node).
    fn plan_nodes(&mut self, body: &SoftBody, faces: &[FacePair]) -> Vec<NodePlan> {
        let tets = body.tets();
        let mut nodes: Vec<u32> = faces
            .iter()
            .flat_map(|f| face_nodes(&tets[f.t as usize], f.j as usize))
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        let mut plan = Vec::with_capacity(nodes.len());
        for v in nodes {
            plan.push(self.plan_node(body, v));
        }
        plan
    }

    /// Node `v`'s split plan: its tets grouped into face-connected components through the
    /// glued faces at `v` (a depth-first search over its star).
    fn plan_node(&mut self, body: &SoftBody, v: u32) -> NodePlan {
        let tets = body.tets();
        let mut star = self.node_tets[v as usize].clone();
        star.sort_unstable();
        // The star's nodes and neighbours, loaded before the search branches on them (the
        // loads are independent, so their cache misses overlap).
        let around: Vec<([u32; 4], [u32; 4])> = star
            .iter()
            .map(|&t| (tets[t as usize], self.neighbours[t as usize]))
            .collect();
        // Each star tet's index in the star, by tet (a scratch array: entries of other tets
        // are stale, so a hit is checked against the star).
        let mut slot = std::mem::take(&mut self.scratch.star_slot);
        slot.resize(self.neighbours.len(), u32::MAX);
        for (i, &t) in star.iter().enumerate() {
            slot[t as usize] = i as u32;
        }
        let mut comp = vec![u32::MAX; star.len()];
        let mut count = 0;
        let mut stack = Vec::new();
        for s in 0..star.len() {
            if comp[s] != u32::MAX {
                continue;
            }
            comp[s] = count;
            stack.push(s);
            while let Some(a) = stack.pop() {
                let (nodes, neighbours) = &around[a];
                for (&node, &u) in nodes.iter().zip(neighbours) {
                    if node == v || u == NO_TET {
                        continue;
                    }
                    // A neighbour across a face at `v` is in its star.
                    let b = slot.get(u as usize).map_or(usize::MAX, |&b| b as usize);
                    if star.get(b) == Some(&u) && comp[b] == u32::MAX {
                        comp[b] = count;
                        stack.push(b);
                    }
                }
            }
            count += 1;
        }
        self.scratch.star_slot = slot;
        NodePlan {
            node: v,
            star,
            comp,
            count,
        }
    }

    /// Indices of the new faces to glue back: those on a boundary edge that would not be
    /// manifold, and all new faces at a vertex whose boundary would be pinched.
    ///
    /// `changed` (sorted) limits the check to what gluing those nodes' faces back can change:
    /// edges at a changed node and vertices sharing a boundary face with one. The caller passes
    /// the nodes of the faces glued back since the last call, whose plans alone changed; every
    /// defect elsewhere was there before and gave no face to glue, so the result is the same
    /// as a full check (`None`). `plan_entry[v]` is node `v`'s index in `plan` (`u32::MAX`
    /// for none); `seen` is scratch, all `false` (and left so).
    fn defects(
        &self,
        body: &SoftBody,
        faces: &[FacePair],
        plan: &[NodePlan],
        plan_entry: &[u32],
        seen: &mut Vec<bool>,
        changed: Option<&[u32]>,
    ) -> Vec<usize> {
        let labels = Labels::new(plan, plan_entry, body.node_count() as u32);
        // The vertices to check: the touched ones, or, limited, those on a boundary face of
        // a tet at a changed node.
        let vertices: Option<Vec<u32>> = changed.map(|c| self.checked_vertices(body, &labels, c));
        let local = self.local_tets(body, plan, vertices.as_deref(), seen);
        let (bad_edges, bad_vertices) =
            self.boundary_defects(body, &labels, &local, changed, vertices.as_deref());
        faces_to_glue(body, faces, &labels, bad_edges, bad_vertices, changed)
    }

    /// The touched vertices a limited check looks at (sorted): the `changed` nodes and the
    /// touched nodes on a boundary face at one of them.
    fn checked_vertices(&self, body: &SoftBody, labels: &Labels<'_>, changed: &[u32]) -> Vec<u32> {
        let tets = body.tets();
        let mut w: Vec<u32> = changed.to_vec();
        for &g in changed {
            for &t in &self.node_tets[g as usize] {
                for j in 0..4 {
                    if self.neighbours[t as usize][j] == NO_TET {
                        let f = face_nodes(&tets[t as usize], j);
                        if f.contains(&g) {
                            w.extend(f.iter().copied().filter(|&v| labels.touched(v)));
                        }
                    }
                }
            }
        }
        w.sort_unstable();
        w.dedup();
        w
    }

    /// The tets whose boundary faces hold every face at the edges and vertices checked: the
    /// stars of the plan's nodes, or of `vertices` when limited. Each once, in the order found
    /// (marked in `seen`, cleared after).
    fn local_tets(
        &self,
        body: &SoftBody,
        plan: &[NodePlan],
        vertices: Option<&[u32]>,
        seen: &mut Vec<bool>,
    ) -> Vec<u32> {
        let mut local: Vec<u32> = Vec::new();
        seen.resize(body.tets().len(), false);
        let stars: Vec<&[u32]> = match vertices {
            None => plan.iter().map(|p| p.star.as_slice()).collect(),
            Some(w) => w
                .iter()
                .map(|&v| self.node_tets[v as usize].as_slice())
                .collect(),
        };
        for &t in stars.into_iter().flatten() {
            if !std::mem::replace(&mut seen[t as usize], true) {
                local.push(t);
            }
        }
        for &t in &local {
            seen[t as usize] = false;
        }
        local
    }

    /// The defects of the boundary faces of the `local` tets in tentative labels: edges (at a
    /// touched node, and at a `changed` one when limited) not used once each way, in original
    /// labels (sorted); vertices checked (touched, and in `vertices` when limited) whose faces
    /// do not make one fan, as the nodes they copy (sorted).
    fn boundary_defects(
        &self,
        body: &SoftBody,
        labels: &Labels<'_>,
        local: &[u32],
        changed: Option<&[u32]>,
        vertices: Option<&[u32]>,
    ) -> (Vec<[u32; 2]>, Vec<u32>) {
        let tets = body.tets();
        let in_changed = |v: u32| changed.is_none_or(|c| c.binary_search(&v).is_ok());
        let check_vertex =
            |v: u32| labels.touched(v) && vertices.is_none_or(|w| w.binary_search(&v).is_ok());
        // Boundary faces' directed edges in tentative labels: count, and the original labels.
        let mut directed: HashMap<[u32; 2], (u32, [u32; 2])> =
            HashMap::with_capacity_and_hasher(2 * local.len(), Default::default());
        // (vertex, link edge) of each boundary face at a checked vertex, grouped by sorting.
        let mut around: Vec<(u32, [u32; 2])> = Vec::new();
        // The local tets' nodes and neighbours, loaded before the loop that branches on them
        // (independent loads: their cache misses overlap).
        let local_tets: Vec<([u32; 4], [u32; 4])> = local
            .iter()
            .map(|&t| (tets[t as usize], self.neighbours[t as usize]))
            .collect();
        for (&t, (nodes, neighbours)) in local.iter().zip(&local_tets) {
            for (j, &u) in neighbours.iter().enumerate() {
                if u != NO_TET {
                    continue;
                }
                let orig = face_nodes(nodes, j);
                let f = orig.map(|v| labels.relabel(t, v));
                for k in 0..3 {
                    let (a, b) = (orig[k], orig[(k + 1) % 3]);
                    if (labels.touched(a) || labels.touched(b)) && (in_changed(a) || in_changed(b))
                    {
                        let e = directed
                            .entry([f[k], f[(k + 1) % 3]])
                            .or_insert((0, [a, b]));
                        e.0 += 1;
                    }
                    if check_vertex(orig[k]) {
                        around.push((f[k], [f[(k + 1) % 3], f[(k + 2) % 3]]));
                    }
                }
            }
        }
        let mut bad_edges: Vec<[u32; 2]> = Vec::new();
        for (&[a, b], &(count, orig)) in &directed {
            let back = directed.get(&[b, a]).map_or(0, |e| e.0);
            if count != 1 || back != 1 {
                bad_edges.push([orig[0].min(orig[1]), orig[0].max(orig[1])]);
            }
        }
        let mut bad_vertices: Vec<u32> = pinched_vertices(&mut around)
            .into_iter()
            .map(|l| labels.original(l))
            .collect();
        bad_edges.sort_unstable();
        bad_edges.dedup();
        bad_vertices.sort_unstable();
        bad_vertices.dedup();
        (bad_edges, bad_vertices)
    }
}

/// One new face per defect: the last new face on each bad edge or at each bad vertex (a chord
/// of the crack between two front nodes, or a crack touching the surface at a point), then
/// every new face none of whose nodes would be split (a zero-width double face: it waits).
/// A defect no new face touches was there before this cut: nothing to glue for it.
fn faces_to_glue(
    body: &SoftBody,
    faces: &[FacePair],
    labels: &Labels<'_>,
    bad_edges: Vec<[u32; 2]>,
    bad_vertices: Vec<u32>,
    changed: Option<&[u32]>,
) -> Vec<usize> {
    let tets = body.tets();
    let in_changed = |v: u32| changed.is_none_or(|c| c.binary_search(&v).is_ok());
    let mut out: Vec<usize> = Vec::new();
    let nodes_of: Vec<[u32; 3]> = faces
        .iter()
        .map(|f| face_nodes(&tets[f.t as usize], f.j as usize))
        .collect();
    for e in &bad_edges {
        let covered = out
            .iter()
            .any(|&i| nodes_of[i].contains(&e[0]) && nodes_of[i].contains(&e[1]));
        if !covered {
            if let Some(i) = (0..faces.len())
                .rev()
                .find(|&i| nodes_of[i].contains(&e[0]) && nodes_of[i].contains(&e[1]))
            {
                out.push(i);
            }
        }
    }
    for v in &bad_vertices {
        if !out.iter().any(|&i| nodes_of[i].contains(v)) {
            if let Some(i) = (0..faces.len()).rev().find(|&i| nodes_of[i].contains(v)) {
                out.push(i);
            }
        }
    }
    for (i, f) in faces.iter().enumerate() {
        if !out.contains(&i)
            && nodes_of[i].iter().any(|&v| in_changed(v))
            && nodes_of[i]
                .iter()
                .all(|&v| labels.relabel(f.t, v) == labels.relabel(f.u, v))
        {
            out.push(i);
        }
    }
    out
}
