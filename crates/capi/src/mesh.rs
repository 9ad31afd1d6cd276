//! Meshes: a validated triangle surface or tet mesh, from a file in any of tissue-meshio's
//! formats or from the caller's arrays, read back into the caller's buffers.

use std::ffi::c_char;
use std::path::Path;

use ::tissue_mesh::{TetMesh, TriMesh};
use glam::Vec3;

use crate::ffi::{
    copy_out, free_handle, get, guard, guard_void, into_handle, put, slice, text, tissue_status,
    Error,
};

/// A mesh: a triangle surface or a tet mesh, valid (every index, coordinate, area or volume and
/// the winding checked when it was made). Immutable: any thread may read it at once.
pub struct tissue_mesh {
    pub(crate) kind: MeshKind,
}

pub(crate) enum MeshKind {
    Surface(TriMesh),
    Tets(TetMesh),
}

/// What a mesh holds.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_mesh_kind {
    /// Triangles (3 indices each).
    TISSUE_MESH_SURFACE = 0,
    /// Tetrahedra (4 indices each).
    TISSUE_MESH_TETS = 1,
}

impl tissue_mesh {
    pub(crate) fn surface(&self) -> Option<&TriMesh> {
        match &self.kind {
            MeshKind::Surface(m) => Some(m),
            MeshKind::Tets(_) => None,
        }
    }

    fn positions(&self) -> &[Vec3] {
        match &self.kind {
            MeshKind::Surface(m) => m.positions(),
            MeshKind::Tets(m) => m.positions(),
        }
    }

    fn indices(&self) -> &[u32] {
        match &self.kind {
            MeshKind::Surface(m) => m.triangles().as_flattened(),
            MeshKind::Tets(m) => m.tets().as_flattened(),
        }
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default()
}

/// Loads `path`: `.obj`, `.ply`, `.stl` as a surface; `.vtu`, `.msh` (Gmsh 1, 2.2, 4.1),
/// `.node`/`.ele` (TetGen) as tets; a legacy `.vtk` as tets when it has tetrahedra, else as a
/// surface. Coordinates as in the file (no unit). The new mesh is the caller's
/// (`tissue_mesh_free`).
///
/// Errors: `TISSUE_INPUT` (missing, unreadable, unsupported), `TISSUE_INVALID_MESH` (malformed,
/// naming the line or element; or an invalid mesh).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_mesh_load(
    path: *const c_char,
    out: *mut *mut tissue_mesh,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract: a NUL-terminated path.
        let path = Path::new(unsafe { text(path, "path") }?);
        let kind = match extension(path).as_str() {
            "obj" | "ply" | "stl" => {
                MeshKind::Surface(tissue_meshio::read_surface(path).map_err(|e| Error::from(&e))?)
            }
            "vtk" => match tissue_meshio::read_tets(path) {
                Ok(m) => MeshKind::Tets(m),
                Err(_) => MeshKind::Surface(
                    tissue_meshio::read_surface(path).map_err(|e| Error::from(&e))?,
                ),
            },
            _ => MeshKind::Tets(tissue_meshio::read_tets(path).map_err(|e| Error::from(&e))?),
        };
        // SAFETY: `out` is NULL or valid.
        unsafe { put(out, "out", into_handle(tissue_mesh { kind })) }
    })
}

/// A surface from the caller's arrays: `positions` holds `vertex_count` × 3 floats (x, y, z),
/// `triangles` `triangle_count` × 3 vertex indices from 0, counter-clockwise seen from outside.
/// Copied: the arrays may be freed after the call.
///
/// Errors: `TISSUE_INVALID_MESH` naming the first defect (an index out of range, a non-finite
/// coordinate, a zero-area or duplicate triangle, an edge in more than two triangles, opposite
/// winding).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_mesh_from_triangles(
    positions: *const f32,
    vertex_count: usize,
    triangles: *const u32,
    triangle_count: usize,
    out: *mut *mut tissue_mesh,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract on the array lengths.
        let (p, t) = unsafe {
            (
                slice(positions, checked(vertex_count, 3)?, "positions")?,
                slice(triangles, checked(triangle_count, 3)?, "triangles")?,
            )
        };
        let mesh = TriMesh::new(
            p.chunks_exact(3).map(Vec3::from_slice).collect(),
            t.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        )
        .map_err(|e| Error::new(tissue_status::TISSUE_INVALID_MESH, e.to_string()))?;
        // SAFETY: `out` is NULL or valid.
        unsafe {
            put(
                out,
                "out",
                into_handle(tissue_mesh {
                    kind: MeshKind::Surface(mesh),
                }),
            )
        }
    })
}

/// A tet mesh from the caller's arrays: `positions` holds `vertex_count` × 3 floats, `tets`
/// `tet_count` × 4 node indices from 0, each tet positively oriented (`(b−a)×(c−a)·(d−a) > 0`).
/// Copied.
///
/// Errors: `TISSUE_INVALID_MESH` naming the first defect (an inverted tet: swap two of its
/// nodes).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_mesh_from_tets(
    positions: *const f32,
    vertex_count: usize,
    tets: *const u32,
    tet_count: usize,
    out: *mut *mut tissue_mesh,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract on the array lengths.
        let (p, t) = unsafe {
            (
                slice(positions, checked(vertex_count, 3)?, "positions")?,
                slice(tets, checked(tet_count, 4)?, "tets")?,
            )
        };
        let mesh = TetMesh::new(
            p.chunks_exact(3).map(Vec3::from_slice).collect(),
            t.chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
        )
        .map_err(|e| Error::new(tissue_status::TISSUE_INVALID_MESH, e.to_string()))?;
        // SAFETY: `out` is NULL or valid.
        unsafe {
            put(
                out,
                "out",
                into_handle(tissue_mesh {
                    kind: MeshKind::Tets(mesh),
                }),
            )
        }
    })
}

fn checked(count: usize, per: usize) -> Result<usize, Error> {
    count
        .checked_mul(per)
        .ok_or_else(|| Error::invalid(format!("a count of {count} is too large")))
}

/// Frees a mesh. NULL does nothing.
///
/// Thread safety: no other call may use the mesh during or after this one.
#[no_mangle]
pub extern "C" fn tissue_mesh_free(mesh: *mut tissue_mesh) {
    // SAFETY: the header's contract: a mesh from this library, freed once.
    guard_void(|| unsafe { free_handle(mesh) });
}

/// What the mesh holds, its vertex count and its element count (triangles or tets). Each output
/// may be NULL.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_mesh_sizes(
    mesh: *const tissue_mesh,
    kind: *mut tissue_mesh_kind,
    vertices: *mut usize,
    elements: *mut usize,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let mesh = unsafe { get(mesh, "mesh") }?;
        let (k, per) = match mesh.kind {
            MeshKind::Surface(_) => (tissue_mesh_kind::TISSUE_MESH_SURFACE, 3),
            MeshKind::Tets(_) => (tissue_mesh_kind::TISSUE_MESH_TETS, 4),
        };
        // SAFETY: each output is NULL or valid.
        unsafe {
            crate::ffi::put_opt(kind, k);
            crate::ffi::put_opt(vertices, mesh.positions().len());
            crate::ffi::put_opt(elements, mesh.indices().len() / per);
        }
        Ok(())
    })
}

/// Copies the vertex positions (x, y, z per vertex) into `out`, which holds `capacity` floats:
/// at least 3 × the vertex count (`tissue_mesh_sizes`), else `TISSUE_BUFFER_TOO_SMALL`.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_mesh_copy_positions(
    mesh: *const tissue_mesh,
    out: *mut f32,
    capacity: usize,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let mesh = unsafe { get(mesh, "mesh") }?;
        let flat: &[f32] = bytemuck_vec3(mesh.positions());
        // SAFETY: `out` holds `capacity` floats.
        unsafe { copy_out(out, capacity, flat, "positions") }
    })
}

/// Copies the element indices (3 per triangle or 4 per tet, from 0) into `out`, which holds
/// `capacity` values: at least 3 (or 4) × the element count, else `TISSUE_BUFFER_TOO_SMALL`.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_mesh_copy_indices(
    mesh: *const tissue_mesh,
    out: *mut u32,
    capacity: usize,
) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let mesh = unsafe { get(mesh, "mesh") }?;
        // SAFETY: `out` holds `capacity` values.
        unsafe { copy_out(out, capacity, mesh.indices(), "indices") }
    })
}

/// Writes a surface to `path`, atomically, in the format of its extension (`.obj`, `.ply`
/// binary, `.stl` binary, `.vtk` legacy).
///
/// Errors: `TISSUE_INVALID_ARGUMENT` for a tet mesh or another extension, `TISSUE_OUTPUT` when
/// writing fails.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_mesh_save(mesh: *const tissue_mesh, path: *const c_char) -> tissue_status {
    guard(|| {
        // SAFETY: the header's contract.
        let (mesh, path) = unsafe { (get(mesh, "mesh")?, text(path, "path")?) };
        let surface = mesh
            .surface()
            .ok_or_else(|| Error::invalid("only a surface can be saved (this mesh holds tets)"))?;
        let path = Path::new(path);
        let written = match extension(path).as_str() {
            "obj" => tissue_meshio::write_obj(path, surface),
            "ply" => tissue_meshio::write_ply(path, surface),
            "stl" => tissue_meshio::write_stl(path, surface),
            "vtk" => tissue_meshio::write_vtk(path, surface, &[]),
            _ => {
                return Err(Error::invalid(format!(
                    "{}: the extension must be .obj, .ply, .stl or .vtk",
                    path.display()
                )))
            }
        };
        written.map_err(|e| {
            Error::new(
                tissue_status::TISSUE_OUTPUT,
                format!("cannot write {}: {e}", path.display()),
            )
        })
    })
}

/// `[Vec3]` as flat floats.
pub(crate) fn bytemuck_vec3(v: &[Vec3]) -> &[f32] {
    // `Vec3` is `#[repr(C)] { x, y, z: f32 }` with no padding (size 12, align 4): glam's
    // documented layout, checked below.
    const _: () = assert!(std::mem::size_of::<Vec3>() == 12 && std::mem::align_of::<Vec3>() == 4);
    // SAFETY: the layout above; the slice covers exactly the same bytes.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<f32>(), v.len() * 3) }
}
