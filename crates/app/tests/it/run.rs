//! Runs through the worker against the library called directly, set-up errors, sweeps and
//! inverse searches, the plane press, host jobs and panics.
#![allow(clippy::panic)]

use crate::common;

use std::ops::ControlFlow;
use std::time::Duration;

use glam::Vec3;
use tissue_app::{
    plan, AppError, Event, Handle, HandleOptions, InverseJob, Job, Outcome, PlanePressJob,
    ProgressEvent, SweepJob,
};
use tissue_implant::{
    place_implant, plane_press, plane_press_region, select_region_with, ImplantError, ImplantShape,
    ImplantSpec, Insertion, InsertionOutcome, InsertionParams, InverseOptions, Param,
    PlanePressParams, TissueLayers,
};

use common::{drain, small_job, touches_vertex};

const LIMIT: Duration = Duration::from_secs(60);

/// Bit-for-bit equality of the numbers of two outcomes and of the region after.
fn assert_same(a: &InsertionOutcome, b: &InsertionOutcome) {
    assert_eq!(a.steps, b.steps);
    assert_eq!(a.area_before.to_bits(), b.area_before.to_bits());
    assert_eq!(a.area_after.to_bits(), b.area_after.to_bits());
    assert_eq!(a.area_gain.to_bits(), b.area_gain.to_bits());
    assert_eq!(a.volume_difference.to_bits(), b.volume_difference.to_bits());
    assert_eq!(
        a.implant_volume_after.to_bits(),
        b.implant_volume_after.to_bits()
    );
    assert_eq!(a.stop_reason, b.stop_reason);
    assert_eq!(a.region_after.positions(), b.region_after.positions());
}

#[test]
fn a_run_finishes_with_the_library_s_results_after_increasing_progress() {
    let volume = 50.0;
    // The library directly, as Table 2's bench sets it up.
    let patient = tissue_mesh::grid(17, 20.0).unwrap();
    let selection = select_region_with(&patient, Vec3::ZERO, 5.25, &touches_vertex()).unwrap();
    let params = InsertionParams::default();
    let layers = TissueLayers::new(selection.mesh(), &params.layers).unwrap();
    let spec =
        ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume).with_vertex_budget(100);
    let implant = place_implant(&layers, &spec, Vec3::ZERO, Vec3::Z, Vec3::X).unwrap();
    let mut insertion = Insertion::new(selection.mesh(), &implant, &params).unwrap();
    let direct = insertion.run(|_| ControlFlow::Continue(())).unwrap();

    // Through the worker, with room for every progress event.
    let mut handle = Handle::start_with(
        Job::Insertion(small_job(volume)),
        HandleOptions {
            progress_capacity: 1 << 20,
        },
    );
    let (progress, terminal) = drain(&mut handle, LIMIT);
    assert!(
        handle.try_event().is_none(),
        "nothing after the terminal event"
    );
    assert!(handle.recv().is_none());
    let planned = match terminal {
        Event::Finished(Outcome::Insertion(p)) => *p,
        other => panic!("expected an insertion result, got {other:?}"),
    };
    assert_same(&planned.outcome, &direct);
    assert_eq!(planned.selection, selection);

    // One progress event per step, in order, each in range.
    assert_eq!(progress.len() as u64, direct.steps);
    for (k, p) in progress.iter().enumerate() {
        assert_eq!(p.run, 0);
        assert_eq!(p.step, k as u64 + 1);
        assert_eq!(p.max_steps, params.run.stop.max_steps);
        assert!(p.displacement.is_finite() && p.displacement >= 0.0);
        assert!((0.0..=1.0).contains(&p.settle), "settle {}", p.settle);
    }
    assert!(progress.windows(2).all(|w| w[0].elapsed <= w[1].elapsed));
    // The meter is 0 before the criterion's window is full, below 1 while the run moves, and 1
    // at the step where the library's criterion fired.
    let window = params.run.stop.window;
    assert!(progress[..window - 1].iter().all(|p| p.settle == 0.0));
    assert!(progress.iter().any(|p| p.settle > 0.0 && p.settle < 1.0));
    let last = progress.last().unwrap();
    if direct.stop_reason == tissue_mss::StopReason::Settled {
        assert_eq!(last.settle, 1.0, "the criterion fired at the last step");
    }

    // The non-threaded entry point gives the same.
    let planned_direct = plan(&small_job(volume), |_| ControlFlow::Continue(())).unwrap();
    assert_same(&planned_direct.outcome, &direct);
    // And the patient with the region replaced is available.
    let after = planned.patient_after(&patient).unwrap();
    assert_eq!(after.vertex_count(), patient.vertex_count());
}

fn failed(job: Job) -> AppError {
    let handle = Handle::start(job);
    match handle.wait() {
        Err(e) => e,
        Ok(outcome) => panic!("expected a failure, got {outcome:?}"),
    }
}

#[test]
fn set_up_errors_come_back_as_failed() {
    // A point 50 cm above a 20 cm plane.
    let mut job = small_job(50.0);
    job.placement.point = Vec3::new(0.0, 0.0, 50.0);
    let e = failed(Job::Insertion(job));
    assert!(
        matches!(e, AppError::Implant(ImplantError::PointOffSurface { .. })),
        "{e:?}"
    );

    // A non-positive volume.
    for volume in [0.0, -10.0] {
        let mut handle = Handle::start(Job::Insertion(small_job(volume)));
        let (progress, terminal) = drain(&mut handle, LIMIT);
        assert!(progress.is_empty());
        match terminal {
            Event::Failed(AppError::Implant(ImplantError::InvalidParameter { param, .. })) => {
                assert_eq!(param, Param::VolumeCm3)
            }
            other => panic!("expected an invalid volume, got {other:?}"),
        }
    }

    // An implant wider than the region.
    let mut job = small_job(50.0);
    job.region_radius = Some(2.0);
    let e = failed(Job::Insertion(job));
    assert!(
        matches!(
            e,
            AppError::Implant(ImplantError::FootprintOutsideRegion { .. })
        ),
        "{e:?}"
    );
}

#[test]
fn a_sweep_returns_one_result_per_volume_in_input_order() {
    let volumes = vec![60.0, 20.0, 40.0];
    let job = SweepJob {
        base: small_job(1.0),
        volumes: volumes.clone(),
    };
    let mut handle = Handle::start_with(
        Job::Sweep(job),
        HandleOptions {
            progress_capacity: 1 << 20,
        },
    );
    let (progress, terminal) = drain(&mut handle, LIMIT);
    let result = match terminal {
        Event::Finished(outcome) => outcome.into_sweep().expect("a sweep result"),
        other => panic!("expected a sweep result, got {other:?}"),
    };
    assert_eq!(result.runs.len(), volumes.len());
    for (run, (entry, &volume)) in result.runs.iter().zip(&volumes).enumerate() {
        assert_eq!(entry.volume, volume);
        let outcome = entry.result.as_ref().unwrap();
        assert!(
            (outcome.implant_volume - volume).abs() <= 0.005 * volume,
            "run {run}: implant of {} cm³ for {volume}",
            outcome.implant_volume
        );
        // Every step of every run was reported, with its run index, in order within the run.
        let steps: Vec<u64> = progress
            .iter()
            .filter(|p| p.run == run)
            .map(|p| p.step)
            .collect();
        assert_eq!(steps, (1..=outcome.steps).collect::<Vec<_>>(), "run {run}");
    }
    assert!(progress.iter().all(|p| p.run < volumes.len()));
    // Larger implants gain more area.
    let gain = |k: usize| result.runs[k].result.as_ref().unwrap().area_gain;
    assert!(gain(1) < gain(2) && gain(2) < gain(0));
    // Each run is the single run of its volume.
    let single = plan(&small_job(20.0), |_| ControlFlow::Continue(())).unwrap();
    let swept = result.runs[1].result.as_ref().unwrap();
    assert_eq!(single.outcome.steps, swept.steps);
    assert_eq!(
        single.outcome.area_gain.to_bits(),
        swept.area_gain.to_bits()
    );
}

#[test]
fn an_inverse_search_returns_its_runs() {
    let options = InverseOptions {
        gain_tolerance: 1.0,
        volume_tolerance: 2.0,
        max_runs: 4,
    };
    let job = InverseJob {
        base: small_job(1.0),
        target_gain: 5.0,
        bracket: (20.0, 60.0),
        options: options.clone(),
    };
    let mut handle = Handle::start_with(
        Job::Inverse(job),
        HandleOptions {
            progress_capacity: 1 << 20,
        },
    );
    let (progress, terminal) = drain(&mut handle, LIMIT);
    let planned = match terminal {
        Event::Finished(outcome) => outcome.into_inverse().expect("an inverse search"),
        other => panic!("expected an inverse search, got {other:?}"),
    };
    // How the solver ended every run, one per run of the search, in order.
    assert_eq!(planned.runs.len(), planned.search.runs.len());
    for figures in &planned.runs {
        assert!(figures.steps > 0 && figures.iterations > 0, "{figures:?}");
    }
    let search = planned.search;
    assert!(search.runs.len() >= 2 && search.runs.len() <= options.max_runs);
    assert_eq!(search.runs[0].volume, 20.0);
    assert_eq!(search.runs[1].volume, 60.0);
    assert!(search.runs[0].gain < 5.0 && search.runs[1].gain > 5.0);
    assert!(search.runs.iter().any(|r| r.volume == search.volume));
    assert!(search.volume > 20.0 && search.volume < 60.0);
    // Progress from every run, in order, none from a run that was not taken.
    let mut runs_seen: Vec<usize> = progress.iter().map(|p| p.run).collect();
    assert!(runs_seen.windows(2).all(|w| w[0] <= w[1]));
    runs_seen.dedup();
    assert_eq!(runs_seen, (0..search.runs.len()).collect::<Vec<_>>());
}

#[test]
fn the_plane_press_runs_on_the_worker() {
    let region = plane_press_region(17).unwrap();
    let params = PlanePressParams::default();
    let direct = plane_press(region.mesh(), &params, |_| ControlFlow::Continue(())).unwrap();
    let handle = Handle::start(Job::PlanePress(PlanePressJob {
        region: region.mesh().clone(),
        params,
    }));
    let press = handle
        .wait()
        .unwrap()
        .into_plane_press()
        .expect("a press result");
    assert_eq!(press.steps, direct.steps);
    assert_eq!(press.area_after.to_bits(), direct.area_after.to_bits());
    assert_eq!(
        press.volume_difference.to_bits(),
        direct.volume_difference.to_bits()
    );
}

/// Waits for the terminal event of a job that should fail, without hanging.
fn terminal_of(job: Job) -> Event {
    let mut handle = Handle::start(job);
    drain(&mut handle, Duration::from_secs(10)).1
}

#[test]
fn a_panic_in_a_job_comes_back_as_failed_with_its_message() {
    // After reporting some progress.
    let job = Job::custom(|sink| -> Result<(), AppError> {
        for step in 1..=3 {
            let _ = sink.report(ProgressEvent {
                run: 0,
                step,
                max_steps: 10,
                displacement: 0.0,
                contacts: 0,
                settle: 0.0,
                elapsed: sink.elapsed(),
                day: None,
            });
        }
        panic!("boom at step {}", 3)
    });
    let mut handle = Handle::start(job);
    let (progress, terminal) = drain(&mut handle, Duration::from_secs(10));
    assert_eq!(progress.len(), 3);
    match terminal {
        Event::Failed(AppError::Panicked { message }) => assert_eq!(message, "boom at step 3"),
        other => panic!("expected a panic report, got {other:?}"),
    }

    // A payload that is not a string.
    let job = Job::custom(|_| -> Result<(), AppError> { std::panic::panic_any(7u32) });
    assert!(matches!(
        terminal_of(job),
        Event::Failed(AppError::Panicked { message }) if message.contains("not a string")
    ));

    // A payload whose drop panics again.
    struct Nasty;
    impl Drop for Nasty {
        fn drop(&mut self) {
            panic!("the payload's drop")
        }
    }
    let job = Job::custom(|_| -> Result<(), AppError> { std::panic::panic_any(Nasty) });
    assert!(matches!(
        terminal_of(job),
        Event::Failed(AppError::Panicked { .. })
    ));

    // `wait` returns the same.
    let handle = Handle::start(Job::custom(|_| -> Result<(), AppError> {
        panic!("waited")
    }));
    assert_eq!(
        handle.wait().unwrap_err(),
        AppError::Panicked {
            message: "waited".into()
        }
    );
}

#[test]
fn host_jobs_return_values_errors_and_cancels() {
    let handle = Handle::start(Job::custom(|_| Ok::<_, AppError>(vec![1u8, 2, 3])));
    let value: Vec<u8> = handle.wait().unwrap().into_custom().unwrap();
    assert_eq!(value, vec![1, 2, 3]);

    let handle = Handle::start(Job::custom(|_| -> Result<(), AppError> {
        Err(AppError::Job {
            message: "no licence".into(),
        })
    }));
    assert_eq!(
        handle.wait().unwrap_err(),
        AppError::Job {
            message: "no licence".into()
        }
    );

    // A host job that runs an insertion through the sink and is cancelled by the host.
    let mut handle = Handle::start(Job::custom(|sink| {
        let job = small_job(50.0);
        let mut monitor = sink.monitor(0, &job.params.run);
        plan(&job, |p| monitor.observe(p)).map_err(AppError::from)
    }));
    let first = handle.recv_timeout(LIMIT);
    assert!(matches!(first, Some(Event::Progress(_))), "{first:?}");
    handle.cancel();
    let (_, terminal) = drain(&mut handle, LIMIT);
    assert!(
        matches!(terminal, Event::Cancelled { steps } if steps >= 1),
        "{terminal:?}"
    );
}

#[test]
fn sweeps_and_searches_cancel_within_a_step() {
    let sweep = Job::Sweep(SweepJob {
        base: small_job(1.0),
        volumes: vec![30.0, 40.0, 50.0, 60.0],
    });
    let inverse = Job::Inverse(InverseJob {
        base: small_job(1.0),
        target_gain: 5.0,
        bracket: (20.0, 60.0),
        options: InverseOptions::default(),
    });
    for job in [sweep, inverse] {
        let kind = job.kind();
        let mut handle = Handle::start(job);
        let first = handle.recv_timeout(LIMIT);
        assert!(
            matches!(first, Some(Event::Progress(_))),
            "{kind}: {first:?}"
        );
        let start = std::time::Instant::now();
        handle.cancel();
        let (_, terminal) = drain(&mut handle, LIMIT);
        let took = start.elapsed();
        assert!(
            matches!(terminal, Event::Cancelled { steps } if steps >= 1),
            "{kind}: {terminal:?}"
        );
        // Not the 4 runs (~1.6 s) of the sweep nor the search's: the runs in flight stopped and
        // the others were not set up.
        assert!(took < Duration::from_millis(300), "{kind}: {took:?}");
    }
}

#[test]
fn everything_a_host_moves_between_threads_is_send() {
    fn send<T: Send + 'static>() {}
    send::<Handle>();
    send::<Job>();
    send::<Event>();
    send::<Outcome>();
    send::<AppError>();
    send::<ProgressEvent>();
}
