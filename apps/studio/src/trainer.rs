//! The trainer's server side: shipped organs and uploads, and one live session at a time — a
//! native simulation thread stepping at a fixed rate, publishing only its newest surface frame,
//! which the socket task sends as a binary WebSocket frame (see `API.md`).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use axum::extract::ws::{Message, WebSocket};
use glam::Vec3;
use serde::Deserialize;
use serde_json::{json, Value};
use tissue_scenes::{Organ, Session, SessionOptions, ShippedOrgan, TrainerEvent};
use tokio::sync::{mpsc, watch};

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

/// What the simulation thread reports besides frames.
#[derive(Debug, Clone, Default)]
pub struct Stats {
    /// Steps taken.
    pub steps: u64,
    /// Median and p99 step time, ms.
    pub step_ms: (f64, f64),
    /// Steps per second, measured over the last second.
    pub steps_per_s: f64,
    /// `V/V₀ − 1`.
    pub volume_drift: f64,
    /// Nodes, tets.
    pub nodes: usize,
    /// Tets.
    pub tets: usize,
    /// Paused.
    pub paused: bool,
    /// |force| on the probe, N.
    pub force_n: f64,
}

/// A command from the page to the simulation thread.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Command {
    /// Start (or restart) with an organ.
    Load {
        /// A shipped organ's id or an upload's.
        organ: String,
    },
    /// The active tool (for the record; the actions say what they are).
    Tool {
        /// `probe`, `scalpel`, `needle`.
        tool: String,
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
    pub fn get(&self, id: &str) -> Result<Arc<Organ>, String> {
        if let Some(s) = ShippedOrgan::from_id(id) {
            return Organ::shipped(s).map(Arc::new).map_err(|e| e.to_string());
        }
        self.uploads
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter()
            .find(|(i, _)| i == id)
            .map(|(_, o)| Arc::clone(o))
            .ok_or_else(|| format!("no organ {id:?}: pick a shipped one or upload it again"))
    }
}

fn error_json(kind: &str, message: impl Into<String>) -> Value {
    json!({ "kind": kind, "field": null, "message": message.into() })
}

/// Serves one tab's trainer socket: one session at a time on the server.
pub async fn serve_socket(studio: Studio, mut socket: WebSocket) {
    let organs = studio.organs();
    let send_timeout = studio.limits().send_timeout;
    if organs.busy.swap(true, Ordering::AcqRel) {
        let refused = json!({ "type": "refused", "error": error_json(
            "busy",
            "a trainer session runs in another tab on this server: close it first (one session \
             runs at a time, so that it keeps its 60 steps per second)") });
        let _ = send_within(
            &mut socket,
            Message::Text(refused.to_string().into()),
            send_timeout,
        )
        .await;
        return;
    }
    let (commands, command_rx) = std::sync::mpsc::sync_channel::<Command>(COMMAND_QUEUE);
    let (frames_tx, mut frames) = watch::channel::<Option<Arc<Frame>>>(None);
    let (stats_tx, stats) = watch::channel(Stats::default());
    let (texts_tx, mut texts) = mpsc::unbounded_channel::<Value>();
    let stop = Arc::new(AtomicBool::new(false));
    let thread = {
        let stop = Arc::clone(&stop);
        let organs = Arc::clone(&organs);
        std::thread::Builder::new()
            .name("studio-trainer".to_owned())
            .spawn(move || {
                simulate(
                    &organs,
                    &command_rx,
                    &frames_tx,
                    &stats_tx,
                    &texts_tx,
                    &stop,
                )
            })
    };
    let mut shutdown = studio.on_shutdown();
    let mut sent_version = 0u64;
    let mut frames_sent = 0u64;
    let mut window = (Instant::now(), 0u64);
    let mut frames_per_s = 0.0;
    let mut ticker = tokio::time::interval(STATS_EVERY);
    if thread.is_ok() {
        loop {
            tokio::select! {
                incoming = socket.recv() => {
                    let text = match incoming {
                        Some(Ok(Message::Text(t))) => t.to_string(),
                        Some(Ok(Message::Close(_)) | Err(_)) | None => break,
                        Some(Ok(_)) => continue,
                    };
                    let refusal = match serde_json::from_str::<Command>(&text) {
                        Ok(c) => match commands.try_send(c) {
                            Ok(()) => None,
                            Err(std::sync::mpsc::TrySendError::Full(_)) => Some(error_json(
                                "busy",
                                format!("more than {COMMAND_QUEUE} commands are waiting for the \
                                         simulation: this one was dropped"),
                            )),
                            Err(std::sync::mpsc::TrySendError::Disconnected(_)) => break,
                        },
                        Err(e) => Some(error_json(
                            "usage", format!("the page sent a message the server does not know: {e}"))),
                    };
                    if let Some(error) = refusal {
                        let m = json!({ "type": "refused", "error": error });
                        if !send_within(&mut socket, Message::Text(m.to_string().into()), send_timeout).await {
                            break;
                        }
                    }
                }
                changed = frames.changed() => {
                    if changed.is_err() {
                        break;
                    }
                    let frame = frames.borrow_and_update().clone();
                    if let Some(frame) = frame {
                        let with_indices = frame.surface.0 != sent_version;
                        let bytes = frame.encode(with_indices);
                        if !send_within(&mut socket, Message::Binary(bytes.into()), send_timeout).await {
                            break;
                        }
                        sent_version = frame.surface.0;
                        frames_sent += 1;
                    }
                }
                Some(text) = texts.recv() => {
                    if text["type"] == "scene" {
                        // A new organ: its first frame carries the index buffer.
                        sent_version = 0;
                    }
                    if !send_within(&mut socket, Message::Text(text.to_string().into()), send_timeout).await {
                        break;
                    }
                }
                _ = ticker.tick() => {
                    let elapsed = window.0.elapsed().as_secs_f64();
                    if elapsed >= 1.0 {
                        frames_per_s = (frames_sent - window.1) as f64 / elapsed;
                        window = (Instant::now(), frames_sent);
                    }
                    let s = stats.borrow().clone();
                    let m = json!({
                        "type": "stats", "steps": s.steps,
                        "step_ms": { "median": s.step_ms.0, "p99": s.step_ms.1 },
                        "steps_per_s": s.steps_per_s, "frames_per_s": frames_per_s,
                        "volume_drift": s.volume_drift, "nodes": s.nodes, "tets": s.tets,
                        "paused": s.paused, "force_n": s.force_n,
                    });
                    if !send_within(&mut socket, Message::Text(m.to_string().into()), send_timeout).await {
                        break;
                    }
                }
                _ = shutdown.changed() => break,
            }
        }
    }
    stop.store(true, Ordering::Relaxed);
    drop(commands);
    if let Ok(handle) = thread {
        let _ = tokio::task::spawn_blocking(move || handle.join()).await;
    }
    organs.busy.store(false, Ordering::Release);
}

/// The simulation thread: applies commands, steps at [`STEPS_PER_SECOND`], publishes frames.
fn simulate(
    organs: &Organs,
    commands: &std::sync::mpsc::Receiver<Command>,
    frames: &watch::Sender<Option<Arc<Frame>>>,
    stats: &watch::Sender<Stats>,
    texts: &mpsc::UnboundedSender<Value>,
    stop: &AtomicBool,
) {
    let _span = tracing::info_span!("studio_trainer").entered();
    let period = Duration::from_secs_f64(1.0 / STEPS_PER_SECOND);
    let mut desk = Desk::default();
    let mut paused = false;
    let mut number = 0u32;
    let mut next = Instant::now();
    let mut rate = (Instant::now(), 0u64, 0.0f64);
    let event = |e: &TrainerEvent| {
        let _ = texts.send(json!({ "type": "event", "event": {
            "kind": e.kind, "step": e.step, "text": e.text } }));
    };
    let fail = |kind: &str, message: String| {
        let _ = texts.send(json!({ "type": "failed", "error": error_json(kind, message) }));
    };
    while !stop.load(Ordering::Relaxed) {
        let mut single = false;
        loop {
            let command = match commands.try_recv() {
                Ok(c) => c,
                Err(std::sync::mpsc::TryRecvError::Empty) => break,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => return,
            };
            let result = match command {
                Command::Load { organ } => organs.get(&organ).and_then(|o| desk.load(o, &organ)),
                Command::Reset => desk.reset(),
                Command::Demo => desk.demo().map(|(scene, started)| {
                    let _ = texts.send(scene);
                    event(&started);
                    None
                }),
                Command::Pause { paused: p } => {
                    paused = p;
                    Ok(None)
                }
                Command::Step => {
                    single = true;
                    Ok(None)
                }
                Command::Tool { .. } => Ok(None),
                other => match &mut desk.live {
                    Some(l) => l.apply(other, &event).map(|()| None),
                    None => Err(desk.not_live()),
                },
            };
            match result {
                Ok(Some(scene)) => {
                    let _ = texts.send(scene);
                    next = Instant::now();
                }
                Ok(None) => {}
                Err(message) => fail("run", message),
            }
        }
        if let Some(l) = &mut desk.live {
            if !paused || single {
                match l.session.step() {
                    Ok(events) => events.iter().for_each(event),
                    Err(e) => {
                        fail(
                            "run",
                            format!("the simulation failed: {e}; press Reset to start again"),
                        );
                        desk.diverged();
                        continue;
                    }
                }
                rate.1 += 1;
            }
            let elapsed = rate.0.elapsed().as_secs_f64();
            if elapsed >= 1.0 {
                rate = (Instant::now(), 0, rate.1 as f64 / elapsed);
            }
            number = number.wrapping_add(1);
            frames.send_replace(Some(Arc::new(l.frame(number))));
            let s = &l.session;
            let (median, p99) = s.step_ms();
            let force = s.tool_force();
            stats.send_replace(Stats {
                steps: s.steps(),
                step_ms: (median, p99),
                steps_per_s: rate.2,
                volume_drift: s.volume_drift(),
                nodes: s.body().node_count(),
                tets: s.body().tets().len(),
                paused,
                force_n: f64::from(force.length()),
            });
        }
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

/// The organ loaded and its live session. The organ outlives a session that failed, so that
/// Reset (and the demonstration) rebuild it: the failure message tells the user to press Reset.
#[derive(Default)]
struct Desk {
    /// The organ and its id, from the last `load`.
    loaded: Option<(Arc<Organ>, String)>,
    /// Its session; `None` before a load and after a failed step.
    live: Option<Live>,
}

impl Desk {
    /// Starts a session on `organ`; the `scene` message.
    fn load(&mut self, organ: Arc<Organ>, id: &str) -> Result<Option<Value>, String> {
        let live = Live::new(&organ, id)?;
        let scene = live.scene_message();
        self.loaded = Some((organ, id.to_owned()));
        self.live = Some(live);
        Ok(Some(scene))
    }

    /// The loaded organ's session afresh (also after a failure); nothing before a load.
    fn reset(&mut self) -> Result<Option<Value>, String> {
        match self.loaded.clone() {
            Some((organ, id)) => self.load(organ, &id),
            None => Ok(None),
        }
    }

    /// The loaded organ afresh with its demonstration playing: the `scene` message and the
    /// demonstration's first event.
    fn demo(&mut self) -> Result<(Value, TrainerEvent), String> {
        let Some((organ, id)) = self.loaded.clone() else {
            return Err(self.not_live());
        };
        let mut fresh = Live::new(&organ, &id)?;
        let started = fresh.session.play().map_err(|e| e.to_string())?;
        let scene = fresh.scene_message();
        self.live = Some(fresh);
        Ok((scene, started))
    }

    /// A step failed: the session is dropped, the organ kept for Reset.
    fn diverged(&mut self) {
        self.live = None;
    }

    /// Why a tool cannot act now.
    fn not_live(&self) -> String {
        if self.loaded.is_some() {
            "the simulation stopped after a failure: press Reset to start again".to_owned()
        } else {
            "load an organ first".to_owned()
        }
    }
}

/// A live session and what the frames need.
struct Live {
    id: String,
    session: Session,
    surface: Arc<(u64, Vec<u32>)>,
}

impl Live {
    fn new(organ: &Organ, id: &str) -> Result<Live, String> {
        let session = Session::new(organ, SessionOptions::default()).map_err(|e| e.to_string())?;
        Ok(Live {
            id: id.to_owned(),
            surface: Arc::new((0, Vec::new())),
            session,
        })
    }

    /// The `scene` message: what the page allocates for.
    fn scene_message(&self) -> Value {
        let s = &self.session;
        let (vertices, triangles) = s.capacity();
        json!({
            "type": "scene", "organ": self.id, "label": s.label(),
            "nodes": s.body().node_count(), "tets": s.body().tets().len(),
            "capacity": { "vertices": vertices, "triangles": triangles },
            "tray": { "size": [s.tray_side(), s.tray_side()], "top": 0.0 },
        })
    }

    fn apply(&mut self, command: Command, event: &impl Fn(&TrainerEvent)) -> Result<(), String> {
        let v = |p: [f32; 3]| Vec3::from_array(p);
        let s = &mut self.session;
        let done = match command {
            Command::Grab { point, triangle } => s.grab(v(point), triangle).map(|e| event(&e)),
            Command::Drag { target } => {
                s.drag(v(target));
                Ok(())
            }
            Command::Release => s.release().map(|e| e.iter().for_each(event)),
            Command::Cut { path, view_dir } => {
                let path: Vec<Vec3> = path.into_iter().map(v).collect();
                s.cut(&path, v(view_dir)).map(|_| ())
            }
            Command::Suture { a, b } => s.suture(v(a), v(b)).map(|e| event(&e)),
            _ => Ok(()),
        };
        done.map_err(|e| e.to_string())
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
        assert_eq!(desk.not_live(), "load an organ first");
        desk.load(Arc::clone(&organ), "appendix").unwrap();
        for _ in 0..3 {
            desk.live.as_mut().unwrap().session.step().unwrap();
        }
        desk.diverged();
        assert!(desk.live.is_none());
        assert!(desk.not_live().contains("press Reset"));
        let scene = desk.reset().unwrap().expect("a scene after Reset");
        assert_eq!(scene["organ"], "appendix");
        let live = desk.live.as_mut().expect("a live session after Reset");
        assert_eq!(live.session.steps(), 0);
        live.session.step().unwrap();
        assert_eq!(live.session.steps(), 1);
        // The demonstration too starts again from the kept organ.
        desk.diverged();
        assert!(desk.demo().is_ok());
        assert!(desk.live.is_some());
    }
}
