//! The real `insert` binary, end to end: the default Table 2 run against the library, every
//! output format read back, the picture, a sweep, a target-gain search, each error's exit code and
//! message, and a Ctrl-C cancel.
//!
//! Small cases run on a coarse 12 cm plane of 17 × 17 vertices with a 4 cm implant (under a
//! second per run); the default Table 2 run takes a few seconds.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::{BufRead, BufReader};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use glam::Vec3;
use serde_json::Value;
use tissue_app::{InsertionJob, Placement, PlannedInsertion, SimMesh};
use tissue_cli::Exit;
use tissue_implant::{ImplantShape, ImplantSpec, RegionOptions, RegionRule};
use tissue_mesh::TriMesh;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_insert"))
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(name)
}

/// A test's scratch folder, `tissue-insert-<pid>-<name>` in the temporary directory. It is
/// removed when the guard drops, so a passing test leaves nothing behind; a failing test
/// (dropped while panicking) keeps it to be looked at.
struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// A fresh, empty scratch folder for one test, removed when the test passes.
fn scratch(name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("tissue-insert-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

/// The scratch guard removes its folder, with what a run wrote into it, when it drops.
#[test]
fn scratch_folders_are_removed_when_the_test_ends() {
    let dir = scratch("guard");
    let path = dir.to_path_buf();
    std::fs::create_dir_all(dir.join("nested")).unwrap();
    std::fs::write(dir.join("nested/report.json"), "{}").unwrap();
    assert!(path.join("nested/report.json").is_file());
    drop(dir);
    assert!(!path.exists(), "{} is left behind", path.display());
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The small test case: a 12 cm plane of 17 × 17 vertices, written in decimetres (so the
/// program scales it), and the same plane in cm as the program sees it.
const SMALL_ARGS: [&str; 10] = [
    "--unit",
    "dm",
    "--at",
    "0,0,0",
    "--diameter",
    "4",
    "--volume",
    "10",
    "--implant-vertices",
    "100",
];

fn small_plane(dir: &Path) -> (PathBuf, TriMesh) {
    let cm = tissue_mesh::grid(17, 12.0).unwrap();
    let dm_positions = cm.positions().iter().map(|&p| p / 10.0).collect();
    let dm = cm.with_positions(dm_positions).unwrap();
    let path = dir.join("plane_dm.obj");
    tissue_meshio::write_obj(&path, &dm).unwrap();
    // As the program reads and scales it.
    let read = tissue_meshio::read_surface(&path).unwrap();
    let scaled = read.positions().iter().map(|&p| p * 10.0).collect();
    (path, read.with_positions(scaled).unwrap())
}

fn small_job(patient: TriMesh, volume: f64) -> InsertionJob {
    let spec =
        ImplantSpec::new(ImplantShape::Round { diameter: 4.0 }, volume).with_vertex_budget(100);
    let mut job = InsertionJob::new(patient, Placement::new(Vec3::ZERO, Vec3::Z, Vec3::X), spec);
    job.region = RegionOptions {
        rule: RegionRule::TouchesVertex,
        ..RegionOptions::default()
    };
    job
}

fn plan(job: &InsertionJob) -> PlannedInsertion {
    tissue_app::plan(job, |_| ControlFlow::Continue(())).unwrap()
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

/// The report's results equal the library's run, field by field.
fn assert_report_matches(report: &Value, planned: &PlannedInsertion) {
    let o = &planned.outcome;
    let f = |name: &str| {
        report[name]
            .as_f64()
            .unwrap_or_else(|| panic!("report has no number {name}: {report}"))
    };
    assert_eq!(report["steps"].as_u64(), Some(o.steps));
    assert_eq!(report["iterations"].as_u64(), Some(o.iterations));
    assert_eq!(report["residual_n"].as_f64(), o.residual_n);
    assert!(
        report.get("residual_n").is_some(),
        "residual_n is always written"
    );
    for (name, value) in [
        ("area_before_cm2", o.area_before),
        ("area_after_cm2", o.area_after),
        ("area_gain_cm2", o.area_gain),
        ("volume_difference_cm3", o.volume_difference),
        ("implant_volume_cm3", o.implant_volume),
        ("implant_volume_end_cm3", o.implant_volume_after),
        ("implant_compression", o.implant_compression),
    ] {
        assert!(
            close(f(name), value),
            "{name}: report {} vs library {value}",
            f(name)
        );
    }
    // f32 results are written in f32's shortest form.
    for (name, value) in [
        ("max_displacement_cm", o.max_displacement),
        ("time_step_s", o.time_step),
    ] {
        assert_eq!(f(name) as f32, value, "{name}");
    }
    // The simulated region: the simulation surface on a remeshed run, else the patient's.
    let simulated = planned
        .surface
        .as_ref()
        .map_or(planned.selection.mesh(), |s| s.mesh());
    assert_eq!(
        report["region_vertices"].as_u64(),
        Some(simulated.vertex_count() as u64)
    );
    assert_eq!(
        report["scan_region_vertices"].as_u64(),
        Some(planned.selection.mesh().vertex_count() as u64)
    );
    match &planned.surface {
        Some(surface) => {
            assert_eq!(report["measured_on"], "simulation_surface");
            assert_eq!(report["inputs"]["sim_mesh"], "remeshed");
            assert_eq!(
                report["inputs"]["sim_edge_cm"].as_f64(),
                Some(surface.edge())
            );
            assert_eq!(report["scan"]["measured_on"], "scan_region_triangles");
            assert!(report["scan"]["area_gain_cm2"].as_f64().unwrap() > 0.0);
        }
        None => {
            assert_eq!(report["measured_on"], "patient_region");
            assert_eq!(report["inputs"]["sim_mesh"], "patient_triangles");
            assert!(report["inputs"]["sim_edge_cm"].is_null());
            assert!(report.get("scan").is_none());
        }
    }
    assert!(report["stop_reason"].is_string());
    assert!(f("wall_time_s") >= 0.0);
    assert!(report["inputs"].is_object());
}

#[test]
fn the_default_run_is_table_2_and_matches_the_library() {
    let dir = scratch("default");
    let report = dir.join("table2.json");
    let start = Instant::now();
    let o = run(&["--report", report.to_str().unwrap()]);
    let took = start.elapsed();
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));
    eprintln!("default run: {took:?}");

    // The Table 2 set-up, as crates/implant/benches/table2.rs has it.
    let patient = tissue_mesh::grid(65, 20.0).unwrap();
    let mut job = InsertionJob::new(
        patient,
        Placement::new(Vec3::ZERO, Vec3::Z, Vec3::X),
        ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, 100.0),
    );
    job.region = RegionOptions {
        rule: RegionRule::TouchesVertex,
        ..RegionOptions::default()
    };
    // The generated plane runs on its own grid, as the thesis's Table 2 did.
    job.sim = SimMesh::Patient;
    let planned = plan(&job);
    let o_lib = &planned.outcome;

    let out = stdout(&o);
    for expected in [
        format!("area before          {:.4} cm²", o_lib.area_before),
        format!("area after           {:.4} cm²", o_lib.area_after),
        format!("area gain            {:.4} cm²", o_lib.area_gain),
        format!("volume difference    {:.4} cm³", o_lib.volume_difference),
        format!(
            "implant compression  {:.4} %",
            100.0 * o_lib.implant_compression
        ),
        format!("steps                {} of at most", o_lib.steps),
    ] {
        assert!(out.contains(&expected), "stdout lacks {expected:?}:\n{out}");
    }
    let json = read_json(&report);
    assert_report_matches(&json, &planned);
    assert_eq!(json["mode"], "single");
    let inputs = &json["inputs"];
    assert_eq!(inputs["mesh_generated"], true);
    assert_eq!(inputs["mesh_vertices"], 4225);
    assert_eq!(inputs["volume_cm3"], 100.0);
    assert_eq!(inputs["region_rule"], "touches-vertex");
    assert_eq!(inputs["region_radius_cm"], 5.25);
    assert_eq!(inputs["shape"]["kind"], "round");
    assert_eq!(inputs["shape"]["diameter_cm"], 7.0);
    assert_eq!(inputs["normal"], serde_json::json!([0.0, 0.0, 1.0]));
    assert_eq!(inputs["tangent"], serde_json::json!([1.0, 0.0, 0.0]));
    assert_eq!(inputs["solver"], "explicit", "the default solver");
    assert_eq!(files_in(&dir), vec!["table2.json"]);
}

/// `--solver explicit` reaches the run and the report: the report's `inputs.solver`, the run's
/// iterations (the explicit solver's steps) and its null residual; the summary names the
/// solver. Beside `--job` the flag is refused, as every request flag is.
#[test]
fn the_solver_flag_reaches_the_report_and_is_refused_beside_a_job() {
    let dir = scratch("solver");
    let (mesh, patient) = small_plane(&dir);
    let report = dir.join("explicit.json");
    let mut args = vec!["--mesh", mesh.to_str().unwrap()];
    args.extend(SMALL_ARGS);
    args.extend([
        "--max-steps",
        "60",
        "--solver",
        "explicit",
        "--report",
        report.to_str().unwrap(),
    ]);
    let o = run(&args);
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));
    let json = read_json(&report);
    assert_eq!(json["inputs"]["solver"], "explicit");
    assert_eq!(json["steps"], 60);
    assert_eq!(
        json["iterations"], 60,
        "the explicit solver's iterations are its steps"
    );
    assert!(json["residual_n"].is_null(), "{}", json["residual_n"]);
    // The library's run of the same job with the explicit solver, field by field.
    let mut job = small_job(patient, 10.0);
    job.params.solver = tissue_implant::Solver::Explicit;
    job.params.run.stop.max_steps = 60;
    let planned = plan(&job);
    assert_eq!(planned.outcome.solver, tissue_implant::Solver::Explicit);
    assert_report_matches(&json, &planned);
    let out = stdout(&o);
    assert!(
        out.contains("solver               explicit: 60 iterations"),
        "{out}"
    );

    // A sweep runs with it too: every row has its iterations.
    let sweep_report = dir.join("sweep.json");
    let mut sweep = vec!["--mesh", mesh.to_str().unwrap()];
    sweep.extend(SMALL_ARGS);
    sweep.extend([
        "--max-steps",
        "40",
        "--solver",
        "explicit",
        "--sweep",
        "5,10",
        "--report",
        sweep_report.to_str().unwrap(),
    ]);
    let o = run(&sweep);
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));
    let json = read_json(&sweep_report);
    assert_eq!(json["inputs"]["solver"], "explicit");
    let runs = json["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    for r in runs {
        assert_eq!(r["iterations"], 40, "{r}");
        assert!(r["residual_n"].is_null(), "{r}");
    }

    // Beside --job, the flag is refused (the job file carries its own "solver").
    let job_file = dir.join("job.json");
    std::fs::write(&job_file, r#"{"request": {"solver": "explicit"}}"#).unwrap();
    assert_fails(
        &[
            "--job",
            job_file.to_str().unwrap(),
            "--solver",
            "quasi_static",
        ],
        Exit::Usage,
        &["--job takes the whole job"],
    );
    // An unknown solver is clap's usage error, with the names it takes.
    let o = run(&["--solver", "implicit"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("quasi_static") && err.contains("explicit"),
        "{err}"
    );
    // In a job file, an unknown solver is refused naming the field and the names.
    std::fs::write(&job_file, r#"{"request": {"solver": "implicit"}}"#).unwrap();
    assert_fails(
        &["--job", job_file.to_str().unwrap()],
        Exit::Usage,
        &["`solver`", "`explicit` or `quasi_static`"],
    );
    let mut written = files_in(&dir);
    written.sort();
    assert_eq!(
        written,
        vec!["explicit.json", "job.json", "plane_dm.obj", "sweep.json"]
    );
}

#[test]
fn the_default_plane_is_the_fixture() {
    let fixture = tissue_meshio::read_surface(fixture("plane_20cm_65.obj")).unwrap();
    assert_eq!(fixture, tissue_mesh::grid(65, 20.0).unwrap());
}

#[test]
fn the_makehuman_fixtures_are_open_patches() {
    for (name, vertices, triangles) in [
        ("makehuman_chest_open.obj", 4921, 9632),
        ("makehuman_head_open.obj", 4257, 8470),
    ] {
        let mesh = tissue_meshio::read_surface(fixture(name)).unwrap();
        assert_eq!(
            (mesh.vertex_count(), mesh.triangle_count()),
            (vertices, triangles)
        );
        assert!(!mesh.is_closed(), "{name}");
    }
}

#[test]
fn every_output_format_round_trips_and_the_picture_is_drawn() {
    let dir = scratch("formats");
    let (mesh, patient) = small_plane(&dir);
    let path = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    let (obj, ply, stl, vtk, png, report) = (
        path("after.obj"),
        path("after.ply"),
        path("after.stl"),
        path("after.vtk"),
        path("after.png"),
        path("report.json"),
    );
    let mut args = vec!["--mesh", mesh.to_str().unwrap()];
    args.extend(SMALL_ARGS);
    args.extend([
        "--out",
        &obj,
        "--out",
        &ply,
        "--out",
        &stl,
        "--out",
        &vtk,
        "--png",
        &png,
        "--png-size",
        "640x360",
        "--color",
        "stretch",
        "--report",
        &report,
    ]);
    let o = run(&args);
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));

    let job = small_job(patient.clone(), 10.0);
    let planned = plan(&job);
    assert_report_matches(&read_json(Path::new(&report)), &planned);
    // The library's result, back in the file's unit (dm).
    let expected = planned.patient_after(&patient).unwrap();
    let expected: Vec<Vec3> = expected.positions().iter().map(|&p| p / 10.0).collect();
    let near =
        |a: Vec3, b: Vec3| (a - b).abs().max_element() <= 1e-6 * b.abs().max_element().max(1.0);
    let moved = expected
        .iter()
        .zip(tissue_meshio::read_surface(&mesh).unwrap().positions())
        .filter(|(a, b)| a != b)
        .count();
    assert!(moved > 10, "the run moved only {moved} vertices");

    for file in [&obj, &ply, &vtk] {
        let back = tissue_meshio::read_surface(file).unwrap();
        assert_eq!(back.vertex_count(), expected.len(), "{file}");
        assert_eq!(back.triangles(), patient.triangles(), "{file}");
        for (v, (&a, &b)) in back.positions().iter().zip(&expected).enumerate() {
            assert!(near(a, b), "{file}: vertex {v} is {a}, the library's {b}");
        }
    }
    // STL stores corners: compare triangle by triangle.
    let back = tissue_meshio::read_surface(&stl).unwrap();
    assert_eq!(back.vertex_count(), expected.len());
    assert_eq!(back.triangle_count(), patient.triangle_count());
    for (t, tri) in patient.triangles().iter().enumerate() {
        let corners = back.corners(t);
        for (k, &v) in tri.iter().enumerate() {
            assert!(near(corners[k], expected[v as usize]), "stl triangle {t}");
        }
    }
    // VTK carries the fields, zero outside the region.
    let data = tissue_meshio::read_vtk(&vtk).unwrap();
    let field = |name: &str| -> Vec<f32> {
        let f = data
            .fields
            .iter()
            .find(|f| f.name == name)
            .unwrap_or_else(|| panic!("no field {name}"));
        match &f.values {
            tissue_meshio::PointValues::Scalars(v) => v.clone(),
            other => panic!("{name} is {other:?}"),
        }
    };
    let (displacement, stretch) = (field("displacement"), field("stretch"));
    assert_eq!(displacement.len(), expected.len());
    assert_eq!(stretch.len(), expected.len());
    // The fields are on the scan's own vertices (mapped from the simulation surface).
    let on_patient = planned.on_patient(&job.patient).unwrap();
    let max = displacement.iter().copied().fold(0.0, f32::max);
    let lib_max = on_patient.displacement.iter().copied().fold(0.0, f32::max);
    assert!((max - lib_max / 10.0).abs() < 1e-6, "{max} vs {lib_max} cm");
    let in_region = field("in_region");
    for v in 0..expected.len() {
        if in_region[v] == 0.0 {
            assert_eq!((displacement[v], stretch[v]), (0.0, 0.0));
        } else {
            assert!(stretch[v] > 0.0);
        }
    }

    // The picture: the size asked for, and not blank.
    let decoder = png::Decoder::new(std::fs::File::open(&png).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (640, 360));
    let channels = info.color_type.samples();
    let mut colours: Vec<&[u8]> = buf[..info.buffer_size()].chunks(channels).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 50, "only {} colours", colours.len());

    // Nothing else left in the folder (no temporary files).
    assert_eq!(
        files_in(&dir),
        vec![
            "after.obj",
            "after.ply",
            "after.png",
            "after.stl",
            "after.vtk",
            "plane_dm.obj",
            "report.json"
        ]
    );
}

#[test]
fn a_sweep_prints_one_row_per_run() {
    let dir = scratch("sweep");
    let (mesh, _) = small_plane(&dir);
    let report = dir.join("sweep.json");
    let mut args = vec!["--mesh", mesh.to_str().unwrap()];
    args.extend(SMALL_ARGS);
    args.extend(["--sweep", "5,10", "--report", report.to_str().unwrap()]);
    let o = run(&args);
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));
    let out = stdout(&o);
    let rows: Vec<&str> = out
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    assert_eq!(rows.len(), 2, "{out}");
    assert!(rows[0].trim_start().starts_with("5.000"), "{out}");
    assert!(rows[1].trim_start().starts_with("10.000"), "{out}");
    let json = read_json(&report);
    assert_eq!(json["mode"], "sweep");
    let runs = json["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    let gain = |i: usize| runs[i]["area_gain_cm2"].as_f64().unwrap();
    assert!(gain(1) > gain(0), "a larger implant stretches more: {json}");
}

#[test]
fn a_target_gain_search_prints_its_runs_and_the_volume() {
    let dir = scratch("inverse");
    let (mesh, _) = small_plane(&dir);
    let mut args = vec!["--mesh", mesh.to_str().unwrap()];
    args.extend(SMALL_ARGS);
    args.extend([
        "--target-gain",
        "4",
        "--bracket",
        "5,20",
        "--gain-tolerance",
        "1",
    ]);
    let o = run(&args);
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));
    let out = stdout(&o);
    let runs = out
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .count();
    assert!(runs >= 2, "{out}");
    let answer = out
        .lines()
        .find_map(|l| l.strip_prefix("answer: "))
        .unwrap_or_else(|| panic!("no answer line:\n{out}"));
    let volume: f64 = answer.split_whitespace().next().unwrap().parse().unwrap();
    assert!((5.0..=20.0).contains(&volume), "{answer}");
    assert!(answer.contains(&format!("{runs} runs")), "{out}");
}

/// Runs with `args`, expects exit `code` and one `insert: error:` line containing `words`.
fn assert_fails(args: &[&str], code: Exit, words: &[&str]) {
    let o = run(args);
    let err = stderr(&o);
    assert_eq!(
        o.status.code(),
        Some(code.code().into()),
        "{args:?}: stderr {err}"
    );
    let errors: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("insert: error:"))
        .collect();
    assert_eq!(errors.len(), 1, "{args:?}: stderr {err}");
    for w in words {
        assert!(
            errors[0].contains(w),
            "{args:?}: {:?} lacks {w:?}",
            errors[0]
        );
    }
    assert!(stdout(&o).is_empty(), "{args:?}: stdout {}", stdout(&o));
}

#[test]
fn each_error_has_its_exit_code_and_a_message_that_says_what_to_change() {
    let dir = scratch("errors");
    let (small, _) = small_plane(&dir);
    let small = small.to_str().unwrap();
    let garbage = dir.join("garbage.obj");
    std::fs::write(&garbage, "this is not a mesh\nv 1 2\nf 1 2 3\n").unwrap();
    let cube = fixture("cube_2cm_386.obj");
    let plane_1cm = fixture("plane_1cm_65.obj");
    let missing = dir.join("missing.obj");

    assert_fails(
        &["--mesh", missing.to_str().unwrap(), "--at", "0,0,0"],
        Exit::Input,
        &["cannot read", "--mesh"],
    );
    assert_fails(
        &["--mesh", garbage.to_str().unwrap(), "--at", "0,0,0"],
        Exit::Mesh,
        &["malformed", "line 2"],
    );
    // A closed surface is taken as it is; this 2 cm cube is too small for the region.
    assert_fails(
        &["--mesh", cube.to_str().unwrap(), "--at", "0,0,1"],
        Exit::Placement,
        &["covers the whole surface", "smaller --radius"],
    );
    assert_fails(
        &["--at", "0,0,5"],
        Exit::Placement,
        &["from the surface", "--at"],
    );
    assert_fails(
        &["--vertex", "99999"],
        Exit::Placement,
        &["out of range", "4225"],
    );
    assert_fails(
        &["--volume", "0"],
        Exit::Parameters,
        &["--volume", "positive"],
    );
    assert_fails(
        &["--volume=-5"],
        Exit::Parameters,
        &["--volume", "positive"],
    );
    assert_fails(
        &["--diameter", "0"],
        Exit::Parameters,
        &["--diameter", "positive"],
    );
    assert_fails(
        &["--mesh", plane_1cm.to_str().unwrap(), "--at", "0,0,0"],
        Exit::Placement,
        &["covers the whole surface", "smaller --radius"],
    );
    let mut diverging = vec!["--mesh", small];
    diverging.extend(SMALL_ARGS);
    diverging.extend(["--time-step", "1e-3"]);
    assert_fails(&diverging, Exit::Run, &["diverged", "--time-step"]);
    let nowhere = dir.join("no/such/folder/out.obj");
    assert_fails(
        &["--out", nowhere.to_str().unwrap()],
        Exit::Output,
        &["does not exist"],
    );
    assert_fails(&["--mesh", small], Exit::Usage, &["--at", "--vertex"]);
    // clap's own usage errors: exit 2.
    assert_eq!(run(&["--no-such-flag"]).status.code(), Some(2));
    assert_eq!(run(&["--out", "x.xyz"]).status.code(), Some(2));
    // Nothing was written anywhere in the scratch folder.
    assert_eq!(files_in(&dir), vec!["garbage.obj", "plane_dm.obj"]);
}

#[test]
fn help_documents_units_exit_codes_and_the_report() {
    let o = run(&["--help"]);
    assert_eq!(o.status.code(), Some(0));
    let help = stdout(&o);
    for needle in [
        "--young <KPA>",
        "kPa",
        "EXIT CODES",
        "130",
        // The report's fields are documented once, in the planner's rustdoc, with a golden
        // report per mode: the help points there instead of copying the list.
        "schema_version",
        "tissue_planner::report",
        "fixtures/reports/",
        "mesh's unit",
        // The crescent's bend radius as the check asks it (the help once said "the width").
        "at least 1.5 × the width",
    ] {
        assert!(help.contains(needle), "--help lacks {needle:?}");
    }
}

/// `--solver` lists its values, in the JSON's names, in the short and the long help, with the
/// default.
#[test]
fn help_lists_the_solvers() {
    for flag in ["-h", "--help"] {
        let help = stdout(&run(&[flag]));
        let section = help
            .lines()
            .skip_while(|l| !l.contains("--solver <SOLVER>"))
            .take_while(|l| !l.contains("--max-steps"))
            .collect::<Vec<_>>()
            .join(" ");
        for needle in [
            "quasi_static",
            "explicit",
            "[default: explicit]",
            "every mode",
        ] {
            assert!(
                section.to_lowercase().contains(&needle.to_lowercase()),
                "{flag}: the --solver help lacks {needle:?}: {section}"
            );
        }
        assert!(!section.contains("quasi-static"), "{flag}: {section}");
    }
}

/// `--time-step`'s help gives the factor of the stability limit the library's automatic step
/// uses (regression: it said half, the library used 0.8).
#[test]
fn help_gives_the_automatic_steps_factor_the_library_uses() {
    let factor = tissue_implant::InsertionParams::default().run.step_safety;
    assert_eq!(factor, tissue_implant::RunParams::DEFAULT_STEP_SAFETY);
    for flag in ["-h", "--help"] {
        let help = stdout(&run(&[flag]));
        let line = help
            .lines()
            .skip_while(|l| !l.contains("--time-step"))
            .take(4)
            .collect::<Vec<_>>()
            .join(" ");
        let line = line.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            line.contains(&format!("automatic, {factor} × the stability limit")),
            "{flag}: {line}"
        );
        assert!(!line.contains("half"), "{flag}: {line}");
    }
}

#[test]
fn ctrl_c_cancels_cleanly_and_writes_nothing() {
    let dir = scratch("cancel");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    let mut child = bin()
        .args([
            "--out",
            &path("after.vtk"),
            "--report",
            &path("report.json"),
            "--png",
            &path("after.png"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first progress line: the run has started.
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let line = lines
            .next()
            .unwrap_or_else(|| panic!("stderr closed before the run started"))
            .unwrap();
        if line.contains("step ") {
            break;
        }
        assert!(Instant::now() < deadline, "no progress line");
    }
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let exit = child.wait().unwrap();
    assert_eq!(
        exit.code(),
        Some(Exit::Interrupted.code().into()),
        "stderr after the signal: {rest:?}"
    );
    assert!(
        rest.iter().any(|l| l.contains("interrupted")),
        "stderr after the signal: {rest:?}"
    );
    assert!(files_in(&dir).is_empty(), "left: {:?}", files_in(&dir));
}

#[test]
fn the_readme_chest_example_runs_to_completion() {
    let mesh = fixture("makehuman_chest_open.obj");
    let dir = scratch("chest");
    let report = dir.join("chest.json");
    let o = run(&[
        "--mesh",
        mesh.to_str().unwrap(),
        "--unit",
        "dm",
        "--vertex",
        "2277",
        "--diameter",
        "6.5",
        "--volume",
        "50",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "stderr: {}", stderr(&o));
    let json = read_json(&report);
    assert_eq!(json["stop_reason"], "settled");
    assert!(json["area_gain_cm2"].as_f64().unwrap() > 0.0);
    assert_eq!(json["inputs"]["unit"], "dm");
}

/// `insert … | head -0`: the reader has gone before the first write. Regression: `println!`
/// panicked with "failed printing to stdout: Broken pipe" (exit 101); now SIGPIPE ends the
/// program (status 141 in a shell) with nothing on stderr and no file or temporary file written,
/// for a single run, a sweep and clap's help.
#[cfg(unix)]
#[test]
fn broken_pipe_ends_insert_quietly_by_sigpipe() {
    let dir = scratch("broken-pipe");
    let (mesh, _) = small_plane(&dir);
    let report = dir.join("report.json");
    for mode in [&[][..], &["--sweep", "5,10"]] {
        let mut run = bin();
        run.args(["--mesh", mesh.to_str().unwrap(), "--quiet"])
            .args(SMALL_ARGS)
            .args(mode)
            .args(["--report", report.to_str().unwrap()]);
        tissue_cli::testing::close_stdout_after(run, 0).assert_killed_by_sigpipe();
        assert_eq!(files_in(&dir), ["plane_dm.obj"], "{mode:?}");
    }

    let mut help = bin();
    help.arg("--help");
    tissue_cli::testing::close_stdout_after(help, 0).assert_killed_by_sigpipe();
}

#[test]
fn a_closed_body_is_taken_as_it_is_and_the_region_cut_out_of_it() {
    // Regression (issue 17): a watertight body was refused with "the skin must be an open scan
    // patch". The MakeHuman body (dm, closed, CC0) ships in fixtures/.
    let body = fixture("makehuman_body_closed.obj");
    let dir = scratch("closed_body");
    let out = dir.join("body_after.obj");
    let o = run(&[
        "--mesh",
        body.to_str().unwrap(),
        "--unit",
        "dm",
        "--at",
        "0,1.5716,1.4268", // the belly, on the midline below the navel
        "--volume",
        "50",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("(settled)"), "{}", stdout(&o));
    let before = tissue_meshio::read_surface(&body).unwrap();
    let after = tissue_meshio::read_surface(&out).unwrap();
    assert!(after.is_closed());
    assert_eq!(after.triangles(), before.triangles());
    // The belly rose; the back did not move.
    let moved: Vec<usize> = (0..before.vertex_count())
        .filter(|&v| before.positions()[v] != after.positions()[v])
        .collect();
    assert!(!moved.is_empty());
    assert!(moved
        .iter()
        .all(|&v| before.positions()[v].z > 0.5 && (before.positions()[v].y - 1.57).abs() < 0.6));
}

#[test]
fn an_expansion_prints_its_weeks_and_band_and_writes_its_report_and_chart() {
    let dir = scratch("expansion");
    let (mesh, _) = small_plane(&dir);
    let report = dir.join("expansion.json");
    let chart = dir.join("expansion.png");
    let o = run(&[
        "--mesh",
        mesh.to_str().unwrap(),
        "--unit",
        "dm",
        "--at",
        "0,0,0",
        "--diameter",
        "4",
        "--volume",
        "12",
        "--scan-triangles",
        "--expand-weeks",
        "2",
        "--hold-weeks",
        "0.5",
        "--band-samples",
        "8",
        "--seed",
        "5",
        "--report",
        report.to_str().unwrap(),
        "--chart",
        chart.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    for needle in [
        "expansion: 2 fills",
        "flap after removal",
        "efficiency",
        "band (8 samples, seed 5)",
    ] {
        assert!(out.contains(needle), "no {needle:?} in:\n{out}");
    }
    let json = read_json(&report);
    assert_eq!(json["mode"], "expansion");
    assert_eq!(json["inputs"]["expand_weeks"], 2);
    assert_eq!(json["band"]["samples"], 8);
    assert!(json["flap"]["flap_area_cm2"].as_f64().unwrap() > 0.0);
    assert!(!json["weeks"].as_array().unwrap().is_empty());
    let png = std::fs::read(&chart).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn a_bad_protocol_is_refused_naming_its_flag() {
    let o = run(&["--expand-weeks", "10", "--leakage", "0.95"]);
    assert_eq!(o.status.code(), Some(6), "{}", stderr(&o));
    assert!(stderr(&o).contains("--leakage"), "{}", stderr(&o));
    let o = run(&["--expand-weeks", "0"]);
    assert_eq!(o.status.code(), Some(6), "{}", stderr(&o));
    assert!(stderr(&o).contains("--expand-weeks"), "{}", stderr(&o));
}

/// `--save`: the run stored in the case library (`tests/cli/save.rs`).
#[path = "cli/save.rs"]
mod save;
