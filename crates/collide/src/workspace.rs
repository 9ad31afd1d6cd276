//! Scratch space of detection, created once and reused every step.

use tissue_bvh::BvhWorkspace;

use crate::narrow::ChunkState;

/// Buffers the detection functions reuse, so that a step allocates nothing once they have grown
/// to the largest size a step needed.
#[derive(Debug, Clone, Default)]
pub struct DetectWorkspace {
    pub(crate) bvh: BvhWorkspace,
    pub(crate) pairs: Vec<[u32; 2]>,
    pub(crate) leaves: Vec<u32>,
    pub(crate) chunks: Vec<ChunkState>,
}

impl DetectWorkspace {
    /// An empty workspace.
    pub fn new() -> Self {
        DetectWorkspace {
            bvh: BvhWorkspace::new(),
            ..Default::default()
        }
    }
}
