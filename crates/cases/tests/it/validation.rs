//! Names, notes and labels are checked; unknown ids are named; search matches literally.

use tissue_cases::{CaseError, Library, NewPlan};

use crate::common::{save, table2, table2_single, Tmp};

fn field_of<T: std::fmt::Debug>(r: Result<T, CaseError>) -> &'static str {
    match r {
        Err(CaseError::Invalid { field, message }) => {
            assert!(message.contains(field), "{message:?} does not name {field}");
            field
        }
        other => panic!("expected Invalid, got {other:?}"),
    }
}

#[test]
fn bad_names_notes_and_labels_are_refused_naming_the_field() {
    let tmp = Tmp::new("valid");
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let (_, scan) = table2();
    let (spec, finished) = table2_single(100.0, 40);
    let plan = |name, note| NewPlan {
        name,
        note,
        spec: &spec,
        finished: &finished,
    };
    assert_eq!(field_of(lib.save(&scan, None, plan("  ", ""))), "name");
    let long = "x".repeat(201);
    assert_eq!(field_of(lib.save(&scan, None, plan(&long, ""))), "name");
    let note = "n".repeat(10_001);
    assert_eq!(field_of(lib.save(&scan, None, plan("ok", &note))), "note");
    assert_eq!(field_of(lib.save(&scan, Some(""), plan("ok", ""))), "label");
    assert!(
        lib.patients(None).unwrap().is_empty(),
        "a refused save stored something"
    );
    let saved = lib.save(&scan, None, plan("  trimmed  ", "")).unwrap();
    assert_eq!(saved.name, "trimmed");
    assert_eq!(field_of(lib.rename_plan(&saved.uid, "")), "name");
    assert_eq!(field_of(lib.rename_plan(&saved.uid, "a\u{1b}[31m")), "name");
    assert_eq!(field_of(lib.set_note(&saved.uid, &note)), "note");
    assert_eq!(
        field_of(lib.rename_patient(&saved.patient_uid, " ")),
        "label"
    );
    assert_eq!(
        lib.rename_plan(&saved.uid, "second").unwrap().name,
        "second"
    );
    assert_eq!(lib.set_note(&saved.uid, "a\nb").unwrap().note, "a\nb");
    assert_eq!(
        lib.rename_patient(&saved.patient_uid, "Ms B")
            .unwrap()
            .label,
        "Ms B"
    );
}

#[test]
fn unknown_ids_are_not_found() {
    let tmp = Tmp::new("notfound");
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let plan = "c00000000000000000000000000000000";
    let patient = "p00000000000000000000000000000000";
    let what = |r: Result<(), CaseError>| match r {
        Err(CaseError::NotFound { what, id }) => {
            assert!(id == plan || id == patient);
            what
        }
        other => panic!("expected NotFound, got {other:?}"),
    };
    assert_eq!(what(lib.plan(plan).map(|_| ())), "plan");
    assert_eq!(what(lib.open_plan(plan).map(|_| ())), "plan");
    assert_eq!(what(lib.rename_plan(plan, "x").map(|_| ())), "plan");
    assert_eq!(what(lib.set_note(plan, "x").map(|_| ())), "plan");
    assert_eq!(what(lib.delete_plan(plan)), "plan");
    assert_eq!(what(lib.compare(plan, plan).map(|_| ())), "plan");
    assert_eq!(what(lib.patient(patient).map(|_| ())), "patient");
    assert_eq!(what(lib.plans(patient).map(|_| ())), "patient");
    assert_eq!(what(lib.scan(patient).map(|_| ())), "patient");
    assert_eq!(what(lib.load_patient(patient).map(|_| ())), "patient");
    assert_eq!(
        what(lib.rename_patient(patient, "x").map(|_| ())),
        "patient"
    );
    assert_eq!(what(lib.erase_patient(patient)), "patient");
    assert_eq!(what(lib.export_case(patient).map(|_| ())), "patient");
}

#[test]
fn search_is_case_insensitive_and_literal_and_lists_newest_activity_first() {
    let tmp = Tmp::new("search");
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    let (plane, scan) = table2();
    let mut other = scan.clone();
    other.unit = tissue_planner::Unit::Mm;
    let mut third = scan.clone();
    third.unit = tissue_planner::Unit::M;
    let a = lib.add_patient(&scan, Some("50% Flap")).unwrap();
    let b = lib.add_patient(&other, Some("500 flap_x")).unwrap();
    let c = lib.add_patient(&third, Some("Mr C")).unwrap();
    let labels = |q: Option<&str>| -> Vec<String> {
        lib.patients(q)
            .unwrap()
            .into_iter()
            .map(|p| p.label)
            .collect()
    };
    assert_eq!(labels(Some("%")), vec!["50% Flap"]);
    assert_eq!(labels(Some("_")), vec!["500 flap_x"]);
    assert_eq!(labels(Some("FLAP")), vec!["500 flap_x", "50% Flap"]);
    assert_eq!(labels(Some("0%")), vec!["50% Flap"]);
    assert!(labels(Some("nobody")).is_empty());
    // Newest activity first: c was added last; then a plan on a puts a first.
    assert_eq!(labels(None), vec!["Mr C", "500 flap_x", "50% Flap"]);
    let _ = (plane, b, c);
    let (spec, finished) = table2_single(100.0, 40);
    save(&lib, &scan, "plan", &spec, &finished);
    assert_eq!(labels(None), vec!["50% Flap", "Mr C", "500 flap_x"]);
    assert_eq!(lib.patient(&a.uid).unwrap().plans, 1);
    assert!(lib.patient(&a.uid).unwrap().last_plan_at.is_some());
}
