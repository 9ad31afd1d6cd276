//! Measures of a [`TriMesh`]: areas, normals, centroid, bounding box, enclosed volume, and the
//! volume between two open surfaces that share their boundary (the thesis's "volume difference",
//! SPEC A.5 step 5).
//!
//! Units: lengths are in the units of the positions (cm in tissue), areas in their square (cm²),
//! volumes in their cube (cm³ = mL). Positions are `f32`; every product and sum below is formed
//! in `f64` ([`glam::DVec3`]).
//!
//! ## Equations
//! For a triangle `t = (a, b, c)` wound counter-clockwise seen from the side its normal points to:
//! - area vector `N_t = (b − a) × (c − a) / 2`, area `A_t = |N_t|`, unit normal `N_t / A_t`;
//! - mesh area `A = Σ_t A_t`; area-weighted centroid `Σ_t A_t (a + b + c)/3 / A` (the centre of
//!   mass of a thin uniform shell, not of the enclosed solid);
//! - vertex normal: `Σ_{t∋v} 2 N_t`, normalised (larger triangles weigh more).
//!
//! **Signed volume** (divergence theorem, `V = ⅓ ∮ (x − r)·n dA`, exact for flat triangles): the sum
//! of the signed tetrahedra spanned by a reference point `r` and each triangle,
//!
//! `V = Σ_t (a − r)·((b − r) × (c − r)) / 6`.
//!
//! Expanding the product gives, exactly, `V(r) = V(0) − r·N / 3` with `N = Σ_t N_t` the surface's
//! vector area. `N` depends only on the boundary (`N = ½ Σ_{(p,q) ∈ ∂} p × q` over the boundary
//! edges), so on a closed surface `N = 0` and `V` is independent of `r`. We take `r` = the centre
//! of the bounding box so that the terms are of the size of the mesh rather than of its distance
//! from the origin (far from the origin `V(0)` would be a difference of huge terms). `V > 0` when
//! the normals point outward.
//!
//! **Volume between two surfaces** `before` and `after`, open, with the same boundary `∂`
//! ([`volume_between`]): the closed surface `S = after ∪ reverse(before)` (before's triangles with
//! their winding reversed) encloses the region between them, and
//!
//! `ΔV = Σ_{t ∈ after} T_r(t) − Σ_{t ∈ before} T_r(t)`, `T_r(a, b, c) = (a − r)·((b − r) × (c − r)) / 6`.
//!
//! By the identity above, `ΔV(r) = ΔV(0) − r·(N_after − N_before)/3`: the result is independent of
//! `r` exactly when the two boundaries coincide, which is why [`volume_between`] checks them and
//! welds `after`'s boundary onto `before`'s. `ΔV > 0` when `after` lies on the side `before`'s
//! normals point to (a skin region pushed outward by an implant gives a positive volume when the
//! region's normals point out of the body). Where the surfaces cross, volumes on the two sides
//! cancel: the result is the signed (net) volume.

use glam::{DVec3, Vec3};

use crate::{Aabb, MeshError, TriMesh};

/// Boundary vertices of the two surfaces given to [`volume_between`] count as the same point when
/// they are at most this fraction of the diagonal of `before`'s bounding box apart (`1e-5`: 2 µm
/// on a 20 cm region, above the rounding of `f32` and of 6-digit text files, far below a mesh
/// edge).
pub const BOUNDARY_TOLERANCE: f64 = 1e-5;

/// Twice the area vector of a triangle, `(b − a) × (c − a)`, in `f64`.
#[inline]
fn doubled_area_vector([a, b, c]: [Vec3; 3]) -> DVec3 {
    let a = a.as_dvec3();
    (b.as_dvec3() - a).cross(c.as_dvec3() - a)
}

/// Six times the signed volume of the tetrahedron `(0, a, b, c)`.
#[inline]
fn triple(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    a.dot(b.cross(c))
}

/// `Σ_t (a − r)·((b − r) × (c − r))`: six times the divergence-theorem volume about `reference`.
/// The indices must be valid (as in a [`TriMesh`]).
pub(crate) fn sixfold_volume_about(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    reference: DVec3,
) -> f64 {
    let at = |i: u32| positions[i as usize].as_dvec3() - reference;
    let mut sum = 0.0;
    for &[a, b, c] in triangles {
        sum += triple(at(a), at(b), at(c));
    }
    sum
}

/// `Σ_t a·(b × c)` over positions already made relative to the reference point.
fn sixfold_volume_relative(relative: &[DVec3], triangles: &[[u32; 3]]) -> f64 {
    let mut sum = 0.0;
    for &[a, b, c] in triangles {
        sum += triple(
            relative[a as usize],
            relative[b as usize],
            relative[c as usize],
        );
    }
    sum
}

/// The centre of the bounding box in `f64`.
fn box_center(mesh: &TriMesh) -> DVec3 {
    let b = mesh.bounding_box();
    (b.min.as_dvec3() + b.max.as_dvec3()) * 0.5
}

impl TriMesh {
    /// Area of each triangle, `|(b − a) × (c − a)| / 2`, in the positions' units squared.
    pub fn triangle_areas(&self) -> Vec<f64> {
        (0..self.triangle_count())
            .map(|t| 0.5 * doubled_area_vector(self.corners(t)).length())
            .collect()
    }

    /// Total area `Σ_t A_t`, summed in `f64` in triangle order.
    pub fn area(&self) -> f64 {
        let mut sum = 0.0;
        for t in 0..self.triangle_count() {
            sum += 0.5 * doubled_area_vector(self.corners(t)).length();
        }
        sum
    }

    /// Unit normal of each triangle, on the side from which it is wound counter-clockwise.
    /// `Vec3::ZERO` for a triangle of zero area (possible after [`TriMesh::with_positions`]).
    pub fn triangle_normals(&self) -> Vec<Vec3> {
        (0..self.triangle_count())
            .map(|t| {
                doubled_area_vector(self.corners(t))
                    .normalize_or_zero()
                    .as_vec3()
            })
            .collect()
    }

    /// Area-weighted vertex normals: at each vertex the sum of the unnormalised cross products
    /// `(b − a) × (c − a)` of its triangles, normalised. `Vec3::ZERO` for an unreferenced vertex
    /// (or where the sum vanishes).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut sums = vec![DVec3::ZERO; self.vertex_count()];
        for (t, tri) in self.triangles().iter().enumerate() {
            let n = doubled_area_vector(self.corners(t));
            for &v in tri {
                sums[v as usize] += n;
            }
        }
        sums.into_iter()
            .map(|n| n.normalize_or_zero().as_vec3())
            .collect()
    }

    /// Area-weighted centroid of the surface, `Σ_t A_t (a + b + c)/3 / Σ_t A_t`: the centre of
    /// mass of a uniform thin shell on the triangles (for a closed surface this is in general not
    /// the centroid of the enclosed solid). Unreferenced vertices do not count. If every triangle
    /// has zero area (a collapsed deformed state), the plain mean of the triangle centroids.
    pub fn centroid(&self) -> DVec3 {
        let mut weighted = DVec3::ZERO;
        let mut plain = DVec3::ZERO;
        let mut total = 0.0;
        for t in 0..self.triangle_count() {
            let p = self.corners(t);
            let mid = (p[0].as_dvec3() + p[1].as_dvec3() + p[2].as_dvec3()) / 3.0;
            let area = 0.5 * doubled_area_vector(p).length();
            weighted += area * mid;
            plain += mid;
            total += area;
        }
        if total > 0.0 {
            weighted / total
        } else {
            plain / self.triangle_count() as f64
        }
    }

    /// The bounding box of all stored vertices (unreferenced ones included).
    pub fn bounding_box(&self) -> Aabb {
        // A TriMesh has at least one vertex, so the fallback is never taken.
        Aabb::from_points(self.positions()).unwrap_or(Aabb {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
        })
    }

    /// Enclosed volume by the divergence theorem, `Σ_t (a − r)·((b − r) × (c − r)) / 6` with `r`
    /// the centre of the bounding box (see the module equations): positive when the normals point
    /// outward, negative when they point inward. A surface of several closed components gives the
    /// sum of their signed volumes.
    ///
    /// ```
    /// // The thesis's test cube: side 2 cm, 386 vertices, 768 triangles.
    /// let cube = tissue_mesh::subdivided_cube(8, 2.0)?;
    /// assert_eq!(cube.signed_volume()?, 8.0);
    /// # Ok::<(), tissue_mesh::MeshError>(())
    /// ```
    ///
    /// # Errors
    /// [`MeshError::NotClosed`] for a surface with a boundary (an open surface encloses nothing;
    /// for two surfaces sharing a boundary use [`volume_between`]).
    pub fn signed_volume(&self) -> Result<f64, MeshError> {
        let topology = self.topology();
        if !topology.is_closed() {
            return Err(MeshError::NotClosed {
                boundary_edges: topology.boundary_edge_count(),
                loops: topology.boundary_loops().len(),
            });
        }
        Ok(sixfold_volume_about(self.positions(), self.triangles(), box_center(self)) / 6.0)
    }
}

/// The signed volume between two open surfaces with the same boundary (the thesis's volume
/// difference): the divergence-theorem volume of the closed surface made of `after`'s triangles
/// and `before`'s triangles reversed (see the module equations), positive when `after` lies on
/// the side that `before`'s normals point to. The reference point is the centre of `before`'s
/// bounding box.
///
/// The boundaries must coincide: the same number of boundary loops, and each loop of `before`
/// matched by a loop of `after` of the same length, running in the same direction, whose
/// vertices (allowing a cyclic shift of the starting vertex) lie within [`BOUNDARY_TOLERANCE`] ×
/// the diagonal of `before`'s bounding box of `before`'s. `after`'s boundary vertices are then
/// taken at `before`'s positions (welded), so that the joined surface is exactly closed and the
/// result does not depend on the reference point.
///
/// The common case — `after` is `before.with_positions(..)` with its boundary vertices unmoved —
/// is checked vertex by vertex and summed triangle by triangle as `T(after_t) − T(before_t)`, so
/// `volume_between(m, m)` is exactly `0.0` and small differences keep their precision.
///
/// ```
/// use glam::Vec3;
/// use tissue_mesh::{disc, volume_between};
///
/// // A flat disc (normal +z) whose interior vertices are lifted by 1 cm, boundary kept.
/// let before = disc(4, 16, 2.0)?;
/// let on_boundary = before.topology().boundary_vertex_mask(before.vertex_count());
/// let lifted = before
///     .positions()
///     .iter()
///     .zip(&on_boundary)
///     .map(|(&p, &fixed)| if fixed { p } else { p + Vec3::Z })
///     .collect();
/// let after = before.with_positions(lifted)?;
/// let v = volume_between(&before, &after)?;
/// // Positive (lifted along the normals), less than the 1 cm prism over the disc.
/// assert!(v > 0.0 && v < before.area());
/// assert!((volume_between(&after, &before)? + v).abs() < 1e-12); // roles swapped
/// assert_eq!(volume_between(&before, &before)?, 0.0);
/// # Ok::<(), tissue_mesh::MeshError>(())
/// ```
///
/// # Errors
/// - [`MeshError::NotOpen`] when either surface is closed;
/// - [`MeshError::BoundaryMismatch`] when the boundaries differ, saying which loop or vertex.
pub fn volume_between(before: &TriMesh, after: &TriMesh) -> Result<f64, MeshError> {
    volume_between_about(before, after, box_center(before))
}

/// [`volume_between`] about a given reference point.
pub(crate) fn volume_between_about(
    before: &TriMesh,
    after: &TriMesh,
    reference: DVec3,
) -> Result<f64, MeshError> {
    let _span = tracing::debug_span!(
        "volume_between",
        before_triangles = before.triangle_count(),
        after_triangles = after.triangle_count()
    )
    .entered();
    if before.is_closed() {
        return Err(MeshError::NotOpen { surface: "before" });
    }
    if after.is_closed() {
        return Err(MeshError::NotOpen { surface: "after" });
    }
    let tolerance = BOUNDARY_TOLERANCE * f64::from(before.bounding_box().size().length());
    let relative = |p: &Vec3| p.as_dvec3() - reference;
    let before_rel: Vec<DVec3> = before.positions().iter().map(relative).collect();

    // Fast path: the same triangles over the same vertex numbering.
    let mut fixed_boundary_error = None;
    if before.vertex_count() == after.vertex_count() && before.triangles() == after.triangles() {
        match check_fixed_boundary(before, after, tolerance) {
            Ok(()) => {
                let on_boundary = before
                    .topology()
                    .boundary_vertex_mask(before.vertex_count());
                let after_rel: Vec<DVec3> = after
                    .positions()
                    .iter()
                    .zip(&before_rel)
                    .zip(&on_boundary)
                    .map(|((p, &b), &fixed)| if fixed { b } else { relative(p) })
                    .collect();
                let mut sum = 0.0;
                for &[a, b, c] in before.triangles() {
                    let (a, b, c) = (a as usize, b as usize, c as usize);
                    sum += triple(after_rel[a], after_rel[b], after_rel[c])
                        - triple(before_rel[a], before_rel[b], before_rel[c]);
                }
                return Ok(sum / 6.0);
            }
            // The boundary may still match up to a renumbering (e.g. rotated along itself).
            Err(e) => fixed_boundary_error = Some(e),
        }
    }

    let weld = match match_boundaries(before, after, tolerance) {
        Ok(weld) => weld,
        Err(e) => return Err(fixed_boundary_error.unwrap_or(e)),
    };
    let mut after_rel: Vec<DVec3> = after.positions().iter().map(relative).collect();
    for (a, b) in weld {
        after_rel[a as usize] = before_rel[b as usize];
    }
    let sum = sixfold_volume_relative(&after_rel, after.triangles())
        - sixfold_volume_relative(&before_rel, before.triangles());
    Ok(sum / 6.0)
}

fn mismatch(reason: String) -> MeshError {
    MeshError::BoundaryMismatch { reason }
}

/// Same triangles: every boundary vertex of `before` must be where it was.
fn check_fixed_boundary(
    before: &TriMesh,
    after: &TriMesh,
    tolerance: f64,
) -> Result<(), MeshError> {
    for (i, boundary_loop) in before.topology().boundary_loops().iter().enumerate() {
        for &v in boundary_loop {
            let (p, q) = (
                before.positions()[v as usize],
                after.positions()[v as usize],
            );
            let distance = (q.as_dvec3() - p.as_dvec3()).length();
            if distance > tolerance {
                return Err(mismatch(format!(
                    "boundary vertex {v} (boundary loop {i}) moved by {distance:e}, from {:?} to {:?}, \
                     more than the tolerance {tolerance:e}: keep the boundary vertices fixed",
                    p.to_array(),
                    q.to_array()
                )));
            }
        }
    }
    Ok(())
}

/// Matches every boundary loop of `before` with one of `after` (same length, same direction, a
/// cyclic shift, positions within `tolerance`). Returns `(after vertex, before vertex)` pairs.
fn match_boundaries(
    before: &TriMesh,
    after: &TriMesh,
    tolerance: f64,
) -> Result<Vec<(u32, u32)>, MeshError> {
    let (before_loops, after_loops) = (
        before.topology().boundary_loops(),
        after.topology().boundary_loops(),
    );
    if before_loops.len() != after_loops.len() {
        return Err(mismatch(format!(
            "before has {} boundary loops, after has {}",
            before_loops.len(),
            after_loops.len()
        )));
    }
    let (bp, ap) = (before.positions(), after.positions());
    let distance =
        |a: u32, b: u32| (ap[a as usize].as_dvec3() - bp[b as usize].as_dvec3()).length();
    let close = |a: u32, b: u32| distance(a, b) <= tolerance;
    let mut used = vec![false; after_loops.len()];
    let mut weld = Vec::new();
    for (i, lb) in before_loops.iter().enumerate() {
        let n = lb.len();
        // First position q where after's loop `la` started at `k` (step ±1) leaves before's loop.
        let first_miss = |la: &[u32], k: usize, forward: bool| {
            (0..n).find(|&q| {
                let at = if forward {
                    (k + q) % n
                } else {
                    (k + n - q) % n
                };
                !close(la[at], lb[q])
            })
        };
        let mut found = None;
        let mut reversed = None;
        // (matched vertices, after loop, start) of the longest partial match, for the message.
        let mut best: Option<(usize, usize, usize)> = None;
        'search: for (j, la) in after_loops.iter().enumerate() {
            if used[j] || la.len() != n {
                continue;
            }
            for k in (0..n).filter(|&k| close(la[k], lb[0])) {
                match first_miss(la, k, true) {
                    None => {
                        found = Some((j, k));
                        break 'search;
                    }
                    Some(q) => {
                        if best.is_none_or(|(m, _, _)| q > m) {
                            best = Some((q, j, k));
                        }
                    }
                }
                if n > 2 && first_miss(la, k, false).is_none() {
                    reversed = Some(j);
                }
            }
        }
        let Some((j, k)) = found else {
            let start = lb[0];
            let head = format!(
                "before's boundary loop {i} ({n} vertices, from vertex {start} at {:?})",
                bp[start as usize].to_array()
            );
            let reason = if let Some(j) = reversed {
                format!(
                    "{head} matches after's boundary loop {j} only in the opposite direction: \
                     the normals of one surface are flipped"
                )
            } else if let Some((q, j, k)) = best {
                let (bv, av) = (lb[q], after_loops[j][(k + q) % n]);
                format!(
                    "{head} follows after's boundary loop {j} for {q} vertices, then before's \
                     vertex {bv} at {:?} faces after's vertex {av} at {:?}, {:e} apart (tolerance \
                     {tolerance:e})",
                    bp[bv as usize].to_array(),
                    ap[av as usize].to_array(),
                    distance(av, bv)
                )
            } else if after_loops
                .iter()
                .zip(&used)
                .any(|(la, &u)| !u && la.len() == n)
            {
                format!(
                    "{head}: no boundary vertex of after lies within {tolerance:e} of its start"
                )
            } else {
                let lengths: Vec<usize> = after_loops
                    .iter()
                    .zip(&used)
                    .filter(|&(_, &u)| !u)
                    .map(|(la, _)| la.len())
                    .collect();
                format!("{head}: after has no unmatched boundary loop of that length (lengths {lengths:?})")
            };
            return Err(mismatch(reason));
        };
        used[j] = true;
        let la = &after_loops[j];
        weld.extend((0..n).map(|q| (la[(k + q) % n], lb[q])));
    }
    Ok(weld)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3×3-vertex square patch in z = 0 (normal +z), and the same patch with its centre vertex
    /// (4) lifted to `lift`.
    fn patch(lift: f32) -> (TriMesh, TriMesh) {
        let mut p = Vec::new();
        for row in 0..3 {
            for col in 0..3 {
                p.push(Vec3::new(col as f32 - 1.0, row as f32 - 1.0, 0.0));
            }
        }
        let mut t = Vec::new();
        for row in 0..2u32 {
            for col in 0..2u32 {
                let v = row * 3 + col;
                t.push([v, v + 1, v + 4]);
                t.push([v, v + 4, v + 3]);
            }
        }
        let before = TriMesh::new(p.clone(), t).unwrap();
        p[4].z = lift;
        let after = before.with_positions(p).unwrap();
        (before, after)
    }

    #[test]
    fn lifted_centre_of_a_patch_is_a_hat_function() {
        let (before, after) = patch(0.75);
        // The integral of a hat function: height × (area of the lifted vertex's star) / 3, and
        // vertex 4 has six triangles of area ½.
        let v = volume_between(&before, &after).unwrap();
        assert!((v - 0.75 * 3.0 / 3.0).abs() < 1e-12, "{v}");
    }

    #[test]
    fn volume_between_does_not_depend_on_the_reference_when_boundaries_coincide() {
        let (before, after) = patch(0.75);
        let at_origin = volume_between_about(&before, &after, DVec3::ZERO).unwrap();
        for r in [
            DVec3::new(100.0, -50.0, 30.0),
            DVec3::new(-1e3, 2e3, 5e2),
            DVec3::new(0.5, 0.5, -7.0),
        ] {
            let v = volume_between_about(&before, &after, r).unwrap();
            assert!((v - at_origin).abs() < 1e-9, "{v} vs {at_origin} about {r}");
        }
    }

    #[test]
    fn raw_sum_depends_on_the_reference_when_boundaries_differ() {
        // Why volume_between checks the boundary: ΔV(r) = ΔV(0) − r·(N_after − N_before)/3.
        // Lift the whole patch by 1 and pull corner 0 outward: the two boundaries differ and so
        // do the vector areas (4 vs 4.25 along +z), so the raw sum moves with r.
        let (before, _) = patch(0.0);
        let mut moved: Vec<Vec3> = before.positions().to_vec();
        for p in &mut moved {
            p.z += 1.0;
        }
        moved[0].x -= 0.5;
        let raw = |r: DVec3| {
            (sixfold_volume_about(&moved, before.triangles(), r)
                - sixfold_volume_about(before.positions(), before.triangles(), r))
                / 6.0
        };
        let shift = raw(DVec3::ZERO) - raw(DVec3::new(0.0, 0.0, 3.0));
        assert!((shift - 0.25).abs() < 1e-12, "{shift}");
        let moved = before.with_positions(moved).unwrap();
        assert!(matches!(
            volume_between(&before, &moved),
            Err(MeshError::BoundaryMismatch { .. })
        ));
    }

    #[test]
    fn vertex_normals_are_unit_or_zero() {
        let (_, after) = patch(0.5);
        let normals = after.vertex_normals();
        for n in &normals {
            assert!((n.length() - 1.0).abs() < 1e-6);
        }
        // The lifted apex is symmetric: its normal is +z.
        assert!((normals[4] - Vec3::Z).length() < 1e-6);
        // An unreferenced vertex gets zero.
        let mut p = after.positions().to_vec();
        p.push(Vec3::new(5.0, 5.0, 5.0));
        let m = TriMesh::new(p, after.triangles().to_vec()).unwrap();
        assert_eq!(m.vertex_normals()[9], Vec3::ZERO);
        assert_eq!(m.bounding_box().max, Vec3::splat(5.0));
    }

    #[test]
    fn triangle_normals_and_areas_of_a_flat_patch() {
        let (before, _) = patch(0.0);
        assert!(before.triangle_normals().iter().all(|&n| n == Vec3::Z));
        assert!(before.triangle_areas().iter().all(|&a| a == 0.5));
        assert_eq!(before.area(), 4.0);
        assert!(before.centroid().length() < 1e-15);
    }

    #[test]
    fn collapsed_mesh_has_a_centroid_and_zero_normals() {
        let (before, _) = patch(0.0);
        let flat = before
            .with_positions(vec![Vec3::new(1.0, 2.0, 3.0); 9])
            .unwrap();
        assert_eq!(flat.area(), 0.0);
        assert_eq!(flat.centroid(), DVec3::new(1.0, 2.0, 3.0));
        assert!(flat.triangle_normals().iter().all(|&n| n == Vec3::ZERO));
        assert!(flat.vertex_normals().iter().all(|&n| n == Vec3::ZERO));
    }

    #[test]
    fn open_surface_has_no_signed_volume_and_closed_has_no_volume_between() {
        let (before, _) = patch(0.0);
        assert_eq!(
            before.signed_volume(),
            Err(MeshError::NotClosed {
                boundary_edges: 8,
                loops: 1
            })
        );
        let tet = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap();
        assert!((tet.signed_volume().unwrap() - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(
            volume_between(&tet, &before),
            Err(MeshError::NotOpen { surface: "before" })
        );
        assert_eq!(
            volume_between(&before, &tet),
            Err(MeshError::NotOpen { surface: "after" })
        );
    }
}
