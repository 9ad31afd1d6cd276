//! The commands on plans saved by `insert --save`.

use super::*;
use tissue_cli::Exit;

#[test]
fn two_saves_are_listed_newest_first_and_a_report_is_shown_byte_for_byte() {
    let dir = scratch("list");
    let data = dir.join("library");
    let first = insert_save(&data, &dir, "first", &table2("100"));
    let second = insert_save(&data, &dir, "second", &table2("80"));
    assert_eq!(first.patient, second.patient, "one scan, one patient");

    let list = list_json(&data);
    let entries = list.as_array().unwrap();
    assert_eq!(entries.len(), 1, "{list:#}");
    let patient = &entries[0]["patient"];
    assert_eq!(patient["uid"], first.patient.as_str());
    assert_eq!(patient["label"], "Table 2 plane");
    assert_eq!(patient["unit"], "cm");
    assert_eq!(patient["plans"], 2);
    let plans = entries[0]["plans"].as_array().unwrap();
    let uids: Vec<&str> = plans.iter().map(|p| p["uid"].as_str().unwrap()).collect();
    assert_eq!(
        uids,
        [second.plan.as_str(), first.plan.as_str()],
        "newest first"
    );
    for (plan, saved) in plans.iter().zip([&second, &first]) {
        let report: Value = serde_json::from_slice(&saved.report).unwrap();
        assert_eq!(plan["mode"], "single");
        assert_eq!(plan["tool"], "insert");
        assert_eq!(plan["patient_uid"], first.patient.as_str());
        assert_eq!(plan["area_gain_cm2"], report["area_gain_cm2"]);
        assert_eq!(plan["has_result"], true);
    }
    // The readable list names them too, the patient before its plans.
    let text = stdout(&ok(&data, &["list"]));
    let at = |s: &str| text.find(s).unwrap_or_else(|| panic!("no {s} in:\n{text}"));
    assert!(at(&first.patient) < at(&second.plan));
    assert!(at(&second.plan) < at(&first.plan));
    assert!(
        text.contains("Table 2 plane") && text.contains("second"),
        "{text}"
    );

    // The report, byte for byte what insert --report wrote; by its id or a beginning of it.
    for id in [first.plan.as_str(), &first.plan[..9]] {
        let shown = ok(&data, &["show", id, "--report"]).stdout;
        assert_eq!(shown, first.report, "show {id} --report");
    }
    assert_eq!(
        ok(&data, &["show", &second.plan, "--report"]).stdout,
        second.report
    );
    let shown: Value =
        serde_json::from_slice(&ok(&data, &["show", &first.plan, "--json"]).stdout).unwrap();
    assert_eq!(shown["plan"]["uid"], first.plan.as_str());
    assert_eq!(shown["patient"]["uid"], first.patient.as_str());
    assert_eq!(
        shown["report"],
        serde_json::from_slice::<Value>(&first.report).unwrap()
    );
    assert_eq!(shown["job"]["request"]["volume_cm3"], 100.0);
    let text = stdout(&ok(&data, &["show", &first.plan]));
    assert!(
        text.contains("first") && text.contains("\"mode\": \"single\""),
        "{text}"
    );
    // A beginning that fits both plans is refused, naming them; a patient has no report.
    fails(
        &data,
        &["show", "c", "--report"],
        Exit::Usage,
        &["2 plans' ids", &first.plan, &second.plan],
    );
    fails(
        &data,
        &["show", &first.patient, "--report"],
        Exit::Usage,
        &["--report", "patient"],
    );
    // A patient: its details and plans.
    let shown: Value =
        serde_json::from_slice(&ok(&data, &["show", &first.patient, "--json"]).stdout).unwrap();
    assert_eq!(shown, entries[0]);
    let text = stdout(&ok(&data, &["show", &first.patient]));
    assert!(text.contains("4225 vertices"), "{text}");

    // The search keeps the labels that contain it, whatever the case.
    let found = stdout(&ok(&data, &["list", "--search", "TABLE 2", "--json"]));
    assert_eq!(serde_json::from_str::<Value>(&found).unwrap(), list);
    let none = ok(&data, &["list", "--search", "chest"]);
    assert!(stdout(&none).is_empty());
    assert!(stderr(&none).contains("no patients"), "{}", stderr(&none));

    // Rename and note.
    ok(&data, &["rename", &first.plan, "first, renamed"]);
    ok(&data, &["rename", &first.patient, "Mrs T."]);
    ok(&data, &["note", &second.plan, "smaller fill"]);
    let list = list_json(&data);
    assert_eq!(list[0]["patient"]["label"], "Mrs T.");
    assert_eq!(list[0]["plans"][1]["name"], "first, renamed");
    assert_eq!(list[0]["plans"][0]["note"], "smaller fill");
    fails(&data, &["rename", &first.plan, " "], Exit::Usage, &["name"]);
    // The report is as it was.
    assert_eq!(
        ok(&data, &["show", &first.plan, "--report"]).stdout,
        first.report
    );
}

#[test]
fn an_exported_case_imports_into_another_library_as_it_was() {
    let dir = scratch("export");
    let data = dir.join("library");
    let single = insert_save(&data, &dir, "single", &table2("100"));
    let sweep = insert_save(
        &data,
        &dir,
        "sweep",
        &["--max-steps", "60", "--sweep", "80,120"],
    );
    assert_eq!(single.patient, sweep.patient);
    let zip = dir.join("case.zip");
    let o = ok(
        &data,
        &["export", &single.patient, "--out", zip.to_str().unwrap()],
    );
    assert!(stderr(&o).contains("wrote"), "{}", stderr(&o));
    let bytes = std::fs::read(&zip).unwrap();
    assert_eq!(&bytes[..2], b"PK", "a zip");
    // Written atomically: no temporary file beside it.
    let mut names: Vec<String> = std::fs::read_dir(&*dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["case.zip", "library", "single.json", "sweep.json"]);

    let other = dir.join("other library");
    let o = ok(&other, &["import", zip.to_str().unwrap(), "--json"]);
    let summary: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["patient"]["uid"], single.patient.as_str());
    assert_eq!(summary["plans_added"], 2);
    assert_eq!(summary["plans_skipped"], 0);
    assert_eq!(
        ids_and_names(&list_json(&other)),
        ids_and_names(&list_json(&data))
    );
    for saved in [&single, &sweep] {
        let shown = ok(&other, &["show", &saved.plan, "--report"]).stdout;
        assert_eq!(shown, saved.report);
    }
    // Again: nothing added, nothing changed.
    let again = stdout(&ok(&other, &["import", zip.to_str().unwrap()]));
    assert!(again.contains("0 plans added, 2 already"), "{again}");
    assert_eq!(
        ids_and_names(&list_json(&other)),
        ids_and_names(&list_json(&data))
    );
    // A file that is not a case archive.
    let junk = dir.join("junk.zip");
    std::fs::write(&junk, b"not a zip").unwrap();
    fails(
        &other,
        &["import", junk.to_str().unwrap()],
        Exit::Input,
        &["archive"],
    );
    fails(
        &other,
        &["import", dir.join("missing.zip").to_str().unwrap()],
        Exit::Input,
        &["missing.zip"],
    );
}

#[test]
fn delete_and_erase_remove_them_and_erase_asks_for_yes() {
    let dir = scratch("erase");
    let data = dir.join("library");
    let a = insert_save(&data, &dir, "a", &table2("100"));
    let b = insert_save(&data, &dir, "b", &table2("60"));
    // A second patient: the Table 2 plane's file with a comment added, so other bytes (the
    // fixture as it is would be the same scan as the generated plane, so the same patient).
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/plane_20cm_65.obj");
    let mut bytes = std::fs::read(&fixture).unwrap();
    bytes.extend_from_slice(b"# the second patient\n");
    let second = dir.join("second.obj");
    std::fs::write(&second, bytes).unwrap();
    let other = insert_save(
        &data,
        &dir,
        "other",
        &[
            "--mesh",
            second.to_str().unwrap(),
            "--at",
            "0,0,0",
            "--scan-triangles",
            "--max-steps",
            "60",
        ],
    );
    assert_ne!(other.patient, a.patient);
    assert_eq!(list_json(&data).as_array().unwrap().len(), 2);

    // Delete a plan: its patient and the other plan stay.
    let o = ok(&data, &["delete", &a.plan]);
    assert!(stderr(&o).contains("deleted plan"), "{}", stderr(&o));
    fails(
        &data,
        &["show", &a.plan],
        Exit::Input,
        &["no plan", &a.plan],
    );
    fails(&data, &["delete", &a.plan], Exit::Input, &["no plan"]);
    let list = list_json(&data);
    let names: Vec<(String, String)> = ids_and_names(&list);
    assert!(names.contains(&(b.plan.clone(), "b".into())), "{names:?}");
    assert!(!names.iter().any(|(uid, _)| *uid == a.plan));

    // Erase without --yes: refused, saying what would go; nothing is erased.
    fails(
        &data,
        &["erase", &a.patient],
        Exit::Usage,
        &[&a.patient, "1 plan", "scan", "cannot be undone", "--yes"],
    );
    assert_eq!(list_json(&data), list);
    // With --yes: the patient, its plan and its scan are gone; the other patient stays.
    let o = ok(&data, &["erase", &a.patient, "--yes"]);
    assert!(stderr(&o).contains("erased patient"), "{}", stderr(&o));
    let list = list_json(&data);
    assert_eq!(
        ids_and_names(&list),
        [
            (other.patient.clone(), "second.obj".to_owned()),
            (other.plan.clone(), "other".to_owned())
        ]
    );
    fails(&data, &["show", &a.patient], Exit::Input, &["no patient"]);
    fails(&data, &["show", &b.plan], Exit::Input, &["no plan"]);
    let check = ok(&data, &["check"]);
    assert_eq!(stdout(&check), "ok\n");
}
