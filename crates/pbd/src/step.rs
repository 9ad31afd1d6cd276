//! One step, in the order of Müller et al.: external forces → prediction → attachments →
//! contact generation → `K` × (distance, volume, floor projection, contacts) → velocity and
//! position update → rigid-mode damping.

use crate::body::{Block, SPARE};
use crate::constraint::{
    gather, project_centroid, project_distance, project_neo_hookean, project_tet_volume, scatter,
    CentroidBatch, DistanceBatch, NeoHookeanBatch, TetBatch, F, LANES, P4,
};
use crate::edit::DynSet;
use crate::{PbdError, SoftBody, Solver, VolumeConstraintKind};
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DMat3, DVec3, Vec3A, Vec4};

/// Projects `batches` once, in order (Gauss–Seidel; the 4 lanes of a batch share no node), on
/// `p` (the node range of their block). `L` multipliers per batch.
#[inline(always)]
fn project_batches<B, const N: usize, const L: usize>(
    batches: &[B],
    lambda: &mut [F],
    p: &mut [Vec4],
    nodes: impl Fn(&B) -> &[[u32; LANES]; N],
    kernel: impl Fn(&mut [P4; N], &[F; N], &B, &mut [F]),
) {
    for (b, lam) in batches.iter().zip(lambda.chunks_exact_mut(L)) {
        let ids = nodes(b);
        let (mut q, mut w) = ([P4::ZERO; N], [F::ZERO; N]);
        for k in 0..N {
            (q[k], w[k]) = gather(p, &ids[k]);
        }
        kernel(&mut q, &w, b, lam);
        for k in 0..N {
            scatter(p, &ids[k], q[k], w[k]);
        }
    }
}

/// How many times its mass a pinned node weighs in the rigid-mode damping's
/// fit of the body's rigid motion ([`SoftBody::step`], step 5).
const HELD_WEIGHT: f32 = 1e3;

/// One Gauss–Seidel sweep over the block tree (see [`crate::partition`]).
struct Sweep<'a> {
    blocks: &'a [Block],
    distance: &'a [DistanceBatch],
    tet: &'a [TetBatch],
    centroid: &'a [CentroidBatch],
    neo_hookean: &'a [NeoHookeanBatch],
    /// The blocks' dynamic batches (`edit.rs`), by heap index.
    dynamic: &'a [DynSet],
    kind: TetKind,
    parallel: bool,
}

/// What the body projects per tet and edge: the volume constraints of a
/// [`VolumeConstraintKind`] with the distance constraints, or (an elastic material) the
/// neo-Hookean pairs alone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum TetKind {
    Volume(VolumeConstraintKind),
    /// The pairs, with `1 − β` of their over-relaxation
    /// ([`crate::StepSettings::over_relaxation`]).
    NeoHookean {
        keep: f32,
    },
}

impl TetKind {
    /// Multipliers per tet.
    pub(crate) fn per_tet(self) -> usize {
        match self {
            TetKind::Volume(VolumeConstraintKind::None) => 0,
            TetKind::Volume(VolumeConstraintKind::Classic) => 1,
            TetKind::Volume(VolumeConstraintKind::Centroid) => 4,
            TetKind::NeoHookean { .. } => 2,
        }
    }
}

/// The multipliers of a subtree's batches: tree distances, tree volumes, dynamic distances,
/// dynamic volumes.
struct Lambdas<'a> {
    d: &'a mut [F],
    v: &'a mut [F],
    dd: &'a mut [F],
    dv: &'a mut [F],
}

impl<'a> Lambdas<'a> {
    /// Splits off the multipliers of the left and the right child's subtrees (`l`, `r`) of
    /// block `b`; `self` keeps the block's own.
    fn split(self, b: &Block, l: &Block, r: &Block, per_tet: usize) -> [Self; 3] {
        fn cut(x: &mut [F], b: [u32; 3], l: [u32; 3], r: [u32; 3], per: usize) -> [&mut [F]; 3] {
            let (left, rest) = x.split_at_mut((l[2] - b[0]) as usize * per);
            let (right, own) = rest.split_at_mut((r[2] - l[2]) as usize * per);
            [left, right, own]
        }
        let [dl, dr, d] = cut(self.d, b.distance, l.distance, r.distance, 1);
        let [vl, vr, v] = cut(self.v, b.tets, l.tets, r.tets, per_tet);
        let [ddl, ddr, dd] = cut(self.dd, b.dyn_distance, l.dyn_distance, r.dyn_distance, 1);
        let [dvl, dvr, dv] = cut(self.dv, b.dyn_tets, l.dyn_tets, r.dyn_tets, per_tet);
        [
            Lambdas {
                d: dl,
                v: vl,
                dd: ddl,
                dv: dvl,
            },
            Lambdas {
                d: dr,
                v: vr,
                dd: ddr,
                dv: dvr,
            },
            Lambdas { d, v, dd, dv },
        ]
    }
}

impl Sweep<'_> {
    fn per_tet(&self) -> usize {
        self.kind.per_tet()
    }

    /// Projects the constraints of block `h`'s subtree: both children (at the same time in
    /// parallel mode: they touch disjoint node ranges), then the block's own constraints. `p` is
    /// the block's slot range, `lam` the multipliers of its subtree's batches.
    fn block<const XPBD: bool>(&self, h: usize, p: &mut [Vec4], lam: Lambdas<'_>) {
        let b = self.blocks[h];
        let lam = if 2 * h + 1 < self.blocks.len() {
            let (l, r) = (self.blocks[2 * h + 1], self.blocks[2 * h + 2]);
            let (pl, pr) = p.split_at_mut((b.nodes[1] - b.nodes[0]) as usize);
            let [laml, lamr, lam] = lam.split(&b, &l, &r, self.per_tet());
            if self.parallel {
                rayon::join(
                    || self.block::<XPBD>(2 * h + 1, pl, laml),
                    || self.block::<XPBD>(2 * h + 2, pr, lamr),
                );
            } else {
                self.block::<XPBD>(2 * h + 1, pl, laml);
                self.block::<XPBD>(2 * h + 2, pr, lamr);
            }
            lam
        } else {
            lam
        };
        if self.parallel && h == 0 && 2 * h + 1 < self.blocks.len() {
            // The root's own constraints are the one serial phase of an iteration. Meanwhile
            // another worker, if one took the second job, waits here awake instead of going to
            // sleep, so that it takes its half of the next iteration without a wake-up (tens of
            // µs). Run by this thread itself, the second job finds `done` set and returns.
            let done = AtomicBool::new(false);
            rayon::join(
                || {
                    self.own::<XPBD>(h, p, lam);
                    done.store(true, Ordering::Release);
                },
                || {
                    let mut spins = 0u32;
                    while !done.load(Ordering::Acquire) {
                        if spins < 4096 {
                            spins += 1;
                            std::hint::spin_loop();
                        } else {
                            std::thread::yield_now();
                        }
                    }
                },
            );
        } else {
            self.own::<XPBD>(h, p, lam);
        }
    }

    /// Projects block `h`'s own constraints: its tree batches (distances, then volumes), then
    /// its dynamic batches (volumes, then distances, as the serial set).
    fn own<const XPBD: bool>(&self, h: usize, p: &mut [Vec4], lam: Lambdas<'_>) {
        let b = &self.blocks[h];
        let [_, ds, de] = b.distance.map(|i| i as usize);
        let [_, ts, te] = b.tets.map(|i| i as usize);
        // (Only the batches of the body's volume kind exist.)
        project_set::<XPBD>(
            self.kind,
            &self.distance[ds..de],
            self.tet.get(ts..te).unwrap_or_default(),
            self.centroid.get(ts..te).unwrap_or_default(),
            self.neo_hookean.get(ts..te).unwrap_or_default(),
            lam.d,
            lam.v,
            p,
        );
        let dynamic = &self.dynamic[h];
        if !(dynamic.distance_lanes.is_empty() && dynamic.tet_lanes.is_empty()) {
            // Volumes, then distances: the same routine, one kind at a time.
            project_set::<XPBD>(
                self.kind,
                &[],
                &dynamic.tet_batches,
                &dynamic.centroid_batches,
                &dynamic.neo_hookean_batches,
                &mut [],
                lam.dv,
                p,
            );
            project_set::<XPBD>(
                self.kind,
                &dynamic.distance_batches,
                &[],
                &[],
                &[],
                lam.dd,
                &mut [],
                p,
            );
        }
    }
}

/// Projects distance batches, then the volume batches of `kind`, on `p` with their multipliers
/// `ld`, `lv`; for [`TetKind::NeoHookean`] the neo-Hookean pairs alone (the distances are not
/// projected). Not inlined: one copy for the tree's and the dynamic batches keeps the plain
/// step's code small and fast.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn project_set<const XPBD: bool>(
    kind: TetKind,
    distance: &[DistanceBatch],
    tet: &[TetBatch],
    centroid: &[CentroidBatch],
    neo_hookean: &[NeoHookeanBatch],
    ld: &mut [F],
    lv: &mut [F],
    p: &mut [Vec4],
) {
    match kind {
        TetKind::Volume(volume) => {
            project_batches::<_, 2, 1>(distance, ld, p, |b| &b.nodes, project_distance::<XPBD>);
            match volume {
                VolumeConstraintKind::None => {}
                VolumeConstraintKind::Classic => {
                    project_batches::<_, 4, 1>(tet, lv, p, |b| &b.nodes, project_tet_volume::<XPBD>)
                }
                VolumeConstraintKind::Centroid => project_batches::<_, 4, 4>(
                    centroid,
                    lv,
                    p,
                    |b| &b.nodes,
                    project_centroid::<XPBD>,
                ),
            }
        }
        TetKind::NeoHookean { keep } => {
            // Through a closure, so that the kernel is inlined into the loop (passed as the
            // function itself it went through a call shim that was not inlined).
            let keep = F::splat(keep);
            project_batches::<_, 4, 2>(
                neo_hookean,
                lv,
                p,
                |b| &b.nodes,
                |q, w, b, l| project_neo_hookean(q, w, b, l, keep),
            )
        }
    }
}

impl SoftBody {
    /// Advances the body by one step of the current [`crate::StepSettings`]: `n` substeps of
    /// `h = Δt/n` (one when `n = 1`; before each, every tool is moved `1/(substeps left)` of
    /// the way to the pose the host set, so that it sweeps its path in `n` parts), each:
    /// 1. `v += h·g` for free nodes (`w·f_ext` with `f_ext = m g`);
    /// 2. `p = x + h·v`; attached nodes take their targets; contacts with colliders and tools are
    ///    generated for the predictions (see [`crate::Contact`]);
    /// 3. `K` times: distance and volume constraints (an elastic body: its neo-Hookean pairs)
    ///    block by block, then the floor (Gauss–Seidel
    ///    in the order of the crate docs, in solver node order), then the contacts with friction;
    ///    XPBD multipliers start at 0 each step;
    /// 4. `v = (1 − c)(p − x − s)/h` (`c` the linear damping per substep, default 0; `s` the
    ///    pieces' volume correction of the last substep, positional only: see `pieces.rs`),
    ///    `x = p` (the old `x` becomes [`SoftBody::previous_positions`]);
    /// 5. after the last substep, rigid-mode damping of the free nodes (about the rigid motion
    ///    the pinned nodes allow for an elastic body: they weigh `HELD_WEIGHT` = 1000 times
    ///    their mass in its fit; attached nodes, and every held node of the other materials,
    ///    have no part in it).
    ///
    /// With substeps, [`SoftBody::contacts`] and [`SoftBody::previous_positions`] are those of
    /// the last substep, and nodes the constraints pushed into a collider or tool are put back
    /// on its surface after the last substep only (the next substep's contacts catch them).
    ///
    /// Allocates nothing.
    ///
    /// # Errors
    /// [`PbdError::Diverged`] when a node became non-finite (the state is kept as it is).
    pub fn step(&mut self) -> Result<(), PbdError> {
        let _span = tracing::debug_span!("pbd_step", step = self.step_count).entered();
        let n = self.settings.substeps;
        // Momentum before the step, for the holders' reaction (force.rs; only with attachments).
        let held_from = self.holding_momentum();
        if n > 1 {
            self.collision.save_tool_targets();
        }
        if self.pieces.enabled && self.pieces.stale {
            // After a topology edit (allocates; a plain step does not).
            self.pieces
                .rebuild(&self.tets, &self.edits.tet_rest, &self.rank, self.q.len());
        }
        for j in 0..n {
            if n > 1 {
                self.collision.substep_tool_poses(n - j);
            }
            self.collision.last_substep = j + 1 == n;
            self.substep(j == 0, j + 1 == n);
        }
        self.finish_holding(held_from);
        let step = self.step_count;
        self.step_count += 1;
        if let Some(i) = self
            .x
            .iter()
            .zip(&self.v)
            .position(|(x, v)| !(x.is_finite() && v.is_finite()))
        {
            return Err(PbdError::Diverged {
                step,
                node: i as u32,
            });
        }
        Ok(())
    }

    /// One substep of `Δt/n` (the whole step when `n = 1`): steps 1–5 of [`SoftBody::step`].
    fn substep(&mut self, first: bool, last: bool) {
        let s = self.settings;
        let (dt, g) = (s.substep_dt(), Vec3A::from(s.gravity));
        // 1–2, straight into solver order (crate::partition): the projection works on `q`.
        // Over the slots in use: empty ones (SPARE) stay as they are, zero, never touched.
        for r in self.edits.used_slots(self.q.len()) {
            for ((q, qw), &o) in self.q[r.clone()]
                .iter_mut()
                .zip(&mut self.qw[r.clone()])
                .zip(&self.order[r])
            {
                debug_assert_ne!(o, SPARE);
                let (o, w) = (o as usize, self.w[o as usize]);
                if w > 0.0 {
                    self.v[o] += dt * g;
                }
                *qw = w;
                *q = (self.x[o] + dt * self.v[o]).extend(w);
            }
        }
        for (node, target) in self.attachments.iter() {
            let s = self.rank[node as usize] as usize;
            self.q[s] = target.extend(self.qw[s]);
        }
        // Contacts with colliders and tools for the predictions (contact.rs).
        self.generate_contacts(dt, first);
        // Self-contacts of the surface (selfcol.rs).
        self.generate_self_contacts(first);
        if self.pieces.enabled && last {
            // The pieces' volumes are projected in the step's last substep (contact.rs): the
            // nodes the colliders, tools and attachments hold in it.
            let rank = &self.rank;
            self.pieces.hold(
                &self.qw,
                (self.collision.contacts.iter().map(|c| c.node))
                    .chain(self.attachments.iter().map(|a| a.0))
                    .map(|i| rank[i as usize]),
            );
            if let Some(f) = self.floor {
                // And those on the floor (predicted at or under it): the floor holds them.
                self.pieces.hold_on_floor(&self.q, f.axis, f.height);
            }
        }
        let xpbd = s.solver == Solver::Xpbd;
        if xpbd {
            self.distance_lambda.fill(F::ZERO);
            self.volume_lambda.fill(F::ZERO);
            self.edits.dyn_distance_lambda.fill(F::ZERO);
            self.edits.dyn_volume_lambda.fill(F::ZERO);
            self.edits.link_lambda.fill(F::ZERO);
        }
        {
            let _span = tracing::trace_span!("project", iterations = s.iterations).entered();
            for _ in 0..s.iterations {
                if xpbd {
                    self.project_once::<true>();
                } else {
                    self.project_once::<false>();
                }
                // Self-contacts after the body's own constraints (selfcol.rs).
                self.project_self_contacts();
                // Contacts last, so that the positions of each iteration satisfy them (contact.rs).
                self.project_contacts();
            }
        }
        // 4, back in the caller's order (walked in that order: `q` is the array still in
        // cache), gathering the rigid-mode sums of step 5 on the way.
        let scale = (1.0 - s.per_substep(s.linear_damping)) / dt;
        let mut rigid = RigidSums::default();
        let damp = s.damping > 0.0 && last;
        let pieces = self.pieces.enabled && last;
        // The pins' weight in the rigid fit: an elastic body's (material scheme); the other
        // materials' damping keeps its fit to the free nodes (their scripts were tuned to it).
        let pinned = if self.elastic.is_some() {
            HELD_WEIGHT
        } else {
            0.0
        };
        for ((x, prev), (v, (&r, (&m, &w)))) in self.x.iter_mut().zip(&mut self.p).zip(
            self.v
                .iter_mut()
                .zip(self.rank.iter().zip(self.mass.iter().zip(&self.w))),
        ) {
            let p = Vec3A::from(self.q[r as usize].truncate());
            // The pieces' volume correction moves the node without giving it a velocity.
            let kick = if pieces {
                self.pieces.take_shift(r as usize)
            } else {
                Vec3A::ZERO
            };
            *v = (p - *x - kick) * scale;
            *prev = *x;
            *x = p;
            if damp {
                // Pinned nodes (`w = 0`) weigh `HELD_WEIGHT` times their mass in the rigid fit,
                // so that it is a motion the pins allow (none for a clamped beam, a turn about a
                // single pin) and a pinned body's swing is damped as the deformation it is.
                rigid.add(if w > 0.0 { m } else { pinned * m }, p, *v);
            }
        }
        if damp {
            // Attached nodes (`w = 0` too) are moved by the host: they take no part in the fit
            // (the organ's rigid motion is free to follow a grab), as before the pins had one.
            for (node, _) in self.attachments.iter() {
                let i = node as usize;
                rigid.add(-pinned * self.mass[i], self.x[i], self.v[i]);
            }
            self.damp_rigid_modes(s.damping, &rigid);
        }
    }

    /// One sweep over all constraints (the block tree with its blocks' dynamic batches, then the
    /// serial dynamic set and the links of `edit.rs`), then the floor. `p` and `w` are in solver
    /// order.
    fn project_once<const XPBD: bool>(&mut self) {
        let kind = self.tet_kind();
        let (p, w) = (&mut self.q, &self.qw);
        let e = &mut self.edits;
        let root = self.blocks[0];
        let per_tet = kind.per_tet();
        // The blocks' dynamic multipliers come first, the serial set's after them.
        let (dd, serial_dd) = e
            .dyn_distance_lambda
            .split_at_mut(root.dyn_distance[2] as usize);
        let (dv, serial_dv) = e
            .dyn_volume_lambda
            .split_at_mut(root.dyn_tets[2] as usize * per_tet);
        let (tree_p, _) = p.split_at_mut(e.tree.node_count);
        Sweep {
            blocks: &self.blocks,
            distance: &self.distance_batches,
            tet: &self.tet_batches,
            centroid: &self.centroid_batches,
            neo_hookean: &self.neo_hookean_batches,
            dynamic: &e.sets,
            kind,
            parallel: self.settings.parallel,
        }
        .block::<XPBD>(
            0,
            tree_p,
            Lambdas {
                d: &mut self.distance_lambda,
                v: &mut self.volume_lambda,
                dd,
                dv,
            },
        );
        // The serial dynamic set (edited and added constraints on nodes past the tree's slots),
        // in edit order, on all nodes: volumes, then distances, then links (sutures).
        let serial = &e.sets[self.blocks.len()];
        match kind {
            TetKind::Volume(VolumeConstraintKind::None) => {}
            TetKind::NeoHookean { keep } => {
                let keep = F::splat(keep);
                project_batches::<_, 4, 2>(
                    &serial.neo_hookean_batches,
                    serial_dv,
                    p,
                    |b| &b.nodes,
                    |q, w, b, l| project_neo_hookean(q, w, b, l, keep),
                )
            }
            TetKind::Volume(VolumeConstraintKind::Classic) => project_batches::<_, 4, 1>(
                &serial.tet_batches,
                serial_dv,
                p,
                |b| &b.nodes,
                project_tet_volume::<XPBD>,
            ),
            TetKind::Volume(VolumeConstraintKind::Centroid) => project_batches::<_, 4, 4>(
                &serial.centroid_batches,
                serial_dv,
                p,
                |b| &b.nodes,
                project_centroid::<XPBD>,
            ),
        }
        if !serial.distance_batches.is_empty() && !matches!(kind, TetKind::NeoHookean { .. }) {
            project_batches::<_, 2, 1>(
                &serial.distance_batches,
                serial_dd,
                p,
                |b| &b.nodes,
                project_distance::<XPBD>,
            );
        }
        // Links (sutures) last.
        if !e.link_batches.is_empty() {
            project_batches::<_, 2, 1>(
                &e.link_batches,
                &mut e.link_lambda,
                p,
                |b| &b.nodes,
                project_distance::<XPBD>,
            );
        }
        // Per-node projections from here on: `p` (xyz; w = inverse mass) and `w` are in solver
        // order, the caller's node `i` is `p[self.rank[i]]`.
        // The floor's `Σ m Δx` goes to its reaction (contact.rs, force.rs).
        if let Some(f) = self.floor {
            let mut pushed = 0.0f32;
            for r in e.used_slots(p.len()) {
                for (p, &w) in p[r.clone()].iter_mut().zip(&w[r]) {
                    if w > 0.0 && p[f.axis] < f.height {
                        pushed += (f.height - p[f.axis]) / w;
                        p[f.axis] = f.height;
                    }
                }
            }
            self.collision.floor_pending += pushed;
        }
    }

    /// What the body projects per tet and edge.
    pub(crate) fn tet_kind(&self) -> TetKind {
        if self.elastic.is_some() {
            TetKind::NeoHookean {
                keep: 1.0 - self.settings.over_relaxation,
            }
        } else {
            TetKind::Volume(self.volume_kind)
        }
    }

    /// Rigid-mode damping (Müller et al.): with `x_cm`, `v_cm`, `L = Σ rᵢ × mᵢvᵢ`,
    /// `I = Σ r̃ᵢ r̃ᵢᵀ mᵢ`, `ω = I⁻¹L`: `vᵢ += k (v_cm + ω × rᵢ − vᵢ)` over the free nodes. A free
    /// body keeps its linear and angular momentum; everything else is damped by `(1 − k)`.
    /// `sums` are the free nodes' raw moments and (an elastic body) the pinned nodes' with
    /// `HELD_WEIGHT` times their mass: the fitted motion is then one the pins allow (nothing for a clamped beam,
    /// whose swing is damped), and the pins take the momentum the damping removes. About the centre of mass (`Σ mᵢrᵢ = 0`)
    /// `L = Σ mᵢ xᵢ × vᵢ − x_cm × Σ mᵢvᵢ` and `Σ mᵢ rᵢrᵢᵀ = Σ mᵢ xᵢxᵢᵀ − M x_cm x_cmᵀ`.
    fn damp_rigid_modes(&mut self, k: f32, sums: &RigidSums) {
        let _span = tracing::trace_span!("damp").entered();
        if sums.m <= 0.0 {
            return;
        }
        let (x_cm, v_cm) = (sums.mx / sums.m, sums.mv / sums.m);
        let l = sums.mxv - x_cm.cross(sums.mv);
        // Σ m r rᵀ, then I = tr(·) 1 − (·).
        let [xx, yy, zz, xy, xz, yz] = sums.mxx;
        let c = sums.m * x_cm;
        let rr = DMat3::from_cols(
            DVec3::new(xx, xy, xz) - c * x_cm.x,
            DVec3::new(xy, yy, yz) - c * x_cm.y,
            DVec3::new(xz, yz, zz) - c * x_cm.z,
        );
        let trace = rr.x_axis.x + rr.y_axis.y + rr.z_axis.z;
        let inertia = DMat3::from_diagonal(DVec3::splat(trace)) - rr;
        let det = inertia.determinant();
        let scale = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
        let omega = if det.abs() > 1e-12 * scale.powi(3) {
            inertia.inverse() * l
        } else {
            DVec3::ZERO
        };
        let (v_cm, omega, x_cm) = (v_cm.as_vec3a(), omega.as_vec3a(), x_cm.as_vec3a());
        for ((v, x), &w) in self.v.iter_mut().zip(&self.x).zip(&self.w) {
            if w > 0.0 {
                let rigid = v_cm + omega.cross(*x - x_cm);
                *v += k * (rigid - *v);
            }
        }
    }
}

/// Raw moments of the free nodes for the rigid-mode damping, in `f64`: `Σm`, `Σmx`, `Σmv`,
/// `Σ m x xᵀ` (xx, yy, zz, xy, xz, yz) and `Σ m x × v`.
#[derive(Debug, Default)]
struct RigidSums {
    m: f64,
    mx: DVec3,
    mv: DVec3,
    mxx: [f64; 6],
    mxv: DVec3,
}

impl RigidSums {
    #[inline]
    fn add(&mut self, m: f32, x: Vec3A, v: Vec3A) {
        let (m, x, v) = (m as f64, x.as_dvec3(), v.as_dvec3());
        let (mx, mv) = (m * x, m * v);
        self.m += m;
        self.mx += mx;
        self.mv += mv;
        self.mxx[0] += mx.x * x.x;
        self.mxx[1] += mx.y * x.y;
        self.mxx[2] += mx.z * x.z;
        self.mxx[3] += mx.x * x.y;
        self.mxx[4] += mx.x * x.z;
        self.mxx[5] += mx.y * x.z;
        self.mxv += x.cross(mv);
    }
}
