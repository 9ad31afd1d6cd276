//! The report: the JSON contract every front end writes (`insert --report`, the studio's
//! `report.json`, the C ABI's result).
//!
//! # The JSON contract
//! Field names are a contract: they are only ever added to, never renamed or removed; a change
//! that is not an addition raises [`SCHEMA_VERSION`]. Units are in the names (`_cm`, `_cm2`,
//! `_cm3`, `_s`, `_kpa`); everything is in cm whatever the mesh's unit. Every report has
//! `schema_version`, `tool` (the front end: `"insert"`, `"studio"`), `version`, `mode` and
//! `inputs` ([`Inputs`]).
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
//! - `mode: "expansion"` ([`ExpansionReport`], issue 21; asked by `expand_weeks`): `protocol`
//!   (`fills` as `day`/`volume_cm3`, `removal_day`, `leakage`, `nominal_volume_cm3`,
//!   `injected_cm3`), `growth` (`rate_per_h`, `prestretch`, `threshold`, `step_h`,
//!   `flap_release`), `weeks` (one [`ExpansionRow`] per week and at removal: `day`, `week`,
//!   `injected_cm3`, `volume_cm3`, `area_gain_cm2` (elastic and grown together),
//!   `grown_area_cm2`, `grown_gain_cm2`, `mean_growth`), `days` (the same after every fill
//!   and growth step), `flap` ([`FlapFigures`]: `base_area_cm2`, `recruited_area_cm2`,
//!   `dome_area_cm2`, `grown_area_cm2`, `flap_area_cm2`, `retraction` (linear, a fraction),
//!   `geometric_gain_cm2`, `grown_gain_cm2`, `efficiency`, `flap_growth`), `band` (null
//!   without one; [`BandFigures`]: `samples`, `seed`, `method` (`"surrogate"`), and
//!   `p5`/`p50`/`p95` of `flap_area_cm2`, `retraction`, `efficiency`, `grown_area_cm2`),
//!   `steps`, `reference_steps`, `wall_time_s`. `inputs` carries the request's expansion
//!   fields (`expand_weeks`, `hold_weeks`, `leakage`, `overfill`, `band_samples`,
//!   `band_seed`, `growth_step_h`).

use serde::Serialize;
use tissue_app::{PlannedInsertion, SimMesh, SweepResult};
use tissue_implant::{ImplantShape, InsertionOutcome, InverseSearch, ScanResult, SimSurface};
use tissue_mss::StopReason;

use crate::error::{ErrorKind, PlanError};
use crate::scenario::Scenario;
use crate::units::KPA;

/// The report's schema version: raised when a field changes meaning or goes (never for an
/// added field).
pub const SCHEMA_VERSION: u32 = 1;

/// What produced the results: the mesh, the placement, the implant, the tissue and the run.
#[derive(Debug, Clone, Serialize)]
pub struct Inputs {
    /// The patient file as named (a path or an upload's name), or a description of the
    /// generated Table 2 plane.
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
    /// `at` as given (mesh unit), or null.
    pub at: Option<[f32; 3]>,
    /// `vertex` as given, or null.
    pub vertex: Option<u32>,
    /// The picked point, cm.
    pub point_cm: [f32; 3],
    /// The nearest surface point (the region's and the implant's centre), cm.
    pub surface_point_cm: [f32; 3],
    /// The implant's outward normal (unit).
    pub normal: [f32; 3],
    /// The implant's local x direction (unit).
    pub tangent: [f32; 3],
    /// The tangent's turn about the normal, degrees.
    pub rotation_deg: f32,
    /// The base outline: `kind` and its sizes in cm.
    pub shape: ShapeInputs,
    /// The request's volume, cm³ (for a sweep or a search, the volumes are in their own fields).
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
    /// The simulation mesh's edge used, cm (`sim_edge_cm` or its default); null on the mesh's own
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
    /// The time step asked for, s, or null for automatic.
    pub time_step_s: Option<f32>,
    /// The expander's fill time, s.
    pub fill_time_s: f32,
    /// The sweep's volumes, cm³ (sweep only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep_volumes_cm3: Option<Vec<f64>>,
    /// The wanted area gain, cm² (search only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_gain_cm2: Option<f64>,
    /// The searched volume bracket, cm³ (search only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bracket_cm3: Option<[f64; 2]>,
    /// Expansion only: weekly fills.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub expand_weeks: Option<u32>,
    /// Expansion only: the hold, weeks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hold_weeks: Option<f64>,
    /// Expansion only: the leakage fraction.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leakage: Option<f64>,
    /// Expansion only: the over-fill fraction.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overfill: Option<f64>,
    /// Expansion only: the band's samples (0: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band_samples: Option<usize>,
    /// Expansion only: the band's seed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band_seed: Option<u64>,
    /// Expansion only: the growth step, hours.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub growth_step_h: Option<f64>,
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

impl From<ImplantShape> for ShapeInputs {
    /// The shape as built, every kind with its own sizes (the match is exhaustive: a new
    /// [`ImplantShape`] must be given its own report entry).
    fn from(shape: ImplantShape) -> Self {
        match shape {
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
        }
    }
}

impl Inputs {
    /// The inputs of `scenario`: the request as given and what it resolved to.
    ///
    /// # Errors
    /// A shape whose region radius is unknown.
    pub fn new(scenario: &Scenario) -> Result<Self, PlanError> {
        let region_radius_cm = scenario.region_radius()?;
        let sim_edge_cm = scenario.sim_edge()?;
        let request = &scenario.request;
        let job = &scenario.job;
        let remeshed = matches!(job.sim, SimMesh::Remeshed(_));
        let shape = ShapeInputs::from(job.implant.shape);
        Ok(Inputs {
            mesh: scenario.patient.label.clone(),
            mesh_generated: scenario.patient.generated,
            unit: scenario.patient.unit.symbol(),
            cm_per_unit: scenario.cm_per_unit(),
            mesh_vertices: scenario.patient.cm.vertex_count(),
            mesh_triangles: scenario.patient.cm.triangle_count(),
            at: request.at,
            vertex: request.vertex,
            point_cm: scenario.point.to_array(),
            surface_point_cm: scenario.surface_point.to_array(),
            normal: scenario.normal.to_array(),
            tangent: scenario.tangent.to_array(),
            rotation_deg: request.rotation_deg,
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
            max_hole_cm: remeshed.then_some(request.max_hole_cm),
            region_rule: request.region_rule.name(),
            young_kpa: job.params.layers.young / KPA,
            poisson: job.params.layers.poisson,
            thickness_cm: job.params.layers.skin_thickness,
            density_g_cm3: job.params.layers.density,
            detect: request.detect.name(),
            max_steps: job.params.run.stop.max_steps,
            time_step_s: job.params.run.time_step,
            fill_time_s: job
                .run_params()
                .map_or(job.params.fill_time, |p| p.fill_time),
            sweep_volumes_cm3: None,
            expand_weeks: None,
            hold_weeks: None,
            leakage: None,
            overfill: None,
            band_samples: None,
            band_seed: None,
            growth_step_h: None,
            target_gain_cm2: None,
            bracket_cm3: None,
        })
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
    /// The report's schema ([`SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// The front end that wrote it (`"insert"`, `"studio"`).
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
    /// The report's schema ([`SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// The front end that wrote it (`"insert"`, `"studio"`).
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
    /// The report's schema ([`SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// The front end that wrote it (`"insert"`, `"studio"`).
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

/// The planner's version (the workspace's).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The single-run report.
pub fn single(tool: &'static str, inputs: Inputs, result: RunResult) -> SingleReport {
    SingleReport {
        schema_version: SCHEMA_VERSION,
        tool,
        version: VERSION,
        mode: "single",
        inputs,
        result,
    }
}

/// The sweep report (every run succeeded).
pub fn sweep(
    tool: &'static str,
    mut inputs: Inputs,
    result: &SweepResult,
    rows: Vec<SweepRow>,
) -> SweepReport {
    inputs.sweep_volumes_cm3 = Some(result.runs.iter().map(|r| r.volume).collect());
    SweepReport {
        schema_version: SCHEMA_VERSION,
        tool,
        version: VERSION,
        mode: "sweep",
        inputs,
        runs: rows,
    }
}

/// The search report.
pub fn inverse(
    tool: &'static str,
    mut inputs: Inputs,
    target: f64,
    bracket: (f64, f64),
    search: &InverseSearch,
) -> InverseReport {
    inputs.target_gain_cm2 = Some(target);
    inputs.bracket_cm3 = Some([bracket.0, bracket.1]);
    InverseReport {
        schema_version: SCHEMA_VERSION,
        tool,
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

/// Each run of a sweep as a report row, or why it has none (a failed or diverged run).
pub fn sweep_rows(result: &SweepResult, max_steps: u64) -> Vec<(f64, Result<SweepRow, PlanError>)> {
    result
        .runs
        .iter()
        .map(|run| {
            let row = match &run.result {
                Ok(outcome) if outcome.is_finite() => Ok(SweepRow {
                    volume_cm3: run.volume,
                    result: RunResult::new(
                        outcome,
                        &result.selection,
                        result.surface.as_ref(),
                        max_steps,
                    ),
                }),
                Ok(_) => Err(PlanError::new(
                    ErrorKind::Run,
                    "the run diverged (positions not finite)",
                )),
                Err(e) => Err(PlanError::from_implant(e)),
            };
            (run.volume, row)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Patient, PlanRequest, Shipped};

    /// Every implant shape is reported as itself with its own sizes (issue 22: a shape the
    /// report did not know was written as a round one of 0 cm; the set of shapes is now closed
    /// and the conversion exhaustive, so no shape can be reported as another).
    #[test]
    fn every_shape_is_reported_as_itself_with_its_sizes() -> Result<(), serde_json::Error> {
        let cases = [
            (
                ImplantShape::Round { diameter: 6.5 },
                serde_json::json!({ "kind": "round", "diameter_cm": 6.5 }),
            ),
            (
                ImplantShape::Rectangular {
                    length: 8.0,
                    width: 4.5,
                    corner_radius: 1.0,
                },
                serde_json::json!({
                    "kind": "rectangular", "length_cm": 8.0, "width_cm": 4.5,
                    "corner_radius_cm": 1.0
                }),
            ),
            (
                ImplantShape::Crescent {
                    length: 9.0,
                    width: 3.0,
                    bend_radius: 6.0,
                },
                serde_json::json!({
                    "kind": "crescent", "length_cm": 9.0, "width_cm": 3.0, "bend_radius_cm": 6.0
                }),
            ),
        ];
        for (shape, expected) in cases {
            assert_eq!(
                serde_json::to_value(ShapeInputs::from(shape))?,
                expected,
                "{shape:?}"
            );
        }
        Ok(())
    }

    #[test]
    fn a_single_report_carries_the_schema_the_tool_and_the_inputs() -> Result<(), PlanError> {
        let request = PlanRequest {
            max_steps: 5,
            rotation_deg: 30.0,
            ..PlanRequest::default()
        };
        let scenario = Scenario::new(Patient::shipped(Shipped::Table2)?, request)?;
        let planned = tissue_app::plan(&scenario.job, |_| std::ops::ControlFlow::Continue(()))
            .map_err(|e| PlanError::from_implant(&e))?;
        let report = single(
            "studio",
            Inputs::new(&scenario)?,
            RunResult::of(&planned, None, 5),
        );
        let json = serde_json::to_value(&report)
            .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
        assert_eq!(json["schema_version"], SCHEMA_VERSION);
        assert_eq!(json["tool"], "studio");
        assert_eq!(json["mode"], "single");
        assert_eq!(json["steps"], 5);
        assert_eq!(json["inputs"]["region_radius_cm"], 5.25);
        assert_eq!(json["inputs"]["rotation_deg"], 30.0);
        assert_eq!(json["inputs"]["sim_mesh"], "patient_triangles");
        assert_eq!(json["inputs"]["shape"]["kind"], "round");
        assert_eq!(json["measured_on"], "patient_region");
        // The tangent turned 30° from +x about +z.
        let t = &json["inputs"]["tangent"];
        let angle = t[1]
            .as_f64()
            .unwrap_or(0.0)
            .atan2(t[0].as_f64().unwrap_or(0.0));
        assert!((angle.to_degrees() - 30.0).abs() < 1e-4, "{t}");
        Ok(())
    }
}

/// One row of an expansion's weekly or daily figures.
#[derive(Debug, Clone, Serialize)]
pub struct ExpansionRow {
    /// The protocol day.
    pub day: f64,
    /// Whole weeks since the first fill.
    pub week: u32,
    /// Saline injected so far, cm³.
    pub injected_cm3: f64,
    /// The expander's volume (injected less leakage), cm³.
    pub volume_cm3: f64,
    /// The region's area now less at rest, cm² (elastic and grown).
    pub area_gain_cm2: f64,
    /// The region's grown area `Σ θg·A₀`, cm².
    pub grown_area_cm2: f64,
    /// The skin made by growth over the region, cm².
    pub grown_gain_cm2: f64,
    /// The region's area-weighted mean `θg`.
    pub mean_growth: f64,
}

/// The fill protocol as run.
#[derive(Debug, Clone, Serialize)]
pub struct ProtocolFigures {
    /// Every fill.
    pub fills: Vec<FillFigures>,
    /// The removal day.
    pub removal_day: f64,
    /// The leakage fraction.
    pub leakage: f64,
    /// The nominal volume, cm³.
    pub nominal_volume_cm3: f64,
    /// Injected in all, cm³.
    pub injected_cm3: f64,
}

/// One fill.
#[derive(Debug, Clone, Serialize)]
pub struct FillFigures {
    /// Its day.
    pub day: f64,
    /// Injected, cm³.
    pub volume_cm3: f64,
}

/// The growth parameters as run.
#[derive(Debug, Clone, Serialize)]
pub struct GrowthFigures {
    /// `k`, 1/h.
    pub rate_per_h: f64,
    /// `θp`.
    pub prestretch: f64,
    /// The threshold `c`.
    pub threshold: f64,
    /// The growth step, hours.
    pub step_h: f64,
    /// The flap's area release at removal.
    pub flap_release: f64,
}

/// The flap at removal.
#[derive(Debug, Clone, Serialize)]
pub struct FlapFigures {
    /// The expander's base area, cm².
    pub base_area_cm2: f64,
    /// The flap's scan area less the base's, cm².
    pub recruited_area_cm2: f64,
    /// The flap on the expander, cm².
    pub dome_area_cm2: f64,
    /// The flap's grown area, cm².
    pub grown_area_cm2: f64,
    /// The flap after removal, cm².
    pub flap_area_cm2: f64,
    /// The linear retraction at removal (a fraction).
    pub retraction: f64,
    /// The dome's area less the base's at the injected total without growth, cm².
    pub geometric_gain_cm2: f64,
    /// The grown area less the base's, cm².
    pub grown_gain_cm2: f64,
    /// Grown gain over geometric gain.
    pub efficiency: f64,
    /// The flap's mean `θg`.
    pub flap_growth: f64,
}

/// P5, P50, P95.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Spread {
    /// 5th percentile.
    pub p5: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
}

impl From<tissue_implant::Percentiles> for Spread {
    fn from(p: tissue_implant::Percentiles) -> Self {
        Spread {
            p5: p.p5,
            p50: p.p50,
            p95: p.p95,
        }
    }
}

/// The band at removal.
#[derive(Debug, Clone, Serialize)]
pub struct BandFigures {
    /// Samples.
    pub samples: usize,
    /// The seed.
    pub seed: u64,
    /// How a sample is computed: `"surrogate"` (tissue-implant's expansion docs).
    pub method: &'static str,
    /// The flap after removal, cm².
    pub flap_area_cm2: Spread,
    /// The linear retraction.
    pub retraction: Spread,
    /// The efficiency.
    pub efficiency: Spread,
    /// The flap's grown area, cm².
    pub grown_area_cm2: Spread,
}

/// `mode: "expansion"`.
#[derive(Debug, Clone, Serialize)]
pub struct ExpansionReport {
    /// The report's schema ([`SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// The front end that wrote it.
    pub tool: &'static str,
    /// The program's version.
    pub version: &'static str,
    /// `"expansion"`.
    pub mode: &'static str,
    /// What produced the results.
    pub inputs: Inputs,
    /// The fills.
    pub protocol: ProtocolFigures,
    /// The growth parameters.
    pub growth: GrowthFigures,
    /// Weekly figures (and at removal).
    pub weeks: Vec<ExpansionRow>,
    /// After every fill and growth step.
    pub days: Vec<ExpansionRow>,
    /// The flap at removal.
    pub flap: FlapFigures,
    /// The band, or null.
    pub band: Option<BandFigures>,
    /// Steps of the protocol's run.
    pub steps: u64,
    /// Steps of the reference runs.
    pub reference_steps: u64,
    /// Wall time, s.
    pub wall_time_s: f64,
}

/// The expansion report of `job` and its result.
pub fn expansion(
    tool: &'static str,
    mut inputs: Inputs,
    request: &crate::PlanRequest,
    job: &tissue_app::ExpansionJob,
    planned: &tissue_app::PlannedExpansion,
) -> ExpansionReport {
    inputs.expand_weeks = request.expand_weeks;
    inputs.hold_weeks = Some(request.hold_weeks);
    inputs.leakage = Some(request.leakage);
    inputs.overfill = Some(request.overfill);
    inputs.band_samples = Some(request.band_samples);
    inputs.band_seed = Some(request.band_seed);
    inputs.growth_step_h = Some(request.growth_step_h);
    let o = &planned.outcome;
    let p = &job.protocol;
    let start = p.start_day();
    let row = |r: &tissue_implant::ExpansionRecord| ExpansionRow {
        day: r.day,
        week: ((r.day - start) / 7.0 + 1e-9).floor().max(0.0) as u32,
        injected_cm3: r.injected,
        volume_cm3: r.volume,
        area_gain_cm2: r.area_gain,
        grown_area_cm2: r.grown_area,
        grown_gain_cm2: r.grown_gain,
        mean_growth: r.mean_growth,
    };
    let days: Vec<ExpansionRow> = o.records.iter().map(row).collect();
    // The last record of every week (the state before the next week's fill), and removal.
    let mut weeks: Vec<ExpansionRow> = Vec::new();
    for (i, r) in days.iter().enumerate() {
        let next_week = days.get(i + 1).map(|n| n.week);
        if next_week != Some(r.week) && (r.day - start) > 0.0 {
            weeks.push(r.clone());
        }
    }
    let g = &job.growth;
    ExpansionReport {
        schema_version: SCHEMA_VERSION,
        tool,
        version: VERSION,
        mode: "expansion",
        inputs,
        protocol: ProtocolFigures {
            fills: p
                .fills
                .iter()
                .map(|f| FillFigures {
                    day: f.day,
                    volume_cm3: f.volume,
                })
                .collect(),
            removal_day: p.removal_day,
            leakage: p.leakage,
            nominal_volume_cm3: p.nominal_volume,
            injected_cm3: p.injected_total(),
        },
        growth: GrowthFigures {
            rate_per_h: g.law.rate,
            prestretch: g.law.prestretch,
            threshold: g.law.threshold,
            step_h: g.step_hours,
            flap_release: g.flap_release,
        },
        weeks,
        days,
        flap: FlapFigures {
            base_area_cm2: o.base_area,
            recruited_area_cm2: o.recruited_area,
            dome_area_cm2: o.dome_area,
            grown_area_cm2: o.grown_area,
            flap_area_cm2: o.flap_area,
            retraction: o.retraction,
            geometric_gain_cm2: o.geometric_gain,
            grown_gain_cm2: o.grown_gain,
            efficiency: o.efficiency,
            flap_growth: o.flap_growth,
        },
        band: o.band.as_ref().map(|b| BandFigures {
            samples: b.samples.len(),
            seed: b.seed,
            method: "surrogate",
            flap_area_cm2: b.flap_area.into(),
            retraction: b.retraction.into(),
            efficiency: b.efficiency.into(),
            grown_area_cm2: b.grown_area.into(),
        }),
        steps: o.steps,
        reference_steps: o.reference_steps,
        wall_time_s: o.wall_time.as_secs_f64(),
    }
}

impl ExpansionReport {
    /// The chart over the protocol's days as PNG bytes: the expander's volume (cm³), the
    /// region's area gain and the skin grown (cm²), and at removal the flap's area with its
    /// P5–P95 whisker when there is a band.
    ///
    /// # Errors
    /// [`ErrorKind::Output`] when drawing or encoding fails.
    pub fn chart(&self, size: (u32, u32)) -> Result<Vec<u8>, PlanError> {
        use tissue_render::{LineChart, Rgb, Series, Whisker};
        let series = |label: &str, color: [u8; 3], f: fn(&ExpansionRow) -> f64| Series {
            label: label.into(),
            color: Rgb(color),
            points: self.days.iter().map(|r| (r.day, f(r))).collect(),
        };
        let removal = self.protocol.removal_day;
        let mut whiskers = Vec::new();
        if let Some(b) = &self.band {
            whiskers.push(Whisker {
                x: removal,
                low: b.flap_area_cm2.p5,
                mid: b.flap_area_cm2.p50,
                high: b.flap_area_cm2.p95,
                color: Rgb([200, 60, 40]),
            });
        }
        let chart = LineChart {
            title: format!(
                "Expansion: {} fills to {:.0} cm3, removal day {:.0}, flap {:.1} cm2, retraction {:.0} %",
                self.protocol.fills.len(),
                self.protocol.injected_cm3,
                removal,
                self.flap.flap_area_cm2,
                100.0 * self.flap.retraction
            ),
            x_label: "day".into(),
            y_label: "cm2 / cm3".into(),
            series: vec![
                series("expander volume, cm3", [90, 90, 90], |r| r.volume_cm3),
                series("area gain, cm2", [40, 90, 200], |r| r.area_gain_cm2),
                series("skin grown, cm2", [30, 150, 60], |r| r.grown_gain_cm2),
                Series {
                    label: "flap after removal, P5-P95, cm2".into(),
                    color: Rgb([200, 60, 40]),
                    points: vec![(removal, self.flap.flap_area_cm2)],
                },
            ],
            whiskers,
        };
        let output = |e: &dyn std::fmt::Display| {
            PlanError::new(ErrorKind::Output, format!("cannot draw the chart: {e}"))
        };
        let image = chart.draw(size.0, size.1).map_err(|e| output(&e))?;
        image.encode_png().map_err(|e| output(&e))
    }
}
