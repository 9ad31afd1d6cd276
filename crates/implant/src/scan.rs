//! Planning on a real patient scan: a simulation surface of the planner's own, mapped back onto
//! the scan (the mechanical and visual models of SOFA's mappings).
//!
//! A photogrammetric scan is fine (0.5 mm edges), noisy (0.2 mm), uneven and has holes. Run on
//! its own triangles, their size sets the time step, their noise folds the inward offset of the
//! layers, and their irregularity breaks the expander's base. So [`prepare_scan`]:
//!
//! 1. **fills the scan's holes** up to [`ScanOptions::max_hole`] across (scanner drop-outs;
//!    `tissue_remesh::fill_holes`): the filled scan is what the region is selected on and what
//!    the simulation surface covers. Larger holes and the scan's outer border stay open;
//! 2. **selects the region** (geodesic, [`select_region_with`]) on the filled scan, and refuses
//!    a region that reaches an open border ([`ImplantError::RegionReachesBorder`], saying how
//!    far the border is, how small the region or the expander must be, and where a region of
//!    this size would fit). Steps 1 and 2 run on the part of the scan within reach of the
//!    region (every triangle with a corner within `d + R + 4 × the longest edge` of the point,
//!    `d` its distance from the scan, or within any hole up to `max_hole` across that comes that
//!    near): a hole that touches the region lies in it whole, and the part keeps the scan's order, so the region and its fills are the whole
//!    scan's while a scan of millions of triangles costs one pass over it, not a fill, a
//!    validation and a geodesic over all of it. Only a refused region is looked at again on the
//!    whole scan, for where one would fit;
//! 3. **remeshes the region** to a near-uniform edge `h` ([`ScanOptions::sim_edge`], by default
//!    [`default_sim_edge`]): isotropic remeshing with every vertex projected onto a
//!    moving-least-squares plane fit of the scan ([`ScanOptions::smoothing`]: 2 × the larger of
//!    `h` and the default edge, at least 1.5 × the depth and 1.6 scan edges), so noise below
//!    the simulation's own scale, and a coarse scan's facets, are smoothed out of the
//!    mechanics, and a finer `h` samples the same surface;
//! 4. **binds every vertex of the scan region to the simulation surface**
//!    ([`SimSurface::map_to_scan`]): its closest point on the rest surface (triangle,
//!    barycentric coordinates `bᵢ`) and its offset `o` along the interpolated normal
//!    `n(b) = normalise(Σ bᵢ nᵢ)`. After the run the vertex moves by
//!    `Σ bᵢ (xᵢ' − xᵢ) + o·(n'(b) − n(b))`: it follows the deformed surface and keeps its own
//!    detail (its offset from the smooth surface), so the output is the scan's vertices and
//!    triangles with the region moved. Vertices on the region's boundary and outside it keep
//!    their positions bit for bit; since the simulation surface is held at the same boundary,
//!    the moves fall continuously to zero at the seam.
//!
//! ## The default simulation edge
//! Table 2's region (SPEC A.5) has 1008 vertices per layer on 92.57 cm². An equilateral mesh of
//! edge `h` has `2/(√3·h²)` vertices per cm², so a region of radius `R` (area about `πR²`) has
//! the same count when `h = R·√(2π/(√3·1008))` = `0.0600·R`: 0.315 cm for Table 2's 5.25 cm
//! region (its grid has 0.3125 cm), 0.18 cm for a 4 cm expander's 3 cm region. The run's cost
//! then is about Table 2's whatever the scan's resolution.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::{Vec3, Vec3A};
use tissue_bvh::{BuildOptions, Bvh, BvhWorkspace, Triangles};
use tissue_mesh::{volume_between, TriMesh};
use tissue_remesh::{fill_holes, remesh, Hole, RemeshOptions, RemeshStats};

use crate::adjacency::VertexNeighbours;
use crate::Param;
use crate::{
    select_region_with, vertex_stretch, ImplantError, RegionOptions, RegionSelection,
    SearchedSurface,
};

/// Region vertices per layer in Table 2's run (SPEC A.5: 2016 for both layers).
pub const TABLE2_REGION_VERTICES: f64 = 1008.0;

/// Holes up to this size across (cm) are filled by default: scanner drop-outs.
pub const DEFAULT_MAX_HOLE: f64 = 1.5;

/// The simulation edge (cm) that gives a region of radius `region_radius` (cm) about Table 2's
/// vertex count: `h = R·√(2π/(√3·1008))` (module docs).
///
/// ```
/// let h = tissue_implant::default_sim_edge(5.25)?;
/// assert!((h - 0.315).abs() < 0.001); // Table 2's grid: 0.3125 cm
/// # Ok::<(), tissue_implant::ImplantError>(())
/// ```
///
/// # Errors
/// [`ImplantError::InvalidParameter`] for a radius that is not finite and positive.
pub fn default_sim_edge(region_radius: f64) -> Result<f64, ImplantError> {
    if !(region_radius.is_finite() && region_radius > 0.0) {
        return Err(ImplantError::InvalidParameter {
            param: Param::RegionRadius,
            value: region_radius,
            expected: "a finite region radius > 0 cm".into(),
        });
    }
    Ok(region_radius
        * (2.0 * std::f64::consts::PI / (3.0f64.sqrt() * TABLE2_REGION_VERTICES)).sqrt())
}

/// How a scan is prepared for the mechanics ([`prepare_scan`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ScanOptions {
    /// The simulation surface's target edge, cm; `None`: [`default_sim_edge`] of the region's
    /// radius.
    pub sim_edge: Option<f64>,
    /// Holes of the scan up to this size across (cm, the largest distance between two of their
    /// boundary vertices) are filled for the simulation (default [`DEFAULT_MAX_HOLE`]); never
    /// a loop wider than half the scan's bounding-box diagonal (its border).
    pub max_hole: f64,
    /// The radius of the smoothing (the moving-least-squares fit the remeshed vertices are
    /// projected onto), in simulation edges (default 2: at 1, a face scan's 0.2 mm noise left
    /// enough ripple on 1.1 mm edges to fold the layers' 2.5 mm inward offset). The edge is
    /// the larger of the asked one and [`default_sim_edge`], so that refining the simulation
    /// mesh does not change the surface it samples; the radius is also at least 1.5 × the
    /// depth and 1.6 × the scan region's median edge. 0 turns the smoothing off.
    pub smoothing: f64,
    /// Remeshing iterations (default 8).
    pub iterations: u32,
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions {
            sim_edge: None,
            max_hole: DEFAULT_MAX_HOLE,
            smoothing: 2.0,
            iterations: 8,
        }
    }
}

impl ScanOptions {
    fn check(&self) -> Result<(), ImplantError> {
        if let Some(h) = self.sim_edge {
            if !(h.is_finite() && h > 0.0) {
                return Err(ImplantError::InvalidParameter {
                    param: Param::SimEdge,
                    value: h,
                    expected: "a finite simulation edge > 0 cm (or none for the default)".into(),
                });
            }
        }
        if !(self.max_hole.is_finite() && self.max_hole >= 0.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::MaxHole,
                value: self.max_hole,
                expected: "a finite hole size ≥ 0 cm".into(),
            });
        }
        if !(self.smoothing.is_finite() && self.smoothing >= 0.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::Smoothing,
                value: self.smoothing,
                expected: "a finite smoothing radius ≥ 0, in simulation edges".into(),
            });
        }
        if self.iterations == 0 {
            return Err(ImplantError::InvalidParameter {
                param: Param::Iterations,
                value: 0.0,
                expected: "at least 1 remeshing iteration".into(),
            });
        }
        Ok(())
    }
}

/// Where a scan region vertex sits on the simulation surface.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Binding {
    /// Simulation triangle, or [`PINNED`] for a vertex that does not move (region boundary).
    triangle: u32,
    /// Barycentric coordinates of its closest point there.
    barycentric: [f32; 3],
    /// Its offset along the interpolated normal, cm.
    offset: f32,
}

const PINNED: u32 = u32::MAX;

/// The simulation surface of a scan region, bound to the scan ([`prepare_scan`]).
#[derive(Debug, Clone)]
pub struct SimSurface {
    mesh: TriMesh,
    edge: f64,
    /// The larger of `edge` and the default edge for the region's radius (cm).
    model_edge: f64,
    binding: Vec<Binding>,
    scan_vertices: usize,
    scan_triangles: usize,
    holes_filled: Vec<Hole>,
    stats: RemeshStats,
}

/// The scan after a run, mapped from the simulation surface ([`SimSurface::map_to_scan`]).
#[derive(Debug, Clone)]
pub struct ScanResult {
    /// The scan with the region moved: its own vertices (count and order) and triangles.
    pub patient_after: TriMesh,
    /// Per scan vertex: how far it moved (cm); 0 outside the region.
    pub displacement: Vec<f32>,
    /// Per scan vertex: the simulation surface's stretch (area after / before) where the vertex
    /// is bound; 1 outside the region.
    pub stretch: Vec<f32>,
    /// Per scan vertex: whether it is in the region.
    pub in_region: Vec<bool>,
    /// Area of the scan's own region triangles (holes not counted) before, cm².
    pub area_before: f64,
    /// The same after, cm².
    pub area_after: f64,
    /// `area_after − area_before`, cm².
    pub area_gain: f64,
    /// Volume between the scan region (its holes filled) before and after, cm³.
    pub volume_difference: f64,
    /// The largest move of a scan vertex within one simulation edge of the region's boundary
    /// (by geodesic distance from the centre, `d ≥ R − h`), cm: how smoothly the result meets
    /// the unchanged scan (0 at the boundary itself).
    pub seam_max_move: f32,
}

/// The length the simulation surface's model is set by (cm): the larger of the asked edge and
/// [`default_sim_edge`] of the region's radius. The smoothing, layer 2's offset, the rim's
/// clearance from the border and the run's times follow it, so that halving the edge samples the
/// same model more finely.
///
/// # Errors
/// Those of [`default_sim_edge`].
pub fn model_edge(region_radius: f64, sim_edge: Option<f64>) -> Result<f64, ImplantError> {
    let default = default_sim_edge(region_radius)?;
    Ok(sim_edge.map_or(default, |h| h.max(default)))
}

/// Fills the scan's small holes, selects the region around `point` and remeshes it into the
/// simulation surface, bound to the scan (module docs). `depth` (cm) is the layers' placement
/// depth: the smoothing radius is at least 1.5 × it, so that the inward offset does not fold on
/// what is left of the noise.
///
/// Returns the region (selected on the scan with its small holes filled: the scan's vertices
/// keep their numbers, the fills' vertices come after them) and the simulation surface.
///
/// # Errors
/// - [`ImplantError::InvalidParameter`] for options out of range;
/// - the region selection's errors ([`select_region_with`]);
/// - [`ImplantError::RegionReachesBorder`] when the region reaches the scan's border or a hole
///   larger than [`ScanOptions::max_hole`];
/// - [`ImplantError::Remesh`] when the hole filling or the remeshing refuses the surface.
pub fn prepare_scan(
    patient: &TriMesh,
    point: Vec3,
    radius: f64,
    depth: f64,
    region: &RegionOptions,
    options: &ScanOptions,
) -> Result<(RegionSelection, SimSurface), ImplantError> {
    let _span = tracing::info_span!(
        "prepare_scan",
        vertices = patient.vertex_count(),
        triangles = patient.triangle_count()
    )
    .entered();
    options.check()?;
    let edge = match options.sim_edge {
        Some(h) => h,
        None => default_sim_edge(radius)?,
    };
    let model_edge = model_edge(radius, options.sim_edge)?;
    // A loop as wide as half the scan is its border, not a drop-out, however small the scan.
    let max_hole = options
        .max_hole
        .min(0.5 * f64::from(patient.bounding_box().size().length()));
    let (selection, holes_filled) = match near_region(patient, point, radius, max_hole, region)? {
        Some(found) => found,
        None => whole_scan_region(patient, point, radius, max_hole, region, options.max_hole)?,
    };
    // The smoothing is a length of the model, not of the mesh: the larger of the asked edge and
    // the default one, so a finer simulation surface is the same surface more finely sampled;
    // at least 1.5 × the depth; and at least COARSE_SMOOTHING scan edges, so a coarse scan's
    // facets are rounded into the surface they sample instead of followed crease by crease (a
    // coarse body's 0.65 cm facets, followed at h/2 = 0.16 cm, crossed the expander's base).
    let smoothing = (options.smoothing * model_edge)
        .max(depth_smoothing(depth))
        .max(COARSE_SMOOTHING * median_edge(selection.mesh()));
    let smoothing = (options.smoothing > 0.0).then_some(smoothing);
    let remeshed = {
        let _span = tracing::info_span!("remesh", edge).entered();
        remesh(
            selection.mesh(),
            &RemeshOptions {
                target_edge: edge,
                iterations: options.iterations,
                smoothing_radius: smoothing,
            },
        )?
    };
    let mesh = taubin(&remeshed.mesh, TAUBIN_ITERATIONS)?;
    let binding = {
        let _span = tracing::info_span!("bind").entered();
        bind(selection.mesh(), &mesh)?
    };
    tracing::debug!(
        sim_vertices = mesh.vertex_count(),
        region_vertices = selection.mesh().vertex_count(),
        holes = holes_filled.len(),
        "simulation surface"
    );
    Ok((
        selection,
        SimSurface {
            mesh,
            edge,
            model_edge,
            binding,
            scan_vertices: patient.vertex_count(),
            scan_triangles: patient.triangle_count(),
            holes_filled,
            stats: remeshed.stats,
        },
    ))
}

/// Steps 1 and 2 on the whole scan: its small holes filled, the region selected on it and
/// refused when it reaches an open border (with where one would fit); the filled holes at the
/// region.
fn whole_scan_region(
    patient: &TriMesh,
    point: Vec3,
    radius: f64,
    max_hole: f64,
    region: &RegionOptions,
    asked_max_hole: f64,
) -> Result<(RegionSelection, Vec<Hole>), ImplantError> {
    let fill = fill_holes(patient, max_hole)?;
    let filled = &fill.mesh;
    let selection = select_region_with(filled, point, radius, region)?;
    check_border(filled, &selection, &fill.open, radius, asked_max_hole)?;
    let holes_filled: Vec<Hole> = fill
        .filled
        .into_iter()
        .filter(|h| {
            h.vertices
                .iter()
                .any(|&v| selection.patient_to_region()[v as usize] != crate::NOT_IN_REGION)
        })
        .collect();
    Ok((selection, holes_filled))
}

/// Steps 1 and 2 on the part of the scan within reach of the region only, for scans much larger
/// than their region (a fine scan of millions of triangles): every triangle with a corner within
/// `near = d + radius + 4 × the longest edge` of `point` (`d`: how far `point` is from the
/// scan), or within the farthest vertex (plus the same margin) of a boundary loop that comes
/// within `near` and spreads over at most `max_hole` (every hole that may be filled and touch
/// the region), so such a hole lies in the part whole and is filled as on the whole scan; the
/// part's cut lies farther than the region reaches. The part keeps the scan's order, so the region, its mesh and its fills are the
/// whole scan's, bit for bit; the selection is renumbered to the whole scan (fill vertices and
/// triangles after the scan's). `None` when the part would be the whole scan or when the region
/// is refused there (the whole scan then gives the error, with where a region would fit).
fn near_region(
    patient: &TriMesh,
    point: Vec3,
    radius: f64,
    max_hole: f64,
    region: &RegionOptions,
) -> Result<Option<(RegionSelection, Vec<Hole>)>, ImplantError> {
    let _span = tracing::info_span!("near_region").entered();
    let max_snap = region
        .max_snap_distance
        .unwrap_or_else(|| crate::default_snap_distance(patient));
    // On the scan without its fills: no nearer than on the filled one, so the part holds the
    // nearest point of either (a point over a hole may be too far from this one only).
    let Ok(snapped) = crate::snap_to_surface(patient, point, max_snap) else {
        return Ok(None);
    };
    // The region lies within `near` of the point; a hole that comes within it (its loop's
    // distances from the point spread over at most `max_hole`) is taken whole.
    let margin = 4.0 * longest_edge(patient);
    let near = snapped.distance() + radius + margin;
    let centre = point.as_dvec3();
    let p = patient.positions();
    let mut reach = near;
    for l in patient.topology().boundary_loops() {
        let (lo, hi) = l.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
            let d = p[v as usize].as_dvec3().distance(centre);
            (lo.min(d), hi.max(d))
        });
        if lo <= near && hi - lo <= max_hole {
            reach = reach.max(hi + margin);
        }
    }
    let Some(part) = Part::around(patient, point, reach)? else {
        return Ok(None);
    };
    let fill = fill_holes(&part.mesh, max_hole)?;
    let options = RegionOptions {
        max_snap_distance: Some(max_snap),
        ..*region
    };
    let Ok(selection) = select_region_with(&fill.mesh, point, radius, &options) else {
        return Ok(None);
    };
    if check_border(&fill.mesh, &selection, &fill.open, radius, max_hole).is_err() {
        return Ok(None);
    }
    let (n, nt) = (patient.vertex_count(), patient.triangle_count());
    let (part_n, part_t) = (part.mesh.vertex_count(), part.mesh.triangle_count());
    let new_vertices = fill.mesh.vertex_count() - part_n;
    let vertex_map: Vec<u32> = part
        .vertices
        .iter()
        .copied()
        .chain((0..new_vertices).map(|k| (n + k) as u32))
        .collect();
    let triangle_map: Vec<u32> = part
        .triangles
        .iter()
        .copied()
        .chain((0..fill.mesh.triangle_count() - part_t).map(|k| (nt + k) as u32))
        .collect();
    let selection = selection.renumbered(&vertex_map, &triangle_map, n + new_vertices);
    let holes_filled = fill
        .filled
        .into_iter()
        .map(|mut h| {
            h.vertices
                .iter_mut()
                .for_each(|v| *v = vertex_map[*v as usize]);
            h
        })
        .filter(|h| {
            h.vertices
                .iter()
                .any(|&v| selection.patient_to_region()[v as usize] != crate::NOT_IN_REGION)
        })
        .collect();
    Ok(Some((selection, holes_filled)))
}

/// The triangles of a scan with a corner within a distance of a point, as a surface of their
/// own in the scan's order, with where its vertices and triangles are in the scan.
struct Part {
    mesh: TriMesh,
    vertices: Vec<u32>,
    triangles: Vec<u32>,
}

impl Part {
    /// The part within `reach` of `point`; `None` when it is the whole scan.
    fn around(patient: &TriMesh, point: Vec3, reach: f64) -> Result<Option<Part>, ImplantError> {
        let _span = tracing::debug_span!("part", reach).entered();
        let p = patient.positions();
        let centre = point.as_dvec3();
        let near: Vec<bool> = p
            .iter()
            .map(|x| x.as_dvec3().distance_squared(centre) <= reach * reach)
            .collect();
        let all = patient.triangles();
        let triangles: Vec<u32> = (0..all.len() as u32)
            .filter(|&t| all[t as usize].iter().any(|&v| near[v as usize]))
            .collect();
        if triangles.len() == all.len() {
            return Ok(None);
        }
        let mut local = vec![u32::MAX; p.len()];
        for &t in &triangles {
            for v in all[t as usize] {
                local[v as usize] = 0;
            }
        }
        let mut vertices = Vec::new();
        for (v, slot) in local.iter_mut().enumerate() {
            if *slot != u32::MAX {
                *slot = vertices.len() as u32;
                vertices.push(v as u32);
            }
        }
        let positions = vertices.iter().map(|&v| p[v as usize]).collect();
        let tris = triangles
            .iter()
            .map(|&t| all[t as usize].map(|v| local[v as usize]))
            .collect();
        Ok(Some(Part {
            mesh: TriMesh::new(positions, tris)?,
            vertices,
            triangles,
        }))
    }
}

/// The longest edge of a surface, in `f64`.
fn longest_edge(mesh: &TriMesh) -> f64 {
    let p = mesh.positions();
    mesh.topology()
        .edges()
        .iter()
        .map(|&[a, b]| f64::from(p[a as usize].distance(p[b as usize])))
        .fold(0.0, f64::max)
}

/// The smoothing radius in the scan region's own median edges, at least: enough of its vertices
/// (about 8) for the plane fit.
const COARSE_SMOOTHING: f64 = 1.6;

/// Taubin λ|μ passes over the simulation surface (boundary held): what is left of a kink at the
/// scale of one edge (a triangle the remesher could not make well) is smoothed out before the
/// layers are offset from it, at no cost in volume (the μ pass undoes the λ pass's shrinking).
const TAUBIN_ITERATIONS: usize = 4;

/// `iterations` Taubin passes (λ = 0.5, μ = −0.53, umbrella weights), boundary vertices fixed.
fn taubin(mesh: &TriMesh, iterations: usize) -> Result<TriMesh, ImplantError> {
    let n = mesh.vertex_count();
    let fixed = mesh.topology().boundary_vertex_mask(n);
    let edges = mesh.topology().edges();
    let mut p: Vec<glam::DVec3> = mesh.positions().iter().map(|x| x.as_dvec3()).collect();
    let mut sum = vec![glam::DVec3::ZERO; n];
    let mut count = vec![0u32; n];
    for &[a, b] in edges {
        count[a as usize] += 1;
        count[b as usize] += 1;
    }
    for _ in 0..iterations {
        for factor in [0.5, -0.53] {
            sum.iter_mut().for_each(|s| *s = glam::DVec3::ZERO);
            for &[a, b] in edges {
                let (a, b) = (a as usize, b as usize);
                sum[a] += p[b] - p[a];
                sum[b] += p[a] - p[b];
            }
            for v in 0..n {
                if !fixed[v] && count[v] > 0 {
                    p[v] += sum[v] * (factor / f64::from(count[v]));
                }
            }
        }
    }
    Ok(mesh.with_positions(p.iter().map(|x| x.as_vec3()).collect())?)
}

/// The median edge length of `mesh`.
fn median_edge(mesh: &TriMesh) -> f64 {
    let p = mesh.positions();
    let mut lengths: Vec<f32> = mesh
        .topology()
        .edges()
        .iter()
        .map(|&[a, b]| p[a as usize].distance(p[b as usize]))
        .collect();
    if lengths.is_empty() {
        return 0.0;
    }
    let mid = lengths.len() / 2;
    let (_, m, _) = lengths.select_nth_unstable_by(mid, f32::total_cmp);
    f64::from(*m)
}

/// The smallest smoothing radius for a placement depth: the layers' inward offset folds where
/// the surface curves more tightly than the depth, so ripples left by the scan's noise must be
/// smoothed out over a length of about the depth (the chin of the face scan folded at a 2 cm
/// expander's 0.09 cm simulation edge with twice that radius). A non-finite or negative depth
/// gives 0 (the layers refuse it).
fn depth_smoothing(depth: f64) -> f64 {
    if depth.is_finite() && depth > 0.0 {
        1.5 * depth
    } else {
        0.0
    }
}

/// Binds every vertex of `region` to its closest point on `sim` (pinned on the boundary).
fn bind(region: &TriMesh, sim: &TriMesh) -> Result<Vec<Binding>, ImplantError> {
    let positions: Vec<Vec3A> = sim.positions().iter().map(|&p| p.into()).collect();
    let searchable = |source| ImplantError::Search {
        surface: SearchedSurface::SimulationSurface,
        source,
    };
    let triangles = Triangles::new(&positions, sim.triangles()).map_err(searchable)?;
    let bvh = Bvh::build(&triangles, &BuildOptions::default()).map_err(searchable)?;
    let normals = sim.vertex_normals();
    let on_boundary = region
        .topology()
        .boundary_vertex_mask(region.vertex_count());
    let mut ws = BvhWorkspace::default();
    let mut binding = Vec::with_capacity(region.vertex_count());
    for (&p, &fixed) in region.positions().iter().zip(&on_boundary) {
        if fixed {
            binding.push(Binding {
                triangle: PINNED,
                barycentric: [0.0; 3],
                offset: 0.0,
            });
            continue;
        }
        let Some(hit) = bvh.closest_point(&triangles, p.into(), f32::INFINITY, &mut ws) else {
            return Err(ImplantError::InvalidParameter {
                param: Param::SimEdge,
                value: 0.0,
                expected: "a simulation surface with triangles".into(),
            });
        };
        let tri = sim.triangles()[hit.primitive as usize];
        let corners = tri.map(|v| positions[v as usize]);
        let (q, barycentric) =
            tissue_bvh::closest_point_on_triangle(p.into(), corners[0], corners[1], corners[2]);
        let n = interpolate(&normals, tri, barycentric);
        binding.push(Binding {
            triangle: hit.primitive,
            barycentric,
            offset: (Vec3A::from(p) - q).dot(n.into()),
        });
    }
    Ok(binding)
}

/// `normalise(Σ bᵢ nᵢ)`.
fn interpolate(normals: &[Vec3], tri: [u32; 3], b: [f32; 3]) -> Vec3 {
    (normals[tri[0] as usize] * b[0]
        + normals[tri[1] as usize] * b[1]
        + normals[tri[2] as usize] * b[2])
        .normalize_or_zero()
}

impl SimSurface {
    /// The simulation surface at rest (layer 1 of the model), cm.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// How far the offset of layer 2 averages the normals ([`LayerParams::offset_reach`],
    /// cm): half the default edge for the region's radius ([`default_sim_edge`]), or half the
    /// edge asked for if that is longer. A length of the model, not of the mesh: a finer
    /// simulation surface follows creases a coarser one cuts across (a noisy scan's border, a
    /// coarse body's facets), and offset along its own finer normals those folded layer 2 at
    /// `h/2` on the face and the body.
    ///
    /// [`LayerParams::offset_reach`]: crate::LayerParams::offset_reach
    pub fn offset_reach(&self) -> f64 {
        0.5 * self.model_edge
    }

    /// The larger of the asked edge and the default edge for the region's radius (cm): the
    /// length the model's smoothing and offset are set by, the same at `h` and `h/2`. The
    /// expander's rim must stay at least this far inside the region's border
    /// ([`crate::rim_border_clearance`]).
    pub fn model_edge(&self) -> f64 {
        self.model_edge
    }

    /// The target edge length of the simulation surface, cm.
    pub fn edge(&self) -> f64 {
        self.edge
    }

    /// The remesher's figures (edge lengths, angles, operations).
    pub fn remesh_stats(&self) -> &RemeshStats {
        &self.stats
    }

    /// The scan's holes that were filled inside or at the region (their loops in the scan's
    /// numbering).
    pub fn holes_filled(&self) -> &[Hole] {
        &self.holes_filled
    }

    /// The surface's unit normal at its point nearest to `p` (interpolated vertex normals):
    /// the expander's frame normal, free of the scan's noise.
    pub fn normal_near(&self, p: Vec3) -> Vec3 {
        let normals = self.mesh.vertex_normals();
        let mut best = (f32::INFINITY, Vec3::Z);
        for (t, tri) in self.mesh.triangles().iter().enumerate() {
            let c = self.mesh.corners(t).map(Vec3A::from);
            let (q, b) = tissue_bvh::closest_point_on_triangle(p.into(), c[0], c[1], c[2]);
            let d = q.distance_squared(p.into());
            if d < best.0 {
                best = (d, interpolate(&normals, *tri, b));
            }
        }
        best.1
    }

    /// The scan after a run: `sim_after` is the simulation surface after it (same triangles),
    /// `selection` and `patient` the region and the scan [`prepare_scan`] was given; the
    /// region's vertices move with the surface (module docs), the rest keep their positions
    /// bit for bit.
    ///
    /// # Errors
    /// [`ImplantError::InvalidParameter`] when `sim_after` is not a state of this surface, or
    /// `selection` / `patient` are not the ones it was made from; mesh errors if the moved scan
    /// is not a valid mesh.
    pub fn map_to_scan(
        &self,
        selection: &RegionSelection,
        patient: &TriMesh,
        sim_after: &TriMesh,
    ) -> Result<ScanResult, ImplantError> {
        let _span = tracing::info_span!("map_to_scan").entered();
        if patient.vertex_count() != self.scan_vertices
            || selection.mesh().vertex_count() != self.binding.len()
        {
            return Err(ImplantError::InvalidParameter {
                param: Param::Patient,
                value: patient.vertex_count() as f64,
                expected: format!(
                    "the scan of {} vertices and the region of {} vertices this simulation \
                     surface was made from",
                    self.scan_vertices,
                    self.binding.len()
                ),
            });
        }
        let stretch_sim = vertex_stretch(&self.mesh, sim_after)?;
        let (before, after) = (self.mesh.positions(), sim_after.positions());
        let (n_before, n_after) = (self.mesh.vertex_normals(), sim_after.vertex_normals());
        let region = selection.mesh();
        let mut region_after = region.positions().to_vec();
        let mut region_stretch = vec![1.0f32; region_after.len()];
        for (r, b) in self.binding.iter().enumerate() {
            if b.triangle == PINNED {
                continue;
            }
            let tri = self.mesh.triangles()[b.triangle as usize];
            let w = b.barycentric;
            let mut shift = Vec3::ZERO;
            let mut stretch = 0.0;
            for i in 0..3 {
                let v = tri[i] as usize;
                shift += (after[v] - before[v]) * w[i];
                stretch += stretch_sim[v] * w[i];
            }
            let turn = interpolate(&n_after, tri, w) - interpolate(&n_before, tri, w);
            region_after[r] += shift + turn * b.offset;
            region_stretch[r] = stretch;
        }
        if let Some(r) = region_after.iter().position(|p| !p.is_finite()) {
            return Err(ImplantError::InvalidParameter {
                param: Param::SimAfter,
                value: f64::NAN,
                expected: format!(
                    "finite positions, but region vertex {r} maps to a non-finite one: the run \
                     diverged"
                ),
            });
        }
        let region_after_mesh = region.with_positions(region_after.clone())?;
        let volume_difference = volume_between(region, &region_after_mesh)?;

        let n = patient.vertex_count();
        let mut positions = patient.positions().to_vec();
        let mut displacement = vec![0.0f32; n];
        let mut stretch = vec![1.0f32; n];
        let mut in_region = vec![false; n];
        for (r, &p) in selection.region_to_patient().iter().enumerate() {
            let p = p as usize;
            if p >= n {
                continue; // a vertex of a hole's fill
            }
            in_region[p] = true;
            stretch[p] = region_stretch[r];
            if self.binding[r].triangle != PINNED {
                positions[p] = region_after[r];
                displacement[p] = (region_after[r].as_dvec3() - patient.positions()[p].as_dvec3())
                    .length() as f32;
            }
        }
        // Areas of the scan's own triangles of the region.
        let mut area_before = 0.0f64;
        let mut area_after = 0.0f64;
        for (t, &pt) in selection.triangle_to_patient().iter().enumerate() {
            if (pt as usize) >= self.scan_triangles {
                continue;
            }
            let tri = region.triangles()[t];
            let area = |p: &[Vec3]| {
                let [a, b, c] = tri.map(|v| p[v as usize].as_dvec3());
                0.5 * (b - a).cross(c - a).length()
            };
            area_before += area(region.positions());
            area_after += area(&region_after);
        }
        // The largest move within one simulation edge of the seam.
        let band = selection.radius() - self.edge;
        let seam_max_move = region_after
            .iter()
            .zip(region.positions())
            .zip(selection.distances())
            .filter(|&(_, &d)| d >= band)
            .map(|((a, b), _)| a.distance(*b))
            .fold(0.0f32, f32::max);
        let patient_after = patient.with_positions(positions)?;
        Ok(ScanResult {
            patient_after,
            displacement,
            stretch,
            in_region,
            area_before,
            area_after,
            area_gain: area_after - area_before,
            volume_difference,
            seam_max_move,
        })
    }
}

/// Refuses a region that reaches an open border of the (filled) scan, with what would fit.
fn check_border(
    filled: &TriMesh,
    selection: &RegionSelection,
    open: &[Hole],
    radius: f64,
    max_hole: f64,
) -> Result<(), ImplantError> {
    let n = filled.vertex_count();
    let border = filled.topology().boundary_vertex_mask(n);
    let distances = selection.patient_distances();
    let Some(&nearest) = selection
        .region_to_patient()
        .iter()
        .filter(|&&v| border[v as usize])
        .min_by(|&&a, &&b| distances[a as usize].total_cmp(&distances[b as usize]))
    else {
        return Ok(());
    };
    let distance = distances[nearest as usize];
    // The open loop it is on: the scan's outer border (the longest open loop) or a hole.
    let longest = open.iter().map(|h| h.perimeter).fold(0.0f64, f64::max);
    let what = match open.iter().find(|h| h.vertices.contains(&nearest)) {
        Some(h) if h.perimeter < longest => format!(
            "a hole of the scan {:.2} cm across (only holes up to {max_hole:.2} cm are filled) \
             around {} cm",
            h.diameter,
            format_point(h.centroid)
        ),
        _ => "the scan's outer border".to_string(),
    };
    // A margin of one scan edge near the border keeps the region's boundary off it.
    let fit_radius = (distance * 0.95).max(0.0);
    let shrink_percent = 100.0 * (1.0 - fit_radius / radius);
    // Where a region of this radius would fit: the nearest vertex at least that far (along
    // the surface) from every open border.
    let from_border = border_distances(filled, &border);
    let centre = selection.centre().position();
    let needed = radius / 0.95;
    let elsewhere = (0..n)
        .filter(|&v| from_border[v] >= needed)
        .min_by(|&a, &b| {
            let (pa, pb) = (filled.positions()[a], filled.positions()[b]);
            pa.distance_squared(centre)
                .total_cmp(&pb.distance_squared(centre))
        });
    let elsewhere = match elsewhere {
        Some(v) => {
            let p = filled.positions()[v];
            format!(
                "a region of this radius fits around {} cm, {:.2} cm from the point picked",
                format_point(p),
                p.distance(centre)
            )
        }
        None => {
            let best = from_border
                .iter()
                .copied()
                .filter(|d| d.is_finite())
                .fold(0.0f64, f64::max);
            format!(
                "no point of this scan is {radius:.2} cm from its border: the largest region \
                 that fits anywhere has a radius of about {:.2} cm",
                best * 0.95
            )
        }
    };
    Err(ImplantError::RegionReachesBorder {
        radius,
        centre: centre.to_array(),
        what,
        distance,
        fit_radius,
        shrink_percent,
        elsewhere,
    })
}

fn format_point(p: Vec3) -> String {
    format!("({:.2}, {:.2}, {:.2})", p.x, p.y, p.z)
}

/// Distance along the edges from the nearest vertex of `border` (multi-source Dijkstra),
/// an upper bound of the geodesic distance (by at most about 8 % on a regular mesh).
fn border_distances(mesh: &TriMesh, border: &[bool]) -> Vec<f64> {
    #[derive(PartialEq)]
    struct Item(f64, u32);
    impl Eq for Item {}
    impl PartialOrd for Item {
        fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
            Some(self.cmp(other))
        }
    }
    impl Ord for Item {
        fn cmp(&self, other: &Self) -> Ordering {
            other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
        }
    }
    let n = mesh.vertex_count();
    let adjacency = VertexNeighbours::of(mesh);
    let p = mesh.positions();
    let mut dist = vec![f64::INFINITY; n];
    let mut heap = BinaryHeap::new();
    for v in 0..n {
        if border[v] {
            dist[v] = 0.0;
            heap.push(Item(0.0, v as u32));
        }
    }
    while let Some(Item(d, v)) = heap.pop() {
        if d > dist[v as usize] {
            continue;
        }
        for &w in adjacency.of_vertex(v) {
            let nd = d + f64::from(p[v as usize].distance(p[w as usize]));
            if nd < dist[w as usize] {
                dist[w as usize] = nd;
                heap.push(Item(nd, w));
            }
        }
    }
    dist
}
