//! From a patient and a request to a job: the picked point snapped to the surface, the normal
//! and tangent there, the tissue-app job; and the preview a planner sees before Run (the
//! implant's footprint and the region outline on the surface, and whether the set-up succeeds).

use glam::{Quat, Vec3};
use serde::Serialize;
use tissue_app::{InsertionJob, InverseJob, Placement, SimMesh, SweepJob};
use tissue_implant::{
    default_snap_distance, select_region_with, snap_to_surface, ImplantSpec, InverseOptions,
    RegionOptions, RegionRule,
};
use tissue_mesh::TriMesh;

use crate::error::{ErrorKind, PlanError};
use crate::patient::Patient;
use crate::request::PlanRequest;
use crate::units::Rule;

/// A patient, a request, and the job they make.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The patient (as the file has it, and in cm).
    pub patient: Patient,
    /// What was asked.
    pub request: PlanRequest,
    /// The picked point, cm.
    pub point: Vec3,
    /// The nearest surface point (the region's and the implant's centre), cm.
    pub surface_point: Vec3,
    /// The surface's outward normal there.
    pub normal: Vec3,
    /// The implant's local x direction (unit, across the normal).
    pub tangent: Vec3,
    /// The job for tissue-app (its `implant.volume_cm3` is the request's volume).
    pub job: InsertionJob,
}

impl Scenario {
    /// Places the implant of `request` on `patient`.
    ///
    /// # Errors
    /// [`ErrorKind::Parameters`] for a value out of range, [`ErrorKind::Usage`] for a missing
    /// size or placement, [`ErrorKind::Placement`] for a point off the surface, a vertex out of
    /// range or a tangent along the normal.
    pub fn new(patient: Patient, request: PlanRequest) -> Result<Scenario, PlanError> {
        request.check()?;
        let shape = request.implant_shape()?;
        let point = picked_point(&request, &patient)?;
        let snapped = snap_to_surface(&patient.cm, point, default_snap_distance(&patient.cm))
            .map_err(|e| PlanError::from_implant(&e))?;
        let normal = surface_normal(&patient.cm, snapped.triangle(), snapped.barycentric());
        let tangent = tangent(normal, request.tangent, request.rotation_deg)?;
        let spec = ImplantSpec::new(shape, request.volume_cm3)
            .with_vertex_budget(request.implant_vertices);
        let job = InsertionJob {
            patient: patient.cm.clone(),
            placement: Placement::new(point, normal, tangent),
            implant: spec,
            region_radius: request.region_radius_cm,
            region: region_options(request.region_rule),
            params: request.params(),
            sim: request.sim_mesh(patient.generated),
        };
        Ok(Scenario {
            patient,
            request,
            point,
            surface_point: snapped.position(),
            normal,
            tangent,
            job,
        })
    }

    /// Centimetres per mesh unit.
    pub fn cm_per_unit(&self) -> f32 {
        self.patient.cm_per_unit()
    }

    /// The region radius the job uses (cm).
    ///
    /// # Errors
    /// A shape whose footprint radius is unknown.
    pub fn region_radius(&self) -> Result<f64, PlanError> {
        self.job.radius().map_err(|e| PlanError::from_implant(&e))
    }

    /// The simulation mesh's edge the job uses (cm), or `None` on the patient's own triangles.
    ///
    /// # Errors
    /// As [`Scenario::region_radius`].
    pub fn sim_edge(&self) -> Result<Option<f64>, PlanError> {
        self.job.sim_edge().map_err(|e| PlanError::from_implant(&e))
    }

    /// Whether the mechanics run on a simulation mesh of their own.
    pub fn remeshed(&self) -> bool {
        matches!(self.job.sim, SimMesh::Remeshed(_))
    }

    /// The expansion over weeks the request asks for (`expand_weeks`), or `None`.
    ///
    /// # Errors
    /// [`PlanRequest::expansion_protocol`]'s.
    pub fn expansion_job(&self) -> Result<Option<tissue_app::ExpansionJob>, PlanError> {
        Ok(self
            .request
            .expansion_protocol()?
            .map(|protocol| tissue_app::ExpansionJob {
                insertion: self.job.clone(),
                protocol,
                growth: self.request.growth(),
                band: self.request.band(),
            }))
    }

    /// The sweep over `volumes` (cm³) from this placement.
    ///
    /// # Errors
    /// [`check_sweep`](crate::check_sweep)'s.
    pub fn sweep_job(&self, volumes: &[f64]) -> Result<SweepJob, PlanError> {
        crate::check_sweep(volumes)?;
        Ok(SweepJob {
            base: self.job.clone(),
            volumes: volumes.to_vec(),
        })
    }

    /// The search for the volume that gives `target_gain_cm2`, between `bracket_cm3` (default:
    /// a quarter to twice the request's volume), stopping within `gain_tolerance_cm2`.
    ///
    /// # Errors
    /// [`check_search`](crate::check_search)'s.
    pub fn inverse_job(
        &self,
        target_gain_cm2: f64,
        bracket_cm3: Option<(f64, f64)>,
        gain_tolerance_cm2: f64,
    ) -> Result<InverseJob, PlanError> {
        let bracket = crate::check_search(
            target_gain_cm2,
            bracket_cm3,
            gain_tolerance_cm2,
            self.request.volume_cm3,
        )?;
        Ok(InverseJob {
            base: self.job.clone(),
            target_gain: target_gain_cm2,
            bracket,
            options: InverseOptions {
                gain_tolerance: gain_tolerance_cm2,
                ..InverseOptions::default()
            },
        })
    }

    /// What the planner sees before Run: the footprint and the region outline on the surface,
    /// and the set-up's verdict (the same [`tissue_app::prepare`] the run starts with, so a
    /// placement that cannot run is refused here with the run's own message).
    pub fn preview(&self) -> Preview {
        let _span = tracing::info_span!("planner_preview").entered();
        let footprint = self.footprint();
        let mut preview = Preview {
            ok: false,
            error: None,
            region_radius_cm: None,
            sim_edge_cm: None,
            region_vertices: 0,
            footprint,
            region_outline: Vec::new(),
        };
        let radius = match self.region_radius() {
            Ok(r) => r,
            Err(e) => {
                preview.error = Some(e);
                return preview;
            }
        };
        preview.region_radius_cm = Some(radius);
        match select_region_with(&self.patient.cm, self.point, radius, &self.job.region) {
            Ok(selection) => {
                let p = selection.mesh().positions();
                preview.region_vertices = selection.mesh().vertex_count();
                preview.region_outline = selection
                    .boundary_loops()
                    .iter()
                    .map(|l| l.iter().map(|&v| p[v as usize].to_array()).collect())
                    .collect();
            }
            Err(e) => {
                preview.error = Some(PlanError::from_implant(&e));
                return preview;
            }
        }
        match self.sim_edge() {
            Ok(h) => preview.sim_edge_cm = h,
            Err(e) => {
                preview.error = Some(e);
                return preview;
            }
        }
        match tissue_app::prepare(&self.job) {
            Ok(_) => preview.ok = true,
            Err(e) => preview.error = Some(PlanError::from_implant(&e)),
        }
        preview
    }

    /// The implant's base outline laid on the surface: the flat outline in the tangent plane,
    /// each point moved to the nearest surface point and lifted [`FOOTPRINT_LIFT_CM`] along the
    /// normal (empty if the implant cannot be built).
    pub fn footprint(&self) -> Vec<[f32; 3]> {
        let Ok(implant) = self.job.implant.build() else {
            return Vec::new();
        };
        let bitangent = self.normal.cross(self.tangent);
        let positions = implant.mesh().positions();
        let snap = default_snap_distance(&self.patient.cm).max(1.0);
        implant
            .rim()
            .map(|v| {
                let local = positions[v as usize];
                let flat = self.surface_point + self.tangent * local.x + bitangent * local.y;
                let on =
                    snap_to_surface(&self.patient.cm, flat, snap).map_or(flat, |s| s.position());
                (on + self.normal * FOOTPRINT_LIFT_CM).to_array()
            })
            .collect()
    }
}

/// The search's default tolerance on the area gain, cm².
pub fn default_gain_tolerance() -> f64 {
    InverseOptions::default().gain_tolerance
}

/// How far the drawn footprint is lifted off the surface (cm), so that it is not hidden in it.
pub const FOOTPRINT_LIFT_CM: f32 = 0.02;

/// The set-up's verdict and the outlines to draw, before Run.
#[derive(Debug, Clone, Serialize)]
pub struct Preview {
    /// Whether the set-up succeeds: the run can start.
    pub ok: bool,
    /// Why not.
    pub error: Option<PlanError>,
    /// The region radius used, cm.
    pub region_radius_cm: Option<f64>,
    /// The simulation mesh's edge, cm (null on the patient's own triangles).
    pub sim_edge_cm: Option<f64>,
    /// Vertices of the patient's region.
    pub region_vertices: usize,
    /// The implant's base outline on the surface (closed; cm).
    pub footprint: Vec<[f32; 3]>,
    /// The region's boundary loops on the surface (cm).
    pub region_outline: Vec<Vec<[f32; 3]>>,
}

fn region_options(rule: Rule) -> RegionOptions {
    RegionOptions {
        rule: match rule {
            Rule::TouchesVertex => RegionRule::TouchesVertex,
            Rule::Centroid => RegionRule::Centroid,
        },
        ..RegionOptions::default()
    }
}

/// The picked point (cm): `vertex`, `at`, or the origin of the generated plane.
fn picked_point(request: &PlanRequest, patient: &Patient) -> Result<Vec3, PlanError> {
    if let Some(v) = request.vertex {
        return patient
            .cm
            .positions()
            .get(v as usize)
            .copied()
            .ok_or_else(|| {
                PlanError::field(
                    ErrorKind::Placement,
                    "vertex",
                    format!(
                        "`vertex` {v} is out of range: the mesh has {} vertices (0 to {})",
                        patient.cm.vertex_count(),
                        patient.cm.vertex_count().saturating_sub(1)
                    ),
                )
            });
    }
    match (request.at, patient.generated) {
        (Some(at), _) => Ok(Vec3::from_array(at) * patient.cm_per_unit()),
        (None, true) => Ok(Vec3::ZERO),
        (None, false) => Err(PlanError::field(
            ErrorKind::Usage,
            "at",
            "a patient file needs `at` X,Y,Z (in the mesh's unit) or `vertex` N: where the \
             implant goes",
        )),
    }
}

/// The outward normal at a surface point: the area-weighted vertex normals of its triangle,
/// interpolated with its barycentric coordinates (the triangle's own normal where they cancel).
fn surface_normal(patient: &TriMesh, triangle: u32, barycentric: [f32; 3]) -> Vec3 {
    let normals = patient.vertex_normals();
    let tri = patient.triangles()[triangle as usize];
    let n = tri
        .iter()
        .zip(barycentric)
        .map(|(&v, w)| normals[v as usize] * w)
        .fold(Vec3::ZERO, |a, b| a + b)
        .normalize_or_zero();
    if n != Vec3::ZERO {
        return n;
    }
    patient.triangle_normals()[triangle as usize]
}

/// The tangent: `wanted` (or +x, or +y near ±x) with its part along `normal` removed, then
/// turned by `rotation_deg` about the normal (counter-clockwise seen from outside).
fn tangent(normal: Vec3, wanted: Option<[f32; 3]>, rotation_deg: f32) -> Result<Vec3, PlanError> {
    let axis = match wanted {
        Some(t) => Vec3::from_array(t),
        // cos 25° ≈ 0.906
        None if normal.x.abs() > 0.906 => Vec3::Y,
        None => Vec3::X,
    };
    let t = (axis - normal * axis.dot(normal)).normalize_or_zero();
    if t == Vec3::ZERO {
        return Err(PlanError::field(
            ErrorKind::Placement,
            "tangent",
            format!(
                "`tangent` {axis} is along the surface normal {normal} at the point: give a \
                 direction across the skin"
            ),
        ));
    }
    if rotation_deg == 0.0 {
        return Ok(t);
    }
    let turned = Quat::from_axis_angle(normal, rotation_deg.to_radians()) * t;
    Ok((turned - normal * turned.dot(normal)).normalize_or(t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patient::Shipped;

    #[test]
    fn tangent_is_x_across_a_z_normal_y_near_x_and_turns_counter_clockwise() {
        assert_eq!(tangent(Vec3::Z, None, 0.0).ok(), Some(Vec3::X));
        assert_eq!(tangent(Vec3::X, None, 0.0).ok(), Some(Vec3::Y));
        assert!(tangent(Vec3::Z, Some([0.0, 0.0, 2.0]), 0.0).is_err());
        let t = tangent(Vec3::Z, None, 90.0).unwrap_or(Vec3::ZERO);
        assert!((t - Vec3::Y).length() < 1e-6, "{t}");
    }

    #[test]
    fn the_table2_preview_is_the_runs_region_and_a_7cm_circle() -> Result<(), PlanError> {
        let s = Scenario::new(Patient::shipped(Shipped::Table2)?, PlanRequest::default())?;
        assert_eq!(s.normal, Vec3::Z);
        let p = s.preview();
        assert!(p.ok, "{:?}", p.error);
        assert_eq!(p.region_radius_cm, Some(5.25));
        // The footprint lies on the plane (lifted), at the base's radius, 3.5 cm.
        assert!(p.footprint.len() > 16);
        for q in &p.footprint {
            let r = Vec3::from_array(*q).truncate().length();
            assert!((r - 3.5).abs() < 0.05, "footprint point at r = {r}");
            assert!((q[2] - FOOTPRINT_LIFT_CM).abs() < 1e-6);
        }
        // One outline loop, every point within one grid edge of the 5.25 cm circle's outside.
        assert_eq!(p.region_outline.len(), 1);
        let edge = 20.0 / 64.0;
        for q in &p.region_outline[0] {
            let r = Vec3::from_array(*q).truncate().length();
            assert!(
                r > 5.25 - 1e-4 && r < 5.25 + 1.5 * edge,
                "outline point at r = {r}"
            );
        }
        Ok(())
    }

    #[test]
    fn a_placement_at_the_border_is_refused_before_run_with_the_runs_message(
    ) -> Result<(), PlanError> {
        let request = PlanRequest {
            at: Some([8.0, 0.0, 0.0]),
            ..PlanRequest::default()
        };
        let s = Scenario::new(Patient::shipped(Shipped::Table2)?, request)?;
        let p = s.preview();
        assert!(!p.ok);
        let e = p.error.map(|e| e.kind);
        assert_eq!(e, Some(ErrorKind::Placement));
        assert!(
            !p.footprint.is_empty(),
            "the footprint is drawn even when refused"
        );
        Ok(())
    }
}
