//! The live preview over the job socket: answered with the planner's coarse run, only the
//! newest of a burst computed and answered, errors named by field.

use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use tokio_tungstenite::tungstenite::Message;

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;
type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// The next `preview` answer, and how many came before it with other seqs.
async fn answer(socket: &mut Socket, seq: u64) -> Result<(Value, usize)> {
    let mut others = 0;
    loop {
        let message = tokio::time::timeout(Duration::from_secs(120), socket.next())
            .await?
            .ok_or("the socket closed")??;
        let Message::Text(text) = message else {
            continue;
        };
        let m: Value = serde_json::from_str(&text)?;
        if m["type"] != "preview" {
            continue;
        }
        if m["seq"] == seq {
            return Ok((m, others));
        }
        others += 1;
    }
}

async fn preview(socket: &mut Socket, patient: &Value, seq: u64, request: Value) -> Result {
    let m = json!({ "type": "preview", "patient": patient, "seq": seq, "request": request });
    socket.send(Message::Text(m.to_string().into())).await?;
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_burst_of_previews_computes_few_and_answers_the_last() -> Result {
    let (studio, addr, server) = crate::serve().await?;
    let client = reqwest_free_post(&studio).await?;
    let patient = client["patient"].clone();
    let (mut tab, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/ws")).await?;

    preview(&mut tab, &patient, 1, json!({})).await?;
    let (first, _) = answer(&mut tab, 1).await?;
    let p = &first["preview"];
    assert!(first["error"].is_null(), "{first}");
    let radius = 5.25; // Table 2's 7 cm expander
    let edge = tissue_planner::preview_edge_cm(radius)?;
    assert_eq!(p["edge_cm"].as_f64(), Some(edge));
    assert!(p["gain_cm2"].as_f64().unwrap_or(0.0) > 20.0, "{p}");
    assert!(p["steps"].as_u64().unwrap_or(u64::MAX) <= tissue_planner::PREVIEW_MAX_STEPS);
    let before = first["computed"].as_u64().ok_or("computed")?;
    assert_eq!(before, 1);

    // 40 previews as fast as the socket takes them: the server computes a few, answers the
    // last, and its answer is the last request's.
    let sent: u32 = 40;
    for i in 0..sent {
        let volume = 60.0 + f64::from(i);
        preview(
            &mut tab,
            &patient,
            2 + u64::from(i),
            json!({ "volume_cm3": volume }),
        )
        .await?;
    }
    let last = 1 + u64::from(sent);
    let (m, others) = answer(&mut tab, last).await?;
    let computed = m["computed"].as_u64().ok_or("computed")? - before;
    assert!(computed <= 5, "{computed} of {sent} computed");
    assert!(others <= 5, "{others} superseded answers sent");
    let patient_cm = std::sync::Arc::new(tissue_planner::Patient::shipped(
        tissue_planner::Shipped::Table2,
    )?);
    let request = tissue_planner::PlanRequest {
        volume_cm3: 60.0 + f64::from(sent - 1),
        ..tissue_planner::PlanRequest::default()
    };
    let direct = tissue_planner::Previewer::new()
        .preview(&patient_cm, request, &tissue_planner::CancelToken::new())
        .map_err(|e| format!("{e:?}"))?;
    assert_eq!(m["preview"]["gain_cm2"].as_f64(), Some(direct.gain_cm2));

    // Errors: the field at fault, and an unknown patient.
    preview(&mut tab, &patient, 100, json!({ "depth_cm": -1 })).await?;
    let (bad, _) = answer(&mut tab, 100).await?;
    assert_eq!(bad["error"]["field"], "depth_cm", "{bad}");
    assert!(bad["preview"].is_null());
    preview(&mut tab, &json!("p0"), 101, json!({})).await?;
    let (gone, _) = answer(&mut tab, 101).await?;
    assert_eq!(gone["error"]["kind"], "usage", "{gone}");
    // An unknown member is refused as a run's is.
    let m = json!({ "type": "preview", "patient": patient, "volume": 50 });
    tab.send(Message::Text(m.to_string().into())).await?;
    loop {
        let message = tokio::time::timeout(Duration::from_secs(30), tab.next())
            .await?
            .ok_or("the socket closed")??;
        if let Message::Text(text) = message {
            let m: Value = serde_json::from_str(&text)?;
            if m["type"] == "refused" {
                assert_eq!(m["error"]["kind"], "usage");
                break;
            }
        }
    }
    studio.shutdown();
    server.abort();
    Ok(())
}

/// Loads Table 2 through the router.
async fn reqwest_free_post(studio: &tissue_studio::Studio) -> Result<Value> {
    use axum::body::Body;
    use axum::http::Request;
    use tower::ServiceExt;
    let response = crate::app(studio)
        .oneshot(Request::post("/api/patients?shipped=table2").body(Body::empty())?)
        .await?;
    let bytes = axum::body::to_bytes(response.into_body(), usize::MAX).await?;
    Ok(serde_json::from_slice(&bytes)?)
}
