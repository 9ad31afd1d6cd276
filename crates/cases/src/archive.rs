//! A case as one zip (deflate): export and import.
//!
//! The archive holds `case.json` (format [`FORMAT`], version [`FORMAT_VERSION`]: the patient,
//! each plan, and the SHA-256 and size of every other file), `scan/<file>` (the scan's bytes
//! as stored), and per plan `plans/<uid>/job.json`, `report.json`, for a single run
//! `result.bin` (the stored result blob) with `patient.ply` and `patient.vtk` (for people;
//! ignored on import), and an expansion's `chart.png`.
//!
//! An import trusts nothing in the archive: its size, entry count and every entry's size are
//! bounded (read through `take`, whatever the headers say), every file's hash is checked
//! against `case.json`, the scan is parsed again and each result checked against its vertex
//! count, all before one transaction writes anything.

use std::collections::BTreeMap;
use std::io::{Cursor, Read, Write};

use serde::{Deserialize, Serialize};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipArchive, ZipWriter};

use crate::blob::{self, sha256_hex};
use crate::store::{self, check_name, check_note, is_uid, NewPlanRow, ReportFigures};
use crate::{db, CaseError, ImportSummary, Library, Scan};

/// `case.json`'s format name.
pub const FORMAT: &str = "tissue-case";
/// `case.json`'s format version.
pub const FORMAT_VERSION: u32 = 1;
/// The largest archive imported (bytes).
pub const MAX_ARCHIVE_BYTES: u64 = 512 << 20;
/// The most entries an archive may have.
pub const MAX_ARCHIVE_ENTRIES: usize = 10_000;
/// The largest entry, uncompressed (bytes).
pub const MAX_ENTRY_BYTES: u64 = 256 << 20;
/// The largest total of all entries, uncompressed (bytes).
pub const MAX_TOTAL_BYTES: u64 = 1 << 30;

/// A file's hash and size in `case.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct FileEntry {
    sha256: String,
    size: u64,
}

/// The patient in `case.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct CasePatient {
    uid: String,
    label: String,
    unit: String,
    scan_name: String,
    /// The scan's entry in the archive (`scan/` and the name made safe for a path).
    scan_file: String,
    scan_sha256: String,
    scan_bytes: u64,
    summary: serde_json::Value,
    added_at: String,
}

/// A plan in `case.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct CasePlan {
    uid: String,
    name: String,
    note: String,
    mode: String,
    tool: String,
    solver: String,
    library_version: String,
    run_at: String,
    area_gain_cm2: Option<f64>,
    volume_cm3: Option<f64>,
    has_result: bool,
    has_chart: bool,
}

/// `case.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct CaseJson {
    format: String,
    format_version: u32,
    patient: CasePatient,
    plans: Vec<CasePlan>,
    files: BTreeMap<String, FileEntry>,
}

fn refuse(message: impl Into<String>) -> CaseError {
    CaseError::Archive {
        message: message.into(),
    }
}

/// A file name safe as one path component in the archive.
fn safe_component(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_control() || matches!(c, '/' | '\\' | ':') {
                '_'
            } else {
                c
            }
        })
        .collect();
    match s.trim() {
        "" | "." | ".." => "scan".to_owned(),
        t => t.to_owned(),
    }
}

/// Exports patient `uid`'s case.
pub(crate) fn export(lib: &Library, uid: &str) -> Result<Vec<u8>, CaseError> {
    let _span = tracing::info_span!("cases_export").entered();
    // Everything read in one read transaction: the case as of one moment.
    let (patient, scan_bytes, plans) = {
        let mut conn = lib.lock();
        let tx = conn.transaction().map_err(db("exporting a case"))?;
        let patient = store::patient_info(&tx, uid)?;
        let row = store::patient_row(&tx, uid)?;
        let scan = store::blob(&tx, &row.scan_blob, "the patient's scan")?;
        let mut plans = Vec::new();
        // Oldest first, so that an import lists them as here.
        let mut infos = store::plans_of(&tx, row.id)?;
        infos.reverse();
        for info in infos {
            plans.push(store::stored_plan(&tx, &info.uid)?);
        }
        tx.finish().map_err(db("exporting a case"))?;
        (patient, scan, plans)
    };
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    let scan_file = format!("scan/{}", safe_component(&patient.scan_name));
    files.push((scan_file.clone(), scan_bytes));
    let tmp = crate::temp::TempDir::new_in(lib.dir()).map_err(|source| CaseError::Write {
        path: lib.dir().to_path_buf(),
        source,
    })?;
    let mut case_plans = Vec::new();
    for p in plans {
        let dir = format!("plans/{}", p.info.uid);
        files.push((format!("{dir}/job.json"), p.job.into_bytes()));
        files.push((format!("{dir}/report.json"), p.report.into_bytes()));
        if let (Some(result), Some(mesh)) = (&p.result, &p.mesh) {
            let what = format!("plan {}'s result", p.info.uid);
            let before = blob::decode_mesh(mesh, &what)?;
            let data = blob::decode_result(result, before.positions().len(), &what)?;
            let rebuilt = blob::rebuild_result(&before, data, p.unit.cm_per_unit(), &what)?;
            for ext in ["ply", "vtk"] {
                let path = tmp.path().join(format!("patient.{ext}"));
                rebuilt.write_mesh(&path)?;
                let bytes = std::fs::read(&path).map_err(|source| CaseError::Write {
                    path: path.clone(),
                    source,
                })?;
                files.push((format!("{dir}/patient.{ext}"), bytes));
            }
            files.push((format!("{dir}/result.bin"), result.clone()));
        }
        if let Some(chart) = &p.chart {
            files.push((format!("{dir}/chart.png"), chart.clone()));
        }
        let i = p.info;
        case_plans.push(CasePlan {
            has_result: p.result.is_some(),
            has_chart: p.chart.is_some(),
            uid: i.uid,
            name: i.name,
            note: i.note,
            mode: i.mode,
            tool: i.tool,
            solver: i.solver,
            library_version: i.library_version,
            run_at: i.run_at,
            area_gain_cm2: i.area_gain_cm2,
            volume_cm3: i.volume_cm3,
        });
    }
    let case = CaseJson {
        format: FORMAT.to_owned(),
        format_version: FORMAT_VERSION,
        patient: CasePatient {
            uid: patient.uid,
            label: patient.label,
            unit: patient.unit,
            scan_name: patient.scan_name,
            scan_file,
            scan_sha256: patient.scan_sha256,
            scan_bytes: patient.scan_bytes,
            summary: patient.summary,
            added_at: patient.added_at,
        },
        plans: case_plans,
        files: files
            .iter()
            .map(|(name, bytes)| {
                (
                    name.clone(),
                    FileEntry {
                        sha256: sha256_hex(bytes),
                        size: bytes.len() as u64,
                    },
                )
            })
            .collect(),
    };
    let mut case_json = serde_json::to_vec_pretty(&case).map_err(|e| CaseError::Archive {
        message: format!("cannot write case.json: {e}"),
    })?;
    case_json.push(b'\n');
    let zip_err = |e: &dyn std::fmt::Display| refuse(format!("cannot write the archive: {e}"));
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    for (name, bytes) in std::iter::once(("case.json".to_owned(), case_json)).chain(files) {
        let options = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Deflated)
            .large_file(bytes.len() as u64 >= u64::from(u32::MAX));
        zip.start_file(name, options).map_err(|e| zip_err(&e))?;
        zip.write_all(&bytes).map_err(|e| zip_err(&e))?;
    }
    Ok(zip.finish().map_err(|e| zip_err(&e))?.into_inner())
}

/// Reads every entry of `zip`, bounded.
fn entries(zip: &[u8]) -> Result<BTreeMap<String, Vec<u8>>, CaseError> {
    const FIX: &str = "import a .zip made by `tissue-cases export` (or the studio's Export)";
    if zip.len() as u64 > MAX_ARCHIVE_BYTES {
        return Err(refuse(format!(
            "the archive has {} bytes, more than the {} MiB a case may have: {FIX}",
            zip.len(),
            MAX_ARCHIVE_BYTES >> 20
        )));
    }
    let mut archive = ZipArchive::new(Cursor::new(zip))
        .map_err(|e| refuse(format!("it is not a zip archive ({e}): {FIX}")))?;
    if archive.len() > MAX_ARCHIVE_ENTRIES {
        return Err(refuse(format!(
            "it has {} entries, more than the {MAX_ARCHIVE_ENTRIES} a case may have: {FIX}",
            archive.len()
        )));
    }
    let mut files = BTreeMap::new();
    let mut total: u64 = 0;
    for i in 0..archive.len() {
        let mut file = archive
            .by_index(i)
            .map_err(|e| refuse(format!("entry {i} cannot be read ({e}): {FIX}")))?;
        if file.is_dir() {
            continue;
        }
        let name = file
            .name()
            .map_err(|e| refuse(format!("entry {i} has no readable name ({e}): {FIX}")))?
            .into_owned();
        let too_big = |size: u64| {
            refuse(format!(
                "{name} unpacks to {size} bytes or more, over the {} MiB a file of a case may have: {FIX}",
                MAX_ENTRY_BYTES >> 20
            ))
        };
        if file.size() > MAX_ENTRY_BYTES {
            return Err(too_big(file.size()));
        }
        let mut bytes = Vec::with_capacity(file.size().min(1 << 20) as usize);
        (&mut file)
            .take(MAX_ENTRY_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| refuse(format!("{name} does not unpack ({e}): {FIX}")))?;
        if bytes.len() as u64 > MAX_ENTRY_BYTES {
            return Err(too_big(bytes.len() as u64));
        }
        total += bytes.len() as u64;
        if total > MAX_TOTAL_BYTES {
            return Err(refuse(format!(
                "its files unpack to more than {} MiB: {FIX}",
                MAX_TOTAL_BYTES >> 20
            )));
        }
        if files.insert(name.clone(), bytes).is_some() {
            return Err(refuse(format!("{name} is in the archive twice: {FIX}")));
        }
    }
    Ok(files)
}

/// A text field of `case.json` that is stored as it is: 1 to 64 printable characters.
fn check_stamp(what: &str, value: &str) -> Result<(), CaseError> {
    if value.is_empty() || value.len() > 64 || value.chars().any(char::is_control) {
        return Err(refuse(format!(
            "case.json's {what} {value:?} is not a time: the archive is damaged; export it again"
        )));
    }
    Ok(())
}

/// A plan checked and ready to insert.
struct ImportPlan {
    row: NewPlanRow,
}

/// Imports a case archive.
pub(crate) fn import(lib: &Library, zip: &[u8]) -> Result<ImportSummary, CaseError> {
    let _span = tracing::info_span!("cases_import").entered();
    let files = entries(zip)?;
    let case_bytes = files.get("case.json").ok_or_else(|| {
        refuse(
            "it has no case.json, so it is not a tissue case: import a .zip made by \
             `tissue-cases export`",
        )
    })?;
    let case: CaseJson = serde_json::from_slice(case_bytes).map_err(|e| {
        refuse(format!(
            "its case.json does not read as a tissue case ({e}): export the case again"
        ))
    })?;
    if case.format != FORMAT {
        return Err(refuse(format!(
            "case.json says format {:?}, not {FORMAT:?}: import a tissue case",
            case.format
        )));
    }
    if case.format_version != FORMAT_VERSION {
        return Err(refuse(format!(
            "case.json has format version {}, this program reads {FORMAT_VERSION}: update tissue",
            case.format_version
        )));
    }
    // Every file listed is there with its hash and size, and nothing else is.
    for (name, bytes) in &files {
        if name == "case.json" {
            continue;
        }
        let entry = case.files.get(name).ok_or_else(|| {
            refuse(format!(
                "{name} is not listed in case.json: the archive was changed after export; export it again"
            ))
        })?;
        if entry.size != bytes.len() as u64 || entry.sha256 != sha256_hex(bytes) {
            return Err(refuse(format!(
                "{name} does not match its SHA-256 or size in case.json: the archive is damaged or was changed; export it again"
            )));
        }
    }
    let file = |name: &str| -> Result<&Vec<u8>, CaseError> {
        match (files.get(name), case.files.contains_key(name)) {
            (Some(bytes), true) => Ok(bytes),
            _ => Err(refuse(format!(
                "{name} is missing from the archive: the archive is incomplete; export it again"
            ))),
        }
    };
    for name in case.files.keys() {
        file(name)?;
    }
    let invalid = |e: CaseError| refuse(format!("case.json: {e}"));

    // The patient: its scan parsed again, its hash and unit checked.
    let p = &case.patient;
    if !is_uid(&p.uid, 'p') {
        return Err(refuse(format!(
            "case.json's patient id {:?} is not a patient id: the archive is damaged",
            p.uid
        )));
    }
    let unit = tissue_planner::Unit::from_symbol(&p.unit).ok_or_else(|| {
        refuse(format!(
            "case.json's unit {:?} is not mm, cm, dm or m: the archive is damaged",
            p.unit
        ))
    })?;
    let label = check_name("label", &p.label).map_err(invalid)?;
    check_stamp("added_at", &p.added_at)?;
    let scan = Scan {
        name: p.scan_name.clone(),
        unit,
        bytes: file(&p.scan_file)?.clone(),
    };
    let sha = scan.sha256();
    if sha != p.scan_sha256 {
        return Err(refuse(format!(
            "the scan {} does not have the SHA-256 case.json gives: the archive is damaged",
            p.scan_file
        )));
    }
    let prepared = store::PreparedPatient::of(&scan).map_err(|e| {
        refuse(format!(
            "the scan {} does not read as a surface: {e}",
            p.scan_file
        ))
    })?;

    // The plans: names, texts and blobs checked.
    let mut plans = Vec::new();
    for c in &case.plans {
        if !is_uid(&c.uid, 'c') {
            return Err(refuse(format!(
                "case.json's plan id {:?} is not a plan id: the archive is damaged",
                c.uid
            )));
        }
        let dir = format!("plans/{}", c.uid);
        let text = |name: &str| -> Result<String, CaseError> {
            String::from_utf8(file(&format!("{dir}/{name}"))?.clone())
                .map_err(|_| refuse(format!("{dir}/{name} is not UTF-8 text: export it again")))
        };
        let job = text("job.json")?;
        serde_json::from_str::<serde_json::Value>(&job)
            .map_err(|e| refuse(format!("{dir}/job.json is not JSON ({e}): export it again")))?;
        let report = text("report.json")?;
        let figures = ReportFigures::read(&report)
            .map_err(|m| refuse(format!("{dir}/report.json: {m}; export it again")))?;
        let result = if c.has_result {
            let bytes = file(&format!("{dir}/result.bin"))?;
            blob::decode_result(bytes, prepared.vertices, &format!("{dir}/result.bin"))
                .map_err(|e| refuse(format!("{e}; export it again")))?;
            Some(bytes.clone())
        } else {
            None
        };
        let chart = if c.has_chart {
            let bytes = file(&format!("{dir}/chart.png"))?;
            if !bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
                return Err(refuse(format!(
                    "{dir}/chart.png is not a PNG: export it again"
                )));
            }
            Some(bytes.clone())
        } else {
            None
        };
        check_stamp("run_at", &c.run_at)?;
        plans.push(ImportPlan {
            row: NewPlanRow {
                uid: c.uid.clone(),
                name: check_name("name", &c.name).map_err(invalid)?,
                note: check_note(&c.note).map_err(invalid)?,
                job,
                report,
                figures,
                run_at: Some(c.run_at.clone()),
                result,
                chart,
            },
        });
    }

    // A patient of that id with another scan is not this patient.
    {
        let conn = lib.lock();
        if let Ok(existing) = store::patient_info(&conn, &p.uid) {
            if existing.scan_sha256 != sha || existing.unit != p.unit {
                return Err(refuse(format!(
                    "the library has another patient with the id {} (another scan or unit): the archive is not this library's patient; it was not imported",
                    p.uid
                )));
            }
        }
    }

    let keep = (p.uid.as_str(), p.added_at.as_str());
    lib.with_prepared_patient(
        &scan,
        Some(&label),
        Some(keep),
        Some(prepared),
        |tx, row| {
            let (mut added, mut skipped) = (0, 0);
            for plan in &plans {
                let exists = tx
                    .query_row(
                        "SELECT 1 FROM plans WHERE uid = ?1",
                        [&plan.row.uid],
                        |_| Ok(()),
                    )
                    .map(|()| true)
                    .or_else(|e| match e {
                        rusqlite::Error::QueryReturnedNoRows => Ok(false),
                        e => Err(e),
                    })
                    .map_err(db("importing a case"))?;
                if exists {
                    skipped += 1;
                } else {
                    store::insert_plan(tx, row.id, &plan.row)?;
                    added += 1;
                }
            }
            Ok(ImportSummary {
                patient: store::patient_info(tx, &row.uid)?,
                plans_added: added,
                plans_skipped: skipped,
            })
        },
    )
}
