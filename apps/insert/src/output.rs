//! The output files: the deformed patient (OBJ, PLY, STL, VTK with fields), the JSON report and
//! the PNG, staged as hidden temporary files beside their targets and renamed into place only
//! once every one of them was written; a failure or Ctrl-C removes the staged files.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;
use tissue_app::PlannedInsertion;
use tissue_mesh::TriMesh;
use tissue_meshio::{FieldValues, SurfaceFormat, VertexField};
use tissue_render::{before_after, BeforeAfterOptions};

use crate::cli::{Cli, ColorBy};
use crate::failure::{code, Failure};
use crate::progress::Interrupt;
use crate::setup::Scenario;

/// Every output path of the command line.
fn targets(cli: &Cli) -> Vec<&Path> {
    cli.out
        .iter()
        .map(PathBuf::as_path)
        .chain(cli.report.as_deref())
        .chain(cli.png.as_deref())
        .collect()
}

/// Refuses, before anything runs, an output whose folder does not exist.
pub fn check_targets(cli: &Cli) -> Result<(), Failure> {
    for path in targets(cli) {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !dir.is_dir() {
            return Err(Failure::new(
                code::OUTPUT,
                format!(
                    "cannot write {}: the folder {} does not exist; create it or pick another path",
                    path.display(),
                    dir.display()
                ),
            ));
        }
        if path.is_dir() {
            return Err(Failure::new(
                code::OUTPUT,
                format!(
                    "cannot write {}: it is a folder; give a file name",
                    path.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Output files written to hidden temporary names, waiting to be renamed into place.
#[derive(Debug, Default)]
pub struct Staged {
    files: Vec<(PathBuf, PathBuf)>,
}

impl Staged {
    /// A temporary name beside `target`: `.NAME.insert-PID.EXT` (the extension kept).
    fn stage(&mut self, target: &Path) -> PathBuf {
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "output".to_owned());
        let ext = target
            .extension()
            .map(|e| format!(".{}", e.to_string_lossy()))
            .unwrap_or_default();
        let tmp_name = format!(
            ".{name}.insert-{}-{}{ext}",
            std::process::id(),
            self.files.len()
        );
        let tmp = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.join(tmp_name),
            _ => PathBuf::from(tmp_name),
        };
        self.files.push((tmp.clone(), target.to_path_buf()));
        tmp
    }

    /// Stages `bytes` for `target`.
    pub fn bytes(&mut self, target: &Path, bytes: &[u8], what: &str) -> Result<(), Failure> {
        let tmp = self.stage(target);
        let write = || -> std::io::Result<()> {
            let mut file = File::create(&tmp)?;
            file.write_all(bytes)?;
            file.sync_all()
        };
        write().map_err(|e| Failure::output(what, format!("{}: {e}", target.display())))
    }

    /// Stages the mesh `mesh` for `target` in the format of its extension; VTK gets `fields`.
    pub fn mesh(
        &mut self,
        target: &Path,
        mesh: &TriMesh,
        fields: &[VertexField<'_>],
    ) -> Result<(), Failure> {
        let tmp = self.stage(target);
        let written = match SurfaceFormat::from_path(target) {
            Some(SurfaceFormat::Obj) => tissue_meshio::write_obj(&tmp, mesh),
            Some(SurfaceFormat::Ply) => tissue_meshio::write_ply(&tmp, mesh),
            Some(SurfaceFormat::Stl) => tissue_meshio::write_stl(&tmp, mesh),
            Some(SurfaceFormat::Vtk) => tissue_meshio::write_vtk(&tmp, mesh, fields),
            _ => {
                return Err(Failure::new(
                    code::USAGE,
                    format!(
                        "--out {}: the extension must be .obj, .ply, .stl or .vtk",
                        target.display()
                    ),
                ))
            }
        };
        written.map_err(|e| Failure::output("mesh", format!("{} ({e})", target.display())))
    }

    /// Renames every staged file into place, unless Ctrl-C was pressed.
    pub fn commit(mut self, interrupt: &Interrupt) -> Result<Vec<PathBuf>, Failure> {
        interrupt.check()?;
        let mut done = Vec::new();
        for (tmp, target) in std::mem::take(&mut self.files) {
            if let Err(e) = std::fs::rename(&tmp, &target) {
                let _ = std::fs::remove_file(&tmp);
                return Err(Failure::output(
                    "output",
                    format!("{}: {e}", target.display()),
                ));
            }
            done.push(target);
        }
        Ok(done)
    }
}

impl Drop for Staged {
    /// Removes what was staged but not committed.
    fn drop(&mut self) {
        for (tmp, _) in &self.files {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// The patient before and after, in the mesh's unit, with per-vertex fields.
#[derive(Debug, Clone)]
pub struct PatientResult {
    /// The patient before (mesh unit).
    pub before: TriMesh,
    /// The patient after (mesh unit). Vertices that did not move keep the file's positions.
    pub after: TriMesh,
    /// How far each vertex moved (mesh unit); 0 outside the region.
    pub displacement: Vec<f32>,
    /// Area after / area before around each region vertex; 0 outside the region.
    pub stretch: Vec<f32>,
    /// 1 for a region vertex, 0 outside.
    pub in_region: Vec<f32>,
    /// The areas and volume on the scan's own triangles (a remeshed run).
    pub scan: Option<tissue_implant::ScanResult>,
}

impl PatientResult {
    /// The patient after `planned` in the mesh's unit, and its fields.
    pub fn new(scenario: &Scenario, planned: &PlannedInsertion) -> Result<Self, Failure> {
        let on_patient = planned
            .on_patient(&scenario.patient)
            .map_err(|e| Failure::from_implant(&e))?;
        let scale = scenario.cm_per_unit();
        // Vertices that did not move keep the file's positions bit for bit.
        let after_positions: Vec<Vec3> = on_patient
            .mesh
            .positions()
            .iter()
            .zip(scenario.patient_file.positions())
            .zip(scenario.patient.positions())
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
        let before = scenario.patient_file.clone();
        let after = before
            .with_positions(after_positions)
            .map_err(|e| Failure::new(code::RUN, format!("the result is not a valid mesh: {e}")))?;
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
            displacement: on_patient.displacement.iter().map(|d| d / scale).collect(),
            stretch,
            in_region,
            scan: on_patient.scan,
        })
    }

    /// The VTK point fields.
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

    /// The before/after picture, coloured by `color` (stretch 1 outside the region).
    pub fn picture(
        &self,
        color: ColorBy,
        size: (u32, u32),
        unit: &str,
    ) -> Result<Vec<u8>, Failure> {
        let (field, title) = match color {
            ColorBy::Displacement => (self.displacement.clone(), format!("displacement, {unit}")),
            ColorBy::Stretch => (
                self.stretch
                    .iter()
                    .zip(&self.in_region)
                    .map(|(&s, &inside)| if inside > 0.0 { s } else { 1.0 })
                    .collect(),
                "stretch, area after/before".to_owned(),
            ),
        };
        let options = BeforeAfterOptions {
            width: size.0,
            height: size.1,
            title,
            ..BeforeAfterOptions::default()
        };
        let image = before_after(&self.before, &self.after, &field, &options)
            .map_err(|e| Failure::output("picture", e))?;
        image
            .encode_png()
            .map_err(|e| Failure::output("picture", e))
    }
}
