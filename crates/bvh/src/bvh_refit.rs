//! Refit after the primitives moved, with the thesis's semantics (SPEC A.3).

use glam::Vec3A;

use crate::{Aabb, Bvh, BvhError, BvhNode, Primitives};

/// What a refit did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefitReport {
    /// Nodes whose box changed (leaves and inner nodes).
    pub nodes_changed: u32,
    /// Leaves whose box changed.
    pub leaves_changed: u32,
    /// [`Bvh::cost`] after the refit (computed in the same pass).
    pub cost: f32,
}

impl Bvh {
    /// Updates the boxes to the primitives' current positions, keeping the tree.
    ///
    /// Thesis semantics: a leaf recomputes the box of its primitives (grown by the margin) and
    /// takes it only if it differs from the stored one; an inner node recomputes only if a child
    /// changed. Leaves are done first, then the inner nodes in reverse index order, which is
    /// children before parents (flat loops instead of the thesis's recursion from the root, same
    /// result). Does not allocate.
    ///
    /// Leaves are recomputed first, in parallel for hierarchies over 16 k primitives or more
    /// (feature `parallel`), each independently, so the result is the same on any number of
    /// threads.
    ///
    /// # Errors
    /// [`BvhError::PrimitiveCount`] if `prims` is not the set the hierarchy was built over;
    /// [`BvhError::NonFiniteBounds`] naming a primitive with a NaN or infinite box (of the leaf
    /// with the smallest node index that has one). After that error the leaf boxes are updated
    /// but the inner ones are not: refit again with finite positions, or rebuild.
    pub fn refit<P: Primitives + Sync + ?Sized>(
        &mut self,
        prims: &P,
    ) -> Result<RefitReport, BvhError> {
        if prims.primitive_count() != self.order.len() {
            return Err(BvhError::PrimitiveCount {
                expected: self.order.len(),
                got: prims.primitive_count(),
            });
        }
        let _span = tracing::trace_span!("bvh_refit", nodes = self.nodes.len()).entered();
        // Leaves first (independent of each other: in parallel for large hierarchies), then the
        // inner nodes in reverse index order, children before parents.
        let (leaves_changed, bad_leaf) = self.refit_leaves(prims);
        if let Some(leaf) = bad_leaf {
            let n = self.nodes[leaf as usize];
            return Err(non_finite(
                prims,
                &self.order[n.first as usize..(n.first + n.count) as usize],
            ));
        }
        let mut nodes_changed = leaves_changed;
        let mut area_sum = 0.0f64;
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            if node.is_leaf() {
                area_sum += f64::from(node.aabb.surface_area()) * f64::from(node.count);
                continue;
            }
            let c = node.first as usize;
            let changed = (self.changed[c] || self.changed[c + 1]) && {
                let b = self.nodes[c].aabb.union(&self.nodes[c + 1].aabb);
                let differs = b != node.aabb;
                self.nodes[i].aabb = b;
                differs
            };
            area_sum += f64::from(self.nodes[i].aabb.surface_area());
            self.changed[i] = changed;
            nodes_changed += u32::from(changed);
        }
        let root = f64::from(self.nodes[0].aabb.surface_area());
        let cost = if root > 0.0 {
            (area_sum / root) as f32
        } else {
            crate::bvh::sah_cost(&self.nodes)
        };
        Ok(RefitReport {
            nodes_changed,
            leaves_changed,
            cost,
        })
    }

    /// Recomputes every leaf; returns the number that changed and the smallest index of a leaf
    /// whose box is not finite.
    fn refit_leaves<P: Primitives + Sync + ?Sized>(&mut self, prims: &P) -> (u32, Option<u32>) {
        let order = &self.order;
        let margin = self.options.margin;
        let chunk = |first: usize, nodes: &mut [BvhNode], changed: &mut [bool]| {
            let mut count = 0u32;
            let mut bad = None;
            for (k, (node, flag)) in nodes.iter_mut().zip(changed.iter_mut()).enumerate() {
                if !node.is_leaf() {
                    continue;
                }
                let mut lo = Vec3A::splat(f32::INFINITY);
                let mut hi = Vec3A::splat(f32::NEG_INFINITY);
                for &p in &order[node.first as usize..(node.first + node.count) as usize] {
                    prims.grow(p, &mut lo, &mut hi);
                }
                let mut b = Aabb::new(lo.into(), hi.into());
                if margin > 0.0 {
                    b = b.expanded(margin);
                }
                if !b.is_finite() && bad.is_none() {
                    bad = Some((first + k) as u32);
                }
                *flag = b != node.aabb;
                if *flag {
                    node.aabb = b;
                    count += 1;
                }
            }
            (count, bad)
        };
        #[cfg(feature = "parallel")]
        if order.len() >= PARALLEL_MIN {
            use rayon::prelude::*;
            return self
                .nodes
                .par_chunks_mut(CHUNK)
                .zip(self.changed.par_chunks_mut(CHUNK))
                .enumerate()
                .map(|(c, (nodes, changed))| chunk(c * CHUNK, nodes, changed))
                .reduce(|| (0, None), |(a, x), (b, y)| (a + b, min_some(x, y)));
        }
        chunk(0, &mut self.nodes, &mut self.changed)
    }
}

/// Hierarchies over at least this many primitives refit their leaves in parallel.
#[cfg(feature = "parallel")]
const PARALLEL_MIN: usize = 16 * 1024;
/// Nodes per parallel refit task.
#[cfg(feature = "parallel")]
const CHUNK: usize = 1024;

#[cfg(feature = "parallel")]
fn min_some(x: Option<u32>, y: Option<u32>) -> Option<u32> {
    match (x, y) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

fn non_finite<P: Primitives + ?Sized>(prims: &P, slots: &[u32]) -> BvhError {
    let p = slots
        .iter()
        .copied()
        .find(|&p| !prims.bounds(p).is_finite())
        .unwrap_or(slots[0]);
    let b = prims.bounds(p);
    BvhError::NonFiniteBounds {
        primitive: p,
        min: b.min.to_array(),
        max: b.max.to_array(),
    }
}
