//! The trainer: a soft body (tissue-scenes' `Session` on tissue-pbd) stepped by the host, its
//! surface with revision counters, contact tools posed by the host, the scalpel, the needle and
//! the probe's grasp, the surgery events, and the haptic force query.
//!
//! Threads: the body's simulation state sits behind one mutex, held by every call that reads or
//! changes it (a step holds it for the whole step). The tool poses the host sets and the force
//! models of the last step sit apart, each behind a lock held only to copy a few bytes (the
//! model is shared by `Arc`), so `tissue_tool_set_pose` and `tissue_tool_force` never wait for a
//! step.

use std::collections::VecDeque;
use std::ffi::c_char;
use std::sync::{Arc, Mutex, MutexGuard, RwLock};

use ::tissue_mesh::{TetMesh, TriMesh};
use glam::{Quat, Vec3};
use tissue_pbd::{ContactForceModel, Pose, ToolShape};
use tissue_scenes::{
    Organ, SelfCollision, Session, SessionOptions, TrainerEvent, TrainerEventKind,
};

use crate::ffi::{
    copy_out, free_handle, get, guard, guard_void, into_handle, poisoned, put, put_opt, slice,
    tissue_status, vec3, Error,
};
use crate::material::{shipped_of, tissue_material, tissue_scheme};
use crate::mesh::{bytemuck_vec3, tissue_mesh, MeshKind};

/// A rigid placement: `world = rotation · local + translation`, cm.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct tissue_pose {
    /// A unit quaternion (x, y, z, w); identity is {0, 0, 0, 1}.
    pub rotation: [f32; 4],
    /// cm.
    pub translation: [f32; 3],
}

/// An organ shipped with the library.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_shipped_organ {
    /// The Stanford Bunny, 10 cm, on a tray (its surface filled with tetrahedra on load).
    TISSUE_ORGAN_BUNNY = 0,
    /// SOFA's liver, 16 cm, on a tray.
    TISSUE_ORGAN_LIVER = 1,
    /// An appendix-like organ along x, 8 × 2 × 2 cm, lying on a floor at y = 0, its base
    /// (x < −3.7 cm) pinned.
    TISSUE_ORGAN_APPENDIX = 2,
}

/// What happened (`tissue_event.kind`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_event_kind {
    /// The scalpel opened more of the tissue.
    TISSUE_EVENT_CUT_ADVANCED = 0,
    /// A piece came off.
    TISSUE_EVENT_PIECE_DETACHED = 1,
    /// A suture was placed.
    TISSUE_EVENT_SUTURE_PLACED = 2,
    /// A suture was removed.
    TISSUE_EVENT_SUTURE_REMOVED = 3,
    /// The needle crossed no wound.
    TISSUE_EVENT_SUTURE_MISSED = 4,
    /// The probe grasped tissue.
    TISSUE_EVENT_GRABBED = 5,
    /// The probe let go.
    TISSUE_EVENT_RELEASED = 6,
    /// A surgery event of a kind this list does not name yet (tissue-scenes' `surgery` kind);
    /// its text says what it is.
    TISSUE_EVENT_OTHER = 7,
    /// A demonstration started (`tissue_body_play`).
    TISSUE_EVENT_DEMO_STARTED = 8,
    /// The demonstration ended: the organ is the host's again.
    TISSUE_EVENT_DEMO_FINISHED = 9,
}

impl From<TrainerEventKind> for tissue_event_kind {
    /// Every kind of tissue-scenes to its own C value, in one exhaustive match (a new kind is a
    /// compile error here until the header has its value).
    fn from(kind: TrainerEventKind) -> Self {
        use tissue_event_kind::*;
        match kind {
            TrainerEventKind::CutAdvanced => TISSUE_EVENT_CUT_ADVANCED,
            TrainerEventKind::PieceDetached => TISSUE_EVENT_PIECE_DETACHED,
            TrainerEventKind::SuturePlaced => TISSUE_EVENT_SUTURE_PLACED,
            TrainerEventKind::SutureRemoved => TISSUE_EVENT_SUTURE_REMOVED,
            TrainerEventKind::SutureMissed => TISSUE_EVENT_SUTURE_MISSED,
            TrainerEventKind::Grabbed => TISSUE_EVENT_GRABBED,
            TrainerEventKind::Released => TISSUE_EVENT_RELEASED,
            TrainerEventKind::Surgery => TISSUE_EVENT_OTHER,
            TrainerEventKind::DemoStarted => TISSUE_EVENT_DEMO_STARTED,
            TrainerEventKind::DemoFinished => TISSUE_EVENT_DEMO_FINISHED,
        }
    }
}

/// Bytes of `tissue_event.text`, NUL included.
pub const TISSUE_EVENT_TEXT: usize = 160;

/// A trainer event: when, what, and a line for a person.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct tissue_event {
    /// The step it happened in.
    pub step: u64,
    /// What happened.
    pub kind: tissue_event_kind,
    /// One line, UTF-8, NUL-terminated (truncated to fit).
    pub text: [c_char; TISSUE_EVENT_TEXT],
}

/// The body's figures.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct tissue_body_info {
    /// Nodes (the surface's vertices are among them); grows when cuts split nodes.
    pub nodes: u64,
    /// Tetrahedra.
    pub tets: u64,
    /// Surface triangles.
    pub triangles: u64,
    /// Steps taken.
    pub steps: u64,
    /// Changes whenever node positions may have changed (every step, cut or suture).
    pub positions_revision: u64,
    /// Changes whenever the surface's triangles (or node count) change (cuts, sutures).
    pub topology_revision: u64,
    /// `V / V₀ − 1`.
    pub volume_drift: f64,
    /// Median of the recent step times, ms.
    pub step_ms_median: f64,
    /// 99th percentile of the recent step times, ms.
    pub step_ms_p99: f64,
    /// The step, s (10 ms).
    pub time_step_s: f64,
    /// Contact tools added.
    pub tools: u32,
    /// Whether self-collision is on (issue 35; `tissue_material.self_collision`,
    /// `tissue_body_set_self_collision`).
    pub self_collision: bool,
    /// Self-contacts of the last step: the surface's vertex–triangle pairs within the detection
    /// band (0 with self-collision off).
    pub self_contacts: u64,
    /// Of those, the ones the solver had to push apart.
    pub self_contacts_active: u64,
}

/// A trainee's soft body: its simulation behind a mutex, its haptic state apart (module docs).
/// Every `tissue_body_*` and `tissue_tool_*` call but `tissue_body_free` may be made from any
/// thread.
pub struct tissue_body {
    sim: Mutex<Sim>,
    haptic: Haptic,
}

struct Sim {
    session: Session,
    events: VecDeque<TrainerEvent>,
    /// Changes with every step and edit.
    positions_revision: u64,
    /// The material scheme's material as given (checked); `None`: the real-time preset.
    material: Option<tissue_material>,
}

#[derive(Default)]
struct Haptic {
    /// The newest pose the host set per tool.
    poses: Mutex<Vec<Pose>>,
    /// The force models of the last step, per tool.
    models: RwLock<Arc<Vec<ContactForceModel>>>,
}

impl tissue_body {
    /// A body of the real-time preset.
    fn new(organ: &Organ) -> Result<Self, Error> {
        Self::with_options(organ, SessionOptions::default(), None)
    }

    fn with_options(
        organ: &Organ,
        options: SessionOptions,
        material: Option<tissue_material>,
    ) -> Result<Self, Error> {
        let session = Session::new(organ, options)?;
        Ok(tissue_body {
            sim: Mutex::new(Sim {
                session,
                events: VecDeque::new(),
                positions_revision: 1,
                material,
            }),
            haptic: Haptic::default(),
        })
    }

    fn sim(&self) -> Result<MutexGuard<'_, Sim>, Error> {
        self.sim.lock().map_err(poisoned)
    }
}

/// `&*body`, or `TISSUE_NULL_ARGUMENT`.
fn body_of<'a>(p: *const tissue_body) -> Result<&'a tissue_body, Error> {
    // SAFETY: the header's contract: NULL or a live body.
    unsafe { get(p, "body") }
}

fn pose_of(p: *const tissue_pose, name: &str) -> Result<Pose, Error> {
    // SAFETY: the header's contract.
    let p = unsafe { get(p, name) }?;
    let [x, y, z, w] = p.rotation;
    let rotation = Quat::from_xyzw(x, y, z, w);
    let translation = Vec3::from_array(p.translation);
    if !(rotation.is_finite() && translation.is_finite()) || (rotation.length() - 1.0).abs() > 1e-3
    {
        return Err(Error::invalid(format!(
            "`{name}` needs a unit quaternion (x, y, z, w) and a finite translation, got \
             {rotation} and {translation}"
        )));
    }
    Ok(Pose::new(rotation.normalize(), translation))
}

fn give_body(out: *mut *mut tissue_body, value: tissue_body) -> Result<(), Error> {
    let handle = into_handle(value);
    // SAFETY: `out` is NULL or valid.
    let written = unsafe { put(out, "out", handle) };
    if written.is_err() {
        // SAFETY: just made, not handed out.
        unsafe { free_handle(handle) };
    }
    written
}

/// A body from a mesh whose coordinates are in cm × `cm_per_unit` (1 for cm): a tet mesh as it
/// is, or a closed surface filled with tetrahedra (tissue-tetra). It is placed on a tray (a
/// static box whose top is y = 0; y is up): centred on x = z = 0 with its lowest node on y = 0;
/// read its positions back to see where. Soft-tissue material, 10 ms steps of 9 substeps,
/// self-collision on (`tissue_body_set_self_collision` switches it off).
///
/// Errors: `TISSUE_INVALID_MESH` for a surface that cannot be filled (open, non-manifold,
/// inside out) or a mesh of more than 150 000 tets; `TISSUE_INVALID_ARGUMENT` for a scale
/// that is not positive.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_body_new(
    mesh: *const tissue_mesh,
    cm_per_unit: f32,
    out: *mut *mut tissue_body,
) -> tissue_status {
    guard(|| give_body(out, tissue_body::new(&organ_of(mesh, cm_per_unit)?)?))
}

/// A session's settings for the caller's material (checked by tissue-scenes'
/// `SessionOptions::material`), and the material the body reports.
fn options_of(
    material: *const tissue_material,
) -> Result<(SessionOptions, Option<tissue_material>), Error> {
    // SAFETY: the header's contract: NULL or a valid struct.
    unsafe { get(material, "material") }?.session_options()
}

/// The organ of a caller's mesh in cm × `cm_per_unit` (`tissue_body_new`).
fn organ_of(mesh: *const tissue_mesh, cm_per_unit: f32) -> Result<Organ, Error> {
    // SAFETY: the header's contract.
    let mesh = unsafe { get(mesh, "mesh") }?;
    if !(cm_per_unit.is_finite() && cm_per_unit > 0.0) {
        return Err(Error::invalid(format!(
            "`cm_per_unit` must be a positive scale (1 for cm, 0.1 for mm), got {cm_per_unit}"
        )));
    }
    let invalid = |e: ::tissue_mesh::MeshError| {
        Error::new(
            tissue_status::TISSUE_INVALID_MESH,
            format!("the mesh is not valid once scaled by {cm_per_unit}: {e}"),
        )
    };
    let organ = match &mesh.kind {
        MeshKind::Surface(m) => {
            let scaled = TriMesh::new(
                m.positions().iter().map(|&p| p * cm_per_unit).collect(),
                m.triangles().to_vec(),
            )
            .map_err(invalid)?;
            Organ::from_surface(&scaled, "caller's surface")?
        }
        MeshKind::Tets(m) => {
            let scaled = TetMesh::new(
                m.positions().iter().map(|&p| p * cm_per_unit).collect(),
                m.tets().to_vec(),
            )
            .map_err(invalid)?;
            Organ::from_tets(&scaled, "caller's tet mesh")?
        }
    };
    Ok(organ)
}

/// A body from a mesh, as `tissue_body_new`, of the material `material` (a
/// `tissue_material`: `tissue_material_default`, `tissue_material_preset`, or the caller's
/// values).
///
/// Errors: as `tissue_body_new`; `TISSUE_PARAMETERS` for a material value out of its range (the
/// message names the field: `material->poisson`, ...); `TISSUE_INVALID_ARGUMENT` for a scheme
/// that is not a `tissue_scheme`.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_body_new_with_material(
    mesh: *const tissue_mesh,
    cm_per_unit: f32,
    material: *const tissue_material,
    out: *mut *mut tissue_body,
) -> tissue_status {
    guard(|| {
        // The material first: it is checked in no time, a surface is filled in seconds.
        let (options, reported) = options_of(material)?;
        let organ = organ_of(mesh, cm_per_unit)?;
        give_body(out, tissue_body::with_options(&organ, options, reported)?)
    })
}

/// A body of a shipped organ (a `tissue_shipped_organ`).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_body_new_shipped(organ: u32, out: *mut *mut tissue_body) -> tissue_status {
    guard(|| {
        let which = shipped_of(organ)?;
        give_body(out, tissue_body::new(&Organ::shipped(which)?)?)
    })
}

/// A body of a shipped organ (a `tissue_shipped_organ`) of the material `material` (a
/// `tissue_material`; `tissue_material_shipped` gives the organ's own tissue's).
///
/// Errors: as `tissue_body_new_with_material`.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_body_new_shipped_with_material(
    organ: u32,
    material: *const tissue_material,
    out: *mut *mut tissue_body,
) -> tissue_status {
    guard(|| {
        let which = shipped_of(organ)?;
        let (options, reported) = options_of(material)?;
        let organ = Organ::shipped(which)?;
        give_body(out, tissue_body::with_options(&organ, options, reported)?)
    })
}

/// Frees a body. NULL does nothing.
///
/// Thread safety: no other call (a haptic thread's included) may use the body during or after
/// this one: stop the haptic loop first.
#[no_mangle]
pub extern "C" fn tissue_body_free(body: *mut tissue_body) {
    // SAFETY: the header's contract: a body from this library, freed once.
    guard_void(|| unsafe { free_handle(body) });
}

/// One step (10 ms of simulated time): the tools move to the poses last set
/// (`tissue_tool_set_pose`), the probe's grasp follows its target, the body is solved, one queued
/// scalpel segment is cut, and each tool's force model is renewed. `*events` (may be NULL) is
/// set to the number of events it added (read them with `tissue_body_next_event`).
///
/// Errors: `TISSUE_SIMULATION` when the body diverges or a cut fails.
///
/// Thread safety: any thread; it holds the body's lock for the step, so other body calls wait,
/// but `tissue_tool_set_pose` and `tissue_tool_force` do not.
#[no_mangle]
pub extern "C" fn tissue_body_step(body: *const tissue_body, events: *mut usize) -> tissue_status {
    guard(|| {
        let body = body_of(body)?;
        let mut sim = body.sim()?;
        let poses = body.haptic.poses.lock().map_err(poisoned)?.clone();
        for (id, pose) in poses.into_iter().enumerate() {
            sim.session.set_tool_pose(id, pose)?;
        }
        let added = sim.session.step()?;
        let n = added.len();
        sim.events.extend(added);
        sim.positions_revision += 1;
        let models: Vec<ContactForceModel> = (0..sim.session.tool_count())
            .filter_map(|id| sim.session.contact_force_model(id).cloned())
            .collect();
        *body.haptic.models.write().map_err(poisoned)? = Arc::new(models);
        // SAFETY: `events` is NULL or valid.
        unsafe { put_opt(events, n) };
        Ok(())
    })
}

/// The body's figures (counts, revisions, volume drift, step times).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_get_info(
    body: *const tissue_body,
    info: *mut tissue_body_info,
) -> tissue_status {
    guard(|| {
        let sim = body_of(body)?.sim()?;
        let s = &sim.session;
        let (median, p99) = s.step_ms();
        let out = tissue_body_info {
            nodes: s.body().node_count() as u64,
            tets: s.body().tets().len() as u64,
            triangles: s.surface().len() as u64,
            steps: s.steps(),
            positions_revision: sim.positions_revision,
            topology_revision: s.surface_version(),
            volume_drift: s.volume_drift(),
            step_ms_median: median,
            step_ms_p99: p99,
            time_step_s: f64::from(s.body().settings().dt),
            tools: s.tool_count() as u32,
            self_collision: s.options().self_collision.is_some(),
            self_contacts: s.self_contacts().0 as u64,
            self_contacts_active: s.self_contacts().1 as u64,
        };
        // SAFETY: `info` is NULL or valid.
        unsafe { put(info, "info", out) }
    })
}

/// The body's material in force: for the material scheme the values it was made with; for the
/// real-time preset (`tissue_body_new`, or `TISSUE_SCHEME_REALTIME`) `scheme`
/// `TISSUE_SCHEME_REALTIME`, 0 for the modulus and the ratio (it has none), its density and the
/// relaxation time of its damping.
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_get_material(
    body: *const tissue_body,
    material: *mut tissue_material,
) -> tissue_status {
    guard(|| {
        let sim = body_of(body)?.sim()?;
        // The body's own, whatever the material was made with: switched live, or the session's
        // default (on) for the real-time preset.
        let self_collision = sim.session.options().self_collision.is_some();
        let out = match sim.material {
            Some(m) => tissue_material {
                self_collision,
                ..m
            },
            None => tissue_material {
                scheme: tissue_scheme::TISSUE_SCHEME_REALTIME as u32,
                young_kpa: 0.0,
                poisson: 0.0,
                density: f64::from(sim.session.body().density()),
                relaxation_time: f64::from(sim.session.body().settings().relaxation_time()),
                self_collision,
            },
        };
        // SAFETY: `material` is NULL or valid.
        unsafe { put(material, "material", out) }
    })
}

/// Switches self-collision of the body's surface on (`true`, tissue-scenes' default settings)
/// or off (`false`, for comparison) from the next step on (issue 35; every body starts with it
/// on unless its `tissue_material` says `false`; `tissue_body_get_info` says which is in force
/// and counts the last step's self-contacts).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_set_self_collision(
    body: *const tissue_body,
    on: bool,
) -> tissue_status {
    guard(|| {
        let mut sim = body_of(body)?.sim()?;
        let settings = on.then(SelfCollision::default);
        sim.session.set_self_collision(settings)?;
        Ok(())
    })
}

/// Sets `*count` to the number of pairs of surface triangles that intersect now, counted exactly
/// (tissue-scenes' `Session::self_intersections`: 0 when the organ does not pass through
/// itself; the two walls of a fresh cut touch and count until the steps part them).
///
/// Errors: `TISSUE_SIMULATION` for a diverged body (a position not finite).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_self_intersections(
    body: *const tissue_body,
    count: *mut u64,
) -> tissue_status {
    guard(|| {
        let sim = body_of(body)?.sim()?;
        let n = sim.session.self_intersections()? as u64;
        // SAFETY: `count` is NULL or valid.
        unsafe { put(count, "count", n) }
    })
}

/// Copies every node's position (x, y, z, cm) into `out` (`capacity` floats: at least 3 ×
/// `tissue_body_info.nodes`), and sets `*revision` (may be NULL) to the positions' revision
/// they are from. The surface triangles index these nodes.
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_copy_positions(
    body: *const tissue_body,
    out: *mut f32,
    capacity: usize,
    revision: *mut u64,
) -> tissue_status {
    guard(|| {
        let sim = body_of(body)?.sim()?;
        let positions: Vec<Vec3> = sim.session.positions().iter().map(|&p| p.into()).collect();
        // SAFETY: `out` holds `capacity` floats; `revision` is NULL or valid.
        unsafe {
            copy_out(out, capacity, bytemuck_vec3(&positions), "positions")?;
            put_opt(revision, sim.positions_revision);
        }
        Ok(())
    })
}

/// Copies the surface triangles (3 node indices each, counter-clockwise seen from outside) into
/// `out` (`capacity` values: at least 3 × `tissue_body_info.triangles`), and sets `*revision`
/// (may be NULL) to the topology revision they are from.
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_copy_triangles(
    body: *const tissue_body,
    out: *mut u32,
    capacity: usize,
    revision: *mut u64,
) -> tissue_status {
    guard(|| {
        let sim = body_of(body)?.sim()?;
        // SAFETY: `out` holds `capacity` values; `revision` is NULL or valid.
        unsafe {
            copy_out(
                out,
                capacity,
                sim.session.surface().as_flattened(),
                "triangles",
            )?;
            put_opt(revision, sim.session.surface_version());
        }
        Ok(())
    })
}

fn add_tool(
    body: *const tissue_body,
    shape: ToolShape,
    at: Pose,
    id: *mut u32,
) -> Result<(), Error> {
    let body = body_of(body)?;
    let mut sim = body.sim()?;
    let mut poses = body.haptic.poses.lock().map_err(poisoned)?;
    let new = sim.session.add_tool(shape, at)?;
    poses.push(at);
    drop(poses);
    let mut models: Vec<ContactForceModel> = body.haptic.models.read().map_err(poisoned)?.to_vec();
    models.push(
        sim.session
            .contact_force_model(new)
            .cloned()
            .unwrap_or_default(),
    );
    *body.haptic.models.write().map_err(poisoned)? = Arc::new(models);
    // SAFETY: `id` is NULL or valid.
    unsafe { put_opt(id, new as u32) };
    Ok(())
}

/// Adds a capsule tool (a probe's tip, a needle, an instrument's shaft): the points within
/// `radius` cm of the segment `a`–`b` in the tool's frame, placed at `pose`. It pushes the
/// tissue (with friction) from the next step on. `*id` (may be NULL) is set to its id: 0, 1, …
/// in the order tools are added.
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_add_capsule(
    body: *const tissue_body,
    a: *const f32,
    b: *const f32,
    radius: f32,
    pose: *const tissue_pose,
    id: *mut u32,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract: 3 floats each.
        let (a, b) = unsafe { (vec3(a, "a")?, vec3(b, "b")?) };
        let shape = ToolShape::Capsule { a, b, radius };
        add_tool(body, shape, pose_of(pose, "pose")?, id)
    })
}

/// Adds a blade tool: the points within `thickness / 2` cm of the triangle `a b c` in the
/// tool's frame, placed at `pose`. It pushes the tissue like any tool (it does not cut: cut with
/// `tissue_body_cut_sweep` or `tissue_body_cut`).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_add_blade(
    body: *const tissue_body,
    a: *const f32,
    b: *const f32,
    c: *const f32,
    thickness: f32,
    pose: *const tissue_pose,
    id: *mut u32,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract: 3 floats each.
        let (a, b, c) = unsafe { (vec3(a, "a")?, vec3(b, "b")?, vec3(c, "c")?) };
        let shape = ToolShape::Blade { a, b, c, thickness };
        add_tool(body, shape, pose_of(pose, "pose")?, id)
    })
}

/// Sets tool `tool`'s newest pose: the next step sweeps the tool from its last pose to it, and
/// `tissue_tool_force` evaluates the force there from now on.
///
/// Thread safety: any thread, at any rate (a lock held only to copy the pose: it never waits
/// for a step). Meant for the haptic thread.
#[no_mangle]
pub extern "C" fn tissue_tool_set_pose(
    body: *const tissue_body,
    tool: u32,
    pose: *const tissue_pose,
) -> tissue_status {
    guard(|| {
        let body = body_of(body)?;
        let p = pose_of(pose, "pose")?;
        let mut poses = body.haptic.poses.lock().map_err(poisoned)?;
        let count = poses.len();
        let slot = poses
            .get_mut(tool as usize)
            .ok_or_else(|| no_tool(tool, count))?;
        *slot = p;
        Ok(())
    })
}

fn no_tool(tool: u32, count: usize) -> Error {
    Error::invalid(format!(
        "no tool {tool}: the body has {count} (add them with tissue_body_add_capsule or \
         tissue_body_add_blade)"
    ))
}

/// The force of the tissue on tool `tool`, in newtons (world axes), at the tool's newest pose
/// (`tissue_tool_set_pose`), from the last step's contacts through a local linear model: the
/// last step's force, plus for each of its contacts a one-sided spring along the contact's
/// normal, loaded further as the tool moves on into the tissue and let go as it backs off
/// (`docs/c-api.md`, "The force model"). It varies continuously with the pose between steps
/// and equals the step's own force at the step's pose. `*step` (may be NULL) is set to the step
/// the model is from.
///
/// Thread safety: any thread, at 1 kHz or more while another thread steps: it takes two short
/// locks that only copy (a pose, and an `Arc` of the model) and never waits for a step;
/// allocation-free; a few hundred nanoseconds for tens of contacts.
#[no_mangle]
pub extern "C" fn tissue_tool_force(
    body: *const tissue_body,
    tool: u32,
    force_newtons: *mut f32,
    step: *mut u64,
) -> tissue_status {
    guard(|| {
        let body = body_of(body)?;
        let position = {
            let poses = body.haptic.poses.lock().map_err(poisoned)?;
            poses
                .get(tool as usize)
                .ok_or_else(|| no_tool(tool, poses.len()))?
                .translation
        };
        let models = Arc::clone(&*body.haptic.models.read().map_err(poisoned)?);
        let model = models
            .get(tool as usize)
            .ok_or_else(|| no_tool(tool, models.len()))?;
        let f = model.evaluate(position);
        if force_newtons.is_null() {
            return Err(Error::null("force_newtons"));
        }
        // SAFETY: 3 floats by the header's contract; `step` is NULL or valid.
        unsafe {
            copy_out(force_newtons, 3, &f.to_array(), "force_newtons")?;
            put_opt(step, model.step);
        }
        Ok(())
    })
}

/// Grasps the surface near `point` (cm) on surface triangle `triangle` (an index into the
/// triangles of `tissue_body_copy_triangles`): the free surface nodes within 0.6 cm, and at
/// least the triangle's corners, follow the probe's target (`tissue_body_drag`) until
/// `tissue_body_release`. Adds a `TISSUE_EVENT_GRABBED` event.
///
/// Errors: `TISSUE_INVALID_ARGUMENT` for a triangle out of range or a point outside the tools'
/// working space (see `tissue_body_drag`).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_grab(
    body: *const tissue_body,
    point: *const f32,
    triangle: u32,
) -> tissue_status {
    guard(|| {
        // SAFETY: 3 floats.
        let point = unsafe { vec3(point, "point") }?;
        let mut sim = body_of(body)?.sim()?;
        let e = sim.session.grab(point, triangle as usize)?;
        sim.events.push_back(e);
        Ok(())
    })
}

/// Moves the grasped point towards `target` (cm) from the next step on (nothing while nothing is
/// grasped), clamped into the tools' working space: the tray's square grown by half its side on
/// every edge (x and z within ± the tray's side), from 1 cm below the tray's top to a tray's side
/// above it.
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_drag(body: *const tissue_body, target: *const f32) -> tissue_status {
    guard(|| {
        // SAFETY: 3 floats.
        let target = unsafe { vec3(target, "target") }?;
        body_of(body)?.sim()?.session.drag(target);
        Ok(())
    })
}

/// Lets go of what the probe grasps (nothing when nothing is).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_release(body: *const tissue_body) -> tissue_status {
    guard(|| {
        let mut sim = body_of(body)?.sim()?;
        if let Some(e) = sim.session.release()? {
            sim.events.push_back(e);
        }
        Ok(())
    })
}

/// The force of the tissue on the grasp at the last step, newtons (zero when nothing is
/// grasped).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_grasp_force(
    body: *const tissue_body,
    force_newtons: *mut f32,
) -> tissue_status {
    guard(|| {
        let f = body_of(body)?.sim()?.session.tool_force();
        if force_newtons.is_null() {
            return Err(Error::null("force_newtons"));
        }
        // SAFETY: 3 floats by the header's contract.
        unsafe { copy_out(force_newtons, 3, &f.to_array(), "force_newtons") }
    })
}

/// Queues a scalpel cut along `path` (`point_count` surface points, x y z each, cm) seen along
/// `view_dir`: the blade's plane holds the path's overall direction and the view direction; it
/// cuts 1 cm below the path, one segment (about 0.4 cm) per step. `*segments` (may be NULL) is
/// set to the segments queued.
///
/// Errors: `TISSUE_INVALID_ARGUMENT` for fewer than two distinct points, more than 10000 (refused
/// before they are read), a point outside the tools' working space (see `tissue_body_drag`), a
/// path along the view, a path too short, or a cut that would queue more than four tray sides
/// of segments (counting those still waiting; nothing is queued).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_cut(
    body: *const tissue_body,
    path: *const f32,
    point_count: usize,
    view_dir: *const f32,
    segments: *mut usize,
) -> tissue_status {
    guard(|| {
        if point_count > tissue_scenes::MAX_CUT_POINTS {
            return Err(Error::invalid(format!(
                "a cut path of {point_count} points: at most {} are taken; send fewer points",
                tissue_scenes::MAX_CUT_POINTS
            )));
        }
        // SAFETY: the header's contract.
        let (points, view) = unsafe {
            (
                slice(path, point_count.saturating_mul(3), "path")?,
                vec3(view_dir, "view_dir")?,
            )
        };
        let points: Vec<Vec3> = points.chunks_exact(3).map(Vec3::from_slice).collect();
        let n = body_of(body)?.sim()?.session.cut(&points, view)?;
        // SAFETY: NULL or valid.
        unsafe { put_opt(segments, n) };
        Ok(())
    })
}

/// Cuts at once along the scalpel blade's sweep from pose `from` to pose `to` (cm). The blade in
/// its own frame: its plane x = 0, its cutting edge along z at y = −1 cm (z from −0.05 to
/// 0.05), its back at y = +1; so a pose puts its origin on the surface where the cut goes, local
/// −y into the tissue and local z along the cut. Every tet face the swept edge crosses opens;
/// the events are queued (`tissue_body_next_event`).
///
/// Errors: `TISSUE_INVALID_ARGUMENT` for a bad pose, `TISSUE_SIMULATION` when the cut fails.
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_cut_sweep(
    body: *const tissue_body,
    from: *const tissue_pose,
    to: *const tissue_pose,
) -> tissue_status {
    guard(|| {
        let (from, to) = (pose_of(from, "from")?, pose_of(to, "to")?);
        let mut sim = body_of(body)?.sim()?;
        let events = sim.session.cut_sweep(from, to)?;
        sim.events.extend(events);
        sim.positions_revision += 1;
        Ok(())
    })
}

/// Places a suture between surface points `a` and `b` (cm) on the two sides of a wound: a needle
/// passes below them, and the nodes of the wound's walls nearest its crossings are linked. The
/// event (`TISSUE_EVENT_SUTURE_PLACED`, or `TISSUE_EVENT_SUTURE_MISSED` when the needle crossed
/// no wound) is queued and, if `event` is not NULL, also written there.
///
/// Errors: `TISSUE_INVALID_ARGUMENT` for points that are not finite, coincide, or lie outside
/// the tools' working space (see `tissue_body_drag`), and when a suture is already there: a
/// second stitch within 0.5 cm (along the wound) of an existing one is not a new stitch.
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_suture(
    body: *const tissue_body,
    a: *const f32,
    b: *const f32,
    event: *mut tissue_event,
) -> tissue_status {
    guard(|| {
        // SAFETY: 3 floats each.
        let (a, b) = unsafe { (vec3(a, "a")?, vec3(b, "b")?) };
        let mut sim = body_of(body)?.sim()?;
        let e = sim.session.suture(a, b)?;
        // SAFETY: NULL or valid.
        unsafe { put_opt(event, to_c(&e)) };
        sim.events.push_back(e);
        sim.positions_revision += 1;
        Ok(())
    })
}

/// Plays the organ's demonstration from the next step on (tissue-scenes' scripted scenario, the
/// one the studio plays): on the appendix the procedure (grasped and lifted, incised, its tip cut
/// off, the incision sutured; 200 steps), on a tray a probe pressed 1.5 cm into the organ and
/// dragged across it (250 steps; the probe is added as the next tool, parked above the organ
/// after the run, and reused when the demonstration is played again). A
/// `TISSUE_EVENT_DEMO_STARTED` event is queued now; the demonstration's events come with the
/// steps (`tissue_body_step`), the last one `TISSUE_EVENT_DEMO_FINISHED`. Meant for a fresh
/// body; while it plays, grab, cut and suture are refused.
///
/// Errors: `TISSUE_INVALID_ARGUMENT` when a demonstration is already playing.
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_play(body: *const tissue_body) -> tissue_status {
    guard(|| {
        let body = body_of(body)?;
        let mut sim = body.sim()?;
        let started = sim.session.play()?;
        sim.events.push_back(started);
        // A tray's demonstration adds its probe as a tool: the host's pose list and the force
        // models follow, so that tool ids stay the session's.
        let mut poses = body.haptic.poses.lock().map_err(poisoned)?;
        let mut models: Vec<ContactForceModel> =
            body.haptic.models.read().map_err(poisoned)?.to_vec();
        for id in poses.len()..sim.session.tool_count() {
            let pose = sim.session.body().tool(id)?.pose();
            poses.push(pose);
            models.push(
                sim.session
                    .contact_force_model(id)
                    .cloned()
                    .unwrap_or_default(),
            );
        }
        drop(poses);
        *body.haptic.models.write().map_err(poisoned)? = Arc::new(models);
        Ok(())
    })
}

fn to_c(e: &TrainerEvent) -> tissue_event {
    let kind = tissue_event_kind::from(e.kind);
    let mut text = [0 as c_char; TISSUE_EVENT_TEXT];
    let mut n = e.text.len().min(TISSUE_EVENT_TEXT - 1);
    while !e.text.is_char_boundary(n) {
        n -= 1;
    }
    for (t, &b) in text.iter_mut().zip(&e.text.as_bytes()[..n]) {
        *t = b as c_char;
    }
    tissue_event {
        step: e.step,
        kind,
        text,
    }
}

/// Takes the oldest queued event into `*event`; `*has_event` is set to whether there was one
/// (the event is left alone when not).
///
/// Thread safety: any thread (waits for a running step).
#[no_mangle]
pub extern "C" fn tissue_body_next_event(
    body: *const tissue_body,
    event: *mut tissue_event,
    has_event: *mut bool,
) -> tissue_status {
    guard(|| {
        if event.is_null() {
            return Err(Error::null("event"));
        }
        if has_event.is_null() {
            return Err(Error::null("has_event"));
        }
        let next = body_of(body)?.sim()?.events.pop_front();
        // SAFETY: `event` is valid (checked not NULL); `has_event` NULL or valid.
        unsafe {
            put(has_event, "has_event", next.is_some())?;
            if let Some(e) = next {
                event.write(to_c(&e));
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every tissue-scenes event kind has its own C value; only the surgery events the list does
    /// not name yet are `TISSUE_EVENT_OTHER`.
    #[test]
    fn every_event_kind_has_its_own_c_value() {
        let values: Vec<u32> = TrainerEventKind::ALL
            .iter()
            .map(|&k| tissue_event_kind::from(k) as u32)
            .collect();
        let mut distinct = values.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), values.len(), "{values:?}");
        for kind in TrainerEventKind::ALL {
            let other = tissue_event_kind::from(kind) == tissue_event_kind::TISSUE_EVENT_OTHER;
            assert_eq!(other, kind == TrainerEventKind::Surgery, "{kind}");
        }
    }

    /// A tray's demonstration adds its probe as a tool: the host's tools keep the session's ids
    /// (the next capsule is tool 1, and moving it moves it, not the probe).
    #[test]
    fn a_tray_demonstration_probe_keeps_the_hosts_tool_ids() {
        let cube = ::tissue_mesh::tet_box(3, 3, 3, Vec3::splat(4.0)).unwrap();
        let organ = Organ::from_tets(&cube, "cube").unwrap();
        let body: *mut tissue_body = into_handle(tissue_body::new(&organ).unwrap());
        assert_eq!(tissue_body_play(body), tissue_status::TISSUE_OK);
        let (a, b) = ([0.0f32; 3], [0.0f32, 1.0, 0.0]);
        let pose = tissue_pose {
            rotation: [0.0, 0.0, 0.0, 1.0],
            translation: [5.0, 1.0, 0.0],
        };
        let mut id = u32::MAX;
        let added = tissue_body_add_capsule(body, a.as_ptr(), b.as_ptr(), 0.2, &pose, &mut id);
        assert_eq!(added, tissue_status::TISSUE_OK);
        assert_eq!(id, 1, "the probe is tool 0");
        assert_eq!(
            tissue_body_step(body, std::ptr::null_mut()),
            tissue_status::TISSUE_OK
        );
        let mut info = tissue_body_info::default();
        assert_eq!(
            tissue_body_get_info(body, &mut info),
            tissue_status::TISSUE_OK
        );
        assert_eq!(info.tools, 2);
        // SAFETY: a live body.
        let sim = unsafe { &*body }.sim().unwrap();
        let at = |tool| sim.session.body().tool(tool).unwrap().pose().translation;
        assert_eq!(at(1), Vec3::from_array(pose.translation));
        assert!(
            at(0).y > 4.0,
            "the probe is still parked above the cube: {}",
            at(0)
        );
        drop(sim);
        tissue_body_free(body);
    }
}
