//! The real `tissue-cases` binary, end to end, on plans stored as `insert --save` stores them, in
//! scratch libraries (`--data`; never the user's data folder): the list, a report byte for byte,
//! export and import into another library, rename and note, delete and erase, the integrity
//! check, and each error's exit code.
#![allow(clippy::unwrap_used, clippy::panic, clippy::expect_used)]

mod commands;
mod errors;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

/// The `tissue-cases` binary.
fn cases() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tissue-cases"))
}

/// A test's scratch folder in the temporary directory, removed when the test passes (kept to be
/// looked at when it fails).
struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

fn scratch(name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("tissue-cases-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `tissue-cases --data DATA ARGS…`, which must succeed.
fn ok(data: &Path, args: &[&str]) -> Output {
    let o = cases().arg("--data").arg(data).args(args).output().unwrap();
    assert!(
        o.status.success(),
        "tissue-cases {args:?}: {}\n{}",
        o.status,
        stderr(&o)
    );
    o
}

/// `tissue-cases --data DATA ARGS…`, which must fail with `code`, one error line on stderr
/// holding every one of `words`, and nothing on stdout.
fn fails(data: &Path, args: &[&str], code: tissue_cli::Exit, words: &[&str]) -> String {
    let o = cases().arg("--data").arg(data).args(args).output().unwrap();
    let err = stderr(&o);
    assert_eq!(
        o.status.code(),
        Some(code.code().into()),
        "tissue-cases {args:?}: {err}"
    );
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].starts_with("tissue-cases: error: "), "{err}");
    for w in words {
        assert!(lines[0].contains(w), "{args:?}: {err:?} lacks {w:?}");
    }
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    err
}

/// `list --json` as JSON.
fn list_json(data: &Path) -> Value {
    serde_json::from_slice(&ok(data, &["list", "--json"]).stdout).unwrap()
}

/// A plan saved by `insert --save`: its ids and the report `insert --report` wrote.
struct Saved {
    plan: String,
    patient: String,
    report: Vec<u8>,
}

/// A plan saved as `insert ARGS… --save NAME --data DATA` saves it (the same planner run and
/// library call, `tissue_cases::Library::save`, in this process: a test of this package cannot
/// run another package's binary; `insert`'s own tests run `insert --save`): its ids and its
/// report as `insert --report` writes it. `ARGS` may hold `--max-steps N`, `--volume V`,
/// `--sweep V1,V2`, `--mesh FILE` (cm), `--at X,Y,Z` and `--scan-triangles`.
fn insert_save(data: &Path, dir: &Path, name: &str, args: &[&str]) -> Saved {
    use tissue_cases::{Library, NewPlan, Scan};
    use tissue_planner::{CancelToken, JobSpec, Patient, Scenario, Tool, Unit};
    let mut request = serde_json::Map::new();
    let mut job = serde_json::Map::new();
    let mut mesh: Option<PathBuf> = None;
    let mut it = args.iter();
    let numbers = |v: &str| -> Vec<f64> { v.split(',').map(|x| x.parse().unwrap()).collect() };
    while let Some(&flag) = it.next() {
        match flag {
            "--scan-triangles" => {
                request.insert("scan_triangles".into(), true.into());
            }
            "--max-steps" => {
                let n: u64 = it.next().unwrap().parse().unwrap();
                request.insert("max_steps".into(), n.into());
            }
            "--volume" => {
                request.insert("volume_cm3".into(), numbers(it.next().unwrap())[0].into());
            }
            "--at" => {
                request.insert("at".into(), numbers(it.next().unwrap()).into());
            }
            "--sweep" => {
                job.insert("mode".into(), "sweep".into());
                job.insert("volumes_cm3".into(), numbers(it.next().unwrap()).into());
            }
            "--mesh" => mesh = Some(PathBuf::from(it.next().unwrap())),
            other => panic!("insert_save does not know {other}"),
        }
    }
    job.insert("request".into(), request.into());
    let spec: JobSpec = serde_json::from_value(job.into()).unwrap();
    let (patient, scan, label) = match &mesh {
        Some(path) => (
            Patient::read(path, Unit::Cm).unwrap(),
            Scan::read(path, Unit::Cm).unwrap(),
            None,
        ),
        None => {
            let p = Patient::table2().unwrap();
            let scan = Scan::of_mesh(&p, "table2").unwrap();
            (p, scan, Some("Table 2 plane"))
        }
    };
    let scenario = Scenario::new(patient, spec.request.clone()).unwrap();
    let finished = spec
        .plan(&scenario)
        .unwrap()
        .run(&scenario, Tool::Insert, &CancelToken::new(), |_| {})
        .unwrap();
    let report = dir.join(format!("{}.json", name.replace(' ', "_")));
    finished.report.write(&report).unwrap();
    let library = Library::open(data).unwrap();
    let plan = library
        .save(
            &scan,
            label,
            NewPlan {
                name,
                note: "",
                spec: &spec,
                finished: &finished,
            },
        )
        .unwrap();
    Saved {
        plan: plan.uid,
        patient: plan.patient_uid,
        report: std::fs::read(&report).unwrap(),
    }
}

/// Table 2 cut short (60 steps) at `volume` cm³.
fn table2(volume: &str) -> [&str; 4] {
    ["--max-steps", "60", "--volume", volume]
}

/// The (uid, name) of every patient and plan of `list --json`, in order.
fn ids_and_names(list: &Value) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for entry in list.as_array().unwrap() {
        let p = &entry["patient"];
        out.push((
            p["uid"].as_str().unwrap().to_owned(),
            p["label"].as_str().unwrap().to_owned(),
        ));
        for plan in entry["plans"].as_array().unwrap() {
            out.push((
                plan["uid"].as_str().unwrap().to_owned(),
                plan["name"].as_str().unwrap().to_owned(),
            ));
        }
    }
    out
}
