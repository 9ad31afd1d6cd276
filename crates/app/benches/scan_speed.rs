//! Issue 17's speed target: a planning case on a 160k-triangle scan, loading and writing
//! included, against Table 2's default case (100 cm³, round 7 cm, the 65² plane) measured in
//! the same run. Prints the median of each over `N` alternating repeats and their ratio
//! (target ≤ 5, aim 2).
//!
//! ```sh
//! cargo bench -p tissue-app --bench scan_speed            # 5 repeats
//! cargo bench -p tissue-app --bench scan_speed -- 9       # 9 repeats
//! ```
//!
//! The scan is `tissue-testscans`' noisy face (seed 1: 152 852 triangles, 0.5 mm edges, mm,
//! holes), written once as an OBJ to a temporary folder; each repeat reads it, plans a round
//! 2.5 cm, 2 cm³ expander at the forehead on the default simulation mesh, maps the result back
//! onto the scan and writes it as an OBJ. The Table 2 case generates its plane, plans on its
//! own grid and writes the deformed plane as an OBJ.
#![allow(clippy::print_stdout, clippy::unwrap_used, clippy::expect_used)]

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use glam::Vec3;
use tissue_app::{plan, InsertionJob, Placement, SimMesh};
use tissue_implant::{ImplantShape, ImplantSpec, RegionOptions, RegionRule};

fn median(mut d: Vec<Duration>) -> Duration {
    d.sort();
    d[d.len() / 2]
}

fn table2(dir: &std::path::Path) -> (Duration, u64) {
    let start = Instant::now();
    let plane = tissue_mesh::grid(65, 20.0).unwrap();
    let implant = ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, 100.0);
    let mut job = InsertionJob::new(plane, Placement::new(Vec3::ZERO, Vec3::Z, Vec3::X), implant);
    job.region = RegionOptions {
        rule: RegionRule::TouchesVertex,
        ..RegionOptions::default()
    };
    job.sim = SimMesh::Patient;
    let planned = plan(&job, |_| ControlFlow::Continue(())).unwrap();
    let after = planned.patient_after(&job.patient).unwrap();
    tissue_meshio::write_obj(dir.join("table2_after.obj"), &after).unwrap();
    (start.elapsed(), planned.outcome.steps)
}

fn scan_case(
    path: &std::path::Path,
    point_mm: Vec3,
    dir: &std::path::Path,
) -> (Duration, u64, usize) {
    let start = Instant::now();
    let mm = tissue_meshio::read_surface(path).unwrap();
    let cm = mm.positions().iter().map(|&p| p * 0.1).collect();
    let patient = mm.with_positions(cm).unwrap();
    let point = point_mm * 0.1;
    let implant = ImplantSpec::new(ImplantShape::Round { diameter: 2.5 }, 2.0);
    let mut normal = Vec3::Z;
    if let Some(v) = patient
        .positions()
        .iter()
        .position(|&p| p.distance(point) < 1e-4)
    {
        normal = patient.vertex_normals()[v];
    }
    let job = InsertionJob::new(patient, Placement::new(point, normal, Vec3::X), implant);
    let planned = plan(&job, |_| ControlFlow::Continue(())).unwrap();
    let after = planned.on_patient(&job.patient).unwrap();
    let back: Vec<Vec3> = after.mesh.positions().iter().map(|&p| p * 10.0).collect();
    let after_mm = mm.with_positions(back).unwrap();
    tissue_meshio::write_obj(dir.join("face_after.obj"), &after_mm).unwrap();
    let sim = planned
        .surface
        .as_ref()
        .map_or(0, |s| s.mesh().vertex_count());
    (start.elapsed(), planned.outcome.steps, sim)
}

fn main() {
    let repeats: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(5);
    let scan = match tissue_testscans::noisy_face_scan(1) {
        Ok(scan) => scan,
        Err(e) => {
            println!("scan_speed: skipped, {e}");
            return;
        }
    };
    let dir = std::env::temp_dir().join(format!("tissue-scan-speed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("face.obj");
    tissue_meshio::write_obj(&path, &scan.mesh).unwrap();
    let forehead = scan
        .points
        .iter()
        .find(|p| p.name == "forehead")
        .expect("forehead")
        .position;
    println!(
        "scan: {} vertices, {} triangles (mm); Table 2: 65² plane, 100 cm³; {repeats} alternating repeats",
        scan.mesh.vertex_count(),
        scan.mesh.triangle_count()
    );
    let (mut t2, mut sc) = (Vec::new(), Vec::new());
    for i in 0..repeats {
        let (a, steps_a) = table2(&dir);
        let (b, steps_b, sim) = scan_case(&path, forehead, &dir);
        println!(
            "  repeat {}: Table 2 {:.3} s ({steps_a} steps), scan {:.3} s ({steps_b} steps, {sim} sim vertices), ratio {:.2}",
            i + 1,
            a.as_secs_f64(),
            b.as_secs_f64(),
            b.as_secs_f64() / a.as_secs_f64()
        );
        t2.push(a);
        sc.push(b);
    }
    let (a, b) = (median(t2), median(sc));
    println!(
        "median: Table 2 {:.3} s, 160k-triangle scan {:.3} s, ratio {:.2} (target ≤ 5, aim 2)",
        a.as_secs_f64(),
        b.as_secs_f64(),
        b.as_secs_f64() / a.as_secs_f64()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
