//! Robustness: no reader panics, whatever the bytes. Every input of a small corpus (files in
//! `fixtures/`, the real third-party meshes among them, meshes generated and written here in
//! every format, hand-made ASCII/big-endian variants) is truncated and corrupted at
//! seeded positions, and each result must be `Ok` or `Err`.

// Test code: a failed unwrap is a failed test.
#![allow(clippy::unwrap_used)]

use std::fs;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use glam::Vec3;
use tissue_mesh::TriMesh;
use tissue_meshio::{
    parse_surface_data, parse_tet_data, parse_tetgen, parse_vtk, write_obj, write_ply, write_stl,
    write_vtk, write_vtk_tets, FieldValues, VertexField,
};

/// xorshift64*: tiny, deterministic, good enough to pick positions.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(seed | 1)
    }
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Bytes and tokens that tend to find parser bugs.
const BYTES: &[u8] = b"0123456789-+. \n\r\t#/eExX\x00\xff\x80";
const SPLICES: &[&str] = &[
    "99999999999999999999999",
    "18446744073709551615",
    "4294967295",
    "-2147483648",
    "-1",
    "0",
    "nan",
    "inf",
    "1e39",
    "\u{e9}",
    "\r\n",
    " end_header\n",
    "\n",
];

/// One input: a file name (its extension picks the reader), its bytes, and for TetGen the
/// other file of the pair.
struct Input {
    name: String,
    bytes: Vec<u8>,
    partner: Option<Vec<u8>>,
}

fn read_any(input: &Input, bytes: &[u8]) {
    let ext = Path::new(&input.name)
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let partner = input.partner.as_deref().unwrap_or_default();
    match ext.as_str() {
        "vtk" => drop(parse_vtk(bytes, &input.name)),
        "vtu" | "msh" => drop(parse_tet_data(bytes, &input.name)),
        "node" => drop(parse_tetgen(bytes, &input.name, partner, "partner.ele")),
        "ele" => drop(parse_tetgen(partner, "partner.node", bytes, &input.name)),
        _ => drop(parse_surface_data(bytes, &input.name)),
    }
}

/// `count` seeded mutations of `bytes`, each with a description.
fn mutations(bytes: &[u8], seed: u64, count: usize) -> Vec<(String, Vec<u8>)> {
    let mut rng = Rng::new(seed);
    let mut out = Vec::with_capacity(count);
    for m in 0..count {
        let len = bytes.len();
        match m % 5 {
            // Truncation: the most common real-world damage.
            0 | 1 => {
                let cut = rng.below(len + 1);
                out.push((format!("truncate at {cut}"), bytes[..cut].to_vec()));
            }
            // Overwrite 1..4 bytes.
            2 => {
                let mut b = bytes.to_vec();
                let mut what = Vec::new();
                for _ in 0..1 + rng.below(4) {
                    if b.is_empty() {
                        break;
                    }
                    let at = rng.below(b.len());
                    let v = if rng.below(2) == 0 {
                        BYTES[rng.below(BYTES.len())]
                    } else {
                        rng.next() as u8
                    };
                    b[at] = v;
                    what.push(format!("[{at}]={v:#04x}"));
                }
                out.push((format!("overwrite {}", what.join(" ")), b));
            }
            // Grow or change a number of a header (counts, sizes, indices): insert a hostile
            // token next to a digit among the first 512 bytes.
            4 => {
                let digits: Vec<usize> = (0..len.min(512))
                    .filter(|&i| bytes[i].is_ascii_digit())
                    .collect();
                let at = if digits.is_empty() {
                    rng.below(len + 1)
                } else {
                    digits[rng.below(digits.len())] + rng.below(2)
                };
                let s = SPLICES[rng.below(6)];
                let mut b = bytes.to_vec();
                b.splice(at..at, s.bytes());
                out.push((format!("insert {s:?} at digit {at}"), b));
            }
            // Splice a hostile token in (or delete a span).
            _ => {
                let mut b = bytes.to_vec();
                let at = rng.below(len + 1);
                if rng.below(3) == 0 && at < len {
                    let end = (at + 1 + rng.below(16)).min(len);
                    b.drain(at..end);
                    out.push((format!("delete {at}..{end}"), b));
                } else {
                    let s = SPLICES[rng.below(SPLICES.len())];
                    b.splice(at..at, s.bytes());
                    out.push((format!("insert {s:?} at {at}"), b));
                }
            }
        }
    }
    out
}

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tissue-meshio-{}-{test}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn generated_inputs() -> Vec<Input> {
    let dir = scratch("fuzz-corpus");
    let mut positions = Vec::new();
    let n = 4u32;
    for j in 0..n {
        for i in 0..n {
            positions.push(Vec3::new(
                i as f32 * 0.1,
                j as f32 / 3.0,
                1e-7 * (i * j) as f32,
            ));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            triangles.push([a, a + 1, a + n + 1]);
            triangles.push([a, a + n + 1, a + n]);
        }
    }
    let mesh = TriMesh::new(positions, triangles).unwrap();
    let values: Vec<f32> = (0..mesh.vertex_count()).map(|i| i as f32 / 3.0).collect();
    let fields = [VertexField {
        name: "s",
        values: FieldValues::Scalars(&values),
    }];
    write_obj(dir.join("grid.obj"), &mesh).unwrap();
    write_ply(dir.join("grid.ply"), &mesh).unwrap();
    write_stl(dir.join("grid.stl"), &mesh).unwrap();
    write_vtk(dir.join("grid.vtk"), &mesh, &fields).unwrap();
    let tets = tissue_mesh::tet_box(2, 1, 1, Vec3::new(0.2, 0.1, 1.0 / 3.0)).unwrap();
    write_vtk_tets(dir.join("tets.vtk"), &tets, &[]).unwrap();

    let mut inputs: Vec<Input> = ["grid.obj", "grid.ply", "grid.stl", "grid.vtk", "tets.vtk"]
        .iter()
        .map(|f| Input {
            name: f.to_string(),
            bytes: fs::read(dir.join(f)).unwrap(),
            partner: None,
        })
        .collect();
    fs::remove_dir_all(&dir).unwrap();

    // ASCII and big-endian PLY, ASCII STL, which the writers do not make.
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property double z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let quad = [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.5],
        [0.0, 1.0, 0.0],
    ];
    let mut ascii = header("ascii");
    for p in quad {
        ascii += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    ascii += "3 0 1 2\n3 0 2 3\n";
    let mut big = header("binary_big_endian").into_bytes();
    for p in quad {
        big.extend_from_slice(&p[0].to_be_bytes());
        big.extend_from_slice(&p[1].to_be_bytes());
        big.extend_from_slice(&f64::from(p[2]).to_be_bytes());
    }
    for f in [[0i32, 1, 2], [0, 2, 3]] {
        big.push(3);
        for i in f {
            big.extend_from_slice(&i.to_be_bytes());
        }
    }
    let stl = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\n\
               facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid s\n";
    let node = "# c\n5 3 1 1\n1 0 0 0 2.5 1\n2 1 0 0 2.5 1\n3 0 1 0 2.5 1\n4 0 0 1 2.5 0\n5 0.7 0.7 0.7 2.5 1\n";
    let ele = "2 4 1\n1 1 2 3 4 7\n2 2 3 4 5 7\n# Generated by hand\n";
    inputs.push(Input {
        name: "ascii.ply".into(),
        bytes: ascii.into_bytes(),
        partner: None,
    });
    inputs.push(Input {
        name: "big.ply".into(),
        bytes: big,
        partner: None,
    });
    inputs.push(Input {
        name: "ascii.stl".into(),
        bytes: stl.as_bytes().to_vec(),
        partner: None,
    });
    inputs.push(Input {
        name: "m.node".into(),
        bytes: node.as_bytes().to_vec(),
        partner: Some(ele.as_bytes().to_vec()),
    });
    inputs.push(Input {
        name: "m.ele".into(),
        bytes: ele.as_bytes().to_vec(),
        partner: Some(node.as_bytes().to_vec()),
    });
    inputs
}

/// Files from a folder that one of the readers understands, at most `max_bytes` each.
fn folder_inputs(dir: &Path, max_bytes: u64) -> Vec<Input> {
    let Ok(entries) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    let mut inputs = Vec::new();
    for path in paths {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        if !["obj", "ply", "stl", "vtk", "vtu", "msh", "node", "ele"].contains(&ext.as_str()) {
            continue;
        }
        if fs::metadata(&path)
            .map(|m| m.len() > max_bytes)
            .unwrap_or(true)
        {
            continue;
        }
        let partner_ext = match ext.as_str() {
            "node" => Some("ele"),
            "ele" => Some("node"),
            _ => None,
        };
        let partner = partner_ext.and_then(|p| fs::read(path.with_extension(p)).ok());
        if partner_ext.is_some() && partner.is_none() {
            continue;
        }
        inputs.push(Input {
            name: path.file_name().unwrap().to_string_lossy().into_owned(),
            bytes: fs::read(&path).unwrap(),
            partner,
        });
    }
    inputs
}

fn seed_of(name: &str) -> u64 {
    name.bytes().fold(0x9E37_79B9_7F4A_7C15, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01B3)
    })
}

/// Runs every mutation of every input; returns the ones that panicked.
fn panics(inputs: &[Input], per_input: usize) -> Vec<String> {
    let mut failures = Vec::new();
    for input in inputs {
        // The unmodified input must not panic either (it may be Err for a fixture of a bad file).
        let mut cases = vec![("original".to_string(), input.bytes.clone())];
        cases.extend(mutations(&input.bytes, seed_of(&input.name), per_input));
        for (what, bytes) in cases {
            if catch_unwind(AssertUnwindSafe(|| read_any(input, &bytes))).is_err() {
                failures.push(format!("{}: {what}", input.name));
            }
        }
    }
    failures
}

#[test]
fn no_reader_panics_on_mutated_generated_files() {
    let inputs = generated_inputs();
    assert_eq!(inputs.len(), 10);
    let failures = panics(&inputs, 1000);
    assert!(
        failures.is_empty(),
        "readers panicked on:\n{}",
        failures.join("\n")
    );
}

#[test]
fn no_reader_panics_on_mutated_fixtures_and_real_meshes() {
    // The generated fixtures and the real meshes shipped beside them (MakeHuman, the bunny, the
    // liver, the TetGen armadillo).
    let fixtures = folder_inputs(
        Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures")),
        2_000_000,
    );
    assert!(fixtures.len() >= 13, "{} fixtures", fixtures.len());
    let failures = panics(&fixtures, 200);
    assert!(
        failures.is_empty(),
        "readers panicked on fixtures:\n{}",
        failures.join("\n")
    );
    // The .vtu and .msh files written by Gmsh, meshio and pyevtk.
    let tets = folder_inputs(
        Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/tets")),
        200_000,
    );
    assert!(tets.len() >= 12, "{} tet fixtures", tets.len());
    let failures = panics(&tets, 200);
    assert!(
        failures.is_empty(),
        "readers panicked on tet fixtures:\n{}",
        failures.join("\n")
    );
}

/// Counts far beyond what the data hold must fail fast, without huge allocations.
#[test]
fn hostile_counts_are_errors() {
    let cases: [(&str, &[u8]); 8] = [
        ("a.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 4294967294\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0"),
        ("b.ply", b"ply\nformat ascii 1.0\nelement vertex 18446744073709551615\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n"),
        ("c.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\xff\xff\xff\xff\0\0\0\0"),
        ("d.stl", b"solid\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"),
        ("e.vtk", b"# vtk DataFile Version 3.0\n\nASCII\nDATASET POLYDATA\nPOINTS 18446744073709551615 float\n0 0 0\n"),
        ("f.vtk", b"# vtk DataFile Version 3.0\n\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n0 0 0\nCELLS 4611686018427387904 4611686018427387904\n1 0\n"),
        ("g.obj", b"v 0 0 0\nf 1 1 -9223372036854775808\n"),
        ("i.stl", &[0xff; 84]),
    ];
    for (name, bytes) in cases {
        let result = catch_unwind(|| {
            parse_surface_data(bytes, name).map(|_| ()).or_else(|e| {
                // VTK tets are not a surface; parse them as VTK to reach the count.
                if name.ends_with(".vtk") {
                    parse_vtk(bytes, name).map(|_| ())
                } else {
                    Err(e)
                }
            })
        });
        match result {
            Ok(r) => assert!(r.is_err(), "{name} was accepted"),
            Err(_) => panic!("{name} panicked"),
        }
    }
    let huge_node = b"18446744073709551615 3 0 0\n0 0 0 0\n";
    assert!(parse_tetgen(huge_node, "h.node", b"0 4 0\n", "h.ele").is_err());
    let huge_ele = b"1 3 0 0\n0 0 0 0\n";
    assert!(parse_tetgen(
        huge_ele,
        "h.node",
        b"18446744073709551615 4 0\n0 0 0 0 0\n",
        "h.ele"
    )
    .is_err());
}
