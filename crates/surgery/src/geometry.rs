//! Small exact-enough geometric kernels in `f64`.

use glam::DVec3;

/// Where the segment `p → q` crosses the triangle `a b c`: the parameter `t ∈ [0, 1]` along the
/// segment (Möller–Trumbore, both sides, edges included), `None` if it misses or is parallel.
pub(crate) fn segment_triangle(p: DVec3, q: DVec3, [a, b, c]: [DVec3; 3]) -> Option<f64> {
    let d = q - p;
    let (e1, e2) = (b - a, c - a);
    let h = d.cross(e2);
    let det = e1.dot(h);
    let scale = e1.length() * e2.length() * d.length();
    if det.abs() <= 1e-12 * scale || scale == 0.0 {
        return None;
    }
    let f = 1.0 / det;
    let s = p - a;
    let u = f * s.dot(h);
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = s.cross(e1);
    let v = f * d.dot(qv);
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = f * e2.dot(qv);
    (0.0..=1.0).contains(&t).then_some(t)
}

/// Radius ratio `3 r_in / r_circ` of a tet (1 for the regular tet, 0 for a flat one).
pub(crate) fn radius_ratio([a, b, c, d]: [DVec3; 4]) -> f64 {
    let (u, v, w) = (b - a, c - a, d - a);
    let six_v = u.cross(v).dot(w);
    if six_v <= 0.0 {
        return 0.0;
    }
    let area = |p: DVec3, q: DVec3, r: DVec3| 0.5 * (q - p).cross(r - p).length();
    let s = area(a, b, c) + area(a, b, d) + area(a, c, d) + area(b, c, d);
    let r_in = 0.5 * six_v / s; // 3V / S
                                // Circumcentre relative to a: (|u|² v×w + |v|² w×u + |w|² u×v) / (2 · 6V).
    let o = (u.length_squared() * v.cross(w)
        + v.length_squared() * w.cross(u)
        + w.length_squared() * u.cross(v))
        / (2.0 * six_v);
    let r_circ = o.length();
    if r_circ > 0.0 {
        3.0 * r_in / r_circ
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_hits_and_misses() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let t = segment_triangle(DVec3::new(0.2, 0.2, -1.0), DVec3::new(0.2, 0.2, 1.0), tri);
        assert!(t.is_some_and(|t| (t - 0.5).abs() < 1e-12));
        assert!(
            segment_triangle(DVec3::new(0.8, 0.8, -1.0), DVec3::new(0.8, 0.8, 1.0), tri).is_none()
        );
        assert!(
            segment_triangle(DVec3::new(0.2, 0.2, 0.5), DVec3::new(0.2, 0.2, 1.0), tri).is_none()
        );
    }

    #[test]
    fn regular_tet_has_ratio_one() {
        let s = 1.0 / 2f64.sqrt();
        let t = [
            DVec3::new(1.0, 0.0, -s),
            DVec3::new(-1.0, 0.0, -s),
            DVec3::new(0.0, 1.0, s),
            DVec3::new(0.0, -1.0, s),
        ];
        let r = radius_ratio(t).max(radius_ratio([t[1], t[0], t[2], t[3]]));
        assert!((r - 1.0).abs() < 1e-9, "{r}");
    }
}

/// A small fast hasher for `u32` keys (FxHash's multiply–rotate), so that the maps of a cut do
/// not pay for SipHash. Not DoS-resistant; keys here are node and tet indices.
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct FxHasher(u64);

impl FxHasher {
    #[inline]
    fn add(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl std::hash::Hasher for FxHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        // Eight bytes per round (an edge `[u32; 2]` is one), then the tail.
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            let mut b = [0u8; 8];
            b.copy_from_slice(w);
            self.add(u64::from_le_bytes(b));
        }
        for &b in words.remainder() {
            self.add(b as u64);
        }
    }
    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.add(i as u64);
    }
    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.add(i as u64);
    }
    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }
    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }
    #[inline]
    fn finish(&self) -> u64 {
        // The product's high bits depend on every input bit, its low ones (the table's bucket)
        // only on the low input bits: rotate the high ones down.
        self.0.rotate_left(26)
    }
}

/// A `HashMap` with [`FxHasher`].
pub(crate) type FxMap<K, V> =
    std::collections::HashMap<K, V, std::hash::BuildHasherDefault<FxHasher>>;
