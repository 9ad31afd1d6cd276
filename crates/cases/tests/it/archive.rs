//! Export and import: a case moves between libraries whole, and a damaged, foreign or
//! oversized archive is refused without changing anything.

use std::io::{Cursor, Read, Write};

use tissue_cases::{CaseError, Library};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipArchive, ZipWriter};

use crate::common::{run, save, table2, Lcg, Tmp};

/// The entries of a zip, in order.
fn unzip(bytes: &[u8]) -> Vec<(String, Vec<u8>)> {
    let mut ar = ZipArchive::new(Cursor::new(bytes)).unwrap();
    (0..ar.len())
        .map(|i| {
            let mut f = ar.by_index(i).unwrap();
            let mut b = Vec::new();
            f.read_to_end(&mut b).unwrap();
            (f.name().unwrap().into_owned(), b)
        })
        .collect()
}

fn rezip(entries: &[(String, Vec<u8>)]) -> Vec<u8> {
    let mut w = ZipWriter::new(Cursor::new(Vec::new()));
    for (name, bytes) in entries {
        w.start_file(
            name.as_str(),
            SimpleFileOptions::default().compression_method(CompressionMethod::Deflated),
        )
        .unwrap();
        w.write_all(bytes).unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// `zip` with the uncompressed size of entry `name` set to `size` in its local and central
/// headers (no zip64, no data descriptor: what `ZipWriter` writes to a `Cursor`).
fn claim_size(zip: &[u8], name: &str, size: u32) -> Vec<u8> {
    let mut out = zip.to_vec();
    let mut patched = 0;
    for i in 0..out.len().saturating_sub(46) {
        // (where the name starts, the uncompressed size, the name's length) per header.
        let (name_at, size_at, len_at) = match &out[i..i + 4] {
            b"PK\x03\x04" => (30, 22, 26),
            b"PK\x01\x02" => (46, 24, 28),
            _ => continue,
        };
        let len = u16::from_le_bytes([out[i + len_at], out[i + len_at + 1]]) as usize;
        if out.get(i + name_at..i + name_at + len) == Some(name.as_bytes()) {
            out[i + size_at..i + size_at + 4].copy_from_slice(&size.to_le_bytes());
            patched += 1;
        }
    }
    assert_eq!(patched, 2, "the entry's two headers");
    out
}

/// Everything a library holds, to see that a refused import changed nothing.
fn snapshot(lib: &Library) -> Vec<String> {
    let mut out = Vec::new();
    for p in lib.patients(None).unwrap() {
        out.push(format!("{p:?}"));
        for c in lib.plans(&p.uid).unwrap() {
            out.push(format!("{c:?}"));
        }
    }
    out
}

fn assert_archive_error(r: Result<tissue_cases::ImportSummary, CaseError>, says: &str) {
    match r {
        Err(CaseError::Archive { message }) => {
            assert!(message.contains(says), "{message:?} does not say {says:?}")
        }
        other => panic!("expected an archive error, got {other:?}"),
    }
}

#[test]
fn a_case_exports_and_imports_whole_once() {
    let tmp = Tmp::new("export");
    let (patient, scan) = table2();
    let (single_spec, single) = run(&patient, r#"{ "request": { "max_steps": 40 } }"#);
    let (sweep_spec, sweep) = run(
        &patient,
        r#"{ "mode": "sweep", "volumes_cm3": [20, 40], "request": { "max_steps": 40 } }"#,
    );
    let from = Library::open(&tmp.0.join("from")).unwrap();
    let a = save(&from, &scan, "single", &single_spec, &single);
    let b = save(&from, &scan, "sweep", &sweep_spec, &sweep);
    from.set_note(&a.uid, "fill slowly").unwrap();
    from.rename_patient(&a.patient_uid, "Ms Example").unwrap();
    let path = tmp.0.join("case.zip");
    from.export_case_to(&a.patient_uid, &path).unwrap();
    let zip = std::fs::read(&path).unwrap();
    let names: Vec<String> = unzip(&zip).into_iter().map(|(n, _)| n).collect();
    for want in [
        "case.json".to_owned(),
        "scan/table2.obj".to_owned(),
        format!("plans/{}/job.json", a.uid),
        format!("plans/{}/report.json", a.uid),
        format!("plans/{}/result.bin", a.uid),
        format!("plans/{}/patient.ply", a.uid),
        format!("plans/{}/patient.vtk", a.uid),
        format!("plans/{}/report.json", b.uid),
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    assert!(!names.contains(&format!("plans/{}/result.bin", b.uid)));
    let case: serde_json::Value = serde_json::from_slice(&unzip(&zip)[0].1).unwrap();
    assert_eq!(case["format"], "tissue-case");
    assert_eq!(case["format_version"], 1);

    let to = Library::open(&tmp.0.join("to")).unwrap();
    let summary = to.import_case(&zip).unwrap();
    assert_eq!((summary.plans_added, summary.plans_skipped), (2, 0));
    assert_eq!(summary.patient.uid, a.patient_uid);
    assert_eq!(summary.patient.label, "Ms Example");
    assert_eq!(to.scan(&a.patient_uid).unwrap().bytes, scan.bytes);
    for (uid, finished) in [(&a.uid, &single), (&b.uid, &sweep)] {
        let x = from.open_plan(uid).unwrap();
        let y = to.open_plan(uid).unwrap();
        assert_eq!(y.report_json, finished.report.to_json().unwrap());
        assert_eq!(x.info, y.info);
        assert_eq!(x.job_json, y.job_json);
        let bits = |r: &Option<tissue_planner::PatientResult>| {
            r.as_ref().map(|r| {
                let mut v: Vec<u32> = r
                    .after
                    .positions()
                    .iter()
                    .flat_map(|p| p.to_array())
                    .map(f32::to_bits)
                    .collect();
                v.extend(
                    r.displacement
                        .iter()
                        .chain(&r.stretch)
                        .chain(&r.in_region)
                        .map(|x| x.to_bits()),
                );
                v
            })
        };
        assert_eq!(bits(&x.result), bits(&y.result));
    }
    assert_eq!(to.plan(&a.uid).unwrap().note, "fill slowly");
    // Twice: nothing added.
    let again = to.import_case(&zip).unwrap();
    assert_eq!((again.plans_added, again.plans_skipped), (0, 2));
    assert_eq!(to.patients(None).unwrap().len(), 1);
    assert_eq!(to.integrity_check().unwrap(), "ok");
}

#[test]
fn damaged_foreign_and_oversized_archives_are_refused_and_change_nothing() {
    let tmp = Tmp::new("refuse");
    let (patient, scan) = table2();
    let (spec, finished) = run(&patient, r#"{ "request": { "max_steps": 40 } }"#);
    let from = Library::open(&tmp.0.join("from")).unwrap();
    let a = save(&from, &scan, "single", &spec, &finished);
    let zip = from.export_case(&a.patient_uid).unwrap();
    let entries = unzip(&zip);

    // The target holds another case, which must stay as it is.
    let to = Library::open(&tmp.0.join("to")).unwrap();
    let (chest_scan, chest_spec, chest) = crate::common::chest_single(40);
    save(&to, &chest_scan, "chest", &chest_spec, &chest);
    let before = snapshot(&to);

    // One byte of report.json changed.
    let mut tampered = entries.clone();
    let report = format!("plans/{}/report.json", a.uid);
    let e = tampered.iter_mut().find(|(n, _)| *n == report).unwrap();
    let i = e.1.len() / 2;
    e.1[i] = if e.1[i] == b'1' { b'2' } else { b'1' };
    assert_archive_error(to.import_case(&rezip(&tampered)), "SHA-256");

    // A file not listed in case.json.
    let mut extra = entries.clone();
    extra.push(("plans/extra.txt".into(), b"hello".to_vec()));
    assert_archive_error(to.import_case(&rezip(&extra)), "not listed");

    // A listed file missing.
    let missing: Vec<_> = entries
        .iter()
        .filter(|(n, _)| !n.ends_with("result.bin"))
        .cloned()
        .collect();
    assert_archive_error(to.import_case(&rezip(&missing)), "missing");

    // No case.json.
    let no_case: Vec<_> = entries
        .iter()
        .filter(|(n, _)| n != "case.json")
        .cloned()
        .collect();
    assert_archive_error(to.import_case(&rezip(&no_case)), "case.json");

    // Random bytes.
    let mut rng = Lcg(42);
    let noise: Vec<u8> = (0..10_000).map(|_| rng.next() as u8).collect();
    assert_archive_error(to.import_case(&noise), "not a zip");

    // A zip bomb: 300 MiB of zeros, a few hundred KiB compressed.
    let mut w = ZipWriter::new(Cursor::new(Vec::new()));
    w.start_file(
        "case.json",
        SimpleFileOptions::default().compression_method(CompressionMethod::Deflated),
    )
    .unwrap();
    w.write_all(&entries[0].1).unwrap();
    w.start_file(
        "scan/table2.obj",
        SimpleFileOptions::default()
            .compression_method(CompressionMethod::Deflated)
            .large_file(false),
    )
    .unwrap();
    let zeros = vec![0u8; 1 << 20];
    for _ in 0..300 {
        w.write_all(&zeros).unwrap();
    }
    let bomb = w.finish().unwrap().into_inner();
    assert!(bomb.len() < 2 << 20, "the bomb is {} bytes", bomb.len());
    assert_archive_error(to.import_case(&bomb), "MiB");

    // The same bomb with headers that claim 1000 bytes: the unpacking itself is bounded.
    let lying = claim_size(&bomb, "scan/table2.obj", 1000);
    assert_archive_error(to.import_case(&lying), "scan/table2.obj does not unpack");

    assert_eq!(snapshot(&to), before);
    assert_eq!(to.integrity_check().unwrap(), "ok");
    // And the untampered archive still imports.
    assert_eq!(to.import_case(&zip).unwrap().plans_added, 1);
}
