//! Region selection (SPEC A.5): the geodesic disc of the patient surface around the implant
//! position, as its own mesh with maps back to the patient's vertices. The phases are in the docs
//! of [`select_region_with`], the rules in [`RegionRule`], the default radius in
//! [`default_radius`].

use glam::Vec3;
use tissue_mesh::{TriMesh, NO_TRIANGLE};

pub use crate::geodesic::{
    default_snap_distance, geodesic_distances, snap_to_surface, SurfacePoint, DEFAULT_SNAP_FRACTION,
};
use crate::ImplantError;
use crate::Param;

/// [`default_radius`] is this many times the implant footprint radius.
pub const DEFAULT_RADIUS_FACTOR: f64 = 1.5;

/// Marks a patient vertex that is not in the region in [`RegionSelection::patient_to_region`].
pub const NOT_IN_REGION: u32 = u32::MAX;

/// Which triangles within the geodesic radius form the region.
///
/// [`RegionRule::Centroid`] (the default) keeps a triangle when the geodesic distance at its
/// centroid, taken as the mean of its corners' distances, is at most the radius. The boundary then
/// follows the circle `d = r` with triangles on both sides of it, so the area is πr² up to a small
/// fraction of one ring of triangles (0.4424 cm² for πr² = 0.4418 cm² on the thesis's 65 × 65
/// plane), and boundary vertices lie within about an edge length of `d = r`.
///
/// [`RegionRule::TouchesVertex`] keeps every triangle with a corner within the radius. It matches
/// the thesis's regions: on its 1 cm planes (65², 129², 257² vertices, r = 0.375 cm) it gives
/// 0.456, 0.450, 0.446 cm² against the thesis's 0.458, 0.450, 0.446; on the 20 cm plane with
/// r = 5.25 cm, 91.4 cm² against 92.57 cm². It is about half a ring larger than πr².
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum RegionRule {
    /// The mean of the corners' distances is at most the radius: area ≈ πr² on a plane.
    #[default]
    Centroid,
    /// Some corner is within the radius: the thesis's rule, about half a ring larger.
    TouchesVertex,
}

impl RegionRule {
    /// Whether a triangle with corner distances `d` belongs to a region of radius `radius`.
    fn keeps(self, d: [f64; 3], radius: f64) -> bool {
        if d.iter().any(|x| !x.is_finite()) {
            return false;
        }
        self.measure(d) <= radius
    }

    /// The distance the rule compares with the radius.
    fn measure(self, d: [f64; 3]) -> f64 {
        match self {
            RegionRule::Centroid => (d[0] + d[1] + d[2]) / 3.0,
            RegionRule::TouchesVertex => d[0].min(d[1]).min(d[2]),
        }
    }
}

/// Options of [`select_region_with`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RegionOptions {
    /// Largest distance from the given point to the surface, in cm; `None` for
    /// [`default_snap_distance`] (5 % of the bounding-box diagonal).
    pub max_snap_distance: Option<f64>,
    /// Which triangles form the region.
    pub rule: RegionRule,
}

/// The default region radius for an implant whose footprint (base) has radius
/// `footprint_radius` cm: [`DEFAULT_RADIUS_FACTOR`] × `footprint_radius` (a 7 cm round base,
/// radius 3.5 cm, gives 5.25 cm).
///
/// Why 1.5: the skin stretched over an expander lifts and spreads beyond its base, so the free
/// region must reach past the base by a margin that grows with the implant. Half the base radius
/// is what the thesis's reference runs imply: its plane-press regions (see
/// [`RegionRule::TouchesVertex`]) converge to π(1.5 · 0.25 cm)² = 0.442 cm² as the mesh is refined
/// under a 0.25 cm sphere, and its 7 cm round base gave regions of 91–92.6 cm² ≈ π(5.25 cm)² plus
/// half a ring of triangles.
///
/// # Errors
/// [`ImplantError::InvalidParameter`] when `footprint_radius` is not finite and positive.
pub fn default_radius(footprint_radius: f64) -> Result<f64, ImplantError> {
    if !(footprint_radius.is_finite() && footprint_radius > 0.0) {
        return Err(ImplantError::InvalidParameter {
            param: Param::FootprintRadius,
            value: footprint_radius,
            expected: "a finite radius > 0 cm (half the implant's base diameter)".to_string(),
        });
    }
    Ok(DEFAULT_RADIUS_FACTOR * footprint_radius)
}

/// Selects the geodesic disc of radius `radius` cm around `point` on the patient surface, with
/// the default [`RegionOptions`]; see [`select_region_with`].
///
/// ```
/// use glam::Vec3;
/// use tissue_implant::select_region;
///
/// // A 10 cm plane of 33 × 33 vertices; a point picked 2 mm above its centre.
/// let plane = tissue_mesh::grid(33, 10.0)?;
/// let region = select_region(&plane, Vec3::new(0.5, 0.0, 0.2), 3.0)?;
/// assert_eq!(region.centre().position(), Vec3::new(0.5, 0.0, 0.0));
/// assert_eq!(region.boundary_loops().len(), 1);
/// let disc = std::f64::consts::PI * 3.0 * 3.0;
/// assert!((region.area() - disc).abs() < 0.03 * disc);
/// // Every region vertex is a patient vertex, in the patient's order.
/// let map = region.region_to_patient();
/// assert!(map.windows(2).all(|w| w[0] < w[1]));
/// # Ok::<(), tissue_implant::ImplantError>(())
/// ```
///
/// # Errors
/// See [`select_region_with`].
pub fn select_region(
    patient: &TriMesh,
    point: Vec3,
    radius: f64,
) -> Result<RegionSelection, ImplantError> {
    select_region_with(patient, point, radius, &RegionOptions::default())
}

/// Selects the geodesic disc of radius `radius` cm around `point` (snapped to the nearest point
/// of `patient`): the triangles that satisfy `options.rule`, in one edge-connected piece around
/// the centre.
///
/// # Phases (each a `tracing` span)
/// 1. **Snap** the given point to the nearest surface point ([`snap_to_surface`]); a point farther
///    than [`RegionOptions::max_snap_distance`] (default 5 % of the bounding-box diagonal,
///    [`default_snap_distance`]) is an error.
/// 2. **Geodesic distances** from the snapped point by fast marching ([`geodesic_distances`]),
///    stopped at `radius + 1.5 × longest edge` (no corner of a kept triangle lies beyond
///    `radius + longest edge`).
/// 3. **Select**: the triangles that satisfy the [`RegionRule`], then only the edge-connected piece
///    that holds the centre's triangle (a fold of the surface that comes back within the radius
///    elsewhere is left out).
/// 4. **Extract** the region as a [`TriMesh`]: region vertices are the patient vertices it uses in
///    increasing patient order (so neighbours stay as close in memory as they were in the patient
///    mesh, which the mass–spring model's speed depends on), triangles in patient order.
///
/// # Closed and open surfaces
/// The planning system works on open scans, but a closed patient surface is accepted: a region
/// on it is still an open disc. What is refused is a region that takes the whole connected piece
/// of the surface it lies on ([`ImplantError::RegionCoversSurface`]): no skin would be left
/// around it to hold its boundary.
///
/// # Errors
/// - [`ImplantError::InvalidParameter`]: `radius` not finite and positive, a non-finite `point`,
///   or a negative or NaN `max_snap_distance`;
/// - [`ImplantError::PointOffSurface`]: `point` is farther from the surface than allowed;
/// - [`ImplantError::EmptyRegion`]: the radius does not reach over the centre's triangle;
/// - [`ImplantError::RegionCoversSurface`]: the region would be the whole connected piece of the
///   surface (no boundary inside the patient surface);
/// - [`ImplantError::Mesh`]: the region mesh failed validation (not expected: it is a subset of a
///   valid mesh).
pub fn select_region_with(
    patient: &TriMesh,
    point: Vec3,
    radius: f64,
    options: &RegionOptions,
) -> Result<RegionSelection, ImplantError> {
    let _span = tracing::info_span!(
        "select_region",
        radius,
        vertices = patient.vertex_count(),
        triangles = patient.triangle_count()
    )
    .entered();
    if !(radius.is_finite() && radius > 0.0) {
        return Err(ImplantError::InvalidParameter {
            param: Param::Radius,
            value: radius,
            expected: "a finite region radius > 0 cm (see default_radius)".to_string(),
        });
    }
    let max_snap = options
        .max_snap_distance
        .unwrap_or_else(|| default_snap_distance(patient));
    let centre = snap_to_surface(patient, point, max_snap)?;
    // Beyond `radius + longest edge` no vertex of a kept triangle can lie (neighbouring distances
    // differ by at most their edge); the factor leaves room for rounding.
    let limit = radius + 1.5 * longest_edge(patient);
    let distances = geodesic_distances(patient, &centre, limit)?;
    let selected = {
        let _span = tracing::debug_span!("select").entered();
        select_triangles(patient, &centre, &distances, radius, options.rule)?
    };
    let _span = tracing::debug_span!("extract", triangles = selected.len()).entered();
    RegionSelection::extract(patient, centre, radius, distances, &selected)
}

/// The longest edge of the mesh, in `f64`.
fn longest_edge(mesh: &TriMesh) -> f64 {
    let p = mesh.positions();
    mesh.topology()
        .edges()
        .iter()
        .map(|&[a, b]| f64::from(p[a as usize].distance(p[b as usize])))
        .fold(0.0, f64::max)
}

/// Phase 3: the triangles of the region, in increasing order.
fn select_triangles(
    patient: &TriMesh,
    centre: &SurfacePoint,
    distances: &[f64],
    radius: f64,
    rule: RegionRule,
) -> Result<Vec<u32>, ImplantError> {
    let triangles = patient.triangles();
    let corner_distances = |t: usize| triangles[t].map(|v| distances[v as usize]);
    let t0 = centre.triangle() as usize;
    if !rule.keeps(corner_distances(t0), radius) {
        return Err(ImplantError::EmptyRegion {
            radius,
            min_radius: rule.measure(corner_distances(t0)),
            triangle: t0 as u32,
        });
    }
    // Flood fill across edges from the centre's triangle.
    let topology = patient.topology();
    let mut inside = vec![false; triangles.len()];
    inside[t0] = true;
    let mut stack = vec![t0 as u32];
    while let Some(t) = stack.pop() {
        for &e in &topology.triangle_edges()[t as usize] {
            for n in topology.edge_triangles()[e as usize] {
                if n != NO_TRIANGLE
                    && !inside[n as usize]
                    && rule.keeps(corner_distances(n as usize), radius)
                {
                    inside[n as usize] = true;
                    stack.push(n);
                }
            }
        }
    }
    let selected: Vec<u32> = (0..triangles.len() as u32)
        .filter(|&t| inside[t as usize])
        .collect();
    let components = topology.triangle_components();
    let piece = components[t0];
    let piece_size = components.iter().filter(|&&c| c == piece).count();
    if selected.len() == piece_size {
        let farthest = triangles
            .iter()
            .zip(components)
            .filter(|&(_, &c)| c == piece)
            .flat_map(|(tri, _)| tri.iter().map(|&v| distances[v as usize]))
            .fold(0.0, f64::max);
        return Err(ImplantError::RegionCoversSurface {
            radius,
            triangles: piece_size,
            farthest,
        });
    }
    Ok(selected)
}

/// A region of the patient surface: its own mesh, the maps between its vertices and the
/// patient's, its boundary, area, centre and geodesic distances. Made by [`select_region`].
///
/// Invariants: `region_to_patient` is strictly increasing; `patient_to_region[region_to_patient[i]]
/// == i` and every other entry is [`NOT_IN_REGION`]; region triangle `t` is patient triangle
/// `triangle_to_patient[t]` renumbered (strictly increasing too); the mesh is one edge-connected
/// piece with at least one boundary loop.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionSelection {
    mesh: TriMesh,
    region_to_patient: Vec<u32>,
    patient_to_region: Vec<u32>,
    triangle_to_patient: Vec<u32>,
    centre: SurfacePoint,
    centre_triangle: u32,
    radius: f64,
    area: f64,
    distances: Vec<f64>,
    patient_distances: Vec<f64>,
}

impl RegionSelection {
    /// Phase 4: the region mesh and its maps from the selected patient triangles.
    fn extract(
        patient: &TriMesh,
        centre: SurfacePoint,
        radius: f64,
        patient_distances: Vec<f64>,
        selected: &[u32],
    ) -> Result<RegionSelection, ImplantError> {
        let mut patient_to_region = vec![NOT_IN_REGION; patient.vertex_count()];
        for &t in selected {
            for v in patient.triangles()[t as usize] {
                patient_to_region[v as usize] = 0;
            }
        }
        let mut region_to_patient = Vec::new();
        for (v, slot) in patient_to_region.iter_mut().enumerate() {
            if *slot != NOT_IN_REGION {
                *slot = region_to_patient.len() as u32;
                region_to_patient.push(v as u32);
            }
        }
        let positions = region_to_patient
            .iter()
            .map(|&v| patient.positions()[v as usize])
            .collect();
        let triangles = selected
            .iter()
            .map(|&t| patient.triangles()[t as usize].map(|v| patient_to_region[v as usize]))
            .collect();
        let mesh = TriMesh::new(positions, triangles)?;
        let distances = region_to_patient
            .iter()
            .map(|&v| patient_distances[v as usize])
            .collect();
        let centre_triangle = selected.partition_point(|&t| t < centre.triangle()) as u32;
        Ok(RegionSelection {
            area: mesh.area(),
            mesh,
            region_to_patient,
            patient_to_region,
            triangle_to_patient: selected.to_vec(),
            centre,
            centre_triangle,
            radius,
            distances,
            patient_distances,
        })
    }

    /// The same region of a larger surface of which the surface it was selected on is an
    /// order-preserving part: its vertex `v` is the larger one's `vertex_map[v]`, its triangle
    /// `t` the larger one's `triangle_map[t]` (both strictly increasing), and the larger one has
    /// `vertex_count` vertices. Distances of the vertices outside the part are infinite.
    pub(crate) fn renumbered(
        self,
        vertex_map: &[u32],
        triangle_map: &[u32],
        vertex_count: usize,
    ) -> RegionSelection {
        let region_to_patient: Vec<u32> = self
            .region_to_patient
            .iter()
            .map(|&v| vertex_map[v as usize])
            .collect();
        let mut patient_to_region = vec![NOT_IN_REGION; vertex_count];
        for (r, &v) in region_to_patient.iter().enumerate() {
            patient_to_region[v as usize] = r as u32;
        }
        let mut patient_distances = vec![f64::INFINITY; vertex_count];
        for (v, &d) in self.patient_distances.iter().enumerate() {
            patient_distances[vertex_map[v] as usize] = d;
        }
        let centre_triangle = triangle_map[self.centre.triangle() as usize];
        RegionSelection {
            mesh: self.mesh,
            region_to_patient,
            patient_to_region,
            triangle_to_patient: self
                .triangle_to_patient
                .iter()
                .map(|&t| triangle_map[t as usize])
                .collect(),
            centre: self.centre.with_triangle(centre_triangle),
            centre_triangle: self.centre_triangle,
            radius: self.radius,
            area: self.area,
            distances: self.distances,
            patient_distances,
        }
    }

    /// The region as a surface of its own (region vertex numbering).
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// Gives the region mesh back.
    pub fn into_mesh(self) -> TriMesh {
        self.mesh
    }

    /// For each region vertex, its patient vertex (strictly increasing).
    pub fn region_to_patient(&self) -> &[u32] {
        &self.region_to_patient
    }

    /// For each patient vertex, its region vertex, or [`NOT_IN_REGION`].
    pub fn patient_to_region(&self) -> &[u32] {
        &self.patient_to_region
    }

    /// For each region triangle, its patient triangle (strictly increasing).
    pub fn triangle_to_patient(&self) -> &[u32] {
        &self.triangle_to_patient
    }

    /// The region's boundary loops in region vertex numbering (from its topology; see
    /// [`tissue_mesh::Topology::boundary_loops`]). One loop for a disc; more when the disc takes
    /// in a hole of the patient surface.
    pub fn boundary_loops(&self) -> &[Vec<u32>] {
        self.mesh.topology().boundary_loops()
    }

    /// Area of the region, cm².
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The centre: the given point snapped to the patient surface (its triangle is a patient
    /// triangle).
    pub fn centre(&self) -> &SurfacePoint {
        &self.centre
    }

    /// The region triangle that holds the centre.
    pub fn centre_triangle(&self) -> u32 {
        self.centre_triangle
    }

    /// The radius asked for, cm.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Geodesic distance from the centre of each region vertex, cm.
    pub fn distances(&self) -> &[f64] {
        &self.distances
    }

    /// Geodesic distance from the centre of each patient vertex, cm; `f64::INFINITY` beyond
    /// `radius + 1.5 × longest edge` (where marching stopped) and where the surface does not
    /// connect.
    pub fn patient_distances(&self) -> &[f64] {
        &self.patient_distances
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks the invariants in the type's docs.
    fn check_well_formed(r: &RegionSelection, patient: &TriMesh) {
        assert!(r.region_to_patient.windows(2).all(|w| w[0] < w[1]));
        assert!(r.triangle_to_patient.windows(2).all(|w| w[0] < w[1]));
        for (i, &v) in r.region_to_patient.iter().enumerate() {
            assert_eq!(r.patient_to_region[v as usize], i as u32);
            assert_eq!(r.mesh.positions()[i], patient.positions()[v as usize]);
            assert_eq!(r.distances[i], r.patient_distances[v as usize]);
        }
        let mapped = r
            .patient_to_region
            .iter()
            .filter(|&&x| x != NOT_IN_REGION)
            .count();
        assert_eq!(mapped, r.region_to_patient.len());
        for (t, &pt) in r.triangle_to_patient.iter().enumerate() {
            let tri = r.mesh.triangles()[t].map(|v| r.region_to_patient[v as usize]);
            assert_eq!(tri, patient.triangles()[pt as usize]);
        }
        assert_eq!(
            r.triangle_to_patient[r.centre_triangle as usize],
            r.centre.triangle()
        );
        assert_eq!(r.mesh.topology().component_count(), 1);
        assert!(!r.boundary_loops().is_empty());
    }

    #[test]
    fn region_on_a_grid_is_well_formed() {
        let plane = tissue_mesh::grid(33, 10.0).unwrap();
        for rule in [RegionRule::Centroid, RegionRule::TouchesVertex] {
            let options = RegionOptions {
                rule,
                ..RegionOptions::default()
            };
            let r = select_region_with(&plane, Vec3::new(1.1, -0.7, 0.0), 2.5, &options).unwrap();
            check_well_formed(&r, &plane);
        }
    }

    #[test]
    fn region_on_a_closed_sphere_is_an_open_disc() {
        let sphere = tissue_mesh::uv_sphere(24, 23, 2.0).unwrap();
        let r = select_region(&sphere, Vec3::new(0.0, 2.1, 0.3), 1.5).unwrap();
        check_well_formed(&r, &sphere);
        assert_eq!(r.boundary_loops().len(), 1);
    }

    #[test]
    fn touching_rule_is_larger_than_centroid_rule() {
        let plane = tissue_mesh::grid(33, 10.0).unwrap();
        let select = |rule| {
            let options = RegionOptions {
                rule,
                ..RegionOptions::default()
            };
            select_region_with(&plane, Vec3::ZERO, 3.0, &options).unwrap()
        };
        let (centroid, touching) = (
            select(RegionRule::Centroid),
            select(RegionRule::TouchesVertex),
        );
        assert!(touching.area() > centroid.area());
        for &t in centroid.triangle_to_patient() {
            assert!(touching.triangle_to_patient().binary_search(&t).is_ok());
        }
    }

    #[test]
    fn default_radius_is_one_and_a_half_footprints() {
        assert_eq!(default_radius(3.5).unwrap(), 5.25);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                default_radius(bad),
                Err(ImplantError::InvalidParameter {
                    param: Param::FootprintRadius,
                    ..
                })
            ));
        }
    }
}
