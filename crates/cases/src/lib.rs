//! # tissue-cases: the case library
//!
//! A planning system keeps its cases: the patients (their scans), every plan run on them, and
//! its result, in one embedded SQLite database (`cases.sqlite` in a data folder) that needs no
//! server and no set-up. `insert --save`, the `tissue-cases` command and the studio all go
//! through this crate, so that a plan saved by one is opened by the others.
//!
//! ## Key types
//! - [`Library`]: the database in a folder ([`Library::open`], [`default_data_dir`]); `Send +
//!   Sync` (one connection behind a mutex), so a server shares one.
//! - [`Scan`]: a patient's scan as it came (file name, unit, bytes); its SHA-256 identifies the
//!   patient (same bytes and unit: same patient).
//! - [`PatientInfo`], [`PlanInfo`]: what a list shows. [`StoredPlan`]: a plan opened, with its
//!   job and report JSON exactly as the planner wrote them and its result on the patient
//!   ([`tissue_planner::PatientResult`]), so nothing is recomputed.
//! - [`Comparison`]: two plans of one patient, their figures side by side and the per-vertex
//!   difference map.
//! - [`CaseError`]: what went wrong, where, and what to do.
//!
//! ## Storage (schema version [`SCHEMA_VERSION`], `PRAGMA user_version`)
//! - `patients`: uid, label, unit, scan file name, scan SHA-256, the scan's summary (JSON), when
//!   added, the scan bytes' blob and its decoded mesh's blob.
//! - `plans`: uid, patient, name, note, mode, tool, solver, library version, when run, the job
//!   JSON and the report JSON (text, byte for byte as the planner wrote it), key figures for
//!   lists, and the result's blob (a single run's patient after and its fields) and an
//!   expansion's chart.
//! - `blobs`: content-addressed (SHA-256) bytes, each stored once however many rows name it;
//!   a blob no row names is removed with the row that named it last.
//!
//! ## Invariants
//! - Every write is one transaction; the database runs in WAL mode with `synchronous=FULL`, so a
//!   process killed at any moment loses at most the plan being written, and the file always
//!   passes `PRAGMA integrity_check`.
//! - Schema migrations run in order from version 1 at [`Library::open`]; a database written by a
//!   newer version is refused ([`CaseError::Newer`]), never altered.
//! - The folder is made with mode 0700 and the database file 0600 (SQLite gives its `-wal` and
//!   `-shm` files the database's mode).
//! - `secure_delete` is on: deleted rows are overwritten with zeros. [`Library::erase_patient`]
//!   also checkpoints the WAL, truncates it, and vacuums, so the patient's scan bytes are gone
//!   from every file of the library afterwards.
//! - Identifiers (`uid`) are 128 random bits in hex with a prefix (`p…` patient, `c…` plan),
//!   so that one cannot be guessed from another.
//!
//! ## Limits and formats
//! - Names and labels are trimmed and hold 1 to [`MAX_NAME_CHARS`] characters without control
//!   characters; a note holds up to [`MAX_NOTE_CHARS`] (line breaks and tabs allowed). A
//!   patient added without a label is labelled with its scan's file name.
//! - A plan's `volume_cm3` is the search's volume (target-gain) or a single run's asked volume
//!   (`inputs.volume_cm3`); `area_gain_cm2` is the report's, where it has one.
//! - The result blob is little-endian: magic `TSCRSLT\0`, format version 1 (`u32`), the vertex
//!   count (`u32`), the positions after (scan unit, f32×3 each), then `displacement`, `stretch`
//!   and `in_region` (f32 each). The patient's mesh blob: magic `TSCMESH\0`, version 1, vertex
//!   and triangle counts, positions (f32×3) and triangles (u32×3). [`Library::open_plan`]
//!   rebuilds the result from both: `after_cm` is the positions after × the unit's cm, `scan`
//!   is `None`; the mesh downloads written from it are byte for byte those of the run.
//! - An expansion's chart is stored as drawn at [`CHART_SIZE`].
//! - The case archive ([`Library::export_case`]): `case.json` (format [`ARCHIVE_FORMAT`],
//!   version [`ARCHIVE_FORMAT_VERSION`]: the patient, each plan, and the SHA-256 and size of
//!   every other file), `scan/<file name>`, and per plan `plans/<uid>/job.json`,
//!   `report.json`, for a single run `result.bin` (the stored blob) with `patient.ply` and
//!   `patient.vtk` (for people; not read on import), and an expansion's `chart.png`. An import
//!   takes at most [`MAX_ARCHIVE_BYTES`], [`MAX_ARCHIVE_ENTRIES`] entries of at most
//!   [`MAX_ENTRY_BYTES`] each and [`MAX_TOTAL_BYTES`] in all (counted as they unpack, whatever
//!   the headers say), checks every hash, parses the scan again and checks each result against
//!   its vertex count, then writes in one transaction; ids are kept, plans already present are
//!   skipped.
//! - [`MIGRATIONS`] lists the schema's migrations (entry `i` takes version `i` to `i + 1`).
//! - When the system's random source fails (no identifier can be drawn), the write is refused
//!   as [`CaseError::Open`]; no variant was added for it.
//!
//! ## Example: save a plan, list it, open it
//! ```
//! use tissue_cases::{Library, NewPlan, Scan};
//! use tissue_planner::{CancelToken, JobSpec, Patient, PlanError, Scenario, Shipped, Tool};
//!
//! let dir = std::env::temp_dir().join(format!("tissue-cases-doc-{}", std::process::id()));
//! let library = Library::open(&dir)?;
//!
//! // A short Table 2 run, as every front end plans it.
//! let patient = Patient::shipped(Shipped::Table2)?;
//! let scan = Scan::of_mesh(&patient, "table2")?;
//! let spec: JobSpec = serde_json::from_str(r#"{ "request": { "max_steps": 40 } }"#)?;
//! let scenario = Scenario::new(patient, spec.request.clone())?;
//! let finished = spec
//!     .plan(&scenario)?
//!     .run(&scenario, Tool::Insert, &CancelToken::new(), |_| {})
//!     .map_err(PlanError::from)?;
//!
//! let plan = NewPlan { name: "100 cm³ round", note: "", spec: &spec, finished: &finished };
//! let saved = library.save(&scan, Some("Table 2 plane"), plan)?;
//!
//! let patients = library.patients(Some("table"))?;
//! assert_eq!(patients[0].label, "Table 2 plane");
//! assert_eq!(library.plans(&patients[0].uid)?[0].uid, saved.uid);
//!
//! // Opened again: the report as the planner wrote it and the result, nothing recomputed.
//! let opened = library.open_plan(&saved.uid)?;
//! assert_eq!(opened.report_json, finished.report.to_json()?);
//! assert_eq!(
//!     opened.result.as_ref().map(|r| r.after.positions().to_vec()),
//!     finished.patient.as_ref().map(|r| r.after.positions().to_vec())
//! );
//! # drop(library);
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! No HTTP, no terminal, no threads of its own.
#![forbid(unsafe_code)]

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use rusqlite::{Connection, TransactionBehavior};
use serde::Serialize;
use tissue_planner::{Finished, JobReport, JobSpec, Patient, PatientResult, Unit};

mod archive;
mod blob;
mod schema;
mod store;
mod temp;

pub use archive::{
    FORMAT as ARCHIVE_FORMAT, FORMAT_VERSION as ARCHIVE_FORMAT_VERSION, MAX_ARCHIVE_BYTES,
    MAX_ARCHIVE_ENTRIES, MAX_ENTRY_BYTES, MAX_TOTAL_BYTES,
};
use schema::db;
pub use schema::MIGRATIONS;
pub use store::{MAX_NAME_CHARS, MAX_NOTE_CHARS};

/// An expansion's chart as stored (pixels, width × height).
pub const CHART_SIZE: (u32, u32) = (1200, 600);

/// The schema version this library writes (`PRAGMA user_version`).
pub const SCHEMA_VERSION: u32 = 1;

/// How old a leftover export folder (`.tissue-cases-*` in the library's folder, left by an export
/// that was killed) must be for [`Library::open`] to remove it: 10 minutes.
pub const STALE_EXPORT: std::time::Duration = std::time::Duration::from_secs(600);

/// The database file's name in the data folder.
pub const DATABASE_FILE: &str = "cases.sqlite";

/// The platform's data folder for tissue: `$XDG_DATA_HOME/tissue` or `~/.local/share/tissue` on
/// Linux, `~/Library/Application Support/tissue` on macOS, `%APPDATA%\tissue` on Windows.
///
/// # Errors
/// [`CaseError::NoDataDir`] when the platform has none (no home folder): pass a folder.
pub fn default_data_dir() -> Result<PathBuf, CaseError> {
    dirs::data_dir()
        .map(|d| d.join("tissue"))
        .ok_or(CaseError::NoDataDir)
}

/// What went wrong with the library, where, and what to do.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    /// The platform has no user data folder.
    #[error("this computer has no user data folder (no home folder?): give the library's folder with --data DIR")]
    NoDataDir,
    /// The folder or database file could not be made or opened.
    #[error("cannot open the case library in {path}: {source}; check the folder is writable, or give another with --data DIR")]
    Open {
        /// The folder or file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The database was written by a newer version of tissue.
    #[error("the case library {path} has schema version {found}, newer than this program's {supported}: update tissue (the library was not changed)")]
    Newer {
        /// The database file.
        path: PathBuf,
        /// Its version.
        found: u32,
        /// Ours.
        supported: u32,
    },
    /// SQLite failed (a full disk, a damaged file, a lock held too long).
    #[error("the case library's database failed while {doing}: {source}")]
    Database {
        /// What it was doing (`saving the plan`, …).
        doing: &'static str,
        /// SQLite's error.
        source: rusqlite::Error,
    },
    /// No patient or plan of that id.
    #[error("no {what} {id:?} in the case library: list them with `tissue-cases list`")]
    NotFound {
        /// `patient` or `plan`.
        what: &'static str,
        /// The id asked for.
        id: String,
    },
    /// A value given is not acceptable (an empty name, a note too long).
    #[error("{field}: {message}")]
    Invalid {
        /// The field (`name`, `note`, `label`).
        field: &'static str,
        /// What is wrong and what to do.
        message: String,
    },
    /// Stored data does not decode (a blob of the wrong length or hash).
    #[error("the case library holds damaged data ({what}): {message}")]
    Damaged {
        /// Which record.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// A case archive (zip) that cannot be imported.
    #[error("the case archive cannot be imported: {message}")]
    Archive {
        /// What is wrong with it and what to do.
        message: String,
    },
    /// The plan or patient given cannot be stored (the planner failed to encode it).
    #[error("cannot store the plan: {0}")]
    Plan(#[from] tissue_planner::PlanError),
    /// Writing an export failed.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// A patient's scan as it came: the file name (its extension names the format), its unit and its
/// bytes. The shipped meshes are stored as OBJ written from their mesh.
#[derive(Debug, Clone)]
pub struct Scan {
    /// File name, no folder (`p17.ply`).
    pub name: String,
    /// The file's unit.
    pub unit: Unit,
    /// The bytes.
    pub bytes: Vec<u8>,
}

impl Scan {
    /// The file at `path` in `unit`.
    ///
    /// # Errors
    /// [`CaseError::Open`] when it cannot be read.
    pub fn read(path: &Path, unit: Unit) -> Result<Scan, CaseError> {
        let bytes = std::fs::read(path).map_err(|source| CaseError::Open {
            path: path.to_path_buf(),
            source,
        })?;
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        Ok(Scan { name, unit, bytes })
    }

    /// The scan of a patient that was not read from bytes (a shipped or generated mesh): its
    /// file mesh written as OBJ, named after `name` with `.obj`.
    ///
    /// # Errors
    /// [`CaseError::Plan`] when it cannot be written.
    pub fn of_mesh(patient: &Patient, name: &str) -> Result<Scan, CaseError> {
        use tissue_planner::{ErrorKind, PlanError};
        let name = if name.to_ascii_lowercase().ends_with(".obj") {
            name.to_owned()
        } else {
            format!("{name}.obj")
        };
        let output = |e: &dyn std::fmt::Display| {
            PlanError::new(
                ErrorKind::Output,
                format!("cannot write the patient's mesh as OBJ: {e}; check the temporary folder is writable"),
            )
        };
        let tmp = temp::TempDir::new_in(&std::env::temp_dir()).map_err(|e| output(&e))?;
        let path = tmp.path().join("scan.obj");
        tissue_meshio::write_obj(&path, &patient.file).map_err(|e| output(&e))?;
        let bytes = std::fs::read(&path).map_err(|e| output(&e))?;
        Ok(Scan {
            name,
            unit: patient.unit,
            bytes,
        })
    }

    /// The patient these bytes are (parsed as the planner parses an upload).
    ///
    /// # Errors
    /// [`CaseError::Plan`] when they do not parse.
    pub fn patient(&self) -> Result<Patient, CaseError> {
        Ok(Patient::parse(&self.bytes, &self.name, self.unit)?)
    }

    /// Its SHA-256 in hex.
    pub fn sha256(&self) -> String {
        blob::sha256_hex(&self.bytes)
    }
}

/// A patient as a list shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PatientInfo {
    /// Its id (`p` and 32 hex digits).
    pub uid: String,
    /// What the surgeon calls it (the scan's file name until renamed).
    pub label: String,
    /// The scan's unit (`mm`, `cm`, `dm`, `m`).
    pub unit: String,
    /// The scan's file name.
    pub scan_name: String,
    /// The scan's SHA-256 (hex).
    pub scan_sha256: String,
    /// The scan's size (bytes).
    pub scan_bytes: u64,
    /// The scan's summary as the planner gives it ([`tissue_planner::MeshSummary`] JSON).
    pub summary: serde_json::Value,
    /// When it was added (RFC 3339, UTC).
    pub added_at: String,
    /// Its plans.
    pub plans: u64,
    /// When its newest plan ran (RFC 3339, UTC), if it has one.
    pub last_plan_at: Option<String>,
}

/// A plan as a list shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanInfo {
    /// Its id (`c` and 32 hex digits).
    pub uid: String,
    /// Its patient's id.
    pub patient_uid: String,
    /// Its name.
    pub name: String,
    /// Its note (may be empty).
    pub note: String,
    /// The job's mode (`single`, `sweep`, `target-gain`, `expansion`).
    pub mode: String,
    /// The front end that ran it (`insert`, `studio`, …: the report's `tool`).
    pub tool: String,
    /// The solver its runs used (the report's `inputs.solver`).
    pub solver: String,
    /// The library version that ran it (the report's version).
    pub library_version: String,
    /// When it was run (RFC 3339, UTC).
    pub run_at: String,
    /// Skin gained (cm²), for a single run and the search's final run.
    pub area_gain_cm2: Option<f64>,
    /// The implant's volume (cm³), for a single run.
    pub volume_cm3: Option<f64>,
    /// Whether it has a result on the patient (a single run: a 3D view and meshes).
    pub has_result: bool,
}

/// A plan to store: its name and note, the job that ran and what it finished with.
#[derive(Debug, Clone, Copy)]
pub struct NewPlan<'a> {
    /// Its name (1 to 200 characters).
    pub name: &'a str,
    /// A note (up to 10 000 characters; may be empty).
    pub note: &'a str,
    /// The job as it was asked.
    pub spec: &'a JobSpec,
    /// What it finished with.
    pub finished: &'a Finished,
}

/// A plan opened: everything the studio shows and the downloads, without recomputing.
#[derive(Debug, Clone)]
pub struct StoredPlan {
    /// The plan.
    pub info: PlanInfo,
    /// Its patient.
    pub patient: PatientInfo,
    /// The job JSON as stored.
    pub job_json: String,
    /// The report JSON exactly as the planner wrote it.
    pub report_json: String,
    /// A single run's patient before and after, with its fields (in the scan's unit; `after_cm`
    /// in cm), as the run gave them.
    pub result: Option<PatientResult>,
    /// An expansion's chart (PNG).
    pub chart_png: Option<Vec<u8>>,
}

/// One figure of two plans side by side.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FigureRow {
    /// The report field (`area_gain_cm2`, …).
    pub name: String,
    /// Plan A's value.
    pub a: Option<f64>,
    /// Plan B's value.
    pub b: Option<f64>,
    /// B − A, when both have it.
    pub difference: Option<f64>,
}

/// Two plans of one patient compared.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Plan A.
    pub a: PlanInfo,
    /// Plan B.
    pub b: PlanInfo,
    /// Their report figures side by side.
    pub figures: Vec<FigureRow>,
    /// Per patient vertex: |after_B − after_A| in the scan's unit (both single runs), else empty.
    pub difference: Vec<f32>,
    /// The largest entry of `difference` (scan unit).
    pub max_difference: f32,
}

/// What an import added.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportSummary {
    /// The patient (existing, when the same scan and unit were in the library already).
    pub patient: PatientInfo,
    /// Plans added.
    pub plans_added: u64,
    /// Plans already in the library (same id), left as they were.
    pub plans_skipped: u64,
}

/// The case library: one SQLite database in a folder.
#[derive(Debug)]
pub struct Library {
    dir: PathBuf,
    conn: Mutex<Connection>,
}

impl Library {
    /// Opens (or makes) the library in `dir`: the folder (mode 0700) and `cases.sqlite` (0600),
    /// WAL, migrations to [`SCHEMA_VERSION`].
    ///
    /// # Errors
    /// [`CaseError::Open`], [`CaseError::Newer`], [`CaseError::Database`].
    pub fn open(dir: &Path) -> Result<Library, CaseError> {
        let _span = tracing::info_span!("cases_open", dir = %dir.display()).entered();
        let conn = schema::open(dir)?;
        // An export killed mid-way leaves its folder of meshes: gone at the next open.
        temp::sweep_stale(dir, STALE_EXPORT);
        Ok(Library {
            dir: dir.to_path_buf(),
            conn: Mutex::new(conn),
        })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The database file.
    pub fn database_path(&self) -> PathBuf {
        self.dir.join(DATABASE_FILE)
    }

    /// The connection; a mutex poisoned by a panicking thread is taken as it is (every write is
    /// a transaction, rolled back when its guard dropped).
    pub(crate) fn lock(&self) -> MutexGuard<'_, Connection> {
        self.conn.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Stores `plan` for the patient of `scan` (added, labelled `label` or the file name, unless
    /// the same scan in the same unit is there already), in one transaction.
    ///
    /// # Errors
    /// [`CaseError::Invalid`] for a bad name or note; [`CaseError::Database`].
    pub fn save(
        &self,
        scan: &Scan,
        label: Option<&str>,
        plan: NewPlan<'_>,
    ) -> Result<PlanInfo, CaseError> {
        let _span = tracing::info_span!("cases_save").entered();
        let name = store::check_name("name", plan.name)?;
        let note = store::check_note(plan.note)?;
        let label = label.map(|l| store::check_name("label", l)).transpose()?;
        let job = serde_json::to_string(plan.spec).map_err(|e| CaseError::Invalid {
            field: "job",
            message: format!("the job cannot be written as JSON: {e}"),
        })?;
        let report = plan.finished.report.to_json()?;
        let figures =
            store::ReportFigures::read(&report).map_err(|message| CaseError::Invalid {
                field: "report",
                message,
            })?;
        let result = plan
            .finished
            .patient
            .as_ref()
            .map(blob::encode_result)
            .transpose()?;
        let chart = match &plan.finished.report {
            JobReport::Expansion(r) => Some(r.chart(CHART_SIZE)?),
            _ => None,
        };
        let new = store::NewPlanRow {
            uid: store::new_uid('c')?,
            name,
            note,
            job,
            report,
            figures,
            run_at: None,
            result,
            chart,
        };
        let result_vertices = plan
            .finished
            .patient
            .as_ref()
            .map(|p| p.after.positions().len());
        let info = self.with_patient(scan, label.as_deref(), None, |tx, patient| {
            if let Some(n) = result_vertices {
                if n != patient.vertices {
                    return Err(CaseError::Invalid {
                        field: "scan",
                        message: format!(
                            "the result has {n} vertices but the scan {} has {}: save the plan with the scan it ran on",
                            scan.name, patient.vertices
                        ),
                    });
                }
            }
            store::insert_plan(tx, patient.id, &new)?;
            store::plan_info(tx, &new.uid)
        })?;
        Ok(info)
    }

    /// Finds the patient of `scan` or adds it (parsed outside the lock), then runs `then` in the
    /// same `BEGIN IMMEDIATE` transaction and commits.
    fn with_patient<T>(
        &self,
        scan: &Scan,
        label: Option<&str>,
        keep: Option<(&str, &str)>,
        then: impl FnOnce(&rusqlite::Transaction<'_>, &store::PatientRow) -> Result<T, CaseError>,
    ) -> Result<T, CaseError> {
        self.with_prepared_patient(scan, label, keep, None, then)
    }

    /// [`Library::with_patient`] with the scan already parsed (`prepared`), as an import has it.
    pub(crate) fn with_prepared_patient<T>(
        &self,
        scan: &Scan,
        label: Option<&str>,
        keep: Option<(&str, &str)>,
        mut prepared: Option<store::PreparedPatient>,
        then: impl FnOnce(&rusqlite::Transaction<'_>, &store::PatientRow) -> Result<T, CaseError>,
    ) -> Result<T, CaseError> {
        let sha = scan.sha256();
        let unit = scan.unit.symbol();
        if prepared.is_none() && store::find_patient(&self.lock(), &sha, unit)?.is_none() {
            prepared = Some(store::PreparedPatient::of(scan)?);
        }
        loop {
            let mut conn = self.lock();
            let tx = conn
                .transaction_with_behavior(TransactionBehavior::Immediate)
                .map_err(db("starting a write"))?;
            let row = match store::find_patient(&tx, &sha, unit)? {
                Some(row) => row,
                None => match &prepared {
                    Some(p) => store::insert_patient(&tx, scan, &sha, label, keep, p)?,
                    None => {
                        // Erased between the look-up and the write: parse it after all.
                        drop(tx);
                        drop(conn);
                        prepared = Some(store::PreparedPatient::of(scan)?);
                        continue;
                    }
                },
            };
            let out = then(&tx, &row)?;
            tx.commit().map_err(db("committing"))?;
            return Ok(out);
        }
    }

    /// Adds the patient of `scan` without a plan (or finds it).
    ///
    /// # Errors
    /// [`CaseError::Database`], [`CaseError::Plan`] when the scan does not parse.
    pub fn add_patient(&self, scan: &Scan, label: Option<&str>) -> Result<PatientInfo, CaseError> {
        let _span = tracing::info_span!("cases_add_patient").entered();
        let label = label.map(|l| store::check_name("label", l)).transpose()?;
        self.with_patient(scan, label.as_deref(), None, |tx, row| {
            store::patient_info(tx, &row.uid)
        })
    }

    /// The patients, newest plan (or addition) first; `search` keeps those whose label contains
    /// it (case-insensitive).
    ///
    /// # Errors
    /// [`CaseError::Database`].
    pub fn patients(&self, search: Option<&str>) -> Result<Vec<PatientInfo>, CaseError> {
        let _span = tracing::info_span!("cases_patients").entered();
        store::patients(&self.lock(), search)
    }

    /// Patient `uid`.
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn patient(&self, uid: &str) -> Result<PatientInfo, CaseError> {
        store::patient_info(&self.lock(), uid)
    }

    /// Patient `uid`'s scan as it came.
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn scan(&self, uid: &str) -> Result<Scan, CaseError> {
        let _span = tracing::info_span!("cases_scan").entered();
        let conn = self.lock();
        let row = store::patient_row(&conn, uid)?;
        let bytes = store::blob(&conn, &row.scan_blob, "the patient's scan")?;
        Ok(Scan {
            name: row.scan_name,
            unit: row.unit,
            bytes,
        })
    }

    /// Patient `uid` ready to plan on (its stored mesh, no parsing).
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Damaged`], [`CaseError::Database`].
    pub fn load_patient(&self, uid: &str) -> Result<Patient, CaseError> {
        let _span = tracing::info_span!("cases_load_patient").entered();
        let (row, bytes) = {
            let conn = self.lock();
            let row = store::patient_row(&conn, uid)?;
            let bytes = store::blob(&conn, &row.mesh_blob, "the patient's mesh")?;
            (row, bytes)
        };
        let mesh = blob::decode_mesh(&bytes, &format!("patient {uid}'s mesh"))?;
        Ok(Patient::from_mesh(mesh, row.unit, row.scan_name)?)
    }

    /// Patient `uid`'s plans, newest first.
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn plans(&self, patient_uid: &str) -> Result<Vec<PlanInfo>, CaseError> {
        let conn = self.lock();
        let row = store::patient_row(&conn, patient_uid)?;
        store::plans_of(&conn, row.id)
    }

    /// Plan `uid` as a list shows it.
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn plan(&self, uid: &str) -> Result<PlanInfo, CaseError> {
        store::plan_info(&self.lock(), uid)
    }

    /// Plan `uid` opened: its report, job and result, as stored.
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Damaged`], [`CaseError::Database`].
    pub fn open_plan(&self, uid: &str) -> Result<StoredPlan, CaseError> {
        let _span = tracing::info_span!("cases_open_plan").entered();
        let stored = {
            let mut conn = self.lock();
            // One read transaction: the plan, its patient and their blobs as of one moment.
            let tx = conn.transaction().map_err(db("reading a plan"))?;
            let stored = store::stored_plan(&tx, uid)?;
            tx.finish().map_err(db("reading a plan"))?;
            stored
        };
        let result = match (&stored.result, &stored.mesh) {
            (Some(bytes), Some(mesh)) => {
                let what = format!("plan {uid}'s result");
                let before = blob::decode_mesh(mesh, &what)?;
                let data = blob::decode_result(bytes, before.positions().len(), &what)?;
                let unit = stored.unit;
                Some(blob::rebuild_result(
                    &before,
                    data,
                    unit.cm_per_unit(),
                    &what,
                )?)
            }
            _ => None,
        };
        Ok(StoredPlan {
            info: stored.info,
            patient: stored.patient,
            job_json: stored.job,
            report_json: stored.report,
            result,
            chart_png: stored.chart,
        })
    }

    /// Plans `a` and `b` of one patient compared.
    ///
    /// # Errors
    /// [`CaseError::NotFound`]; [`CaseError::Invalid`] when they are of two patients.
    pub fn compare(&self, a: &str, b: &str) -> Result<Comparison, CaseError> {
        let _span = tracing::info_span!("cases_compare").entered();
        let pa = self.open_plan(a)?;
        let pb = self.open_plan(b)?;
        if pa.patient.uid != pb.patient.uid {
            return Err(CaseError::Invalid {
                field: "b",
                message: format!(
                    "plan {b} is of patient {} and plan {a} of patient {}: compare two plans of one patient",
                    pb.patient.uid, pa.patient.uid
                ),
            });
        }
        let figures = store::figures(&pa.report_json, &pb.report_json)?;
        let difference: Vec<f32> = match (&pa.result, &pb.result) {
            (Some(ra), Some(rb)) => ra
                .after
                .positions()
                .iter()
                .zip(rb.after.positions())
                .map(|(&x, &y)| (y - x).length())
                .collect(),
            _ => Vec::new(),
        };
        let max_difference = difference.iter().copied().fold(0.0_f32, f32::max);
        Ok(Comparison {
            a: pa.info,
            b: pb.info,
            figures,
            difference,
            max_difference,
        })
    }

    /// Renames plan `uid`.
    ///
    /// # Errors
    /// [`CaseError::Invalid`], [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn rename_plan(&self, uid: &str, name: &str) -> Result<PlanInfo, CaseError> {
        let name = store::check_name("name", name)?;
        self.update_plan(uid, "UPDATE plans SET name = ?2 WHERE uid = ?1", &name)
    }

    /// Sets plan `uid`'s note.
    ///
    /// # Errors
    /// [`CaseError::Invalid`], [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn set_note(&self, uid: &str, note: &str) -> Result<PlanInfo, CaseError> {
        let note = store::check_note(note)?;
        self.update_plan(uid, "UPDATE plans SET note = ?2 WHERE uid = ?1", &note)
    }

    fn update_plan(&self, uid: &str, sql: &str, value: &str) -> Result<PlanInfo, CaseError> {
        let _span = tracing::info_span!("cases_update_plan").entered();
        self.write(|tx| {
            let n = tx
                .execute(sql, rusqlite::params![uid, value])
                .map_err(db("updating a plan"))?;
            if n == 0 {
                return Err(store::not_found("plan", uid));
            }
            store::plan_info(tx, uid)
        })
    }

    /// Renames patient `uid`.
    ///
    /// # Errors
    /// [`CaseError::Invalid`], [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn rename_patient(&self, uid: &str, label: &str) -> Result<PatientInfo, CaseError> {
        let _span = tracing::info_span!("cases_rename_patient").entered();
        let label = store::check_name("label", label)?;
        self.write(|tx| {
            let n = tx
                .execute(
                    "UPDATE patients SET label = ?2 WHERE uid = ?1",
                    rusqlite::params![uid, label],
                )
                .map_err(db("renaming a patient"))?;
            if n == 0 {
                return Err(store::not_found("patient", uid));
            }
            store::patient_info(tx, uid)
        })
    }

    /// Runs `f` in one `BEGIN IMMEDIATE` transaction and commits it (rolled back on error).
    pub(crate) fn write<T>(
        &self,
        f: impl FnOnce(&rusqlite::Transaction<'_>) -> Result<T, CaseError>,
    ) -> Result<T, CaseError> {
        let mut conn = self.lock();
        let tx = conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(db("starting a write"))?;
        let out = f(&tx)?;
        tx.commit().map_err(db("committing"))?;
        Ok(out)
    }

    /// Deletes plan `uid` (and blobs no other row names).
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn delete_plan(&self, uid: &str) -> Result<(), CaseError> {
        let _span = tracing::info_span!("cases_delete_plan").entered();
        self.write(|tx| {
            let n = tx
                .execute("DELETE FROM plans WHERE uid = ?1", [uid])
                .map_err(db("deleting a plan"))?;
            if n == 0 {
                return Err(store::not_found("plan", uid));
            }
            store::collect_blobs(tx)
        })
    }

    /// Erases patient `uid` and everything of theirs, leaving no trace in the library's files:
    /// the rows and blobs deleted under `secure_delete`, the WAL checkpointed and truncated, the
    /// database vacuumed.
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Database`] (also when another program keeps a read
    /// of the library open past the 10 s busy timeout, so that the WAL cannot be truncated:
    /// the rows are deleted then, but old copies of their pages may stay in the WAL until the
    /// next erasure checkpoints it).
    pub fn erase_patient(&self, uid: &str) -> Result<(), CaseError> {
        let _span = tracing::info_span!("cases_erase_patient").entered();
        let mut conn = self.lock();
        {
            let tx = conn
                .transaction_with_behavior(TransactionBehavior::Immediate)
                .map_err(db("starting a write"))?;
            let n = tx
                .execute("DELETE FROM patients WHERE uid = ?1", [uid])
                .map_err(db("erasing a patient"))?;
            if n == 0 {
                return Err(store::not_found("patient", uid));
            }
            store::collect_blobs(&tx)?;
            tx.commit().map_err(db("committing"))?;
        }
        store::checkpoint(&conn)?;
        conn.execute_batch("VACUUM")
            .map_err(db("vacuuming after an erasure"))?;
        store::checkpoint(&conn)?;
        Ok(())
    }

    /// Patient `uid`'s case as one zip: `case.json` (the patient, the plans and a SHA-256 of
    /// every file), the scan as it came, and per plan its job and report JSON, its result (the
    /// patient after as PLY and VTK with fields, and the exact stored result) and an
    /// expansion's chart.
    ///
    /// # Errors
    /// [`CaseError::NotFound`], [`CaseError::Database`].
    pub fn export_case(&self, uid: &str) -> Result<Vec<u8>, CaseError> {
        archive::export(self, uid)
    }

    /// [`Library::export_case`] written atomically to `path`.
    ///
    /// # Errors
    /// As [`Library::export_case`]; [`CaseError::Write`].
    pub fn export_case_to(&self, uid: &str, path: &Path) -> Result<(), CaseError> {
        let bytes = self.export_case(uid)?;
        tissue_meshio::write_bytes(path, &bytes).map_err(|e| CaseError::Write {
            path: path.to_path_buf(),
            source: std::io::Error::other(e.to_string()),
        })
    }

    /// Imports a case zip made by [`Library::export_case`] (on this computer or another): every
    /// file's hash checked, sizes bounded (a zip bomb is refused), in one transaction.
    ///
    /// # Errors
    /// [`CaseError::Archive`] for a damaged, foreign or oversized archive; [`CaseError::Database`].
    pub fn import_case(&self, zip: &[u8]) -> Result<ImportSummary, CaseError> {
        archive::import(self, zip)
    }

    /// `PRAGMA integrity_check`'s answer (`ok` when sound).
    ///
    /// # Errors
    /// [`CaseError::Database`].
    pub fn integrity_check(&self) -> Result<String, CaseError> {
        let rows = store::all_rows(
            &self.lock(),
            "PRAGMA integrity_check",
            [],
            |row| row.get::<_, String>(0),
            "checking the database",
        )?;
        Ok(rows.join("\n"))
    }
}
