//! The split's plan: what a sweep's split will create, made before anything is applied, with
//! typed ids for the nodes it creates.
//!
//! The planning phases (module `split`, and the tips of module `tip`) judge pieces of tets
//! whose nodes do not exist yet. Such a node is a [`NewNode`]: its index among the new nodes
//! of the plan being judged. A piece's corner is a [`NodeRef`]: a node of the body or a new
//! one. Only [`crate::Surgery::apply_split`] gives new nodes their numbers in the body (the
//! first new node is appended at the body's node count, the others after it in order), so
//! no body node id is ever guessed or reserved while planning.

use std::ops::Range;

use glam::DVec3;

use crate::tip::FourWayTip;

/// A node a planned split creates: its index among the plan's new nodes (edge nodes first, in
/// the order of their edges, then the four-way tips' points).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct NewNode(pub u32);

/// A corner of a planned piece: a node of the body, or a node the plan creates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum NodeRef {
    Body(u32),
    New(NewNode),
}

impl NodeRef {
    /// The node's number in the body once the plan's new nodes are appended from `first`.
    pub fn resolve(self, first: u32) -> u32 {
        match self {
            NodeRef::Body(v) => v,
            NodeRef::New(NewNode(k)) => first + k,
        }
    }
}

impl From<u32> for NodeRef {
    fn from(v: u32) -> Self {
        NodeRef::Body(v)
    }
}

impl From<NewNode> for NodeRef {
    fn from(k: NewNode) -> Self {
        NodeRef::New(k)
    }
}

/// A crossing edge of a sweep: the crossing parameter from its smaller node, whether the
/// crossing point counts as inside the polygon, whether it is split, and its new node.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EdgeCut {
    pub s: f64,
    /// The crossing point is in this sweep's polygon or was in an earlier sweep's at about the
    /// same place along the edge.
    pub inside: bool,
    /// The edge is planned for a split.
    pub valid: bool,
    /// Its node in the plan being judged (set when the plan numbers its edges; meaningful
    /// only while `valid`).
    pub node: Option<NewNode>,
}

/// A new node inside a boundary triangle (a four-way tip, module `tip`): the weighted sum of
/// three existing nodes (weights positive, summing to 1), in current, previous and rest
/// position and velocity.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FacePoint {
    pub nodes: [u32; 3],
    pub weights: [f64; 3],
}

impl FacePoint {
    /// Its rest position from the rest positions `rest` of the body's nodes.
    pub fn rest(&self, rest: &[DVec3]) -> DVec3 {
        (0..3)
            .map(|k| rest[self.nodes[k] as usize] * self.weights[k])
            .sum()
    }
}

/// A split edge of a plan: its ends (sorted) and the crossing parameter from the first.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SplitEdge {
    pub ends: [u32; 2],
    pub s: f64,
}

/// A tet of a plan and its pieces (a range of [`SplitPlan::pieces`]; the first piece keeps
/// the tet's record).
#[derive(Debug, Clone)]
pub(crate) struct TetSplit {
    pub tet: u32,
    pub pieces: Range<usize>,
}

/// What a split will create, ready to apply ([`crate::Surgery::apply_split`]): the new nodes
/// (`NewNode(k)`: edge `k` of `edges`, then tip `k − edges.len()` of `tips`), their rest
/// positions, and each split tet's pieces.
#[derive(Debug, Default)]
pub(crate) struct SplitPlan {
    /// The split edges, sorted, in the order of their new nodes.
    pub edges: Vec<SplitEdge>,
    /// The four-way tips, whose points are new nodes after the edges' (module `tip`).
    pub tips: Vec<FourWayTip>,
    /// Rest position of each new node.
    pub new_rest: Vec<DVec3>,
    /// The tets to split, in the order their pieces are made.
    pub tets: Vec<TetSplit>,
    pub pieces: Vec<[NodeRef; 4]>,
}

impl SplitPlan {
    /// How many nodes it creates.
    pub fn new_node_count(&self) -> u32 {
        (self.edges.len() + self.tips.len()) as u32
    }

    /// The new node of tip `k`.
    pub fn tip_node(&self, k: usize) -> NewNode {
        NewNode((self.edges.len() + k) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// New nodes resolve past the body's nodes in plan order; body nodes stay themselves.
    #[test]
    fn new_nodes_resolve_in_plan_order() {
        assert_eq!(NodeRef::from(7).resolve(100), 7);
        assert_eq!(NodeRef::from(NewNode(0)).resolve(100), 100);
        assert_eq!(NodeRef::from(NewNode(3)).resolve(100), 103);
        let plan = SplitPlan {
            edges: vec![
                SplitEdge {
                    ends: [0, 1],
                    s: 0.5,
                };
                2
            ],
            ..SplitPlan::default()
        };
        assert_eq!(plan.tip_node(0), NewNode(2));
        assert_eq!(plan.new_node_count(), 2);
    }
}
