//! The one error type of the crate.

use tissue_implant::ImplantError;

/// Why a job did not give a result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AppError {
    /// Setting up or running the simulation failed (point off the surface, region too large,
    /// invalid parameter, divergence, …): the library's error, unchanged.
    #[error(transparent)]
    Implant(#[from] ImplantError),
    /// The job was cancelled between two steps ([`Handle::cancel`](crate::Handle::cancel) or a
    /// dropped handle). Returned by [`Handle::wait`](crate::Handle::wait); as an event it is
    /// [`Event::Cancelled`](crate::Event::Cancelled).
    #[error("cancelled after {steps} steps")]
    Cancelled {
        /// Steps completed before the cancel (summed over the job's runs).
        steps: u64,
    },
    /// The job panicked; the worker caught it.
    #[error("the job panicked: {message}")]
    Panicked {
        /// The panic message (or a note that the payload was not a string).
        message: String,
    },
    /// The worker thread ended without reporting a result (it died outside the job, e.g. while
    /// dropping a panic payload).
    #[error("the worker thread ended without reporting a result")]
    WorkerLost,
    /// The worker thread could not be started.
    #[error("could not start the worker thread: {message}")]
    Spawn {
        /// The operating system's reason.
        message: String,
    },
    /// The terminal event of this handle was already received (by
    /// [`Handle::try_event`](crate::Handle::try_event), [`Handle::recv`](crate::Handle::recv) or
    /// the event iterator) before [`Handle::wait`](crate::Handle::wait).
    #[error("the job's result was already received")]
    AlreadyReceived,
    /// A host job ([`Job::Custom`](crate::Job::Custom)) failed with its own message.
    #[error("{message}")]
    Job {
        /// The host's description of the failure.
        message: String,
    },
}

impl AppError {
    /// The steps done before a cancel, when this is a cancel (of the app or of the library).
    pub fn cancelled_steps(&self) -> Option<u64> {
        match self {
            AppError::Cancelled { steps }
            | AppError::Implant(ImplantError::Cancelled { steps }) => Some(*steps),
            _ => None,
        }
    }
}
