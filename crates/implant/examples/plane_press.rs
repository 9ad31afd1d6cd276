//! The plane press of SPEC Table 1: a 0.25 cm sphere (994 vertices) pushed from below into the
//! centre of a skin region of a 1 cm plane at 65², 129² and 257² vertices, with the thesis's
//! numbers beside ours.
//!
//! ```text
//! cargo run --release -p tissue-implant --example plane_press
//! cargo run --release -p tissue-implant --example plane_press -- 65 129   # some resolutions
//! cargo run --release -p tissue-implant --example plane_press -- --speed 200 65
//! cargo run --release -p tissue-implant --example plane_press -- --halving 65
//! ```
//!
//! `--halving` runs every resolution also at half the speed and prints the relative change of
//! the area and the volume (the check behind the default speed). The 257² run takes about
//! 4 508 steps at the default 100 cm/s (one to two minutes).
#![allow(clippy::print_stdout)]

use std::error::Error;
use std::ops::ControlFlow;

use tissue_implant::{plane_press, plane_press_region, PlanePressOutcome, PlanePressParams};

/// The thesis's Table 1 for a resolution: region vertices and triangles (both layers), springs,
/// area before and after (cm²), volume after (cm³), time (s).
fn thesis(n: u32) -> Option<(usize, usize, usize, f64, f64, f64, f64)> {
    match n {
        65 => Some((3922, 7504, 22176, 0.458, 0.672, 0.062, 11.0)),
        129 => Some((15090, 29512, 87872, 0.450, 0.689, 0.063, 31.0)),
        257 => Some((59154, 116984, 349632, 0.446, 0.698, 0.064, 97.0)),
        _ => None,
    }
}

fn run(n: u32, params: &PlanePressParams) -> Result<PlanePressOutcome, Box<dyn Error>> {
    let selection = plane_press_region(n)?;
    Ok(plane_press(selection.mesh(), params, |_| {
        ControlFlow::Continue(())
    })?)
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut params = PlanePressParams::default();
    let mut halving = false;
    let mut resolutions = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--speed" => {
                let value = args.next().ok_or("--speed needs a value (cm/s)")?;
                params.speed = value.parse()?;
            }
            "--halving" => halving = true,
            n => resolutions.push(n.parse::<u32>()?),
        }
    }
    if resolutions.is_empty() {
        resolutions = vec![65, 129, 257];
    }
    println!(
        "plane press: sphere r = {} cm ({}×{}), speed {} cm/s, layers {} cm apart",
        params.sphere_radius,
        params.sphere_resolution.0,
        params.sphere_resolution.1,
        params.speed,
        params.depth
    );
    for &n in &resolutions {
        let selection = plane_press_region(n)?;
        let region = selection.mesh();
        let out = plane_press(region, &params, |_| ControlFlow::Continue(()))?;
        let top =
            |m: &tissue_mesh::TriMesh| m.positions().iter().map(|p| p.z).fold(f32::MIN, f32::max);
        println!(
            "\n{n}² plane: {} vertices, {} triangles",
            n * n,
            2 * (n - 1) * (n - 1)
        );
        println!(
            "  region vertices / triangles (both layers): {} / {}",
            2 * region.vertex_count(),
            2 * region.triangle_count()
        );
        println!("  springs: {}", out.springs);
        println!(
            "  area before → after: {:.4} → {:.4} cm² (+{:.1} %)",
            out.area_before,
            out.area_after,
            100.0 * (out.area_after / out.area_before - 1.0)
        );
        println!("  volume after: {:.4} cm³", out.volume_difference);
        println!(
            "  steps: {}, h = {:.3e} s, speed {:.2} cm/s, travel {:.4} cm",
            out.steps, out.time_step, out.speed, out.travel
        );
        println!(
            "  wall time: {:.2} s (setup {:.3} s)",
            out.wall_time.as_secs_f64(),
            out.setup_time.as_secs_f64()
        );
        println!(
            "  end: tops skin {:.4}, layer 2 {:.4}, sphere {:.4} cm; penetration {:.2e} cm; \
             boundary unchanged: {}",
            top(&out.region_after),
            top(&out.inner_after),
            top(&out.sphere_after),
            out.max_penetration,
            out.boundary_unchanged
        );
        if let Some((v, t, s, a0, a1, vol, time)) = thesis(n) {
            println!(
                "  thesis: {v} / {t}, {s} springs, {a0:.3} → {a1:.3} cm², {vol:.3} cm³, {time} s"
            );
        }
        if halving {
            let slow = PlanePressParams {
                speed: 0.5 * params.speed,
                ..params.clone()
            };
            let half = run(n, &slow)?;
            println!(
                "  at {} cm/s: {:.4} cm², {:.4} cm³ in {} steps: area {:+.2} %, volume {:+.2} %",
                slow.speed,
                half.area_after,
                half.volume_difference,
                half.steps,
                100.0 * (half.area_after / out.area_after - 1.0),
                100.0 * (half.volume_difference / out.volume_difference - 1.0)
            );
        }
    }
    Ok(())
}
