//! The result on the patient: every vertex of the patient after the run, in the file's unit,
//! with its per-vertex fields, written as mesh files or drawn as a picture.

use std::path::Path;

use glam::Vec3;
use tissue_app::PlannedInsertion;
use tissue_implant::ScanResult;
use tissue_mesh::TriMesh;
use tissue_meshio::{FieldValues, SurfaceFormat, VertexField};
use tissue_render::{before_after, BeforeAfterOptions};

use crate::error::{ErrorKind, PlanError};
use crate::scenario::Scenario;
use crate::units::ColorBy;

/// Whether `path`'s extension names a mesh format a result can be written in (`.obj`, `.ply`,
/// `.stl`, `.vtk`).
pub fn is_mesh_path(path: &Path) -> bool {
    SurfaceFormat::from_path(path).is_some()
}

/// The patient before and after, in the mesh's unit, with per-vertex fields.
#[derive(Debug, Clone)]
pub struct PatientResult {
    /// The patient before (mesh unit).
    pub before: TriMesh,
    /// The patient after (mesh unit). Vertices that did not move keep the file's positions bit
    /// for bit.
    pub after: TriMesh,
    /// The patient after, cm.
    pub after_cm: TriMesh,
    /// How far each vertex moved (mesh unit); 0 outside the region.
    pub displacement: Vec<f32>,
    /// Area after / area before around each region vertex; 0 outside the region.
    pub stretch: Vec<f32>,
    /// 1 for a region vertex, 0 outside.
    pub in_region: Vec<f32>,
    /// The areas and volume on the scan's own triangles (a remeshed run).
    pub scan: Option<ScanResult>,
}

impl PatientResult {
    /// The patient after `planned`, in the mesh's unit, and its fields.
    ///
    /// # Errors
    /// [`ErrorKind::Run`] when the mapping fails or the result is not a valid mesh.
    pub fn new(scenario: &Scenario, planned: &PlannedInsertion) -> Result<Self, PlanError> {
        let _span = tracing::info_span!("planner_on_patient").entered();
        let on_patient = planned
            .on_patient(&scenario.patient.cm)
            .map_err(|e| PlanError::from_implant(&e))?;
        let scale = scenario.cm_per_unit();
        let after_positions: Vec<Vec3> = on_patient
            .mesh
            .positions()
            .iter()
            .zip(scenario.patient.file.positions())
            .zip(scenario.patient.cm.positions())
            .map(|((&c, &f), &rest)| {
                if c == rest {
                    f
                } else if scale == 1.0 {
                    c
                } else {
                    c / scale
                }
            })
            .collect();
        let before = scenario.patient.file.clone();
        let after = before.with_positions(after_positions).map_err(|e| {
            PlanError::new(
                ErrorKind::Run,
                format!("the result is not a valid mesh: {e}"),
            )
        })?;
        let in_region: Vec<f32> = on_patient
            .in_region
            .iter()
            .map(|&inside| if inside { 1.0 } else { 0.0 })
            .collect();
        let stretch = on_patient
            .stretch
            .iter()
            .zip(&on_patient.in_region)
            .map(|(&s, &inside)| if inside { s } else { 0.0 })
            .collect();
        Ok(PatientResult {
            before,
            after,
            after_cm: on_patient.mesh,
            displacement: on_patient.displacement.iter().map(|d| d / scale).collect(),
            stretch,
            in_region,
            scan: on_patient.scan,
        })
    }

    /// The VTK point fields: `displacement`, `stretch`, `in_region`.
    pub fn fields(&self) -> [VertexField<'_>; 3] {
        [
            VertexField {
                name: "displacement",
                values: FieldValues::Scalars(&self.displacement),
            },
            VertexField {
                name: "stretch",
                values: FieldValues::Scalars(&self.stretch),
            },
            VertexField {
                name: "in_region",
                values: FieldValues::Scalars(&self.in_region),
            },
        ]
    }

    /// Stretch with 1 outside the region (what a colour map shows).
    pub fn stretch_or_one(&self) -> Vec<f32> {
        self.stretch
            .iter()
            .zip(&self.in_region)
            .map(|(&s, &inside)| if inside > 0.0 { s } else { 1.0 })
            .collect()
    }

    /// Writes the patient after, atomically, in the format of `path`'s extension (`.obj`,
    /// `.ply`, `.stl`, `.vtk`; VTK carries the fields), in the mesh's unit.
    ///
    /// # Errors
    /// [`ErrorKind::Usage`] for another extension, [`ErrorKind::Output`] when writing fails.
    pub fn write_mesh(&self, path: &Path) -> Result<(), PlanError> {
        let written = match SurfaceFormat::from_path(path) {
            Some(SurfaceFormat::Obj) => tissue_meshio::write_obj(path, &self.after),
            Some(SurfaceFormat::Ply) => tissue_meshio::write_ply(path, &self.after),
            Some(SurfaceFormat::Stl) => tissue_meshio::write_stl(path, &self.after),
            Some(SurfaceFormat::Vtk) => tissue_meshio::write_vtk(path, &self.after, &self.fields()),
            _ => {
                return Err(PlanError::field(
                    ErrorKind::Usage,
                    "out",
                    format!(
                        "`out` {}: the extension must be .obj, .ply, .stl or .vtk",
                        path.display()
                    ),
                ))
            }
        };
        written.map_err(|e| {
            PlanError::new(
                ErrorKind::Output,
                format!(
                    "cannot write the mesh: {} ({e}); check the folder exists and is writable",
                    path.display()
                ),
            )
        })
    }

    /// The before/after picture as PNG bytes, coloured by `color` (stretch 1 outside the
    /// region); `unit` labels the displacement's colour bar.
    ///
    /// # Errors
    /// [`ErrorKind::Output`] when drawing or encoding fails.
    pub fn picture(
        &self,
        color: ColorBy,
        size: (u32, u32),
        unit: &str,
    ) -> Result<Vec<u8>, PlanError> {
        let (field, title) = match color {
            ColorBy::Displacement => (self.displacement.clone(), format!("displacement, {unit}")),
            ColorBy::Stretch => (
                self.stretch_or_one(),
                "stretch, area after/before".to_owned(),
            ),
        };
        let options = BeforeAfterOptions {
            width: size.0,
            height: size.1,
            title,
            ..BeforeAfterOptions::default()
        };
        let output = |e: &dyn std::fmt::Display| {
            PlanError::new(ErrorKind::Output, format!("cannot draw the picture: {e}"))
        };
        let image =
            before_after(&self.before, &self.after, &field, &options).map_err(|e| output(&e))?;
        image.encode_png().map_err(|e| output(&e))
    }
}
