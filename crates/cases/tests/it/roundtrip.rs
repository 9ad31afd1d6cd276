//! Save, reopen from a new handle, and compare everything a front end shows or downloads.

use tissue_cases::Library;
use tissue_cases::StoredPlan;
use tissue_planner::{Finished, PatientResult};

use crate::common::{save, table2, table2_single, Tmp};

/// The three mesh downloads of `r`, written through `PatientResult::write_mesh`.
fn downloads(r: &PatientResult, dir: &std::path::Path, tag: &str) -> Vec<Vec<u8>> {
    ["ply", "obj", "vtk"]
        .iter()
        .map(|ext| {
            let path = dir.join(format!("{tag}.{ext}"));
            r.write_mesh(&path).unwrap();
            std::fs::read(&path).unwrap()
        })
        .collect()
}

/// The reopened plan's report is the run's byte for byte, its result bit for bit, and its
/// three mesh downloads byte for byte; returns both results.
fn assert_reopened<'a>(
    finished: &'a Finished,
    opened: &'a StoredPlan,
    dir: &std::path::Path,
) -> (&'a PatientResult, &'a PatientResult) {
    assert_eq!(opened.report_json, finished.report.to_json().unwrap());
    let (orig, back) = (
        finished.patient.as_ref().unwrap(),
        opened.result.as_ref().unwrap(),
    );
    assert_same_result(orig, back);
    assert_eq!(downloads(orig, dir, "orig"), downloads(back, dir, "back"));
    (orig, back)
}

fn assert_same_result(a: &PatientResult, b: &PatientResult) {
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let pos = |m: &tissue_mesh::TriMesh| {
        m.positions()
            .iter()
            .flat_map(|p| p.to_array())
            .map(f32::to_bits)
            .collect::<Vec<_>>()
    };
    assert_eq!(pos(&a.before), pos(&b.before));
    assert_eq!(a.before.triangles(), b.before.triangles());
    assert_eq!(pos(&a.after), pos(&b.after));
    assert_eq!(bits(&a.displacement), bits(&b.displacement));
    assert_eq!(bits(&a.stretch), bits(&b.stretch));
    assert_eq!(bits(&a.in_region), bits(&b.in_region));
}

#[test]
fn a_single_run_reopens_byte_identical_from_a_new_handle() {
    let tmp = Tmp::new("roundtrip");
    let (_, scan) = table2();
    let (spec, finished) = table2_single(100.0, 40);
    let saved = {
        let lib = Library::open(&tmp.lib_dir()).unwrap();
        save(&lib, &scan, "first try", &spec, &finished)
    };
    assert!(saved.uid.starts_with('c') && saved.uid.len() == 33);
    assert_eq!(saved.mode, "single");
    assert!(saved.has_result);
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let patients = lib.patients(None).unwrap();
    assert_eq!(patients.len(), 1);
    assert_eq!(patients[0].plans, 1);
    assert_eq!(patients[0].scan_bytes, scan.bytes.len() as u64);
    assert_eq!(lib.plans(&patients[0].uid).unwrap(), vec![saved.clone()]);
    let opened = lib.open_plan(&saved.uid).unwrap();
    assert_eq!(opened.job_json, serde_json::to_string(&spec).unwrap());
    assert_reopened(&finished, &opened, tmp.path());
    // The scan comes back as it went in, and the stored mesh is the parsed one.
    let stored_scan = lib.scan(&patients[0].uid).unwrap();
    assert_eq!(stored_scan.bytes, scan.bytes);
    let loaded = lib.load_patient(&patients[0].uid).unwrap();
    let parsed = scan.patient().unwrap();
    assert_eq!(loaded.file.positions(), parsed.file.positions());
    assert_eq!(loaded.cm.positions(), parsed.cm.positions());
    assert_eq!(lib.integrity_check().unwrap(), "ok");
}

#[test]
fn a_dm_scan_reopens_with_its_downloads_and_cm_positions() {
    let tmp = Tmp::new("chest");
    let (scan, spec, finished) = crate::common::chest_single(40);
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let saved = save(&lib, &scan, "chest", &spec, &finished);
    drop(lib);
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let opened = lib.open_plan(&saved.uid).unwrap();
    assert_eq!(opened.patient.unit, "dm");
    let (orig, back) = assert_reopened(&finished, &opened, tmp.path());
    // after_cm is the positions after in cm (10 cm per dm), within f32 rounding of the run's.
    let moved = orig
        .after
        .positions()
        .iter()
        .zip(orig.before.positions())
        .filter(|(a, b)| a != b)
        .count();
    assert!(moved > 0, "the run moved nothing");
    for ((c, o), a) in back
        .after_cm
        .positions()
        .iter()
        .zip(orig.after_cm.positions())
        .zip(back.after.positions())
    {
        assert_eq!(*c, *a * 10.0);
        assert!(
            (*c - *o).length() <= 1e-5 * o.length().max(1.0),
            "{c} vs {o}"
        );
    }
    assert!(back.scan.is_none());
}

#[test]
fn a_sweep_and_an_expansion_round_trip_with_the_chart() {
    let tmp = Tmp::new("modes");
    let (patient, scan) = table2();
    let (sweep_spec, sweep) = crate::common::run(
        &patient,
        r#"{ "mode": "sweep", "volumes_cm3": [20, 40], "request": { "max_steps": 40 } }"#,
    );
    let (exp_spec, expansion) = crate::common::run(
        &patient,
        r#"{ "mode": "expansion", "request": { "expand_weeks": 2, "band_samples": 8, "max_steps": 40 } }"#,
    );
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let s = save(&lib, &scan, "sweep", &sweep_spec, &sweep);
    let e = save(&lib, &scan, "expansion", &exp_spec, &expansion);
    assert_eq!((s.mode.as_str(), s.has_result), ("sweep", false));
    assert_eq!((e.mode.as_str(), e.has_result), ("expansion", false));
    assert_eq!(s.area_gain_cm2, None);
    drop(lib);
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    // Newest first.
    let listed: Vec<String> = lib
        .plans(&s.patient_uid)
        .unwrap()
        .into_iter()
        .map(|p| p.uid)
        .collect();
    assert_eq!(listed, vec![e.uid.clone(), s.uid.clone()]);
    let os = lib.open_plan(&s.uid).unwrap();
    assert_eq!(os.report_json, sweep.report.to_json().unwrap());
    assert!(os.result.is_none() && os.chart_png.is_none());
    let oe = lib.open_plan(&e.uid).unwrap();
    assert_eq!(oe.report_json, expansion.report.to_json().unwrap());
    let tissue_planner::JobReport::Expansion(r) = &expansion.report else {
        panic!("not an expansion")
    };
    let chart = oe.chart_png.expect("the expansion's chart");
    assert!(chart.starts_with(b"\x89PNG"));
    assert_eq!(chart, r.chart(tissue_cases::CHART_SIZE).unwrap());
}

#[test]
fn the_same_scan_and_unit_is_one_patient_and_another_unit_another() {
    let tmp = Tmp::new("same");
    let (_, scan) = table2();
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let a = lib.add_patient(&scan, Some("Ms A")).unwrap();
    let again = lib.add_patient(&scan, Some("ignored")).unwrap();
    assert_eq!(a.uid, again.uid);
    assert_eq!(again.label, "Ms A");
    assert!(a.uid.starts_with('p') && a.uid.len() == 33);
    assert_eq!(a.summary["vertices"], 4225);
    let mut in_mm = scan.clone();
    in_mm.unit = tissue_planner::Unit::Mm;
    let b = lib.add_patient(&in_mm, None).unwrap();
    assert_ne!(a.uid, b.uid);
    assert_eq!(b.label, "table2.obj");
    assert_eq!(lib.patients(None).unwrap().len(), 2);
    // One blob for the shared scan bytes, one mesh blob per unit? No: the file mesh is the
    // same in both units, so it too is stored once.
    assert_eq!(crate::common::blob_count(&lib), 2);
}

#[test]
fn a_noisy_holed_mm_scan_read_from_a_ply_file_reopens_byte_identical() {
    let tmp = Tmp::new("noisy");
    let face = tissue_testscans::noisy_face_scan(1).unwrap();
    assert_eq!(face.unit_name, "mm");
    let path = tmp.path().join("face.ply");
    tissue_meshio::write_ply(&path, &face.mesh).unwrap();
    let scan = tissue_cases::Scan::read(&path, tissue_planner::Unit::Mm).unwrap();
    assert_eq!(scan.name, "face.ply");
    let patient = scan.patient().unwrap();
    let forehead = face.points.iter().find(|p| p.name == "forehead").unwrap();
    let (spec, finished) = crate::common::run(
        &patient,
        &format!(
            r#"{{ "request": {{ "vertex": {}, "diameter_cm": 2.5, "volume_cm3": 2, "max_steps": 40 }} }}"#,
            forehead.vertex
        ),
    );
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let saved = save(&lib, &scan, "forehead", &spec, &finished);
    drop(lib);
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let opened = lib.open_plan(&saved.uid).unwrap();
    let (orig, _) = assert_reopened(&finished, &opened, tmp.path());
    assert!(orig.displacement.iter().any(|&d| d > 0.0));
    // Planning again on the stored patient needs no parse and gives the same mesh.
    let loaded = lib.load_patient(&saved.patient_uid).unwrap();
    assert_eq!(loaded.file.positions(), patient.file.positions());
    assert_eq!(loaded.file.triangles(), patient.file.triangles());
    assert_eq!(
        lib.patient(&saved.patient_uid).unwrap().summary["vertices"],
        patient.file.positions().len()
    );
}
