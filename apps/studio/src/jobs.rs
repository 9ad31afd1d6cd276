//! The job socket: one WebSocket per tab; `run` starts a job on tissue-app's worker (one at a
//! time on the server), `cancel` or a closed socket cancels it; progress, then one terminal
//! message, go back on the socket.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use axum::extract::ws::{Message, WebSocket};
use serde::Deserialize;
use serde_json::{json, Value};
use tissue_planner::report::{self, Inputs, RunResult};
use tissue_planner::{
    ErrorKind, Event, Handle, Job, JobKind, JobSpec, Outcome, PatientResult, PlanError, PlannedJob,
};
use tokio::sync::mpsc;

use crate::api::{scenario, ErrorBody};
use crate::serve::send_within;
use crate::state::{Running, Studio};

/// The report's `tool`.
const TOOL: &str = "studio";

/// How often the job thread looks at the cancel flag while it waits for events.
const POLL: Duration = Duration::from_millis(10);

/// The least time between two progress messages.
const PROGRESS_EVERY: Duration = Duration::from_millis(50);

/// A message from the page.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum ClientMessage {
    Run(Box<RunMessage>),
    Cancel,
}

/// A run: the patient's id and what to run, tissue-planner's [`JobSpec`] (the C ABI's job JSON),
/// whose unknown members are refused (serde's `flatten` would let them through).
#[derive(Debug)]
struct RunMessage {
    patient: String,
    spec: JobSpec,
}

impl<'de> Deserialize<'de> for RunMessage {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut members = serde_json::Map::<String, Value>::deserialize(d)?;
        let Some(Value::String(patient)) = members.remove("patient") else {
            return Err(D::Error::custom(
                "a run needs `patient`: the id an upload or a shipped patient returned",
            ));
        };
        let spec = JobSpec::deserialize(Value::Object(members)).map_err(D::Error::custom)?;
        Ok(RunMessage { patient, spec })
    }
}

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
            r.cancel.store(true, Ordering::Relaxed);
        }
    }
}

/// Serves one tab's socket until it closes or the server stops; its job is cancelled then.
pub async fn serve_socket(studio: Studio, mut socket: WebSocket) {
    let (tx, mut rx) = mpsc::unbounded_channel::<Value>();
    let mut shutdown = studio.on_shutdown();
    let send_timeout = studio.limits().send_timeout;
    let mut mine = Owned::default();
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
                    Ok(ClientMessage::Run(run)) => {
                        match start(&studio, *run, tx.clone()) {
                            Ok(r) => mine.started(r),
                            Err(body) => {
                                let _ = tx.send(json!({ "type": "refused", "error": body }));
                            }
                        }
                    }
                    Err(e) => {
                        let body = ErrorBody {
                            kind: "usage".to_owned(),
                            field: None,
                            message: format!("the page sent a message the server does not know: {e}"),
                        };
                        let _ = tx.send(json!({ "type": "refused", "error": body }));
                    }
                }
            }
            Some(out) = rx.recv() => {
                let terminal = matches!(out["type"].as_str(), Some("finished" | "failed" | "cancelled"));
                if !send_within(&mut socket, Message::Text(out.to_string().into()), send_timeout).await {
                    break;
                }
                if terminal {
                    if let Some(id) = out["job"].as_str() {
                        mine.ended(id);
                    }
                }
            }
            _ = shutdown.changed() => break,
        }
    }
    // The tab is gone (or the server stops): its job is cancelled.
    mine.cancel();
}

/// Starts `run` on a thread of its own, unless a job runs.
fn start(
    studio: &Studio,
    run: RunMessage,
    tx: mpsc::UnboundedSender<Value>,
) -> Result<Running, ErrorBody> {
    let id = studio.id("j");
    let running = studio.start_job(&id).map_err(|other| ErrorBody {
        kind: "busy".to_owned(),
        field: None,
        message: format!(
            "a job ({other}) is running on this server, from this tab or another: wait for it \
             or cancel it; one job runs at a time because each uses every core"
        ),
    })?;
    let _ = tx.send(json!({ "type": "accepted", "job": id, "mode": run.spec.mode.name() }));
    let owner = studio.clone();
    let job = running.clone();
    let spawned = std::thread::Builder::new()
        .name(format!("studio-{id}"))
        .spawn(move || {
            let _span = tracing::info_span!("studio_job", job = %job.id).entered();
            let message = match run_job(&owner, &job, run, &tx) {
                Ok(done) => done,
                Err(End::Cancelled(steps)) => {
                    json!({ "type": "cancelled", "job": job.id, "steps": steps })
                }
                Err(End::Failed(e)) if e.kind == ErrorKind::Cancelled => {
                    json!({ "type": "cancelled", "job": job.id, "steps": 0 })
                }
                Err(End::Failed(e)) => {
                    json!({ "type": "failed", "job": job.id, "error": ErrorBody::of(&e) })
                }
            };
            owner.end_job(&job.id);
            let _ = tx.send(message);
        });
    if let Err(e) = spawned {
        studio.end_job(&id);
        return Err(ErrorBody {
            kind: "run".to_owned(),
            field: None,
            message: format!("could not start the job: {e}"),
        });
    }
    Ok(running)
}

/// How a job ended without a result.
enum End {
    /// Cancelled after this many steps.
    Cancelled(u64),
    /// Refused or failed.
    Failed(PlanError),
}

impl From<PlanError> for End {
    fn from(e: PlanError) -> End {
        End::Failed(e)
    }
}

/// Runs the job to its end on this thread; the terminal message, or the error.
fn run_job(
    studio: &Studio,
    running: &Running,
    run: RunMessage,
    tx: &mpsc::UnboundedSender<Value>,
) -> Result<Value, End> {
    let scenario = scenario(studio, &run.patient, run.spec.request.clone())?;
    let inputs = Inputs::new(&scenario)?;
    let max_steps = scenario.job.params.run.stop.max_steps;
    let PlannedJob { job, runs, kind } = run.spec.plan(&scenario)?;
    let outcome = drive(job, running, runs, tx)?;
    let dir = studio
        .job_dir(&running.id)
        .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
    let finished = match outcome {
        Outcome::Insertion(planned) => {
            let patient = PatientResult::new(&scenario, &planned)?;
            let result = RunResult::of(&planned, patient.scan.as_ref(), max_steps);
            let report = serde_json::to_value(report::single(TOOL, inputs, result))
                .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
            for name in ["patient.ply", "patient.obj", "patient.vtk"] {
                patient.write_mesh(&dir.join(name))?;
            }
            write_report(&dir, &report)?;
            let scale = scenario.cm_per_unit();
            let fields = json!({
                "after": patient.after_cm.positions().iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>(),
                "displacement": patient.displacement.iter().map(|d| d * scale).collect::<Vec<f32>>(),
                "stretch": patient.stretch_or_one(),
                "in_region": patient.in_region,
            });
            json!({ "type": "finished", "job": running.id, "report": report, "fields": fields })
        }
        Outcome::Sweep(sweep) => {
            let mut rows = Vec::new();
            let mut warnings = Vec::new();
            for (volume, row) in report::sweep_rows(&sweep, max_steps) {
                match row {
                    Ok(row) => rows.push(row),
                    Err(e) => warnings.push(format!(
                        "the {volume} cm³ run failed: {}",
                        ErrorBody::of(&e).message
                    )),
                }
            }
            let report = serde_json::to_value(report::sweep(TOOL, inputs, &sweep, rows))
                .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
            write_report(&dir, &report)?;
            json!({ "type": "finished", "job": running.id, "report": report, "fields": null, "warnings": warnings })
        }
        Outcome::Expansion(planned) => {
            let JobKind::Expansion(job) = kind else {
                return Err(End::Failed(PlanError::new(
                    ErrorKind::Run,
                    "an expansion result without its job",
                )));
            };
            let r = report::expansion(TOOL, inputs, &scenario.request, &job, &planned);
            let png = r.chart((1200, 600))?;
            let report = serde_json::to_value(&r)
                .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
            write_report(&dir, &report)?;
            let tmp = dir.join(".chart.png.tmp");
            std::fs::write(&tmp, png)
                .and_then(|()| std::fs::rename(&tmp, dir.join("chart.png")))
                .map_err(|e| {
                    PlanError::new(ErrorKind::Output, format!("cannot write the chart: {e}"))
                })?;
            json!({ "type": "finished", "job": running.id, "report": report, "fields": null })
        }
        Outcome::Inverse(found) => {
            let JobKind::TargetGain { target, bracket } = kind else {
                return Err(End::Failed(PlanError::new(
                    ErrorKind::Run,
                    "a search result without its target",
                )));
            };
            let report =
                serde_json::to_value(report::inverse(TOOL, inputs, target, bracket, &found))
                    .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
            write_report(&dir, &report)?;
            json!({ "type": "finished", "job": running.id, "report": report, "fields": null })
        }
        other => {
            return Err(End::Failed(PlanError::new(
                ErrorKind::Run,
                format!("the worker returned an unexpected result: {other:?}"),
            )))
        }
    };
    studio.add_finished(&running.id, dir);
    Ok(finished)
}

fn write_report(dir: &std::path::Path, report: &Value) -> Result<(), PlanError> {
    let text = serde_json::to_string_pretty(report)
        .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
    let tmp = dir.join(".report.json.tmp");
    std::fs::write(&tmp, text + "\n")
        .and_then(|()| std::fs::rename(&tmp, dir.join("report.json")))
        .map_err(|e| PlanError::new(ErrorKind::Output, format!("cannot write the report: {e}")))
}

/// Runs `job` on tissue-app's worker, forwarding progress and watching the cancel flag.
fn drive(
    job: Job,
    running: &Running,
    runs: usize,
    tx: &mpsc::UnboundedSender<Value>,
) -> Result<Outcome, End> {
    let mut handle = Handle::start(job);
    let mut last = Instant::now() - PROGRESS_EVERY;
    loop {
        if running.cancel.load(Ordering::Relaxed) && !handle.is_cancelled() {
            handle.cancel();
        }
        let Some(event) = handle.recv_timeout(POLL) else {
            continue;
        };
        match event {
            Event::Progress(p) => {
                if last.elapsed() >= PROGRESS_EVERY {
                    last = Instant::now();
                    let _ = tx.send(json!({
                        "type": "progress", "job": running.id, "run": p.run,
                        "runs": runs.max(p.run + 1), "step": p.step, "max_steps": p.max_steps,
                        "settle": p.settle, "elapsed_s": p.elapsed.as_secs_f64(),
                        "day": p.day,
                    }));
                }
            }
            Event::Finished(outcome) => return Ok(outcome),
            Event::Cancelled { steps } => return Err(End::Cancelled(steps)),
            Event::Failed(e) => return Err(End::Failed(PlanError::from_app(&e))),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;

    use super::*;

    fn job(id: &str) -> Running {
        Running {
            id: id.to_owned(),
            cancel: Arc::new(AtomicBool::new(false)),
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
        assert!(
            b.cancel.load(Ordering::Relaxed),
            "closing the tab cancels B"
        );
        assert!(!a.cancel.load(Ordering::Relaxed));
        mine.ended("jb");
        assert!(mine.0.is_none(), "nothing owned after B's end");
    }
}
