//! The job socket: one WebSocket per tab; `run` starts a job on the planner's front door (one at
//! a time on the server), `cancel` or a closed socket cancels it; progress, then one terminal
//! message, go back on the socket ([`JobMessage`]). `preview` asks for a live preview
//! ([`crate::preview`]), answered on the same socket.

use std::time::{Duration, Instant};

use axum::extract::ws::{Message, WebSocket};
use tissue_planner::{Finished, JobReport, PlanError, Stopped, Tool};
use tokio::sync::mpsc;

use crate::api::loaded;
use crate::messages::{
    ClientMessage, ErrorBody, ErrorKind, FailedRow, Fields, JobMessage, RunMessage,
};
use crate::serve::send_within;
use crate::state::{KeptJob, Running, Studio};

/// The least time between two progress messages.
const PROGRESS_EVERY: Duration = Duration::from_millis(50);

/// The job a tab owns. It is set when the tab's run is accepted and cleared only by *that* job's
/// terminal message: a tab's next run can be accepted (the server frees its one job slot as the
/// previous job ends) before the previous job's terminal message has been sent on, and clearing
/// on any terminal message left the new job with no owner (nobody could cancel it, and closing
/// the tab did not either).
#[derive(Debug, Default)]
struct Owned(Option<Running>);

impl Owned {
    /// The tab's run `job` was accepted.
    fn started(&mut self, job: Running) {
        self.0 = Some(job);
    }

    /// A terminal message of job `id` went out: the tab owns nothing if that was its job.
    fn ended(&mut self, id: &str) {
        if self.0.as_ref().is_some_and(|r| r.id == id) {
            self.0 = None;
        }
    }

    /// Cancels the tab's job, if it has one.
    fn cancel(&self) {
        if let Some(r) = &self.0 {
            r.cancel.cancel();
        }
    }
}

/// Serves one tab's socket until it closes or the server stops; its job is cancelled then.
pub async fn serve_socket(studio: Studio, mut socket: WebSocket) {
    let (tx, mut rx) = mpsc::unbounded_channel::<JobMessage>();
    let mut shutdown = studio.on_shutdown();
    let send_timeout = studio.limits().send_timeout;
    let mut mine = Owned::default();
    let previews = crate::preview::Previews::start(studio.clone(), tx.clone());
    loop {
        tokio::select! {
            incoming = socket.recv() => {
                let text = match incoming {
                    Some(Ok(Message::Text(t))) => t.to_string(),
                    Some(Ok(Message::Close(_)) | Err(_)) | None => break,
                    Some(Ok(_)) => continue,
                };
                match serde_json::from_str::<ClientMessage>(&text) {
                    Ok(ClientMessage::Cancel) => mine.cancel(),
                    Ok(ClientMessage::Preview(p)) => previews.request(*p),
                    Ok(ClientMessage::Run(run)) => match start(&studio, *run, tx.clone()) {
                        Ok(r) => mine.started(r),
                        Err(error) => {
                            let _ = tx.send(JobMessage::Refused { error });
                        }
                    },
                    Err(e) => {
                        let error = ErrorBody::new(
                            ErrorKind::Usage,
                            format!("the page sent a message the server does not know: {e}"),
                        );
                        let _ = tx.send(JobMessage::Refused { error });
                    }
                }
            }
            Some(out) = rx.recv() => {
                let text = match serde_json::to_string(&out) {
                    Ok(text) => text,
                    Err(e) => {
                        tracing::error!(error = %e, "a job message could not be written");
                        continue;
                    }
                };
                if !send_within(&mut socket, Message::Text(text.into()), send_timeout).await {
                    break;
                }
                if let Some(id) = out.ended_job() {
                    mine.ended(id);
                }
            }
            _ = shutdown.changed() => break,
        }
    }
    // The tab is gone (or the server stops): its job and its preview are cancelled.
    mine.cancel();
    drop(previews);
}

/// Starts `run` on a thread of its own, unless a job runs.
fn start(
    studio: &Studio,
    run: RunMessage,
    tx: mpsc::UnboundedSender<JobMessage>,
) -> Result<Running, ErrorBody> {
    let id = studio.id("j");
    let running = studio.start_job(&id).map_err(|other| {
        ErrorBody::new(
            ErrorKind::Busy,
            format!(
                "a job ({other}) is running on this server, from this tab or another: wait for \
                 it or cancel it; one job runs at a time because each uses every core"
            ),
        )
    })?;
    let _ = tx.send(JobMessage::Accepted {
        job: id.clone(),
        mode: run.spec.mode,
    });
    let owner = studio.clone();
    let job = running.clone();
    let spawned = std::thread::Builder::new()
        .name(format!("studio-{id}"))
        .spawn(move || {
            let _span = tracing::info_span!("studio_job", job = %job.id).entered();
            let message = match run_job(&owner, &job, run, &tx) {
                Ok(done) => done,
                Err(Stopped::Cancelled { steps }) => JobMessage::Cancelled {
                    job: job.id.clone(),
                    steps,
                },
                Err(Stopped::Failed(e)) => JobMessage::Failed {
                    job: job.id.clone(),
                    error: ErrorBody::of(&e),
                },
            };
            owner.end_job(&job.id);
            let _ = tx.send(message);
        });
    if let Err(e) = spawned {
        studio.end_job(&id);
        return Err(ErrorBody::new(
            ErrorKind::Run,
            format!("could not start the job: {e}"),
        ));
    }
    Ok(running)
}

/// Runs the job through the planner to its end on this thread, writes its files, and gives
/// the terminal message.
fn run_job(
    studio: &Studio,
    running: &Running,
    run: RunMessage,
    tx: &mpsc::UnboundedSender<JobMessage>,
) -> Result<JobMessage, Stopped> {
    let patient = loaded(studio, &run.patient)?;
    let scenario = tissue_planner::Scenario::new(
        tissue_planner::Patient::clone(&patient.patient),
        run.spec.request.clone(),
    )?;
    let planned = run.spec.plan(&scenario)?;
    let runs = planned.runs;
    let mut last: Option<Instant> = None;
    let finished = planned.run(&scenario, Tool::Studio, &running.cancel, |p| {
        if last.is_none_or(|t| t.elapsed() >= PROGRESS_EVERY) {
            last = Some(Instant::now());
            let _ = tx.send(JobMessage::progress(&running.id, runs, p));
        }
    })?;
    let dir = studio
        .job_dir(&running.id)
        .map_err(|e| PlanError::new(tissue_planner::ErrorKind::Output, e.to_string()))?;
    write_files(&dir, &finished)?;
    let message = finished_message(&running.id, &finished, scenario.cm_per_unit())?;
    let kept = KeptJob {
        spec: run.spec,
        finished,
        patient,
    };
    studio.add_finished(&running.id, dir, kept);
    Ok(message)
}

/// The job's files: `report.json`, a single run's patient as PLY, OBJ and VTK (with its fields),
/// an expansion's `chart.png`. A stored plan's downloads are written by the same calls
/// (`cases.rs`), so they are byte for byte the job's.
pub(crate) fn write_files(dir: &std::path::Path, finished: &Finished) -> Result<(), PlanError> {
    finished.report.write(&dir.join("report.json"))?;
    if let Some(patient) = &finished.patient {
        for name in ["patient.ply", "patient.obj", "patient.vtk"] {
            patient.write_mesh(&dir.join(name))?;
        }
    }
    if let JobReport::Expansion(r) = &finished.report {
        r.write_chart(&dir.join("chart.png"), (1200, 600))?;
    }
    Ok(())
}

/// The `finished` message: the report, a single run's fields (displacement in the file's unit:
/// `scale` cm per unit), a sweep's failed runs with their messages as the page labels fields.
fn finished_message(job: &str, finished: &Finished, scale: f32) -> Result<JobMessage, PlanError> {
    let fields = finished
        .patient
        .as_ref()
        .map(|patient| Box::new(Fields::of(patient, scale)));
    let failed_runs = match &finished.report {
        JobReport::Sweep(r) => r
            .body
            .failed_runs
            .iter()
            .map(|f| FailedRow {
                volume_cm3: f.volume_cm3,
                error: ErrorBody::of(&f.error),
            })
            .collect(),
        _ => Vec::new(),
    };
    Ok(JobMessage::Finished {
        job: job.to_owned(),
        report: finished.report.to_value()?,
        fields,
        failed_runs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tissue_planner::CancelToken;

    fn job(id: &str) -> Running {
        Running {
            id: id.to_owned(),
            cancel: CancelToken::new(),
        }
    }

    /// The orphan-job race of the security probe: run A ends, the tab's next run B is accepted,
    /// and only then does A's terminal message go out. The tab must still own B.
    #[test]
    fn a_terminal_message_clears_only_its_own_job() {
        let (a, b) = (job("ja"), job("jb"));
        let mut mine = Owned::default();
        mine.started(a.clone());
        mine.started(b.clone());
        mine.ended("ja");
        mine.cancel();
        assert!(b.cancel.is_cancelled(), "closing the tab cancels B");
        assert!(!a.cancel.is_cancelled());
        mine.ended("jb");
        assert!(mine.0.is_none(), "nothing owned after B's end");
    }
}
