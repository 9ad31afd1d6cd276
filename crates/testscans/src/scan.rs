//! What every generator returns, the error type, and where the fixture meshes are.

use std::path::PathBuf;

use glam::Vec3;
use tissue_mesh::{MeshError, TriMesh};
use tissue_meshio::MeshIoError;

/// A generated test scan: a valid surface and what a test needs to know about it.
#[derive(Debug, Clone)]
pub struct Scan {
    /// The surface (valid, outward normals).
    pub mesh: TriMesh,
    /// The unit of the positions: `"mm"`, `"cm"` or `"dm"`.
    pub unit_name: &'static str,
    /// Centimetres per unit of the positions (`0.1` for mm, `1` for cm, `10` for dm).
    pub cm_per_unit: f32,
    /// Named points on the surface (each a vertex of `mesh`), where a planner may place things.
    pub points: Vec<NamedPoint>,
    /// The small holes punched into the surface (empty when none).
    pub holes: Vec<PunchedHole>,
    /// The one large hole, for tests that a region over a hole is refused (`None` when none).
    pub big_hole: Option<PunchedHole>,
    /// The noise-free, hole-free surface the scan was made from (`None` when the scan has no
    /// noise and no holes).
    pub truth: Option<TriMesh>,
    /// For each vertex of `mesh`, its vertex in `truth` (empty when `truth` is `None`).
    pub truth_vertex: Vec<u32>,
    /// Mean distance of the vertices from the axis, for tube-like scans (in the unit).
    pub radius: Option<f32>,
}

/// A point on a scan where a test may place a region or an implant.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedPoint {
    /// Short name, e.g. `"cheek_left"`.
    pub name: &'static str,
    /// What the point is, in words.
    pub what: &'static str,
    /// The vertex of the mesh at the point.
    pub vertex: u32,
    /// Its position (in the scan's unit).
    pub position: Vec3,
    /// Euclidean distance to the nearest boundary vertex (`f32::INFINITY` on a closed surface).
    pub border_distance: f32,
}

/// A hole punched into a scan: the triangles whose centroid lay within `diameter / 2` of
/// `centre` were removed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PunchedHole {
    /// Centre of the removed disc (a vertex position of the surface before the hole).
    pub centre: Vec3,
    /// Diameter of the removed disc (in the scan's unit).
    pub diameter: f32,
}

/// Why a scan could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScanError {
    /// The fixture mesh a generator reads is not there ([`ScanError::is_absent`]); the meshes
    /// ship in the repository's `fixtures/`, so this means a broken checkout.
    #[error("{}: the fixture mesh is missing (it ships in the repository's fixtures/)", .path.display())]
    Absent {
        /// The file looked for.
        path: PathBuf,
    },
    /// The fixture mesh exists but could not be read.
    #[error(transparent)]
    Io(#[from] MeshIoError),
    /// A generated surface failed validation (a bug in the generator, or an extreme parameter).
    #[error("generated surface is invalid: {0}")]
    Mesh(#[from] MeshError),
    /// Removing triangles left nothing.
    #[error("no triangle left after removing triangles")]
    NothingLeft,
    /// The shared mesh is not what the generator expects (a changed file).
    #[error("{what}")]
    Unexpected {
        /// What was found.
        what: String,
    },
}

impl ScanError {
    /// `true` when the fixture mesh is missing.
    pub fn is_absent(&self) -> bool {
        matches!(self, ScanError::Absent { .. })
    }
}

/// The folder of the third-party meshes the generators read (the repository's `fixtures/`,
/// provenance and licences in its README), found from this crate's manifest, never from the
/// working directory.
pub fn meshes_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures"))
}

/// Reads a fixture mesh by file name (through `tissue-meshio`, the crate that touches files);
/// [`ScanError::Absent`] when it is not there.
pub(crate) fn read_shared(name: &str) -> Result<TriMesh, ScanError> {
    let path = meshes_dir().join(name);
    match tissue_meshio::read_surface(&path) {
        Err(MeshIoError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            Err(ScanError::Absent { path })
        }
        other => Ok(other?),
    }
}

/// Boundary vertex positions of a mesh.
pub(crate) fn boundary_points(mesh: &TriMesh) -> Vec<Vec3> {
    mesh.topology()
        .boundary_loops()
        .iter()
        .flatten()
        .map(|&v| mesh.positions()[v as usize])
        .collect()
}

/// Euclidean distance from `p` to the nearest of `points` (`f32::INFINITY` when none).
pub(crate) fn nearest_distance(points: &[Vec3], p: Vec3) -> f32 {
    points
        .iter()
        .map(|q| q.distance_squared(p))
        .fold(f32::INFINITY, f32::min)
        .sqrt()
}

/// A named point at vertex `vertex` of `mesh`.
pub(crate) fn named_point(
    mesh: &TriMesh,
    border: &[Vec3],
    name: &'static str,
    what: &'static str,
    vertex: u32,
) -> NamedPoint {
    let position = mesh.positions()[vertex as usize];
    NamedPoint {
        name,
        what,
        vertex,
        position,
        border_distance: nearest_distance(border, position),
    }
}

/// Flips every triangle when the normals point towards `inside` on the whole (`Σ n·(c − inside)`
/// over the triangles, area-weighted, is negative).
pub(crate) fn orient_outward(triangles: &mut [[u32; 3]], positions: &[Vec3], inside: Vec3) {
    let mut s = 0.0f64;
    for t in triangles.iter() {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        s += f64::from(n.dot((a + b + c) / 3.0 - inside));
    }
    if s < 0.0 {
        for t in triangles.iter_mut() {
            t.swap(1, 2);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_shared_mesh_is_absent_not_an_io_error() {
        let err = read_shared("no_such_mesh_here.obj").err();
        assert!(err.is_some_and(|e| e.is_absent()));
    }
}
