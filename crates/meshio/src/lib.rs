//! # tissue-meshio: mesh files in and out (the only library crate that touches files)
//!
//! ## Brief overview
//! - [`read_surface`] reads an `.obj`, `.ply`, `.stl` or `.vtk` file (by extension) into a
//!   validated [`tissue_mesh::TriMesh`]; [`read_surface_data`] stops before validation and gives
//!   the raw [`SurfaceData`], so that a tool can list every defect of a bad file.
//! - [`read_tets`] reads a validated [`tissue_mesh::TetMesh`], by extension ([`TetFormat`]), from
//!   - VTK XML unstructured grids `.vtu` ([`read_vtu`]): ascii, inline base64 (UInt32 or
//!     UInt64 `header_type`), `<AppendedData>` raw or base64, uncompressed or zlib
//!     (`vtkZLibDataCompressor`, meshio's default); LZ4/LZMA are refused with the fix;
//!   - Gmsh `.msh` ([`read_msh`]): MSH 1 (`$NOD`/`$ELM`, as SOFA ships its meshes), 2.x and
//!     4.1, ASCII and binary; node tags of any value are renumbered 0, 1, ... in file order;
//!     MSH 3 and 4.0 are refused with how to re-save;
//!   - legacy VTK `.vtk` ([`read_vtk`], which also returns `POINT_DATA` fields);
//!   - TetGen `.node`/`.ele` ([`read_tetgen`]), named by either file or their stem.
//!
//!   Of a `.vtu` or `.msh` only the linear tetrahedra (VTK cell type 10, Gmsh element type 4)
//!   are kept; other cells (points, lines, triangles, ...) are skipped, and a file without
//!   tetrahedra is an error saying what it holds. [`read_tet_data`] stops before validation and
//!   gives the raw [`TetData`]; [`parse_tet_data`] does the same for bytes in memory. An
//!   extension no tet reader knows is [`MeshIoError::UnsupportedFormat`] listing the formats.
//! - Orientation: every tet reader returns the tetrahedra as stored (VTK, Gmsh and TetGen share
//!   our convention: `(b−a)×(c−a)·(d−a) > 0`), and [`tissue_mesh::TetMesh::new`] refuses an
//!   inverted one, naming it ([`tissue_mesh::MeshError::InvertedTet`]); nothing is flipped
//!   silently.
//! - [`write_surface`] writes by extension; [`write_obj`], [`write_ply`] (binary),
//!   [`write_stl`] (binary), [`write_vtk`] and [`write_vtk_tets`] (ASCII, with per-vertex
//!   [`VertexField`]s for ParaView) write one format each.
//! - [`MeshIoError`]: every error names the file, and the line (text) or element (binary), and
//!   says how to fix it where it can.
//!
//! Every reader also has a `parse_*` twin that takes bytes and a display name, for data that is
//! not in a file. What each format supports is in the docs of its reader.
//!
//! Units: none are converted. Positions are stored and returned as the file has them (`f32`);
//! the rest of tissue works in centimetres, so convert on load if a file is in other units.
//!
//! Invariants:
//! - Reads never panic, whatever the bytes: a malformed, truncated or hostile file is an
//!   `Err`, and no count in a file makes an allocation larger than the file can fill.
//! - Reads bound the work any input can cause (the studio reads uploads from the network):
//!   memory and time stay linear in the file's size, with small factors, whatever its counts
//!   say. See [Limits](#limits).
//! - Indices in returned data are in range (0-based), and vertices keep the file's order (STL,
//!   which stores corners, numbers the welded vertices in order of first appearance).
//! - Writes are atomic: data go to a temporary file in the target's folder, which is synced and
//!   then renamed over the target; on failure it is removed. A reader never sees half a file.
//! - What is written reads back identically: the same triangles, and positions with the same
//!   `f32` bits (STL: the same triangles up to vertex numbering, since STL stores corners).
//!
//! ## Limits
//! A reader trusts no count or size in a file before checking it against what the file holds:
//! - Capacities reserved for a declared count (vertices, nodes, cells, elements) are bounded by
//!   what the bytes left can hold (at the smallest size a record can have), and every loop over
//!   a declared count consumes at least one byte, token or line per step, so a count larger
//!   than the data ends in a "truncated" error at the end of the data. Text is read token by
//!   token or line by line, never split into a list of every line first.
//! - Compressed data exist only in `.vtu` (zlib; nothing else in these formats is
//!   compressed). There each array's size follows from `NumberOfPoints`, `NumberOfCells` and
//!   the offsets, and a header declaring another size is refused before anything is inflated;
//!   the arrays of one file may decode to at most [`MAX_INFLATION_RATIO`] times its size
//!   (at least 1 MiB) and never more than [`MAX_INFLATED`] (1 GiB); arrays the reader does not
//!   use are never decoded. The details are in [`read_vtu`].
//! - What a file names by number (cell and element types) is tallied in bounded space; XML
//!   nesting in a `.vtu` is bounded ([`MAX_DEPTH`]); PLY element and property names are at
//!   most 255 bytes (ply-rs copies them for every record).
//!
//! What is not bounded here is the file itself: [`read_surface`] and the other `read_*`
//! functions read the whole file, so a server caps the size of uploads before calling a
//! `parse_*` function (the studio takes at most 64 MiB).
//!
//! ```
//! use glam::Vec3;
//! use tissue_mesh::TriMesh;
//!
//! // A tetrahedron's surface, outward normals.
//! let mesh = TriMesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, 0.1)],
//!     vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
//! )?;
//! let path = std::env::temp_dir().join(format!("meshio-doc-{}.ply", std::process::id()));
//! tissue_meshio::write_surface(&path, &mesh)?;
//! let back = tissue_meshio::read_surface(&path)?;
//! assert_eq!(back, mesh);
//! std::fs::remove_file(&path).ok();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]

mod atomic;
mod data;
mod error;
mod gmsh;
mod obj;
mod ply;
mod stl;
mod tally;
mod tetgen;
mod text;
mod vtk;
mod vtu;

pub use atomic::write_bytes;
pub use data::{
    parse_surface_data, parse_tet_data, read_surface, read_surface_data, read_tet_data, read_tets,
    write_surface, SurfaceData, SurfaceFormat, TetData, TetFormat,
};
pub use error::MeshIoError;
pub use gmsh::{parse_msh, read_msh};
pub use obj::{parse_obj, read_obj, write_obj};
pub use ply::{parse_ply, read_ply, write_ply};
pub use stl::{parse_stl, read_stl, write_stl};
pub use tetgen::{parse_tetgen, read_tetgen};
pub use vtk::{
    parse_vtk, read_vtk, write_vtk, write_vtk_tets, FieldValues, PointField, PointValues,
    VertexField, VtkData, VtkMesh,
};
pub use vtu::{parse_vtu, read_vtu, MAX_DEPTH, MAX_INFLATED, MAX_INFLATION_RATIO};
