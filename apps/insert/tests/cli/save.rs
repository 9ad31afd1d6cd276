//! `insert --save`: the run stored in the case library, read back through tissue-cases. Every
//! test gives the library's folder (`--data`, or `XDG_DATA_HOME` for the default), never the
//! real user data folder.

use super::*;
use tissue_cases::Library;

/// Table 2, cut short: a plan in about a second.
const SHORT_TABLE2: [&str; 2] = ["--max-steps", "60"];

/// The plan and patient ids of `insert: saved plan c… "NAME" for patient p… in PATH`, checking
/// the line's shape and its database path.
fn saved_ids(err: &str, name: &str, data: &Path) -> (String, String) {
    let line = err
        .lines()
        .find(|l| l.starts_with("insert: saved plan "))
        .unwrap_or_else(|| panic!("no saved line in:\n{err}"));
    let words: Vec<&str> = line.split(' ').collect();
    let plan = words[3].to_owned();
    assert!(
        plan.starts_with('c') && plan.len() == 33,
        "plan id in {line:?}"
    );
    assert!(
        line.contains(&format!(" {name:?} for patient p")),
        "{line:?}"
    );
    let at = line.find("for patient ").unwrap() + "for patient ".len();
    let patient = line[at..at + 33].to_owned();
    assert!(patient.starts_with('p'), "patient id in {line:?}");
    let db = data.join(tissue_cases::DATABASE_FILE);
    assert!(
        line.ends_with(&format!(" in {}", db.display())),
        "{line:?} does not name {}",
        db.display()
    );
    (plan, patient)
}

#[test]
fn a_saved_run_keeps_its_report_byte_for_byte_in_a_private_library() {
    let dir = scratch("save-table2");
    let data = dir.join("library");
    let report = dir.join("r.json");
    let o = run(&[
        SHORT_TABLE2[0],
        SHORT_TABLE2[1],
        "--quiet",
        "--report",
        report.to_str().unwrap(),
        "--save",
        "first plan",
        "--note",
        "short run\nfor the test",
        "--data",
        data.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    // The outputs are written before the plan is saved.
    let wrote = err.find("insert: wrote").unwrap();
    assert!(wrote < err.find("insert: saved plan").unwrap(), "{err}");
    let (plan_uid, patient_uid) = saved_ids(&err, "first plan", &data);

    let library = Library::open(&data).unwrap();
    let stored = library.open_plan(&plan_uid).unwrap();
    assert_eq!(
        stored.report_json.as_bytes(),
        std::fs::read(&report).unwrap(),
        "the stored report is not insert --report's file"
    );
    assert_eq!(stored.info.name, "first plan");
    assert_eq!(stored.info.note, "short run\nfor the test");
    assert_eq!(stored.info.mode, "single");
    assert_eq!(stored.info.tool, "insert");
    assert!(stored.info.has_result && stored.result.is_some());
    let job: Value = serde_json::from_str(&stored.job_json).unwrap();
    assert_eq!(job["request"]["max_steps"], 60);
    let patient = library.patient(&patient_uid).unwrap();
    assert_eq!(patient.label, "Table 2 plane");
    assert_eq!(patient.unit, "cm");
    assert_eq!(patient.plans, 1);

    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&data), 0o700, "the library's folder");
        assert_eq!(
            mode(&data.join(tissue_cases::DATABASE_FILE)),
            0o600,
            "the database file"
        );
    }
}

#[test]
fn a_scan_in_mm_is_saved_with_its_bytes_and_unit() {
    let dir = scratch("save-mm");
    let data = dir.join("library");
    // The small plane written by hand in millimetres: 120 mm across.
    let cm = tissue_mesh::grid(17, 12.0).unwrap();
    let mut obj = String::from("# 12 cm plane in mm\n");
    for p in cm.positions() {
        obj.push_str(&format!("v {} {} {}\n", p.x * 10.0, p.y * 10.0, p.z * 10.0));
    }
    for t in cm.triangles() {
        obj.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    let mesh = dir.join("plane_mm.obj");
    std::fs::write(&mesh, &obj).unwrap();
    let args = |volume: &str, name: &str| {
        vec![
            "--mesh".to_owned(),
            mesh.to_str().unwrap().to_owned(),
            "--unit".into(),
            "mm".into(),
            "--at".into(),
            "0,0,0".into(),
            "--diameter".into(),
            "4".into(),
            "--implant-vertices".into(),
            "100".into(),
            "--quiet".into(),
            "--data".into(),
            data.to_str().unwrap().into(),
            "--save".into(),
            name.into(),
            "--sweep".into(),
            volume.into(),
        ]
    };
    let o = bin().args(args("5,10", "a sweep")).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let (sweep_uid, patient_uid) = saved_ids(&stderr(&o), "a sweep", &data);
    // The same scan in the same unit is the same patient; a label given later is not applied.
    let mut single = args("10", "one run");
    single.truncate(single.len() - 2);
    single.extend([
        "--volume".into(),
        "10".into(),
        "--label".into(),
        "other".into(),
    ]);
    let o = bin().args(&single).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let (single_uid, same_patient) = saved_ids(&stderr(&o), "one run", &data);
    assert_eq!(same_patient, patient_uid);

    let library = Library::open(&data).unwrap();
    let patient = library.patient(&patient_uid).unwrap();
    assert_eq!(patient.unit, "mm");
    assert_eq!(patient.scan_name, "plane_mm.obj");
    assert_eq!(
        patient.label, "plane_mm.obj",
        "the default label is the file name"
    );
    assert_eq!(patient.plans, 2);
    let scan = library.scan(&patient_uid).unwrap();
    assert_eq!(scan.bytes, obj.as_bytes(), "the scan is stored as it came");
    assert_eq!(scan.unit, tissue_planner::Unit::Mm);
    assert_eq!(library.plan(&sweep_uid).unwrap().mode, "sweep");
    let single = library.open_plan(&single_uid).unwrap();
    assert_eq!(single.info.mode, "single");
    // The result is in the scan's unit: the plane is 120 mm across.
    let result = single.result.unwrap();
    let width = result
        .after
        .positions()
        .iter()
        .map(|p| p.x)
        .fold(f32::MIN, f32::max);
    assert!((width - 60.0).abs() < 1e-3, "half-width {width} mm");
    let plans = library.plans(&patient_uid).unwrap();
    let names: Vec<&str> = plans.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["one run", "a sweep"], "newest first");
}

/// A search and an expansion are saved like a single run: their mode, their report byte for
/// byte, the search's answer among the list's figures, the expansion's chart.
#[test]
fn a_search_and_an_expansion_are_saved_with_their_report() {
    let dir = scratch("save-modes");
    let data = dir.join("library");
    let mut saved = Vec::new();
    for (name, mode_args) in [
        (
            "search",
            &["--target-gain", "10", "--bracket", "50,150"][..],
        ),
        (
            "expansion",
            &["--expand-weeks", "2", "--band-samples", "0"][..],
        ),
    ] {
        let report = dir.join(format!("{name}.json"));
        let o = bin()
            .args(SHORT_TABLE2)
            .args(mode_args)
            .args(["--quiet", "--save", name, "--data"])
            .arg(&data)
            .arg("--report")
            .arg(&report)
            .output()
            .unwrap();
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let (plan, _) = saved_ids(&stderr(&o), name, &data);
        saved.push((plan, std::fs::read(&report).unwrap()));
    }
    let library = Library::open(&data).unwrap();
    let search = library.open_plan(&saved[0].0).unwrap();
    assert_eq!(search.info.mode, "target-gain");
    assert_eq!(search.report_json.as_bytes(), saved[0].1);
    let report: Value = serde_json::from_slice(&saved[0].1).unwrap();
    assert_eq!(search.info.volume_cm3, report["volume_cm3"].as_f64());
    assert_eq!(search.info.area_gain_cm2, report["area_gain_cm2"].as_f64());
    assert!(search.info.volume_cm3.is_some());
    let expansion = library.open_plan(&saved[1].0).unwrap();
    assert_eq!(expansion.info.mode, "expansion");
    assert_eq!(expansion.report_json.as_bytes(), saved[1].1);
    assert!(!expansion.info.has_result && expansion.result.is_none());
    let chart = expansion.chart_png.expect("an expansion's chart");
    assert_eq!(&chart[1..4], b"PNG");
}

#[test]
fn a_bad_name_or_library_is_refused_before_the_run() {
    let dir = scratch("save-refused");
    let data = dir.join("library");
    for name in ["", "   ", "two\nlines"] {
        let o = run(&["--save", name, "--data", data.to_str().unwrap()]);
        let err = stderr(&o);
        assert_eq!(
            o.status.code(),
            Some(Exit::Usage.code().into()),
            "{name:?}: {err}"
        );
        assert!(err.contains("insert: error: --save"), "{err}");
        assert!(!err.contains("step"), "it ran: {err}");
        assert!(!data.exists(), "the library was made for a refused name");
    }
    let long = "x".repeat(201);
    assert_fails(
        &["--save", &long, "--data", data.to_str().unwrap()],
        Exit::Usage,
        &["--save", "201 characters", "at most 200"],
    );
    assert_fails(
        &[
            "--save",
            "ok",
            "--label",
            "",
            "--data",
            data.to_str().unwrap(),
        ],
        Exit::Usage,
        &["--label", "empty"],
    );
    // --data on a file: a clear error, before the run, and the file is untouched.
    let file = dir.join("not-a-folder");
    std::fs::write(&file, "keep me").unwrap();
    let o = run(&["--save", "ok", "--data", file.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(Exit::Output.code().into()), "{err}");
    assert!(
        err.contains("not-a-folder") && err.contains("--data"),
        "{err}"
    );
    assert!(!err.contains("step"), "it ran: {err}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep me");
    // The library's flags need --save.
    for flag in ["--note", "--label", "--data"] {
        let o = run(&[flag, "x"]);
        assert_eq!(o.status.code(), Some(2), "{flag}: {}", stderr(&o));
        assert!(stderr(&o).contains("--save"), "{}", stderr(&o));
    }
}

#[test]
fn a_library_of_a_newer_tissue_is_refused_before_the_run() {
    let dir = scratch("save-newer");
    let data = dir.join("library");
    let report = dir.join("r.json");
    // A database written by a newer tissue (its schema version raised) is refused, never
    // altered: the library is opened before the run, so the run does not start.
    Library::open(&data).unwrap();
    let db = data.join(tissue_cases::DATABASE_FILE);
    let mut bytes = std::fs::read(&db).unwrap();
    // SQLite's header: the user version is the big-endian u32 at offset 60.
    bytes[60..64].copy_from_slice(&99u32.to_be_bytes());
    std::fs::write(&db, &bytes).unwrap();
    let o = run(&[
        SHORT_TABLE2[0],
        SHORT_TABLE2[1],
        "--quiet",
        "--report",
        report.to_str().unwrap(),
        "--save",
        "newer",
        "--data",
        data.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(Exit::Output.code().into()), "{err}");
    assert!(
        err.contains("newer") && err.contains("update tissue"),
        "{err}"
    );
    assert!(!err.contains("step"), "it ran: {err}");
    assert!(!report.exists());
    assert_eq!(
        std::fs::read(&db).unwrap(),
        bytes,
        "the newer library was altered"
    );
}

/// Without --data the library is the platform's data folder: `$XDG_DATA_HOME/tissue` on Linux
/// (set to a scratch folder here).
#[cfg(target_os = "linux")]
#[test]
fn the_default_library_is_in_the_data_folder() {
    let dir = scratch("save-default");
    let o = bin()
        .args([
            SHORT_TABLE2[0],
            SHORT_TABLE2[1],
            "--quiet",
            "--save",
            "default",
        ])
        .env("XDG_DATA_HOME", dir.as_ref())
        .env("HOME", dir.as_ref())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let data = dir.join("tissue");
    saved_ids(&stderr(&o), "default", &data);
    assert!(data.join(tissue_cases::DATABASE_FILE).is_file());
}

/// Ctrl-C once the outputs are written, while the plan is being saved: the save is not cut (the
/// handler only sets the cancel flag), the program ends as it would have, and the library holds
/// the plan and passes its integrity check.
#[cfg(unix)]
#[test]
fn ctrl_c_during_the_save_does_not_cut_it() {
    let dir = scratch("save-ctrl-c");
    let data = dir.join("library");
    let report = dir.join("r.json");
    let mut child = bin()
        .args(SHORT_TABLE2)
        .args(["--quiet", "--save", "interrupted?", "--data"])
        .arg(&data)
        .arg("--report")
        .arg(&report)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let mut seen = Vec::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        let wrote = line.starts_with("insert: wrote");
        seen.push(line);
        if wrote {
            // The outputs are in place: the save comes next. Interrupt it, several times.
            for _ in 0..3 {
                let _ = Command::new("kill")
                    .args(["-INT", &child.id().to_string()])
                    .status();
            }
            break;
        }
    }
    seen.extend(lines.map_while(Result::ok));
    let exit = child.wait().unwrap();
    let err = seen.join("\n");
    assert!(exit.success(), "{exit}: {err}");
    let (plan, _) = saved_ids(&err, "interrupted?", &data);
    let library = Library::open(&data).unwrap();
    assert_eq!(library.integrity_check().unwrap(), "ok");
    assert_eq!(
        library.open_plan(&plan).unwrap().report_json.as_bytes(),
        std::fs::read(&report).unwrap()
    );
}

#[test]
fn help_documents_the_case_library() {
    let o = run(&["--help"]);
    assert!(o.status.success());
    let help = stdout(&o).split_whitespace().collect::<Vec<_>>().join(" ");
    for needle in [
        "--save <NAME>",
        "--note <TEXT>",
        "--label <TEXT>",
        "--data <DIR>",
        "~/.local/share/tissue",
        "CASE LIBRARY",
        "docs/cases.md",
        "the plan could not be stored",
    ] {
        assert!(help.contains(needle), "no {needle:?} in:\n{help}");
    }
}
