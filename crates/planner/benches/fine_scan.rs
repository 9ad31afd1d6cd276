//! Issue 31 (part 7): a scan as fine as scanners make them, planned through the front door
//! (read the file, place, prepare, run, map back, write), against the Table 2 case measured in
//! the same run. A bench binary, not criterion: one plan takes seconds.
//!
//! ```sh
//! cargo bench -p tissue-planner --bench fine_scan                 # 3 repeats, 2 subdivisions
//! cargo bench -p tissue-planner --bench fine_scan -- 5 1          # 5 repeats, 1 subdivision
//! ```
//!
//! The scan is `tissue_testscans::fine_face_scan(1, S, 770 mm along x)`: the noisy face (mm)
//! midpoint-subdivided `S` times (2: about 2.6 million triangles, 0.125 mm edges) with six
//! holes whose loops have straight runs of collinear vertices, 77 cm from the origin in `f32`,
//! written once as a binary PLY to a temporary folder. Each repeat reads it, plans a round
//! 2.5 cm, 2 cm³ expander at the forehead (as `crates/app/benches/scan_speed.rs`), maps the
//! result back onto the scan and writes it as a binary PLY. The Table 2 case is the shipped
//! plane with the default request (100 cm³, round 7 cm), its result written as an OBJ.
//!
//! Printed: per repeat the wall times and the phases (the `tracing` spans of the planner, the
//! app and the libraries, summed by name), then the medians and their ratio, and the peak
//! resident memory of the scan's plans (`VmHWM` of `/proc/self/status`, reset through
//! `/proc/self/clear_refs` after the scan is generated and written, so it counts the plan and
//! what the process holds anyway).
#![allow(clippy::print_stdout, clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glam::Vec3;
use tissue_planner::{CancelToken, JobSpec, Patient, PlanRequest, Scenario, Tool, Unit};
use tracing::span;
use tracing_subscriber::layer::{Context, SubscriberExt};
use tracing_subscriber::registry::LookupSpan;
use tracing_subscriber::Layer;

/// Sums the busy-or-not wall time of every span by name.
#[derive(Clone, Default)]
struct Phases(Arc<Mutex<BTreeMap<&'static str, (Duration, u32)>>>);

struct Started(Instant);

impl<S> Layer<S> for Phases
where
    S: tracing::Subscriber + for<'a> LookupSpan<'a>,
{
    fn on_new_span(&self, _: &span::Attributes<'_>, id: &span::Id, ctx: Context<'_, S>) {
        if let Some(span) = ctx.span(id) {
            span.extensions_mut().insert(Started(Instant::now()));
        }
    }

    fn on_close(&self, id: span::Id, ctx: Context<'_, S>) {
        if let Some(span) = ctx.span(&id) {
            if let Some(Started(t)) = span.extensions().get::<Started>() {
                let mut map = self.0.lock().unwrap();
                let e = map.entry(span.name()).or_default();
                e.0 += t.elapsed();
                e.1 += 1;
            }
        }
    }
}

impl Phases {
    fn take(&self) -> BTreeMap<&'static str, (Duration, u32)> {
        std::mem::take(&mut *self.0.lock().unwrap())
    }
}

/// `VmHWM` (peak resident set) and `VmRSS` of this process, MiB.
fn memory_mib() -> (f64, f64) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let field = |name: &str| {
        status
            .lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kb| kb.parse::<f64>().ok())
            .map_or(f64::NAN, |kb| kb / 1024.0)
    };
    (field("VmHWM:"), field("VmRSS:"))
}

/// Resets `VmHWM` to the current resident set (Linux ≥ 4.0).
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

fn median(mut d: Vec<Duration>) -> Duration {
    d.sort();
    d[d.len() / 2]
}

fn table2(dir: &Path) -> Duration {
    let start = Instant::now();
    let scenario = Scenario::new(Patient::table2().unwrap(), PlanRequest::default()).unwrap();
    let finished = JobSpec::default()
        .plan(&scenario)
        .unwrap()
        .run(&scenario, Tool::Insert, &CancelToken::new(), |_| {})
        .unwrap();
    finished
        .patient
        .unwrap()
        .write_mesh(&dir.join("table2_after.obj"))
        .unwrap();
    start.elapsed()
}

fn scan_case(path: &Path, vertex: u32, dir: &Path) -> Duration {
    let start = Instant::now();
    let patient = {
        let _span = tracing::info_span!("bench_read").entered();
        Patient::read(path, Unit::Mm).unwrap()
    };
    let request = PlanRequest {
        vertex: Some(vertex),
        diameter_cm: 2.5,
        volume_cm3: 2.0,
        ..PlanRequest::default()
    };
    let scenario = {
        let _span = tracing::info_span!("bench_place").entered();
        Scenario::new(patient, request).unwrap()
    };
    let finished = JobSpec::default()
        .plan(&scenario)
        .unwrap()
        .run(&scenario, Tool::Insert, &CancelToken::new(), |_| {})
        .unwrap();
    {
        let _span = tracing::info_span!("bench_write").entered();
        finished
            .patient
            .unwrap()
            .write_mesh(&dir.join("face_after.ply"))
            .unwrap();
    }
    start.elapsed()
}

fn main() {
    let numbers: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let repeats = numbers.first().map_or(3, |&n| n.max(1) as usize);
    let subdivisions = numbers.get(1).copied().unwrap_or(2);
    let phases = Phases::default();
    let subscriber = tracing_subscriber::registry().with(phases.clone());
    tracing::subscriber::set_global_default(subscriber).unwrap();

    let dir = std::env::temp_dir().join(format!("tissue-fine-scan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("fine_face.ply");
    let offset = Vec3::new(770.0, 0.0, 0.0);
    let generated = Instant::now();
    let (vertex, triangles) = match tissue_testscans::fine_face_scan(1, subdivisions, offset) {
        Ok(scan) => {
            tissue_meshio::write_ply(&path, &scan.mesh).unwrap();
            let forehead = scan.points.iter().find(|p| p.name == "forehead").unwrap();
            (forehead.vertex, scan.mesh.triangle_count())
        }
        Err(e) => {
            println!("fine_scan: skipped, {e}");
            return;
        }
    };
    let bytes = std::fs::metadata(&path).map_or(0, |m| m.len());
    println!(
        "scan: fine face, {subdivisions} subdivisions, {triangles} triangles, 77 cm from the \
         origin, {:.0} MB PLY (made in {:.1} s); Table 2: the shipped plane, default request; \
         {repeats} alternating repeats",
        bytes as f64 / 1e6,
        generated.elapsed().as_secs_f64()
    );
    phases.take();
    let (mut t2, mut sc) = (Vec::new(), Vec::new());
    let mut peak = 0.0f64;
    for i in 0..repeats {
        let a = table2(&dir);
        phases.take();
        reset_peak();
        let (_, rss_before) = memory_mib();
        let b = scan_case(&path, vertex, &dir);
        let (hwm, _) = memory_mib();
        peak = peak.max(hwm);
        let spans = phases.take();
        println!(
            "  repeat {}: Table 2 {:.3} s, scan {:.3} s, ratio {:.2}; peak {:.0} MiB (from {:.0} MiB)",
            i + 1,
            a.as_secs_f64(),
            b.as_secs_f64(),
            b.as_secs_f64() / a.as_secs_f64(),
            hwm,
            rss_before
        );
        let mut line = String::from("    phases:");
        for (name, (d, n)) in &spans {
            if d.as_secs_f64() >= 0.005 {
                line += &format!(" {name} {:.3}", d.as_secs_f64());
                if *n > 1 {
                    line += &format!("(×{n})");
                }
            }
        }
        println!("{line}");
        t2.push(a);
        sc.push(b);
    }
    let (a, b) = (median(t2), median(sc));
    println!(
        "median: Table 2 {:.3} s, {triangles}-triangle scan {:.3} s, ratio {:.2} (target ≤ 3); \
         peak memory {peak:.0} MiB (target ≤ 1024)",
        a.as_secs_f64(),
        b.as_secs_f64(),
        b.as_secs_f64() / a.as_secs_f64()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
