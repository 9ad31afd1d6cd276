//! The studio's server without a browser: the routes through the router, and the job socket
//! over a real TCP connection (Table 2 run in full, a cancel, the one-job policy, a closed tab).

use std::time::{Duration, Instant};

use axum::body::Body;
use axum::http::{Request, StatusCode};
use futures_util::{SinkExt, StreamExt};
use http_body_util::BodyExt;
use serde_json::{json, Value};
use tokio_tungstenite::tungstenite::Message;
use tower::ServiceExt;

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

async fn call(app: &axum::Router, request: Request<Body>) -> Result<(StatusCode, Value)> {
    let response = app.clone().oneshot(request).await?;
    let status = response.status();
    let bytes = response.into_body().collect().await?.to_bytes();
    let value = serde_json::from_slice(&bytes).unwrap_or(Value::Null);
    Ok((status, value))
}

fn post_json(uri: &str, body: &Value) -> Result<Request<Body>> {
    Ok(Request::post(uri)
        .header("content-type", "application/json")
        .body(Body::from(body.to_string()))?)
}

#[tokio::test]
async fn patients_load_summarise_and_refuse_broken_or_oversize_files() -> Result {
    let studio = tissue_studio::Studio::new()?;
    let app = crate::app(&studio);

    let (status, meshes) = call(&app, Request::get("/api/meshes").body(Body::empty())?).await?;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(meshes[0]["id"], "table2");
    assert_eq!(meshes[0]["default"], true);

    let (status, plane) = call(
        &app,
        Request::post("/api/patients?shipped=table2").body(Body::empty())?,
    )
    .await?;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(plane["summary"]["vertices"], 4225);
    assert_eq!(
        plane["summary"]["boundary_loops"].as_array().map(Vec::len),
        Some(1)
    );
    assert_eq!(
        plane["mesh"]["positions"].as_array().map(Vec::len),
        Some(3 * 4225)
    );
    assert_eq!(
        plane["mesh"]["triangles"].as_array().map(Vec::len),
        Some(3 * 8192)
    );
    assert_eq!(plane["suggested"]["point"], json!([0.0, 0.0, 0.0]));

    // The chest in dm comes out in cm: its box is tens of cm, not a few dm.
    let (status, chest) = call(
        &app,
        Request::post("/api/patients?shipped=chest").body(Body::empty())?,
    )
    .await?;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(chest["unit"], "dm");
    let size = chest["summary"]["bounding_box_cm"]["size"][0]
        .as_f64()
        .unwrap_or(0.0);
    assert!(size > 15.0, "chest width {size} cm");

    // A broken file: the loader's message, naming the file and the line.
    let (status, broken) = call(
        &app,
        Request::post("/api/patients?name=broken.obj&unit=mm")
            .header("content-type", "application/octet-stream")
            .body(Body::from("v 0 0 0\nf 1 2 3\n"))?,
    )
    .await?;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    let message = broken["error"]["message"].as_str().unwrap_or("");
    assert!(
        message.contains("broken.obj") && message.contains("line 2"),
        "{message}"
    );
    assert_eq!(broken["error"]["kind"], "mesh");

    // An unknown format, an unknown unit, an empty file.
    for (uri, body, kind) in [
        ("/api/patients?name=scan.xyz&unit=mm", "1 2 3", "input"),
        ("/api/patients?name=scan.obj&unit=inch", "v 0 0 0", "usage"),
        ("/api/patients?name=scan.obj&unit=mm", "", "input"),
    ] {
        let request = Request::post(uri)
            .header("content-type", "application/octet-stream")
            .body(Body::from(body))?;
        let (status, e) = call(&app, request).await?;
        assert_eq!(status, StatusCode::BAD_REQUEST, "{uri}");
        assert_eq!(e["error"]["kind"], kind, "{uri}: {e}");
    }

    // Over the limit: 413 with a message.
    let big = vec![b' '; tissue_studio::UPLOAD_LIMIT + 1];
    let (status, e) = call(
        &app,
        Request::post("/api/patients?name=big.obj&unit=mm")
            .header("content-type", "application/octet-stream")
            .body(Body::from(big))?,
    )
    .await?;
    assert_eq!(status, StatusCode::PAYLOAD_TOO_LARGE);
    assert_eq!(e["error"]["kind"], "too_large");
    assert!(e["error"]["message"]
        .as_str()
        .unwrap_or("")
        .contains("64 MiB"));

    // Nothing written outside the temporary folder, and that is removed on shutdown.
    let temp = studio.temp_dir().to_path_buf();
    assert!(temp.is_dir());
    studio.shutdown();
    assert!(!temp.exists());
    Ok(())
}

#[tokio::test]
async fn the_preview_draws_the_runs_region_and_refuses_the_border_before_run() -> Result {
    let studio = tissue_studio::Studio::new()?;
    let app = crate::app(&studio);
    let (_, plane) = call(
        &app,
        Request::post("/api/patients?shipped=table2").body(Body::empty())?,
    )
    .await?;
    let id = plane["patient"].clone();

    let (status, ok) = call(
        &app,
        post_json(
            "/api/preview",
            &json!({ "patient": id, "request": { "at": [0.1, -0.1, 0.0], "rotation_deg": 90 } }),
        )?,
    )
    .await?;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(ok["ok"], true, "{ok}");
    assert_eq!(ok["region_radius_cm"], 5.25);
    let tangent = &ok["placement"]["tangent"];
    assert!(
        tangent[1].as_f64().unwrap_or(0.0) > 0.999,
        "turned 90°: {tangent}"
    );
    let footprint = ok["footprint"].as_array().cloned().unwrap_or_default();
    assert!(footprint.len() > 16);
    let outline = ok["region_outline"][0]
        .as_array()
        .cloned()
        .unwrap_or_default();
    assert!(outline.len() > 50, "{} outline points", outline.len());

    // Too near the border: refused before Run, with the run's own message and the outlines.
    let (_, border) = call(
        &app,
        post_json(
            "/api/preview",
            &json!({ "patient": id, "request": { "at": [8.0, 0.0, 0.0] } }),
        )?,
    )
    .await?;
    assert_eq!(border["ok"], false);
    assert_eq!(border["error"]["kind"], "placement");
    assert!(border["error"]["message"]
        .as_str()
        .unwrap_or("")
        .contains("region radius"));
    assert!(!border["footprint"]
        .as_array()
        .cloned()
        .unwrap_or_default()
        .is_empty());

    // Bad parameters and an unknown patient are explained too.
    let (_, bad) = call(
        &app,
        post_json(
            "/api/preview",
            &json!({ "patient": id, "request": { "volume_cm3": -3 } }),
        )?,
    )
    .await?;
    assert_eq!(bad["error"]["field"], "volume_cm3");
    assert!(bad["error"]["message"]
        .as_str()
        .unwrap_or("")
        .starts_with("volume must be"));
    let (_, gone) = call(
        &app,
        post_json("/api/preview", &json!({ "patient": "p999", "request": {} }))?,
    )
    .await?;
    assert_eq!(gone["ok"], false);
    let (status, _) = call(&app, post_json("/api/preview", &json!({ "nonsense": 1 }))?).await?;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    studio.shutdown();
    Ok(())
}

type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn next(socket: &mut Socket) -> Result<Value> {
    loop {
        let message = tokio::time::timeout(Duration::from_secs(600), socket.next())
            .await?
            .ok_or("the socket closed")??;
        if let Message::Text(text) = message {
            return Ok(serde_json::from_str(&text)?);
        }
    }
}

async fn until(socket: &mut Socket, kinds: &[&str]) -> Result<Value> {
    loop {
        let m = next(socket).await?;
        if kinds.iter().any(|k| m["type"] == *k) {
            return Ok(m);
        }
    }
}

async fn send(socket: &mut Socket, value: Value) -> Result {
    socket.send(Message::Text(value.to_string().into())).await?;
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn jobs_run_table2_in_band_cancel_refuse_a_second_and_end_with_the_tab() -> Result {
    let (studio, addr, server) = crate::serve().await?;
    let client = crate::app(&studio);
    let (_, plane) = call(
        &client,
        Request::post("/api/patients?shipped=table2").body(Body::empty())?,
    )
    .await?;
    let patient = plane["patient"].clone();
    let (mut tab, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/ws")).await?;

    // A member the job JSON does not have is refused, as the C ABI refuses it.
    send(
        &mut tab,
        json!({ "type": "run", "patient": patient, "mode": "single", "volume": 50 }),
    )
    .await?;
    let refused = until(&mut tab, &["refused"]).await?;
    assert_eq!(refused["error"]["kind"], "usage", "{refused}");
    assert!(
        refused["error"]["message"]
            .as_str()
            .is_some_and(|m| m.contains("volume")),
        "{refused}"
    );

    // Table 2, in full: the gain in the thesis's band (34.98 cm² measured, band ±2.5).
    send(
        &mut tab,
        json!({ "type": "run", "patient": patient, "mode": "single", "request": {} }),
    )
    .await?;
    let accepted = until(&mut tab, &["accepted"]).await?;
    let job = accepted["job"].as_str().unwrap_or("").to_owned();
    let mut progress = 0;
    let finished = loop {
        let m = next(&mut tab).await?;
        match m["type"].as_str() {
            Some("progress") => {
                progress += 1;
                let settle = m["settle"].as_f64().unwrap_or(-1.0);
                assert!((0.0..=1.0).contains(&settle), "{m}");
            }
            _ => break m,
        }
    };
    assert_eq!(finished["type"], "finished", "{finished}");
    assert!(progress > 0);
    let report = &finished["report"];
    let gain = report["area_gain_cm2"].as_f64().unwrap_or(0.0);
    assert!((32.5..=37.5).contains(&gain), "Table 2 gain {gain} cm²");
    assert_eq!(report["tool"], "studio");
    assert_eq!(report["schema_version"], 1);
    assert_eq!(report["boundary_unchanged"], true);
    let fields = &finished["fields"];
    assert_eq!(fields["after"].as_array().map(Vec::len), Some(3 * 4225));
    let top = fields["displacement"]
        .as_array()
        .map(|d| d.iter().filter_map(Value::as_f64).fold(0.0, f64::max))
        .unwrap_or(0.0);
    assert!((top - report["max_displacement_cm"].as_f64().unwrap_or(-1.0)).abs() < 1e-4);

    // Its files download; the report is the one sent.
    for file in ["patient.ply", "patient.obj", "patient.vtk", "report.json"] {
        let (status, _) = call(
            &client,
            Request::get(format!("/api/results/{job}/{file}")).body(Body::empty())?,
        )
        .await?;
        assert_eq!(status, StatusCode::OK, "{file}");
    }
    let (_, saved) = call(
        &client,
        Request::get(format!("/api/results/{job}/report.json")).body(Body::empty())?,
    )
    .await?;
    assert_eq!(&saved, report);

    // A second run, cancelled once it steps; a run from another tab meanwhile is refused.
    send(
        &mut tab,
        json!({ "type": "run", "patient": patient, "request": {} }),
    )
    .await?;
    until(&mut tab, &["progress"]).await?;
    let (mut other, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/ws")).await?;
    send(
        &mut other,
        json!({ "type": "run", "patient": patient, "request": {} }),
    )
    .await?;
    let refused = until(&mut other, &["refused", "accepted"]).await?;
    assert_eq!(refused["type"], "refused", "{refused}");
    assert_eq!(refused["error"]["kind"], "busy");
    let asked = Instant::now();
    send(&mut tab, json!({ "type": "cancel" })).await?;
    let cancelled = until(&mut tab, &["cancelled", "finished", "failed"]).await?;
    let latency = asked.elapsed();
    assert_eq!(cancelled["type"], "cancelled", "{cancelled}");
    eprintln!("cancel latency over the socket: {latency:?}");

    // A third run; its tab closes: the job is cancelled and the server is free again.
    send(
        &mut other,
        json!({ "type": "run", "patient": patient, "request": {} }),
    )
    .await?;
    until(&mut other, &["progress"]).await?;
    drop(other);
    let deadline = Instant::now() + Duration::from_secs(10);
    while studio.is_busy() {
        assert!(Instant::now() < deadline, "the closed tab's job should end");
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    // A sweep of two volumes: a report with a run per volume, gain growing with volume.
    send(&mut tab, json!({ "type": "run", "patient": patient, "mode": "sweep", "volumes_cm3": [20, 40], "request": { "max_steps": 150 } })).await?;
    let swept = until(&mut tab, &["finished", "failed", "refused"]).await?;
    assert_eq!(swept["type"], "finished", "{swept}");
    let runs = swept["report"]["runs"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    assert_eq!(runs.len(), 2);
    let g = |i: usize| runs[i]["area_gain_cm2"].as_f64().unwrap_or(f64::NAN);
    assert!(g(1) > g(0), "{} then {}", g(0), g(1));
    studio.shutdown();
    server.abort();
    Ok(())
}

/// The binary's failures use the exit-code table every tissue binary shares: a port already
/// taken is `Exit::Failure` (1), with one line naming the flag to change.
#[test]
fn a_taken_port_exits_with_the_shared_failure_code() -> Result<()> {
    let taken = std::net::TcpListener::bind("127.0.0.1:0")?;
    let port = taken.local_addr()?.port().to_string();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_studio"))
        .args(["--port", &port])
        .output()?;
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(tissue_cli::Exit::Failure.code().into()),
        "{err}"
    );
    assert!(err.contains("--port"), "{err}");
    Ok(())
}
