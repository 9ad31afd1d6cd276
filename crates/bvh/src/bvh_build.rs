//! Top-down build: the thesis's equal-area split (SPEC A.3) or a binned SAH split.
//!
//! Nodes are numbered depth first: a node's two children are pushed together (adjacent), the left
//! subtree is built before the right, so every child index is larger than its parent's. Leaf boxes
//! are set when a leaf is made, inner boxes in one reverse pass (children before parents).
//!
//! With the `parallel` feature, a node of at least 16 k primitives is split on the calling thread
//! and its two halves are built on rayon's threads, each into its own node array, then spliced
//! into the serial depth-first numbering; the splits themselves are the same. So the build is
//! deterministic and the same on any number of threads: the same primitives give the same
//! hierarchy, bit for bit (a test compares 1 and 2 threads).

use glam::Vec3A;

use crate::bvh::sah_cost;
use crate::{Aabb, BuildOptions, Bvh, BvhError, BvhNode, Primitives, Split};

/// The largest number of primitives a hierarchy holds: `2n − 1` nodes must fit `u32` indices.
pub const MAX_PRIMITIVES: usize = (u32::MAX / 2) as usize;

/// Bins per axis of the equal-area split's ordering pass (the cut itself is exact, see
/// [`Split::EqualArea`]).
const AREA_BINS: usize = 64;
/// Bins per axis of the SAH split.
const SAH_BINS: usize = 16;

/// Scratch space of a build, kept by callers that rebuild during a run so that a rebuild reuses
/// its buffers (a parallel build of a large hierarchy still allocates its subtrees' node arrays).
#[derive(Debug, Clone, Default)]
pub struct BuildWorkspace {
    boxes: Vec<Aabb>,
    items: Vec<Item>,
    stack: Vec<Task>,
}

impl BuildWorkspace {
    /// An empty workspace; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }
}

/// A primitive as the split sees it, kept in a compact array that is partitioned in place (the
/// build reads it sequentially instead of through the index permutation).
#[derive(Debug, Clone, Copy)]
struct Item {
    centroid: [f32; 3],
    weight: f32,
    index: u32,
}

/// A node still to be built: its item range, the box of its centroids and its summed weight.
#[derive(Debug, Clone, Copy)]
struct Task {
    node: u32,
    start: u32,
    end: u32,
    summary: Summary,
}

#[derive(Debug, Clone, Copy)]
struct Summary {
    lo: Vec3A,
    hi: Vec3A,
    weight: f64,
}

impl Summary {
    const EMPTY: Summary = Summary {
        lo: Vec3A::splat(f32::INFINITY),
        hi: Vec3A::splat(f32::NEG_INFINITY),
        weight: 0.0,
    };

    #[inline]
    fn add(&mut self, it: &Item) {
        let c = Vec3A::from_array(it.centroid);
        self.lo = self.lo.min(c);
        self.hi = self.hi.max(c);
        self.weight += f64::from(it.weight);
    }
}

fn summarize(items: &[Item]) -> Summary {
    let mut s = Summary::EMPTY;
    for it in items {
        s.add(it);
    }
    s
}

impl Bvh {
    /// Builds a hierarchy over `prims`.
    ///
    /// # Errors
    /// [`BvhError::Empty`], [`BvhError::TooManyPrimitives`], [`BvhError::InvalidLeafSize`],
    /// [`BvhError::InvalidMargin`], or [`BvhError::NonFiniteBounds`] naming the first primitive
    /// with a NaN or infinite box.
    pub fn build<P: Primitives + ?Sized>(
        prims: &P,
        options: &BuildOptions,
    ) -> Result<Bvh, BvhError> {
        Self::build_with(prims, options, &mut BuildWorkspace::new())
    }

    /// [`Bvh::build`] with the caller's scratch space.
    ///
    /// # Errors
    /// As [`Bvh::build`].
    pub fn build_with<P: Primitives + ?Sized>(
        prims: &P,
        options: &BuildOptions,
        ws: &mut BuildWorkspace,
    ) -> Result<Bvh, BvhError> {
        validate(options, prims.primitive_count())?;
        let mut bvh = Bvh {
            nodes: Vec::new(),
            order: Vec::new(),
            changed: Vec::new(),
            options: *options,
            build_cost: 0.0,
        };
        gather(prims, ws)?;
        build_from_gathered(&mut bvh, ws);
        Ok(bvh)
    }

    /// Builds again over `prims` (same count as before) with the same options, reusing this
    /// hierarchy's arrays and `ws`: the caller's remedy when [`Bvh::cost`] has grown too far
    /// above [`Bvh::build_cost`] after many refits.
    ///
    /// # Errors
    /// [`BvhError::PrimitiveCount`] when the count differs, [`BvhError::NonFiniteBounds`] as in
    /// [`Bvh::build`]. On error the hierarchy is left unchanged.
    pub fn rebuild<P: Primitives + ?Sized>(
        &mut self,
        prims: &P,
        ws: &mut BuildWorkspace,
    ) -> Result<(), BvhError> {
        if prims.primitive_count() != self.order.len() {
            return Err(BvhError::PrimitiveCount {
                expected: self.order.len(),
                got: prims.primitive_count(),
            });
        }
        gather(prims, ws)?;
        build_from_gathered(self, ws);
        Ok(())
    }
}

fn validate(options: &BuildOptions, count: usize) -> Result<(), BvhError> {
    if count == 0 {
        return Err(BvhError::Empty);
    }
    if count > MAX_PRIMITIVES {
        return Err(BvhError::TooManyPrimitives {
            count,
            max: MAX_PRIMITIVES,
        });
    }
    if options.leaf_size == 0 {
        return Err(BvhError::InvalidLeafSize {
            leaf_size: options.leaf_size,
        });
    }
    if !(options.margin.is_finite() && options.margin >= 0.0) {
        return Err(BvhError::InvalidMargin {
            margin: options.margin,
        });
    }
    Ok(())
}

/// Reads every primitive's box, centroid and weight once.
fn gather<P: Primitives + ?Sized>(prims: &P, ws: &mut BuildWorkspace) -> Result<(), BvhError> {
    let n = prims.primitive_count();
    ws.boxes.clear();
    ws.items.clear();
    for i in 0..n as u32 {
        let (b, c, w) = prims.build_data(i);
        if !b.is_finite() {
            return Err(BvhError::NonFiniteBounds {
                primitive: i,
                min: b.min.to_array(),
                max: b.max.to_array(),
            });
        }
        ws.boxes.push(b);
        ws.items.push(Item {
            centroid: c.to_array(),
            weight: if w.is_finite() && w > 0.0 { w } else { 0.0 },
            index: i,
        });
    }
    Ok(())
}

/// What every subtree build reads.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    boxes: &'a [Aabb],
    leaf_size: u32,
    split: Split,
    margin: f32,
}

impl Ctx<'_> {
    fn split(&self, range: &mut [Item], summary: &Summary) -> (usize, Summary, Summary) {
        match self.split {
            Split::EqualArea => split_equal_area(range, summary),
            Split::Sah => split_sah(range, summary, self.boxes),
        }
    }

    fn leaf_box(&self, items: &[Item]) -> Aabb {
        let mut b = Aabb::EMPTY;
        for it in items {
            b = b.union(&self.boxes[it.index as usize]);
        }
        if self.margin > 0.0 {
            b.expanded(self.margin)
        } else {
            b
        }
    }
}

fn build_from_gathered(bvh: &mut Bvh, ws: &mut BuildWorkspace) {
    let _span = tracing::debug_span!(
        "bvh_build",
        primitives = ws.items.len(),
        leaf_size = bvh.options.leaf_size,
        split = ?bvh.options.split
    )
    .entered();
    let ctx = Ctx {
        boxes: &ws.boxes,
        leaf_size: bvh.options.leaf_size,
        split: bvh.options.split,
        margin: bvh.options.margin,
    };
    let summary = summarize(&ws.items);
    let nodes = &mut bvh.nodes;
    nodes.clear();
    if ws.items.len() >= PARALLEL_MIN {
        *nodes = build_parallel(ctx, &mut ws.items, 0, summary);
    } else {
        build_serial(ctx, &mut ws.items, 0, summary, &mut ws.stack, nodes);
    }
    bvh.order.clear();
    bvh.order.extend(ws.items.iter().map(|it| it.index));
    bvh.changed.clear();
    bvh.changed.resize(nodes.len(), false);
    bvh.build_cost = sah_cost(nodes);
}

/// Subtrees of at least this many primitives are split on the calling thread and their two
/// halves built in parallel (rayon); smaller ones are built serially.
const PARALLEL_MIN: usize = 16 * 1024;

/// The subtree over `items` (whose first item has global offset `base`) as `[root, desc(root)]`,
/// boxes filled, where `desc(x) = [left(x), right(x)] ++ desc(left(x)) ++ desc(right(x))` (empty
/// for a leaf): the layout the serial depth-first builder produces. Halves of at least
/// [`PARALLEL_MIN`] primitives are built in parallel and spliced into that same layout, so the
/// result does not depend on the number of threads.
fn build_parallel(ctx: Ctx<'_>, items: &mut [Item], base: u32, summary: Summary) -> Vec<BvhNode> {
    if items.len() < PARALLEL_MIN {
        let mut nodes = Vec::new();
        build_serial(ctx, items, base, summary, &mut Vec::new(), &mut nodes);
        return nodes;
    }
    let (cut, ls, rs) = ctx.split(items, &summary);
    let (left_items, right_items) = items.split_at_mut(cut);
    let (l, r) = join(
        || build_parallel(ctx, left_items, base, ls),
        || build_parallel(ctx, right_items, base + cut as u32, rs),
    );
    // [root, l[0], r[0], l[1..], r[1..]]: shift the child indices of the inner nodes.
    let mut nodes = Vec::with_capacity(1 + l.len() + r.len());
    let shift = |n: BvhNode, by: u32| {
        if n.is_leaf() {
            n
        } else {
            BvhNode {
                first: n.first + by,
                ..n
            }
        }
    };
    let (l_by, r_by) = (2, l.len() as u32 + 1);
    nodes.push(BvhNode {
        aabb: l[0].aabb.union(&r[0].aabb),
        first: 1,
        count: 0,
    });
    nodes.push(shift(l[0], l_by));
    nodes.push(shift(r[0], r_by));
    nodes.extend(l[1..].iter().map(|&n| shift(n, l_by)));
    nodes.extend(r[1..].iter().map(|&n| shift(n, r_by)));
    nodes
}

#[cfg(feature = "parallel")]
fn join<A: Send, B: Send>(a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B + Send) -> (A, B) {
    rayon::join(a, b)
}

#[cfg(not(feature = "parallel"))]
fn join<A, B>(a: impl FnOnce() -> A, b: impl FnOnce() -> B) -> (A, B) {
    (a(), b())
}

/// Depth-first build of the subtree over `items` into `nodes` (cleared) as `[root, desc(root)]`;
/// leaf offsets are global (`base` + local).
fn build_serial(
    ctx: Ctx<'_>,
    items: &mut [Item],
    base: u32,
    summary: Summary,
    stack: &mut Vec<Task>,
    nodes: &mut Vec<BvhNode>,
) {
    let n = items.len() as u32;
    nodes.clear();
    nodes.reserve(2 * (n as usize).div_ceil(ctx.leaf_size as usize));
    nodes.push(BvhNode {
        aabb: Aabb::EMPTY,
        first: 0,
        count: n,
    });
    stack.clear();
    stack.push(Task {
        node: 0,
        start: 0,
        end: n,
        summary,
    });
    while let Some(Task {
        node,
        start,
        end,
        summary,
    }) = stack.pop()
    {
        let count = end - start;
        let range = &mut items[start as usize..end as usize];
        if count <= ctx.leaf_size {
            nodes[node as usize] = BvhNode {
                aabb: ctx.leaf_box(range),
                first: base + start,
                count,
            };
            continue;
        }
        let (cut, left_summary, right_summary) = ctx.split(range, &summary);
        let mid = start + cut as u32;
        let left = nodes.len() as u32;
        let placeholder = BvhNode {
            aabb: Aabb::EMPTY,
            first: 0,
            count: 0,
        };
        nodes.push(placeholder);
        nodes.push(placeholder);
        nodes[node as usize].first = left;
        nodes[node as usize].count = 0;
        stack.push(Task {
            node: left + 1,
            start: mid,
            end,
            summary: right_summary,
        });
        stack.push(Task {
            node: left,
            start,
            end: mid,
            summary: left_summary,
        });
    }
    // Inner boxes, children before parents (leaf boxes were set when the leaves were made).
    for i in (0..nodes.len()).rev() {
        let node = nodes[i];
        if !node.is_leaf() {
            let c = node.first as usize;
            nodes[i].aabb = nodes[c].aabb.union(&nodes[c + 1].aabb);
        }
    }
}

/// The thesis's split of `range` (≥ 2 items): returns the size `k` of the left child,
/// `1 ≤ k < range.len()`, with `range[..k]` reordered to be the left child, and both children's
/// summaries.
///
/// Definition: sort the primitives by (centroid on the longest axis of the centroid box,
/// primitive index) and cut where the prefix weight is closest to half the total (ties: the
/// smaller `k`). If every weight is 0 the counts are balanced instead; if all centroids coincide
/// the order is by index.
///
/// Implementation, `O(n)` plus a sort of one bin: the centroids are binned on that axis (the bin
/// of a coordinate is monotone in it, so bins respect the order), the bin where the prefix weight
/// crosses half is found, the range is partitioned into (before, that bin, after), and only that
/// bin is sorted to place the cut exactly.
fn split_equal_area(range: &mut [Item], summary: &Summary) -> (usize, Summary, Summary) {
    let n = range.len();
    let ext = summary.hi - summary.lo;
    let axis = longest_axis(ext);
    let unit = summary.weight.is_nan() || summary.weight <= 0.0;
    let total = if unit { n as f64 } else { summary.weight };
    let weight = |it: &Item| if unit { 1.0 } else { f64::from(it.weight) };
    let half = total * 0.5;
    let extent = ext[axis];
    if extent.is_nan() || extent <= 0.0 {
        range.sort_unstable_by_key(|it| it.index);
        let cut = exact_cut(range, 0, n, 0.0, half, weight);
        return (cut, summarize(&range[..cut]), summarize(&range[cut..]));
    }
    let lo = summary.lo[axis];
    let scale = AREA_BINS as f32 / extent;
    let bin_of =
        |it: &Item| -> usize { (((it.centroid[axis] - lo) * scale) as usize).min(AREA_BINS - 1) };
    // Four interleaved accumulators: neighbouring items usually share a bin, and one array
    // would chain every add through the same memory slot.
    let mut bin_weight = [[0.0f64; AREA_BINS]; 4];
    for (k, it) in range.iter().enumerate() {
        bin_weight[k & 3][bin_of(it)] += weight(it);
    }
    let mut before = 0.0f64;
    let mut crossing = AREA_BINS - 1;
    let [w0, w1, w2, w3] = &bin_weight;
    for b in 0..AREA_BINS {
        let w = (w0[b] + w1[b]) + (w2[b] + w3[b]);
        if before + w >= half {
            crossing = b;
            break;
        }
        before += w;
    }
    // Three-way partition [bin < crossing | bin == crossing | bin > crossing] as two branch-free
    // two-way passes (the bins of neighbouring items are not predictable along a new axis).
    let lt = partition(range, |it| bin_of(it) < crossing);
    let gt = lt + partition(&mut range[lt..], |it| bin_of(it) == crossing);
    let mut left = summarize(&range[..lt]);
    let mut right = summarize(&range[gt..]);
    range[lt..gt].sort_unstable_by(|x, y| {
        x.centroid[axis]
            .total_cmp(&y.centroid[axis])
            .then(x.index.cmp(&y.index))
    });
    let cut = exact_cut(range, lt, gt, before, half, weight);
    if cut < lt || cut > gt {
        // Only if the crossing bin were empty (it holds the item that crosses half).
        return (cut, summarize(&range[..cut]), summarize(&range[cut..]));
    }
    for it in &range[lt..cut] {
        left.add(it);
    }
    for it in &range[cut..gt] {
        right.add(it);
    }
    (cut, left, right)
}

/// Moves the items for which `pred` holds to the front (order within each side unspecified but
/// deterministic) and returns their number. Branch-free Lomuto: every item is written once.
#[inline]
fn partition(range: &mut [Item], pred: impl Fn(&Item) -> bool) -> usize {
    let mut k = 0;
    for i in 0..range.len() {
        let it = range[i];
        let take = pred(&it);
        range[i] = range[k];
        range[k] = it;
        k += usize::from(take);
    }
    k
}

/// Within the sorted run `range[lo..hi]`, preceded by weight `before`, the cut position `k ∈
/// [lo, hi]` whose prefix weight is closest to `half`, clamped to `1..n`.
fn exact_cut(
    range: &[Item],
    lo: usize,
    hi: usize,
    before: f64,
    half: f64,
    weight: impl Fn(&Item) -> f64,
) -> usize {
    let mut prefix = before;
    let mut best = lo;
    let mut best_err = (prefix - half).abs();
    for (k, it) in range.iter().enumerate().take(hi).skip(lo) {
        prefix += weight(it);
        let err = (prefix - half).abs();
        if err < best_err {
            best_err = err;
            best = k + 1;
        }
        if prefix >= half {
            break;
        }
    }
    best.clamp(1, range.len() - 1)
}

fn longest_axis(ext: Vec3A) -> usize {
    if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    }
}

/// Binned SAH split of `range` (≥ 2 items); returns the left size, `1 ≤ k < n`, and both
/// children's summaries.
fn split_sah(range: &mut [Item], summary: &Summary, boxes: &[Aabb]) -> (usize, Summary, Summary) {
    let n = range.len();
    let (lo, ext) = (summary.lo, summary.hi - summary.lo);
    let bin = |it: &Item, axis: usize, scale: f32| {
        (((it.centroid[axis] - lo[axis]) * scale) as usize).min(SAH_BINS - 1)
    };
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bins on the left)
    for axis in 0..3 {
        if ext[axis].is_nan() || ext[axis] <= 0.0 {
            continue;
        }
        let scale = SAH_BINS as f32 / ext[axis];
        let mut bin_box = [Aabb::EMPTY; SAH_BINS];
        let mut bin_count = [0u32; SAH_BINS];
        for it in range.iter() {
            let b = bin(it, axis, scale);
            bin_box[b] = bin_box[b].union(&boxes[it.index as usize]);
            bin_count[b] += 1;
        }
        // Areas of the right sides, then a sweep from the left.
        let mut right_area = [0.0f32; SAH_BINS];
        let mut acc = Aabb::EMPTY;
        for b in (1..SAH_BINS).rev() {
            acc = acc.union(&bin_box[b]);
            right_area[b] = acc.surface_area();
        }
        let mut left = Aabb::EMPTY;
        let mut left_count = 0u32;
        for b in 1..SAH_BINS {
            left = left.union(&bin_box[b - 1]);
            left_count += bin_count[b - 1];
            let right_count = n as u32 - left_count;
            if left_count == 0 || right_count == 0 {
                continue;
            }
            let cost = left.surface_area() * left_count as f32 + right_area[b] * right_count as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    let cut = match best {
        None => {
            range.sort_unstable_by_key(|it| it.index);
            n / 2
        }
        Some((_, axis, split_bin)) => {
            let scale = SAH_BINS as f32 / ext[axis];
            let mut k = 0;
            for i in 0..n {
                if bin(&range[i], axis, scale) < split_bin {
                    range.swap(k, i);
                    k += 1;
                }
            }
            k.clamp(1, n - 1)
        }
    };
    (cut, summarize(&range[..cut]), summarize(&range[cut..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn items_on_a_line(weights: &[f32]) -> Vec<Item> {
        weights
            .iter()
            .enumerate()
            .map(|(i, &w)| Item {
                centroid: [i as f32, 0.25, 0.25],
                weight: w,
                index: i as u32,
            })
            .collect()
    }

    #[test]
    fn equal_weights_split_in_half_along_the_long_axis() {
        let mut items = items_on_a_line(&[1.0; 10]);
        items.reverse();
        let s = summarize(&items);
        let (k, left, right) = split_equal_area(&mut items, &s);
        assert_eq!(k, 5);
        let mut l: Vec<u32> = items[..5].iter().map(|it| it.index).collect();
        l.sort_unstable();
        assert_eq!(l, vec![0, 1, 2, 3, 4]);
        assert_eq!((left.weight, right.weight), (5.0, 5.0));
        assert_eq!((left.hi.x, right.lo.x), (4.0, 5.0));
    }

    #[test]
    fn heavy_primitive_moves_the_cut() {
        let mut w = [1.0; 10];
        w[9] = 9.0; // total 18, half 9: left = 0..=8
        let mut items = items_on_a_line(&w);
        let s = summarize(&items);
        let (k, _, _) = split_equal_area(&mut items, &s);
        assert_eq!(k, 9);
        assert_eq!(items[9].index, 9);
    }

    #[test]
    fn coincident_centroids_split_by_index() {
        let mut items: Vec<Item> = [5u32, 3, 1, 0, 2, 4]
            .iter()
            .map(|&i| Item {
                centroid: [1.0; 3],
                weight: 1.0,
                index: i,
            })
            .collect();
        let s = summarize(&items);
        let (k, _, _) = split_equal_area(&mut items, &s);
        assert_eq!(k, 3);
        let left: Vec<u32> = items[..3].iter().map(|it| it.index).collect();
        assert_eq!(left, vec![0, 1, 2]);
    }

    #[test]
    fn sah_separates_two_clusters() {
        use glam::Vec3;
        let xs = [0.0f32, 1.0, 2.0, 3.0, 100.0, 101.0, 102.0, 103.0];
        let boxes: Vec<Aabb> = xs
            .iter()
            .map(|&x| Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 0.5, 0.5, 0.5)))
            .collect();
        let mut items: Vec<Item> = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| Item {
                centroid: b.center().to_array(),
                weight: 1.0,
                index: i as u32,
            })
            .collect();
        let s = summarize(&items);
        let (k, _, _) = split_sah(&mut items, &s, &boxes);
        assert_eq!(k, 4);
        assert!(items[..4].iter().all(|it| it.index < 4));
    }
}
