//! A small axis-aligned bounding box for measures and generators (the `bvh` crate has its own,
//! laid out for traversal).

use glam::Vec3;

/// An axis-aligned box: the points `p` with `min ≤ p ≤ max` in every coordinate, in the units of
/// the positions it bounds (cm in tissue).
///
/// A box built by [`Aabb::from_points`] or [`crate::TriMesh::bounding_box`] has `min ≤ max`; a box
/// of one point has zero size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// The smallest coordinate on each axis.
    pub min: Vec3,
    /// The largest coordinate on each axis.
    pub max: Vec3,
}

impl Aabb {
    /// The smallest box containing every point, or `None` for no points. Non-finite coordinates
    /// are not filtered: a NaN makes the result meaningless (a validated mesh has none).
    pub fn from_points(points: &[Vec3]) -> Option<Aabb> {
        let (&first, rest) = points.split_first()?;
        let mut b = Aabb {
            min: first,
            max: first,
        };
        for &p in rest {
            b.min = b.min.min(p);
            b.max = b.max.max(p);
        }
        Some(b)
    }

    /// Edge lengths `max − min`.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre `(min + max) / 2`, computed in `f64` so that it cannot overflow.
    pub fn center(&self) -> Vec3 {
        ((self.min.as_dvec3() + self.max.as_dvec3()) * 0.5).as_vec3()
    }

    /// The smallest box containing both boxes.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// `true` when `p` lies in the box, its faces included.
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_points_bounds_every_point() {
        let pts = [
            Vec3::new(1.0, -2.0, 3.0),
            Vec3::new(-1.0, 5.0, 0.5),
            Vec3::new(0.0, 0.0, 4.0),
        ];
        let b = Aabb::from_points(&pts).unwrap();
        assert_eq!(b.min, Vec3::new(-1.0, -2.0, 0.5));
        assert_eq!(b.max, Vec3::new(1.0, 5.0, 4.0));
        assert!(pts.iter().all(|&p| b.contains_point(p)));
        assert_eq!(b.size(), Vec3::new(2.0, 7.0, 3.5));
        assert_eq!(b.center(), Vec3::new(0.0, 1.5, 2.25));
        assert!(Aabb::from_points(&[]).is_none());
    }

    #[test]
    fn union_contains_both_and_faces_count_as_inside() {
        let a = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let b = Aabb {
            min: Vec3::splat(2.0),
            max: Vec3::splat(3.0),
        };
        let u = a.union(&b);
        assert_eq!(u, b.union(&a));
        assert_eq!(u.min, Vec3::ZERO);
        assert_eq!(u.max, Vec3::splat(3.0));
        assert!(a.contains_point(Vec3::new(1.0, 0.0, 0.5)));
        assert!(!a.contains_point(Vec3::new(1.0 + 1e-6, 0.0, 0.5)));
        assert!(!a.contains_point(Vec3::new(0.5, f32::NAN, 0.5)));
    }

    #[test]
    fn center_of_huge_box_does_not_overflow() {
        let b = Aabb {
            min: Vec3::splat(f32::MAX),
            max: Vec3::splat(f32::MAX),
        };
        assert_eq!(b.center(), Vec3::splat(f32::MAX));
    }
}
