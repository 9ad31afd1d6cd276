//! The trainer's socket without a browser: the appendix loads, frames stream in the documented
//! binary layout (the index buffer first and after a cut), a cut and a suture give their events,
//! a second tab is refused, and closing the tab frees the server; errors arrive with their
//! kinds. The messages are built and read with the studio's own types (`Command`,
//! `TrainerMessage`).

use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::Value;
use tissue_scenes::{TrainerEvent, TrainerEventKind};
use tissue_studio::trainer::{Command, SceneInfo, TrainerMessage};
use tokio_tungstenite::tungstenite::Message;

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;
type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

#[derive(Debug)]
struct Frame {
    flags: u32,
    step: u32,
    vertices: usize,
    triangles: usize,
    positions: Vec<f32>,
}

fn word(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]])
}

fn decode(b: &[u8]) -> Result<Frame> {
    assert_eq!(word(b, 0), tissue_studio::trainer::FRAME_MAGIC);
    let flags = word(b, 1);
    let (vertices, triangles) = (word(b, 4) as usize, word(b, 5) as usize);
    let expected = 48 + 12 * vertices + if flags & 1 == 1 { 12 * triangles } else { 0 };
    assert_eq!(b.len(), expected, "frame length");
    let positions = (0..3 * vertices)
        .map(|i| f32::from_bits(word(b, 12 + i)))
        .collect();
    Ok(Frame {
        flags,
        step: word(b, 3),
        vertices,
        triangles,
        positions,
    })
}

/// A message of the server as the tests read it: the studio's own type, its errors as JSON.
type Msg = TrainerMessage<Value>;

enum In {
    Text(Msg),
    Frame(Frame),
}

async fn next(socket: &mut Socket) -> Result<In> {
    loop {
        let m = tokio::time::timeout(Duration::from_secs(60), socket.next())
            .await?
            .ok_or("the socket closed")??;
        match m {
            Message::Text(t) => return Ok(In::Text(serde_json::from_str(&t)?)),
            Message::Binary(b) => return Ok(In::Frame(decode(&b)?)),
            _ => {}
        }
    }
}

/// The first message `pick` takes, within 60 s; a `failed` message it does not take is an
/// error.
async fn until<T>(socket: &mut Socket, what: &str, pick: impl Fn(&Msg) -> Option<T>) -> Result<T> {
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut seen = Vec::new();
    loop {
        assert!(
            Instant::now() < deadline,
            "no {what} within 60 s; events seen: {seen:?}"
        );
        if let In::Text(m) = next(socket).await? {
            if let Some(t) = pick(&m) {
                return Ok(t);
            }
            match m {
                Msg::Event { event } => seen.push(event.kind),
                Msg::Failed { error } => {
                    return Err(format!("waiting for {what}, the server failed: {error}").into())
                }
                _ => {}
            }
        }
    }
}

async fn scene(socket: &mut Socket) -> Result<SceneInfo> {
    until(socket, "a scene", |m| match m {
        Msg::Scene(s) => Some(s.clone()),
        _ => None,
    })
    .await
}

async fn event(socket: &mut Socket, kind: TrainerEventKind) -> Result<TrainerEvent> {
    until(socket, kind.name(), |m| match m {
        Msg::Event { event } if event.kind == kind => Some(event.clone()),
        _ => None,
    })
    .await
}

/// The error of the next `failed` message.
async fn failed(socket: &mut Socket) -> Result<Value> {
    until(socket, "a failure", |m| match m {
        Msg::Failed { error } => Some(error.clone()),
        _ => None,
    })
    .await
}

/// The error of the next `refused` message.
async fn refused(socket: &mut Socket) -> Result<Value> {
    until(socket, "a refusal", |m| match m {
        Msg::Refused { error } => Some(error.clone()),
        _ => None,
    })
    .await
}

async fn frame_with(socket: &mut Socket, indices: bool) -> Result<Frame> {
    loop {
        if let In::Frame(f) = next(socket).await? {
            if !indices || f.flags & 1 == 1 {
                return Ok(f);
            }
        }
    }
}

async fn send(socket: &mut Socket, command: &Command) -> Result {
    let text = serde_json::to_string(command)?;
    socket.send(Message::Text(text.into())).await?;
    Ok(())
}

fn load(organ: &str) -> Command {
    Command::Load {
        organ: organ.to_owned(),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_appendix_streams_is_cut_and_sutured_and_one_session_runs_at_a_time() -> Result {
    let (studio, addr, server) = crate::serve().await?;
    let url = format!("ws://{addr}/api/trainer/ws");
    let (mut tab, _) = tokio_tungstenite::connect_async(&url).await?;
    send(&mut tab, &load("appendix")).await?;
    let scene = scene(&mut tab).await?;
    let nodes = scene.nodes;
    assert_eq!(nodes, 33 * 9 * 9);
    assert!(scene.capacity.vertices > nodes);
    // Self-collision is on by default, and the scene says so (the page's checkbox starts so).
    assert!(scene.self_collision);

    // The first frame carries the index buffer; the next ones positions only, steps advancing.
    let first = frame_with(&mut tab, true).await?;
    assert_eq!(first.vertices, nodes);
    assert!(first.triangles > 0);
    let later = frame_with(&mut tab, false).await?;
    assert_eq!(later.flags & 1, 0);
    assert!(later.step > first.step);
    assert!(later.positions.iter().all(|p| p.is_finite()));

    // A second tab is refused while this one runs.
    let (mut other, _) = tokio_tungstenite::connect_async(&url).await?;
    let error = refused(&mut other).await?;
    assert_eq!(error["kind"], "busy");

    // A cut across the top at x = 0, seen from above.
    let top = later
        .positions
        .chunks(3)
        .filter(|p| p[0].abs() < 0.2)
        .map(|p| p[1])
        .fold(f32::MIN, f32::max);
    let path: Vec<[f32; 3]> = (0..=10)
        .map(|i| [0.0, top, -1.3 + 0.26 * i as f32])
        .collect();
    let cut = Command::Cut {
        path,
        view_dir: [0.0, -1.0, 0.0],
    };
    send(&mut tab, &cut).await?;
    event(&mut tab, TrainerEventKind::CutAdvanced).await?;
    let cut = frame_with(&mut tab, true).await?;
    assert!(
        cut.triangles > first.triangles,
        "{} → {}",
        first.triangles,
        cut.triangles
    );
    assert!(cut.vertices > first.vertices);

    // The needle across the wound, once the whole path is cut (a segment per step).
    tokio::time::sleep(Duration::from_millis(1000)).await;
    let suture = Command::Suture {
        a: [-0.3, top, 0.0],
        b: [0.3, top, 0.0],
    };
    send(&mut tab, &suture).await?;
    event(&mut tab, TrainerEventKind::SuturePlaced).await?;

    // Pause: the steps stop; one step advances by exactly one.
    send(&mut tab, &Command::Pause { paused: true }).await?;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let paused = frame_with(&mut tab, false).await?;
    tokio::time::sleep(Duration::from_millis(200)).await;
    send(&mut tab, &Command::Step).await?;
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let f = frame_with(&mut tab, false).await?;
        if f.step != paused.step {
            assert_eq!(f.step, paused.step + 1);
            break;
        }
        assert!(Instant::now() < deadline, "the single step should come");
    }
    let stats = until(&mut tab, "stats", |m| match m {
        Msg::Stats(s) => Some(s.clone()),
        _ => None,
    })
    .await?;
    assert!(stats.paused);
    assert!(stats.volume_drift.is_finite());

    // Closing the tab ends the session: another tab can start one.
    drop(tab);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (mut again, _) = tokio_tungstenite::connect_async(&url).await?;
        send(&mut again, &load("appendix")).await?;
        match next(&mut again).await? {
            In::Text(Msg::Scene(_)) => break,
            In::Text(Msg::Refused { .. }) => {
                assert!(
                    Instant::now() < deadline,
                    "the closed tab should free the server"
                );
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
            _ => break,
        }
    }
    studio.shutdown();
    server.abort();
    Ok(())
}

/// The demonstration is tissue-scenes' appendix procedure played in the session: the trainee's
/// tools wait, the tip comes off, three stitches are placed, and it ends.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_appendix_demonstration_plays_the_procedure_to_its_end() -> Result {
    let (studio, addr, server) = crate::serve().await?;
    let url = format!("ws://{addr}/api/trainer/ws");
    let (mut tab, _) = tokio_tungstenite::connect_async(&url).await?;
    send(&mut tab, &Command::Demo).await?;
    let error = failed(&mut tab).await?;
    assert_eq!(
        error["kind"], "usage",
        "a demonstration needs an organ first: {error}"
    );
    send(&mut tab, &load("appendix")).await?;
    scene(&mut tab).await?;
    send(&mut tab, &Command::Demo).await?;
    scene(&mut tab).await?;
    event(&mut tab, TrainerEventKind::DemoStarted).await?;
    // The trainee's scalpel is refused while it plays.
    let cut = Command::Cut {
        path: vec![[0.0, 2.0, -1.0], [0.0, 2.0, 1.0]],
        view_dir: [0.0, -1.0, 0.0],
    };
    send(&mut tab, &cut).await?;
    let (mut pieces, mut sutures, mut refused) = (Vec::new(), 0, 0);
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        assert!(Instant::now() < deadline, "the demonstration did not end");
        match next(&mut tab).await? {
            In::Text(Msg::Failed { error }) => {
                assert_eq!(error["kind"], "usage", "{error}");
                refused += 1;
            }
            In::Text(Msg::Event { event }) => match event.kind {
                TrainerEventKind::PieceDetached => pieces.push(event.text),
                TrainerEventKind::SuturePlaced => sutures += 1,
                TrainerEventKind::DemoFinished => break,
                _ => {}
            },
            _ => {}
        }
    }
    assert_eq!(refused, 1, "the cut during the demonstration is refused");
    assert_eq!(sutures, 3);
    // The tip (about 7.8 cm³ at rest) is among the pieces.
    let volumes: Vec<f64> = pieces
        .iter()
        .filter_map(|t| t.rsplit(", ").next()?.trim_end_matches(" cm³").parse().ok())
        .collect();
    assert!(
        volumes.iter().any(|v| (6.0..11.0).contains(v)),
        "pieces: {pieces:?}"
    );
    studio.shutdown();
    server.abort();
    Ok(())
}

/// Errors arrive with their own kinds, not all as `run`: a tool before any organ is a usage
/// error, an organ that is not there is not found, a message the server does not know (the old
/// `tool` message) is refused as usage, a grab off the surface is a usage error.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn trainer_errors_arrive_with_their_kinds() -> Result {
    let (studio, addr, server) = crate::serve().await?;
    let url = format!("ws://{addr}/api/trainer/ws");
    let (mut tab, _) = tokio_tungstenite::connect_async(&url).await?;
    send(&mut tab, &Command::Release).await?;
    let error = failed(&mut tab).await?;
    assert_eq!(error["kind"], "usage", "{error}");
    assert_eq!(error["message"], "load an organ first");
    send(&mut tab, &load("u-not-uploaded")).await?;
    let error = failed(&mut tab).await?;
    assert_eq!(error["kind"], "not_found", "{error}");
    let tool = r#"{"type": "tool", "tool": "probe"}"#;
    tab.send(Message::Text(tool.into())).await?;
    let error = refused(&mut tab).await?;
    assert_eq!(error["kind"], "usage", "{error}");
    send(&mut tab, &load("appendix")).await?;
    scene(&mut tab).await?;
    let grab = Command::Grab {
        point: [0.0, 1.0, 0.0],
        triangle: usize::MAX,
    };
    send(&mut tab, &grab).await?;
    let error = failed(&mut tab).await?;
    assert_eq!(error["kind"], "usage", "{error}");
    assert!(
        error["message"]
            .as_str()
            .is_some_and(|m| m.contains("no surface triangle")),
        "{error}"
    );
    studio.shutdown();
    server.abort();
    Ok(())
}

/// The material over the socket: out of range refused naming the field, taken with a
/// `material` message, in force from the next reset (the scene says so), and the realtime
/// scheme back the same way.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_material_is_applied_on_the_next_reset() -> Result {
    use tissue_studio::material::TissueMaterial;
    let (studio, addr, server) = crate::serve().await?;
    let url = format!("ws://{addr}/api/trainer/ws");
    let (mut tab, _) = tokio_tungstenite::connect_async(&url).await?;
    send(&mut tab, &load("appendix")).await?;
    let first = scene(&mut tab).await?;
    assert_eq!(
        first.material,
        TissueMaterial::default_for(Some(tissue_scenes::ShippedOrgan::Appendix))
    );
    let material = |young_kpa, poisson| Command::Material {
        material: TissueMaterial::Material {
            young_kpa,
            poisson,
            density: 1.04,
        },
    };
    send(&mut tab, &material(7.0, 0.5)).await?;
    let error = failed(&mut tab).await?;
    assert_eq!(error["kind"], "parameters", "{error}");
    assert_eq!(error["field"], "poisson", "{error}");
    send(&mut tab, &material(7.0, 0.49)).await?;
    let state = until(&mut tab, "the material message", |m| match m {
        Msg::Material(s) => Some(*s),
        _ => None,
    })
    .await?;
    assert_eq!(state.in_force, Some(first.material));
    let custom = TissueMaterial::Material {
        young_kpa: 7.0,
        poisson: 0.49,
        density: 1.04,
    };
    assert_eq!(state.pending, Some(custom));
    send(&mut tab, &Command::Reset).await?;
    let after = scene(&mut tab).await?;
    assert_eq!(after.material, custom);
    assert_eq!(after.top, first.top, "the organ's top as loaded");
    frame_with(&mut tab, false).await?;
    let realtime = Command::Material {
        material: TissueMaterial::Realtime {},
    };
    send(&mut tab, &realtime).await?;
    send(&mut tab, &Command::Reset).await?;
    assert_eq!(scene(&mut tab).await?.material, TissueMaterial::Realtime {});
    studio.shutdown();
    server.abort();
    Ok(())
}
