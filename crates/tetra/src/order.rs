//! Insertion order: a biased randomised insertion order (BRIO, Amenta–Choi–Rote) whose rounds
//! are each sorted along a Morton (Z-order) curve.
//!
//! The points are shuffled with a fixed seed and cut into rounds of sizes …, n/8, n/4, n/2 (the
//! last round is the largest); each round is sorted by the 63-bit Morton code of its
//! coordinates quantised to 21 bits per axis over the bounding box. Randomness between rounds
//! keeps cavities small on average; the curve within a round keeps each point close to the
//! previous one, so the point-location walk is short. Deterministic: same input, same order.

use crate::predicates::P3;

/// Spreads the low 21 bits of `x` to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// The indices `0..pts.len()` in BRIO-Morton insertion order.
pub(crate) fn insertion_order(pts: &[P3]) -> Vec<u32> {
    let n = pts.len();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in pts {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let scale = if extent > 0.0 {
        f64::from((1u32 << 21) - 1) / extent
    } else {
        0.0
    };
    let code = |p: &P3| -> u64 {
        let q = [0, 1, 2].map(|k| ((p[k] - lo[k]) * scale) as u64);
        spread(q[0]) | spread(q[1]) << 1 | spread(q[2]) << 2
    };

    // Fixed-seed Fisher–Yates shuffle (SplitMix64).
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    for i in (1..n).rev() {
        let j = (next() % (i as u64 + 1)) as usize;
        order.swap(i, j);
    }
    // Rounds from the end: [.., n/8, n/4, n/2]; the first round takes what is left (≤ 64).
    let mut end = n;
    while end > 0 {
        let start = if end <= 64 { 0 } else { end - end / 2 };
        order[start..end].sort_by_cached_key(|&i| code(&pts[i as usize]));
        end = start;
    }
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_a_permutation_and_deterministic() {
        let pts: Vec<P3> = (0..1000)
            .map(|i| {
                let f = f64::from(i);
                [(f * 0.37).sin(), (f * 0.11).cos(), f * 1e-3]
            })
            .collect();
        let a = insertion_order(&pts);
        let mut s = a.clone();
        s.sort_unstable();
        assert_eq!(s, (0..1000).collect::<Vec<u32>>());
        assert_eq!(a, insertion_order(&pts));
    }

    #[test]
    fn morton_spread_interleaves() {
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread(0x1f_ffff).count_ones(), 21);
    }
}
