//! The one error type of the crate.

use tissue_mesh::MeshError;

/// Why a surface could not be tetrahedralised. Every variant names the element (vertex,
/// triangle, edge, counted from 0 as stored) and says how to fix the input where it can.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TetraError {
    /// The surface has a hole: an edge with a triangle on one side only.
    #[error(
        "the surface is open: edge {edge:?} of triangle {triangle} has no triangle on its other \
         side ({boundary_edges} boundary edges in {loops} loops); only a closed surface encloses \
         a volume, so close the holes first"
    )]
    OpenSurface {
        /// The first boundary edge, smaller vertex first.
        edge: [u32; 2],
        /// Its one triangle.
        triangle: u32,
        /// Number of boundary edges.
        boundary_edges: usize,
        /// Number of boundary loops.
        loops: usize,
    },
    /// An edge is shared by more than two triangles (only reachable through
    /// [`tetrahedralize_triangles`](crate::tetrahedralize_triangles): a
    /// [`tissue_mesh::TriMesh`] cannot hold one).
    #[error(
        "edge {edge:?} is shared by {} triangles {triangles:?}; a closed surface has exactly two \
         on every edge: split the surface there into separate solids",
        triangles.len()
    )]
    NonManifoldEdge {
        /// The edge, smaller vertex first.
        edge: [u32; 2],
        /// Every triangle on it.
        triangles: Vec<u32>,
    },
    /// Two parts of the surface touch at one vertex only: its triangles make more than one fan.
    #[error(
        "vertex {vertex} is non-manifold: its {triangles} triangles form {fans} separate fans \
         (parts of the surface touch at this vertex only); give each fan its own vertex"
    )]
    NonManifoldVertex {
        /// The vertex.
        vertex: u32,
        /// Number of triangles around it.
        triangles: usize,
        /// Number of edge-connected fans among them.
        fans: usize,
    },
    /// Two vertices used by triangles are at the same position.
    #[error(
        "vertices {first} and {second} are both at {position:?}; weld them (merge the two and \
         re-index the triangles) or move one"
    )]
    CoincidentVertices {
        /// The smaller index.
        first: u32,
        /// The larger index.
        second: u32,
        /// The shared position.
        position: [f32; 3],
    },
    /// A triangle has zero area (only reachable through
    /// [`tetrahedralize_triangles`](crate::tetrahedralize_triangles)).
    #[error("triangle {triangle} {vertices:?} has zero area ({area:e}): remove it or merge its vertices")]
    DegenerateTriangle {
        /// The triangle.
        triangle: u32,
        /// Its vertices.
        vertices: [u32; 3],
        /// Its area.
        area: f64,
    },
    /// The surface's normals point inward.
    #[error(
        "the surface is inside out: its signed volume is {volume:e} < 0 (normals point inward); \
         reverse the winding of every triangle"
    )]
    InsideOut {
        /// The signed volume.
        volume: f64,
    },
    /// The surface encloses (almost) no volume: flat, or two sheets on top of each other.
    #[error(
        "the surface encloses no volume (signed volume {volume:e} for a bounding box of \
         diagonal {diagonal:e}): it is flat or folded onto itself"
    )]
    NoVolume {
        /// The signed volume.
        volume: f64,
        /// The bounding box diagonal, for scale.
        diagonal: f64,
    },
    /// Fewer than four vertices are used by triangles.
    #[error("the surface uses {vertices} vertices; a solid needs at least 4")]
    TooFewPoints {
        /// Number of vertices used by triangles.
        vertices: usize,
    },
    /// Another defect of raw surface data (see [`tissue_mesh::diagnose`]).
    #[error("invalid surface: {0}")]
    InvalidSurface(#[source] MeshError),
    /// An option is out of range.
    #[error("invalid option: {what}")]
    InvalidOption {
        /// Which option and why.
        what: String,
    },
    /// More tetrahedra than [`TetraOptions::max_tets`](crate::TetraOptions::max_tets) allows.
    #[error("{}", too_many_tets(*tets, *max, *when, *triangles, *decimate_to))]
    TooManyTets {
        /// The count that was over: estimated, of the Delaunay tetrahedralisation, or made.
        tets: usize,
        /// The limit ([`TetraOptions::max_tets`](crate::TetraOptions::max_tets)).
        max: usize,
        /// Which count.
        when: TetCount,
        /// The surface's triangles.
        triangles: usize,
        /// About how many triangles the same shape, decimated evenly, may have to stay within
        /// the limit ([`TetEstimate::triangles_for`](crate::TetEstimate::triangles_for)).
        decimate_to: Option<usize>,
    },
    /// The mesher failed for numerical reasons (a bug or an extreme input, never bad luck).
    #[error(
        "numerical failure while {stage}{}: {detail}; please report it with the input mesh",
        vertex.map(|v| format!(" (at node {v})")).unwrap_or_default()
    )]
    NumericalFailure {
        /// The phase: `"inserting points"`, `"carving"`, `"building the mesh"`.
        stage: &'static str,
        /// The node (surface vertices first, then interior points) it failed at, if any.
        vertex: Option<u32>,
        /// What went wrong.
        detail: String,
    },
}

/// Which count of tetrahedra went over [`TetraOptions::max_tets`](crate::TetraOptions::max_tets)
/// ([`TetraError::TooManyTets`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TetCount {
    /// [`estimate_tets`](crate::estimate_tets), before any meshing.
    Estimated,
    /// The Delaunay tetrahedralisation under construction: it outgrew the estimate (4 × + 1000),
    /// the surface's points being badly distributed for Delaunay.
    Delaunay,
    /// The tetrahedra made.
    Made,
}

fn too_many_tets(
    tets: usize,
    max: usize,
    when: TetCount,
    triangles: usize,
    decimate_to: Option<usize>,
) -> String {
    let fix = match decimate_to {
        Some(n) if n < triangles => {
            format!("decimate the surface to about {n} triangles or fewer (it has {triangles})")
        }
        _ => format!("decimate the surface (it has {triangles} triangles) or coarsen the spacing"),
    };
    match when {
        TetCount::Estimated => format!(
            "the surface would fill with about {tets} tetrahedra (estimated before meshing), \
             more than the limit of {max}: {fix}"
        ),
        TetCount::Delaunay => format!(
            "meshing stopped: the Delaunay tetrahedralisation grew to {tets} tetrahedra, far \
             more than the estimate for this surface (the limit is {max}): its vertices are \
             badly spread (e.g. many on a few lines, with long thin triangles between them); \
             remesh the surface with even triangles"
        ),
        TetCount::Made => format!(
            "the surface filled with {tets} tetrahedra, more than the limit of {max}: {fix}"
        ),
    }
}
