//! Local topology edits for cutting and suturing (issue 8): nodes appended, tets relabelled,
//! distance constraints added, relabelled or removed, masses set — without rebuilding the
//! domain decomposition.
//!
//! Design (kept apart from the block tree on purpose):
//! - **Nodes are appended**: a new node gets the next caller index *and* the next solver index,
//!   after the block tree's node range `[0, n₀)`. The tree never sees it.
//! - **A constraint that changes leaves the tree**: its lanes in its block's batch are switched
//!   off in place — all the lane's nodes set to the lane's first node (a zero-length distance, a
//!   flat tet: the kernels' validity masks skip it), its rest value 0 and its parameter "off"
//!   (`k = 0`; for XPBD `α̃ = f32::MAX`, so `Δλ = −C/α̃` underflows to 0). A switched-off lane
//!   touches only its own node and writes back exactly what it read, so the batch's other lanes
//!   and the colouring are untouched.
//! - **The dynamic set** holds every added or relabelled constraint, in the order the edits
//!   made them, in solver indices: one batch per constraint (its eight lanes equal, as padding
//!   lanes are). Each iteration projects it serially after the block tree (its volumes, then
//!   its distances, so that links added last, like sutures, are projected last) and before the
//!   floor and contacts. So serial and parallel stay bit-identical, and steps allocate nothing.
//! - Removed constraints keep their record (so indices stay stable) with
//!   [`ConstraintSlot::Removed`]; [`SoftBody::distance_slot`] says where each record is.
//! - Masses are set per node ([`SoftBody::set_node_mass`]); [`SoftBody::tet_rest_volumes`] and
//!   [`SoftBody::density`] let the caller rebuild them locally (eq. (1)).
//!
//! Edits allocate (they are rare); a step after an edit allocates nothing. No re-partition is
//! done: after very many edits the dynamic set grows and with it the serial part of a step.

use glam::{Vec3A, Vec4};

use crate::body::SoftBody;
use crate::constraint::{CentroidBatch, DistanceBatch, TetBatch, F, LANES};
use crate::{DistanceConstraint, PbdError, Solver, VolumeConstraintKind};

/// Where a distance constraint or tet is projected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintSlot {
    /// In batch `batch` of the block tree (as built).
    Tree {
        /// Batch index.
        batch: u32,
    },
    /// In the dynamic set, at this position (projected after the tree).
    Dynamic {
        /// Position in the dynamic set.
        position: u32,
    },
    /// Removed: the record is kept but has no effect.
    Removed,
}

/// The edit state of a body.
#[derive(Debug, Clone, Default)]
pub(crate) struct Edits {
    pub density: f32,
    /// Nodes of the block tree, `n₀`.
    pub tree_nodes: usize,
    pub tet_rest: Vec<f32>,
    pub distance_slot: Vec<ConstraintSlot>,
    pub tet_slot: Vec<ConstraintSlot>,
    /// Dynamic distance constraints: record index, batch (solver indices), multiplier.
    pub dyn_distance: Vec<u32>,
    pub dyn_distance_batches: Vec<DistanceBatch>,
    pub dyn_distance_lambda: Vec<F>,
    /// Dynamic tets: tet index, batch of the body's volume kind, multipliers (1 or 4 each).
    pub dyn_tets: Vec<u32>,
    pub dyn_tet_batches: Vec<TetBatch>,
    pub dyn_centroid_batches: Vec<CentroidBatch>,
    pub dyn_volume_lambda: Vec<F>,
}

impl Edits {
    pub(crate) fn new(body: &SoftBody, density: f32) -> Self {
        let mut distance_slot = vec![ConstraintSlot::Removed; body.distance.len()];
        for (b, lanes) in body.distance_lanes.iter().enumerate() {
            for &r in lanes {
                distance_slot[r as usize] = ConstraintSlot::Tree { batch: b as u32 };
            }
        }
        let mut tet_slot = vec![ConstraintSlot::Removed; body.tets.len()];
        for (b, lanes) in body.tet_lanes.iter().enumerate() {
            for &r in lanes {
                tet_slot[r as usize] = ConstraintSlot::Tree { batch: b as u32 };
            }
        }
        let tet_rest = body
            .tets
            .iter()
            .map(|t| {
                let [a, b, c, d] = t.map(|i| body.x[i as usize]);
                (b - a).cross(c - a).dot(d - a) / 6.0
            })
            .collect();
        Self {
            density,
            tree_nodes: body.x.len(),
            tet_rest,
            distance_slot,
            tet_slot,
            ..Default::default()
        }
    }
}

/// The kernels' parameter of a switched-off lane.
fn off(solver: Solver) -> f32 {
    if solver == Solver::Xpbd {
        f32::MAX
    } else {
        0.0
    }
}

fn set_lane(f: &mut F, lane: usize, v: f32) {
    f.0[lane / 4][lane % 4] = v;
}

impl SoftBody {
    /// Re-applies the edit state to the per-step parameters (after [`SoftBody::set_settings`]).
    pub(crate) fn refresh_edit_params(&mut self) {
        let off = off(self.settings.solver);
        let s = self.settings;
        // Switched-off tree lanes.
        for (b, lanes) in self.distance_batches.iter_mut().zip(&self.distance_lanes) {
            for (l, &r) in lanes.iter().enumerate() {
                if !matches!(
                    self.edits.distance_slot[r as usize],
                    ConstraintSlot::Tree { .. }
                ) {
                    set_lane(&mut b.param, l, off);
                }
            }
        }
        for (k, lanes) in self.tet_lanes.iter().enumerate() {
            for (l, &r) in lanes.iter().enumerate() {
                if !matches!(self.edits.tet_slot[r as usize], ConstraintSlot::Tree { .. }) {
                    if let Some(b) = self.tet_batches.get_mut(k) {
                        set_lane(&mut b.param, l, off);
                    }
                    if let Some(b) = self.centroid_batches.get_mut(k) {
                        for p in &mut b.param {
                            set_lane(p, l, off);
                        }
                    }
                }
            }
        }
        // Dynamic constraints.
        for (b, &r) in self
            .edits
            .dyn_distance_batches
            .iter_mut()
            .zip(&self.edits.dyn_distance)
        {
            let c = &self.distance[r as usize];
            b.param = F::splat(s.param(c.stiffness, c.compliance));
        }
        for (k, &t) in self.edits.dyn_tets.iter().enumerate() {
            let t = t as usize;
            if let Some(b) = self.edits.dyn_tet_batches.get_mut(k) {
                let c = &self.tet_volume[t];
                b.param = F::splat(s.param(c.stiffness, c.compliance));
            }
            if let Some(b) = self.edits.dyn_centroid_batches.get_mut(k) {
                for j in 0..4 {
                    let c = &self.centroid[4 * t + j];
                    b.param[j] = F::splat(s.param(c.stiffness, c.compliance));
                }
            }
        }
    }

    /// Number of nodes of the block tree (the node count at construction); nodes past it were
    /// appended by [`SoftBody::duplicate_nodes`].
    pub fn tree_node_count(&self) -> usize {
        self.edits.tree_nodes
    }
    /// Density (g/cm³) of the material the body was built with.
    pub fn density(&self) -> f32 {
        self.edits.density
    }
    /// Rest volume of each tet (cm³), in [`SoftBody::tets`] order.
    pub fn tet_rest_volumes(&self) -> &[f32] {
        &self.edits.tet_rest
    }
    /// Where distance constraint `c` is projected (`None` past the end).
    pub fn distance_slot(&self, c: usize) -> Option<ConstraintSlot> {
        self.edits.distance_slot.get(c).copied()
    }
    /// Where tet `t`'s volume constraints are projected (`None` past the end).
    pub fn tet_slot(&self, t: usize) -> Option<ConstraintSlot> {
        self.edits.tet_slot.get(t).copied()
    }
    /// Sizes of the dynamic set: (distance constraints, tets).
    pub fn dynamic_counts(&self) -> (usize, usize) {
        (self.edits.dyn_distance.len(), self.edits.dyn_tets.len())
    }

    /// Appends one node per entry of `sources`, each a copy of its source (position, previous
    /// position, velocity, mass, inverse mass: a pinned source gives a pinned copy). Returns the
    /// index of the first new node; the others follow. The new nodes carry no constraint until
    /// tets or constraints are moved onto them.
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`] for a bad source (nothing is changed).
    pub fn duplicate_nodes(&mut self, sources: &[u32]) -> Result<u32, PbdError> {
        let n = self.x.len();
        if let Some(&bad) = sources.iter().find(|&&s| s as usize >= n) {
            return Err(PbdError::NodeOutOfRange {
                element: "duplicated node",
                index: bad as usize,
                node: bad,
                count: n,
            });
        }
        if n + sources.len() >= u32::MAX as usize {
            return Err(PbdError::InvalidParameter {
                name: "node count",
                value: (n + sources.len()) as f64,
                expected: "fewer than 2³² nodes",
            });
        }
        for &s in sources {
            let s = s as usize;
            let i = self.x.len() as u32;
            self.x.push(self.x[s]);
            self.p.push(self.p[s]);
            self.v.push(self.v[s]);
            self.mass.push(self.mass[s]);
            self.w.push(self.w[s]);
            self.order.push(i);
            self.rank.push(i);
            self.q.push(Vec4::ZERO);
            self.qw.push(0.0);
        }
        self.collision.reserve(self.x.len());
        Ok(n as u32)
    }

    /// Sets a node's mass (g). A pinned or attached node (inverse mass 0 with a mass) stays
    /// pinned; otherwise the inverse mass becomes `1/mass` (0 for mass 0).
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`], [`PbdError::InvalidParameter`] for a negative or
    /// non-finite mass.
    pub fn set_node_mass(&mut self, node: u32, mass: f32) -> Result<(), PbdError> {
        let i = node as usize;
        if i >= self.x.len() {
            return Err(PbdError::NodeOutOfRange {
                element: "mass",
                index: i,
                node,
                count: self.x.len(),
            });
        }
        if !(mass.is_finite() && mass >= 0.0) {
            return Err(PbdError::InvalidParameter {
                name: "mass",
                value: mass as f64,
                expected: "finite and ≥ 0 (g)",
            });
        }
        let pinned = self.w[i] == 0.0 && self.mass[i] > 0.0;
        self.mass[i] = mass;
        self.w[i] = if pinned || mass <= 0.0 {
            0.0
        } else {
            1.0 / mass
        };
        if self.w[i] == 0.0 {
            self.v[i] = Vec3A::ZERO;
        }
        Ok(())
    }

    fn check_nodes<const N: usize>(
        &self,
        element: &'static str,
        index: usize,
        nodes: &[u32; N],
    ) -> Result<(), PbdError> {
        for (k, &a) in nodes.iter().enumerate() {
            if a as usize >= self.x.len() {
                return Err(PbdError::NodeOutOfRange {
                    element,
                    index,
                    node: a,
                    count: self.x.len(),
                });
            }
            if nodes[..k].contains(&a) {
                return Err(PbdError::InvalidParameter {
                    name: "constraint nodes",
                    value: a as f64,
                    expected: "distinct nodes",
                });
            }
        }
        Ok(())
    }

    /// Switches off distance record `r`'s lanes in its tree batch.
    fn switch_off_distance_lanes(&mut self, batch: usize) -> usize {
        let off = off(self.settings.solver);
        let b = &mut self.distance_batches[batch];
        let mut count = 0;
        for (l, &r) in self.distance_lanes[batch].iter().enumerate() {
            if !matches!(
                self.edits.distance_slot[r as usize],
                ConstraintSlot::Tree { .. }
            ) {
                b.nodes[1][l] = b.nodes[0][l];
                set_lane(&mut b.rest, l, 0.0);
                set_lane(&mut b.param, l, off);
                count += 1;
            }
        }
        count
    }

    fn switch_off_tet_lanes(&mut self, batch: usize) {
        let off = off(self.settings.solver);
        for (l, &r) in self.tet_lanes[batch].iter().enumerate() {
            if matches!(self.edits.tet_slot[r as usize], ConstraintSlot::Tree { .. }) {
                continue;
            }
            if let Some(b) = self.tet_batches.get_mut(batch) {
                for k in 1..4 {
                    b.nodes[k][l] = b.nodes[0][l];
                }
                set_lane(&mut b.rest, l, 0.0);
                set_lane(&mut b.param, l, off);
            }
            if let Some(b) = self.centroid_batches.get_mut(batch) {
                for k in 1..4 {
                    b.nodes[k][l] = b.nodes[0][l];
                }
                for j in 0..4 {
                    set_lane(&mut b.rest[j], l, 0.0);
                    set_lane(&mut b.param[j], l, off);
                }
            }
        }
    }

    fn distance_batch_of(&self, c: &DistanceConstraint) -> DistanceBatch {
        let [a, b] = c.nodes.map(|i| [self.rank[i as usize]; LANES]);
        DistanceBatch {
            nodes: [a, b],
            rest: F::splat(c.rest_length),
            param: F::splat(self.settings.param(c.stiffness, c.compliance)),
        }
    }

    /// Adds a distance constraint to the dynamic set (a suture link, a new edge after a cut).
    /// Returns its record index.
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`], [`PbdError::InvalidParameter`] for repeated nodes or a
    /// bad rest length, stiffness or compliance.
    pub fn add_distance_constraint(&mut self, c: DistanceConstraint) -> Result<usize, PbdError> {
        let index = self.distance.len();
        self.check_nodes("distance constraint", index, &c.nodes)?;
        check_distance_values(&c)?;
        let batch = self.distance_batch_of(&c);
        self.distance.push(c);
        self.edits.distance_slot.push(ConstraintSlot::Dynamic {
            position: self.edits.dyn_distance.len() as u32,
        });
        self.edits.dyn_distance.push(index as u32);
        self.edits.dyn_distance_batches.push(batch);
        self.edits.dyn_distance_lambda.push(F::ZERO);
        Ok(index)
    }

    /// Moves distance constraint `c` onto other nodes (rest length, stiffness, compliance kept);
    /// it is projected in the dynamic set from now on.
    ///
    /// # Errors
    /// [`PbdError::NoSuchElement`] for a bad or removed record, [`PbdError::NodeOutOfRange`],
    /// [`PbdError::InvalidParameter`] for repeated nodes.
    pub fn set_distance_nodes(&mut self, c: usize, nodes: [u32; 2]) -> Result<(), PbdError> {
        let slot = self.live_distance(c)?;
        self.check_nodes("distance constraint", c, &nodes)?;
        self.distance[c].nodes = nodes;
        let batch = self.distance_batch_of(&self.distance[c]);
        match slot {
            ConstraintSlot::Dynamic { position } => {
                self.edits.dyn_distance_batches[position as usize] = batch;
            }
            ConstraintSlot::Tree { batch: b } => {
                self.edits.distance_slot[c] = ConstraintSlot::Dynamic {
                    position: self.edits.dyn_distance.len() as u32,
                };
                self.switch_off_distance_lanes(b as usize);
                self.edits.dyn_distance.push(c as u32);
                self.edits.dyn_distance_batches.push(batch);
                self.edits.dyn_distance_lambda.push(F::ZERO);
            }
            ConstraintSlot::Removed => {}
        }
        Ok(())
    }

    /// Removes distance constraint `c` (a suture cut, an edge that a cut separated). Its record
    /// stays, with [`ConstraintSlot::Removed`].
    ///
    /// # Errors
    /// [`PbdError::NoSuchElement`] for a bad or already removed record.
    pub fn remove_distance_constraint(&mut self, c: usize) -> Result<(), PbdError> {
        match self.live_distance(c)? {
            ConstraintSlot::Tree { batch } => {
                self.edits.distance_slot[c] = ConstraintSlot::Removed;
                self.switch_off_distance_lanes(batch as usize);
            }
            ConstraintSlot::Dynamic { position } => {
                let p = position as usize;
                self.edits.distance_slot[c] = ConstraintSlot::Removed;
                self.edits.dyn_distance.remove(p);
                self.edits.dyn_distance_batches.remove(p);
                self.edits.dyn_distance_lambda.remove(p);
                for (k, &r) in self.edits.dyn_distance.iter().enumerate().skip(p) {
                    self.edits.distance_slot[r as usize] =
                        ConstraintSlot::Dynamic { position: k as u32 };
                }
            }
            ConstraintSlot::Removed => {}
        }
        Ok(())
    }

    fn live_distance(&self, c: usize) -> Result<ConstraintSlot, PbdError> {
        match self.edits.distance_slot.get(c) {
            Some(&s) if s != ConstraintSlot::Removed => Ok(s),
            _ => Err(PbdError::NoSuchElement {
                what: "distance constraint",
                index: c,
                count: self.distance.len(),
            }),
        }
    }

    /// Moves tet `t` (and its volume constraints) onto other nodes, keeping its rest values: the
    /// way a cut separates the two sides (a node duplicated, the tets of one side moved onto the
    /// copy). The new nodes must keep the tet positively oriented (the caller's duty; the rest
    /// values are not recomputed). From now on the tet is projected in the dynamic set.
    ///
    /// # Errors
    /// [`PbdError::NoSuchElement`], [`PbdError::NodeOutOfRange`],
    /// [`PbdError::InvalidParameter`] for repeated nodes.
    pub fn set_tet_nodes(&mut self, t: usize, nodes: [u32; 4]) -> Result<(), PbdError> {
        let slot = match self.edits.tet_slot.get(t) {
            Some(&s) if s != ConstraintSlot::Removed => s,
            _ => {
                return Err(PbdError::NoSuchElement {
                    what: "tet",
                    index: t,
                    count: self.tets.len(),
                })
            }
        };
        self.check_nodes("tet", t, &nodes)?;
        self.tets[t] = nodes;
        if let Some(c) = self.tet_volume.get_mut(t) {
            c.nodes = nodes;
        }
        if self.volume_kind == VolumeConstraintKind::Centroid {
            for j in 0..4 {
                let c = &mut self.centroid[4 * t + j];
                c.face = [nodes[(j + 1) & 3], nodes[(j + 2) & 3], nodes[(j + 3) & 3]];
                c.apex = nodes[j];
            }
        }
        let s = nodes.map(|i| [self.rank[i as usize]; LANES]);
        let tet_batch = self.tet_volume.get(t).map(|c| TetBatch {
            nodes: s,
            rest: F::splat(c.rest_volume),
            param: F::splat(self.settings.param(c.stiffness, c.compliance)),
        });
        let centroid_batch = (self.volume_kind == VolumeConstraintKind::Centroid).then(|| {
            let c = &self.centroid[4 * t..4 * t + 4];
            CentroidBatch {
                nodes: s,
                rest: [0, 1, 2, 3].map(|j| F::splat(c[j].rest_height)),
                param: [0, 1, 2, 3]
                    .map(|j| F::splat(self.settings.param(c[j].stiffness, c[j].compliance))),
            }
        });
        let position = match slot {
            ConstraintSlot::Dynamic { position } => position as usize,
            _ => {
                let position = self.edits.dyn_tets.len();
                self.edits.tet_slot[t] = ConstraintSlot::Dynamic {
                    position: position as u32,
                };
                if let ConstraintSlot::Tree { batch } = slot {
                    self.switch_off_tet_lanes(batch as usize);
                }
                self.edits.dyn_tets.push(t as u32);
                if tet_batch.is_some() {
                    self.edits.dyn_tet_batches.push(TetBatch {
                        nodes: s,
                        rest: F::ZERO,
                        param: F::ZERO,
                    });
                }
                if centroid_batch.is_some() {
                    self.edits.dyn_centroid_batches.push(CentroidBatch {
                        nodes: s,
                        rest: [F::ZERO; 4],
                        param: [F::ZERO; 4],
                    });
                }
                let per_tet = match self.volume_kind {
                    VolumeConstraintKind::None => 0,
                    VolumeConstraintKind::Classic => 1,
                    VolumeConstraintKind::Centroid => 4,
                };
                self.edits
                    .dyn_volume_lambda
                    .extend(std::iter::repeat_n(F::ZERO, per_tet));
                position
            }
        };
        if let Some(b) = tet_batch {
            self.edits.dyn_tet_batches[position] = b;
        }
        if let Some(b) = centroid_batch {
            self.edits.dyn_centroid_batches[position] = b;
        }
        Ok(())
    }
}

fn check_distance_values(c: &DistanceConstraint) -> Result<(), PbdError> {
    for (name, v, ok) in [
        (
            "rest_length",
            c.rest_length,
            c.rest_length.is_finite() && c.rest_length >= 0.0,
        ),
        ("stiffness", c.stiffness, (0.0..=1.0).contains(&c.stiffness)),
        (
            "compliance",
            c.compliance,
            c.compliance.is_finite() && c.compliance >= 0.0,
        ),
    ] {
        if !ok {
            return Err(PbdError::InvalidParameter {
                name,
                value: v as f64,
                expected: "rest length ≥ 0, stiffness in [0, 1], compliance ≥ 0 (all finite)",
            });
        }
    }
    Ok(())
}
