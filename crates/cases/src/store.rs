//! The rows: validation of what a user names, identifiers, and the SQL that reads and writes
//! patients, plans and blobs. Every function runs on a connection or transaction the caller
//! holds; none opens a transaction of its own.

use rusqlite::{params, Connection, OptionalExtension};
use tissue_planner::Unit;

use crate::blob::{self, sha256_hex};
use crate::schema::db;
use crate::{CaseError, FigureRow, PatientInfo, PlanInfo, Scan};

/// The longest name or label (characters, after trimming).
pub const MAX_NAME_CHARS: usize = 200;
/// The longest note (characters).
pub const MAX_NOTE_CHARS: usize = 10_000;

/// SQLite's "now" as RFC 3339 UTC with milliseconds.
const NOW: &str = "strftime('%Y-%m-%dT%H:%M:%fZ','now')";

/// A name or label: trimmed, 1 to [`MAX_NAME_CHARS`] characters, no control characters.
pub(crate) fn check_name(field: &'static str, value: &str) -> Result<String, CaseError> {
    let v = value.trim();
    let n = v.chars().count();
    if n == 0 {
        return Err(CaseError::Invalid {
            field,
            message: format!("the {field} is empty: give 1 to {MAX_NAME_CHARS} characters"),
        });
    }
    if n > MAX_NAME_CHARS {
        return Err(CaseError::Invalid {
            field,
            message: format!(
                "the {field} has {n} characters: shorten it to at most {MAX_NAME_CHARS}"
            ),
        });
    }
    if let Some(c) = v.chars().find(|c| c.is_control()) {
        return Err(CaseError::Invalid {
            field,
            message: format!(
                "the {field} holds a control character ({:?}): use printable characters only",
                c
            ),
        });
    }
    Ok(v.to_owned())
}

/// A note: at most [`MAX_NOTE_CHARS`] characters (line breaks and tabs allowed).
pub(crate) fn check_note(value: &str) -> Result<String, CaseError> {
    let n = value.chars().count();
    if n > MAX_NOTE_CHARS {
        return Err(CaseError::Invalid {
            field: "note",
            message: format!("the note has {n} characters: shorten it to at most {MAX_NOTE_CHARS}"),
        });
    }
    if let Some(c) = value
        .chars()
        .find(|&c| c.is_control() && !matches!(c, '\n' | '\r' | '\t'))
    {
        return Err(CaseError::Invalid {
            field: "note",
            message: format!(
                "the note holds a control character ({c:?}): use text, line breaks and tabs only"
            ),
        });
    }
    Ok(value.to_owned())
}

/// A default label from a scan's file name: control characters dropped, trimmed, at most
/// [`MAX_NAME_CHARS`] characters, `scan` when nothing is left.
pub(crate) fn label_of_name(name: &str) -> String {
    let clean: String = name.chars().filter(|c| !c.is_control()).collect();
    let label: String = clean.trim().chars().take(MAX_NAME_CHARS).collect();
    let label = label.trim().to_owned();
    if label.is_empty() {
        "scan".to_owned()
    } else {
        label
    }
}

/// A fresh identifier: `prefix` and 128 random bits as 32 hex digits.
pub(crate) fn new_uid(prefix: char) -> Result<String, CaseError> {
    let mut bits = [0u8; 16];
    getrandom::fill(&mut bits).map_err(|e| CaseError::Open {
        path: std::path::PathBuf::from("(the system's random source)"),
        source: std::io::Error::other(format!("cannot draw a random identifier: {e}")),
    })?;
    Ok(format!("{prefix}{}", blob::hex(&bits)))
}

/// Whether `uid` has the shape of an identifier of `prefix`.
pub(crate) fn is_uid(uid: &str, prefix: char) -> bool {
    uid.len() == 33
        && uid.starts_with(prefix)
        && uid[1..]
            .bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

/// No `what` of `id`.
pub(crate) fn not_found(what: &'static str, id: &str) -> CaseError {
    CaseError::NotFound {
        what,
        id: id.to_owned(),
    }
}

/// What a plan's row repeats from its report, for lists.
#[derive(Debug, Clone)]
pub(crate) struct ReportFigures {
    pub mode: String,
    pub tool: String,
    pub solver: String,
    pub version: String,
    pub area_gain_cm2: Option<f64>,
    pub volume_cm3: Option<f64>,
}

impl ReportFigures {
    /// Reads them from a report's JSON: `mode`, `tool`, `version`, `inputs.solver`,
    /// `area_gain_cm2` (a single run, the search), `volume_cm3` (the search's volume, or a
    /// single run's `inputs.volume_cm3`).
    pub(crate) fn read(report: &str) -> Result<ReportFigures, String> {
        let v: serde_json::Value =
            serde_json::from_str(report).map_err(|e| format!("the report is not JSON: {e}"))?;
        let text = |key: &str, value: Option<&serde_json::Value>| {
            value
                .and_then(|x| x.as_str())
                .map(str::to_owned)
                .ok_or_else(|| format!("the report has no `{key}` text"))
        };
        let mode = text("mode", v.get("mode"))?;
        let inputs = v.get("inputs");
        let volume_cm3 = match v.get("volume_cm3").and_then(|x| x.as_f64()) {
            Some(x) => Some(x),
            None if mode == "single" => inputs
                .and_then(|i| i.get("volume_cm3"))
                .and_then(|x| x.as_f64()),
            None => None,
        };
        Ok(ReportFigures {
            tool: text("tool", v.get("tool"))?,
            version: text("version", v.get("version"))?,
            solver: text("inputs.solver", inputs.and_then(|i| i.get("solver")))?,
            area_gain_cm2: v.get("area_gain_cm2").and_then(|x| x.as_f64()),
            volume_cm3,
            mode,
        })
    }
}

/// The top-level numeric fields of a report (its body's figures), in the report's order.
fn numbers(report: &str) -> Result<Vec<(String, Option<f64>)>, CaseError> {
    let v: serde_json::Value = serde_json::from_str(report).map_err(|e| CaseError::Damaged {
        what: "a plan's report".to_owned(),
        message: format!("not JSON: {e}"),
    })?;
    let Some(map) = v.as_object() else {
        return Ok(Vec::new());
    };
    Ok(map
        .iter()
        .filter(|(k, _)| k.as_str() != "schema_version")
        .filter(|(_, x)| x.is_number() || x.is_null())
        .map(|(k, x)| (k.clone(), x.as_f64()))
        .collect())
}

/// Two reports' figures side by side: every top-level number of either, A's order first.
pub(crate) fn figures(a: &str, b: &str) -> Result<Vec<FigureRow>, CaseError> {
    let na = numbers(a)?;
    let nb = numbers(b)?;
    let mut names: Vec<&String> = na.iter().map(|(k, _)| k).collect();
    for (k, _) in &nb {
        if !names.contains(&k) {
            names.push(k);
        }
    }
    let get = |list: &[(String, Option<f64>)], name: &str| {
        list.iter().find(|(k, _)| k == name).and_then(|(_, v)| *v)
    };
    Ok(names
        .into_iter()
        .filter_map(|name| {
            let (a, b) = (get(&na, name), get(&nb, name));
            if a.is_none() && b.is_none() {
                return None;
            }
            Some(FigureRow {
                name: name.clone(),
                a,
                b,
                difference: a.zip(b).map(|(a, b)| b - a),
            })
        })
        .collect())
}

/// A patient's row, what writes and opens need.
#[derive(Debug, Clone)]
pub(crate) struct PatientRow {
    pub id: i64,
    pub uid: String,
    pub unit: Unit,
    pub scan_name: String,
    pub scan_blob: String,
    pub mesh_blob: String,
    pub vertices: usize,
}

const PATIENT_ROW: &str = "SELECT id, uid, unit, scan_name, scan_blob, mesh_blob, \
     COALESCE(json_extract(summary, '$.vertices'), -1) FROM patients";

fn unit_of(symbol: &str) -> rusqlite::Result<Unit> {
    Unit::from_symbol(symbol).ok_or_else(|| {
        rusqlite::Error::FromSqlConversionFailure(
            2,
            rusqlite::types::Type::Text,
            format!("unknown unit {symbol:?}").into(),
        )
    })
}

fn patient_row_of(row: &rusqlite::Row<'_>) -> rusqlite::Result<PatientRow> {
    let unit: String = row.get(2)?;
    let vertices: i64 = row.get(6)?;
    Ok(PatientRow {
        id: row.get(0)?,
        uid: row.get(1)?,
        unit: unit_of(&unit)?,
        scan_name: row.get(3)?,
        scan_blob: row.get(4)?,
        mesh_blob: row.get(5)?,
        vertices: usize::try_from(vertices).unwrap_or(usize::MAX),
    })
}

/// The patient of scan `sha` in `unit`, if any.
pub(crate) fn find_patient(
    conn: &Connection,
    sha: &str,
    unit: &str,
) -> Result<Option<PatientRow>, CaseError> {
    conn.query_row(
        &format!("{PATIENT_ROW} WHERE scan_sha256 = ?1 AND unit = ?2"),
        params![sha, unit],
        patient_row_of,
    )
    .optional()
    .map_err(db("looking up a patient"))
}

/// Patient `uid`'s row.
pub(crate) fn patient_row(conn: &Connection, uid: &str) -> Result<PatientRow, CaseError> {
    conn.query_row(
        &format!("{PATIENT_ROW} WHERE uid = ?1"),
        [uid],
        patient_row_of,
    )
    .optional()
    .map_err(db("reading a patient"))?
    .ok_or_else(|| not_found("patient", uid))
}

/// A new patient's stored forms, made before the write's lock (parsing takes time).
#[derive(Debug)]
pub(crate) struct PreparedPatient {
    pub mesh_blob: Vec<u8>,
    pub mesh_hash: String,
    pub summary: String,
    pub vertices: usize,
}

impl PreparedPatient {
    pub(crate) fn of(scan: &Scan) -> Result<PreparedPatient, CaseError> {
        let _span = tracing::info_span!("cases_parse_scan").entered();
        let patient = scan.patient()?;
        let mesh_blob = blob::encode_mesh(&patient.file)?;
        let summary =
            serde_json::to_string(&patient.summary()).map_err(|e| CaseError::Invalid {
                field: "scan",
                message: format!("the scan's summary cannot be written as JSON: {e}"),
            })?;
        Ok(PreparedPatient {
            vertices: patient.file.positions().len(),
            mesh_hash: sha256_hex(&mesh_blob),
            mesh_blob,
            summary,
        })
    }
}

/// Stores `bytes` under `hash` unless they are there already.
pub(crate) fn put_blob(conn: &Connection, hash: &str, bytes: &[u8]) -> Result<(), CaseError> {
    conn.execute(
        "INSERT OR IGNORE INTO blobs (hash, size, bytes) VALUES (?1, ?2, ?3)",
        params![hash, bytes.len() as i64, bytes],
    )
    .map_err(db("storing a blob"))?;
    Ok(())
}

/// Blob `hash`'s bytes.
pub(crate) fn blob(conn: &Connection, hash: &str, what: &str) -> Result<Vec<u8>, CaseError> {
    conn.query_row("SELECT bytes FROM blobs WHERE hash = ?1", [hash], |r| {
        r.get::<_, Vec<u8>>(0)
    })
    .optional()
    .map_err(db("reading a blob"))?
    .ok_or_else(|| CaseError::Damaged {
        what: what.to_owned(),
        message: format!("its blob {hash} is missing"),
    })
}

/// Adds the patient of `scan` (its bytes, mesh and summary), with a fresh uid and now as its
/// time unless `keep` gives both (an import).
pub(crate) fn insert_patient(
    conn: &Connection,
    scan: &Scan,
    sha: &str,
    label: Option<&str>,
    keep: Option<(&str, &str)>,
    prepared: &PreparedPatient,
) -> Result<PatientRow, CaseError> {
    put_blob(conn, sha, &scan.bytes)?;
    put_blob(conn, &prepared.mesh_hash, &prepared.mesh_blob)?;
    let uid = match keep {
        Some((uid, _)) => uid.to_owned(),
        None => new_uid('p')?,
    };
    let label = label.map_or_else(|| label_of_name(&scan.name), str::to_owned);
    conn.execute(
        &format!(
            "INSERT INTO patients (uid, label, unit, scan_name, scan_sha256, scan_blob, \
             mesh_blob, summary, added_at) VALUES (?1, ?2, ?3, ?4, ?5, ?5, ?6, ?7, \
             COALESCE(?8, {NOW}))"
        ),
        params![
            uid,
            label,
            scan.unit.symbol(),
            scan.name,
            sha,
            prepared.mesh_hash,
            prepared.summary,
            keep.map(|k| k.1),
        ],
    )
    .map_err(db("adding a patient"))?;
    patient_row(conn, &uid)
}

/// A plan's row to insert.
#[derive(Debug)]
pub(crate) struct NewPlanRow {
    pub uid: String,
    pub name: String,
    pub note: String,
    pub job: String,
    pub report: String,
    pub figures: ReportFigures,
    /// When it ran (an import keeps it); now when `None`.
    pub run_at: Option<String>,
    pub result: Option<Vec<u8>>,
    pub chart: Option<Vec<u8>>,
}

/// Inserts a plan row and its blobs.
pub(crate) fn insert_plan(
    conn: &Connection,
    patient_id: i64,
    plan: &NewPlanRow,
) -> Result<(), CaseError> {
    let hash = |bytes: &Option<Vec<u8>>| -> Result<Option<String>, CaseError> {
        match bytes {
            Some(b) => {
                let h = sha256_hex(b);
                put_blob(conn, &h, b)?;
                Ok(Some(h))
            }
            None => Ok(None),
        }
    };
    let result = hash(&plan.result)?;
    let chart = hash(&plan.chart)?;
    let f = &plan.figures;
    conn.execute(
        &format!(
            "INSERT INTO plans (uid, patient_id, name, note, mode, tool, solver, \
             library_version, run_at, job, report, area_gain_cm2, volume_cm3, result_blob, \
             chart_blob) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, COALESCE(?9, {NOW}), ?10, ?11, \
             ?12, ?13, ?14, ?15)"
        ),
        params![
            plan.uid,
            patient_id,
            plan.name,
            plan.note,
            f.mode,
            f.tool,
            f.solver,
            f.version,
            plan.run_at,
            plan.job,
            plan.report,
            f.area_gain_cm2,
            f.volume_cm3,
            result,
            chart,
        ],
    )
    .map_err(db("saving the plan"))?;
    Ok(())
}

const PATIENT_INFO: &str = "SELECT p.uid, p.label, p.unit, p.scan_name, p.scan_sha256, b.size, \
     p.summary, p.added_at, \
     (SELECT COUNT(*) FROM plans c WHERE c.patient_id = p.id), \
     (SELECT MAX(c.run_at) FROM plans c WHERE c.patient_id = p.id) \
     FROM patients p JOIN blobs b ON b.hash = p.scan_blob";

fn patient_info_of(row: &rusqlite::Row<'_>) -> rusqlite::Result<PatientInfo> {
    let summary: String = row.get(6)?;
    let summary = serde_json::from_str(&summary).map_err(|e| {
        rusqlite::Error::FromSqlConversionFailure(6, rusqlite::types::Type::Text, Box::new(e))
    })?;
    Ok(PatientInfo {
        uid: row.get(0)?,
        label: row.get(1)?,
        unit: row.get(2)?,
        scan_name: row.get(3)?,
        scan_sha256: row.get(4)?,
        scan_bytes: u64::try_from(row.get::<_, i64>(5)?).unwrap_or(0),
        summary,
        added_at: row.get(7)?,
        plans: u64::try_from(row.get::<_, i64>(8)?).unwrap_or(0),
        last_plan_at: row.get(9)?,
    })
}

/// Patient `uid` as a list shows it.
pub(crate) fn patient_info(conn: &Connection, uid: &str) -> Result<PatientInfo, CaseError> {
    conn.query_row(
        &format!("{PATIENT_INFO} WHERE p.uid = ?1"),
        [uid],
        patient_info_of,
    )
    .optional()
    .map_err(db("reading a patient"))?
    .ok_or_else(|| not_found("patient", uid))
}

/// `text` as a LIKE pattern that matches it literally anywhere (`\` escapes `%`, `_`, `\`).
fn like_pattern(text: &str) -> String {
    let mut p = String::with_capacity(text.len() + 2);
    p.push('%');
    for c in text.chars() {
        if matches!(c, '%' | '_' | '\\') {
            p.push('\\');
        }
        p.push(c);
    }
    p.push('%');
    p
}

/// The patients, newest activity (plan or addition) first, those whose label contains
/// `search` (case-insensitive for ASCII letters, SQLite's LIKE).
pub(crate) fn patients(
    conn: &Connection,
    search: Option<&str>,
) -> Result<Vec<PatientInfo>, CaseError> {
    let sql = format!(
        "{PATIENT_INFO} WHERE ?1 IS NULL OR p.label LIKE ?1 ESCAPE '\\' \
         ORDER BY MAX(p.added_at, COALESCE((SELECT MAX(c.run_at) FROM plans c \
         WHERE c.patient_id = p.id), p.added_at)) DESC, p.id DESC"
    );
    let pattern = search.map(like_pattern);
    all_rows(conn, &sql, [pattern], patient_info_of, "listing patients")
}

/// Every row of `sql` with `params`, mapped by `map`.
pub(crate) fn all_rows<T, P: rusqlite::Params>(
    conn: &Connection,
    sql: &str,
    params: P,
    map: impl FnMut(&rusqlite::Row<'_>) -> rusqlite::Result<T>,
    doing: &'static str,
) -> Result<Vec<T>, CaseError> {
    let mut stmt = conn.prepare(sql).map_err(db(doing))?;
    let rows = stmt.query_map(params, map).map_err(db(doing))?;
    rows.collect::<Result<Vec<_>, _>>().map_err(db(doing))
}

const PLAN_INFO: &str = "SELECT c.uid, p.uid, c.name, c.note, c.mode, c.tool, c.solver, \
     c.library_version, c.run_at, c.area_gain_cm2, c.volume_cm3, c.result_blob IS NOT NULL \
     FROM plans c JOIN patients p ON p.id = c.patient_id";

fn plan_info_of(row: &rusqlite::Row<'_>) -> rusqlite::Result<PlanInfo> {
    Ok(PlanInfo {
        uid: row.get(0)?,
        patient_uid: row.get(1)?,
        name: row.get(2)?,
        note: row.get(3)?,
        mode: row.get(4)?,
        tool: row.get(5)?,
        solver: row.get(6)?,
        library_version: row.get(7)?,
        run_at: row.get(8)?,
        area_gain_cm2: row.get(9)?,
        volume_cm3: row.get(10)?,
        has_result: row.get(11)?,
    })
}

/// Plan `uid` as a list shows it.
pub(crate) fn plan_info(conn: &Connection, uid: &str) -> Result<PlanInfo, CaseError> {
    conn.query_row(
        &format!("{PLAN_INFO} WHERE c.uid = ?1"),
        [uid],
        plan_info_of,
    )
    .optional()
    .map_err(db("reading a plan"))?
    .ok_or_else(|| not_found("plan", uid))
}

/// The plans of patient row `patient_id`, newest first.
pub(crate) fn plans_of(conn: &Connection, patient_id: i64) -> Result<Vec<PlanInfo>, CaseError> {
    all_rows(
        conn,
        &format!("{PLAN_INFO} WHERE c.patient_id = ?1 ORDER BY c.run_at DESC, c.id DESC"),
        [patient_id],
        plan_info_of,
        "listing plans",
    )
}

/// A plan's stored parts, not yet decoded.
#[derive(Debug)]
pub(crate) struct StoredRow {
    pub info: PlanInfo,
    pub patient: PatientInfo,
    pub unit: Unit,
    pub job: String,
    pub report: String,
    /// The result blob, when it has one.
    pub result: Option<Vec<u8>>,
    /// The patient's mesh blob, read when there is a result.
    pub mesh: Option<Vec<u8>>,
    pub chart: Option<Vec<u8>>,
}

/// Plan `uid`'s stored parts.
pub(crate) fn stored_plan(conn: &Connection, uid: &str) -> Result<StoredRow, CaseError> {
    let info = plan_info(conn, uid)?;
    let (job, report, result_hash, chart_hash): (String, String, Option<String>, Option<String>) =
        conn.query_row(
            "SELECT job, report, result_blob, chart_blob FROM plans WHERE uid = ?1",
            [uid],
            |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)),
        )
        .map_err(db("reading a plan"))?;
    let patient = patient_info(conn, &info.patient_uid)?;
    let row = patient_row(conn, &info.patient_uid)?;
    let what = format!("plan {uid}");
    let result = result_hash
        .map(|h| blob(conn, &h, &format!("{what}'s result")))
        .transpose()?;
    let mesh = match result {
        Some(_) => Some(blob(conn, &row.mesh_blob, "the patient's mesh")?),
        None => None,
    };
    let chart = chart_hash
        .map(|h| blob(conn, &h, &format!("{what}'s chart")))
        .transpose()?;
    Ok(StoredRow {
        info,
        patient,
        unit: row.unit,
        job,
        report,
        result,
        mesh,
        chart,
    })
}

/// Deletes the blobs no row names (after a delete, in its transaction).
pub(crate) fn collect_blobs(conn: &Connection) -> Result<(), CaseError> {
    conn.execute(
        "DELETE FROM blobs WHERE hash NOT IN ( \
            SELECT scan_blob FROM patients \
            UNION SELECT mesh_blob FROM patients \
            UNION SELECT result_blob FROM plans WHERE result_blob IS NOT NULL \
            UNION SELECT chart_blob FROM plans WHERE chart_blob IS NOT NULL)",
        [],
    )
    .map_err(db("removing unused blobs"))?;
    Ok(())
}

/// `PRAGMA wal_checkpoint(TRUNCATE)`, which must not be left busy (another reader holding
/// the log): the erased bytes would stay in the WAL.
pub(crate) fn checkpoint(conn: &Connection) -> Result<(), CaseError> {
    let (busy, _, _): (i64, i64, i64) = conn
        .query_row("PRAGMA wal_checkpoint(TRUNCATE)", [], |r| {
            Ok((r.get(0)?, r.get(1)?, r.get(2)?))
        })
        .map_err(db("checkpointing the write-ahead log"))?;
    if busy != 0 {
        return Err(CaseError::Database {
            doing: "checkpointing the write-ahead log (another program is reading the library: close it and erase again)",
            source: rusqlite::Error::SqliteFailure(
                rusqlite::ffi::Error::new(rusqlite::ffi::SQLITE_BUSY),
                Some("the checkpoint could not finish".to_owned()),
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_trimmed_and_bounded() {
        assert_eq!(check_name("name", "  a b ").unwrap(), "a b");
        assert!(check_name("name", "   ").is_err());
        assert!(check_name("name", &"x".repeat(201)).is_err());
        assert!(check_name("name", &"é".repeat(200)).is_ok());
        assert!(check_name("name", "a\u{7}b").is_err());
        assert!(check_note(&"n".repeat(10_000)).is_ok());
        assert!(check_note(&"n".repeat(10_001)).is_err());
        assert!(check_note("line\nline").is_ok());
    }

    #[test]
    fn list_figures_are_read_from_every_modes_golden_report() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/reports");
        let read = |mode: &str| {
            let text = std::fs::read_to_string(dir.join(format!("{mode}.json"))).unwrap();
            ReportFigures::read(&text).unwrap()
        };
        let single = read("single");
        assert_eq!(
            (single.mode.as_str(), single.solver.as_str()),
            ("single", "explicit")
        );
        assert_eq!(single.area_gain_cm2, Some(34.97813738911668));
        assert_eq!(single.volume_cm3, Some(100.0));
        let search = read("target-gain");
        assert_eq!(search.area_gain_cm2, Some(20.594834752596853));
        assert_eq!(search.volume_cm3, Some(69.3786993695329));
        for mode in ["sweep", "expansion"] {
            let f = read(mode);
            assert_eq!(f.mode, mode);
            assert_eq!((f.area_gain_cm2, f.volume_cm3), (None, None));
        }
        assert!(ReportFigures::read("{}").is_err());
        assert!(ReportFigures::read("not json").is_err());
    }

    #[test]
    fn like_patterns_escape_wildcards() {
        assert_eq!(like_pattern("50%_a\\"), "%50\\%\\_a\\\\%");
    }

    #[test]
    fn uids_have_their_shape_and_differ() {
        let a = new_uid('c').unwrap();
        let b = new_uid('c').unwrap();
        assert!(is_uid(&a, 'c') && is_uid(&b, 'c'));
        assert_ne!(a, b);
        assert!(!is_uid(&a, 'p'));
        assert!(!is_uid("c../../x", 'c'));
    }
}
