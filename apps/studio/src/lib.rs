//! # tissue-studio: the planner in a browser
//!
//! The server behind `studio`: an axum router ([`router`]) over a [`Studio`] (the patients
//! loaded, the finished jobs' files, the one running job), the page's static files embedded in
//! the binary ([`assets`]), and the planning done by tissue-planner on tissue-app's worker — the
//! same code as `insert`. The binary (`main.rs`) only parses flags, binds and serves.
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
//!   how far. Previews (the set-up without the run) are not jobs and are always answered.
//! - **Closing the tab cancels its job**: a job belongs to its WebSocket; when the socket closes
//!   the job is cancelled (within one simulation step).
//! - **Limits.** Uploads up to [`UPLOAD_LIMIT`] bytes; at most [`KEPT`] patients and [`KEPT`]
//!   finished jobs are kept, the oldest dropped first (their files deleted).
//! - **Files.** The server writes only in its temporary folder ([`Studio::temp_dir`]), which it
//!   removes when it stops.
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
//! let app = tissue_studio::router(studio.clone());
//! let response = app
//!     .oneshot(Request::post("/api/patients?shipped=table2").body(Body::empty())?)
//!     .await?;
//! assert_eq!(response.status(), StatusCode::OK);
//! studio.shutdown();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! # })?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::print_stdout,
    clippy::print_stderr
)]

mod api;
pub mod assets;
mod jobs;
mod state;
pub mod trainer;

pub use api::router;
pub use state::{Studio, KEPT, UPLOAD_LIMIT};
