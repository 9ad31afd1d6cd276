//! The collision phase of a simulation step for one pair of surfaces, with everything it keeps
//! between steps: the surfaces' topology, A's hierarchy, B's hierarchy or voxel grid, the scratch
//! space and the contacts.

use glam::Vec3A;
use tissue_bvh::{BuildOptions, BuildWorkspace, Bvh, RefitReport, Triangles};
use tissue_mesh::TriMesh;

use crate::edge_triangle::{edge_against, TrianglePlane};
use crate::{
    apply_impulses, correct_positions, detect_bvh_bvh, detect_bvh_voxels, Bodies, CollideError,
    Contact, ContactParams, CorrectionReport, DetectStats, DetectWorkspace, ImpulseReport,
    ImpulseWorkspace, ResponseParams, Side, Snapshot, Surface, SurfaceView, VoxelGrid,
};

/// How surface B is represented for the broad phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BroadPhase {
    /// A hierarchy over each surface ([`detect_bvh_bvh`]).
    #[default]
    BvhBvh,
    /// A hierarchy over A, a voxel grid over B ([`detect_bvh_voxels`]); meant for a small B.
    BvhVoxels,
}

/// Configuration of a [`Collider`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColliderOptions {
    /// B's representation.
    pub broad_phase: BroadPhase,
    /// A's hierarchy.
    pub bvh_a: BuildOptions,
    /// B's hierarchy (with [`BroadPhase::BvhBvh`]).
    pub bvh_b: BuildOptions,
    /// B's voxel size in cm (with [`BroadPhase::BvhVoxels`]); `None` =
    /// [`VoxelGrid::suggested_cell_size`] at the initial positions.
    pub cell_size: Option<f32>,
    /// What counts as a contact. With `shared_particles`, both meshes index one particle array:
    /// pass the same positions for A and B, and [`Bodies::One`] to the response.
    pub contact: ContactParams,
    /// A hierarchy is rebuilt when a refit leaves its [`Bvh::cost`] above this multiple of its
    /// [`Bvh::build_cost`] (`f32::INFINITY`: never).
    pub rebuild_ratio: f32,
    /// Temporal coherence (cm, ≥ 0; 0 turns it off): a full detection also keeps every pair
    /// within `tolerance + coherence_margin`, and while no particle of A plus no particle of B
    /// has moved more than the margin in all since, [`Collider::detect`] only re-tests those
    /// pairs (no refit, no broad phase). A pair that was farther than `tolerance + margin` can
    /// only have closed by the two moves, so the contact set is exactly a full detection's.
    /// The same bound, per pair (its distance then minus its edge's and its triangle's largest
    /// particle move since), skips re-testing pairs still out of reach. While the particles
    /// move more than the margin per detection (an expander being filled), the kept pairs
    /// could never be re-tested: the full detection then runs at the bare tolerance, and a call
    /// at unchanged positions returns its contacts as they are.
    pub coherence_margin: f32,
}

impl Default for ColliderOptions {
    /// BVH vs BVH with the thesis's equal-area split, leaves of 16 (A) and 2 (B) triangles (the
    /// fastest equal-area pair in the plane-press bench), tolerance 0, rebuild at twice the build
    /// cost.
    fn default() -> Self {
        ColliderOptions {
            broad_phase: BroadPhase::BvhBvh,
            bvh_a: BuildOptions {
                leaf_size: 16,
                ..BuildOptions::default()
            },
            bvh_b: BuildOptions {
                leaf_size: 2,
                ..BuildOptions::default()
            },
            cell_size: None,
            contact: ContactParams::default(),
            rebuild_ratio: 2.0,
            coherence_margin: 0.0,
        }
    }
}

#[derive(Debug, Clone)]
enum Broad {
    Bvh(Bvh),
    Voxels(VoxelGrid),
}

/// What [`Collider::update`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateReport {
    /// A's refit.
    pub refit_a: RefitReport,
    /// B's refit (`None` with a voxel grid, which is re-binned instead).
    pub refit_b: Option<RefitReport>,
    /// Hierarchies rebuilt because their cost passed [`ColliderOptions::rebuild_ratio`].
    pub rebuilds: u32,
}

/// What [`Collider::separate`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SeparationReport {
    /// Rounds of detect-then-correct run.
    pub iterations: u32,
    /// Corrections applied over all rounds.
    pub corrected: u32,
    /// Edges still through a triangle after the last round (0 unless only fixed particles are
    /// involved or `max_iterations` was too small).
    pub remaining: u32,
}

/// Collision handling between two surfaces with separate particle arrays, for one simulation
/// step at a time. The step's collision phase (SPEC A.2 phase 3) is [`Collider::detect`] then
/// [`Collider::apply_impulses`]; after the positions are integrated (phase 4),
/// [`Collider::separate`] leaves no edge through a triangle.
///
/// Nothing allocates in a step once the buffers have grown to the largest contact set seen,
/// except a hierarchy rebuild (rare, see [`ColliderOptions::rebuild_ratio`]).
#[derive(Debug, Clone)]
pub struct Collider {
    a: Surface,
    b: Surface,
    bvh_a: Bvh,
    broad_b: Broad,
    options: ColliderOptions,
    ws: DetectWorkspace,
    build_ws: BuildWorkspace,
    impulse_ws: ImpulseWorkspace,
    contacts: Vec<Contact>,
    stats: DetectStats,
    coherence: Coherence,
}

/// Temporal coherence: the pairs within `tolerance + margin` at the last full detection, sorted
/// by key, the positions then, and the re-test's scratch.
#[derive(Debug, Clone, Default)]
struct Coherence {
    near: Vec<Contact>,
    anchor_a: Vec<Vec3A>,
    anchor_b: Vec<Vec3A>,
    /// How far each particle has moved from its anchor (as of the last [`Coherence::moved`]).
    moved_a: Vec<f32>,
    moved_b: Vec<f32>,
    /// Whether the anchor positions are set.
    anchored: bool,
    /// Whether `near` holds the margin's pairs at the anchor positions.
    valid: bool,
    /// Detections since the anchor (re-tests included).
    calls: u32,
    /// The positions of the last successful detection, whose contacts [`Collider::contacts`]
    /// holds (`last_valid`).
    last_a: Vec<Vec3A>,
    last_b: Vec<Vec3A>,
    last_valid: bool,
    /// Per-thread contacts of a parallel re-test, concatenated in order.
    chunks: Vec<Vec<Contact>>,
    planes: RetestPlanes,
}

impl Coherence {
    /// How far the particles have moved since the last full detection: the largest move of a
    /// particle of A plus that of B (`f32::INFINITY` before the first, or when a surface's
    /// particle count changed). Records each particle's move, which [`Coherence::retest`] uses
    /// to skip pairs that cannot have come within reach.
    fn moved(&mut self, pos_a: &[Vec3A], pos_b: &[Vec3A]) -> f32 {
        if !self.anchored
            || pos_a.len() != self.anchor_a.len()
            || pos_b.len() != self.anchor_b.len()
        {
            return f32::INFINITY;
        }
        moves(pos_a, &self.anchor_a, &mut self.moved_a)
            + moves(pos_b, &self.anchor_b, &mut self.moved_b)
    }

    /// Anchors the positions of a full detection (every particle's move is then 0); `near` is
    /// valid for re-tests when the detection kept the margin's pairs.
    fn anchor(&mut self, pos_a: &[Vec3A], pos_b: &[Vec3A], near_valid: bool) {
        for (anchor, moved, pos) in [
            (&mut self.anchor_a, &mut self.moved_a, pos_a),
            (&mut self.anchor_b, &mut self.moved_b, pos_b),
        ] {
            anchor.clear();
            anchor.extend_from_slice(pos);
            moved.clear();
            moved.resize(pos.len(), 0.0);
        }
        self.anchored = true;
        self.valid = near_valid;
        self.calls = 0;
    }

    /// The contacts among `near` at the views' positions, into `out`.
    fn retest(
        &mut self,
        a: &SurfaceView<'_>,
        b: &SurfaceView<'_>,
        tolerance: f32,
        out: &mut Vec<Contact>,
    ) {
        self.planes.prepare(&self.near, a, b);
        let moved = Moved {
            a: &self.moved_a,
            b: &self.moved_b,
        };
        retest_parallel(
            &self.near,
            a,
            b,
            &self.planes,
            moved,
            tolerance,
            &mut self.chunks,
            out,
        );
    }
}

/// Triangle planes prepared once per re-test for the triangles its pairs name.
#[derive(Debug, Clone, Default)]
struct RetestPlanes {
    slot: [Vec<u32>; 2],
    stamp: [Vec<u32>; 2],
    current: u32,
    planes: Vec<TrianglePlane>,
}

impl RetestPlanes {
    /// Prepares the plane of every triangle `near` names, at the current positions.
    fn prepare(&mut self, near: &[Contact], a: &SurfaceView<'_>, b: &SurfaceView<'_>) {
        for (k, view) in [a, b].into_iter().enumerate() {
            let n = view.surface().triangle_count();
            if self.stamp[k].len() != n {
                self.stamp[k] = vec![0; n];
                self.slot[k] = vec![0; n];
            }
        }
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            self.stamp.iter_mut().for_each(|s| s.fill(0));
            self.current = 1;
        }
        self.planes.clear();
        for c in near {
            let (k, view) = match c.edge_side {
                Side::A => (1, b),
                Side::B => (0, a),
            };
            let t = c.triangle as usize;
            if self.stamp[k][t] != self.current {
                self.stamp[k][t] = self.current;
                self.slot[k][t] = self.planes.len() as u32;
                let [x, y, z] = view.corners(c.triangle);
                self.planes.push(TrianglePlane::new(x, y, z));
            }
        }
    }

    /// The plane of the triangle contact `c` names (prepared).
    #[inline]
    fn of(&self, c: &Contact) -> &TrianglePlane {
        let k = match c.edge_side {
            Side::A => 1,
            Side::B => 0,
        };
        &self.planes[self.slot[k][c.triangle as usize] as usize]
    }
}

impl Collider {
    /// Surfaces A and B at their meshes' positions.
    ///
    /// # Errors
    /// [`CollideError::InvalidParameter`] for bad options,
    /// [`CollideError::Bvh`] when a hierarchy cannot be built, the voxel grid's errors.
    pub fn new(a: &TriMesh, b: &TriMesh, options: &ColliderOptions) -> Result<Self, CollideError> {
        options.contact.validate()?;
        if !(options.coherence_margin.is_finite() && options.coherence_margin >= 0.0) {
            return Err(CollideError::InvalidParameter {
                name: "coherence_margin",
                value: options.coherence_margin,
                expected: "finite and at least 0 (cm)",
            });
        }
        if options.rebuild_ratio.is_nan() || options.rebuild_ratio <= 1.0 {
            return Err(CollideError::InvalidParameter {
                name: "rebuild_ratio",
                value: options.rebuild_ratio,
                expected: "greater than 1 (f32::INFINITY: never rebuild)",
            });
        }
        let (sa, sb) = (Surface::new(a), Surface::new(b));
        let pa: Vec<Vec3A> = a.positions().iter().map(|&p| p.into()).collect();
        let pb: Vec<Vec3A> = b.positions().iter().map(|&p| p.into()).collect();
        let mut build_ws = BuildWorkspace::new();
        let va = sa.view(Side::A, &pa)?;
        let vb = sb.view(Side::B, &pb)?;
        let bvh_a =
            Bvh::build_with(va.triangles(), &options.bvh_a, &mut build_ws).map_err(|source| {
                CollideError::Bvh {
                    side: Side::A,
                    source,
                }
            })?;
        let broad_b = match options.broad_phase {
            BroadPhase::BvhBvh => Broad::Bvh(
                Bvh::build_with(vb.triangles(), &options.bvh_b, &mut build_ws).map_err(
                    |source| CollideError::Bvh {
                        side: Side::B,
                        source,
                    },
                )?,
            ),
            BroadPhase::BvhVoxels => {
                let h = options
                    .cell_size
                    .unwrap_or_else(|| VoxelGrid::suggested_cell_size(&vb));
                Broad::Voxels(VoxelGrid::new(&vb, h)?)
            }
        };
        Ok(Collider {
            a: sa,
            b: sb,
            bvh_a,
            broad_b,
            options: *options,
            ws: DetectWorkspace::new(),
            build_ws,
            impulse_ws: ImpulseWorkspace::new(),
            contacts: Vec::new(),
            stats: DetectStats::default(),
            coherence: Coherence::default(),
        })
    }

    /// The surface of `side`.
    pub fn surface(&self, side: Side) -> &Surface {
        match side {
            Side::A => &self.a,
            Side::B => &self.b,
        }
    }

    /// A's hierarchy.
    pub fn bvh_a(&self) -> &Bvh {
        &self.bvh_a
    }

    /// B's hierarchy, if it has one.
    pub fn bvh_b(&self) -> Option<&Bvh> {
        match &self.broad_b {
            Broad::Bvh(b) => Some(b),
            Broad::Voxels(_) => None,
        }
    }

    /// B's voxel grid, if it has one.
    pub fn voxels_b(&self) -> Option<&VoxelGrid> {
        match &self.broad_b {
            Broad::Voxels(g) => Some(g),
            Broad::Bvh(_) => None,
        }
    }

    /// The options.
    pub fn options(&self) -> &ColliderOptions {
        &self.options
    }

    /// The contacts of the last detection, sorted by [`Contact::key`].
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }

    /// Counts from the last detection.
    pub fn stats(&self) -> DetectStats {
        self.stats
    }

    /// Brings A's hierarchy and B's hierarchy or grid to the given positions (refit, or rebuild
    /// when the cost ratio is passed; re-bin the grid).
    ///
    /// # Errors
    /// [`CollideError::ParticleCount`], [`CollideError::Bvh`] (e.g. a non-finite position),
    /// the grid's errors.
    pub fn update(
        &mut self,
        pos_a: &[Vec3A],
        pos_b: &[Vec3A],
    ) -> Result<UpdateReport, CollideError> {
        let va = self.a.view(Side::A, pos_a)?;
        let vb = self.b.view(Side::B, pos_b)?;
        let ratio = self.options.rebuild_ratio;
        let mut rebuilds = 0;
        let mut refit = |bvh: &mut Bvh,
                         side: Side,
                         tris: &Triangles<'_>|
         -> Result<RefitReport, CollideError> {
            let err = |source| CollideError::Bvh { side, source };
            let report = bvh.refit(tris).map_err(err)?;
            if report.cost > ratio * bvh.build_cost() {
                bvh.rebuild(tris, &mut self.build_ws).map_err(err)?;
                rebuilds += 1;
            }
            Ok(report)
        };
        let refit_a = refit(&mut self.bvh_a, Side::A, va.triangles())?;
        let refit_b = match &mut self.broad_b {
            Broad::Bvh(bvh) => Some(refit(bvh, Side::B, vb.triangles())?),
            Broad::Voxels(grid) => {
                grid.update(&vb)?;
                None
            }
        };
        Ok(UpdateReport {
            refit_a,
            refit_b,
            rebuilds,
        })
    }

    /// [`Collider::update`], then detection by the configured broad phase; returns the contacts
    /// (also kept for [`Collider::apply_impulses`]).
    ///
    /// # Errors
    /// As [`Collider::update`].
    pub fn detect(&mut self, pos_a: &[Vec3A], pos_b: &[Vec3A]) -> Result<&[Contact], CollideError> {
        let c = &mut self.coherence;
        if c.last_valid && same_bits(pos_a, &c.last_a) && same_bits(pos_b, &c.last_b) {
            // Nothing moved since the last detection (a step's detection after a separation
            // that corrected nothing): its contacts stand.
            return Ok(&self.contacts);
        }
        c.last_valid = false;
        self.detect_moved(pos_a, pos_b)?;
        let c = &mut self.coherence;
        for (last, pos) in [(&mut c.last_a, pos_a), (&mut c.last_b, pos_b)] {
            last.clear();
            last.extend_from_slice(pos);
        }
        c.last_valid = true;
        Ok(&self.contacts)
    }

    /// [`Collider::detect`] at positions that differ from the last detection's.
    fn detect_moved(&mut self, pos_a: &[Vec3A], pos_b: &[Vec3A]) -> Result<(), CollideError> {
        let margin = self.options.coherence_margin;
        let tolerance = self.options.contact.tolerance;
        let moved = if margin > 0.0 {
            self.coherence.moved(pos_a, pos_b)
        } else {
            f32::INFINITY
        };
        self.coherence.calls += 1;
        if self.coherence.valid && moved <= margin {
            let _span = tracing::trace_span!("retest", pairs = self.coherence.near.len()).entered();
            let va = self.a.view(Side::A, pos_a)?;
            let vb = self.b.view(Side::B, pos_b)?;
            self.coherence
                .retest(&va, &vb, tolerance, &mut self.contacts);
            let pairs = self.coherence.near.len() as u32;
            self.stats = DetectStats {
                candidates: pairs,
                triangle_pairs: 0,
                edge_tests: pairs,
                contacts: self.contacts.len() as u32,
            };
            return Ok(());
        }
        self.update(pos_a, pos_b)?;
        let va = self.a.view(Side::A, pos_a)?;
        let vb = self.b.view(Side::B, pos_b)?;
        // Keep the margin's pairs only if they can be re-tested next time: when the particles
        // moved more than the margin per detection since the last full one, the next call would
        // fail the coherence test anyway, and a detection at the bare tolerance is cheaper. The
        // contacts are the same either way.
        let keep_margin = margin > 0.0 && moved <= margin * self.coherence.calls as f32;
        let params = ContactParams {
            tolerance: if keep_margin {
                tolerance + margin
            } else {
                tolerance
            },
            ..self.options.contact
        };
        let out = if keep_margin {
            &mut self.coherence.near
        } else {
            &mut self.contacts
        };
        self.stats = match &self.broad_b {
            Broad::Bvh(bvh_b) => {
                detect_bvh_bvh(&va, &self.bvh_a, &vb, bvh_b, &params, &mut self.ws, out)?
            }
            Broad::Voxels(grid) => {
                detect_bvh_voxels(&va, &self.bvh_a, &vb, grid, &params, &mut self.ws, out)?
            }
        };
        if margin > 0.0 {
            let c = &mut self.coherence;
            c.anchor(pos_a, pos_b, keep_margin);
            if keep_margin {
                c.retest(&va, &vb, tolerance, &mut self.contacts);
                self.stats.contacts = self.contacts.len() as u32;
            }
        }
        Ok(())
    }

    /// Impulses for the contacts of the last detection ([`apply_impulses`]); `velocities` holds
    /// the particles' velocities.
    ///
    /// # Errors
    /// As [`apply_impulses`].
    pub fn apply_impulses(
        &mut self,
        velocities: &mut Bodies<'_>,
        params: &ResponseParams,
    ) -> Result<ImpulseReport, CollideError> {
        apply_impulses(&self.contacts, velocities, params, &mut self.impulse_ws)
    }

    /// Detects at the current `positions` and corrects every crossing ([`correct_positions`],
    /// back to the side each edge had at the `previous` positions, the start of the step),
    /// repeating until no edge passes through a triangle or `params.max_iterations` rounds have
    /// run. Leaves [`Collider::contacts`] as detected at the final positions.
    ///
    /// # Errors
    /// As [`Collider::detect`] and [`correct_positions`].
    pub fn separate(
        &mut self,
        positions: &mut Bodies<'_>,
        previous: Option<Snapshot<'_>>,
        params: &ResponseParams,
    ) -> Result<SeparationReport, CollideError> {
        params.validate()?;
        let _span = tracing::trace_span!("separate").entered();
        let mut report = SeparationReport::default();
        loop {
            let crossing = self
                .detect(positions.state(Side::A), positions.state(Side::B))?
                .iter()
                .filter(|c| c.is_crossing())
                .count() as u32;
            report.remaining = crossing;
            if crossing == 0 || report.iterations == params.max_iterations {
                return Ok(report);
            }
            let c: CorrectionReport =
                correct_positions(&self.contacts, positions, previous, params)?;
            report.iterations += 1;
            report.corrected += c.corrected;
            if c.corrected == 0 {
                // Only fixed particles left: nothing more can move.
                return Ok(report);
            }
        }
    }
}

/// Whether `a` and `b` hold the same positions, bit for bit.
fn same_bits(a: &[Vec3A], b: &[Vec3A]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.x.to_bits() == y.x.to_bits()
                && x.y.to_bits() == y.y.to_bits()
                && x.z.to_bits() == y.z.to_bits()
        })
}

/// The distances between `now[i]` and `then[i]`, into `moved` (resized to match); returns the
/// largest.
fn moves(now: &[Vec3A], then: &[Vec3A], moved: &mut Vec<f32>) -> f32 {
    moved.resize(now.len(), 0.0);
    let mut largest = 0.0f32;
    for ((m, a), b) in moved.iter_mut().zip(now).zip(then) {
        *m = (*a - *b).length();
        largest = largest.max(*m);
    }
    largest
}

/// Each particle's move since the last full detection, per side.
#[derive(Debug, Clone, Copy)]
struct Moved<'a> {
    a: &'a [f32],
    b: &'a [f32],
}

impl Moved<'_> {
    /// A lower bound of how near pair `c` can be now, from its distance at the full detection
    /// (0 when it crossed): a segment (triangle) whose corners each moved at most `m` has every
    /// point within `m` of where it was, so the distance fell by at most the largest move of
    /// the edge's particles plus that of the triangle's.
    #[inline]
    fn distance_bound(&self, c: &Contact) -> f32 {
        let (edge, tri) = match c.edge_side {
            Side::A => (self.a, self.b),
            Side::B => (self.b, self.a),
        };
        let [i, j] = c.edge_particles;
        let [x, y, z] = c.triangle_particles;
        let edge_move = edge[i as usize].max(edge[j as usize]);
        let tri_move = tri[x as usize].max(tri[y as usize]).max(tri[z as usize]);
        (-c.depth).max(0.0) - edge_move - tri_move
    }
}

/// Pairs per thread below which a re-test stays on the calling thread.
#[cfg(feature = "parallel")]
const RETEST_PARALLEL_MIN: usize = 1024;

/// [`retest`] in consecutive chunks, one per rayon thread when the pairs are many enough
/// (feature `parallel`); the chunks' contacts are concatenated in order, so the result is the
/// serial one.
#[allow(clippy::too_many_arguments)]
fn retest_parallel(
    near: &[Contact],
    a: &SurfaceView<'_>,
    b: &SurfaceView<'_>,
    planes: &RetestPlanes,
    moved: Moved<'_>,
    tolerance: f32,
    chunks: &mut Vec<Vec<Contact>>,
    out: &mut Vec<Contact>,
) {
    #[cfg(feature = "parallel")]
    {
        let k = rayon::current_num_threads()
            .min(near.len() / RETEST_PARALLEL_MIN)
            .max(1);
        if k > 1 {
            use rayon::prelude::*;
            if chunks.len() < k {
                chunks.resize_with(k, Vec::new);
            }
            let per = near.len().div_ceil(k);
            chunks[..k]
                .par_iter_mut()
                .zip(near.par_chunks(per))
                .for_each(|(chunk, pairs)| retest(pairs, a, b, planes, moved, tolerance, chunk));
            out.clear();
            for chunk in &chunks[..k] {
                out.extend_from_slice(chunk);
            }
            return;
        }
    }
    let _ = chunks;
    retest(near, a, b, planes, moved, tolerance, out);
}

/// The contacts among the pairs `near` at the current positions, with the narrow phase's own
/// test (the arithmetic of [`edge_triangle`] and of every detection, on the triangle's prepared
/// plane), in `near`'s (key) order.
fn retest(
    near: &[Contact],
    a: &SurfaceView<'_>,
    b: &SurfaceView<'_>,
    planes: &RetestPlanes,
    moved: Moved<'_>,
    tolerance: f32,
    out: &mut Vec<Contact>,
) {
    out.clear();
    for c in near {
        let ev = match c.edge_side {
            Side::A => a,
            Side::B => b,
        };
        let [i, j] = c.edge_particles;
        let (p, q) = (ev.positions()[i as usize], ev.positions()[j as usize]);
        let plane = planes.of(c);
        // Still out of reach by the bound (with room for the test's rounding, which the reach
        // itself allows 10⁻⁶ of the scale): the test would find nothing.
        let scale = plane.longest().max((q - p).length());
        if moved.distance_bound(c) > 1.001 * tolerance + 1e-5 * scale {
            continue;
        }
        if let Some(hit) =
            edge_against(plane, p, q, plane.distance(p), plane.distance(q), tolerance)
        {
            out.push(Contact {
                s: hit.s,
                barycentric: hit.barycentric,
                normal: hit.normal.into(),
                depth: hit.depth,
                ..*c
            });
        }
    }
}
