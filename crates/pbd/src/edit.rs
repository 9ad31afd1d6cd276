//! Local topology edits for cutting and suturing: nodes appended, tets relabelled,
//! distance constraints added, relabelled or removed, masses set — without rebuilding the
//! domain decomposition.
//!
//! Design (the block tree is built once; edits fit into it where they can):
//! - **Nodes are appended** to the caller's numbering (a new node gets the next caller index).
//!   Its *solver slot* is a spare slot of the leaf block holding its source node
//!   ([`SoftBody::duplicate_nodes`]; every leaf has as many spare slots as real nodes, see
//!   `crate::partition`), so the constraints on it still fall into the block tree. Only when
//!   that leaf has no spare left (or the source is itself past the tree) does the node go to the
//!   *tail*, after the tree's slots, which no block covers.
//! - **A constraint that changes keeps its tree lane when it can**: when its new nodes lie in
//!   its tree batch's block and no other lane of that batch touches them (the usual case for a
//!   tet or edge moved onto the copy of one of its nodes: the copy is in its source's leaf, and
//!   no other lane of the batch has the source), its lane (and the padding lanes that copy it)
//!   is rewritten in place: a step does the same work as before. Otherwise it **leaves its tree
//!   batch**: its lanes are switched off in place — all the lane's nodes set to the lane's first
//!   node (a zero-length distance, a flat tet: the kernels' validity masks skip it), its rest
//!   value 0 and its parameter "off" (`k = 0`; for XPBD `α̃ = f32::MAX`, so `Δλ = −C/α̃`
//!   underflows to 0). A switched-off lane touches only its own node and writes back exactly
//!   what it read, so the batch's other lanes and the colouring are untouched.
//! - **Dynamic batches**: every added constraint, and every changed one that left its tree
//!   batch, is *dynamic*, packed eight to a batch in a *dynamic set*: it takes the next lane of
//!   one of the set's last [`SEARCH`] batches where no lane touches its nodes, else opens a new
//!   batch whose unused lanes copy its lane 0 (as padding does). A constraint whose slots all
//!   lie in the tree goes to the set of the deepest block holding them
//!   ([`ConstraintSlot::Block`]), in that block's slot-local indices: it is projected right
//!   after that block's own tree batches (the block's tree distances and volumes, then its
//!   dynamic volumes and distances, the order of the serial set), in parallel with the sibling
//!   subtree like them. A constraint touching a tail node goes to the **serial set**
//!   ([`ConstraintSlot::Dynamic`]), projected serially after the whole tree (its volumes, then
//!   its distances) and before the links, the floor and contacts. A changed dynamic constraint
//!   keeps its lane when it stays in the same set and no other lane of its batch touches its
//!   new nodes; otherwise, and when removed, its lane is switched off like a tree lane and the
//!   constraint, if changed, is packed again. The order of the batches depends on the edits
//!   alone, so serial and parallel stay bit-identical, and steps allocate nothing.
//! - **Links** ([`SoftBody::add_link_constraint`], for sutures) are kept apart from the packed
//!   dynamic sets and projected after the serial set, one per batch, in the order added: a link
//!   of stiffness 1 is satisfied at the end of every iteration.
//! - Removed constraints keep their record (so indices stay stable) with
//!   [`ConstraintSlot::Removed`]; [`SoftBody::distance_slot`] says where each record is.
//! - Masses are set per node ([`SoftBody::set_node_mass`]); [`SoftBody::tet_rest_volumes`] and
//!   [`SoftBody::density`] let the caller rebuild them locally (eq. (1)).
//!
//! Edits allocate (they are rare); a step after an edit allocates nothing. No re-partition is
//! done: after very many edits the dynamic batches grow, and once leaves run out of spares, so
//! does the serial set.

use glam::{DVec3, Vec3, Vec3A, Vec4};

use crate::body::{Block, SoftBody};
use crate::constraint::{
    neo_hookean_batch, set_neo_hookean_lane, CentroidBatch, DistanceBatch, NeoHookeanBatch,
    TetBatch, F, LANES,
};
use crate::partition::Tree;
use crate::{
    CentroidVolumeConstraint, DistanceConstraint, NeoHookeanConstraint, PbdError, PbdParam, Solver,
    TetVolumeConstraint, VolumeConstraintKind,
};

/// Where a distance constraint or tet is projected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintSlot {
    /// In batch `batch` of the block tree (as built; a changed constraint may keep its lane).
    Tree {
        /// Batch index.
        batch: u32,
    },
    /// In the dynamic batches of block `block` of the tree (heap numbering: root 0, children
    /// `2h+1`, `2h+2`), at this position: an added or changed constraint whose nodes all lie in
    /// the block, projected right after the block's own tree constraints (in parallel with the
    /// sibling subtree).
    Block {
        /// Heap index of the block.
        block: u32,
        /// Position (batch × 8 + lane) in the block's dynamic batches.
        position: u32,
    },
    /// In the serial dynamic set, at this position (batch × 8 + lane): an added or changed
    /// constraint on a node past the block tree's slots, projected serially after the tree.
    Dynamic {
        /// Position in the serial dynamic set.
        position: u32,
    },
    /// A link (e.g. a suture), at this position of the link list: projected after everything
    /// else of the body, one per batch, in the order added.
    Link {
        /// Position in the link list.
        position: u32,
    },
    /// Removed: the record is kept but has no effect.
    Removed,
}

/// One dynamic set: added or changed constraints packed eight to a batch (lanes sharing no
/// node), in the slot-local indices of its block (absolute slots for the serial set). For each
/// kind, the record of each lane (unused lanes repeat lane 0, as padding does), the lanes in use
/// and the batches (volumes: of the body's volume kind).
#[derive(Debug, Clone, Default)]
pub(crate) struct DynSet {
    pub distance_lanes: Vec<[u32; LANES]>,
    pub distance_fill: Vec<u8>,
    pub distance_batches: Vec<DistanceBatch>,
    pub tet_lanes: Vec<[u32; LANES]>,
    pub tet_fill: Vec<u8>,
    pub tet_batches: Vec<TetBatch>,
    pub centroid_batches: Vec<CentroidBatch>,
    pub neo_hookean_batches: Vec<NeoHookeanBatch>,
}

/// The edit state of a body.
#[derive(Debug, Clone, Default)]
pub(crate) struct Edits {
    pub density: f32,
    /// Rest position of each node (cm): the positions at construction, then whatever
    /// [`SoftBody::set_rest_position`] set (appended nodes copy their source's).
    pub rest_x: Vec<Vec3A>,
    /// Nodes at construction, `n₀`.
    pub tree_nodes: usize,
    /// The block tree over the solver slots (`crate::partition`): slots `[0, tree.node_count)`,
    /// the tail after them.
    pub tree: Tree,
    /// The blocks in post order.
    pub post: Vec<usize>,
    /// Slots in use (real nodes, then filled spares) of each leaf, by leaf number.
    pub leaf_fill: Vec<u32>,
    pub tet_rest: Vec<f32>,
    pub distance_slot: Vec<ConstraintSlot>,
    pub tet_slot: Vec<ConstraintSlot>,
    /// The dynamic sets: one per block (heap index), then the serial set.
    pub sets: Vec<DynSet>,
    /// Multipliers of the dynamic batches: the blocks' in post order (ranges in
    /// `Block::dyn_distance`, `Block::dyn_tets`), then the serial set's; one per distance batch,
    /// 1 or 4 per volume batch. Zeroed at the start of every step, so a new batch just extends
    /// them.
    pub dyn_distance_lambda: Vec<F>,
    pub dyn_volume_lambda: Vec<F>,
    /// Live dynamic constraints: (distances, tets) in all sets, and in the serial set.
    pub dyn_live: (usize, usize),
    pub serial_live: (usize, usize),
    /// Links: record per position, batches (all lanes equal), multipliers.
    pub links: Vec<u32>,
    pub link_batches: Vec<DistanceBatch>,
    pub link_lambda: Vec<F>,
}

impl Edits {
    /// `tree`: the block tree over the solver slots, `post` its blocks in post order.
    pub(crate) fn new(body: &SoftBody, density: f32, tree: Tree, post: Vec<usize>) -> Self {
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
        // Real nodes take the first slots of each leaf.
        let leaves = 1usize << tree.depth;
        let mut leaf_fill = vec![0u32; leaves];
        for &r in &body.rank {
            leaf_fill[tree.leaf_of(r as usize) + 1 - leaves] += 1;
        }
        Self {
            density,
            rest_x: body.x.clone(),
            tree_nodes: body.x.len(),
            tree,
            post,
            leaf_fill,
            tet_rest,
            distance_slot,
            tet_slot,
            sets: vec![DynSet::default(); tree.block_count() + 1],
            ..Default::default()
        }
    }

    /// The solver slots in use, `slot_count` in all: each leaf's (its real nodes, then its
    /// filled spares), then the tail.
    pub(crate) fn used_slots(
        &self,
        slot_count: usize,
    ) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let per = self.tree.leaf_slots();
        self.leaf_fill
            .iter()
            .enumerate()
            .map(move |(k, &fill)| k * per..k * per + fill as usize)
            .chain(std::iter::once(self.tree.node_count..slot_count))
    }

    /// The serial set's index.
    fn serial(&self) -> usize {
        self.sets.len() - 1
    }

    /// The dynamic set for a constraint on solver slots `s`: the deepest block holding them all,
    /// the serial set when one is past the tree.
    fn set_for(&self, s: &[u32]) -> usize {
        if s.iter().all(|&i| (i as usize) < self.tree.node_count) {
            self.tree.block_of(s)
        } else {
            self.serial()
        }
    }

    /// The slot of position `position` of set `set`.
    fn slot_at(&self, set: usize, position: usize) -> ConstraintSlot {
        slot_at(set, self.serial(), position)
    }

    /// Set and position of a dynamic slot.
    fn position(&self, slot: ConstraintSlot) -> Option<(usize, usize)> {
        match slot {
            ConstraintSlot::Block { block, position } => Some((block as usize, position as usize)),
            ConstraintSlot::Dynamic { position } => Some((self.serial(), position as usize)),
            _ => None,
        }
    }

    /// Counts a constraint into (`by = 1`) or out of (`by = -1`) set `set`'s live ones; `tet`
    /// for a tet.
    fn count(&mut self, set: usize, tet: bool, by: isize) {
        let serial = set == self.serial();
        for (on, live) in [(true, &mut self.dyn_live), (serial, &mut self.serial_live)] {
            if on {
                let n = if tet { &mut live.1 } else { &mut live.0 };
                *n = n.saturating_add_signed(by);
            }
        }
    }

    /// A free spare slot of the leaf holding slot `source` (taken), `None` when that leaf has
    /// none left or `source` is past the tree.
    fn spare(&mut self, source: u32) -> Option<u32> {
        let s = source as usize;
        if s >= self.tree.node_count {
            return None;
        }
        let leaves = 1usize << self.tree.depth;
        let k = self.tree.leaf_of(s) + 1 - leaves;
        let per = self.tree.leaf_slots();
        let fill = &mut self.leaf_fill[k];
        if (*fill as usize) < per {
            *fill += 1;
            Some((k * per) as u32 + *fill - 1)
        } else {
            None
        }
    }
}

/// How many of the last dynamic batches a new constraint may join (a lane free, no node shared).
const SEARCH: usize = 64;

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
        self.refresh_link_params();
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
                    if let Some(b) = self.neo_hookean_batches.get_mut(k) {
                        for p in &mut b.param {
                            set_lane(p, l, off);
                        }
                    }
                }
            }
        }
        // Dynamic constraints, set by set, lane by lane.
        let e = &mut self.edits;
        let serial = e.sets.len() - 1;
        for (set, d) in e.sets.iter_mut().enumerate() {
            let at = |position| slot_at(set, serial, position);
            for (b, (batch, lanes)) in d
                .distance_batches
                .iter_mut()
                .zip(&d.distance_lanes)
                .enumerate()
            {
                let fill = d.distance_fill[b] as usize;
                for (l, &r) in lanes.iter().enumerate() {
                    let live = dyn_live(&e.distance_slot, r, at, b, l, fill);
                    let c = &self.distance[r as usize];
                    set_lane(
                        &mut batch.param,
                        l,
                        if live {
                            s.param(c.stiffness, c.compliance)
                        } else {
                            off
                        },
                    );
                }
            }
            for (b, lanes) in d.tet_lanes.iter().enumerate() {
                let fill = d.tet_fill[b] as usize;
                for (l, &r) in lanes.iter().enumerate() {
                    let live = dyn_live(&e.tet_slot, r, at, b, l, fill);
                    let t = r as usize;
                    if let Some(batch) = d.tet_batches.get_mut(b) {
                        let c = &self.tet_volume[t];
                        set_lane(
                            &mut batch.param,
                            l,
                            if live {
                                s.param(c.stiffness, c.compliance)
                            } else {
                                off
                            },
                        );
                    }
                    if let Some(batch) = d.neo_hookean_batches.get_mut(b) {
                        let p = self.neo_hookean[t].params(s.substep_dt());
                        for (param, v) in batch.param.iter_mut().zip(p) {
                            set_lane(param, l, if live { v } else { off });
                        }
                    }
                    if let Some(batch) = d.centroid_batches.get_mut(b) {
                        for j in 0..4 {
                            let c = &self.centroid[4 * t + j];
                            set_lane(
                                &mut batch.param[j],
                                l,
                                if live {
                                    s.param(c.stiffness, c.compliance)
                                } else {
                                    off
                                },
                            );
                        }
                    }
                }
            }
        }
    }

    /// Refreshes the links' parameters.
    fn refresh_link_params(&mut self) {
        for (b, &r) in self.edits.link_batches.iter_mut().zip(&self.edits.links) {
            let c = &self.distance[r as usize];
            b.param = F::splat(self.settings.param(c.stiffness, c.compliance));
        }
    }

    /// Number of nodes the block tree was built on (the node count at construction); nodes past
    /// it were appended by [`SoftBody::duplicate_nodes`] (and are projected in spare slots of the
    /// tree's leaves while there are any, see the module docs).
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
    /// Where tet `t`'s volume constraints (or neo-Hookean pair) are projected (`None` past the
    /// end).
    pub fn tet_slot(&self, t: usize) -> Option<ConstraintSlot> {
        self.edits.tet_slot.get(t).copied()
    }
    /// Sizes of the dynamic sets: (distance constraints, tets), the live ones of all of them —
    /// every added constraint but the links, and every changed one that could not keep its tree
    /// lane, whether in a block of the tree ([`ConstraintSlot::Block`]) or in the serial set
    /// ([`ConstraintSlot::Dynamic`]).
    pub fn dynamic_counts(&self) -> (usize, usize) {
        self.edits.dyn_live
    }
    /// Batches of the dynamic sets, of all of them: (distance, tet); up to eight constraints
    /// each.
    pub fn dynamic_batch_counts(&self) -> (usize, usize) {
        self.edits.sets.iter().fold((0, 0), |(d, t), set| {
            (d + set.distance_lanes.len(), t + set.tet_lanes.len())
        })
    }
    /// The part of [`SoftBody::dynamic_counts`] in the serial set (constraints on nodes past the
    /// block tree's slots, projected serially after the tree).
    pub fn serial_dynamic_counts(&self) -> (usize, usize) {
        self.edits.serial_live
    }
    /// Batches of the serial set: (distance, tet).
    pub fn serial_dynamic_batch_counts(&self) -> (usize, usize) {
        let set = &self.edits.sets[self.edits.serial()];
        (set.distance_lanes.len(), set.tet_lanes.len())
    }

    /// Appends one node per entry of `sources`, each a copy of its source (position, previous
    /// position, velocity, mass, inverse mass: a pinned source gives a pinned copy). Returns the
    /// index of the first new node; the others follow. The new nodes carry no constraint until
    /// tets or constraints are moved onto them. Each copy is projected with its source's leaf
    /// block while that block has spare slots (constraints on it then stay in the parallel
    /// tree), past the tree otherwise (see the module docs).
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
        // Solver slots (at least one per node) must stay below SPARE.
        if self.q.len() + sources.len() >= u32::MAX as usize {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::NodeCount,
                value: (n + sources.len()) as f64,
                expected: "fewer than 2³² solver slots",
            });
        }
        for &s in sources {
            let s = s as usize;
            let i = self.x.len() as u32;
            self.pieces.stale = true;
            self.self_collision.stale = true;
            self.pieces.split.push(s as u32);
            self.pieces.split.push(self.x.len() as u32);
            self.x.push(self.x[s]);
            self.p.push(self.p[s]);
            self.v.push(self.v[s]);
            self.mass.push(self.mass[s]);
            self.w.push(self.w[s]);
            let slot = match self.edits.spare(self.rank[s]) {
                Some(slot) => {
                    self.order[slot as usize] = i;
                    slot
                }
                None => {
                    self.order.push(i);
                    self.q.push(Vec4::ZERO);
                    self.qw.push(0.0);
                    (self.q.len() - 1) as u32
                }
            };
            self.rank.push(slot);
            let r = self.edits.rest_x[s];
            self.edits.rest_x.push(r);
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
                param: PbdParam::Mass,
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
                    param: PbdParam::ConstraintNodes,
                    value: a as f64,
                    expected: "distinct nodes",
                });
            }
        }
        Ok(())
    }

    /// Switches off the lanes of tree batch `batch` whose records are no longer in the tree
    /// (moved to a dynamic set or removed): both nodes the same, rest length 0, the solver's
    /// "off" parameter.
    fn switch_off_distance_lanes(&mut self, batch: usize) {
        let off = off(self.settings.solver);
        let b = &mut self.distance_batches[batch];
        for (l, &r) in self.distance_lanes[batch].iter().enumerate() {
            if !matches!(
                self.edits.distance_slot[r as usize],
                ConstraintSlot::Tree { .. }
            ) {
                b.nodes[1][l] = b.nodes[0][l];
                set_lane(&mut b.rest, l, 0.0);
                set_lane(&mut b.param, l, off);
            }
        }
    }

    fn switch_off_tet_lanes(&mut self, batch: usize) {
        let off = off(self.settings.solver);
        for (l, &r) in self.tet_lanes[batch].iter().enumerate() {
            if matches!(self.edits.tet_slot[r as usize], ConstraintSlot::Tree { .. }) {
                continue;
            }
            switch_off_tet_lane(
                self.tet_batches.get_mut(batch),
                self.centroid_batches.get_mut(batch),
                self.neo_hookean_batches.get_mut(batch),
                l,
                off,
            );
        }
    }

    /// The dynamic set for a constraint on the caller's nodes `nodes`, and its nodes in that
    /// set's indices (slots local to the block; absolute slots in the serial set).
    fn dyn_place<const N: usize>(&self, nodes: [u32; N]) -> (usize, [u32; N]) {
        let s = nodes.map(|i| self.rank[i as usize]);
        let set = self.edits.set_for(&s);
        let base = if set == self.edits.serial() {
            0
        } else {
            self.blocks[set].nodes[0]
        };
        (set, s.map(|i| i - base))
    }

    /// Lays the blocks' dynamic multipliers out in post order, the serial set's after them
    /// (after a set got a new batch).
    fn layout_dyn(&mut self) {
        let (mut d, mut t) = (0u32, 0u32);
        for &h in &self.edits.post {
            let set = &self.edits.sets[h];
            let start = if self.edits.tree.is_leaf(h) {
                (d, t)
            } else {
                let left = &self.blocks[2 * h + 1];
                (left.dyn_distance[0], left.dyn_tets[0])
            };
            let end = (
                d + set.distance_lanes.len() as u32,
                t + set.tet_lanes.len() as u32,
            );
            let b = &mut self.blocks[h];
            b.dyn_distance = [start.0, d, end.0];
            b.dyn_tets = [start.1, t, end.1];
            (d, t) = end;
        }
    }

    /// Puts distance record `r` into its dynamic set (the deepest block holding its nodes, else
    /// the serial set): into a free lane of one of the set's last [`SEARCH`] batches none of
    /// whose lanes touches its nodes, else into a new batch (all lanes copies).
    fn push_dyn_distance(&mut self, r: u32) {
        let c = self.distance[r as usize];
        let (set, s) = self.dyn_place(c.nodes);
        let param = self.settings.param(c.stiffness, c.compliance);
        let e = &mut self.edits;
        let d = &mut e.sets[set];
        let count = d.distance_batches.len();
        let mut found = None;
        for batch in (count.saturating_sub(SEARCH)..count).rev() {
            let (b, fill) = (&mut d.distance_batches[batch], &mut d.distance_fill[batch]);
            let lane = *fill as usize;
            if lane >= LANES || b.nodes.iter().any(|ids| ids.iter().any(|n| s.contains(n))) {
                continue;
            }
            for (ids, &n) in b.nodes.iter_mut().zip(&s) {
                ids[lane] = n;
            }
            set_lane(&mut b.rest, lane, c.rest_length);
            set_lane(&mut b.param, lane, param);
            *fill += 1;
            d.distance_lanes[batch][lane] = r;
            found = Some(batch * LANES + lane);
            break;
        }
        let position = found.unwrap_or_else(|| {
            let batch = d.distance_batches.len();
            d.distance_batches.push(DistanceBatch {
                nodes: [[s[0]; LANES], [s[1]; LANES]],
                rest: F::splat(c.rest_length),
                param: F::splat(param),
            });
            d.distance_lanes.push([r; LANES]);
            d.distance_fill.push(1);
            e.dyn_distance_lambda.push(F::ZERO);
            batch * LANES
        });
        e.distance_slot[r as usize] = e.slot_at(set, position);
        e.count(set, false, 1);
        if found.is_none() {
            self.layout_dyn();
        }
    }

    /// Switches off the lanes of batch `b` of dynamic set `set` that hold no live distance
    /// constraint.
    fn switch_off_dyn_distance_lanes(&mut self, set: usize, b: usize) {
        let off = off(self.settings.solver);
        let e = &mut self.edits;
        let serial = e.serial();
        let d = &mut e.sets[set];
        let fill = d.distance_fill[b] as usize;
        let batch = &mut d.distance_batches[b];
        let at = |position| slot_at(set, serial, position);
        for (l, &r) in d.distance_lanes[b].iter().enumerate() {
            if !dyn_live(&e.distance_slot, r, at, b, l, fill) {
                batch.nodes[1][l] = batch.nodes[0][l];
                set_lane(&mut batch.rest, l, 0.0);
                set_lane(&mut batch.param, l, off);
            }
        }
    }

    /// Puts tet `t` into its dynamic set (as [`SoftBody::push_dyn_distance`]).
    fn push_dyn_tet(&mut self, t: u32) {
        let (set, s) = self.dyn_place(self.tets[t as usize]);
        let tet = self.tet_volume.get(t as usize).map(|c| {
            (
                c.rest_volume,
                self.settings.param(c.stiffness, c.compliance),
            )
        });
        let centroid = (self.volume_kind == VolumeConstraintKind::Centroid).then(|| {
            let c = &self.centroid[4 * t as usize..4 * t as usize + 4];
            (
                [0, 1, 2, 3].map(|j| c[j].rest_height),
                [0, 1, 2, 3].map(|j| self.settings.param(c[j].stiffness, c[j].compliance)),
            )
        });
        let neo_hookean = self
            .neo_hookean
            .get(t as usize)
            .map(|c| (*c, c.params(self.settings.substep_dt())));
        let per_tet = self.tet_kind().per_tet();
        let e = &mut self.edits;
        let d = &mut e.sets[set];
        let count = d.tet_lanes.len();
        let mut found = None;
        for b in (count.saturating_sub(SEARCH)..count).rev() {
            let lane = d.tet_fill[b] as usize;
            if lane >= LANES {
                continue;
            }
            let ids = d
                .tet_batches
                .get(b)
                .map(|x| x.nodes)
                .or_else(|| d.centroid_batches.get(b).map(|x| x.nodes))
                .or_else(|| d.neo_hookean_batches.get(b).map(|x| x.nodes));
            let clash = ids.is_some_and(|ids| ids.iter().any(|l| l.iter().any(|n| s.contains(n))));
            if clash {
                continue;
            }
            if let (Some(x), Some((rest, param))) = (d.tet_batches.get_mut(b), tet) {
                for (ids, &n) in x.nodes.iter_mut().zip(&s) {
                    ids[lane] = n;
                }
                set_lane(&mut x.rest, lane, rest);
                set_lane(&mut x.param, lane, param);
            }
            if let (Some(x), Some((rest, param))) = (d.centroid_batches.get_mut(b), centroid) {
                for k in 0..4 {
                    x.nodes[k][lane] = s[k];
                    set_lane(&mut x.rest[k], lane, rest[k]);
                    set_lane(&mut x.param[k], lane, param[k]);
                }
            }
            if let (Some(x), Some((c, param))) = (d.neo_hookean_batches.get_mut(b), &neo_hookean) {
                set_neo_hookean_lane(x, lane, s, c, *param);
            }
            d.tet_fill[b] += 1;
            d.tet_lanes[b][lane] = t;
            found = Some(b * LANES + lane);
            break;
        }
        let position = found.unwrap_or_else(|| {
            let b = d.tet_lanes.len();
            let ids = s.map(|n| [n; LANES]);
            if let Some((rest, param)) = tet {
                d.tet_batches.push(TetBatch {
                    nodes: ids,
                    rest: F::splat(rest),
                    param: F::splat(param),
                });
            }
            if let Some((rest, param)) = centroid {
                d.centroid_batches.push(CentroidBatch {
                    nodes: ids,
                    rest: rest.map(F::splat),
                    param: param.map(F::splat),
                });
            }
            if let Some((c, param)) = &neo_hookean {
                d.neo_hookean_batches.push(neo_hookean_batch(s, c, *param));
            }
            d.tet_lanes.push([t; LANES]);
            d.tet_fill.push(1);
            e.dyn_volume_lambda
                .extend(std::iter::repeat_n(F::ZERO, per_tet));
            b * LANES
        });
        e.tet_slot[t as usize] = e.slot_at(set, position);
        e.count(set, true, 1);
        if found.is_none() {
            self.layout_dyn();
        }
    }

    /// Switches off the lanes of batch `b` of dynamic set `set` that hold no live tet.
    fn switch_off_dyn_tet_lanes(&mut self, set: usize, b: usize) {
        let off = off(self.settings.solver);
        let e = &mut self.edits;
        let serial = e.serial();
        let d = &mut e.sets[set];
        let fill = d.tet_fill[b] as usize;
        let at = |position| slot_at(set, serial, position);
        for (l, &r) in d.tet_lanes[b].iter().enumerate() {
            if dyn_live(&e.tet_slot, r, at, b, l, fill) {
                continue;
            }
            switch_off_tet_lane(
                d.tet_batches.get_mut(b),
                d.centroid_batches.get_mut(b),
                d.neo_hookean_batches.get_mut(b),
                l,
                off,
            );
        }
    }

    /// Adds a distance constraint (a new edge after a cut) to the dynamic batches of the deepest
    /// block holding its nodes, or the serial set when one is past the tree. Returns its record
    /// index.
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`], [`PbdError::InvalidParameter`] for repeated nodes or a
    /// bad rest length, stiffness or compliance.
    pub fn add_distance_constraint(&mut self, c: DistanceConstraint) -> Result<usize, PbdError> {
        let index = self.distance.len();
        self.check_nodes("distance constraint", index, &c.nodes)?;
        check_distance_values(&c)?;
        self.distance.push(c);
        self.edits.distance_slot.push(ConstraintSlot::Removed);
        self.push_dyn_distance(index as u32);
        Ok(index)
    }

    /// Moves distance constraint `c` onto other nodes (rest length, stiffness, compliance kept).
    /// It keeps its lane if it can (see the module docs), else it is projected in a dynamic set
    /// from now on.
    ///
    /// # Errors
    /// [`PbdError::NoSuchElement`] for a bad or removed record, [`PbdError::NodeOutOfRange`],
    /// [`PbdError::InvalidParameter`] for repeated nodes.
    pub fn set_distance_nodes(&mut self, c: usize, nodes: [u32; 2]) -> Result<(), PbdError> {
        let slot = self.live_distance(c)?;
        self.check_nodes("distance constraint", c, &nodes)?;
        self.distance[c].nodes = nodes;
        if let ConstraintSlot::Link { position } = slot {
            let s = nodes.map(|i| [self.rank[i as usize]; LANES]);
            self.edits.link_batches[position as usize].nodes = s;
            return Ok(());
        }
        if let ConstraintSlot::Tree { batch } = slot {
            if self.update_tree_distance_in_place(c, batch as usize) {
                return Ok(());
            }
        }
        let dynamic = self.edits.position(slot);
        if let Some((set, position)) = dynamic {
            if self.update_dyn_distance_in_place(c, set, position) {
                return Ok(());
            }
        }
        self.edits.distance_slot[c] = ConstraintSlot::Removed;
        if let Some((set, position)) = dynamic {
            self.edits.count(set, false, -1);
            self.switch_off_dyn_distance_lanes(set, position / LANES);
        } else if let ConstraintSlot::Tree { batch } = slot {
            self.switch_off_distance_lanes(batch as usize);
        }
        self.push_dyn_distance(c as u32);
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
            slot @ (ConstraintSlot::Dynamic { .. } | ConstraintSlot::Block { .. }) => {
                self.edits.distance_slot[c] = ConstraintSlot::Removed;
                if let Some((set, position)) = self.edits.position(slot) {
                    self.edits.count(set, false, -1);
                    self.switch_off_dyn_distance_lanes(set, position / LANES);
                }
            }
            ConstraintSlot::Link { position } => {
                let p = position as usize;
                self.edits.distance_slot[c] = ConstraintSlot::Removed;
                let e = &mut self.edits;
                e.links.remove(p);
                e.link_batches.remove(p);
                e.link_lambda.remove(p);
                for (k, &r) in e.links.iter().enumerate().skip(p) {
                    e.distance_slot[r as usize] = ConstraintSlot::Link { position: k as u32 };
                }
            }
            ConstraintSlot::Removed => {}
        }
        Ok(())
    }

    /// Adds a link between two nodes (a suture): a distance constraint projected after
    /// everything else of the body in every iteration (links in the order added), so that with
    /// stiffness 1 the linked nodes end each iteration together. Returns its record index.
    ///
    /// # Errors
    /// As [`SoftBody::add_distance_constraint`].
    pub fn add_link_constraint(&mut self, c: DistanceConstraint) -> Result<usize, PbdError> {
        let index = self.distance.len();
        self.check_nodes("link", index, &c.nodes)?;
        check_distance_values(&c)?;
        let s = c.nodes.map(|i| [self.rank[i as usize]; LANES]);
        let param = self.settings.param(c.stiffness, c.compliance);
        self.distance.push(c);
        let e = &mut self.edits;
        e.distance_slot.push(ConstraintSlot::Link {
            position: e.links.len() as u32,
        });
        e.links.push(index as u32);
        e.link_batches.push(DistanceBatch {
            nodes: s,
            rest: F::splat(c.rest_length),
            param: F::splat(param),
        });
        e.link_lambda.push(F::ZERO);
        Ok(index)
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
    /// values are not recomputed). The tet keeps its lane if it can (see the module docs), else
    /// it is projected in a dynamic set from now on.
    ///
    /// # Errors
    /// [`PbdError::NoSuchElement`], [`PbdError::NodeOutOfRange`],
    /// [`PbdError::InvalidParameter`] for repeated nodes.
    pub fn set_tet_nodes(&mut self, t: usize, nodes: [u32; 4]) -> Result<(), PbdError> {
        let slot = self.live_tet(t)?;
        self.check_nodes("tet", t, &nodes)?;
        self.rewrite_tet(t, slot, nodes, None, None);
        Ok(())
    }

    /// Gives live tet `t` (in `slot`) new nodes and, with `rest`, a new rest volume and rest
    /// heights: in place in its lane when it can, else moved into its dynamic set.
    fn rewrite_tet(
        &mut self,
        t: usize,
        slot: ConstraintSlot,
        nodes: [u32; 4],
        rest: Option<(f32, [f32; 4])>,
        neo_hookean: Option<NeoHookeanConstraint>,
    ) {
        self.tets[t] = nodes;
        if let Some(c) = self.neo_hookean.get_mut(t) {
            c.nodes = nodes;
            if let Some(new) = neo_hookean {
                *c = new;
            }
        }
        self.pieces.stale = true;
        self.self_collision.stale = true;
        if let Some((volume, _)) = rest {
            self.edits.tet_rest[t] = volume;
        }
        if let Some(c) = self.tet_volume.get_mut(t) {
            c.nodes = nodes;
            if let Some((volume, _)) = rest {
                c.rest_volume = volume;
            }
        }
        if self.volume_kind == VolumeConstraintKind::Centroid {
            for j in 0..4 {
                let c = &mut self.centroid[4 * t + j];
                c.face = [nodes[(j + 1) & 3], nodes[(j + 2) & 3], nodes[(j + 3) & 3]];
                c.apex = nodes[j];
                if let Some((_, heights)) = rest {
                    c.rest_height = heights[j];
                }
            }
        }
        if let ConstraintSlot::Tree { batch } = slot {
            if self.update_tree_tet_in_place(t, batch as usize) {
                return;
            }
        }
        if let Some((set, position)) = self.edits.position(slot) {
            if self.update_dyn_tet_in_place(t, set, position) {
                return;
            }
        }
        self.retire_tet_slot(t, slot);
        self.push_dyn_tet(t as u32);
    }

    /// Gives tet `t` new nodes **and** a new rest shape: its rest volume (classic), rest
    /// heights (centroid) or neo-Hookean pair (`D_m⁻¹`, `V₀`, compliances) are computed from
    /// `rest`, the rest positions of `nodes` (cm, `f64`),
    /// which must be positively oriented. The way a cut reuses a tet it splits for one of the
    /// pieces, or rebuilds a tet whose node was snapped onto the cut. The tet keeps its lane if
    /// it can (see the module docs), else it is projected in a dynamic set from now on.
    ///
    /// # Errors
    /// [`PbdError::NoSuchElement`], [`PbdError::NodeOutOfRange`],
    /// [`PbdError::InvalidParameter`] for repeated nodes or a rest shape that is not finite
    /// with a positive volume (nothing is changed then).
    pub fn reshape_tet(
        &mut self,
        t: usize,
        nodes: [u32; 4],
        rest: [DVec3; 4],
    ) -> Result<(), PbdError> {
        let slot = self.live_tet(t)?;
        self.check_nodes("tet", t, &nodes)?;
        let shape = rest_shape(&rest)?;
        let neo_hookean = self.neo_hookean_for(nodes, rest)?;
        self.rewrite_tet(t, slot, nodes, Some(shape), neo_hookean);
        Ok(())
    }

    /// Appends a tet on `nodes` with the rest shape `rest` (as [`SoftBody::reshape_tet`]) and
    /// the volume stiffness and compliance of tet `like` (an elastic body: its material's pair
    /// for this rest shape); it is projected in a dynamic set (that
    /// of the deepest block holding its nodes, or the serial set).
    /// Returns its index (the next one of [`SoftBody::tets`]). Masses are not changed: set them
    /// with [`SoftBody::set_node_mass`].
    ///
    /// # Errors
    /// [`PbdError::NoSuchElement`] for a bad `like`, [`PbdError::NodeOutOfRange`],
    /// [`PbdError::InvalidParameter`] for repeated nodes or a bad rest shape (nothing is
    /// changed then).
    pub fn add_tet(
        &mut self,
        like: usize,
        nodes: [u32; 4],
        rest: [DVec3; 4],
    ) -> Result<usize, PbdError> {
        let t = self.tets.len();
        if like >= t {
            return Err(PbdError::NoSuchElement {
                what: "tet",
                index: like,
                count: t,
            });
        }
        if t + 1 >= u32::MAX as usize {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::TetCount,
                value: t as f64,
                expected: "fewer than 2³² tets",
            });
        }
        self.check_nodes("tet", t, &nodes)?;
        let (volume, heights) = rest_shape(&rest)?;
        if let Some(c) = self.neo_hookean_for(nodes, rest)? {
            self.neo_hookean.push(c);
        }
        self.tets.push(nodes);
        self.pieces.stale = true;
        self.self_collision.stale = true;
        self.edits.tet_rest.push(volume);
        self.edits.tet_slot.push(ConstraintSlot::Removed);
        match self.volume_kind {
            VolumeConstraintKind::None => {}
            VolumeConstraintKind::Classic => {
                let c = self.tet_volume[like];
                self.tet_volume.push(TetVolumeConstraint {
                    nodes,
                    rest_volume: volume,
                    ..c
                });
            }
            VolumeConstraintKind::Centroid => {
                for j in 0..4 {
                    let c = self.centroid[4 * like + j];
                    self.centroid.push(CentroidVolumeConstraint {
                        face: [nodes[(j + 1) & 3], nodes[(j + 2) & 3], nodes[(j + 3) & 3]],
                        apex: nodes[j],
                        rest_height: heights[j],
                        ..c
                    });
                }
            }
        }
        self.push_dyn_tet(t as u32);
        Ok(t)
    }

    /// Moves distance constraint `c` onto `nodes` with a new rest length (stiffness and
    /// compliance kept): an edge split by a cut, an edge whose node was snapped. As
    /// [`SoftBody::set_distance_nodes`] (a link stays a link).
    ///
    /// # Errors
    /// [`PbdError::NoSuchElement`] for a bad or removed record, [`PbdError::NodeOutOfRange`],
    /// [`PbdError::InvalidParameter`] for repeated nodes or a bad rest length.
    pub fn reset_distance_constraint(
        &mut self,
        c: usize,
        nodes: [u32; 2],
        rest_length: f32,
    ) -> Result<(), PbdError> {
        self.live_distance(c)?;
        self.check_nodes("distance constraint", c, &nodes)?;
        check_distance_values(&DistanceConstraint {
            rest_length,
            ..self.distance[c]
        })?;
        self.distance[c].rest_length = rest_length;
        if let Some(ConstraintSlot::Link { position }) = self.distance_slot(c) {
            self.edits.link_batches[position as usize].rest = F::splat(rest_length);
        }
        self.set_distance_nodes(c, nodes)
    }

    /// Rest positions of the nodes (cm): the positions the body was built on, appended nodes
    /// their source's, then as [`SoftBody::set_rest_position`] set them. Bookkeeping for the
    /// caller of local edits: the constraints' rest values are set by the edits themselves.
    pub fn rest_positions(&self) -> &[Vec3A] {
        &self.edits.rest_x
    }

    /// Records node `node`'s rest position (see [`SoftBody::rest_positions`]).
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`], [`PbdError::NonFinite`].
    pub fn set_rest_position(&mut self, node: u32, rest: Vec3) -> Result<(), PbdError> {
        self.check_nodes("rest position", node as usize, &[node])?;
        if !rest.is_finite() {
            return Err(PbdError::NonFinite {
                node,
                what: "rest position",
            });
        }
        self.edits.rest_x[node as usize] = rest.into();
        // Self-collision's rest relations are cached per surface build (selfcol.rs).
        self.self_collision.stale = true;
        Ok(())
    }

    /// Sets one node's position, previous position and velocity (a node created on a cut edge,
    /// interpolated from its ends; a node snapped onto a cut). A pinned node keeps velocity 0.
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`], [`PbdError::NonFinite`].
    pub fn set_node_state(
        &mut self,
        node: u32,
        position: Vec3,
        previous: Vec3,
        velocity: Vec3,
    ) -> Result<(), PbdError> {
        self.check_nodes("node state", node as usize, &[node])?;
        for (v, what) in [
            (position, "position"),
            (previous, "previous position"),
            (velocity, "velocity"),
        ] {
            if !v.is_finite() {
                return Err(PbdError::NonFinite { node, what });
            }
        }
        let i = node as usize;
        self.x[i] = position.into();
        self.p[i] = previous.into();
        self.v[i] = if self.w[i] == 0.0 {
            Vec3A::ZERO
        } else {
            velocity.into()
        };
        Ok(())
    }

    fn live_tet(&self, t: usize) -> Result<ConstraintSlot, PbdError> {
        match self.edits.tet_slot.get(t) {
            Some(&s) if s != ConstraintSlot::Removed => Ok(s),
            _ => Err(PbdError::NoSuchElement {
                what: "tet",
                index: t,
                count: self.tets.len(),
            }),
        }
    }

    /// The slots of the caller's `nodes` local to block `h`, `None` when one is outside its
    /// slot range.
    fn local_to<const N: usize>(&self, h: usize, nodes: [u32; N]) -> Option<[u32; N]> {
        let [start, _, end] = self.blocks[h].nodes;
        let s = nodes.map(|i| self.rank[i as usize]);
        s.iter()
            .all(|i| (start..end).contains(i))
            .then(|| s.map(|i| i - start))
    }

    /// The block whose own tree batches (`range`: its `distance` or `tets`) hold batch `batch`:
    /// in post order the blocks' own batch ranges follow one another, so it is the first block
    /// whose range ends past `batch`.
    fn tree_block(&self, batch: usize, range: impl Fn(&Block) -> [u32; 3]) -> usize {
        let post = &self.edits.post;
        let k = post.partition_point(|&h| range(&self.blocks[h])[2] as usize <= batch);
        post.get(k).copied().unwrap_or(0)
    }

    /// Rewrites tree distance constraint `c`'s lanes in tree batch `batch` (its lane and, for
    /// lane 0, the padding lanes that copy it: nodes, rest length, parameter) when its new
    /// nodes lie in the batch's block and no other lane of the batch touches them: a changed
    /// constraint then stays where it is, adding no work to a step. `false` (nothing changed)
    /// otherwise.
    fn update_tree_distance_in_place(&mut self, c: usize, batch: usize) -> bool {
        let d = self.distance[c];
        let Some(s) = self.local_to(self.tree_block(batch, |b| b.distance), d.nodes) else {
            return false;
        };
        let param = self.settings.param(d.stiffness, d.compliance);
        let lanes = self.distance_lanes[batch];
        let b = &mut self.distance_batches[batch];
        let clash = (0..LANES)
            .filter(|&l| lanes[l] != c as u32)
            .any(|l| b.nodes.iter().any(|ids| s.contains(&ids[l])));
        if clash {
            return false;
        }
        for l in (0..LANES).filter(|&l| lanes[l] == c as u32) {
            b.nodes[0][l] = s[0];
            b.nodes[1][l] = s[1];
            set_lane(&mut b.rest, l, d.rest_length);
            set_lane(&mut b.param, l, param);
        }
        true
    }

    /// As [`SoftBody::update_tree_distance_in_place`] for tet `t` (nodes, rest values and
    /// parameters of its volume constraints).
    fn update_tree_tet_in_place(&mut self, t: usize, batch: usize) -> bool {
        let Some(s) = self.local_to(self.tree_block(batch, |b| b.tets), self.tets[t]) else {
            return false;
        };
        let settings = self.settings;
        let lanes = self.tet_lanes[batch];
        let ids = self
            .tet_batches
            .get(batch)
            .map(|x| x.nodes)
            .or_else(|| self.centroid_batches.get(batch).map(|x| x.nodes))
            .or_else(|| self.neo_hookean_batches.get(batch).map(|x| x.nodes));
        if let Some(ids) = ids {
            let clash = (0..LANES)
                .filter(|&l| lanes[l] != t as u32)
                .any(|l| ids.iter().any(|k| s.contains(&k[l])));
            if clash {
                return false;
            }
        }
        for l in (0..LANES).filter(|&l| lanes[l] == t as u32) {
            if let (Some(x), Some(c)) = (self.tet_batches.get_mut(batch), self.tet_volume.get(t)) {
                for (ids, &n) in x.nodes.iter_mut().zip(&s) {
                    ids[l] = n;
                }
                set_lane(&mut x.rest, l, c.rest_volume);
                set_lane(&mut x.param, l, settings.param(c.stiffness, c.compliance));
            }
            if let (Some(x), Some(c)) = (
                self.neo_hookean_batches.get_mut(batch),
                self.neo_hookean.get(t),
            ) {
                set_neo_hookean_lane(x, l, s, c, c.params(settings.substep_dt()));
            }
            if let Some(x) = self.centroid_batches.get_mut(batch) {
                for (k, &n) in s.iter().enumerate() {
                    let c = &self.centroid[4 * t + k];
                    x.nodes[k][l] = n;
                    set_lane(&mut x.rest[k], l, c.rest_height);
                    set_lane(
                        &mut x.param[k],
                        l,
                        settings.param(c.stiffness, c.compliance),
                    );
                }
            }
        }
        true
    }

    /// Rewrites dynamic distance constraint `c`'s lane at `position` of set `set` (its nodes,
    /// rest length and parameter, and the padding lanes that copy it) when its new nodes belong
    /// to the same set and no other lane of its batch touches them: a changed constraint then
    /// keeps its lane instead of leaving a dead one. `false` (nothing changed) otherwise.
    fn update_dyn_distance_in_place(&mut self, c: usize, set: usize, position: usize) -> bool {
        let (b, l) = (position / LANES, position % LANES);
        let d = self.distance[c];
        let (target, s) = self.dyn_place(d.nodes);
        if target != set {
            return false;
        }
        let param = self.settings.param(d.stiffness, d.compliance);
        let e = &mut self.edits.sets[set];
        let fill = e.distance_fill[b] as usize;
        let batch = &mut e.distance_batches[b];
        let clash = (0..fill)
            .filter(|&lane| lane != l)
            .any(|lane| s.contains(&batch.nodes[0][lane]) || s.contains(&batch.nodes[1][lane]));
        if clash {
            return false;
        }
        let padding = if l == 0 { fill..LANES } else { 0..0 };
        for lane in std::iter::once(l).chain(padding) {
            batch.nodes[0][lane] = s[0];
            batch.nodes[1][lane] = s[1];
            set_lane(&mut batch.rest, lane, d.rest_length);
            set_lane(&mut batch.param, lane, param);
        }
        true
    }

    /// As [`SoftBody::update_dyn_distance_in_place`] for tet `t` (nodes and rest values of its
    /// volume constraints).
    fn update_dyn_tet_in_place(&mut self, t: usize, set: usize, position: usize) -> bool {
        let (b, l) = (position / LANES, position % LANES);
        let (target, s) = self.dyn_place(self.tets[t]);
        if target != set {
            return false;
        }
        let tet = self.tet_volume.get(t).map(|c| {
            (
                c.rest_volume,
                self.settings.param(c.stiffness, c.compliance),
            )
        });
        let centroid = (self.volume_kind == VolumeConstraintKind::Centroid).then(|| {
            let c = &self.centroid[4 * t..4 * t + 4];
            (
                [0, 1, 2, 3].map(|j| c[j].rest_height),
                [0, 1, 2, 3].map(|j| self.settings.param(c[j].stiffness, c[j].compliance)),
            )
        });
        let neo_hookean = self
            .neo_hookean
            .get(t)
            .map(|c| (*c, c.params(self.settings.substep_dt())));
        let e = &mut self.edits.sets[set];
        let fill = e.tet_fill[b] as usize;
        let ids = e
            .tet_batches
            .get(b)
            .map(|x| x.nodes)
            .or_else(|| e.centroid_batches.get(b).map(|x| x.nodes))
            .or_else(|| e.neo_hookean_batches.get(b).map(|x| x.nodes));
        if let Some(ids) = ids {
            let clash = (0..fill)
                .filter(|&lane| lane != l)
                .any(|lane| ids.iter().any(|k| s.contains(&k[lane])));
            if clash {
                return false;
            }
        }
        let padding = if l == 0 { fill..LANES } else { 0..0 };
        for lane in std::iter::once(l).chain(padding) {
            if let (Some(x), Some((rest, param))) = (e.tet_batches.get_mut(b), tet) {
                for (ids, &n) in x.nodes.iter_mut().zip(&s) {
                    ids[lane] = n;
                }
                set_lane(&mut x.rest, lane, rest);
                set_lane(&mut x.param, lane, param);
            }
            if let (Some(x), Some(centroid)) = (e.centroid_batches.get_mut(b), centroid) {
                let (rest, param) = centroid;
                for k in 0..4 {
                    x.nodes[k][lane] = s[k];
                    set_lane(&mut x.rest[k], lane, rest[k]);
                    set_lane(&mut x.param[k], lane, param[k]);
                }
            }
            if let (Some(x), Some((c, param))) = (e.neo_hookean_batches.get_mut(b), &neo_hookean) {
                set_neo_hookean_lane(x, lane, s, c, *param);
            }
        }
        true
    }

    /// The neo-Hookean pair of a tet on `nodes` with rest positions `rest`, for an elastic body
    /// (`None` otherwise).
    fn neo_hookean_for(
        &self,
        nodes: [u32; 4],
        rest: [DVec3; 4],
    ) -> Result<Option<NeoHookeanConstraint>, PbdError> {
        let Some((_, mu, lambda)) = self.elastic else {
            return Ok(None);
        };
        match NeoHookeanConstraint::new(nodes, rest, mu, lambda) {
            Some(c) => Ok(Some(c)),
            None => Err(PbdError::InvalidParameter {
                param: PbdParam::RestVolume,
                value: (rest[1] - rest[0])
                    .cross(rest[2] - rest[0])
                    .dot(rest[3] - rest[0])
                    / 6.0,
                expected: "finite and > 0: rest positions positively oriented, not flat",
            }),
        }
    }

    /// Takes tet `t` out of its current slot (its lane switched off).
    fn retire_tet_slot(&mut self, t: usize, slot: ConstraintSlot) {
        self.edits.tet_slot[t] = ConstraintSlot::Removed;
        if let Some((set, position)) = self.edits.position(slot) {
            self.edits.count(set, true, -1);
            self.switch_off_dyn_tet_lanes(set, position / LANES);
        } else if let ConstraintSlot::Tree { batch } = slot {
            self.switch_off_tet_lanes(batch as usize);
        }
    }
}

/// Rest volume and the four rest heights (apex `j` to the centroid of the face opposite it) of
/// a tet with rest positions `r`.
fn rest_shape(r: &[DVec3; 4]) -> Result<(f32, [f32; 4]), PbdError> {
    let [a, b, c, d] = *r;
    let volume = (b - a).cross(c - a).dot(d - a) / 6.0;
    if !(volume.is_finite() && volume > 0.0 && (volume as f32) > 0.0) {
        return Err(PbdError::InvalidParameter {
            param: PbdParam::RestVolume,
            value: volume,
            expected: "finite and > 0: rest positions positively oriented, not flat",
        });
    }
    let heights = [0, 1, 2, 3].map(|j| {
        let face = (r[(j + 1) & 3] + r[(j + 2) & 3] + r[(j + 3) & 3]) / 3.0;
        r[j].distance(face) as f32
    });
    Ok((volume as f32, heights))
}

/// Whether lane `l` of batch `b` (`fill` lanes in use) of a dynamic set, whose slots `at`
/// gives by position, holds a live constraint: its record's slot is this lane, or it is a
/// padding lane copying a live lane 0.
fn dyn_live(
    slots: &[ConstraintSlot],
    r: u32,
    at: impl Fn(usize) -> ConstraintSlot,
    b: usize,
    l: usize,
    fill: usize,
) -> bool {
    let slot = slots[r as usize];
    slot == at(b * LANES + l) || (l >= fill && slot == at(b * LANES))
}

/// The slot of position `position` of dynamic set `set` (`serial`: the serial set's index).
fn slot_at(set: usize, serial: usize, position: usize) -> ConstraintSlot {
    if set == serial {
        ConstraintSlot::Dynamic {
            position: position as u32,
        }
    } else {
        ConstraintSlot::Block {
            block: set as u32,
            position: position as u32,
        }
    }
}

fn check_distance_values(c: &DistanceConstraint) -> Result<(), PbdError> {
    for (param, v, ok) in [
        (
            PbdParam::RestLength,
            c.rest_length,
            c.rest_length.is_finite() && c.rest_length >= 0.0,
        ),
        (
            PbdParam::Stiffness,
            c.stiffness,
            (0.0..=1.0).contains(&c.stiffness),
        ),
        (
            PbdParam::Compliance,
            c.compliance,
            c.compliance.is_finite() && c.compliance >= 0.0,
        ),
    ] {
        if !ok {
            return Err(PbdError::InvalidParameter {
                param,
                value: v as f64,
                expected: "rest length ≥ 0, stiffness in [0, 1], compliance ≥ 0 (all finite)",
            });
        }
    }
    Ok(())
}

/// Switches lane `l` of a classic and/or centroid volume batch off in place: its nodes collapsed
/// onto its first, rest 0, parameter `off`, so the kernels compute no correction for it.
fn switch_off_tet_lane(
    tet: Option<&mut TetBatch>,
    centroid: Option<&mut CentroidBatch>,
    neo_hookean: Option<&mut NeoHookeanBatch>,
    l: usize,
    off: f32,
) {
    if let Some(b) = neo_hookean {
        for k in 1..4 {
            b.nodes[k][l] = b.nodes[0][l];
        }
        for p in &mut b.param {
            set_lane(p, l, off);
        }
    }
    if let Some(b) = tet {
        for k in 1..4 {
            b.nodes[k][l] = b.nodes[0][l];
        }
        set_lane(&mut b.rest, l, 0.0);
        set_lane(&mut b.param, l, off);
    }
    if let Some(b) = centroid {
        for k in 1..4 {
            b.nodes[k][l] = b.nodes[0][l];
        }
        for j in 0..4 {
            set_lane(&mut b.rest[j], l, 0.0);
            set_lane(&mut b.param[j], l, off);
        }
    }
}
