//! The narrow phase: one edge against one triangle (SPEC A.4, "edges of one triangle against the
//! other triangle"), robust at shared-vertex, touching, coplanar and parallel configurations.

use glam::Vec3A;
use tissue_bvh::{closest_point_on_triangle, Aabb};

/// A crossing point whose barycentric coordinates are all `≥ −BARY_SLACK` counts as inside: an
/// edge through the common side of two triangles is then found by both, never by neither.
const BARY_SLACK: f32 = 1e-5;

/// The result of [`edge_triangle`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeTriangleHit {
    /// Parameter of the contact point along the edge `p → q`, in `[0, 1]`.
    pub s: f32,
    /// Barycentric coordinates of the contact point on the triangle (each in `[0, 1]`, sum 1).
    pub barycentric: [f32; 3],
    /// Unit vector along which the edge must move relative to the triangle to separate.
    pub normal: Vec3A,
    /// `> 0`: the edge crosses the triangle, and this is the distance from its nearer endpoint to
    /// the triangle's plane (how far the edge must move along `normal` to clear the plane). `≤ 0`:
    /// minus the distance between edge and triangle.
    pub depth: f32,
}

/// Tests the edge `p → q` against the triangle `abc`: a contact when the edge passes through the
/// triangle, or when their distance is at most `tolerance` (touching counts, at distance 0).
///
/// 1. Signed distances `d_p`, `d_q` of the endpoints to the triangle's plane: both beyond the
///    reach (below) on one side means no contact (the common, cheap exit).
/// 2. The edge's box and the triangle's box must overlap once grown by `tolerance`
///    ([`Aabb::overlaps`], the broad phase's own test), so a contact is never outside what any
///    conservative broad phase reports.
/// 3. Strictly opposite signs: the crossing point `x = p + s(q − p)`, `s = d_p/(d_p − d_q)`, and
///    its barycentric coordinates; inside (each `≥ −10⁻⁵`, so that an edge through the common
///    side of two triangles is found by both, never by neither) gives a crossing contact with
///    `depth = min(|d_p|, |d_q|)` and the normal pointing to the side of the farther endpoint (the
///    smallest move that clears the plane). Outside, and farther from the triangle than the part
///    of the edge near the plane can reach (bounded from `x`'s distance to the triangle's box and
///    its barycentric coordinates), no contact.
/// 4. Otherwise (including an edge lying in the plane, touching at a vertex, or parallel to the
///    triangle) the closest points of edge and triangle, from the five candidates (each endpoint
///    against the triangle, the edge against each side); within the reach this is a near
///    contact with `depth = −distance`, normal from the triangle's point to the edge's, or, when
///    they touch, the plane normal toward the edge's farther endpoint (`+n` when it lies in the
///    plane).
///
/// Distances are compared with the reach `tolerance + 10⁻⁶·L` (`L` the longest side of the edge
/// or the triangle), so that a pair touching exactly, like an endpoint on the triangle, is not
/// lost to the rounding of the closest-point computation; a distance below `10⁻⁶·L` is reported
/// as exactly 0.
///
/// A degenerate (zero-area) triangle has no plane: only step 4 applies. Whether an edge and a
/// triangle that share a particle may be in contact is the caller's decision
/// ([`crate::ContactParams::shared_particles`]).
pub fn edge_triangle(
    p: Vec3A,
    q: Vec3A,
    a: Vec3A,
    b: Vec3A,
    c: Vec3A,
    tolerance: f32,
) -> Option<EdgeTriangleHit> {
    let plane = TrianglePlane::new(a, b, c);
    edge_against(
        &plane,
        p,
        q,
        plane.distance(p),
        plane.distance(q),
        tolerance,
    )
}

/// What [`edge_triangle`] computes once per triangle: the narrow phase builds it once per triangle
/// pair and tests all the edges involved against it, with the same arithmetic (so the same
/// results) as separate calls.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TrianglePlane {
    a: Vec3A,
    b: Vec3A,
    c: Vec3A,
    aabb: Aabb,
    /// `(b − a) × (c − a)`, its squared length, and the unit normal (zero if not planar).
    nr: Vec3A,
    nn: f32,
    n: Vec3A,
    /// `|nr|` (twice the area), the longest side and its square.
    len: f32,
    longest: f32,
    longest_sq: f32,
    planar: bool,
    /// Each side's outward normal in the plane, `(end − start) × n` (length: the side's), for
    /// sides ab, bc, ca.
    side: [Vec3A; 3],
}

impl TrianglePlane {
    #[inline]
    pub fn new(a: Vec3A, b: Vec3A, c: Vec3A) -> TrianglePlane {
        let nr = (b - a).cross(c - a);
        let nn = nr.length_squared();
        let longest_sq = (b - a)
            .length_squared()
            .max((c - b).length_squared())
            .max((a - c).length_squared());
        // A plane exists when the triangle's height exceeds ~1e-6 of its longest side.
        let planar = nn > 1e-12 * longest_sq * longest_sq && nn.is_finite();
        let len = nn.sqrt();
        let n = if planar { nr / len } else { Vec3A::ZERO };
        let side = [(b - a).cross(n), (c - b).cross(n), (a - c).cross(n)];
        TrianglePlane {
            a,
            b,
            c,
            aabb: Aabb::from_triangle(a, b, c),
            nr,
            nn,
            n,
            len,
            longest: longest_sq.sqrt(),
            longest_sq,
            planar,
            side,
        }
    }

    /// `true` when the triangle has a plane and both `p` and `q` lie beyond one of its sides by
    /// more than `reach` (measured across the side, in the plane's directions): then the whole
    /// segment is that far from the triangle, which lies entirely on the inner side.
    #[inline]
    fn beyond_a_side(&self, p: Vec3A, q: Vec3A, reach: f32) -> bool {
        if !self.planar {
            return false;
        }
        let corners = [self.a, self.b, self.c];
        (0..3).any(|k| {
            let m = self.side[k];
            let limit = reach * m.length();
            (p - corners[k]).dot(m) > limit && (q - corners[k]).dot(m) > limit
        })
    }

    /// The longest side.
    #[inline]
    pub fn longest(&self) -> f32 {
        self.longest
    }

    /// `true` when the triangle has a plane and the distances `d` all exceed `reach` on one side
    /// of it: then no edge between these points with a reach of at most `reach` passes the first
    /// test of [`edge_against`].
    #[inline]
    pub fn all_beyond(&self, d: [f32; 3], reach: f32) -> bool {
        self.planar
            && ((d[0] > reach && d[1] > reach && d[2] > reach)
                || (d[0] < -reach && d[1] < -reach && d[2] < -reach))
    }

    /// Signed distance of `x` to the plane (0 without a plane).
    #[inline]
    pub fn distance(&self, x: Vec3A) -> f32 {
        self.n.dot(x - self.a)
    }
}

/// [`edge_triangle`] with the triangle prepared and the endpoints' plane distances
/// `dp = plane.distance(p)`, `dq = plane.distance(q)` given.
#[inline]
pub(crate) fn edge_against(
    plane: &TrianglePlane,
    p: Vec3A,
    q: Vec3A,
    dp: f32,
    dq: f32,
    tolerance: f32,
) -> Option<EdgeTriangleHit> {
    let TrianglePlane { a, b, c, .. } = *plane;
    let edge_sq = (q - p).length_squared();
    let scale = plane.longest_sq.max(edge_sq).sqrt();
    let reach = tolerance + 1e-6 * scale;
    if plane.planar && ((dp > reach && dq > reach) || (dp < -reach && dq < -reach)) {
        return None;
    }
    if !Aabb::from_segment(p, q).overlaps(&plane.aabb, tolerance) {
        return None;
    }
    // Beyond one of the triangle's sides (by the reach, plus a margin for rounding): the common
    // exit for an edge resting on a neighbouring triangle.
    if plane.beyond_a_side(p, q, 1.001 * reach) {
        return None;
    }
    if plane.planar && ((dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0)) {
        let (nr, nn, n) = (plane.nr, plane.nn, plane.n);
        let s = dp / (dp - dq);
        let x = p + (q - p) * s;
        // The part of the edge within `reach` of the plane lies within `spread` of the crossing
        // point `x`; if `x` is farther than `reach + spread` from the triangle's box (hence from
        // the triangle), no point of the edge is within `reach` of the triangle.
        let spread = reach * ((q - p).length() / (dp - dq).abs());
        if plane.aabb.distance_squared(x) > 4.0 * (reach + spread) * (reach + spread) {
            return None;
        }
        let u = nr.dot((b - x).cross(c - x)) / nn;
        let v = nr.dot((c - x).cross(a - x)) / nn;
        let w = 1.0 - u - v;
        let outside = -(u.min(v).min(w));
        if outside <= BARY_SLACK {
            let (near, far) = if dp.abs() <= dq.abs() {
                (dp, dq)
            } else {
                (dq, dp)
            };
            return Some(EdgeTriangleHit {
                s: s.clamp(0.0, 1.0),
                barycentric: normalized([u, v, w]),
                normal: n * far.signum(),
                depth: near.abs(),
            });
        }
        // The crossing point lies outside the triangle, at least `outside·(2·area/longest side)`
        // from it in the plane. The part of the edge within `reach` of the plane lies within
        // `reach·|q − p|/|dp − dq|` of the crossing point, so if that is still farther than
        // `reach` from the triangle, no point of the edge is within `reach` of it.
        let in_plane = outside * plane.len / plane.longest;
        if in_plane > 2.0 * (reach + spread) {
            return None;
        }
    }
    let (dist2, s, bary, on_edge, on_tri) = if plane.planar {
        closest_segment_planar(plane, p, q, dp, dq)
    } else {
        closest_segment_triangle(p, q, a, b, c)
    };
    if dist2.is_nan() || dist2 > reach * reach {
        return None;
    }
    // Touching to within rounding counts as touching: depth exactly 0.
    let dist = if dist2 <= (1e-6 * scale) * (1e-6 * scale) {
        0.0
    } else {
        dist2.sqrt()
    };
    let normal = if dist > 1e-5 * scale {
        (on_edge - on_tri) / dist
    } else if plane.planar {
        let far = if dp.abs() >= dq.abs() { dp } else { dq };
        if far < 0.0 {
            -plane.n
        } else {
            plane.n
        }
    } else {
        (q - p).any_orthonormal_vector()
    };
    Some(EdgeTriangleHit {
        s,
        barycentric: bary,
        normal,
        depth: 0.0 - dist,
    })
}

/// A closest pair of a segment and a triangle: `(distance², s on the segment, barycentric on the
/// triangle, point on the segment, point on the triangle)`.
type ClosestPair = (f32, f32, [f32; 3], Vec3A, Vec3A);

/// Clamps to `[0, 1]` and rescales to sum 1.
fn normalized(b: [f32; 3]) -> [f32; 3] {
    let c = b.map(|x| x.clamp(0.0, 1.0));
    let sum = c[0] + c[1] + c[2];
    if sum > 0.0 {
        c.map(|x| x / sum)
    } else {
        [1.0 / 3.0; 3]
    }
}

/// [`closest_segment_triangle`] on a prepared plane (`dp`, `dq` the endpoints' plane distances),
/// for a segment that does not cross the triangle's interior: the same closest pair from fewer
/// candidates.
///
/// Each endpoint whose projection on the plane lies inside the triangle (on the inner side of
/// all three sides) is a candidate at its plane distance; each side beyond which the projection
/// of at least one endpoint lies is tested against the segment. No other side can hold the
/// closest point: the closest point `y` of the triangle to a segment point `x` lies on side `k`
/// only if `x`'s projection is beyond side `k`'s line (or `y` is a corner, which the other side
/// through it then covers), and the segment's projection is beyond the line only if an endpoint's
/// is. A segment crossing the plane does so outside the triangle here, so an interior closest
/// point is still at an endpoint. Without a crossing, no point of the segment (and no side,
/// which lies in the plane) is nearer than the nearer endpoint's plane distance: when that
/// endpoint projects inside, it is the answer.
fn closest_segment_planar(
    plane: &TrianglePlane,
    p: Vec3A,
    q: Vec3A,
    dp: f32,
    dq: f32,
) -> ClosestPair {
    let corners = [plane.a, plane.b, plane.c];
    // How far beyond each side's line (scaled by the side's length) each endpoint projects.
    let out_p: [f32; 3] = std::array::from_fn(|k| (p - corners[k]).dot(plane.side[k]));
    let out_q: [f32; 3] = std::array::from_fn(|k| (q - corners[k]).dot(plane.side[k]));
    // Barycentric weights of a projection: corner a's is the (scaled) distance inside side bc.
    let bary = |o: [f32; 3]| [-o[1] / plane.len, -o[2] / plane.len, -o[0] / plane.len];
    let inside = |o: [f32; 3]| o.iter().all(|&x| x <= 0.0);
    let mut best = (f32::INFINITY, 0.0, [1.0 / 3.0; 3], p, p);
    if inside(out_p) {
        best = (dp * dp, 0.0, bary(out_p), p, p - plane.n * dp);
    }
    if inside(out_q) && dq * dq < best.0 {
        best = (dq * dq, 1.0, bary(out_q), q, q - plane.n * dq);
    }
    // Without a sign change, no point of the segment is nearer the plane (in which the sides
    // lie) than the nearer endpoint: when that endpoint projects inside, no side can be closer.
    let one_side = !((dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0));
    if one_side && best.0 <= (dp * dp).min(dq * dq) {
        return best;
    }
    let beyond: [bool; 3] = std::array::from_fn(|k| out_p[k] > 0.0 || out_q[k] > 0.0);
    closer_to_sides(p, q, corners, beyond, best)
}

/// `best` replaced by the closest pair of segment `pq` and side `k` (`corners[k]` to
/// `corners[k + 1]`) wherever that is closer, for the sides `test` selects.
fn closer_to_sides(
    p: Vec3A,
    q: Vec3A,
    corners: [Vec3A; 3],
    test: [bool; 3],
    mut best: ClosestPair,
) -> ClosestPair {
    for k in (0..3).filter(|&k| test[k]) {
        let (s, t, on_seg, on_side) =
            closest_segment_segment(p, q, corners[k], corners[(k + 1) % 3]);
        let d = (on_seg - on_side).length_squared();
        if d < best.0 {
            let mut bary = [0.0; 3];
            bary[k] = 1.0 - t;
            bary[(k + 1) % 3] = t;
            best = (d, s, bary, on_seg, on_side);
        }
    }
    best
}

/// Closest points of segment `pq` and triangle `abc` when the segment does not cross the
/// triangle's interior: `(distance², s on the segment, barycentric on the triangle, point on the
/// segment, point on the triangle)`.
fn closest_segment_triangle(p: Vec3A, q: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> ClosestPair {
    let (tp, bp) = closest_point_on_triangle(p, a, b, c);
    let mut best = ((tp - p).length_squared(), 0.0, bp, p, tp);
    let (tq, bq) = closest_point_on_triangle(q, a, b, c);
    let dq = (tq - q).length_squared();
    if dq < best.0 {
        best = (dq, 1.0, bq, q, tq);
    }
    // Both endpoints over the triangle's interior (and, here, not crossing it there): every
    // point of the segment is over the interior, its distance to the plane is linear along the
    // segment, so the nearer endpoint is the closest point and no side can be closer.
    if bp.iter().chain(&bq).all(|&x| x > 0.0) {
        return best;
    }
    closer_to_sides(p, q, [a, b, c], [true; 3], best)
}

/// Closest points of segments `p1q1` and `p2q2` (Ericson, *Real-Time Collision Detection* 5.1.9):
/// `(s, t, p1 + s(q1 − p1), p2 + t(q2 − p2))`, parallel and point-like segments included.
pub(crate) fn closest_segment_segment(
    p1: Vec3A,
    q1: Vec3A,
    p2: Vec3A,
    q2: Vec3A,
) -> (f32, f32, Vec3A, Vec3A) {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(r);
    let tiny = f32::MIN_POSITIVE;
    let (s, t) = if a <= tiny && e <= tiny {
        (0.0, 0.0)
    } else if a <= tiny {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= tiny {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (s, t, p1 + d1 * s, p2 + d2 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_segment_crossing_parallel_and_degenerate() {
        let (s, t, c1, c2) = closest_segment_segment(
            Vec3A::new(-1.0, 0.0, 0.0),
            Vec3A::new(1.0, 0.0, 0.0),
            Vec3A::new(0.0, -1.0, 1.0),
            Vec3A::new(0.0, 1.0, 1.0),
        );
        assert_eq!((s, t), (0.5, 0.5));
        assert!((c1 - c2).length() - 1.0 < 1e-6);
        // Parallel: some pair at the right distance.
        let (_, _, c1, c2) = closest_segment_segment(
            Vec3A::ZERO,
            Vec3A::X,
            Vec3A::new(0.5, 0.0, 2.0),
            Vec3A::new(1.5, 0.0, 2.0),
        );
        assert!(((c1 - c2).length() - 2.0).abs() < 1e-6);
        // A point against a segment.
        let (_, t, _, c2) =
            closest_segment_segment(Vec3A::Y, Vec3A::Y, Vec3A::ZERO, Vec3A::new(2.0, 0.0, 0.0));
        assert_eq!(t, 0.0);
        assert_eq!(c2, Vec3A::ZERO);
    }

    /// Deterministic pseudo-random points (xorshift), so the check needs no dependency.
    fn points(seed: &mut u64, n: usize, scale: f32) -> Vec<Vec3A> {
        (0..n)
            .map(|_| {
                Vec3A::from_array(std::array::from_fn(|_| {
                    *seed ^= *seed << 13;
                    *seed ^= *seed >> 7;
                    *seed ^= *seed << 17;
                    ((*seed >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * scale
                }))
            })
            .collect()
    }

    #[test]
    fn planar_closest_pair_matches_the_five_candidate_search() {
        let mut seed = 0x9E37_79B9_7F4A_7C15u64;
        let mut tested = 0;
        for _ in 0..20_000 {
            let v = points(&mut seed, 5, 2.0);
            let (p, q, a, b, c) = (v[0], v[1], v[2], v[3], v[4]);
            let plane = TrianglePlane::new(a, b, c);
            let (dp, dq) = (plane.distance(p), plane.distance(q));
            if !plane.planar {
                continue;
            }
            // A segment crossing the triangle's interior takes the crossing branch instead.
            if (dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0) {
                let x = p + (q - p) * (dp / (dp - dq));
                let (_, bary) = closest_point_on_triangle(x, a, b, c);
                if bary.iter().all(|&w| w > 1e-4) {
                    continue;
                }
            }
            tested += 1;
            let fast = closest_segment_planar(&plane, p, q, dp, dq);
            let slow = closest_segment_triangle(p, q, a, b, c);
            let scale = plane.longest.max((q - p).length());
            assert!(
                (fast.0.sqrt() - slow.0.sqrt()).abs() <= 1e-5 * scale,
                "{p} {q} / {a} {b} {c}: {} vs {}",
                fast.0.sqrt(),
                slow.0.sqrt()
            );
            // The reported points are on the segment and the triangle, at that distance.
            let on_seg = p + (q - p) * fast.1;
            let on_tri = a * fast.2[0] + b * fast.2[1] + c * fast.2[2];
            assert!((on_seg - fast.3).length() <= 1e-5 * scale);
            assert!((on_tri - fast.4).length() <= 1e-5 * scale);
        }
        assert!(tested > 10_000, "{tested}");
    }

    #[test]
    fn normalized_clamps_and_sums_to_one() {
        let b = normalized([-1e-6, 0.5, 0.500001]);
        assert!(b.iter().all(|&x| (0.0..=1.0).contains(&x)));
        assert!((b.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    }
}
