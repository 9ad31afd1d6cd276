//! Runs the real `meshinfo` binary on the fixtures, the real third-party meshes among them.
#![allow(clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use tissue_cli::Exit;

/// The code of `exit`, as the process reports it.
fn code(exit: Exit) -> i32 {
    exit.code().into()
}

fn fixture(name: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures")).join(name)
}

/// Runs meshinfo; returns (exit code, stdout, stderr).
fn run(args: &[&std::ffi::OsStr]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_meshinfo"))
        .args(args)
        .output()
        .expect("meshinfo runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn json(path: &Path) -> (i32, Value) {
    let (code, stdout, stderr) = run(&[path.as_os_str(), "--json".as_ref()]);
    let v: Value = serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {stdout}\nstderr: {stderr}"));
    (code, v)
}

#[test]
fn plane_fixture_text_report() {
    let (code, out, err) = run(&[fixture("plane_1cm_65.obj").as_os_str()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("vertices              4225"), "{out}");
    assert!(out.contains("triangles             8192"), "{out}");
    assert!(out.contains("area                  1.000000"), "{out}");
    assert!(out.contains("closed                no"), "{out}");
    assert!(out.contains("boundary loops        1"), "{out}");
    assert!(out.contains("loop 0: 256 edges, length 4.000000"), "{out}");
    assert!(out.contains("Euler characteristic  1"), "{out}");
    assert!(out.contains("defects               none"), "{out}");
}

#[test]
fn cube_fixture_json_report() {
    let (code, v) = json(&fixture("cube_2cm_386.obj"));
    assert_eq!(code, 0);
    assert_eq!(v["vertices"], 386);
    assert_eq!(v["triangles"], 768);
    assert_eq!(v["edges"], 1152);
    assert_eq!(v["closed"], true);
    assert_eq!(v["euler_characteristic"], 2);
    assert!((v["volume"].as_f64().unwrap() - 8.0).abs() < 1e-5);
    assert!((v["area"].as_f64().unwrap() - 24.0).abs() < 1e-5);
    assert_eq!(v["boundary_loops"].as_array().unwrap().len(), 0);
    assert_eq!(v["bounding_box"]["size"][0].as_f64().unwrap(), 2.0);
}

#[test]
fn binary_ply_fixture_loads() {
    let (code, v) = json(&fixture("plane_1cm_129.ply"));
    assert_eq!(code, 0);
    assert_eq!(v["vertices"], 16641);
    assert_eq!(v["triangles"], 32768);
    assert_eq!(v["boundary_loops"][0]["edges"], 512);
}

#[test]
fn broken_mesh_lists_every_defect_and_exits_with_the_mesh_code() {
    let (status, v) = json(&fixture("defects/broken.obj"));
    assert_eq!(status, code(Exit::Mesh));
    assert_eq!(v["loaded"], false);
    assert_eq!(v["vertices"], 11);
    assert_eq!(v["triangles"], 10);
    let kinds: Vec<(String, String)> = v["defects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| {
            (
                d["kind"].as_str().unwrap().to_string(),
                d["message"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    let has = |kind: &str, text: &str| kinds.iter().any(|(k, m)| k == kind && m.contains(text));
    assert!(has("DegenerateTriangle", "triangle 9 "), "{kinds:?}");
    assert!(
        has("DuplicateTriangle", "triangle 8 repeats triangle 3"),
        "{kinds:?}"
    );
    assert!(has("InconsistentWinding", "[0, 1]"), "{kinds:?}");
    assert!(has("InconsistentWinding", "[1, 4]"), "{kinds:?}");
    assert!(has("UnreferencedVertex", "vertex 9 "), "{kinds:?}");
    assert_eq!(kinds.len(), 5, "{kinds:?}");

    // The text form says the same, and stderr says why it was rejected.
    let (status, out, err) = run(&[fixture("defects/broken.obj").as_os_str()]);
    assert_eq!(status, code(Exit::Mesh));
    assert!(
        out.contains("defects               5 (4 errors, 1 warnings)"),
        "{out}"
    );
    assert!(err.contains("rejected"), "{err}");
}

#[test]
fn unreferenced_vertex_is_a_warning_and_loads() {
    let (code, out, _) = run(&[fixture("defects/unreferenced_vertex.obj").as_os_str()]);
    assert_eq!(code, 0);
    assert!(
        out.contains("warning: vertex 9 is not used by any element"),
        "{out}"
    );
    assert!(out.contains("area                  4.000000"), "{out}");
}

#[test]
fn unreadable_file_exits_with_the_input_code_naming_it() {
    let missing = fixture("no_such_mesh.obj");
    let (status, out, err) = run(&[missing.as_os_str()]);
    assert_eq!(status, code(Exit::Input));
    assert!(out.is_empty());
    assert!(err.contains("no_such_mesh.obj"), "{err}");

    let (status, _, err) = run(&[fixture("README.md").as_os_str()]);
    assert_eq!(status, code(Exit::Input));
    assert!(err.contains("README.md"), "{err}");
}

#[test]
fn real_open_scans_report_their_boundary_loops() {
    let dir = fixture("");
    for (file, v, f, edges) in [
        ("makehuman_head_open.obj", 4257, 8470, 42),
        ("makehuman_chest_open.obj", 4921, 9632, 208),
    ] {
        let (code, r) = json(&dir.join(file));
        assert_eq!(code, 0, "{file}");
        assert_eq!(r["vertices"], v, "{file}");
        assert_eq!(r["triangles"], f, "{file}");
        assert_eq!(r["closed"], false, "{file}");
        assert_eq!(r["euler_characteristic"], 1, "{file}");
        assert_eq!(r["components"], 1, "{file}");
        let loops = r["boundary_loops"].as_array().unwrap();
        assert_eq!(loops.len(), 1, "{file}");
        assert_eq!(loops[0]["edges"], edges, "{file}");
    }
}

#[test]
fn real_tet_mesh_reports_nodes_tets_and_closed_boundary() {
    let (code, r) = json(&fixture("armadillo_4k.node"));
    assert_eq!(code, 0, "{r}");
    assert_eq!(r["kind"], "tetrahedral");
    assert_eq!(r["vertices"], 1180);
    assert_eq!(r["tetrahedra"], 3717);
    assert_eq!(r["triangles"], 2102);
    assert_eq!(r["closed"], true);
    assert_eq!(r["euler_characteristic"], 2);
    assert!(r["volume"].as_f64().unwrap() > 0.0);
}

/// `meshinfo FILE | head -0`: the reader has gone before the first write. Regression: `println!`
/// panicked with "failed printing to stdout: Broken pipe"; now SIGPIPE ends the program (status
/// 141 in a shell) with nothing on stderr, for the text report, the JSON and clap's help.
#[cfg(unix)]
#[test]
fn broken_pipe_ends_meshinfo_quietly_by_sigpipe() {
    let cube = fixture("cube_2cm_386.obj");
    for args in [
        &[cube.as_os_str()][..],
        &[cube.as_os_str(), "--json".as_ref()],
        &["--help".as_ref()],
    ] {
        let mut command = Command::new(env!("CARGO_BIN_EXE_meshinfo"));
        command.args(args);
        tissue_cli::testing::close_stdout_after(command, 0).assert_killed_by_sigpipe();
    }
}

/// `meshinfo FILE | head -1` on a report far larger than a pipe holds (a grid with 4000 unused
/// vertices: one warning line each): the reader takes the first line and goes while meshinfo is
/// still writing. It must end quietly (here by SIGPIPE), text and JSON alike.
#[cfg(unix)]
#[test]
fn broken_pipe_after_the_first_line_ends_meshinfo_quietly() {
    let mut obj = std::fs::read_to_string(fixture("defects/unreferenced_vertex.obj")).unwrap();
    for i in 0..4000 {
        obj.push_str(&format!("v {i} 5 5\n"));
    }
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("meshinfo_many_unused_vertices.obj");
    std::fs::write(&path, obj).unwrap();
    for json in [false, true] {
        let mut command = Command::new(env!("CARGO_BIN_EXE_meshinfo"));
        command.arg(&path);
        if json {
            command.arg("--json");
        }
        let ended = tissue_cli::testing::close_stdout_after(command, 1);
        let first = if json { "{" } else { "file " };
        assert!(ended.read.starts_with(first), "{}", ended.read);
        ended.assert_quiet();
    }
}

#[test]
fn vtu_and_msh_tet_meshes_are_reported() {
    // The Gmsh box of fixtures/tets: 50 nodes, 107 tetrahedra, volume 3 cm³.
    for name in [
        "box_v1.msh",
        "box_v22_binary.msh",
        "box_v41_ascii.msh",
        "box_zlib.vtu",
        "box_appended_raw.vtu",
    ] {
        let (code, r) = json(&fixture("tets").join(name));
        assert_eq!(code, 0, "{name}: {r}");
        assert_eq!(r["kind"], "tetrahedral", "{name}");
        assert_eq!(r["vertices"], 50, "{name}");
        assert_eq!(r["tetrahedra"], 107, "{name}");
        assert_eq!(r["closed"], true, "{name}");
        assert!(
            (r["volume"].as_f64().unwrap() - 3.0).abs() < 1e-4,
            "{name}: {r}"
        );
    }
}

#[test]
fn unreadable_tet_files_say_why() {
    let (status, _, stderr) = run(&[fixture("tets/square_no_tets.vtu").as_os_str()]);
    assert_eq!(status, code(Exit::Mesh));
    assert!(stderr.contains("no tetrahedra"), "{stderr}");
    let (status, _, stderr) = run(&["organ.xyz".as_ref()]);
    assert_eq!(status, code(Exit::Input));
    assert!(
        stderr.contains("unsupported") && stderr.contains(".msh"),
        "{stderr}"
    );
}
