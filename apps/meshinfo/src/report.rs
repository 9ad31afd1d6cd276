//! Builds the report of one mesh file: what `meshinfo` prints as text or JSON.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;
use tissue_mesh::{diagnose, diagnose_tets, MeshError, TetMesh, TriMesh};
use tissue_meshio::{
    read_surface_data, read_tet_data, read_vtk, MeshIoError, SurfaceFormat, TetFormat, VtkMesh,
};

/// Everything `meshinfo` says about a file.
#[derive(Debug, Serialize)]
pub struct Report {
    pub file: String,
    /// `surface` or `tetrahedral`.
    pub kind: &'static str,
    /// `true` when the mesh passed every hard check (warnings allowed).
    pub loaded: bool,
    pub vertices: usize,
    pub triangles: usize,
    pub tetrahedra: Option<usize>,
    pub edges: Option<usize>,
    pub bounding_box: Option<BoxReport>,
    /// Surface area (of the boundary surface for a tetrahedral mesh).
    pub area: Option<f64>,
    pub closed: Option<bool>,
    /// Enclosed volume: of the closed surface, or the sum of the tetrahedra.
    pub volume: Option<f64>,
    pub boundary_loops: Vec<LoopReport>,
    pub components: Option<usize>,
    pub euler_characteristic: Option<i64>,
    pub defects: Vec<DefectReport>,
}

#[derive(Debug, Serialize)]
pub struct BoxReport {
    pub min: [f32; 3],
    pub max: [f32; 3],
    pub size: [f32; 3],
}

#[derive(Debug, Serialize)]
pub struct LoopReport {
    /// Number of edges (= vertices) in the loop.
    pub edges: usize,
    /// Summed edge length.
    pub length: f64,
    /// The vertex the loop starts at.
    pub first_vertex: u32,
}

#[derive(Debug, Serialize)]
pub struct DefectReport {
    /// `error` or `warning`.
    pub severity: &'static str,
    /// The defect's kind, e.g. `IndexOutOfRange`.
    pub kind: String,
    pub message: String,
}

impl Report {
    /// What is known before the mesh is built: counts, box and defects; the rest is filled in
    /// once it loads.
    fn unloaded(
        path: &Path,
        kind: &'static str,
        positions: &[glam::Vec3],
        defects: &[MeshError],
    ) -> Report {
        Report {
            file: path.display().to_string(),
            kind,
            loaded: false,
            vertices: positions.len(),
            triangles: 0,
            tetrahedra: None,
            edges: None,
            bounding_box: finite_box(positions),
            area: None,
            closed: None,
            volume: None,
            boundary_loops: Vec::new(),
            components: None,
            euler_characteristic: None,
            defects: defect_reports(defects),
        }
    }

    pub fn hard_defect_count(&self) -> usize {
        self.defects
            .iter()
            .filter(|d| d.severity == "error")
            .count()
    }

    pub fn first_hard_defect(&self) -> Option<&str> {
        self.defects
            .iter()
            .find(|d| d.severity == "error")
            .map(|d| d.message.as_str())
    }

    /// The human-readable form.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "file                  {}", self.file);
        let _ = writeln!(s, "kind                  {}", self.kind);
        let _ = writeln!(s, "vertices              {}", self.vertices);
        let _ = writeln!(s, "triangles             {}", self.triangles);
        if let Some(t) = self.tetrahedra {
            let _ = writeln!(s, "tetrahedra            {t}");
        }
        if let Some(e) = self.edges {
            let _ = writeln!(s, "edges                 {e}");
        }
        if let Some(b) = &self.bounding_box {
            let _ = writeln!(
                s,
                "bounding box          min {:?} max {:?} size {:?}",
                b.min, b.max, b.size
            );
        }
        if let Some(a) = self.area {
            let _ = writeln!(s, "area                  {a:.6}");
        }
        if let Some(c) = self.closed {
            let _ = writeln!(s, "closed                {}", if c { "yes" } else { "no" });
        }
        match (self.volume, self.closed) {
            (Some(v), _) => {
                let _ = writeln!(s, "volume                {v:.6}");
            }
            (None, Some(false)) => {
                let _ = writeln!(s, "volume                - (open surface)");
            }
            _ => {}
        }
        if self.loaded {
            let _ = writeln!(s, "boundary loops        {}", self.boundary_loops.len());
            for (i, l) in self.boundary_loops.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "  loop {i}: {} edges, length {:.6}, from vertex {}",
                    l.edges, l.length, l.first_vertex
                );
            }
        }
        if let Some(c) = self.components {
            let _ = writeln!(s, "components            {c}");
        }
        if let Some(x) = self.euler_characteristic {
            let _ = writeln!(s, "Euler characteristic  {x}");
        }
        if self.defects.is_empty() {
            let _ = writeln!(s, "defects               none");
        } else {
            let errors = self.hard_defect_count();
            let _ = writeln!(
                s,
                "defects               {} ({} errors, {} warnings)",
                self.defects.len(),
                errors,
                self.defects.len() - errors
            );
            for d in &self.defects {
                let _ = writeln!(s, "  {}: {}", d.severity, d.message);
            }
        }
        s
    }
}

/// The file name endings `meshinfo` reads.
const FORMATS: &str = ".obj, .ply, .stl, .vtk (surface or tets), .vtu, .msh, or TetGen .node/.ele";

/// Reads and inspects one file: a surface (`.obj`, `.ply`, `.stl`, a `.vtk` surface) or a
/// tetrahedral mesh (`.vtu`, `.msh`, a `.vtk` tet grid, TetGen `.node`/`.ele`). `Err` only when
/// the file cannot be read or parsed at all; a mesh with defects gives `Ok` with
/// `loaded == false`.
pub fn inspect(path: &Path) -> Result<Report, MeshIoError> {
    match TetFormat::from_path(path) {
        Some(TetFormat::Vtk) => match read_vtk(path)?.mesh {
            VtkMesh::Surface(s) => Ok(inspect_surface(path, s.positions, s.triangles)),
            VtkMesh::Tets(t) => Ok(inspect_tets(path, t.positions, t.tets)),
        },
        Some(_) => {
            let data = read_tet_data(path)?;
            Ok(inspect_tets(path, data.positions, data.tets))
        }
        None if SurfaceFormat::from_path(path).is_some() => {
            let data = read_surface_data(path)?;
            Ok(inspect_surface(path, data.positions, data.triangles))
        }
        None => Err(MeshIoError::UnsupportedFormat {
            path: path.to_path_buf(),
            supported: FORMATS,
        }),
    }
}

fn defect_reports(defects: &[MeshError]) -> Vec<DefectReport> {
    defects
        .iter()
        .map(|d| {
            let debug = format!("{d:?}");
            let kind = debug
                .split(|c: char| !c.is_alphanumeric())
                .next()
                .unwrap_or("")
                .to_string();
            DefectReport {
                severity: if d.is_warning() { "warning" } else { "error" },
                kind,
                message: d.to_string(),
            }
        })
        .collect()
}

fn finite_box(positions: &[glam::Vec3]) -> Option<BoxReport> {
    let mut it = positions.iter().filter(|p| p.is_finite());
    let first = *it.next()?;
    let (min, max) = it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    Some(BoxReport {
        min: min.to_array(),
        max: max.to_array(),
        size: (max - min).to_array(),
    })
}

fn surface_fields(report: &mut Report, mesh: &TriMesh) {
    let topo = mesh.topology();
    report.edges = Some(topo.edges().len());
    report.area = Some(mesh.area());
    report.closed = Some(mesh.is_closed());
    report.components = Some(topo.component_count());
    report.euler_characteristic = Some(mesh.euler_characteristic());
    let p = mesh.positions();
    report.boundary_loops = topo
        .boundary_loops()
        .iter()
        .map(|l| LoopReport {
            edges: l.len(),
            length: (0..l.len())
                .map(|i| {
                    let (a, b) = (l[i] as usize, l[(i + 1) % l.len()] as usize);
                    (p[a].as_dvec3() - p[b].as_dvec3()).length()
                })
                .sum(),
            first_vertex: l[0],
        })
        .collect();
}

fn inspect_surface(path: &Path, positions: Vec<glam::Vec3>, triangles: Vec<[u32; 3]>) -> Report {
    let defects = diagnose(&positions, &triangles);
    let mut report = Report::unloaded(path, "surface", &positions, &defects);
    report.triangles = triangles.len();
    if let Ok(mesh) = TriMesh::new(positions, triangles) {
        report.loaded = true;
        surface_fields(&mut report, &mesh);
        report.volume = mesh.signed_volume().ok();
    }
    report
}

fn inspect_tets(path: &Path, positions: Vec<glam::Vec3>, tets: Vec<[u32; 4]>) -> Report {
    let defects = diagnose_tets(&positions, &tets);
    let mut report = Report::unloaded(path, "tetrahedral", &positions, &defects);
    report.tetrahedra = Some(tets.len());
    let Ok(tet_mesh) = TetMesh::new(positions, tets) else {
        return report;
    };
    report.volume = Some(tet_mesh.volume());
    match tet_mesh.boundary_surface() {
        Ok(surface) => {
            report.loaded = true;
            report.triangles = surface.triangle_count();
            surface_fields(&mut report, &surface);
            // The boundary surface keeps every node, so its χ would count interior nodes: report
            // the surface's own V − E + F over the nodes it uses.
            let used = surface.vertex_count() - surface.unreferenced_vertices().len();
            report.euler_characteristic = Some(
                used as i64 - surface.topology().edges().len() as i64
                    + surface.triangle_count() as i64,
            );
        }
        Err(e) => report.defects.extend(defect_reports(&[e])),
    }
    report
}
