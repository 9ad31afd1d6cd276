//! The generators' promises: valid meshes with the documented counts, outward normals,
//! determinism, placement points on the surface and away from the border.
#![allow(clippy::panic, clippy::print_stderr)]

use std::time::Instant;

use glam::{DVec3, Vec3};
use tissue_mesh::TriMesh;
use tissue_testscans::{
    closed_body, forearm_from_body, median_edge, noisy_face_scan, tapered_tube, Scan, ScanError,
};

/// Runs a generator, timing it. Panics when it fails, a missing fixture mesh included.
fn generate(name: &str, make: impl Fn() -> Result<Scan, ScanError>) -> Scan {
    let start = Instant::now();
    match make() {
        Ok(scan) => {
            let m = &scan.mesh;
            eprintln!(
                "{name}: {:.3} s, {} vertices, {} triangles, median edge {:.4} {}, {} loops, area {:.1} {}²",
                start.elapsed().as_secs_f64(),
                m.vertex_count(),
                m.triangle_count(),
                median_edge(m),
                scan.unit_name,
                m.topology().boundary_loops().len(),
                m.area(),
                scan.unit_name,
            );
            for p in &scan.points {
                eprintln!(
                    "  point {:<18} vertex {:>7} at {:?}, {:.2} {} from the border: {}",
                    p.name, p.vertex, p.position, p.border_distance, scan.unit_name, p.what
                );
            }
            scan
        }
        Err(e) => panic!("{name}: {e}"),
    }
}

/// Checks shared by every scan: the data rebuild into the same valid mesh, one component, every
/// point a vertex at its position.
fn check_common(scan: &Scan) {
    let m = &scan.mesh;
    let rebuilt = TriMesh::new(m.positions().to_vec(), m.triangles().to_vec());
    assert_eq!(rebuilt.as_ref(), Ok(m));
    assert_eq!(m.topology().component_count(), 1);
    assert!(m.unreferenced_vertices().is_empty());
    for p in &scan.points {
        assert_eq!(m.positions()[p.vertex as usize], p.position, "{}", p.name);
        assert!(!m.topology().vertex_triangles(p.vertex).is_empty());
    }
    assert_eq!(
        scan.cm_per_unit,
        match scan.unit_name {
            "mm" => 0.1,
            "cm" => 1.0,
            "dm" => 10.0,
            other => panic!("unit {other}"),
        }
    );
}

/// Smallest interior angle of any triangle, degrees.
fn min_angle_degrees(m: &TriMesh) -> f64 {
    let mut min = 180.0f64;
    for t in 0..m.triangle_count() {
        let c = m.corners(t).map(|p| p.as_dvec3());
        for k in 0..3 {
            let (a, b, o) = (c[(k + 1) % 3], c[(k + 2) % 3], c[k]);
            min = min.min((a - o).angle_between(b - o).to_degrees());
        }
    }
    min
}

/// Σ over triangles of the area vector · (centroid − nearest axis point), positive when the
/// normals point away from the axis everywhere on the whole.
fn outward_from_axis(m: &TriMesh, axis: impl Fn(DVec3) -> DVec3) -> (f64, usize) {
    let normals = m.triangle_normals();
    let mut sum = 0.0;
    let mut inward = 0;
    for (t, n) in normals.iter().enumerate() {
        let c = m.corners(t).map(|p| p.as_dvec3());
        let mid = (c[0] + c[1] + c[2]) / 3.0;
        let d = n.as_dvec3().dot(mid - axis(mid));
        sum += d;
        if d < 0.0 {
            inward += 1;
        }
    }
    (sum, inward)
}

#[test]
fn face_scan_is_a_noisy_holed_half_millimetre_disc() {
    let scan = generate("face", || noisy_face_scan(1));
    check_common(&scan);
    let m = &scan.mesh;
    assert_eq!(scan.unit_name, "mm");
    assert!(
        (100_000..=200_000).contains(&m.triangle_count()),
        "{}",
        m.triangle_count()
    );
    let truth = scan.truth.as_ref().expect("the face has a truth");
    let edge = median_edge(truth);
    assert!((0.35..=0.65).contains(&edge), "median edge {edge}");
    assert!(
        (15_000.0..=20_000.0).contains(&truth.area()),
        "area {}",
        truth.area()
    );
    assert_eq!(truth.topology().boundary_loops().len(), 1);
    let big = scan.big_hole.expect("the face has a big hole");
    assert_eq!(big.diameter, 30.0);
    assert!(
        (10..=20).contains(&scan.holes.len()),
        "{} holes",
        scan.holes.len()
    );
    eprintln!("  big hole at {:?}, {} mm", big.centre, big.diameter);
    for h in &scan.holes {
        assert!((2.0..=15.0).contains(&h.diameter));
        eprintln!("  hole at {:?}, {:.2} mm", h.centre, h.diameter);
    }
    let loops = m.topology().boundary_loops();
    for l in loops {
        let c = l.iter().map(|&v| m.positions()[v as usize]).sum::<Vec3>() / l.len() as f32;
        eprintln!("  loop of {} vertices around {c:?}", l.len());
    }
    assert_eq!(loops.len(), 1 + scan.holes.len() + 1);
    // Each hole is ringed by its own loop: some loop's vertices all lie within its rim.
    for h in scan.holes.iter().chain([&big]) {
        let ringed = loops.iter().any(|l| {
            l.iter()
                .all(|&v| m.positions()[v as usize].distance(h.centre) <= 0.5 * h.diameter + 1.5)
        });
        assert!(ringed, "hole at {:?}", h.centre);
    }
    // Noise: along the normals, σ ≈ 0.2 mm against the truth.
    assert_eq!(scan.truth_vertex.len(), m.vertex_count());
    let (mut sum, mut sq) = (0.0f64, 0.0f64);
    let normals = truth.vertex_normals();
    for (v, &t) in scan.truth_vertex.iter().enumerate() {
        let d = m.positions()[v] - truth.positions()[t as usize];
        let along = f64::from(d.dot(normals[t as usize]));
        assert!(f64::from(d.length()) - along.abs() < 1e-3);
        sum += along;
        sq += along * along;
    }
    let n = m.vertex_count() as f64;
    let sigma = (sq / n - (sum / n).powi(2)).sqrt();
    assert!((0.19..0.21).contains(&sigma), "noise σ {sigma}");
    // Outward: the face looks to +z (out of the head).
    let mean_normal: Vec3 = m.triangle_normals().iter().copied().sum::<Vec3>();
    assert!(mean_normal.normalize().z > 0.8, "{mean_normal:?}");
    // Points well inside: at least 15 mm from any boundary, none inside a hole.
    assert_eq!(scan.points.len(), 5);
    for p in &scan.points {
        assert!(
            p.border_distance >= 15.0,
            "{} at {}",
            p.name,
            p.border_distance
        );
    }
    // Determinism.
    let again = noisy_face_scan(1).expect("second run");
    assert_eq!(again.mesh, scan.mesh);
    assert_eq!(again.holes, scan.holes);
    let other = noisy_face_scan(2).expect("seed 2");
    assert_ne!(other.mesh.positions(), scan.mesh.positions());
}

#[test]
fn tube_is_uneven_outward_and_open_at_both_ends() {
    let scan = generate("tube", || tapered_tube(7));
    check_common(&scan);
    let m = &scan.mesh;
    assert_eq!(m.topology().boundary_loops().len(), 2);
    let edge = median_edge(m);
    assert!((0.175..=0.325).contains(&edge), "median edge {edge}");
    let p = m.positions();
    let lengths: Vec<f32> = m
        .topology()
        .edges()
        .iter()
        .map(|&[a, b]| p[a as usize].distance(p[b as usize]))
        .collect();
    let (lo, hi) = lengths
        .iter()
        .fold((f32::INFINITY, 0.0f32), |(lo, hi), &l| {
            (lo.min(l), hi.max(l))
        });
    let angle = min_angle_degrees(m);
    eprintln!("  tube edges {lo:.3}–{hi:.3} cm, min angle {angle:.1}°");
    assert!(lo >= 0.05 && hi <= 0.6, "edges {lo}–{hi}");
    assert!(angle > 10.0, "min angle {angle}");
    let (sum, inward) = outward_from_axis(m, |x| DVec3::new(0.0, x.y, 0.0));
    assert!(sum > 0.0 && inward == 0, "{sum} {inward}");
    let bb = m.bounding_box();
    assert!((bb.min.y - 0.0).abs() < 1e-5 && (bb.max.y - 25.0).abs() < 1e-4);
    for q in &scan.points {
        assert!(q.position.y >= 8.0 && q.position.y <= 17.0);
        assert!(q.border_distance >= 8.0);
        let r = 2.5 + 1.5 * q.position.y / 25.0;
        assert!((glam::Vec2::new(q.position.x, q.position.z).length() - r).abs() < 0.01);
    }
    assert_eq!(tapered_tube(7).expect("again").mesh, scan.mesh);
    assert_ne!(tapered_tube(8).expect("seed 8").mesh, scan.mesh);
}

#[test]
fn arm_is_an_open_refined_tube_with_two_cuts() {
    let scan = generate("arm", forearm_from_body);
    check_common(&scan);
    let m = &scan.mesh;
    assert_eq!(scan.unit_name, "dm");
    assert_eq!(m.topology().boundary_loops().len(), 2);
    let edge = median_edge(m);
    assert!((0.0175..=0.0325).contains(&edge), "median edge {edge}");
    let radius = scan.radius.expect("arm radius");
    eprintln!(
        "  arm radius {radius:.3} dm, min angle {:.1}°",
        min_angle_degrees(m)
    );
    assert!((0.25..0.6).contains(&radius));
    let segments = [
        (tissue_testscans::ARM_UPPER_CUT, tissue_testscans::ARM_ELBOW),
        (tissue_testscans::ARM_ELBOW, tissue_testscans::ARM_WRIST),
    ];
    let axis = |x: DVec3| {
        segments
            .iter()
            .map(|&(a, b)| {
                let (a, b) = (a.as_dvec3(), b.as_dvec3());
                let s = ((x - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
                a + (b - a) * s
            })
            .min_by(|p, q| p.distance(x).total_cmp(&q.distance(x)))
            .unwrap_or(x)
    };
    let (sum, inward) = outward_from_axis(m, axis);
    eprintln!(
        "  arm triangles facing the axis: {inward} of {}",
        m.triangle_count()
    );
    assert!(sum > 0.0 && inward * 100 < m.triangle_count());
    for p in &scan.points {
        assert!(
            p.border_distance >= 0.6,
            "{} at {}",
            p.name,
            p.border_distance
        );
    }
    assert_eq!(forearm_from_body().expect("again").mesh, scan.mesh);
}

#[test]
fn body_is_closed_outward_and_unmodified() {
    let scan = generate("body", closed_body);
    check_common(&scan);
    let m = &scan.mesh;
    assert_eq!((m.vertex_count(), m.triangle_count()), (13_380, 26_756));
    assert!(m.is_closed());
    let volume = m.signed_volume().expect("closed");
    eprintln!("  body volume {volume:.2} dm³");
    assert!((54.0..56.0).contains(&volume));
    let normals = m.vertex_normals();
    for p in &scan.points {
        let n = normals[p.vertex as usize];
        let front = matches!(p.name, "belly" | "thigh_left");
        assert!(
            if front { n.z > 0.5 } else { n.z < -0.5 },
            "{} normal {n:?}",
            p.name
        );
    }
}
