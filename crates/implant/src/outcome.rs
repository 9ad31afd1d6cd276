//! The results of a run as geometry: how far each vertex of the skin region moved
//! ([`vertex_displacements`]), how much the skin around it stretched ([`vertex_stretch`]), the
//! patient surface with the simulated region put back in ([`replace_region`]), and the range of a
//! per-vertex field for a report ([`FieldRange`]).
//!
//! Pure functions of meshes: the "before" and "after" meshes are the same triangles in two states
//! (as [`TriMesh::with_positions`] makes them). Sums of areas are accumulated in `f64`.

use glam::Vec3;
use tissue_mesh::TriMesh;

use crate::Param;
use crate::{ImplantError, RegionSelection};

/// Checks that `after` is a deformed state of `before`: the same vertex count and the same
/// triangles in the same order.
fn check_same_mesh(before: &TriMesh, after: &TriMesh) -> Result<(), ImplantError> {
    if before.vertex_count() != after.vertex_count() {
        return Err(ImplantError::InvalidParameter {
            param: Param::After,
            value: after.vertex_count() as f64,
            expected: format!(
                "the same vertex count as `before` ({} vertices), but `after` has {}: compare two \
                 states of the same mesh",
                before.vertex_count(),
                after.vertex_count()
            ),
        });
    }
    if before.triangle_count() != after.triangle_count() {
        return Err(ImplantError::InvalidParameter {
            param: Param::After,
            value: after.triangle_count() as f64,
            expected: format!(
                "the same triangle count as `before` ({} triangles), but `after` has {}: compare \
                 two states of the same mesh",
                before.triangle_count(),
                after.triangle_count()
            ),
        });
    }
    if let Some(t) = before
        .triangles()
        .iter()
        .zip(after.triangles())
        .position(|(b, a)| b != a)
    {
        let (b, a) = (before.triangles()[t], after.triangles()[t]);
        return Err(ImplantError::InvalidParameter {
            param: Param::After,
            value: t as f64,
            expected: format!(
                "the same triangles as `before`, but triangle {t} is {a:?} in `after` and {b:?} in \
                 `before`: compare two states of the same mesh"
            ),
        });
    }
    Ok(())
}

/// How far each vertex moved: `|after_i − before_i|` (in the positions' units, cm), computed in
/// `f64` and rounded to `f32`.
///
/// ```
/// use glam::Vec3;
/// use tissue_implant::vertex_displacements;
///
/// let before = tissue_mesh::grid(5, 4.0)?;
/// let lifted = before.positions().iter().map(|&p| p + Vec3::new(0.0, 0.0, 0.5)).collect();
/// let after = before.with_positions(lifted)?;
/// let d = vertex_displacements(&before, &after)?;
/// assert!(d.iter().all(|&d| d == 0.5));
/// # Ok::<(), tissue_implant::ImplantError>(())
/// ```
///
/// # Errors
/// [`ImplantError::InvalidParameter`] (named `after`) when the two meshes differ in vertex count
/// or in their triangles: they must be two states of one mesh.
pub fn vertex_displacements(before: &TriMesh, after: &TriMesh) -> Result<Vec<f32>, ImplantError> {
    check_same_mesh(before, after)?;
    Ok(before
        .positions()
        .iter()
        .zip(after.positions())
        .map(|(b, a)| (a.as_dvec3() - b.as_dvec3()).length() as f32)
        .collect())
}

/// Each vertex's tributary area: one third of the area of every triangle it is a corner of (so
/// the tributary areas sum to the mesh area), in `f64`.
fn tributary_areas(mesh: &TriMesh) -> Vec<f64> {
    let mut areas = vec![0.0_f64; mesh.vertex_count()];
    for (tri, area) in mesh.triangles().iter().zip(mesh.triangle_areas()) {
        for &v in tri {
            if let Some(slot) = areas.get_mut(v as usize) {
                *slot += area / 3.0;
            }
        }
    }
    areas
}

/// How much the skin around each vertex stretched: the ratio of its tributary area (one third of
/// each incident triangle's area) after to before. 1 means unchanged, 4 a doubling in both
/// directions of the surface, below 1 a compression; 1 for a vertex that no triangle uses.
///
/// ```
/// use tissue_implant::vertex_stretch;
///
/// // Stretched by 2 along x only: every vertex's area doubles.
/// let before = tissue_mesh::grid(5, 4.0)?;
/// let wider = before.positions().iter().map(|&p| p * glam::Vec3::new(2.0, 1.0, 1.0)).collect();
/// let after = before.with_positions(wider)?;
/// let s = vertex_stretch(&before, &after)?;
/// assert!(s.iter().all(|&s| (s - 2.0).abs() < 1e-5));
/// # Ok::<(), tissue_implant::ImplantError>(())
/// ```
///
/// # Errors
/// [`ImplantError::InvalidParameter`]:
/// - named `after` when the two meshes differ in vertex count or in their triangles;
/// - named `before` when a vertex's triangles all have zero area in `before` (possible only for
///   a deformed `before`), where the ratio is undefined.
pub fn vertex_stretch(before: &TriMesh, after: &TriMesh) -> Result<Vec<f32>, ImplantError> {
    check_same_mesh(before, after)?;
    let (area_before, area_after) = (tributary_areas(before), tributary_areas(after));
    let topology = before.topology();
    let mut stretch = Vec::with_capacity(area_before.len());
    for (v, (&b, &a)) in area_before.iter().zip(&area_after).enumerate() {
        if topology.vertex_triangles(v as u32).is_empty() {
            stretch.push(1.0);
        } else if b > 0.0 {
            stretch.push((a / b) as f32);
        } else {
            return Err(ImplantError::InvalidParameter {
                param: Param::Before,
                value: b,
                expected: format!(
                    "a positive area around every vertex, but vertex {v} has zero tributary area \
                     in `before` (all its triangles are degenerate): its stretch is undefined"
                ),
            });
        }
    }
    Ok(stretch)
}

/// The patient surface with the region's vertices moved to `region_after` (indexed by region
/// vertex, as `selection.mesh()` numbers them) through [`RegionSelection::region_to_patient`].
///
/// The region's boundary vertices (those on [`RegionSelection::boundary_loops`]) keep the
/// patient's positions bit for bit, whatever `region_after` holds there, so the result is
/// seamless: the region's edge meets the untouched skin around it exactly. Every vertex outside
/// the region keeps its position too; the triangles are the patient's.
///
/// ```
/// use glam::Vec3;
/// use tissue_implant::{replace_region, select_region};
///
/// let patient = tissue_mesh::grid(33, 10.0)?;
/// let region = select_region(&patient, Vec3::ZERO, 3.0)?;
/// let lifted: Vec<Vec3> = region.mesh().positions().iter().map(|&p| p + Vec3::Z).collect();
/// let after = replace_region(&patient, &region, &lifted)?;
/// let centre = 16 * 33 + 16; // the patient vertex at the origin
/// assert_eq!(after.positions()[centre], Vec3::Z);
/// assert_eq!(after.triangles(), patient.triangles());
/// # Ok::<(), tissue_implant::ImplantError>(())
/// ```
///
/// # Errors
/// [`ImplantError::InvalidParameter`]:
/// - named `patient` when `patient` is not the mesh the selection was made from (a different
///   vertex count, a region vertex out of its range, or a region triangle that is not the
///   patient's);
/// - named `region_after` when it does not hold one position per region vertex, or holds a
///   non-finite position (the message names the region vertex).
pub fn replace_region(
    patient: &TriMesh,
    selection: &RegionSelection,
    region_after: &[Vec3],
) -> Result<TriMesh, ImplantError> {
    check_patient(patient, selection)?;
    let region_to_patient = selection.region_to_patient();
    if region_after.len() != region_to_patient.len() {
        return Err(ImplantError::InvalidParameter {
            param: Param::RegionAfter,
            value: region_after.len() as f64,
            expected: format!(
                "one position per region vertex ({}), but {} were given",
                region_to_patient.len(),
                region_after.len()
            ),
        });
    }
    if let Some(i) = region_after.iter().position(|p| !p.is_finite()) {
        let p = region_after[i];
        let bad = p
            .to_array()
            .into_iter()
            .find(|c| !c.is_finite())
            .unwrap_or(f32::NAN);
        return Err(ImplantError::InvalidParameter {
            param: Param::RegionAfter,
            value: f64::from(bad),
            expected: format!(
                "finite positions, but region vertex {i} (patient vertex {}) is {:?}: the run \
                 that produced it diverged",
                region_to_patient[i],
                p.to_array()
            ),
        });
    }
    let mut on_boundary = vec![false; region_to_patient.len()];
    for &v in selection.boundary_loops().iter().flatten() {
        if let Some(flag) = on_boundary.get_mut(v as usize) {
            *flag = true;
        }
    }
    let mut positions = patient.positions().to_vec();
    for ((&p, &after), &fixed) in region_to_patient.iter().zip(region_after).zip(&on_boundary) {
        if !fixed {
            if let Some(slot) = positions.get_mut(p as usize) {
                *slot = after;
            }
        }
    }
    Ok(patient.with_positions(positions)?)
}

/// Checks that `patient` is the mesh `selection` was made from: its vertex count, every region
/// vertex in range, every region triangle a patient triangle renumbered.
fn check_patient(patient: &TriMesh, selection: &RegionSelection) -> Result<(), ImplantError> {
    let n = patient.vertex_count();
    let mismatch = |what: String| ImplantError::InvalidParameter {
        param: Param::Patient,
        value: n as f64,
        expected: format!(
            "the patient mesh the region was selected from, but {what}: select the region again \
             on this patient"
        ),
    };
    if selection.patient_to_region().len() != n {
        return Err(mismatch(format!(
            "the selection was made on {} vertices and this patient has {n}",
            selection.patient_to_region().len()
        )));
    }
    if let Some((i, &p)) = selection
        .region_to_patient()
        .iter()
        .enumerate()
        .find(|&(_, &p)| p as usize >= n)
    {
        return Err(mismatch(format!(
            "region vertex {i} is patient vertex {p} and this patient has {n} vertices"
        )));
    }
    let region_to_patient = selection.region_to_patient();
    for (t, (tri, &pt)) in selection
        .mesh()
        .triangles()
        .iter()
        .zip(selection.triangle_to_patient())
        .enumerate()
    {
        let mapped = tri.map(|v| region_to_patient.get(v as usize).copied());
        let expected = patient
            .triangles()
            .get(pt as usize)
            .map(|tri| tri.map(Some));
        if expected != Some(mapped) {
            return Err(mismatch(format!(
                "region triangle {t} is patient triangle {pt}, which is not the same triangle \
                 in this patient"
            )));
        }
    }
    Ok(())
}

/// The range and mean of a per-vertex field (a displacement in cm, a stretch ratio), for a
/// report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldRange {
    /// Smallest value.
    pub min: f32,
    /// Largest value.
    pub max: f32,
    /// Arithmetic mean over the values (summed in `f64`).
    pub mean: f32,
}

impl FieldRange {
    /// The range and mean of `values`; `None` when there are none or one is not finite.
    ///
    /// ```
    /// use tissue_implant::FieldRange;
    ///
    /// let r = FieldRange::of(&[1.0, 4.0, 1.0]).ok_or("empty")?;
    /// assert_eq!((r.min, r.max, r.mean), (1.0, 4.0, 2.0));
    /// assert_eq!(FieldRange::of(&[]), None);
    /// # Ok::<(), &str>(())
    /// ```
    pub fn of(values: &[f32]) -> Option<FieldRange> {
        if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let (mut min, mut max, mut sum) = (f32::INFINITY, f32::NEG_INFINITY, 0.0_f64);
        for &v in values {
            min = min.min(v);
            max = max.max(v);
            sum += f64::from(v);
        }
        Some(FieldRange {
            min,
            max,
            mean: (sum / values.len() as f64) as f32,
        })
    }
}
