//! The worker thread, its jobs and events, and the handle that drives it.

use std::any::Any;
use std::fmt;
use std::ops::ControlFlow;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{bounded, Receiver, RecvTimeoutError, Sender, TryRecvError};
use tissue_implant::{
    plane_press, ExpansionProgress, ExpansionStage, ImplantError, PlanePressOutcome, Progress,
    RunParams,
};

use crate::plan::{
    expansion_with, inverse_with, prepare_with, saturating_elapsed, sweep_with, ExpansionJob,
    InsertionJob, InverseJob, PlanePressJob, PlannedExpansion, PlannedInsertion, PlannedInverse,
    RunEvent, SweepJob, SweepResult,
};
use crate::settle::SettleMeter;
use crate::AppError;

/// A host's own job: runs on the worker with a [`ProgressSink`] to report progress and see
/// cancels, and returns any `Send` value (delivered as [`Outcome::Custom`]).
pub type CustomJob =
    Box<dyn FnOnce(&ProgressSink) -> Result<Box<dyn Any + Send>, AppError> + Send + 'static>;

/// What the worker runs.
pub enum Job {
    /// One insertion ([`plan`](crate::plan)); gives [`Outcome::Insertion`].
    Insertion(InsertionJob),
    /// A series of volumes in parallel ([`plan_sweep`](crate::plan_sweep)); gives
    /// [`Outcome::Sweep`]. Progress comes from several runs interleaved.
    Sweep(SweepJob),
    /// The volume for a target area gain ([`plan_inverse`](crate::plan_inverse)); gives
    /// [`Outcome::Inverse`].
    Inverse(InverseJob),
    /// The plane press ([`tissue_implant::plane_press`]); gives [`Outcome::PlanePress`].
    PlanePress(PlanePressJob),
    /// Expansion over weeks with skin growth and its band
    /// ([`plan_expansion`](crate::plan_expansion)); gives [`Outcome::Expansion`]. Progress:
    /// one event per settle step, tagged with the protocol day.
    Expansion(Box<ExpansionJob>),
    /// A host's own work ([`Job::custom`]); gives [`Outcome::Custom`]. A panic in it comes back
    /// as [`Event::Failed`] with [`AppError::Panicked`]; returning [`AppError::Cancelled`] (or
    /// the library's `Cancelled`) gives [`Event::Cancelled`].
    Custom(CustomJob),
}

impl Job {
    /// A [`Job::Custom`] from a closure.
    pub fn custom<T, F>(f: F) -> Job
    where
        T: Any + Send,
        F: FnOnce(&ProgressSink) -> Result<T, AppError> + Send + 'static,
    {
        Job::Custom(Box::new(move |sink| {
            f(sink).map(|value| Box::new(value) as Box<dyn Any + Send>)
        }))
    }

    /// The job's kind, for logs: `"insertion"`, `"sweep"`, `"inverse"`, `"plane_press"`,
    /// `"custom"`.
    pub fn kind(&self) -> &'static str {
        match self {
            Job::Insertion(_) => "insertion",
            Job::Sweep(_) => "sweep",
            Job::Inverse(_) => "inverse",
            Job::PlanePress(_) => "plane_press",
            Job::Expansion(_) => "expansion",
            Job::Custom(_) => "custom",
        }
    }
}

impl fmt::Debug for Job {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Job::Insertion(j) => f.debug_tuple("Insertion").field(j).finish(),
            Job::Sweep(j) => f.debug_tuple("Sweep").field(j).finish(),
            Job::Inverse(j) => f.debug_tuple("Inverse").field(j).finish(),
            Job::PlanePress(j) => f.debug_tuple("PlanePress").field(j).finish(),
            Job::Expansion(j) => f.debug_tuple("Expansion").field(j).finish(),
            Job::Custom(_) => f.write_str("Custom(..)"),
        }
    }
}

/// What a finished job gives.
pub enum Outcome {
    /// Of [`Job::Insertion`].
    Insertion(Box<PlannedInsertion>),
    /// Of [`Job::Sweep`]: one run per volume, in input order.
    Sweep(Box<SweepResult>),
    /// Of [`Job::Inverse`]: the volume found, every run taken and how each ended.
    Inverse(Box<PlannedInverse>),
    /// Of [`Job::PlanePress`].
    PlanePress(Box<PlanePressOutcome>),
    /// Of [`Job::Expansion`].
    Expansion(Box<PlannedExpansion>),
    /// Of [`Job::Custom`]: the host's value (downcast with [`Outcome::into_custom`]).
    Custom(Box<dyn Any + Send>),
}

impl Outcome {
    /// The insertion result, if this is one.
    pub fn into_insertion(self) -> Option<PlannedInsertion> {
        match self {
            Outcome::Insertion(p) => Some(*p),
            _ => None,
        }
    }

    /// The sweep result, if this is one.
    pub fn into_sweep(self) -> Option<SweepResult> {
        match self {
            Outcome::Sweep(s) => Some(*s),
            _ => None,
        }
    }

    /// The inverse search, if this is one.
    pub fn into_inverse(self) -> Option<PlannedInverse> {
        match self {
            Outcome::Inverse(s) => Some(*s),
            _ => None,
        }
    }

    /// The plane press's outcome, if this is one.
    pub fn into_plane_press(self) -> Option<PlanePressOutcome> {
        match self {
            Outcome::PlanePress(p) => Some(*p),
            _ => None,
        }
    }

    /// The expansion's result, if this is one.
    pub fn into_expansion(self) -> Option<PlannedExpansion> {
        match self {
            Outcome::Expansion(p) => Some(*p),
            _ => None,
        }
    }

    /// A custom job's value, if this is one of type `T`.
    pub fn into_custom<T: Any>(self) -> Option<T> {
        match self {
            Outcome::Custom(value) => value.downcast::<T>().ok().map(|b| *b),
            _ => None,
        }
    }
}

impl fmt::Debug for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Outcome::Insertion(p) => f.debug_tuple("Insertion").field(p).finish(),
            Outcome::Sweep(s) => f.debug_tuple("Sweep").field(s).finish(),
            Outcome::Inverse(s) => f.debug_tuple("Inverse").field(s).finish(),
            Outcome::PlanePress(p) => f.debug_tuple("PlanePress").field(p).finish(),
            Outcome::Expansion(p) => f.debug_tuple("Expansion").field(p).finish(),
            Outcome::Custom(_) => f.write_str("Custom(..)"),
        }
    }
}

/// One step of one run, as the worker reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProgressEvent {
    /// Which run of the job: 0 for a single insertion or plane press; the index into
    /// [`SweepJob::volumes`] for a sweep; the search's run number (from 0) for an inverse search.
    pub run: usize,
    /// Steps done in this run (1 after the first step).
    pub step: u64,
    /// The run's step limit.
    pub max_steps: u64,
    /// Summed displacement of every particle in the last step (cm).
    pub displacement: f64,
    /// Contacts found in the last step.
    pub contacts: u32,
    /// How close the run is to its stop criterion, in `[0, 1]`: `0` until the criterion's
    /// window (`RunParams::stop.window` steps) is full, then the larger of
    /// `(min / max) / (1 − tolerance)` over the window's summed displacements (the thesis's
    /// ratio test) and `floor / max` (the speed floor from `RunParams::settle_speed`), clamped;
    /// `1` means the criterion is met. An indicator: the library ignores the expander's fill
    /// steps, so a run may end slightly before or after it reaches 1. The plane press ends on its
    /// step count, not on this.
    pub settle: f64,
    /// Wall time since the worker started the job.
    pub elapsed: Duration,
    /// An expansion job's protocol day (of its nominal run; `None` for its reference runs and
    /// every other job). An expansion's `run` is 0 for the protocol, `1 + i` for reference
    /// run `i`; `step` and `max_steps` count the current settle.
    pub day: Option<f64>,
}

/// What the worker reports: zero or more [`Event::Progress`], then exactly one terminal event
/// ([`Event::Finished`], [`Event::Cancelled`] or [`Event::Failed`]).
#[derive(Debug)]
pub enum Event {
    /// A step was done (some may be dropped when the receiver is slow).
    Progress(ProgressEvent),
    /// The job finished.
    Finished(Outcome),
    /// The job was cancelled between two steps.
    Cancelled {
        /// Steps completed before the cancel, summed over the job's runs.
        steps: u64,
    },
    /// The job failed (set-up or run error, panic, lost worker).
    Failed(AppError),
}

impl Event {
    /// Whether this is the last event of the job.
    pub fn is_terminal(&self) -> bool {
        !matches!(self, Event::Progress(_))
    }
}

/// The worker's side of the progress channel, given to [`Job::Custom`] jobs: report steps, see
/// cancels. `Sync`: a job may report from several threads.
#[derive(Debug)]
pub struct ProgressSink {
    tx: Sender<ProgressEvent>,
    cancel: Cancel,
    start: Instant,
    steps: AtomicU64,
}

impl ProgressSink {
    /// Whether the handle asked to cancel (or was dropped).
    pub fn is_cancelled(&self) -> bool {
        self.cancel.is_cancelled()
    }

    /// [`ControlFlow::Break`] once cancelled.
    pub fn checkpoint(&self) -> ControlFlow<()> {
        if self.is_cancelled() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    /// Wall time since the worker started the job.
    pub fn elapsed(&self) -> Duration {
        saturating_elapsed(self.start)
    }

    /// Steps reported so far (every [`ProgressSink::report`] and [`RunMonitor::observe`] call
    /// counts one), summed over runs.
    pub fn steps(&self) -> u64 {
        self.steps.load(Ordering::Relaxed)
    }

    /// Reports one step as given and counts it; dropped without waiting when the receiver's
    /// queue is full. Returns [`ProgressSink::checkpoint`].
    pub fn report(&self, event: ProgressEvent) -> ControlFlow<()> {
        self.steps.fetch_add(1, Ordering::Relaxed);
        // Full or disconnected: drop it, the simulation never waits for the receiver.
        let _ = self.tx.try_send(event);
        self.checkpoint()
    }

    /// A per-run observer for a library run with `params` (its stop criterion drives
    /// [`ProgressEvent::settle`]), to pass as the run's progress callback:
    /// `insertion.run(|p| monitor.observe(p))`.
    pub fn monitor(&self, run: usize, params: &RunParams) -> RunMonitor<'_> {
        RunMonitor {
            sink: self,
            run,
            meter: SettleMeter::new(params),
        }
    }
}

/// Turns a library run's [`Progress`] into [`ProgressEvent`]s with the settle meter
/// ([`ProgressSink::monitor`]).
#[derive(Debug)]
pub struct RunMonitor<'a> {
    sink: &'a ProgressSink,
    run: usize,
    meter: SettleMeter,
}

impl RunMonitor<'_> {
    /// The same with the criterion's speed floor (cm of summed displacement per step; e.g.
    /// [`PreparedInsertion::settle_floor`](crate::PreparedInsertion::settle_floor)).
    pub fn with_floor(self, floor: f64) -> Self {
        RunMonitor {
            meter: self.meter.with_floor(floor),
            ..self
        }
    }

    /// Reports `progress` and returns [`ControlFlow::Break`] once cancelled.
    pub fn observe(&mut self, progress: &Progress) -> ControlFlow<()> {
        let settle = self.meter.push(progress.last.displacement);
        self.sink.report(ProgressEvent {
            run: self.run,
            step: progress.steps,
            max_steps: progress.max_steps,
            displacement: progress.last.displacement,
            contacts: progress.last.contacts,
            settle,
            elapsed: self.sink.elapsed(),
            day: None,
        })
    }
}

/// A cancel request shared between threads: clone it into a Ctrl-C handler, a socket's task or
/// a C host's call, and the job started with it ([`Handle::start_cancellable`]) ends within one
/// step of [`CancelToken::cancel`]. Cancelling is sticky: a token, once cancelled, stays so.
#[derive(Debug, Clone, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token not cancelled.
    pub fn new() -> Self {
        CancelToken::default()
    }

    /// Asks every job started with this token (or a clone) to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`CancelToken::cancel`] was called on this token or a clone.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// What a job's worker reads: the handle's own flag (set by [`Handle::cancel`] and by dropping
/// the handle) and the caller's token it was started with. Dropping a handle never cancels the
/// caller's token, which may outlive the job (a Ctrl-C flag read again afterwards).
#[derive(Debug, Clone, Default)]
struct Cancel {
    own: CancelToken,
    caller: Option<CancelToken>,
}

impl Cancel {
    fn is_cancelled(&self) -> bool {
        self.own.is_cancelled() || self.caller.as_ref().is_some_and(CancelToken::is_cancelled)
    }
}

/// Options of [`Handle::start_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HandleOptions {
    /// Progress events queued for the receiver; more are dropped until it reads (default 64).
    /// At least 1.
    pub progress_capacity: usize,
}

impl Default for HandleOptions {
    /// 64 queued progress events.
    fn default() -> Self {
        HandleOptions {
            progress_capacity: 64,
        }
    }
}

/// One job on its own worker thread: read its events, cancel it, wait for it. Dropping the
/// handle cancels the job and joins the thread.
#[derive(Debug)]
pub struct Handle {
    progress: Receiver<ProgressEvent>,
    terminal: Receiver<Event>,
    /// A terminal event taken from its channel, held back until the queued progress is read.
    pending: Option<Event>,
    /// The terminal event was handed out.
    done: bool,
    cancel: Cancel,
    thread: Option<JoinHandle<()>>,
}

impl Handle {
    /// Starts `job` on a new worker thread with [`HandleOptions::default`].
    pub fn start(job: Job) -> Handle {
        Handle::start_with(job, HandleOptions::default())
    }

    /// Starts `job` on a new worker thread. If the thread cannot be started, the handle's only
    /// event is [`Event::Failed`] with [`AppError::Spawn`].
    pub fn start_with(job: Job, options: HandleOptions) -> Handle {
        Handle::start_inner(job, options, Cancel::default())
    }

    /// Starts `job` on a new worker thread, cancelled through `cancel` (or [`Handle::cancel`]):
    /// a token already cancelled ends the job before its first phase. The handle never cancels
    /// `cancel` itself (not even when dropped): the caller may read it afterwards.
    pub fn start_cancellable(job: Job, options: HandleOptions, cancel: CancelToken) -> Handle {
        let cancel = Cancel {
            own: CancelToken::new(),
            caller: Some(cancel),
        };
        Handle::start_inner(job, options, cancel)
    }

    fn start_inner(job: Job, options: HandleOptions, cancel: Cancel) -> Handle {
        let (progress_tx, progress) = bounded(options.progress_capacity.max(1));
        let (terminal_tx, terminal) = bounded(1);
        let sink = ProgressSink {
            tx: progress_tx,
            cancel: cancel.clone(),
            start: Instant::now(),
            steps: AtomicU64::new(0),
        };
        let spawned = std::thread::Builder::new()
            .name("tissue-app-worker".into())
            .spawn(move || worker(job, sink, terminal_tx));
        let (thread, pending) = match spawned {
            Ok(thread) => (Some(thread), None),
            Err(e) => (
                None,
                Some(Event::Failed(AppError::Spawn {
                    message: e.to_string(),
                })),
            ),
        };
        Handle {
            progress,
            terminal,
            pending,
            done: false,
            cancel,
            thread,
        }
    }

    /// Asks the job to stop: it ends within one step (or one set-up phase) with
    /// [`Event::Cancelled`]. A job that finishes its last step first still reports
    /// [`Event::Finished`].
    pub fn cancel(&self) {
        self.cancel.own.cancel();
    }

    /// Whether [`Handle::cancel`] was called (or the job's [`CancelToken`] cancelled).
    pub fn is_cancelled(&self) -> bool {
        self.cancel.is_cancelled()
    }

    /// Blocks until the job ends, handing every progress event to `on_progress` on this thread
    /// (no polling: the call sleeps until the worker reports). Cancel it from another thread
    /// through the token the job was started with ([`Handle::start_cancellable`]).
    ///
    /// # Errors
    /// As [`Handle::wait`]: [`AppError::Cancelled`] with the steps done for a cancelled job,
    /// the job's error for a failed one.
    pub fn run(mut self, mut on_progress: impl FnMut(&ProgressEvent)) -> Result<Outcome, AppError> {
        while let Some(event) = self.recv() {
            match event {
                Event::Progress(p) => on_progress(&p),
                Event::Finished(outcome) => return Ok(outcome),
                Event::Cancelled { steps } => return Err(AppError::Cancelled { steps }),
                Event::Failed(e) => return Err(e),
            }
        }
        Err(AppError::AlreadyReceived)
    }

    /// Whether the worker thread has ended: its terminal event is then ready (or was already
    /// received).
    pub fn is_finished(&self) -> bool {
        self.thread.as_ref().is_none_or(|t| t.is_finished())
    }

    /// The next event if one is ready, without blocking; `None` when none is ready or the
    /// terminal event was already received. Progress queued before the terminal event always
    /// comes first.
    pub fn try_event(&mut self) -> Option<Event> {
        if self.done {
            return None;
        }
        if self.pending.is_none() {
            if let Ok(p) = self.progress.try_recv() {
                return Some(Event::Progress(p));
            }
            match self.terminal.try_recv() {
                Ok(event) => self.pending = Some(event),
                Err(TryRecvError::Empty) => return None,
                Err(TryRecvError::Disconnected) => {
                    self.pending = Some(Event::Failed(AppError::WorkerLost));
                }
            }
        }
        self.after_terminal()
    }

    /// The next event, blocking until one comes; `None` once the terminal event was received.
    pub fn recv(&mut self) -> Option<Event> {
        self.recv_deadline(None)
    }

    /// The next event, blocking at most `timeout`; `None` on timeout or once the terminal
    /// event was received.
    pub fn recv_timeout(&mut self, timeout: Duration) -> Option<Event> {
        self.recv_deadline(Instant::now().checked_add(timeout))
    }

    fn recv_deadline(&mut self, deadline: Option<Instant>) -> Option<Event> {
        if self.done {
            return None;
        }
        if self.pending.is_none() {
            let mut select = crossbeam_channel::Select::new();
            let progress = select.recv(&self.progress);
            let terminal = select.recv(&self.terminal);
            let op = match deadline {
                None => select.select(),
                Some(d) => select.select_deadline(d).ok()?,
            };
            match op.index() {
                i if i == progress => match op.recv(&self.progress) {
                    Ok(p) => return Some(Event::Progress(p)),
                    // The worker dropped its sink: the terminal event is (or will never be) sent.
                    Err(_) => self.pending = Some(self.terminal_blocking(deadline)?),
                },
                i if i == terminal => {
                    self.pending = Some(match op.recv(&self.terminal) {
                        Ok(event) => event,
                        Err(_) => Event::Failed(AppError::WorkerLost),
                    });
                }
                _ => return None,
            }
        }
        self.after_terminal()
    }

    fn terminal_blocking(&self, deadline: Option<Instant>) -> Option<Event> {
        let received = match deadline {
            None => self
                .terminal
                .recv()
                .map_err(|_| RecvTimeoutError::Disconnected),
            Some(d) => self.terminal.recv_deadline(d),
        };
        match received {
            Ok(event) => Some(event),
            Err(RecvTimeoutError::Disconnected) => Some(Event::Failed(AppError::WorkerLost)),
            Err(RecvTimeoutError::Timeout) => None,
        }
    }

    /// With the terminal event held: the progress still queued first, then the terminal event.
    fn after_terminal(&mut self) -> Option<Event> {
        if let Ok(p) = self.progress.try_recv() {
            return Some(Event::Progress(p));
        }
        self.done = true;
        self.pending.take()
    }

    /// A blocking iterator over the remaining events, ending after the terminal event.
    pub fn events(&mut self) -> Events<'_> {
        Events { handle: self }
    }

    /// Blocks until the job ends, discarding progress.
    ///
    /// # Errors
    /// [`AppError::Cancelled`] for a cancelled job, the job's error for a failed one,
    /// [`AppError::AlreadyReceived`] when the terminal event was already taken.
    pub fn wait(mut self) -> Result<Outcome, AppError> {
        if self.done {
            return Err(AppError::AlreadyReceived);
        }
        let event = match self.pending.take() {
            Some(event) => event,
            None => match self.terminal.recv() {
                Ok(event) => event,
                Err(_) => Event::Failed(AppError::WorkerLost),
            },
        };
        self.done = true;
        match event {
            Event::Finished(outcome) => Ok(outcome),
            Event::Cancelled { steps } => Err(AppError::Cancelled { steps }),
            Event::Failed(e) => Err(e),
            // Progress never travels on the terminal channel.
            Event::Progress(_) => Err(AppError::WorkerLost),
        }
    }
}

impl Drop for Handle {
    /// Cancels the job and joins the worker (within one step, or one set-up phase).
    fn drop(&mut self) {
        self.cancel();
        if let Some(thread) = self.thread.take() {
            // A worker that died outside the job has nothing more to report.
            let _ = thread.join();
        }
    }
}

/// The blocking event iterator of [`Handle::events`].
#[derive(Debug)]
pub struct Events<'a> {
    handle: &'a mut Handle,
}

impl Iterator for Events<'_> {
    type Item = Event;

    fn next(&mut self) -> Option<Event> {
        self.handle.recv()
    }
}

/// The worker thread's body: run the job, catch a panic, send the one terminal event.
fn worker(job: Job, sink: ProgressSink, terminal: Sender<Event>) {
    let kind = job.kind();
    let span = tracing::info_span!("app_job", kind);
    let _entered = span.enter();
    let result = catch_unwind(AssertUnwindSafe(|| execute(job, &sink)));
    let event = match result {
        Ok(Ok(outcome)) => Event::Finished(outcome),
        Ok(Err(e)) => match e.cancelled_steps() {
            Some(steps) => Event::Cancelled { steps },
            None => Event::Failed(e),
        },
        Err(payload) => {
            let message = panic_message(payload.as_ref());
            // Dropping the payload may panic again; that must not take the terminal event away.
            let _ = catch_unwind(AssertUnwindSafe(move || drop(payload)));
            Event::Failed(AppError::Panicked { message })
        }
    };
    match &event {
        Event::Finished(_) => tracing::info!(kind, "job finished"),
        Event::Cancelled { steps } => tracing::info!(kind, steps, "job cancelled"),
        Event::Failed(e) => tracing::warn!(kind, error = %e, "job failed"),
        Event::Progress(_) => {}
    }
    drop(sink);
    // Capacity 1 and one message: never blocks. A receiver that is gone has nobody to tell.
    let _ = terminal.send(event);
}

fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic with a payload that is not a string".to_string()
    }
}

fn cancelled(sink: &ProgressSink) -> Result<(), AppError> {
    if sink.is_cancelled() {
        Err(AppError::Cancelled {
            steps: sink.steps(),
        })
    } else {
        Ok(())
    }
}

fn execute(job: Job, sink: &ProgressSink) -> Result<Outcome, AppError> {
    cancelled(sink)?;
    let is_cancelled = || sink.is_cancelled();
    match job {
        Job::Insertion(job) => {
            let prepared = prepare_with(&job, &is_cancelled)?;
            cancelled(sink)?;
            let mut monitor = sink
                .monitor(0, &job.params.run)
                .with_floor(prepared.settle_floor());
            let planned = prepared.run(|p| monitor.observe(p))?;
            Ok(Outcome::Insertion(Box::new(planned)))
        }
        Job::Sweep(job) => {
            let params = &job.base.params.run;
            let result = sweep_with(&job, &is_cancelled, |run, floor| {
                let mut monitor = sink.monitor(run, params).with_floor(floor);
                move |p: &Progress| monitor.observe(p)
            })?;
            // Runs that saw the cancel ended with `Cancelled` in place; the job as a whole was.
            cancelled(sink)?;
            Ok(Outcome::Sweep(Box::new(result)))
        }
        Job::Inverse(job) => {
            let params = &job.base.params.run;
            let mut monitor: Option<RunMonitor<'_>> = None;
            let result = inverse_with(&job, &is_cancelled, |event| match event {
                RunEvent::Start(run, floor) => {
                    monitor = Some(sink.monitor(run, params).with_floor(floor));
                    sink.checkpoint()
                }
                RunEvent::Step(_, p) => match monitor.as_mut() {
                    Some(m) => m.observe(p),
                    None => sink.checkpoint(),
                },
            });
            match result {
                Ok(search) => Ok(Outcome::Inverse(Box::new(search))),
                Err(ImplantError::Cancelled { .. }) => Err(AppError::Cancelled {
                    steps: sink.steps(),
                }),
                Err(e) => Err(e.into()),
            }
        }
        Job::PlanePress(job) => {
            let mut monitor = sink.monitor(0, &job.params.run);
            let outcome = plane_press(&job.region, &job.params, |p| monitor.observe(p))?;
            Ok(Outcome::PlanePress(Box::new(outcome)))
        }
        Job::Expansion(job) => {
            let monitor = |p: &ExpansionProgress| {
                let run = match p.stage {
                    ExpansionStage::Reference { index, .. } => 1 + index,
                    _ => 0,
                };
                sink.report(ProgressEvent {
                    run,
                    step: p.steps,
                    max_steps: p.budget,
                    displacement: 0.0,
                    contacts: 0,
                    settle: 0.0,
                    elapsed: sink.elapsed(),
                    day: (run == 0).then_some(p.day),
                })
            };
            match expansion_with(&job, &is_cancelled, &monitor) {
                Ok(planned) => Ok(Outcome::Expansion(Box::new(planned))),
                Err(ImplantError::Cancelled { .. }) => Err(AppError::Cancelled {
                    steps: sink.steps(),
                }),
                Err(e) => Err(e.into()),
            }
        }
        Job::Custom(f) => {
            let _span = tracing::info_span!("app_custom").entered();
            f(sink).map(Outcome::Custom)
        }
    }
}

#[cfg(test)]
#[allow(clippy::panic, clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A handle over channels the test fills by hand, with no thread.
    fn handle_over(
        progress: Vec<ProgressEvent>,
        terminal: Option<Event>,
    ) -> (Handle, Sender<ProgressEvent>) {
        let (ptx, prx) = bounded(16);
        let (ttx, trx) = bounded(1);
        for p in progress {
            let _ = ptx.try_send(p);
        }
        if let Some(t) = terminal {
            let _ = ttx.try_send(t);
        }
        let handle = Handle {
            progress: prx,
            terminal: trx,
            pending: None,
            done: false,
            cancel: Cancel::default(),
            thread: None,
        };
        (handle, ptx)
    }

    fn step(step: u64) -> ProgressEvent {
        ProgressEvent {
            run: 0,
            step,
            max_steps: 10,
            displacement: 0.0,
            contacts: 0,
            settle: 0.0,
            elapsed: Duration::ZERO,
            day: None,
        }
    }

    #[test]
    fn a_worker_that_dies_without_reporting_gives_failed_not_a_hang() {
        // Both senders dropped, nothing sent: try_event, recv and wait all report the loss.
        let (mut handle, ptx) = handle_over(vec![step(1)], None);
        drop(ptx);
        assert!(matches!(handle.try_event(), Some(Event::Progress(_))));
        assert!(matches!(
            handle.try_event(),
            Some(Event::Failed(AppError::WorkerLost))
        ));
        assert!(handle.try_event().is_none());
        assert!(handle.recv().is_none());

        let (mut handle, ptx) = handle_over(vec![], None);
        drop(ptx);
        assert!(matches!(
            handle.recv(),
            Some(Event::Failed(AppError::WorkerLost))
        ));

        let (handle, ptx) = handle_over(vec![], None);
        drop(ptx);
        assert_eq!(handle.wait().unwrap_err(), AppError::WorkerLost);
    }

    #[test]
    fn queued_progress_comes_before_the_terminal_event() {
        for _ in 0..50 {
            let (mut handle, _ptx) = handle_over(
                vec![step(1), step(2), step(3)],
                Some(Event::Cancelled { steps: 3 }),
            );
            let steps: Vec<u64> = (0..3)
                .map(|_| match handle.recv() {
                    Some(Event::Progress(p)) => p.step,
                    other => panic!("expected progress, got {other:?}"),
                })
                .collect();
            assert_eq!(steps, vec![1, 2, 3]);
            assert!(matches!(handle.recv(), Some(Event::Cancelled { steps: 3 })));
            assert!(handle.recv().is_none());
            assert!(handle.recv_timeout(Duration::from_millis(1)).is_none());
        }
        // A terminal event already received cannot be waited for again.
        let (mut handle, _ptx) = handle_over(vec![], Some(Event::Cancelled { steps: 0 }));
        assert!(handle.try_event().is_some_and(|e| e.is_terminal()));
        assert_eq!(handle.wait().unwrap_err(), AppError::AlreadyReceived);
    }

    #[test]
    fn recv_timeout_times_out_while_the_worker_is_busy() {
        let (mut handle, _ptx) = handle_over(vec![], None);
        // Keep the terminal sender alive by building the handle's channel again.
        let (ttx, trx) = bounded::<Event>(1);
        handle.terminal = trx;
        let start = Instant::now();
        assert!(handle.recv_timeout(Duration::from_millis(20)).is_none());
        assert!(start.elapsed() >= Duration::from_millis(20));
        let _ = ttx.send(Event::Cancelled { steps: 0 });
        assert!(matches!(
            handle.recv_timeout(Duration::from_millis(20)),
            Some(Event::Cancelled { .. })
        ));
    }
}
