//! The tables on stdout and the warnings on stderr, read from the finished job's report. The
//! `--report` JSON is the planner's contract ([`tissue_planner::report`]).

use std::fmt::Write as _;

use tissue_planner::report::{Inputs, InverseReport, RunResult, ShapeInputs, StopReason};
use tissue_planner::{Finished, JobReport};

use crate::failure::{Failure, FromPlan};

/// What the job prints on stdout: a single run's summary, a sweep's table (failed runs as
/// rows), a search's runs and answer, an expansion's weeks and flap.
pub fn stdout(finished: &Finished) -> String {
    match &finished.report {
        JobReport::Single(r) => summary(&r.inputs, &r.body),
        JobReport::Sweep(_) => {
            let mut s = format!("{SWEEP_HEADER}\n");
            for (volume, row) in &finished.sweep {
                let line = match row {
                    Ok(result) => sweep_row(*volume, result),
                    Err(e) => sweep_failed_row(*volume, &Failure::from_plan(e).line()),
                };
                let _ = writeln!(s, "{line}");
            }
            s
        }
        JobReport::TargetGain(r) => search(r),
        JobReport::Expansion(r) => expansion_summary(r),
    }
}

/// What the job warns of on stderr: runs that reached the step limit before the tissue
/// settled, and a sweep's failed runs (the report lists them in `failed_runs`).
pub fn warnings(finished: &Finished) -> Vec<String> {
    let not_at_rest = |r: &RunResult, what: &str| {
        (r.stop_reason != StopReason::Settled).then(|| {
            format!(
                "{what} reached the step limit ({}) before the tissue settled; the results are \
                 not at rest: raise --max-steps",
                r.max_steps
            )
        })
    };
    match &finished.report {
        JobReport::Single(r) => not_at_rest(&r.body, "the run").into_iter().collect(),
        JobReport::Sweep(r) => {
            let mut out: Vec<String> = r
                .body
                .runs
                .iter()
                .filter_map(|row| {
                    not_at_rest(&row.result, &format!("the {} cm³ run", row.volume_cm3))
                })
                .collect();
            if !r.body.failed_runs.is_empty() {
                out.push(format!(
                    "{} of {} runs of the sweep failed (their rows above); the report lists \
                     them in failed_runs",
                    r.body.failed_runs.len(),
                    r.body.failed_runs.len() + r.body.runs.len()
                ));
            }
            out
        }
        JobReport::TargetGain(_) | JobReport::Expansion(_) => Vec::new(),
    }
}

/// A search's runs and its answer.
fn search(r: &InverseReport) -> String {
    let b = &r.body;
    let mut s = String::from("run  volume cm³  area gain cm²\n");
    for (i, run) in b.runs.iter().enumerate() {
        let _ = writeln!(
            s,
            "{:>3}  {:>10.4}  {:>13.4}",
            i + 1,
            run.volume_cm3,
            run.area_gain_cm2
        );
    }
    let _ = writeln!(
        s,
        "answer: {:.4} cm³ gives an area gain of {:.4} cm² (target {} cm², {} runs, {})",
        b.volume_cm3,
        b.area_gain_cm2,
        b.target_gain_cm2,
        b.runs.len(),
        if b.converged {
            "converged"
        } else {
            "not converged: the run budget ran out, best estimate"
        }
    );
    s
}

/// The summary table of one run, for stdout.
fn summary(inputs: &Inputs, r: &RunResult) -> String {
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
        StopReason::Settled => "settled",
        StopReason::StepLimit => "step limit reached: not settled",
    };
    let solver = match r.residual_n {
        Some(residual) => format!(
            "{}: {} iterations, residual {residual:.4e} N",
            inputs.solver.name(),
            r.iterations
        ),
        None => format!("{}: {} iterations", inputs.solver.name(), r.iterations),
    };
    let rows: [(&str, String); 13] = [
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
        ("solver", solver),
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
const SWEEP_HEADER: &str =
    "volume cm³  area gain cm²  area after cm²  vol. diff cm³  compression %  steps  stop        wall s";

/// One sweep row for stdout.
fn sweep_row(volume: f64, r: &RunResult) -> String {
    format!(
        "{volume:>10.3}  {:>13.4}  {:>14.4}  {:>13.4}  {:>13.4}  {:>5}  {:<10}  {:>6.2}",
        r.area_gain_cm2,
        r.area_after_cm2,
        r.volume_difference_cm3,
        100.0 * r.implant_compression,
        r.steps,
        r.stop_reason.name(),
        r.wall_time_s
    )
}

/// One sweep row for a failed run.
fn sweep_failed_row(volume: f64, message: &str) -> String {
    format!("{volume:>10.3}  failed: {message}")
}

/// The summary of an expansion over weeks, for stdout: the protocol, one row per week, the flap
/// at removal and its band.
fn expansion_summary(report: &tissue_planner::report::ExpansionReport) -> String {
    let mut s = String::new();
    let r = &report.body;
    let p = &r.protocol;
    let _ = writeln!(
        s,
        "expansion: {} fills to {:.1} cm³ injected ({:.1} cm³ nominal), {:.0} % leakage, removal on day {:.0}",
        p.fills.len(),
        p.injected_cm3,
        p.nominal_volume_cm3,
        100.0 * p.leakage,
        p.removal_day
    );
    let _ = writeln!(
        s,
        "  week   day  injected cm³  volume cm³  area gain cm²  skin grown cm²  mean growth"
    );
    for w in &r.weeks {
        let _ = writeln!(
            s,
            "  {:>4}  {:>4.0}  {:>12.1}  {:>10.1}  {:>13.2}  {:>14.2}  {:>11.4}",
            w.week,
            w.day,
            w.injected_cm3,
            w.volume_cm3,
            w.area_gain_cm2,
            w.grown_gain_cm2,
            w.mean_growth
        );
    }
    let f = &r.flap;
    let rows: [(&str, String); 8] = [
        ("base area", format!("{:.2} cm²", f.base_area_cm2)),
        (
            "flap on the expander",
            format!(
                "{:.2} cm² (from {:.2} cm² of skin: {:.2} cm² recruited)",
                f.dome_area_cm2,
                f.base_area_cm2 + f.recruited_area_cm2,
                f.recruited_area_cm2
            ),
        ),
        ("flap grown area", format!("{:.2} cm²", f.grown_area_cm2)),
        ("flap after removal", format!("{:.2} cm²", f.flap_area_cm2)),
        (
            "linear retraction",
            format!("{:.1} %", 100.0 * f.retraction),
        ),
        (
            "geometric gain",
            format!("{:.2} cm² (no growth, no leakage)", f.geometric_gain_cm2),
        ),
        ("grown gain", format!("{:.2} cm²", f.grown_gain_cm2)),
        ("efficiency", format!("{:.1} %", 100.0 * f.efficiency)),
    ];
    for (name, value) in rows {
        let _ = writeln!(s, "  {name:<22} {value}");
    }
    if let Some(b) = &r.band {
        let _ = writeln!(
            s,
            "  band ({} samples, seed {}): P5 / P50 / P95",
            b.samples, b.seed
        );
        let _ = writeln!(
            s,
            "  {:<22} {:.2} / {:.2} / {:.2} cm²",
            "flap after removal", b.flap_area_cm2.p5, b.flap_area_cm2.p50, b.flap_area_cm2.p95
        );
        let _ = writeln!(
            s,
            "  {:<22} {:.1} / {:.1} / {:.1} %",
            "linear retraction",
            100.0 * b.retraction.p5,
            100.0 * b.retraction.p50,
            100.0 * b.retraction.p95
        );
        let _ = writeln!(
            s,
            "  {:<22} {:.1} / {:.1} / {:.1} %",
            "efficiency",
            100.0 * b.efficiency.p5,
            100.0 * b.efficiency.p50,
            100.0 * b.efficiency.p95
        );
    }
    let _ = writeln!(
        s,
        "  {:<22} {} + {} reference, {:.1} s",
        "steps", r.steps, r.reference_steps, r.wall_time_s
    );
    s
}
