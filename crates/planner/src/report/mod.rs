//! The report: the JSON contract every front end writes (`insert --report`, the studio's
//! `report.json`, the C ABI's result).
//!
//! # The JSON contract
//! Field names are a contract: they are only ever added to, never renamed or removed; a change
//! that is not an addition raises [`SCHEMA_VERSION`]. Units are in the names (`_cm`, `_cm2`,
//! `_cm3`, `_s`, `_kpa`); everything is in cm whatever the mesh's unit. Every report has
//! `schema_version`, `tool` (the front end: [`Tool`]), `version`, `mode` and
//! `inputs` ([`Inputs`]), whose `solver` ([`Solver`]: `"quasi_static"` or `"explicit"`) is
//! the solver every run of the job was asked to use.
//!
//! - `mode: "single"` ([`SingleReport`]): the fields of [`RunResult`] at the top level:
//!   `area_before_cm2`, `area_after_cm2`, `area_gain_cm2`, `volume_difference_cm3`,
//!   `implant_volume_cm3`, `implant_volume_end_cm3`, `implant_compression` (a fraction),
//!   `dome_height_cm`, `max_displacement_cm`, `max_penetration_cm`, `boundary_unchanged`,
//!   `region_vertices`, `region_triangles`, `region_radius_cm`, `steps`, `max_steps`,
//!   `iterations` (the solver's: the explicit solver's steps, the quasi-static solver's
//!   iterations), `residual_n` (the quasi-static solver's final residual, the largest net force
//!   on a free particle in N; null for the explicit solver),
//!   `stop_reason` ([`StopReason`]: `"settled"` or `"step_limit"`), `time_step_s`, `wall_time_s`,
//!   `measured_on` ([`MeasuredOn`]: `"simulation_surface"` or `"patient_region"`), `scan_region_vertices`, and
//!   on a remeshed run `scan` ([`ScanFigures`]: the areas and volume on the scan itself).
//!   `inputs` carries `sim_mesh` ([`SimMeshKind`]), `sim_edge_cm` and `max_hole_cm`.
//! - `mode: "sweep"` ([`SweepReport`]): `runs`, one [`RunResult`] per volume that ran with
//!   its `volume_cm3`, in the order given, and `failed_runs` ([`FailedRun`]: `volume_cm3` and
//!   `error` {`kind`, `field`, `message`}) for the volumes whose run failed or diverged. A
//!   sweep is a survey: one volume the base cannot hold does not take the others' results
//!   away, so a sweep fails as a whole only when every run failed (every front end follows
//!   this, [`crate::PlannedJob::run`]).
//! - `mode: "target-gain"` ([`InverseReport`]): `target_gain_cm2`, `bracket_cm3`, `volume_cm3`
//!   (the answer), `area_gain_cm2` (its gain), `converged`, `runs` ([`SearchRun`]: `volume_cm3`,
//!   `area_gain_cm2`, `iterations`, `residual_n` of every run, in order).
//! - `mode: "expansion"` ([`ExpansionReport`]: asked by `mode: "expansion"` with `expand_weeks`): `protocol`
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

//!
//! Every report is a [`Report`] envelope (`schema_version`, `tool`, `version`, `mode`,
//! `inputs`) around its mode's body; [`JobReport`] is any of the four. The golden files in
//! `fixtures/reports/` (one per mode) are checked against every front end.

use serde::Serialize;
use tissue_app::SimMesh;
use tissue_implant::ImplantShape;

use crate::error::{ErrorKind, PlanError};
use crate::job::JobMode;
use crate::scenario::Scenario;
use crate::units::{Detect, Rule, Solver, Unit, KPA};

mod expansion;
mod inverse;
mod single;
mod sweep;

pub use expansion::{
    BandFigures, BandMethod, ExpansionBody, ExpansionReport, ExpansionRow, FillFigures,
    FlapFigures, GrowthFigures, ProtocolFigures, Spread,
};
pub use inverse::{InverseBody, InverseReport, SearchRun};
pub use single::{diverged, MeasuredOn, RunResult, ScanFigures, SingleReport, StopReason};
pub use sweep::{FailedRun, SweepBody, SweepOutcomes, SweepReport, SweepRow};

pub(crate) use expansion::expansion;
pub(crate) use inverse::inverse;
pub(crate) use single::single;
pub(crate) use sweep::sweep;

/// The report's schema version: raised when a field changes meaning or goes (never for an
/// added field).
pub const SCHEMA_VERSION: u32 = 1;

/// The planner's version (the workspace's).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The front end that wrote a report (its `tool`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tool {
    /// The `insert` command line.
    Insert,
    /// The browser studio.
    Studio,
    /// The C ABI (`tissue-capi`).
    Capi,
    /// The Python package (`import tissue`, `python/`).
    Python,
}

/// Every report: the envelope (`schema_version`, `tool`, `version`, `mode`, `inputs`) and its
/// mode's body, whose fields follow at the top level.
#[derive(Debug, Clone, Serialize)]
pub struct Report<T> {
    /// The report's schema ([`SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// The front end that wrote it.
    pub tool: Tool,
    /// The program's version ([`VERSION`]).
    pub version: &'static str,
    /// What was run.
    pub mode: JobMode,
    /// What produced the results.
    pub inputs: Inputs,
    /// The mode's results.
    #[serde(flatten)]
    pub body: T,
}

impl<T> Report<T> {
    /// The report of `body`, with the envelope of this schema and version.
    pub fn new(tool: Tool, mode: JobMode, inputs: Inputs, body: T) -> Self {
        Report {
            schema_version: SCHEMA_VERSION,
            tool,
            version: VERSION,
            mode,
            inputs,
            body,
        }
    }
}

/// A finished job's report, whatever its mode (serialized as the mode's report itself).
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum JobReport {
    /// `mode: "single"`.
    Single(SingleReport),
    /// `mode: "sweep"`.
    Sweep(SweepReport),
    /// `mode: "target-gain"`.
    TargetGain(InverseReport),
    /// `mode: "expansion"`.
    Expansion(ExpansionReport),
}

impl JobReport {
    /// The JSON every front end writes: pretty-printed, one object, a final newline.
    ///
    /// # Errors
    /// [`ErrorKind::Output`] when it cannot be serialized (a bug).
    pub fn to_json(&self) -> Result<String, PlanError> {
        let mut text = serde_json::to_string_pretty(self).map_err(|e| {
            PlanError::new(ErrorKind::Output, format!("cannot write the report: {e}"))
        })?;
        text.push('\n');
        Ok(text)
    }

    /// Writes [`JobReport::to_json`] to `path` atomically.
    ///
    /// # Errors
    /// [`ErrorKind::Output`] naming the path when it cannot be written.
    pub fn write(&self, path: &std::path::Path) -> Result<(), PlanError> {
        write_output(path, self.to_json()?.as_bytes(), "report")
    }

    /// The same as a JSON value (what the studio sends on its socket), read back from
    /// [`JobReport::to_json`]'s text so that it prints the same: a value made straight from the
    /// report would widen every `f32` figure (`0.0025` would print as `0.0024999999441206455`).
    ///
    /// # Errors
    /// [`ErrorKind::Output`] when it cannot be serialized (a bug).
    pub fn to_value(&self) -> Result<serde_json::Value, PlanError> {
        serde_json::from_str(&self.to_json()?)
            .map_err(|e| PlanError::new(ErrorKind::Output, format!("cannot write the report: {e}")))
    }
}

/// Writes `bytes` to `path` atomically, or says which output could not be written.
pub(crate) fn write_output(
    path: &std::path::Path,
    bytes: &[u8],
    what: &str,
) -> Result<(), PlanError> {
    tissue_meshio::write_bytes(path, bytes).map_err(|e| {
        PlanError::new(
            ErrorKind::Output,
            format!("cannot write the {what}: {e}; check the folder exists and is writable"),
        )
    })
}

/// What the mechanics ran on (`inputs.sim_mesh`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SimMeshKind {
    /// The region remeshed, the result mapped back onto the scan.
    Remeshed,
    /// The mesh's own triangles.
    PatientTriangles,
}

/// What produced the results: the mesh, the placement, the implant, the tissue and the run.
#[derive(Debug, Clone, Serialize)]
pub struct Inputs {
    /// The patient file as named (a path or an upload's name), or a description of the
    /// generated Table 2 plane.
    pub mesh: String,
    /// Whether the mesh is the generated Table 2 plane.
    pub mesh_generated: bool,
    /// The mesh file's unit (`mm`, `cm`, `dm`, `m`).
    pub unit: Unit,
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
    pub sim_mesh: SimMeshKind,
    /// The simulation mesh's edge used, cm (`sim_edge_cm` or its default); null on the mesh's own
    /// triangles.
    pub sim_edge_cm: Option<f64>,
    /// Holes filled up to this size across, cm; null on the mesh's own triangles.
    pub max_hole_cm: Option<f64>,
    /// `touches-vertex` or `centroid`.
    pub region_rule: Rule,
    /// Skin Young's modulus, kPa.
    pub young_kpa: f64,
    /// Skin Poisson ratio.
    pub poisson: f64,
    /// Skin thickness, cm.
    pub thickness_cm: f64,
    /// Tissue density, g/cm³.
    pub density_g_cm3: f64,
    /// `bvh` or `voxels`.
    pub detect: Detect,
    /// The solver asked for: `quasi_static` or `explicit` (every run of the job used it).
    pub solver: Solver,
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
            unit: scenario.patient.unit,
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
                SimMeshKind::Remeshed
            } else {
                SimMeshKind::PatientTriangles
            },
            sim_edge_cm,
            max_hole_cm: remeshed.then_some(request.max_hole_cm),
            region_rule: request.region_rule,
            young_kpa: job.params.layers.young / KPA,
            poisson: job.params.layers.poisson,
            thickness_cm: job.params.layers.skin_thickness,
            density_g_cm3: job.params.layers.density,
            detect: request.detect,
            solver: job.params.solver.into(),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every implant shape is reported as itself with its own sizes: the set of shapes is
    /// closed and the conversion exhaustive, so no shape can be reported as another (a shape
    /// the report did not know was once written as a round one of 0 cm).
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

    /// The enumerated fields are written as the names the contract has always had.
    #[test]
    fn enumerated_fields_keep_their_json_names() -> Result<(), serde_json::Error> {
        use serde_json::json;
        let names = [
            (serde_json::to_value(Tool::Insert)?, json!("insert")),
            (serde_json::to_value(Tool::Capi)?, json!("capi")),
            (serde_json::to_value(Tool::Python)?, json!("python")),
            (
                serde_json::to_value(JobMode::TargetGain)?,
                json!("target-gain"),
            ),
            (serde_json::to_value(Unit::Dm)?, json!("dm")),
            (
                serde_json::to_value(Rule::TouchesVertex)?,
                json!("touches-vertex"),
            ),
            (serde_json::to_value(Detect::Voxels)?, json!("voxels")),
            (
                serde_json::to_value(Solver::QuasiStatic)?,
                json!("quasi_static"),
            ),
            (serde_json::to_value(Solver::Explicit)?, json!("explicit")),
            (
                serde_json::to_value(SimMeshKind::PatientTriangles)?,
                json!("patient_triangles"),
            ),
            (
                serde_json::to_value(StopReason::StepLimit)?,
                json!("step_limit"),
            ),
            (
                serde_json::to_value(MeasuredOn::ScanRegionHolesFilled)?,
                json!("scan_region_holes_filled"),
            ),
            (
                serde_json::to_value(BandMethod::Surrogate)?,
                json!("surrogate"),
            ),
        ];
        for (value, expected) in names {
            assert_eq!(value, expected);
        }
        Ok(())
    }
}
