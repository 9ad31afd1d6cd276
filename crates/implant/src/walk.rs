//! Walking straight on a surface: the straightest geodesic (Polthier & Schmies, "Straightest
//! geodesics on polyhedral surfaces", 1998) from a point in a tangent direction, and through it
//! the surface's exponential map at a point, which lays a plan drawing (an expander's base) onto
//! a curved body without stretching it.
//!
//! Inside a triangle the walk is a straight segment. Where it crosses an edge into the next
//! triangle, its direction is unfolded about the shared edge: the component along the edge is
//! kept and the component across it turns into the next triangle's plane, so the angle to the
//! edge is the same on both sides. On a developable surface (a plane, a cylinder, a cone) this
//! is the exact geodesic: a walk of length `s` around a cylinder of radius `r` turns by `s/r`.
//!
//! Computed in `f64`. A walk that meets the surface's boundary stops there ([`WalkEnd::Boundary`]).

use glam::DVec3;
use tissue_mesh::{TriMesh, NO_TRIANGLE};

/// The most edges one walk may cross (a bound on the work for a walk that circles).
const MAX_CROSSINGS: usize = 1_000_000;

/// Where a walk on a surface ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WalkEnd {
    /// The whole length was walked.
    Reached {
        /// The triangle the walk ended in.
        triangle: u32,
        /// Barycentric coordinates of the end in it (corners in stored order).
        barycentric: [f64; 3],
        /// The end point.
        position: DVec3,
        /// The walk's unit direction at the end (in the end triangle's plane).
        direction: DVec3,
    },
    /// The walk left the surface through a boundary edge.
    Boundary {
        /// Where it reached the boundary.
        position: DVec3,
        /// The length walked up to there.
        walked: f64,
    },
}

/// Walks `length` along the surface from `start` (a point in triangle `triangle`) in the
/// direction `direction` (its part in the triangle's plane is used), crossing edges as the
/// module docs describe.
///
/// A zero length returns the start. A direction with no part in the triangle's plane, a
/// non-finite input or a triangle index out of range gives [`WalkEnd::Boundary`] at the start
/// with nothing walked.
///
/// ```
/// use glam::DVec3;
/// use tissue_implant::{walk_on_surface, WalkEnd};
///
/// // Around a cylinder of radius 2 (axis y): a walk of a quarter circumference along the
/// // circle turns the walker by 90°.
/// let r = 2.0f32;
/// let (segments, rings) = (256u32, 3u32);
/// let mut positions = Vec::new();
/// for j in 0..rings {
///     for i in 0..segments {
///         let a = std::f32::consts::TAU * i as f32 / segments as f32;
///         positions.push(glam::Vec3::new(r * a.sin(), j as f32 - 1.0, r * a.cos()));
///     }
/// }
/// let mut triangles = Vec::new();
/// for j in 0..rings - 1 {
///     for i in 0..segments {
///         let (a, b) = (j * segments + i, j * segments + (i + 1) % segments);
///         let (c, d) = (a + segments, b + segments);
///         triangles.push([a, c, b]);
///         triangles.push([b, c, d]);
///     }
/// }
/// let tube = tissue_mesh::TriMesh::new(positions, triangles)?;
/// let start = DVec3::new(0.0, -0.5, f64::from(r));
/// let t = (0..tube.triangle_count() as u32)
///     .find(|&t| {
///         let c = tube.corners(t as usize);
///         c.iter().all(|p| p.x >= -1e-3 && p.x < 0.1 && p.y < 0.5)
///     })
///     .unwrap();
/// let quarter = std::f64::consts::FRAC_PI_2 * f64::from(r);
/// match walk_on_surface(&tube, t, start, DVec3::X, quarter) {
///     WalkEnd::Reached { position, .. } => {
///         assert!((position - DVec3::new(2.0, -0.5, 0.0)).length() < 1e-3);
///     }
///     other => panic!("{other:?}"),
/// }
/// # Ok::<(), tissue_mesh::MeshError>(())
/// ```
pub fn walk_on_surface(
    mesh: &TriMesh,
    triangle: u32,
    start: DVec3,
    direction: DVec3,
    length: f64,
) -> WalkEnd {
    let stuck = WalkEnd::Boundary {
        position: start,
        walked: 0.0,
    };
    if triangle as usize >= mesh.triangle_count()
        || !start.is_finite()
        || !direction.is_finite()
        || !length.is_finite()
        || length < 0.0
    {
        return stuck;
    }
    let corners = |t: u32| mesh.corners(t as usize).map(|p| p.as_dvec3());
    let normal = |c: &[DVec3; 3]| (c[1] - c[0]).cross(c[2] - c[0]).normalize_or_zero();
    let topology = mesh.topology();
    let mut t = triangle;
    let mut c = corners(t);
    let mut n = normal(&c);
    let mut d = (direction - n * direction.dot(n)).normalize_or_zero();
    if d == DVec3::ZERO || n == DVec3::ZERO {
        return stuck;
    }
    // The start, put into the triangle's plane.
    let mut p = start - n * (start - c[0]).dot(n);
    let mut left = length;
    let mut walked = 0.0;
    let mut entered: Option<usize> = None;
    for _ in 0..MAX_CROSSINGS {
        // The first side the ray p + s·d leaves the triangle through.
        let mut exit: Option<(usize, f64)> = None;
        for side in 0..3 {
            if Some(side) == entered {
                continue;
            }
            let (u, v) = (c[side], c[(side + 1) % 3]);
            // The side's normal in the plane, pointing into the triangle.
            let inward = n.cross(v - u);
            let closing = d.dot(inward);
            if closing >= 0.0 {
                continue;
            }
            let s = ((p - u).dot(inward) / -closing).max(0.0);
            if exit.is_none_or(|(_, best)| s < best) {
                exit = Some((side, s));
            }
        }
        let Some((side, s)) = exit else {
            // Parallel to every side it could leave by (rounding at a corner): step on the spot.
            return finish(t, &c, p, d);
        };
        if s >= left {
            return finish(t, &c, p + d * left, d);
        }
        let (u, v) = (c[side], c[(side + 1) % 3]);
        let along = (v - u).normalize();
        let cross_point = p + d * s;
        // Keep the crossing on the side's segment.
        let k = (cross_point - u).dot(v - u) / (v - u).length_squared();
        let cross_point = u + (v - u) * k.clamp(0.0, 1.0);
        left -= s;
        walked += s;
        let e = topology.triangle_edges()[t as usize][side] as usize;
        let [t0, t1] = topology.edge_triangles()[e];
        let next = if t0 == t { t1 } else { t0 };
        if next == NO_TRIANGLE {
            return WalkEnd::Boundary {
                position: cross_point,
                walked,
            };
        }
        // Unfold the direction about the shared side.
        let out_of_old = n.cross(v - u).normalize();
        let (a, b) = (d.dot(along), -d.dot(out_of_old));
        let c_next = corners(next);
        let n_next = normal(&c_next);
        if n_next == DVec3::ZERO {
            return WalkEnd::Boundary {
                position: cross_point,
                walked,
            };
        }
        // In the next triangle the same side runs v → u; its inward normal there.
        let into_next = n_next.cross(u - v).normalize();
        d = (along * a + into_next * b).normalize_or_zero();
        if d == DVec3::ZERO {
            return finish(next, &c_next, cross_point, along);
        }
        let next_tri = mesh.triangles()[next as usize];
        let (ua, va) = {
            let tri = mesh.triangles()[t as usize];
            (tri[side], tri[(side + 1) % 3])
        };
        entered = (0..3).find(|&i| {
            let (x, y) = (next_tri[i], next_tri[(i + 1) % 3]);
            (x == va && y == ua) || (x == ua && y == va)
        });
        t = next;
        c = c_next;
        n = n_next;
        p = cross_point;
    }
    WalkEnd::Boundary {
        position: p,
        walked,
    }
}

/// The end of a walk at `p` in triangle `t`.
fn finish(t: u32, c: &[DVec3; 3], p: DVec3, d: DVec3) -> WalkEnd {
    let barycentric = barycentric(c, p);
    let position = c[0] * barycentric[0] + c[1] * barycentric[1] + c[2] * barycentric[2];
    WalkEnd::Reached {
        triangle: t,
        barycentric,
        position,
        direction: d,
    }
}

/// Barycentric coordinates of `p` (in the triangle's plane) in triangle `c`, clamped to it.
fn barycentric(c: &[DVec3; 3], p: DVec3) -> [f64; 3] {
    let (e0, e1, q) = (c[1] - c[0], c[2] - c[0], p - c[0]);
    let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let (d20, d21) = (q.dot(e0), q.dot(e1));
    let denominator = d00 * d11 - d01 * d01;
    if denominator <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let v = ((d11 * d20 - d01 * d21) / denominator).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / denominator).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_a_plane_the_walk_is_a_straight_line() {
        let plane = tissue_mesh::grid(17, 8.0).unwrap();
        // Triangle holding the origin.
        let t = (0..plane.triangle_count() as u32)
            .find(|&t| {
                let c = plane.corners(t as usize);
                let b = barycentric(&c.map(|p| p.as_dvec3()), DVec3::new(0.1, 0.05, 0.0));
                let p = c[0].as_dvec3() * b[0] + c[1].as_dvec3() * b[1] + c[2].as_dvec3() * b[2];
                (p - DVec3::new(0.1, 0.05, 0.0)).length() < 1e-9
            })
            .unwrap();
        for angle in [0.0f64, 0.3, 1.0, 2.5, 4.0, 5.9] {
            let d = DVec3::new(angle.cos(), angle.sin(), 0.0);
            let WalkEnd::Reached { position, .. } =
                walk_on_surface(&plane, t, DVec3::new(0.1, 0.05, 0.0), d, 3.0)
            else {
                panic!("the walk should stay on the plane");
            };
            let want = DVec3::new(0.1, 0.05, 0.0) + d * 3.0;
            assert!((position - want).length() < 1e-9, "{angle}: {position}");
        }
        // Off the edge: stopped at the boundary after the distance to it.
        let end = walk_on_surface(&plane, t, DVec3::new(0.1, 0.05, 0.0), DVec3::X, 10.0);
        let WalkEnd::Boundary { position, walked } = end else {
            panic!("{end:?}");
        };
        assert!((walked - 3.9).abs() < 1e-9 && (position.x - 4.0).abs() < 1e-9);
    }
}
