//! The trainer's server side: shipped organs and uploads, and one live session at a time — a
//! native simulation thread stepping at a fixed rate, publishing only its newest surface frame,
//! which the socket task sends as a binary WebSocket frame (see `API.md`).
//!
//! The socket's text messages are typed: [`Command`] (page → server) and [`TrainerMessage`]
//! (server → page), both `{"type": …}`-tagged JSON; the tests build and read them with these
//! types too. A failure's `error.kind` comes from one function, [`error_body`].

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use axum::extract::ws::{Message, WebSocket};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use tissue_scenes::{
    Organ, SceneError, SceneErrorKind, SelfCollision, Session, SessionOptions, ShippedOrgan,
    TrainerEvent,
};
use tokio::sync::{mpsc, watch};

use crate::material::{MaterialError, TissueMaterial};
use crate::messages::{ErrorBody, ErrorKind};
use crate::serve::send_within;
use crate::state::Studio;

/// Steps per second of the simulation thread.
pub const STEPS_PER_SECOND: f64 = 60.0;

/// How often stats go to the page.
const STATS_EVERY: Duration = Duration::from_millis(250);

/// Commands waiting for the simulation thread; a page that sends more between two steps is told
/// to slow down (the page sends a drag per animation frame).
pub const COMMAND_QUEUE: usize = 256;

/// The frame's magic number, "TSF1" little-endian.
pub const FRAME_MAGIC: u32 = 0x3146_5354;

/// One published surface frame: the newest wins.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Counts frames published.
    pub number: u32,
    /// The session's step.
    pub step: u32,
    /// Node positions, cm, flat.
    pub positions: Vec<f32>,
    /// The tissue's force on the probe, N.
    pub force: [f32; 3],
    /// The probe's tip, cm (NaN when none).
    pub tip: [f32; 3],
    /// The surface's version and its triangles.
    pub surface: Arc<(u64, Vec<u32>)>,
}

impl Frame {
    /// The binary frame of `API.md`; the index buffer only when `with_indices`.
    pub fn encode(&self, with_indices: bool) -> Vec<u8> {
        let triangles = self.surface.1.len() / 3;
        let vertices = self.positions.len() / 3;
        let mut out = Vec::with_capacity(48 + 4 * self.positions.len() + 12 * triangles);
        let mut word = |w: u32| out.extend_from_slice(&w.to_le_bytes());
        word(FRAME_MAGIC);
        word(u32::from(with_indices));
        word(self.number);
        word(self.step);
        word(vertices as u32);
        word(triangles as u32);
        for v in self.force.iter().chain(&self.tip) {
            word(v.to_bits());
        }
        for v in &self.positions {
            out.extend_from_slice(&v.to_le_bytes());
        }
        if with_indices {
            for i in &self.surface.1 {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
        out
    }
}

/// What the simulation thread reports besides frames; with the socket's `frames_per_s`, the
/// `stats` message.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Steps taken.
    pub steps: u64,
    /// Median and p99 step time, ms.
    pub step_ms: StepTimes,
    /// Steps per second, measured over the last second.
    pub steps_per_s: f64,
    /// Frames sent to the page per second, measured over the last second (the socket's).
    pub frames_per_s: f64,
    /// `V/V₀ − 1`.
    pub volume_drift: f64,
    /// Nodes (grows as cuts split them).
    pub nodes: usize,
    /// Tets.
    pub tets: usize,
    /// Paused.
    pub paused: bool,
    /// |force| on the probe, N.
    pub force_n: f64,
    /// Whether the organ's surface collides with itself (the `self_collision` command; on by
    /// default).
    pub self_collision: bool,
    /// Self-contacts of the last step (tissue-scenes' `Session::self_contacts`): the surface
    /// vertex–triangle pairs within the detection band (0 with self-collision off).
    pub self_contacts: usize,
    /// Of those, the ones the solver had to push apart.
    pub self_contacts_active: usize,
}

/// Step times of [`Stats`], ms.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StepTimes {
    /// Median of the recent steps.
    pub median: f64,
    /// 99th percentile of the recent steps.
    pub p99: f64,
}

/// A command from the page to the simulation thread (`{"type": "load", …}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Command {
    /// Start (or restart) with an organ.
    Load {
        /// A shipped organ's id or an upload's.
        organ: String,
    },
    /// Probe down on a surface point.
    Grab {
        /// cm.
        point: [f32; 3],
        /// Index into the current surface's triangles.
        triangle: usize,
    },
    /// Probe moves.
    Drag {
        /// cm.
        target: [f32; 3],
    },
    /// Probe up.
    Release,
    /// Scalpel: a path of surface points and the view direction.
    Cut {
        /// cm.
        path: Vec<[f32; 3]>,
        /// The camera's viewing direction.
        view_dir: [f32; 3],
    },
    /// Needle: the two sides of a wound.
    Suture {
        /// cm.
        a: [f32; 3],
        /// cm.
        b: [f32; 3],
    },
    /// Back to the organ as loaded.
    Reset,
    /// Back to the organ as loaded, then play its demonstration (tissue-scenes' scripted
    /// scenario: the appendix procedure, or a probe pressed and dragged on a tray).
    Demo,
    /// Pause or resume.
    Pause {
        /// Paused?
        paused: bool,
    },
    /// One step while paused.
    Step,
    /// The organ's material, applied on the next reset, load or demonstration (checked now:
    /// refused naming the field out of range); answered with a `material` message.
    Material {
        /// The material asked for.
        material: TissueMaterial,
    },
    /// Self-collision of the organ's surface on or off (on by default, tissue-scenes'
    /// `SessionOptions::self_collision`; off for comparison): at once on the running session,
    /// and for every later one until switched again; the `scene` message and the stats say which
    /// is in force.
    SelfCollision {
        /// On?
        on: bool,
    },
}

/// A text message from the server to the page (`{"type": "scene", …}`). `E` is the error's
/// body: [`ErrorBody`] on the server; a reader that only needs its fields (the tests) reads it
/// as any type that deserializes `{kind, field, message}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum TrainerMessage<E = ErrorBody> {
    /// A session started on an organ: what the page allocates for.
    Scene(SceneInfo),
    /// Something happened in the session.
    Event {
        /// The event (`kind`, `step`, `text`).
        event: TrainerEvent,
    },
    /// The session's figures, every 250 ms.
    Stats(Stats),
    /// A command was not taken (the server is busy, or the message is unknown).
    Refused {
        /// Why.
        error: E,
    },
    /// A command or a step failed.
    Failed {
        /// Why.
        error: E,
    },
    /// The answer to a `material` command: the material in force and the one waiting for the
    /// next reset.
    Material(MaterialState),
}

/// The `material` message.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MaterialState {
    /// The live session's material (null before an organ is loaded).
    pub in_force: Option<TissueMaterial>,
    /// The material applied on the next reset, load or demonstration (null when none waits:
    /// never asked for, or the one in force).
    pub pending: Option<TissueMaterial>,
}

/// The `scene` message: the organ and the buffers the page allocates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneInfo {
    /// The organ's id (a shipped organ's or an upload's).
    pub organ: String,
    /// What a person reads.
    pub label: String,
    /// Nodes as loaded.
    pub nodes: usize,
    /// Tets as loaded.
    pub tets: usize,
    /// Buffer sizes that hold what cuts are likely to add.
    pub capacity: Capacity,
    /// The tray the organ lies on.
    pub tray: TrayInfo,
    /// The organ's top as loaded, before it settles (cm above the tray's top).
    pub top: f32,
    /// The material in force.
    pub material: TissueMaterial,
    /// Whether the session's surface collides with itself: tissue-scenes' default (on) until
    /// the page sends `self_collision` (what the page's checkbox starts from).
    pub self_collision: bool,
}

/// Buffer sizes of [`SceneInfo`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Capacity {
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
}

/// The tray of [`SceneInfo`]: a square centred on x = z = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrayInfo {
    /// Its sides along x and z, cm.
    pub size: [f32; 2],
    /// The height of its top, cm (0).
    pub top: f32,
}

/// Why a command was not done, as the page's `error.kind` ([`error_body`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// A command that cannot be done now (no organ loaded yet) or that the server does not know.
    Usage,
    /// No organ of that id.
    NotFound,
    /// Another tab's session runs, or too many commands wait.
    Busy,
    /// A scene error of this kind (tissue-scenes' [`SceneError::kind`]).
    Scene(SceneErrorKind),
}

/// An error's body: its kind (the one place a [`Fault`] is named for the page) and message.
pub fn error_body(fault: Fault, message: impl Into<String>) -> ErrorBody {
    let kind = match fault {
        Fault::Usage => ErrorKind::Usage,
        Fault::NotFound => ErrorKind::NotFound,
        Fault::Busy => ErrorKind::Busy,
        Fault::Scene(kind) => match kind {
            SceneErrorKind::Input => ErrorKind::Input,
            SceneErrorKind::Mesh | SceneErrorKind::Meshing => ErrorKind::Mesh,
            SceneErrorKind::TooLarge => ErrorKind::TooLarge,
            SceneErrorKind::Parameters => ErrorKind::Parameters,
            SceneErrorKind::Tool => ErrorKind::Usage,
            SceneErrorKind::Simulation => ErrorKind::Run,
        },
    };
    ErrorBody::new(kind, message)
}

/// A command that failed: why and what to do.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    /// Its kind.
    pub fault: Fault,
    /// The command's member at fault (its JSON name), if one is: the page marks its input.
    pub field: Option<&'static str>,
    /// One sentence for the user.
    pub message: String,
}

impl Refusal {
    fn new(fault: Fault, message: impl Into<String>) -> Refusal {
        Refusal {
            fault,
            field: None,
            message: message.into(),
        }
    }

    fn body(self) -> ErrorBody {
        ErrorBody {
            field: self.field.map(str::to_owned),
            ..error_body(self.fault, self.message)
        }
    }
}

impl From<MaterialError> for Refusal {
    fn from(e: MaterialError) -> Refusal {
        Refusal {
            fault: Fault::Scene(SceneErrorKind::Parameters),
            field: e.field(),
            message: e.to_string(),
        }
    }
}

impl From<SceneError> for Refusal {
    fn from(e: SceneError) -> Refusal {
        Refusal::new(Fault::Scene(e.kind()), e.to_string())
    }
}

/// Uploaded organs, kept by id (the last few).
#[derive(Debug, Default)]
pub struct Organs {
    uploads: Mutex<Vec<(String, Arc<Organ>)>>,
    busy: AtomicBool,
}

impl Organs {
    /// Keeps an upload; its id.
    pub fn add(&self, organ: Organ) -> String {
        let id = crate::state::new_id("u");
        let mut list = self.uploads.lock().unwrap_or_else(|p| p.into_inner());
        list.push((id.clone(), Arc::new(organ)));
        if list.len() > crate::state::KEPT {
            list.remove(0);
        }
        id
    }

    /// The organ of `id`: a shipped one or an upload.
    ///
    /// # Errors
    /// A [`Fault::NotFound`] refusal for an unknown id (an upload dropped since); a scene
    /// error's for a shipped organ that cannot be built (not expected).
    pub fn get(&self, id: &str) -> Result<Arc<Organ>, Refusal> {
        if let Some(s) = ShippedOrgan::from_id(id) {
            return Ok(Arc::new(Organ::shipped(s)?));
        }
        self.uploads
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter()
            .find(|(i, _)| i == id)
            .map(|(_, o)| Arc::clone(o))
            .ok_or_else(|| {
                Refusal::new(
                    Fault::NotFound,
                    format!("no organ {id:?}: pick a shipped one or upload it again"),
                )
            })
    }
}

/// The JSON text of a message (the messages' types always serialize; were one not to, the page
/// is told the server failed).
fn text_of(m: &TrainerMessage) -> Message {
    let json = serde_json::to_string(m).unwrap_or_else(|_| {
        r#"{"type":"failed","error":{"kind":"run","field":null,"message":"the server could not write a message"}}"#
            .to_owned()
    });
    Message::Text(json.into())
}

/// Serves one tab's trainer socket: one session at a time on the server.
pub async fn serve_socket(studio: Studio, mut socket: WebSocket) {
    let organs = studio.organs();
    let send_timeout = studio.limits().send_timeout;
    if organs.busy.swap(true, Ordering::AcqRel) {
        let refused = TrainerMessage::Refused {
            error: error_body(
                Fault::Busy,
                "a trainer session runs in another tab on this server: close it first (one \
                 session runs at a time, so that it keeps its 60 steps per second)",
            ),
        };
        let _ = send_within(&mut socket, text_of(&refused), send_timeout).await;
        return;
    }
    let (commands, command_rx) = std::sync::mpsc::sync_channel::<Command>(COMMAND_QUEUE);
    let (frames_tx, frames) = watch::channel::<Option<Arc<Frame>>>(None);
    let (stats_tx, stats) = watch::channel(Stats::default());
    let (texts_tx, texts) = mpsc::unbounded_channel::<TrainerMessage>();
    let stop = Arc::new(AtomicBool::new(false));
    let thread = {
        let stop = Arc::clone(&stop);
        let organs = Arc::clone(&organs);
        std::thread::Builder::new()
            .name("studio-trainer".to_owned())
            .spawn(move || {
                let out = Outlets {
                    frames: frames_tx,
                    stats: stats_tx,
                    texts: texts_tx,
                };
                simulate(&organs, &command_rx, &out, &stop)
            })
    };
    if thread.is_ok() {
        let mut relay = Relay::new(socket, send_timeout);
        relay.run(&studio, &commands, frames, &stats, texts).await;
    }
    stop.store(true, Ordering::Relaxed);
    drop(commands);
    if let Ok(handle) = thread {
        let _ = tokio::task::spawn_blocking(move || handle.join()).await;
    }
    organs.busy.store(false, Ordering::Release);
}

/// The socket's side of a session: what it sent, and its frame rate.
struct Relay {
    socket: WebSocket,
    send_timeout: Duration,
    /// The surface version of the last index buffer sent (0: none yet for this organ).
    sent_version: u64,
    frames_sent: u64,
    /// Since when, and from which count, the frame rate is measured.
    window: (Instant, u64),
    frames_per_s: f64,
}

impl Relay {
    fn new(socket: WebSocket, send_timeout: Duration) -> Relay {
        Relay {
            socket,
            send_timeout,
            sent_version: 0,
            frames_sent: 0,
            window: (Instant::now(), 0),
            frames_per_s: 0.0,
        }
    }

    /// Relays until the tab closes, a send times out, the thread ends or the studio shuts
    /// down: the page's commands in, frames, messages and stats out.
    async fn run(
        &mut self,
        studio: &Studio,
        commands: &std::sync::mpsc::SyncSender<Command>,
        mut frames: watch::Receiver<Option<Arc<Frame>>>,
        stats: &watch::Receiver<Stats>,
        mut texts: mpsc::UnboundedReceiver<TrainerMessage>,
    ) {
        let mut shutdown = studio.on_shutdown();
        let mut ticker = tokio::time::interval(STATS_EVERY);
        loop {
            let go_on = tokio::select! {
                incoming = self.socket.recv() => match incoming {
                    Some(Ok(Message::Text(t))) => self.command(&t, commands).await,
                    Some(Ok(Message::Close(_)) | Err(_)) | None => false,
                    Some(Ok(_)) => true,
                },
                changed = frames.changed() => {
                    let frame = frames.borrow_and_update().clone();
                    changed.is_ok() && self.frame(frame).await
                }
                Some(m) = texts.recv() => self.message(&m).await,
                _ = ticker.tick() => {
                    let now = stats.borrow().clone();
                    self.stats(now).await
                }
                _ = shutdown.changed() => false,
            };
            if !go_on {
                break;
            }
        }
    }

    async fn send(&mut self, m: &TrainerMessage) -> bool {
        send_within(&mut self.socket, text_of(m), self.send_timeout).await
    }

    /// A command from the page: queued for the simulation thread, or refused (unknown, or too
    /// many waiting). False when the thread has gone or the refusal cannot be sent.
    async fn command(
        &mut self,
        text: &str,
        commands: &std::sync::mpsc::SyncSender<Command>,
    ) -> bool {
        use std::sync::mpsc::TrySendError;
        let refusal = match serde_json::from_str::<Command>(text) {
            Ok(c) => match commands.try_send(c) {
                Ok(()) => return true,
                Err(TrySendError::Full(_)) => error_body(
                    Fault::Busy,
                    format!(
                        "more than {COMMAND_QUEUE} commands are waiting for the simulation: \
                         this one was dropped"
                    ),
                ),
                Err(TrySendError::Disconnected(_)) => return false,
            },
            Err(e) => error_body(
                Fault::Usage,
                format!("the page sent a message the server does not know: {e}"),
            ),
        };
        self.send(&TrainerMessage::Refused { error: refusal }).await
    }

    /// The newest frame, with the index buffer when the surface changed since the last sent.
    async fn frame(&mut self, frame: Option<Arc<Frame>>) -> bool {
        let Some(frame) = frame else {
            return true;
        };
        let with_indices = frame.surface.0 != self.sent_version;
        let bytes = frame.encode(with_indices);
        if !send_within(
            &mut self.socket,
            Message::Binary(bytes.into()),
            self.send_timeout,
        )
        .await
        {
            return false;
        }
        self.sent_version = frame.surface.0;
        self.frames_sent += 1;
        true
    }

    /// A message of the simulation thread.
    async fn message(&mut self, m: &TrainerMessage) -> bool {
        if matches!(m, TrainerMessage::Scene(_)) {
            // A new organ: its first frame carries the index buffer.
            self.sent_version = 0;
        }
        self.send(m).await
    }

    /// The stats, with the frame rate measured here.
    async fn stats(&mut self, stats: Stats) -> bool {
        let elapsed = self.window.0.elapsed().as_secs_f64();
        if elapsed >= 1.0 {
            self.frames_per_s = (self.frames_sent - self.window.1) as f64 / elapsed;
            self.window = (Instant::now(), self.frames_sent);
        }
        let m = TrainerMessage::Stats(Stats {
            frames_per_s: self.frames_per_s,
            ..stats
        });
        self.send(&m).await
    }
}

/// Where the simulation thread publishes: the newest frame, the newest stats, and its messages
/// in order.
struct Outlets {
    frames: watch::Sender<Option<Arc<Frame>>>,
    stats: watch::Sender<Stats>,
    texts: mpsc::UnboundedSender<TrainerMessage>,
}

impl Outlets {
    fn send(&self, m: TrainerMessage) {
        // The socket task has gone: the thread is about to be stopped.
        let _ = self.texts.send(m);
    }

    fn event(&self, e: &TrainerEvent) {
        self.send(TrainerMessage::Event { event: e.clone() });
    }

    fn fail(&self, r: Refusal) {
        self.send(TrainerMessage::Failed { error: r.body() });
    }
}

/// The simulation thread: applies commands, steps at [`STEPS_PER_SECOND`], publishes frames.
fn simulate(
    organs: &Organs,
    commands: &std::sync::mpsc::Receiver<Command>,
    out: &Outlets,
    stop: &AtomicBool,
) {
    let _span = tracing::info_span!("studio_trainer").entered();
    let period = Duration::from_secs_f64(1.0 / STEPS_PER_SECOND);
    let mut sim = Simulation::default();
    let mut next = Instant::now();
    while !stop.load(Ordering::Relaxed) {
        loop {
            let command = match commands.try_recv() {
                Ok(c) => c,
                Err(std::sync::mpsc::TryRecvError::Empty) => break,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => return,
            };
            match sim.apply(command, organs, out) {
                // A new scene: its steps start now.
                Ok(true) => next = Instant::now(),
                Ok(false) => {}
                Err(r) => out.fail(r),
            }
        }
        sim.step_live(out);
        sim.publish(out);
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            // Behind (a slow step): do not try to catch up with a burst.
            next = now;
        }
    }
}

/// The simulation thread's state between steps.
#[derive(Default)]
struct Simulation {
    desk: Desk,
    paused: bool,
    /// One step asked for while paused.
    single: bool,
    /// Frames published.
    number: u32,
    /// The step rate: since when, steps since then, the last measured rate.
    rate: Option<(Instant, u64, f64)>,
}

impl Simulation {
    /// Applies one command of the page; whether it started a new scene.
    fn apply(&mut self, command: Command, organs: &Organs, out: &Outlets) -> Result<bool, Refusal> {
        let scene = match command {
            Command::Load { organ } => Some(self.desk.load(organs.get(&organ)?, &organ)?),
            Command::Reset => self.desk.reset()?,
            Command::Demo => {
                let (scene, started) = self.desk.demo()?;
                out.send(TrainerMessage::Scene(scene));
                out.event(&started);
                None
            }
            Command::Pause { paused } => {
                self.paused = paused;
                None
            }
            Command::Step => {
                self.single = true;
                None
            }
            Command::Material { material } => {
                let state = self.desk.set_material(material)?;
                out.send(TrainerMessage::Material(state));
                None
            }
            Command::SelfCollision { on } => {
                self.desk.set_self_collision(on)?;
                None
            }
            tool => {
                match self.desk.live.as_mut() {
                    Some(live) => live.apply(tool, out)?,
                    None => return Err(self.desk.not_live()),
                }
                None
            }
        };
        Ok(match scene {
            Some(scene) => {
                out.send(TrainerMessage::Scene(scene));
                true
            }
            None => false,
        })
    }

    /// One step of the live session, unless paused (one step when asked for while paused); a
    /// step that fails drops the session and tells the page to reset.
    fn step_live(&mut self, out: &Outlets) {
        let single = std::mem::take(&mut self.single);
        let Some(live) = &mut self.desk.live else {
            return;
        };
        if self.paused && !single {
            return;
        }
        match live.session.step() {
            Ok(events) => events.iter().for_each(|e| out.event(e)),
            Err(e) => {
                let kind = e.kind();
                out.fail(Refusal::new(
                    Fault::Scene(kind),
                    format!("the simulation failed: {e}; press Reset to start again"),
                ));
                self.desk.diverged();
                return;
            }
        }
        let rate = self.rate.get_or_insert((Instant::now(), 0, 0.0));
        rate.1 += 1;
    }

    /// The live session's newest frame and stats.
    fn publish(&mut self, out: &Outlets) {
        let Some(live) = &mut self.desk.live else {
            return;
        };
        let rate = self.rate.get_or_insert((Instant::now(), 0, 0.0));
        let elapsed = rate.0.elapsed().as_secs_f64();
        if elapsed >= 1.0 {
            *rate = (Instant::now(), 0, rate.1 as f64 / elapsed);
        }
        let steps_per_s = rate.2;
        self.number = self.number.wrapping_add(1);
        out.frames
            .send_replace(Some(Arc::new(live.frame(self.number))));
        let s = &live.session;
        let (median, p99) = s.step_ms();
        let (self_contacts, self_contacts_active) = s.self_contacts();
        out.stats.send_replace(Stats {
            steps: s.steps(),
            step_ms: StepTimes { median, p99 },
            steps_per_s,
            frames_per_s: 0.0,
            volume_drift: s.volume_drift(),
            nodes: s.body().node_count(),
            tets: s.body().tets().len(),
            paused: self.paused,
            force_n: f64::from(s.tool_force().length()),
            self_collision: s.options().self_collision.is_some(),
            self_contacts,
            self_contacts_active,
        });
    }
}

/// The organ loaded and its live session. The organ outlives a session that failed, so that
/// Reset (and the demonstration) rebuild it: the failure message tells the user to press Reset.
///
/// Self-collision: on until the page switches it off; a switch applies to the live session at
/// once and to every later one (another organ too).
///
/// The material: a `material` command waits in `pending` until the next reset, load or
/// demonstration, which makes it the chosen one; the chosen one stays for every later session
/// (another organ too) until another is chosen. Until the page chooses one, each organ starts
/// with its own ([`TissueMaterial::default_for`]).
#[derive(Default)]
struct Desk {
    /// The organ and its id, from the last `load`.
    loaded: Option<(Arc<Organ>, String)>,
    /// Its session; `None` before a load and after a failed step.
    live: Option<Live>,
    /// The material the page chose, applied (`None`: each organ's default).
    chosen: Option<TissueMaterial>,
    /// The material the page chose, for the next session.
    pending: Option<TissueMaterial>,
    /// Self-collision switched on or off by the page (`None`: tissue-scenes' default, on).
    self_collision_asked: Option<bool>,
}

impl Desk {
    /// Starts a session on `organ` (the pending material applied); the `scene` message.
    fn load(&mut self, organ: Arc<Organ>, id: &str) -> Result<SceneInfo, Refusal> {
        let material = self.next_material(id);
        let live = Live::new(&organ, id, material, self.self_collision())?;
        let scene = live.scene();
        self.loaded = Some((organ, id.to_owned()));
        self.live = Some(live);
        Ok(scene)
    }

    /// The material of the next session on organ `id`: the pending one becomes the chosen one.
    fn next_material(&mut self, id: &str) -> TissueMaterial {
        if let Some(m) = self.pending.take() {
            self.chosen = Some(m);
        }
        self.chosen
            .unwrap_or_else(|| TissueMaterial::default_for(ShippedOrgan::from_id(id)))
    }

    /// Keeps `material` for the next session once it is checked; the `material` message.
    fn set_material(&mut self, material: TissueMaterial) -> Result<MaterialState, Refusal> {
        material.options()?;
        let in_force = self.live.as_ref().map(|l| l.material);
        self.pending = (in_force != Some(material)).then_some(material);
        Ok(MaterialState {
            in_force,
            pending: self.pending,
        })
    }

    /// The self-collision of the sessions: [`SelfCollision::default`] once switched on, none
    /// once switched off, else tissue-scenes' default (on).
    fn self_collision(&self) -> Option<SelfCollision> {
        match self.self_collision_asked {
            Some(true) => Some(SelfCollision::default()),
            Some(false) => None,
            None => SessionOptions::default().self_collision,
        }
    }

    /// Switches self-collision on or off: the live session at once, the later ones too.
    fn set_self_collision(&mut self, on: bool) -> Result<(), Refusal> {
        self.self_collision_asked = Some(on);
        let settings = self.self_collision();
        if let Some(live) = self.live.as_mut() {
            live.session.set_self_collision(settings)?;
        }
        Ok(())
    }

    /// The loaded organ's session afresh (also after a failure); nothing before a load.
    fn reset(&mut self) -> Result<Option<SceneInfo>, Refusal> {
        match self.loaded.clone() {
            Some((organ, id)) => self.load(organ, &id).map(Some),
            None => Ok(None),
        }
    }

    /// The loaded organ afresh with its demonstration playing: the `scene` message and the
    /// demonstration's first event.
    fn demo(&mut self) -> Result<(SceneInfo, TrainerEvent), Refusal> {
        let Some((organ, id)) = self.loaded.clone() else {
            return Err(self.not_live());
        };
        let material = self.next_material(&id);
        let mut fresh = Live::new(&organ, &id, material, self.self_collision())?;
        let started = fresh.session.play()?;
        let scene = fresh.scene();
        self.live = Some(fresh);
        Ok((scene, started))
    }

    /// A step failed: the session is dropped, the organ kept for Reset.
    fn diverged(&mut self) {
        self.live = None;
    }

    /// Why a tool cannot act now.
    fn not_live(&self) -> Refusal {
        if self.loaded.is_some() {
            Refusal::new(
                Fault::Scene(SceneErrorKind::Simulation),
                "the simulation stopped after a failure: press Reset to start again",
            )
        } else {
            Refusal::new(Fault::Usage, "load an organ first")
        }
    }
}

/// A live session and what the frames need.
struct Live {
    id: String,
    session: Session,
    surface: Arc<(u64, Vec<u32>)>,
    /// The material it was built with.
    material: TissueMaterial,
    /// The organ's top as loaded (cm).
    top: f32,
}

impl Live {
    fn new(
        organ: &Organ,
        id: &str,
        material: TissueMaterial,
        self_collision: Option<SelfCollision>,
    ) -> Result<Live, Refusal> {
        let options = SessionOptions {
            self_collision,
            ..material.options()?
        };
        let session = Session::new(organ, options)?;
        let top = session
            .positions()
            .iter()
            .map(|p| p.y)
            .fold(f32::NEG_INFINITY, f32::max);
        Ok(Live {
            id: id.to_owned(),
            surface: Arc::new((0, Vec::new())),
            session,
            material,
            top,
        })
    }

    /// The `scene` message: what the page allocates for.
    fn scene(&self) -> SceneInfo {
        let s = &self.session;
        let (vertices, triangles) = s.capacity();
        SceneInfo {
            organ: self.id.clone(),
            label: s.label().to_owned(),
            nodes: s.body().node_count(),
            tets: s.body().tets().len(),
            capacity: Capacity {
                vertices,
                triangles,
            },
            tray: TrayInfo {
                size: [s.tray_side(), s.tray_side()],
                top: 0.0,
            },
            top: self.top,
            material: self.material,
            self_collision: s.options().self_collision.is_some(),
        }
    }

    /// A trainee's tool command (grab, drag, release, cut, suture); its events go out.
    fn apply(&mut self, command: Command, out: &Outlets) -> Result<(), SceneError> {
        let v = |p: [f32; 3]| Vec3::from_array(p);
        let s = &mut self.session;
        match command {
            Command::Grab { point, triangle } => out.event(&s.grab(v(point), triangle)?),
            Command::Drag { target } => s.drag(v(target)),
            Command::Release => s.release()?.iter().for_each(|e| out.event(e)),
            Command::Cut { path, view_dir } => {
                let path: Vec<Vec3> = path.into_iter().map(v).collect();
                s.cut(&path, v(view_dir))?;
            }
            Command::Suture { a, b } => out.event(&s.suture(v(a), v(b))?),
            Command::Load { .. }
            | Command::Reset
            | Command::Demo
            | Command::Pause { .. }
            | Command::Step
            | Command::Material { .. }
            | Command::SelfCollision { .. } => {}
        }
        Ok(())
    }

    fn frame(&mut self, number: u32) -> Frame {
        let s = &self.session;
        if self.surface.0 != s.surface_version() {
            self.surface = Arc::new((
                s.surface_version(),
                s.surface().iter().flatten().copied().collect(),
            ));
        }
        let tip = s.tool_tip().map_or([f32::NAN; 3], |t| t.to_array());
        Frame {
            number,
            step: s.steps() as u32,
            positions: s.positions().iter().flat_map(|p| p.to_array()).collect(),
            force: s.tool_force().to_array(),
            tip,
            surface: Arc::clone(&self.surface),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probe's "Reset does nothing after a divergence": the failed session is dropped, and
    /// Reset rebuilds it from the organ it was loaded with, at step 0.
    #[test]
    fn reset_rebuilds_a_session_that_failed() {
        let organ = Arc::new(Organ::shipped(ShippedOrgan::Appendix).unwrap());
        let mut desk = Desk::default();
        assert_eq!(
            desk.reset().unwrap(),
            None,
            "nothing to reset before a load"
        );
        assert_eq!(
            desk.not_live(),
            Refusal::new(Fault::Usage, "load an organ first")
        );
        desk.load(Arc::clone(&organ), "appendix").unwrap();
        for _ in 0..3 {
            desk.live.as_mut().unwrap().session.step().unwrap();
        }
        desk.diverged();
        assert!(desk.live.is_none());
        assert!(desk.not_live().message.contains("press Reset"));
        let scene = desk.reset().unwrap().expect("a scene after Reset");
        assert_eq!(scene.organ, "appendix");
        let live = desk.live.as_mut().expect("a live session after Reset");
        assert_eq!(live.session.steps(), 0);
        live.session.step().unwrap();
        assert_eq!(live.session.steps(), 1);
        // The demonstration too starts again from the kept organ.
        desk.diverged();
        assert!(desk.demo().is_ok());
        assert!(desk.live.is_some());
    }

    /// The self-collision command: on by default (tissue-scenes' default, and the scene message
    /// says so, for the page's checkbox); switched off and on again at once on the live session
    /// (its stats say so) and kept for the next sessions (a reset, a demonstration).
    #[test]
    fn self_collision_is_on_by_default_and_switched_live() {
        let organs = Organs::default();
        let (frames, _f) = watch::channel(None);
        let (stats, stats_rx) = watch::channel(Stats::default());
        let (texts, mut received) = mpsc::unbounded_channel();
        let out = Outlets {
            frames,
            stats,
            texts,
        };
        let mut scene_says = || {
            let mut said = None;
            while let Ok(m) = received.try_recv() {
                if let TrainerMessage::Scene(scene) = m {
                    said = Some(scene.self_collision);
                }
            }
            said
        };
        let mut sim = Simulation::default();
        let load = Command::Load {
            organ: "appendix".to_owned(),
        };
        assert!(sim.apply(load, &organs, &out).unwrap());
        let on = |sim: &Simulation| {
            let live = sim.desk.live.as_ref().expect("a live session");
            (
                live.session.options().self_collision.is_some(),
                live.session.body().self_collision().is_some(),
            )
        };
        assert_eq!(on(&sim), (true, true), "on by default");
        assert_eq!(scene_says(), Some(true), "the scene says it is on");
        sim.step_live(&out);
        sim.publish(&out);
        assert!(stats_rx.borrow().self_collision);
        let off = Command::SelfCollision { on: false };
        assert!(!sim.apply(off, &organs, &out).unwrap());
        assert_eq!(on(&sim), (false, false), "switched off on the live session");
        sim.step_live(&out);
        sim.publish(&out);
        let s = stats_rx.borrow().clone();
        assert!(!s.self_collision);
        assert_eq!((s.self_contacts, s.self_contacts_active), (0, 0));
        // Kept through a reset and a demonstration.
        sim.apply(Command::Reset, &organs, &out).unwrap();
        assert_eq!(on(&sim), (false, false), "kept off by Reset");
        assert_eq!(scene_says(), Some(false), "the scene says it is off");
        sim.apply(Command::Demo, &organs, &out).unwrap();
        assert_eq!(on(&sim), (false, false), "kept off by the demonstration");
        sim.apply(Command::SelfCollision { on: true }, &organs, &out)
            .unwrap();
        assert_eq!(
            on(&sim),
            (true, true),
            "switched on again on the live session"
        );
        sim.step_live(&out);
        sim.publish(&out);
        assert!(stats_rx.borrow().self_collision);
        sim.apply(Command::Reset, &organs, &out).unwrap();
        assert_eq!(on(&sim), (true, true), "kept on by Reset");
        assert_eq!(scene_says(), Some(true));
        let json = r#"{"type": "self_collision", "on": false}"#;
        let c: Command = serde_json::from_str(json).unwrap();
        assert_eq!(c, Command::SelfCollision { on: false });
    }

    /// The material command: checked at once (out of range refused naming the field, nothing
    /// kept), kept pending until the next reset, then in force there and in the scene message,
    /// and kept for the resets after; a load applies a pending one too.
    #[test]
    fn a_material_waits_for_the_next_reset() {
        let organs = Organs::default();
        let (frames, _f) = watch::channel(None);
        let (stats, _s) = watch::channel(Stats::default());
        let (texts, mut received) = mpsc::unbounded_channel();
        let out = Outlets {
            frames,
            stats,
            texts,
        };
        let mut sim = Simulation::default();
        let mut last = || {
            let mut m = None;
            while let Ok(x) = received.try_recv() {
                m = Some(x);
            }
            m
        };
        let stiff = TissueMaterial::Material {
            young_kpa: 20.0,
            poisson: 0.45,
            density: 1.05,
        };
        let material = |m| Command::Material { material: m };
        // Before a load: kept, nothing in force.
        sim.apply(material(stiff), &organs, &out).unwrap();
        let expected = MaterialState {
            in_force: None,
            pending: Some(stiff),
        };
        assert_eq!(last(), Some(TrainerMessage::Material(expected)));
        // The load applies it.
        let load = Command::Load {
            organ: "appendix".to_owned(),
        };
        assert!(sim.apply(load, &organs, &out).unwrap());
        let Some(TrainerMessage::Scene(scene)) = last() else {
            panic!("a scene after the load")
        };
        assert_eq!(scene.material, stiff);
        assert!(
            scene.top > 1.0,
            "the appendix's top as loaded: {}",
            scene.top
        );
        // Out of range: refused naming the field; what waits and what is in force stay.
        let soft = TissueMaterial::Material {
            young_kpa: 10.0,
            poisson: 0.45,
            density: 1.05,
        };
        sim.apply(material(soft), &organs, &out).unwrap();
        for (bad, field) in [
            (
                TissueMaterial::Material {
                    young_kpa: 10.0,
                    poisson: 0.5,
                    density: 1.05,
                },
                "poisson",
            ),
            (
                TissueMaterial::Material {
                    young_kpa: 1e6,
                    poisson: 0.45,
                    density: 1.05,
                },
                "young_kpa",
            ),
        ] {
            let refusal = sim.apply(material(bad), &organs, &out).unwrap_err();
            assert_eq!(refusal.field, Some(field), "{}", refusal.message);
            let body = refusal.body();
            assert_eq!(body.kind, ErrorKind::Parameters);
            assert_eq!(body.field.as_deref(), Some(field));
        }
        assert_eq!(sim.desk.pending, Some(soft));
        let live = sim.desk.live.as_ref().unwrap();
        assert_eq!(
            live.material, stiff,
            "applied on the next reset, not before"
        );
        // Reset applies it; the next reset keeps it.
        for _ in 0..2 {
            assert!(sim.apply(Command::Reset, &organs, &out).unwrap());
            let Some(TrainerMessage::Scene(scene)) = last() else {
                panic!("a scene after Reset")
            };
            assert_eq!(scene.material, soft);
            assert_eq!(sim.desk.pending, None);
        }
        // The realtime scheme, and the one in force asked for again: nothing waits then.
        sim.apply(material(TissueMaterial::Realtime {}), &organs, &out)
            .unwrap();
        sim.apply(material(soft), &organs, &out).unwrap();
        let expected = MaterialState {
            in_force: Some(soft),
            pending: None,
        };
        assert_eq!(last(), Some(TrainerMessage::Material(expected)));
        sim.apply(material(TissueMaterial::Realtime {}), &organs, &out)
            .unwrap();
        assert!(sim.apply(Command::Reset, &organs, &out).unwrap());
        let live = sim.desk.live.as_mut().unwrap();
        assert_eq!(live.material, TissueMaterial::Realtime {});
        live.session.step().unwrap();
        // The JSON of the command, and an unknown member refused.
        let c: Command = serde_json::from_str(
            r#"{"type": "material", "material": {"scheme": "material", "young_kpa": 20,
                "poisson": 0.45, "density": 1.05}}"#,
        )
        .unwrap();
        assert_eq!(c, material(stiff));
        let unknown = r#"{"type": "material", "material": {"scheme": "realtime", "e": 1}}"#;
        assert!(serde_json::from_str::<Command>(unknown).is_err());
    }

    /// The kinds the page reads: "load an organ first" is a usage error, an unknown organ is not
    /// found, a tool the session refuses is a usage error, a failed step a run error.
    #[test]
    fn trainer_errors_have_their_own_kinds() {
        // As the page reads them: the JSON name of the kind.
        let name = |b: ErrorBody| serde_json::to_value(b.kind).unwrap_or_default();
        let kind = |f: Fault| name(error_body(f, ""));
        assert_eq!(name(Desk::default().not_live().body()), "usage");
        let unknown = Organs::default().get("u-gone").err().map(Refusal::body);
        assert_eq!(unknown.map(name), Some("not_found".into()));
        assert_eq!(kind(Fault::Busy), "busy");
        assert_eq!(kind(Fault::Scene(SceneErrorKind::Tool)), "usage");
        assert_eq!(kind(Fault::Scene(SceneErrorKind::Simulation)), "run");
        assert_eq!(kind(Fault::Scene(SceneErrorKind::TooLarge)), "too_large");
        assert_eq!(kind(Fault::Scene(SceneErrorKind::Meshing)), "mesh");
    }

    /// The messages keep the shapes the page reads (`API.md`).
    #[test]
    fn messages_are_tagged_by_type() {
        let m: TrainerMessage = TrainerMessage::Refused {
            error: error_body(Fault::Busy, "wait"),
        };
        let v: serde_json::Value = serde_json::to_value(&m).unwrap();
        assert_eq!(
            v,
            serde_json::json!({ "type": "refused",
                "error": { "kind": "busy", "field": null, "message": "wait" } })
        );
        let c: Command = serde_json::from_str(r#"{"type": "pause", "paused": true}"#).unwrap();
        assert_eq!(c, Command::Pause { paused: true });
        assert!(
            serde_json::from_str::<Command>(r#"{"type": "tool", "tool": "probe"}"#).is_err(),
            "the tool message is gone"
        );
    }
}
