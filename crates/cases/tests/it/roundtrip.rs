//! Save, reopen from a new handle, and compare everything a front end shows or downloads.

use tissue_cases::Library;
use tissue_planner::PatientResult;

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
    assert_eq!(opened.report_json, finished.report.to_json().unwrap());
    assert_eq!(opened.job_json, serde_json::to_string(&spec).unwrap());
    let (orig, back) = (
        finished.patient.as_ref().unwrap(),
        opened.result.as_ref().unwrap(),
    );
    assert_same_result(orig, back);
    assert_eq!(
        downloads(orig, tmp.path(), "orig"),
        downloads(back, tmp.path(), "back")
    );
    // The scan comes back as it went in, and the stored mesh is the parsed one.
    let stored_scan = lib.scan(&patients[0].uid).unwrap();
    assert_eq!(stored_scan.bytes, scan.bytes);
    let loaded = lib.load_patient(&patients[0].uid).unwrap();
    let parsed = scan.patient().unwrap();
    assert_eq!(loaded.file.positions(), parsed.file.positions());
    assert_eq!(loaded.cm.positions(), parsed.cm.positions());
    assert_eq!(lib.integrity_check().unwrap(), "ok");
}
