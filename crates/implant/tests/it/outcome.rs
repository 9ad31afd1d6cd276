//! The result geometry through the public API: displacements and stretch against exact values
//! for uniform scalings, lifts and a hand-computed square, the region put back into the patient
//! bit for bit at its seam, and the errors.
#![allow(clippy::unwrap_used, clippy::panic)]

use glam::Vec3;
use tissue_implant::{
    replace_region, select_region, vertex_displacements, vertex_stretch, FieldRange, ImplantError,
    RegionSelection, NOT_IN_REGION,
};
use tissue_mesh::{grid, uv_sphere, TriMesh};

/// `mesh` with every position mapped by `f`.
fn deformed(mesh: &TriMesh, f: impl Fn(Vec3) -> Vec3) -> TriMesh {
    mesh.with_positions(mesh.positions().iter().map(|&p| f(p)).collect())
        .unwrap()
}

/// The bits of a position, to compare positions exactly (also telling 0.0 from −0.0).
fn bits(p: Vec3) -> [u32; 3] {
    p.to_array().map(f32::to_bits)
}

/// The region's boundary vertices as flags over its vertices.
fn boundary_flags(region: &RegionSelection) -> Vec<bool> {
    let mut flags = vec![false; region.mesh().vertex_count()];
    for &v in region.boundary_loops().iter().flatten() {
        flags[v as usize] = true;
    }
    flags
}

/// The message of an `InvalidParameter` error, after checking its name.
fn invalid_parameter<T: std::fmt::Debug>(result: Result<T, ImplantError>, name: &str) -> String {
    match result {
        Err(err @ ImplantError::InvalidParameter { param: n, .. }) if n.name() == name => {
            err.to_string()
        }
        other => panic!("expected InvalidParameter named {name}, got {other:?}"),
    }
}

#[test]
fn scaling_a_plane_by_two_stretches_it_four_times() {
    let before = grid(17, 6.0).unwrap();
    let after = deformed(&before, |p| p * Vec3::new(2.0, 2.0, 1.0));
    let stretch = vertex_stretch(&before, &after).unwrap();
    assert_eq!(stretch.len(), before.vertex_count());
    for (v, &s) in stretch.iter().enumerate() {
        assert!((s - 4.0).abs() < 1e-5, "vertex {v}: stretch {s}");
    }
    let moved = vertex_displacements(&before, &after).unwrap();
    assert_eq!(moved.len(), before.vertex_count());
    for (v, (&d, &p)) in moved.iter().zip(before.positions()).enumerate() {
        // Each vertex moves by its own position: 2p − p = p.
        assert!(
            (d - p.length()).abs() <= 1e-6 * p.length(),
            "vertex {v}: {d} vs {p}"
        );
    }
    // The centre vertex stays put; a corner moves by half the diagonal.
    assert_eq!(moved[8 * 17 + 8], 0.0);
    assert!((moved[0] - 3.0 * 2f32.sqrt()).abs() < 1e-6);
}

#[test]
fn lifting_a_plane_moves_it_without_stretch() {
    let before = grid(9, 4.0).unwrap();
    let after = deformed(&before, |p| p + Vec3::new(0.0, 0.0, 0.75));
    for (v, &s) in vertex_stretch(&before, &after).unwrap().iter().enumerate() {
        assert!((s - 1.0).abs() < 1e-6, "vertex {v}: stretch {s}");
    }
    let moved = vertex_displacements(&before, &after).unwrap();
    assert!(moved.iter().all(|&d| d == 0.75), "{moved:?}");
    // A rigid motion of a curved surface does not stretch it either; scaling it by 3 gives 9.
    let sphere = uv_sphere(16, 15, 2.0).unwrap();
    let (sin, cos) = 0.7f32.sin_cos();
    let turned = deformed(&sphere, |p| {
        Vec3::new(cos * p.x - sin * p.y, sin * p.x + cos * p.y, p.z) + Vec3::new(1.0, -2.0, 0.5)
    });
    let grown = deformed(&sphere, |p| 3.0 * p);
    for (&s, &g) in vertex_stretch(&sphere, &turned)
        .unwrap()
        .iter()
        .zip(&vertex_stretch(&sphere, &grown).unwrap())
    {
        assert!((s - 1.0).abs() < 1e-5, "rigid motion: stretch {s}");
        assert!((g - 9.0).abs() < 1e-4, "scaled by 3: stretch {g}");
    }
}

#[test]
fn stretch_is_the_ratio_of_tributary_areas() {
    // A unit square of two triangles (areas ½, ½); pulling corner 1 to x = 2 doubles triangle 0.
    // Tributary areas before: ⅓, ⅙, ⅓, ⅙; after: ½, ⅓, ½, ⅙.
    let square = TriMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let pulled = square
        .with_positions(vec![
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
        ])
        .unwrap();
    let stretch = vertex_stretch(&square, &pulled).unwrap();
    for (s, want) in stretch.iter().zip([1.5, 2.0, 1.5, 1.0]) {
        assert!((s - want).abs() < 1e-6, "{stretch:?}");
    }
    assert_eq!(
        vertex_displacements(&square, &pulled).unwrap(),
        [0.0, 1.0, 0.0, 0.0]
    );
}

#[test]
fn an_unreferenced_vertex_has_stretch_one() {
    let mesh = TriMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(5.0, 5.0, 5.0)],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let after = deformed(&mesh, |p| 2.0 * p);
    let stretch = vertex_stretch(&mesh, &after).unwrap();
    assert!(stretch[..3].iter().all(|&s| (s - 4.0).abs() < 1e-6));
    assert_eq!(stretch[3], 1.0);
    let moved = vertex_displacements(&mesh, &after).unwrap();
    assert!((moved[3] - 75f32.sqrt()).abs() < 1e-5);
}

#[test]
fn different_meshes_are_refused() {
    let small = grid(5, 4.0).unwrap();
    let large = grid(6, 4.0).unwrap();
    for message in [
        invalid_parameter(vertex_displacements(&small, &large), "after"),
        invalid_parameter(vertex_stretch(&small, &large), "after"),
    ] {
        assert!(
            message.contains("25") && message.contains("36"),
            "{message}"
        );
    }
    // Same vertices, the triangles in another order.
    let (positions, mut triangles) = small.clone().into_parts();
    triangles.reverse();
    let reordered = TriMesh::new(positions, triangles).unwrap();
    for message in [
        invalid_parameter(vertex_displacements(&small, &reordered), "after"),
        invalid_parameter(vertex_stretch(&small, &reordered), "after"),
    ] {
        assert!(message.contains("triangle 0"), "{message}");
    }
    // Fewer triangles on the same vertices (the rest unreferenced).
    let (positions, triangles) = small.clone().into_parts();
    let fewer = TriMesh::new(positions, triangles[..10].to_vec()).unwrap();
    let message = invalid_parameter(vertex_stretch(&small, &fewer), "after");
    assert!(
        message.contains("32") && message.contains("10"),
        "{message}"
    );
}

#[test]
fn stretch_from_a_collapsed_state_is_refused() {
    // A deformed state may be flat; stretch relative to it is undefined.
    let plane = grid(5, 4.0).unwrap();
    let collapsed = deformed(&plane, |p| Vec3::new(p.x, 0.0, 0.0));
    let message = invalid_parameter(vertex_stretch(&collapsed, &plane), "before");
    assert!(message.contains("vertex 0"), "{message}");
    // The other way round is a full compression: stretch 0.
    let stretch = vertex_stretch(&plane, &collapsed).unwrap();
    assert!(stretch.iter().all(|&s| s == 0.0), "{stretch:?}");
}

/// A smooth bump of height 1 cm over the region, plus 0.1 cm everywhere so that even the
/// boundary vertices are given new positions (which must be ignored).
fn bumped(region: &RegionSelection) -> Vec<Vec3> {
    let r = region.radius() as f32;
    region
        .mesh()
        .positions()
        .iter()
        .map(|&p| {
            let t = (p.truncate().length() / r).min(1.0);
            p + Vec3::Z * (0.1 + (1.0 - t * t).powi(2))
        })
        .collect()
}

/// Checks `result` against the patient and the region's new positions vertex by vertex.
fn check_replaced(patient: &TriMesh, region: &RegionSelection, after: &[Vec3], result: &TriMesh) {
    assert_eq!(result.triangles(), patient.triangles());
    assert_eq!(result.vertex_count(), patient.vertex_count());
    let boundary = boundary_flags(region);
    let (mut fixed, mut moved) = (0, 0);
    for (v, (&got, &was)) in result
        .positions()
        .iter()
        .zip(patient.positions())
        .enumerate()
    {
        let r = region.patient_to_region()[v];
        if r == NOT_IN_REGION || boundary[r as usize] {
            assert_eq!(
                bits(got),
                bits(was),
                "patient vertex {v} (region {r}) moved"
            );
            if r != NOT_IN_REGION {
                assert_ne!(
                    bits(after[r as usize]),
                    bits(was),
                    "test data: boundary kept"
                );
                fixed += 1;
            }
        } else {
            assert_eq!(bits(got), bits(after[r as usize]), "patient vertex {v}");
            assert_ne!(
                bits(got),
                bits(was),
                "test data: interior vertex {v} not moved"
            );
            moved += 1;
        }
    }
    assert!(
        fixed >= 8 && moved >= 8,
        "{fixed} boundary, {moved} interior"
    );
}

#[test]
fn replace_region_moves_the_interior_and_keeps_the_seam() {
    let patient = grid(33, 10.0).unwrap();
    let region = select_region(&patient, Vec3::ZERO, 3.0).unwrap();
    let after = bumped(&region);
    let result = replace_region(&patient, &region, &after).unwrap();
    check_replaced(&patient, &region, &after, &result);
    // The centre is lifted by the full bump.
    assert_eq!(result.positions()[16 * 33 + 16], Vec3::new(0.0, 0.0, 1.1));
    // The region alone in the result: its stretch is above 1 inside, exactly 1 nowhere else.
    let stretch = vertex_stretch(&patient, &result).unwrap();
    let moved = vertex_displacements(&patient, &result).unwrap();
    for v in 0..patient.vertex_count() {
        let r = region.patient_to_region()[v];
        if r == NOT_IN_REGION {
            assert_eq!(moved[v], 0.0);
        }
        if r == NOT_IN_REGION
            && patient
                .topology()
                .vertex_triangles(v as u32)
                .iter()
                .all(|&t| {
                    patient.triangles()[t as usize]
                        .iter()
                        .all(|&w| region.patient_to_region()[w as usize] == NOT_IN_REGION)
                })
        {
            assert_eq!(stretch[v], 1.0, "vertex {v} away from the region");
        }
    }
    assert!(stretch[16 * 33 + 16] > 1.0);
    let range = FieldRange::of(&moved).unwrap();
    assert_eq!((range.min, range.max), (0.0, 1.1));
}

#[test]
fn replace_region_on_a_closed_sphere() {
    let patient = uv_sphere(24, 23, 2.0).unwrap();
    let region = select_region(&patient, Vec3::new(0.0, 2.1, 0.3), 1.5).unwrap();
    let after: Vec<Vec3> = region.mesh().positions().iter().map(|&p| 1.1 * p).collect();
    let result = replace_region(&patient, &region, &after).unwrap();
    check_replaced(&patient, &region, &after, &result);
}

#[test]
fn replace_region_refuses_bad_positions() {
    let patient = grid(33, 10.0).unwrap();
    let region = select_region(&patient, Vec3::ZERO, 3.0).unwrap();
    let n = region.mesh().vertex_count();
    let after = bumped(&region);

    for len in [n - 1, n + 1, 0] {
        let mut wrong = after.clone();
        wrong.resize(len, Vec3::ZERO);
        let message = invalid_parameter(replace_region(&patient, &region, &wrong), "region_after");
        assert!(
            message.contains(&n.to_string()) && message.contains(&len.to_string()),
            "{message}"
        );
    }

    let boundary = boundary_flags(&region);
    let interior = (0..n).find(|&i| !boundary[i] && i > 3).unwrap();
    let on_boundary = (0..n).rev().find(|&i| boundary[i]).unwrap();
    for (i, bad) in [
        (interior, f32::NAN),
        (interior, f32::INFINITY),
        // Ignored or not, a non-finite position means the run failed.
        (on_boundary, f32::NEG_INFINITY),
    ] {
        let mut wrong = after.clone();
        wrong[i].y = bad;
        let message = invalid_parameter(replace_region(&patient, &region, &wrong), "region_after");
        assert!(
            message.contains(&format!("region vertex {i} ")),
            "{message}"
        );
        let p = region.region_to_patient()[i];
        assert!(
            message.contains(&format!("patient vertex {p})")),
            "{message}"
        );
    }
}

#[test]
fn replace_region_refuses_another_patient() {
    let patient = grid(33, 10.0).unwrap();
    let region = select_region(&patient, Vec3::ZERO, 3.0).unwrap();
    let after = bumped(&region);

    let smaller = grid(17, 10.0).unwrap();
    let message = invalid_parameter(replace_region(&smaller, &region, &after), "patient");
    assert!(
        message.contains("1089") && message.contains("289"),
        "{message}"
    );

    // Same vertices, the triangles in another order: not the mesh the region came from.
    let (positions, mut triangles) = patient.clone().into_parts();
    triangles.reverse();
    let reordered = TriMesh::new(positions, triangles).unwrap();
    let message = invalid_parameter(replace_region(&reordered, &region, &after), "patient");
    assert!(message.contains("region triangle 0"), "{message}");
}

#[test]
fn field_range_of_values() {
    let r = FieldRange::of(&[2.0, -1.0, 5.0, 2.0]).unwrap();
    assert_eq!(
        r,
        FieldRange {
            min: -1.0,
            max: 5.0,
            mean: 2.0
        }
    );
    assert_eq!(FieldRange::of(&[3.5]).unwrap().mean, 3.5);
    assert_eq!(FieldRange::of(&[]), None);
    assert_eq!(FieldRange::of(&[1.0, f32::NAN]), None);
    assert_eq!(FieldRange::of(&[f32::INFINITY]), None);
}
