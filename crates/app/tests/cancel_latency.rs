//! Cancel latency on Table 2's case (65² plane, 100 cm³ round 7 cm implant, default parameters):
//! from `cancel()` to the `Cancelled` event, at most 50 ms.
#![allow(clippy::panic)]

mod common;

use std::time::{Duration, Instant};

use tissue_app::{Event, Handle, Job};

use common::table2_job;

const BOUND: Duration = Duration::from_millis(50);

/// One try: start, wait until the run is in contact (step 150 of about 370: the expander has
/// filled by step 80, and the steps in contact are the run's slowest), cancel, time until the
/// terminal event.
fn cancel_latency() -> (Duration, u64, u64) {
    let mut handle = Handle::start(Job::Insertion(table2_job(100.0)));
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut last_step = 0;
    while last_step < 150 {
        match handle.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
            Some(Event::Progress(p)) => last_step = p.step,
            other => panic!("expected progress before the cancel, got {other:?}"),
        }
    }
    let start = Instant::now();
    handle.cancel();
    let steps = loop {
        match handle.recv_timeout(Duration::from_secs(10)) {
            Some(Event::Progress(_)) => {}
            Some(Event::Cancelled { steps }) => break steps,
            other => panic!("expected the cancel, got {other:?}"),
        }
    };
    let latency = start.elapsed();
    assert!(handle.try_event().is_none());
    (latency, last_step, steps)
}

#[test]
fn cancel_ends_a_table2_run_within_50_ms() {
    let mut measured = Vec::new();
    // Retried only if a try exceeds the bound (a loaded machine may deschedule the worker).
    for _ in 0..3 {
        let (latency, seen_step, steps) = cancel_latency();
        // The run stopped where the cancel found it, long before its end (~2 500 steps).
        assert!(
            steps >= seen_step && steps < 1000,
            "cancelled after {steps} steps"
        );
        measured.push(latency);
        if latency <= BOUND {
            break;
        }
    }
    eprintln!("cancel latency (Table 2 case): {measured:?}");
    let best = measured.iter().min().copied().unwrap_or(Duration::MAX);
    assert!(
        best <= BOUND,
        "cancel latencies {measured:?} exceed {BOUND:?}"
    );
}
