//! Carving: keep the Delaunay tetrahedra whose centroid is inside the surface.

use crate::delaunay::Delaunay;
use crate::inside::RayCaster;
use crate::predicates::P3;

/// Centroid of a tetrahedron in `f64`.
fn centroid(pts: &[P3], t: &[u32; 4]) -> P3 {
    let mut c = [0.0; 3];
    for &v in t {
        let p = pts[v as usize];
        for k in 0..3 {
            c[k] += 0.25 * p[k];
        }
    }
    c
}

/// The tetrahedra of `dt` (not using the super-tetrahedron) whose centroid `caster` finds
/// inside, as indices into `dt.pts`.
pub(crate) fn carve(dt: &Delaunay, caster: &RayCaster) -> Vec<[u32; 4]> {
    let tets: Vec<[u32; 4]> = dt
        .finite_tets()
        .filter(|(_, v)| caster.is_inside(&centroid(&dt.pts, v)))
        .map(|(_, v)| v)
        .collect();
    tracing::debug!(kept = tets.len(), "carved");
    tets
}
