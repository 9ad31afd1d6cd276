//! Pairs between two hierarchies (SPEC A.4, broad phase of BVH vs BVH): every pair of leaves, one
//! from each, whose boxes overlap.

use crate::{Bvh, BvhWorkspace};

impl Bvh {
    /// Appends to `out` (after clearing it) every `[leaf of self, leaf of other]` whose boxes
    /// overlap once grown by `gap` ([`crate::Aabb::overlaps`]), each pair once, in a
    /// deterministic depth-first order.
    ///
    /// Simultaneous descent from both roots: a pair of overlapping nodes is replaced by the pairs
    /// of the children of the node with the larger box (of the inner one when the other is a
    /// leaf), so both trees are walked only where they overlap. Uses `ws`' pair stack; does not
    /// allocate once the stack has grown to the trees' depth.
    pub fn leaf_pairs(
        &self,
        other: &Bvh,
        gap: f32,
        ws: &mut BvhWorkspace,
        out: &mut Vec<[u32; 2]>,
    ) {
        out.clear();
        let stack = &mut ws.pairs;
        stack.clear();
        let (na, nb) = (&self.nodes, &other.nodes);
        if !na[0].aabb.overlaps(&nb[0].aabb, gap) {
            return;
        }
        stack.push([0, 0]);
        while let Some([a, b]) = stack.pop() {
            let (x, y) = (&na[a as usize], &nb[b as usize]);
            match (x.is_leaf(), y.is_leaf()) {
                (true, true) => out.push([a, b]),
                (false, leaf_b) => {
                    let descend_a = leaf_b || x.aabb.surface_area() >= y.aabb.surface_area();
                    if descend_a {
                        for c in [x.first + 1, x.first] {
                            if na[c as usize].aabb.overlaps(&y.aabb, gap) {
                                stack.push([c, b]);
                            }
                        }
                    } else {
                        for c in [y.first + 1, y.first] {
                            if x.aabb.overlaps(&nb[c as usize].aabb, gap) {
                                stack.push([a, c]);
                            }
                        }
                    }
                }
                (true, false) => {
                    for c in [y.first + 1, y.first] {
                        if x.aabb.overlaps(&nb[c as usize].aabb, gap) {
                            stack.push([a, c]);
                        }
                    }
                }
            }
        }
    }
}
