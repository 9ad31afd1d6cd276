//! A tab's live previews: the `preview` message of the job socket, run by tissue-planner's
//! [`Previewer`] (the coarse run of the request), answered with a `preview` message.
//!
//! Bounded: a tab has at most one preview in flight, the newest. A preview message replaces the
//! one waiting (a `watch` channel holds only the last) and cancels the one computing (its
//! [`CancelToken`], within one step); the replaced one is not answered. The server computes at
//! most [`crate::Limits::previews`] at once over every tab; each is the planner's coarse run
//! (its edge, step and implant caps). Closing the tab cancels its preview.

use std::sync::{Arc, Mutex, PoisonError};

use tissue_planner::{CancelToken, ErrorKind as PlanKind, PlanError, Previewer, Stopped};
use tokio::sync::{mpsc, watch};

use crate::messages::{ErrorBody, JobMessage, PreviewMessage};
use crate::state::Studio;

/// One tab's previews: send [`Previews::request`]; dropping it cancels the one in flight and
/// ends its task.
#[derive(Debug)]
pub struct Previews {
    latest: watch::Sender<Option<PreviewMessage>>,
    current: Arc<Mutex<CancelToken>>,
}

impl Previews {
    /// Starts the tab's preview task, answering on `tx`.
    pub fn start(studio: Studio, tx: mpsc::UnboundedSender<JobMessage>) -> Previews {
        let (latest, rx) = watch::channel(None);
        let current = Arc::new(Mutex::new(CancelToken::new()));
        tokio::spawn(serve(studio, rx, Arc::clone(&current), tx));
        Previews { latest, current }
    }

    /// The newest preview: it replaces the one waiting, and the one computing is cancelled.
    pub fn request(&self, message: PreviewMessage) {
        // First the message, then the cancel: the task either sees the message before it
        // starts computing, or has stored the token this cancels.
        self.latest.send_replace(Some(message));
        self.cancel();
    }

    fn cancel(&self) {
        self.current
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .cancel();
    }
}

impl Drop for Previews {
    fn drop(&mut self) {
        self.cancel();
    }
}

/// The task: the newest preview, one at a time, until the tab's [`Previews`] is dropped.
async fn serve(
    studio: Studio,
    mut rx: watch::Receiver<Option<PreviewMessage>>,
    current: Arc<Mutex<CancelToken>>,
    tx: mpsc::UnboundedSender<JobMessage>,
) {
    let slots = studio.preview_slots();
    let mut previewer = Previewer::new();
    let mut computed = 0u64;
    while rx.changed().await.is_ok() {
        let Some(message) = rx.borrow_and_update().clone() else {
            continue;
        };
        let token = CancelToken::new();
        *current.lock().unwrap_or_else(PoisonError::into_inner) = token.clone();
        let Ok(_slot) = Arc::clone(&slots).acquire_owned().await else {
            return;
        };
        if rx.has_changed().unwrap_or(true) || token.is_cancelled() {
            continue; // a newer one came while this one waited
        }
        let Some(loaded) = studio.patient(&message.patient) else {
            let e = PlanError::new(
                PlanKind::Usage,
                "no such patient on the server (it keeps the last few): load it again",
            );
            let _ = tx.send(answer(message.seq, computed, Err(ErrorBody::of(&e))));
            continue;
        };
        let request = message.request;
        let run = tokio::task::spawn_blocking(move || {
            let result = previewer.preview(&loaded.patient, request, &token);
            (previewer, result)
        })
        .await;
        let result = match run {
            Ok((kept, result)) => {
                previewer = kept;
                result
            }
            Err(e) => {
                previewer = Previewer::new();
                Err(Stopped::Failed(PlanError::new(
                    PlanKind::Run,
                    format!("the preview failed: {e}; report this"),
                )))
            }
        };
        let out = match result {
            Ok(preview) => {
                computed += u64::from(!preview.reused);
                Ok(Box::new(preview))
            }
            // Replaced by a newer one (or the tab is closing): not answered.
            Err(Stopped::Cancelled { .. }) => continue,
            Err(Stopped::Failed(e)) => Err(ErrorBody::of(&e)),
        };
        let _ = tx.send(answer(message.seq, computed, out));
    }
}

fn answer(
    seq: u64,
    computed: u64,
    result: Result<Box<tissue_planner::DomePreview>, ErrorBody>,
) -> JobMessage {
    let (preview, error) = match result {
        Ok(p) => (Some(p), None),
        Err(e) => (None, Some(e)),
    };
    JobMessage::Preview {
        seq,
        computed,
        preview,
        error,
    }
}
