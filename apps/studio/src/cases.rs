//! The Cases routes: the studio's side of the case library (tissue-cases). Each translates one
//! HTTP request into one [`tissue_cases::Library`] call, made off the async threads, and its
//! answer into JSON; nothing about storing is decided here.
//!
//! - `POST /api/cases/save` keeps a finished job (what [`crate::state::KeptJob`] holds) as a plan.
//! - `GET /api/cases/patients?search=`, `GET /api/cases/plans/{uid}` (opened without recomputing:
//!   the report as stored, the patient's mesh and the result's fields as a job's `finished`
//!   message has them), `GET /api/cases/plans/{uid}/files/{file}` (the job's downloads, byte for
//!   byte), `GET /api/cases/compare?a=&b=`.
//! - `POST` rename, note, delete (a plan), rename, erase (a patient), `open` (the stored patient
//!   loaded to plan on), `import` (a case zip); `GET …/export` (the zip).
//!
//! Ids are checked for their form (`p`/`c` and 32 hex digits) before the library sees them, so
//! an id echoed in a message is short; a wrong one is 404 as an unknown one is.

use std::collections::HashMap;
use std::sync::Arc;

use axum::body::Body;
use axum::extract::{Path, Query, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use tissue_cases::{CaseError, FigureRow, NewPlan, PatientInfo, PlanInfo, StoredPlan};
use tissue_planner::{PatientResult, Unit};

use crate::api::{attachment, blocking, patient_answer, read_upload, shorten, ApiError};
use crate::messages::{ErrorKind, Fields};
use crate::state::Studio;

/// The files a stored plan offers (those of its kind: a single run's meshes, an expansion's
/// chart), as a finished job does.
pub const PLAN_FILES: [&str; 5] = crate::api::DOWNLOADS;

/// The longest search text (characters).
const SEARCH_LIMIT: usize = 200;

/// The Cases routes (merged into [`crate::router`], behind its guard).
pub(crate) fn routes() -> Router<Studio> {
    Router::new()
        .route("/api/cases/save", post(save))
        .route("/api/cases/patients", get(patients))
        .route("/api/cases/plans/{uid}", get(open_plan))
        .route("/api/cases/plans/{uid}/files/{file}", get(plan_file))
        .route("/api/cases/plans/{uid}/rename", post(rename_plan))
        .route("/api/cases/plans/{uid}/note", post(note_plan))
        .route("/api/cases/plans/{uid}/delete", post(delete_plan))
        .route("/api/cases/compare", get(compare))
        .route("/api/cases/patients/{uid}/rename", post(rename_patient))
        .route("/api/cases/patients/{uid}/erase", post(erase_patient))
        .route("/api/cases/patients/{uid}/export", get(export))
        .route("/api/cases/patients/{uid}/open", post(open_patient))
        .route("/api/cases/import", post(import))
}

/// The library's error as the page shows it: 404 for an unknown id, 400 for a value or an
/// archive refused, 500 when the library itself failed.
pub(crate) fn case_error(e: &CaseError) -> ApiError {
    let (status, kind, field) = match e {
        CaseError::NotFound { .. } => (StatusCode::NOT_FOUND, ErrorKind::NotFound, None),
        CaseError::Invalid { field, .. } => {
            (StatusCode::BAD_REQUEST, ErrorKind::Usage, Some(*field))
        }
        CaseError::Archive { .. } => (StatusCode::BAD_REQUEST, ErrorKind::Input, None),
        CaseError::Plan(p) => return ApiError::plan(p),
        _ => (StatusCode::INTERNAL_SERVER_ERROR, ErrorKind::Library, None),
    };
    ApiError::with_field(status, kind, field, e.to_string())
}

/// 404 unless `uid` has the form of a library id with `prefix` (`p` patient, `c` plan).
fn check_uid(uid: &str, prefix: char, what: &str) -> Result<(), ApiError> {
    let hex = uid.strip_prefix(prefix).unwrap_or("");
    if hex.len() == 32 && hex.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f')) {
        return Ok(());
    }
    Err(ApiError::new(
        StatusCode::NOT_FOUND,
        ErrorKind::NotFound,
        format!(
            "no {what} {:?} in the case library: its id is {prefix} and 32 hex digits, as the \
             Cases list gives it",
            shorten(uid)
        ),
    ))
}

/// A JSON body, or 400 naming what is wrong with it.
fn body<T>(
    what: &str,
    b: Result<Json<T>, axum::extract::rejection::JsonRejection>,
) -> Result<T, ApiError> {
    b.map(|Json(v)| v).map_err(|e| {
        ApiError::new(
            StatusCode::BAD_REQUEST,
            ErrorKind::Usage,
            format!("the {what} request is not valid: {}", e.body_text()),
        )
    })
}

/// `value` as a JSON response, serialized off the async threads by the caller.
fn json_bytes(value: &impl Serialize) -> Result<Response, ApiError> {
    let bytes = serde_json::to_vec(value).map_err(|e| {
        ApiError::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            ErrorKind::Output,
            format!("cannot write the answer: {e}; report this"),
        )
    })?;
    Ok(([(header::CONTENT_TYPE, "application/json")], bytes).into_response())
}

/// `POST /api/cases/save`: `{job, name, note?, label?}`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SaveRequest {
    job: String,
    name: String,
    #[serde(default)]
    note: String,
    #[serde(default)]
    label: Option<String>,
}

async fn save(
    State(studio): State<Studio>,
    request: Result<Json<SaveRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<PlanInfo>, ApiError> {
    let request = body("save", request)?;
    let kept = studio.kept_job(&request.job).ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            ErrorKind::NotFound,
            format!(
                "no finished job {:?} on the server (it keeps the last few): run it again to save it",
                shorten(&request.job)
            ),
        )
    })?;
    let library = Arc::clone(studio.library());
    blocking(move || {
        let _span = tracing::info_span!("studio_save").entered();
        let label = request
            .label
            .as_deref()
            .unwrap_or(kept.patient.label.as_str());
        let plan = NewPlan {
            name: &request.name,
            note: &request.note,
            spec: &kept.spec,
            finished: &kept.finished,
        };
        library
            .save(&kept.patient.scan, Some(label), plan)
            .map(Json)
            .map_err(|e| case_error(&e))
    })
    .await
}

/// A patient with its plans, newest first.
#[derive(Debug, Serialize)]
struct PatientEntry {
    patient: PatientInfo,
    plans: Vec<PlanInfo>,
}

async fn patients(
    State(studio): State<Studio>,
    Query(query): Query<HashMap<String, String>>,
) -> Result<Response, ApiError> {
    let search = query
        .get("search")
        .map(|s| s.trim().to_owned())
        .filter(|s| !s.is_empty());
    if search
        .as_ref()
        .is_some_and(|s| s.chars().count() > SEARCH_LIMIT)
    {
        return Err(ApiError::with_field(
            StatusCode::BAD_REQUEST,
            ErrorKind::Usage,
            Some("search"),
            format!("a search is at most {SEARCH_LIMIT} characters of a patient's label"),
        ));
    }
    let library = Arc::clone(studio.library());
    blocking(move || {
        let list = library
            .patients(search.as_deref())
            .map_err(|e| case_error(&e))?;
        let mut entries = Vec::with_capacity(list.len());
        for patient in list {
            let plans = library.plans(&patient.uid).map_err(|e| case_error(&e))?;
            entries.push(PatientEntry { patient, plans });
        }
        json_bytes(&json!({ "patients": entries }))
    })
    .await
}

/// A mesh for the page: positions (cm, flat xyz) and triangles (flat indices).
#[derive(Debug, Serialize)]
struct MeshJson {
    positions: Vec<f32>,
    triangles: Vec<u32>,
}

impl MeshJson {
    /// The patient before a result, in cm (as `/api/patients` sends a patient).
    fn before_cm(result: &PatientResult, scale: f32) -> MeshJson {
        MeshJson {
            positions: result
                .before
                .positions()
                .iter()
                .flat_map(|&p| (if scale == 1.0 { p } else { p * scale }).to_array())
                .collect(),
            triangles: result
                .before
                .triangles()
                .iter()
                .flatten()
                .copied()
                .collect(),
        }
    }

    fn of_cm(positions: &[glam::Vec3], triangles: &[[u32; 3]]) -> MeshJson {
        MeshJson {
            positions: positions.iter().flat_map(|p| p.to_array()).collect(),
            triangles: triangles.iter().flatten().copied().collect(),
        }
    }
}

/// The scan's unit of a stored patient, and cm per unit.
fn unit_of(patient: &PatientInfo) -> Result<Unit, ApiError> {
    Unit::from_symbol(&patient.unit).ok_or_else(|| {
        case_error(&CaseError::Damaged {
            what: format!("patient {}", patient.uid),
            message: format!(
                "unit {:?} is not one of mm, cm, dm, m",
                shorten(&patient.unit)
            ),
        })
    })
}

/// The files plan `stored` offers.
fn files_of(stored: &StoredPlan) -> Vec<&'static str> {
    PLAN_FILES
        .into_iter()
        .filter(|f| match *f {
            "report.json" => true,
            "chart.png" => stored.chart_png.is_some(),
            _ => stored.result.is_some(),
        })
        .collect()
}

/// `GET /api/cases/plans/{uid}`: the plan opened, as the page shows it at once.
#[derive(Debug, Serialize)]
struct OpenedPlan {
    plan: PlanInfo,
    patient: PatientInfo,
    unit: &'static str,
    cm_per_unit: f32,
    /// The report (the stored text, parsed); the text itself is `files/report.json`.
    report: Value,
    /// The job as it was asked.
    job: Value,
    /// The patient (cm), when the plan has a result on it.
    mesh: Option<MeshJson>,
    /// The result's fields as the job's `finished` message had them.
    fields: Option<Fields>,
    /// The files it offers (`files/{file}`).
    files: Vec<&'static str>,
}

/// Plan `uid` opened and its JSON answer: library read and JSON, the whole of what the page
/// gets (the bench measures this).
fn opened(studio: &Studio, uid: &str) -> Result<Response, ApiError> {
    let _span = tracing::info_span!("studio_open_plan").entered();
    let stored = studio
        .library()
        .open_plan(uid)
        .map_err(|e| case_error(&e))?;
    let unit = unit_of(&stored.patient)?;
    let scale = unit.cm_per_unit();
    let parse = |what: &str, text: &str| {
        serde_json::from_str::<Value>(text).map_err(|e| {
            case_error(&CaseError::Damaged {
                what: format!("plan {uid}'s {what}"),
                message: e.to_string(),
            })
        })
    };
    let answer = OpenedPlan {
        report: parse("report", &stored.report_json)?,
        job: parse("job", &stored.job_json)?,
        mesh: stored
            .result
            .as_ref()
            .map(|r| MeshJson::before_cm(r, scale)),
        fields: stored.result.as_ref().map(|r| Fields::of(r, scale)),
        files: files_of(&stored),
        unit: unit.symbol(),
        cm_per_unit: scale,
        plan: stored.info,
        patient: stored.patient,
    };
    json_bytes(&answer)
}

async fn open_plan(
    State(studio): State<Studio>,
    Path(uid): Path<String>,
) -> Result<Response, ApiError> {
    check_uid(&uid, 'c', "plan")?;
    blocking(move || opened(&studio, &uid)).await
}

async fn plan_file(
    State(studio): State<Studio>,
    Path((uid, file)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    check_uid(&uid, 'c', "plan")?;
    if !PLAN_FILES.contains(&file.as_str()) {
        return Err(ApiError::new(
            StatusCode::NOT_FOUND,
            ErrorKind::NotFound,
            format!(
                "no file {:?}: a plan offers {}",
                shorten(&file),
                PLAN_FILES.join(", ")
            ),
        ));
    }
    let name = format!("{uid}-{file}");
    let bytes = blocking(move || {
        let stored = studio
            .library()
            .open_plan(&uid)
            .map_err(|e| case_error(&e))?;
        let missing = || {
            ApiError::new(
                StatusCode::NOT_FOUND,
                ErrorKind::NotFound,
                format!(
                    "plan {uid} has no {file} (a series or a search has the report only, an \
                     expansion the report and chart.png)"
                ),
            )
        };
        match file.as_str() {
            "report.json" => Ok(stored.report_json.into_bytes()),
            "chart.png" => stored.chart_png.ok_or_else(missing),
            _ => {
                let result = stored.result.as_ref().ok_or_else(missing)?;
                mesh_file(&studio, result, &file)
            }
        }
    })
    .await?;
    Ok(attachment(&name, bytes))
}

/// A stored result written as `file` (`patient.ply`, …) by the call that wrote the job's
/// download, through a transient file in the temporary folder (removed at once).
fn mesh_file(studio: &Studio, result: &PatientResult, file: &str) -> Result<Vec<u8>, ApiError> {
    let path = studio
        .temp_dir()
        .join(format!("{}-{file}", crate::state::new_id("f")));
    let written = result.write_mesh(&path).map_err(|e| ApiError::plan(&e));
    let bytes = written.and_then(|()| {
        std::fs::read(&path).map_err(|e| {
            ApiError::new(
                StatusCode::INTERNAL_SERVER_ERROR,
                ErrorKind::Output,
                format!("cannot read back {file}: {e}"),
            )
        })
    });
    let _ = std::fs::remove_file(&path);
    bytes
}

/// `GET /api/cases/compare?a=&b=`: the figures side by side, the difference map, and what the
/// view draws it on.
#[derive(Debug, Serialize)]
struct Compared {
    a: PlanInfo,
    b: PlanInfo,
    patient: PatientInfo,
    unit: &'static str,
    cm_per_unit: f32,
    figures: Vec<FigureRow>,
    /// Per vertex |after_B − after_A|, the scan's unit (empty unless both are single runs).
    difference: Vec<f32>,
    max_difference: f32,
    /// The patient (cm).
    mesh: MeshJson,
    /// Each plan's patient after (cm, flat xyz), when it has a result.
    after_a: Option<Vec<f32>>,
    after_b: Option<Vec<f32>>,
}

async fn compare(
    State(studio): State<Studio>,
    Query(query): Query<HashMap<String, String>>,
) -> Result<Response, ApiError> {
    let get = |k: &str| query.get(k).cloned().unwrap_or_default();
    let (a, b) = (get("a"), get("b"));
    check_uid(&a, 'c', "plan")?;
    check_uid(&b, 'c', "plan")?;
    blocking(move || {
        let _span = tracing::info_span!("studio_compare").entered();
        let library = studio.library();
        let c = library.compare(&a, &b).map_err(|e| case_error(&e))?;
        let (pa, pb) = (
            library.open_plan(&a).map_err(|e| case_error(&e))?,
            library.open_plan(&b).map_err(|e| case_error(&e))?,
        );
        let unit = unit_of(&pb.patient)?;
        let scale = unit.cm_per_unit();
        let mesh = match pb.result.as_ref().or(pa.result.as_ref()) {
            Some(r) => MeshJson::before_cm(r, scale),
            None => {
                let p = library
                    .load_patient(&pb.patient.uid)
                    .map_err(|e| case_error(&e))?;
                MeshJson::of_cm(p.cm.positions(), p.cm.triangles())
            }
        };
        let after = |p: &StoredPlan| p.result.as_ref().map(|r| Fields::of(r, scale).after);
        json_bytes(&Compared {
            after_a: after(&pa),
            after_b: after(&pb),
            a: c.a,
            b: c.b,
            patient: pb.patient,
            unit: unit.symbol(),
            cm_per_unit: scale,
            figures: c.figures,
            difference: c.difference,
            max_difference: c.max_difference,
            mesh,
        })
    })
    .await
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct NameRequest {
    name: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct NoteRequest {
    note: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LabelRequest {
    label: String,
}

async fn rename_plan(
    State(studio): State<Studio>,
    Path(uid): Path<String>,
    request: Result<Json<NameRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<PlanInfo>, ApiError> {
    check_uid(&uid, 'c', "plan")?;
    let request = body("rename", request)?;
    let library = Arc::clone(studio.library());
    blocking(move || {
        library
            .rename_plan(&uid, &request.name)
            .map(Json)
            .map_err(|e| case_error(&e))
    })
    .await
}

async fn note_plan(
    State(studio): State<Studio>,
    Path(uid): Path<String>,
    request: Result<Json<NoteRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<PlanInfo>, ApiError> {
    check_uid(&uid, 'c', "plan")?;
    let request = body("note", request)?;
    let library = Arc::clone(studio.library());
    blocking(move || {
        library
            .set_note(&uid, &request.note)
            .map(Json)
            .map_err(|e| case_error(&e))
    })
    .await
}

async fn delete_plan(
    State(studio): State<Studio>,
    Path(uid): Path<String>,
) -> Result<Json<Value>, ApiError> {
    check_uid(&uid, 'c', "plan")?;
    let library = Arc::clone(studio.library());
    blocking(move || {
        library.delete_plan(&uid).map_err(|e| case_error(&e))?;
        Ok(Json(json!({ "deleted": uid })))
    })
    .await
}

async fn rename_patient(
    State(studio): State<Studio>,
    Path(uid): Path<String>,
    request: Result<Json<LabelRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<PatientInfo>, ApiError> {
    check_uid(&uid, 'p', "patient")?;
    let request = body("rename", request)?;
    let library = Arc::clone(studio.library());
    blocking(move || {
        library
            .rename_patient(&uid, &request.label)
            .map(Json)
            .map_err(|e| case_error(&e))
    })
    .await
}

/// Erases the patient from the library (no trace in its files) and forgets it in the studio
/// too: the loaded patients and finished jobs of the same scan, with their folders.
async fn erase_patient(
    State(studio): State<Studio>,
    Path(uid): Path<String>,
) -> Result<Json<Value>, ApiError> {
    check_uid(&uid, 'p', "patient")?;
    blocking(move || {
        let _span = tracing::info_span!("studio_erase").entered();
        let library = studio.library();
        let info = library.patient(&uid).map_err(|e| case_error(&e))?;
        library.erase_patient(&uid).map_err(|e| case_error(&e))?;
        let forgotten = studio.forget_scan(&info.scan_sha256, info.scan_bytes);
        Ok(Json(json!({
            "erased": uid, "plans": info.plans, "forgotten_in_studio": forgotten,
        })))
    })
    .await
}

async fn export(
    State(studio): State<Studio>,
    Path(uid): Path<String>,
) -> Result<Response, ApiError> {
    check_uid(&uid, 'p', "patient")?;
    let name = format!("case-{uid}.zip");
    let library = Arc::clone(studio.library());
    let zip = blocking(move || library.export_case(&uid).map_err(|e| case_error(&e))).await?;
    Ok(attachment(&name, zip))
}

async fn import(
    State(studio): State<Studio>,
    headers: HeaderMap,
    body: Body,
) -> Result<Json<tissue_cases::ImportSummary>, ApiError> {
    let (bytes, slot) = read_upload(&studio, &headers, body, "the case archive").await?;
    if bytes.is_empty() {
        return Err(ApiError::new(
            StatusCode::BAD_REQUEST,
            ErrorKind::Input,
            "the case archive is empty: pick the .zip a studio's Export gave",
        ));
    }
    let library = Arc::clone(studio.library());
    blocking(move || {
        let _span = tracing::info_span!("studio_import").entered();
        let summary = library.import_case(&bytes).map_err(|e| case_error(&e));
        drop(slot);
        summary.map(Json)
    })
    .await
}

/// Loads stored patient `uid` into the studio to plan on; answers as `POST /api/patients` does,
/// plus `case_patient` (the library's id).
async fn open_patient(
    State(studio): State<Studio>,
    Path(uid): Path<String>,
) -> Result<Json<Value>, ApiError> {
    check_uid(&uid, 'p', "patient")?;
    blocking(move || {
        let _span = tracing::info_span!("studio_open_patient").entered();
        let library = studio.library();
        let info = library.patient(&uid).map_err(|e| case_error(&e))?;
        let mut patient = library.load_patient(&uid).map_err(|e| case_error(&e))?;
        let scan = library.scan(&uid).map_err(|e| case_error(&e))?;
        patient.label.clone_from(&info.label);
        let mut answer = patient_answer(&studio, patient, scan, info.label, None);
        answer["case_patient"] = json!(uid);
        Ok(Json(answer))
    })
    .await
}
