//! The golden reports through the C ABI: each golden job given to `tissue_job_start_json`
//! finishes with the golden report (volatile fields masked), as `insert --job` and the studio's
//! socket do for the same job; and a sweep's rows follow the one sweep policy (a failed run has
//! its own status, the others their numbers).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::ffi::CString;
use std::ptr;

use tissue::{
    tissue_job, tissue_job_free, tissue_job_report_json, tissue_job_start_json,
    tissue_job_sweep_count, tissue_job_sweep_row, tissue_job_wait, tissue_patient,
    tissue_patient_free, tissue_patient_shipped, tissue_plan_result, tissue_status,
};
use tissue_planner::golden;

fn report(job: *const tissue_job) -> String {
    let mut length = 0usize;
    let status = tissue_job_report_json(job, ptr::null_mut(), 0, &mut length);
    assert_eq!(status, tissue_status::TISSUE_BUFFER_TOO_SMALL);
    let mut buffer = vec![0u8; length];
    let status = tissue_job_report_json(job, buffer.as_mut_ptr().cast(), length, &mut length);
    assert_eq!(status, tissue_status::TISSUE_OK);
    buffer.pop(); // the NUL
    String::from_utf8(buffer).unwrap()
}

#[test]
fn every_golden_job_gives_the_golden_report_through_the_c_abi() {
    let mut patient: *mut tissue_patient = ptr::null_mut();
    assert_eq!(
        tissue_patient_shipped(0, &mut patient),
        tissue_status::TISSUE_OK
    );
    for name in golden::JOBS {
        let (_, text) = golden::job(name).unwrap();
        let json = CString::new(text).unwrap();
        let mut job: *mut tissue_job = ptr::null_mut();
        assert_eq!(
            tissue_job_start_json(patient, json.as_ptr(), &mut job),
            tissue_status::TISSUE_OK,
            "{name}"
        );
        assert_eq!(
            tissue_job_wait(job, -1.0),
            tissue_status::TISSUE_OK,
            "{name}"
        );
        if let Err(e) = golden::check(name, &report(job)) {
            panic!("{e}");
        }
        if name == "sweep" {
            // 20, 40 and 4000 cm³: the last cannot be held by the base; its row says so and
            // the others have their numbers.
            let mut count = 0usize;
            assert_eq!(
                tissue_job_sweep_count(job, &mut count),
                tissue_status::TISSUE_OK
            );
            assert_eq!(count, 3);
            let mut volume = 0.0;
            let mut row = tissue_plan_result::default();
            for i in 0..2 {
                assert_eq!(
                    tissue_job_sweep_row(job, i, &mut volume, &mut row),
                    tissue_status::TISSUE_OK
                );
                assert!(row.area_gain_cm2 > 0.0);
            }
            assert_eq!(
                tissue_job_sweep_row(job, 2, &mut volume, &mut row),
                tissue_status::TISSUE_PARAMETERS
            );
            assert_eq!(volume, 4000.0);
        }
        tissue_job_free(job);
    }
    tissue_patient_free(patient);
}
