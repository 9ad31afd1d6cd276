//! Shared scenes and helpers of the integration tests.
#![allow(dead_code, clippy::expect_used, clippy::panic)]

use std::time::{Duration, Instant};

use glam::Vec3;
use tissue_app::{Event, Handle, InsertionJob, Placement, ProgressEvent, SimMesh};
use tissue_implant::{ImplantShape, ImplantSpec, RegionOptions, RegionRule};

/// The thesis's region rule.
pub fn touches_vertex() -> RegionOptions {
    RegionOptions {
        rule: RegionRule::TouchesVertex,
        ..RegionOptions::default()
    }
}

/// A small, fast case: a 20 cm plane of 17² vertices, a round 7 cm implant of `volume` with
/// about 100 vertices at the centre, the default region radius (5.25 cm), default parameters.
/// About 0.4 s and 2 900 steps at 50 cm³.
pub fn small_job(volume: f64) -> InsertionJob {
    let patient = tissue_mesh::grid(17, 20.0).expect("grid");
    let implant =
        ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume).with_vertex_budget(100);
    let mut job = InsertionJob::new(
        patient,
        Placement::new(Vec3::ZERO, Vec3::Z, Vec3::X),
        implant,
    );
    job.region = touches_vertex();
    // The plane's own grid, as the thesis ran it.
    job.sim = SimMesh::Patient;
    job
}

/// Table 2's case: a 20 cm plane of 65² vertices, a round 7 cm implant of `volume` (default
/// vertex budget), the region of radius 5.25 cm with the thesis's rule, default parameters.
pub fn table2_job(volume: f64) -> InsertionJob {
    let patient = tissue_mesh::grid(65, 20.0).expect("grid");
    let implant = ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume);
    let mut job = InsertionJob::new(
        patient,
        Placement::new(Vec3::ZERO, Vec3::Z, Vec3::X),
        implant,
    );
    job.region = touches_vertex();
    // The plane's own grid, as the thesis ran it.
    job.sim = SimMesh::Patient;
    job
}

/// Every event until the terminal one, failing (not hanging) after `limit`.
pub fn drain(handle: &mut Handle, limit: Duration) -> (Vec<ProgressEvent>, Event) {
    let deadline = Instant::now() + limit;
    let mut progress = Vec::new();
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        match handle.recv_timeout(left) {
            Some(Event::Progress(p)) => progress.push(p),
            Some(terminal) => return (progress, terminal),
            None => panic!("no terminal event within {limit:?}"),
        }
    }
}
