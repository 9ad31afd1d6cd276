//! Interior points: a body-centred cubic (BCC) lattice clipped to the surface.
//!
//! The BCC lattice — cube corners `a·(i, j, k)` plus cube centres `a·(i+½, j+½, k+½)` — has a
//! unique Delaunay tetrahedralisation made of congruent tetrahedra with dihedral angles of 60°
//! and 90° (radius ratio 0.84), so the interior of the model gets good elements without
//! smoothing. A lattice point is kept when it is inside the surface ([`RayCaster`]) and
//! - at least `clearance · a` from every surface triangle, so the layer between the lattice and
//!   the surface is not squashed, and
//! - outside every surface triangle's *protecting ball* (centred at the triangle's circumcentre,
//!   through its corners; only for triangles whose circumradius is at most `a`, since a very
//!   obtuse triangle's ball is huge): a triangle whose ball is empty of other points
//!   is a face of the Delaunay tetrahedralisation, so the lattice never hides a surface
//!   triangle that the surface's own vertices leave visible.
//!
//! Points are rounded to `f32` before any test, so the Delaunay predicates see the coordinates
//! the mesh will store.

use crate::inside::{distance_sq_to_triangle, RayCaster, SurfaceGrid};
use crate::predicates::P3;

/// Circumcentre and circumradius of a triangle (`None` when it is flat).
fn circumcircle([a, b, c]: &[P3; 3]) -> Option<(P3, f64)> {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ac = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [
        ab[1] * ac[2] - ab[2] * ac[1],
        ab[2] * ac[0] - ab[0] * ac[2],
        ab[0] * ac[1] - ab[1] * ac[0],
    ];
    let nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if nn <= 0.0 {
        return None;
    }
    let l_ab = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    let l_ac = ac[0] * ac[0] + ac[1] * ac[1] + ac[2] * ac[2];
    // centre − a = (|ac|² (n × ab) + |ab|² (ac × n)) / (2 |n|²)
    let n_ab = [
        n[1] * ab[2] - n[2] * ab[1],
        n[2] * ab[0] - n[0] * ab[2],
        n[0] * ab[1] - n[1] * ab[0],
    ];
    let ac_n = [
        ac[1] * n[2] - ac[2] * n[1],
        ac[2] * n[0] - ac[0] * n[2],
        ac[0] * n[1] - ac[1] * n[0],
    ];
    let off = [0, 1, 2].map(|k| (l_ac * n_ab[k] + l_ab * ac_n[k]) / (2.0 * nn));
    let r = (off[0] * off[0] + off[1] * off[1] + off[2] * off[2]).sqrt();
    Some(([0, 1, 2].map(|k| a[k] + off[k]), r))
}

/// The BCC lattice points of spacing `spacing` inside the surface `tris` that pass the filters of
/// the module doc, in lattice order (`f32`-exact `f64` coordinates).
pub(crate) fn interior_points(
    tris: &[[P3; 3]],
    caster: &RayCaster,
    spacing: f64,
    clearance: f64,
) -> Vec<P3> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in tris {
        for p in t {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let balls: Vec<Option<(P3, f64)>> = tris
        .iter()
        .map(|t| circumcircle(t).filter(|b| b.1 <= spacing))
        .collect();
    let keep_off = clearance * spacing;
    let grid = SurfaceGrid::new(tris, spacing, |t| {
        keep_off.max(balls[t].map_or(0.0, |b| 2.0 * b.1))
    });
    // Lattice centred in the bounding box.
    let counts = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / spacing).floor() as i64);
    let origin = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]) - 0.5 * counts[k] as f64 * spacing);
    let mut out = Vec::new();
    for half in [0.0, 0.5] {
        for i in -1..=counts[0] + 1 {
            for j in -1..=counts[1] + 1 {
                for k in -1..=counts[2] + 1 {
                    let q = [i, j, k].map(|x| x as f64 + half);
                    let p: P3 = [0, 1, 2].map(|d| f64::from((origin[d] + q[d] * spacing) as f32));
                    if !(0..3).all(|d| p[d] > lo[d] && p[d] < hi[d]) || !caster.is_inside(&p) {
                        continue;
                    }
                    let blocked = grid.near(&p).iter().any(|&t| {
                        let t = t as usize;
                        distance_sq_to_triangle(&p, &tris[t]) < keep_off * keep_off
                            || balls[t].is_some_and(|(c, r)| {
                                let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
                                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r * r
                            })
                    });
                    if !blocked {
                        out.push(p);
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circumcircle_of_right_triangle_is_on_hypotenuse() {
        let (c, r) = circumcircle(&[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]).unwrap();
        assert!((c[0] - 1.0).abs() < 1e-12 && (c[1] - 1.0).abs() < 1e-12 && c[2].abs() < 1e-12);
        assert!((r - 2f64.sqrt()).abs() < 1e-12);
        assert!(circumcircle(&[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]).is_none());
    }
}
