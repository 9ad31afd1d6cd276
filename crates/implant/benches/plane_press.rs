//! End-to-end timing of the thesis's Table 1 plane press (a bench binary, not criterion: one
//! 257² run takes seconds to minutes). `cargo bench -p tissue-implant --bench plane_press
//! [-- REPEATS RESOLUTIONS…]` presses the 0.25 cm sphere into the 1 cm plane at each resolution
//! (default 257) `REPEATS` times (default 5) with the default parameters and prints the median
//! wall time, the steps, the step size and the area and volume after (thesis: 0.672 / 0.689 /
//! 0.698 cm² at 65² / 129² / 257², 97 s at 257² on the thesis's 2016 PC; target ≤ 5 s).
#![allow(missing_docs, clippy::print_stdout)]

use std::ops::ControlFlow;
use std::time::Duration;

use tissue_implant::{plane_press, plane_press_region, PlanePressParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Numbers among the arguments (cargo bench adds `--bench`): repeats, then resolutions.
    let numbers: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let repeats = numbers.first().map_or(5, |&n| n.max(1) as usize);
    let resolutions = if numbers.len() > 1 {
        numbers[1..].to_vec()
    } else {
        vec![257]
    };
    let params = PlanePressParams::default();
    println!(
        "Table 1 plane press: sphere r = {} cm at {} cm/s, layers {} cm apart; median of {repeats}",
        params.sphere_radius, params.speed, params.depth
    );
    println!("plane   wall(median)  steps  h (s)       area after cm²  volume cm³");
    for &n in &resolutions {
        let selection = plane_press_region(n)?;
        let mut times: Vec<Duration> = Vec::new();
        let mut last = None;
        for _ in 0..repeats {
            let out = plane_press(selection.mesh(), &params, |_| ControlFlow::Continue(()))?;
            times.push(out.wall_time);
            last = Some(out);
        }
        times.sort();
        if let Some(out) = last {
            println!(
                "{n:>4}²  {:>10.3} s  {:>5}  {:.3e}  {:>14.4}  {:>10.4}",
                times[times.len() / 2].as_secs_f64(),
                out.steps,
                out.time_step,
                out.area_after,
                out.volume_difference
            );
        }
    }
    Ok(())
}
