//! The expansion job on the worker (issue 21): progress tagged with days, the result equal to
//! the thread-free call, and a cancel.
#![allow(missing_docs, clippy::panic)]

use std::ops::ControlFlow;
use std::time::Duration;

use glam::Vec3;
use tissue_app::{
    plan_expansion, Event, ExpansionJob, Handle, InsertionJob, Job, Placement, SimMesh,
};
use tissue_implant::{ImplantShape, ImplantSpec, Protocol};

fn job() -> ExpansionJob {
    let mut insertion = InsertionJob::new(
        tissue_mesh::grid(25, 20.0).unwrap_or_else(|e| panic!("{e}")),
        Placement::new(Vec3::ZERO, Vec3::Z, Vec3::X),
        ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, 60.0).with_vertex_budget(120),
    );
    insertion.sim = SimMesh::Patient;
    let mut job = ExpansionJob::weekly(insertion, 2).unwrap_or_else(|e| panic!("{e}"));
    job.protocol = Protocol::weekly(60.0, 2, 0.3, 0.2, 0.0).unwrap_or_else(|e| panic!("{e}"));
    job.band = None;
    job
}

#[test]
fn an_expansion_runs_on_the_worker_with_days_in_its_progress_and_equals_the_direct_call() {
    let mut handle = Handle::start(Job::Expansion(Box::new(job())));
    let mut days = Vec::new();
    let outcome = loop {
        match handle.recv_timeout(Duration::from_secs(600)) {
            Some(Event::Progress(p)) => days.extend(p.day),
            Some(Event::Finished(o)) => break o,
            other => panic!("unexpected {other:?}"),
        }
    };
    let planned = outcome
        .into_expansion()
        .unwrap_or_else(|| panic!("not an expansion"));
    assert!(
        days.iter().any(|&d| d > 7.0),
        "days seen: {:?}",
        days.last()
    );
    let direct =
        plan_expansion(&job(), &|_| ControlFlow::Continue(())).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(planned.outcome.flap_area, direct.outcome.flap_area);
    assert_eq!(planned.outcome.records.len(), direct.outcome.records.len());
    assert!(planned.outcome.flap_area > 0.0);
}

#[test]
fn an_expansion_can_be_cancelled_between_steps() {
    let mut handle = Handle::start(Job::Expansion(Box::new(job())));
    let terminal = loop {
        match handle.recv_timeout(Duration::from_secs(600)) {
            Some(Event::Progress(_)) => handle.cancel(),
            Some(other) => break other,
            None => panic!("no terminal event"),
        }
    };
    assert!(matches!(terminal, Event::Cancelled { .. }), "{terminal:?}");
}
