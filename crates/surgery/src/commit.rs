//! The commit of a cut (step 6 of module `cut`), once the guard holds: split nodes
//! duplicated, tets moved onto the copies, the distance constraints of edges that now exist
//! twice, masses, the opened faces recorded, and pieces detached.

use tissue_pbd::{DistanceConstraint, SoftBody};

use crate::geometry::FxMap as HashMap;
use crate::guard::NodePlan;
use crate::state::{face_nodes, FacePair};
use crate::{Surgery, SurgeryError, SurgeryEvent};

/// What moving the tets onto the copies did.
struct Moved {
    /// The split nodes (sorted).
    split_nodes: Vec<u32>,
    /// Tets moved onto a copy (sorted).
    changed: Vec<u32>,
    /// The tets around the split nodes, with their nodes before the move (sorted).
    region: Vec<(u32, [u32; 4])>,
}

impl Surgery {
    /// Commits the opened `faces` with the nodes' split `plan` (module docs step 6); returns
    /// the events: [`SurgeryEvent::CutAdvanced`] (its new tets, split tets, snapped nodes and
    /// split triangles left to the caller) and one [`SurgeryEvent::PieceDetached`] per piece.
    pub(crate) fn commit(
        &mut self,
        body: &mut SoftBody,
        faces: &[FacePair],
        plan: Vec<NodePlan>,
    ) -> Result<Vec<SurgeryEvent>, SurgeryError> {
        // New nodes: one per extra component of each split node.
        let sources: Vec<u32> = plan
            .iter()
            .flat_map(|p| std::iter::repeat_n(p.node, p.copies() as usize))
            .collect();
        let first = if sources.is_empty() {
            body.node_count() as u32
        } else {
            body.duplicate_nodes(&sources)?
        };
        let next = first + sources.len() as u32;
        let pairs = separated_pairs(&plan);
        let moved = self.move_tets(body, &plan, first)?;
        self.copy_constraints(body, &moved)?;
        self.split_node_masses(body, &moved.split_nodes, first..next)?;
        let opened = self.record_faces(body, faces);
        let mut events = vec![SurgeryEvent::CutAdvanced {
            new_nodes: first..next,
            new_tets: 0..0,
            split_tets: Vec::new(),
            snapped_nodes: Vec::new(),
            split_triangles: Vec::new(),
            changed_tets: moved.changed,
            opened_faces: opened,
        }];
        if next > first {
            self.detached_pieces(body, &pairs, &mut events);
        }
        tracing::debug!(
            faces = faces.len(),
            new_nodes = next - first,
            "cut advanced"
        );
        Ok(events)
    }

    /// Moves each split node's tets of components after the first onto its copies (numbered
    /// from `first` in plan order) in the body and in node → tets; the copies inherit origin,
    /// reach and rest position.
    fn move_tets(
        &mut self,
        body: &mut SoftBody,
        plan: &[NodePlan],
        first: u32,
    ) -> Result<Moved, SurgeryError> {
        let mut new_tets: HashMap<u32, [u32; 4]> = HashMap::default();
        let mut next = first;
        let mut split_nodes: Vec<u32> = Vec::new();
        for p in plan.iter().filter(|p| p.splits()) {
            let v = p.node;
            split_nodes.push(v);
            let base = next;
            next += p.copies();
            let mut keep = Vec::new();
            let mut moved: Vec<Vec<u32>> = vec![Vec::new(); p.copies() as usize];
            for (&t, &c) in p.star.iter().zip(&p.comp) {
                if c == 0 {
                    keep.push(t);
                } else {
                    let nodes = new_tets.entry(t).or_insert(body.tets()[t as usize]);
                    for n in nodes.iter_mut() {
                        if *n == v {
                            *n = base + c - 1;
                        }
                    }
                    moved[c as usize - 1].push(t);
                }
            }
            self.node_tets[v as usize] = keep;
            for m in moved {
                self.node_tets.push(m);
                self.origin.push(self.origin[v as usize]);
                self.node_reach.push(self.node_reach[v as usize]);
                self.rest.push(self.rest[v as usize]);
            }
        }
        let mut changed: Vec<u32> = new_tets.keys().copied().collect();
        changed.sort_unstable();
        let mut region: Vec<(u32, [u32; 4])> = plan
            .iter()
            .filter(|p| p.splits())
            .flat_map(|p| p.star.iter().map(|&t| (t, body.tets()[t as usize])))
            .collect();
        region.sort_unstable();
        region.dedup();
        for &t in &changed {
            body.set_tet_nodes(t as usize, new_tets[&t])?;
        }
        split_nodes.sort_unstable();
        Ok(Moved {
            split_nodes,
            changed,
            region,
        })
    }

    /// Distance constraints after the move: each old edge at a split node maps to the edges
    /// its tets now use; an edge that kept its nodes keeps its constraint, otherwise the
    /// constraint moves onto the first image (unless the old edge is still used) and every
    /// other image gets a copy of it.
    fn copy_constraints(&mut self, body: &mut SoftBody, moved: &Moved) -> Result<(), SurgeryError> {
        let is_split = |v: u32| moved.split_nodes.binary_search(&v).is_ok();
        let mut images: Vec<([u32; 2], [u32; 2])> = Vec::new();
        let tets_now = body.tets();
        for &(t, o) in &moved.region {
            let n = tets_now[t as usize];
            for a in 0..4 {
                for b in a + 1..4 {
                    if is_split(o[a]) || is_split(o[b]) {
                        let oe = [o[a].min(o[b]), o[a].max(o[b])];
                        let ne = [n[a].min(n[b]), n[a].max(n[b])];
                        images.push((oe, ne));
                    }
                }
            }
        }
        images.sort_unstable();
        images.dedup();
        for group in images.chunk_by(|x, y| x.0 == y.0) {
            let oe = group[0].0;
            if group.len() == 1 && group[0].1 == oe {
                // The edge kept its nodes: its constraint stays as it is.
                continue;
            }
            let Some(&c) = self.edge_constraint.get(&oe) else {
                continue;
            };
            let group: Vec<[u32; 2]> = group.iter().map(|p| p.1).collect();
            let record: DistanceConstraint = body.distance_constraints()[c as usize];
            let mut rest = group.as_slice();
            if !group.contains(&oe) {
                body.set_distance_nodes(c as usize, group[0])?;
                self.edge_constraint.remove(&oe);
                self.edge_constraint.insert(group[0], c);
                rest = &group[1..];
            }
            for &ne in rest {
                if ne == oe || self.edge_constraint.contains_key(&ne) {
                    continue;
                }
                let id = body.add_distance_constraint(DistanceConstraint {
                    nodes: ne,
                    ..record
                })?;
                self.edge_constraint.insert(ne, id as u32);
            }
        }
        Ok(())
    }

    /// Masses of the split nodes and their copies `copies`, from their tets' rest volumes
    /// (eq. (1)).
    fn split_node_masses(
        &self,
        body: &mut SoftBody,
        split_nodes: &[u32],
        copies: std::ops::Range<u32>,
    ) -> Result<(), SurgeryError> {
        let rest = body.tet_rest_volumes();
        let density = body.density();
        let mut masses = Vec::new();
        for v in split_nodes.iter().copied().chain(copies) {
            let m: f64 = self.node_tets[v as usize]
                .iter()
                .map(|&t| density as f64 * rest[t as usize] as f64 / 4.0)
                .sum();
            masses.push((v, m as f32));
        }
        for (v, m) in masses {
            body.set_node_mass(v, m)?;
        }
        Ok(())
    }

    /// Records the opened `faces` as cut walls (both sides); returns their triangles.
    fn record_faces(&mut self, body: &SoftBody, faces: &[FacePair]) -> Vec<[u32; 3]> {
        for f in faces {
            self.cut_faces.push((f.t, f.j));
            self.cut_faces.push((f.u, f.k));
            self.wall[f.t as usize] |= 1 << f.j;
            self.wall[f.u as usize] |= 1 << f.k;
        }
        faces
            .iter()
            .flat_map(|f| {
                [
                    face_nodes(&body.tets()[f.t as usize], f.j as usize),
                    face_nodes(&body.tets()[f.u as usize], f.k as usize),
                ]
            })
            .collect()
    }

    /// The pieces the cut detached, if any (`pairs`: see [`separated_pairs`]): relabelled and
    /// reported as [`SurgeryEvent::PieceDetached`] events.
    fn detached_pieces(
        &mut self,
        body: &SoftBody,
        pairs: &[(u32, u32)],
        events: &mut Vec<SurgeryEvent>,
    ) {
        let pieces = if self.still_connected(body, pairs) {
            Vec::new()
        } else {
            self.relabel_pieces(body)
        };
        for piece in pieces {
            let component = self.tet_component[piece[0] as usize];
            let volume = piece
                .iter()
                .map(|&t| body.tet_rest_volumes()[t as usize] as f64)
                .sum();
            let mut nodes: Vec<u32> = piece
                .iter()
                .flat_map(|&t| body.tets()[t as usize])
                .collect();
            nodes.sort_unstable();
            nodes.dedup();
            events.push(SurgeryEvent::PieceDetached {
                component,
                tets: piece,
                nodes,
                rest_volume: volume,
            });
        }
    }

    /// Whether every node this cut split still holds its groups of tets together: for each pair
    /// of tets that shared a split node (one from the group that kept it, one from each group
    /// that got a copy), two searches through shared nodes, one from each, taking a tet in turn,
    /// until they meet (a pair one earlier search found together is skipped). `false` as soon as
    /// one search runs out first: a piece may have come apart. Costs about the way around the
    /// cut's front, so an incision stays cheap.
    fn still_connected(&mut self, body: &SoftBody, pairs: &[(u32, u32)]) -> bool {
        let tets = body.tets();
        // Per tet, in scratch arrays stamped per call: the search that found it (`found`:
        // `call + search`), and the side of the current search that reached it (`mark`:
        // `base + side`, `base` fresh and even per search; older values are stale).
        let mut found = std::mem::take(&mut self.scratch.found_by);
        let mut mark = std::mem::take(&mut self.scratch.search_side);
        found.resize(tets.len(), 0);
        mark.resize(tets.len(), 0);
        if self.scratch.search_stamp > u32::MAX - 4 * (pairs.len() as u32 + 1) {
            self.scratch.search_stamp = 0;
            found.fill(0);
            mark.fill(0);
        }
        let call = self.scratch.search_stamp + 1;
        self.scratch.search_stamp += pairs.len() as u32 + 1;
        let mut connected = true;
        for (search, &(a, b)) in pairs.iter().enumerate() {
            let id = call + search as u32;
            let found_by = |t: u32| {
                let f = found[t as usize];
                (f >= call).then_some(f)
            };
            if found_by(a).is_some_and(|s| found_by(b) == Some(s)) {
                continue;
            }
            self.scratch.search_stamp += 2;
            let base = self.scratch.search_stamp & !1;
            let mut side: [Vec<u32>; 2] = [vec![a], vec![b]];
            let mut head = [0usize; 2];
            mark[a as usize] = base;
            mark[b as usize] = base + 1;
            let met = 'search: loop {
                for s in 0..2 {
                    let Some(&t) = side[s].get(head[s]) else {
                        break 'search false;
                    };
                    head[s] += 1;
                    for &v in &tets[t as usize] {
                        for &u in &self.node_tets[v as usize] {
                            let m = mark[u as usize];
                            if m < base {
                                mark[u as usize] = base + s as u32;
                                side[s].push(u);
                            } else if m != base + s as u32 {
                                break 'search true;
                            }
                        }
                    }
                }
            };
            if !met {
                connected = false;
                break;
            }
            for &t in side.iter().flatten() {
                found[t as usize] = id;
            }
        }
        self.scratch.found_by = found;
        self.scratch.search_side = mark;
        connected
    }
}

/// One tet of the group that keeps each split node and one of each group with a copy: node
/// splits are the only way pieces come apart, so the cut detached nothing when every pair is
/// still connected.
fn separated_pairs(plan: &[NodePlan]) -> Vec<(u32, u32)> {
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for p in plan {
        for c in 1..p.count {
            let first_of = |k: u32| p.star.iter().zip(&p.comp).find(|e| *e.1 == k).map(|e| *e.0);
            if let (Some(a), Some(b)) = (first_of(0), first_of(c)) {
                pairs.push((a, b));
            }
        }
    }
    pairs
}
