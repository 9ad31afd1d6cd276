//! What the host hears about: cuts, pieces, sutures.

use std::ops::Range;

/// An event for the host (rendering, scoring), with the ids it needs.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SurgeryEvent {
    /// A cut opened faces.
    CutAdvanced {
        /// Nodes appended to the body (copies of split nodes; see
        /// [`crate::Surgery::origins`]).
        new_nodes: Range<u32>,
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
