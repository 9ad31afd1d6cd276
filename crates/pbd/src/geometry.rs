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

/// The point of the triangle `a b c` (with its interior) closest to `p` (Ericson, *Real-Time
/// Collision Detection*, 5.1.5: Voronoi regions of the vertices, edges and face in turn).
#[inline]
pub(crate) fn closest_point_on_triangle(p: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> Vec3A {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + v * ab;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + w * ac;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + w * (c - b);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    a + ab * v + ac * w
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
