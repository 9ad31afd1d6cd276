//! The routes: pages, static files, patients, the placement preview, downloads, and the job
//! socket ([`crate::jobs`]).

use std::collections::HashMap;
use std::sync::Arc;

use axum::body::{Body, Bytes};
use axum::extract::{Path, Query, State, WebSocketUpgrade};
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::{Deserialize, Serialize};
use serde_json::json;
use tissue_planner::{
    ErrorKind as PlanKind, Patient, PlanError, PlanRequest, Scenario, Shipped, Unit,
};
use tissue_scenes::{Organ, ShippedOrgan, TissuePreset};

use crate::access::{self, Access};
use crate::assets;
use crate::messages::{ErrorBody, ErrorKind};
use crate::serve::BodyTimeout;
use crate::state::{Studio, UPLOAD_LIMIT};

/// The largest WebSocket message or frame either socket takes (the page's largest, a scalpel
/// path, is a few kB).
pub const MESSAGE_LIMIT: usize = 1024 * 1024;

/// The studio's routes over `studio`, for the clients `access` lets in: every request passes
/// [`access::guard`] (Host, Origin, token) and every response gets the security headers.
pub fn router(studio: Studio, access: Access) -> Router {
    Router::new()
        .route("/", get(|| async { assets::serve("index.html") }))
        .route("/planner", get(|| async { assets::serve("planner.html") }))
        .route("/trainer", get(|| async { assets::serve("trainer.html") }))
        .route("/cases", get(|| async { assets::serve("cases.html") }))
        .route("/api/organs", get(organs).post(upload_organ))
        .route("/api/tissues", get(tissues))
        .route("/api/trainer/ws", get(trainer_socket))
        .route("/static/{*path}", get(static_file))
        .route("/api/meshes", get(meshes))
        .route("/api/patients", post(upload))
        .route("/api/preview", post(preview))
        .route("/api/results/{job}/{file}", get(download))
        .route("/api/ws", get(socket))
        .merge(crate::cases::routes())
        .fallback(|| async {
            ApiError::new(StatusCode::NOT_FOUND, ErrorKind::NotFound, "no such page")
        })
        .with_state(studio)
        .layer(axum::middleware::from_fn_with_state(
            Arc::new(access),
            access::guard,
        ))
        .layer(axum::middleware::from_fn(access::headers))
}

/// An error as the page shows it: `{"error": {kind, field, message}}` with an HTTP status.
#[derive(Debug)]
pub struct ApiError {
    status: StatusCode,
    body: ErrorBody,
}

impl ApiError {
    /// An error of `kind` with `status`.
    pub fn new(status: StatusCode, kind: ErrorKind, message: impl Into<String>) -> ApiError {
        ApiError {
            status,
            body: ErrorBody::new(kind, message),
        }
    }

    /// An error of `kind` with `status` about request field `field`.
    pub fn with_field(
        status: StatusCode,
        kind: ErrorKind,
        field: Option<&str>,
        message: impl Into<String>,
    ) -> ApiError {
        let mut body = ErrorBody::new(kind, message);
        body.field = field.map(str::to_owned);
        ApiError { status, body }
    }

    /// The planner's error with its status (500 for a run or output failure, else 400).
    pub(crate) fn plan(e: &PlanError) -> ApiError {
        let status = match e.kind {
            PlanKind::Run | PlanKind::Output => StatusCode::INTERNAL_SERVER_ERROR,
            _ => StatusCode::BAD_REQUEST,
        };
        ApiError {
            status,
            body: ErrorBody::of(e),
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.status, Json(json!({ "error": self.body }))).into_response()
    }
}

async fn organs() -> Json<Vec<serde_json::Value>> {
    Json(
        ShippedOrgan::ALL
            .iter()
            .map(|&o| json!({ "id": o.id(), "label": o.label(), "default": o == ShippedOrgan::Bunny }))
            .collect(),
    )
}

/// The tissue presets the trainer's Tissue panel offers: their constants and sources.
async fn tissues() -> Json<Vec<serde_json::Value>> {
    Json(
        TissuePreset::ALL
            .iter()
            .map(|&t| {
                json!({
                    "id": t.id(), "label": crate::material::preset_label(t),
                    "young_kpa": t.young_kpa(), "poisson": t.poisson(), "density": t.density(),
                    "source": t.source(),
                })
            })
            .collect(),
    )
}

async fn upload_organ(
    State(studio): State<Studio>,
    Query(query): Query<HashMap<String, String>>,
    headers: HeaderMap,
    body: Body,
) -> Result<Json<serde_json::Value>, ApiError> {
    let (name, unit) = name_and_unit(&query)?;
    let (bytes, _slot) = read_upload(&studio, &headers, body, &name).await?;
    let organ = blocking(move || {
        Organ::from_bytes(&bytes, &name, unit.cm_per_unit())
            .map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, ErrorKind::Mesh, e.to_string()))
    })
    .await?;
    let reply = json!({
        "label": organ.label, "nodes": organ.mesh.vertex_count(), "tets": organ.mesh.tets().len(),
    });
    let id = studio.organs().add(organ);
    let mut reply = reply;
    reply["organ"] = json!(id);
    Ok(Json(reply))
}

/// An upload's `?name=` (its extension picks the format) and `?unit=` (cm when not given).
fn name_and_unit(query: &HashMap<String, String>) -> Result<(String, Unit), ApiError> {
    let name = query.get("name").cloned().ok_or_else(|| {
        ApiError::new(
            StatusCode::BAD_REQUEST,
            ErrorKind::Usage,
            "an upload needs ?name=FILE (its extension picks the format) and ?unit=",
        )
    })?;
    let symbol = query.get("unit").map_or("cm", String::as_str);
    let unit = Unit::from_symbol(symbol).ok_or_else(|| {
        ApiError::new(
            StatusCode::BAD_REQUEST,
            ErrorKind::Usage,
            format!("unit {symbol:?} is not one of mm, cm, dm, m"),
        )
    })?;
    Ok((name, unit))
}

/// An upload's bytes, read once its content type is the page's and a place among
/// [`crate::Limits::uploads`] is free (the place is held until the returned permit drops, so
/// the parsing counts too). Bounded by [`UPLOAD_LIMIT`] and the body's deadlines.
pub(crate) async fn read_upload(
    studio: &Studio,
    headers: &HeaderMap,
    body: Body,
    name: &str,
) -> Result<(Bytes, tokio::sync::OwnedSemaphorePermit), ApiError> {
    let kind = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("");
    if !kind
        .trim()
        .to_ascii_lowercase()
        .starts_with("application/octet-stream")
    {
        return Err(ApiError::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            ErrorKind::Usage,
            format!(
                "an upload is sent as application/octet-stream (as the studio's page does), not \
                 {kind:?}"
            ),
        ));
    }
    let declared = headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<u64>().ok());
    if declared.is_some_and(|n| n > UPLOAD_LIMIT as u64) {
        return Err(too_large(name));
    }
    let slot = studio.upload_slot().ok_or_else(|| {
        ApiError::new(
            StatusCode::SERVICE_UNAVAILABLE,
            ErrorKind::Busy,
            format!(
                "{} uploads are being read already: try again when one has finished",
                studio.limits().uploads
            ),
        )
    })?;
    let bytes = axum::body::to_bytes(body, UPLOAD_LIMIT)
        .await
        .map_err(|e| body_error(name, &e))?;
    Ok((bytes, slot))
}

fn too_large(name: &str) -> ApiError {
    ApiError::new(
        StatusCode::PAYLOAD_TOO_LARGE,
        ErrorKind::TooLarge,
        format!(
            "{name} is larger than the upload limit of {} MiB; decimate the scan or crop it to \
             the region of interest",
            UPLOAD_LIMIT / (1024 * 1024)
        ),
    )
}

/// A body that could not be read: too large (413), too slow (408), or broken off (400).
fn body_error(name: &str, e: &axum::Error) -> ApiError {
    let mut source: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(s) = source {
        if let Some(t) = s.downcast_ref::<BodyTimeout>() {
            return ApiError::new(
                StatusCode::REQUEST_TIMEOUT,
                ErrorKind::Timeout,
                format!("{name}: {t}; send it again"),
            );
        }
        if s.is::<http_body_util::LengthLimitError>() {
            return too_large(name);
        }
        source = s.source();
    }
    ApiError::new(
        StatusCode::BAD_REQUEST,
        ErrorKind::Input,
        format!("{name}: the upload broke off ({e}); send it again"),
    )
}

async fn trainer_socket(State(studio): State<Studio>, ws: WebSocketUpgrade) -> Response {
    ws.max_message_size(MESSAGE_LIMIT)
        .max_frame_size(MESSAGE_LIMIT)
        .on_upgrade(move |socket| crate::trainer::serve_socket(studio, socket))
}

async fn static_file(Path(path): Path<String>) -> Response {
    assets::serve(&path)
}

#[derive(Debug, Serialize)]
struct MeshEntry {
    id: &'static str,
    label: &'static str,
    unit: &'static str,
    default: bool,
}

async fn meshes() -> Json<Vec<MeshEntry>> {
    Json(
        Shipped::ALL
            .iter()
            .map(|&s| MeshEntry {
                id: s.id(),
                label: s.label(),
                unit: s.unit().symbol(),
                default: s == Shipped::Table2,
            })
            .collect(),
    )
}

/// Runs `f` off the async threads (loading, remeshing and the set-up take seconds on a scan).
pub(crate) async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f).await.unwrap_or_else(|e| {
        Err(ApiError::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            ErrorKind::Run,
            format!("the server's task failed: {e}; report this"),
        ))
    })
}

async fn upload(
    State(studio): State<Studio>,
    Query(query): Query<HashMap<String, String>>,
    headers: HeaderMap,
    body: Body,
) -> Result<Json<serde_json::Value>, ApiError> {
    let mut _slot = None;
    let source = if let Some(id) = query.get("shipped") {
        let shipped = Shipped::from_id(id).ok_or_else(|| {
            ApiError::new(
                StatusCode::BAD_REQUEST,
                ErrorKind::Input,
                format!("no shipped mesh {id:?}: pick table2, chest or head"),
            )
        })?;
        Source::Shipped(shipped)
    } else {
        let (name, unit) = name_and_unit(&query)?;
        let (bytes, slot) = read_upload(&studio, &headers, body, &name).await?;
        _slot = Some(slot);
        if bytes.is_empty() {
            return Err(ApiError::new(
                StatusCode::BAD_REQUEST,
                ErrorKind::Input,
                format!("{name} is empty: pick the scan file again"),
            ));
        }
        Source::Upload { name, unit, bytes }
    };
    let (patient, scan, label, suggested) = blocking(move || {
        let _span = tracing::info_span!("studio_load").entered();
        match source {
            Source::Shipped(s) => {
                let p = Patient::shipped(s).map_err(|e| ApiError::plan(&e))?;
                let v = s.suggested_vertex(&p.cm);
                let scan = tissue_cases::Scan::of_mesh(&p, s.id())
                    .map_err(|e| crate::cases::case_error(&e))?;
                Ok((p, scan, s.label().to_owned(), Some(v)))
            }
            Source::Upload { name, unit, bytes } => {
                let p = Patient::parse(&bytes, &name, unit).map_err(|e| ApiError::plan(&e))?;
                let scan = tissue_cases::Scan {
                    name: name.clone(),
                    unit,
                    bytes: bytes.to_vec(),
                };
                Ok((p, scan, name, None))
            }
        }
    })
    .await?;
    Ok(Json(patient_answer(
        &studio, patient, scan, label, suggested,
    )))
}

/// Keeps `patient` (with its `scan` and its `label` in the case library) and gives the `/api/patients` answer: its id, label, unit,
/// summary, mesh (cm) and the suggested placement.
pub(crate) fn patient_answer(
    studio: &Studio,
    patient: Patient,
    scan: tissue_cases::Scan,
    case_label: String,
    suggested: Option<u32>,
) -> serde_json::Value {
    let summary = patient.summary();
    let positions: Vec<f32> = patient
        .cm
        .positions()
        .iter()
        .flat_map(|p| p.to_array())
        .collect();
    let triangles: Vec<u32> = patient.cm.triangles().iter().flatten().copied().collect();
    let suggested = suggested
        .map(|v| json!({ "vertex": v, "point": patient.cm.positions()[v as usize].to_array() }));
    let label = patient.label.clone();
    let unit = patient.unit;
    let id = studio.add_patient(patient, scan, case_label);
    json!({
        "patient": id,
        "label": label,
        "unit": unit.symbol(),
        "cm_per_unit": unit.cm_per_unit(),
        "summary": summary,
        "mesh": { "positions": positions, "triangles": triangles },
        "suggested": suggested,
    })
}

enum Source {
    Shipped(Shipped),
    Upload {
        name: String,
        unit: Unit,
        bytes: Bytes,
    },
}

/// A request for a job or a preview: the patient's id and the planning request.
#[derive(Debug, Deserialize)]
pub struct PatientRequest {
    /// The patient's id from `/api/patients`.
    pub patient: String,
    /// What to plan.
    #[serde(default)]
    pub request: PlanRequest,
}

/// The patient `patient` the studio holds, or why not.
pub fn loaded(studio: &Studio, patient: &str) -> Result<Arc<crate::state::Loaded>, PlanError> {
    studio.patient(patient).ok_or_else(|| {
        PlanError::new(
            PlanKind::Usage,
            format!(
                "no patient {:?} on the server (it keeps the last few): load it again",
                shorten(patient)
            ),
        )
    })
}

/// The scenario of `patient` and `request`, or why not.
pub fn scenario(
    studio: &Studio,
    patient: &str,
    request: PlanRequest,
) -> Result<Scenario, PlanError> {
    let p = loaded(studio, patient)?;
    Scenario::new(Patient::clone(&p.patient), request)
}

/// `text` cut to 40 characters (an id echoed back in a message: a client may send megabytes).
pub(crate) fn shorten(text: &str) -> String {
    match text.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &text[..i]),
        None => text.to_owned(),
    }
}

async fn preview(
    State(studio): State<Studio>,
    body: Result<Json<PatientRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<serde_json::Value>, ApiError> {
    let Json(body) = body.map_err(|e| {
        ApiError::new(
            StatusCode::BAD_REQUEST,
            ErrorKind::Usage,
            format!("the placement request is not valid: {}", e.body_text()),
        )
    })?;
    let vertex = body.request.vertex;
    blocking(move || {
        let _span = tracing::info_span!("studio_preview").entered();
        let s = match scenario(&studio, &body.patient, body.request) {
            Ok(s) => s,
            Err(e) => {
                return Ok(Json(json!({
                    "ok": false, "error": ErrorBody::of(&e), "placement": null,
                    "footprint": [], "region_outline": [],
                })))
            }
        };
        let p = s.preview();
        Ok(Json(json!({
            "ok": p.ok,
            "error": p.error.as_ref().map(ErrorBody::of),
            "placement": {
                "point": s.point.to_array(),
                "vertex": vertex,
                "surface_point": s.surface_point.to_array(),
                "normal": s.normal.to_array(),
                "tangent": s.tangent.to_array(),
            },
            "footprint": p.footprint,
            "region_outline": p.region_outline,
            "region_radius_cm": p.region_radius_cm,
            "sim_edge_cm": p.sim_edge_cm,
            "region_vertices": p.region_vertices,
        })))
    })
    .await
}

/// The files a finished job offers.
pub const DOWNLOADS: [&str; 5] = [
    "patient.ply",
    "patient.obj",
    "patient.vtk",
    "report.json",
    "chart.png",
];

async fn download(
    State(studio): State<Studio>,
    Path((job, file)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    if !DOWNLOADS.contains(&file.as_str()) {
        return Err(ApiError::new(
            StatusCode::NOT_FOUND,
            ErrorKind::NotFound,
            format!(
                "no download {file:?}: a job offers {}",
                DOWNLOADS.join(", ")
            ),
        ));
    }
    let dir = studio.finished_dir(&job).ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            ErrorKind::NotFound,
            format!("no finished job {job:?} (the server keeps the last few): run it again"),
        )
    })?;
    let bytes = tokio::fs::read(dir.join(&file)).await.map_err(|_| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            ErrorKind::NotFound,
            format!("job {job} has no {file} (a sweep or a search has the report only, an expansion the report and chart.png)"),
        )
    })?;
    Ok(attachment(&format!("{job}-{file}"), bytes))
}

/// `bytes` as a download named `name` (its extension gives the content type). `name` is made of
/// checked ids and known file names only.
pub(crate) fn attachment(name: &str, bytes: Vec<u8>) -> Response {
    let mime = mime_guess::from_path(name).first_or_octet_stream();
    (
        [
            (header::CONTENT_TYPE, mime.as_ref().to_owned()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"{name}\""),
            ),
        ],
        bytes,
    )
        .into_response()
}

async fn socket(State(studio): State<Studio>, ws: WebSocketUpgrade) -> Response {
    let Some(slot) = studio.socket_slot() else {
        return ApiError::new(
            StatusCode::SERVICE_UNAVAILABLE,
            ErrorKind::Busy,
            format!(
                "{} job sockets are open on this server: close some of its tabs",
                crate::state::JOB_SOCKETS
            ),
        )
        .into_response();
    };
    ws.max_message_size(MESSAGE_LIMIT)
        .max_frame_size(MESSAGE_LIMIT)
        .on_upgrade(move |socket| async move {
            crate::jobs::serve_socket(studio, socket).await;
            drop(slot);
        })
}
