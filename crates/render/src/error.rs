//! The one error type of the crate.

use std::path::PathBuf;

use crate::image::Image;

/// Why a picture could not be made or written.
///
/// Bad input (sizes, meshes, fields, cameras, colour ranges) is reported before anything is drawn,
/// so an image passed to a failing call is left unchanged.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The requested image size is zero or too large (see [`Image::MAX_SIDE`] and
    /// [`Image::MAX_PIXELS`]).
    #[error(
        "image size {width}x{height} is not allowed: each side must be 1..={max_side} pixels and \
         the image at most {max_pixels} pixels",
        max_side = Image::MAX_SIDE,
        max_pixels = Image::MAX_PIXELS
    )]
    ImageSize {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
    },
    /// A per-vertex field does not have one value per vertex.
    #[error("the field has {field} values but the mesh has {vertices} vertices (need one value per vertex)")]
    FieldLength {
        /// Number of field values given.
        field: usize,
        /// Number of vertices of the mesh.
        vertices: usize,
    },
    /// A surface has no vertices or no triangles.
    #[error("the mesh is empty ({vertices} vertices, {triangles} triangles): nothing to draw")]
    EmptyMesh {
        /// Number of vertices given.
        vertices: usize,
        /// Number of triangles given.
        triangles: usize,
    },
    /// A vertex position is NaN or infinite.
    #[error("vertex {vertex} has a non-finite position {position:?}")]
    NonFinitePosition {
        /// Index of the first such vertex.
        vertex: usize,
        /// Its stored coordinates.
        position: [f32; 3],
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// The camera cannot be built: a zero or non-finite view direction, an up vector parallel to
    /// it, or a non-finite box to frame.
    #[error("invalid camera: {reason}")]
    InvalidCamera {
        /// What is wrong.
        reason: String,
    },
    /// A colour range whose ends are not finite or not increasing.
    #[error("invalid colour range [{min}, {max}]: both ends must be finite and min < max")]
    InvalidRange {
        /// Lower end given.
        min: f32,
        /// Upper end given.
        max: f32,
    },
    /// The PNG encoder failed.
    #[error("PNG encoding failed: {0}")]
    Encode(#[from] png::EncodingError),
    /// Writing the PNG file failed.
    #[error("cannot write PNG file {}: {source}", path.display())]
    Io {
        /// The file that was to be written.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}
