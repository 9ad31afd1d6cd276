//! Every defect kind of a triangle surface is detected and names the right element; the topology
//! of valid meshes (edges, boundary loops, components) matches hand counts.
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::{diagnose, MeshError, TriMesh, NO_TRIANGLE};

/// An `n`×`n`-vertex unit grid in z = 0, normal +z, each cell split along the same diagonal.
fn grid(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for row in 0..n {
        for col in 0..n {
            p.push(Vec3::new(col as f32, row as f32, 0.0));
        }
    }
    let mut t = Vec::new();
    for row in 0..n - 1 {
        for col in 0..n - 1 {
            let v = row * n + col;
            t.push([v, v + 1, v + n + 1]);
            t.push([v, v + n + 1, v + n]);
        }
    }
    (p, t)
}

/// A regular octahedron, normals outward.
fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let t = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    (p, t)
}

fn only_defect(p: &[Vec3], t: &[[u32; 3]]) -> MeshError {
    let defects = diagnose(p, t);
    assert_eq!(defects.len(), 1, "expected one defect, got {defects:?}");
    defects.into_iter().next().unwrap()
}

#[test]
fn valid_meshes_have_no_defects() {
    let (p, t) = grid(5);
    assert!(diagnose(&p, &t).is_empty());
    let (p, t) = octahedron();
    assert!(diagnose(&p, &t).is_empty());
}

#[test]
fn index_out_of_range_names_triangle_and_index() {
    let (p, mut t) = grid(4);
    t[7][2] = 99;
    let d = only_defect(&p, &t);
    assert_eq!(
        d,
        MeshError::IndexOutOfRange {
            triangle: 7,
            index: 99,
            vertex_count: 16
        }
    );
    assert_eq!(TriMesh::new(p, t).unwrap_err(), d);
    assert!(d.to_string().contains("triangle 7"));
}

#[test]
fn non_finite_coordinate_names_vertex() {
    let (mut p, t) = grid(4);
    p[5].y = f32::INFINITY;
    let defects = diagnose(&p, &t);
    assert!(matches!(
        defects[0],
        MeshError::NonFiniteCoordinate { vertex: 5, .. }
    ));
    assert!(matches!(
        TriMesh::new(p, t),
        Err(MeshError::NonFiniteCoordinate { vertex: 5, .. })
    ));
}

#[test]
fn repeated_vertex_and_collinear_triangles_are_zero_area() {
    // Repeated index: triangle 3 becomes a line.
    let (p, mut t) = grid(4);
    t[3] = [1, 1, 6];
    let defects = diagnose(&p, &t);
    assert!(
        defects.iter().any(|d| matches!(
            d,
            MeshError::DegenerateTriangle {
                triangle: 3,
                vertices: [1, 1, 6],
                ..
            }
        )),
        "{defects:?}"
    );
    // Collinear: move vertex 5 onto the edge 0–1 of triangle 0 = [0, 1, 5]; its other five
    // triangles keep their area.
    let (mut p, t) = grid(4);
    p[5] = Vec3::new(0.5, 0.0, 0.0);
    let d = only_defect(&p, &t);
    assert!(
        matches!(
            d,
            MeshError::DegenerateTriangle {
                triangle: 0,
                vertices: [0, 1, 5],
                area,
            } if area < 1e-12
        ),
        "{d:?}"
    );
    // A thin but honest sliver (height 1e-4 of its length) is not degenerate.
    p[5] = Vec3::new(0.5, 1e-4, 0.0);
    assert!(diagnose(&p, &t).is_empty());
}

#[test]
fn duplicate_triangle_names_both() {
    let (p, mut t) = octahedron();
    t.push([4, 0, 2]); // triangle 0 again, rotated
    let defects = diagnose(&p, &t);
    assert_eq!(
        defects,
        vec![MeshError::DuplicateTriangle {
            triangle: 8,
            first: 0,
            vertices: [4, 0, 2]
        }]
    );
}

#[test]
fn edge_in_three_triangles_is_non_manifold() {
    // A "book" of three pages on the spine 0–1.
    let p = vec![
        Vec3::ZERO,
        Vec3::Z,
        Vec3::X,
        Vec3::Y,
        Vec3::new(-1.0, -1.0, 0.0),
    ];
    let t = vec![[0, 2, 1], [0, 1, 3], [0, 4, 1]];
    let defects = diagnose(&p, &t);
    assert!(
        defects.contains(&MeshError::NonManifoldEdge {
            edge: [0, 1],
            triangles: vec![0, 1, 2]
        }),
        "{defects:?}"
    );
    assert!(matches!(
        TriMesh::new(p, t),
        Err(MeshError::NonManifoldEdge { .. })
    ));
}

#[test]
fn flipped_neighbour_is_inconsistent_winding() {
    let (p, mut t) = grid(3);
    // Triangle 1 = [0, 4, 3]; flip it. Its edges 0–4 (shared with triangle 0) and 3–4 (shared with
    // triangle 5... in the row above: none, grid(3) has rows 0..2) now run the same way as the
    // neighbours'.
    t[1] = [0, 3, 4];
    let defects = diagnose(&p, &t);
    assert!(
        defects.contains(&MeshError::InconsistentWinding {
            edge: [0, 4],
            triangles: [0, 1]
        }),
        "{defects:?}"
    );
    assert!(defects
        .iter()
        .all(|d| matches!(d, MeshError::InconsistentWinding { .. })));
}

#[test]
fn unreferenced_vertex_is_a_warning_only() {
    let (mut p, t) = octahedron();
    p.push(Vec3::splat(7.0));
    let d = only_defect(&p, &t);
    assert_eq!(d, MeshError::UnreferencedVertex { vertex: 6 });
    assert!(d.is_warning());
    let m = TriMesh::new(p, t).expect("warnings do not stop loading");
    assert_eq!(m.unreferenced_vertices(), vec![6]);
    assert!(m.is_closed());
    assert_eq!(m.euler_characteristic(), 3); // 7 − 12 + 8: the stray vertex counts
}

#[test]
fn octahedron_topology() {
    let (p, t) = octahedron();
    let m = TriMesh::new(p, t).unwrap();
    let topo = m.topology();
    assert_eq!(topo.edges().len(), 12);
    assert!(m.is_closed());
    assert!(topo.boundary_loops().is_empty());
    assert_eq!(m.euler_characteristic(), 2);
    assert_eq!(topo.component_count(), 1);
    assert!(topo.edge_triangles().iter().all(|e| e[1] != NO_TRIANGLE));
    for v in 0..6 {
        assert_eq!(topo.vertex_triangles(v).len(), 4);
    }
    // triangle_edges and edges agree.
    for (tri, sides) in m.triangles().iter().zip(topo.triangle_edges()) {
        for s in 0..3 {
            let mut e = [tri[s], tri[(s + 1) % 3]];
            e.sort_unstable();
            assert_eq!(topo.edges()[sides[s] as usize], e);
        }
    }
}

#[test]
fn grid_boundary_loop_is_ordered_counter_clockwise() {
    let n = 6;
    let (p, t) = grid(n);
    let m = TriMesh::new(p, t).unwrap();
    let topo = m.topology();
    let loops = topo.boundary_loops();
    assert_eq!(loops.len(), 1);
    let l = &loops[0];
    assert_eq!(l.len() as u32, 4 * (n - 1));
    assert_eq!(topo.boundary_edge_count() as u32, 4 * (n - 1));
    // Consecutive loop vertices are grid neighbours, and the shoelace area is positive (CCW from +z).
    let pos = m.positions();
    let mut shoelace = 0.0f64;
    for i in 0..l.len() {
        let (a, b) = (pos[l[i] as usize], pos[l[(i + 1) % l.len()] as usize]);
        assert!(((a - b).length() - 1.0).abs() < 1e-6);
        shoelace += f64::from(a.x * b.y - b.x * a.y);
    }
    assert_eq!(shoelace / 2.0, f64::from((n - 1) * (n - 1)));
    assert_eq!(m.euler_characteristic(), 1);
    let mask = topo.boundary_vertex_mask(m.vertex_count());
    assert_eq!(mask.iter().filter(|&&b| b).count() as u32, 4 * (n - 1));
    assert!(!mask[(n + 1) as usize]);
}

#[test]
fn annulus_has_two_loops_and_two_components_are_found() {
    // A 4×4-vertex grid with its central cell removed: an annulus with an outer and an inner loop.
    let (p, mut t) = grid(4);
    // Central cell (row 1, col 1) is cell index 4 → triangles 8 and 9.
    t.drain(8..10);
    let m = TriMesh::new(p.clone(), t.clone()).unwrap();
    let loops = m.topology().boundary_loops();
    assert_eq!(loops.len(), 2);
    let mut lengths: Vec<usize> = loops.iter().map(Vec::len).collect();
    lengths.sort_unstable();
    assert_eq!(lengths, vec![4, 12]);
    assert_eq!(m.euler_characteristic(), 0);
    assert_eq!(m.topology().component_count(), 1);

    // Two disjoint copies: two components, labelled in order of their first triangle.
    let offset = p.len() as u32;
    let mut p2 = p.clone();
    p2.extend(p.iter().map(|v| *v + Vec3::new(10.0, 0.0, 0.0)));
    let mut t2 = t.clone();
    t2.extend(t.iter().map(|tri| tri.map(|i| i + offset)));
    let m2 = TriMesh::new(p2, t2).unwrap();
    assert_eq!(m2.topology().component_count(), 2);
    let comps = m2.topology().triangle_components();
    assert!(comps[..t.len()].iter().all(|&c| c == 0));
    assert!(comps[t.len()..].iter().all(|&c| c == 1));
    assert_eq!(m2.topology().boundary_loops().len(), 4);
}

#[test]
fn every_defect_is_listed_not_just_the_first() {
    let (mut p, mut t) = grid(4);
    p[2].x = f32::NAN;
    t[0][1] = 40;
    t.push(t[5]);
    p.push(Vec3::ONE);
    let defects = diagnose(&p, &t);
    assert!(defects
        .iter()
        .any(|d| matches!(d, MeshError::NonFiniteCoordinate { vertex: 2, .. })));
    assert!(defects.iter().any(|d| matches!(
        d,
        MeshError::IndexOutOfRange {
            triangle: 0,
            index: 40,
            ..
        }
    )));
    assert!(defects.iter().any(|d| matches!(
        d,
        MeshError::DuplicateTriangle {
            triangle: 18,
            first: 5,
            ..
        }
    )));
    assert!(defects
        .iter()
        .any(|d| matches!(d, MeshError::UnreferencedVertex { vertex: 16 })));
}
