//! The raw data types and the functions that pick a format by file extension.

use std::path::Path;

use glam::Vec3;
use tissue_mesh::{TetMesh, TriMesh};

use crate::atomic::read_file;
use crate::error::{SURFACE_EXTENSIONS, TET_EXTENSIONS};
use crate::tetgen::tetgen_paths;
use crate::{
    parse_msh, parse_obj, parse_ply, parse_stl, parse_vtk, parse_vtu, read_tetgen, write_obj,
    write_ply, write_stl, write_vtk, MeshIoError, VtkMesh,
};

/// A triangle surface as a file stores it: not validated, so that every defect can still be
/// listed (e.g. by [`tissue_mesh::diagnose`]).
///
/// What the readers guarantee: every index is `< positions.len()` (an index out of range is a
/// parse error naming the line or element), and `positions.len() < u32::MAX`. Everything else
/// (non-finite coordinates, degenerate or duplicate triangles, non-manifold edges, unreferenced
/// vertices, an empty mesh) is left for validation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SurfaceData {
    /// Vertex positions, in the file's units and order.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`, counted from 0; polygons already fan-triangulated.
    pub triangles: Vec<[u32; 3]>,
}

/// A tetrahedral mesh as a file stores it: not validated. As for [`SurfaceData`], every index is
/// `< positions.len()`; orientation, degeneracy and the rest are left for validation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TetData {
    /// Node positions, in the file's units and order.
    pub positions: Vec<Vec3>,
    /// Tetrahedra `[a, b, c, d]` as indices into `positions`, counted from 0.
    pub tets: Vec<[u32; 4]>,
}

/// A surface file format, told by the file name's extension (ASCII case-insensitive).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SurfaceFormat {
    /// Wavefront `.obj`.
    Obj,
    /// Stanford `.ply`.
    Ply,
    /// `.stl`.
    Stl,
    /// Legacy VTK `.vtk`.
    Vtk,
}

impl SurfaceFormat {
    /// The format of a file name, or `None` for another extension.
    pub fn from_path(path: impl AsRef<Path>) -> Option<Self> {
        let ext = path.as_ref().extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "obj" => SurfaceFormat::Obj,
            "ply" => SurfaceFormat::Ply,
            "stl" => SurfaceFormat::Stl,
            "vtk" => SurfaceFormat::Vtk,
            _ => return None,
        })
    }

    fn of(path: &Path) -> Result<Self, MeshIoError> {
        Self::from_path(path).ok_or_else(|| MeshIoError::UnsupportedFormat {
            path: path.to_path_buf(),
            supported: SURFACE_EXTENSIONS,
        })
    }
}

/// Reads a surface file (`.obj`, `.ply`, `.stl` or `.vtk`, by extension) without validating it.
pub fn read_surface_data(path: impl AsRef<Path>) -> Result<SurfaceData, MeshIoError> {
    let path = path.as_ref();
    let format = SurfaceFormat::of(path)?;
    let _span = tracing::info_span!("read_surface_data", path = %path.display()).entered();
    let bytes = read_file(path)?;
    parse_as(format, &bytes, path)
}

/// Parses surface data held in memory, in the format that `name`'s extension tells; `name` also
/// stands for the file in error messages.
pub fn parse_surface_data(
    bytes: &[u8],
    name: impl AsRef<Path>,
) -> Result<SurfaceData, MeshIoError> {
    let path = name.as_ref();
    parse_as(SurfaceFormat::of(path)?, bytes, path)
}

fn parse_as(format: SurfaceFormat, bytes: &[u8], path: &Path) -> Result<SurfaceData, MeshIoError> {
    match format {
        SurfaceFormat::Obj => parse_obj(bytes, path),
        SurfaceFormat::Ply => parse_ply(bytes, path),
        SurfaceFormat::Stl => parse_stl(bytes, path),
        SurfaceFormat::Vtk => match parse_vtk(bytes, path)?.mesh {
            VtkMesh::Surface(s) => Ok(s),
            VtkMesh::Tets(_) => Err(MeshIoError::WrongKind {
                path: path.to_path_buf(),
                found: "tetrahedra",
                wanted: "triangles",
                hint: "read it with read_tet_data or read_vtk",
            }),
        },
    }
}

/// Reads a surface file (see [`read_surface_data`]) and validates it into a [`TriMesh`]; a
/// defect is [`MeshIoError::Invalid`] with the file's path and the [`tissue_mesh::MeshError`]
/// naming the element.
pub fn read_surface(path: impl AsRef<Path>) -> Result<TriMesh, MeshIoError> {
    let path = path.as_ref();
    let data = read_surface_data(path)?;
    let _span = tracing::debug_span!("validate", path = %path.display()).entered();
    TriMesh::new(data.positions, data.triangles).map_err(|source| MeshIoError::Invalid {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes a surface in the format its extension names (`.obj`, `.ply`, `.stl`, `.vtk` without
/// fields), atomically.
pub fn write_surface(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    let format = SurfaceFormat::of(path)?;
    let _span = tracing::info_span!("write_surface", path = %path.display()).entered();
    match format {
        SurfaceFormat::Obj => write_obj(path, mesh),
        SurfaceFormat::Ply => write_ply(path, mesh),
        SurfaceFormat::Stl => write_stl(path, mesh),
        SurfaceFormat::Vtk => write_vtk(path, mesh, &[]),
    }
}

/// A tetrahedral mesh file format, told by the file name's extension (ASCII case-insensitive).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum TetFormat {
    /// VTK XML unstructured grid `.vtu` ([`crate::read_vtu`]).
    Vtu,
    /// Gmsh `.msh`, versions 1, 2 and 4.1 ([`crate::read_msh`]).
    Msh,
    /// Legacy VTK `.vtk` ([`crate::read_vtk`]).
    Vtk,
    /// TetGen `.node` + `.ele` ([`read_tetgen`]).
    TetGen,
}

impl TetFormat {
    /// The format of a file name: `.vtu`, `.msh`, `.vtk`, or `.node`/`.ele` for TetGen; `None`
    /// for another extension or none (which [`read_tet_data`] may still read as a TetGen stem).
    pub fn from_path(path: impl AsRef<Path>) -> Option<Self> {
        let ext = path.as_ref().extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "vtu" => TetFormat::Vtu,
            "msh" => TetFormat::Msh,
            "vtk" => TetFormat::Vtk,
            "node" | "ele" => TetFormat::TetGen,
            _ => return None,
        })
    }
}

/// Reads a tetrahedral mesh without validating it, in the format its extension names: `.vtu`
/// (VTK XML), `.msh` (Gmsh 1, 2 or 4.1), `.vtk` (legacy VTK), or a TetGen mesh named by its
/// `.node` or `.ele` file or by their stem (see [`read_tetgen`]).
///
/// A path without an extension, or whose extension is a number (`bunny.1`), is a TetGen stem.
/// Any other extension is [`MeshIoError::UnsupportedFormat`] listing the formats, unless a TetGen
/// `.node` file of that stem exists.
pub fn read_tet_data(path: impl AsRef<Path>) -> Result<TetData, MeshIoError> {
    let path = path.as_ref();
    let _span = tracing::info_span!("read_tet_data", path = %path.display()).entered();
    match TetFormat::from_path(path) {
        Some(TetFormat::TetGen) => read_tetgen(path),
        Some(format) => parse_tets_as(format, &read_file(path)?, path),
        None => {
            let ext = path.extension().and_then(|e| e.to_str());
            let stem = ext.is_none_or(|e| e.bytes().all(|b| b.is_ascii_digit()));
            if stem || tetgen_paths(path).0.is_file() {
                read_tetgen(path)
            } else {
                Err(MeshIoError::UnsupportedFormat {
                    path: path.to_path_buf(),
                    supported: TET_EXTENSIONS,
                })
            }
        }
    }
}

/// Parses tetrahedral mesh data held in memory, in the format that `name`'s extension tells
/// (`.vtu`, `.msh` or `.vtk`); `name` also stands for the file in error messages. A TetGen mesh
/// is two files: parse it with [`crate::parse_tetgen`].
pub fn parse_tet_data(bytes: &[u8], name: impl AsRef<Path>) -> Result<TetData, MeshIoError> {
    let path = name.as_ref();
    match TetFormat::from_path(path) {
        Some(TetFormat::TetGen) => Err(MeshIoError::UnsupportedFormat {
            path: path.to_path_buf(),
            supported: ".vtu, .msh or .vtk (a TetGen mesh is two files, .node and .ele: parse them together with parse_tetgen)",
        }),
        Some(format) => parse_tets_as(format, bytes, path),
        None => Err(MeshIoError::UnsupportedFormat {
            path: path.to_path_buf(),
            supported: ".vtu, .msh or .vtk",
        }),
    }
}

fn parse_tets_as(format: TetFormat, bytes: &[u8], path: &Path) -> Result<TetData, MeshIoError> {
    match format {
        TetFormat::Vtu => parse_vtu(bytes, path),
        TetFormat::Msh => parse_msh(bytes, path),
        TetFormat::Vtk => match parse_vtk(bytes, path)?.mesh {
            VtkMesh::Tets(t) => Ok(t),
            VtkMesh::Surface(_) => Err(MeshIoError::WrongKind {
                path: path.to_path_buf(),
                found: "a triangle surface",
                wanted: "tetrahedra",
                hint: "read it with read_surface or read_vtk",
            }),
        },
        TetFormat::TetGen => Err(MeshIoError::UnsupportedFormat {
            path: path.to_path_buf(),
            supported: TET_EXTENSIONS,
        }),
    }
}

/// Reads a tetrahedral mesh (see [`read_tet_data`]) and validates it into a [`TetMesh`]; a defect
/// is [`MeshIoError::Invalid`] with the file's path and the [`tissue_mesh::MeshError`] naming the
/// element.
pub fn read_tets(path: impl AsRef<Path>) -> Result<TetMesh, MeshIoError> {
    let path = path.as_ref();
    let data = read_tet_data(path)?;
    let _span = tracing::debug_span!("validate", path = %path.display()).entered();
    TetMesh::new(data.positions, data.tets).map_err(|source| MeshIoError::Invalid {
        path: path.to_path_buf(),
        source,
    })
}
