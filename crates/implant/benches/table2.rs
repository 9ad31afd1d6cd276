//! End-to-end timing of the thesis's Table 2 runs (a bench binary, not criterion: one run takes
//! seconds). `cargo bench -p tissue-implant --bench table2 [-- REPEATS]` runs the round 7 cm
//! implant of 50, 100 and 150 cm³ under the 20 cm plane of 4225 vertices with the default
//! parameters (or the volumes given after `REPEATS`), `REPEATS` times each (default 5), and prints per volume the median wall time,
//! the steps, the stop reason and the results (area gain, volume difference, compression).
//! `--membrane` adds, alternating with each default run, the same run without the skin's bending
//! (`LayerParams::skin_bending`, the thesis's membrane) and prints the ratio of the medians: what
//! the bending costs, measured in one run. `--quasi-static` adds, alternating likewise, the same
//! run with the quasi-static solver and prints both end-to-end medians (setup included), their
//! ratio, the solver's iterations and residual and its results.
#![allow(missing_docs, clippy::print_stdout)]

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use glam::Vec3;
use tissue_implant::{
    default_radius, place_implant, select_region_with, ImplantShape, ImplantSpec, Insertion,
    InsertionOutcome, InsertionParams, RegionOptions, RegionRule, Solver, TissueLayers,
};

fn table2_run(
    volume: f64,
    bending: bool,
    solver: Solver,
) -> Result<InsertionOutcome, Box<dyn std::error::Error>> {
    let patient = tissue_mesh::grid(65, 20.0)?;
    let selection = select_region_with(
        &patient,
        Vec3::ZERO,
        default_radius(3.5)?,
        &RegionOptions {
            rule: RegionRule::TouchesVertex,
            ..RegionOptions::default()
        },
    )?;
    let mut params = InsertionParams {
        solver,
        ..InsertionParams::default()
    };
    params.layers.skin_bending = bending;
    let layers = TissueLayers::new(selection.mesh(), &params.layers)?;
    let spec = ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume);
    let implant = place_implant(&layers, &spec, Vec3::ZERO, Vec3::Z, Vec3::X)?;
    let mut insertion = Insertion::new(selection.mesh(), &implant, &params)?;
    Ok(insertion.run(|_| ControlFlow::Continue(()))?)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Numbers among the arguments (cargo bench adds `--bench`): repeats, then volumes.
    let numbers: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let repeats = numbers.first().map_or(5, |&n| n.max(1.0) as usize);
    let membrane = std::env::args().any(|a| a == "--membrane");
    let statics = std::env::args().any(|a| a == "--quasi-static");
    let volumes = if numbers.len() > 1 {
        numbers[1..].to_vec()
    } else {
        vec![50.0, 100.0, 150.0]
    };
    println!("Table 2: 20 cm plane (4225 vertices), round 7 cm implant; median of {repeats}");
    println!("volume  wall(median)  steps  stop        gain cm²  vol.diff cm³  compression");
    for &volume in &volumes {
        let mut times: Vec<Duration> = Vec::new();
        let mut membrane_times: Vec<Duration> = Vec::new();
        let (mut whole, mut static_whole) = (Vec::new(), Vec::new());
        let mut last = None;
        let mut last_static = None;
        for _ in 0..repeats {
            let start = Instant::now();
            let out = table2_run(volume, true, Solver::Explicit)?;
            whole.push(start.elapsed());
            times.push(out.wall_time);
            last = Some(out);
            if membrane {
                membrane_times.push(table2_run(volume, false, Solver::Explicit)?.wall_time);
            }
            if statics {
                let start = Instant::now();
                last_static = Some(table2_run(volume, true, Solver::QuasiStatic)?);
                static_whole.push(start.elapsed());
            }
        }
        times.sort();
        membrane_times.sort();
        whole.sort();
        static_whole.sort();
        if let Some(out) = last {
            let median = times[times.len() / 2].as_secs_f64();
            println!(
                "{volume:>6}  {:>10.3} s  {:>5}  {:<10}  {:>8.2}  {:>12.2}  {:>10.3} %",
                median,
                out.steps,
                format!("{:?}", out.stop_reason),
                out.area_gain,
                out.volume_difference,
                100.0 * out.implant_compression
            );
            if let (Some(q), Some(e), Some(o)) = (
                static_whole.get(static_whole.len() / 2),
                whole.get(whole.len() / 2),
                &last_static,
            ) {
                println!(
                    "        end to end: explicit {:.3} s, quasi-static {:.3} s (× {:.2} faster); \
                     quasi-static {} iterations, residual {:.3e} N, {:?}, gain {:.2}, vol.diff \
                     {:.2}, penetration {:.4}",
                    e.as_secs_f64(),
                    q.as_secs_f64(),
                    e.as_secs_f64() / q.as_secs_f64(),
                    o.iterations,
                    o.residual_n.unwrap_or(f64::NAN),
                    o.stop_reason,
                    o.area_gain,
                    o.volume_difference,
                    o.max_penetration
                );
            }
            if let Some(m) = membrane_times.get(membrane_times.len() / 2) {
                println!(
                    "        without bending {:.3} s: bending costs × {:.3}",
                    m.as_secs_f64(),
                    median / m.as_secs_f64()
                );
            }
        }
    }
    Ok(())
}
