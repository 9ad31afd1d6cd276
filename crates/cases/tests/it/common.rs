//! Shared helpers: temporary folders and short real planning runs.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use tissue_cases::{Library, NewPlan, PlanInfo, Scan};
use tissue_planner::{CancelToken, Finished, JobSpec, Patient, Scenario, Shipped, Tool};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A temporary folder removed on drop.
pub struct Tmp(pub PathBuf);

impl Tmp {
    pub fn new(tag: &str) -> Tmp {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos();
        let path = std::env::temp_dir().join(format!(
            "tissue-cases-test-{tag}-{}-{nanos}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&path).unwrap();
        Tmp(path)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }

    /// A library folder inside (not yet made).
    pub fn lib_dir(&self) -> PathBuf {
        self.0.join("library")
    }
}

impl Drop for Tmp {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `job` (JSON) on `patient`.
pub fn run(patient: &Patient, job: &str) -> (JobSpec, Finished) {
    let spec: JobSpec = serde_json::from_str(job).unwrap();
    let scenario = Scenario::new(patient.clone(), spec.request.clone()).unwrap();
    let finished = spec
        .clone()
        .plan(&scenario)
        .unwrap()
        .run(&scenario, Tool::Insert, &CancelToken::new(), |_| {})
        .map_err(tissue_planner::PlanError::from)
        .unwrap();
    (spec, finished)
}

/// The Table 2 plane as a scan (OBJ of its mesh).
pub fn table2() -> (Patient, Scan) {
    let patient = Patient::shipped(Shipped::Table2).unwrap();
    let scan = Scan::of_mesh(&patient, "table2").unwrap();
    (patient, scan)
}

/// A short Table 2 single run of `volume` cm³.
pub fn table2_single(volume: f64, steps: u32) -> (JobSpec, Finished) {
    let (patient, _) = table2();
    run(
        &patient,
        &format!(r#"{{ "request": {{ "volume_cm3": {volume}, "max_steps": {steps} }} }}"#),
    )
}

/// Saves `finished` as `name`.
pub fn save(
    lib: &Library,
    scan: &Scan,
    name: &str,
    spec: &JobSpec,
    finished: &Finished,
) -> PlanInfo {
    lib.save(
        scan,
        None,
        NewPlan {
            name,
            note: "",
            spec,
            finished,
        },
    )
    .unwrap()
}

/// The shipped chest (dm) as a scan, and a short single run at vertex 2277.
pub fn chest_single(steps: u32) -> (Scan, JobSpec, Finished) {
    let patient = Patient::shipped(Shipped::Chest).unwrap();
    let scan = Scan::of_mesh(&patient, "chest").unwrap();
    let (spec, finished) = run(
        &patient,
        &format!(r#"{{ "request": {{ "vertex": 2277, "max_steps": {steps} }} }}"#),
    );
    (scan, spec, finished)
}

/// FNV-1a (64 bits) of `bytes`: a report's fingerprint passed between processes.
pub fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A fixed-seed sequence (an LCG's high bits).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.0 >> 33
    }
}

/// How many blobs the library's database holds (read through a second connection).
pub fn blob_count(lib: &Library) -> i64 {
    rusqlite::Connection::open(lib.database_path())
        .unwrap()
        .query_row("SELECT COUNT(*) FROM blobs", [], |r| r.get(0))
        .unwrap()
}
