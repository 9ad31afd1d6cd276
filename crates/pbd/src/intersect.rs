//! Exact count of intersecting triangle pairs of a surface (issue 35): the measure the
//! self-collision is judged by, on positions and triangles alone (no body needed).
//!
//! ## What counts as an intersection
//! Triangles are closed sets, tested in `f64` on the given (`f32`) corners with Möller's method
//! (1997): the signed distances of each triangle's corners to the other's plane, then the
//! overlap of the two intervals the triangles cut on the line where the planes meet; coplanar
//! pairs in 2D (the plane's dominant axis dropped). What two triangles share is read from their
//! **indices**, never from coinciding positions:
//! - no shared vertex: any common point counts, touching included (two walls of a fresh cut,
//!   their nodes duplicated at one place, do intersect: the self-collision parts them);
//! - one shared vertex `s`: they count only if they share more than `s`: not coplanar, the two
//!   intervals (both contain `s`'s parameter exactly) overlap over a positive length; coplanar,
//!   their wedges at `s` overlap in their interiors (the surface folded flat onto itself);
//! - two shared vertices (an edge): only if coplanar with the two opposite corners on the same
//!   side of the edge (folded back flat); otherwise they meet only along the edge;
//! - three shared vertices (one face twice): never.
//!
//! The pairs are found with a [`tissue_bvh::Bvh`] over the triangles (leaf pairs of the
//! hierarchy with itself, each unordered pair once); [`intersecting_pairs_brute_force`] is the
//! O(n²) reference the tests compare with.

use glam::{DVec2, DVec3, Vec3A};
use tissue_bvh::{Aabb, BuildOptions, Bvh, BvhWorkspace, Triangles};

use crate::PbdError;

/// Checks the triangles' indices and the positions they use.
fn check(positions: &[Vec3A], triangles: &[[u32; 3]]) -> Result<(), PbdError> {
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            let Some(p) = positions.get(v as usize) else {
                return Err(PbdError::NodeOutOfRange {
                    element: "triangle",
                    index: t,
                    node: v,
                    count: positions.len(),
                });
            };
            if !p.is_finite() {
                return Err(PbdError::NonFinite {
                    node: v,
                    what: "position",
                });
            }
        }
    }
    Ok(())
}

/// Every unordered pair `[i, j]`, `i < j`, of `triangles` (indices into `positions`, cm) that
/// intersect in the sense of the module doc, sorted; found with a hierarchy.
///
/// # Errors
/// [`PbdError::NodeOutOfRange`] for a triangle naming a missing position,
/// [`PbdError::NonFinite`] for a non-finite position it uses.
pub fn intersecting_pairs(
    positions: &[Vec3A],
    triangles: &[[u32; 3]],
) -> Result<Vec<[u32; 2]>, PbdError> {
    let _span = tracing::debug_span!("intersecting_pairs", triangles = triangles.len()).entered();
    check(positions, triangles)?;
    let mut out = Vec::new();
    if triangles.len() < 2 {
        return Ok(out);
    }
    let prims = Triangles::new(positions, triangles).map_err(|_| PbdError::NodeOutOfRange {
        element: "triangle",
        index: 0,
        node: u32::MAX,
        count: positions.len(),
    })?;
    // Only the count can fail here (indices and positions were checked).
    let Ok(bvh) = Bvh::build(&prims, &BuildOptions::default()) else {
        return intersecting_pairs_brute_force(positions, triangles);
    };
    let mut ws = BvhWorkspace::new();
    let mut leaves = Vec::new();
    bvh.leaf_pairs(&bvh, 0.0, &mut ws, &mut leaves);
    let boxes: Vec<Aabb> = triangles
        .iter()
        .map(|t| {
            Aabb::from_triangle(
                positions[t[0] as usize],
                positions[t[1] as usize],
                positions[t[2] as usize],
            )
        })
        .collect();
    for &[a, b] in &leaves {
        if a > b {
            continue;
        }
        let (la, lb) = (bvh.leaf_primitives(a), bvh.leaf_primitives(b));
        for (k, &i) in la.iter().enumerate() {
            let others = if a == b { &lb[k + 1..] } else { lb };
            for &j in others {
                if boxes[i as usize].overlaps(&boxes[j as usize], 0.0)
                    && triangles_intersect(positions, triangles[i as usize], triangles[j as usize])
                {
                    out.push([i.min(j), i.max(j)]);
                }
            }
        }
    }
    out.sort_unstable();
    Ok(out)
}

/// The number of [`intersecting_pairs`].
///
/// # Errors
/// As [`intersecting_pairs`].
pub fn count_intersecting_pairs(
    positions: &[Vec3A],
    triangles: &[[u32; 3]],
) -> Result<usize, PbdError> {
    intersecting_pairs(positions, triangles).map(|p| p.len())
}

/// [`intersecting_pairs`] by testing every pair (O(n²)): the reference.
///
/// # Errors
/// As [`intersecting_pairs`].
pub fn intersecting_pairs_brute_force(
    positions: &[Vec3A],
    triangles: &[[u32; 3]],
) -> Result<Vec<[u32; 2]>, PbdError> {
    check(positions, triangles)?;
    let mut out = Vec::new();
    for (i, &a) in triangles.iter().enumerate() {
        for (j, &b) in triangles.iter().enumerate().skip(i + 1) {
            if triangles_intersect(positions, a, b) {
                out.push([i as u32, j as u32]);
            }
        }
    }
    Ok(out)
}

/// Whether triangles `a` and `b` (indices into `positions`) intersect in the sense of the module
/// doc. Indices must be in range (unchecked here: out-of-range indices give `false`).
pub fn triangles_intersect(positions: &[Vec3A], a: [u32; 3], b: [u32; 3]) -> bool {
    let get = |t: [u32; 3]| -> Option<[DVec3; 3]> {
        Some([
            positions.get(t[0] as usize)?.as_dvec3(),
            positions.get(t[1] as usize)?.as_dvec3(),
            positions.get(t[2] as usize)?.as_dvec3(),
        ])
    };
    let (Some(p), Some(q)) = (get(a), get(b)) else {
        return false;
    };
    // Which corners are shared: `sa[i]` = the corner of `b` equal to `a[i]`.
    let mut sa = [None; 3];
    let mut shared = 0;
    for i in 0..3 {
        sa[i] = b.iter().position(|&v| v == a[i]);
        shared += usize::from(sa[i].is_some());
    }
    let sb = |j: usize| a.iter().position(|&v| v == b[j]);
    match shared {
        0 => general(p, q, [false; 3], [false; 3], false),
        1 => {
            let (ia, ib) = match (0..3).find_map(|i| sa[i].map(|j| (i, j))) {
                Some(x) => x,
                None => return false,
            };
            let mut za = [false; 3];
            let mut zb = [false; 3];
            za[ia] = true;
            zb[ib] = true;
            general(p, q, za, zb, true)
        }
        2 => {
            // The corner of each not on the shared edge.
            let (Some(oa), Some(ob)) = (
                (0..3).find(|&i| sa[i].is_none()),
                (0..3).find(|&j| sb(j).is_none()),
            ) else {
                return false;
            };
            let Some(e0) = (0..3).find(|&i| sa[i].is_some()) else {
                return false;
            };
            let Some(e1) = (e0 + 1..3).find(|&i| sa[i].is_some()) else {
                return false;
            };
            let (s0, s1) = (p[e0], p[e1]);
            let n = (s1 - s0).cross(p[oa] - s0);
            if n.dot(q[ob] - s0) != 0.0 {
                return false;
            }
            // Coplanar: the same side of the edge.
            (s1 - s0).cross(p[oa] - s0).dot((s1 - s0).cross(q[ob] - s0)) > 0.0
        }
        _ => false,
    }
}

/// `(b − a) × (c − a) · (d − a)`.
fn orient(t: &[DVec3; 3], d: DVec3) -> f64 {
    (t[1] - t[0]).cross(t[2] - t[0]).dot(d - t[0])
}

/// Distances (scaled) of `of`'s corners to `plane`'s plane; corners flagged `zero` (shared) are
/// exactly on it.
fn distances(plane: &[DVec3; 3], of: &[DVec3; 3], zero: [bool; 3]) -> [f64; 3] {
    let mut d = [0.0; 3];
    for i in 0..3 {
        if !zero[i] {
            d[i] = orient(plane, of[i]);
        }
    }
    d
}

fn same_strict_sign(d: [f64; 3]) -> bool {
    (d[0] > 0.0 && d[1] > 0.0 && d[2] > 0.0) || (d[0] < 0.0 && d[1] < 0.0 && d[2] < 0.0)
}

/// The interval triangle `t` (distances `d` to the other plane) cuts on the line of direction
/// `dir`, as parameters `dir · x`.
fn interval(t: &[DVec3; 3], d: [f64; 3], dir: DVec3) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut add = |x: f64| {
        lo = lo.min(x);
        hi = hi.max(x);
    };
    for i in 0..3 {
        if d[i] == 0.0 {
            add(dir.dot(t[i]));
        }
        let j = (i + 1) % 3;
        if (d[i] > 0.0 && d[j] < 0.0) || (d[i] < 0.0 && d[j] > 0.0) {
            let s = d[i] / (d[i] - d[j]);
            add(dir.dot(t[i] + (t[j] - t[i]) * s));
        }
    }
    (lo, hi)
}

/// Möller's test with the shared corners' distances exactly zero; `one_shared`: count only an
/// overlap beyond the shared vertex.
fn general(p: [DVec3; 3], q: [DVec3; 3], zp: [bool; 3], zq: [bool; 3], one_shared: bool) -> bool {
    let dq = distances(&p, &q, zq);
    if same_strict_sign(dq) {
        return false;
    }
    let dp = distances(&q, &p, zp);
    if same_strict_sign(dp) {
        return false;
    }
    if dq == [0.0; 3] || dp == [0.0; 3] {
        return coplanar(p, q, zp, zq, one_shared);
    }
    let dir = (p[1] - p[0])
        .cross(p[2] - p[0])
        .cross((q[1] - q[0]).cross(q[2] - q[0]));
    let (a0, a1) = interval(&p, dp, dir);
    let (b0, b1) = interval(&q, dq, dir);
    let (lo, hi) = (a0.max(b0), a1.min(b1));
    if one_shared {
        hi > lo
    } else {
        hi >= lo
    }
}

/// `(b − a) × (c − a)` in 2D.
fn orient2(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether closed segments `ab` and `cd` meet (2D).
fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (o1, o2) = (orient2(a, b, c), orient2(a, b, d));
    let (o3, o4) = (orient2(c, d, a), orient2(c, d, b));
    let on = |a: DVec2, b: DVec2, p: DVec2| {
        p.x >= a.x.min(b.x) && p.x <= a.x.max(b.x) && p.y >= a.y.min(b.y) && p.y <= a.y.max(b.y)
    };
    if o1 == 0.0 && on(a, b, c) || o2 == 0.0 && on(a, b, d) {
        return true;
    }
    if o3 == 0.0 && on(c, d, a) || o4 == 0.0 && on(c, d, b) {
        return true;
    }
    (o1 > 0.0) != (o2 > 0.0)
        && o1 != 0.0
        && o2 != 0.0
        && (o3 > 0.0) != (o4 > 0.0)
        && o3 != 0.0
        && o4 != 0.0
}

/// Whether `x` is in the closed triangle `t` (2D, either orientation).
fn inside(t: [DVec2; 3], x: DVec2) -> bool {
    let o = [
        orient2(t[0], t[1], x),
        orient2(t[1], t[2], x),
        orient2(t[2], t[0], x),
    ];
    (o[0] >= 0.0 && o[1] >= 0.0 && o[2] >= 0.0) || (o[0] <= 0.0 && o[1] <= 0.0 && o[2] <= 0.0)
}

/// Whether direction `x − s` is strictly inside the (convex, < π) wedge `(a − s, b − s)`.
fn in_wedge(s: DVec2, a: DVec2, b: DVec2, x: DVec2) -> bool {
    let w = orient2(s, a, b);
    let (u, v) = (orient2(s, a, x), orient2(s, x, b));
    (w > 0.0 && u > 0.0 && v > 0.0) || (w < 0.0 && u < 0.0 && v < 0.0)
}

/// The coplanar case, in the plane with `p`'s normal's dominant axis dropped.
fn coplanar(p: [DVec3; 3], q: [DVec3; 3], zp: [bool; 3], zq: [bool; 3], one_shared: bool) -> bool {
    let n = (p[1] - p[0]).cross(p[2] - p[0]).abs();
    let flat = |v: DVec3| {
        if n.x >= n.y && n.x >= n.z {
            DVec2::new(v.y, v.z)
        } else if n.y >= n.z {
            DVec2::new(v.x, v.z)
        } else {
            DVec2::new(v.x, v.y)
        }
    };
    let (a, b) = (p.map(flat), q.map(flat));
    if one_shared {
        // The wedges at the shared corner overlap in their interiors.
        let (Some(i), Some(j)) = ((0..3).find(|&i| zp[i]), (0..3).find(|&j| zq[j])) else {
            return false;
        };
        let s = a[i];
        let (a1, a2) = (a[(i + 1) % 3], a[(i + 2) % 3]);
        let (b1, b2) = (b[(j + 1) % 3], b[(j + 2) % 3]);
        if in_wedge(s, a1, a2, b1)
            || in_wedge(s, a1, a2, b2)
            || in_wedge(s, b1, b2, a1)
            || in_wedge(s, b1, b2, a2)
        {
            return true;
        }
        // The same wedge (its two rays along each other's).
        let along = |u: DVec2, v: DVec2| orient2(s, u, v) == 0.0 && (u - s).dot(v - s) > 0.0;
        return (along(a1, b1) && along(a2, b2)) || (along(a1, b2) && along(a2, b1));
    }
    for i in 0..3 {
        for j in 0..3 {
            if segments_meet(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]) {
                return true;
            }
        }
    }
    inside(a, b[0]) || inside(b, a[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32) -> Vec3A {
        Vec3A::new(x, y, z)
    }

    #[test]
    fn hand_made_cases() {
        // Two crossing triangles.
        let p = vec![
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(0.0, 2.0, 0.0),
            v(0.5, 0.5, -1.0),
            v(0.5, 0.5, 1.0),
            v(3.0, 3.0, 0.0),
        ];
        assert!(triangles_intersect(&p, [0, 1, 2], [3, 4, 5]));
        // Lifted clear of the plane: no.
        let mut lifted = p.clone();
        for x in &mut lifted[3..] {
            x.z += 1.5;
        }
        assert!(!triangles_intersect(&lifted, [0, 1, 2], [3, 4, 5]));
        // Touching at an edge (no shared index): counts.
        let touch = vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 0.0, 1.0),
        ];
        assert!(triangles_intersect(&touch, [0, 1, 2], [3, 4, 5]));
        // The same, sharing the edge by index: not an intersection.
        assert!(!triangles_intersect(&touch, [0, 1, 2], [0, 1, 5]));
        // Coplanar overlap, then coplanar apart.
        let cop = vec![
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(0.0, 2.0, 0.0),
            v(0.5, 0.5, 0.0),
            v(3.0, 0.5, 0.0),
            v(0.5, 3.0, 0.0),
            v(5.0, 5.0, 0.0),
            v(6.0, 5.0, 0.0),
            v(5.0, 6.0, 0.0),
        ];
        assert!(triangles_intersect(&cop, [0, 1, 2], [3, 4, 5]));
        assert!(!triangles_intersect(&cop, [0, 1, 2], [6, 7, 8]));
        // One shared vertex: a fan around it does not intersect; a fold through it does.
        let fan = vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(0.0, -1.0, 0.3),
            v(0.5, 0.5, 1.0),
            v(0.5, 0.5, -1.0),
        ];
        assert!(!triangles_intersect(&fan, [0, 1, 2], [0, 3, 4]));
        assert!(triangles_intersect(&fan, [0, 1, 2], [0, 5, 6]));
        // Coplanar with one shared vertex: adjacent wedges no, overlapping wedges yes.
        let wedge = vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(-1.0, 1.0, 0.0),
            v(1.0, 1.0, 0.0),
        ];
        assert!(!triangles_intersect(&wedge, [0, 1, 2], [0, 2, 3]));
        assert!(triangles_intersect(&wedge, [0, 1, 2], [0, 4, 3]));
        // Shared edge folded flat onto itself, and opened.
        let fold = vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.5, 1.0, 0.0),
            v(0.3, 0.8, 0.0),
            v(0.5, -1.0, 0.0),
        ];
        assert!(triangles_intersect(&fold, [0, 1, 2], [1, 0, 3]));
        assert!(!triangles_intersect(&fold, [0, 1, 2], [1, 0, 4]));
    }
}
