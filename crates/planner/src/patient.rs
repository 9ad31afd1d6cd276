//! The patient: a surface read from a file or bytes (OBJ, PLY, STL, VTK) in its unit and scaled
//! to cm, or one of the meshes shipped with the program; and the summary a planner reads before
//! placing anything (what `meshinfo` says of a surface).

use std::path::Path;

use glam::Vec3;
use serde::Serialize;
use tissue_mesh::TriMesh;

use crate::error::{ErrorKind, PlanError};
use crate::units::Unit;

/// The Table 2 plane: 65 × 65 vertices, 20 cm square, centred at the origin in z = 0 (the same
/// mesh as `fixtures/plane_20cm_65.obj`).
pub const TABLE2_VERTICES_PER_SIDE: u32 = 65;
/// The Table 2 plane's side (cm).
pub const TABLE2_SIDE_CM: f32 = 20.0;

/// A mesh shipped with the program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shipped {
    /// The thesis's Table 2 plane, generated (cm).
    Table2,
    /// MakeHuman's chest, an open patch (dm, CC0; `fixtures/makehuman_chest_open.obj`).
    Chest,
    /// MakeHuman's head, an open patch (dm, CC0; `fixtures/makehuman_head_open.obj`).
    Head,
}

impl Shipped {
    /// Every shipped mesh, the default first.
    pub const ALL: [Shipped; 3] = [Shipped::Table2, Shipped::Chest, Shipped::Head];

    /// Its short name (`table2`, `chest`, `head`).
    pub fn id(self) -> &'static str {
        match self {
            Shipped::Table2 => "table2",
            Shipped::Chest => "chest",
            Shipped::Head => "head",
        }
    }

    /// The mesh of `id`, or `None`.
    pub fn from_id(id: &str) -> Option<Shipped> {
        Shipped::ALL.into_iter().find(|s| s.id() == id)
    }

    /// What a person reads.
    pub fn label(self) -> &'static str {
        match self {
            Shipped::Table2 => "Table 2 plane: 20 cm skin square, 65 × 65 vertices (cm)",
            Shipped::Chest => "MakeHuman chest patch (dm, CC0)",
            Shipped::Head => "MakeHuman head patch (dm, CC0)",
        }
    }

    /// The file's unit.
    pub fn unit(self) -> Unit {
        match self {
            Shipped::Table2 => Unit::Cm,
            Shipped::Chest | Shipped::Head => Unit::Dm,
        }
    }

    /// A placement that runs with the default implant: the plane's centre, the chest's vertex
    /// of the README's example, the top of the forehead.
    pub fn suggested_vertex(self, patient: &TriMesh) -> u32 {
        let toward = |dir: Vec3| {
            patient
                .positions()
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.dot(dir).total_cmp(&b.1.dot(dir)))
                .map_or(0, |(i, _)| i as u32)
        };
        match self {
            Shipped::Table2 => {
                let n = TABLE2_VERTICES_PER_SIDE;
                (n / 2) * n + n / 2
            }
            Shipped::Chest => 2277,
            Shipped::Head => toward(Vec3::new(0.0, 1.0, 1.0)),
        }
    }
}

const CHEST_OBJ: &[u8] = include_bytes!("../../../fixtures/makehuman_chest_open.obj");
const HEAD_OBJ: &[u8] = include_bytes!("../../../fixtures/makehuman_head_open.obj");

/// The patient surface as the file has it and in cm.
#[derive(Debug, Clone)]
pub struct Patient {
    /// As the file has it (mesh unit).
    pub file: TriMesh,
    /// Scaled to cm.
    pub cm: TriMesh,
    /// The file's unit.
    pub unit: Unit,
    /// The path or name, or a description of the generated plane.
    pub label: String,
    /// Whether it is the generated Table 2 plane.
    pub generated: bool,
}

impl Patient {
    /// The Table 2 plane (cm).
    ///
    /// # Errors
    /// None in practice (the grid is valid); [`ErrorKind::Run`] if it could not be made.
    pub fn table2() -> Result<Patient, PlanError> {
        let plane = tissue_mesh::grid(TABLE2_VERTICES_PER_SIDE, TABLE2_SIDE_CM).map_err(|e| {
            PlanError::new(
                ErrorKind::Run,
                format!("cannot make the Table 2 plane: {e}"),
            )
        })?;
        Ok(Patient {
            file: plane.clone(),
            cm: plane,
            unit: Unit::Cm,
            label: format!(
                "generated: Table 2 plane, {TABLE2_VERTICES_PER_SIDE} x \
                 {TABLE2_VERTICES_PER_SIDE} vertices, {TABLE2_SIDE_CM} cm (= \
                 fixtures/plane_20cm_65.obj)"
            ),
            generated: true,
        })
    }

    /// A shipped mesh.
    ///
    /// # Errors
    /// None in practice (the shipped files are valid).
    pub fn shipped(which: Shipped) -> Result<Patient, PlanError> {
        let bytes = match which {
            Shipped::Table2 => return Patient::table2(),
            Shipped::Chest => CHEST_OBJ,
            Shipped::Head => HEAD_OBJ,
        };
        let name = format!("{}.obj", which.id());
        let mut p = Patient::parse(bytes, &name, which.unit())?;
        p.label = which.label().to_owned();
        Ok(p)
    }

    /// Reads a patient file (`.obj`, `.ply`, `.stl`, `.vtk` by extension) in `unit`.
    ///
    /// # Errors
    /// [`ErrorKind::Input`] for a missing or unsupported file, [`ErrorKind::Mesh`] for a
    /// malformed one or an invalid surface (the loader's message, naming line or element).
    pub fn read(path: &Path, unit: Unit) -> Result<Patient, PlanError> {
        let mesh = tissue_meshio::read_surface(path).map_err(|e| PlanError::from_mesh_io(&e))?;
        Patient::from_mesh(mesh, unit, path.display().to_string())
    }

    /// Parses a patient file held in memory; `name`'s extension picks the format and stands for
    /// the file in messages.
    ///
    /// # Errors
    /// As [`Patient::read`].
    pub fn parse(bytes: &[u8], name: &str, unit: Unit) -> Result<Patient, PlanError> {
        let data = tissue_meshio::parse_surface_data(bytes, name)
            .map_err(|e| PlanError::from_mesh_io(&e))?;
        let mesh = TriMesh::new(data.positions, data.triangles).map_err(|source| {
            PlanError::from_mesh_io(&tissue_meshio::MeshIoError::Invalid {
                path: name.into(),
                source,
            })
        })?;
        Patient::from_mesh(mesh, unit, name.to_owned())
    }

    /// A patient from a mesh in `unit`.
    ///
    /// # Errors
    /// [`ErrorKind::Mesh`] when the mesh is no longer valid once scaled to cm.
    pub fn from_mesh(mesh: TriMesh, unit: Unit, label: String) -> Result<Patient, PlanError> {
        let scale = unit.cm_per_unit();
        let cm = if scale == 1.0 {
            mesh.clone()
        } else {
            let scaled = mesh.positions().iter().map(|&p| p * scale).collect();
            mesh.with_positions(scaled).map_err(|e| {
                PlanError::field(
                    ErrorKind::Mesh,
                    "unit",
                    format!("{label}: not valid once scaled to cm: {e}; check the `unit`"),
                )
            })?
        };
        Ok(Patient {
            file: mesh,
            cm,
            unit,
            label,
            generated: false,
        })
    }

    /// Centimetres per mesh unit.
    pub fn cm_per_unit(&self) -> f32 {
        self.unit.cm_per_unit()
    }

    /// What a planner reads before placing anything (in cm).
    pub fn summary(&self) -> MeshSummary {
        MeshSummary::of(&self.cm)
    }
}

/// A surface's counts, size, borders and defects (cm): `meshinfo`'s summary of a patient.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshSummary {
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Surface area, cm².
    pub area_cm2: f64,
    /// Whether the surface is closed (watertight).
    pub closed: bool,
    /// Connected pieces.
    pub components: usize,
    /// The borders: the scan's outline and its holes, longest first.
    pub boundary_loops: Vec<LoopSummary>,
    /// The bounding box, cm.
    pub bounding_box_cm: BoxSummary,
    /// The median edge length, cm.
    pub median_edge_cm: f64,
    /// What is odd about the surface but does not stop a run (unreferenced vertices, …).
    pub defects: Vec<DefectSummary>,
}

/// A border loop.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoopSummary {
    /// Its edges (= vertices).
    pub edges: usize,
    /// Its length, cm.
    pub length_cm: f64,
}

/// An axis-aligned box, cm.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoxSummary {
    /// Lowest corner.
    pub min: [f32; 3],
    /// Highest corner.
    pub max: [f32; 3],
    /// `max − min`.
    pub size: [f32; 3],
}

/// A defect of the surface.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DefectSummary {
    /// `error` or `warning`.
    pub severity: &'static str,
    /// The defect's kind, e.g. `UnreferencedVertex`.
    pub kind: String,
    /// What and where.
    pub message: String,
}

impl MeshSummary {
    /// The summary of `mesh` (its units are the summary's).
    pub fn of(mesh: &TriMesh) -> MeshSummary {
        let topo = mesh.topology();
        let p = mesh.positions();
        let length =
            |a: u32, b: u32| (p[a as usize].as_dvec3() - p[b as usize].as_dvec3()).length();
        let mut boundary_loops: Vec<LoopSummary> = topo
            .boundary_loops()
            .iter()
            .map(|l| LoopSummary {
                edges: l.len(),
                length_cm: (0..l.len())
                    .map(|i| length(l[i], l[(i + 1) % l.len()]))
                    .sum(),
            })
            .collect();
        boundary_loops.sort_by(|a, b| b.length_cm.total_cmp(&a.length_cm));
        let mut edges: Vec<f64> = topo.edges().iter().map(|&[a, b]| length(a, b)).collect();
        let median_edge_cm = if edges.is_empty() {
            0.0
        } else {
            let mid = edges.len() / 2;
            *edges.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        let bbox = mesh.bounding_box();
        let defects = tissue_mesh::diagnose(mesh.positions(), mesh.triangles())
            .iter()
            .map(|d| DefectSummary {
                severity: if d.is_warning() { "warning" } else { "error" },
                kind: format!("{d:?}")
                    .split(|c: char| !c.is_alphanumeric())
                    .next()
                    .unwrap_or("")
                    .to_owned(),
                message: d.to_string(),
            })
            .collect();
        MeshSummary {
            vertices: mesh.vertex_count(),
            triangles: mesh.triangle_count(),
            area_cm2: mesh.area(),
            closed: mesh.is_closed(),
            components: topo.component_count(),
            boundary_loops,
            bounding_box_cm: BoxSummary {
                min: bbox.min.to_array(),
                max: bbox.max.to_array(),
                size: (bbox.max - bbox.min).to_array(),
            },
            median_edge_cm,
            defects,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_meshes_load_in_cm_with_their_summaries() -> Result<(), PlanError> {
        let plane = Patient::shipped(Shipped::Table2)?;
        let s = plane.summary();
        assert_eq!((s.vertices, s.triangles), (65 * 65, 2 * 64 * 64));
        assert!((s.area_cm2 - 400.0).abs() < 1e-6, "{}", s.area_cm2);
        assert_eq!(s.boundary_loops.len(), 1);
        assert!((s.boundary_loops[0].length_cm - 80.0).abs() < 1e-4);
        assert!(
            (s.median_edge_cm - 20.0 / 64.0).abs() < 1e-6,
            "{}",
            s.median_edge_cm
        );
        let centre = Shipped::Table2.suggested_vertex(&plane.cm) as usize;
        assert!(plane.cm.positions()[centre].length() < 1e-6);
        let head = Patient::shipped(Shipped::Head)?;
        assert_eq!(head.file.vertex_count(), 4257);
        // dm on file, cm inside: the head is about 2 dm = 20 cm across.
        let size = head.summary().bounding_box_cm.size;
        assert!((10.0..40.0).contains(&size[0]), "{size:?}");
        assert!(!head.summary().closed);
        Ok(())
    }

    #[test]
    fn a_broken_file_gives_the_loaders_message() {
        let e = Patient::parse(b"v 0 0 0\nf 1 2 3\n", "broken.obj", Unit::Mm).err();
        let e = e
            .map(|e| (e.kind, e.message))
            .unwrap_or((ErrorKind::Run, String::new()));
        assert!(matches!(e.0, ErrorKind::Mesh), "{e:?}");
        assert!(e.1.contains("broken.obj"), "{}", e.1);
        let e = Patient::parse(b"", "scan.xyz", Unit::Mm).err();
        assert_eq!(e.map(|e| e.kind), Some(ErrorKind::Input));
    }
}
