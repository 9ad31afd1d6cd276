//! Domain decomposition: nodes renumbered by recursive coordinate bisection, and a binary tree of
//! blocks over the renumbered nodes, fixed by the mesh alone (never by the thread count).
//!
//! Block `h` (heap numbering: root 0, children `2h+1`, `2h+2`) owns the contiguous node range
//! [`Tree::range`]; its children split that range at its middle. A constraint belongs to the
//! deepest block whose range holds all its nodes, so the constraints of two blocks that are not
//! ancestor and descendant touch disjoint node ranges: sibling subtrees can be projected at the
//! same time on disjoint `&mut` slices, and a block's own constraints (those crossing the cut
//! between its children) come after both children.
//!
//! **Spare slots.** The tree is laid over *solver slots*, not over the nodes themselves: every
//! leaf owns [`Tree::leaf_slots`] slots, twice the most real nodes of any leaf
//! ([`spare_tree`]). The real nodes of leaf `k` (the `k`-th chunk of the bisection order, at
//! most [`LEAF_NODES`]) take the first slots of its range, the rest are spares for nodes that
//! cutting adds near them (`edit.rs`): a copy of a node takes a spare of its source's leaf, so
//! the constraints an edit adds on it still fall into the tree and are projected in parallel.
//! A spare slot that holds no node is never touched by a step (no constraint names it, the
//! step's per-node loops skip it). As every leaf has the same number of slots, the halving of
//! [`Tree::range`] is exact and leaf `k` is `[k·slots, (k+1)·slots)`; the tree's constraints
//! and their blocks are those of the tree over the nodes alone (the slots keep the bisection
//! order).

use glam::Vec3;

/// Nodes per leaf block at most: 20 KiB of positions, so a leaf's sweep runs in L1. Larger
/// leaves mean fewer, fuller colours, smaller ones more blocks for more threads.
pub(crate) const LEAF_NODES: usize = 1280;

/// The solver slots of `n` nodes: the tree of [`Tree::for_nodes`] over the nodes, each leaf
/// given as many spare slots as its most real nodes, and the slot of each position of the
/// bisection order (the `j`-th node of leaf `k` takes slot `k·slots + j`). `None` when the slots
/// would not fit below `u32::MAX`.
pub(crate) fn spare_tree(n: usize) -> Option<(Tree, Vec<u32>)> {
    let real = Tree::for_nodes(n);
    let leaves = 1usize << real.depth;
    let slots = 2 * n.div_ceil(leaves);
    let total = slots.checked_mul(leaves)?;
    if total >= u32::MAX as usize {
        return None;
    }
    let tree = Tree {
        node_count: total,
        depth: real.depth,
    };
    let mut slot = Vec::with_capacity(n);
    for k in 0..leaves {
        let [start, _, end] = real.range(leaves - 1 + k);
        slot.extend((0..end - start).map(|j| (k * slots + j) as u32));
    }
    Some((tree, slot))
}

/// Solver order of the nodes: recursive coordinate bisection of `positions` (split at the median
/// along the longest side of the bounding box, halves as [`Tree::range`] makes them), down to
/// single nodes, so that nodes close in the order are close in space. Returns `order` (solver
/// index → caller's index).
pub(crate) fn bisection_order(positions: &[Vec3]) -> Vec<u32> {
    let mut order: Vec<u32> = (0..positions.len() as u32).collect();
    bisect(&mut order, positions);
    order
}

fn bisect(ids: &mut [u32], positions: &[Vec3]) {
    if ids.len() <= 2 {
        return;
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &i in ids.iter() {
        lo = lo.min(positions[i as usize]);
        hi = hi.max(positions[i as usize]);
    }
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = ids.len() / 2;
    // Ties broken by index: the order is a function of the positions alone.
    ids.select_nth_unstable_by(mid, |&a, &b| {
        positions[a as usize][axis]
            .total_cmp(&positions[b as usize][axis])
            .then(a.cmp(&b))
    });
    let (left, right) = ids.split_at_mut(mid);
    bisect(left, positions);
    bisect(right, positions);
}

/// The block tree over `node_count` renumbered nodes (or solver slots, see [`spare_tree`]):
/// `depth` levels below the root, `2^depth` leaves.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Tree {
    pub node_count: usize,
    pub depth: u32,
}

impl Tree {
    /// The shallowest tree whose leaves have at most [`LEAF_NODES`] nodes.
    pub(crate) fn for_nodes(node_count: usize) -> Self {
        let mut depth = 0;
        while node_count.div_ceil(1 << depth) > LEAF_NODES {
            depth += 1;
        }
        Self { node_count, depth }
    }

    /// Slots per leaf: `node_count / 2^depth` (exact in a tree of [`spare_tree`]).
    pub(crate) fn leaf_slots(&self) -> usize {
        self.node_count >> self.depth
    }

    /// Heap index of the leaf holding slot `s` (`s < node_count`, a tree of [`spare_tree`]).
    pub(crate) fn leaf_of(&self, s: usize) -> usize {
        (1 << self.depth) - 1 + s / self.leaf_slots()
    }

    /// Number of blocks, `2^(depth+1) − 1`.
    pub(crate) fn block_count(&self) -> usize {
        (2 << self.depth) - 1
    }

    /// Whether block `h` is a leaf.
    pub(crate) fn is_leaf(&self, h: usize) -> bool {
        h >= (1 << self.depth) - 1
    }

    /// The node range `[start, mid, end)` of block `h`; its children own `[start, mid)` and
    /// `[mid, end)`.
    pub(crate) fn range(&self, h: usize) -> [usize; 3] {
        // The path from the root: the bits of h + 1 below its leading one.
        let level = (h + 1).ilog2();
        let (mut start, mut end) = (0, self.node_count);
        for bit in (0..level).rev() {
            let mid = start + (end - start) / 2;
            if (h + 1) >> bit & 1 == 0 {
                end = mid;
            } else {
                start = mid;
            }
        }
        [start, start + (end - start) / 2, end]
    }

    /// The deepest block whose range holds all of `nodes` (solver indices).
    pub(crate) fn block_of(&self, nodes: &[u32]) -> usize {
        let (mut h, mut start, mut end) = (0, 0, self.node_count);
        for _ in 0..self.depth {
            let mid = start + (end - start) / 2;
            if nodes.iter().all(|&i| (i as usize) < mid) {
                (h, end) = (2 * h + 1, mid);
            } else if nodes.iter().all(|&i| (i as usize) >= mid) {
                (h, start) = (2 * h + 2, mid);
            } else {
                break;
            }
        }
        h
    }

    /// The blocks in projection order: post-order (left subtree, right subtree, the block).
    pub(crate) fn post_order(&self) -> Vec<usize> {
        fn visit(tree: &Tree, h: usize, out: &mut Vec<usize>) {
            if !tree.is_leaf(h) {
                visit(tree, 2 * h + 1, out);
                visit(tree, 2 * h + 2, out);
            }
            out.push(h);
        }
        let mut out = Vec::with_capacity(self.block_count());
        visit(self, 0, &mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_nest_and_constraints_land_in_the_deepest_common_block() {
        let tree = Tree {
            node_count: 1001,
            depth: 3,
        };
        assert_eq!(tree.block_count(), 15);
        assert_eq!(tree.range(0), [0, 500, 1001]);
        for h in 0..7 {
            let [s, m, e] = tree.range(h);
            assert_eq!(tree.range(2 * h + 1)[0], s);
            assert_eq!(tree.range(2 * h + 1)[2], m);
            assert_eq!(tree.range(2 * h + 2)[0], m);
            assert_eq!(tree.range(2 * h + 2)[2], e);
        }
        assert_eq!(tree.block_of(&[0, 499]), 1);
        assert_eq!(tree.block_of(&[499, 500]), 0);
        assert_eq!(tree.block_of(&[1000]), 14);
        let order = tree.post_order();
        assert_eq!(order.len(), 15);
        assert_eq!(*order.last().unwrap_or(&99), 0);
        assert_eq!(order[0], 7);
        assert_eq!(Tree::for_nodes(LEAF_NODES).depth, 0);
        assert_eq!(Tree::for_nodes(LEAF_NODES + 1).depth, 1);
        assert_eq!(Tree::for_nodes(8 * LEAF_NODES + 1).depth, 4);
    }

    #[test]
    fn spare_slots_keep_each_leaf_of_the_bisection_order_together() {
        for n in [
            1,
            7,
            1000,
            LEAF_NODES,
            LEAF_NODES + 1,
            9261,
            8 * LEAF_NODES + 3,
        ] {
            let real = Tree::for_nodes(n);
            let (tree, slot) = spare_tree(n).unwrap_or_default();
            assert_eq!(slot.len(), n);
            assert_eq!(tree.depth, real.depth);
            let leaves = 1 << tree.depth;
            let per = tree.leaf_slots();
            assert_eq!(per * leaves, tree.node_count);
            for k in 0..leaves {
                let h = leaves - 1 + k;
                let [s, _, e] = real.range(h);
                let [ps, _, pe] = tree.range(h);
                assert_eq!((ps, pe), (k * per, (k + 1) * per));
                // Real nodes first, then at least as many spares.
                for (j, &sj) in slot[s..e].iter().enumerate() {
                    assert_eq!(sj as usize, ps + j);
                    assert_eq!(tree.leaf_of(sj as usize), h);
                }
                assert!(2 * (e - s) <= pe - ps);
            }
            // Monotone: the constraints' order and blocks are those of the unpadded tree.
            assert!(slot.windows(2).all(|w| w[0] < w[1]));
        }
        assert!(spare_tree(u32::MAX as usize / 2 + 1).is_none());
    }

    #[test]
    fn bisection_order_is_a_permutation() {
        let p: Vec<Vec3> = (0..100)
            .map(|i| Vec3::new((i * 37 % 100) as f32, (i % 7) as f32, 0.0))
            .collect();
        let mut order = bisection_order(&p);
        order.sort_unstable();
        assert!(order.iter().enumerate().all(|(i, &o)| i as u32 == o));
    }
}
