//! The request's `solver` through the C ABI's JSON entry point: the job runs with the solver
//! asked for and its report says so (`inputs.solver`) with the run's `iterations` and
//! `residual_n`; the default is `explicit`; an unknown solver is refused as `TISSUE_USAGE`
//! naming the field and the solvers.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::ffi::CString;
use std::ptr;

use serde_json::Value;
use tissue::{
    tissue_job, tissue_job_free, tissue_job_report_json, tissue_job_result, tissue_job_start_json,
    tissue_job_wait, tissue_last_error, tissue_patient, tissue_patient_free,
    tissue_patient_shipped, tissue_plan_result, tissue_status,
};

/// The report of a finished job, as JSON.
fn report(job: *const tissue_job) -> Value {
    let mut length = 0usize;
    assert_eq!(
        tissue_job_report_json(job, ptr::null_mut(), 0, &mut length),
        tissue_status::TISSUE_BUFFER_TOO_SMALL
    );
    let mut buffer = vec![0u8; length];
    assert_eq!(
        tissue_job_report_json(job, buffer.as_mut_ptr().cast(), length, &mut length),
        tissue_status::TISSUE_OK
    );
    buffer.pop(); // the NUL
    serde_json::from_slice(&buffer).unwrap()
}

fn last_error() -> String {
    let n = tissue_last_error(ptr::null_mut(), 0);
    let mut buffer = vec![0u8; n.max(1)];
    tissue_last_error(buffer.as_mut_ptr().cast(), buffer.len());
    buffer.pop();
    String::from_utf8_lossy(&buffer).into_owned()
}

/// Runs `json` on the Table 2 plane to its end and gives its report and its numbers.
fn run(patient: *const tissue_patient, json: &str) -> (Value, tissue_plan_result) {
    let json = CString::new(json).unwrap();
    let mut job: *mut tissue_job = ptr::null_mut();
    assert_eq!(
        tissue_job_start_json(patient, json.as_ptr(), &mut job),
        tissue_status::TISSUE_OK,
        "{}",
        last_error()
    );
    assert_eq!(tissue_job_wait(job, -1.0), tissue_status::TISSUE_OK);
    let mut numbers = tissue_plan_result::default();
    assert_eq!(
        tissue_job_result(job, &mut numbers),
        tissue_status::TISSUE_OK
    );
    let report = report(job);
    tissue_job_free(job);
    (report, numbers)
}

#[test]
fn the_solver_of_a_json_request_runs_and_is_reported() {
    let mut patient: *mut tissue_patient = ptr::null_mut();
    assert_eq!(
        tissue_patient_shipped(0, &mut patient),
        tissue_status::TISSUE_OK
    );
    // Table 2's case, a short run: the explicit solver asked for.
    let (explicit, numbers) = run(
        patient,
        r#"{"request": {"solver": "explicit", "max_steps": 40}}"#,
    );
    assert_eq!(explicit["tool"], "capi");
    assert_eq!(explicit["inputs"]["solver"], "explicit");
    assert_eq!(explicit["iterations"], 40, "the explicit solver's steps");
    assert_eq!(explicit["iterations"].as_u64(), Some(numbers.steps));
    assert!(
        explicit["residual_n"].is_null(),
        "{}",
        explicit["residual_n"]
    );
    assert!(explicit["area_gain_cm2"].as_f64().unwrap() > 0.0);

    // Left out, the solver is the default, and the report says which.
    let (default, _) = run(patient, r#"{"request": {"max_steps": 40}}"#);
    assert_eq!(default["inputs"]["solver"], "explicit");
    assert!(default["iterations"].as_u64().is_some_and(|i| i > 0));
    assert!(default.get("residual_n").is_some(), "always written");

    // An unknown solver: refused before anything runs, naming the field and the solvers.
    let bad = CString::new(r#"{"request": {"solver": "implicit"}}"#).unwrap();
    let mut job: *mut tissue_job = ptr::null_mut();
    assert_eq!(
        tissue_job_start_json(patient, bad.as_ptr(), &mut job),
        tissue_status::TISSUE_USAGE
    );
    assert!(job.is_null());
    let message = last_error();
    assert!(
        message.contains("`solver`") && message.contains("`explicit` or `quasi_static`"),
        "{message}"
    );
    tissue_patient_free(patient);
}
