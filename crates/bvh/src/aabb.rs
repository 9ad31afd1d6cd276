//! The axis-aligned box of the hierarchy, laid out for traversal (24 bytes, `#[repr(C)]`).

use glam::{Vec3, Vec3A};

/// An axis-aligned box: the points `p` with `min ≤ p ≤ max` on every axis, in the units of the
/// positions it bounds (cm in tissue).
///
/// [`Aabb::EMPTY`] (`min = +∞`, `max = −∞`) is the identity of [`Aabb::union`] and overlaps
/// nothing. Every comparison is inclusive: boxes that share a face overlap.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Aabb {
    /// The smallest coordinate on each axis.
    pub min: Vec3,
    /// The largest coordinate on each axis.
    pub max: Vec3,
}

const _: () = assert!(std::mem::size_of::<Aabb>() == 24);

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    /// The empty box: contains nothing, overlaps nothing, `EMPTY.union(b) == b`.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The box with these corners (not checked: `min > max` on an axis makes an empty box).
    #[inline]
    pub const fn new(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    /// The box of one point (zero size).
    #[inline]
    pub fn from_point(p: Vec3A) -> Aabb {
        Aabb {
            min: p.into(),
            max: p.into(),
        }
    }

    /// The box of a triangle (or of any three points).
    #[inline]
    pub fn from_triangle(a: Vec3A, b: Vec3A, c: Vec3A) -> Aabb {
        Aabb {
            min: a.min(b).min(c).into(),
            max: a.max(b).max(c).into(),
        }
    }

    /// The box of a segment.
    #[inline]
    pub fn from_segment(a: Vec3A, b: Vec3A) -> Aabb {
        Aabb {
            min: a.min(b).into(),
            max: a.max(b).into(),
        }
    }

    /// The smallest box containing both. Exact (only `min`/`max` of the stored values).
    #[inline]
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The box grown by `margin` on every side.
    #[inline]
    pub fn expanded(&self, margin: f32) -> Aabb {
        Aabb {
            min: self.min - Vec3::splat(margin),
            max: self.max + Vec3::splat(margin),
        }
    }

    /// `true` when the boxes overlap once each is grown by `gap` (inclusive: touching boxes
    /// overlap; `gap = 0` is the plain test).
    ///
    /// Written as `a.min ≤ b.max + gap` on each axis in both directions. Every query and every
    /// caller that must agree with a query uses this one expression: IEEE rounding is monotone,
    /// so if a small box passes it, any box containing the small one passes it too.
    #[inline]
    pub fn overlaps(&self, other: &Aabb, gap: f32) -> bool {
        self.min.x <= other.max.x + gap
            && other.min.x <= self.max.x + gap
            && self.min.y <= other.max.y + gap
            && other.min.y <= self.max.y + gap
            && self.min.z <= other.max.z + gap
            && other.min.z <= self.max.z + gap
    }

    /// `true` when `other` lies inside this box (faces included). Every box contains
    /// [`Aabb::EMPTY`].
    #[inline]
    pub fn contains(&self, other: &Aabb) -> bool {
        other.is_empty() || (self.min.cmple(other.min).all() && other.max.cmple(self.max).all())
    }

    /// `true` when `p` lies in the box, faces included.
    #[inline]
    pub fn contains_point(&self, p: Vec3A) -> bool {
        let p = Vec3::from(p);
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    /// `true` when `min > max` on some axis (nothing is inside), as for [`Aabb::EMPTY`].
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// `true` when every coordinate is finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// Edge lengths `max − min` (negative for an empty box).
    #[inline]
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre `(min + max) / 2`.
    #[inline]
    pub fn center(&self) -> Vec3A {
        (Vec3A::from(self.min) + Vec3A::from(self.max)) * 0.5
    }

    /// Surface area `2(xy + yz + zx)`; 0 for an empty box.
    #[inline]
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.size();
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// Squared distance from `p` to the box (0 inside).
    #[inline]
    pub fn distance_squared(&self, p: Vec3A) -> f32 {
        let q = p.clamp(self.min.into(), self.max.into());
        (p - q).length_squared()
    }

    /// The entry parameter of the ray `origin + t·dir` into the box, if it enters at some
    /// `t ∈ [0, t_max]` (0 when the origin is inside). `inv_dir` is `1/dir` per component. A zero
    /// component of `dir` is handled exactly: the ray then meets the slab of that axis only if the
    /// origin lies in it (faces included).
    #[inline]
    pub fn ray_entry(&self, origin: Vec3A, dir: Vec3A, inv_dir: Vec3A, t_max: f32) -> Option<f32> {
        let (lo, hi) = (Vec3A::from(self.min), Vec3A::from(self.max));
        let mut near = 0.0f32;
        let mut far = t_max;
        for axis in 0..3 {
            if dir[axis] == 0.0 {
                if origin[axis] < lo[axis] || origin[axis] > hi[axis] {
                    return None;
                }
                continue;
            }
            let t0 = (lo[axis] - origin[axis]) * inv_dir[axis];
            let t1 = (hi[axis] - origin[axis]) * inv_dir[axis];
            near = near.max(t0.min(t1));
            far = far.min(t0.max(t1));
        }
        (near <= far).then_some(near)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn empty_is_the_identity_of_union_and_overlaps_nothing() {
        let b = unit();
        assert_eq!(Aabb::EMPTY.union(&b), b);
        assert!(!Aabb::EMPTY.overlaps(&b, 0.0));
        assert!(!b.overlaps(&Aabb::EMPTY, 1.0));
        assert!(b.contains(&Aabb::EMPTY));
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
    }

    #[test]
    fn touching_boxes_overlap_and_gap_widens() {
        let a = unit();
        let b = Aabb::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 1.0));
        assert!(a.overlaps(&b, 0.0));
        let c = Aabb::new(Vec3::new(1.5, 0.0, 0.0), Vec3::new(2.0, 1.0, 1.0));
        assert!(!a.overlaps(&c, 0.0));
        assert!(!a.overlaps(&c, 0.49));
        assert!(a.overlaps(&c, 0.5));
        assert!(c.overlaps(&a, 0.5));
    }

    #[test]
    fn ray_entry_hits_misses_and_starts_inside() {
        let b = unit();
        let d = Vec3A::X;
        let inv = d.recip();
        let o = Vec3A::new(-1.0, 0.5, 0.5);
        assert_eq!(b.ray_entry(o, d, inv, 10.0), Some(1.0));
        assert_eq!(b.ray_entry(o, d, inv, 0.5), None);
        assert_eq!(b.ray_entry(Vec3A::new(-1.0, 1.5, 0.5), d, inv, 10.0), None);
        assert_eq!(b.ray_entry(Vec3A::splat(0.5), d, inv, 10.0), Some(0.0));
        // Along a face: the origin lies on a slab plane of an axis the ray does not move along.
        assert_eq!(
            b.ray_entry(Vec3A::new(-1.0, 1.0, 0.0), d, inv, 10.0),
            Some(1.0)
        );
        assert_eq!(
            b.ray_entry(Vec3A::new(-1.0, 0.0, 1.0), d, inv, 10.0),
            Some(1.0)
        );
    }

    #[test]
    fn distance_and_area() {
        let b = unit();
        assert_eq!(b.distance_squared(Vec3A::splat(0.5)), 0.0);
        assert_eq!(b.distance_squared(Vec3A::new(3.0, 0.5, 0.5)), 4.0);
        assert_eq!(b.surface_area(), 6.0);
        assert_eq!(b.center(), Vec3A::splat(0.5));
    }
}
