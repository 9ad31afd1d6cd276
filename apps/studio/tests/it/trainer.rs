//! The trainer's socket without a browser: the appendix loads, frames stream in the documented
//! binary layout (the index buffer first and after a cut), a cut and a suture give their events,
//! a second tab is refused, and closing the tab frees the server.

use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
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

enum In {
    Text(Value),
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

async fn text_of(socket: &mut Socket, kind: &str, field: Option<(&str, &str)>) -> Result<Value> {
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut seen = Vec::new();
    loop {
        assert!(
            Instant::now() < deadline,
            "no {kind} {field:?} within 60 s; events seen: {seen:?}"
        );
        if let In::Text(v) = next(socket).await? {
            if v["type"] == "event" {
                seen.push(v["event"]["kind"].clone());
            }
            let field_ok = field.is_none_or(|(k, want)| v["event"][k] == want);
            if v["type"] == kind && field_ok {
                return Ok(v);
            }
            assert_ne!(v["type"], "failed", "{v}");
        }
    }
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

async fn send(socket: &mut Socket, v: Value) -> Result {
    socket.send(Message::Text(v.to_string().into())).await?;
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_appendix_streams_is_cut_and_sutured_and_one_session_runs_at_a_time() -> Result {
    let (studio, addr, server) = crate::serve().await?;
    let url = format!("ws://{addr}/api/trainer/ws");
    let (mut tab, _) = tokio_tungstenite::connect_async(&url).await?;
    send(&mut tab, json!({ "type": "load", "organ": "appendix" })).await?;
    let scene = text_of(&mut tab, "scene", None).await?;
    let nodes = scene["nodes"].as_u64().unwrap_or(0) as usize;
    assert_eq!(nodes, 33 * 9 * 9);
    assert!(scene["capacity"]["vertices"].as_u64().unwrap_or(0) as usize > nodes);

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
    let refused = text_of(&mut other, "refused", None).await?;
    assert_eq!(refused["error"]["kind"], "busy");

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
    send(
        &mut tab,
        json!({ "type": "cut", "path": path, "view_dir": [0, -1, 0] }),
    )
    .await?;
    text_of(&mut tab, "event", Some(("kind", "cut_advanced"))).await?;
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
    send(
        &mut tab,
        json!({ "type": "suture", "a": [-0.3, top, 0.0], "b": [0.3, top, 0.0] }),
    )
    .await?;
    text_of(&mut tab, "event", Some(("kind", "suture_placed"))).await?;

    // Pause: the steps stop; one step advances by exactly one.
    send(&mut tab, json!({ "type": "pause", "paused": true })).await?;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let paused = frame_with(&mut tab, false).await?;
    tokio::time::sleep(Duration::from_millis(200)).await;
    send(&mut tab, json!({ "type": "step" })).await?;
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let f = frame_with(&mut tab, false).await?;
        if f.step != paused.step {
            assert_eq!(f.step, paused.step + 1);
            break;
        }
        assert!(Instant::now() < deadline, "the single step should come");
    }
    let stats = text_of(&mut tab, "stats", None).await?;
    assert_eq!(stats["paused"], true);
    assert!(stats["volume_drift"].as_f64().is_some_and(f64::is_finite));

    // Closing the tab ends the session: another tab can start one.
    drop(tab);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let (mut again, _) = tokio_tungstenite::connect_async(&url).await?;
        send(&mut again, json!({ "type": "load", "organ": "appendix" })).await?;
        match next(&mut again).await? {
            In::Text(v) if v["type"] == "scene" => break,
            In::Text(v) if v["type"] == "refused" => {
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
    send(&mut tab, json!({ "type": "demo" })).await?;
    let refused = text_of(&mut tab, "failed", None).await;
    assert!(refused.is_ok(), "a demonstration needs an organ first");
    send(&mut tab, json!({ "type": "load", "organ": "appendix" })).await?;
    text_of(&mut tab, "scene", None).await?;
    send(&mut tab, json!({ "type": "demo" })).await?;
    text_of(&mut tab, "scene", None).await?;
    text_of(&mut tab, "event", Some(("kind", "demo_started"))).await?;
    // The trainee's scalpel is refused while it plays.
    send(
        &mut tab,
        json!({ "type": "cut", "path": [[0, 2, -1], [0, 2, 1]], "view_dir": [0, -1, 0] }),
    )
    .await?;
    let (mut pieces, mut sutures, mut refused) = (Vec::new(), 0, 0);
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        assert!(Instant::now() < deadline, "the demonstration did not end");
        let In::Text(v) = next(&mut tab).await? else {
            continue;
        };
        if v["type"] == "failed" {
            refused += 1;
            continue;
        }
        if v["type"] != "event" {
            continue;
        }
        match v["event"]["kind"].as_str() {
            Some("piece_detached") => pieces.push(v["event"]["text"].to_string()),
            Some("suture_placed") => sutures += 1,
            Some("demo_finished") => break,
            _ => {}
        }
    }
    assert_eq!(refused, 1, "the cut during the demonstration is refused");
    assert_eq!(sutures, 3);
    // The tip (about 7.8 cm³ at rest) is among the pieces.
    let volumes: Vec<f64> = pieces
        .iter()
        .filter_map(|t| {
            t.trim_matches('"')
                .rsplit(", ")
                .next()?
                .trim_end_matches(" cm³")
                .parse()
                .ok()
        })
        .collect();
    assert!(
        volumes.iter().any(|v| (6.0..11.0).contains(v)),
        "pieces: {pieces:?}"
    );
    studio.shutdown();
    server.abort();
    Ok(())
}
