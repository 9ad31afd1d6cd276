//! One step, in the order of Müller et al.: external forces → prediction → attachments →
//! contact generation → `K` × (distance, volume, floor projection, contacts) → velocity and
//! position update → rigid-mode damping.

use glam::{DMat3, DVec3, Vec3A};
use rayon::prelude::*;

use crate::constraint::{project_centroid, project_distance, project_tet_volume};
use crate::{PbdError, SoftBody, Solver, VolumeConstraintKind};

/// Colours with fewer constraints than this are projected serially even in parallel mode (same
/// result; saves a fork–join).
const PARALLEL_MIN: usize = 1024;
/// Constraints per rayon task. Results do not depend on it.
const CHUNK: usize = 256;

/// Projects all constraints of one kind once, colour by colour. `L` multipliers per row.
///
/// Serial and parallel give bit-identical results: a colour's constraints share no node, so
/// projecting each on the positions from before the colour (parallel: computed into `scratch`,
/// then written back) is what projecting them one after another does.
#[allow(clippy::too_many_arguments)]
fn project_kind<R: Sync, const N: usize, const L: usize>(
    rows: &[R],
    offsets: &[u32],
    lambda: &mut [f32],
    p: &mut [Vec3A],
    w: &[f32],
    scratch: &mut [[Vec3A; 4]],
    parallel: bool,
    nodes: impl Fn(&R) -> [u32; N] + Sync,
    kernel: impl Fn(&mut [Vec3A; N], [f32; N], &R, &mut [f32]) + Sync,
) {
    let serial = |rows: &[R], lambda: &mut [f32], p: &mut [Vec3A]| {
        for (r, lam) in rows.iter().zip(lambda.chunks_exact_mut(L)) {
            let ids = nodes(r);
            let mut q = ids.map(|i| p[i as usize]);
            kernel(&mut q, ids.map(|i| w[i as usize]), r, lam);
            for k in 0..N {
                p[ids[k] as usize] = q[k];
            }
        }
    };
    if !parallel {
        serial(rows, lambda, p);
        return;
    }
    for range in offsets.windows(2) {
        let (s, e) = (range[0] as usize, range[1] as usize);
        let (rows, lambda) = (&rows[s..e], &mut lambda[s * L..e * L]);
        if e - s < PARALLEL_MIN {
            serial(rows, lambda, p);
            continue;
        }
        let out = &mut scratch[..e - s];
        let read: &[Vec3A] = p;
        rows.par_chunks(CHUNK)
            .zip(lambda.par_chunks_mut(CHUNK * L))
            .zip(out.par_chunks_mut(CHUNK))
            .for_each(|((rows, lambda), out)| {
                for ((r, lam), o) in rows.iter().zip(lambda.chunks_exact_mut(L)).zip(out) {
                    let ids = nodes(r);
                    let mut q = ids.map(|i| read[i as usize]);
                    kernel(&mut q, ids.map(|i| w[i as usize]), r, lam);
                    o[..N].copy_from_slice(&q);
                }
            });
        for (r, o) in rows.iter().zip(out.iter()) {
            let ids = nodes(r);
            for k in 0..N {
                p[ids[k] as usize] = o[k];
            }
        }
    }
}

impl SoftBody {
    /// Advances the body by one step of the current [`crate::StepSettings`]:
    /// 1. `v += Δt·g` for free nodes (`w·f_ext` with `f_ext = m g`);
    /// 2. `p = x + Δt·v`; attached nodes take their targets; contacts with colliders and tools are
    ///    generated for the predictions (see [`crate::Contact`]);
    /// 3. `K` times: distance constraints, volume constraints, floor (Gauss–Seidel, colour order),
    ///    then the contacts with friction;
    ///    XPBD multipliers start at 0 each step;
    /// 4. `v = (1 − c)(p − x)/Δt` (`c` the linear damping, default 0), `x = p` (the old `x` becomes [`SoftBody::previous_positions`]);
    /// 5. rigid-mode damping of the free nodes.
    ///
    /// Allocates nothing.
    ///
    /// # Errors
    /// [`PbdError::Diverged`] when a node became non-finite (the state is kept as it is).
    pub fn step(&mut self) -> Result<(), PbdError> {
        let _span = tracing::debug_span!("pbd_step", step = self.step_count).entered();
        let s = self.settings;
        let (dt, g) = (s.dt, Vec3A::from(s.gravity));
        for ((p, v), (x, &w)) in self
            .p
            .iter_mut()
            .zip(&mut self.v)
            .zip(self.x.iter().zip(&self.w))
        {
            if w > 0.0 {
                *v += dt * g;
            }
            *p = *x + dt * *v;
        }
        for &(node, target) in &self.attachments {
            self.p[node as usize] = target;
        }
        // Contacts with colliders and tools for the predictions (contact.rs).
        self.generate_contacts();
        let xpbd = s.solver == Solver::Xpbd;
        if xpbd {
            self.distance_lambda.fill(0.0);
            self.volume_lambda.fill(0.0);
        }
        {
            let _span = tracing::trace_span!("project", iterations = s.iterations).entered();
            for _ in 0..s.iterations {
                if xpbd {
                    self.project_once::<true>();
                } else {
                    self.project_once::<false>();
                }
                // Contacts last, so that the positions of each iteration satisfy them (contact.rs).
                self.project_contacts();
            }
        }
        let scale = (1.0 - s.linear_damping) / dt;
        for ((v, p), x) in self.v.iter_mut().zip(&self.p).zip(&self.x) {
            *v = (*p - *x) * scale;
        }
        std::mem::swap(&mut self.x, &mut self.p);
        if s.damping > 0.0 {
            self.damp_rigid_modes(s.damping);
        }
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

    fn project_once<const XPBD: bool>(&mut self) {
        let par = self.settings.parallel;
        let (p, w, scratch) = (&mut self.p, &self.w, &mut self.scratch);
        project_kind::<_, 2, 1>(
            &self.distance_rows,
            &self.distance_offsets,
            &mut self.distance_lambda,
            p,
            w,
            scratch,
            par,
            |r| r.nodes,
            |q, w, r, l| project_distance::<XPBD>(q, w, r, &mut l[0]),
        );
        match self.volume_kind {
            VolumeConstraintKind::None => {}
            VolumeConstraintKind::Classic => project_kind::<_, 4, 1>(
                &self.tet_rows,
                &self.tet_offsets,
                &mut self.volume_lambda,
                p,
                w,
                scratch,
                par,
                |r| r.nodes,
                |q, w, r, l| project_tet_volume::<XPBD>(q, w, r, &mut l[0]),
            ),
            VolumeConstraintKind::Centroid => project_kind::<_, 4, 4>(
                &self.centroid_rows,
                &self.tet_offsets,
                &mut self.volume_lambda,
                p,
                w,
                scratch,
                par,
                |r| r.nodes,
                project_centroid::<XPBD>,
            ),
        }
        if let Some(f) = self.floor {
            for (p, &w) in p.iter_mut().zip(w) {
                if w > 0.0 && p[f.axis] < f.height {
                    p[f.axis] = f.height;
                }
            }
        }
    }

    /// Rigid-mode damping (Müller et al.): with `x_cm`, `v_cm`, `L = Σ rᵢ × mᵢvᵢ`,
    /// `I = Σ r̃ᵢ r̃ᵢᵀ mᵢ`, `ω = I⁻¹L`: `vᵢ += k (v_cm + ω × rᵢ − vᵢ)` over the free nodes. Keeps
    /// their linear and angular momentum; damps everything else by `(1 − k)`.
    fn damp_rigid_modes(&mut self, k: f32) {
        let _span = tracing::trace_span!("damp").entered();
        let (mut m_sum, mut mx, mut mv) = (0.0f64, DVec3::ZERO, DVec3::ZERO);
        for ((&m, &w), (x, v)) in self
            .mass
            .iter()
            .zip(&self.w)
            .zip(self.x.iter().zip(&self.v))
        {
            if w > 0.0 {
                let m = m as f64;
                m_sum += m;
                mx += m * x.as_dvec3();
                mv += m * v.as_dvec3();
            }
        }
        if m_sum <= 0.0 {
            return;
        }
        let (x_cm, v_cm) = (mx / m_sum, mv / m_sum);
        let (mut l, mut inertia) = (DVec3::ZERO, DMat3::ZERO);
        for ((&m, &w), (x, v)) in self
            .mass
            .iter()
            .zip(&self.w)
            .zip(self.x.iter().zip(&self.v))
        {
            if w > 0.0 {
                let m = m as f64;
                let r = x.as_dvec3() - x_cm;
                l += r.cross(m * v.as_dvec3());
                // r̃ r̃ᵀ = |r|² 1 − r rᵀ.
                inertia += m
                    * (DMat3::from_diagonal(DVec3::splat(r.length_squared()))
                        - DMat3::from_cols(r * r.x, r * r.y, r * r.z));
            }
        }
        let det = inertia.determinant();
        let scale = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
        let omega = if det.abs() > 1e-12 * scale.powi(3) {
            inertia.inverse() * l
        } else {
            DVec3::ZERO
        };
        let (v_cm, omega, x_cm, k) = (v_cm.as_vec3a(), omega.as_vec3a(), x_cm.as_vec3a(), k);
        for ((v, x), &w) in self.v.iter_mut().zip(&self.x).zip(&self.w) {
            if w > 0.0 {
                let rigid = v_cm + omega.cross(*x - x_cm);
                *v += k * (rigid - *v);
            }
        }
    }
}
