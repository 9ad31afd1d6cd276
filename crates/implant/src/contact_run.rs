//! The tissue layers stepped against a second body, in the thesis's step order.
//!
//! Each step (SPEC A.2, A.5 step 4):
//! 1. forces on the tissue and on the body;
//! 2. velocities of both (damped);
//! 3. collisions between layer 2 and the body: detection (BVH vs BVH or BVH vs voxels, with
//!    contact anticipation) and impulses on the velocities;
//! 4. positions of both, the slab's thickness guard ([`TissueLayers::hold_thickness`]), then a
//!    position correction so that no layer-2 edge is left through the
//!    body (back to the side it had at the start of the step);
//! 5. the stop check on the summed displacements of both bodies.
//!
//! The positions use the velocities after the collision impulses (symplectic Euler): phase 3
//! between the velocity and the position update only has an effect if phase 4 uses the new
//! velocities. The thesis's explicit Euler (`x ← x + v_old·h`) also gains energy `1 + (ωh)²`
//! per step, which the damping factor `d` only holds while `ωh < √(1/d² − 1)`; symplectic Euler
//! is stable to `ωh < 2` at the same cost.
//!
//! Collisions run on the particle arrays directly: layer 2 is given to the collider as a surface
//! over the tissue's particle indices (`2r + 1` for region vertex `r`; the layer-1 particles are
//! unreferenced vertices of it), and the body's surface is its own particle array, so nothing is
//! copied per step except the start-of-step positions the correction needs.

use glam::Vec3A;
use tissue_collide::{
    Bodies, BroadPhase, Collider, ColliderOptions, ContactParams, ResponseParams, Snapshot,
};
use tissue_mesh::TriMesh;
use tissue_mss::{Integrator, MassSpringSystem, MssError, SettleDetector, StopCriterion};

use crate::Param;
use crate::{ImplantError, Layer, TissueLayers};

/// How a run steps, damps, collides and stops. Units: s, cm.
#[derive(Debug, Clone, PartialEq)]
pub struct RunParams {
    /// Time step (s); `None`: [`RunParams::step_safety`] × the stability limit of the stiffest
    /// particle (see [`MassSpringSystem::stable_time_step`]), so a finer mesh gets a smaller step by itself.
    pub time_step: Option<f32>,
    /// Fraction of the stability limit used when the step is automatic, in (0, 1].
    pub step_safety: f32,
    /// Damping time `τ` (s): velocities are multiplied by `exp(−h/τ)` each step (the thesis's
    /// damping factor, made independent of the step so that runs on different meshes are
    /// comparable).
    pub damping_time: f32,
    /// Broad phase of the collision detection (the thesis has both).
    pub broad_phase: BroadPhase,
    /// Contact anticipation (cm): layer-2 edges closer than this to the body get impulses in
    /// phase 3, so an approaching particle is stopped before it crosses. `None`:
    /// [`RunParams::contact_fraction`] × the mean edge length of layer 2.
    pub contact_distance: Option<f32>,
    /// The automatic contact distance as a fraction of layer 2's mean edge length.
    pub contact_fraction: f32,
    /// Temporal coherence of the detection, as a multiple of the contact distance
    /// ([`tissue_collide::ColliderOptions::coherence_margin`]; 0 turns it off): between full
    /// detections only the pairs then this much closer than the contact distance are re-tested.
    /// The contacts are the same either way; the work is not.
    pub coherence: f32,
    /// Collision response: restitution, friction, Gauss–Seidel sweeps, correction settings.
    pub response: ResponseParams,
    /// The stop criterion's window and ratio tolerance (SPEC A.2) and the step limit.
    pub stop: StopCriterion,
    /// Skip the position correction (and its detection) in a step where no particle moved by
    /// half the contact distance: phase 3 already held every pair that close. `false` corrects
    /// every step.
    pub skip_safe_separation: bool,
    /// The run has also settled when the mean speed of the moving particles stays below this
    /// (cm/s) over the window (the criterion's floor, scaled by the particle count and step).
    pub settle_speed: f64,
}

impl RunParams {
    /// The default [`RunParams::step_safety`]: the automatic step is this fraction of the
    /// stability limit (why 0.8: see [`RunParams::default`]).
    pub const DEFAULT_STEP_SAFETY: f32 = 0.8;
}

impl Default for RunParams {
    /// Automatic step at 0.8 of the stability limit (the Gershgorin bound overestimates the
    /// highest frequency, and a step at the bound lets resting contacts chatter); damping time
    /// 1 ms (the lowest modes of a skin region — layer 2 on its anchors, the expander's dome —
    /// have periods of a few ms, so this is about critical for them); BVH vs BVH; contacts from
    /// a tenth of an edge; inelastic contact with Coulomb friction 0.3 (silicone on tissue;
    /// without friction tissue on an expander's flank slides against its anchors and never
    /// settles), 8 Gauss–Seidel sweeps warm-started from the last step's impulses (so resting
    /// contacts converge instead of chattering); window 50 steps, tolerance 0.01, at most
    /// 20 000 steps (several times the thesis's runs); settled below a mean speed of 5 cm/s
    /// (above the jitter of resting contacts, which the thesis's ratio test alone never
    /// accepts). The measurements behind these values: docs/tuning-log.md.
    fn default() -> Self {
        RunParams {
            time_step: None,
            step_safety: RunParams::DEFAULT_STEP_SAFETY,
            damping_time: 1e-3,
            broad_phase: BroadPhase::BvhBvh,
            contact_distance: None,
            contact_fraction: 0.1,
            coherence: 1.0,
            response: ResponseParams {
                friction: 0.3,
                warm_start: 1.0,
                ..ResponseParams::default()
            },
            stop: StopCriterion {
                window: 50,
                tolerance: 0.01,
                max_steps: 20_000,
                floor: 0.0,
            },
            settle_speed: 5.0,
            skip_safe_separation: true,
        }
    }
}

impl RunParams {
    fn check(&self) -> Result<(), ImplantError> {
        let bad = |param: Param, value: f64, expected: &str| {
            Err(ImplantError::InvalidParameter {
                param,
                value,
                expected: expected.into(),
            })
        };
        if let Some(h) = self.time_step {
            if !(h.is_finite() && h > 0.0) {
                return bad(Param::TimeStep, f64::from(h), "positive and finite (s)");
            }
        }
        if !(self.step_safety > 0.0 && self.step_safety <= 1.0) {
            return bad(Param::StepSafety, f64::from(self.step_safety), "in (0, 1]");
        }
        if !(self.damping_time.is_finite() && self.damping_time > 0.0) {
            return bad(
                Param::DampingTime,
                f64::from(self.damping_time),
                "positive and finite (s)",
            );
        }
        if let Some(d) = self.contact_distance {
            if !(d.is_finite() && d >= 0.0) {
                return bad(Param::ContactDistance, f64::from(d), "finite and ≥ 0 (cm)");
            }
        }
        if !(self.contact_fraction.is_finite() && self.contact_fraction >= 0.0) {
            return bad(
                Param::ContactFraction,
                f64::from(self.contact_fraction),
                "finite and ≥ 0",
            );
        }
        if !(self.coherence.is_finite() && self.coherence >= 0.0) {
            return bad(
                Param::Coherence,
                f64::from(self.coherence),
                "finite and ≥ 0",
            );
        }
        if !(self.settle_speed.is_finite() && self.settle_speed >= 0.0) {
            return bad(
                Param::SettleSpeed,
                self.settle_speed,
                "finite and ≥ 0 (cm/s)",
            );
        }
        self.response.validate()?;
        Ok(())
    }
}

/// A kinematic phase of the body: particles moving at constant velocity from where they are to
/// `end` over `steps` steps, then released to the forces.
#[derive(Debug, Clone)]
pub(crate) struct Fill {
    pub(crate) particles: Vec<u32>,
    pub(crate) end: Vec<Vec3A>,
    steps: u64,
}

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSummary {
    /// The step (0-based).
    pub step: u64,
    /// Summed displacement of all particles of both bodies in the step (cm).
    pub displacement: f64,
    /// Contacts found in phase 3.
    pub contacts: u32,
    /// Layer-2 edges still through the body after the correction (0 when it held, and 0 when the
    /// correction was skipped because nothing moved far enough to cross).
    pub remaining_crossings: u32,
    /// Layer-1 particles held off layer 2 ([`TissueLayers::hold_thickness`]).
    pub thinned: u32,
}

/// The tissue layers and a second body (the implant, or the plane press's sphere), stepped
/// together (see the module docs).
#[derive(Debug, Clone)]
pub struct ContactRun {
    pub(crate) layers: TissueLayers,
    pub(crate) body: MassSpringSystem,
    collider: Collider,
    previous_tissue: Vec<Vec3A>,
    previous_body: Vec<Vec3A>,
    h: f32,
    pub(crate) contact_distance: f32,
    params: RunParams,
    detector: SettleDetector,
    /// The stop criterion's speed floor (summed displacement per step, cm).
    floor: f64,
    pub(crate) fill: Option<Fill>,
    pub(crate) settled: bool,
    pub(crate) steps: u64,
    /// The body's surface (vertex `v` is body particle `v`) and which of its vertices were free
    /// when the run was built (the expander's dome; none of the press's sphere).
    pub(crate) body_triangles: Vec<[u32; 3]>,
    pub(crate) dome_vertex: Vec<bool>,
    /// Layer 2's mean edge length at rest (cm).
    pub(crate) mean_edge: f32,
    /// How deep below the contact distance the quasi-static solver looks for contacts (cm).
    pub(crate) static_reach: f32,
}

impl ContactRun {
    /// Prepares the run: integrator, damping and step of both systems, the collider between
    /// layer 2 and `body_mesh` (the body's surface; vertex `v` is particle `v` of `body`).
    pub(crate) fn new(
        mut layers: TissueLayers,
        mut body: MassSpringSystem,
        body_mesh: &TriMesh,
        params: &RunParams,
    ) -> Result<Self, ImplantError> {
        params.check()?;
        let h = match params.time_step {
            Some(h) => h,
            None => {
                let tissue = layers.stable_time_step();
                let other = body.stable_time_step();
                let limit = match (tissue, other) {
                    (Some(a), Some(b)) => a.min(b),
                    (Some(a), None) | (None, Some(a)) => a,
                    (None, None) => {
                        return Err(ImplantError::InvalidParameter {
                            param: Param::TimeStep,
                            value: 0.0,
                            expected: "given explicitly: no free particle has a spring to \
                                       derive a stable step from"
                                .into(),
                        })
                    }
                };
                limit * params.step_safety
            }
        };
        let damping = (-f64::from(h) / f64::from(params.damping_time)).exp() as f32;
        for system in [layers.system_mut(), &mut body] {
            system.set_integrator(Integrator::SymplecticEuler);
            system.set_damping(damping)?;
        }
        let tissue_positions: Vec<glam::Vec3> = layers
            .system()
            .particles()
            .positions()
            .iter()
            .map(|&p| p.into())
            .collect();
        let triangles: Vec<[u32; 3]> = layers
            .rest(Layer::Inner)
            .triangles()
            .iter()
            .map(|t| t.map(|r| TissueLayers::particle(Layer::Inner, r)))
            .collect();
        let surface = TriMesh::new(tissue_positions, triangles)?;
        let mean_edge = mean_edge_length(layers.rest(Layer::Inner));
        let contact_distance = params
            .contact_distance
            .unwrap_or(params.contact_fraction * mean_edge);
        let body_inverse = body.particles().inverse_masses();
        let any_free = body_inverse.iter().any(|&w| w > 0.0);
        let dome_vertex: Vec<bool> = body_inverse.iter().map(|&w| w > 0.0 || !any_free).collect();
        let body_now: Vec<glam::Vec3> = body
            .particles()
            .positions()
            .iter()
            .map(|&p| p.into())
            .collect();
        let collider = Collider::new(
            &surface,
            &body_mesh.with_positions(body_now)?,
            &ColliderOptions {
                broad_phase: params.broad_phase,
                contact: ContactParams {
                    tolerance: contact_distance,
                    shared_particles: false,
                },
                coherence_margin: params.coherence * contact_distance,
                ..ColliderOptions::default()
            },
        )?;
        let moving = layers
            .system()
            .particles()
            .inverse_masses()
            .iter()
            .chain(body.particles().inverse_masses())
            .filter(|&&w| w > 0.0)
            .count();
        let stop = StopCriterion {
            floor: params.settle_speed * moving as f64 * f64::from(h),
            ..params.stop
        };
        let detector = SettleDetector::new(&stop)?;
        let floor = stop.floor;
        Ok(ContactRun {
            previous_tissue: vec![Vec3A::ZERO; layers.system().particles().len()],
            previous_body: vec![Vec3A::ZERO; body.particles().len()],
            layers,
            body,
            collider,
            h,
            contact_distance,
            params: params.clone(),
            detector,
            floor,
            fill: None,
            settled: false,
            steps: 0,
            body_triangles: body_mesh.triangles().to_vec(),
            dome_vertex,
            mean_edge,
            static_reach: 0.0,
        })
    }

    /// Moves the body's free particles kinematically from `start` to their current positions
    /// over `duration` (s, at least one step), then releases them to the forces: the expander
    /// being filled. The stop criterion counts only after the release.
    pub(crate) fn fill_body(&mut self, start: &[Vec3A], duration: f32) -> Result<(), ImplantError> {
        let particles = self.body.particles_mut();
        if start.len() != particles.len() {
            return Err(ImplantError::InvalidParameter {
                param: Param::Start,
                value: start.len() as f64,
                expected: format!("one position per body particle ({})", particles.len()),
            });
        }
        let steps = (f64::from(duration) / f64::from(self.h)).ceil().max(1.0) as u64;
        let free: Vec<u32> = (0..particles.len() as u32)
            .filter(|&i| !particles.is_fixed(i))
            .collect();
        let end: Vec<Vec3A> = free
            .iter()
            .map(|&i| particles.positions()[i as usize])
            .collect();
        let span = steps as f32 * self.h;
        for (&i, &to) in free.iter().zip(&end) {
            particles.fix(i)?;
            let from = start[i as usize];
            particles.positions_mut()[i as usize] = from;
            particles.velocities_mut()[i as usize] = (to - from) / span;
        }
        self.fill = Some(Fill {
            particles: free,
            end,
            steps,
        });
        Ok(())
    }

    /// Ends the fill when its time has come.
    fn end_fill(&mut self) -> Result<(), ImplantError> {
        let Some(fill) = &self.fill else {
            return Ok(());
        };
        if self.steps < fill.steps {
            return Ok(());
        }
        let particles = self.body.particles_mut();
        for (&i, &to) in fill.particles.iter().zip(&fill.end) {
            particles.positions_mut()[i as usize] = to;
            particles.velocities_mut()[i as usize] = Vec3A::ZERO;
            particles.release(i)?;
        }
        self.fill = None;
        self.detector.reset();
        Ok(())
    }

    /// Starts the stop criterion over (a warm start: the tissue's rest metric or the body
    /// changed and the run is to settle again from where it is).
    pub(crate) fn restart_settle(&mut self) {
        self.detector.reset();
        self.settled = false;
    }

    /// The stop criterion's speed floor: summed displacement per step (cm) below which the
    /// particles' mean speed is under `RunParams::settle_speed`.
    pub(crate) fn speed_floor(&self) -> f64 {
        self.floor
    }

    /// The layers, taken back (to build a new run on them, warm).
    pub(crate) fn into_layers(self) -> TissueLayers {
        self.layers
    }

    /// The layers, to change their rest metric between settles.
    pub(crate) fn layers_mut(&mut self) -> &mut TissueLayers {
        &mut self.layers
    }

    /// Whether the body is still being filled.
    pub fn filling(&self) -> bool {
        self.fill.is_some()
    }

    /// The time step in use (s).
    pub fn time_step(&self) -> f32 {
        self.h
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Whether the stop criterion has fired.
    pub fn settled(&self) -> bool {
        self.settled
    }

    /// The stop criterion's window (steps).
    pub fn stop_window(&self) -> usize {
        self.params.stop.window
    }

    /// The step limit.
    pub fn max_steps(&self) -> u64 {
        self.params.stop.max_steps
    }

    /// The contact distance in use (cm).
    pub fn contact_distance(&self) -> f32 {
        self.contact_distance
    }

    /// The tissue layers.
    pub fn layers(&self) -> &TissueLayers {
        &self.layers
    }

    /// The second body's mass–spring system.
    pub fn body(&self) -> &MassSpringSystem {
        &self.body
    }

    /// One step in the thesis's order (module docs).
    pub fn step(&mut self) -> Result<StepSummary, ImplantError> {
        let _span = tracing::debug_span!("implant_step", step = self.steps).entered();
        self.end_fill()?;
        let h = self.h;
        let step = self.steps;
        self.layers.compute_forces();
        let tissue = self.layers.system_mut();
        self.body.compute_forces();
        tissue
            .update_velocities(h)
            .map_err(|e| diverged(e, "tissue velocity"))?;
        self.body
            .update_velocities(h)
            .map_err(|e| diverged(e, "implant velocity"))?;
        self.previous_tissue
            .copy_from_slice(tissue.particles().positions());
        self.previous_body
            .copy_from_slice(self.body.particles().positions());
        let contacts = {
            let _c = tracing::debug_span!("collide").entered();
            let (pos_a, vel_a, inv_a) = tissue.particles_mut().state_mut();
            let (pos_b, vel_b, inv_b) = self.body.particles_mut().state_mut();
            let n = self.collider.detect(pos_a, pos_b)?.len() as u32;
            if n > 0 {
                self.collider.apply_impulses(
                    &mut Bodies::two(vel_a, inv_a, vel_b, inv_b),
                    &self.params.response,
                )?;
            }
            n
        };
        let a = tissue
            .update_positions(h)
            .map_err(|e| diverged(e, "tissue position"))?;
        let b = self
            .body
            .update_positions(h)
            .map_err(|e| diverged(e, "implant position"))?;
        let thinned = self.layers.hold_thickness();
        let tissue = self.layers.system_mut();
        // Phase 3's contacts cover every pair closer than the contact distance and stopped
        // their approach, so an edge can only have crossed if something moved by a good part
        // of that distance; only then is the (detection-priced) correction run.
        let moved = a.max_move + b.max_move;
        let remaining = if moved >= 0.5 * self.contact_distance || !self.params.skip_safe_separation
        {
            let _c = tracing::debug_span!("separate").entered();
            let (pos_a, _, inv_a) = tissue.particles_mut().state_mut();
            let (pos_b, _, inv_b) = self.body.particles_mut().state_mut();
            self.collider
                .separate(
                    &mut Bodies::two(pos_a, inv_a, pos_b, inv_b),
                    Some(Snapshot {
                        a: &self.previous_tissue,
                        b: &self.previous_body,
                    }),
                    &self.params.response,
                )?
                .remaining
        } else {
            0
        };
        let displacement = a.displacement + b.displacement;
        self.steps += 1;
        if self.fill.is_none() && self.detector.push(displacement) {
            self.settled = true;
        }
        Ok(StepSummary {
            step,
            displacement,
            contacts,
            remaining_crossings: remaining,
            thinned,
        })
    }

    /// The deepest crossing of a layer-2 edge through the body at the current positions (cm; 0
    /// when nothing crosses), found by a fresh detection.
    pub fn max_penetration(&mut self) -> Result<f32, ImplantError> {
        let a = self.layers.system().particles().positions();
        let b = self.body.particles().positions();
        let contacts = self.collider.detect(a, b)?;
        Ok(contacts
            .iter()
            .filter(|c| c.is_crossing())
            .map(|c| c.depth)
            .fold(0.0, f32::max))
    }
}

/// The mean edge length of `mesh` (cm).
pub(crate) fn mean_edge_length(mesh: &TriMesh) -> f32 {
    let topo = mesh.topology();
    let p = mesh.positions();
    let total: f64 = topo
        .edges()
        .iter()
        .map(|&[a, b]| f64::from(p[a as usize].distance(p[b as usize])))
        .sum();
    (total / topo.edges().len().max(1) as f64) as f32
}

fn diverged(e: MssError, what: &'static str) -> ImplantError {
    match e {
        MssError::Diverged { step, particle } => ImplantError::Diverged {
            step,
            particle,
            what,
        },
        other => other.into(),
    }
}
