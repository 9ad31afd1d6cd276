//! Applying a split's plan ([`SplitPlan`], module `plan`) to the body and the surgery state,
//! in phases: the new nodes, the pieces, their adjacency, the walls and surface triangles they
//! carry, their constraints, masses and depths.

use glam::{DVec3, Vec3};
use tissue_mesh::NO_TET;
use tissue_pbd::{DistanceConstraint, SoftBody};

use crate::geometry::FxMap as HashMap;
use crate::plan::SplitPlan;
use crate::split::{sorted2, SplitOutcome};
use crate::state::face_nodes;
use crate::{SplitTriangle, Surgery, SurgeryError};

/// A piece made by the split: its tet and the position of its parent in the plan.
#[derive(Debug, Clone, Copy)]
struct Piece {
    tet: u32,
    parent: usize,
}

/// A face of a piece (or of a whole neighbour of a split tet) waiting for its match: the
/// tet, its local face, and the tet it came from (its parent, or itself when whole).
#[derive(Debug, Clone, Copy)]
struct HalfFace {
    tet: u32,
    face: u8,
    parent: u32,
}

/// The split tets as they were before the split, by position in the plan.
struct Parents {
    tets: Vec<[u32; 4]>,
    neighbours: Vec<[u32; 4]>,
    /// Their wall bits (`Surgery::wall`).
    walls: Vec<u8>,
    depths: Vec<u8>,
    /// A distance constraint on one of each tet's edges: the template of its pieces' new
    /// edges' constraints.
    templates: Vec<Option<DistanceConstraint>>,
    /// Tet → its position in the plan.
    index: HashMap<u32, usize>,
}

impl Parents {
    fn new(s: &Surgery, body: &SoftBody, plan: &SplitPlan) -> Self {
        let tets: Vec<[u32; 4]> = plan
            .tets
            .iter()
            .map(|p| body.tets()[p.tet as usize])
            .collect();
        // Templates for new distance constraints: a constraint of each split tet's edges.
        let template = |tet: &[u32; 4]| -> Option<DistanceConstraint> {
            (0..4)
                .flat_map(|a| (a + 1..4).map(move |b| (a, b)))
                .find_map(|(a, b)| s.edge_constraint.get(&sorted2(tet[a], tet[b])))
                .map(|&c| body.distance_constraints()[c as usize])
        };
        Self {
            neighbours: plan
                .tets
                .iter()
                .map(|p| s.neighbours[p.tet as usize])
                .collect(),
            walls: plan.tets.iter().map(|p| s.wall[p.tet as usize]).collect(),
            depths: plan.tets.iter().map(|p| s.depth[p.tet as usize]).collect(),
            templates: tets.iter().map(template).collect(),
            tets,
            index: plan
                .tets
                .iter()
                .enumerate()
                .map(|(k, p)| (p.tet, k))
                .collect(),
        }
    }

    /// Whether split tets `a` and `b` were face neighbours before the split.
    fn were_neighbours(&self, a: u32, b: u32) -> bool {
        self.index
            .get(&a)
            .is_some_and(|&k| self.neighbours[k].contains(&b))
            || self
                .index
                .get(&b)
                .is_some_and(|&k| self.neighbours[k].contains(&a))
    }
}

impl Surgery {
    /// Applies `plan` (module `plan`): new nodes appended (edge nodes, then tip points), each
    /// split tet's record reused for its first piece and the other pieces appended, adjacency,
    /// walls and split surface triangles carried onto the pieces, distance constraints (a split
    /// edge's moves onto its first half, new edges get one), masses and depths. `out` gets the
    /// new nodes and tets, the split tets and the split boundary triangles.
    pub(crate) fn apply_split(
        &mut self,
        body: &mut SoftBody,
        plan: &SplitPlan,
        out: &mut SplitOutcome,
    ) -> Result<(), SurgeryError> {
        let (first, supports) = self.add_split_nodes(body, plan)?;
        out.first_node = first;
        out.end_node = first + plan.new_node_count();
        // The pieces with the new nodes numbered (a workspace buffer).
        let mut pieces = std::mem::take(&mut self.scratch.pieces);
        pieces.clear();
        pieces.extend(plan.pieces.iter().map(|p| p.map(|v| v.resolve(first))));
        let parents = Parents::new(self, body, plan);
        let made = self.place_pieces(body, plan, &parents, &pieces, out);
        let piece_count = pieces.len();
        self.scratch.pieces = pieces;
        let made = made?;
        self.link_pieces(body, plan, &parents, &made);
        self.carry_boundary(body, plan, &parents, &made, first, &supports, out);
        self.constrain_pieces(body, plan, &parents, &made, first)?;
        let touched: Vec<u32> = made.iter().map(|m| m.tet).collect();
        self.rebuild_masses(body, &touched)?;
        self.depth.resize(body.tets().len(), 0);
        for m in &made {
            self.depth[m.tet as usize] = parents.depths[m.parent].saturating_add(1);
        }
        tracing::debug!(
            split = plan.tets.len(),
            pieces = piece_count,
            nodes = plan.edges.len(),
            snapped = out.snapped.len(),
            "tets split"
        );
        Ok(())
    }

    /// The plan's new nodes, one per split edge and then one per tip point, each copied from
    /// a free node it lies between (so a pinned one does not pin it), then interpolated:
    /// edge nodes as `a + (b − a) s` in `f32`, tip points as the weighted sum in `f64`.
    /// Returns the first new node and the existing nodes each lies between.
    fn add_split_nodes(
        &mut self,
        body: &mut SoftBody,
        plan: &SplitPlan,
    ) -> Result<(u32, Vec<[u32; 3]>), SurgeryError> {
        let w = body.inverse_masses();
        let free_of = |nodes: &[u32]| {
            nodes
                .iter()
                .copied()
                .find(|&v| w[v as usize] > 0.0)
                .unwrap_or(nodes[0])
        };
        let sources: Vec<u32> = plan
            .edges
            .iter()
            .map(|e| free_of(&e.ends))
            .chain(plan.tips.iter().map(|t| free_of(&t.point.nodes)))
            .collect();
        let first = body.duplicate_nodes(&sources)?;
        // Each new node as a weighted sum of existing nodes.
        let weighted: Vec<([u32; 3], [f64; 3])> = plan
            .edges
            .iter()
            .map(|e| ([e.ends[0], e.ends[1], e.ends[1]], [1.0 - e.s, e.s, 0.0]))
            .chain(plan.tips.iter().map(|t| (t.point.nodes, t.point.weights)))
            .collect();
        for (k, (nodes, weights)) in weighted.iter().enumerate() {
            let v = first + k as u32;
            let sum = |field: &[glam::Vec3A]| {
                if k < plan.edges.len() {
                    let (a, b) = (field[nodes[0] as usize], field[nodes[1] as usize]);
                    return Vec3::from(a + (b - a) * weights[1] as f32);
                }
                let mut acc = DVec3::ZERO;
                for (&u, &wu) in nodes.iter().zip(weights) {
                    acc += field[u as usize].as_dvec3() * wu;
                }
                acc.as_vec3()
            };
            let (x, p, vel) = (
                sum(body.positions()),
                sum(body.previous_positions()),
                sum(body.velocities()),
            );
            body.set_node_state(v, x, p, vel)?;
            body.set_rest_position(v, plan.new_rest[k].as_vec3())?;
            self.rest.push(plan.new_rest[k]);
            self.origin.push(v);
            let reach = nodes
                .iter()
                .map(|&u| self.node_reach[u as usize])
                .fold(0.0f32, f32::max);
            self.node_reach.push(reach);
            self.node_tets.push(Vec::new());
        }
        Ok((first, weighted.into_iter().map(|w| w.0).collect()))
    }

    /// The pieces (`pieces`, the plan's with the new nodes numbered): the record of each split
    /// tet keeps its first piece, the others are appended (rest shapes from the rest
    /// positions); the per-tet state grows with them, and node → tets follows.
    fn place_pieces(
        &mut self,
        body: &mut SoftBody,
        plan: &SplitPlan,
        parents: &Parents,
        pieces: &[[u32; 4]],
        out: &mut SplitOutcome,
    ) -> Result<Vec<Piece>, SurgeryError> {
        out.first_tet = body.tets().len() as u32;
        let mut made: Vec<Piece> = Vec::with_capacity(pieces.len());
        for (k, split) in plan.tets.iter().enumerate() {
            let t = split.tet;
            for (i, p) in pieces[split.pieces.clone()].iter().enumerate() {
                let rest = p.map(|v| self.rest[v as usize]);
                let tet = if i == 0 {
                    body.reshape_tet(t as usize, *p, rest)?;
                    t
                } else {
                    body.add_tet(t as usize, *p, rest)? as u32
                };
                made.push(Piece { tet, parent: k });
            }
            out.split.push(t);
        }
        out.end_tet = body.tets().len() as u32;
        let added = (out.end_tet - out.first_tet) as usize;
        self.neighbours
            .extend(std::iter::repeat_n([NO_TET; 4], added));
        self.scratch.tet_mark.extend(std::iter::repeat_n(0, added));
        for m in &made {
            if m.tet >= out.first_tet {
                let c = self.tet_component[plan.tets[m.parent].tet as usize];
                self.tet_component.push(c);
            }
        }
        for (k, split) in plan.tets.iter().enumerate() {
            for &v in &parents.tets[k] {
                self.node_tets[v as usize].retain(|u| *u != split.tet);
            }
        }
        for m in &made {
            for &v in &body.tets()[m.tet as usize] {
                self.node_tets[v as usize].push(m.tet);
            }
        }
        Ok(made)
    }

    /// Adjacency of the pieces: pieces of one tet, or of two tets that were neighbours,
    /// sharing a face; whole neighbours across an unsplit face of a split tet.
    fn link_pieces(
        &mut self,
        body: &SoftBody,
        plan: &SplitPlan,
        parents: &Parents,
        made: &[Piece],
    ) {
        // Faces not matched yet, by sorted nodes.
        let mut faces: HashMap<[u32; 3], HalfFace> = HashMap::default();
        let mut link = |s: &mut Self, key: [u32; 3], me: HalfFace| match faces.remove(&key) {
            Some(other) => {
                if other.parent == me.parent || parents.were_neighbours(me.parent, other.parent) {
                    s.neighbours[me.tet as usize][me.face as usize] = other.tet;
                    s.neighbours[other.tet as usize][other.face as usize] = me.tet;
                }
            }
            None => {
                faces.insert(key, me);
            }
        };
        for m in made {
            self.neighbours[m.tet as usize] = [NO_TET; 4];
            let tet = body.tets()[m.tet as usize];
            for j in 0..4 {
                let mut key = face_nodes(&tet, j);
                key.sort_unstable();
                link(
                    self,
                    key,
                    HalfFace {
                        tet: m.tet,
                        face: j as u8,
                        parent: plan.tets[m.parent].tet,
                    },
                );
            }
        }
        for (k, nb) in parents.neighbours.iter().enumerate() {
            for &u in nb {
                if u == NO_TET || parents.index.contains_key(&u) {
                    continue;
                }
                let tet = body.tets()[u as usize];
                for j in 0..4 {
                    if self.neighbours[u as usize][j] == plan.tets[k].tet {
                        self.neighbours[u as usize][j] = NO_TET;
                        let mut key = face_nodes(&tet, j);
                        key.sort_unstable();
                        link(
                            self,
                            key,
                            HalfFace {
                                tet: u,
                                face: j as u8,
                                parent: u,
                            },
                        );
                    }
                }
            }
        }
    }

    /// Cut walls and the surface carried onto the pieces: a piece's face on a boundary face of
    /// its parent is a wall where the parent's was, and the parent's boundary faces in more
    /// than one piece are reported as split triangles. Faces glued earlier at a split tet
    /// are forgotten (their tets changed). `supports[k]`: the nodes new node `first + k` lies
    /// between.
    #[allow(clippy::too_many_arguments)]
    fn carry_boundary(
        &mut self,
        body: &SoftBody,
        plan: &SplitPlan,
        parents: &Parents,
        made: &[Piece],
        first: u32,
        supports: &[[u32; 3]],
        out: &mut SplitOutcome,
    ) {
        // The existing nodes a new node lies between (on their edge or triangle).
        let support_of =
            |v: u32| -> Option<[u32; 3]> { (v >= first).then(|| supports[(v - first) as usize]) };
        // Which face of its parent a piece's face lies on.
        let on_parent_face = |parent: [u32; 4], f: [u32; 3]| -> Option<usize> {
            let mut support = [false; 4];
            for v in f {
                let ends = support_of(v).unwrap_or([v, v, v]);
                for e in ends {
                    let i = parent.iter().position(|&p| p == e)?;
                    support[i] = true;
                }
            }
            let missing: Vec<usize> = (0..4).filter(|&i| !support[i]).collect();
            (missing.len() == 1).then(|| missing[0])
        };
        // The split tets' wall bits go before their records (now their first pieces) get
        // their pieces' bits.
        self.wall.resize(body.tets().len(), 0);
        if parents.walls.iter().any(|&b| b != 0) {
            for split in &plan.tets {
                self.wall[split.tet as usize] = 0;
            }
            let wall = &self.wall;
            self.cut_faces
                .retain(|&(t, j)| wall[t as usize] >> j & 1 == 1);
        }
        let mut surface: HashMap<(usize, usize), Vec<[u32; 3]>> = HashMap::default();
        for m in made {
            let (idx, k) = (m.tet, m.parent);
            let tet = body.tets()[idx as usize];
            for j in 0..4 {
                if self.neighbours[idx as usize][j] != NO_TET {
                    continue;
                }
                let f = face_nodes(&tet, j);
                if let Some(pj) = on_parent_face(parents.tets[k], f) {
                    if parents.neighbours[k][pj] == NO_TET {
                        if parents.walls[k] >> pj & 1 == 1 {
                            self.cut_faces.push((idx, j as u8));
                            self.wall[idx as usize] |= 1 << j;
                        }
                        surface.entry((k, pj)).or_default().push(f);
                    }
                }
            }
        }
        let mut keys: Vec<(usize, usize)> = surface.keys().copied().collect();
        keys.sort_unstable();
        for key in keys {
            if let Some(p) = surface.remove(&key) {
                if p.len() > 1 {
                    out.surface.push(SplitTriangle {
                        original: face_nodes(&parents.tets[key.0], key.1),
                        pieces: p,
                    });
                }
            }
        }
        let split_set = |t: u32| parents.index.contains_key(&t);
        self.pending.retain(|p| !split_set(p.t) && !split_set(p.u));
    }

    /// Distance constraints of the pieces: a split edge's constraint moves onto its first
    /// half, and every piece edge without one gets one (its parent's template, rest length
    /// from the rest positions).
    fn constrain_pieces(
        &mut self,
        body: &mut SoftBody,
        plan: &SplitPlan,
        parents: &Parents,
        made: &[Piece],
        first: u32,
    ) -> Result<(), SurgeryError> {
        for (k, e) in plan.edges.iter().enumerate() {
            let (e, m) = (e.ends, first + k as u32);
            if let Some(c) = self.edge_constraint.remove(&e) {
                let l = self.rest[e[0] as usize].distance(self.rest[m as usize]);
                body.reset_distance_constraint(c as usize, [e[0], m], l as f32)?;
                self.edge_constraint.insert(sorted2(e[0], m), c);
            }
        }
        for m in made {
            let Some(record) = parents.templates[m.parent] else {
                continue;
            };
            let tet = body.tets()[m.tet as usize];
            for a in 0..4 {
                for b in a + 1..4 {
                    let e = sorted2(tet[a], tet[b]);
                    if self.edge_constraint.contains_key(&e) {
                        continue;
                    }
                    let l = self.rest[e[0] as usize].distance(self.rest[e[1] as usize]);
                    let c = body.add_distance_constraint(DistanceConstraint {
                        nodes: e,
                        rest_length: l as f32,
                        ..record
                    })?;
                    self.edge_constraint.insert(e, c as u32);
                }
            }
        }
        Ok(())
    }
}
