//! The driver: check → interior points → insert → carve → build and measure.

use glam::Vec3;
use tissue_mesh::{TetMesh, TriMesh};

use crate::carve::carve;
use crate::check::{check_raw, check_surface};
use crate::delaunay::{Delaunay, DelaunayFailure};
use crate::estimate::TetEstimate;
use crate::improve::improve;
use crate::inside::RayCaster;
use crate::lattice::interior_points;
use crate::order::insertion_order;
use crate::predicates::P3;
use crate::quality::QualityReport;
use crate::{TetCount, TetraError};

/// Most lattice points (in the surface's bounding box) a spacing may ask for.
const MAX_LATTICE_POINTS: f64 = 2e7;

/// With [`TetraOptions::max_tets`], the Delaunay tetrahedralisation under construction may hold
/// at most `DELAUNAY_PER_ESTIMATED_TET ×` the estimated count `+ DELAUNAY_SLACK` tetrahedra
/// (live and free slots). Evenly sampled surfaces need at most 2× (1.4× for the bunny and the
/// MakeHuman body, 2.0× for the armadillo and a 256-triangle sphere, whose convex hulls are
/// large for their size); points badly distributed for Delaunay (many on a few lines, whose
/// tetrahedralisation grows with the square of their number while the estimate grows with the
/// number) outgrow it early, before the carving and recovery that would take long on them.
const DELAUNAY_PER_ESTIMATED_TET: usize = 4;
const DELAUNAY_SLACK: usize = 1000;

/// Options of [`tetrahedralize`]. `TetraOptions::default()` gives about 40 000 tetrahedra for a
/// 10 000-triangle bunny.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetraOptions {
    /// Spacing `a` of the interior BCC lattice (edge of its cubes), in the surface's units (cm).
    /// `None`: `spacing_factor` × the mean surface edge length. A spacing that would put more
    /// than 2·10⁷ lattice points in the bounding box is refused.
    pub spacing: Option<f32>,
    /// The default spacing as a multiple of the mean surface edge length (used when `spacing`
    /// is `None`). Default 1.68.
    pub spacing_factor: f32,
    /// Interior points are kept at least `clearance · a` away from the surface. Default 0.5.
    pub clearance: f32,
    /// Add interior points at all; `false` gives the Delaunay tetrahedralisation of the surface
    /// vertices alone, carved. Default `true`.
    pub interior_points: bool,
    /// Boundary tetrahedra whose radius ratio is below this are peeled off after carving and
    /// sliver removal (repeatedly, as peeling exposes new ones) when that takes no surface
    /// triangle off the boundary. Default 0.02; 0 keeps them.
    pub sliver_radius_ratio: f32,
    /// Boundary tetrahedra whose radius ratio is below this are peeled off even when that takes
    /// surface triangles off the boundary. Default 0.001 (dihedral angles of about 0.1°).
    pub degenerate_radius_ratio: f32,
    /// The most tetrahedra to make, so that the work is bounded whatever the surface. With
    /// `Some(m)`, [`tetrahedralize`] refuses with [`TetraError::TooManyTets`]: before any meshing
    /// when [`estimate_tets`](crate::estimate_tets) expects more than `m`
    /// ([`TetCount::Estimated`]); while inserting points when the Delaunay tetrahedralisation
    /// outgrows 4 × the estimate + 1000 tetrahedra, so the estimate was wrong: the surface's
    /// points are badly spread, e.g. many on a few lines ([`TetCount::Delaunay`]); and at the
    /// end when more than `m` were made ([`TetCount::Made`]). The work is then linear in `m`
    /// up to the Delaunay tetrahedralisation. Default `None`: no limit.
    pub max_tets: Option<usize>,
}

impl Default for TetraOptions {
    fn default() -> Self {
        TetraOptions {
            spacing: None,
            spacing_factor: 1.68,
            clearance: 0.5,
            interior_points: true,
            sliver_radius_ratio: 0.02,
            degenerate_radius_ratio: 0.001,
            max_tets: None,
        }
    }
}

impl TetraOptions {
    /// The lattice spacing for a surface whose mean edge is `mean_edge`.
    pub(crate) fn spacing_for(&self, mean_edge: f64) -> f32 {
        self.spacing
            .unwrap_or((f64::from(self.spacing_factor) * mean_edge) as f32)
    }

    /// [`TetraOptions::spacing_for`], refused when it is not a positive length.
    pub(crate) fn check_spacing(&self, mean_edge: f64) -> Result<f32, TetraError> {
        let spacing = self.spacing_for(mean_edge);
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(TetraError::InvalidOption {
                what: format!("the spacing came out as {spacing}; give one explicitly"),
            });
        }
        Ok(spacing)
    }

    pub(crate) fn validate(&self) -> Result<(), TetraError> {
        let bad = |what: String| Err(TetraError::InvalidOption { what });
        if let Some(s) = self.spacing {
            if !(s.is_finite() && s > 0.0) {
                return bad(format!("spacing = {s}, must be finite and positive"));
            }
        }
        if !(self.spacing_factor.is_finite() && self.spacing_factor > 0.0) {
            return bad(format!(
                "spacing_factor = {}, must be finite and positive",
                self.spacing_factor
            ));
        }
        if !(self.clearance.is_finite() && (0.0..=2.0).contains(&self.clearance)) {
            return bad(format!("clearance = {}, must be in [0, 2]", self.clearance));
        }
        if !(self.sliver_radius_ratio.is_finite() && (0.0..1.0).contains(&self.sliver_radius_ratio))
        {
            return bad(format!(
                "sliver_radius_ratio = {}, must be in [0, 1)",
                self.sliver_radius_ratio
            ));
        }
        if !(self.degenerate_radius_ratio.is_finite()
            && (0.0..1.0).contains(&self.degenerate_radius_ratio))
        {
            return bad(format!(
                "degenerate_radius_ratio = {}, must be in [0, 1)",
                self.degenerate_radius_ratio
            ));
        }
        if self.max_tets == Some(0) {
            return bad("max_tets = 0, must be at least 1 (or None: no limit)".to_owned());
        }
        Ok(())
    }
}

/// The result of [`tetrahedralize`].
#[derive(Debug, Clone, PartialEq)]
pub struct Tetrahedralization {
    /// The tetrahedra. Nodes `0..surface_nodes` are the surface's vertices in its order, the rest
    /// interior points.
    pub mesh: TetMesh,
    /// Its quality, measured against the input surface.
    pub report: QualityReport,
    /// The interior lattice spacing used (cm).
    pub spacing: f32,
    /// Boundary slivers peeled off.
    pub slivers_removed: usize,
}

/// Fills a closed surface with tetrahedra. See the crate doc for the algorithm and guarantees.
///
/// # Errors
/// [`TetraError::OpenSurface`], [`TetraError::NonManifoldVertex`],
/// [`TetraError::CoincidentVertices`], [`TetraError::InsideOut`], [`TetraError::NoVolume`],
/// [`TetraError::TooFewPoints`] for a surface that cannot be filled;
/// [`TetraError::InvalidOption`]; [`TetraError::TooManyTets`] beyond
/// [`TetraOptions::max_tets`]; [`TetraError::NumericalFailure`] if the mesher itself fails.
pub fn tetrahedralize(
    surface: &TriMesh,
    options: &TetraOptions,
) -> Result<Tetrahedralization, TetraError> {
    let _span = tracing::info_span!(
        "tetrahedralize",
        vertices = surface.vertex_count(),
        triangles = surface.triangle_count()
    )
    .entered();
    options.validate()?;
    let checked = {
        let _s = tracing::debug_span!("check").entered();
        check_surface(surface)?
    };
    let n_surface = surface.vertex_count();
    let spacing = options.check_spacing(checked.mean_edge)?;
    // With a limit, the estimate refuses what is clearly too large before any meshing; the
    // Delaunay and final counts below catch what it misjudged.
    let limit = options
        .max_tets
        .map(|max| Limit::new(max, TetEstimate::new(surface, &checked, options)));
    if let Some(limit) = &limit {
        tracing::debug!(
            estimated = limit.estimate.tets,
            max = limit.max,
            "estimated tets"
        );
        limit.check(limit.estimate.tets, TetCount::Estimated)?;
    }
    if options.interior_points {
        let bb = surface.bounding_box();
        let cells: f64 = (0..3)
            .map(|k| (f64::from(bb.max[k] - bb.min[k]) / f64::from(spacing)).floor() + 3.0)
            .product();
        if 2.0 * cells > MAX_LATTICE_POINTS {
            return Err(TetraError::InvalidOption {
                what: format!(
                    "spacing = {spacing} would put about {:.1e} lattice points in the surface's \
                     bounding box (at most {MAX_LATTICE_POINTS:.0e}); use a larger spacing",
                    2.0 * cells
                ),
            });
        }
    }
    let to_p3 = |p: Vec3| -> P3 { [f64::from(p.x), f64::from(p.y), f64::from(p.z)] };
    let tris: Vec<[P3; 3]> = surface
        .triangles()
        .iter()
        .map(|t| t.map(|v| to_p3(surface.positions()[v as usize])))
        .collect();
    let caster = RayCaster::new(tris.clone());

    let interior = if options.interior_points {
        let _s = tracing::debug_span!("lattice", spacing).entered();
        interior_points(
            &tris,
            &caster,
            f64::from(spacing),
            f64::from(options.clearance),
        )
    } else {
        Vec::new()
    };
    tracing::debug!(interior = interior.len(), spacing, "interior points");

    let mut pts: Vec<P3> = surface.positions().iter().map(|&p| to_p3(p)).collect();
    pts.extend_from_slice(&interior);
    let candidates: Vec<u32> = (0..pts.len() as u32)
        .filter(|&i| (i as usize) >= n_surface || checked.used[i as usize])
        .collect();

    let dt = {
        let _s = tracing::info_span!("insert", points = candidates.len()).entered();
        let cand_pts: Vec<P3> = candidates.iter().map(|&i| pts[i as usize]).collect();
        let order = insertion_order(&cand_pts);
        let mut dt = Delaunay::new(pts.clone());
        for &k in &order {
            dt.insert(candidates[k as usize]).map_err(failure)?;
            if let Some(limit) = &limit {
                limit.check(dt.tets.len(), TetCount::Delaunay)?;
            }
        }
        tracing::debug!(
            walk_steps = dt.walk_steps,
            cavity_tets = dt.cavity_tets,
            "inserted"
        );
        dt
    };

    let (tets, stats) = {
        let _s = tracing::info_span!("carve").entered();
        let tets = carve(&dt, &caster);
        improve(
            &dt.pts,
            tets,
            surface,
            f64::from(options.sliver_radius_ratio),
            f64::from(options.degenerate_radius_ratio),
        )
    };
    tracing::debug!(
        recovered_quads = stats.recovered_quads,
        sliver_edges_removed = stats.sliver_edges_removed,
        peeled = stats.peeled,
        flat_dropped = stats.flat_dropped,
        "improved"
    );
    let slivers_removed = stats.peeled + stats.flat_dropped;
    if let Some(limit) = &limit {
        limit.check(tets.len(), TetCount::Made)?;
    }
    if tets.is_empty() {
        return Err(TetraError::NumericalFailure {
            stage: "carving",
            vertex: None,
            detail: "no tetrahedron lies inside the surface".into(),
        });
    }

    let _s = tracing::info_span!("quality").entered();
    // Renumber: surface vertices keep their numbers; interior points used by a tet follow, in
    // lattice order.
    let mut new_index = vec![u32::MAX; pts.len()];
    for (v, slot) in new_index.iter_mut().enumerate().take(n_surface) {
        *slot = v as u32;
    }
    let mut used_interior = vec![false; pts.len()];
    for t in &tets {
        for &v in t {
            used_interior[v as usize] = v as usize >= n_surface;
        }
    }
    let mut positions: Vec<Vec3> = surface.positions().to_vec();
    for v in n_surface..pts.len() {
        if used_interior[v] {
            new_index[v] = positions.len() as u32;
            let p = pts[v];
            positions.push(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32));
        }
    }
    let tets: Vec<[u32; 4]> = tets
        .iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    let mesh = TetMesh::new(positions, tets).map_err(|e| TetraError::NumericalFailure {
        stage: "building the mesh",
        vertex: None,
        detail: e.to_string(),
    })?;
    let report = QualityReport::measure(&mesh, surface);
    debug_assert!(checked.volume > 0.0);
    tracing::info!(
        tets = report.tets,
        nodes = report.nodes,
        volume_ratio = report.volume_ratio,
        "tetrahedralized"
    );
    Ok(Tetrahedralization {
        mesh,
        report,
        spacing,
        slivers_removed,
    })
}

/// [`tetrahedralize`] for raw surface data: validates it first (see [`tissue_mesh::diagnose`]),
/// naming the defect.
///
/// # Errors
/// As [`tetrahedralize`], plus [`TetraError::NonManifoldEdge`], [`TetraError::DegenerateTriangle`]
/// and [`TetraError::InvalidSurface`] for data that do not make a [`TriMesh`].
pub fn tetrahedralize_triangles(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    options: &TetraOptions,
) -> Result<Tetrahedralization, TetraError> {
    check_raw(positions, triangles)?;
    let surface =
        TriMesh::new(positions.to_vec(), triangles.to_vec()).map_err(TetraError::InvalidSurface)?;
    tetrahedralize(&surface, options)
}

/// [`TetraOptions::max_tets`] and the estimate it is checked against.
struct Limit {
    max: usize,
    estimate: TetEstimate,
}

impl Limit {
    fn new(max: usize, estimate: TetEstimate) -> Self {
        Limit { max, estimate }
    }

    /// Refuses `tets` counted `when` above the limit for that count.
    fn check(&self, tets: usize, when: TetCount) -> Result<(), TetraError> {
        let allowed = match when {
            TetCount::Estimated | TetCount::Made => self.max,
            TetCount::Delaunay => self
                .estimate
                .tets
                .saturating_mul(DELAUNAY_PER_ESTIMATED_TET)
                .saturating_add(DELAUNAY_SLACK),
        };
        if tets <= allowed {
            return Ok(());
        }
        Err(TetraError::TooManyTets {
            tets,
            max: self.max,
            when,
            triangles: self.estimate.triangles,
            decimate_to: self.estimate.triangles_for(self.max),
        })
    }
}

fn failure(f: DelaunayFailure) -> TetraError {
    let (vertex, detail) = match f {
        DelaunayFailure::WalkDidNotEnd { point } => {
            (point, "the point-location walk did not end".to_string())
        }
        DelaunayFailure::OutsideSuperTet { point } => (
            point,
            "the point lies outside the enclosing tetrahedron".to_string(),
        ),
        DelaunayFailure::OpenCavity { point } => {
            (point, "the cavity had an open boundary".to_string())
        }
    };
    TetraError::NumericalFailure {
        stage: "inserting points",
        vertex: Some(vertex),
        detail,
    }
}
