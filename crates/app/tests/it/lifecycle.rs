//! The handle's life: dropping it mid-run, a slow receiver.

use crate::common;

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use tissue_app::{plan, AppError, Event, Handle, HandleOptions, Job};

use common::{drain, small_job, table2_job};

/// Sets its flag when dropped: moved into a job, it tells when the job's state is gone.
struct DropFlag(Arc<AtomicBool>);

impl Drop for DropFlag {
    fn drop(&mut self) {
        self.0.store(true, Ordering::SeqCst);
    }
}

#[test]
fn dropping_the_handle_mid_run_cancels_and_joins_promptly() {
    // A host job running Table 2's insertion (about 4 s to the end), holding a drop flag.
    let dropped = Arc::new(AtomicBool::new(false));
    let flag = DropFlag(Arc::clone(&dropped));
    let mut handle = Handle::start(Job::custom(move |sink| {
        let _flag = flag;
        let job = table2_job(100.0);
        let mut monitor = sink.monitor(0, &job.params.run);
        plan(&job, |p| monitor.observe(p)).map_err(AppError::from)
    }));
    let first = handle.recv_timeout(Duration::from_secs(60));
    assert!(matches!(first, Some(Event::Progress(_))), "{first:?}");
    assert!(!dropped.load(Ordering::SeqCst), "the job is still running");
    let start = Instant::now();
    drop(handle);
    let took = start.elapsed();
    // The job's state was dropped before the handle's drop returned: the thread was joined.
    assert!(dropped.load(Ordering::SeqCst), "the worker was not joined");
    assert!(took < Duration::from_millis(200), "drop took {took:?}");

    // The same with a plain insertion job: the drop returns long before the run would end.
    let mut handle = Handle::start(Job::Insertion(table2_job(100.0)));
    let first = handle.recv_timeout(Duration::from_secs(60));
    assert!(matches!(first, Some(Event::Progress(_))), "{first:?}");
    let start = Instant::now();
    drop(handle);
    let took = start.elapsed();
    assert!(took < Duration::from_millis(200), "drop took {took:?}");
}

#[test]
fn a_slow_receiver_does_not_stall_the_run() {
    let job = || Job::Insertion(small_job(50.0));
    let capacity = 16;
    let options = HandleOptions {
        progress_capacity: capacity,
    };

    // A fast reader.
    let start = Instant::now();
    let mut handle = Handle::start_with(job(), options);
    let (fast_progress, terminal) = drain(&mut handle, Duration::from_secs(60));
    let fast = start.elapsed();
    let steps = match terminal {
        Event::Finished(outcome) => outcome.into_insertion().expect("insertion").outcome.steps,
        other => panic!("expected a result, got {other:?}"),
    };
    assert!(fast_progress.len() as u64 <= steps);

    // A reader that reads nothing until the worker has ended.
    let start = Instant::now();
    let mut handle = Handle::start_with(job(), options);
    let deadline = start + Duration::from_secs(60);
    while !handle.is_finished() {
        assert!(
            Instant::now() < deadline,
            "the run stalled behind the full queue"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
    let slow = start.elapsed();
    let (slow_progress, terminal) = drain(&mut handle, Duration::from_secs(1));
    match terminal {
        Event::Finished(outcome) => {
            assert_eq!(
                outcome.into_insertion().expect("insertion").outcome.steps,
                steps
            );
        }
        other => panic!("expected a result, got {other:?}"),
    }
    // The queue kept the first events and dropped the rest.
    assert_eq!(slow_progress.len(), capacity);
    assert!((slow_progress.len() as u64) <= steps);
    let first: Vec<u64> = slow_progress.iter().map(|p| p.step).collect();
    assert_eq!(first, (1..=capacity as u64).collect::<Vec<_>>());
    // About the same time as with the fast reader.
    assert!(
        slow <= fast.mul_f64(1.5) + Duration::from_millis(200),
        "slow reader {slow:?} against fast reader {fast:?}"
    );
    assert!(handle.try_event().is_none());

    // The same run without a worker, for scale.
    let start = Instant::now();
    let direct = plan(&small_job(50.0), |_| ControlFlow::Continue(())).expect("run");
    assert_eq!(direct.outcome.steps, steps);
    assert!(
        slow <= start.elapsed().mul_f64(1.5) + Duration::from_millis(200),
        "slow reader {slow:?} against no worker {:?}",
        start.elapsed()
    );
}

/// The blocking run: progress on the calling thread, no polling; a token cancelled from another
/// thread ends it with the steps done, and the same job run to its end gives its outcome.
#[test]
fn run_blocks_with_progress_and_a_token_cancels_it_from_another_thread() {
    let token = tissue_app::CancelToken::new();
    let handle = Handle::start_cancellable(
        Job::Insertion(table2_job(100.0)),
        HandleOptions::default(),
        token.clone(),
    );
    let caller = std::thread::current().id();
    let (seen_tx, seen_rx) = std::sync::mpsc::channel::<u64>();
    let canceller = std::thread::spawn(move || {
        // Cancel once the fifth step was seen.
        while let Ok(step) = seen_rx.recv() {
            if step >= 5 {
                token.cancel();
                break;
            }
        }
    });
    let mut last = 0;
    let result = handle.run(|p| {
        assert_eq!(
            std::thread::current().id(),
            caller,
            "progress on the caller's thread"
        );
        assert!(p.step > last || p.step == 1, "steps in order");
        last = p.step;
        let _ = seen_tx.send(p.step);
    });
    let _ = canceller.join();
    match result {
        Err(AppError::Cancelled { steps }) => {
            assert!((5..4000).contains(&steps), "cancelled after {steps} steps")
        }
        other => panic!("expected a cancel, got {other:?}"),
    }

    // A small job runs to its end: its outcome, and its progress seen.
    let mut progress = 0;
    let outcome = Handle::start(Job::Insertion(small_job(50.0))).run(|_| progress += 1);
    assert!(
        matches!(outcome, Ok(tissue_app::Outcome::Insertion(_))),
        "{outcome:?}"
    );
    assert!(progress > 0);

    // A token cancelled before the start ends the job before its first step.
    let token = tissue_app::CancelToken::new();
    token.cancel();
    let early = Handle::start_cancellable(
        Job::Insertion(small_job(50.0)),
        HandleOptions::default(),
        token,
    )
    .run(|_| panic!("no step after a cancel before the start"));
    assert!(
        matches!(early, Err(AppError::Cancelled { steps: 0 })),
        "{early:?}"
    );
}
