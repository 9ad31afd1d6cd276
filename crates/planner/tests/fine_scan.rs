//! Issue 31 (part 7): a scan as fine as scanners make them, far from the origin, plans; no
//! triangle the hole filling, the remeshing or the plan makes is degenerate.
//!
//! The scan is `tissue_testscans::fine_face_scan(1, 1, 770 mm along x)`: the noisy face once
//! midpoint-subdivided (about 650k triangles, 0.25 mm edges), 77 cm from the origin in `f32`,
//! with six holes whose loops have straight runs of collinear vertices (the case that made a
//! zero-area fill triangle on the 2.6-million-triangle scan). The bench
//! `benches/fine_scan.rs` runs the twice-subdivided one.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::print_stderr
)]

use glam::Vec3;
use tissue_implant::{default_radius, prepare_scan, RegionOptions, ScanOptions};
use tissue_mesh::TriMesh;
use tissue_planner::{CancelToken, JobSpec, Patient, PlanRequest, Scenario, Tool, Unit};

/// The floor every made triangle's height stays above, as a fraction of its longest edge:
/// `2·area / longest² ≥ FLOOR` (1000 × the mesh checks' zero-area tolerance; an equilateral
/// triangle has 0.87).
const FLOOR: f64 = 1e-4;

/// The smallest `2·area / longest²` of the triangles of `mesh` from `first` on, in `f64`.
fn thinnest(mesh: &TriMesh, first: usize) -> f64 {
    (first..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh.corners(t).map(|p| p.as_dvec3());
            let longest = (b - a)
                .length_squared()
                .max((c - b).length_squared())
                .max((a - c).length_squared());
            (b - a).cross(c - a).length() / longest
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_fine_scan_far_from_the_origin_fills_remeshes_and_plans_without_degenerate_triangles() {
    let offset = Vec3::new(770.0, 0.0, 0.0);
    let scan = match tissue_testscans::fine_face_scan(1, 1, offset) {
        Ok(scan) => scan,
        Err(e) => panic!("the fine face scan: {e}"),
    };
    assert!(
        scan.mesh.triangle_count() > 600_000,
        "{}",
        scan.mesh.triangle_count()
    );
    let patient = Patient::from_mesh(scan.mesh.clone(), Unit::Mm, "fine face".into()).unwrap();

    // Every hole of the scan filled on the whole scan, no fill triangle near degenerate.
    let fill = tissue_remesh::fill_holes(&patient.cm, 1.5).unwrap();
    assert_eq!(fill.filled.len(), scan.holes.len(), "{:?}", fill.open.len());
    let fills = thinnest(&fill.mesh, fill.first_fill_triangle);
    eprintln!(
        "{} triangles, {} holes filled with {} triangles, thinnest fill {fills:.3e}",
        scan.mesh.triangle_count(),
        fill.filled.len(),
        fill.mesh.triangle_count() - fill.first_fill_triangle
    );
    assert!(
        fills >= FLOOR,
        "a fill triangle of height {fills:e} × its longest edge"
    );

    // A region at a hole's rim: the hole is filled inside it, and the simulation surface has no
    // thin triangle either.
    let radius = default_radius(0.5).unwrap();
    let mut with_hole = 0;
    for hole in &scan.holes {
        let centre = hole.centre * 0.1;
        let Some(rim) = fill.filled.iter().find_map(|h| {
            h.vertices
                .iter()
                .map(|&v| patient.cm.positions()[v as usize])
                .min_by(|a, b| a.distance(centre).total_cmp(&b.distance(centre)))
                .filter(|p| p.distance(centre) < 0.5 * hole.diameter * 0.1 + 0.1)
        }) else {
            continue;
        };
        let prepared = prepare_scan(
            &patient.cm,
            rim,
            radius,
            0.25,
            &RegionOptions::default(),
            &ScanOptions::default(),
        );
        let Ok((selection, surface)) = prepared else {
            continue; // too near the border for this radius
        };
        assert!(thinnest(selection.mesh(), 0) >= FLOOR);
        let sim = thinnest(surface.mesh(), 0);
        assert!(sim >= FLOOR, "a simulation triangle of height {sim:e}");
        if !surface.holes_filled().is_empty() {
            with_hole += 1;
        }
    }
    assert!(
        with_hole > 0,
        "no region at a hole's rim had the hole filled"
    );

    // The plan through the front door, at the forehead.
    let forehead = scan.points.iter().find(|p| p.name == "forehead").unwrap();
    let request = PlanRequest {
        vertex: Some(forehead.vertex),
        diameter_cm: 2.5,
        volume_cm3: 2.0,
        ..PlanRequest::default()
    };
    let scenario = Scenario::new(patient, request).unwrap();
    let finished = JobSpec::default()
        .plan(&scenario)
        .unwrap()
        .run(&scenario, Tool::Insert, &CancelToken::new(), |_| {})
        .unwrap_or_else(|e| panic!("the plan on the fine scan: {e:?}"));
    let result = finished.patient.unwrap();
    let moved = result.displacement.iter().fold(0.0f32, |a, &b| a.max(b));
    let after = thinnest(&result.after, 0);
    eprintln!("plan: largest move {moved:.2} mm, thinnest triangle after {after:.3e}");
    assert!(moved > 0.5, "{moved}");
    assert!(
        after >= FLOOR,
        "a scan triangle of height {after:e} after the plan"
    );
    assert_eq!(result.after.triangles(), scan.mesh.triangles());
}
