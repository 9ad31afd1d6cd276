//! The one error type of the crate: every defect a user's mesh can have, naming the element.

/// A defect of a mesh, or a measure asked of a mesh that cannot give it.
///
/// Each variant names the element (vertex, triangle, edge, tetrahedron) where the defect was found,
/// with indices counted from 0 as stored. [`MeshError::is_warning`] tells the warning-level
/// defects (a mesh with only those is accepted) from the hard ones.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The mesh has no vertices or no elements.
    #[error("the mesh is empty ({vertices} vertices, {elements} elements): nothing to simulate")]
    Empty {
        /// Number of vertices given.
        vertices: usize,
        /// Number of triangles or tetrahedra given.
        elements: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate {position:?}: fix or remove it in the source file")]
    NonFiniteCoordinate {
        /// Vertex index.
        vertex: u32,
        /// The stored coordinates.
        position: [f32; 3],
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has only {vertex_count} vertices")]
    IndexOutOfRange {
        /// Triangle index.
        triangle: u32,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices in the mesh.
        vertex_count: u32,
    },
    /// A triangle has zero area: a repeated vertex, or three (nearly) collinear vertices.
    #[error(
        "triangle {triangle} {vertices:?} has zero area ({area:e}): remove it or merge its vertices"
    )]
    DegenerateTriangle {
        /// Triangle index.
        triangle: u32,
        /// Its vertex indices.
        vertices: [u32; 3],
        /// Its area in the mesh's units squared.
        area: f64,
    },
    /// Two triangles use the same three vertices.
    #[error(
        "triangle {triangle} repeats triangle {first} (same vertices {vertices:?}): remove one"
    )]
    DuplicateTriangle {
        /// The later triangle's index.
        triangle: u32,
        /// The first triangle with these vertices.
        first: u32,
        /// The shared vertices, as stored in `triangle`.
        vertices: [u32; 3],
    },
    /// An edge is shared by more than two triangles (non-manifold).
    #[error("edge {edge:?} is shared by {} triangles {triangles:?}; a surface edge may have at most two", triangles.len())]
    NonManifoldEdge {
        /// The edge's vertices, smaller index first.
        edge: [u32; 2],
        /// All triangles that contain it.
        triangles: Vec<u32>,
    },
    /// Two neighbouring triangles traverse their shared edge in the same direction, so their
    /// normals point to opposite sides.
    #[error(
        "triangles {triangles:?} share edge {edge:?} but have opposite winding: flip one of them"
    )]
    InconsistentWinding {
        /// The shared edge, smaller index first.
        edge: [u32; 2],
        /// The two triangles.
        triangles: [u32; 2],
    },
    /// A vertex is used by no element (warning level: the mesh is still accepted).
    #[error("vertex {vertex} is not used by any element; it is ignored")]
    UnreferencedVertex {
        /// Vertex index.
        vertex: u32,
    },
    /// A tetrahedron refers to a vertex that does not exist.
    #[error(
        "tetrahedron {tet} refers to vertex {index}, but the mesh has only {vertex_count} vertices"
    )]
    TetIndexOutOfRange {
        /// Tetrahedron index.
        tet: u32,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices in the mesh.
        vertex_count: u32,
    },
    /// A tetrahedron has zero or negative volume for its vertex order `a b c d`
    /// (`(b−a)×(c−a)·(d−a)` must be positive).
    #[error("tetrahedron {tet} {vertices:?} has volume {volume:e} ≤ 0: swap two of its vertices if it is inverted, remove it if it is flat")]
    InvertedTet {
        /// Tetrahedron index.
        tet: u32,
        /// Its vertex indices.
        vertices: [u32; 4],
        /// Its signed volume.
        volume: f64,
    },
    /// A triangular face is shared by more than two tetrahedra.
    #[error("face {face:?} is shared by {} tetrahedra {tets:?}; at most two may share a face", tets.len())]
    NonManifoldFace {
        /// The face's vertices, sorted.
        face: [u32; 3],
        /// All tetrahedra that contain it.
        tets: Vec<u32>,
    },
    /// A measure that needs a closed surface was asked of an open one.
    #[error("the surface is open ({boundary_edges} boundary edges in {loops} loops); this measure needs a closed surface")]
    NotClosed {
        /// Number of boundary edges.
        boundary_edges: usize,
        /// Number of boundary loops.
        loops: usize,
    },
    /// Two open surfaces that should share their boundary do not.
    #[error("the two surfaces do not share their boundary: {reason}")]
    BoundaryMismatch {
        /// What differs.
        reason: String,
    },
    /// New positions given for a mesh have the wrong count.
    #[error("expected {expected} positions, got {got}")]
    PositionCount {
        /// Vertex count of the mesh.
        expected: usize,
        /// Count given.
        got: usize,
    },
    /// A generator was asked for a mesh it cannot make.
    #[error("invalid generator parameter: {what}")]
    InvalidParameter {
        /// Which parameter and why.
        what: String,
    },
    /// Two tetrahedra use the same four vertices.
    #[error(
        "tetrahedron {tet} repeats tetrahedron {first} (same vertices {vertices:?}): remove one"
    )]
    DuplicateTet {
        /// The later tetrahedron's index.
        tet: u32,
        /// The first tetrahedron with these vertices.
        first: u32,
        /// The shared vertices, as stored in `tet`.
        vertices: [u32; 4],
    },
    /// A measure that needs an open surface (one with a boundary) was given a closed one.
    #[error("the {surface} surface is closed (it has no boundary); the volume between two surfaces needs two open surfaces with the same boundary (for a closed surface, use its signed volume)")]
    NotOpen {
        /// Which surface: `"before"` or `"after"`.
        surface: &'static str,
    },
}

impl MeshError {
    /// `true` for the warning-level defects, which do not stop a mesh from loading.
    pub fn is_warning(&self) -> bool {
        matches!(self, MeshError::UnreferencedVertex { .. })
    }
}
