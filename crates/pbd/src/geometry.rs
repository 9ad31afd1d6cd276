//! Closest points on the primitives of the collision code (pure functions, `f32`).

use glam::Vec3A;

/// The point of the segment `a–b` closest to `p` (`a` itself when the segment is a point).
#[inline]
pub(crate) fn closest_point_on_segment(p: Vec3A, a: Vec3A, b: Vec3A) -> Vec3A {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= 0.0 {
        return a;
    }
    let t = ((p - a).dot(ab) / len2).clamp(0.0, 1.0);
    a + t * ab
}

/// The point of the triangle `a b c` (with its interior) closest to `p`: `tissue-bvh`'s Ericson
/// walk (robust for squashed triangles), without its barycentric coordinates.
#[inline]
pub(crate) fn closest_point_on_triangle(p: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> Vec3A {
    tissue_bvh::closest_point_on_triangle(p, a, b, c).0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the closest of a fine barycentric sampling.
    fn sampled(p: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> f32 {
        let n = 200;
        let mut best = f32::INFINITY;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                let q = a + u * (b - a) + v * (c - a);
                best = best.min(p.distance(q));
            }
        }
        best
    }

    #[test]
    fn triangle_closest_point_matches_sampling() {
        let (a, b, c) = (
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(2.0, 0.1, 0.0),
            Vec3A::new(0.3, 1.5, 0.4),
        );
        let mut s = 1u32;
        for _ in 0..200 {
            let mut r = || {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (s >> 8) as f32 / (1u32 << 24) as f32 * 6.0 - 3.0
            };
            let p = Vec3A::new(r(), r(), r());
            let exact = p.distance(closest_point_on_triangle(p, a, b, c));
            let brute = sampled(p, a, b, c);
            assert!(
                exact <= brute + 1e-5 && brute - exact < 0.02,
                "{p}: {exact} vs {brute}"
            );
        }
        let q = closest_point_on_segment(Vec3A::new(5.0, 1.0, 0.0), Vec3A::ZERO, Vec3A::X);
        assert_eq!(q, Vec3A::X);
    }
}
