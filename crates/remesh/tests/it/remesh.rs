//! The public API of tissue-remesh on seeded and real surfaces: the output's invariants
//! (validity, topology, orientation, closeness to the input, edge lengths), smoothing, errors,
//! determinism.
#![allow(clippy::unwrap_used, clippy::print_stdout)]

use crate::common;

use common::{assert_same_topology, fit, read_obj};
use glam::Vec3;
use tissue_mesh::TriMesh;
use tissue_remesh::{remesh, scenes, RemeshError, RemeshOptions, Remeshed};

/// Remeshes `input` to `l` and checks every invariant: same topology, orientation, boundary and
/// interior vertices within `tol` of the input, ≥ 90 % of the edges in `[0.7L, 1.45L]`, at least
/// `agree` of the triangles facing the input's side at their centroid's closest point.
fn check(name: &str, input: &TriMesh, l: f64, tol: f64) -> Remeshed {
    check_with(name, input, l, tol, 1.0)
}

fn check_with(name: &str, input: &TriMesh, l: f64, tol: f64, agree: f64) -> Remeshed {
    let t0 = std::time::Instant::now();
    let out = remesh(input, &RemeshOptions::new(l)).unwrap();
    let elapsed = t0.elapsed();
    assert_same_topology(input, &out.mesh);
    let f = fit(input, &out.mesh);
    let q = &out.stats.quality;
    println!(
        "{name}: {} -> {} triangles in {elapsed:?}; agreeing {:.4}; edges {:.3}/{:.3}/{:.3}, in [0.8L,4/3L] {:.1} %, \
         in [0.7L,1.45L] {:.1} %; min angle {:.1}°, mean min angle {:.1}°, {} below 20°; \
         boundary {:.2e}, interior {:.2e}, min normal dot {:.2}",
        input.triangle_count(),
        q.triangles,
        f.agreeing,
        q.edge_min,
        q.edge_mean,
        q.edge_max,
        100.0 * q.edges_in_band,
        100.0 * q.edges_in_wide_band,
        q.min_angle_deg,
        q.mean_min_angle_deg,
        q.triangles_below_20_deg,
        f.boundary_max,
        f.interior_max,
        f.min_normal_dot,
    );
    assert!(
        f.agreeing >= agree,
        "{name}: {} of the triangles keep the input's orientation",
        f.agreeing
    );
    assert!(
        f.boundary_max <= tol,
        "{name}: boundary off by {}",
        f.boundary_max
    );
    assert!(
        f.interior_max <= tol,
        "{name}: interior off by {}",
        f.interior_max
    );
    assert!(q.edges_in_wide_band >= 0.9, "{name}: {q:?}");
    assert!(q.min_angle_deg > 10.0, "{name}: {q:?}");
    out
}

#[test]
fn fine_noisy_disc_to_three_millimetres() {
    let disc = scenes::noisy_disc(5.0, 0.05, 0.02, 1).unwrap();
    let out = check("noisy disc r=5, 0.05 -> 0.3", &disc, 0.3, 1e-3);
    assert!(out.stats.collapses > 10_000);
}

#[test]
fn fine_noisy_cylinder_patch() {
    let cyl = scenes::noisy_cylinder_patch(3.0, 8.0, 8.0, 0.05, 0.02, 2).unwrap();
    check("noisy cylinder R=3, 0.05 -> 0.3", &cyl, 0.3, 1e-3);
}

#[test]
fn coarse_disc_is_refined() {
    // 2.5 cm rings, 16 segments: triangles up to ~2 cm, refined to 0.3.
    let coarse = tissue_mesh::disc(2, 16, 5.0).unwrap();
    let out = check("coarse disc r=5 -> 0.3", &coarse, 0.3, 1e-3);
    assert!(out.stats.splits > 500);
}

#[test]
fn patch_with_holes_keeps_every_loop() {
    let plane = scenes::noisy_plane(6.0, 0.05, 0.02, 4).unwrap();
    let punched = scenes::punch_holes(
        &plane,
        &[
            Vec3::new(-1.5, -1.5, 0.0),
            Vec3::new(1.5, -1.0, 0.0),
            Vec3::new(0.0, 1.5, 0.0),
        ],
        0.5,
    )
    .unwrap();
    assert_eq!(punched.topology().boundary_loops().len(), 4);
    check("plane with 3 holes -> 0.3", &punched, 0.3, 1e-3);
}

#[test]
fn closed_sphere_stays_closed() {
    let sphere = scenes::noisy_sphere(2.0, 0.1, 0.0, 0).unwrap();
    let out = check("sphere r=2, 0.1 -> 0.3", &sphere, 0.3, 1e-3);
    assert!(out.mesh.is_closed());
    assert_eq!(out.mesh.euler_characteristic(), 2);
}

/// The MakeHuman head (decimetres, ×10 to cm): a Euclidean disc of radius 5 cm around the
/// front-most vertex (the nose), its connected part containing that vertex, refined to 0.3 cm.
#[test]
fn makehuman_head_disc_is_refined() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/makehuman_head_open.obj"
    );
    let head = read_obj(path, 10.0).unwrap_or_else(|| panic!("{path} cannot be read"));
    let (nose, _) = head
        .positions()
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.z.total_cmp(&b.1.z))
        .unwrap();
    let centre = head.positions()[nose];
    let cut = scenes::keep_triangles(&head, |t| {
        let [a, b, c] = head.corners(t);
        ((a + b + c) / 3.0 - centre).length() <= 5.0
    })
    .unwrap();
    let comps = cut.topology().triangle_components();
    let near = (0..cut.triangle_count())
        .min_by(|&x, &y| {
            let d = |t: usize| {
                let [a, b, c] = cut.corners(t);
                ((a + b + c) / 3.0 - centre).length()
            };
            d(x).total_cmp(&d(y))
        })
        .unwrap();
    let region = scenes::keep_triangles(&cut, |t| comps[t] == comps[near]).unwrap();
    let input_q = tissue_remesh::MeshQuality::measure(&region, 0.3);
    println!(
        "head region: {} triangles, edges {:.2}..{:.2} cm, {} loops",
        region.triangle_count(),
        input_q.edge_min,
        input_q.edge_max,
        region.topology().boundary_loops().len()
    );
    // Around the nostrils a 0.3 cm triangle spans folds of the coarse input, where its centroid's
    // closest input point can lie on the facing fold: 2 of ~2700 triangles there.
    check_with(
        "MakeHuman head disc r=5 cm -> 0.3",
        &region,
        0.3,
        1e-4,
        0.995,
    );
}

fn rms_distance(mesh: &TriMesh, distance: impl Fn(Vec3) -> f64) -> f64 {
    let sum: f64 = mesh.positions().iter().map(|&p| distance(p).powi(2)).sum();
    (sum / mesh.vertex_count() as f64).sqrt()
}

#[test]
fn smoothing_removes_noise_on_a_plane() {
    let plane = scenes::noisy_plane(6.0, 0.05, 0.02, 11).unwrap();
    let noise = rms_distance(&plane, |p| f64::from(p.z));
    let raw = remesh(&plane, &RemeshOptions::new(0.3)).unwrap();
    let smooth = remesh(&plane, &RemeshOptions::new(0.3).with_smoothing(0.3)).unwrap();
    let (e_raw, e_smooth) = (
        rms_distance(&raw.mesh, |p| f64::from(p.z)),
        rms_distance(&smooth.mesh, |p| f64::from(p.z)),
    );
    println!(
        "plane noise RMS {noise:.4}: remeshed without smoothing {e_raw:.4}, with r = 0.3 {e_smooth:.4} \
         ({:.1}x less)",
        noise / e_smooth
    );
    assert!(e_smooth <= 0.25 * noise);
    assert_same_topology(&plane, &smooth.mesh);
    assert!(smooth.stats.quality.edges_in_wide_band >= 0.9);
}

#[test]
fn smoothing_removes_noise_on_a_sphere() {
    let sphere = scenes::noisy_sphere(3.0, 0.05, 0.02, 12).unwrap();
    let dist = |p: Vec3| f64::from(p.length()) - 3.0;
    let noise = rms_distance(&sphere, dist);
    let smooth = remesh(&sphere, &RemeshOptions::new(0.3).with_smoothing(0.3)).unwrap();
    let e = rms_distance(&smooth.mesh, dist);
    println!(
        "sphere r=3 noise RMS {noise:.4}: remeshed with r = 0.3 {e:.4} ({:.1}x less)",
        noise / e
    );
    assert!(e <= 0.25 * noise);
    assert!(smooth.mesh.is_closed());
}

#[test]
fn same_input_same_output_bit_for_bit() {
    let cyl = scenes::noisy_cylinder_patch(3.0, 4.0, 4.0, 0.05, 0.02, 3).unwrap();
    let options = RemeshOptions::new(0.3).with_smoothing(0.3);
    let a = remesh(&cyl, &options).unwrap();
    let b = remesh(&cyl, &options).unwrap();
    assert_eq!(a.mesh, b.mesh);
    assert_eq!(a.stats, b.stats);
}

#[test]
fn bad_options_are_errors_that_say_what_to_do() {
    let plane = tissue_mesh::grid(5, 1.0).unwrap();
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = remesh(&plane, &RemeshOptions::new(bad)).unwrap_err();
        assert!(matches!(err, RemeshError::InvalidTargetEdge { .. }));
        assert!(err.to_string().contains("must be finite and > 0"));
    }
    let err = remesh(&plane, &RemeshOptions::new(0.3).with_smoothing(-0.1)).unwrap_err();
    assert!(matches!(err, RemeshError::InvalidSmoothingRadius { .. }));
    let err = remesh(&plane, &RemeshOptions::new(1e-5)).unwrap_err();
    assert!(matches!(err, RemeshError::TooManyTriangles { .. }));
    assert!(
        err.to_string().contains("use a target edge of at least"),
        "{err}"
    );
}

#[test]
fn eighty_thousand_triangle_patch_remeshes_in_well_under_a_second() {
    let patch = scenes::noisy_plane(10.0, 0.05, 0.02, 7).unwrap();
    assert_eq!(patch.triangle_count(), 80_000);
    let t0 = std::time::Instant::now();
    let out = remesh(&patch, &RemeshOptions::new(0.3)).unwrap();
    let elapsed = t0.elapsed();
    println!(
        "80k patch -> {} triangles in {elapsed:?}",
        out.mesh.triangle_count()
    );
    assert_same_topology(&patch, &out.mesh);
    // A loose bound (shared, debug-info test builds); the bench measures the real figure.
    assert!(elapsed.as_secs_f64() < 2.0);
}
