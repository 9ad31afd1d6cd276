//! The one error type of the crate: every failure names the file, and where it can, the line
//! (text formats) or the element (binary formats), and says how to fix it.

use std::path::{Path, PathBuf};

use tissue_mesh::MeshError;

/// The file name endings the surface readers and [`crate::write_surface`] understand.
pub(crate) const SURFACE_EXTENSIONS: &str = ".obj, .ply, .stl or .vtk";

/// The file name endings [`crate::read_tet_data`] understands.
pub(crate) const TET_EXTENSIONS: &str =
    ".vtu (VTK XML), .msh (Gmsh), .vtk (legacy VTK), or TetGen .node/.ele";

/// Why reading or writing a mesh file failed.
///
/// `path` is the file that was read or the file that was to be written (for data parsed from
/// memory, the name given by the caller). Lines count from 1; element indices from 0, as stored.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshIoError {
    /// The operating system refused: missing file or folder, no permission, disk full, ...
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file read or written.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A text file (OBJ, ASCII PLY or STL, VTK, TetGen, or a PLY header) does not say what its
    /// format requires at this line.
    #[error("{}, line {line}: {message}", .path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The offending line, counted from 1.
        line: usize,
        /// What was expected and what was found.
        message: String,
    },
    /// A binary file (binary PLY or STL) is truncated or holds a value that cannot be right.
    #[error("{}, {element}{}: {message}", .path.display(), index_suffix(.index))]
    Binary {
        /// The file.
        path: PathBuf,
        /// The kind of element: `"header"`, `"triangle"`, or a PLY element name (`"vertex"`,
        /// `"face"`, ...).
        element: String,
        /// Which element, counted from 0 (`None` for the header).
        index: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The file name does not end in an extension the function understands.
    #[error(
        "{}: unsupported mesh file type: rename or convert it to one ending in {supported}",
        .path.display()
    )]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// The extensions that are understood, e.g. `".obj, .ply, .stl or .vtk"`.
        supported: &'static str,
    },
    /// The file was read, but its data do not make a valid mesh (see [`MeshError`], which names
    /// the element).
    #[error("{}: not a valid mesh: {source}", .path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The first hard defect found.
        source: MeshError,
    },
    /// The file holds a different kind of mesh than the function reads (tetrahedra where a
    /// surface was asked for, or the other way round).
    #[error("{}: holds {found}, but {wanted} were asked for: {hint}", .path.display())]
    WrongKind {
        /// The file.
        path: PathBuf,
        /// What the file holds, e.g. `"tetrahedra"`.
        found: &'static str,
        /// What the caller asked for, e.g. `"triangles"`.
        wanted: &'static str,
        /// Which function reads what the file holds.
        hint: &'static str,
    },
    /// A per-vertex field given to a VTK writer has the wrong number of values.
    #[error(
        "{}: vertex field `{field}` has {len} values, but the mesh has {expected} vertices: give one value per vertex",
        .path.display()
    )]
    FieldLength {
        /// The file that was to be written.
        path: PathBuf,
        /// The field's name.
        field: String,
        /// Number of values given.
        len: usize,
        /// Number of vertices of the mesh.
        expected: usize,
    },
    /// A per-vertex field given to a VTK writer has a name VTK cannot store.
    #[error(
        "{}: vertex field name {field:?} cannot be written to VTK: use a non-empty name without whitespace",
        .path.display()
    )]
    FieldName {
        /// The file that was to be written.
        path: PathBuf,
        /// The offending name.
        field: String,
    },
    /// A mesh handed to a writer refers to a vertex it does not have. Validated meshes never do;
    /// this guards the writers against a broken invariant instead of panicking.
    #[error(
        "{}: {element} {index} refers to vertex {vertex}, but the mesh has only {vertex_count} vertices",
        .path.display()
    )]
    IndexOutOfRange {
        /// The file that was to be written.
        path: PathBuf,
        /// `"triangle"` or `"tetrahedron"`.
        element: &'static str,
        /// Which element, counted from 0.
        index: usize,
        /// The vertex index it holds.
        vertex: u32,
        /// Number of vertices of the mesh.
        vertex_count: usize,
    },
}

impl MeshIoError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            MeshIoError::Io { path, .. }
            | MeshIoError::Parse { path, .. }
            | MeshIoError::Binary { path, .. }
            | MeshIoError::UnsupportedFormat { path, .. }
            | MeshIoError::Invalid { path, .. }
            | MeshIoError::WrongKind { path, .. }
            | MeshIoError::FieldLength { path, .. }
            | MeshIoError::FieldName { path, .. }
            | MeshIoError::IndexOutOfRange { path, .. } => path,
        }
    }

    /// A [`MeshIoError::Parse`] at `line` of `path`.
    pub(crate) fn parse(path: &Path, line: usize, message: impl Into<String>) -> Self {
        MeshIoError::Parse {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
    }

    /// A [`MeshIoError::Binary`] about `element` number `index` of `path`.
    pub(crate) fn binary(
        path: &Path,
        element: impl Into<String>,
        index: Option<usize>,
        message: impl Into<String>,
    ) -> Self {
        MeshIoError::Binary {
            path: path.to_path_buf(),
            element: element.into(),
            index,
            message: message.into(),
        }
    }

    /// A [`MeshIoError::Io`] about `path`.
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        MeshIoError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

fn index_suffix(index: &Option<usize>) -> String {
    match index {
        Some(i) => format!(" {i}"),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_file_and_location() {
        let e = MeshIoError::parse(Path::new("a.obj"), 7, "expected a number");
        assert_eq!(e.to_string(), "a.obj, line 7: expected a number");
        let e = MeshIoError::binary(Path::new("b.stl"), "triangle", Some(3), "file ends early");
        assert_eq!(e.to_string(), "b.stl, triangle 3: file ends early");
        let e = MeshIoError::binary(Path::new("b.stl"), "header", None, "too short");
        assert_eq!(e.to_string(), "b.stl, header: too short");
        assert_eq!(e.path(), Path::new("b.stl"));
    }
}
