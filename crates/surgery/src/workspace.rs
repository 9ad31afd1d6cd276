//! The cut pipeline's workspace: scratch buffers reused by every cut, apart from the
//! persistent state of [`crate::Surgery`]. None of it carries meaning from one cut to the
//! next; it is kept only so that a cut in steady state allocates no new per-tet or per-node
//! arrays (they grow with the body and are otherwise reused as they are).
//!
//! Marks are *stamped*: an entry equal to the current stamp is set, any other value is stale,
//! so no array is cleared between uses (only when a stamp wraps around).

/// Scratch of the cut pipeline, one per [`crate::Surgery`] (a private field), by phase.
#[derive(Debug, Clone, Default)]
pub(crate) struct CutScratch {
    /// Straddling search and face search: per tet, marked with `stamp` (the tets near this
    /// sweep; then the candidates, so that each pair is tested once; then the crumbs found).
    /// Sized to the tets.
    pub tet_mark: Vec<u32>,
    /// The current stamp of `tet_mark`; see [`CutScratch::next_stamp`].
    pub stamp: u32,
    /// Straddling search, split and tips: each node's signed distance from the current
    /// blade's plane (cm), for the body's nodes before this cut's split.
    pub side: Vec<f64>,
    /// Straddling search: the tets of the nodes near the plane, and their nodes.
    pub near_tets: Vec<u32>,
    pub near_nodes: Vec<[u32; 4]>,
    /// Crumb search: per tet, marked with `group_stamp` (see `Surgery::small_group`).
    pub group_mark: Vec<u32>,
    pub group_stamp: u32,
    /// Manifold guard: per node, its entry in the nodes' split plan (`u32::MAX` when it has
    /// none; reset after each use).
    pub plan_entry: Vec<u32>,
    /// A node's split plan: per tet, its index in the node's star (stale for other tets).
    pub star_slot: Vec<u32>,
    /// Manifold guard: per tet, all `false` between uses.
    pub tet_seen: Vec<bool>,
    /// Connectivity proof after a cut (`Surgery::still_connected`): per tet, the search that
    /// found it and the side that reached it, stamped from `search_stamp`.
    pub found_by: Vec<u32>,
    pub search_side: Vec<u32>,
    pub search_stamp: u32,
    /// Applying a split: the plan's pieces with its new nodes numbered.
    pub pieces: Vec<[u32; 4]>,
}

impl CutScratch {
    /// The workspace for a body of `tets` tets.
    pub fn new(tets: usize) -> Self {
        Self {
            tet_mark: vec![0; tets],
            ..Self::default()
        }
    }

    /// A fresh stamp for `tet_mark` (never 0).
    pub fn next_stamp(&mut self) -> u32 {
        self.stamp = self.stamp.wrapping_add(1).max(1);
        self.stamp
    }
}
