//! The hierarchy itself: flat node array, its invariants, statistics and the well-formedness check.

use crate::{Aabb, Primitives};

/// One node of a [`Bvh`]: 32 bytes, `#[repr(C)]`.
///
/// Inner node: `count == 0`, children at `first` and `first + 1` (adjacent, both with a larger
/// index than their parent). Leaf: `count ≥ 1` primitives, `primitive_order()[first..first + count]`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct BvhNode {
    /// Inner node: the union of the children's boxes. Leaf: the union of its primitives' boxes,
    /// grown by the build margin.
    pub aabb: Aabb,
    /// Inner node: index of the first child. Leaf: offset of its first primitive in
    /// [`Bvh::primitive_order`].
    pub first: u32,
    /// Leaf: number of primitives (≥ 1). Inner node: 0.
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);

impl BvhNode {
    /// `true` for a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// How a node is split in two during the build.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Split {
    /// The thesis's split (SPEC A.3): order the node's primitives by centroid along the longest
    /// axis of their centroid box (ties by primitive index) and cut that order where the two
    /// halves' summed weights (triangle areas) are closest to equal.
    #[default]
    EqualArea,
    /// Binned surface-area heuristic: 16 bins on each axis, the cut minimising
    /// `area(left)·n_left + area(right)·n_right`.
    Sah,
}

/// Parameters of a build, kept by the hierarchy for its refits and rebuilds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuildOptions {
    /// A node with at most this many primitives is a leaf (≥ 1).
    pub leaf_size: u32,
    /// How inner nodes are split.
    pub split: Split,
    /// Every leaf box is grown by this much on each side (≥ 0, units of the positions), so that
    /// queries also find primitives that are about to touch. 0 = tight boxes.
    pub margin: f32,
}

impl Default for BuildOptions {
    /// Leaves of at most 8 primitives, equal-area split, no margin.
    fn default() -> Self {
        BuildOptions {
            leaf_size: 8,
            split: Split::EqualArea,
            margin: 0.0,
        }
    }
}

/// An axis-aligned bounding-box hierarchy over a set of [`Primitives`].
///
/// Invariants (established by [`Bvh::build`], kept by [`Bvh::refit`], checked by
/// [`Bvh::assert_well_formed`]):
/// - `nodes()[0]` is the root; the two children of an inner node are adjacent and come after it;
///   a hierarchy over `n` primitives with `L` leaves has `2L − 1` nodes;
/// - `primitive_order()` is a permutation of `0..n`; the leaves' ranges in it are disjoint and
///   cover it, so every primitive is in exactly one leaf;
/// - every leaf box contains its primitives' boxes (grown by the margin) and every inner box
///   contains its children's boxes.
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    pub(crate) nodes: Vec<BvhNode>,
    pub(crate) order: Vec<u32>,
    /// Refit scratch: whether a node's box changed in the last refit.
    pub(crate) changed: Vec<bool>,
    pub(crate) options: BuildOptions,
    pub(crate) build_cost: f32,
}

impl Bvh {
    /// The nodes; `nodes()[0]` is the root.
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// Primitive indices in leaf order: leaf `l` holds `primitive_order()[l.first..l.first + l.count]`.
    pub fn primitive_order(&self) -> &[u32] {
        &self.order
    }

    /// The primitives of node `node` if it is a leaf, else (or out of range) an empty slice.
    #[inline]
    pub fn leaf_primitives(&self, node: u32) -> &[u32] {
        match self.nodes.get(node as usize) {
            Some(n) if n.is_leaf() => {
                &self.order[n.first as usize..n.first as usize + n.count as usize]
            }
            _ => &[],
        }
    }

    /// The root's box: it contains every primitive.
    pub fn root_aabb(&self) -> Aabb {
        self.nodes[0].aabb
    }

    /// The options the hierarchy was built with.
    pub fn options(&self) -> &BuildOptions {
        &self.options
    }

    /// Number of primitives the hierarchy was built over.
    pub fn primitive_count(&self) -> usize {
        self.order.len()
    }

    /// Number of nodes, inner and leaves.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of leaves (`(node_count() + 1) / 2`).
    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.is_leaf()).count()
    }

    /// Number of nodes at each depth: `level_counts()[0] == 1` (the root), `[1]` its children, …
    /// (The thesis counts levels from 1 at the root: its level `k` is index `k − 1` here.)
    pub fn level_counts(&self) -> Vec<u32> {
        let mut depth = vec![0u32; self.nodes.len()];
        let mut counts = vec![0u32];
        counts[0] = 1;
        for (i, n) in self.nodes.iter().enumerate() {
            if !n.is_leaf() {
                let d = depth[i] + 1;
                depth[n.first as usize] = d;
                depth[n.first as usize + 1] = d;
                if counts.len() <= d as usize {
                    counts.push(0);
                }
                counts[d as usize] += 2;
            }
        }
        counts
    }

    /// Number of levels (1 for a hierarchy that is a single leaf).
    pub fn depth(&self) -> usize {
        self.level_counts().len()
    }

    /// The surface-area cost of the hierarchy, a figure of its query efficiency that grows as
    /// refits stretch the boxes: `Σ_inner A(n)/A(root) + Σ_leaf A(n)/A(root)·count(n)` (the
    /// expected number of box tests plus primitive tests of a random query, with unit costs).
    /// Computed in `O(nodes)`; compare it with [`Bvh::build_cost`] to decide when to rebuild.
    pub fn cost(&self) -> f32 {
        sah_cost(&self.nodes)
    }

    /// [`Bvh::cost`] right after the last build or rebuild.
    pub fn build_cost(&self) -> f32 {
        self.build_cost
    }

    /// Checks every invariant listed on [`Bvh`] against `prims` (the primitives at their current
    /// positions, after a build or a refit).
    ///
    /// # Panics
    /// With a message naming the node or primitive at fault when an invariant does not hold.
    #[allow(
        clippy::panic,
        reason = "a checker for tests, documented to panic naming the defect"
    )]
    pub fn assert_well_formed<P: Primitives + ?Sized>(&self, prims: &P) {
        if let Some(defect) = self.defect(prims) {
            panic!("malformed BVH: {defect}");
        }
    }

    fn defect<P: Primitives + ?Sized>(&self, prims: &P) -> Option<String> {
        let n = self.order.len();
        if prims.primitive_count() != n {
            return Some(format!(
                "built over {n} primitives, checked against {}",
                prims.primitive_count()
            ));
        }
        if self.nodes.is_empty() || self.changed.len() != self.nodes.len() {
            return Some("no nodes, or scratch of the wrong size".into());
        }
        let mut seen = vec![false; n];
        for &p in &self.order {
            match seen.get_mut(p as usize) {
                Some(s) if !*s => *s = true,
                _ => return Some(format!("primitive order repeats or overflows at {p}")),
            }
        }
        // Walk from the root: every node reached exactly once, ranges covering the order once.
        let mut reached = vec![false; self.nodes.len()];
        let mut covered = vec![false; n];
        let mut stack = vec![0usize];
        let mut leaves = 0usize;
        reached[0] = true;
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i];
            if node.is_leaf() {
                leaves += 1;
                if node.count > self.options.leaf_size {
                    return Some(format!(
                        "leaf {i} holds {} primitives, more than the leaf size {}",
                        node.count, self.options.leaf_size
                    ));
                }
                let (a, b) = (
                    node.first as usize,
                    node.first as usize + node.count as usize,
                );
                if b > n {
                    return Some(format!("leaf {i} range {a}..{b} exceeds {n} primitives"));
                }
                for (k, slot) in covered.iter_mut().enumerate().take(b).skip(a) {
                    if *slot {
                        return Some(format!("primitive slot {k} is in two leaves (leaf {i})"));
                    }
                    *slot = true;
                    let p = self.order[k];
                    let pb = prims.bounds(p);
                    if !node.aabb.contains(&pb) {
                        return Some(format!(
                            "leaf {i} box {:?} does not contain primitive {p}'s box {pb:?}",
                            node.aabb
                        ));
                    }
                }
            } else {
                let c = node.first as usize;
                if c <= i || c + 1 >= self.nodes.len() {
                    return Some(format!("inner node {i} has children at {c}, {}", c + 1));
                }
                for child in [c, c + 1] {
                    if reached[child] {
                        return Some(format!("node {child} is reached twice"));
                    }
                    reached[child] = true;
                    if !node.aabb.contains(&self.nodes[child].aabb) {
                        return Some(format!(
                            "node {i} box {:?} does not contain child {child}'s box {:?}",
                            node.aabb, self.nodes[child].aabb
                        ));
                    }
                    stack.push(child);
                }
            }
        }
        if let Some(i) = reached.iter().position(|r| !r) {
            return Some(format!("node {i} is not reachable from the root"));
        }
        if let Some(k) = covered.iter().position(|c| !c) {
            return Some(format!(
                "primitive {} is in no leaf",
                self.order.get(k).copied().unwrap_or(u32::MAX)
            ));
        }
        if self.nodes.len() != 2 * leaves - 1 {
            return Some(format!(
                "{} nodes for {leaves} leaves (expected {})",
                self.nodes.len(),
                2 * leaves - 1
            ));
        }
        None
    }
}

/// See [`Bvh::cost`].
pub(crate) fn sah_cost(nodes: &[BvhNode]) -> f32 {
    let root = f64::from(nodes[0].aabb.surface_area());
    if root.is_nan() || root <= 0.0 {
        return nodes.iter().map(|n| n.count as f32).sum::<f32>().max(1.0);
    }
    let mut sum = 0.0f64;
    for n in nodes {
        let a = f64::from(n.aabb.surface_area());
        sum += if n.is_leaf() {
            a * f64::from(n.count)
        } else {
            a
        };
    }
    (sum / root) as f32
}
