//! Organs: the shipped ones (the bunny and the liver surfaces in `fixtures/`, tetrahedralised on
//! load; the appendix, generated) and uploads (a closed surface, tetrahedralised, or a tet mesh),
//! placed on the tray: centred on x = z = 0 with its lowest node on y = 0 (y up).

use glam::{Vec3, Vec3A};
use tissue_mesh::{TetMesh, TriMesh};
use tissue_pbd::{
    ColliderShape, ContactParams, Floor, Material, OrientedBox, SoftBody, StepSettings,
    VoxelCollider,
};
use tissue_tetra::{tetrahedralize, QualityReport, TetCount, TetraError, TetraOptions};

use crate::error::SceneError;

/// The most tetrahedra a real-time session takes (a step must stay well under 16 ms). A closed
/// surface is refused before it is meshed when `tissue-tetra`'s estimate (within about 10 % of
/// the count it makes) is above this, and the mesher stops if its work outgrows it, so an upload
/// costs at most about a second of meshing; a tet mesh is refused before it is built.
pub const MAX_TETS: usize = 150_000;

/// How an organ is held in the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Setting {
    /// Free, lying on the tray (a static voxel collider whose top is y = 0).
    Tray,
    /// The appendix: its base (x below [`APPENDIX_BASE_X`]) pinned to the cecum, lying on the
    /// abdominal wall (a floor at y = 0).
    Appendix,
    /// A beam along x clamped at x = 0 (its nodes there pinned), nothing under it
    /// ([`Organ::cantilever`]): a check of the material against beam theory.
    Cantilever,
}

/// Nodes of the appendix with x below this (cm) are pinned: its base.
pub const APPENDIX_BASE_X: f32 = -3.7;

/// An organ shipped with the program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShippedOrgan {
    /// The Stanford Bunny of the PositionBasedDynamics demos, 10 cm (`fixtures/bunny_10k.obj`).
    Bunny,
    /// SOFA's liver, 16 cm across (`fixtures/liver_sofa.obj`).
    Liver,
    /// An appendix-like organ, 8 × 2 × 2 cm, 32 × 8 × 8 cells, pinned at its base.
    Appendix,
}

const BUNNY_OBJ: &[u8] = include_bytes!("../../../fixtures/bunny_10k.obj");
const LIVER_OBJ: &[u8] = include_bytes!("../../../fixtures/liver_sofa.obj");

impl ShippedOrgan {
    /// Every shipped organ, the default first.
    pub const ALL: [ShippedOrgan; 3] = [
        ShippedOrgan::Bunny,
        ShippedOrgan::Liver,
        ShippedOrgan::Appendix,
    ];

    /// Its short name.
    pub fn id(self) -> &'static str {
        match self {
            ShippedOrgan::Bunny => "bunny",
            ShippedOrgan::Liver => "liver",
            ShippedOrgan::Appendix => "appendix",
        }
    }

    /// The organ of `id`.
    pub fn from_id(id: &str) -> Option<ShippedOrgan> {
        ShippedOrgan::ALL.into_iter().find(|o| o.id() == id)
    }

    /// What a person reads.
    pub fn label(self) -> &'static str {
        match self {
            ShippedOrgan::Bunny => "Stanford Bunny, 10 cm (PositionBasedDynamics demos)",
            ShippedOrgan::Liver => "Liver, 16 cm (SOFA Framework, LGPL-2.1)",
            ShippedOrgan::Appendix => "Appendix, 8 × 2 × 2 cm, base pinned",
        }
    }
}

/// An organ ready for a session: its tet mesh in cm, placed, and how it is held.
#[derive(Debug, Clone)]
pub struct Organ {
    /// What a person reads.
    pub label: String,
    /// The tet mesh, cm, y up.
    pub mesh: TetMesh,
    /// How it is held.
    pub setting: Setting,
    /// The tet mesher's report when the organ was filled from a closed surface.
    pub quality: Option<QualityReport>,
}

/// The tray an organ lies on ([`Setting::Tray`]): a square slab centred on x = z = 0 whose top
/// is y = 0, as a static voxel collider.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tray {
    /// Its side (cm).
    pub side: f32,
    /// The voxel cell of its collider (cm).
    pub cell: f32,
}

impl Tray {
    /// The tray for an organ of largest extent `extent` cm: three times as wide, cells of a
    /// twentieth of the organ (0.2–1 cm).
    pub fn for_extent(extent: f32) -> Tray {
        let extent = extent.max(1.0);
        Tray {
            side: 3.0 * extent,
            cell: (extent / 20.0).clamp(0.2, 1.0),
        }
    }
}

impl Organ {
    /// A shipped organ.
    ///
    /// # Errors
    /// Not expected (the shipped files are valid); [`SceneError::Mesh`] if meshing failed.
    pub fn shipped(which: ShippedOrgan) -> Result<Organ, SceneError> {
        let _span = tracing::info_span!("organ_shipped", organ = which.id()).entered();
        let (bytes, size) = match which {
            ShippedOrgan::Bunny => (BUNNY_OBJ, 10.0),
            ShippedOrgan::Liver => (LIVER_OBJ, 16.0),
            ShippedOrgan::Appendix => {
                let mesh = tissue_mesh::tet_box(32, 8, 8, Vec3::new(8.0, 2.0, 2.0))
                    .map_err(|e| SceneError::mesh(which.id(), e))?;
                // The generated box is centred on the origin: its underside onto y = 0.
                let lifted = mesh.positions().iter().map(|&p| p + Vec3::Y).collect();
                return Ok(Organ {
                    label: which.label().to_owned(),
                    mesh: TetMesh::new(lifted, mesh.tets().to_vec())
                        .map_err(|e| SceneError::mesh(which.id(), e))?,
                    setting: Setting::Appendix,
                    quality: None,
                });
            }
        };
        let name = format!("{}.obj", which.id());
        let data = tissue_meshio::parse_surface_data(bytes, &name).map_err(SceneError::Read)?;
        let surface =
            TriMesh::new(data.positions, data.triangles).map_err(|e| SceneError::mesh(&name, e))?;
        let (tets, quality) = fill(&surface, &name)?;
        let (lo, hi) = bounds(tets.positions());
        let scale = size / (hi - lo).max_element();
        Ok(Organ {
            label: which.label().to_owned(),
            mesh: place(&tets, scale, &name)?,
            setting: Setting::Tray,
            quality: Some(quality),
        })
    }

    /// An organ from a file's bytes in `cm_per_unit`: a closed surface (`.obj`, `.ply`,
    /// `.stl`), tetrahedralised, or a tet mesh (legacy `.vtk`, VTK XML `.vtu`, Gmsh `.msh` v1,
    /// v2, v4: tissue-meshio's `parse_tet_data`); kept at its size, placed on the tray.
    ///
    /// # Errors
    /// [`SceneError::Read`] (the loader's message), [`SceneError::Mesh`] for an invalid mesh,
    /// [`SceneError::Meshing`] for a surface that cannot be filled, [`SceneError::TooLarge`]
    /// for more than [`MAX_TETS`] tetrahedra (a surface expected to fill with more is refused
    /// before it is meshed, a tet mesh before it is built).
    pub fn from_bytes(bytes: &[u8], name: &str, cm_per_unit: f32) -> Result<Organ, SceneError> {
        let _span = tracing::info_span!("organ_upload", name).entered();
        let ext = std::path::Path::new(name)
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        if is_surface(&ext) {
            let data = tissue_meshio::parse_surface_data(bytes, name).map_err(SceneError::Read)?;
            let surface = scaled_surface(data.positions, data.triangles, cm_per_unit, name)?;
            Organ::from_surface(&surface, name)
        } else {
            let data = tissue_meshio::parse_tet_data(bytes, name).map_err(SceneError::Read)?;
            // Counted before the mesh (its neighbours) is built.
            if data.tets.len() > MAX_TETS {
                return Err(SceneError::TooLarge {
                    name: name.to_owned(),
                    tets: data.tets.len(),
                    estimated: false,
                    decimate_to: None,
                });
            }
            let scaled: Vec<Vec3> = data.positions.iter().map(|&p| p * cm_per_unit).collect();
            let tets = TetMesh::new(scaled, data.tets).map_err(|e| SceneError::mesh(name, e))?;
            Organ::from_tets(&tets, name)
        }
    }

    /// The organ's largest extent (cm).
    pub fn extent(&self) -> f32 {
        let (lo, hi) = bounds(self.mesh.positions());
        (hi - lo).max_element()
    }

    /// The same organ scaled so that its largest extent is `size` cm, placed again.
    ///
    /// # Errors
    /// [`SceneError::Size`] when `size` is not a positive length; [`SceneError::Mesh`] when the
    /// scaled mesh is no longer valid (a size so small that tets become flat in `f32`).
    pub fn scaled_to(&self, size: f32) -> Result<Organ, SceneError> {
        if !(size.is_finite() && size > 0.0) {
            return Err(SceneError::Size { size });
        }
        let scale = size / self.extent();
        let name = format!("{} at {size} cm", self.label);
        Ok(Organ {
            mesh: place(&self.mesh, scale, &name)?,
            label: self.label.clone(),
            setting: self.setting,
            quality: self.quality.clone(),
        })
    }

    /// The organ as a body, held as its [`Setting`] says: on `tray` (a static voxel collider
    /// with `contact`), or the appendix's base pinned over a floor at y = 0.
    ///
    /// # Errors
    /// [`SceneError::Pbd`] when the solver refuses the material, the step or the tray.
    pub fn body(
        &self,
        material: &Material,
        step: StepSettings,
        contact: ContactParams,
        tray: Tray,
    ) -> Result<SoftBody, SceneError> {
        let mut body = SoftBody::new(&self.mesh, material)?;
        body.set_settings(step)?;
        match self.setting {
            Setting::Tray => {
                let slab = OrientedBox::tray(0.0, 0.0, 0.0, tray.side, tray.side, 2.0);
                let collider = VoxelCollider::new(
                    &[ColliderShape::Box(slab)],
                    tray.cell,
                    tray.cell.max(contact.margin + contact.detection),
                )?;
                body.add_collider(collider, contact)?;
            }
            Setting::Appendix => {
                body.set_floor(Some(Floor::y(0.0)))?;
                for i in 0..body.node_count() as u32 {
                    if body.positions()[i as usize].x < APPENDIX_BASE_X {
                        body.pin(i)?;
                    }
                }
            }
            Setting::Cantilever => {
                for i in self.clamped_nodes() {
                    body.pin(i)?;
                }
            }
        }
        Ok(body)
    }
}

impl Organ {
    /// A beam of square section `thickness` × `thickness` along x from 0 to `length` (cm), its
    /// bottom at y = 0, `cells` cells through the thickness and as many per thickness along
    /// it (`tissue_mesh::tet_box`, six tetrahedra a cell), clamped at x = 0
    /// ([`Setting::Cantilever`]).
    ///
    /// # Errors
    /// [`SceneError::Size`] for a length or thickness that is not a positive length, or a
    /// beam thinner than a tenth of a millimetre; [`SceneError::TooLarge`] above [`MAX_TETS`].
    pub fn cantilever(length: f32, thickness: f32, cells: u32) -> Result<Organ, SceneError> {
        for size in [length, thickness] {
            if !(size.is_finite() && size >= 0.01) {
                return Err(SceneError::Size { size });
            }
        }
        let name = format!("cantilever {length} × {thickness} × {thickness} cm");
        let across = cells.max(1);
        let along = ((f64::from(length) / f64::from(thickness)) * f64::from(across))
            .ceil()
            .max(1.0);
        let tets = 6.0 * along * f64::from(across) * f64::from(across);
        if tets > MAX_TETS as f64 {
            return Err(SceneError::TooLarge {
                name,
                tets: tets as usize,
                estimated: false,
                decimate_to: None,
            });
        }
        let mesh = tissue_mesh::tet_box(
            along as u32,
            across,
            across,
            Vec3::new(length, thickness, thickness),
        )
        .map_err(|e| SceneError::mesh(&name, e))?;
        let shift = Vec3::new(0.5 * length, 0.5 * thickness, 0.0);
        let positions = mesh.positions().iter().map(|&p| p + shift).collect();
        let mesh = TetMesh::new(positions, mesh.tets().to_vec())
            .map_err(|e| SceneError::mesh(&name, e))?;
        Ok(Organ {
            label: name,
            mesh,
            setting: Setting::Cantilever,
            quality: None,
        })
    }

    /// The nodes a [`Setting::Cantilever`] clamps: those at its smallest x (none for the
    /// other settings).
    pub fn clamped_nodes(&self) -> Vec<u32> {
        if self.setting != Setting::Cantilever {
            return Vec::new();
        }
        let lo = self
            .mesh
            .positions()
            .iter()
            .map(|p| p.x)
            .fold(f32::INFINITY, f32::min);
        let tolerance = 1e-4 * self.extent();
        (0..self.mesh.positions().len() as u32)
            .filter(|&i| self.mesh.positions()[i as usize].x <= lo + tolerance)
            .collect()
    }

    /// How far a [`Setting::Cantilever`]'s free end has come down at `positions` (cm): the mean
    /// drop of its nodes at the largest x from where they were loaded. `None` for the other
    /// settings or a position count that is not the organ's.
    pub fn tip_deflection(&self, positions: &[Vec3A]) -> Option<f64> {
        let rest = self.mesh.positions();
        if self.setting != Setting::Cantilever || positions.len() != rest.len() {
            return None;
        }
        let hi = rest.iter().map(|p| p.x).fold(f32::NEG_INFINITY, f32::max);
        let tolerance = 1e-4 * self.extent();
        let (sum, n) = rest
            .iter()
            .zip(positions)
            .filter(|(r, _)| r.x >= hi - tolerance)
            .fold((0.0f64, 0usize), |(s, n), (r, p)| {
                (s + f64::from(r.y - p.y), n + 1)
            });
        (n > 0).then(|| sum / n as f64)
    }
}

impl Organ {
    /// An organ from a closed surface in cm, filled with tetrahedra by `tissue-tetra`, kept at
    /// its size, placed on the tray; `name` stands for it in messages.
    ///
    /// # Errors
    /// [`SceneError::Meshing`] for a surface that cannot be filled, [`SceneError::TooLarge`]
    /// (before meshing when `tissue-tetra`'s estimate is above [`MAX_TETS`]).
    pub fn from_surface(surface: &TriMesh, name: &str) -> Result<Organ, SceneError> {
        let (tets, quality) = fill(surface, name)?;
        Ok(Organ {
            label: name.to_owned(),
            mesh: place(&tets, 1.0, name)?,
            setting: Setting::Tray,
            quality: Some(quality),
        })
    }

    /// An organ from a tet mesh in cm, kept at its size, placed on the tray.
    ///
    /// # Errors
    /// [`SceneError::TooLarge`], [`SceneError::Mesh`] if it is not valid once placed.
    pub fn from_tets(tets: &TetMesh, name: &str) -> Result<Organ, SceneError> {
        Ok(Organ {
            label: name.to_owned(),
            mesh: place(tets, 1.0, name)?,
            setting: Setting::Tray,
            quality: None,
        })
    }
}

fn is_surface(ext: &str) -> bool {
    matches!(ext, "obj" | "ply" | "stl")
}

fn scaled_surface(
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    cm_per_unit: f32,
    name: &str,
) -> Result<TriMesh, SceneError> {
    let scaled = positions.iter().map(|&p| p * cm_per_unit).collect();
    TriMesh::new(scaled, triangles).map_err(|e| SceneError::mesh(name, e))
}

/// Fills a closed surface with tetrahedra, refusing more than [`MAX_TETS`]: by the estimate
/// before meshing, or by the mesher's counts (`TetraOptions::max_tets`).
fn fill(surface: &TriMesh, name: &str) -> Result<(TetMesh, QualityReport), SceneError> {
    let options = TetraOptions {
        max_tets: Some(MAX_TETS),
        ..TetraOptions::default()
    };
    let tets = tetrahedralize(surface, &options).map_err(|e| match e {
        TetraError::TooManyTets {
            tets,
            when: when @ (TetCount::Estimated | TetCount::Made),
            decimate_to,
            ..
        } => SceneError::TooLarge {
            name: name.to_owned(),
            tets,
            estimated: when == TetCount::Estimated,
            decimate_to,
        },
        e => SceneError::Meshing {
            name: name.to_owned(),
            reason: e.to_string(),
        },
    })?;
    check_size(&tets.mesh, name)?;
    Ok((tets.mesh, tets.report))
}

fn check_size(mesh: &TetMesh, name: &str) -> Result<(), SceneError> {
    if mesh.tets().len() > MAX_TETS {
        return Err(SceneError::TooLarge {
            name: name.to_owned(),
            tets: mesh.tets().len(),
            estimated: false,
            decimate_to: None,
        });
    }
    Ok(())
}

fn bounds(positions: &[Vec3]) -> (Vec3, Vec3) {
    positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

/// Scales by `scale`, centres on x = z = 0 and sets the lowest node on y = 0.
fn place(mesh: &TetMesh, scale: f32, name: &str) -> Result<TetMesh, SceneError> {
    check_size(mesh, name)?;
    let (lo, hi) = bounds(mesh.positions());
    let centre = Vec3::new((lo.x + hi.x) * 0.5, lo.y, (lo.z + hi.z) * 0.5);
    let positions = mesh
        .positions()
        .iter()
        .map(|&p| (p - centre) * scale)
        .collect();
    TetMesh::new(positions, mesh.tets().to_vec()).map_err(|e| SceneError::mesh(name, e))
}

#[cfg(test)]
#[allow(clippy::panic)]
mod tests {
    use super::*;

    /// A surface as OBJ bytes.
    fn obj(surface: &TriMesh) -> Vec<u8> {
        let mut text = String::new();
        for p in surface.positions() {
            text.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        for t in surface.triangles() {
            text.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
        }
        text.into_bytes()
    }

    /// Each triangle split into four at its edges' midpoints (tissue-testscans): the same
    /// shape, four times the triangles.
    fn refined(s: &TriMesh) -> Result<TriMesh, SceneError> {
        tissue_testscans::subdivide_midpoint(s).map_err(|e| SceneError::mesh("refined", e))
    }

    fn fixture(name: &str) -> Result<TriMesh, SceneError> {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/");
        let bytes =
            std::fs::read(format!("{path}{name}")).map_err(|e| SceneError::mesh(name, e))?;
        let data = tissue_meshio::parse_surface_data(&bytes, name).map_err(SceneError::Read)?;
        TriMesh::new(data.positions, data.triangles).map_err(|e| SceneError::mesh(name, e))
    }

    #[test]
    fn surfaces_expected_over_max_tets_are_refused_before_meshing_with_a_triangle_count(
    ) -> Result<(), SceneError> {
        let bunny = fixture("bunny_10k.obj")?;
        let once = refined(&bunny)?; // 40 000 triangles: about 290 000 tets
        let twice = refined(&once)?; // 160 000: about 2.3 million (minutes and GBs to mesh)
        for (surface, at_least) in [(&once, 250_000), (&twice, 2_000_000)] {
            let triangles = surface.triangle_count();
            let refused = Organ::from_bytes(&obj(surface), "big.obj", 1.0);
            let text = refused.as_ref().err().map(ToString::to_string);
            let text = text.unwrap_or_default();
            match refused {
                Err(SceneError::TooLarge {
                    tets,
                    estimated,
                    decimate_to,
                    ..
                }) => {
                    // Refused by the estimate: nothing was meshed.
                    assert!(estimated, "{text}");
                    assert!(tets >= at_least, "{text}");
                    // The bunny's shape fits at about 25 000 triangles, from either resolution.
                    let n = decimate_to.unwrap_or(0);
                    assert!((20_000..30_000).contains(&n), "{text}");
                    assert!(
                        text.contains("estimated before meshing")
                            && text
                                .contains(&format!("decimate the surface to about {n} triangles")),
                        "{text}"
                    );
                }
                other => panic!("{triangles} triangles: {other:?}"),
            }
        }
        Ok(())
    }

    #[test]
    fn legit_uploads_up_to_near_the_limit_are_accepted() -> Result<(), SceneError> {
        // The bunny (about 40 000 tets), the liver refined to 9 344 triangles (44 000) and the
        // MakeHuman body in dm (26 756 triangles: 133 000 tets, estimated 133 339).
        let bunny = fixture("bunny_10k.obj")?;
        let liver = refined(&fixture("liver_sofa.obj")?)?;
        let body = fixture("makehuman_body_closed.obj")?;
        for (surface, name, cm_per_unit, tets) in [
            (&bunny, "bunny.obj", 1.0, 36_000..44_000),
            (&liver, "liver.obj", 1.0, 40_000..50_000),
            (&body, "body.obj", 10.0, 120_000..MAX_TETS + 1),
        ] {
            let organ = Organ::from_bytes(&obj(surface), name, cm_per_unit)?;
            let n = organ.mesh.tets().len();
            assert!(tets.contains(&n), "{name}: {n} tets");
        }
        Ok(())
    }

    #[test]
    fn a_tet_mesh_over_max_tets_is_refused() -> Result<(), SceneError> {
        // 32 × 32 × 25 cells of 6 tets: 153 600.
        let mesh = tissue_mesh::tet_box(32, 32, 25, Vec3::splat(10.0))
            .map_err(|e| SceneError::mesh("box", e))?;
        let mut vtk = format!(
            "# vtk DataFile Version 3.0\nbox\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {} float\n",
            mesh.vertex_count()
        );
        for p in mesh.positions() {
            vtk.push_str(&format!("{} {} {}\n", p.x, p.y, p.z));
        }
        let n = mesh.tets().len();
        vtk.push_str(&format!("CELLS {n} {}\n", 5 * n));
        for t in mesh.tets() {
            vtk.push_str(&format!("4 {} {} {} {}\n", t[0], t[1], t[2], t[3]));
        }
        vtk.push_str(&format!("CELL_TYPES {n}\n"));
        vtk.push_str(&"10\n".repeat(n));
        match Organ::from_bytes(vtk.as_bytes(), "box.vtk", 1.0) {
            Err(SceneError::TooLarge {
                tets: 153_600,
                estimated: false,
                decimate_to: None,
                ..
            }) => Ok(()),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn shipped_organs_are_placed_on_the_tray_at_their_sizes() -> Result<(), SceneError> {
        for which in ShippedOrgan::ALL {
            let organ = Organ::shipped(which)?;
            let (lo, hi) = bounds(organ.mesh.positions());
            assert!(
                lo.y.abs() < 1e-5,
                "{}: lowest node at y = {}",
                which.id(),
                lo.y
            );
            assert!((lo.x + hi.x).abs() < 1e-4 && (lo.z + hi.z).abs() < 1e-4);
            let size = (hi - lo).max_element();
            let want = match which {
                ShippedOrgan::Bunny => 10.0,
                ShippedOrgan::Liver => 16.0,
                ShippedOrgan::Appendix => 8.0,
            };
            assert!((size - want).abs() < 1e-3, "{}: {size} cm", which.id());
            assert!(organ.mesh.volume() > 0.0);
        }
        Ok(())
    }

    #[test]
    fn uploads_keep_their_size_in_their_unit_and_broken_files_say_why() -> Result<(), SceneError> {
        // A 2 cm cube surface in mm: 20 mm.
        let cube =
            tissue_mesh::subdivided_cube(4, 20.0).map_err(|e| SceneError::mesh("cube", e))?;
        let mut obj = String::new();
        for p in cube.positions() {
            obj.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        for t in cube.triangles() {
            obj.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
        }
        let organ = Organ::from_bytes(obj.as_bytes(), "cube.obj", 0.1)?;
        assert!(
            (organ.mesh.volume() - 8.0).abs() < 0.05,
            "{} cm³",
            organ.mesh.volume()
        );
        let broken = Organ::from_bytes(b"v 0 0 0\nf 1 2 3\n", "broken.obj", 1.0);
        assert!(matches!(broken, Err(SceneError::Read(_))), "{broken:?}");
        let open = Organ::from_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "open.obj", 1.0);
        assert!(matches!(open, Err(SceneError::Meshing { .. })), "{open:?}");
        Ok(())
    }
}
