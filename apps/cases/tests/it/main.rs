//! The real `tissue-cases` binary, end to end, on plans that the real `insert --save` stored in
//! scratch libraries (`--data`; never the user's data folder): the list, a report byte for byte,
//! export and import into another library, rename and note, delete and erase, the integrity
//! check, and each error's exit code.
#![allow(clippy::unwrap_used, clippy::panic, clippy::expect_used)]

mod commands;
mod errors;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use serde_json::Value;

/// The `tissue-cases` binary.
fn cases() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tissue-cases"))
}

/// The `insert` binary of this build's profile, in this target folder. Cargo builds only this
/// package's binaries for its tests, so it is built here once (a no-op when it is up to date:
/// `cargo test --workspace` has built it).
fn insert_bin() -> &'static Path {
    static INSERT: OnceLock<PathBuf> = OnceLock::new();
    INSERT.get_or_init(|| {
        let ours = Path::new(env!("CARGO_BIN_EXE_tissue-cases"));
        let profile_dir = ours.parent().unwrap();
        let target = profile_dir.parent().unwrap();
        let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let mut build = Command::new(cargo);
        build
            .current_dir(&workspace)
            .args(["build", "--quiet", "-p", "tissue-insert", "--bin", "insert"])
            .arg("--target-dir")
            .arg(target);
        if profile_dir.file_name().is_some_and(|n| n == "release") {
            build.arg("--release");
        }
        let status = build.status().expect("cargo runs");
        assert!(status.success(), "building insert failed: {status}");
        let insert = profile_dir.join(format!("insert{}", std::env::consts::EXE_SUFFIX));
        assert!(insert.is_file(), "no {}", insert.display());
        insert
    })
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

/// Runs `insert ARGS… --save NAME --data DATA --report DIR/NAME.json --quiet` and reads the
/// ids from its `insert: saved plan c… "NAME" for patient p… in …` line.
fn insert_save(data: &Path, dir: &Path, name: &str, args: &[&str]) -> Saved {
    let report = dir.join(format!("{}.json", name.replace(' ', "_")));
    let o = Command::new(insert_bin())
        .args(args)
        .args(["--quiet", "--save", name, "--data"])
        .arg(data)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "insert {args:?}: {err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("insert: saved plan "))
        .unwrap_or_else(|| panic!("no saved line: {err}"));
    let words: Vec<&str> = line.split(' ').collect();
    let at = line.find("for patient ").unwrap() + "for patient ".len();
    Saved {
        plan: words[3].to_owned(),
        patient: line[at..at + 33].to_owned(),
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
