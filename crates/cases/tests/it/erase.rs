//! Erasure: a patient's scan leaves no bytes in the library's files.

use tissue_cases::{Library, Scan};
use tissue_planner::Unit;

use crate::common::{blob_count, chest_single, run, save, table2, Lcg, Tmp};

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    hay.windows(needle.len()).any(|w| w == needle)
}

/// The library's files as bytes: the database and its WAL (empty when absent).
fn files(lib: &Library) -> (Vec<u8>, Vec<u8>) {
    let db = std::fs::read(lib.database_path()).unwrap();
    let wal = std::fs::read(lib.dir().join("cases.sqlite-wal")).unwrap_or_default();
    (db, wal)
}

#[test]
fn an_erased_patients_scan_is_in_no_file_and_the_other_is_intact() {
    let tmp = Tmp::new("erase");
    // A scan whose first line holds a 64-byte random marker.
    let seed = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64;
    let mut rng = Lcg(seed);
    let marker: String = (0..64)
        .map(|_| char::from(b"0123456789abcdefghijklmnopqrstuvwxyz"[(rng.next() % 36) as usize]))
        .collect();
    let (plane, plain) = table2();
    let mut bytes = format!("# marker {marker}\n").into_bytes();
    bytes.extend_from_slice(&plain.bytes);
    let scan = Scan {
        name: "secret.obj".into(),
        unit: Unit::Cm,
        bytes,
    };
    // A long run of its vertex data, from the middle of its vertex lines.
    let text = String::from_utf8(plain.bytes.clone()).unwrap();
    let start = text.find("\nv ").unwrap() + 2000;
    let vertex_run = text.as_bytes()[start..start + 400].to_vec();
    assert!(contains(&vertex_run, b"\nv "));
    // And its mesh as stored (f32 positions, little-endian): the first 20 vertices.
    let mesh_run: Vec<u8> = plane.file.positions()[..20]
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();

    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let (spec, finished) = run(&plane, r#"{ "request": { "max_steps": 40 } }"#);
    let secret = save(&lib, &scan, "to erase", &spec, &finished);
    save(&lib, &scan, "to erase too", &spec, &finished);
    let (chest_scan, chest_spec, chest) = chest_single(40);
    let kept = save(&lib, &chest_scan, "kept", &chest_spec, &chest);

    let (db, wal) = files(&lib);
    let all = [db, wal].concat();
    assert!(
        contains(&all, marker.as_bytes()),
        "the marker was never written"
    );
    assert!(contains(&all, &vertex_run));
    assert!(contains(&all, &mesh_run));

    lib.erase_patient(&secret.patient_uid).unwrap();
    let (db, wal) = files(&lib);
    for (name, file) in [("cases.sqlite", &db), ("cases.sqlite-wal", &wal)] {
        assert!(
            !contains(file, marker.as_bytes()),
            "the marker is in {name}"
        );
        assert!(
            !contains(file, &vertex_run),
            "the scan's vertex lines are in {name}"
        );
        assert!(!contains(file, &mesh_run), "the stored mesh is in {name}");
    }
    assert_eq!(lib.integrity_check().unwrap(), "ok");
    assert!(matches!(
        lib.patient(&secret.patient_uid),
        Err(tissue_cases::CaseError::NotFound { .. })
    ));
    assert!(lib.open_plan(&secret.uid).is_err());
    let patients = lib.patients(None).unwrap();
    assert_eq!(patients.len(), 1);
    let opened = lib.open_plan(&kept.uid).unwrap();
    assert_eq!(opened.report_json, chest.report.to_json().unwrap());
    assert_eq!(lib.scan(&kept.patient_uid).unwrap().bytes, chest_scan.bytes);
    // Only the kept patient's blobs remain: scan, mesh, result.
    assert_eq!(blob_count(&lib), 3);
}

#[test]
fn deleting_a_plan_removes_its_unshared_blobs_only() {
    let tmp = Tmp::new("delete");
    let (_, scan) = table2();
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let (spec, a) = crate::common::table2_single(100.0, 40);
    let (spec_b, b) = crate::common::table2_single(60.0, 40);
    let pa = save(&lib, &scan, "a", &spec, &a);
    let pa2 = save(&lib, &scan, "a again", &spec, &a);
    let pb = save(&lib, &scan, "b", &spec_b, &b);
    let count = || blob_count(&lib);
    assert_eq!(count(), 4); // scan, mesh, two results
    lib.delete_plan(&pb.uid).unwrap();
    assert_eq!(count(), 3);
    lib.delete_plan(&pa.uid).unwrap();
    assert_eq!(count(), 3, "a's result is still named by its copy");
    assert!(lib.open_plan(&pa2.uid).unwrap().result.is_some());
    assert!(matches!(
        lib.delete_plan(&pa.uid),
        Err(tissue_cases::CaseError::NotFound { what: "plan", .. })
    ));
    assert_eq!(lib.integrity_check().unwrap(), "ok");
}
