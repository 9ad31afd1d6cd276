//! Exact-as-`f32`-allows primitive tests used by the triangle queries: closest point on a triangle,
//! ray against a triangle.

use glam::{DVec3, Vec3A};

/// Defines a closest-point-on-triangle function and its degenerate fallback for one
/// precision (the `f32` and `f64` versions share one body).
macro_rules! closest_point_on_triangle {
    ($(#[$doc:meta])* $name:ident, $sides:ident, $v:ty, $s:ty) => {
        $(#[$doc])*
        pub fn $name(p: $v, a: $v, b: $v, c: $v) -> ($v, [$s; 3]) {
            let ab = b - a;
            let ac = c - a;
            let ap = p - a;
            let d1 = ab.dot(ap);
            let d2 = ac.dot(ap);
            if d1 <= 0.0 && d2 <= 0.0 {
                return (a, [1.0, 0.0, 0.0]);
            }
            let bp = p - b;
            let d3 = ab.dot(bp);
            let d4 = ac.dot(bp);
            if d3 >= 0.0 && d4 <= d3 {
                return (b, [0.0, 1.0, 0.0]);
            }
            let vc = d1 * d4 - d3 * d2;
            if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
                let v = d1 / (d1 - d3);
                return (a + ab * v, [1.0 - v, v, 0.0]);
            }
            let cp = p - c;
            let d5 = ab.dot(cp);
            let d6 = ac.dot(cp);
            if d6 >= 0.0 && d5 <= d6 {
                return (c, [0.0, 0.0, 1.0]);
            }
            let vb = d5 * d2 - d1 * d6;
            if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
                let w = d2 / (d2 - d6);
                return (a + ac * w, [1.0 - w, 0.0, w]);
            }
            let va = d3 * d6 - d5 * d4;
            if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
                let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
                return (b + (c - b) * w, [0.0, 1.0 - w, w]);
            }
            let sum = va + vb + vc;
            if !(sum > 0.0 && sum.is_finite()) {
                return $sides(p, a, b, c);
            }
            let v = vb / sum;
            let w = vc / sum;
            (a + ab * v + ac * w, [1.0 - v - w, v, w])
        }

                /// Closest point over the three sides of a (degenerate) triangle.
        fn $sides(p: $v, a: $v, b: $v, c: $v) -> ($v, [$s; 3]) {
            let on = |x: $v, y: $v| {
                let d = y - x;
                let len2 = d.length_squared();
                let t = if len2 > 0.0 {
                    ((p - x).dot(d) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (x + d * t, t)
            };
            let (pab, tab) = on(a, b);
            let (pbc, tbc) = on(b, c);
            let (pca, tca) = on(c, a);
            let candidates = [
                (pab, [1.0 - tab, tab, 0.0]),
                (pbc, [0.0, 1.0 - tbc, tbc]),
                (pca, [tca, 0.0, 1.0 - tca]),
            ];
            let mut best = candidates[0];
            for cand in &candidates[1..] {
                if (cand.0 - p).length_squared() < (best.0 - p).length_squared() {
                    best = *cand;
                }
            }
            best
        }
    };
}

closest_point_on_triangle!(
    /// The point of triangle `abc` closest to `p`, and its barycentric coordinates `[u, v, w]`
    /// (`point = u·a + v·b + w·c`, each in `[0, 1]`, summing to 1).
    ///
    /// Ericson's Voronoi-region walk (*Real-Time Collision Detection*, 5.1.5): vertex regions, then edge
    /// regions, then the face. A triangle squashed to a segment or a point (possible in a deformed
    /// mesh) falls back to the closest of its three sides, so the result is always finite for finite
    /// input.
    closest_point_on_triangle,
    closest_on_sides,
    Vec3A,
    f32
);

closest_point_on_triangle!(
    /// [`closest_point_on_triangle`] in `f64`: for solvers that differentiate it.
    closest_point_on_triangle_f64,
    closest_on_sides_f64,
    DVec3,
    f64
);

/// Where the ray `origin + t·dir` meets triangle `abc` (either side), if at some `t ∈ [0, t_max]`:
/// `(t, [u, v, w])` with the hit point `u·a + v·b + w·c`.
///
/// Möller–Trumbore. A ray parallel to the triangle's plane (zero determinant) does not hit it,
/// even when it runs inside the plane; edges and vertices count as hits.
pub fn ray_triangle(
    origin: Vec3A,
    dir: Vec3A,
    t_max: f32,
    a: Vec3A,
    b: Vec3A,
    c: Vec3A,
) -> Option<(f32, [f32; 3])> {
    let e1 = b - a;
    let e2 = c - a;
    let pvec = dir.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tvec = origin - a;
    let u = tvec.dot(pvec) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = dir.dot(qvec) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qvec) * inv;
    (0.0..=t_max)
        .contains(&t)
        .then_some((t, [1.0 - u - v, u, v]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [Vec3A; 3] {
        [Vec3A::ZERO, Vec3A::X, Vec3A::Y]
    }

    #[test]
    fn closest_point_in_every_region() {
        let [a, b, c] = tri();
        let cases = [
            (Vec3A::new(0.25, 0.25, 1.0), Vec3A::new(0.25, 0.25, 0.0)), // face
            (Vec3A::new(-1.0, -1.0, 0.0), a),                           // vertex a
            (Vec3A::new(2.0, -0.5, 0.3), b),                            // vertex b
            (Vec3A::new(-0.5, 2.0, 0.0), c),                            // vertex c
            (Vec3A::new(0.5, -1.0, 0.0), Vec3A::new(0.5, 0.0, 0.0)),    // edge ab
            (Vec3A::new(-1.0, 0.5, 0.0), Vec3A::new(0.0, 0.5, 0.0)),    // edge ac
            (Vec3A::new(1.0, 1.0, 0.0), Vec3A::new(0.5, 0.5, 0.0)),     // edge bc
        ];
        for (p, expected) in cases {
            let (q, bary) = closest_point_on_triangle(p, a, b, c);
            assert!(
                (q - expected).length() < 1e-6,
                "{p} -> {q}, expected {expected}"
            );
            let back = a * bary[0] + b * bary[1] + c * bary[2];
            assert!((back - q).length() < 1e-6);
            assert!((bary.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn closest_point_on_degenerate_triangle_is_finite() {
        let (a, b, c) = (Vec3A::ZERO, Vec3A::X, Vec3A::new(2.0, 0.0, 0.0));
        let (q, _) = closest_point_on_triangle(Vec3A::new(1.5, 1.0, 0.0), a, b, c);
        assert!((q - Vec3A::new(1.5, 0.0, 0.0)).length() < 1e-6);
        let (q, _) = closest_point_on_triangle(Vec3A::ONE, a, a, a);
        assert_eq!(q, a);
    }

    #[test]
    fn ray_hits_from_both_sides_and_misses_parallel() {
        let [a, b, c] = tri();
        let (t, bary) = ray_triangle(Vec3A::new(0.2, 0.2, 1.0), -Vec3A::Z, 10.0, a, b, c).unwrap();
        assert!((t - 1.0).abs() < 1e-6);
        assert!((bary[1] - 0.2).abs() < 1e-6 && (bary[2] - 0.2).abs() < 1e-6);
        assert!(ray_triangle(Vec3A::new(0.2, 0.2, -1.0), Vec3A::Z, 10.0, a, b, c).is_some());
        assert!(ray_triangle(Vec3A::new(0.2, 0.2, 1.0), Vec3A::Z, 10.0, a, b, c).is_none());
        assert!(ray_triangle(Vec3A::new(-1.0, 0.2, 0.0), Vec3A::X, 10.0, a, b, c).is_none());
        assert!(ray_triangle(Vec3A::new(0.2, 0.2, 1.0), -Vec3A::Z, 0.5, a, b, c).is_none());
    }
}
