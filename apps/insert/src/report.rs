//! The tables on stdout. The `--report` JSON is the planner's contract
//! ([`tissue_planner::report`]).

use std::fmt::Write as _;

use tissue_planner::report::{Inputs, RunResult, ShapeInputs};

/// The summary table of one run, for stdout.
pub fn summary(inputs: &Inputs, r: &RunResult) -> String {
    let mut s = String::new();
    let shape = match inputs.shape {
        ShapeInputs::Round { diameter_cm } => format!("round {diameter_cm} cm"),
        ShapeInputs::Rectangular {
            length_cm,
            width_cm,
            ..
        } => format!("rectangular {length_cm} x {width_cm} cm"),
        ShapeInputs::Crescent {
            length_cm,
            width_cm,
            ..
        } => format!("crescent {length_cm} x {width_cm} cm"),
    };
    let _ = writeln!(
        s,
        "implant insertion: {shape}, {} cm³, {} cm deep, under {}",
        inputs.volume_cm3, inputs.depth_cm, inputs.mesh
    );
    let stop = match r.stop_reason {
        "settled" => "settled",
        _ => "step limit reached: not settled",
    };
    let rows: [(&str, String); 12] = [
        (
            "region",
            format!(
                "{} vertices, {} triangles, radius {:.4} cm",
                r.region_vertices, r.region_triangles, r.region_radius_cm
            ),
        ),
        ("area before", format!("{:.4} cm²", r.area_before_cm2)),
        ("area after", format!("{:.4} cm²", r.area_after_cm2)),
        ("area gain", format!("{:.4} cm²", r.area_gain_cm2)),
        (
            "volume difference",
            format!("{:.4} cm³", r.volume_difference_cm3),
        ),
        ("implant volume", format!("{:.4} cm³", r.implant_volume_cm3)),
        (
            "implant volume end",
            format!("{:.4} cm³", r.implant_volume_end_cm3),
        ),
        (
            "implant compression",
            format!("{:.4} %", 100.0 * r.implant_compression),
        ),
        (
            "max displacement",
            format!("{:.4} cm", r.max_displacement_cm),
        ),
        (
            "steps",
            format!("{} of at most {} ({stop})", r.steps, r.max_steps),
        ),
        ("time step", format!("{:.4e} s", r.time_step_s)),
        ("wall time", format!("{:.3} s", r.wall_time_s)),
    ];
    for (name, value) in rows {
        let _ = writeln!(s, "  {name:<20} {value}");
    }
    if let Some(edge) = inputs.sim_edge_cm {
        let _ = writeln!(
            s,
            "  {:<20} remeshed to {edge:.4} cm edges ({} scan vertices in the region); areas \
             and volume above are on it",
            "simulation mesh", r.scan_region_vertices
        );
    }
    if let Some(scan) = &r.scan {
        let _ = writeln!(
            s,
            "  {:<20} area {:.4} → {:.4} cm² (gain {:.4}), volume difference {:.4} cm³, \
             {} holes filled, seam moves ≤ {:.4} cm",
            "on the scan",
            scan.area_before_cm2,
            scan.area_after_cm2,
            scan.area_gain_cm2,
            scan.volume_difference_cm3,
            scan.holes_filled,
            scan.seam_max_move_cm
        );
    }
    s
}

/// The header of the sweep table.
pub const SWEEP_HEADER: &str =
    "volume cm³  area gain cm²  area after cm²  vol. diff cm³  compression %  steps  stop        wall s";

/// One sweep row for stdout.
pub fn sweep_row(volume: f64, r: &RunResult) -> String {
    format!(
        "{volume:>10.3}  {:>13.4}  {:>14.4}  {:>13.4}  {:>13.4}  {:>5}  {:<10}  {:>6.2}",
        r.area_gain_cm2,
        r.area_after_cm2,
        r.volume_difference_cm3,
        100.0 * r.implant_compression,
        r.steps,
        r.stop_reason,
        r.wall_time_s
    )
}

/// One sweep row for a failed run.
pub fn sweep_failed_row(volume: f64, message: &str) -> String {
    format!("{volume:>10.3}  failed: {message}")
}
