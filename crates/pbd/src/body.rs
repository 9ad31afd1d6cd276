//! The soft body: node arrays, constraints by kind block by block, construction and access.

use glam::{DVec3, Vec3, Vec3A, Vec4};
use tissue_mesh::{TetMesh, ZERO_VOLUME_TOLERANCE};

use crate::colour::{colour_order, greedy_colours};
use crate::constraint::{
    set_neo_hookean_lane, CentroidBatch, DistanceBatch, NeoHookeanBatch, TetBatch, F, LANES,
};
use crate::partition::{bisection_order, spare_tree, Tree};
use crate::{
    AttachmentId, CentroidVolumeConstraint, DistanceConstraint, Elastic, Floor, Material,
    NeoHookeanConstraint, PbdError, PbdParam, Solver, StepSettings, TetVolumeConstraint,
    VolumeConstraintKind,
};

/// A tetrahedral soft body simulated by position-based dynamics.
///
/// Invariants (established by the constructors, kept by every method):
/// - all public node arrays have one entry per node; `inverse_masses[i] == 0` exactly when node
///   `i` is pinned, attached or carries no tet; otherwise it is `1 / masses[i]`;
/// - every constraint's nodes are `< node_count`; constraints of a kind are stored block by block
///   of the domain decomposition (`crate::partition`, post order) and colour by colour within a
///   block; as built, no two constraints (for volumes: no two tets) of one colour of a block
///   share a node, and edits keep the lanes of every batch free of shared nodes;
/// - after edits (`crate::edit`) every record is in one place, its [`crate::ConstraintSlot`]: a
///   lane of its tree batch (possibly rewritten in place), the dynamic batches of the deepest
///   block holding its slots, the serial set (a node past the tree), the links, or nowhere
///   (removed); the batches of a block, tree or dynamic, touch only that block's slots;
/// - the public node arrays are in the caller's order; the projection works on a copy in solver
///   order, made at the start of every step. Solver order has *slots*: the block tree's slots
///   (each leaf its real nodes, then spare slots for nodes added by edits, `crate::partition`),
///   then a tail of nodes appended when their leaf had no spare left. `rank[i]` is node `i`'s
///   slot, `order[s]` the node in slot `s` or `SPARE` for an empty slot (`q`, `qw` zero there,
///   never touched by a step); `order`, `q` and `qw` have one entry per slot;
/// - the hot batches (8 constraints each, see `crate::constraint`) mirror the public records,
///   with the per-constraint parameter of the current [`StepSettings`].
#[derive(Debug, Clone)]
pub struct SoftBody {
    /// This body's identity ([`SoftBody::id`]).
    id: BodyId,
    pub(crate) x: Vec<Vec3A>,
    pub(crate) p: Vec<Vec3A>,
    pub(crate) v: Vec<Vec3A>,
    pub(crate) mass: Vec<f32>,
    pub(crate) w: Vec<f32>,

    /// Solver order of the nodes: `order[s]` is the caller's index of the node in solver slot `s`
    /// ([`SPARE`] for an empty slot).
    pub(crate) order: Vec<u32>,
    /// Its inverse: `rank[i]` is the solver slot of the caller's node `i`.
    pub(crate) rank: Vec<u32>,
    /// Predicted positions `p` (xyz) with the inverse mass (w), in solver order, for the
    /// projection; and the inverse masses alone, also in solver order.
    pub(crate) q: Vec<Vec4>,
    pub(crate) qw: Vec<f32>,
    /// The block tree (heap numbering), see [`Block`]; its node ranges are slot ranges.
    pub(crate) blocks: Vec<Block>,
    /// Most colours in any block: distances, tets.
    pub(crate) colours: (usize, usize),

    pub(crate) distance: Vec<DistanceConstraint>,
    pub(crate) distance_batches: Vec<DistanceBatch>,
    /// The record (index into `distance`) of each lane of each batch.
    pub(crate) distance_lanes: Vec<[u32; LANES]>,
    /// One multiplier per lane (XPBD).
    pub(crate) distance_lambda: Vec<F>,

    /// Tets in projection order (the order of the volume constraints), caller's node indices.
    pub(crate) tets: Vec<[u32; 4]>,
    pub(crate) volume_kind: VolumeConstraintKind,
    pub(crate) tet_volume: Vec<TetVolumeConstraint>,
    pub(crate) tet_batches: Vec<TetBatch>,
    pub(crate) centroid: Vec<CentroidVolumeConstraint>,
    pub(crate) centroid_batches: Vec<CentroidBatch>,
    /// The tet (index into `tets`) of each lane of each volume batch.
    pub(crate) tet_lanes: Vec<[u32; LANES]>,
    /// One multiplier per lane and volume constraint (1 or 4 per tet; 2 for the neo-Hookean
    /// pair).
    pub(crate) volume_lambda: Vec<F>,
    /// The hyperelastic material ([`Material::elastic`]), its energy's `(μ, λ)` (dyn/cm²), and
    /// its constraint pairs (one per tet, in tet order) and their batches (by `tet_lanes`).
    pub(crate) elastic: Option<(Elastic, f64, f64)>,
    pub(crate) neo_hookean: Vec<NeoHookeanConstraint>,
    pub(crate) neo_hookean_batches: Vec<NeoHookeanBatch>,

    pub(crate) floor: Option<Floor>,
    pub(crate) attachments: crate::attachment::Attachments,
    /// Colliders, tools and this step's contacts (`contact.rs`).
    pub(crate) collision: crate::contact::ContactState,
    pub(crate) settings: StepSettings,
    pub(crate) step_count: u64,
    rest_volume: f64,
    /// Topology edits (`edit.rs`): where each record is projected, the dynamic set, rest
    /// volumes and density for local mass rebuilds.
    pub(crate) edits: crate::edit::Edits,
    /// The connected pieces and their volume constraints (`pieces.rs`).
    pub(crate) pieces: crate::pieces::Pieces,
    /// Self-collision of the surface (`selfcol.rs`).
    pub(crate) self_collision: crate::selfcol::SelfState,
}

/// The identity of a [`SoftBody`] ([`SoftBody::id`]): a process-unique number given at
/// construction, kept by clones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyId(u64);

impl BodyId {
    /// A number no body built before in this process has.
    fn next() -> Self {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        BodyId(NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
    }

    /// The number.
    pub fn get(self) -> u64 {
        self.0
    }
}

impl std::fmt::Display for BodyId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "body #{}", self.0)
    }
}

/// `order` of an empty solver slot.
pub(crate) const SPARE: u32 = u32::MAX;

/// One block of the domain decomposition (see [`crate::partition`]). Its batches are stored in
/// post order, so the batches of its subtree are one contiguous range: `distance` and `tets`
/// are `[subtree start, own start, end)` into the batch arrays. `dyn_distance` and `dyn_tets`
/// are the same for the multipliers of the blocks' dynamic batches (`edit.rs`), in batches.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Block {
    /// Solver slot range `[start, mid, end)`; the children own `[start, mid)` and `[mid, end)`.
    pub nodes: [u32; 3],
    pub distance: [u32; 3],
    pub tets: [u32; 3],
    pub dyn_distance: [u32; 3],
    pub dyn_tets: [u32; 3],
}

/// How the constraints of one kind are laid out.
struct Layout {
    /// Item index of each record, in projection order.
    records: Vec<usize>,
    /// Record index of each lane of each batch (padding lanes repeat lane 0).
    lanes: Vec<[u32; LANES]>,
    /// Batch range `[start, end)` of each block, by heap index.
    ranges: Vec<[u32; 2]>,
    /// The most colours in any block.
    colours: usize,
}

/// Lays out `items` (solver node indices) block by block in post order; within a block, greedily
/// coloured and in the given order within a colour; each colour cut into batches of [`LANES`].
fn arrange<const N: usize>(tree: &Tree, post: &[usize], items: &[[u32; N]]) -> Layout {
    let mut by_block: Vec<Vec<usize>> = vec![Vec::new(); tree.block_count()];
    for (i, item) in items.iter().enumerate() {
        by_block[tree.block_of(item)].push(i);
    }
    let mut out = Layout {
        records: Vec::with_capacity(items.len()),
        lanes: Vec::with_capacity(items.len() / LANES + post.len()),
        ranges: vec![[0u32; 2]; tree.block_count()],
        colours: 0,
    };
    for &h in post {
        let [start, _, end] = tree.range(h);
        let local: Vec<[u32; N]> = by_block[h]
            .iter()
            .map(|&i| items[i].map(|n| n - start as u32))
            .collect();
        let (colours, count) = greedy_colours(end - start, &local);
        let (within, offsets) = colour_order(&colours, count);
        out.colours = out.colours.max(count as usize);
        out.ranges[h][0] = out.lanes.len() as u32;
        for colour in offsets.windows(2) {
            for batch in within[colour[0] as usize..colour[1] as usize].chunks(LANES) {
                let first = out.records.len() as u32;
                out.records.extend(batch.iter().map(|&k| by_block[h][k]));
                let mut lanes = [first; LANES];
                for (l, lane) in lanes.iter_mut().enumerate().take(batch.len()) {
                    *lane = first + l as u32;
                }
                out.lanes.push(lanes);
            }
        }
        out.ranges[h][1] = out.lanes.len() as u32;
    }
    out
}

fn sixfold_volume(t: [Vec3; 4]) -> f64 {
    let [a, b, c, d] = t.map(|p| p.as_dvec3());
    (b - a).cross(c - a).dot(d - a)
}

impl SoftBody {
    /// A body on a validated tet mesh.
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] for a bad material.
    pub fn new(mesh: &TetMesh, material: &Material) -> Result<Self, PbdError> {
        Self::from_tets(mesh.positions(), mesh.tets(), material)
    }

    /// A body on raw positions (cm) and positively oriented tets: masses from eq. (1) (a quarter
    /// of each tet's mass `density × volume` to each of its nodes), one distance constraint per
    /// unique tet edge, the volume constraints of `material.volume` or, with
    /// [`Material::elastic`], one stable neo-Hookean pair per tet instead (the initial settings
    /// are then [`StepSettings::material`], else [`StepSettings::default`]).
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] for a bad material, [`PbdError::NonFinite`] for a bad
    /// position, [`PbdError::NodeOutOfRange`] for a tet index past the nodes,
    /// [`PbdError::DegenerateTet`] for a flat, inverted or repeated-node tet.
    pub fn from_tets(
        positions: &[Vec3],
        tets: &[[u32; 4]],
        material: &Material,
    ) -> Result<Self, PbdError> {
        material.validate()?;
        let n = positions.len();
        // Solver slots: the nodes and the spares of the block tree (crate::partition).
        let spare = if n == 0 || tets.is_empty() {
            None
        } else {
            spare_tree(n)
        };
        let Some((tree, slot)) = spare else {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::NodeTetCount,
                value: n as f64,
                expected: "at least one node and one tet, fewer than 2³¹ nodes",
            });
        };
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(PbdError::NonFinite {
                node: i as u32,
                what: "position",
            });
        }
        let mut mass = vec![0.0f64; n];
        for (t, tet) in tets.iter().enumerate() {
            if let Some(&node) = tet.iter().find(|&&i| i as usize >= n) {
                return Err(PbdError::NodeOutOfRange {
                    element: "tet",
                    index: t,
                    node,
                    count: n,
                });
            }
            let q = tet.map(|i| positions[i as usize]);
            let six = sixfold_volume(q);
            let mut longest = 0.0f64;
            for a in 0..4 {
                for b in a + 1..4 {
                    longest = longest.max(q[a].as_dvec3().distance(q[b].as_dvec3()));
                }
            }
            if six.is_nan() || six <= ZERO_VOLUME_TOLERANCE * longest.powi(3) {
                return Err(PbdError::DegenerateTet {
                    tet: t,
                    volume: six / 6.0,
                });
            }
            for &i in tet {
                mass[i as usize] += material.density as f64 * six / 24.0;
            }
        }
        let rest_volume = tets
            .iter()
            .map(|t| sixfold_volume(t.map(|i| positions[i as usize])))
            .sum::<f64>()
            / 6.0;

        // Solver order of the nodes and the block tree over it (crate::partition): the j-th
        // node of the bisection order in slot `slot[j]`.
        let mut order = vec![SPARE; tree.node_count];
        let mut rank = vec![0u32; n];
        for (&o, &s) in bisection_order(positions).iter().zip(&slot) {
            rank[o as usize] = s;
            order[s as usize] = o;
        }
        let post = tree.post_order();

        // Unique edges in solver indices, sorted by node for locality, then laid out by block.
        let mut edges: Vec<[u32; 2]> = Vec::with_capacity(tets.len() * 6);
        for t in tets {
            let t = t.map(|i| rank[i as usize]);
            for a in 0..4 {
                for b in a + 1..4 {
                    edges.push([t[a].min(t[b]), t[a].max(t[b])]);
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let dl = arrange(&tree, &post, &edges);

        // Tets (solver indices, orientation kept) sorted by their smallest node, laid out by block.
        let mut sorted: Vec<[u32; 4]> = tets.iter().map(|t| t.map(|i| rank[i as usize])).collect();
        sorted.sort_by_key(|t| {
            let mut k = *t;
            k.sort_unstable();
            k
        });
        let tl = arrange(&tree, &post, &sorted);

        let blocks: Vec<Block> = (0..tree.block_count())
            .map(|h| {
                let [start, mid, end] = tree.range(h).map(|i| i as u32);
                // Post order: a subtree's batches start where its leftmost leaf's do.
                let mut leaf = h;
                while !tree.is_leaf(leaf) {
                    leaf = 2 * leaf + 1;
                }
                Block {
                    nodes: [start, mid, end],
                    distance: [dl.ranges[leaf][0], dl.ranges[h][0], dl.ranges[h][1]],
                    tets: [tl.ranges[leaf][0], tl.ranges[h][0], tl.ranges[h][1]],
                    dyn_distance: [0; 3],
                    dyn_tets: [0; 3],
                }
            })
            .collect();
        // The node range start of each batch's block: batches index that range.
        let batch_base = |ranges: &[[u32; 2]], count: usize| {
            let mut base = vec![0u32; count];
            for (h, r) in ranges.iter().enumerate() {
                base[r[0] as usize..r[1] as usize].fill(blocks[h].nodes[0]);
            }
            base
        };
        let original = |i: u32| order[i as usize];

        // Records in projection order, caller's node indices.
        let distance: Vec<DistanceConstraint> = dl
            .records
            .iter()
            .map(|&e| {
                let [a, b] = edges[e].map(original);
                DistanceConstraint {
                    nodes: [a, b],
                    rest_length: positions[a as usize].distance(positions[b as usize]),
                    stiffness: material.distance_stiffness,
                    compliance: material.distance_compliance,
                }
            })
            .collect();
        let distance_batches: Vec<DistanceBatch> = dl
            .lanes
            .iter()
            .zip(batch_base(&dl.ranges, dl.lanes.len()))
            .map(|(lanes, base)| DistanceBatch {
                nodes: [0, 1].map(|k| lanes.map(|r| edges[dl.records[r as usize]][k] - base)),
                rest: F::from_lanes(lanes.map(|r| distance[r as usize].rest_length)),
                param: F::ZERO,
            })
            .collect();
        let tets: Vec<[u32; 4]> = tl
            .records
            .iter()
            .map(|&t| sorted[t].map(original))
            .collect();
        let tet_nodes: Vec<[[u32; LANES]; 4]> = tl
            .lanes
            .iter()
            .zip(batch_base(&tl.ranges, tl.lanes.len()))
            .map(|(lanes, base)| {
                [0, 1, 2, 3].map(|k| lanes.map(|r| sorted[tl.records[r as usize]][k] - base))
            })
            .collect();

        let (mut tet_volume, mut centroid) = (Vec::new(), Vec::new());
        let (mut tet_batches, mut centroid_batches) = (Vec::new(), Vec::new());
        let mut volume_lambda = Vec::new();
        let elastic = material.elastic.map(|e| {
            let (mu, lambda) = e.energy_parameters();
            (e, mu, lambda)
        });
        let volume_kind = if elastic.is_some() {
            VolumeConstraintKind::None
        } else {
            material.volume
        };
        let (mut neo_hookean, mut neo_hookean_batches) = (Vec::new(), Vec::new());
        if let Some((_, mu, lambda)) = elastic {
            for (k, t) in tets.iter().enumerate() {
                let rest = t.map(|i| positions[i as usize].as_dvec3());
                let Some(c) = NeoHookeanConstraint::new(*t, rest, mu, lambda) else {
                    return Err(PbdError::DegenerateTet {
                        tet: k,
                        volume: sixfold_volume(t.map(|i| positions[i as usize])) / 6.0,
                    });
                };
                neo_hookean.push(c);
            }
            neo_hookean_batches = tet_nodes
                .iter()
                .zip(&tl.lanes)
                .map(|(&nodes, lanes)| {
                    let mut b = crate::constraint::neo_hookean_batch(
                        [0; 4],
                        &neo_hookean[lanes[0] as usize],
                        [0.0; 2],
                    );
                    for (l, &r) in lanes.iter().enumerate() {
                        let s = [0, 1, 2, 3].map(|k| nodes[k][l]);
                        set_neo_hookean_lane(&mut b, l, s, &neo_hookean[r as usize], [0.0; 2]);
                    }
                    b
                })
                .collect();
            volume_lambda = vec![F::ZERO; 2 * tl.lanes.len()];
        }
        match volume_kind {
            VolumeConstraintKind::None => {}
            VolumeConstraintKind::Classic => {
                tet_volume = tets
                    .iter()
                    .map(|t| TetVolumeConstraint {
                        nodes: *t,
                        rest_volume: (sixfold_volume(t.map(|i| positions[i as usize])) / 6.0)
                            as f32,
                        stiffness: material.volume_stiffness,
                        compliance: material.volume_compliance,
                    })
                    .collect();
                tet_batches = tet_nodes
                    .iter()
                    .zip(&tl.lanes)
                    .map(|(&nodes, lanes)| TetBatch {
                        nodes,
                        rest: F::from_lanes(lanes.map(|r| tet_volume[r as usize].rest_volume)),
                        param: F::ZERO,
                    })
                    .collect();
                volume_lambda = vec![F::ZERO; tl.lanes.len()];
            }
            VolumeConstraintKind::Centroid => {
                for t in &tets {
                    for j in 0..4 {
                        let face = [t[(j + 1) & 3], t[(j + 2) & 3], t[(j + 3) & 3]];
                        let c = face.iter().map(|&i| positions[i as usize]).sum::<Vec3>() / 3.0;
                        centroid.push(CentroidVolumeConstraint {
                            face,
                            apex: t[j],
                            rest_height: positions[t[j] as usize].distance(c),
                            stiffness: material.volume_stiffness,
                            compliance: material.volume_compliance,
                        });
                    }
                }
                centroid_batches = tet_nodes
                    .iter()
                    .zip(&tl.lanes)
                    .map(|(&nodes, lanes)| CentroidBatch {
                        nodes,
                        rest: [0, 1, 2, 3].map(|j| {
                            F::from_lanes(lanes.map(|r| centroid[4 * r as usize + j].rest_height))
                        }),
                        param: [F::ZERO; 4],
                    })
                    .collect();
                volume_lambda = vec![F::ZERO; 4 * tl.lanes.len()];
            }
        }
        let mass: Vec<f32> = mass.iter().map(|&m| m as f32).collect();
        let w = mass
            .iter()
            .map(|&m| if m > 0.0 { 1.0 / m } else { 0.0 })
            .collect();
        let x: Vec<Vec3A> = positions.iter().map(|&p| p.into()).collect();
        let mut body = Self {
            id: BodyId::next(),
            p: x.clone(),
            v: vec![Vec3A::ZERO; n],
            x,
            mass,
            w,
            order,
            rank,
            q: vec![Vec4::ZERO; tree.node_count],
            qw: vec![0.0; tree.node_count],
            blocks,
            colours: (dl.colours, tl.colours),
            distance_lambda: vec![F::ZERO; distance_batches.len()],
            distance_batches,
            distance_lanes: dl.lanes,
            distance,
            tets,
            volume_kind,
            tet_volume,
            tet_batches,
            centroid,
            centroid_batches,
            tet_lanes: tl.lanes,
            volume_lambda,
            elastic,
            neo_hookean,
            neo_hookean_batches,
            floor: None,
            attachments: Default::default(),
            collision: Default::default(),
            self_collision: Default::default(),
            settings: StepSettings::default(),
            step_count: 0,
            rest_volume,
            edits: Default::default(),
            pieces: crate::pieces::Pieces::new(
                material.hold_piece_volumes,
                material.volume_stiffness,
            ),
        };
        body.edits = crate::edit::Edits::new(&body, material.density, tree, post);
        body.set_settings(if body.elastic.is_some() {
            StepSettings::material()
        } else {
            StepSettings::default()
        })?;
        Ok(body)
    }

    /// Sets how steps are taken and refreshes the constraints' per-step parameters.
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] for `dt ≤ 0`, `iterations == 0`, damping outside `[0, 1]`
    /// or non-finite gravity, and for a solver other than [`Solver::Xpbd`] on an elastic body
    /// ([`PbdParam::Solver`]).
    pub fn set_settings(&mut self, settings: StepSettings) -> Result<(), PbdError> {
        settings.validate()?;
        if self.elastic.is_some() && settings.solver != Solver::Xpbd {
            return Err(PbdError::InvalidParameter {
                param: PbdParam::Solver,
                value: settings.solver as u8 as f64,
                expected: "Solver::Xpbd for an elastic material (its constraints have compliances, not stiffnesses): use StepSettings::material() or set solver: Solver::Xpbd",
            });
        }
        self.settings = settings;
        let s = &self.settings;
        for (b, lanes) in self.distance_batches.iter_mut().zip(&self.distance_lanes) {
            b.param = F::from_lanes(lanes.map(|r| {
                let c = &self.distance[r as usize];
                s.param(c.stiffness, c.compliance)
            }));
        }
        for (b, lanes) in self.tet_batches.iter_mut().zip(&self.tet_lanes) {
            b.param = F::from_lanes(lanes.map(|r| {
                let c = &self.tet_volume[r as usize];
                s.param(c.stiffness, c.compliance)
            }));
        }
        for (b, lanes) in self.centroid_batches.iter_mut().zip(&self.tet_lanes) {
            b.param = [0, 1, 2, 3].map(|j| {
                F::from_lanes(lanes.map(|r| {
                    let c = &self.centroid[4 * r as usize + j];
                    s.param(c.stiffness, c.compliance)
                }))
            });
        }
        let h = s.substep_dt();
        for (b, lanes) in self.neo_hookean_batches.iter_mut().zip(&self.tet_lanes) {
            let p = lanes.map(|r| self.neo_hookean[r as usize].params(h));
            b.param = [0, 1].map(|j| F::from_lanes(p.map(|x| x[j])));
        }
        self.refresh_edit_params();
        // Projected in the K iterations of the last substep only (pieces.rs).
        let iterations = settings.iterations as f64;
        self.pieces.per_iteration =
            1.0 - ((1.0 - self.pieces.stiffness as f64).powf(1.0 / iterations)) as f32;
        Ok(())
    }

    /// The current step settings.
    pub fn settings(&self) -> &StepSettings {
        &self.settings
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.x.len()
    }
    /// Node positions `x` (cm).
    pub fn positions(&self) -> &[Vec3A] {
        &self.x
    }
    /// Node positions at the start of the last step (after [`SoftBody::step`]; the initial ones
    /// before).
    pub fn previous_positions(&self) -> &[Vec3A] {
        &self.p
    }
    /// Node velocities (cm/s).
    pub fn velocities(&self) -> &[Vec3A] {
        &self.v
    }
    /// Node masses (g), from eq. (1); kept when a node is pinned.
    pub fn masses(&self) -> &[f32] {
        &self.mass
    }
    /// Inverse masses (1/g); 0 = pinned, attached or without tets.
    pub fn inverse_masses(&self) -> &[f32] {
        &self.w
    }
    /// Tets in the body's projection order (block by block, by colour within a block).
    pub fn tets(&self) -> &[[u32; 4]] {
        &self.tets
    }
    /// Distance constraints, one per unique tet edge, in projection order.
    pub fn distance_constraints(&self) -> &[DistanceConstraint] {
        &self.distance
    }
    /// Classic volume constraints (empty unless the material asked for them), in tet order.
    pub fn tet_volume_constraints(&self) -> &[TetVolumeConstraint] {
        &self.tet_volume
    }
    /// Centroid volume constraints, 4 per tet (apex = tet node 0..3), in tet order.
    pub fn centroid_volume_constraints(&self) -> &[CentroidVolumeConstraint] {
        &self.centroid
    }
    /// The stable neo-Hookean constraint pairs, one per tet in tet order (empty unless the
    /// material is [`Material::elastic`]).
    pub fn neo_hookean_constraints(&self) -> &[NeoHookeanConstraint] {
        &self.neo_hookean
    }
    /// The hyperelastic material the body was built with ([`Material::elastic`]).
    pub fn elastic(&self) -> Option<Elastic> {
        self.elastic.map(|e| e.0)
    }
    /// The volume constraint kind ([`VolumeConstraintKind::None`] for an elastic material:
    /// its neo-Hookean pairs hold the volume).
    pub fn volume_kind(&self) -> VolumeConstraintKind {
        self.volume_kind
    }
    /// Number of colours of the distance constraints and of the tets (volume constraints): the
    /// most in any block of the domain decomposition (each block is coloured on its own).
    pub fn colour_counts(&self) -> (usize, usize) {
        self.colours
    }
    /// Number of blocks of the domain decomposition (`2^d − 1`, fixed by the node count).
    pub fn block_count(&self) -> usize {
        self.blocks.len()
    }
    /// Steps taken since construction.
    pub fn step_count(&self) -> u64 {
        self.step_count
    }

    fn check_len(&self, what: &'static str, got: usize) -> Result<(), PbdError> {
        if got == self.x.len() {
            Ok(())
        } else {
            Err(PbdError::LengthMismatch {
                what,
                got,
                expected: self.x.len(),
            })
        }
    }

    fn check_node(&self, element: &'static str, node: u32) -> Result<(), PbdError> {
        if (node as usize) < self.x.len() {
            Ok(())
        } else {
            Err(PbdError::NodeOutOfRange {
                element,
                index: node as usize,
                node,
                count: self.x.len(),
            })
        }
    }

    /// Moves the nodes (e.g. a deformed start); the rest state is unchanged.
    ///
    /// # Errors
    /// [`PbdError::LengthMismatch`], [`PbdError::NonFinite`].
    pub fn set_positions(&mut self, positions: &[Vec3]) -> Result<(), PbdError> {
        self.check_len("positions", positions.len())?;
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(PbdError::NonFinite {
                node: i as u32,
                what: "position",
            });
        }
        for (x, &q) in self.x.iter_mut().zip(positions) {
            *x = q.into();
        }
        self.p.copy_from_slice(&self.x);
        Ok(())
    }

    /// Sets the velocities (cm/s); pinned and attached nodes keep zero.
    ///
    /// # Errors
    /// [`PbdError::LengthMismatch`], [`PbdError::NonFinite`].
    pub fn set_velocities(&mut self, velocities: &[Vec3]) -> Result<(), PbdError> {
        self.check_len("velocities", velocities.len())?;
        if let Some(i) = velocities.iter().position(|p| !p.is_finite()) {
            return Err(PbdError::NonFinite {
                node: i as u32,
                what: "velocity",
            });
        }
        for ((v, &u), &w) in self.v.iter_mut().zip(velocities).zip(&self.w) {
            *v = if w > 0.0 { u.into() } else { Vec3A::ZERO };
        }
        Ok(())
    }

    /// Pins a node where it is (inverse mass 0, velocity 0).
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`].
    pub fn pin(&mut self, node: u32) -> Result<(), PbdError> {
        self.check_node("pin", node)?;
        self.w[node as usize] = 0.0;
        self.v[node as usize] = Vec3A::ZERO;
        Ok(())
    }

    /// Frees a pinned or attached node again. Its attachments are removed and their ids become
    /// stale; the ids of other attachments stay valid.
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`].
    pub fn unpin(&mut self, node: u32) -> Result<(), PbdError> {
        self.check_node("pin", node)?;
        let m = self.mass[node as usize];
        self.w[node as usize] = if m > 0.0 { 1.0 / m } else { 0.0 };
        self.attachments.remove_node(node);
        Ok(())
    }

    /// Attaches a node to a kinematic point: the node becomes pinned and is moved to `target` at
    /// the start of every step (its velocity follows). Returns the attachment's id for
    /// [`SoftBody::set_attachment_target`], valid until the node is freed ([`SoftBody::unpin`]).
    ///
    /// # Errors
    /// [`PbdError::NodeOutOfRange`], [`PbdError::NonFinite`].
    pub fn attach(&mut self, node: u32, target: Vec3) -> Result<AttachmentId, PbdError> {
        self.check_node("attachment", node)?;
        if !target.is_finite() {
            return Err(PbdError::NonFinite {
                node,
                what: "position",
            });
        }
        self.pin(node)?;
        Ok(self.attachments.insert(node, target.into()))
    }

    /// Moves an attachment's target; the node follows in the next step.
    ///
    /// # Errors
    /// [`PbdError::NoSuchAttachment`] (also for the id of a freed node's attachment),
    /// [`PbdError::NonFinite`].
    pub fn set_attachment_target(
        &mut self,
        id: AttachmentId,
        target: Vec3,
    ) -> Result<(), PbdError> {
        let a = self.attachments.get_mut(id)?;
        if !target.is_finite() {
            return Err(PbdError::NonFinite {
                node: a.0,
                what: "position",
            });
        }
        a.1 = target.into();
        Ok(())
    }

    /// Sets or removes the static floor.
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] for an axis past 2 or a non-finite height.
    pub fn set_floor(&mut self, floor: Option<Floor>) -> Result<(), PbdError> {
        if let Some(f) = floor {
            if f.axis > 2 {
                return Err(PbdError::InvalidParameter {
                    param: PbdParam::FloorAxis,
                    value: f.axis as f64,
                    expected: "0, 1 or 2",
                });
            }
            if !f.height.is_finite() {
                return Err(PbdError::InvalidParameter {
                    param: PbdParam::FloorHeight,
                    value: f.height as f64,
                    expected: "finite",
                });
            }
        }
        self.floor = floor;
        Ok(())
    }

    /// This body's identity: unique in the process among bodies built by [`SoftBody::new`] or
    /// [`SoftBody::from_tets`], even from the same mesh. A clone keeps it: a clone is a snapshot
    /// of the same body, so that a body and the state kept beside it (e.g. a
    /// `tissue_surgery::Surgery`) can be cloned together and go on together.
    pub fn id(&self) -> BodyId {
        self.id
    }

    /// Total mass (g), in `f64`.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().map(|&m| m as f64).sum()
    }
    /// Current volume, the sum of the tets' signed volumes (cm³), in `f64`.
    pub fn volume(&self) -> f64 {
        let x = &self.x;
        self.tets
            .iter()
            .map(|t| sixfold_volume(t.map(|i| Vec3::from(x[i as usize]))))
            .sum::<f64>()
            / 6.0
    }
    /// Volume at construction (cm³).
    pub fn rest_volume(&self) -> f64 {
        self.rest_volume
    }
    /// `Σ mᵢ vᵢ` (g·cm/s).
    pub fn linear_momentum(&self) -> DVec3 {
        self.mass
            .iter()
            .zip(&self.v)
            .map(|(&m, v)| m as f64 * v.as_dvec3())
            .sum()
    }
    /// `Σ xᵢ × mᵢ vᵢ` about the origin (g·cm²/s).
    pub fn angular_momentum(&self) -> DVec3 {
        self.mass
            .iter()
            .zip(&self.v)
            .zip(&self.x)
            .map(|((&m, v), x)| x.as_dvec3().cross(m as f64 * v.as_dvec3()))
            .sum()
    }
    /// `½ Σ mᵢ |vᵢ|²` (erg).
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self
            .mass
            .iter()
            .zip(&self.v)
            .map(|(&m, v)| m as f64 * v.as_dvec3().length_squared())
            .sum::<f64>()
    }
}
