//! The one error type of the crate.

/// Why a hierarchy could not be built, refit or queried. Each variant names the element (primitive,
/// triangle, vertex) at fault, counted from 0 as the caller stores them.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BvhError {
    /// There is nothing to build a hierarchy over.
    #[error("no primitives: a hierarchy needs at least one")]
    Empty,
    /// More primitives than `u32` indices can address (two nodes per primitive are needed).
    #[error("{count} primitives: a hierarchy holds at most {max}")]
    TooManyPrimitives {
        /// Number of primitives given.
        count: usize,
        /// The largest number supported.
        max: usize,
    },
    /// The leaf size is zero.
    #[error("leaf size {leaf_size}: a leaf must be allowed at least one primitive")]
    InvalidLeafSize {
        /// The leaf size given.
        leaf_size: u32,
    },
    /// The margin is negative or not finite.
    #[error("margin {margin}: must be finite and at least 0 (in the units of the positions)")]
    InvalidMargin {
        /// The margin given.
        margin: f32,
    },
    /// A primitive's box has a NaN or infinite coordinate (e.g. a vertex of a diverged
    /// simulation).
    #[error("primitive {primitive} has a non-finite bounding box {min:?}..{max:?}: check its vertex positions")]
    NonFiniteBounds {
        /// Primitive (triangle) index.
        primitive: u32,
        /// The box's minimum corner.
        min: [f32; 3],
        /// The box's maximum corner.
        max: [f32; 3],
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {index}, but there are only {vertex_count} positions"
    )]
    IndexOutOfRange {
        /// Triangle index.
        triangle: u32,
        /// The offending vertex index.
        index: u32,
        /// Number of positions given.
        vertex_count: usize,
    },
    /// The positions do not match the mesh they are meant to move.
    #[error("{got} positions given for a mesh of {expected} vertices")]
    PositionCount {
        /// Number of vertices of the mesh.
        expected: usize,
        /// Number of positions given.
        got: usize,
    },
    /// A refit or rebuild was given a different set of primitives than the hierarchy was built on.
    #[error(
        "the hierarchy was built over {expected} primitives but was given {got}: build a new one"
    )]
    PrimitiveCount {
        /// Primitives at build time.
        expected: usize,
        /// Primitives given now.
        got: usize,
    },
}
