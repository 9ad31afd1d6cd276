//! What the host hears about: cuts, pieces, sutures.

use std::ops::Range;

/// An event for the host (rendering, scoring), with the ids it needs.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SurgeryEvent {
    /// A cut split tets or opened faces.
    CutAdvanced {
        /// Nodes appended to the body: first the nodes on split edges (their own origin), then
        /// copies of nodes the opening split (see [`crate::Surgery::origins`]).
        new_nodes: Range<u32>,
        /// Tets appended by splits (indices into [`tissue_pbd::SoftBody::tets`]).
        new_tets: Range<u32>,
        /// Tets split: each record now holds one of its pieces, the others are in `new_tets`.
        split_tets: Vec<u32>,
        /// Nodes moved onto the blade's plane (current and rest position).
        snapped_nodes: Vec<u32>,
        /// Boundary triangles (surface or earlier walls) split into pieces: 3 where the blade
        /// crossed two of their edges, 2 where it crossed one edge and a node, 5 where the
        /// cut's end (its tip) lies inside the triangle. A triangle an earlier sweep split is
        /// reported again as one of its pieces split further.
        split_triangles: Vec<SplitTriangle>,
        /// Tets moved onto new nodes (indices into [`tissue_pbd::SoftBody::tets`]).
        changed_tets: Vec<u32>,
        /// The new wall triangles (both sides, wound outward, current node numbering).
        opened_faces: Vec<[u32; 3]>,
    },
    /// A cut made a new connected piece.
    PieceDetached {
        /// The piece's label ([`crate::Surgery::tet_components`]).
        component: u32,
        /// Its tets.
        tets: Vec<u32>,
        /// Its nodes.
        nodes: Vec<u32>,
        /// Its rest volume (cm³).
        rest_volume: f64,
    },
    /// A suture was placed.
    SuturePlaced {
        /// The suture's id (for [`crate::Surgery::remove_suture`]).
        suture: usize,
        /// The linked nodes.
        nodes: [u32; 2],
        /// The body's distance constraint that links them.
        constraint: usize,
    },
    /// A suture was removed.
    SutureRemoved {
        /// Its id.
        suture: usize,
        /// The nodes it linked.
        nodes: [u32; 2],
    },
}

/// A boundary triangle a cut split, for a renderer to replace.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SplitTriangle {
    /// The triangle before the split (wound outward, node numbering before the split).
    pub original: [u32; 3],
    /// Its pieces (wound outward).
    pub pieces: Vec<[u32; 3]>,
}
