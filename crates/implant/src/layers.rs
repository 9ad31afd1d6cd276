//! The two-layer tissue model of SPEC A.5 steps 1–3 (being written).

/// Material and geometry of the two-layer model.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerParams {}

/// The two-layer mass–spring model of a skin region.
#[derive(Debug)]
pub struct TissueLayers {}
