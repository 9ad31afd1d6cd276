//! The Cases routes: a plan run through the job socket and saved, reopened after the studio is
//! dropped and made again on the same data folder (its report and meshes byte for byte the
//! job's), two tabs saving at the same instant, another site's erase refused, unknown ids, the
//! erasure leaving no scan bytes in the data folder, export then import into another studio, a
//! damaged archive and a zip bomb.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use axum::body::Body;
use axum::http::{Request, StatusCode};
use futures_util::{SinkExt, StreamExt};
use http_body_util::BodyExt;
use serde_json::{json, Value};
use tissue_studio::{Limits, Studio};
use tokio_tungstenite::tungstenite::Message;
use tower::ServiceExt;

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

/// A data folder of the test's own, removed when dropped.
struct Data(PathBuf);

impl Data {
    fn new(name: &str) -> Data {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        Data(std::env::temp_dir().join(format!(
            "tissue-cases-test-{name}-{}-{nanos}",
            std::process::id()
        )))
    }

    fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Data {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `studio` served on a free local port: its address and the server task.
async fn served(studio: &Studio) -> Result<(SocketAddr, tokio::task::JoinHandle<()>)> {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await?;
    let addr = listener.local_addr()?;
    let access = tissue_studio::Access::new(addr, Vec::new(), false)?;
    let server = tokio::spawn(tissue_studio::serve(
        listener,
        studio.clone(),
        access,
        std::future::pending(),
    ));
    Ok((addr, server))
}

async fn call(app: &axum::Router, request: Request<Body>) -> Result<(StatusCode, Vec<u8>)> {
    let response = app.clone().oneshot(request).await?;
    let status = response.status();
    let bytes = response.into_body().collect().await?.to_bytes();
    Ok((status, bytes.to_vec()))
}

async fn get_json(app: &axum::Router, uri: &str) -> Result<(StatusCode, Value)> {
    let (status, bytes) = call(app, Request::get(uri).body(Body::empty())?).await?;
    Ok((
        status,
        serde_json::from_slice(&bytes).unwrap_or(Value::Null),
    ))
}

async fn post_json(app: &axum::Router, uri: &str, body: &Value) -> Result<(StatusCode, Value)> {
    let request = Request::post(uri)
        .header("content-type", "application/json")
        .body(Body::from(body.to_string()))?;
    let (status, bytes) = call(app, request).await?;
    Ok((
        status,
        serde_json::from_slice(&bytes).unwrap_or(Value::Null),
    ))
}

async fn table2(app: &axum::Router) -> Result<Value> {
    let (status, plane) = post_json(app, "/api/patients?shipped=table2", &Value::Null).await?;
    assert_eq!(status, StatusCode::OK, "{plane}");
    Ok(plane["patient"].clone())
}

type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn tab(addr: SocketAddr) -> Result<Socket> {
    Ok(
        tokio_tungstenite::connect_async(format!("ws://{addr}/api/ws"))
            .await?
            .0,
    )
}

/// Runs `request` on `patient` in `tab` to its end: the `finished` message.
async fn run(tab: &mut Socket, patient: &Value, request: Value) -> Result<Value> {
    let run = json!({ "type": "run", "patient": patient, "request": request });
    tab.send(Message::Text(run.to_string().into())).await?;
    loop {
        let m = tokio::time::timeout(Duration::from_secs(600), tab.next())
            .await?
            .ok_or("the socket closed")??;
        let Message::Text(text) = m else { continue };
        let v: Value = serde_json::from_str(&text)?;
        match v["type"].as_str() {
            Some("finished") => return Ok(v),
            Some("failed" | "refused" | "cancelled") => return Err(format!("{v}").into()),
            _ => {}
        }
    }
}

/// A short single run: quick, and its result is a real one (the skin moved).
fn short(volume: f64) -> Value {
    json!({ "at": [0, 0, 0], "volume_cm3": volume, "max_steps": 150 })
}

const FILES: [&str; 4] = ["report.json", "patient.ply", "patient.obj", "patient.vtk"];

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_saved_plan_reopens_after_a_restart_with_the_jobs_report_and_meshes_byte_for_byte(
) -> Result {
    let data = Data::new("restart");
    let studio = Studio::with_data(Limits::default(), data.path())?;
    let (addr, server) = served(&studio).await?;
    let app = crate::app(&studio);
    let patient = table2(&app).await?;
    let mut socket = tab(addr).await?;
    let finished = run(&mut socket, &patient, short(80.0)).await?;
    let job = finished["job"].as_str().unwrap_or("").to_owned();
    let mut downloads = Vec::new();
    for file in FILES {
        let (status, bytes) = call(
            &app,
            Request::get(format!("/api/results/{job}/{file}")).body(Body::empty())?,
        )
        .await?;
        assert_eq!(status, StatusCode::OK, "{file}");
        downloads.push(bytes);
    }
    let (status, saved) = post_json(
        &app,
        "/api/cases/save",
        &json!({ "job": job, "name": "80 cm³ round", "note": "first try" }),
    )
    .await?;
    assert_eq!(status, StatusCode::OK, "{saved}");
    let uid = saved["uid"].as_str().unwrap_or("").to_owned();
    assert!(uid.starts_with('c') && uid.len() == 33, "{saved}");
    assert_eq!(saved["tool"], "studio");
    assert_eq!(saved["has_result"], true);
    // The restart: the studio stops (its temporary folder and the job's files go) and another
    // is made on the same data folder.
    drop(socket);
    studio.shutdown();
    server.abort();
    drop(app);
    let temp = studio.temp_dir().to_path_buf();
    assert!(!temp.exists());
    drop(studio);

    let again = Studio::with_data(Limits::default(), data.path())?;
    let app = crate::app(&again);
    let (status, list) = get_json(&app, "/api/cases/patients").await?;
    assert_eq!(status, StatusCode::OK, "{list}");
    assert_eq!(list["patients"].as_array().map(Vec::len), Some(1), "{list}");
    assert_eq!(list["patients"][0]["plans"][0]["uid"], uid.as_str());
    assert_eq!(list["patients"][0]["plans"][0]["note"], "first try");
    let t0 = Instant::now();
    let (status, opened) = get_json(&app, &format!("/api/cases/plans/{uid}")).await?;
    eprintln!("a 4225-vertex plan opened in {:?}", t0.elapsed());
    assert_eq!(status, StatusCode::OK, "{opened}");
    // What the page draws is what the job's `finished` message drew: report and fields.
    assert_eq!(opened["report"], finished["report"]);
    assert_eq!(opened["fields"], finished["fields"]);
    assert_eq!(
        opened["mesh"]["positions"].as_array().map(Vec::len),
        Some(3 * 4225)
    );
    assert_eq!(opened["unit"], "cm");
    for (file, original) in FILES.iter().zip(&downloads) {
        let (status, bytes) = call(
            &app,
            Request::get(format!("/api/cases/plans/{uid}/files/{file}")).body(Body::empty())?,
        )
        .await?;
        assert_eq!(status, StatusCode::OK, "{file}");
        assert!(bytes == *original, "{file} differs from the job's download");
    }
    let (status, none) = get_json(&app, &format!("/api/cases/plans/{uid}/files/chart.png")).await?;
    assert_eq!(status, StatusCode::NOT_FOUND, "{none}");
    again.shutdown();
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_tabs_finish_one_after_the_other_then_save_at_the_same_instant() -> Result {
    let data = Data::new("two-tabs");
    let studio = Studio::with_data(Limits::default(), data.path())?;
    let (addr, server) = served(&studio).await?;
    let app = crate::app(&studio);
    let patient = table2(&app).await?;
    let (mut one, mut two) = (tab(addr).await?, tab(addr).await?);
    // One job at a time on the server: the second tab runs once the first has finished.
    let a = run(&mut one, &patient, short(60.0)).await?;
    let b = run(&mut two, &patient, short(120.0)).await?;
    let save =
        |job: &Value, name: &str| json!({ "job": job, "name": name, "label": "Table 2 plane" });
    let (save_a, save_b) = (save(&a["job"], "60 cm³"), save(&b["job"], "120 cm³"));
    let (sa, sb) = tokio::join!(
        post_json(&app, "/api/cases/save", &save_a),
        post_json(&app, "/api/cases/save", &save_b),
    );
    let ((sa, pa), (sb, pb)) = (sa?, sb?);
    assert_eq!((sa, sb), (StatusCode::OK, StatusCode::OK), "{pa} {pb}");
    assert_eq!(
        pa["patient_uid"], pb["patient_uid"],
        "one patient: one scan"
    );
    assert_ne!(pa["uid"], pb["uid"]);
    let (_, list) = get_json(&app, "/api/cases/patients?search=table").await?;
    let plans = list["patients"][0]["plans"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    assert_eq!(plans.len(), 2, "{list}");
    assert_eq!(list["patients"][0]["patient"]["label"], "Table 2 plane");
    let (_, none) = get_json(&app, "/api/cases/patients?search=nobody").await?;
    assert_eq!(none["patients"].as_array().map(Vec::len), Some(0), "{none}");

    // The two side by side: the figures, B − A, the difference map on the patient.
    let (status, c) = get_json(
        &app,
        &format!(
            "/api/cases/compare?a={}&b={}",
            pa["uid"].as_str().unwrap_or(""),
            pb["uid"].as_str().unwrap_or("")
        ),
    )
    .await?;
    assert_eq!(status, StatusCode::OK, "{c}");
    let gain = c["figures"]
        .as_array()
        .and_then(|f| f.iter().find(|r| r["name"] == "area_gain_cm2"))
        .cloned()
        .unwrap_or(Value::Null);
    let (ga, gb) = (
        a["report"]["area_gain_cm2"].as_f64().unwrap_or(f64::NAN),
        b["report"]["area_gain_cm2"].as_f64().unwrap_or(f64::NAN),
    );
    assert!(
        (gain["a"].as_f64().unwrap_or(0.0) - ga).abs() < 1e-9,
        "{gain}"
    );
    assert!(
        (gain["difference"].as_f64().unwrap_or(0.0) - (gb - ga)).abs() < 1e-6,
        "{gain}"
    );
    assert_eq!(c["difference"].as_array().map(Vec::len), Some(4225));
    let max = c["max_difference"].as_f64().unwrap_or(0.0);
    assert!(max > 0.0, "120 cm³ raises the skin more than 60 cm³: {max}");
    assert_eq!(
        c["mesh"]["triangles"].as_array().map(Vec::len),
        Some(3 * 8192)
    );

    // Rename, note, delete a plan; rename the patient.
    let ca = pa["uid"].as_str().unwrap_or("");
    let (s, renamed) = post_json(
        &app,
        &format!("/api/cases/plans/{ca}/rename"),
        &json!({ "name": "small" }),
    )
    .await?;
    assert_eq!(
        (s, renamed["name"].as_str()),
        (StatusCode::OK, Some("small")),
        "{renamed}"
    );
    let (s, noted) = post_json(
        &app,
        &format!("/api/cases/plans/{ca}/note"),
        &json!({ "note": "too little" }),
    )
    .await?;
    assert_eq!(
        (s, noted["note"].as_str()),
        (StatusCode::OK, Some("too little")),
        "{noted}"
    );
    let (s, bad) = post_json(
        &app,
        &format!("/api/cases/plans/{ca}/rename"),
        &json!({ "name": "" }),
    )
    .await?;
    assert_eq!(s, StatusCode::BAD_REQUEST, "{bad}");
    assert_eq!(bad["error"]["field"], "name", "{bad}");
    let p = pa["patient_uid"].as_str().unwrap_or("");
    let (s, relabelled) = post_json(
        &app,
        &format!("/api/cases/patients/{p}/rename"),
        &json!({ "label": "Mrs T." }),
    )
    .await?;
    assert_eq!(
        (s, relabelled["label"].as_str()),
        (StatusCode::OK, Some("Mrs T.")),
        "{relabelled}"
    );
    let (s, _) = post_json(&app, &format!("/api/cases/plans/{ca}/delete"), &json!({})).await?;
    assert_eq!(s, StatusCode::OK);
    let (s, _) = get_json(&app, &format!("/api/cases/plans/{ca}")).await?;
    assert_eq!(s, StatusCode::NOT_FOUND);
    let (_, list) = get_json(&app, "/api/cases/patients?search=mrs").await?;
    assert_eq!(
        list["patients"][0]["plans"].as_array().map(Vec::len),
        Some(1),
        "{list}"
    );

    // The stored patient opened to plan on: answered as /api/patients is, and a job runs on it.
    let (s, opened) = post_json(&app, &format!("/api/cases/patients/{p}/open"), &json!({})).await?;
    assert_eq!(s, StatusCode::OK, "{opened}");
    assert_eq!(opened["label"], "Mrs T.");
    assert_eq!(
        opened["mesh"]["positions"].as_array().map(Vec::len),
        Some(3 * 4225)
    );
    let again = run(&mut one, &opened["patient"], short(60.0)).await?;
    // The stored patient is the scan as stored (the shipped plane written as OBJ, a file
    // patient now): the same run on it gains what it gained on the shipped plane, within 1 %.
    let gain = |m: &Value| m["report"]["area_gain_cm2"].as_f64().unwrap_or(f64::NAN);
    assert!(
        (gain(&again) - gain(&a)).abs() < 0.01 * gain(&a),
        "{} on the stored patient, {} on the shipped one",
        gain(&again),
        gain(&a)
    );
    let (s, third) = post_json(
        &app,
        "/api/cases/save",
        &json!({ "job": again["job"], "name": "60 again" }),
    )
    .await?;
    assert_eq!(s, StatusCode::OK, "{third}");
    assert_eq!(third["patient_uid"], p, "saved to the same patient");
    studio.shutdown();
    server.abort();
    Ok(())
}

/// A studio on `data` with one plan saved on `scan` (OBJ bytes in cm): the studio, its router,
/// the plan.
async fn one_plan(data: &Data, scan: &[u8]) -> Result<(Studio, axum::Router, Value)> {
    let studio = Studio::with_data(Limits::default(), data.path())?;
    let (addr, server) = served(&studio).await?;
    let app = crate::app(&studio);
    let request = Request::post("/api/patients?name=p17.obj&unit=cm")
        .header("content-type", "application/octet-stream")
        .body(Body::from(scan.to_vec()))?;
    let (status, bytes) = call(&app, request).await?;
    let loaded: Value = serde_json::from_slice(&bytes)?;
    assert_eq!(status, StatusCode::OK, "{loaded}");
    let mut socket = tab(addr).await?;
    let finished = run(
        &mut socket,
        &loaded["patient"],
        json!({ "at": [0, 0, 0], "max_steps": 100 }),
    )
    .await?;
    let (status, plan) = post_json(
        &app,
        "/api/cases/save",
        &json!({ "job": finished["job"], "name": "plan", "label": "P17" }),
    )
    .await?;
    assert_eq!(status, StatusCode::OK, "{plan}");
    server.abort();
    Ok((studio, app, plan))
}

/// The Table 2 plane as OBJ text with a marker comment no mesh writer would make: the scan's
/// own bytes are recognisable in the data folder's files.
fn marked_scan(marker: &str) -> Result<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/plane_20cm_65.obj");
    let mut bytes = format!("# {marker}\n").into_bytes();
    bytes.extend(std::fs::read(root)?);
    Ok(bytes)
}

/// Whether any file under `dir` holds `needle`.
fn holds(dir: &Path, needle: &[u8]) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            found.extend(holds(&path, needle)?);
        } else if std::fs::read(&path)?
            .windows(needle.len())
            .any(|w| w == needle)
        {
            found.push(path);
        }
    }
    Ok(found)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn another_site_cannot_erase_unknown_ids_are_404_and_erasure_leaves_no_scan_bytes() -> Result
{
    let data = Data::new("erase");
    let marker = "patient-marker-3f9e1c27ab";
    let (studio, app, plan) = one_plan(&data, &marked_scan(marker)?).await?;
    let patient = plan["patient_uid"].as_str().unwrap_or("").to_owned();
    assert!(
        !holds(data.path(), marker.as_bytes())?.is_empty(),
        "the scan is stored"
    );

    // Another site's page: refused, nothing erased.
    let erase = format!("/api/cases/patients/{patient}/erase");
    for (header, value) in [
        ("origin", "http://evil.example"),
        ("sec-fetch-site", "cross-site"),
    ] {
        let request = Request::post(&erase)
            .header(header, value)
            .body(Body::empty())?;
        let (status, _) = call(&app, request).await?;
        assert_eq!(status, StatusCode::FORBIDDEN, "{header}: {value}");
    }
    let (status, _) = get_json(
        &app,
        &format!("/api/cases/plans/{}", plan["uid"].as_str().unwrap_or("")),
    )
    .await?;
    assert_eq!(status, StatusCode::OK, "still there");

    // Unknown and malformed ids: 404, the id echoed short.
    let unknown_plan = format!("c{}", "0".repeat(32));
    let unknown_patient = format!("p{}", "0".repeat(32));
    let long = "c".repeat(5000);
    for uri in [
        format!("/api/cases/plans/{unknown_plan}"),
        format!("/api/cases/plans/{unknown_plan}/files/report.json"),
        format!("/api/cases/plans/{long}"),
        format!(
            "/api/cases/plans/{}/files/secret.txt",
            plan["uid"].as_str().unwrap_or("")
        ),
        format!("/api/cases/patients/{unknown_patient}/export"),
        format!(
            "/api/cases/compare?a={unknown_plan}&b={}",
            plan["uid"].as_str().unwrap_or("")
        ),
    ] {
        let (status, e) = get_json(&app, &uri).await?;
        assert_eq!(status, StatusCode::NOT_FOUND, "{uri}: {e}");
        assert_eq!(e["error"]["kind"], "not_found", "{e}");
        assert!(
            e["error"]["message"].as_str().unwrap_or("").len() < 300,
            "{e}"
        );
    }
    for uri in [
        format!("/api/cases/patients/{unknown_patient}/erase"),
        format!("/api/cases/plans/{unknown_plan}/delete"),
        format!("/api/cases/patients/{unknown_patient}/open"),
    ] {
        let (status, e) = post_json(&app, &uri, &json!({})).await?;
        assert_eq!(status, StatusCode::NOT_FOUND, "{uri}: {e}");
    }
    let (status, e) = post_json(
        &app,
        "/api/cases/save",
        &json!({ "job": "j1", "name": "x" }),
    )
    .await?;
    assert_eq!(status, StatusCode::NOT_FOUND, "{e}");
    let (status, e) = post_json(&app, "/api/cases/save", &json!({ "name": "x" })).await?;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{e}");

    // The erasure: no byte of the scan in any file of the data folder afterwards.
    let (status, erased) = post_json(&app, &erase, &json!({})).await?;
    assert_eq!(status, StatusCode::OK, "{erased}");
    assert_eq!(erased["plans"], 1);
    let left = holds(data.path(), marker.as_bytes())?;
    assert!(left.is_empty(), "the scan's bytes are still in {left:?}");
    let (_, list) = get_json(&app, "/api/cases/patients").await?;
    assert_eq!(list["patients"].as_array().map(Vec::len), Some(0), "{list}");
    assert_eq!(studio.library().integrity_check()?, "ok");
    studio.shutdown();
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_case_exported_and_imported_into_another_studio_has_the_same_plans() -> Result {
    let (here, there) = (Data::new("export"), Data::new("import"));
    let (studio, app, plan) = one_plan(&here, &marked_scan("export")?).await?;
    let (uid, patient) = (
        plan["uid"].as_str().unwrap_or("").to_owned(),
        plan["patient_uid"].as_str().unwrap_or("").to_owned(),
    );
    let response = app
        .clone()
        .oneshot(Request::get(format!("/api/cases/patients/{patient}/export")).body(Body::empty())?)
        .await?;
    assert_eq!(response.status(), StatusCode::OK);
    let disposition = response
        .headers()
        .get("content-disposition")
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_owned();
    assert!(
        disposition.starts_with("attachment") && disposition.contains(".zip"),
        "{disposition}"
    );
    let zip = response.into_body().collect().await?.to_bytes();
    assert!(zip.starts_with(b"PK"), "a zip");

    let other = Studio::with_data(Limits::default(), there.path())?;
    let other_app = crate::app(&other);
    let upload = |bytes: Vec<u8>, kind: &str| {
        Request::post("/api/cases/import")
            .header("content-type", kind)
            .body(Body::from(bytes))
    };
    // Not as the page sends it: refused before reading (a cross-site form cannot send it).
    let (status, _) = call(&other_app, upload(zip.to_vec(), "text/plain")?).await?;
    assert_eq!(status, StatusCode::UNSUPPORTED_MEDIA_TYPE);
    let (status, bytes) = call(
        &other_app,
        upload(zip.to_vec(), "application/octet-stream")?,
    )
    .await?;
    let summary: Value = serde_json::from_slice(&bytes)?;
    assert_eq!(status, StatusCode::OK, "{summary}");
    assert_eq!(summary["plans_added"], 1, "{summary}");
    assert_eq!(summary["patient"]["label"], "P17");
    // The same plans: the same ids, reports, and files byte for byte.
    let (_, mine) = get_json(&app, "/api/cases/patients").await?;
    let (_, theirs) = get_json(&other_app, "/api/cases/patients").await?;
    assert_eq!(mine["patients"][0]["plans"], theirs["patients"][0]["plans"]);
    for file in FILES {
        let uri = format!("/api/cases/plans/{uid}/files/{file}");
        let (s1, a) = call(&app, Request::get(&uri).body(Body::empty())?).await?;
        let (s2, b) = call(&other_app, Request::get(&uri).body(Body::empty())?).await?;
        assert_eq!((s1, s2), (StatusCode::OK, StatusCode::OK), "{file}");
        assert!(a == b, "{file} differs after the import");
    }
    // Again: nothing added twice.
    let (_, bytes) = call(
        &other_app,
        upload(zip.to_vec(), "application/octet-stream")?,
    )
    .await?;
    let again: Value = serde_json::from_slice(&bytes)?;
    assert_eq!(
        (
            again["plans_added"].as_u64(),
            again["plans_skipped"].as_u64()
        ),
        (Some(0), Some(1)),
        "{again}"
    );

    // Random bytes: 400 with the archive error's message.
    let mut noise = vec![0u8; 4096];
    getrandom_fill(&mut noise);
    let (status, bytes) = call(&other_app, upload(noise, "application/octet-stream")?).await?;
    let e: Value = serde_json::from_slice(&bytes)?;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{e}");
    assert!(
        e["error"]["message"]
            .as_str()
            .unwrap_or("")
            .starts_with("the case archive cannot be imported"),
        "{e}"
    );
    studio.shutdown();
    other.shutdown();
    Ok(())
}

/// Bytes that look random (xorshift, seeded): no zip, no anything.
fn getrandom_fill(out: &mut [u8]) {
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    for b in out {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        *b = (x >> 24) as u8;
    }
}

/// A zip of one `case.json` that inflates to `size` bytes of spaces (a few hundred kB packed).
fn zip_bomb(size: usize) -> Result<Vec<u8>> {
    use std::io::Write;
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .large_file(size > u32::MAX as usize);
    zip.start_file("case.json", options)?;
    let block = vec![b' '; 1 << 20];
    for _ in 0..size / block.len() {
        zip.write_all(&block)?;
    }
    Ok(zip.finish()?.into_inner())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_zip_bomb_is_refused_without_inflating_it() -> Result {
    let data = Data::new("bomb");
    let studio = Studio::with_data(Limits::default(), data.path())?;
    let app = crate::app(&studio);
    let bomb = zip_bomb(1 << 30)?;
    assert!(
        bomb.len() < tissue_studio::UPLOAD_LIMIT,
        "{} bytes packed",
        bomb.len()
    );
    let t0 = Instant::now();
    let request = Request::post("/api/cases/import")
        .header("content-type", "application/octet-stream")
        .body(Body::from(bomb))?;
    let (status, bytes) = call(&app, request).await?;
    let took = t0.elapsed();
    let e: Value = serde_json::from_slice(&bytes)?;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{e}");
    assert_eq!(e["error"]["kind"], "input", "{e}");
    // Inflating 1 GiB and parsing it would take seconds and a gigabyte; a refusal by the
    // declared sizes takes milliseconds.
    assert!(took < Duration::from_secs(3), "{took:?}");
    let (_, list) = get_json(&app, "/api/cases/patients").await?;
    assert_eq!(list["patients"].as_array().map(Vec::len), Some(0));
    // Over the upload limit: refused before reading, as an upload is.
    let request = Request::post("/api/cases/import")
        .header("content-type", "application/octet-stream")
        .header(
            "content-length",
            (tissue_studio::UPLOAD_LIMIT + 1).to_string(),
        )
        .body(Body::from(vec![0u8; tissue_studio::UPLOAD_LIMIT + 1]))?;
    let (status, _) = call(&app, request).await?;
    assert_eq!(status, StatusCode::PAYLOAD_TOO_LARGE);
    studio.shutdown();
    Ok(())
}
