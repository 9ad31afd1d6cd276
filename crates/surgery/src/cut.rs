//! The scalpel cut: after the split (module `split`), tets separated along the faces the
//! blade's swept surface crosses.
//!
//! 1. The blade's cut surface for one step is the blade triangle at both poses plus the
//!    surfaces swept by its three edges, projected onto the blade's plane at the end pose
//!    (eight coplanar triangles, world space, current positions): the area the blade swept in
//!    its own plane.
//! 2. The split snaps nodes onto that plane and splits the crossed tets (module `split`).
//! 3. A face shared by tets `t` and `u` is cut when the segment between their centroids crosses
//!    that surface, unless `t` or `u` is at the cut's front (crossed only partly). After the
//!    split these are faces on the blade's plane; where a split was refused, faces of the
//!    whole tets (within one tet of the blade).
//! 4. Each node on a newly cut face is split by the face-connected components of its tets: the
//!    first component keeps the node, each other one gets a copy (appended to the body).
//! 5. Before anything is committed, the boundary around the touched nodes is checked: an edge
//!    used by more or fewer than two boundary faces, or a vertex whose boundary faces do not
//!    make one fan (a pinch at the cut's front), has its newly cut faces glued back, and the
//!    check repeats. So the surface stays manifold and consistently oriented.
//! 6. Commit: nodes duplicated, tets moved onto them (rest values kept), every edge that now
//!    exists twice gets a second distance constraint with the same rest length, masses of the
//!    touched nodes rebuilt from their tets (eq. (1)), pieces recounted.

use crate::geometry::FxMap as HashMap;

use glam::{DVec3, Vec3};
use tissue_mesh::NO_TET;
use tissue_pbd::{DistanceConstraint, Pose, SoftBody, Tool, ToolShape};

use crate::split::CutPlane;
use crate::state::{face_nodes, pinched_vertices};
use crate::{Surgery, SurgeryError, SurgeryEvent};

/// A blade's sweep over one step, in world coordinates: its corners at the start and the end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BladeSweep {
    /// Corners `a b c` at the start of the step.
    pub from: [Vec3; 3],
    /// Corners at the end.
    pub to: [Vec3; 3],
}

impl BladeSweep {
    /// The sweep of a [`ToolShape::Blade`] from one pose to another.
    ///
    /// # Errors
    /// [`SurgeryError::InvalidTool`] for a capsule or a non-finite pose.
    pub fn new(shape: &ToolShape, from: &Pose, to: &Pose) -> Result<Self, SurgeryError> {
        let ToolShape::Blade { a, b, c, .. } = *shape else {
            return Err(SurgeryError::InvalidTool {
                reason: "a cut needs a ToolShape::Blade (the scalpel)",
            });
        };
        let s = Self {
            from: [a, b, c].map(|p| from.transform_point(p)),
            to: [a, b, c].map(|p| to.transform_point(p)),
        };
        if s.from.iter().chain(&s.to).all(|p| p.is_finite()) {
            Ok(s)
        } else {
            Err(SurgeryError::InvalidTool {
                reason: "the blade's poses must be finite",
            })
        }
    }

    /// The sweep of the last step of a blade tool of a body ([`Tool::last_sweep`]).
    ///
    /// # Errors
    /// As [`BladeSweep::new`].
    pub fn from_tool(tool: &Tool) -> Result<Self, SurgeryError> {
        let (from, to) = tool.last_sweep();
        Self::new(tool.shape(), &from, &to)
    }

    /// The eight triangles of the cut surface (see the module docs): the blade at the end pose,
    /// and the blade at the start pose and the surfaces its edges swept, all projected onto the
    /// end pose's plane. Only the blade's motion within its own plane cuts; motion along its
    /// normal pushes tissue (a contact tool's job) and cuts nothing, so a blade moved flat-on
    /// does not chop out a slab.
    pub(crate) fn triangles(&self) -> [[DVec3; 3]; 8] {
        let t = self.to.map(|p| p.as_dvec3());
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        let f = self.from.map(|p| {
            let p = p.as_dvec3();
            p - n * n.dot(p - t[0])
        });
        let mut out = [[DVec3::ZERO; 3]; 8];
        out[0] = f;
        out[1] = t;
        for k in 0..3 {
            let (i, j) = (k, (k + 1) % 3);
            out[2 + 2 * k] = [f[i], f[j], t[j]];
            out[3 + 2 * k] = [f[i], t[j], t[i]];
        }
        out
    }
}

/// Smallest piece (tets) a cut may detach: smaller face-connected groups that new faces would
/// enclose stay glued, and so do groups of less rest volume than this many median tets of the
/// input (a slab between two nearly parallel walls, made of pieces of splits).
pub const MIN_PIECE: usize = 16;

/// A face opened by this cut: tet `t` face `j` against tet `u` face `k`.
#[derive(Debug, Clone, Copy)]
struct NewFace {
    t: u32,
    j: u8,
    u: u32,
    k: u8,
}

impl Surgery {
    /// Cuts `body` along a blade's sweep (see the crate docs), returning the events:
    /// [`SurgeryEvent::CutAdvanced`] when tets were split, nodes snapped or faces opened, then one
    /// [`SurgeryEvent::PieceDetached`] per new piece. A sweep that crosses no face returns no
    /// event. Call it after each step with the blade's sweep of that step (e.g.
    /// [`BladeSweep::from_tool`]) to cut over many steps.
    ///
    /// # Errors
    /// [`SurgeryError::BodyMismatch`] when `body` is not this state's body; [`SurgeryError::Body`]
    /// should an edit be refused (the body is then left as it was before the failing edit).
    pub fn cut(
        &mut self,
        body: &mut SoftBody,
        sweep: &BladeSweep,
    ) -> Result<Vec<SurgeryEvent>, SurgeryError> {
        let _span = tracing::debug_span!("cut").entered();
        self.check_body(body)?;
        let surface = sweep.triangles();
        let origin = surface[1][0];
        let normal = (surface[1][1] - origin)
            .cross(surface[1][2] - origin)
            .normalize_or_zero();
        let plane = CutPlane {
            origin,
            normal,
            surface: &surface,
        };
        let mut candidates = if normal == DVec3::ZERO || !self.settings.split_tets {
            Vec::new()
        } else {
            self.straddling_tets(body, &plane)
        };
        let split = self.split_along(body, &plane, &candidates)?;
        // The faces to open are faces of the straddling tets or of the pieces.
        candidates.extend(split.first_tet..split.end_tet);
        if !self.settings.split_tets && normal != DVec3::ZERO {
            candidates = self.straddling_tets(body, &plane);
        }
        let mut events = self.open_faces(body, &plane, &split.front, &candidates)?;
        let geometric = !split.split.is_empty() || !split.snapped.is_empty();
        match events.first_mut() {
            Some(SurgeryEvent::CutAdvanced {
                new_nodes,
                new_tets,
                split_tets,
                snapped_nodes,
                split_triangles,
                ..
            }) => {
                new_nodes.start = split.first_node;
                *new_tets = split.first_tet..split.end_tet;
                *split_tets = split.split;
                *snapped_nodes = split.snapped;
                *split_triangles = split.surface;
            }
            _ if geometric => events.insert(
                0,
                SurgeryEvent::CutAdvanced {
                    new_nodes: split.first_node..split.end_node,
                    new_tets: split.first_tet..split.end_tet,
                    split_tets: split.split,
                    snapped_nodes: split.snapped,
                    split_triangles: split.surface,
                    changed_tets: Vec::new(),
                    opened_faces: Vec::new(),
                },
            ),
            _ => {}
        }
        Ok(events)
    }

    /// The face separation of a cut (steps 2–5 of the module docs), after the split.
    fn open_faces(
        &mut self,
        body: &mut SoftBody,
        plane: &CutPlane<'_>,
        front: &[u32],
        candidates: &[u32],
    ) -> Result<Vec<SurgeryEvent>, SurgeryError> {
        let mut faces = self.crossed_faces(body, plane, front, candidates);
        // Faces the blade crossed before but that had to stay glued (at the cut's front then):
        // retried now that the cut may have moved on.
        let near = self.scratch.stamp;
        let mut far = Vec::new();
        for [t, j, u, k] in std::mem::take(&mut self.pending) {
            if self.scratch.tet_mark[t as usize] != near && self.scratch.tet_mark[u as usize] != near {
                // Far from this sweep: it waits for a blade nearby.
                if self.neighbours[t as usize][j as usize] == u {
                    far.push([t, j, u, k]);
                }
                continue;
            }
            if self.neighbours[t as usize][j as usize] == u
                && !faces
                    .iter()
                    .any(|f| (f.t == t && f.j as u32 == j) || (f.u == t && f.k as u32 == j))
            {
                faces.push(NewFace {
                    t,
                    j: j as u8,
                    u,
                    k: k as u8,
                });
            }
        }
        self.pending = far;
        if faces.is_empty() {
            return Ok(Vec::new());
        }
        for f in &faces {
            self.neighbours[f.t as usize][f.j as usize] = NO_TET;
            self.neighbours[f.u as usize][f.k as usize] = NO_TET;
        }
        // Crumbs: a group of fewer than MIN_PIECE tets that the new faces would enclose is a
        // staircase artefact (or a sliver between two cuts); it stays attached. With splits, a
        // crumb whose new faces lead to both sides of the blade's plane (a slab between an
        // earlier wall and this one, on a body that moved between the sweeps) stays attached to
        // one side only — the side its centroid lies on — so that it does not bridge the cut.
        let mut crumbs: Vec<Vec<u32>> = Vec::new();
        self.scratch.next_stamp();
        let big = self.next_group_stamp();
        for f in &faces {
            for t in [f.t, f.u] {
                if self.scratch.tet_mark[t as usize] != self.scratch.stamp {
                    if let Some(group) = self.small_group(body, t, big) {
                        for &g in &group {
                            self.scratch.tet_mark[g as usize] = self.scratch.stamp;
                        }
                        crumbs.push(group);
                    }
                }
            }
        }
        if !crumbs.is_empty() {
            let stamp = self.scratch.stamp;
            let side = tet_sides(body, plane);
            // Tet → its crumb.
            let mut crumb_of: HashMap<u32, usize> = HashMap::default();
            for (c, group) in crumbs.iter().enumerate() {
                for &t in group {
                    crumb_of.insert(t, c);
                }
            }
            // Each crumb's side: where its rest-volume-weighted centroid lies; `None` keeps all
            // of its faces glued (face separation, or every neighbour on one side).
            let rest = body.tet_rest_volumes();
            let crumb_side: Vec<Option<bool>> = crumbs
                .iter()
                .enumerate()
                .map(|(c, group)| {
                    if !self.settings.split_tets {
                        return None;
                    }
                    let mut outer = [false; 2];
                    for f in &faces {
                        for (a, b) in [(f.t, f.u), (f.u, f.t)] {
                            if crumb_of.get(&a) == Some(&c) && crumb_of.get(&b) != Some(&c) {
                                outer[usize::from(side(b) > 0.0)] = true;
                            }
                        }
                    }
                    if !(outer[0] && outer[1]) {
                        return None;
                    }
                    let d: f64 = group
                        .iter()
                        .map(|&t| rest[t as usize] as f64 * side(t))
                        .sum();
                    Some(d > 0.0)
                })
                .collect();
            let marks = std::mem::take(&mut self.scratch.tet_mark);
            faces.retain(|f| {
                let glue = if marks[f.t as usize] != stamp && marks[f.u as usize] != stamp {
                    false
                } else {
                    match (crumb_of.get(&f.t), crumb_of.get(&f.u)) {
                        (Some(&c), None) => crumb_side[c].is_none_or(|s| (side(f.u) > 0.0) == s),
                        (None, Some(&c)) => crumb_side[c].is_none_or(|s| (side(f.t) > 0.0) == s),
                        _ => true,
                    }
                };
                if glue {
                    self.neighbours[f.t as usize][f.j as usize] = f.u;
                    self.neighbours[f.u as usize][f.k as usize] = f.t;
                }
                !glue
            });
            self.scratch.tet_mark = marks;
            if faces.is_empty() {
                return Ok(Vec::new());
            }
        }
        // Glue back what would leave the surface non-manifold, until nothing does.
        // Gluing a face back changes the plan of its three nodes only: the plan is updated, not
        // rebuilt, between rounds.
        let mut plan = self.plan_split(body, &faces);
        let mut changed: Option<Vec<u32>> = None;
        let split = loop {
            let mut entry = std::mem::take(&mut self.scratch.plan_entry);
            entry.resize(body.node_count(), u32::MAX);
            for (i, p) in plan.iter().enumerate() {
                entry[p.0 as usize] = i as u32;
            }
            let mut seen = std::mem::take(&mut self.scratch.tet_seen);
            let bad = self.defects(body, &faces, &plan, &entry, &mut seen, changed.as_deref());
            self.scratch.tet_seen = seen;
            for p in &plan {
                entry[p.0 as usize] = u32::MAX;
            }
            self.scratch.plan_entry = entry;
            if bad.is_empty() {
                break plan;
            }
            let mut keep = Vec::with_capacity(faces.len());
            let mut touched: Vec<u32> = Vec::new();
            for (i, f) in faces.iter().enumerate() {
                if bad.contains(&i) {
                    self.neighbours[f.t as usize][f.j as usize] = f.u;
                    self.neighbours[f.u as usize][f.k as usize] = f.t;
                    self.pending.push([f.t, f.j as u32, f.u, f.k as u32]);
                    touched.extend(face_nodes(&body.tets()[f.t as usize], f.j as usize));
                } else {
                    keep.push(*f);
                }
            }
            faces = keep;
            if faces.is_empty() {
                return Ok(Vec::new());
            }
            let mut on_faces: Vec<u32> = faces
                .iter()
                .flat_map(|f| face_nodes(&body.tets()[f.t as usize], f.j as usize))
                .collect();
            on_faces.sort_unstable();
            on_faces.dedup();
            plan.retain(|p| on_faces.binary_search(&p.0).is_ok());
            touched.sort_unstable();
            touched.dedup();
            for &v in &touched {
                if let Ok(i) = plan.binary_search_by_key(&v, |p| p.0) {
                    plan[i] = self.plan_node(body, v);
                }
            }
            changed = Some(touched);
        };
        self.commit(body, &faces, split)
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

    /// The tets face-connected to `t` when they are a crumb: fewer than [`MIN_PIECE`] tets, or
    /// less rest volume than [`MIN_PIECE`] median tets of the input (pieces of splits are
    /// small tets). `None` for a bigger group (the search stops early).
    ///
    /// Tets marked `big` (found in a bigger group by an earlier search of this cut) end the
    /// search at once; a search that finds a bigger group marks every tet it saw `big`.
    fn small_group(&mut self, body: &SoftBody, t: u32, big: u32) -> Option<Vec<u32>> {
        let rest = body.tet_rest_volumes();
        let limit = MIN_PIECE as f64 * self.median_rest_volume;
        let stamp = self.next_group_stamp();
        if self.scratch.group_mark[t as usize] == big {
            return None;
        }
        let mut group = vec![t];
        self.scratch.group_mark[t as usize] = stamp;
        let mut volume = rest[t as usize] as f64;
        let mut i = 0;
        while i < group.len() {
            for &u in &self.neighbours[group[i] as usize] {
                if u == NO_TET || self.scratch.group_mark[u as usize] == stamp {
                    continue;
                }
                volume += rest[u as usize] as f64;
                if self.scratch.group_mark[u as usize] == big
                    || (group.len() + 1 >= MIN_PIECE
                        && (volume >= limit || !self.settings.split_tets))
                    || group.len() >= 64 * MIN_PIECE
                {
                    for &g in &group {
                        self.scratch.group_mark[g as usize] = big;
                    }
                    return None;
                }
                self.scratch.group_mark[u as usize] = stamp;
                group.push(u);
            }
            i += 1;
        }
        Some(group)
    }

    /// A fresh stamp for `group_mark` (sized to the tets).
    fn next_group_stamp(&mut self) -> u32 {
        self.scratch.group_mark.resize(self.neighbours.len(), 0);
        self.scratch.group_stamp = self.scratch.group_stamp.wrapping_add(1).max(1);
        if self.scratch.group_stamp == 1 {
            self.scratch.group_mark.fill(0);
        }
        self.scratch.group_stamp
    }

    /// The tets that straddle the plane of `plane` and meet the box of its polygon (sorted):
    /// nodes near the box first, then their tets. A crossing point lies in such a tet.
    pub(crate) fn straddling_tets(&mut self, body: &SoftBody, plane: &CutPlane<'_>) -> Vec<u32> {
        let x = body.positions();
        let tets = body.tets();
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for tri in plane.surface {
            for p in tri {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        let (origin, normal) = (plane.origin, plane.normal);
        let stamp = self.scratch.next_stamp();
        let mut candidates = Vec::new();
        // Each node's signed distance, once: a tet's straddling test reads four of them.
        let mut side = std::mem::take(&mut self.scratch.side);
        side.clear();
        side.extend(x.iter().map(|p| normal.dot(p.as_dvec3() - origin)));
        // A straddling tet has a node on the plane or on its positive side, within that node's
        // reach of the plane (a tet's nodes lie within their reach of each other): only those
        // nodes' tets are looked at. Their tets are gathered first and their nodes loaded in a
        // loop of independent loads, apart from the tests that branch on them: the body's
        // arrays are out of cache after a step, and the misses then overlap.
        let mut near_tets = std::mem::take(&mut self.scratch.near_tets);
        near_tets.clear();
        for (v, (p, &d)) in x.iter().zip(&side).enumerate() {
            let reach = self.node_reach[v] as f64;
            if !(0.0..=reach).contains(&d) {
                continue;
            }
            let p = p.as_dvec3();
            if p.cmplt(lo - DVec3::splat(reach)).any() || p.cmpgt(hi + DVec3::splat(reach)).any() {
                continue;
            }
            near_tets.extend_from_slice(&self.node_tets[v]);
        }
        let mut near_nodes = std::mem::take(&mut self.scratch.near_nodes);
        near_nodes.clear();
        near_nodes.extend(near_tets.iter().map(|&t| tets[t as usize]));
        for (&t, tet) in near_tets.iter().zip(&near_nodes) {
            let d = tet.map(|i| side[i as usize]);
            if !(d.iter().any(|&d| d >= 0.0) && d.iter().any(|&d| d <= 0.0))
                || self.scratch.tet_mark[t as usize] == stamp
            {
                continue;
            }
            self.scratch.tet_mark[t as usize] = stamp;
            let q = tet.map(|i| x[i as usize].as_dvec3());
            let (tlo, thi) = (
                q[0].min(q[1]).min(q[2].min(q[3])),
                q[0].max(q[1]).max(q[2].max(q[3])),
            );
            if tlo.cmple(hi).all() && thi.cmpge(lo).all() {
                candidates.push(t);
            }
        }
        self.scratch.near_tets = near_tets;
        self.scratch.near_nodes = near_nodes;
        self.scratch.side = side;
        candidates.sort_unstable();
        candidates
    }

    /// Faces between tets whose centroid segment crosses the cut surface, except faces of the
    /// tets in `front` (sorted: crossed only partly by this sweep, see `split`).
    fn crossed_faces(
        &mut self,
        body: &SoftBody,
        plane: &CutPlane<'_>,
        front: &[u32],
        candidates: &[u32],
    ) -> Vec<NewFace> {
        let x = body.positions();
        let tets = body.tets();
        let (origin, normal) = (plane.origin, plane.normal);
        let centroid = |t: u32| -> DVec3 {
            tets[t as usize]
                .iter()
                .map(|&i| x[i as usize].as_dvec3())
                .sum::<DVec3>()
                * 0.25
        };
        // Candidates get a second mark so that each pair of candidates is tested once.
        let stamp = self.scratch.next_stamp();
        for &t in candidates {
            self.scratch.tet_mark[t as usize] = stamp;
        }
        let in_front = |t: u32| front.binary_search(&t).is_ok();
        // All eight triangles lie in the end pose's plane: a centroid segment crosses the cut
        // surface when its ends are on opposite sides and the crossing point lies in one of them.
        let inside = |p: DVec3| plane.contains(p);
        let mut out = Vec::new();
        for &t in candidates {
            if in_front(t) {
                continue;
            }
            let ct = centroid(t);
            let dt = normal.dot(ct - origin);
            for j in 0..4 {
                let u = self.neighbours[t as usize][j];
                if u == NO_TET || (u < t && self.scratch.tet_mark[u as usize] == stamp) || in_front(u) {
                    continue;
                }
                let cu = centroid(u);
                let du = normal.dot(cu - origin);
                if (dt > 0.0) == (du > 0.0) || dt == du {
                    continue;
                }
                let p = ct + (cu - ct) * (dt / (dt - du));
                if inside(p) {
                    if let Some(k) = self.neighbours[u as usize].iter().position(|&w| w == t) {
                        out.push(NewFace {
                            t,
                            j: j as u8,
                            u,
                            k: k as u8,
                        });
                    }
                }
            }
        }
        // A tet whose four faces would all be cut is an island of one side inside the other
        // (the staircase, not the blade, cut it out): it stays with its neighbours.
        let mut count: HashMap<u32, u32> = HashMap::default();
        for f in &out {
            *count.entry(f.t).or_default() += 1;
            *count.entry(f.u).or_default() += 1;
        }
        let open = |t: u32| {
            self.neighbours[t as usize]
                .iter()
                .filter(|&&w| w == NO_TET)
                .count() as u32
        };
        out.retain(|f| count[&f.t] + open(f.t) < 4 && count[&f.u] + open(f.u) < 4);
        out
    }

    /// For each node on a new face: its tets grouped into face-connected components (through
    /// faces containing the node). `(node, tets, component of each tet, component count)`.
    fn plan_split(
        &mut self,
        body: &SoftBody,
        faces: &[NewFace],
    ) -> Vec<(u32, Vec<u32>, Vec<u32>, u32)> {
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

    /// One node's entry of [`Self::plan_split`].
    fn plan_node(&mut self, body: &SoftBody, v: u32) -> (u32, Vec<u32>, Vec<u32>, u32) {
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
        (v, star, comp, count)
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
        faces: &[NewFace],
        plan: &[(u32, Vec<u32>, Vec<u32>, u32)],
        plan_entry: &[u32],
        seen: &mut Vec<bool>,
        changed: Option<&[u32]>,
    ) -> Vec<usize> {
        let tets = body.tets();
        // Tentative labels: the copies of plan entry `i` are numbered from `base[i]`.
        let mut base = Vec::with_capacity(plan.len());
        let mut next = body.node_count() as u32;
        for p in plan {
            base.push(next);
            next += p.3.saturating_sub(1);
        }
        let entry = |v: u32| {
            let i = plan_entry.get(v as usize).copied().unwrap_or(u32::MAX);
            (i != u32::MAX).then_some(i as usize)
        };
        let relabel = |t: u32, v: u32| -> u32 {
            if let Some(i) = entry(v) {
                let (_, star, comp, count) = &plan[i];
                if *count > 1 {
                    if let Ok(s) = star.binary_search(&t) {
                        if comp[s] > 0 {
                            return base[i] + comp[s] - 1;
                        }
                    }
                }
            }
            v
        };
        let original = |label: u32| -> u32 {
            let i = base.partition_point(|&b| b <= label);
            if label < body.node_count() as u32 || i == 0 {
                label
            } else {
                plan[i - 1].0
            }
        };
        let is_touched = |v: u32| entry(v).is_some();
        let in_changed = |v: u32| changed.is_none_or(|c| c.binary_search(&v).is_ok());
        // The vertices to check: the touched ones, or, limited, those on a boundary face of
        // a tet at a changed node.
        let vertices: Option<Vec<u32>> = changed.map(|c| {
            let mut w: Vec<u32> = c.to_vec();
            for &g in c {
                for &t in &self.node_tets[g as usize] {
                    for j in 0..4 {
                        if self.neighbours[t as usize][j] == NO_TET {
                            let f = face_nodes(&tets[t as usize], j);
                            if f.contains(&g) {
                                w.extend(f.iter().copied().filter(|&v| is_touched(v)));
                            }
                        }
                    }
                }
            }
            w.sort_unstable();
            w.dedup();
            w
        });
        let check_vertex = |v: u32| {
            is_touched(v)
                && vertices
                    .as_ref()
                    .is_none_or(|w| w.binary_search(&v).is_ok())
        };
        // The tets whose boundary faces hold every face at those edges and vertices.
        // Each once, in the order found (marked in `seen`, cleared after).
        let mut local: Vec<u32> = Vec::new();
        seen.resize(tets.len(), false);
        let stars: Vec<&[u32]> = match &vertices {
            None => plan.iter().map(|p| p.1.as_slice()).collect(),
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
        // Boundary faces of the local tets, in tentative labels, with the original labels.
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
                let f = orig.map(|v| relabel(t, v));
                for k in 0..3 {
                    let (a, b) = (orig[k], orig[(k + 1) % 3]);
                    if (is_touched(a) || is_touched(b)) && (in_changed(a) || in_changed(b)) {
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
        // Back to the original label: the node itself or the one it copies.
        let mut bad_vertices: Vec<u32> = pinched_vertices(&mut around)
            .into_iter()
            .map(original)
            .collect();
        // One face per defect: the last new face on the bad edge or at the bad vertex (a chord
        // of the crack between two front nodes, or a crack touching the surface at a point).
        let mut out: Vec<usize> = Vec::new();
        let nodes_of: Vec<[u32; 3]> = faces
            .iter()
            .map(|f| face_nodes(&tets[f.t as usize], f.j as usize))
            .collect();
        bad_edges.sort_unstable();
        bad_edges.dedup();
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
        bad_vertices.sort_unstable();
        bad_vertices.dedup();
        for v in &bad_vertices {
            if !out.iter().any(|&i| nodes_of[i].contains(v)) {
                if let Some(i) = (0..faces.len()).rev().find(|&i| nodes_of[i].contains(v)) {
                    out.push(i);
                }
            }
        }
        // A new face none of whose nodes is split would be a zero-width double face: it waits.
        for (i, f) in faces.iter().enumerate() {
            if !out.contains(&i)
                && nodes_of[i].iter().any(|&v| in_changed(v))
                && nodes_of[i]
                    .iter()
                    .all(|&v| relabel(f.t, v) == relabel(f.u, v))
            {
                out.push(i);
            }
        }
        // A defect no new face touches was there before this cut: nothing to glue for it.
        out
    }

    fn commit(
        &mut self,
        body: &mut SoftBody,
        faces: &[NewFace],
        plan: Vec<(u32, Vec<u32>, Vec<u32>, u32)>,
    ) -> Result<Vec<SurgeryEvent>, SurgeryError> {
        // New nodes: one per extra component of each split node.
        let sources: Vec<u32> = plan
            .iter()
            .flat_map(|(v, _, _, count)| std::iter::repeat_n(*v, count.saturating_sub(1) as usize))
            .collect();
        let first = if sources.is_empty() {
            body.node_count() as u32
        } else {
            body.duplicate_nodes(&sources)?
        };
        let mut new_tets: HashMap<u32, [u32; 4]> = HashMap::default();
        // One tet of the group that keeps each split node and one of each group with a copy:
        // node splits are the only way pieces come apart.
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (_, star, comp, count) in &plan {
            for c in 1..*count {
                let first_of = |k: u32| star.iter().zip(comp).find(|e| *e.1 == k).map(|e| *e.0);
                if let (Some(a), Some(b)) = (first_of(0), first_of(c)) {
                    pairs.push((a, b));
                }
            }
        }
        let mut next = first;
        let mut split_nodes: Vec<u32> = Vec::new();
        for (v, star, comp, count) in &plan {
            if *count <= 1 {
                continue;
            }
            split_nodes.push(*v);
            let base = next;
            next += count - 1;
            let mut keep = Vec::new();
            let mut moved: Vec<Vec<u32>> = vec![Vec::new(); *count as usize - 1];
            for (&t, &c) in star.iter().zip(comp) {
                if c == 0 {
                    keep.push(t);
                } else {
                    let nodes = new_tets.entry(t).or_insert(body.tets()[t as usize]);
                    for n in nodes.iter_mut() {
                        if *n == *v {
                            *n = base + c - 1;
                        }
                    }
                    moved[c as usize - 1].push(t);
                }
            }
            self.node_tets[*v as usize] = keep;
            for m in moved {
                self.node_tets.push(m);
                self.origin.push(self.origin[*v as usize]);
                self.node_reach.push(self.node_reach[*v as usize]);
                self.rest.push(self.rest[*v as usize]);
            }
        }
        let mut changed: Vec<u32> = new_tets.keys().copied().collect();
        changed.sort_unstable();
        // The tets around the split nodes, with their nodes before the move.
        let mut region: Vec<(u32, [u32; 4])> = plan
            .iter()
            .filter(|p| p.3 > 1)
            .flat_map(|p| p.1.iter().map(|&t| (t, body.tets()[t as usize])))
            .collect();
        region.sort_unstable();
        region.dedup();
        for &t in &changed {
            body.set_tet_nodes(t as usize, new_tets[&t])?;
        }
        // Distance constraints: each old edge at a split node maps to the edges its tets now use.
        split_nodes.sort_unstable();
        let is_split = |v: u32| split_nodes.binary_search(&v).is_ok();
        let mut images: Vec<([u32; 2], [u32; 2])> = Vec::new();
        let tets_now = body.tets();
        for &(t, o) in &region {
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
        let mut i = 0;
        while i < images.len() {
            let oe = images[i].0;
            let mut j = i;
            while j < images.len() && images[j].0 == oe {
                j += 1;
            }
            let unchanged = j == i + 1 && images[i].1 == oe;
            let group: Vec<[u32; 2]> = images[i..j].iter().map(|p| p.1).collect();
            i = j;
            if unchanged {
                // The edge kept its nodes: its constraint stays as it is.
                continue;
            }
            let Some(&c) = self.edge_constraint.get(&oe) else {
                continue;
            };
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
        // Masses of the split nodes and their copies, from their tets' rest volumes (eq. (1)).
        let rest = body.tet_rest_volumes();
        let density = body.density();
        let mut masses = Vec::new();
        for v in split_nodes.iter().copied().chain(first..next) {
            let m: f64 = self.node_tets[v as usize]
                .iter()
                .map(|&t| density as f64 * rest[t as usize] as f64 / 4.0)
                .sum();
            masses.push((v, m as f32));
        }
        for (v, m) in masses {
            body.set_node_mass(v, m)?;
        }
        for f in faces {
            self.cut_faces.push((f.t, f.j));
            self.cut_faces.push((f.u, f.k));
            self.wall[f.t as usize] |= 1 << f.j;
            self.wall[f.u as usize] |= 1 << f.k;
        }
        let opened: Vec<[u32; 3]> = faces
            .iter()
            .flat_map(|f| {
                [
                    face_nodes(&body.tets()[f.t as usize], f.j as usize),
                    face_nodes(&body.tets()[f.u as usize], f.k as usize),
                ]
            })
            .collect();
        let mut events = vec![SurgeryEvent::CutAdvanced {
            new_nodes: first..next,
            new_tets: 0..0,
            split_tets: Vec::new(),
            snapped_nodes: Vec::new(),
            split_triangles: Vec::new(),
            changed_tets: changed,
            opened_faces: opened,
        }];
        if next > first {
            let pieces = if self.still_connected(body, &pairs) {
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
        tracing::debug!(
            faces = faces.len(),
            new_nodes = next - first,
            "cut advanced"
        );
        Ok(events)
    }
}

/// The signed distance of each tet's current centroid from the plane of `plane` (a closure).
fn tet_sides<'a>(body: &'a SoftBody, plane: &CutPlane<'_>) -> impl Fn(u32) -> f64 + 'a {
    let (origin, normal) = (plane.origin, plane.normal);
    move |t: u32| {
        let x = body.positions();
        let c = body.tets()[t as usize]
            .iter()
            .map(|&i| x[i as usize].as_dvec3())
            .sum::<DVec3>()
            * 0.25;
        normal.dot(c - origin)
    }
}
