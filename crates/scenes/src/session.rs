//! The interactive session: an organ on its tray, stepped in real time, with the trainee's
//! tools — the probe (grab and drag), the scalpel (a cut along a path), the needle (a suture
//! across a wound) — its events, its surface for drawing, its volume drift and the force of the
//! tissue on the probe.

use std::collections::VecDeque;
use std::time::Instant;

use glam::{Mat3, Quat, Vec3, Vec3A};
use tissue_pbd::{
    ContactForceModel, ContactParams, Material, Pose, SelfCollision, SoftBody, StepSettings,
    StiffnessEstimator, ToolShape, DYN_PER_NEWTON,
};
use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent, SurgerySettings};

use crate::error::SceneError;
use crate::event::{TrainerEvent, TrainerEventKind};
use crate::organ::{Organ, Setting, Tray};
use crate::script::{AppendixPlan, AppendixProcedure, PressAndDrag, PressPlan, Script};

/// How many recent step times the session keeps for its median and p99.
const TIMES_KEPT: usize = 600;

/// The most points a scalpel path may have ([`Session::cut`]); a longer one is refused before
/// anything is done with it. A path drawn for a minute at 60 points a second has 3 600.
pub const MAX_CUT_POINTS: usize = 10_000;

/// The scalpel's queue ([`Session::cut`]) holds at most this many tray sides of cut, in segments
/// of [`SessionOptions::cut_segment`] (and never more than [`MAX_CUT_POINTS`] segments): 240
/// segments (2.4 s of cutting) on the appendix's 24 cm tray, 300 on the bunny's. A cut that
/// would queue more is refused, not truncated.
pub const CUT_QUEUE_TRAY_SIDES: f32 = 4.0;

/// Two sutures closer than this (cm, along the wound: where the needle would cross it against
/// the existing suture's linked nodes, whatever the depth) are the same stitch: the second is
/// refused ([`Session::suture`]). Skin stitches are placed 0.5–1 cm apart.
pub const SUTURE_SPACING_CM: f32 = 0.5;

/// How far below the tray's top (y = 0) the working space reaches, cm
/// ([`Session::work_space`]).
const WORK_SPACE_BELOW_CM: f32 = 1.0;

/// A session's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionOptions {
    /// The organ's material ([`Material::soft_tissue`]).
    pub material: Material,
    /// The solver's step ([`StepSettings::realtime`]: 10 ms as 9 substeps, in parallel).
    pub step: StepSettings,
    /// Contact with the tray and tools.
    pub contact: ContactParams,
    /// How deep the scalpel cuts below the surface it is drawn over (cm).
    pub cut_depth: f32,
    /// The probe grabs the surface nodes within this of the picked point (at least the picked
    /// triangle's corners), cm.
    pub grab_radius: f32,
    /// How far below the surface the needle passes (cm).
    pub suture_depth: f32,
    /// Scalpel paths are taken in segments of at least this length (cm); one segment is cut per
    /// step.
    pub cut_segment: f32,
    /// Self-collision of the organ's surface, cut walls included (tissue-pbd's
    /// [`SoftBody::set_self_collision`]; issue 35): on by default,
    /// `Some(`[`SelfCollision::default`]`)`, in every front end; `None` switches it off, for
    /// comparison (the trainer's `--no-self-collision`, the studio's checkbox, the C ABI's
    /// `self_collision` field, Python's `Body.self_collision`). Its cost: on the shipped bunny
    /// the trainer's realtime step with it is about twice the step without it, headless, and
    /// the studio runs the bunny with a cut at about 56 steps/s with it against about 58
    /// without (docs/trainer.md, "Self-collision in the front ends").
    /// [`Session::set_self_collision`] switches it on a running session.
    pub self_collision: Option<SelfCollision>,
}

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            material: Material::soft_tissue(),
            step: StepSettings {
                parallel: true,
                ..StepSettings::realtime()
            },
            contact: ContactParams {
                static_friction: 0.5,
                kinetic_friction: 0.5,
                ..ContactParams::default()
            },
            cut_depth: 1.0,
            grab_radius: 0.6,
            suture_depth: 0.35,
            cut_segment: 0.4,
            self_collision: Some(SelfCollision::default()),
        }
    }
}

/// A physical organ material for a session (issue 32): what the trainer's `--young-kpa`,
/// `--poisson`, `--density`, `--relaxation-time`, the studio's sliders and the C ABI's
/// material fields all give, turned into a session's settings once
/// ([`SessionOptions::material`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrganMaterial {
    /// Young's modulus `E` (kPa), Poisson's ratio `ν` (0 to 0.495), density `ρ` (g/cm³).
    pub elastic: tissue_fem::ElasticMaterial,
    /// The relaxation time `τ` (s) of the damping: every motion relative to the organ's rigid
    /// motion decays as `e^{−t/τ}` ([`StepSettings::with_relaxation_time`]).
    pub relaxation_time: f32,
}

impl OrganMaterial {
    /// The material scheme's default organ: 10 kPa, `ν = 0.45`, 1.05 g/cm³, `τ = 0.1 s`.
    pub fn soft_organ() -> Self {
        OrganMaterial {
            elastic: tissue_fem::ElasticMaterial {
                young_kpa: f64::from(Material::ORGAN_YOUNG_KPA),
                poisson: f64::from(Material::ORGAN_POISSON),
                density: f64::from(Material::ORGAN_DENSITY),
            },
            relaxation_time: StepSettings::MATERIAL_RELAXATION_TIME,
        }
    }

    /// A preset tissue's `E`, `ν`, `ρ` with the default relaxation time.
    pub fn preset(tissue: crate::TissuePreset) -> Self {
        OrganMaterial {
            elastic: tissue.material(),
            ..Self::soft_organ()
        }
    }

    /// The solver's material (stable neo-Hookean pairs, no distance or volume constraints).
    ///
    /// # Errors
    /// [`SceneError::Pbd`] naming the parameter out of its range (`E ≤ 0`, `ν` outside
    /// 0–0.495, `ρ ≤ 0`, or not finite) and the range.
    pub fn pbd(&self) -> Result<Material, SceneError> {
        Ok(Material::elastic(
            self.elastic.young_kpa as f32,
            self.elastic.poisson as f32,
            self.elastic.density as f32,
        )?)
    }
}

/// A parameter of an [`OrganMaterial`]: what a front end names when the session refuses a
/// material ([`SceneError::material_field`]), each in its own words (the trainer's flag, the C
/// ABI's struct field, the studio's input).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MaterialField {
    /// `E` (kPa).
    YoungKpa,
    /// `ν`.
    Poisson,
    /// `ρ` (g/cm³).
    Density,
    /// `τ` (s).
    RelaxationTime,
}

impl MaterialField {
    /// The field's name in [`OrganMaterial`] and in the front ends' JSON and C structs
    /// (`young_kpa`, `poisson`, `density`, `relaxation_time`).
    pub fn name(self) -> &'static str {
        match self {
            MaterialField::YoungKpa => "young_kpa",
            MaterialField::Poisson => "poisson",
            MaterialField::Density => "density",
            MaterialField::RelaxationTime => "relaxation_time",
        }
    }

    /// The field's value in `m`.
    pub fn of(self, m: &OrganMaterial) -> f64 {
        match self {
            MaterialField::YoungKpa => m.elastic.young_kpa,
            MaterialField::Poisson => m.elastic.poisson,
            MaterialField::Density => m.elastic.density,
            MaterialField::RelaxationTime => f64::from(m.relaxation_time),
        }
    }

    /// The material field a solver parameter is, if it is one.
    pub fn of_param(param: tissue_pbd::PbdParam) -> Option<MaterialField> {
        use tissue_pbd::PbdParam as P;
        match param {
            P::YoungModulus => Some(MaterialField::YoungKpa),
            P::PoissonRatio => Some(MaterialField::Poisson),
            P::Density => Some(MaterialField::Density),
            P::DistanceStiffness
            | P::VolumeStiffness
            | P::DistanceCompliance
            | P::VolumeCompliance
            | P::Dt
            | P::Substeps
            | P::Iterations
            | P::GravityX
            | P::GravityY
            | P::GravityZ
            | P::Damping
            | P::LinearDamping
            | P::Margin
            | P::Detection
            | P::StaticFriction
            | P::KineticFriction
            | P::ContactReach
            | P::CellSize
            | P::ColliderReach
            | P::Shapes
            | P::FloorAxis
            | P::FloorHeight
            | P::NodeTetCount
            | P::NodeCount
            | P::TetCount
            | P::Mass
            | P::ConstraintNodes
            | P::RestVolume
            | P::RestLength
            | P::Stiffness
            | P::Compliance
            | P::Solver
            | P::OverRelaxation => None,
        }
    }
}

impl SessionOptions {
    /// A session of the material scheme: `material`'s organ, stepped as
    /// [`StepSettings::material`] (32 XPBD substeps of 10 ms, in parallel) with its relaxation
    /// time; contact, tools and scalpel as [`SessionOptions::default`].
    ///
    /// # Errors
    /// [`SceneError::Pbd`] naming the material parameter out of range.
    ///
    /// ```
    /// use tissue_scenes::{MaterialField, OrganMaterial, SessionOptions, TissuePreset};
    /// let liver = OrganMaterial::preset(TissuePreset::Liver);
    /// let options = SessionOptions::material(&liver)?;
    /// assert_eq!(options.step.substeps, 32);
    /// let mut wrong = liver;
    /// wrong.elastic.poisson = 0.5;
    /// let refused = SessionOptions::material(&wrong).unwrap_err();
    /// assert_eq!(refused.material_field(), Some(MaterialField::Poisson));
    /// # Ok::<(), tissue_scenes::SceneError>(())
    /// ```
    pub fn material(material: &OrganMaterial) -> Result<SessionOptions, SceneError> {
        if !(material.relaxation_time.is_finite() && material.relaxation_time > 0.0) {
            return Err(SceneError::RelaxationTime {
                seconds: material.relaxation_time,
            });
        }
        Ok(SessionOptions {
            material: material.pbd()?,
            step: StepSettings {
                parallel: true,
                ..StepSettings::material()
            }
            .with_relaxation_time(material.relaxation_time),
            ..SessionOptions::default()
        })
    }
}

#[derive(Debug, Clone)]
struct Grab {
    /// (node, attachment id, the node's offset from the grabbed point).
    nodes: Vec<(u32, tissue_pbd::AttachmentId, Vec3)>,
    /// The force on the body's holders just before the grab (dyn): the pins' share, which the
    /// probe's force leaves out.
    baseline: Vec3,
    /// Where the grabbed point is asked to be.
    target: Vec3,
}

/// A demonstration the session plays on its organ ([`Session::play`]): the scripted scenario
/// of its setting, the same one the headless `trainer` runs.
struct Playing {
    script: Box<dyn Script + Send>,
    /// The script's steps taken.
    k: usize,
    /// The probe's tool id when the demonstration presses one into the organ.
    probe: Option<usize>,
}

/// A trainee's session on one organ.
pub struct Session {
    label: String,
    setting: Setting,
    options: SessionOptions,
    body: SoftBody,
    surgery: Surgery,
    initial_nodes: usize,
    initial_triangles: usize,
    surface: Vec<[u32; 3]>,
    surface_version: u64,
    grab: Option<Grab>,
    force: Vec3,
    cuts: VecDeque<(Pose, Pose)>,
    blade: ToolShape,
    times_ms: VecDeque<f64>,
    steps: u64,
    worst_drift: f64,
    /// The organ's largest extent (cm); its tray is [`Tray::for_extent`] of it.
    extent: f32,
    tray_side: f32,
    /// Per contact tool ([`Session::add_tool`]): its force model after the last step and the
    /// stiffness estimate that feeds it.
    tools: Vec<(ContactForceModel, StiffnessEstimator)>,
    /// The demonstration playing, if any.
    playing: Option<Playing>,
    /// The tray demonstration's probe, once added (a contact tool; parked between plays).
    demo_probe: Option<usize>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("label", &self.label)
            .field("nodes", &self.body.node_count())
            .field("tets", &self.body.tets().len())
            .field("steps", &self.steps)
            .finish_non_exhaustive()
    }
}

impl Session {
    /// A session on `organ`.
    ///
    /// # Errors
    /// [`SceneError::Pbd`] / [`SceneError::Surgery`] if the body cannot be built.
    pub fn new(organ: &Organ, options: SessionOptions) -> Result<Session, SceneError> {
        let _span = tracing::info_span!("session_new", organ = %organ.label).entered();
        let extent = organ.extent();
        let tray = Tray::for_extent(extent);
        let mut body = organ.body(&options.material, options.step, options.contact, tray)?;
        body.set_self_collision(options.self_collision)?;
        let tray_side = tray.side;
        let surgery = Surgery::new(&body, SurgerySettings::default())?;
        let surface = surgery.boundary_faces(&body);
        let depth = options.cut_depth;
        Ok(Session {
            label: organ.label.clone(),
            setting: organ.setting,
            initial_nodes: body.node_count(),
            initial_triangles: surface.len(),
            surface,
            surface_version: 1,
            grab: None,
            force: Vec3::ZERO,
            cuts: VecDeque::new(),
            // A blade in its local plane x = 0: the cutting edge `depth` below the surface
            // (local −y is into the tissue), the back 1 cm above it.
            blade: ToolShape::Blade {
                a: Vec3::new(0.0, -depth, -0.05),
                b: Vec3::new(0.0, -depth, 0.05),
                c: Vec3::new(0.0, 1.0, 0.0),
                thickness: 0.02,
            },
            times_ms: VecDeque::with_capacity(TIMES_KEPT),
            steps: 0,
            worst_drift: 0.0,
            extent,
            tray_side,
            tools: Vec::new(),
            playing: None,
            demo_probe: None,
            options,
            body,
            surgery,
        })
    }

    /// The organ's label.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// How the organ is held.
    pub fn setting(&self) -> Setting {
        self.setting
    }

    /// The tray's side (cm): a square centred on x = z = 0, its top at y = 0.
    pub fn tray_side(&self) -> f32 {
        self.tray_side
    }

    /// The working space of the trainee's tools (cm), as its lowest and highest corners: the
    /// tray's square grown by half its side on every edge (x and z within ± the tray's side),
    /// from 1 cm below the tray's top to a tray's side (three times the organ) above it. Drag
    /// targets are clamped into it ([`Session::drag`]); grab, cut and suture points outside it
    /// are refused.
    pub fn work_space(&self) -> (Vec3, Vec3) {
        let s = self.tray_side;
        (Vec3::new(-s, -WORK_SPACE_BELOW_CM, -s), Vec3::new(s, s, s))
    }

    /// Refuses a tool's point that is not finite or is outside [`Session::work_space`].
    fn in_work_space(&self, what: &str, p: Vec3) -> Result<(), SceneError> {
        let (lo, hi) = self.work_space();
        if p.is_finite() && p.cmpge(lo).all() && p.cmple(hi).all() {
            return Ok(());
        }
        Err(SceneError::Tool(format!(
            "{what} ({}, {}, {}) cm is off the tray: the tools work within x and z of ±{} cm, y \
             from {} to {} cm; pick a point on the organ",
            p.x, p.y, p.z, hi.x, lo.y, hi.y
        )))
    }

    /// The most scalpel segments the queue holds ([`CUT_QUEUE_TRAY_SIDES`]).
    pub fn max_queued_cuts(&self) -> usize {
        let length = CUT_QUEUE_TRAY_SIDES * self.tray_side;
        let segments = (length / self.options.cut_segment.max(0.01)).ceil();
        if segments.is_finite() {
            (segments as usize).clamp(1, MAX_CUT_POINTS)
        } else {
            MAX_CUT_POINTS
        }
    }

    /// Scalpel segments queued, cut one per step.
    pub fn queued_cuts(&self) -> usize {
        self.cuts.len()
    }

    /// The body (read only).
    pub fn body(&self) -> &SoftBody {
        &self.body
    }

    /// Node positions, cm.
    pub fn positions(&self) -> &[Vec3A] {
        self.body.positions()
    }

    /// The surface triangles (outward), over the node indices.
    pub fn surface(&self) -> &[[u32; 3]] {
        &self.surface
    }

    /// Changes whenever [`Session::surface`] does (after a cut or suture).
    pub fn surface_version(&self) -> u64 {
        self.surface_version
    }

    /// The session's settings (with the self-collision in force).
    pub fn options(&self) -> &SessionOptions {
        &self.options
    }

    /// Switches self-collision of the organ's surface on (with these settings) or off (`None`)
    /// from the next step on ([`SessionOptions::self_collision`]).
    ///
    /// # Errors
    /// [`SceneError::Pbd`] for settings out of range (a thickness fraction outside `(0, 1]`, a
    /// negative friction coefficient); the setting in force is then kept.
    pub fn set_self_collision(
        &mut self,
        settings: Option<SelfCollision>,
    ) -> Result<(), SceneError> {
        self.body.set_self_collision(settings)?;
        self.options.self_collision = settings;
        Ok(())
    }

    /// The self-contacts of the last step's last substep: (found, active), the vertex–triangle
    /// pairs of the surface within the detection band, and those the solver had to push apart
    /// (tissue-pbd's [`SoftBody::self_contact_counts`]); `(0, 0)` with self-collision off.
    pub fn self_contacts(&self) -> (usize, usize) {
        if self.body.self_collision().is_none() {
            return (0, 0);
        }
        self.body.self_contact_counts()
    }

    /// Self-contacts the last step found past the solver's buffers and so did not hold
    /// (tissue-pbd's [`SoftBody::self_contacts_dropped`]): 0 unless the surface is badly
    /// tangled.
    pub fn self_contacts_dropped(&self) -> usize {
        if self.body.self_collision().is_none() {
            return 0;
        }
        self.body.self_contacts_dropped()
    }

    /// The number of pairs of [`Session::surface`]'s triangles that intersect now, counted
    /// exactly ([`surface_self_intersections`]): 0 when the organ does not pass through itself.
    /// The two walls of a fresh cut touch (their nodes were duplicated in place) and count until
    /// the steps part them. Allocates; one BVH over the surface.
    ///
    /// # Errors
    /// [`SceneError::Pbd`] for a non-finite position (a diverged body).
    pub fn self_intersections(&self) -> Result<usize, SceneError> {
        surface_self_intersections(self.body.positions(), &self.surface)
    }

    /// Buffer sizes that hold what cuts are likely to add: (vertices, triangles).
    pub fn capacity(&self) -> (usize, usize) {
        (
            self.initial_nodes + (self.initial_nodes / 2).max(20_000),
            2 * self.initial_triangles + 40_000,
        )
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// `V / V₀ − 1`: the volume now against the rest volume of its tetrahedra.
    pub fn volume_drift(&self) -> f64 {
        self.body.volume() / self.body.rest_volume() - 1.0
    }

    /// The largest |volume drift| seen at the end of a step.
    pub fn worst_drift(&self) -> f64 {
        self.worst_drift
    }

    /// Median and 99th percentile of the recent step times (ms), the tool work included.
    pub fn step_ms(&self) -> (f64, f64) {
        let mut t: Vec<f64> = self.times_ms.iter().copied().collect();
        if t.is_empty() {
            return (0.0, 0.0);
        }
        t.sort_by(f64::total_cmp);
        let at = |q: f64| t[((t.len() - 1) as f64 * q).round() as usize];
        (at(0.5), at(0.99))
    }

    /// The force of the tissue on the probe at the last step (newtons; zero when nothing is
    /// held).
    pub fn tool_force(&self) -> Vec3 {
        self.force
    }

    /// The probe's tip: where the grabbed point is asked to be, or the demonstration's probe
    /// while it is pressed in; `None` otherwise.
    pub fn tool_tip(&self) -> Option<Vec3> {
        if let Some(g) = &self.grab {
            return Some(g.target);
        }
        let probe = self.playing.as_ref()?.probe?;
        let tip = self.body.tool(probe).ok()?.pose().translation;
        // Parked above the organ until the press starts.
        (tip.y < self.extent + 1.0).then_some(tip)
    }

    /// Takes one step: the probe's targets, the solver, one queued scalpel segment.
    ///
    /// # Errors
    /// [`SceneError::Pbd`] when the simulation diverges, [`SceneError::Surgery`] when a cut
    /// fails.
    pub fn step(&mut self) -> Result<Vec<TrainerEvent>, SceneError> {
        let start = Instant::now();
        let mut events = Vec::new();
        if let Some(p) = &mut self.playing {
            p.k += 1;
            p.script.before_step(p.k, &mut self.body)?;
        }
        if let Some(g) = &self.grab {
            for &(_, id, offset) in &g.nodes {
                self.body.set_attachment_target(id, g.target + offset)?;
            }
        }
        self.body.step()?;
        self.steps += 1;
        self.force = self.probe_force();
        for (id, (model, estimator)) in self.tools.iter_mut().enumerate() {
            let mut next = ContactForceModel::from_body(&self.body, id, 0.0)?;
            next.stiffness = estimator.update(&next);
            *model = next;
        }
        if let Some((from, to)) = self.cuts.pop_front() {
            let sweep = BladeSweep::new(&self.blade, &from, &to)?;
            let happened = self.surgery.cut(&mut self.body, &sweep)?;
            self.record(&happened, &mut events);
        }
        self.play_after_step(&mut events)?;
        let drift = self.volume_drift().abs();
        if drift.is_finite() {
            self.worst_drift = self.worst_drift.max(drift);
        }
        if self.times_ms.len() == TIMES_KEPT {
            self.times_ms.pop_front();
        }
        self.times_ms.push_back(start.elapsed().as_secs_f64() * 1e3);
        Ok(events)
    }

    /// Adds a kinematic contact tool (a capsule: a probe's tip, a needle, a shaft; or a blade)
    /// at `pose` (cm) and returns its id (0, 1, … in order). It pushes the tissue with the
    /// session's contact parameters from the next step on; its force is
    /// [`Session::contact_force_model`].
    ///
    /// # Errors
    /// [`SceneError::Pbd`] for a degenerate shape or a bad pose.
    pub fn add_tool(&mut self, shape: ToolShape, pose: Pose) -> Result<usize, SceneError> {
        let id = self.body.add_tool(shape, pose, self.options.contact)?;
        self.track_tool(pose);
        Ok(id)
    }

    /// Starts the force model of the tool just added to the body at `pose`.
    fn track_tool(&mut self, pose: Pose) {
        let model = ContactForceModel {
            step: self.body.step_count(),
            origin: pose.translation,
            ..ContactForceModel::default()
        };
        self.tools.push((model, StiffnessEstimator::default()));
    }

    /// Moves contact tool `id`: the next step sweeps it from its last pose to `pose`.
    ///
    /// # Errors
    /// [`SceneError::Pbd`] for an unknown tool or a bad pose.
    pub fn set_tool_pose(&mut self, id: usize, pose: Pose) -> Result<(), SceneError> {
        Ok(self.body.set_tool_pose(id, pose)?)
    }

    /// The contact tools added so far.
    pub fn tool_count(&self) -> usize {
        self.tools.len()
    }

    /// Contact tool `id`'s force model after the last step (`tissue-pbd`'s
    /// [`ContactForceModel`]: evaluate it at the tool's newest position for the force in
    /// newtons between steps), or `None` for an unknown tool.
    pub fn contact_force_model(&self, id: usize) -> Option<&ContactForceModel> {
        self.tools.get(id).map(|t| &t.0)
    }

    /// Cuts at once along a blade sweep from `from` to `to` (the scalpel's blade in its own
    /// frame: its plane x = 0, its edge along z [`SessionOptions::cut_depth`] below the frame's
    /// origin, i.e. at local y = −depth, its back 1 cm above; a pose puts the origin on the
    /// surface where the cut goes, local −y into the tissue, local z along the cut).
    ///
    /// # Errors
    /// [`SceneError::Pbd`] for a bad pose, [`SceneError::Surgery`] when the cut fails.
    pub fn cut_sweep(&mut self, from: Pose, to: Pose) -> Result<Vec<TrainerEvent>, SceneError> {
        let sweep = BladeSweep::new(&self.blade, &from, &to)?;
        let happened = self.surgery.cut(&mut self.body, &sweep)?;
        let mut events = Vec::new();
        self.record(&happened, &mut events);
        Ok(events)
    }

    /// Starts the demonstration of the organ's setting, from the next step on: on the
    /// appendix the procedure ([`AppendixProcedure`]: grasp and lift, incise, cut off, suture;
    /// 200 steps), on a tray a probe pressed 1.5 cm into the organ's top and dragged across it
    /// ([`PressAndDrag::on_tray`] with [`PressPlan::default`]: 250 steps, the headless
    /// `trainer`'s timeline; the probe is a contact tool, added at the first play, parked above
    /// the organ after each). It is meant for a fresh session (the procedure grasps the
    /// appendix's tip where it lies). While it plays, the trainee's tools are refused; its
    /// events come from [`Session::step`], the last one `demo_finished`.
    ///
    /// # Errors
    /// [`SceneError::Tool`] when a demonstration is already playing or the organ does not
    /// suit its setting's script; [`SceneError::Pbd`] when the solver refuses the probe.
    pub fn play(&mut self) -> Result<TrainerEvent, SceneError> {
        if self.playing.is_some() {
            return Err(SceneError::Tool(
                "a demonstration is already playing: wait for it to end or reset".to_owned(),
            ));
        }
        self.release()?;
        self.cuts.clear();
        let (script, probe, text): (Box<dyn Script + Send>, _, _) = match self.setting {
            Setting::Appendix => (
                Box::new(AppendixProcedure::new(
                    &mut self.body,
                    AppendixPlan::default(),
                )?),
                None,
                "demonstration: the appendix is grasped, incised, its tip cut off, the \
                 incision sutured",
            ),
            Setting::Cantilever => {
                return Err(SceneError::Tool(
                    "a cantilever has no demonstration: it settles under its own weight".into(),
                ))
            }
            Setting::Tray => {
                let (extent, plan) = (self.extent, PressPlan::default());
                let script = match self.demo_probe {
                    Some(tool) => PressAndDrag::again(&mut self.body, tool, extent, plan)?,
                    None => {
                        let script = PressAndDrag::on_tray(
                            &mut self.body,
                            extent,
                            plan,
                            self.options.contact,
                        )?;
                        self.track_tool(PressAndDrag::parked(extent));
                        script
                    }
                };
                let tool = script.tool();
                self.demo_probe = Some(tool);
                (
                    Box::new(script),
                    Some(tool),
                    "demonstration: a probe presses 1.5 cm into the organ and drags across it",
                )
            }
        };
        self.playing = Some(Playing {
            script,
            k: 0,
            probe,
        });
        Ok(TrainerEvent::new(
            self.steps,
            TrainerEventKind::DemoStarted,
            text,
        ))
    }

    /// Whether a demonstration is playing.
    pub fn playing(&self) -> bool {
        self.playing.is_some()
    }

    /// The demonstration's part of a step after the solver's: its cuts and sutures, the probe's
    /// force, and its end.
    fn play_after_step(&mut self, events: &mut Vec<TrainerEvent>) -> Result<(), SceneError> {
        let Some(p) = &mut self.playing else {
            return Ok(());
        };
        let out = p
            .script
            .after_step(p.k, &mut self.body, &mut self.surgery)?;
        let finished = p.k >= p.script.steps();
        if let Some(tool) = p.probe {
            self.force = self.body.tool_force(tool)? / DYN_PER_NEWTON;
            if finished {
                self.body
                    .set_tool_pose(tool, PressAndDrag::parked(self.extent))?;
            }
        }
        self.record(&out.events, events);
        if finished {
            self.playing = None;
            self.force = Vec3::ZERO;
            events.push(TrainerEvent::new(
                self.steps,
                TrainerEventKind::DemoFinished,
                "demonstration finished: the organ is yours",
            ));
        }
        Ok(())
    }

    /// Refuses a trainee's tool while a demonstration plays.
    fn hands_off(&self) -> Result<(), SceneError> {
        if self.playing.is_some() {
            return Err(SceneError::Tool(
                "a demonstration is playing: wait for it to end or reset".to_owned(),
            ));
        }
        Ok(())
    }

    /// The force of the tissue on the grabbed nodes (N).
    fn probe_force(&self) -> Vec3 {
        let Some(g) = &self.grab else {
            return Vec3::ZERO;
        };
        // tissue-pbd gives the force on all holders together (attachments and pins): the probe's
        // is what the grab added to it.
        (self.body.holding_force() - g.baseline) / DYN_PER_NEWTON
    }

    fn record(&mut self, happened: &[SurgeryEvent], events: &mut Vec<TrainerEvent>) {
        if happened.is_empty() {
            return;
        }
        events.extend(
            happened
                .iter()
                .map(|e| TrainerEvent::surgery(self.steps, e)),
        );
        self.surface = self.surgery.boundary_faces(&self.body);
        self.surface_version += 1;
    }

    /// Grabs the surface near `point` on surface triangle `triangle` (an index into
    /// [`Session::surface`]): the free surface nodes within the grab radius, at least the
    /// triangle's corners, follow the probe until [`Session::release`].
    ///
    /// # Errors
    /// [`SceneError::Tool`] for a triangle out of range or a point that is not finite or is
    /// outside [`Session::work_space`].
    pub fn grab(&mut self, point: Vec3, triangle: usize) -> Result<TrainerEvent, SceneError> {
        self.hands_off()?;
        let corners = *self.surface.get(triangle).ok_or_else(|| {
            SceneError::Tool(format!(
                "no surface triangle {triangle} (the surface has {}): pick the organ again",
                self.surface.len()
            ))
        })?;
        if !point.is_finite() {
            return Err(SceneError::Tool("the grab point is not finite".to_owned()));
        }
        self.in_work_space("the grab point", point)?;
        self.release()?;
        let x = self.body.positions();
        let w = self.body.inverse_masses();
        let r2 = self.options.grab_radius * self.options.grab_radius;
        let mut picked: Vec<u32> = self
            .surface
            .iter()
            .flatten()
            .copied()
            .filter(|&n| Vec3::from(x[n as usize]).distance_squared(point) <= r2)
            .chain(corners)
            .filter(|&n| w[n as usize] > 0.0)
            .collect();
        picked.sort_unstable();
        picked.dedup();
        let baseline = self.body.holding_force();
        let mut nodes = Vec::with_capacity(picked.len());
        for n in picked {
            let p = Vec3::from(self.body.positions()[n as usize]);
            let id = self.body.attach(n, p)?;
            nodes.push((n, id, p - point));
        }
        let count = nodes.len();
        self.grab = Some(Grab {
            nodes,
            baseline,
            target: point,
        });
        Ok(TrainerEvent::new(
            self.steps,
            TrainerEventKind::Grabbed,
            format!("probe grabbed {count} nodes"),
        ))
    }

    /// Moves the grabbed point towards `target` (cm) from the next step on, clamped into
    /// [`Session::work_space`] (a target off the tray pulls to its edge; one that is not finite
    /// is ignored).
    pub fn drag(&mut self, target: Vec3) {
        let (lo, hi) = self.work_space();
        if let Some(g) = &mut self.grab {
            if target.is_finite() {
                g.target = target.clamp(lo, hi);
            }
        }
    }

    /// Lets go of what the probe holds.
    ///
    /// # Errors
    /// [`SceneError::Pbd`] (not expected: the nodes exist).
    pub fn release(&mut self) -> Result<Option<TrainerEvent>, SceneError> {
        let Some(g) = self.grab.take() else {
            return Ok(None);
        };
        for &(n, _, _) in &g.nodes {
            self.body.unpin(n)?;
        }
        self.force = Vec3::ZERO;
        Ok(Some(TrainerEvent::new(
            self.steps,
            TrainerEventKind::Released,
            format!("probe released {} nodes", g.nodes.len()),
        )))
    }

    /// Queues a scalpel cut along `path` (surface points, cm) seen along `view_dir`: the blade's
    /// plane holds the path's overall direction and the view direction; it cuts
    /// [`SessionOptions::cut_depth`] below the path, one segment per step. Returns the segments
    /// queued.
    ///
    /// Bounded: a path of more than [`MAX_CUT_POINTS`] points is refused before it is looked
    /// at, and a cut that would queue more segments than [`Session::max_queued_cuts`] (counting
    /// those still waiting) is refused whole, nothing queued.
    ///
    /// # Errors
    /// [`SceneError::Tool`] for fewer than two distinct points, more than [`MAX_CUT_POINTS`], a
    /// path along the view, non-finite input, a point outside [`Session::work_space`], or a
    /// full queue.
    pub fn cut(&mut self, path: &[Vec3], view_dir: Vec3) -> Result<usize, SceneError> {
        self.hands_off()?;
        if path.len() > MAX_CUT_POINTS {
            return Err(SceneError::Tool(format!(
                "a cut path of {} points: at most {MAX_CUT_POINTS} are taken; send fewer points \
                 (one every few millimetres is enough)",
                path.len()
            )));
        }
        let v = view_dir.normalize_or_zero();
        if v == Vec3::ZERO || path.iter().any(|p| !p.is_finite()) {
            return Err(SceneError::Tool(
                "a cut needs finite surface points and a view direction".to_owned(),
            ));
        }
        for p in path {
            self.in_work_space("a cut path point", *p)?;
        }
        let (Some(&first), Some(&last)) = (path.first(), path.last()) else {
            return Err(SceneError::Tool(
                "a cut needs a path of two points or more".to_owned(),
            ));
        };
        let across = last - first;
        let d = (across - v * across.dot(v)).normalize_or_zero();
        if d == Vec3::ZERO {
            return Err(SceneError::Tool(
                "draw the cut across the organ, not along the view".to_owned(),
            ));
        }
        let n = d.cross(v).normalize();
        // Local x = the blade's normal, local y = towards the viewer, local z = along the cut.
        let rotation = Quat::from_mat3(&Mat3::from_cols(n, -v, d));
        let centroid = path.iter().copied().sum::<Vec3>() / path.len() as f32;
        let on_plane = |p: Vec3| p - n * n.dot(p - centroid);
        let mut points = vec![on_plane(first)];
        for &p in &path[1..] {
            let q = on_plane(p);
            let last_kept = points[points.len() - 1];
            if q.distance(last_kept) >= self.options.cut_segment {
                points.push(q);
            }
        }
        let end = on_plane(last);
        if points.len() == 1 || points[points.len() - 1].distance(end) > 1e-4 {
            points.push(end);
        }
        if points.len() < 2 || points[0].distance(end) < 1e-3 {
            return Err(SceneError::Tool(
                "the cut is too short: drag further".to_owned(),
            ));
        }
        let segments = points.len() - 1;
        let (queued, max) = (self.cuts.len(), self.max_queued_cuts());
        if queued + segments > max {
            return Err(SceneError::Tool(format!(
                "this cut would queue {segments} segments behind {queued} still to cut, more \
                 than the {max} a session holds ({CUT_QUEUE_TRAY_SIDES} tray sides): wait for \
                 the cut in progress to finish, or draw a shorter cut"
            )));
        }
        let pose = |p: Vec3| Pose::new(rotation, p);
        for pair in points.windows(2) {
            self.cuts.push_back((pose(pair[0]), pose(pair[1])));
        }
        Ok(segments)
    }

    /// Places a suture between surface points `a` and `b` on the two sides of a wound: a needle
    /// passes below them (the depth along the surface's inward normal), and the nodes of the
    /// wound's walls nearest its crossings are linked.
    ///
    /// A second stitch at the same place is not a new stitch: a suture whose needle would pass
    /// within [`SUTURE_SPACING_CM`] of an existing suture's linked nodes (at any of the depths it
    /// tries) is refused, and nothing is placed.
    ///
    /// # Errors
    /// [`SceneError::Tool`] for non-finite or coincident points, points outside
    /// [`Session::work_space`], or a suture already there; [`SceneError::Surgery`].
    pub fn suture(&mut self, a: Vec3, b: Vec3) -> Result<TrainerEvent, SceneError> {
        self.hands_off()?;
        if !(a.is_finite() && b.is_finite()) || a.distance(b) < 1e-3 {
            return Err(SceneError::Tool(
                "click two different points, one on each side of the wound".to_owned(),
            ));
        }
        self.in_work_space("the suture's first point", a)?;
        self.in_work_space("the suture's second point", b)?;
        let inward = -(self.normal_near(a) + self.normal_near(b)).normalize_or(Vec3::Y);
        let dir = (b - a).normalize();
        let reach = 0.5 * a.distance(b) + 0.6;
        let mid = 0.5 * (a + b);
        let base = self.options.suture_depth;
        const DEPTHS: [f32; 4] = [1.0, 0.6, 1.6, 2.4];
        // Where the needle crosses the wound, at the depths it tries: from mid + inward·0.6·base
        // to mid + inward·2.4·base.
        let (shallow, deep) = (mid + inward * 0.6 * base, mid + inward * 2.4 * base);
        let x = self.body.positions();
        for (id, suture) in self.surgery.sutures().iter().enumerate() {
            let Some(suture) = suture else { continue };
            let [p, q] = suture.nodes.map(|n| Vec3::from(x[n as usize]));
            let d = distance_to_segment(0.5 * (p + q), shallow, deep);
            if d < SUTURE_SPACING_CM {
                return Err(SceneError::Tool(format!(
                    "a suture is already there (suture {id}, {d:.2} cm from where this one would \
                     go): a second stitch at the same place is not a new one; place the next at \
                     least {SUTURE_SPACING_CM} cm along the wound"
                )));
            }
        }
        for depth in DEPTHS.map(|k| k * base) {
            let c = mid + inward * depth;
            if let Some(e) =
                self.surgery
                    .suture_segment(&mut self.body, c - dir * reach, c + dir * reach)?
            {
                self.surface_version += 1;
                return Ok(TrainerEvent::surgery(self.steps, &e));
            }
        }
        Ok(TrainerEvent::new(
            self.steps,
            TrainerEventKind::SutureMissed,
            "the needle did not cross a wound there: click on each side of an open cut",
        ))
    }

    /// The outward normal of the surface triangle nearest `p` (by centroid).
    fn normal_near(&self, p: Vec3) -> Vec3 {
        let x = self.body.positions();
        self.surface
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| Vec3::from(x[i as usize]));
                ((a + b + c) / 3.0, (b - a).cross(c - a))
            })
            .min_by(|u, v| u.0.distance_squared(p).total_cmp(&v.0.distance_squared(p)))
            .map_or(Vec3::Y, |(_, n)| n.normalize_or(Vec3::Y))
    }
}

/// The number of pairs of `surface`'s triangles (over `positions`, cm) that intersect, counted
/// exactly (tissue-pbd's [`tissue_pbd::count_intersecting_pairs`]: a triangle–triangle test in
/// `f64`, neighbours by their shared indices): what self-collision is judged by
/// ([`Session::self_intersections`], the headless `trainer`'s `self-intersections N`).
///
/// # Errors
/// [`SceneError::Pbd`] for a triangle naming a missing node or a non-finite position.
pub fn surface_self_intersections(
    positions: &[Vec3A],
    surface: &[[u32; 3]],
) -> Result<usize, SceneError> {
    Ok(tissue_pbd::count_intersecting_pairs(positions, surface)?)
}

/// The distance from `p` to the segment `a`–`b`.
fn distance_to_segment(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Self-collision is on by default, switched off and on again on a running session (a
    /// refused setting keeps the one in force), off through the options (`None`), and a box at
    /// rest does not pass through itself.
    #[test]
    fn self_collision_is_on_by_default_and_switched() {
        let tets = tissue_mesh::tet_box(4, 2, 4, Vec3::new(4.0, 2.0, 4.0)).unwrap();
        let organ = Organ::from_tets(&tets, "box").unwrap();
        let mut s = Session::new(&organ, SessionOptions::default()).unwrap();
        assert_eq!(s.options().self_collision, Some(SelfCollision::default()));
        assert!(s.body().self_collision().is_some());
        for _ in 0..5 {
            s.step().unwrap();
        }
        assert_eq!(s.self_intersections().unwrap(), 0);
        assert_eq!(s.self_contacts_dropped(), 0);
        let bad = SelfCollision {
            thickness_fraction: 0.0,
            ..SelfCollision::default()
        };
        assert!(s.set_self_collision(Some(bad)).is_err());
        assert_eq!(s.options().self_collision, Some(SelfCollision::default()));
        assert!(s.body().self_collision().is_some());
        s.set_self_collision(None).unwrap();
        assert!(s.body().self_collision().is_none() && s.options().self_collision.is_none());
        s.step().unwrap();
        assert_eq!(s.self_contacts(), (0, 0));
        s.set_self_collision(Some(SelfCollision::default()))
            .unwrap();
        assert_eq!(s.options().self_collision, Some(SelfCollision::default()));
        assert!(s.body().self_collision().is_some());
        s.step().unwrap();
        assert_eq!(s.self_intersections().unwrap(), 0);
        // Off from the start through the options, for comparison.
        let options = SessionOptions {
            self_collision: None,
            ..SessionOptions::default()
        };
        let s = Session::new(&organ, options).unwrap();
        assert_eq!(s.options().self_collision, None);
        assert!(s.body().self_collision().is_none());
    }
}
