//! The `--report` JSON and the tables on stdout.
//!
//! # The JSON contract
//! Field names are a contract: they are only ever added to, never renamed or removed. Units are
//! in the names (`_cm`, `_cm2`, `_cm3`, `_s`, `_kpa`); everything is in cm whatever the mesh's
//! unit. Every report has `tool` (`"insert"`), `version`, `mode` and `inputs` ([`Inputs`]).
//!
//! - `mode: "single"` ([`SingleReport`]): the fields of [`RunResult`] at the top level:
//!   `area_before_cm2`, `area_after_cm2`, `area_gain_cm2`, `volume_difference_cm3`,
//!   `implant_volume_cm3`, `implant_volume_end_cm3`, `implant_compression` (a fraction),
//!   `dome_height_cm`, `max_displacement_cm`, `max_penetration_cm`, `boundary_unchanged`,
//!   `region_vertices`, `region_triangles`, `region_radius_cm`, `steps`, `max_steps`,
//!   `stop_reason` (`"settled"` or `"step_limit"`), `time_step_s`, `wall_time_s`,
//!   `measured_on` (`"simulation_surface"` or `"patient_region"`), `scan_region_vertices`, and
//!   on a remeshed run `scan` ([`ScanFigures`]: the areas and volume on the scan itself).
//!   `inputs` carries `sim_mesh`, `sim_edge_cm` and `max_hole_cm`.
//! - `mode: "sweep"` ([`SweepReport`]): `runs`, one [`RunResult`] per volume with its
//!   `volume_cm3`, in the order given.
//! - `mode: "target-gain"` ([`InverseReport`]): `target_gain_cm2`, `bracket_cm3`, `volume_cm3`
//!   (the answer), `area_gain_cm2` (its gain), `converged`, `runs` (`volume_cm3`,
//!   `area_gain_cm2` of every run, in order).

use std::fmt::Write as _;

use serde::Serialize;
use tissue_app::{PlannedInsertion, SimMesh, SweepResult};
use tissue_implant::{ImplantShape, InsertionOutcome, InverseSearch, ScanResult, SimSurface};
use tissue_mss::StopReason;

use crate::cli::{Cli, Detect, Rule, KPA};
use crate::setup::Scenario;

/// What produced the results: the mesh, the placement, the implant, the tissue and the run.
#[derive(Debug, Clone, Serialize)]
pub struct Inputs {
    /// The `--mesh` path as given, or a description of the generated Table 2 plane.
    pub mesh: String,
    /// Whether the mesh is the generated Table 2 plane.
    pub mesh_generated: bool,
    /// The mesh file's unit (`mm`, `cm`, `dm`, `m`).
    pub unit: &'static str,
    /// Centimetres per mesh unit.
    pub cm_per_unit: f32,
    /// Vertices of the patient mesh.
    pub mesh_vertices: usize,
    /// Triangles of the patient mesh.
    pub mesh_triangles: usize,
    /// `--at` as given (mesh unit), or null.
    pub at: Option<[f32; 3]>,
    /// `--vertex` as given, or null.
    pub vertex: Option<u32>,
    /// The picked point, cm.
    pub point_cm: [f32; 3],
    /// The nearest surface point (the region's and the implant's centre), cm.
    pub surface_point_cm: [f32; 3],
    /// The implant's outward normal (unit).
    pub normal: [f32; 3],
    /// The implant's local x direction (unit).
    pub tangent: [f32; 3],
    /// The base outline: `kind` and its sizes in cm.
    pub shape: ShapeInputs,
    /// `--volume`, cm³ (for a sweep or a search, the volumes are in their own fields).
    pub volume_cm3: f64,
    /// The implant mesh's wanted vertex count.
    pub implant_vertices: u32,
    /// Placement depth, cm.
    pub depth_cm: f64,
    /// The region radius used, cm (given or default).
    pub region_radius_cm: f64,
    /// What the mechanics ran on: `remeshed` (the region remeshed, the result mapped back onto
    /// the scan) or `patient_triangles` (the mesh's own triangles).
    pub sim_mesh: &'static str,
    /// The simulation mesh's edge used, cm (`--sim-edge` or its default); null on the mesh's own
    /// triangles.
    pub sim_edge_cm: Option<f64>,
    /// Holes filled up to this size across, cm; null on the mesh's own triangles.
    pub max_hole_cm: Option<f64>,
    /// `touches-vertex` or `centroid`.
    pub region_rule: &'static str,
    /// Skin Young's modulus, kPa.
    pub young_kpa: f64,
    /// Skin Poisson ratio.
    pub poisson: f64,
    /// Skin thickness, cm.
    pub thickness_cm: f64,
    /// Tissue density, g/cm³.
    pub density_g_cm3: f64,
    /// `bvh` or `voxels`.
    pub detect: &'static str,
    /// The step limit.
    pub max_steps: u64,
    /// `--time-step`, s, or null for automatic.
    pub time_step_s: Option<f32>,
    /// The expander's fill time, s.
    pub fill_time_s: f32,
    /// `--sweep` volumes, cm³ (sweep only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep_volumes_cm3: Option<Vec<f64>>,
    /// `--target-gain`, cm² (search only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_gain_cm2: Option<f64>,
    /// The searched volume bracket, cm³ (search only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bracket_cm3: Option<[f64; 2]>,
}

/// The implant's base outline in the report.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ShapeInputs {
    /// Round.
    Round {
        /// cm.
        diameter_cm: f32,
    },
    /// Rectangular.
    Rectangular {
        /// cm.
        length_cm: f32,
        /// cm.
        width_cm: f32,
        /// cm.
        corner_radius_cm: f32,
    },
    /// Crescent.
    Crescent {
        /// cm.
        length_cm: f32,
        /// cm.
        width_cm: f32,
        /// cm.
        bend_radius_cm: f32,
    },
}

impl Inputs {
    /// The inputs of `scenario` as the command line `cli` gave them.
    pub fn new(
        cli: &Cli,
        scenario: &Scenario,
        region_radius_cm: f64,
        sim_edge_cm: Option<f64>,
    ) -> Self {
        let job = &scenario.job;
        let remeshed = matches!(job.sim, SimMesh::Remeshed(_));
        let shape = match job.implant.shape {
            ImplantShape::Round { diameter } => ShapeInputs::Round {
                diameter_cm: diameter,
            },
            ImplantShape::Rectangular {
                length,
                width,
                corner_radius,
            } => ShapeInputs::Rectangular {
                length_cm: length,
                width_cm: width,
                corner_radius_cm: corner_radius,
            },
            ImplantShape::Crescent {
                length,
                width,
                bend_radius,
            } => ShapeInputs::Crescent {
                length_cm: length,
                width_cm: width,
                bend_radius_cm: bend_radius,
            },
            // The shapes this program makes are the three above.
            _ => ShapeInputs::Round { diameter_cm: 0.0 },
        };
        Inputs {
            mesh: scenario.mesh_label.clone(),
            mesh_generated: scenario.mesh_generated,
            unit: scenario.unit.symbol(),
            cm_per_unit: scenario.cm_per_unit(),
            mesh_vertices: scenario.patient.vertex_count(),
            mesh_triangles: scenario.patient.triangle_count(),
            at: cli.at,
            vertex: cli.vertex,
            point_cm: scenario.point.to_array(),
            surface_point_cm: scenario.surface_point.to_array(),
            normal: scenario.normal.to_array(),
            tangent: scenario.tangent.to_array(),
            shape,
            volume_cm3: job.implant.volume_cm3,
            implant_vertices: job.implant.vertex_budget,
            depth_cm: job.params.layers.depth,
            region_radius_cm,
            sim_mesh: if remeshed {
                "remeshed"
            } else {
                "patient_triangles"
            },
            sim_edge_cm,
            max_hole_cm: remeshed.then_some(cli.max_hole),
            region_rule: match cli.region_rule {
                Rule::TouchesVertex => "touches-vertex",
                Rule::Centroid => "centroid",
            },
            young_kpa: job.params.layers.young / KPA,
            poisson: job.params.layers.poisson,
            thickness_cm: job.params.layers.skin_thickness,
            density_g_cm3: job.params.layers.density,
            detect: match cli.detect {
                Detect::Bvh => "bvh",
                Detect::Voxels => "voxels",
            },
            max_steps: job.params.run.stop.max_steps,
            time_step_s: job.params.run.time_step,
            fill_time_s: job
                .run_params()
                .map_or(job.params.fill_time, |p| p.fill_time),
            sweep_volumes_cm3: None,
            target_gain_cm2: None,
            bracket_cm3: None,
        }
    }
}

/// The results of one run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunResult {
    /// Skin region area before the run, cm².
    pub area_before_cm2: f64,
    /// Skin region area after the run, cm².
    pub area_after_cm2: f64,
    /// `area_after − area_before`, cm²: the skin gained.
    pub area_gain_cm2: f64,
    /// Volume between the skin before and after, cm³.
    pub volume_difference_cm3: f64,
    /// The implant's volume as built, cm³.
    pub implant_volume_cm3: f64,
    /// The implant's volume at the end, cm³.
    pub implant_volume_end_cm3: f64,
    /// `1 − end / built` (a fraction).
    pub implant_compression: f64,
    /// The implant's dome height as built, cm.
    pub dome_height_cm: f64,
    /// The largest displacement of a skin vertex, cm.
    pub max_displacement_cm: f32,
    /// The deepest tissue edge through the implant at the end, cm (0: none).
    pub max_penetration_cm: f32,
    /// Whether every region boundary vertex stayed exactly in place.
    pub boundary_unchanged: bool,
    /// Vertices of the simulated skin region.
    pub region_vertices: usize,
    /// Triangles of the simulated skin region.
    pub region_triangles: usize,
    /// The region's geodesic radius, cm.
    pub region_radius_cm: f64,
    /// Steps taken.
    pub steps: u64,
    /// The step limit.
    pub max_steps: u64,
    /// `settled` or `step_limit`.
    pub stop_reason: &'static str,
    /// The time step, s.
    pub time_step_s: f32,
    /// Wall time of the stepping, s.
    pub wall_time_s: f64,
    /// The surface the area and volume figures above were measured on: `simulation_surface`
    /// (the remeshed region) or `patient_region` (the mesh's own triangles).
    pub measured_on: &'static str,
    /// Vertices of the patient's region (on a remeshed run, with its small holes filled).
    pub scan_region_vertices: usize,
    /// On a remeshed single run: the same figures measured on the scan (see [`ScanFigures`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scan: Option<ScanFigures>,
}

/// A remeshed run's results on the scan itself, after mapping.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanFigures {
    /// Where the areas were measured: `scan_region_triangles` (the scan's own triangles of the
    /// region, its holes not counted).
    pub measured_on: &'static str,
    /// cm².
    pub area_before_cm2: f64,
    /// cm².
    pub area_after_cm2: f64,
    /// cm².
    pub area_gain_cm2: f64,
    /// Volume between the scan's region before and after, cm³.
    pub volume_difference_cm3: f64,
    /// Where the volume was measured: `scan_region_holes_filled`.
    pub volume_measured_on: &'static str,
    /// Holes of the scan filled in or at the region.
    pub holes_filled: usize,
    /// The largest move of a scan vertex within one simulation edge of the region's boundary, cm.
    pub seam_max_move_cm: f32,
}

impl ScanFigures {
    /// The figures of `scan`, mapped from `surface`.
    pub fn new(scan: &ScanResult, surface: &SimSurface) -> Self {
        ScanFigures {
            measured_on: "scan_region_triangles",
            area_before_cm2: scan.area_before,
            area_after_cm2: scan.area_after,
            area_gain_cm2: scan.area_gain,
            volume_difference_cm3: scan.volume_difference,
            volume_measured_on: "scan_region_holes_filled",
            holes_filled: surface.holes_filled().len(),
            seam_max_move_cm: scan.seam_max_move,
        }
    }
}

impl RunResult {
    /// The results of `outcome` on `selection`.
    pub fn new(
        outcome: &InsertionOutcome,
        selection: &tissue_implant::RegionSelection,
        surface: Option<&SimSurface>,
        max_steps: u64,
    ) -> Self {
        let simulated = surface.map_or(selection.mesh(), SimSurface::mesh);
        RunResult {
            area_before_cm2: outcome.area_before,
            area_after_cm2: outcome.area_after,
            area_gain_cm2: outcome.area_gain,
            volume_difference_cm3: outcome.volume_difference,
            implant_volume_cm3: outcome.implant_volume,
            implant_volume_end_cm3: outcome.implant_volume_after,
            implant_compression: outcome.implant_compression,
            dome_height_cm: outcome.dome_height,
            max_displacement_cm: outcome.max_displacement,
            max_penetration_cm: outcome.max_penetration,
            boundary_unchanged: outcome.boundary_unchanged,
            region_vertices: simulated.vertex_count(),
            region_triangles: simulated.triangle_count(),
            region_radius_cm: selection.radius(),
            steps: outcome.steps,
            max_steps,
            stop_reason: match outcome.stop_reason {
                StopReason::Settled => "settled",
                StopReason::StepLimit => "step_limit",
            },
            time_step_s: outcome.time_step,
            wall_time_s: outcome.wall_time.as_secs_f64(),
            measured_on: if surface.is_some() {
                "simulation_surface"
            } else {
                "patient_region"
            },
            scan_region_vertices: selection.mesh().vertex_count(),
            scan: None,
        }
    }

    /// The results of a planned insertion, with its figures on the scan when it was remeshed.
    pub fn of(planned: &PlannedInsertion, scan: Option<&ScanResult>, max_steps: u64) -> Self {
        let mut r = RunResult::new(
            &planned.outcome,
            &planned.selection,
            planned.surface.as_ref(),
            max_steps,
        );
        if let (Some(scan), Some(surface)) = (scan, &planned.surface) {
            r.scan = Some(ScanFigures::new(scan, surface));
        }
        r
    }
}

/// `mode: "single"`.
#[derive(Debug, Clone, Serialize)]
pub struct SingleReport {
    /// `"insert"`.
    pub tool: &'static str,
    /// The program's version.
    pub version: &'static str,
    /// `"single"`.
    pub mode: &'static str,
    /// What produced the results.
    pub inputs: Inputs,
    /// The results.
    #[serde(flatten)]
    pub result: RunResult,
}

/// One run of a sweep.
#[derive(Debug, Clone, Serialize)]
pub struct SweepRow {
    /// The implant volume run, cm³.
    pub volume_cm3: f64,
    /// Its results.
    #[serde(flatten)]
    pub result: RunResult,
}

/// `mode: "sweep"`.
#[derive(Debug, Clone, Serialize)]
pub struct SweepReport {
    /// `"insert"`.
    pub tool: &'static str,
    /// The program's version.
    pub version: &'static str,
    /// `"sweep"`.
    pub mode: &'static str,
    /// What produced the results.
    pub inputs: Inputs,
    /// One row per volume, in the order given.
    pub runs: Vec<SweepRow>,
}

/// One run of a search.
#[derive(Debug, Clone, Serialize)]
pub struct SearchRun {
    /// The implant volume run, cm³.
    pub volume_cm3: f64,
    /// The area gain it gave, cm².
    pub area_gain_cm2: f64,
}

/// `mode: "target-gain"`.
#[derive(Debug, Clone, Serialize)]
pub struct InverseReport {
    /// `"insert"`.
    pub tool: &'static str,
    /// The program's version.
    pub version: &'static str,
    /// `"target-gain"`.
    pub mode: &'static str,
    /// What produced the results.
    pub inputs: Inputs,
    /// The wanted area gain, cm².
    pub target_gain_cm2: f64,
    /// The volumes searched between, cm³.
    pub bracket_cm3: [f64; 2],
    /// The answer, cm³.
    pub volume_cm3: f64,
    /// The area gain of the answer's run, cm².
    pub area_gain_cm2: f64,
    /// Whether a stopping rule was met (else the run budget ran out: best estimate).
    pub converged: bool,
    /// Every run, in order.
    pub runs: Vec<SearchRun>,
}

/// The program's version.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The single-run report.
pub fn single(inputs: Inputs, result: RunResult) -> SingleReport {
    SingleReport {
        tool: "insert",
        version: VERSION,
        mode: "single",
        inputs,
        result,
    }
}

/// The sweep report (every run succeeded).
pub fn sweep(mut inputs: Inputs, result: &SweepResult, rows: Vec<SweepRow>) -> SweepReport {
    inputs.sweep_volumes_cm3 = Some(result.runs.iter().map(|r| r.volume).collect());
    SweepReport {
        tool: "insert",
        version: VERSION,
        mode: "sweep",
        inputs,
        runs: rows,
    }
}

/// The search report.
pub fn inverse(
    mut inputs: Inputs,
    target: f64,
    bracket: (f64, f64),
    search: &InverseSearch,
) -> InverseReport {
    inputs.target_gain_cm2 = Some(target);
    inputs.bracket_cm3 = Some([bracket.0, bracket.1]);
    InverseReport {
        tool: "insert",
        version: VERSION,
        mode: "target-gain",
        inputs,
        target_gain_cm2: target,
        bracket_cm3: [bracket.0, bracket.1],
        volume_cm3: search.volume,
        area_gain_cm2: search.gain,
        converged: search.converged,
        runs: search
            .runs
            .iter()
            .map(|r| SearchRun {
                volume_cm3: r.volume,
                area_gain_cm2: r.gain,
            })
            .collect(),
    }
}

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
