//! `mode: "single"`: one run's figures ([`RunResult`]), on the simulation surface and, on a
//! remeshed run, on the scan ([`ScanFigures`]).

use serde::Serialize;
use tissue_app::PlannedInsertion;
use tissue_implant::{InsertionOutcome, ScanResult, SimSurface};

use super::{Inputs, Report, Tool};
use crate::error::{ErrorKind, PlanError};
use crate::job::JobMode;

/// `mode: "single"`: the envelope and one run's figures at the top level.
pub type SingleReport = Report<RunResult>;

/// Why a run stopped (`stop_reason`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The stop criterion was met: the tissue is at rest.
    Settled,
    /// The step limit came first: the results are not at rest.
    StepLimit,
}

impl StopReason {
    /// Its JSON name.
    pub fn name(self) -> &'static str {
        match self {
            StopReason::Settled => "settled",
            StopReason::StepLimit => "step_limit",
        }
    }
}

impl From<tissue_implant::StopReason> for StopReason {
    fn from(reason: tissue_implant::StopReason) -> Self {
        match reason {
            tissue_implant::StopReason::Settled => StopReason::Settled,
            tissue_implant::StopReason::StepLimit => StopReason::StepLimit,
        }
    }
}

/// The surface a figure was measured on (`measured_on`, `scan.measured_on`,
/// `scan.volume_measured_on`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MeasuredOn {
    /// The remeshed simulation surface of the region.
    SimulationSurface,
    /// The patient mesh's own triangles of the region.
    PatientRegion,
    /// The scan's own triangles of the region, its holes not counted.
    ScanRegionTriangles,
    /// The scan's region with its holes filled.
    ScanRegionHolesFilled,
}

/// A run whose positions are not finite: the one message every front end gives.
pub fn diverged() -> PlanError {
    PlanError::field(
        ErrorKind::Run,
        "time_step_s",
        "the run diverged: the result has positions that are not finite; leave `time_step_s` \
         automatic, or lower it",
    )
}

/// The single-run report.
pub(crate) fn single(tool: Tool, inputs: Inputs, result: RunResult) -> SingleReport {
    Report::new(tool, JobMode::Single, inputs, result)
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
    /// The solver's iterations: the explicit solver's steps (as `steps`), or the quasi-static
    /// solver's iterations.
    pub iterations: u64,
    /// The quasi-static solver's final residual: the largest net force on a free particle, N;
    /// null for the explicit solver.
    pub residual_n: Option<f64>,
    /// `settled` or `step_limit`.
    pub stop_reason: StopReason,
    /// The time step, s.
    pub time_step_s: f32,
    /// Wall time of the stepping, s.
    pub wall_time_s: f64,
    /// The surface the area and volume figures above were measured on: `simulation_surface`
    /// (the remeshed region) or `patient_region` (the mesh's own triangles).
    pub measured_on: MeasuredOn,
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
    pub measured_on: MeasuredOn,
    /// cm².
    pub area_before_cm2: f64,
    /// cm².
    pub area_after_cm2: f64,
    /// cm².
    pub area_gain_cm2: f64,
    /// Volume between the scan's region before and after, cm³.
    pub volume_difference_cm3: f64,
    /// Where the volume was measured: `scan_region_holes_filled`.
    pub volume_measured_on: MeasuredOn,
    /// Holes of the scan filled in or at the region.
    pub holes_filled: usize,
    /// The largest move of a scan vertex within one simulation edge of the region's boundary, cm.
    pub seam_max_move_cm: f32,
}

impl ScanFigures {
    /// The figures of `scan`, mapped from `surface`.
    pub fn new(scan: &ScanResult, surface: &SimSurface) -> Self {
        ScanFigures {
            measured_on: MeasuredOn::ScanRegionTriangles,
            area_before_cm2: scan.area_before,
            area_after_cm2: scan.area_after,
            area_gain_cm2: scan.area_gain,
            volume_difference_cm3: scan.volume_difference,
            volume_measured_on: MeasuredOn::ScanRegionHolesFilled,
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
            iterations: outcome.iterations,
            residual_n: outcome.residual_n,
            stop_reason: outcome.stop_reason.into(),
            time_step_s: outcome.time_step,
            wall_time_s: outcome.wall_time.as_secs_f64(),
            measured_on: if surface.is_some() {
                MeasuredOn::SimulationSurface
            } else {
                MeasuredOn::PatientRegion
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Patient, PlanRequest, Scenario, Shipped};

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
            Tool::Studio,
            Inputs::new(&scenario)?,
            RunResult::of(&planned, None, 5),
        );
        let json = serde_json::to_value(&report)
            .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
        assert_eq!(json["schema_version"], super::super::SCHEMA_VERSION);
        assert_eq!(json["tool"], "studio");
        assert_eq!(json["mode"], "single");
        assert_eq!(json["steps"], 5);
        // The solver asked for (the default), the run's iterations and residual.
        assert_eq!(json["inputs"]["solver"], "explicit");
        assert_eq!(json["iterations"], planned.outcome.iterations);
        assert!(json["iterations"].as_u64().is_some_and(|i| i > 0));
        assert_eq!(
            json["residual_n"].as_f64(),
            planned.outcome.residual_n,
            "null exactly when the run has no residual"
        );
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

    /// The explicit solver, asked for, is the report's input; its run has iterations (its steps)
    /// and no residual (`residual_n` is written, as null).
    #[test]
    fn an_explicit_run_reports_its_solver_iterations_and_a_null_residual() -> Result<(), PlanError>
    {
        let request = PlanRequest {
            max_steps: 4,
            solver: crate::Solver::Explicit,
            ..PlanRequest::default()
        };
        let scenario = Scenario::new(Patient::shipped(Shipped::Table2)?, request)?;
        assert_eq!(scenario.job.params.solver, tissue_implant::Solver::Explicit);
        let planned = tissue_app::plan(&scenario.job, |_| std::ops::ControlFlow::Continue(()))
            .map_err(|e| PlanError::from_implant(&e))?;
        let report = single(
            Tool::Insert,
            Inputs::new(&scenario)?,
            RunResult::of(&planned, None, 4),
        );
        let json = serde_json::to_value(&report)
            .map_err(|e| PlanError::new(ErrorKind::Output, e.to_string()))?;
        assert_eq!(json["inputs"]["solver"], "explicit");
        assert_eq!(json["iterations"], 4);
        assert_eq!(json["iterations"], json["steps"]);
        let body = json.as_object().map(|o| o.contains_key("residual_n"));
        assert_eq!(body, Some(true), "residual_n is always written");
        assert!(json["residual_n"].is_null());
        Ok(())
    }
}
