//! The `.vtu` and `.msh` tetrahedral readers on files written by other tools (Gmsh, meshio,
//! pyevtk: see `fixtures/tets/README.md`), and their errors.
#![allow(clippy::panic)]
// Test code: a failed unwrap is a failed test.
#![allow(clippy::unwrap_used)]

use std::fs;
use std::path::{Path, PathBuf};

use tissue_mesh::MeshError;
use tissue_meshio::{
    parse_msh, parse_tet_data, parse_vtu, read_msh, read_tet_data, read_tets, read_vtu,
    MeshIoError, TetData,
};

/// The box every fixture holds: [0, 2] x [0, 1.5] x [0, 1], meshed by Gmsh.
const BOX_VOLUME: f64 = 3.0;
const BOX_NODES: usize = 50;
const BOX_TETS: usize = 107;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/tets")
        .join(name)
}

fn signed_volume(d: &TetData, t: [u32; 4]) -> f64 {
    let p = t.map(|i| d.positions[i as usize].as_dvec3());
    (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) / 6.0
}

/// Counts, every tet positive, total volume, and that it validates into a `TetMesh`.
fn check_box(name: &str) {
    let path = fixture(name);
    let d = read_tet_data(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(d.positions.len(), BOX_NODES, "{name}");
    assert_eq!(d.tets.len(), BOX_TETS, "{name}");
    let mut total = 0.0;
    for (i, &t) in d.tets.iter().enumerate() {
        let v = signed_volume(&d, t);
        assert!(v > 0.0, "{name}: tet {i} {t:?} has volume {v}");
        total += v;
    }
    assert!((total - BOX_VOLUME).abs() < 1e-5, "{name}: volume {total}");
    let lo = d.positions.iter().fold(glam::Vec3::MAX, |a, &p| a.min(p));
    let hi = d.positions.iter().fold(glam::Vec3::MIN, |a, &p| a.max(p));
    assert_eq!(
        (lo, hi),
        (glam::Vec3::ZERO, glam::Vec3::new(2.0, 1.5, 1.0)),
        "{name}"
    );
    let mesh = read_tets(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh.tets().len(), BOX_TETS);
    // The same from memory, by extension.
    let bytes = fs::read(&path).unwrap();
    assert_eq!(parse_tet_data(&bytes, name).unwrap(), d, "{name}");
}

#[test]
fn vtu_ascii_by_meshio() {
    check_box("box_ascii.vtu");
}

#[test]
fn vtu_base64_by_meshio() {
    check_box("box_base64.vtu");
}

#[test]
fn vtu_base64_uint64_header_by_meshio() {
    check_box("box_base64_uint64.vtu");
}

#[test]
fn vtu_zlib_by_meshio() {
    check_box("box_zlib.vtu");
}

#[test]
fn vtu_appended_raw_by_pyevtk() {
    check_box("box_appended_raw.vtu");
}

#[test]
fn msh_v1_by_gmsh() {
    check_box("box_v1.msh");
}

#[test]
fn msh_v22_ascii_by_gmsh() {
    check_box("box_v22_ascii.msh");
}

#[test]
fn msh_v22_binary_by_gmsh() {
    check_box("box_v22_binary.msh");
}

#[test]
fn msh_v41_ascii_by_gmsh() {
    check_box("box_v41_ascii.msh");
}

#[test]
fn msh_v41_binary_by_gmsh() {
    check_box("box_v41_binary.msh");
}

#[test]
fn every_format_gives_the_same_mesh() {
    // Gmsh's own files agree exactly (same tags, same order); meshio and pyevtk keep the order.
    let reference = read_msh(fixture("box_v41_ascii.msh")).unwrap();
    for name in [
        "box_v1.msh",
        "box_v22_ascii.msh",
        "box_v22_binary.msh",
        "box_v41_binary.msh",
        "box_ascii.vtu",
        "box_base64.vtu",
        "box_base64_uint64.vtu",
        "box_zlib.vtu",
        "box_appended_raw.vtu",
    ] {
        let d = read_tet_data(fixture(name)).unwrap();
        assert_eq!(d.tets, reference.tets, "{name}");
        for (a, b) in d.positions.iter().zip(&reference.positions) {
            assert!((*a - *b).abs().max_element() < 1e-6, "{name}: {a} vs {b}");
        }
    }
}

// ---------------------------------------------------------------- errors

#[test]
fn no_tets_is_an_error_that_says_what_the_file_holds() {
    for name in ["square_no_tets.msh", "square_no_tets.vtu"] {
        let e = read_tet_data(fixture(name)).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("square_no_tets"), "{msg}");
        assert!(msg.contains("no ") && msg.contains("tetrahedra"), "{msg}");
        assert!(msg.contains("triangles (type"), "{msg}");
    }
}

#[test]
fn lzma_compression_is_refused_with_the_fix() {
    let e = read_vtu(fixture("box_lzma.vtu")).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, MeshIoError::Parse { line: 2, .. }), "{msg}");
    assert!(msg.contains("vtkLZMADataCompressor"), "{msg}");
    assert!(msg.contains("uncompressed or with zlib"), "{msg}");
}

#[test]
fn truncated_files_are_errors() {
    for name in [
        "box_v1.msh",
        "box_v22_ascii.msh",
        "box_v22_binary.msh",
        "box_v41_ascii.msh",
        "box_v41_binary.msh",
        "box_ascii.vtu",
        "box_base64.vtu",
        "box_zlib.vtu",
        "box_appended_raw.vtu",
    ] {
        let bytes = fs::read(fixture(name)).unwrap();
        for keep in [bytes.len() / 3, bytes.len() / 2, bytes.len() * 9 / 10] {
            let e = parse_tet_data(&bytes[..keep], name)
                .err()
                .unwrap_or_else(|| panic!("{name} cut at {keep} was accepted"));
            assert!(e.to_string().contains(name), "{e}");
        }
    }
    let bytes = fs::read(fixture("box_v41_ascii.msh")).unwrap();
    let e = parse_msh(&bytes[..bytes.len() / 2], "cut.msh").unwrap_err();
    assert!(e.to_string().contains("truncated"), "{e}");
    let bytes = fs::read(fixture("box_v22_binary.msh")).unwrap();
    let e = parse_msh(&bytes[..bytes.len() / 2], "cut.msh").unwrap_err();
    assert!(
        matches!(&e, MeshIoError::Binary { element, .. } if element == "node" || element == "element"),
        "{e}"
    );
}

#[test]
fn a_bad_node_tag_names_the_line() {
    let text = fs::read_to_string(fixture("box_v22_ascii.msh")).unwrap();
    // The last tetrahedron refers to node 50; make it 51, which does not exist.
    let lines: Vec<&str> = text.lines().collect();
    let k = lines
        .iter()
        .rposition(|l| l.split(' ').nth(1) == Some("4"))
        .unwrap();
    let mut words: Vec<&str> = lines[k].split(' ').collect();
    let last = words.len() - 1;
    words[last] = "51";
    let bad_line = words.join(" ");
    let mut bad: Vec<&str> = lines.clone();
    bad[k] = &bad_line;
    let e = parse_msh(bad.join("\n").as_bytes(), "bad.msh").unwrap_err();
    assert!(
        matches!(&e, MeshIoError::Parse { line, .. } if *line == k + 1),
        "{e}"
    );
    assert!(e.to_string().contains("node tag 51"), "{e}");
    // A tag that is not a number.
    bad[k] = "x";
    let e = parse_msh(bad.join("\n").as_bytes(), "bad.msh").unwrap_err();
    assert!(e.to_string().contains("element tag"), "{e}");
    // A duplicate node tag.
    let dup = text.replacen("\n2 0 0 0\n", "\n1 0 0 0\n", 1);
    let e = parse_msh(dup.as_bytes(), "dup.msh").unwrap_err();
    assert!(e.to_string().contains("appears twice"), "{e}");
}

#[test]
fn a_bad_vtu_index_names_the_array() {
    let text = fs::read_to_string(fixture("box_ascii.vtu")).unwrap();
    // meshio writes one value a line; the connectivity's first value is a vertex of a cell.
    let lines: Vec<&str> = text.lines().collect();
    let k = lines
        .iter()
        .position(|l| l.contains("Name=\"connectivity\""))
        .unwrap();
    let mut bad_lines = lines.clone();
    bad_lines[k + 1] = "999";
    let e = parse_vtu(bad_lines.join("\n").as_bytes(), "bad.vtu").unwrap_err();
    assert!(e.to_string().contains("bad.vtu"), "{e}");
    assert!(
        e.to_string().contains("connectivity") && e.to_string().contains("999"),
        "{e}"
    );
    assert!(
        matches!(e, MeshIoError::Parse { line, .. } if line == k + 1),
        "{e}"
    );
    bad_lines[k + 1] = "0x";
    let e = parse_vtu(bad_lines.join("\n").as_bytes(), "bad.vtu").unwrap_err();
    assert!(e.to_string().contains("`0x`"), "{e}");
    let bad = text.replacen("type=\"UnstructuredGrid\"", "type=\"PolyData\"", 1);
    let e = parse_vtu(bad.as_bytes(), "p.vtu").unwrap_err();
    assert!(e.to_string().contains("UnstructuredGrid"), "{e}");
}

#[test]
fn negative_tets_are_read_as_stored_and_refused_by_validation() {
    // The policy of every tet reader: data come back as stored; TetMesh refuses inverted tets.
    let text = fs::read_to_string(fixture("box_v41_ascii.msh")).unwrap();
    let d = parse_msh(text.as_bytes(), "box.msh").unwrap();
    let [a, b, c, dd] = d.tets[0];
    // Swap two nodes of the first tetrahedron (MSH 4.1 lines: `<tag> <node tags...>`).
    let want = [a, b, c, dd].map(|i| (i + 1).to_string());
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let k = lines
        .iter()
        .position(|l| {
            l.split_whitespace()
                .skip(1)
                .eq(want.iter().map(String::as_str))
        })
        .unwrap();
    let tag = lines[k].split_whitespace().next().unwrap().to_string();
    lines[k] = format!("{tag} {} {} {} {}", want[1], want[0], want[2], want[3]);
    let flipped = lines.join("\n");
    let path = std::env::temp_dir().join(format!("meshio-flipped-{}.msh", std::process::id()));
    fs::write(&path, &flipped).unwrap();
    let data = read_tet_data(&path).unwrap();
    assert_eq!(data.tets[0], [b, a, c, dd]);
    let e = read_tets(&path).unwrap_err();
    fs::remove_file(&path).ok();
    assert!(
        matches!(
            e,
            MeshIoError::Invalid {
                source: MeshError::InvertedTet { tet: 0, .. },
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn unknown_extensions_are_unsupported_not_tetgen() {
    let dir = std::env::temp_dir().join(format!("meshio-ext-{}", std::process::id()));
    fs::create_dir_all(&dir).unwrap();
    let liver = dir.join("liver.xyz");
    fs::write(&liver, "x").unwrap();
    let e = read_tet_data(&liver).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, MeshIoError::UnsupportedFormat { .. }), "{msg}");
    assert!(
        msg.contains(".vtu") && msg.contains(".msh") && !msg.contains("liver.xyz.node"),
        "{msg}"
    );
    for name in ["liver.obj", "liver.stl"] {
        let e = read_tet_data(dir.join(name)).unwrap_err();
        assert!(matches!(e, MeshIoError::UnsupportedFormat { .. }), "{e}");
    }
    // A missing .vtu names the .vtu, not a TetGen file.
    let e = read_tet_data(dir.join("liver.vtu")).unwrap_err();
    assert!(
        matches!(&e, MeshIoError::Io { path, .. } if path.ends_with("liver.vtu")),
        "{e}"
    );
    // A TetGen stem with a dotted name still reads as TetGen.
    fs::write(
        dir.join("m.final.node"),
        "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n",
    )
    .unwrap();
    fs::write(dir.join("m.final.ele"), "1 4 0\n0 0 1 2 3\n").unwrap();
    assert_eq!(read_tet_data(dir.join("m.final")).unwrap().tets.len(), 1);
    fs::remove_dir_all(&dir).ok();
    // From memory.
    let e = parse_tet_data(b"", "x.node").unwrap_err();
    assert!(e.to_string().contains("parse_tetgen"), "{e}");
    let e = parse_tet_data(b"", "x.obj").unwrap_err();
    assert!(matches!(e, MeshIoError::UnsupportedFormat { .. }), "{e}");
}
