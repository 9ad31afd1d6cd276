//! # tissue-studio: the planner in a browser
//!
//! The server behind `studio`: an axum router ([`router`]) over a [`Studio`] (the patients
//! loaded, the finished jobs' files, the one running job, the case library), the page's static
//! files embedded in the binary ([`assets`]), and the planning done by tissue-planner on
//! tissue-app's worker — the same code as `insert`.
//!
//! The Cases view (`/cases`, the `/api/cases/…` routes): the case library of tissue-cases (one
//! SQLite database in the `--data` folder, [`Studio::with_data`]) as the surgeon sees it: a
//! finished job saved with its patient's scan, the patients and their plans, a plan opened
//! without recomputing, two compared, rename, note, delete, erase, export and import. Each route
//! is one library call made off the async threads; what the `tissue-cases` command also needs is
//! in the library, not here. [`serve`] runs it on a listener with time limits and a stop that always
//! ends; [`Access`] says who may use it (Host, Origin, token). The binary (`main.rs`) only parses
//! flags, binds, and turns signals into the stop.
//!
//! `apps/studio/SECURITY.md` is the threat model: who attacks a server holding patient scans, and
//! which defence here stops what.
//!
//! The HTTP API, the WebSocket messages and the JSON are in `apps/studio/API.md`.
//!
//! The trainer (`/trainer`): a session of tissue-scenes on a native thread at 60 steps per
//! second, its newest surface frame sent as a binary WebSocket message ([`trainer`]); one
//! session at a time.
//!
//! ## Policies
//! - **One job at a time.** The simulation uses every core; a second run, from the same tab or
//!   another, is refused (`refused`, kind `busy`) with a message that says a job is running and
//!   how far. Previews are not jobs: the placement check (the set-up without the run) is
//!   always answered, and a live preview (the `preview` message: a coarse, capped run, one in
//!   flight per tab, the newest, at most [`Limits::previews`] at once on the server) is
//!   answered beside a running job.
//! - **Closing the tab cancels its job**: a job belongs to its WebSocket; when the socket closes
//!   the job is cancelled (within one simulation step).
//! - **Only its own page.** Every request must name this server in `Host`; WebSocket upgrades and
//!   POSTs from another origin are refused; off loopback, every request needs the token
//!   ([`Access`]). Ids of patients, jobs and organs are 128 random bits.
//! - **Limits.** Uploads up to [`UPLOAD_LIMIT`] bytes, [`Limits::uploads`] at a time, sent as
//!   `application/octet-stream`; header, body and send timeouts ([`Limits`]); at most [`KEPT`]
//!   patients and [`KEPT`] finished jobs are kept, the oldest dropped first (their files
//!   deleted).
//! - **Files.** The server writes its transient files only in its temporary folder
//!   ([`Studio::temp_dir`], mode 0700, made afresh), which it removes when it stops, and what is
//!   saved in the case library ([`Studio::library`]: the `--data` folder; for [`Studio::new`] a
//!   folder inside the temporary one, so tests never touch the user's library).
//! - **No panics on input.** Every user error is a JSON `{"error": {kind, field, message}}`.
//!
//! ## Example: the API without a browser
//! ```
//! use axum::body::Body;
//! use axum::http::{Request, StatusCode};
//! use tower::ServiceExt;
//!
//! # tokio::runtime::Runtime::new()?.block_on(async {
//! let studio = tissue_studio::Studio::new()?;
//! let app = tissue_studio::router(studio.clone(), tissue_studio::Access::loopback(8000));
//! let response = app
//!     .clone()
//!     .oneshot(
//!         Request::post("/api/patients?shipped=table2")
//!             .header("host", "127.0.0.1:8000")
//!             .body(Body::empty())?,
//!     )
//!     .await?;
//! assert_eq!(response.status(), StatusCode::OK);
//! // A page at another address (DNS rebinding) is not served.
//! let rebound = app
//!     .oneshot(
//!         Request::get("/api/meshes")
//!             .header("host", "rebind.evil.example:8000")
//!             .body(Body::empty())?,
//!     )
//!     .await?;
//! assert_eq!(rebound.status(), StatusCode::MISDIRECTED_REQUEST);
//! studio.shutdown();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! # })?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]

mod access;
mod api;
pub mod assets;
mod cases;
mod jobs;
pub mod material;
pub mod messages;
mod preview;
mod serve;
mod state;
pub mod trainer;

pub use access::{content_security_policy, Access};
pub use api::router;
pub use serve::{serve, BodyTimeout};
pub use state::{KeptJob, Limits, Loaded, Studio, JOB_SOCKETS, KEPT, UPLOAD_LIMIT};
