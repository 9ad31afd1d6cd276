//! Scratch space of the queries, created once and passed to every call so that a simulation step
//! allocates nothing.

/// Traversal stacks for [`crate::Bvh`] queries.
///
/// The stacks grow on first use to the depth the hierarchy needs and keep their capacity, so after
/// the first query of each kind no query allocates. One workspace serves any number of
/// hierarchies (one query at a time).
#[derive(Debug, Clone, Default)]
pub struct BvhWorkspace {
    pub(crate) stack: Vec<u32>,
    pub(crate) scored: Vec<(f32, u32)>,
    pub(crate) pairs: Vec<[u32; 2]>,
}

impl BvhWorkspace {
    /// A workspace with room for hierarchies of depth 64 (any depth works; deeper ones grow it
    /// once).
    pub fn new() -> Self {
        BvhWorkspace {
            stack: Vec::with_capacity(128),
            scored: Vec::with_capacity(128),
            pairs: Vec::with_capacity(256),
        }
    }
}
