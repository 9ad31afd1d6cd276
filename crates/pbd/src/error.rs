//! The one error type of the crate.

/// What can go wrong building or stepping a soft body. Every variant names the element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PbdError {
    /// A material or step parameter is out of range.
    #[error("invalid parameter {name} = {value}: expected {expected}")]
    InvalidParameter {
        /// Parameter name, e.g. `"distance_stiffness"` or `"dt"`.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range.
        expected: &'static str,
    },
    /// An element (tetrahedron, pin, attachment) refers to a node that does not exist.
    #[error("{element} {index} refers to node {node}, but the body has {count} nodes")]
    NodeOutOfRange {
        /// What refers to the node: `"tet"`, `"pin"`, `"attachment"`.
        element: &'static str,
        /// Index of that element (for a pin or attachment, the node itself).
        index: usize,
        /// The node index given.
        node: u32,
        /// Number of nodes.
        count: usize,
    },
    /// A tetrahedron has (numerically) zero or negative volume, or repeats a node: it cannot carry
    /// mass or volume constraints. Fix or drop it in the mesh.
    #[error("tet {tet} is degenerate (signed volume {volume}); it must be positively oriented and not flat")]
    DegenerateTet {
        /// Tetrahedron index as given.
        tet: usize,
        /// Its signed volume `(b−a)×(c−a)·(d−a)/6`.
        volume: f64,
    },
    /// A node position or velocity given is not finite.
    #[error("node {node}: {what} is not finite")]
    NonFinite {
        /// Node index.
        node: u32,
        /// `"position"` or `"velocity"`.
        what: &'static str,
    },
    /// An array given has the wrong length.
    #[error("{what} has {got} entries but the body has {expected} nodes")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The node count.
        expected: usize,
    },
    /// No attachment has this id: it was never made on this body, or its node was freed.
    #[error("attachment {id} does not exist or its node was freed (the body has {count} live attachments)")]
    NoSuchAttachment {
        /// The id given.
        id: crate::AttachmentId,
        /// Number of live attachments.
        count: usize,
    },
    /// A node became non-finite during a step: the step or the stiffness is too large, or the
    /// input is not finite. Reduce `dt` or raise the compliance.
    #[error("diverged at step {step}: node {node} became non-finite; reduce dt or the stiffness")]
    Diverged {
        /// Step number (0-based, counted since the body was built).
        step: u64,
        /// The first node found non-finite.
        node: u32,
    },
    /// A collider shape cannot be voxelised: the message says which shape (its index in the list
    /// given to [`crate::VoxelCollider::new`]) and why.
    #[error("collider shape {shape}: {reason}")]
    InvalidColliderShape {
        /// Index of the shape in the list given.
        shape: usize,
        /// What is wrong and how to fix it.
        reason: &'static str,
    },
    /// A collider mesh is not closed, so inside and outside are undefined.
    #[error("collider shape {shape}: the mesh is not closed ({boundary_edges} boundary edges); a static collider needs a closed surface to tell inside from outside: close the holes, or use boxes")]
    ColliderMeshNotClosed {
        /// Index of the shape in the list given.
        shape: usize,
        /// Number of edges used by one triangle only.
        boundary_edges: usize,
    },
    /// The voxel grid would be too large.
    #[error("the collider's voxel grid would have {corners} corners (limit {limit}) at cell size {cell_size} cm; use a larger cell size")]
    ColliderTooLarge {
        /// Grid corners needed.
        corners: u64,
        /// The largest grid accepted.
        limit: u64,
        /// The cell size given (cm).
        cell_size: f32,
    },
    /// A tool primitive is degenerate or has a bad size.
    #[error("tool: {reason}")]
    InvalidTool {
        /// What is wrong and how to fix it.
        reason: &'static str,
    },
    /// No collider (`what = "collider"`) or tool (`what = "tool"`) has this id.
    #[error("{what} {id} does not exist (the body has {count})")]
    NoSuchContactSource {
        /// `"collider"` or `"tool"`.
        what: &'static str,
        /// The id given.
        id: usize,
        /// How many there are.
        count: usize,
    },
    /// A topology edit names a constraint or tet that does not exist or was removed.
    #[error("{what} {index} does not exist or was removed (the body has {count})")]
    NoSuchElement {
        /// `"distance constraint"` or `"tet"`.
        what: &'static str,
        /// The index given.
        index: usize,
        /// How many there are.
        count: usize,
    },
}
