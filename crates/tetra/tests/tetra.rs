//! The public API of tissue-tetra: generated surfaces, the bunny and liver of `fixtures/`, and every
//! error a user can cause.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use glam::Vec3;
use tissue_mesh::{subdivided_cube, uv_sphere, TriMesh};
use tissue_tetra::{
    tetrahedralize, tetrahedralize_triangles, QualityReport, TetCount, TetraError, TetraOptions,
    Tetrahedralization,
};

/// A file of the repository's `fixtures/` folder (the real meshes ship there).
fn fixture(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures")).join(name)
}

/// The checks every result must pass: surface vertices first and unchanged, every tet positive,
/// volume within `tolerance` of the surface's, the report consistent with the mesh.
fn check(surface: &TriMesh, result: &Tetrahedralization, tolerance: f64) {
    let mesh = &result.mesh;
    let n = surface.vertex_count();
    assert!(mesh.vertex_count() >= n);
    assert_eq!(
        &mesh.positions()[..n],
        surface.positions(),
        "surface vertices first, in order"
    );
    for (t, tet) in mesh.tets().iter().enumerate() {
        let [a, b, c, d] = tet.map(|i| mesh.positions()[i as usize].as_dvec3());
        assert!(
            (b - a).cross(c - a).dot(d - a) > 0.0,
            "tet {t} {tet:?} not positive"
        );
    }
    // Re-validation by the mesh crate (flatness, duplicates, faces on > 2 tets).
    let rebuilt = tissue_mesh::TetMesh::new(mesh.positions().to_vec(), mesh.tets().to_vec());
    assert!(rebuilt.is_ok(), "{rebuilt:?}");
    let enclosed = surface.signed_volume().unwrap();
    let ratio = mesh.volume() / enclosed;
    assert!(
        (ratio - 1.0).abs() <= tolerance,
        "volume {} vs surface {enclosed} (ratio {ratio})",
        mesh.volume()
    );
    let r = &result.report;
    assert_eq!(r.tets, mesh.tet_count());
    assert_eq!(r.nodes, mesh.vertex_count());
    assert_eq!(r.surface_nodes, n);
    assert_eq!(r.interior_nodes, mesh.vertex_count() - n);
    assert_eq!(r.radius_ratio_histogram.iter().sum::<usize>(), r.tets);
    assert!(r.min_volume > 0.0);
    assert!((r.volume_ratio - ratio).abs() < 1e-12);
    assert!(r.min_dihedral_deg > 0.0 && r.min_dihedral_deg <= 70.53);
    assert!(r.max_dihedral_deg >= 70.52 && r.max_dihedral_deg < 180.0);
    assert!(r.surface_triangles_recovered <= r.surface_triangles);
    // Interior nodes are really inside: strictly off the surface's vertices.
    assert!(mesh.positions()[n..]
        .iter()
        .all(|p| p.is_finite() && !surface.positions().contains(p)));
}

#[test]
fn cube_volume_is_exact_and_surface_comes_first() {
    let cube = subdivided_cube(8, 2.0).unwrap(); // 386 vertices, 768 triangles, 8 cm³
    let result = tetrahedralize(&cube, &TetraOptions::default()).unwrap();
    check(&cube, &result, 0.02);
    // A convex polyhedron is filled exactly (the Delaunay tets tile its hull).
    assert!(
        (result.mesh.volume() - 8.0).abs() < 1e-4,
        "{}",
        result.report
    );
    assert!(result.report.interior_nodes > 0);
    // The cube's faces are planar grids of cospherical points: ties are broken, no flat tets.
    assert!(result.report.min_dihedral_deg > 1.0, "{}", result.report);
    let boundary = result.mesh.boundary_surface().unwrap();
    assert!(boundary.is_closed());
}

#[test]
fn sphere_fills_its_mesh_volume() {
    let sphere = uv_sphere(40, 20, 1.5).unwrap();
    let result = tetrahedralize(&sphere, &TetraOptions::default()).unwrap();
    check(&sphere, &result, 0.02);
    let r = &result.report;
    assert!(
        r.surface_triangles_recovered * 100 >= r.surface_triangles * 95,
        "{r}"
    );
    assert!(r.boundary_faces >= r.surface_triangles_recovered);
    // The mesh volume is the polyhedron's, below the true ball's 4/3 π r³.
    assert!(result.mesh.volume() < 4.0 / 3.0 * std::f64::consts::PI * 1.5f64.powi(3));
}

#[test]
fn spacing_controls_the_size_and_no_interior_option_works() {
    let sphere = uv_sphere(24, 12, 1.0).unwrap();
    let coarse = tetrahedralize(
        &sphere,
        &TetraOptions {
            spacing: Some(0.4),
            ..TetraOptions::default()
        },
    )
    .unwrap();
    let fine = tetrahedralize(
        &sphere,
        &TetraOptions {
            spacing: Some(0.1),
            ..TetraOptions::default()
        },
    )
    .unwrap();
    assert!(fine.report.interior_nodes > 4 * coarse.report.interior_nodes.max(1));
    assert_eq!(fine.spacing, 0.1);
    check(&sphere, &coarse, 0.02);
    check(&sphere, &fine, 0.02);
    let bare = tetrahedralize(
        &sphere,
        &TetraOptions {
            interior_points: false,
            ..TetraOptions::default()
        },
    )
    .unwrap();
    assert_eq!(bare.report.interior_nodes, 0);
    check(&sphere, &bare, 0.02);
}

#[test]
fn tiny_huge_and_two_part_surfaces() {
    for radius in [1e-3f32, 1e3] {
        let s = uv_sphere(16, 8, radius).unwrap();
        let result = tetrahedralize(&s, &TetraOptions::default()).unwrap();
        check(&s, &result, 0.02);
    }
    // Two disjoint spheres in one mesh.
    let a = uv_sphere(16, 8, 1.0).unwrap();
    let (mut p, mut t) = a.clone().into_parts();
    let n = p.len() as u32;
    p.extend(a.positions().iter().map(|&x| x + Vec3::new(3.0, 0.0, 0.0)));
    t.extend(a.triangles().iter().map(|tri| tri.map(|v| v + n)));
    let two = TriMesh::new(p, t).unwrap();
    let result = tetrahedralize(&two, &TetraOptions::default()).unwrap();
    check(&two, &result, 0.02);
}

#[test]
fn same_input_same_mesh() {
    let s = uv_sphere(20, 10, 1.0).unwrap();
    let a = tetrahedralize(&s, &TetraOptions::default()).unwrap();
    let b = tetrahedralize(&s, &TetraOptions::default()).unwrap();
    assert_eq!(a, b);
}

#[test]
fn report_displays_its_figures() {
    let cube = subdivided_cube(3, 1.0).unwrap();
    let r = tetrahedralize(&cube, &TetraOptions::default())
        .unwrap()
        .report;
    let text = r.to_string();
    for needle in [
        format!("{} tets", r.tets),
        format!("{} surface", r.surface_nodes),
        "dihedral".to_string(),
        "radius ratio".to_string(),
        "recovered".to_string(),
    ] {
        assert!(text.contains(&needle), "{needle:?} missing from:\n{text}");
    }
}

#[test]
fn bunny_gives_about_40k_tets_that_follow_its_surface() {
    let path = fixture("bunny_10k.obj");
    let bunny = tissue_meshio::read_surface(&path).unwrap();
    assert_eq!(bunny.triangle_count(), 10_000);
    let start = std::time::Instant::now();
    let result = tetrahedralize(&bunny, &TetraOptions::default()).unwrap();
    let seconds = start.elapsed().as_secs_f64();
    eprintln!("bunny ({seconds:.3} s):\n{}", result.report);
    check(&bunny, &result, 0.02);
    let r = &result.report;
    assert!((36_000..=44_000).contains(&r.tets), "{r}");
    // The boundary faces cover the surface: nearly every triangle is one of them.
    assert!(
        r.surface_triangles_recovered * 100 >= r.surface_triangles * 95,
        "{r}"
    );
    assert!(r.min_dihedral_deg > 0.1, "{r}");
    // The loaded-and-written mesh reads back through tissue-meshio unchanged.
    let out = std::env::temp_dir().join(format!("tetra-bunny-{}.vtk", std::process::id()));
    tissue_meshio::write_vtk_tets(&out, &result.mesh, &[]).unwrap();
    let back = tissue_meshio::read_tets(&out).unwrap();
    std::fs::remove_file(&out).ok();
    assert_eq!(back.tets(), result.mesh.tets());
    assert_eq!(back.positions(), result.mesh.positions());
}

#[test]
fn liver_is_closed_and_tetrahedralizes() {
    let path = fixture("liver_sofa.obj");
    let liver = tissue_meshio::read_surface(&path).unwrap();
    assert!(liver.is_closed());
    let result = tetrahedralize(&liver, &TetraOptions::default()).unwrap();
    eprintln!("liver:\n{}", result.report);
    check(&liver, &result, 0.02);
    let r = &result.report;
    assert!(
        r.surface_triangles_recovered * 100 >= r.surface_triangles * 85,
        "{r}"
    );
}

#[test]
fn tetgen_armadillo_measures_as_a_constrained_mesh() {
    // A mesh by another tool (TetGen, the PositionBasedDynamics demos' armadillo): measured on
    // its own, its boundary faces are its surface, all recovered, and enclose its volume.
    let data = tissue_meshio::read_tetgen(fixture("armadillo_4k")).unwrap();
    let tetgen = tissue_mesh::TetMesh::new(data.positions, data.tets).unwrap();
    let own = QualityReport::of_mesh(&tetgen);
    eprintln!("TetGen armadillo:\n{own}");
    assert_eq!(own.tets, 3_717);
    assert_eq!(own.nodes, 1_180);
    assert_eq!(own.boundary_faces, 2_102);
    assert_eq!(own.surface_triangles_recovered, own.boundary_faces);
    assert!((own.volume_ratio - 1.0).abs() < 1e-9);
}

// --- errors ---------------------------------------------------------------------------------

/// A tetrahedron's surface (outward), shifted by `at`, with vertex numbers from `first`.
fn tet_surface(at: Vec3, first: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = vec![at, at + Vec3::X, at + Vec3::Y, at + Vec3::Z];
    let t = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
        .map(|f: [u32; 3]| f.map(|v| v + first))
        .to_vec();
    (p, t)
}

#[test]
fn open_surface_names_a_boundary_edge() {
    let cube = subdivided_cube(2, 1.0).unwrap();
    let (p, mut t) = cube.into_parts();
    let removed = t.remove(5);
    let open = TriMesh::new(p, t).unwrap();
    match tetrahedralize(&open, &TetraOptions::default()) {
        Err(TetraError::OpenSurface {
            edge,
            triangle,
            boundary_edges,
            loops,
        }) => {
            assert_eq!((boundary_edges, loops), (3, 1));
            // The edge is a side of the removed triangle, and of the triangle named.
            let sides = |tri: [u32; 3]| {
                [0, 1, 2].map(|i| {
                    let (a, b) = (tri[i], tri[(i + 1) % 3]);
                    [a.min(b), a.max(b)]
                })
            };
            assert!(sides(removed).contains(&edge));
            assert!(sides(open.triangles()[triangle as usize]).contains(&edge));
            let msg = TetraError::OpenSurface {
                edge,
                triangle,
                boundary_edges,
                loops,
            }
            .to_string();
            assert!(msg.contains(&format!("triangle {triangle}")), "{msg}");
        }
        other => panic!("expected OpenSurface, got {other:?}"),
    }
}

#[test]
fn non_manifold_edge_and_vertex_are_named() {
    // Two tetrahedra glued along edge 0–1 (raw data: a TriMesh cannot hold this).
    let (mut p, mut t) = tet_surface(Vec3::ZERO, 0);
    p.extend([Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 0.0, -1.0)]);
    // Second tet on vertices 0, 1, 4, 5, outward.
    let second = [[0u32, 1, 4], [0, 4, 5], [0, 5, 1], [1, 5, 4]];
    let v = [Vec3::ZERO, Vec3::X, p[4], p[5]];
    let oriented = |f: [u32; 3]| {
        let q = f.map(|i| {
            v[match i {
                0 => 0,
                1 => 1,
                4 => 2,
                _ => 3,
            }]
        });
        let centre = (v[0] + v[1] + v[2] + v[3]) / 4.0;
        let n = (q[1] - q[0]).cross(q[2] - q[0]);
        if n.dot(q[0] - centre) > 0.0 {
            f
        } else {
            [f[0], f[2], f[1]]
        }
    };
    t.extend(second.map(oriented));
    match tetrahedralize_triangles(&p, &t, &TetraOptions::default()) {
        Err(TetraError::NonManifoldEdge { edge, triangles }) => {
            assert_eq!(edge, [0, 1]);
            assert_eq!(triangles.len(), 4);
        }
        other => panic!("expected NonManifoldEdge, got {other:?}"),
    }

    // Two tetrahedra touching at one vertex (vertex 3 = the first's apex = the second's base).
    let (mut p, mut t) = tet_surface(Vec3::ZERO, 0);
    let (q, u) = tet_surface(Vec3::Z, 4);
    p.extend(q);
    t.extend(u.iter().map(|f| f.map(|v| if v == 4 { 3 } else { v })));
    p[4] = Vec3::splat(99.0); // now unreferenced
    match tetrahedralize_triangles(&p, &t, &TetraOptions::default()) {
        Err(TetraError::NonManifoldVertex {
            vertex,
            triangles,
            fans,
        }) => {
            assert_eq!((vertex, triangles, fans), (3, 6, 2));
        }
        other => panic!("expected NonManifoldVertex, got {other:?}"),
    }
}

#[test]
fn coincident_inside_out_flat_and_tiny_inputs_are_refused() {
    // Two tetrahedra whose corners meet at the same position but are different vertices.
    let (mut p, mut t) = tet_surface(Vec3::ZERO, 0);
    let (q, u) = tet_surface(Vec3::Z, 4);
    p.extend(q);
    t.extend(u);
    match tetrahedralize_triangles(&p, &t, &TetraOptions::default()) {
        Err(TetraError::CoincidentVertices {
            first,
            second,
            position,
        }) => {
            assert_eq!((first, second, position), (3, 4, [0.0, 0.0, 1.0]));
        }
        other => panic!("expected CoincidentVertices, got {other:?}"),
    }

    let cube = subdivided_cube(2, 1.0).unwrap();
    let (p, t) = cube.into_parts();
    let flipped: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
    assert!(matches!(
        tetrahedralize_triangles(&p, &flipped, &TetraOptions::default()),
        Err(TetraError::InsideOut { volume }) if (volume + 1.0).abs() < 1e-9
    ));

    let p3 = [Vec3::ZERO, Vec3::X, Vec3::Y];
    assert!(matches!(
        tetrahedralize_triangles(&p3, &[[0, 1, 2], [0, 2, 1]], &TetraOptions::default()),
        Err(TetraError::TooFewPoints { vertices: 3 })
    ));

    let (mut p, t) = tet_surface(Vec3::ZERO, 0);
    p[3] = Vec3::new(0.5, 0.5, 0.0); // on the base's plane: every triangle flat or coplanar
    let e = tetrahedralize_triangles(&p, &t, &TetraOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            TetraError::DegenerateTriangle { .. } | TetraError::NoVolume { .. }
        ),
        "{e:?}"
    );

    let (p, mut t) = tet_surface(Vec3::ZERO, 0);
    t[1] = [0, 1, 7];
    assert!(matches!(
        tetrahedralize_triangles(&p, &t, &TetraOptions::default()),
        Err(TetraError::InvalidSurface(_))
    ));
}

#[test]
fn bad_options_are_refused() {
    let s = uv_sphere(8, 4, 1.0).unwrap();
    for opts in [
        TetraOptions {
            spacing: Some(0.0),
            ..TetraOptions::default()
        },
        TetraOptions {
            spacing: Some(f32::NAN),
            ..TetraOptions::default()
        },
        TetraOptions {
            spacing_factor: -1.0,
            ..TetraOptions::default()
        },
        TetraOptions {
            clearance: 5.0,
            ..TetraOptions::default()
        },
        TetraOptions {
            sliver_radius_ratio: 1.0,
            ..TetraOptions::default()
        },
        TetraOptions {
            degenerate_radius_ratio: -0.1,
            ..TetraOptions::default()
        },
        // 10⁹ lattice points: refused up front rather than exhausting memory.
        TetraOptions {
            spacing: Some(2e-3),
            ..TetraOptions::default()
        },
    ] {
        let e = tetrahedralize(&s, &opts).unwrap_err();
        assert!(matches!(e, TetraError::InvalidOption { .. }), "{e:?}");
        assert!(e.to_string().starts_with("invalid option"));
    }
}

// --- the estimate and the limit ---------------------------------------------------------------

/// Each triangle split into four at its edges' midpoints (tissue-testscans): the same shape with
/// four times the triangles and half the edge length (a refined upload).
fn refined(s: &TriMesh) -> TriMesh {
    tissue_testscans::subdivide_midpoint(s).unwrap()
}

/// `s` stretched by `k` along the axes.
fn stretched(s: &TriMesh, k: Vec3) -> TriMesh {
    TriMesh::new(
        s.positions().iter().map(|&p| p * k).collect(),
        s.triangles().to_vec(),
    )
    .unwrap()
}

/// A tetrahedron whose opposite edges (on the x axis, and on a skew line at z = 1) are split
/// into `n` segments each, its faces fanned: all its vertices lie on two skew lines, whose
/// Delaunay tetrahedralisation has n² tetrahedra while the estimate (a thin volume, 2n + 2
/// vertices) expects about 6n.
fn two_skew_lines(n: u32) -> TriMesh {
    let along = |i: u32| -1.0 + 2.0 * i as f32 / n as f32;
    let mut p: Vec<Vec3> = (0..=n).map(|i| Vec3::new(along(i), 0.0, 0.0)).collect();
    p.extend((0..=n).map(|i| Vec3::new(0.0, along(i), 1.0)));
    let (ab, cd) = (|i: u32| i, |i: u32| n + 1 + i);
    let (a, b, c, d) = (ab(0), ab(n), cd(0), cd(n));
    let mut t = Vec::new();
    for i in 0..n {
        t.push([c, ab(i), ab(i + 1)]);
        t.push([d, ab(i + 1), ab(i)]);
        t.push([a, cd(i), cd(i + 1)]);
        t.push([b, cd(i + 1), cd(i)]);
    }
    let s = TriMesh::new(p, t).unwrap();
    assert!(s.signed_volume().unwrap() > 0.0);
    s
}

#[test]
fn the_estimate_is_within_0_8_to_1_25_of_the_mesher_on_real_and_refined_surfaces() {
    let read = |name: &str| tissue_meshio::read_surface(fixture(name)).unwrap();
    let bunny = read("bunny_10k.obj");
    let liver = read("liver_sofa.obj");
    let armadillo = {
        let d = tissue_meshio::read_tetgen(fixture("armadillo_4k")).unwrap();
        let tets = tissue_mesh::TetMesh::new(d.positions, d.tets).unwrap();
        tets.boundary_surface().unwrap()
    };
    let cube = subdivided_cube(20, 1.0).unwrap();
    let default = TetraOptions::default();
    let fine = TetraOptions {
        spacing: Some(0.1),
        ..TetraOptions::default()
    };
    let cases = [
        ("bunny 10k", refined(&bunny), default), // 40 000 triangles
        ("bunny", bunny, default),
        ("liver", liver.clone(), default),
        ("liver refined", refined(&liver), default),
        ("armadillo", armadillo.clone(), default),
        ("armadillo refined", refined(&armadillo), default),
        ("MakeHuman body", read("makehuman_body_closed.obj"), default),
        ("sphere", uv_sphere(64, 32, 1.0).unwrap(), default),
        ("sphere, spacing 0.1", uv_sphere(24, 12, 1.0).unwrap(), fine),
        ("cube", subdivided_cube(30, 1.0).unwrap(), default),
        (
            "flat box",
            stretched(&cube, Vec3::new(1.0, 0.1, 1.0)),
            default,
        ),
        (
            "long box",
            stretched(&cube, Vec3::new(10.0, 1.0, 1.0)),
            default,
        ),
    ];
    for (name, surface, options) in cases {
        let estimate = tissue_tetra::estimate_tets(&surface, &options).unwrap();
        let made = tetrahedralize(&surface, &options).unwrap();
        let ratio = estimate.tets as f64 / made.report.tets as f64;
        eprintln!(
            "{name}: {} triangles, {} tets estimated, {} made ({ratio:.3}×); interior {} / {}",
            surface.triangle_count(),
            estimate.tets,
            made.report.tets,
            estimate.interior_points,
            made.report.interior_nodes
        );
        assert!((0.8..=1.25).contains(&ratio), "{name}: {ratio}");
        assert_eq!(
            estimate.spacing, made.spacing,
            "{name}: the mesher's spacing"
        );
        assert_eq!(estimate.triangles, surface.triangle_count());
    }
}

#[test]
fn the_decimation_hint_is_the_same_for_the_same_shape_at_any_resolution() {
    let bunny = tissue_meshio::read_surface(fixture("bunny_10k.obj")).unwrap();
    let finer = refined(&bunny);
    let options = TetraOptions::default();
    let coarse = tissue_tetra::estimate_tets(&bunny, &options).unwrap();
    let fine = tissue_tetra::estimate_tets(&finer, &options).unwrap();
    // Within the limit already: the triangles it has.
    assert_eq!(coarse.triangles_for(150_000), Some(10_000));
    // The bunny refined to 40 000 triangles (about 290 000 tets) fits 150 000 at about 25 000
    // triangles, whichever resolution it starts from; and 40 000 tets at about the bunny's own
    // 10 000.
    let hint = fine.triangles_for(150_000).unwrap();
    assert!((20_000..=30_000).contains(&hint), "{hint}");
    let from_coarse = coarse.triangles_for(40_000).unwrap();
    let from_fine = fine.triangles_for(40_000).unwrap();
    for n in [from_coarse, from_fine] {
        assert!((9_000..=11_000).contains(&n), "{from_coarse} / {from_fine}");
    }
}

#[test]
fn max_tets_refuses_by_the_estimate_before_meshing_by_the_delaunay_size_and_by_the_count() {
    let bunny = tissue_meshio::read_surface(fixture("bunny_10k.obj")).unwrap();
    let limited = |max: usize| TetraOptions {
        max_tets: Some(max),
        ..TetraOptions::default()
    };
    let unlimited = tetrahedralize(&bunny, &TetraOptions::default()).unwrap();
    // Within the limit: the same mesh as without one.
    assert_eq!(tetrahedralize(&bunny, &limited(45_000)).unwrap(), unlimited);

    // Estimated at 39 176: refused before meshing, with the triangles to decimate to.
    let e = tetrahedralize(&bunny, &limited(10_000)).unwrap_err();
    match &e {
        TetraError::TooManyTets {
            tets,
            max: 10_000,
            when: TetCount::Estimated,
            triangles: 10_000,
            decimate_to: Some(n),
        } => {
            assert!((35_000..45_000).contains(tets), "{e}");
            assert!((2_000..10_000).contains(n), "{e}");
        }
        other => panic!("{other:?}"),
    }
    let text = e.to_string();
    assert!(
        text.contains("estimated before meshing") && text.contains("decimate the surface to about"),
        "{text}"
    );

    // Estimated under 39 500, made 39 706: refused by the count.
    assert!(unlimited.report.tets > 39_500);
    let e = tetrahedralize(&bunny, &limited(39_500)).unwrap_err();
    assert!(
        matches!(
            e,
            TetraError::TooManyTets {
                when: TetCount::Made,
                ..
            }
        ),
        "{e:?}"
    );

    // Points on two skew lines fool the estimate (n² tets for about 6n expected); the Delaunay
    // size stops them, however high the limit.
    let skew = two_skew_lines(60);
    let estimate = tissue_tetra::estimate_tets(&skew, &TetraOptions::default()).unwrap();
    let made = tetrahedralize(&skew, &TetraOptions::default()).unwrap();
    assert!(
        made.report.tets > 8 * estimate.tets,
        "{made:?} {estimate:?}"
    );
    let e = tetrahedralize(&skew, &limited(150_000)).unwrap_err();
    assert!(
        matches!(
            e,
            TetraError::TooManyTets {
                when: TetCount::Delaunay,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("badly spread"), "{e}");

    // The estimate checks the surface as the mesher does.
    let (p, t) = tet_surface(Vec3::ZERO, 0);
    let open = TriMesh::new(p, t[..3].to_vec()).unwrap();
    assert!(matches!(
        tissue_tetra::estimate_tets(&open, &TetraOptions::default()),
        Err(TetraError::OpenSurface { .. })
    ));
    assert!(matches!(
        tetrahedralize(&bunny, &limited(0)),
        Err(TetraError::InvalidOption { .. })
    ));
}
