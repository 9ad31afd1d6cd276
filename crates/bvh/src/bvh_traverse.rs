//! Single-hierarchy queries: boxes overlapping a box, closest primitive to a point, first primitive
//! along a ray. Depth first with an explicit stack from the workspace; nearer children first for
//! the point and ray queries, which prune by the best distance found so far.

use glam::Vec3A;

use crate::{Aabb, Bvh, BvhWorkspace, ClosestPoint, Primitives, Ray, RayIntersect};

/// The result of [`Bvh::closest_point`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointHit {
    /// The closest primitive (the smallest index among equally close ones).
    pub primitive: u32,
    /// Its point closest to the query point.
    pub point: Vec3A,
    /// The distance from the query point.
    pub distance: f32,
}

/// The result of [`Bvh::cast_ray`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// The primitive hit first (the smallest index among hits at the same `t`).
    pub primitive: u32,
    /// Ray parameter of the hit: the point is `ray.at(t)`.
    pub t: f32,
}

impl Bvh {
    /// Appends to `out` (after clearing it) the leaves whose boxes overlap `aabb` grown by `gap`
    /// ([`Aabb::overlaps`]), in depth-first order.
    pub fn overlapping_leaves(
        &self,
        aabb: &Aabb,
        gap: f32,
        ws: &mut BvhWorkspace,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        self.visit_overlapping_leaves(aabb, gap, &mut ws.stack, |leaf| out.push(leaf));
    }

    /// Appends to `out` (after clearing it) the primitives whose own boxes overlap `aabb` grown by
    /// `gap`, in leaf order.
    pub fn overlapping_primitives<P: Primitives + ?Sized>(
        &self,
        prims: &P,
        aabb: &Aabb,
        gap: f32,
        ws: &mut BvhWorkspace,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        self.visit_overlapping_leaves(aabb, gap, &mut ws.stack, |leaf| {
            let node = &self.nodes[leaf as usize];
            let slots = node.first as usize..(node.first + node.count) as usize;
            out.extend(
                self.order[slots]
                    .iter()
                    .copied()
                    .filter(|&p| prims.bounds(p).overlaps(aabb, gap)),
            );
        });
    }

    /// Calls `visit` with every leaf whose box overlaps `aabb` grown by `gap`, depth first,
    /// using `stack` as scratch.
    fn visit_overlapping_leaves(
        &self,
        aabb: &Aabb,
        gap: f32,
        stack: &mut Vec<u32>,
        mut visit: impl FnMut(u32),
    ) {
        stack.clear();
        if !self.nodes[0].aabb.overlaps(aabb, gap) {
            return;
        }
        stack.push(0);
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            if node.is_leaf() {
                visit(i);
                continue;
            }
            let c = node.first;
            if self.nodes[c as usize + 1].aabb.overlaps(aabb, gap) {
                stack.push(c + 1);
            }
            if self.nodes[c as usize].aabb.overlaps(aabb, gap) {
                stack.push(c);
            }
        }
    }

    /// The primitive closest to `p` within `max_distance` (use `f32::INFINITY` for no limit), or
    /// `None` if there is none that close.
    pub fn closest_point<P: ClosestPoint + ?Sized>(
        &self,
        prims: &P,
        p: Vec3A,
        max_distance: f32,
        ws: &mut BvhWorkspace,
    ) -> Option<PointHit> {
        let mut best_d2 = if max_distance.is_finite() {
            max_distance * max_distance
        } else {
            f32::INFINITY
        };
        let mut best: Option<(u32, Vec3A)> = None;
        let stack = &mut ws.scored;
        stack.clear();
        let d0 = self.nodes[0].aabb.distance_squared(p);
        if d0 > best_d2 {
            return None;
        }
        stack.push((d0, 0));
        while let Some((d, i)) = stack.pop() {
            if d > best_d2 {
                continue;
            }
            let node = &self.nodes[i as usize];
            if node.is_leaf() {
                let slots = node.first as usize..(node.first + node.count) as usize;
                for &prim in &self.order[slots] {
                    let q = prims.closest_point(prim, p);
                    let d2 = (q - p).length_squared();
                    let better = d2 < best_d2
                        || (d2 == best_d2 && best.is_some_and(|(b, _)| prim < b))
                        || (d2 == best_d2 && best.is_none());
                    if better {
                        best_d2 = d2;
                        best = Some((prim, q));
                    }
                }
                continue;
            }
            let c = node.first;
            let dl = self.nodes[c as usize].aabb.distance_squared(p);
            let dr = self.nodes[c as usize + 1].aabb.distance_squared(p);
            // Push the farther first so that the nearer is visited first.
            let (near, far) = if dl <= dr {
                ((dl, c), (dr, c + 1))
            } else {
                ((dr, c + 1), (dl, c))
            };
            if far.0 <= best_d2 {
                stack.push(far);
            }
            if near.0 <= best_d2 {
                stack.push(near);
            }
        }
        best.map(|(primitive, point)| PointHit {
            primitive,
            point,
            distance: best_d2.sqrt(),
        })
    }

    /// The first primitive `ray` meets at some `t ∈ [0, t_max]`, or `None`.
    pub fn cast_ray<P: RayIntersect + ?Sized>(
        &self,
        prims: &P,
        ray: &Ray,
        t_max: f32,
        ws: &mut BvhWorkspace,
    ) -> Option<RayHit> {
        let mut best_t = t_max;
        let mut best: Option<u32> = None;
        let stack = &mut ws.scored;
        stack.clear();
        let entry = |b: &Aabb, t: f32| b.ray_entry(ray.origin, ray.dir, ray.inv_dir, t);
        let t0 = entry(&self.nodes[0].aabb, best_t)?;
        stack.push((t0, 0));
        while let Some((t, i)) = stack.pop() {
            if t > best_t {
                continue;
            }
            let node = &self.nodes[i as usize];
            if node.is_leaf() {
                let slots = node.first as usize..(node.first + node.count) as usize;
                for &prim in &self.order[slots] {
                    if let Some(th) = prims.ray_intersect(prim, ray, best_t) {
                        let better = th < best_t
                            || best.is_none()
                            || (th == best_t && best.is_some_and(|b| prim < b));
                        if better {
                            best_t = th;
                            best = Some(prim);
                        }
                    }
                }
                continue;
            }
            let c = node.first;
            let tl = entry(&self.nodes[c as usize].aabb, best_t);
            let tr = entry(&self.nodes[c as usize + 1].aabb, best_t);
            match (tl, tr) {
                (Some(a), Some(b)) => {
                    if a <= b {
                        stack.push((b, c + 1));
                        stack.push((a, c));
                    } else {
                        stack.push((a, c));
                        stack.push((b, c + 1));
                    }
                }
                (Some(a), None) => stack.push((a, c)),
                (None, Some(b)) => stack.push((b, c + 1)),
                (None, None) => {}
            }
        }
        best.map(|primitive| RayHit {
            primitive,
            t: best_t,
        })
    }
}
