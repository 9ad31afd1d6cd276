//! How springs and anchors are ordered so that forces can be summed block by block, in parallel,
//! with the same result for any number of threads.
//!
//! Particles are cut into contiguous blocks whose length depends only on the particle count.
//! A spring with both ends in block `b` is *internal* to `b`; one with ends in blocks `b` and
//! `b + 1` belongs to *pair* `b`; the rest are *far*. Springs are stored in that order: internal by
//! block, then by pair, then far (each group sorted by lower end, for a sequential sweep over
//! positions). The force phase runs in four passes, each over disjoint slices of the force array:
//! (1) every block adds its internal springs; (2) the even pairs (blocks 0–1, 2–3, …) add theirs;
//! (3) the odd pairs (blocks 1–2, 3–4, …); (4) the far springs, serially. Passes 1–3 run their
//! slices in parallel. Every particle's forces are therefore added in one fixed order: the serial
//! path runs the same passes one slice after another and is bit-identical.
//!
//! With particles numbered so that neighbours are close (a grid row by row, the two layers of a
//! region interleaved), almost every spring is internal.

use crate::spring::Spring;

/// At most this many blocks: enough for load balance on a few cores, few enough that crossing
/// springs (which run serially) stay a small share.
pub(crate) const MAX_BLOCKS: usize = 16;
/// At least this many particles per block, so small systems stay in one block (serial) where a
/// thread hand-off would cost more than the work.
pub(crate) const MIN_BLOCK_LEN: usize = 2048;

/// A zero-length spring to a fixed point, as the force loop reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AnchorRecord {
    pub particle: u32,
    pub k: f32,
    pub target: glam::Vec3A,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Layout {
    /// Particles per block (the last block may be shorter).
    pub block_len: usize,
    /// Number of blocks (≥ 1).
    pub count: usize,
    /// Group `g`'s springs are `springs[spring_start[g]..spring_start[g + 1]]`: groups
    /// `0..count` are the blocks' internal springs, `count..2·count − 1` the pairs
    /// (`count + b` joins blocks `b` and `b + 1`), and group `2·count − 1` the far springs, which
    /// end at `springs.len()` (`spring_start` has `2·count + 1` entries).
    pub spring_start: Vec<usize>,
    /// `anchors[anchor_start[b]..anchor_start[b + 1]]` act on block `b`.
    pub anchor_start: Vec<usize>,
}

impl Layout {
    pub(crate) fn block_len_for(n: usize) -> usize {
        MIN_BLOCK_LEN.max(n.div_ceil(MAX_BLOCKS))
    }

    /// Sorts `springs` and `anchors` in place into block order and records the block ranges.
    pub(crate) fn arrange(
        n: usize,
        springs: &mut [Spring],
        anchors: &mut [AnchorRecord],
    ) -> Layout {
        let block_len = Self::block_len_for(n);
        let count = n.div_ceil(block_len).max(1);
        let group = |s: &Spring| {
            let (ba, bb) = (s.a as usize / block_len, s.b as usize / block_len);
            let (lo, hi) = (ba.min(bb), ba.max(bb));
            if lo == hi {
                lo
            } else if hi == lo + 1 {
                count + lo
            } else {
                2 * count - 1
            }
        };
        for s in springs.iter_mut() {
            if s.a > s.b {
                // The same spring: the force on each end only changes sign with the direction.
                std::mem::swap(&mut s.a, &mut s.b);
            }
        }
        springs.sort_by_key(|s| (group(s), s.a, s.b));
        let mut spring_start = Vec::with_capacity(2 * count + 1);
        for g in 0..2 * count {
            spring_start.push(springs.partition_point(|s| group(s) < g));
        }
        spring_start.push(springs.len());
        anchors.sort_by_key(|a| a.particle);
        let mut anchor_start = Vec::with_capacity(count + 1);
        for b in 0..=count {
            anchor_start.push(anchors.partition_point(|a| (a.particle as usize) < b * block_len));
        }
        Layout {
            block_len,
            count,
            spring_start,
            anchor_start,
        }
    }

    /// Internal springs of block `b`.
    pub(crate) fn internal(&self, b: usize) -> std::ops::Range<usize> {
        self.spring_start[b]..self.spring_start[b + 1]
    }

    /// Springs joining blocks `b` and `b + 1` (`b + 1 < count`).
    pub(crate) fn pair(&self, b: usize) -> std::ops::Range<usize> {
        self.spring_start[self.count + b]..self.spring_start[self.count + b + 1]
    }

    /// Springs whose blocks are not neighbours (summed serially).
    pub(crate) fn far(&self) -> std::ops::Range<usize> {
        self.spring_start[2 * self.count - 1]..self.spring_start[2 * self.count]
    }

    /// Number of springs that cross blocks.
    pub(crate) fn crossing(&self, springs: usize) -> usize {
        springs - self.spring_start[self.count]
    }
}
