//! What a hierarchy can be built over: anything that gives each of its primitives a box (and, for
//! the point and ray queries, a closest point and a ray hit). Triangles of a mesh are the main
//! case; a slice of boxes is the plain one.

use glam::Vec3A;
use tissue_mesh::TriMesh;

use crate::geometry::{closest_point_on_triangle, ray_triangle};
use crate::{Aabb, BvhError};

/// A set of primitives numbered `0..primitive_count()`, each with a box.
///
/// The hierarchy reads only these methods; it never stores the primitives, so after the
/// primitives move, [`crate::Bvh::refit`] is given them again.
pub trait Primitives {
    /// Number of primitives.
    fn primitive_count(&self) -> usize;

    /// The box of primitive `i` (`i < primitive_count()`).
    fn bounds(&self, i: u32) -> Aabb;

    /// The point that orders primitive `i` along an axis when a node is split; by default the
    /// centre of its box.
    fn centroid(&self, i: u32) -> Vec3A {
        self.bounds(i).center()
    }

    /// The weight the equal-area split balances between the two children: a triangle's area. By
    /// default 1, so that the split balances counts.
    fn weight(&self, i: u32) -> f32 {
        let _ = i;
        1.0
    }

    /// Grows the box `[lo, hi]` to contain primitive `i`'s box (what a refit does per primitive;
    /// override it when the box can be accumulated without building an [`Aabb`]).
    #[inline]
    fn grow(&self, i: u32, lo: &mut Vec3A, hi: &mut Vec3A) {
        let b = self.bounds(i);
        *lo = lo.min(b.min.into());
        *hi = hi.max(b.max.into());
    }

    /// `(bounds(i), centroid(i), weight(i))` in one call, which is all a build reads; override it
    /// when the three share work (as for triangles, which read their corners once).
    fn build_data(&self, i: u32) -> (Aabb, Vec3A, f32) {
        (self.bounds(i), self.centroid(i), self.weight(i))
    }
}

/// Primitives with a closest point, for [`crate::Bvh::closest_point`].
pub trait ClosestPoint: Primitives {
    /// The point of primitive `i` closest to `p`.
    fn closest_point(&self, i: u32, p: Vec3A) -> Vec3A;
}

/// Primitives a ray can hit, for [`crate::Bvh::cast_ray`].
pub trait RayIntersect: Primitives {
    /// The smallest `t ∈ [0, t_max]` at which `ray` meets primitive `i`, if any.
    fn ray_intersect(&self, i: u32, ray: &Ray, t_max: f32) -> Option<f32>;
}

/// A half-line `origin + t·dir`, `t ≥ 0`, with `1/dir` precomputed for the slab tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3A,
    /// Direction (any length; `t` is measured in multiples of it).
    pub dir: Vec3A,
    /// `1/dir` per component.
    pub inv_dir: Vec3A,
}

impl Ray {
    /// A ray from `origin` along `dir`. A zero `dir` gives a ray that hits nothing.
    pub fn new(origin: Vec3A, dir: Vec3A) -> Ray {
        Ray {
            origin,
            dir,
            inv_dir: dir.recip(),
        }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + self.dir * t
    }
}

/// The triangles of a mesh at given vertex positions: `triangles[t]` indexes `positions`.
///
/// Box: the corners' min/max. Centroid: the mean of the corners. Weight: the area (so the
/// equal-area split of the thesis balances summed triangle area).
#[derive(Debug, Clone, Copy)]
pub struct Triangles<'a> {
    positions: &'a [Vec3A],
    triangles: &'a [[u32; 3]],
}

impl<'a> Triangles<'a> {
    /// Raw data: checks every index (`O(triangles)`).
    ///
    /// # Errors
    /// [`BvhError::IndexOutOfRange`] for the first triangle with an index `≥ positions.len()`,
    /// [`BvhError::TooManyPrimitives`] beyond what `u32` node indices address.
    pub fn new(positions: &'a [Vec3A], triangles: &'a [[u32; 3]]) -> Result<Self, BvhError> {
        check_count(triangles.len())?;
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(BvhError::IndexOutOfRange {
                    triangle: t as u32,
                    index,
                    vertex_count: positions.len(),
                });
            }
        }
        Ok(Triangles {
            positions,
            triangles,
        })
    }

    /// The triangles of a validated mesh at new positions (a deformed state): only the count is
    /// checked (`O(1)`), since the mesh's indices are known to be in range.
    ///
    /// # Errors
    /// [`BvhError::PositionCount`] when `positions.len() != mesh.vertex_count()`.
    pub fn from_mesh(mesh: &'a TriMesh, positions: &'a [Vec3A]) -> Result<Self, BvhError> {
        if positions.len() != mesh.vertex_count() {
            return Err(BvhError::PositionCount {
                expected: mesh.vertex_count(),
                got: positions.len(),
            });
        }
        check_count(mesh.triangle_count())?;
        Ok(Triangles {
            positions,
            triangles: mesh.triangles(),
        })
    }

    /// Vertex positions.
    pub fn positions(&self) -> &'a [Vec3A] {
        self.positions
    }

    /// Vertex indices of each triangle.
    pub fn triangles(&self) -> &'a [[u32; 3]] {
        self.triangles
    }

    /// The three corners of triangle `t`.
    ///
    /// # Panics
    /// If `t` is not a triangle index.
    #[inline]
    pub fn corners(&self, t: u32) -> [Vec3A; 3] {
        let [a, b, c] = self.triangles[t as usize];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }
}

fn check_count(count: usize) -> Result<(), BvhError> {
    if count > crate::MAX_PRIMITIVES {
        return Err(BvhError::TooManyPrimitives {
            count,
            max: crate::MAX_PRIMITIVES,
        });
    }
    Ok(())
}

impl Primitives for Triangles<'_> {
    #[inline]
    fn primitive_count(&self) -> usize {
        self.triangles.len()
    }

    #[inline]
    fn bounds(&self, i: u32) -> Aabb {
        let [a, b, c] = self.corners(i);
        Aabb::from_triangle(a, b, c)
    }

    #[inline]
    fn centroid(&self, i: u32) -> Vec3A {
        let [a, b, c] = self.corners(i);
        (a + b + c) * (1.0 / 3.0)
    }

    #[inline]
    fn weight(&self, i: u32) -> f32 {
        let [a, b, c] = self.corners(i);
        0.5 * (b - a).cross(c - a).length()
    }

    #[inline]
    fn grow(&self, i: u32, lo: &mut Vec3A, hi: &mut Vec3A) {
        let [a, b, c] = self.corners(i);
        *lo = lo.min(a.min(b).min(c));
        *hi = hi.max(a.max(b).max(c));
    }

    #[inline]
    fn build_data(&self, i: u32) -> (Aabb, Vec3A, f32) {
        let [a, b, c] = self.corners(i);
        (
            Aabb::from_triangle(a, b, c),
            (a + b + c) * (1.0 / 3.0),
            0.5 * (b - a).cross(c - a).length(),
        )
    }
}

impl ClosestPoint for Triangles<'_> {
    #[inline]
    fn closest_point(&self, i: u32, p: Vec3A) -> Vec3A {
        let [a, b, c] = self.corners(i);
        closest_point_on_triangle(p, a, b, c).0
    }
}

impl RayIntersect for Triangles<'_> {
    #[inline]
    fn ray_intersect(&self, i: u32, ray: &Ray, t_max: f32) -> Option<f32> {
        let [a, b, c] = self.corners(i);
        ray_triangle(ray.origin, ray.dir, t_max, a, b, c).map(|(t, _)| t)
    }
}

/// Boxes as primitives: a hierarchy over arbitrary boxes (weight 1, so the equal-area split
/// balances counts).
impl Primitives for [Aabb] {
    #[inline]
    fn primitive_count(&self) -> usize {
        self.len()
    }

    #[inline]
    fn bounds(&self, i: u32) -> Aabb {
        self[i as usize]
    }
}

impl ClosestPoint for [Aabb] {
    #[inline]
    fn closest_point(&self, i: u32, p: Vec3A) -> Vec3A {
        let b = self[i as usize];
        p.clamp(b.min.into(), b.max.into())
    }
}

impl RayIntersect for [Aabb] {
    #[inline]
    fn ray_intersect(&self, i: u32, ray: &Ray, t_max: f32) -> Option<f32> {
        self[i as usize].ray_entry(ray.origin, ray.dir, ray.inv_dir, t_max)
    }
}
