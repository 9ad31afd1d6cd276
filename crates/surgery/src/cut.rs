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
//! 5. Before anything is committed, the boundary around the touched nodes is checked (module
//!    `guard`): an edge used by more or fewer than two boundary faces, or a vertex whose
//!    boundary faces do not make one fan (a pinch at the cut's front), has its newly cut faces
//!    glued back, and the check repeats. So the surface stays manifold and consistently
//!    oriented.
//! 6. Commit (module `commit`): nodes duplicated, tets moved onto them (rest values kept),
//!    every edge that now exists twice gets a second distance constraint with the same rest
//!    length, masses of the touched nodes rebuilt from their tets (eq. (1)), pieces recounted.

use crate::geometry::FxMap as HashMap;

use glam::{DVec3, Vec3};
use tissue_mesh::NO_TET;
use tissue_pbd::{Pose, SoftBody, Tool, ToolShape};

use crate::split::CutPlane;
use crate::state::FacePair;
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

    /// The face separation of a cut (steps 3–6 of the module docs), after the split: the
    /// faces the sweep crossed and those glued earlier near it are opened, crumbs glued back
    /// ([`Surgery::glue_crumbs`]), the manifold guard run (module `guard`), and the rest
    /// committed (module `commit`).
    fn open_faces(
        &mut self,
        body: &mut SoftBody,
        plane: &CutPlane<'_>,
        front: &[u32],
        candidates: &[u32],
    ) -> Result<Vec<SurgeryEvent>, SurgeryError> {
        let mut faces = self.crossed_faces(body, plane, front, candidates);
        self.retry_pending(&mut faces);
        if faces.is_empty() {
            return Ok(Vec::new());
        }
        for f in &faces {
            self.neighbours[f.t as usize][f.j as usize] = NO_TET;
            self.neighbours[f.u as usize][f.k as usize] = NO_TET;
        }
        self.glue_crumbs(body, plane, &mut faces);
        if faces.is_empty() {
            return Ok(Vec::new());
        }
        let Some(plan) = self.guard_manifold(body, &mut faces) else {
            return Ok(Vec::new());
        };
        self.commit(body, &faces, plan)
    }

    /// Faces the blade crossed before but that had to stay glued (at the cut's front then),
    /// retried now that the cut may have moved on: those at a tet near this sweep (marked by
    /// [`Surgery::crossed_faces`]) join `faces` unless already there; the others wait for a
    /// blade nearby. Faces no longer glued (opened since) are forgotten.
    fn retry_pending(&mut self, faces: &mut Vec<FacePair>) {
        let near = self.scratch.stamp;
        let mut far = Vec::new();
        for p in std::mem::take(&mut self.pending) {
            let (t, j, u) = (p.t, p.j, p.u);
            if self.scratch.tet_mark[t as usize] != near
                && self.scratch.tet_mark[u as usize] != near
            {
                if self.neighbours[t as usize][j as usize] == u {
                    far.push(p);
                }
                continue;
            }
            if self.neighbours[t as usize][j as usize] == u
                && !faces
                    .iter()
                    .any(|f| (f.t == t && f.j == j) || (f.u == t && f.k == j))
            {
                faces.push(p);
            }
        }
        self.pending = far;
    }

    /// Crumbs: a group of fewer than [`MIN_PIECE`] tets that the new `faces` (opened in
    /// `neighbours`) would enclose is a staircase artefact (or a sliver between two cuts); its
    /// faces are glued back and removed from `faces`. With splits, a crumb whose new faces lead
    /// to both sides of the blade's plane (a slab between an earlier wall and this one, on a
    /// body that moved between the sweeps) stays attached to one side only — the side its
    /// centroid lies on — so that it does not bridge the cut.
    fn glue_crumbs(&mut self, body: &SoftBody, plane: &CutPlane<'_>, faces: &mut Vec<FacePair>) {
        let crumbs = self.find_crumbs(body, faces);
        if crumbs.is_empty() {
            return;
        }
        let stamp = self.scratch.stamp;
        let side = tet_sides(body, plane);
        // Tet → its crumb.
        let mut crumb_of: HashMap<u32, usize> = HashMap::default();
        for (c, group) in crumbs.iter().enumerate() {
            for &t in group {
                crumb_of.insert(t, c);
            }
        }
        let crumb_side = self.crumb_sides(body, &crumbs, &crumb_of, faces, &side);
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
    }

    /// The crumbs at the new `faces` ([`Surgery::small_group`] from each of their tets), their
    /// tets marked in `tet_mark` with a fresh stamp.
    fn find_crumbs(&mut self, body: &SoftBody, faces: &[FacePair]) -> Vec<Vec<u32>> {
        let mut crumbs: Vec<Vec<u32>> = Vec::new();
        let stamp = self.scratch.next_stamp();
        let big = self.next_group_stamp();
        for f in faces {
            for t in [f.t, f.u] {
                if self.scratch.tet_mark[t as usize] != stamp {
                    if let Some(group) = self.small_group(body, t, big) {
                        for &g in &group {
                            self.scratch.tet_mark[g as usize] = stamp;
                        }
                        crumbs.push(group);
                    }
                }
            }
        }
        crumbs
    }

    /// Each crumb's side: where its rest-volume-weighted centroid lies (`side`: a tet's
    /// signed distance from the plane); `None` keeps all of its faces glued (face separation,
    /// or every neighbour across its new faces on one side).
    fn crumb_sides(
        &self,
        body: &SoftBody,
        crumbs: &[Vec<u32>],
        crumb_of: &HashMap<u32, usize>,
        faces: &[FacePair],
        side: &impl Fn(u32) -> f64,
    ) -> Vec<Option<bool>> {
        let rest = body.tet_rest_volumes();
        crumbs
            .iter()
            .enumerate()
            .map(|(c, group)| {
                if !self.settings.split_tets {
                    return None;
                }
                let mut outer = [false; 2];
                for f in faces {
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
            .collect()
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
    ) -> Vec<FacePair> {
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
                if u == NO_TET
                    || (u < t && self.scratch.tet_mark[u as usize] == stamp)
                    || in_front(u)
                {
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
                        out.push(FacePair {
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
