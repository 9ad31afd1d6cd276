//! Sutures: the needle's segment crosses the two walls of a wound; the nearest nodes of the two
//! faces it passes between are linked by a distance constraint of (near) zero rest length.

use glam::{DVec3, Vec3};
use tissue_mesh::NO_TET;
use tissue_pbd::{DistanceConstraint, Pose, SoftBody, ToolShape};

use crate::geometry::segment_triangle;
use crate::state::face_nodes;
use crate::{Surgery, SurgeryError, SurgeryEvent, Suture};

/// Where the needle's axis crosses a boundary face: its parameter along the axis, whether it
/// leaves the body there, the face's nodes and the crossing point.
struct Crossing {
    s: f64,
    leaving: bool,
    face: [u32; 3],
    point: DVec3,
}

/// The closest pair of distinct nodes, one from each crossed face, to the two crossings (the
/// faces may share a node at the wound's end).
fn wound_nodes(body: &SoftBody, near: &Crossing, far: &Crossing) -> Option<[u32; 2]> {
    let x = body.positions();
    let dist = |n: u32, at: DVec3| x[n as usize].as_dvec3().distance(at);
    let mut best: Option<(f64, u32, u32)> = None;
    for &a in &near.face {
        for &b in &far.face {
            let d = dist(a, near.point) + dist(b, far.point);
            if a != b && best.is_none_or(|(e, _, _)| d < e) {
                best = Some((d, a, b));
            }
        }
    }
    best.map(|(_, a, b)| [a, b])
}

impl Surgery {
    /// Places a suture where a needle ([`ToolShape::Capsule`] at `pose`, its axis `a → b`) passes
    /// through the body: along the axis, the first boundary face where it leaves the body and
    /// the next one where it enters again are the two sides of the wound; the node of each face
    /// nearest to the crossing is linked, unless the two are already linked (or are the same
    /// node). Returns the event, or `None` when the needle does not bridge a gap.
    ///
    /// # Errors
    /// [`SurgeryError::InvalidTool`] for a blade or a non-finite pose,
    /// [`SurgeryError::BodyMismatch`].
    pub fn suture(
        &mut self,
        body: &mut SoftBody,
        needle: &ToolShape,
        pose: &Pose,
    ) -> Result<Option<SurgeryEvent>, SurgeryError> {
        let _span = tracing::debug_span!("suture").entered();
        self.check_body(body)?;
        let ToolShape::Capsule { a, b, .. } = *needle else {
            return Err(SurgeryError::InvalidTool {
                reason: "a suture needs a ToolShape::Capsule (the needle)",
            });
        };
        let (p, q) = (pose.transform_point(a), pose.transform_point(b));
        if !(p.is_finite() && q.is_finite()) {
            return Err(SurgeryError::InvalidTool {
                reason: "the needle's pose must be finite",
            });
        }
        self.suture_segment(body, p, q)
    }

    /// As [`Surgery::suture`], with the needle's axis given in world coordinates.
    ///
    /// # Errors
    /// [`SurgeryError::BodyMismatch`], [`SurgeryError::InvalidTool`] for non-finite ends.
    pub fn suture_segment(
        &mut self,
        body: &mut SoftBody,
        from: Vec3,
        to: Vec3,
    ) -> Result<Option<SurgeryEvent>, SurgeryError> {
        self.check_body(body)?;
        if !(from.is_finite() && to.is_finite()) {
            return Err(SurgeryError::InvalidTool {
                reason: "the needle's ends must be finite",
            });
        }
        let hits = self.needle_crossings(body, from.as_dvec3(), to.as_dvec3());
        // The wound: the needle leaves the body through one wall and enters it again through
        // the other. Walls that were pressed into each other (nothing keeps a wound's walls
        // apart: there is no self-collision) are crossed the other way round, into the far
        // wall before out of the near one; that overlap is the wound too.
        let Some(w) = hits
            .windows(2)
            .find(|w| w[0].leaving && !w[1].leaving)
            .or_else(|| hits.windows(2).find(|w| !w[0].leaving && w[1].leaving))
        else {
            return Ok(None);
        };
        let Some([na, nb]) = wound_nodes(body, &w[0], &w[1]) else {
            return Ok(None);
        };
        if self
            .sutures
            .iter()
            .flatten()
            .any(|s| s.nodes == [na, nb] || s.nodes == [nb, na])
        {
            return Ok(None);
        }
        self.place_suture(body, [na, nb]).map(Some)
    }

    /// The boundary faces the needle's axis `p → q` crosses, in order along it.
    fn needle_crossings(&self, body: &SoftBody, p: DVec3, q: DVec3) -> Vec<Crossing> {
        let d = q - p;
        let x = body.positions();
        let tets = body.tets();
        let (lo, hi) = (p.min(q), p.max(q));
        let mut hits: Vec<Crossing> = Vec::new();
        for (t, nb) in self.neighbours.iter().enumerate() {
            for (j, &u) in nb.iter().enumerate() {
                if u != NO_TET {
                    continue;
                }
                let f = face_nodes(&tets[t], j);
                let c = f.map(|i| x[i as usize].as_dvec3());
                let (flo, fhi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
                if flo.cmpgt(hi).any() || fhi.cmplt(lo).any() {
                    continue;
                }
                if let Some(s) = segment_triangle(p, q, c) {
                    let normal = (c[1] - c[0]).cross(c[2] - c[0]);
                    hits.push(Crossing {
                        s,
                        leaving: normal.dot(d) > 0.0,
                        face: f,
                        point: p + s * d,
                    });
                }
            }
        }
        hits.sort_by(|a, b| a.s.total_cmp(&b.s));
        hits
    }

    /// Links nodes `na`, `nb` by a suture with the settings' rest length and stiffness
    /// (bad nodes are refused by the body).
    fn place_suture(
        &mut self,
        body: &mut SoftBody,
        [na, nb]: [u32; 2],
    ) -> Result<SurgeryEvent, SurgeryError> {
        let s = self.settings;
        // Refuses bad nodes before they are read.
        let constraint = body.add_link_constraint(DistanceConstraint {
            nodes: [na, nb],
            rest_length: s.suture_rest_length,
            stiffness: s.suture_stiffness,
            compliance: s.suture_compliance,
        })?;
        let x = body.positions();
        let gap = x[na as usize].distance(x[nb as usize]);
        let id = self.sutures.len();
        self.sutures.push(Some(Suture {
            nodes: [na, nb],
            constraint,
            initial_gap: gap,
        }));
        tracing::debug!(suture = id, a = na, b = nb, gap, "suture placed");
        Ok(SurgeryEvent::SuturePlaced {
            suture: id,
            nodes: [na, nb],
            constraint,
        })
    }

    /// Links two given nodes directly (a host that picked them itself).
    ///
    /// # Errors
    /// [`SurgeryError::Body`] for bad nodes, [`SurgeryError::BodyMismatch`].
    pub fn suture_nodes(
        &mut self,
        body: &mut SoftBody,
        nodes: [u32; 2],
    ) -> Result<SurgeryEvent, SurgeryError> {
        let _span = tracing::debug_span!("suture").entered();
        self.check_body(body)?;
        self.place_suture(body, nodes)
    }

    /// Removes a suture: its link constraint is removed from the body.
    ///
    /// # Errors
    /// [`SurgeryError::NoSuchSuture`] for an unknown or removed id.
    pub fn remove_suture(
        &mut self,
        body: &mut SoftBody,
        id: usize,
    ) -> Result<SurgeryEvent, SurgeryError> {
        let _span = tracing::debug_span!("suture").entered();
        let s = self
            .sutures
            .get(id)
            .copied()
            .flatten()
            .ok_or(SurgeryError::NoSuchSuture { id })?;
        body.remove_distance_constraint(s.constraint)?;
        self.sutures[id] = None;
        Ok(SurgeryEvent::SutureRemoved {
            suture: id,
            nodes: s.nodes,
        })
    }
}
