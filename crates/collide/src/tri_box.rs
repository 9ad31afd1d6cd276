//! Exact triangle–box overlap, the test that decides which voxels list a triangle.

use glam::Vec3A;
use tissue_bvh::Aabb;

/// `true` when triangle `abc` and the box share a point (faces included).
///
/// Akenine-Möller's separating-axis test: the three box axes, the triangle's normal, and the nine
/// cross products of a box axis with a triangle side; the two are disjoint exactly when one of
/// these axes separates them. A degenerate triangle has zero normal and sides: those axes never
/// separate, so the answer stays conservative.
pub fn triangle_overlaps_box(a: Vec3A, b: Vec3A, c: Vec3A, aabb: &Aabb) -> bool {
    let center = aabb.center();
    let h = (Vec3A::from(aabb.max) - Vec3A::from(aabb.min)) * 0.5;
    let (v0, v1, v2) = (a - center, b - center, c - center);
    // Box axes: the triangle's box against the box.
    if v0.min(v1).min(v2).cmpgt(h).any() || v0.max(v1).max(v2).cmplt(-h).any() {
        return false;
    }
    // The nine edge axes.
    let separated = |axis: Vec3A, r: f32| {
        let (p0, p1, p2) = (axis.dot(v0), axis.dot(v1), axis.dot(v2));
        p0.min(p1).min(p2) > r || p0.max(p1).max(p2) < -r
    };
    for e in [v1 - v0, v2 - v1, v0 - v2] {
        let f = e.abs();
        if separated(Vec3A::new(0.0, -e.z, e.y), h.y * f.z + h.z * f.y)
            || separated(Vec3A::new(e.z, 0.0, -e.x), h.x * f.z + h.z * f.x)
            || separated(Vec3A::new(-e.y, e.x, 0.0), h.x * f.y + h.y * f.x)
        {
            return false;
        }
    }
    // The triangle's plane against the box.
    let n = (v1 - v0).cross(v2 - v1);
    n.dot(v0).abs() <= h.dot(n.abs())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn inside_outside_and_touching() {
        let b = unit();
        let t = |a: [f32; 3], bb: [f32; 3], c: [f32; 3]| {
            triangle_overlaps_box(Vec3A::from(a), Vec3A::from(bb), Vec3A::from(c), &b)
        };
        assert!(t([0.2, 0.2, 0.5], [0.8, 0.2, 0.5], [0.5, 0.8, 0.5])); // inside
        assert!(!t([2.0, 0.2, 0.5], [3.0, 0.2, 0.5], [2.5, 0.8, 0.5])); // beside
        assert!(t([1.0, 0.2, 0.5], [2.0, 0.2, 0.5], [1.5, 0.8, 0.5])); // touches a face
                                                                       // A big triangle whose interior crosses the box though no vertex is inside.
        assert!(t([-5.0, -5.0, 0.5], [5.0, -5.0, 0.5], [0.0, 10.0, 0.5]));
        // Corner-cutting triangles: x + y + z = 1.5 passes through the centre, = 3.1 misses the
        // box although the triangle's box contains it (only the plane axis separates).
        assert!(t([1.5, 0.0, 0.0], [0.0, 1.5, 0.0], [0.0, 0.0, 1.5]));
        assert!(!t([3.1, 0.0, 0.0], [0.0, 3.1, 0.0], [0.0, 0.0, 3.1]));
    }

    #[test]
    fn agrees_with_sampling_on_random_triangles() {
        // A triangle overlaps the box iff some point of it is inside: sample densely and compare
        // where sampling finds a point (sampling can only miss overlaps, never invent them).
        let b = unit();
        let mut rng = tissue_bvh::scenes::Rng::new(1);
        let mut agree_inside = 0;
        for _ in 0..2000 {
            let c = Vec3A::splat(0.5) + rng.in_cube(1.2);
            let (p0, p1, p2) = (
                c + rng.in_cube(0.6),
                c + rng.in_cube(0.6),
                c + rng.in_cube(0.6),
            );
            let exact = triangle_overlaps_box(p0, p1, p2, &b);
            let mut sampled = false;
            for i in 0..=40 {
                for j in 0..=(40 - i) {
                    let (u, v) = (i as f32 / 40.0, j as f32 / 40.0);
                    if b.contains_point(p0 + (p1 - p0) * u + (p2 - p0) * v) {
                        sampled = true;
                    }
                }
            }
            if sampled {
                assert!(exact, "missed overlap {p0} {p1} {p2}");
                agree_inside += 1;
            }
        }
        assert!(agree_inside > 100);
    }
}
