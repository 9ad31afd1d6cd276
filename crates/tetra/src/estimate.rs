//! How many tetrahedra [`tetrahedralize`](crate::tetrahedralize) will make, estimated before any
//! meshing from the quantities that set it.
//!
//! The mesher inserts the surface's vertices and the points of a body-centred cubic lattice of
//! spacing `a` (two points per `a³` cell) that lie inside the surface at least `clearance · a`
//! from it. So, with `V` the enclosed volume and `A` the surface's area:
//!
//! - interior points `I ≈ 2 (V − clearance · a · A) / a³` (the lattice fills the volume less a
//!   shell of thickness `clearance · a` under the surface; 0 when that is negative);
//! - tetrahedra `T ≈ 6 I + 3 S`, `S` the surface vertices in use: the BCC lattice's Delaunay
//!   tetrahedralisation has exactly 6 tetrahedra per point, and the layer between lattice and
//!   surface about 3 per surface vertex (fitted on the bunny, the liver, the armadillo, spheres
//!   and cubes, flat and long boxes: 2.5–3.1 per vertex).
//!
//! Measured against the mesher (`tests/tetra.rs`): within 0.91–1.04× on every surface tested
//! (bunny 39 176 estimated / 39 706 made, liver 6 352 / 6 336, armadillo 3 354 / 3 656, the
//! MakeHuman body 133 339 / 132 782, the bunny refined to 40 000 triangles 285 997 / 288 074,
//! spheres, cubes, flat and long boxes, an explicit spacing); the tests hold it to 0.8–1.25×. It counts what is carved, not the mesher's work on a surface
//! whose points are badly distributed (many of them on a few lines); [`TetraOptions::max_tets`]
//! bounds that too.

use tissue_mesh::TriMesh;

use crate::check::{check_surface, CheckedSurface};
use crate::mesher::TetraOptions;
use crate::TetraError;

/// Tetrahedra per interior lattice point (the BCC lattice's Delaunay tetrahedralisation).
const TETS_PER_INTERIOR_POINT: f64 = 6.0;
/// Tetrahedra per surface vertex (the layer between the lattice and the surface), fitted.
const TETS_PER_SURFACE_VERTEX: f64 = 3.0;

/// What [`tetrahedralize`](crate::tetrahedralize) is expected to make of a surface
/// ([`estimate_tets`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetEstimate {
    /// About this many tetrahedra (see the module doc for its accuracy).
    pub tets: usize,
    /// About this many interior lattice points.
    pub interior_points: usize,
    /// Surface vertices used by a triangle (all inserted).
    pub surface_vertices: usize,
    /// The surface's triangles.
    pub triangles: usize,
    /// The interior lattice spacing the mesher would use (surface units, cm).
    pub spacing: f32,
    /// The enclosed volume (surface units cubed).
    pub volume: f64,
    /// The surface's area (surface units squared).
    pub area: f64,
    clearance: f64,
    interior: bool,
    /// Whether the spacing follows the surface's edge length (no explicit `spacing`).
    spacing_follows_edges: bool,
}

impl TetEstimate {
    pub(crate) fn new(surface: &TriMesh, checked: &CheckedSurface, options: &TetraOptions) -> Self {
        let spacing = options.spacing_for(checked.mean_edge);
        let surface_vertices = checked.used.iter().filter(|&&u| u).count();
        let mut estimate = TetEstimate {
            tets: 0,
            interior_points: 0,
            surface_vertices,
            triangles: surface.triangle_count(),
            spacing,
            volume: checked.volume,
            area: surface.area(),
            clearance: f64::from(options.clearance),
            interior: options.interior_points,
            spacing_follows_edges: options.spacing.is_none(),
        };
        let (interior, tets) = estimate.at_scale(1.0);
        estimate.interior_points = interior.round() as usize;
        estimate.tets = tets.round().min(usize::MAX as f64) as usize;
        estimate
    }

    /// (interior points, tetrahedra) for the same shape with `x` times as many triangles, evenly
    /// sized (so `x` times the surface vertices and, when the spacing follows the edges, a
    /// spacing `1/√x` times as large).
    fn at_scale(&self, x: f64) -> (f64, f64) {
        let a = f64::from(self.spacing)
            * if self.spacing_follows_edges {
                1.0 / x.sqrt()
            } else {
                1.0
            };
        let interior = if self.interior && a > 0.0 {
            (2.0 * (self.volume - self.clearance * a * self.area) / a.powi(3)).max(0.0)
        } else {
            0.0
        };
        let tets = TETS_PER_INTERIOR_POINT * interior
            + TETS_PER_SURFACE_VERTEX * self.surface_vertices as f64 * x;
        (interior, tets)
    }

    /// About how many triangles the same shape, remeshed evenly (decimated), may have to fill
    /// with at most `tets` tetrahedra under the same options; `None` when no decimation gets
    /// there (an explicit spacing too fine for the volume).
    pub fn triangles_for(&self, tets: usize) -> Option<usize> {
        let target = tets as f64;
        if self.at_scale(1.0).1 <= target {
            return Some(self.triangles);
        }
        // The count grows with the scale (the interior term, where positive, grows faster than
        // its shell): bisect on the scale.
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        if self.at_scale(4.0 / self.triangles.max(4) as f64).1 > target {
            return None;
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.at_scale(mid).1 <= target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(((self.triangles as f64 * lo).floor() as usize).max(4))
    }
}

/// Estimates what [`tetrahedralize`](crate::tetrahedralize) would make of `surface` with
/// `options`, in time linear in the surface (no lattice, no Delaunay): the surface is checked as
/// the mesher checks it, then the count follows from its volume, area, vertices and the lattice
/// spacing `options` give (module doc).
///
/// ```
/// use tissue_tetra::{estimate_tets, tetrahedralize, TetraOptions};
///
/// let sphere = tissue_mesh::uv_sphere(64, 32, 1.0)?;
/// let estimate = estimate_tets(&sphere, &TetraOptions::default())?;
/// let made = tetrahedralize(&sphere, &TetraOptions::default())?.report.tets;
/// let ratio = estimate.tets as f64 / made as f64;
/// assert!((0.8..=1.25).contains(&ratio), "{} estimated, {made} made", estimate.tets);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// The surface and option errors of [`tetrahedralize`](crate::tetrahedralize), found the same
/// way.
pub fn estimate_tets(surface: &TriMesh, options: &TetraOptions) -> Result<TetEstimate, TetraError> {
    options.validate()?;
    let checked = check_surface(surface)?;
    options.check_spacing(checked.mean_edge)?;
    Ok(TetEstimate::new(surface, &checked, options))
}
