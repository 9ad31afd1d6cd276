//! # tissue-app: planning runs on a worker thread (SPEC A.6)
//!
//! The thesis's planning system keeps the simulation in its insertion module and runs it on a
//! thread of its own, so that the user can keep working and cancel. This crate is that module:
//!
//! - [`Handle::start`] runs a [`Job`] on a new worker thread: one insertion
//!   ([`InsertionJob`]), a sweep over implant volumes run in parallel ([`SweepJob`]), the
//!   inverse search for the volume of a target area gain ([`InverseJob`]), the plane press
//!   ([`PlanePressJob`]), an expansion over weeks with skin growth and its band
//!   ([`ExpansionJob`]; progress per settle, tagged with the protocol day), or a host's own work ([`Job::custom`], reporting through a
//!   [`ProgressSink`]).
//! - The handle delivers [`Event`]s: [`Event::Progress`] ([`ProgressEvent`]: run, step, step
//!   limit, the last step's summed displacement, how close the stop criterion is, elapsed time),
//!   then one of [`Event::Finished`] ([`Outcome`]), [`Event::Cancelled`], [`Event::Failed`]
//!   ([`AppError`]). Poll with [`Handle::try_event`] from a UI loop, block with
//!   [`Handle::recv`] / [`Handle::events`], or just [`Handle::wait`] for the result; or
//!   [`Handle::run`] with a progress callback, cancelled from any thread through the
//!   [`CancelToken`] given to [`Handle::start_cancellable`].
//! - The mechanics run on a simulation surface of their own by default ([`SimMesh::Remeshed`]:
//!   the region of a real scan filled, remeshed and smoothed, the result mapped back onto the
//!   patient's vertices by [`PlannedInsertion::on_patient`]), or on the patient's own triangles
//!   ([`SimMesh::Patient`], the thesis's planes).
//! - The set-up ("region + layers + implant, then run") is in one place, [`prepare`] /
//!   [`plan`] (and [`plan_sweep`], [`plan_inverse`]), callable without threads: the worker runs
//!   the same code, so its results equal theirs bit for bit.
//!
//! ## Invariants
//! - **One worker per handle**; a handle runs one job.
//! - **Event order**: zero or more progress events, then exactly one terminal event
//!   (finished, cancelled or failed); nothing after it. If the worker thread dies without
//!   reporting, the receiver still gets [`Event::Failed`] with [`AppError::WorkerLost`]; a panic
//!   in a job is caught and reported as [`AppError::Panicked`] with its message.
//! - **The simulation never waits for the receiver**: progress goes through a bounded queue
//!   ([`HandleOptions::progress_capacity`]) and is dropped while the queue is full; the
//!   terminal event has its own channel and is never dropped.
//! - **Cancel latency ≤ one step**: [`Handle::cancel`] sets a flag that the worker reads after
//!   every step (and between set-up phases); the job then ends with [`Event::Cancelled`].
//! - **Drop = cancel + join**: dropping the handle cancels the job and joins the thread.
//!
//! No file I/O, no terminal output; the job phases are `tracing` spans (`app_job`,
//! `app_setup`, `app_region`, `app_implant`, `app_run`, `app_sweep_run`, `app_inverse_run`).
//! Every type in events is owned and `Send`, so a host (e.g. a C++ application behind an FFI
//! layer) can move them where it likes.
//!
//! ## Example: a host UI thread
//! ```
//! use std::time::{Duration, Instant};
//!
//! use glam::Vec3;
//! use tissue_app::{Event, Handle, InsertionJob, Job, Placement};
//! use tissue_implant::{ImplantShape, ImplantSpec};
//!
//! // A 20 cm plane of 17 × 17 vertices and a small round implant at its centre.
//! let patient = tissue_mesh::grid(17, 20.0)?;
//! let implant = ImplantSpec::new(ImplantShape::Round { diameter: 5.0 }, 10.0)
//!     .with_vertex_budget(60);
//! let job = InsertionJob::new(
//!     patient,
//!     Placement::new(Vec3::ZERO, Vec3::Z, Vec3::X),
//!     implant,
//! );
//! let mut handle = Handle::start(Job::Insertion(job));
//!
//! // The UI loop: draw a progress bar from the events, cancel after a few steps.
//! let deadline = Instant::now() + Duration::from_secs(60);
//! let mut seen = 0;
//! let terminal = 'ui: loop {
//!     while let Some(event) = handle.try_event() {
//!         match event {
//!             Event::Progress(p) => {
//!                 seen += 1;
//!                 // e.g. bar.set(p.step as f64 / p.max_steps as f64), label(p.settle)
//!                 assert!(p.step >= 1 && p.step <= p.max_steps);
//!                 assert!((0.0..=1.0).contains(&p.settle));
//!                 if seen == 5 {
//!                     handle.cancel();
//!                 }
//!             }
//!             terminal => break 'ui terminal,
//!         }
//!     }
//!     assert!(Instant::now() < deadline, "the run should end");
//!     std::thread::sleep(Duration::from_millis(1)); // the rest of the UI's frame
//! };
//! // Cancelled after the fifth step (or finished, if the run was shorter than that).
//! assert!(matches!(terminal, Event::Cancelled { .. } | Event::Finished(_)));
//! assert!(handle.try_event().is_none()); // nothing after the terminal event
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Without threads, the same run is `tissue_app::plan(&job, |_| ControlFlow::Continue(()))`.
#![forbid(unsafe_code)]

mod error;
mod plan;
mod settle;
mod worker;

pub use error::AppError;
pub use plan::{
    footprint_radius, plan, plan_expansion, plan_inverse, plan_sweep, prepare, ExpansionJob,
    InsertionJob, InverseJob, PatientAfter, Placement, PlanePressJob, PlannedExpansion,
    PlannedInsertion, PlannedInverse, PreparedInsertion, SimMesh, SolverFigures, SweepJob,
    SweepResult, SweepRun,
};
pub use worker::{
    CancelToken, CustomJob, Event, Events, Handle, HandleOptions, Job, Outcome, ProgressEvent,
    ProgressSink, RunMonitor,
};
