//! Contacts of a body's nodes with static [`VoxelCollider`]s and kinematic [`Tool`]s: generated
//! once per step after the prediction, projected in each of the `K` iterations after the body's
//! own constraints, with friction.
//!
//! Each contact is an inequality on one node, `C(p) = n·(p − q) − margin ≥ 0`, with the normal
//! `n` and surface point `q` fixed for the step (the plane of the surface where the node's path
//! met it), projected only when `C < 0`: `p ← p − C n`. Friction follows Macklin et al. 2014
//! ("Unified particle physics", §6.1) and limits the node's tangential displacement relative to
//! the surface since the start of the step, `Δx_t = ((p − x) − Δq)_⊥n` (`Δq` the surface's own
//! motion, zero for a static collider): with `d` the normal correction accumulated over the
//! iterations so far, `Δx_t` is removed entirely while `|Δx_t| + r ≤ μ_s d` (static; `r` the
//! tangential correction already made), and otherwise reduced by `μ_k d − r` (kinetic), so that
//! over a step the tangential correction is at most `μ_k` times the normal one, as Coulomb's law
//! for impulses. A collider or tool has no mass: only the node moves.
//!
//! ## Reaction forces
//! Every correction a contact makes to a node (normal and friction parts alike, and the push-out
//! of [`ContactState::resolve_remaining`]) is a position change `Δx` of a node of mass `m`
//! within a (sub)step of length `h`; its velocity `(p − x)/h` so changes by `Δx/h`, an impulse
//! `m Δx / h` given to the tissue by that collider or tool. Contacts are hard inequalities
//! projected as plain position corrections in every solver mode (no compliance), so this is
//! also XPBD's `λ n / h` with the contact's multiplier `λ = m Δx·n` (and the friction's
//! tangential multiplier likewise). Summed per source over the iterations of the (sub)step and
//! over the (sub)steps of a step of total length `T = Σ h`, the force on the source, averaged
//! over the step, is
//!
//! `F = −(1/T) Σ_substeps (1/h) Σ_projections m_i Δx_i`   (dyn = g·cm/s²),
//!
//! i.e. `−Σ m Δx / h²` for one step of length `h`. It is accumulated here (`pending` per
//! (sub)step in `f32`, `impulse` per step in `f64`), independent of the number of iterations and
//! substeps, and read through [`SoftBody::tool_force`] and [`SoftBody::collider_force`]
//! (`force.rs`). The floor's corrections are counted the same way (`step.rs`).

use std::sync::Arc;

use glam::{DVec3, Vec3, Vec3A, Vec4};

use crate::tool::{check_pose, sweep_node, Pose, Tool, ToolShape};
use crate::{PbdError, PbdParam, SoftBody, VoxelCollider};

/// How a body's nodes meet one collider or tool (cm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Distance kept between the nodes and the surface (cm), `≥ 0`.
    pub margin: f32,
    /// Nodes whose path comes within `margin + detection` of the surface get a contact for the
    /// step, inactive while `C ≥ 0`, so that the iterations can not push them in unseen (cm),
    /// `≥ 0`.
    pub detection: f32,
    /// Static friction coefficient `μ_s ≥ 0`.
    pub static_friction: f32,
    /// Kinetic friction coefficient `μ_k ≥ 0`.
    pub kinetic_friction: f32,
    /// Sweep the motion of the step (nodes from `x` to `p`; tools from their old to their new
    /// pose) so that fast motion does not tunnel through thin parts. When `false` only the
    /// predicted positions and the tool's new pose are tested.
    pub continuous: bool,
}

impl Default for ContactParams {
    /// Margin 0, detection 0.1 cm, `μ_s = 0.5`, `μ_k = 0.4` (wet tissue on steel is of that
    /// order), continuous.
    fn default() -> Self {
        Self {
            margin: 0.0,
            detection: 0.1,
            static_friction: 0.5,
            kinetic_friction: 0.4,
            continuous: true,
        }
    }
}

impl ContactParams {
    /// The defaults without friction.
    pub fn frictionless() -> Self {
        Self {
            static_friction: 0.0,
            kinetic_friction: 0.0,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<(), PbdError> {
        for (param, v) in [
            (PbdParam::Margin, self.margin),
            (PbdParam::Detection, self.detection),
            (PbdParam::StaticFriction, self.static_friction),
            (PbdParam::KineticFriction, self.kinetic_friction),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(PbdError::InvalidParameter {
                    param,
                    value: v as f64,
                    expected: "finite and ≥ 0",
                });
            }
        }
        Ok(())
    }
}

/// What a contact is with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactSource {
    /// The collider of this id ([`SoftBody::add_collider`]).
    Collider(usize),
    /// The tool of this id ([`SoftBody::add_tool`]).
    Tool(usize),
}

/// One node's contact for the current step: the inequality `n·(p − q) − margin ≥ 0`, cardinality
/// 1, with what the iterations did to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// The node.
    pub node: u32,
    /// The collider or tool.
    pub source: ContactSource,
    /// Outward unit normal `n` of the surface.
    pub normal: Vec3A,
    /// The surface point `q` (cm).
    pub point: Vec3A,
    /// The distance kept (cm).
    pub margin: f32,
    /// The surface's own displacement over the step (cm; zero for a collider).
    pub surface_motion: Vec3A,
    /// `μ_s`.
    pub static_friction: f32,
    /// `μ_k`.
    pub kinetic_friction: f32,
    /// Normal correction accumulated over the iterations (cm).
    pub normal_correction: f32,
    /// Tangential (friction) correction accumulated over the iterations (cm).
    pub friction_correction: f32,
}

impl Contact {
    /// Equality or inequality.
    pub const KIND: crate::ConstraintKind = crate::ConstraintKind::Inequality;
    /// `C` at `positions` (negative: inside).
    pub fn value(&self, positions: &[Vec3A]) -> f32 {
        self.normal.dot(positions[self.node as usize] - self.point) - self.margin
    }
}

/// The colliders, tools and this step's contacts of a body.
#[derive(Debug, Clone, Default)]
pub(crate) struct ContactState {
    colliders: Vec<(Arc<VoxelCollider>, ContactParams)>,
    tools: Vec<(Tool, ContactParams)>,
    /// Capacity `node_count × (colliders + tools)`, reserved when one is added: a node has at
    /// most one contact per collider or tool, so a step never grows it.
    pub(crate) contacts: Vec<Contact>,
    /// Iterations projected since the contacts were generated.
    iteration: u32,
    /// Reaction accounting (see the module docs), one entry per source, colliders then tools
    /// (sized when one is added, so steps stay allocation-free): `Σ m Δx` of this (sub)step's
    /// corrections (g·cm) ...
    pending: Vec<Vec3A>,
    /// ... and `Σ_substeps (Σ m Δx)/h` of the step: the impulse given to the tissue (g·cm/s).
    impulse: Vec<DVec3>,
    /// The floor's `Σ m Δx` of this (sub)step, along its axis (g·cm), and its impulse.
    pub(crate) floor_pending: f32,
    floor_impulse: f64,
    /// Length `h` of the current (sub)step (s), `T = Σ h` of the step so far (s), and the
    /// body's step count the sums belong to.
    h: f32,
    time: f64,
    accounted_step: Option<u64>,
    /// The force on the body's holders of the last step (`force.rs`), dyn.
    pub(crate) holding: Vec3,
    /// The host's pose of each tool while a step's substeps move it there (step.rs).
    targets: Vec<Pose>,
    /// Whether the current substep is its step's last (step.rs; true without substeps).
    pub(crate) last_substep: bool,
    /// With substeps: the step's contact candidates (Macklin et al. 2019), the free nodes near
    /// each collider or tool over the whole step, found once per step
    /// ([`ContactState::find_candidates`]); each substep evaluates only these. Node indices,
    /// by source (colliders, then tools), in node order within each; `candidate_ends[k]` ends
    /// source `k`'s. Capacity reserved with the contacts'.
    candidates: Vec<u32>,
    candidate_ends: Vec<u32>,
    /// Whether `candidates` hold this step's (set by step.rs for the substeps of a step; when
    /// `false` every free node is tested, as without substeps).
    pub(crate) use_candidates: bool,
}

/// A node's sweep against a collider marches in steps of this many cells.
const MARCH: f32 = 0.5;
/// At most this many samples per node and collider.
const MAX_SAMPLES: f32 = 64.0;

impl ContactState {
    pub(crate) fn reserve(&mut self, nodes: usize) {
        let sources = self.colliders.len() + self.tools.len();
        let need = nodes * sources;
        self.contacts
            .reserve_exact(need.saturating_sub(self.contacts.len()));
        self.candidates
            .reserve_exact(need.saturating_sub(self.candidates.len()));
        self.candidate_ends.resize(sources, 0);
        self.pending.resize(sources, Vec3A::ZERO);
        self.impulse.resize(sources, DVec3::ZERO);
    }

    /// Starts the reaction accounting of a (sub)step of length `h` belonging to the body's step
    /// `step`: the first (sub)step of a step clears the step's sums.
    fn begin_accounting(&mut self, h: f32, step: u64) {
        if self.accounted_step != Some(step) {
            self.accounted_step = Some(step);
            self.impulse.fill(DVec3::ZERO);
            self.floor_impulse = 0.0;
            self.time = 0.0;
        }
        self.pending.fill(Vec3A::ZERO);
        self.floor_pending = 0.0;
        self.h = h;
    }

    /// Ends a (sub)step's accounting (after its last iteration): its `Σ m Δx / h` join the
    /// step's impulses, `h` its time.
    fn end_accounting(&mut self) {
        let inv_h = 1.0 / self.h as f64;
        for (impulse, pending) in self.impulse.iter_mut().zip(&mut self.pending) {
            *impulse += pending.as_dvec3() * inv_h;
            *pending = Vec3A::ZERO;
        }
        self.floor_impulse += self.floor_pending as f64 * inv_h;
        self.floor_pending = 0.0;
        self.time += self.h as f64;
    }

    /// The step's length so far, `T = Σ h` (s; 0 before the first step).
    pub(crate) fn accounted_time(&self) -> f64 {
        self.time
    }

    /// The impulse given to the tissue over the last step by source `index` (colliders, then
    /// tools), g·cm/s.
    pub(crate) fn impulse(&self, index: usize) -> DVec3 {
        self.impulse.get(index).copied().unwrap_or(DVec3::ZERO)
    }

    /// The impulse given by all colliders and tools over the last step, g·cm/s.
    pub(crate) fn total_impulse(&self) -> DVec3 {
        self.impulse.iter().sum()
    }

    /// The floor's impulse over the last step, along its axis, g·cm/s.
    pub(crate) fn floor_impulse(&self) -> f64 {
        self.floor_impulse
    }

    /// The force on source `index` averaged over the last step, `−impulse / T` (dyn).
    pub(crate) fn source_force(&self, index: usize) -> Vec3 {
        if self.time > 0.0 {
            (-self.impulse(index) / self.time).as_vec3()
        } else {
            Vec3::ZERO
        }
    }

    pub(crate) fn collider_count(&self) -> usize {
        self.colliders.len()
    }

    /// Generates this step's contacts: `x` the positions at the start of the step, `p` the
    /// predictions, `w` the inverse masses (nodes with `w = 0` get none).
    ///
    /// The predictions are in solver order (`q[rank[i]]` is node `i`'s); contacts name the
    /// caller's node indices.
    pub(crate) fn generate(&mut self, x: &[Vec3A], q: &[Vec4], rank: &[u32], w: &[f32]) {
        self.contacts.clear();
        self.iteration = 0;
        if self.colliders.is_empty() && self.tools.is_empty() {
            return;
        }
        let _span = tracing::debug_span!(
            "collide",
            colliders = self.colliders.len(),
            tools = self.tools.len()
        )
        .entered();
        let Self {
            colliders,
            tools,
            contacts,
            candidates,
            candidate_ends,
            use_candidates,
            ..
        } = self;
        for (ci, (collider, params)) in colliders.iter().enumerate() {
            let reach = params.margin + params.detection;
            let (lo, hi) = collider.bounds();
            let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
            for i in nodes(candidates, candidate_ends, *use_candidates, ci, x.len()) {
                let (xi, r, wi) = (x[i], rank[i], w[i]);
                if wi <= 0.0 {
                    continue;
                }
                let pi = Vec3A::from(q[r as usize].truncate());
                if pi.min(xi).cmpgt(hi).any() || pi.max(xi).cmplt(lo).any() {
                    continue;
                }
                if let Some((normal, point)) =
                    collider_plane(collider, xi, pi, reach, params.continuous)
                {
                    push(
                        contacts,
                        Contact {
                            node: i as u32,
                            source: ContactSource::Collider(ci),
                            normal,
                            point,
                            margin: params.margin,
                            surface_motion: Vec3A::ZERO,
                            static_friction: params.static_friction,
                            kinetic_friction: params.kinetic_friction,
                            normal_correction: 0.0,
                            friction_correction: 0.0,
                        },
                    );
                }
            }
        }
        for (ti, (tool, params)) in tools.iter_mut().enumerate() {
            let reach = params.margin + params.detection;
            let from = if params.continuous {
                tool.start
            } else {
                tool.pose
            };
            let to = tool.pose;
            let (lo, hi) = tool.swept_bounds(&from, &to, reach);
            let k = colliders.len() + ti;
            for i in nodes(candidates, candidate_ends, *use_candidates, k, x.len()) {
                let (xi, r, wi) = (x[i], rank[i], w[i]);
                if wi <= 0.0 {
                    continue;
                }
                let pi = Vec3A::from(q[r as usize].truncate());
                let start = if params.continuous { xi } else { pi };
                if pi.min(start).cmpgt(hi).any() || pi.max(start).cmplt(lo).any() {
                    continue;
                }
                if let Some(hit) = sweep_node(&tool.shape, &from, &to, start, pi, reach) {
                    push(
                        contacts,
                        Contact {
                            node: i as u32,
                            source: ContactSource::Tool(ti),
                            normal: hit.normal,
                            point: hit.point,
                            margin: params.margin,
                            surface_motion: hit.motion,
                            static_friction: params.static_friction,
                            kinetic_friction: params.kinetic_friction,
                            normal_correction: 0.0,
                            friction_correction: 0.0,
                        },
                    );
                }
            }
            tool.last_sweep = (tool.start, tool.pose);
            tool.start = tool.pose;
        }
    }

    /// With substeps, before the first substep's contacts: this step's candidates (see
    /// `candidates`). `x` the positions at the start of the step, `q` the first substep's
    /// predictions (solver order), `n` the substeps: the step's path of a node is taken as
    /// `x → p̂ = x + n (q − x)`, and widened by its length (the constraints, the tools and the
    /// later substeps' gravity move a node off it). A node is a collider's candidate when that
    /// widened path meets a cell of the collider within its [`VoxelCollider::reach`] (which is
    /// at least `margin + detection`), a tool's when the path's box, widened, meets the tool's
    /// swept box from its pose at the start of the step to the host's, widened by
    /// `margin + detection` and the node's path. Nodes that the constraints push in from
    /// further away are put back by the push-out after the last substep, as without substeps.
    pub(crate) fn find_candidates(
        &mut self,
        x: &[Vec3A],
        q: &[Vec4],
        rank: &[u32],
        w: &[f32],
        n: u32,
    ) {
        self.candidates.clear();
        self.use_candidates = true;
        if self.colliders.is_empty() && self.tools.is_empty() {
            return;
        }
        let _span = tracing::debug_span!("candidates").entered();
        let n = n as f32;
        let Self {
            colliders,
            tools,
            candidates,
            candidate_ends,
            targets,
            ..
        } = self;
        // The node's path over the step, widened: from `x − d` to `x + 2d`, `d = p̂ − x`.
        let path = |i: usize| {
            let xi = x[i];
            let d = (Vec3A::from(q[rank[i] as usize].truncate()) - xi) * n;
            (xi - d, xi + 2.0 * d, d.length())
        };
        let mut k = 0;
        for (collider, _) in colliders.iter() {
            let (lo, hi) = collider.bounds();
            let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
            let reach = collider.reach();
            for (i, &wi) in w.iter().enumerate() {
                if wi <= 0.0 {
                    continue;
                }
                let (a, b, len) = path(i);
                if a.min(b).cmpgt(hi + len).any() || a.max(b).cmplt(lo - len).any() {
                    continue;
                }
                if collider_plane(collider, a, b, reach, true).is_some()
                    && candidates.len() < candidates.capacity()
                {
                    candidates.push(i as u32);
                }
            }
            candidate_ends[k] = candidates.len() as u32;
            k += 1;
        }
        for ((tool, params), target) in tools.iter().zip(targets.iter()) {
            let reach = params.margin + params.detection;
            let (lo, hi) = tool.swept_bounds(&tool.start, target, reach);
            for (i, &wi) in w.iter().enumerate() {
                if wi <= 0.0 {
                    continue;
                }
                let (a, b, len) = path(i);
                if a.min(b).cmpgt(hi + len).any() || a.max(b).cmplt(lo - len).any() {
                    continue;
                }
                if candidates.len() < candidates.capacity() {
                    candidates.push(i as u32);
                }
            }
            candidate_ends[k] = candidates.len() as u32;
            k += 1;
        }
    }

    /// Projects every contact once (one Gauss–Seidel sweep in generation order), with friction
    /// relative to the start-of-step positions `x`.
    /// `p` in solver order (`p[rank[i]]` is node `i`'s, its inverse mass in the w lane).
    /// Each correction's `m Δx` is added to its source's `pending` (module docs).
    pub(crate) fn project(&mut self, p: &mut [Vec4], rank: &[u32], x: &[Vec3A]) {
        let colliders = self.colliders.len();
        for c in &mut self.contacts {
            let i = c.node as usize;
            let s = rank[i] as usize;
            let before = Vec3A::from(p[s].truncate());
            let mut q = before;
            let value = c.normal.dot(q - c.point) - c.margin;
            if value < 0.0 {
                q -= value * c.normal;
                c.normal_correction -= value;
            }
            if c.normal_correction > 0.0 && (c.static_friction > 0.0 || c.kinetic_friction > 0.0) {
                let dx = (q - x[i]) - c.surface_motion;
                let tangential = dx - c.normal * c.normal.dot(dx);
                let len = tangential.length();
                if len > 0.0 {
                    if len + c.friction_correction <= c.static_friction * c.normal_correction {
                        q -= tangential;
                        c.friction_correction += len;
                    } else {
                        let r = (c.kinetic_friction * c.normal_correction - c.friction_correction)
                            .clamp(0.0, len);
                        q -= tangential * (r / len);
                        c.friction_correction += r;
                    }
                }
            }
            let w = p[s].w;
            p[s] = q.extend(w);
            // A contact's node is free (w > 0): it gets contacts only then.
            let source = match c.source {
                ContactSource::Collider(k) => k,
                ContactSource::Tool(k) => colliders + k,
            };
            if let Some(pending) = self.pending.get_mut(source) {
                *pending += (q - before) / w;
            }
        }
    }
}

impl ContactState {
    /// After the last iteration: every free node still closer than the margin to a collider (at
    /// `p`) or a tool (at its new pose) is put back on the surface: for a collider onto the plane
    /// where its path from `x` went in (or, if it started inside, the nearest surface's); for a
    /// tool radially from the core. Such
    /// a node had no contact because its prediction was beyond `margin + detection` and the
    /// body's constraints pushed it in during the iterations; it gets no friction this step.
    ///
    /// `p` in solver order (`p[rank[i]]` is node `i`'s), walked in the caller's node order.
    ///
    /// Their corrections count towards the sources' reactions like the contacts'.
    fn resolve_remaining(&mut self, p: &mut [Vec4], rank: &[u32], x: &[Vec3A], w: &[f32]) {
        let colliders = self.colliders.len();
        let pending = &mut self.pending;
        for (ci, (collider, params)) in self.colliders.iter().enumerate() {
            let (lo, hi) = collider.bounds();
            let (lo, hi) = (Vec3A::from(lo), Vec3A::from(hi));
            for ((&r, &xi), &wi) in rank.iter().zip(x).zip(w) {
                if wi <= 0.0 {
                    continue;
                }
                let slot = &mut p[r as usize];
                let mut moved = Vec3A::from(slot.truncate());
                if moved.cmpgt(hi).any() || moved.cmplt(lo).any() {
                    continue;
                }
                let q = &mut moved;
                let Some((phi, _)) = collider.probe(*q) else {
                    continue;
                };
                if phi >= params.margin {
                    continue;
                }
                // Entered during this step: the plane where the path from x went in; else the
                // surface nearest to where it is.
                let from = match collider.probe(xi) {
                    Some((phi_x, _)) if phi_x < params.margin => *q,
                    _ => xi,
                };
                if let Some((n, point)) = collider_plane(collider, from, *q, params.margin, true) {
                    let c = n.dot(*q - point) - params.margin;
                    if c < 0.0 {
                        *q -= c * n;
                        *slot = moved.extend(slot.w);
                        pending[ci] += (-c * n) / wi;
                    }
                }
            }
        }
        for (ti, (tool, params)) in self.tools.iter().enumerate() {
            let keep = tool.shape.radius() + params.margin;
            let (lo, hi) = tool.swept_bounds(&tool.pose, &tool.pose, params.margin);
            for (&r, &wi) in rank.iter().zip(w) {
                let slot = &mut p[r as usize];
                let q = Vec3A::from(slot.truncate());
                if wi <= 0.0 || q.cmplt(lo).any() || q.cmpgt(hi).any() {
                    continue;
                }
                let local = tool.pose.inverse_transform_point(q.into());
                let core = tool.shape.closest_core_point(local);
                let d = local.distance(core);
                if d < keep && d > 1e-6 {
                    let out = core + (local - core) * (keep / d);
                    let moved = Vec3A::from(tool.pose.transform_point(out));
                    pending[colliders + ti] += (moved - q) / wi;
                    *slot = moved.extend(slot.w);
                }
            }
        }
    }
}

/// The contact plane `(n, q)` of a node moving from `x` to `p` with a collider: at the first
/// point of the path (sampled every half cell when `continuous`, else `p` alone) where
/// `φ < threshold`, the normalised gradient `n` and the surface point `q = s − φ n`. A node that
/// enters a thin collider during the step so gets the normal of the side it came from.
fn collider_plane(
    collider: &VoxelCollider,
    x: Vec3A,
    p: Vec3A,
    threshold: f32,
    continuous: bool,
) -> Option<(Vec3A, Vec3A)> {
    let step = MARCH * collider.cell_size();
    let dist = p.distance(x);
    let samples = if continuous && dist > step {
        (dist / step).ceil().min(MAX_SAMPLES) as usize
    } else {
        1
    };
    for s in 1..=samples {
        let at = if s == samples {
            p
        } else {
            x + (p - x) * (s as f32 / samples as f32)
        };
        let Some((phi, grad)) = collider.probe(at) else {
            continue;
        };
        if phi >= threshold {
            continue;
        }
        let len = grad.length();
        let normal = if len > 1e-6 {
            grad / len
        } else if dist > 0.0 {
            (x - p) / dist
        } else {
            return None;
        };
        return Some((normal, at - normal * phi));
    }
    None
}

/// The nodes a (sub)step tests against source `k`: this step's candidates when `use_them`,
/// else all `count` nodes.
fn nodes<'a>(
    candidates: &'a [u32],
    ends: &'a [u32],
    use_them: bool,
    k: usize,
    count: usize,
) -> impl Iterator<Item = usize> + 'a {
    let (all, some) = if use_them {
        let start = if k == 0 { 0 } else { ends[k - 1] as usize };
        (0..0, &candidates[start..ends[k] as usize])
    } else {
        (0..count, &candidates[..0])
    };
    all.chain(some.iter().map(|&i| i as usize))
}

/// Appends a contact within the reserved capacity (one per node and source), so that a step
/// never grows the buffer.
fn push(contacts: &mut Vec<Contact>, c: Contact) {
    if contacts.len() < contacts.capacity() {
        contacts.push(c);
    }
}

/// Contacts, colliders and tools of a body.
impl SoftBody {
    /// Adds a static collider (shared between bodies through the [`Arc`]) and returns its id.
    /// Reserves the contact buffer (outside the step, so steps stay allocation-free).
    ///
    /// # Errors
    /// [`PbdError::InvalidParameter`] for a negative or non-finite parameter, or when
    /// `margin + detection` exceeds the collider's [`VoxelCollider::reach`] (build it with a
    /// larger reach).
    pub fn add_collider(
        &mut self,
        collider: impl Into<Arc<VoxelCollider>>,
        params: ContactParams,
    ) -> Result<usize, PbdError> {
        let collider = collider.into();
        check_reach(&collider, &params)?;
        self.collision.colliders.push((collider, params));
        self.collision.reserve(self.x.len());
        Ok(self.collision.colliders.len() - 1)
    }

    /// Changes how the nodes meet a collider.
    ///
    /// # Errors
    /// [`PbdError::NoSuchContactSource`], and as [`SoftBody::add_collider`].
    pub fn set_collider_params(
        &mut self,
        id: usize,
        params: ContactParams,
    ) -> Result<(), PbdError> {
        let count = self.collision.colliders.len();
        let entry = self
            .collision
            .colliders
            .get_mut(id)
            .ok_or(PbdError::NoSuchContactSource {
                what: "collider",
                id,
                count,
            })?;
        check_reach(&entry.0, &params)?;
        entry.1 = params;
        Ok(())
    }

    /// The colliders and their contact parameters, by id.
    pub fn colliders(&self) -> impl ExactSizeIterator<Item = (&VoxelCollider, &ContactParams)> {
        self.collision.colliders.iter().map(|(c, p)| (&**c, p))
    }

    /// Adds a kinematic tool at `pose` and returns its id. Reserves the contact buffer.
    ///
    /// # Errors
    /// [`PbdError::InvalidTool`] for a degenerate shape or a bad pose,
    /// [`PbdError::InvalidParameter`] for bad contact parameters.
    pub fn add_tool(
        &mut self,
        shape: ToolShape,
        pose: Pose,
        params: ContactParams,
    ) -> Result<usize, PbdError> {
        params.validate()?;
        self.collision.tools.push((Tool::new(shape, pose)?, params));
        self.collision.targets.push(pose);
        self.collision.reserve(self.x.len());
        Ok(self.collision.tools.len() - 1)
    }

    /// Moves a tool: the next step sweeps it from its pose at the last step to `pose`.
    ///
    /// # Errors
    /// [`PbdError::NoSuchContactSource`], [`PbdError::InvalidTool`] for a non-finite pose or a
    /// rotation that is not a unit quaternion.
    pub fn set_tool_pose(&mut self, id: usize, pose: Pose) -> Result<(), PbdError> {
        check_pose(&pose)?;
        self.tool_mut(id)?.0.pose = pose;
        Ok(())
    }

    /// Changes how the nodes meet a tool.
    ///
    /// # Errors
    /// [`PbdError::NoSuchContactSource`], [`PbdError::InvalidParameter`].
    pub fn set_tool_params(&mut self, id: usize, params: ContactParams) -> Result<(), PbdError> {
        params.validate()?;
        self.tool_mut(id)?.1 = params;
        Ok(())
    }

    /// A tool by id (its shape, pose and last sweep).
    ///
    /// # Errors
    /// [`PbdError::NoSuchContactSource`].
    pub fn tool(&self, id: usize) -> Result<&Tool, PbdError> {
        let count = self.collision.tools.len();
        self.collision
            .tools
            .get(id)
            .map(|t| &t.0)
            .ok_or(PbdError::NoSuchContactSource {
                what: "tool",
                id,
                count,
            })
    }

    fn tool_mut(&mut self, id: usize) -> Result<&mut (Tool, ContactParams), PbdError> {
        let count = self.collision.tools.len();
        self.collision
            .tools
            .get_mut(id)
            .ok_or(PbdError::NoSuchContactSource {
                what: "tool",
                id,
                count,
            })
    }

    /// The contacts of the last step, in projection order (by collider, then tool; by node
    /// within each), with the corrections the iterations made.
    pub fn contacts(&self) -> &[Contact] {
        &self.collision.contacts
    }

    /// Step phase: contacts for the predictions (after attachments) of a (sub)step of length
    /// `h` (s); starts that (sub)step's reaction accounting (the first (sub)step of a step, by
    /// [`SoftBody::step_count`], clears the step's sums).
    ///
    /// With substeps (`substeps > 1`), the first substep (`first`) finds the step's contact
    /// candidates first, and every substep evaluates only those (Macklin et al. 2019).
    pub(crate) fn generate_contacts(&mut self, h: f32, first: bool) {
        self.collision.begin_accounting(h, self.step_count);
        let n = self.settings.substeps;
        if n <= 1 {
            self.collision.use_candidates = false;
        } else if first {
            self.collision
                .find_candidates(&self.x, &self.q, &self.rank, &self.w, n);
        }
        self.collision
            .generate(&self.x, &self.q, &self.rank, &self.w);
    }

    /// Step phase: one projection of every contact (after the body's constraints, in each
    /// iteration), then, in the last substep, of the pieces' volumes (before the push-out).
    pub(crate) fn project_contacts(&mut self) {
        self.collision.project(&mut self.q, &self.rank, &self.x);
        if self.pieces.enabled && self.collision.last_substep {
            // The pieces' volumes after the contacts, the nodes in contact held, in each
            // iteration of the step's last substep (pieces.rs).
            self.pieces.project(&mut self.q);
        }
        self.collision.iteration += 1;
        if self.collision.iteration == self.settings.iterations {
            // The push-out after the last iteration: once per step, after its last substep.
            if self.collision.last_substep {
                self.collision
                    .resolve_remaining(&mut self.q, &self.rank, &self.x, &self.w);
            }
            // Every substep closes its own reaction sums (its corrections over its `h`).
            self.collision.end_accounting();
        }
    }
}

/// Substeps (step.rs): each substep sweeps the tools a part of the way to the host's pose.
impl ContactState {
    /// Before the first substep: remembers the host's poses.
    pub(crate) fn save_tool_targets(&mut self) {
        for ((tool, _), target) in self.tools.iter().zip(&mut self.targets) {
            *target = tool.pose;
        }
    }

    /// Before a substep with `remaining` substeps left (this one included): each tool's pose
    /// for it, `1/remaining` of the way from where the last substep left it to the host's pose
    /// (exactly the host's pose for the last one).
    pub(crate) fn substep_tool_poses(&mut self, remaining: u32) {
        let f = 1.0 / remaining.max(1) as f32;
        for ((tool, _), target) in self.tools.iter_mut().zip(&self.targets) {
            tool.pose = if remaining <= 1 {
                *target
            } else {
                Pose::new(
                    tool.start.rotation.slerp(target.rotation, f),
                    tool.start.translation.lerp(target.translation, f),
                )
            };
        }
    }
}

fn check_reach(collider: &VoxelCollider, params: &ContactParams) -> Result<(), PbdError> {
    params.validate()?;
    let reach = params.margin + params.detection;
    if reach > collider.reach() {
        return Err(PbdError::InvalidParameter {
            param: PbdParam::ContactReach,
            value: reach as f64,
            expected: "at most the collider's reach (VoxelCollider::new's `reach`)",
        });
    }
    Ok(())
}
