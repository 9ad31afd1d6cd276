//! Tetrahedral meshes: the generated box against its closed-form volume and boundary, face
//! adjacency, and every defect kind of `diagnose_tets` naming the right element.
#![allow(clippy::expect_used)]

use glam::Vec3;
use tissue_mesh::{diagnose_tets, tet_box, MeshError, TetMesh, NO_TET, TET_FACES};

/// The data of a 2×1×1 box of side 1 (12 vertices, 12 tetrahedra).
fn two_cells() -> (Vec<Vec3>, Vec<[u32; 4]>) {
    tet_box(2, 1, 1, Vec3::new(2.0, 1.0, 1.0))
        .expect("valid box")
        .into_parts()
}

fn sorted<const N: usize>(mut a: [u32; N]) -> [u32; N] {
    a.sort_unstable();
    a
}

#[test]
fn tet_box_volume_counts_and_validity() {
    for ((nx, ny, nz), size) in [
        ((1, 1, 1), Vec3::ONE),
        ((4, 3, 2), Vec3::new(2.0, 1.5, 3.0)),
        ((5, 3, 2), Vec3::new(1.0, 0.7, 0.3)),
        ((6, 6, 6), Vec3::splat(2.0)),
    ] {
        let m = tet_box(nx, ny, nz, size).unwrap();
        let (nx, ny, nz) = (nx as usize, ny as usize, nz as usize);
        assert_eq!(m.vertex_count(), (nx + 1) * (ny + 1) * (nz + 1));
        assert_eq!(m.tet_count(), 6 * nx * ny * nz);
        assert!(diagnose_tets(m.positions(), m.tets()).is_empty());
        // The tetrahedra tile the box spanned by the f32 corner coordinates exactly, so the
        // volume is the product of its f32 extents up to f64 rounding.
        let (lo, hi) = m.positions().iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let extent = hi.as_dvec3() - lo.as_dvec3();
        let exact = extent.x * extent.y * extent.z;
        assert!(
            (m.volume() - exact).abs() <= 1e-13 * exact,
            "{} vs {exact}",
            m.volume()
        );
        let cell = exact / (nx * ny * nz) as f64;
        for v in m.tet_volumes() {
            assert!(
                (v - cell / 6.0).abs() <= 1e-6 * cell,
                "{v} vs {}",
                cell / 6.0
            );
        }
    }
    // Dyadic lattice: exact.
    assert_eq!(
        tet_box(4, 3, 2, Vec3::new(2.0, 1.5, 3.0)).unwrap().volume(),
        9.0
    );
}

#[test]
fn boundary_surface_is_closed_genus_zero_and_encloses_the_tet_volume() {
    let (nx, ny, nz) = (3, 2, 4);
    let m = tet_box(nx, ny, nz, Vec3::new(1.5, 1.0, 2.0)).unwrap();
    let s = m.boundary_surface().unwrap();
    assert_eq!(s.triangles(), m.boundary_faces());
    assert_eq!(
        s.triangle_count(),
        4 * (nx * ny + ny * nz + nz * nx) as usize
    );
    assert!(s.is_closed());
    assert_eq!(s.topology().component_count(), 1);
    // Interior vertices are unreferenced by the surface; χ = 2 over the vertices it uses.
    let interior = ((nx - 1) * (ny - 1) * (nz - 1)) as usize;
    assert_eq!(s.unreferenced_vertices().len(), interior);
    assert_eq!(s.euler_characteristic() - interior as i64, 2);
    let (surface, solid) = (s.signed_volume().unwrap(), m.volume());
    assert!(
        (surface - solid).abs() <= 1e-13 * solid,
        "{surface} vs {solid}"
    );
    assert!((s.area() - 2.0 * (1.5 + 1.5 * 2.0 + 2.0)).abs() < 1e-12);
}

#[test]
fn neighbours_are_symmetric_and_share_the_face_opposite_the_vertex() {
    let m = tet_box(3, 3, 2, Vec3::ONE).unwrap();
    let face = |t: u32, f: usize| sorted(TET_FACES[f].map(|i| m.tets()[t as usize][i]));
    let mut boundary = 0;
    for (t, row) in m.neighbours().iter().enumerate() {
        let t = t as u32;
        for (f, &other) in row.iter().enumerate() {
            if other == NO_TET {
                boundary += 1;
                continue;
            }
            let back = m.neighbours()[other as usize]
                .iter()
                .position(|&x| x == t)
                .expect("adjacency is symmetric");
            assert_eq!(face(t, f), face(other, back));
            // The vertex opposite the shared face is not on it.
            assert!(!face(t, f).contains(&m.tets()[t as usize][f]));
        }
    }
    assert_eq!(boundary, m.boundary_faces().len());
}

#[test]
fn valid_data_have_no_defects_and_empty_is_an_error() {
    let (p, t) = two_cells();
    assert!(diagnose_tets(&p, &t).is_empty());
    assert_eq!(
        diagnose_tets(&[], &[]),
        vec![MeshError::Empty {
            vertices: 0,
            elements: 0
        }]
    );
    assert!(matches!(
        TetMesh::new(p, vec![]),
        Err(MeshError::Empty { elements: 0, .. })
    ));
}

#[test]
fn non_finite_coordinate_names_the_vertex() {
    let (mut p, t) = two_cells();
    p[4].y = f32::NAN;
    p[9].z = f32::INFINITY;
    let d = diagnose_tets(&p, &t);
    assert!(
        matches!(d[0], MeshError::NonFiniteCoordinate { vertex: 4, .. }),
        "{d:?}"
    );
    assert!(
        matches!(d[1], MeshError::NonFiniteCoordinate { vertex: 9, .. }),
        "{d:?}"
    );
    assert_eq!(
        d.len(),
        2,
        "no volume defects reported for the NaN tets: {d:?}"
    );
    assert!(matches!(
        TetMesh::new(p, t),
        Err(MeshError::NonFiniteCoordinate { vertex: 4, .. })
    ));
}

#[test]
fn index_out_of_range_names_the_tet() {
    let (p, mut t) = two_cells();
    t[5][2] = 999;
    let d = diagnose_tets(&p, &t);
    assert_eq!(
        d[0],
        MeshError::TetIndexOutOfRange {
            tet: 5,
            index: 999,
            vertex_count: 12
        }
    );
    // The vertex it no longer uses may become unreferenced; nothing else is reported.
    assert!(d[1..].iter().all(MeshError::is_warning), "{d:?}");
}

#[test]
fn inverted_and_flat_tets_are_named() {
    let (mut p, mut t) = two_cells();
    t[3].swap(1, 2);
    let d = diagnose_tets(&p, &t);
    match &d[..] {
        [MeshError::InvertedTet {
            tet: 3,
            vertices,
            volume,
        }] => {
            assert_eq!(*vertices, t[3]);
            assert!((volume + 1.0 / 6.0).abs() < 1e-12, "{volume}");
        }
        _ => panic!("{d:?}"),
    }
    // Flatten cell 1 by moving its x = 1 face onto x = 0: every tet of cell 1 becomes flat.
    t[3].swap(1, 2);
    for v in p.iter_mut() {
        if v.x == 1.0 {
            v.x = 0.0;
        }
    }
    let d = diagnose_tets(&p, &t);
    let flat: Vec<u32> = d
        .iter()
        .filter_map(|e| match e {
            MeshError::InvertedTet { tet, .. } => Some(*tet),
            _ => None,
        })
        .collect();
    assert_eq!(flat, (6..12).collect::<Vec<u32>>(), "{d:?}");
}

#[test]
fn duplicate_tet_names_both() {
    let (p, mut t) = two_cells();
    let [a, b, c, d] = t[2];
    t.push([b, c, a, d]); // an even permutation: same orientation, same vertices
    let defects = diagnose_tets(&p, &t);
    assert_eq!(
        defects,
        vec![MeshError::DuplicateTet {
            tet: 12,
            first: 2,
            vertices: [b, c, a, d]
        }]
    );
}

#[test]
fn face_of_three_tets_is_non_manifold() {
    let (mut p, mut t) = two_cells();
    // Tets 0 and 3 of cell 0 (axis orders xyz and xzy) share an interior face; put a third
    // tet on it.
    let shared = (0..4)
        .flat_map(|f| (0..4).map(move |g| (f, g)))
        .map(|(f, g)| {
            (
                sorted(TET_FACES[f].map(|i| t[0][i])),
                sorted(TET_FACES[g].map(|i| t[3][i])),
            )
        })
        .find(|(x, y)| x == y)
        .map(|(x, _)| x)
        .expect("tets 0 and 3 share a face");
    let apex = p.len() as u32;
    p.push(Vec3::new(0.3, -2.0, 0.6));
    let mut extra = [shared[0], shared[1], shared[2], apex];
    let orient = |q: [u32; 4]| {
        let [a, b, c, d] = q.map(|i| p[i as usize].as_dvec3());
        (b - a).cross(c - a).dot(d - a)
    };
    if orient(extra) < 0.0 {
        extra.swap(0, 1);
    }
    t.push(extra);
    let d = diagnose_tets(&p, &t);
    assert_eq!(
        d,
        vec![MeshError::NonManifoldFace {
            face: shared,
            tets: vec![0, 3, 12]
        }]
    );
}

#[test]
fn unreferenced_vertex_is_only_a_warning() {
    let (mut p, t) = two_cells();
    p.push(Vec3::new(5.0, 5.0, 5.0));
    let d = diagnose_tets(&p, &t);
    assert_eq!(d, vec![MeshError::UnreferencedVertex { vertex: 12 }]);
    let m = TetMesh::new(p, t).unwrap();
    assert_eq!(m.vertex_count(), 13);
    assert!((m.volume() - 2.0).abs() < 1e-12);
}

#[test]
fn tets_touching_along_an_edge_only_have_no_valid_boundary_surface() {
    let p = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(0.0, -1.0, 0.0),
    ];
    // Two tets sharing only the edge 0–3.
    let t = vec![[0, 1, 2, 3], [0, 4, 5, 3]];
    let m = TetMesh::new(p, t).unwrap();
    assert_eq!(m.neighbours(), &[[NO_TET; 4]; 2]);
    assert!(matches!(
        m.boundary_surface(),
        Err(MeshError::NonManifoldEdge { edge: [0, 3], .. })
    ));
}
