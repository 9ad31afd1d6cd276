//! The public API of tissue-meshio: round trips, format details, error locations, atomic writes,
//! and the real third-party meshes shipped in `fixtures/`.
#![allow(clippy::panic)]
// Test code: a failed unwrap is a failed test; the skip notice goes to stderr.
#![allow(clippy::unwrap_used, clippy::print_stderr)]

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

use glam::Vec3;
use tissue_mesh::{TetMesh, TriMesh};
use tissue_meshio::{
    parse_ply, parse_stl, parse_surface_data, parse_tetgen, parse_vtk, read_obj, read_stl,
    read_surface, read_surface_data, read_tet_data, read_tetgen, read_tets, read_vtk, write_obj,
    write_stl, write_surface, write_vtk, write_vtk_tets, FieldValues, MeshIoError, PointValues,
    SurfaceData, TetData, VertexField, VtkMesh,
};

// ---------------------------------------------------------------- generated meshes and helpers

/// A closed octahedron with coordinates that are not short decimals.
fn octahedron() -> TriMesh {
    let offset = Vec3::new(1.0 / 3.0, 1e-7, 12.345);
    let positions = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]
        .map(|p| p * 0.1 + offset)
        .to_vec();
    let triangles = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    TriMesh::new(positions, triangles).unwrap()
}

/// An open `nx` × `ny` grid of quads split in two, gently curved.
fn grid(nx: u32, ny: u32) -> TriMesh {
    let mut positions = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (i as f32 * 0.1, j as f32 / 3.0);
            positions.push(Vec3::new(x, y, 1e-7 * (i * j) as f32 + 0.01 * x * x));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let a = j * nx + i;
            let (b, c, d) = (a + 1, a + nx + 1, a + nx);
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh::new(positions, triangles).unwrap()
}

/// The unit cube as 8 vertices and 12 outward triangles.
fn cube() -> TriMesh {
    let positions = (0..8)
        .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
        .collect();
    let triangles = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    TriMesh::new(positions, triangles).unwrap()
}

/// Two positive tetrahedra sharing a face.
fn two_tets() -> TetData {
    TetData {
        positions: vec![
            Vec3::ZERO,
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(0.0, 1.0 / 3.0, 0.0),
            Vec3::new(0.0, 0.0, 1e-7 + 0.5),
            Vec3::splat(0.7),
        ],
        tets: vec![[0, 1, 2, 3], [1, 2, 3, 4]],
    }
}

fn meshes() -> Vec<(&'static str, TriMesh)> {
    vec![
        ("octahedron", octahedron()),
        ("grid", grid(7, 5)),
        ("cube", cube()),
    ]
}

/// A fresh, empty folder for one test.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tissue-meshio-{}-{test}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn bits(positions: &[Vec3]) -> Vec<[u32; 3]> {
    positions
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// Triangles as ordered triples of corner positions (bits), independent of vertex numbering.
fn corner_set(positions: &[Vec3], triangles: &[[u32; 3]]) -> BTreeSet<[[u32; 3]; 3]> {
    triangles
        .iter()
        .map(|t| t.map(|i| positions[i as usize].to_array().map(f32::to_bits)))
        .collect()
}

fn file_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn parse_line(e: &MeshIoError) -> usize {
    match e {
        MeshIoError::Parse { line, .. } => *line,
        other => panic!("expected a parse error, got {other:?}: {other}"),
    }
}

// ------------------------------------------------------------------------------- round trips

#[test]
fn obj_ply_vtk_round_trip_bit_exact() {
    let dir = scratch("round-trip");
    for (name, mesh) in meshes() {
        for ext in ["obj", "ply", "vtk", "OBJ", "Ply"] {
            let path = dir.join(format!("{name}.{ext}"));
            write_surface(&path, &mesh).unwrap();
            let back = read_surface_data(&path).unwrap();
            assert_eq!(back.triangles, mesh.triangles(), "{name}.{ext}");
            assert_eq!(
                bits(&back.positions),
                bits(mesh.positions()),
                "{name}.{ext}"
            );
            assert_eq!(read_surface(&path).unwrap(), mesh, "{name}.{ext}");
        }
    }
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn stl_round_trip_same_triangles_after_welding() {
    let dir = scratch("stl-round-trip");
    for (name, mesh) in meshes() {
        let path = dir.join(format!("{name}.stl"));
        write_stl(&path, &mesh).unwrap();
        assert_eq!(
            fs::metadata(&path).unwrap().len(),
            84 + 50 * mesh.triangle_count() as u64
        );
        let back = read_stl(&path).unwrap();
        assert_eq!(back.positions.len(), mesh.vertex_count(), "{name}");
        assert_eq!(
            corner_set(&back.positions, &back.triangles),
            corner_set(mesh.positions(), mesh.triangles()),
            "{name}"
        );
        // Closed stays closed: welding restores the shared edges.
        let welded = read_surface(&path).unwrap();
        assert_eq!(welded.is_closed(), mesh.is_closed(), "{name}");
    }
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vtk_fields_round_trip_bit_exact() {
    let dir = scratch("vtk-fields");
    let mesh = grid(6, 4);
    let n = mesh.vertex_count();
    let stress: Vec<f32> = (0..n).map(|i| i as f32 / 7.0 - 1e-9).collect();
    let displacement: Vec<Vec3> = mesh.positions().iter().map(|p| *p * 1e-3 + 0.1).collect();
    let fields = [
        VertexField {
            name: "stress",
            values: FieldValues::Scalars(&stress),
        },
        VertexField {
            name: "displacement_cm",
            values: FieldValues::Vectors(&displacement),
        },
    ];
    let path = dir.join("fields.vtk");
    write_vtk(&path, &mesh, &fields).unwrap();
    let back = read_vtk(&path).unwrap();
    let VtkMesh::Surface(surface) = &back.mesh else {
        panic!("{:?}", back.mesh)
    };
    assert_eq!(surface.triangles, mesh.triangles());
    assert_eq!(back.fields.len(), 2);
    assert_eq!(back.fields[0].name, "stress");
    let PointValues::Scalars(s) = &back.fields[0].values else {
        panic!()
    };
    assert_eq!(
        s.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
        stress.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    );
    let PointValues::Vectors(v) = &back.fields[1].values else {
        panic!()
    };
    assert_eq!(bits(v), bits(&displacement));
    // And what was read can be written again.
    let again: Vec<VertexField<'_>> = back.fields.iter().map(|f| f.as_vertex_field()).collect();
    write_vtk(dir.join("again.vtk"), &mesh, &again).unwrap();
    assert_eq!(
        fs::read(&path).unwrap(),
        fs::read(dir.join("again.vtk")).unwrap()
    );
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vtk_field_errors_are_found_before_writing() {
    let dir = scratch("vtk-field-errors");
    let mesh = octahedron();
    let short = [1.0f32; 5];
    let path = dir.join("f.vtk");
    let e = write_vtk(
        &path,
        &mesh,
        &[VertexField {
            name: "s",
            values: FieldValues::Scalars(&short),
        }],
    )
    .unwrap_err();
    assert!(
        matches!(&e, MeshIoError::FieldLength { field, len: 5, expected: 6, .. } if field == "s"),
        "{e}"
    );
    let six = [1.0f32; 6];
    let e = write_vtk(
        &path,
        &mesh,
        &[VertexField {
            name: "two words",
            values: FieldValues::Scalars(&six),
        }],
    )
    .unwrap_err();
    assert!(matches!(e, MeshIoError::FieldName { .. }), "{e}");
    assert!(file_names(&dir).is_empty());
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn tets_round_trip_through_vtk() {
    let dir = scratch("vtk-tets");
    let small = two_tets();
    let small = TetMesh::new(small.positions, small.tets).unwrap();
    let boxed = tissue_mesh::tet_box(3, 2, 2, Vec3::new(1.0 / 3.0, 0.1, 2.5)).unwrap();
    for (name, tets) in [("two", small), ("box", boxed)] {
        let temperature: Vec<f32> = (0..tets.vertex_count())
            .map(|i| 36.6 + i as f32 / 7.0)
            .collect();
        let path = dir.join(format!("{name}.vtk"));
        let fields = [VertexField {
            name: "T",
            values: FieldValues::Scalars(&temperature),
        }];
        write_vtk_tets(&path, &tets, &fields).unwrap();
        let back = read_vtk(&path).unwrap();
        let VtkMesh::Tets(t) = &back.mesh else {
            panic!("{:?}", back.mesh)
        };
        assert_eq!(t.tets, tets.tets(), "{name}");
        assert_eq!(bits(&t.positions), bits(tets.positions()), "{name}");
        assert_eq!(
            back.fields[0].values,
            PointValues::Scalars(temperature),
            "{name}"
        );
        assert_eq!(read_tets(&path).unwrap(), tets, "{name}");
        assert_eq!(read_tet_data(&path).unwrap(), *t, "{name}");
        // A surface reader refuses tetrahedra, and says what to use instead.
        let e = read_surface_data(&path).unwrap_err();
        assert!(matches!(e, MeshIoError::WrongKind { .. }), "{e}");
        assert!(e.to_string().contains("read_vtk"), "{e}");
    }
    // ...and the tet reader refuses a surface.
    write_surface(dir.join("surface.vtk"), &octahedron()).unwrap();
    let e = read_tet_data(dir.join("surface.vtk")).unwrap_err();
    assert!(matches!(e, MeshIoError::WrongKind { .. }), "{e}");
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn tetgen_round_trip_zero_and_one_based() {
    let dir = scratch("tetgen");
    let tets = two_tets();
    for base in [0u32, 1] {
        let mut node = format!("# nodes\n{} 3 0 0\n", tets.positions.len());
        for (i, p) in tets.positions.iter().enumerate() {
            node += &format!("  {} {:?} {:?} {:?}\n", i as u32 + base, p.x, p.y, p.z);
        }
        let mut ele = format!("{} 4 0\n", tets.tets.len());
        for (i, t) in tets.tets.iter().enumerate() {
            let [a, b, c, d] = t.map(|v| v + base);
            ele += &format!("{} {a} {b} {c} {d}\n", i as u32 + base);
        }
        ele += "# Generated by hand\n";
        let stem = dir.join(format!("m{base}.1"));
        fs::write(dir.join(format!("m{base}.1.node")), &node).unwrap();
        fs::write(dir.join(format!("m{base}.1.ele")), &ele).unwrap();
        for path in [
            stem.clone(),
            dir.join(format!("m{base}.1.node")),
            dir.join(format!("m{base}.1.ele")),
        ] {
            let back = read_tetgen(&path).unwrap();
            assert_eq!(back.tets, tets.tets, "{}", path.display());
            assert_eq!(bits(&back.positions), bits(&tets.positions));
        }
        let parsed = parse_tetgen(node.as_bytes(), "n.node", ele.as_bytes(), "n.ele").unwrap();
        assert_eq!(parsed, tets);
    }
    // A missing .ele is an I/O error naming the .ele file.
    fs::write(dir.join("lonely.node"), "1 3 0 0\n0 0 0 0\n").unwrap();
    let e = read_tetgen(dir.join("lonely.node")).unwrap_err();
    assert!(
        matches!(&e, MeshIoError::Io { path, .. } if path.ends_with("lonely.ele")),
        "{e}"
    );
    fs::remove_dir_all(&dir).unwrap();
}

// -------------------------------------------------------------------------- parser specifics

#[derive(Clone, Copy, Debug)]
enum PlyEncoding {
    Ascii,
    Little,
    Big,
}

/// A PLY file with extra properties and an extra element, faces of 3, 4 and 5 corners.
fn ply_bytes(encoding: PlyEncoding) -> Vec<u8> {
    let positions: [[f64; 3]; 6] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.1],
        [1.0, 1.0, 1.0 / 3.0],
        [0.0, 1.0, 1e-7],
        [0.5, 1.5, 0.25],
        [-0.5, 0.5, 0.125],
    ];
    let faces: [&[i32]; 3] = [&[0, 1, 2, 3], &[3, 2, 4], &[0, 3, 4, 5, 1]];
    let format = match encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::Little => "binary_little_endian",
        PlyEncoding::Big => "binary_big_endian",
    };
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment made by a test\nelement vertex 6\nproperty float x\n\
         property float y\nproperty double z\nproperty uchar red\nelement face 3\n\
         property list uchar int vertex_indices\nproperty short flags\nelement edge 1\n\
         property int vertex1\nproperty int vertex2\nend_header\n"
    )
    .into_bytes();
    match encoding {
        PlyEncoding::Ascii => {
            let mut text = String::new();
            for p in positions {
                text += &format!("{} {} {:?} 200\n", p[0] as f32, p[1] as f32, p[2]);
            }
            for f in faces {
                text += &format!(
                    "{} {} -3\n",
                    f.len(),
                    f.iter()
                        .map(|i| i.to_string())
                        .collect::<Vec<_>>()
                        .join(" ")
                );
            }
            text += "0 1\n";
            out.extend_from_slice(text.as_bytes());
        }
        PlyEncoding::Little | PlyEncoding::Big => {
            let little = matches!(encoding, PlyEncoding::Little);
            let mut put = |b: &[u8]| {
                let mut b = b.to_vec();
                if !little {
                    b.reverse();
                }
                out.extend_from_slice(&b);
            };
            for p in positions {
                put(&(p[0] as f32).to_le_bytes());
                put(&(p[1] as f32).to_le_bytes());
                put(&p[2].to_le_bytes());
                put(&[200]);
            }
            for f in faces {
                put(&[f.len() as u8]);
                for i in f {
                    put(&i.to_le_bytes());
                }
                put(&(-3i16).to_le_bytes());
            }
            put(&0i32.to_le_bytes());
            put(&1i32.to_le_bytes());
        }
    }
    out
}

#[test]
fn ply_ascii_and_binary_both_endians_agree() {
    let expected_triangles = vec![
        [0, 1, 2],
        [0, 2, 3],
        [3, 2, 4],
        [0, 3, 4],
        [0, 4, 5],
        [0, 5, 1],
    ];
    let mut results = Vec::new();
    for encoding in [PlyEncoding::Ascii, PlyEncoding::Little, PlyEncoding::Big] {
        let d = parse_ply(&ply_bytes(encoding), "p.ply")
            .unwrap_or_else(|e| panic!("{encoding:?}: {e}"));
        assert_eq!(d.triangles, expected_triangles, "{encoding:?}");
        assert_eq!(
            d.positions[2],
            Vec3::new(1.0, 1.0, (1.0f64 / 3.0) as f32),
            "{encoding:?}"
        );
        results.push(d);
    }
    assert_eq!(bits(&results[0].positions), bits(&results[1].positions));
    assert_eq!(results[1], results[2]);
}

#[test]
fn ply_truncated_binary_names_the_element() {
    let bytes = ply_bytes(PlyEncoding::Little);
    let header_len = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    // Vertex records are 4 + 4 + 8 + 1 = 17 bytes: cut inside vertex 3.
    let cut = &bytes[..header_len + 3 * 17 + 5];
    let e = parse_ply(cut, "cut.ply").unwrap_err();
    assert!(
        matches!(&e, MeshIoError::Binary { element, index: Some(3), .. } if element == "vertex"),
        "{e}"
    );
    assert!(e.to_string().contains("cut.ply, vertex 3"), "{e}");
    // Cut inside the faces.
    let cut = &bytes[..bytes.len() - 12];
    let e = parse_ply(cut, "cut.ply").unwrap_err();
    assert!(
        matches!(&e, MeshIoError::Binary { element, .. } if element == "face"),
        "{e}"
    );
}

#[test]
fn stl_ascii_reads_and_binary_cube_welds_to_8_vertices() {
    let mut text = String::from("solid cube\n");
    let c = cube();
    for t in c.triangles() {
        text += "  facet normal 0 0 0\n    outer loop\n";
        for &i in t {
            let p = c.positions()[i as usize];
            text += &format!("      vertex {} {} {}\n", p.x, p.y, p.z);
        }
        text += "    endloop\n  endfacet\n";
    }
    text += "endsolid cube\n";
    let ascii = parse_stl(text.as_bytes(), "cube.stl").unwrap();
    assert_eq!((ascii.positions.len(), ascii.triangles.len()), (8, 12));

    // Binary, built by hand: 12 triangles = 36 corners, 8 distinct.
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&12u32.to_le_bytes());
    for t in c.triangles() {
        bytes.extend_from_slice(&[0; 12]);
        for &i in t {
            for x in c.positions()[i as usize].to_array() {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0, 0]);
    }
    let binary = parse_stl(&bytes, "cube.stl").unwrap();
    assert_eq!((binary.positions.len(), binary.triangles.len()), (8, 12));
    assert_eq!(binary, ascii);
    // First-appearance order: the first triangle's corners are vertices 0, 1, 2.
    assert_eq!(binary.triangles[0], [0, 1, 2]);
    assert!(TriMesh::new(binary.positions, binary.triangles)
        .unwrap()
        .is_closed());
}

#[test]
fn obj_keeps_file_order_unreferenced_vertices_and_ignores_seams_and_groups() {
    let text = "# two groups sharing an edge, uv and normal seams\nmtllib x.mtl\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n\
        g first\nusemtl a\nf 1/1/1 2/2/1 3/3/1\ng second\nusemtl b\nf 1/3/1 3/1/1 4/2/1\nl 1 2\n";
    let d = parse_surface_data(text.as_bytes(), "seams.obj").unwrap();
    assert_eq!(d.positions.len(), 5, "unreferenced vertex 5 is kept");
    assert_eq!(d.positions[1], Vec3::X);
    assert_eq!(d.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    let defects = tissue_mesh::diagnose(&d.positions, &d.triangles);
    assert!(
        matches!(
            defects.as_slice(),
            [tissue_mesh::MeshError::UnreferencedVertex { vertex: 4 }]
        ),
        "{defects:?}"
    );
}

// ------------------------------------------------------------------------ errors name places

#[test]
fn obj_bad_vertex_line_names_line_7() {
    let text = "# header\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\nv 0 0 one\n";
    let e = parse_surface_data(text.as_bytes(), "bad.obj").unwrap_err();
    assert_eq!(parse_line(&e), 7);
    let message = e.to_string();
    assert!(message.starts_with("bad.obj, line 7:"), "{message}");
    assert!(
        message.contains("z coordinate") && message.contains("`one`"),
        "{message}"
    );
}

#[test]
fn obj_face_index_out_of_range_names_the_line() {
    let dir = scratch("obj-range");
    let path = dir.join("range.obj");
    fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n").unwrap();
    let e = read_obj(&path).unwrap_err();
    assert_eq!(parse_line(&e), 5);
    assert_eq!(e.path(), path);
    assert!(e.to_string().contains("only 3 vertices"), "{e}");
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn stl_truncated_binary_names_the_triangle() {
    let dir = scratch("stl-truncated");
    let path = dir.join("cube.stl");
    write_stl(&path, &cube()).unwrap();
    let bytes = fs::read(&path).unwrap();
    let e = parse_stl(&bytes[..84 + 50 * 7 + 20], "cube.stl").unwrap_err();
    assert!(
        matches!(&e, MeshIoError::Binary { element, index: Some(7), .. } if element == "triangle"),
        "{e}"
    );
    assert!(e.to_string().contains("truncated"), "{e}");
    let e = parse_stl(&bytes[..40], "cube.stl").unwrap_err();
    assert!(matches!(&e, MeshIoError::Binary { index: None, .. }), "{e}");
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vtk_errors_name_the_line() {
    let text = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0\n1 0 0\n0 1 0\nPOLYGONS 1 4\n3 0 1 3\n";
    let e = parse_vtk(text.as_bytes(), "v.vtk").unwrap_err();
    assert_eq!(parse_line(&e), 10);
    assert!(e.to_string().contains("refers to point 3"), "{e}");
}

#[test]
fn unknown_extension_and_missing_file() {
    let e = read_surface_data("mesh.off").unwrap_err();
    assert!(matches!(e, MeshIoError::UnsupportedFormat { .. }), "{e}");
    assert!(e.to_string().contains(".obj, .ply, .stl or .vtk"), "{e}");
    let e = read_surface_data("no-extension").unwrap_err();
    assert!(matches!(e, MeshIoError::UnsupportedFormat { .. }), "{e}");
    let e = write_surface("mesh.off", &octahedron()).unwrap_err();
    assert!(matches!(e, MeshIoError::UnsupportedFormat { .. }), "{e}");
    let e = read_surface("/nonexistent-tissue-dir/mesh.obj").unwrap_err();
    assert!(matches!(e, MeshIoError::Io { .. }), "{e}");
    assert!(
        e.to_string().contains("/nonexistent-tissue-dir/mesh.obj"),
        "{e}"
    );
}

#[test]
fn invalid_mesh_names_file_and_element() {
    let dir = scratch("invalid");
    let path = dir.join("flat.obj");
    fs::write(&path, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    // Raw data read fine...
    assert_eq!(read_surface_data(&path).unwrap().triangles.len(), 1);
    // ...but do not make a mesh.
    let e = read_surface(&path).unwrap_err();
    match &e {
        MeshIoError::Invalid { path: p, source } => {
            assert_eq!(p, &path);
            assert!(matches!(
                source,
                tissue_mesh::MeshError::DegenerateTriangle { triangle: 0, .. }
            ));
        }
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("flat.obj"), "{e}");
    fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------- atomic writes

#[test]
fn write_into_missing_folder_fails_and_leaves_nothing() {
    let dir = scratch("missing-folder");
    let target = dir.join("not-there").join("mesh.obj");
    for ext in ["obj", "ply", "stl", "vtk"] {
        let e = write_surface(target.with_extension(ext), &octahedron()).unwrap_err();
        assert!(matches!(e, MeshIoError::Io { .. }), "{e}");
        assert!(e.to_string().contains("not-there"), "{e}");
    }
    assert!(file_names(&dir).is_empty(), "{:?}", file_names(&dir));
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn writes_leave_no_temporary_files_and_replace_whole() {
    let dir = scratch("replace");
    let big = grid(30, 30);
    let small = octahedron();
    for ext in ["obj", "ply", "stl", "vtk"] {
        let target = dir.join(format!("mesh.{ext}"));
        let reference = dir.join(format!("reference.{ext}"));
        write_surface(&target, &big).unwrap();
        write_surface(&target, &small).unwrap();
        write_surface(&reference, &small).unwrap();
        // No tail of the bigger file survives.
        assert_eq!(
            fs::read(&target).unwrap(),
            fs::read(&reference).unwrap(),
            "{ext}"
        );
    }
    assert_eq!(
        file_names(&dir),
        [
            "mesh.obj",
            "mesh.ply",
            "mesh.stl",
            "mesh.vtk",
            "reference.obj",
            "reference.ply",
            "reference.stl",
            "reference.vtk"
        ]
    );
    // Writing over a folder fails without debris.
    let folder = dir.join("folder.obj");
    fs::create_dir(&folder).unwrap();
    assert!(write_obj(&folder, &small).is_err());
    assert!(folder.is_dir());
    assert_eq!(file_names(&dir).len(), 9);
    fs::remove_dir_all(&dir).unwrap();
}

// ------------------------------------------------------------------------------ real meshes

/// The repository's `fixtures/` folder, where the real meshes the tests read are shipped.
fn fixtures() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures"))
}

#[test]
fn real_surfaces_have_the_documented_counts_and_topology() {
    let dir = fixtures();
    // file, V, F, closed, χ, boundary loop edge counts (fixtures/README.md).
    type Case = (&'static str, usize, usize, bool, i64, &'static [usize]);
    let cases: [Case; 5] = [
        ("makehuman_body_closed.obj", 13_380, 26_756, true, 2, &[]),
        ("makehuman_head_open.obj", 4_257, 8_470, false, 1, &[42]),
        ("makehuman_chest_open.obj", 4_921, 9_632, false, 1, &[208]),
        ("bunny_10k.obj", 5_002, 10_000, true, 2, &[]),
        ("liver_sofa.obj", 1_170, 2_336, true, 2, &[]),
    ];
    for (file, v, f, closed, chi, loops) in cases {
        let path = dir.join(file);
        let data = read_surface_data(&path).unwrap();
        assert_eq!(
            (data.positions.len(), data.triangles.len()),
            (v, f),
            "{file}"
        );
        let mesh = read_surface(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(mesh.is_closed(), closed, "{file}");
        assert_eq!(mesh.euler_characteristic(), chi, "{file}");
        let loop_edges: Vec<usize> = mesh
            .topology()
            .boundary_loops()
            .iter()
            .map(Vec::len)
            .collect();
        assert_eq!(loop_edges, loops, "{file}");
        assert_eq!(mesh.topology().component_count(), 1, "{file}");
    }
}

#[test]
fn real_tet_mesh_has_the_documented_counts() {
    // The TetGen armadillo: nodes, tets, boundary triangles, interior nodes (fixtures/README.md).
    let stem = fixtures().join("armadillo_4k");
    let data = read_tetgen(&stem).unwrap();
    assert_eq!((data.positions.len(), data.tets.len()), (1_180, 3_717));
    // Validation checks what the provenance says: all positive, no face in more than 2 tets.
    let mesh = read_tets(stem.with_extension("ele")).unwrap_or_else(|e| panic!("{e}"));
    let surface = mesh.boundary_surface().unwrap();
    assert_eq!(surface.triangle_count(), 2_102);
    assert!(surface.is_closed());
    let unused = surface.unreferenced_vertices().len();
    assert_eq!(surface.euler_characteristic() - unused as i64, 2);
    assert_eq!(unused, 127);
}

/// tobj (the design card's OBJ crate) as an oracle: on well-formed single-group files it must
/// see the same triangles, corner by corner. (It renumbers vertices, so compare positions.)
#[test]
fn obj_reader_agrees_with_tobj_on_well_formed_files() {
    let dir = scratch("tobj");
    let mut files: Vec<PathBuf> = Vec::new();
    for (name, mesh) in meshes() {
        let path = dir.join(format!("{name}.obj"));
        write_obj(&path, &mesh).unwrap();
        files.push(path);
    }
    for f in ["makehuman_head_open.obj", "liver_sofa.obj", "bunny_10k.obj"] {
        files.push(fixtures().join(f));
    }
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    for path in files {
        let ours = read_obj(&path).unwrap();
        let (models, _) = tobj::load_obj(&path, &options).unwrap();
        assert_eq!(models.len(), 1, "{}", path.display());
        let m = &models[0].mesh;
        let theirs: Vec<[[u32; 3]; 3]> = m
            .indices
            .chunks(3)
            .map(|t| {
                [0, 1, 2].map(|k| {
                    let i = t[k] as usize * 3;
                    [m.positions[i], m.positions[i + 1], m.positions[i + 2]].map(f32::to_bits)
                })
            })
            .collect();
        let ours: Vec<[[u32; 3]; 3]> = ours
            .triangles
            .iter()
            .map(|t| t.map(|i| ours.positions[i as usize].to_array().map(f32::to_bits)))
            .collect();
        assert_eq!(ours, theirs, "{}", path.display());
    }
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn surface_data_default_is_empty_and_fails_validation() {
    let d = SurfaceData::default();
    assert!(tissue_mesh::diagnose(&d.positions, &d.triangles)
        .iter()
        .any(|e| matches!(e, tissue_mesh::MeshError::Empty { .. })));
}
