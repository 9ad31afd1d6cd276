//! Issue 17's convergence figures: every scan case of `tests/scans.rs` run at the default
//! simulation edge `h` and at `h/2`, with the change of the area gain (target < 5 %), for
//! docs/validation.md.
//!
//! ```sh
//! cargo bench -p tissue-app --bench scan_convergence
//! ```
#![allow(clippy::print_stdout, clippy::unwrap_used, clippy::expect_used)]

use std::ops::ControlFlow;

use glam::Vec3;
use tissue_app::{plan, InsertionJob, Placement, SimMesh};
use tissue_implant::{ImplantShape, ImplantSpec, ScanOptions};
use tissue_mesh::TriMesh;
use tissue_testscans::Scan;

/// The step limit (the default is 20 000): a run still moving then is marked `*`.
const MAX_STEPS: u64 = 5000;

fn in_cm(scan: &Scan) -> TriMesh {
    let s = scan.cm_per_unit;
    scan.mesh
        .with_positions(scan.mesh.positions().iter().map(|&p| p * s).collect())
        .unwrap()
}

fn main() {
    let round = |d: f32| ImplantShape::Round { diameter: d };
    let rect = |l: f32, w: f32| ImplantShape::Rectangular {
        length: l,
        width: w,
        corner_radius: 0.5f32.min(0.2 * w),
    };
    let crescent = ImplantShape::Crescent {
        length: 6.0,
        width: 2.0,
        bend_radius: 4.0,
    };
    let arm_axis = Vec3::new(1.0, -1.0, 0.8).normalize();
    type Case = (&'static str, ImplantShape, f64, Vec3);
    // The quicker cases first (the round expanders on the tube take the most steps).
    let sets: Vec<(&str, Result<Scan, tissue_testscans::ScanError>, Vec<Case>)> = vec![
        (
            "tube",
            tissue_testscans::tapered_tube(7),
            vec![
                ("y12_other_side", rect(6.0, 3.0), 15.0, Vec3::Y),
                ("y8_back", crescent, 8.0, Vec3::Y),
            ],
        ),
        (
            "forearm (dm)",
            tissue_testscans::forearm_from_body(),
            vec![
                ("forearm_outer", rect(6.0, 3.0), 15.0, arm_axis),
                ("forearm_front", round(4.0), 10.0, arm_axis),
            ],
        ),
        (
            "face (mm)",
            tissue_testscans::noisy_face_scan(1),
            vec![
                ("forehead", rect(3.0, 1.5), 1.5, Vec3::X),
                ("forehead", round(2.5), 2.0, Vec3::X),
            ],
        ),
        (
            "closed body (dm)",
            tissue_testscans::closed_body(),
            // Not the belly: see tests/scans.rs.
            vec![("back", round(7.0), 50.0, Vec3::X)],
        ),
        (
            "tube",
            tissue_testscans::tapered_tube(7),
            vec![
                ("y16_oblique", round(4.0), 10.0, Vec3::Y),
                ("y8_front", round(4.0), 10.0, Vec3::Y),
                ("y12_side", round(4.0), 10.0, Vec3::Y),
                // Slowest at h/2 (over 10 minutes on the shared machine): last.
                ("y16_front", rect(6.0, 3.0), 15.0, Vec3::X),
            ],
        ),
    ];
    println!("| scan | point | expander | h cm | vertices at h, h/2 | gain at h cm² | gain at h/2 cm² | change | steps at h, h/2 |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut worst: f64 = 0.0;
    for (name, scan, cases) in sets {
        let scan = match scan {
            Ok(s) => s,
            Err(e) => {
                println!("{name}: skipped, {e}");
                continue;
            }
        };
        let patient = in_cm(&scan);
        let normals = patient.vertex_normals();
        for (point, shape, volume, tangent) in cases {
            let p = scan.points.iter().find(|p| p.name == point).unwrap();
            let implant = ImplantSpec::new(shape, volume).with_vertex_budget(300);
            let mut job = InsertionJob::new(
                patient.clone(),
                Placement::new(
                    patient.positions()[p.vertex as usize],
                    normals[p.vertex as usize],
                    tangent,
                ),
                implant,
            );
            job.params.run.stop.max_steps = MAX_STEPS;
            let h = job.sim_edge().unwrap().unwrap();
            let coarse = plan(&job, |_| ControlFlow::Continue(()));
            job.sim = SimMesh::Remeshed(ScanOptions {
                sim_edge: Some(0.5 * h),
                ..ScanOptions::default()
            });
            let fine = plan(&job, |_| ControlFlow::Continue(()));
            let what = match shape {
                ImplantShape::Round { diameter } => format!("round {diameter} cm, {volume} cm³"),
                ImplantShape::Rectangular { length, width, .. } => {
                    format!("rectangular {length} × {width} cm, {volume} cm³")
                }
                _ => format!("crescent 6 × 2 cm, {volume} cm³"),
            };
            match (coarse, fine) {
                (Ok(c), Ok(f)) => {
                    let change = (f.outcome.area_gain - c.outcome.area_gain) / c.outcome.area_gain;
                    worst = worst.max(change.abs());
                    let n = |x: &tissue_app::PlannedInsertion| {
                        x.surface.as_ref().map_or(0, |s| s.mesh().vertex_count())
                    };
                    let star = |x: &tissue_app::PlannedInsertion| {
                        if x.outcome.stop_reason == tissue_mss::StopReason::Settled {
                            ""
                        } else {
                            "*"
                        }
                    };
                    println!(
                        "| {name} | {point} | {what} | {h:.3} | {}, {} | {:.3} | {:.3} | {:+.2} % | {}{}, {}{} |",
                        n(&c),
                        n(&f),
                        c.outcome.area_gain,
                        f.outcome.area_gain,
                        100.0 * change,
                        c.outcome.steps,
                        star(&c),
                        f.outcome.steps,
                        star(&f)
                    );
                }
                (c, f) => println!(
                    "| {name} | {point} | {what} | {h:.3} | failed: {:?} / {:?} |",
                    c.err(),
                    f.err()
                ),
            }
        }
    }
    println!("largest change: {:.2} % (target < 5 %)", 100.0 * worst);
}
