//! # tissue-planner: the planning front door
//!
//! Everything a front end needs to plan an implant insertion, in one place, so that `insert`,
//! the studio and the C ABI cannot drift apart:
//!
//! - **Units** ([`Unit`]: the mesh file's unit; inside everything is cm, g, s) and the
//!   request's named choices ([`Shape`], [`Rule`], [`Detect`], [`Solver`], [`ColorBy`]).
//! - **The patient** ([`Patient`]): read from a file or bytes in its unit and scaled to cm, or a
//!   [`Shipped`] mesh (the Table 2 plane, the chest, the head); its [`MeshSummary`].
//! - **The request** ([`PlanRequest`]): one flat record, JSON names with their units, every
//!   field defaulting to the library's value (`{}` is Table 2), the solver among them
//!   (`"solver": "quasi_static" | "explicit"`, [`Solver`]; every mode's runs use it). [`PlanRequest::check`] refuses a
//!   value that cannot be right, naming the field, and bounds every size and count so that a
//!   request's work is bounded: [`MAX_STEPS`] steps a run, [`MAX_SWEEP_VOLUMES`] volumes a sweep,
//!   lengths up to [`MAX_LENGTH_CM`], volumes up to [`MAX_VOLUME_CM3`], depth and thickness up
//!   to [`MAX_DEPTH_CM`] and [`MAX_THICKNESS_CM`], tissue values up to [`MAX_YOUNG_KPA`] and
//!   [`MAX_DENSITY_G_CM3`], a time step up to [`MAX_TIME_STEP_S`], growth steps of at least
//!   [`MIN_GROWTH_STEP_H`].
//! - **Placing** ([`Scenario`]): the point snapped to the surface, the normal (interpolated
//!   vertex normals), the tangent (given or +x, turned by `rotation_deg`), the
//!   [`tissue_app::InsertionJob`]; [`Scenario::preview`] draws the footprint and the region and
//!   runs the set-up, so that a placement that cannot run is refused before Run.
//! - **The result on the patient** ([`PatientResult`]): the deformed patient in the file's unit
//!   with its fields (displacement, stretch, in-region), as mesh files and a picture.
//! - **The report** ([`report`]): the JSON contract, with [`report::SCHEMA_VERSION`]; field
//!   names are only ever added. Every report names the solver its runs were asked to use
//!   (`inputs.solver`) and every run its solver's `iterations` and final `residual_n`.
//! - **What to run** ([`JobSpec`]): a single run, a sweep, the inverse search or an expansion
//!   over weeks, as one JSON shape (the studio's run message, the C ABI's job JSON, the flags
//!   of `insert`), planned on a [`Scenario`] into the worker's job ([`JobSpec::plan`]).
//! - **Running and finishing it** ([`PlannedJob::run`], [`finish`]): the job run on the
//!   worker with a [`CancelToken`] and a progress callback, then its [`JobReport`], the
//!   deformed patient and a sweep's runs ([`Finished`]); divergence is checked and the sweep
//!   policy applied here, once, for every front end.
//! - **Errors** ([`PlanError`]): a kind ([`ErrorKind`]: a front end's exit code or HTTP status),
//!   the request field at fault, and one sentence that says what to change.
//!
//! No terminal, no threads of its own (jobs run on [`tissue_app`]'s worker), no HTTP.
//!
//! ## Example: Table 2, planned as every front end plans it
//! ```
//! use tissue_planner::{CancelToken, JobReport, JobSpec, Patient, Scenario, Shipped, Tool};
//!
//! // The job as the studio's socket, the C ABI and `insert --job` take it.
//! let spec: JobSpec = serde_json::from_str(r#"{ "request": { "volume_cm3": 100, "max_steps": 40 } }"#)?;
//! let scenario = Scenario::new(Patient::shipped(Shipped::Table2)?, spec.request.clone())?;
//! assert!(scenario.preview().ok);
//! let mut steps = 0;
//! let finished = spec
//!     .plan(&scenario)?
//!     .run(&scenario, Tool::Insert, &CancelToken::new(), |_| steps += 1)
//!     .map_err(tissue_planner::PlanError::from)?;
//! let JobReport::Single(report) = &finished.report else { unreachable!() };
//! assert_eq!(report.body.steps, 40); // a short run for the example: not settled
//! assert!(report.body.area_gain_cm2 > 0.0);
//! assert!(steps > 0 && finished.patient.is_some());
//! assert!(finished.report.to_json()?.contains(r#""mode": "single""#));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]

mod error;
#[cfg(feature = "golden")]
pub mod golden;
mod job;
mod patient;
mod preview;
pub mod report;
mod request;
mod result;
mod run;
mod scenario;
mod units;

pub use error::{ErrorKind, PlanError};
pub use job::{JobKind, JobMode, JobSpec, PlannedJob};
pub use patient::{
    BoxSummary, DefectSummary, LoopSummary, MeshSummary, Patient, Shipped, TABLE2_SIDE_CM,
    TABLE2_VERTICES_PER_SIDE,
};
pub use preview::{
    coarse, preview_edge_cm, DomePreview, Previewer, PREVIEW_COARSENING, PREVIEW_IMPLANT_VERTICES,
    PREVIEW_MAX_STEPS,
};
pub use report::{JobReport, Tool};
pub use request::{
    check_search, check_sweep, PlanRequest, MAX_DENSITY_G_CM3, MAX_DEPTH_CM, MAX_LENGTH_CM,
    MAX_STEPS, MAX_SWEEP_VOLUMES, MAX_THICKNESS_CM, MAX_TIME_STEP_S, MAX_VOLUME_CM3, MAX_YOUNG_KPA,
    MIN_GROWTH_STEP_H,
};
pub use result::{is_mesh_path, PatientResult};
pub use run::{finish, Finished, Stopped};
pub use scenario::{default_gain_tolerance, Preview, Scenario, FOOTPRINT_LIFT_CM};
pub use tissue_app::{CancelToken, Event, Handle, Job, Outcome, ProgressEvent};
pub use units::{ColorBy, Detect, Rule, Shape, Solver, Unit, KPA};
