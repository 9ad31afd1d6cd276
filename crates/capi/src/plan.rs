//! Planning: patients, requests (a C struct of the common fields, or the planner's JSON), jobs on
//! tissue-app's worker with progress, cancel and wait, and their results (the report's numbers
//! and JSON, the deformed patient).

use std::ffi::{c_char, c_int, c_void};
use std::path::Path;
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use tissue_planner::report::{RunResult, StopReason};
use tissue_planner::{
    CancelToken, Finished, JobMode, JobReport, JobSpec, Patient, PlanError, PlanRequest, Scenario,
    Shape, Shipped, Stopped, Tool, Unit,
};

use crate::ffi::{
    copy_out, copy_text, free_handle, get, guard, guard_void, into_handle, poisoned, put, slice,
    text, tissue_status, Error,
};
use crate::mesh::{tissue_mesh, MeshKind};

/// A patient surface, in its file's unit and in cm (the planner's `Patient`). Immutable: any
/// thread may use it at once, e.g. to start several jobs.
pub struct tissue_patient {
    patient: Patient,
}

/// A mesh unit of length (the patient file's; planning runs in cm).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_unit {
    /// Millimetres.
    TISSUE_UNIT_MM = 0,
    /// Centimetres.
    TISSUE_UNIT_CM = 1,
    /// Decimetres (the MakeHuman meshes).
    TISSUE_UNIT_DM = 2,
    /// Metres.
    TISSUE_UNIT_M = 3,
}

/// A patient shipped with the library.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_shipped_patient {
    /// The thesis's Table 2 plane: 20 cm square, 65 × 65 vertices, z = 0, cm.
    TISSUE_PATIENT_TABLE2 = 0,
    /// MakeHuman's chest patch (dm, CC0).
    TISSUE_PATIENT_CHEST = 1,
    /// MakeHuman's head patch (dm, CC0).
    TISSUE_PATIENT_HEAD = 2,
}

/// Where the implant goes (`tissue_plan_options.placement`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_placement {
    /// The Table 2 plane's centre (a patient from a file needs a point or a vertex).
    TISSUE_PLACE_DEFAULT = 0,
    /// `point`, in the mesh's unit, snapped to the nearest surface point.
    TISSUE_PLACE_POINT = 1,
    /// `vertex`, an index into the patient mesh's vertices (file order, from 0).
    TISSUE_PLACE_VERTEX = 2,
}

/// The implant's base outline (`tissue_plan_options.shape`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_shape {
    /// Circular: `diameter_cm`.
    TISSUE_SHAPE_ROUND = 0,
    /// Rectangular: `length_cm` × `width_cm`, corners rounded to `corner_radius_cm`.
    TISSUE_SHAPE_RECTANGULAR = 1,
    /// Crescent: `length_cm` tip to tip, `width_cm`, `bend_radius_cm`.
    TISSUE_SHAPE_CRESCENT = 2,
}

/// The common fields of a planning request (the planner's `PlanRequest`; every other field at
/// the library's default, the solver `explicit` among them: use the JSON entry points for
/// those). Fill it with `tissue_plan_options_default` first, then change what you need.
/// Enum-valued fields are `uint32_t` holding the named enum's values. Lengths in cm; a size of
/// 0 means "not given" (the library's default or, for a rectangle's or crescent's sizes, a
/// `TISSUE_USAGE` error).
/// Bounds (`TISSUE_PARAMETERS` naming the field beyond them; `TISSUE_PLACEMENT` for the region
/// radius): lengths at most 100 cm, `volume_cm3` at most 5000, `depth_cm` at most 10,
/// `max_steps` 1 to 500000.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct tissue_plan_options {
    /// A `tissue_placement`.
    pub placement: u32,
    /// With `TISSUE_PLACE_POINT`: the point, in the mesh's unit.
    pub point: [f32; 3],
    /// With `TISSUE_PLACE_VERTEX`: the vertex.
    pub vertex: u32,
    /// A `tissue_shape`.
    pub shape: u32,
    /// Round: diameter, cm.
    pub diameter_cm: f32,
    /// Rectangular or crescent: length, cm (0: not given).
    pub length_cm: f32,
    /// Rectangular or crescent: width, cm (0: not given).
    pub width_cm: f32,
    /// Rectangular: corner radius, cm.
    pub corner_radius_cm: f32,
    /// Crescent: the centre line's arc radius, cm (0: not given).
    pub bend_radius_cm: f32,
    /// Turns the implant's tangent (+x, or +y near ±x) about the normal, degrees.
    pub rotation_deg: f32,
    /// Fill volume, cm³ (mL).
    pub volume_cm3: f64,
    /// The implant's base lies this far under the skin, cm.
    pub depth_cm: f64,
    /// The region's geodesic radius, cm (0: 1.5 × the footprint radius).
    pub region_radius_cm: f64,
    /// The simulation mesh's edge, cm (0: from the implant's size; on the Table 2 plane, 0 runs
    /// on its own grid).
    pub sim_edge_cm: f64,
    /// A run's step limit (1 to 500000; the default 20000).
    pub max_steps: u64,
    /// Run on the patient mesh's own triangles instead of a simulation mesh of its own.
    pub scan_triangles: bool,
}

/// A planning job's state.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_job_state {
    /// Setting up or stepping.
    TISSUE_JOB_RUNNING = 0,
    /// Finished: the results can be read.
    TISSUE_JOB_FINISHED = 1,
    /// Cancelled.
    TISSUE_JOB_CANCELLED = 2,
    /// Failed (`tissue_job_wait` gives the status and message).
    TISSUE_JOB_FAILED = 3,
}

/// A job's progress, as of its last reported step.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct tissue_progress {
    /// Running, finished, cancelled or failed.
    pub state: tissue_job_state,
    /// Which run of the job the step belongs to (0 for a single insertion; the volume's index
    /// in a sweep; the search's run number in an inverse search).
    pub run: u32,
    /// Runs in the job as far as known (1; the sweep's volumes; runs seen so far in a search).
    pub runs: u32,
    /// Steps done in that run.
    pub step: u64,
    /// That run's step limit.
    pub max_steps: u64,
    /// How close the run is to its stop criterion, 0 to 1 (an indicator: a run may end a little
    /// before or after 1).
    pub settle: f64,
    /// Wall time since the job started, s.
    pub elapsed_s: f64,
}

/// The numbers of one run's report (the JSON report's fields of the same names; cm, cm², cm³).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct tissue_plan_result {
    /// Skin region area before, cm².
    pub area_before_cm2: f64,
    /// Skin region area after, cm².
    pub area_after_cm2: f64,
    /// The skin gained, cm².
    pub area_gain_cm2: f64,
    /// Volume between the skin before and after, cm³.
    pub volume_difference_cm3: f64,
    /// The implant's volume as built, cm³.
    pub implant_volume_cm3: f64,
    /// The implant's volume at the end, cm³.
    pub implant_volume_end_cm3: f64,
    /// `1 − end / built`.
    pub implant_compression: f64,
    /// The implant's dome height as built, cm.
    pub dome_height_cm: f64,
    /// The largest displacement of a skin vertex, cm.
    pub max_displacement_cm: f64,
    /// The deepest tissue edge through the implant at the end, cm.
    pub max_penetration_cm: f64,
    /// The region's geodesic radius, cm.
    pub region_radius_cm: f64,
    /// The time step, s.
    pub time_step_s: f64,
    /// Wall time of the stepping, s.
    pub wall_time_s: f64,
    /// Steps taken.
    pub steps: u64,
    /// The step limit.
    pub max_steps: u64,
    /// Vertices of the simulated skin region.
    pub region_vertices: u64,
    /// Whether the run settled (else it hit the step limit).
    pub settled: bool,
    /// Whether every region boundary vertex stayed exactly in place.
    pub boundary_unchanged: bool,
}

/// The answer of an inverse search (the volume for a target area gain).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct tissue_inverse_result {
    /// The wanted gain, cm².
    pub target_gain_cm2: f64,
    /// The volumes searched between, cm³.
    pub bracket_low_cm3: f64,
    /// The volumes searched between, cm³.
    pub bracket_high_cm3: f64,
    /// The answer, cm³.
    pub volume_cm3: f64,
    /// The gain of the answer's run, cm².
    pub area_gain_cm2: f64,
    /// Whether a stopping rule was met (else: the best estimate when the run budget ran out).
    pub converged: bool,
    /// Runs taken.
    pub runs: u32,
}

/// A per-vertex field of a finished insertion's patient (`tissue_job_copy_field`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_field {
    /// How far each vertex moved, in the mesh's unit (0 outside the region).
    TISSUE_FIELD_DISPLACEMENT = 0,
    /// Area after / area before around each vertex (0 outside the region).
    TISSUE_FIELD_STRETCH = 1,
    /// 1 for a region vertex, 0 outside.
    TISSUE_FIELD_IN_REGION = 2,
}

/// Called by `tissue_job_run` and `tissue_plan_run` on the calling thread about every 50 ms
/// with the job's progress and the caller's `user_data`; a non-zero return cancels the job.
pub type tissue_progress_callback =
    Option<unsafe extern "C" fn(progress: *const tissue_progress, user_data: *mut c_void) -> c_int>;

/// A planning job on its own worker thread (tissue-app's), driven by a second thread of the
/// library that collects its progress. Every `tissue_job_*` call but `tissue_job_free` may be
/// made from any thread, at the same time as others.
pub struct tissue_job {
    shared: Arc<JobShared>,
    driver: Mutex<Option<JoinHandle<()>>>,
}

struct JobShared {
    cancel: CancelToken,
    progress: Mutex<tissue_progress>,
    end: Mutex<Option<Result<Done, Error>>>,
    ended: Condvar,
}

/// A finished job: the planner's results and its report's JSON.
struct Done {
    finished: Finished,
    report: String,
}

fn unit(value: u32) -> Result<Unit, Error> {
    Ok(match value {
        0 => Unit::Mm,
        1 => Unit::Cm,
        2 => Unit::Dm,
        3 => Unit::M,
        _ => {
            return Err(Error::invalid(format!(
                "`unit` {value} is not a tissue_unit (0 mm, 1 cm, 2 dm, 3 m)"
            )))
        }
    })
}

/// One of the patients shipped with the library (a `tissue_shipped_patient`). The new patient
/// is the caller's (`tissue_patient_free`).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_patient_shipped(
    which: u32,
    out: *mut *mut tissue_patient,
) -> tissue_status {
    guard(|| {
        let shipped = match which {
            0 => Shipped::Table2,
            1 => Shipped::Chest,
            2 => Shipped::Head,
            _ => {
                return Err(Error::invalid(format!(
                    "`which` {which} is not a tissue_shipped_patient (0 Table 2, 1 chest, 2 head)"
                )))
            }
        };
        let patient = Patient::shipped(shipped)?;
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(tissue_patient { patient })) }
    })
}

/// Reads a patient surface (`.obj`, `.ply`, `.stl`, `.vtk`) whose coordinates are in `unit`
/// (a `tissue_unit`).
///
/// Errors: `TISSUE_INPUT`, `TISSUE_INVALID_MESH` (the loader's message).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_patient_load(
    path: *const c_char,
    unit_of_file: u32,
    out: *mut *mut tissue_patient,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let path = unsafe { text(path, "path") }?;
        let patient = Patient::read(Path::new(path), unit(unit_of_file)?)?;
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(tissue_patient { patient })) }
    })
}

/// A patient from a surface mesh whose coordinates are in `unit` (a `tissue_unit`); `label`
/// (may be NULL) names it in the report. The mesh is copied.
///
/// Errors: `TISSUE_INVALID_ARGUMENT` for a tet mesh, `TISSUE_INVALID_MESH`.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_patient_from_mesh(
    mesh: *const tissue_mesh,
    unit_of_mesh: u32,
    label: *const c_char,
    out: *mut *mut tissue_patient,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let mesh = unsafe { get(mesh, "mesh") }?;
        let label = if label.is_null() {
            "caller's mesh".to_owned()
        } else {
            // SAFETY: not NULL: a NUL-terminated string.
            unsafe { text(label, "label") }?.to_owned()
        };
        let MeshKind::Surface(surface) = &mesh.kind else {
            return Err(Error::invalid(
                "a patient is a surface: this mesh holds tets",
            ));
        };
        let patient = Patient::from_mesh(surface.clone(), unit(unit_of_mesh)?, label)?;
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(tissue_patient { patient })) }
    })
}

/// The patient's surface as its file has it (its unit), as a new mesh (`tissue_mesh_free`).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_patient_mesh(
    patient: *const tissue_patient,
    out: *mut *mut tissue_mesh,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let patient = unsafe { get(patient, "patient") }?;
        let kind = MeshKind::Surface(patient.patient.file.clone());
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(tissue_mesh { kind })) }
    })
}

/// Frees a patient. NULL does nothing. Jobs started from it keep their own copy.
///
/// Thread safety: no other call may use the patient during or after this one.
#[no_mangle]
pub extern "C" fn tissue_patient_free(patient: *mut tissue_patient) {
    // SAFETY: the header's contract.
    guard_void(|| unsafe { free_handle(patient) });
}

/// Fills `options` with the library's defaults: the Table 2 case (a round 7 cm implant of
/// 100 cm³ at the default placement).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_plan_options_default(options: *mut tissue_plan_options) -> tissue_status {
    guard(|| {
        let r = PlanRequest::default();
        let o = tissue_plan_options {
            placement: tissue_placement::TISSUE_PLACE_DEFAULT as u32,
            point: [0.0; 3],
            vertex: 0,
            shape: tissue_shape::TISSUE_SHAPE_ROUND as u32,
            diameter_cm: r.diameter_cm,
            length_cm: 0.0,
            width_cm: 0.0,
            corner_radius_cm: r.corner_radius_cm,
            bend_radius_cm: 0.0,
            rotation_deg: r.rotation_deg,
            volume_cm3: r.volume_cm3,
            depth_cm: r.depth_cm,
            region_radius_cm: 0.0,
            sim_edge_cm: 0.0,
            max_steps: r.max_steps,
            scan_triangles: r.scan_triangles,
        };
        // SAFETY: `options` is NULL or valid.
        unsafe { put(options, "options", o) }
    })
}

/// The planner's request of `o`.
fn request(o: &tissue_plan_options) -> Result<PlanRequest, Error> {
    let given = |v: f32| (v != 0.0).then_some(v);
    let given64 = |v: f64| (v != 0.0).then_some(v);
    let mut r = PlanRequest {
        rotation_deg: o.rotation_deg,
        shape: match o.shape {
            0 => Shape::Round,
            1 => Shape::Rectangular,
            2 => Shape::Crescent,
            s => {
                return Err(Error::invalid(format!(
                    "`shape` {s} is not a tissue_shape (0 round, 1 rectangular, 2 crescent)"
                )))
            }
        },
        diameter_cm: o.diameter_cm,
        length_cm: given(o.length_cm),
        width_cm: given(o.width_cm),
        corner_radius_cm: o.corner_radius_cm,
        bend_radius_cm: given(o.bend_radius_cm),
        volume_cm3: o.volume_cm3,
        depth_cm: o.depth_cm,
        region_radius_cm: given64(o.region_radius_cm),
        sim_edge_cm: given64(o.sim_edge_cm),
        max_steps: o.max_steps,
        scan_triangles: o.scan_triangles,
        ..PlanRequest::default()
    };
    match o.placement {
        0 => {}
        1 => r.at = Some(o.point),
        2 => r.vertex = Some(o.vertex),
        p => {
            return Err(Error::invalid(format!(
                "`placement` {p} is not a tissue_placement (0 default, 1 point, 2 vertex)"
            )))
        }
    }
    Ok(r)
}

/// Places the spec's request on the patient and starts its job (the checks run here, on the
/// caller's thread, so a bad request fails at once).
fn start(patient: &tissue_patient, spec: JobSpec) -> Result<tissue_job, Error> {
    let scenario = Scenario::new(patient.patient.clone(), spec.request.clone())?;
    let planned = spec.plan(&scenario)?;
    let shared = Arc::new(JobShared {
        cancel: CancelToken::new(),
        progress: Mutex::new(tissue_progress {
            state: tissue_job_state::TISSUE_JOB_RUNNING,
            run: 0,
            runs: planned.runs as u32,
            step: 0,
            max_steps: scenario.job.params.run.stop.max_steps,
            settle: 0.0,
            elapsed_s: 0.0,
        }),
        end: Mutex::new(None),
        ended: Condvar::new(),
    });
    let theirs = Arc::clone(&shared);
    let driver = std::thread::Builder::new()
        .name("tissue-capi-job".into())
        .spawn(move || {
            let started = Instant::now();
            let end = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                finish(planned.run(&scenario, Tool::Capi, &theirs.cancel, |p| {
                    theirs.keep(p);
                }))
            }))
            .unwrap_or_else(|_| {
                Err(Error::new(
                    tissue_status::TISSUE_PANIC,
                    "the planning job panicked (a bug, please report it)",
                ))
            });
            theirs.end(end, started);
        })
        .map_err(|e| {
            Error::new(
                tissue_status::TISSUE_RUN,
                format!("cannot start a thread: {e}"),
            )
        })?;
    Ok(tissue_job {
        shared,
        driver: Mutex::new(Some(driver)),
    })
}

/// The job's end as the C ABI keeps it: the results with the report's JSON, or the error.
fn finish(run: Result<Finished, Stopped>) -> Result<Done, Error> {
    let finished = run.map_err(PlanError::from)?;
    let report = finished.report.to_json()?;
    Ok(Done { finished, report })
}

impl JobShared {
    /// Keeps the latest progress for `tissue_job_progress` and the run callback.
    fn keep(&self, p: &tissue_planner::ProgressEvent) {
        if let Ok(mut q) = self.progress.lock() {
            q.run = p.run as u32;
            q.runs = q.runs.max(p.run as u32 + 1);
            q.step = p.step;
            q.max_steps = p.max_steps;
            q.settle = p.settle;
            q.elapsed_s = p.elapsed.as_secs_f64();
        }
    }

    /// Records the job's end and wakes the waiters.
    fn end(&self, end: Result<Done, Error>, started: Instant) {
        let state = match &end {
            Ok(_) => tissue_job_state::TISSUE_JOB_FINISHED,
            Err(e) if e.status == tissue_status::TISSUE_CANCELLED => {
                tissue_job_state::TISSUE_JOB_CANCELLED
            }
            Err(_) => tissue_job_state::TISSUE_JOB_FAILED,
        };
        if let Ok(mut q) = self.progress.lock() {
            q.state = state;
            q.elapsed_s = started.elapsed().as_secs_f64();
        }
        if let Ok(mut slot) = self.end.lock() {
            *slot = Some(end);
        }
        self.ended.notify_all();
    }
}

/// Starts one insertion of `options` on `patient`, on a worker thread, and returns at once with
/// the job (the caller's: `tissue_job_free`). The request is checked and placed first, on the
/// calling thread, so a request that cannot run fails here.
///
/// Errors: `TISSUE_USAGE`, `TISSUE_PLACEMENT`, `TISSUE_PARAMETERS` (naming the field),
/// `TISSUE_INVALID_ARGUMENT` for a bad enum value.
///
/// Thread safety: any thread; the patient may be shared by concurrent calls.
#[no_mangle]
pub extern "C" fn tissue_plan_start(
    patient: *const tissue_patient,
    options: *const tissue_plan_options,
    out: *mut *mut tissue_job,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let (patient, options) = unsafe { (get(patient, "patient")?, get(options, "options")?) };
        let spec = JobSpec {
            request: request(options)?,
            ..JobSpec::default()
        };
        let job = start(patient, spec)?;
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(job)) }
    })
}

/// Starts a sweep: the insertion of `options` at each of `volumes_cm3` (`count` volumes), run in
/// parallel. Read its rows with `tissue_job_sweep_row`.
///
/// Errors: as `tissue_plan_start`; `TISSUE_PARAMETERS` for no volume, more than 64, or one that
/// is not positive or above 5000 cm³.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_sweep_start(
    patient: *const tissue_patient,
    options: *const tissue_plan_options,
    volumes_cm3: *const f64,
    count: usize,
    out: *mut *mut tissue_job,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let (patient, options, volumes) = unsafe {
            (
                get(patient, "patient")?,
                get(options, "options")?,
                slice(volumes_cm3, count, "volumes_cm3")?,
            )
        };
        // Checked on the caller's array, before it is copied.
        tissue_planner::check_sweep(volumes)?;
        let spec = JobSpec {
            mode: JobMode::Sweep,
            request: request(options)?,
            volumes_cm3: volumes.to_vec(),
            ..JobSpec::default()
        };
        let job = start(patient, spec)?;
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(job)) }
    })
}

/// Starts the inverse search: the volume at which the insertion of `options` gains
/// `target_gain_cm2` of skin, searched between `bracket_low_cm3` and `bracket_high_cm3` (both 0:
/// a quarter to twice `options.volume_cm3`), stopping within `gain_tolerance_cm2` (0: the
/// library's default). Read the answer with `tissue_job_inverse_result`.
///
/// Errors: as `tissue_plan_start`; `TISSUE_PARAMETERS` naming a bad target, bracket or
/// tolerance.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_inverse_start(
    patient: *const tissue_patient,
    options: *const tissue_plan_options,
    target_gain_cm2: f64,
    bracket_low_cm3: f64,
    bracket_high_cm3: f64,
    gain_tolerance_cm2: f64,
    out: *mut *mut tissue_job,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let (patient, options) = unsafe { (get(patient, "patient")?, get(options, "options")?) };
        let bracket = (bracket_low_cm3 != 0.0 || bracket_high_cm3 != 0.0)
            .then_some((bracket_low_cm3, bracket_high_cm3));
        let tolerance = (gain_tolerance_cm2 != 0.0).then_some(gain_tolerance_cm2);
        let spec = JobSpec {
            mode: JobMode::TargetGain,
            request: request(options)?,
            target_gain_cm2: Some(target_gain_cm2),
            bracket_cm3: bracket,
            gain_tolerance_cm2: tolerance,
            ..JobSpec::default()
        };
        let job = start(patient, spec)?;
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(job)) }
    })
}

/// Starts a job described in JSON: every field of the planner's request, with its units in its
/// names, as `insert --report` and the studio take it (`docs/c-api.md`):
///
/// `{"mode": "single" | "sweep" | "target-gain" | "expansion", "request": {"vertex": 2277,
/// "volume_cm3": 50, "sim_edge_cm": 0.3, "solver": "explicit", ...}, "volumes_cm3": [..],
/// "target_gain_cm2": 30, "bracket_cm3": [lo, hi], "gain_tolerance_cm2": 0.5}` (tissue-planner's
/// `JobSpec`)
///
/// `"solver"` is `"explicit"` (the default) or `"quasi_static"` (experimental); the report gives it as
/// `inputs.solver`, with every run's `iterations` and `residual_n` (null for `"explicit"`).
///
/// Every member is optional (`{}` is Table 2's single run on the Table 2 plane); unknown members
/// are refused. An expansion (`"mode": "expansion"` with `"expand_weeks"` in the request) gives
/// its weeks, flap and band in `tissue_job_report_json` only.
///
/// Errors: `TISSUE_USAGE` for JSON that does not parse (the parser's message, with its line and
/// column), and as `tissue_plan_start`.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_job_start_json(
    patient: *const tissue_patient,
    job_json: *const c_char,
    out: *mut *mut tissue_job,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let (patient, source) = unsafe { (get(patient, "patient")?, text(job_json, "job_json")?) };
        let spec: JobSpec = serde_json::from_str(source).map_err(|e| {
            Error::new(
                tissue_status::TISSUE_USAGE,
                format!("the job's JSON does not parse: {e}"),
            )
        })?;
        let job = start(patient, spec)?;
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(job)) }
    })
}

/// The job's progress as of its last reported step (and its state).
///
/// Thread safety: any thread, at any time (a short lock, never held while stepping).
#[no_mangle]
pub extern "C" fn tissue_job_progress(
    job: *const tissue_job,
    progress: *mut tissue_progress,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let job = unsafe { get(job, "job") }?;
        let p = *job.shared.progress.lock().map_err(poisoned)?;
        // SAFETY: `progress` is NULL or valid.
        unsafe { put(progress, "progress", p) }
    })
}

/// Asks the job to stop: it ends within one step (or one set-up phase) as cancelled. A job that
/// finishes its last step first stays finished. Does not wait (see `tissue_job_wait`).
///
/// Thread safety: any thread, at any time (an atomic flag).
#[no_mangle]
pub extern "C" fn tissue_job_cancel(job: *const tissue_job) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let job = unsafe { get(job, "job") }?;
        job.shared.cancel.cancel();
        Ok(())
    })
}

/// The job's end, waiting at most `timeout_s` seconds for it (negative: without limit; 0: just
/// look): `TISSUE_OK` when it finished (its results can be read), `TISSUE_TIMEOUT` while it
/// still runs, else how it ended (`TISSUE_CANCELLED`, or the failed run's status) with its
/// message.
///
/// Thread safety: any thread; several threads may wait at once.
#[no_mangle]
pub extern "C" fn tissue_job_wait(job: *const tissue_job, timeout_s: f64) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let job = unsafe { get(job, "job") }?;
        let deadline = (timeout_s >= 0.0)
            .then(|| Instant::now().checked_add(Duration::from_secs_f64(timeout_s.min(1e9))))
            .flatten();
        let mut end = job.shared.end.lock().map_err(poisoned)?;
        loop {
            match &*end {
                Some(Ok(_)) => return Ok(()),
                Some(Err(e)) => return Err(e.clone()),
                None => {}
            }
            end = match deadline {
                None if timeout_s < 0.0 => job.shared.ended.wait(end).map_err(poisoned)?,
                _ => {
                    let left = deadline.map_or(Duration::ZERO, |d| {
                        d.saturating_duration_since(Instant::now())
                    });
                    if left.is_zero() {
                        return Err(Error::new(
                            tissue_status::TISSUE_TIMEOUT,
                            format!("the job is still running after {timeout_s} s"),
                        ));
                    }
                    job.shared
                        .ended
                        .wait_timeout(end, left)
                        .map_err(poisoned)?
                        .0
                }
            };
        }
    })
}

/// Blocks until the job ends, calling `callback` (may be NULL) on this thread about every 50 ms
/// with its progress; a non-zero return from the callback cancels the job (the call then
/// returns `TISSUE_CANCELLED` once it has stopped). Returns as `tissue_job_wait`.
///
/// Thread safety: any thread; the callback runs on the calling thread only.
#[no_mangle]
pub extern "C" fn tissue_job_run(
    job: *const tissue_job,
    callback: tissue_progress_callback,
    user_data: *mut c_void,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let job_ref = unsafe { get(job, "job") }?;
        loop {
            match tissue_job_wait(job, 0.05) {
                tissue_status::TISSUE_TIMEOUT => {}
                tissue_status::TISSUE_OK => return Ok(()),
                status => return Err(Error::new(status, last_error_text())),
            }
            if let Some(callback) = callback {
                let p = *job_ref.shared.progress.lock().map_err(poisoned)?;
                // SAFETY: the caller's callback, given a valid progress record for the call.
                if unsafe { callback(&p, user_data) } != 0 {
                    job_ref.shared.cancel.cancel();
                }
            }
        }
    })
}

/// The message `tissue_last_error` would give.
fn last_error_text() -> String {
    let n = crate::ffi::tissue_last_error(std::ptr::null_mut(), 0);
    let mut buf = vec![0u8; n.max(1)];
    crate::ffi::tissue_last_error(buf.as_mut_ptr().cast(), buf.len());
    buf.pop();
    String::from_utf8_lossy(&buf).into_owned()
}

/// Plans one insertion and blocks until it ends: `tissue_plan_start` then `tissue_job_run`. The
/// job is returned in `*out` whenever it was started (also when it was cancelled or failed), so
/// that its results or progress can be read; free it with `tissue_job_free`.
///
/// Thread safety: any thread; the callback runs on the calling thread only.
#[no_mangle]
pub extern "C" fn tissue_plan_run(
    patient: *const tissue_patient,
    options: *const tissue_plan_options,
    callback: tissue_progress_callback,
    user_data: *mut c_void,
    out: *mut *mut tissue_job,
) -> tissue_status {
    if out.is_null() {
        return guard(|| Err(Error::null("out")));
    }
    let started = tissue_plan_start(patient, options, out);
    if started != tissue_status::TISSUE_OK {
        return started;
    }
    // SAFETY: `out` was just written with the new job.
    tissue_job_run(unsafe { *out }, callback, user_data)
}

/// Cancels the job if it still runs, waits for its threads to end (within one step) and frees
/// it. NULL does nothing.
///
/// Thread safety: no other call may use the job during or after this one.
#[no_mangle]
pub extern "C" fn tissue_job_free(job: *mut tissue_job) {
    guard_void(|| {
        if job.is_null() {
            return;
        }
        // SAFETY: the header's contract: a job from this library, freed once.
        let job = unsafe { Box::from_raw(job) };
        job.shared.cancel.cancel();
        if let Some(driver) = job.driver.lock().ok().and_then(|mut d| d.take()) {
            let _ = driver.join();
        }
        drop(job);
    });
}

/// Runs `f` on the finished job's results, or says why there are none.
fn with_done<T>(
    job: *const tissue_job,
    f: impl FnOnce(&Done) -> Result<T, Error>,
) -> Result<T, Error> {
    // SAFETY: the header's contract.
    let job = unsafe { get(job, "job") }?;
    let end = job.shared.end.lock().map_err(poisoned)?;
    match &*end {
        Some(Ok(done)) => f(done),
        Some(Err(e)) => Err(Error::new(
            e.status,
            format!("the job has no results: {}", e.message),
        )),
        None => Err(Error::new(
            tissue_status::TISSUE_NOT_READY,
            "the job is still running: wait for it (tissue_job_wait) first",
        )),
    }
}

fn numbers(r: &RunResult) -> tissue_plan_result {
    tissue_plan_result {
        area_before_cm2: r.area_before_cm2,
        area_after_cm2: r.area_after_cm2,
        area_gain_cm2: r.area_gain_cm2,
        volume_difference_cm3: r.volume_difference_cm3,
        implant_volume_cm3: r.implant_volume_cm3,
        implant_volume_end_cm3: r.implant_volume_end_cm3,
        implant_compression: r.implant_compression,
        dome_height_cm: r.dome_height_cm,
        max_displacement_cm: f64::from(r.max_displacement_cm),
        max_penetration_cm: f64::from(r.max_penetration_cm),
        region_radius_cm: r.region_radius_cm,
        time_step_s: f64::from(r.time_step_s),
        wall_time_s: r.wall_time_s,
        steps: r.steps,
        max_steps: r.max_steps,
        region_vertices: r.region_vertices as u64,
        settled: r.stop_reason == StopReason::Settled,
        boundary_unchanged: r.boundary_unchanged,
    }
}

fn not_single() -> Error {
    Error::invalid("this job is not a single insertion: read a sweep with tissue_job_sweep_row, a search with tissue_job_inverse_result, an expansion from tissue_job_report_json")
}

/// A finished single insertion's numbers (the report's fields).
///
/// Errors: `TISSUE_NOT_READY` while it runs; how it ended when it did not finish;
/// `TISSUE_INVALID_ARGUMENT` for a sweep, a search or an expansion.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_job_result(
    job: *const tissue_job,
    result: *mut tissue_plan_result,
) -> tissue_status {
    guard(|| {
        let r = with_done(job, |done| match &done.finished.report {
            JobReport::Single(r) => Ok(numbers(&r.body)),
            _ => Err(not_single()),
        })?;
        // SAFETY: `result` is NULL or valid.
        unsafe { put(result, "result", r) }
    })
}

/// A finished sweep's rows: `*count` (may be NULL) is set to the number of volumes.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_job_sweep_count(
    job: *const tissue_job,
    count: *mut usize,
) -> tissue_status {
    guard(|| {
        let n = with_done(job, |done| match &done.finished.report {
            JobReport::Sweep(_) => Ok(done.finished.sweep.len()),
            _ => Err(Error::invalid("this job is not a sweep")),
        })?;
        // SAFETY: `count` is NULL or valid.
        unsafe { put(count, "count", n) }
    })
}

/// Row `index` of a finished sweep (in the order the volumes were given): its volume and
/// numbers. A run of the sweep that failed gives its own status and message (the others are
/// still there).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_job_sweep_row(
    job: *const tissue_job,
    index: usize,
    volume_cm3: *mut f64,
    result: *mut tissue_plan_result,
) -> tissue_status {
    guard(|| {
        let (volume, row) = with_done(job, |done| match &done.finished.report {
            JobReport::Sweep(_) => done
                .finished
                .sweep
                .get(index)
                .map(|(v, r)| {
                    (
                        *v,
                        r.as_ref().map(numbers).map_err(|e| Error::from(e.clone())),
                    )
                })
                .ok_or_else(|| {
                    Error::invalid(format!(
                        "row {index} of a sweep of {} volumes",
                        done.finished.sweep.len()
                    ))
                }),
            _ => Err(Error::invalid("this job is not a sweep")),
        })?;
        // SAFETY: each output is NULL or valid.
        unsafe { crate::ffi::put_opt(volume_cm3, volume) };
        // SAFETY: as above.
        unsafe { put(result, "result", row?) }
    })
}

/// A finished inverse search's answer.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_job_inverse_result(
    job: *const tissue_job,
    result: *mut tissue_inverse_result,
) -> tissue_status {
    guard(|| {
        let r = with_done(job, |done| match &done.finished.report {
            JobReport::TargetGain(r) => Ok(tissue_inverse_result {
                target_gain_cm2: r.body.target_gain_cm2,
                bracket_low_cm3: r.body.bracket_cm3[0],
                bracket_high_cm3: r.body.bracket_cm3[1],
                volume_cm3: r.body.volume_cm3,
                area_gain_cm2: r.body.area_gain_cm2,
                converged: r.body.converged,
                runs: r.body.runs.len() as u32,
            }),
            _ => Err(Error::invalid("this job is not an inverse search")),
        })?;
        // SAFETY: `result` is NULL or valid.
        unsafe { put(result, "result", r) }
    })
}

/// A finished job's report, the planner's JSON contract (schema_version 1, `tool` `"capi"`):
/// `*length` (may be NULL) is set to the bytes it needs, NUL included; it is copied into
/// `buffer` when `capacity` is at least that (else `TISSUE_BUFFER_TOO_SMALL`: pass NULL, 0 to
/// query).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_job_report_json(
    job: *const tissue_job,
    buffer: *mut c_char,
    capacity: usize,
    length: *mut usize,
) -> tissue_status {
    guard(|| {
        with_done(job, |done| {
            // SAFETY: the header's contract on `buffer`, `capacity` and `length`.
            unsafe { copy_text(buffer, capacity, length, &done.report, "the report") }
        })
    })
}

/// A finished insertion's patient after the run, in the patient file's unit (every vertex; those
/// that did not move keep their positions bit for bit), as a new mesh (`tissue_mesh_free`).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_job_patient_after(
    job: *const tissue_job,
    out: *mut *mut tissue_mesh,
) -> tissue_status {
    guard(|| {
        let mesh = with_done(job, |done| match &done.finished.patient {
            Some(patient) => Ok(patient.after.clone()),
            None => Err(not_single()),
        })?;
        let handle = into_handle(tissue_mesh {
            kind: MeshKind::Surface(mesh),
        });
        // SAFETY: `out` is NULL or valid.
        let written = unsafe { put(out, "out", handle) };
        if written.is_err() {
            // SAFETY: just made, not handed out.
            unsafe { free_handle(handle) };
        }
        written
    })
}

/// Copies a per-vertex field (a `tissue_field`) of a finished insertion's patient into `out`,
/// which holds `capacity` floats: at least the patient's vertex count.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_job_copy_field(
    job: *const tissue_job,
    field: u32,
    out: *mut f32,
    capacity: usize,
) -> tissue_status {
    guard(|| {
        with_done(job, |done| {
            let Some(patient) = &done.finished.patient else {
                return Err(not_single());
            };
            let values = match field {
                0 => &patient.displacement,
                1 => &patient.stretch,
                2 => &patient.in_region,
                f => {
                    return Err(Error::invalid(format!(
                        "`field` {f} is not a tissue_field (0 displacement, 1 stretch, 2 in region)"
                    )))
                }
            };
            // SAFETY: `out` holds `capacity` floats.
            unsafe { copy_out(out, capacity, values, "the field") }
        })
    })
}
