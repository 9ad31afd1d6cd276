//! The implant-insertion run (SPEC A.5): a tissue expander under a skin region, the region
//! lifted by the implant's height and relaxing back onto it.
//!
//! - The tissue is [`TissueLayers`]; the implant is a mass–spring system of its own: springs on
//!   its surface from its silicone shell (Van Gelder, eq. 3), volume preservation (eq. 5) for its
//!   saline fill, mass = volume × density of water.
//! - **The implant's base is held by the deeper tissue**: the expander lies on fascia, muscle or
//!   bone, far stiffer than the skin and fat it pushes up, so its base vertices are fixed where
//!   they were built (on layer 2's rest surface, [`place_implant`]). The dome and its rim move.
//! - Before the run every free tissue particle is lifted by the implant's dome height (plus twice
//!   the contact distance) along the region's normals (SPEC A.5 step 3); the layers then fall
//!   back, held by their anchors, and collide with the implant, which is squeezed but keeps its
//!   volume.
//! - The step is [`ContactRun::step`]; the run ends on the stop criterion or the step limit, and
//!   a progress callback between steps may cancel it.

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use tissue_bvh::{BuildOptions, Bvh, BvhWorkspace, Ray, Triangles};
use tissue_mesh::{volume_between, TriMesh};
use tissue_mss::{
    masses_from_triangles, springs_from_triangles_floored, MassSpringSystem, Particles,
    SheetMaterial, StopReason, VolumePreservation, VolumePressure, WATER_DENSITY,
};

use crate::contact_run::{ContactRun, RunParams, StepSummary};
use crate::outcome::{replace_region, vertex_displacements, vertex_stretch};
use crate::quasi_static::{StaticParams, StaticReport};
use crate::walk::{walk_on_surface, WalkEnd};
use crate::Param;
use crate::{
    Implant, ImplantError, ImplantFrame, ImplantSpec, Layer, LayerParams, RegionSelection,
    SearchedSurface, TissueLayers,
};

/// The implant's mechanics. Units: cm, g, s.
#[derive(Debug, Clone, PartialEq)]
pub struct ImplantParams {
    /// Young's modulus of the silicone shell, g/(cm·s²).
    pub shell_young: f64,
    /// Poisson ratio of the shell.
    pub shell_poisson: f64,
    /// Shell thickness, cm.
    pub shell_thickness: f64,
    /// Density of the fill, g/cm³ (saline: water).
    pub fill_density: f64,
    /// Bulk modulus of the fill, g/(cm·s²): the pressure per relative volume change of the
    /// enclosed fill ([`tissue_mss::VolumePressure`]), which holds the volume itself.
    pub fill_bulk_modulus: f64,
    /// The stiffness of eq. (5)'s volume preservation, the thesis's, given as a modulus: `k_v`
    /// is derived so that a uniform inward move `δ` of every vertex would meet the pressure
    /// `3·k_v·T²·δ/A` (`T` triangles, area `A`), i.e. `k_v = K_r·A²/(3·T²·V)`. Eq. (5) holds
    /// area-weighted radial lengths, which a dome flattened on its top keeps while losing
    /// volume, so it gives the shape's response and the fill's pressure the volume.
    pub radial_modulus: f64,
    /// Eq. (5)'s `C` in (0, 1): the weight of a particle's own radial change.
    pub volume_coupling: f64,
}

impl Default for ImplantParams {
    /// A silicone elastomer shell of `E` = 3 MPa (medical silicones are 1–10 MPa), `ν` = 0.45,
    /// 0.05 cm thick (expander shells are about 0.5 mm); saline fill of density 1 g/cm³ and a
    /// bulk modulus of 10 MPa — far below water's 2.2 GPa, whose breathing mode would set the
    /// step, but stiff enough to hold the volume within `p/K`, inside the 2 % the validation
    /// allows; eq. (5) at a radial modulus of 10 MPa with `C` = 0.5.
    fn default() -> Self {
        ImplantParams {
            shell_young: 3.0e7,
            shell_poisson: 0.45,
            shell_thickness: 0.05,
            fill_density: WATER_DENSITY,
            fill_bulk_modulus: 1.0e8,
            radial_modulus: 1.0e8,
            volume_coupling: 0.5,
        }
    }
}

impl ImplantParams {
    fn check(&self) -> Result<(), ImplantError> {
        for (param, value) in [
            (Param::ShellYoung, self.shell_young),
            (Param::ShellThickness, self.shell_thickness),
            (Param::FillDensity, self.fill_density),
            (Param::FillBulkModulus, self.fill_bulk_modulus),
            (Param::RadialModulus, self.radial_modulus),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ImplantError::InvalidParameter {
                    param,
                    value,
                    expected: "positive and finite".into(),
                });
            }
        }
        if !(0.0..0.5).contains(&self.shell_poisson) {
            return Err(ImplantError::InvalidParameter {
                param: Param::ShellPoisson,
                value: self.shell_poisson,
                expected: "in [0, 0.5)".into(),
            });
        }
        if !(self.volume_coupling > 0.0 && self.volume_coupling < 1.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::VolumeCoupling,
                value: self.volume_coupling,
                expected: "in (0, 1)".into(),
            });
        }
        Ok(())
    }
}

/// How a run reaches the tissue's rest state over the filled expander.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Solver {
    /// Steps the thesis's explicit (symplectic) Euler until the stop criterion fires: the
    /// default, and the reference the quasi-static solver is checked against.
    #[default]
    Explicit,
    /// Solves for the static equilibrium directly ([`StaticParams`]): Newton steps by
    /// conjugate gradients preconditioned with the springs' prefactored Laplacian, penalty
    /// contacts, load steps, stopped on a force tolerance. Experimental: see
    /// docs/validation.md for where it converges and where it does not yet.
    QuasiStatic,
}

impl Solver {
    /// Every solver, the default first.
    pub const ALL: [Solver; 2] = [Solver::Explicit, Solver::QuasiStatic];

    /// The solver's name in reports and on command lines: `"quasi_static"`, `"explicit"`.
    pub fn name(self) -> &'static str {
        match self {
            Solver::QuasiStatic => "quasi_static",
            Solver::Explicit => "explicit",
        }
    }
}

/// Everything a run needs besides its geometry: one parameter set serves every scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct InsertionParams {
    /// How the rest state is found.
    pub solver: Solver,
    /// The quasi-static solver's tolerance, load steps and limits (unused by the explicit one).
    pub statics: StaticParams,
    /// The tissue.
    pub layers: LayerParams,
    /// The implant.
    pub implant: ImplantParams,
    /// Stepping, collisions, stopping.
    pub run: RunParams,
    /// How long the expander takes to fill (s): its dome rises from flat to full at constant
    /// speed, then is released to the forces.
    pub fill_time: f32,
    /// How far beyond the expander's base the pocket is dissected (cm): layer-2 particles
    /// within this distance of the base lose their anchors ([`TissueLayers::detach`]).
    pub pocket_margin: f32,
}

impl Default for InsertionParams {
    /// The defaults of each part; a 2.5 ms fill: short, yet the tissue, damped at 1 ms,
    /// follows the rising dome, so the end state is that of a slower fill; a pocket 0.3 cm
    /// wider than the base (surgeons dissect the pocket a little beyond the expander's edge;
    /// a wider pocket lets more of the free tissue around the expander rise).
    fn default() -> Self {
        InsertionParams {
            solver: Solver::default(),
            statics: StaticParams::default(),
            layers: LayerParams::default(),
            implant: ImplantParams::default(),
            run: RunParams::default(),
            fill_time: 0.0025,
            pocket_margin: 0.3,
        }
    }
}

/// Where the implant's dome starts filling from: every dome vertex at its footing on the
/// base's surface ([`Implant::flat_positions`]), base vertices where they are. A flat disc
/// through the lowest base vertex instead stood out of layer 2 just beyond the rim of an
/// expander wrapped round a limb (the dome's side vertices stand along the tilted normal there),
/// and a finer layer 2, whose gap below the base is smaller, started crossed by it: a tube's
/// round expander at a 0.09 cm edge started with 66 layer-2 edges through it and blew up.
fn flat_start(implant: &Implant) -> Vec<Vec3A> {
    implant
        .flat_positions()
        .iter()
        .map(|&x| Vec3A::from(x))
        .collect()
}

/// Builds `spec` on layer 2's rest surface under `layers` (a fifth of an edge below it, so that
/// the two start apart), centred under the region point `centre` (on layer 1) and wrapped onto
/// layer 2 ([`ImplantSpec::build_wrapped`]): the base's plan point `(x, y)` goes where a walk
/// of length `√(x² + y²)` along layer 2 in the direction `x·t + y·b` ends ([`walk_on_surface`],
/// the surface's exponential map), and the dome stands on it along layer 2's interpolated
/// vertex normal there. The frame's normal is `normal` (the region's at the centre), its
/// tangent `t` the part of `tangent` across it; the walk starts where a ray from `centre` down
/// that normal meets layer 2.
///
/// On a plane this is the flat expander; on a limb the base wraps around the limb without
/// stretching, round and rectangular alike, as far as the region reaches.
///
/// # Errors
/// [`ImplantError::FootprintOutsideRegion`] when a walk leaves layer 2 through its boundary
/// (the region is too small for the implant) or the ray from the centre misses layer 2, and
/// the errors of [`ImplantSpec::build_wrapped`] and [`ImplantFrame::new`].
pub fn place_implant(
    layers: &TissueLayers,
    spec: &ImplantSpec,
    centre: Vec3,
    normal: Vec3,
    tangent: Vec3,
) -> Result<Implant, ImplantError> {
    let _span = tracing::debug_span!("place_implant").entered();
    let frame = ImplantFrame::new(centre, normal, tangent)?;
    let inner = layers.rest(Layer::Inner);
    let positions: Vec<Vec3A> = inner.positions().iter().map(|&p| p.into()).collect();
    let searchable = |source| ImplantError::Search {
        surface: SearchedSurface::RegionInnerLayer,
        source,
    };
    let triangles = Triangles::new(&positions, inner.triangles()).map_err(searchable)?;
    let bvh = Bvh::build(&triangles, &BuildOptions::default()).map_err(searchable)?;
    let reach = (inner.bounding_box().size().length() + 1.0) * 2.0;
    let gap = f64::from(0.2 * crate::contact_run::mean_edge_length(inner));
    let down = Vec3A::from(-frame.normal());
    let ray = Ray::new(Vec3A::from(centre) - down * reach, down);
    let mut ws = BvhWorkspace::default();
    let Some(hit) = bvh.cast_ray(&triangles, &ray, 2.0 * reach, &mut ws) else {
        return Err(ImplantError::FootprintOutsideRegion { x: 0.0, y: 0.0 });
    };
    let start_triangle = hit.primitive;
    let start = (Vec3A::from(centre) + down * (hit.t - reach)).as_dvec3();
    // The frame's axes laid into the start triangle's plane.
    let corners = inner.corners(start_triangle as usize).map(|p| p.as_dvec3());
    let n0 = (corners[1] - corners[0])
        .cross(corners[2] - corners[0])
        .normalize_or_zero();
    let t0 = frame.tangent().as_dvec3();
    let t0 = (t0 - n0 * t0.dot(n0)).normalize_or_zero();
    let b0 = n0.cross(t0);
    let vertex_normals = inner.vertex_normals();
    let inner_triangles = inner.triangles();
    let place = |x: f32, y: f32| {
        let (x64, y64) = (f64::from(x), f64::from(y));
        let length = x64.hypot(y64);
        let direction = if length > 0.0 {
            t0 * x64 + b0 * y64
        } else {
            t0
        };
        match walk_on_surface(inner, start_triangle, start, direction, length) {
            WalkEnd::Reached {
                triangle,
                barycentric,
                position,
                ..
            } => {
                let tri = inner_triangles[triangle as usize];
                let up = (0..3)
                    .map(|i| vertex_normals[tri[i] as usize].as_dvec3() * barycentric[i])
                    .sum::<glam::DVec3>()
                    .normalize_or_zero();
                let up = if up == glam::DVec3::ZERO { n0 } else { up };
                Ok((position.as_vec3(), up.as_vec3()))
            }
            WalkEnd::Boundary { .. } => Err(ImplantError::FootprintOutsideRegion { x, y }),
        }
    };
    let implant = spec.build_wrapped_with_gap(gap, place)?;
    // The gap is laid at the base's vertices; between them the base's flat triangles cut across
    // a layer 2 that curves more tightly than they can follow (a coarse expander over a navel's
    // dimple, a tube's creases), and layer 2 can start on the wrong side of them. Then the whole
    // base goes down by the shortfall.
    let shortfall = base_clearance_shortfall(inner, &implant, 0.5 * gap as f32)?;
    if shortfall > 0.0 {
        tracing::debug!(shortfall, "base lowered under layer 2");
        spec.build_wrapped_with_gap(gap + f64::from(shortfall), place)
    } else {
        Ok(implant)
    }
}

/// The smallest distance (cm) from `implant`'s rim to the fixed border of `layers`' layer 2
/// at rest: how much tissue is left between the expander and what holds the region. On a
/// generous region it is about the region radius less the footprint's; where the region runs
/// into a crease (the groin, from a 7 cm expander just below the navel) it can fall to less than
/// one edge, and that run diverged at half its simulation edge.
pub fn rim_border_clearance(layers: &TissueLayers, implant: &Implant) -> f64 {
    let inner = layers.rest(Layer::Inner);
    let border: Vec<Vec3> = layers
        .boundary()
        .iter()
        .map(|&v| inner.positions()[v as usize])
        .collect();
    let p = implant.mesh().positions();
    implant
        .rim()
        .flat_map(|v| border.iter().map(move |b| b.distance(p[v as usize])))
        .fold(f32::INFINITY, f32::min)
        .into()
}

/// How much further the emptied `implant`'s base must go down so that every vertex of `inner`
/// (layer 2 at rest) over it is at least `clearance` above it (cm, 0 when all are). A vertex
/// counts as over the base when its closest point on the base's triangles is its foot along
/// that triangle's normal (vertices beyond the rim, whose closest point is on the outline, do
/// not count).
fn base_clearance_shortfall(
    inner: &TriMesh,
    implant: &Implant,
    clearance: f32,
) -> Result<f32, ImplantError> {
    let flat: Vec<Vec3A> = implant.flat_positions().iter().map(|&p| p.into()).collect();
    let base = implant.base();
    let base_triangles: Vec<[u32; 3]> = implant
        .mesh()
        .triangles()
        .iter()
        .copied()
        .filter(|t| t.iter().all(|v| base.contains(v)))
        .collect();
    let unsearchable = |source| ImplantError::Search {
        surface: SearchedSurface::ImplantBase,
        source,
    };
    let triangles = Triangles::new(&flat, &base_triangles).map_err(unsearchable)?;
    let bvh = Bvh::build(&triangles, &BuildOptions::default()).map_err(unsearchable)?;
    let mut ws = BvhWorkspace::default();
    let reach = 4.0 * clearance.max(f32::MIN_POSITIVE);
    let mut shortfall = 0.0f32;
    for &x in inner.positions() {
        let x = Vec3A::from(x);
        let Some(hit) = bvh.closest_point(&triangles, x, reach, &mut ws) else {
            continue;
        };
        let [a, b, c] = base_triangles[hit.primitive as usize].map(|v| flat[v as usize]);
        // The base's outward normal points away from the dome, into the body.
        let inward = -(b - a).cross(c - a).normalize_or_zero();
        let height = (x - hit.point).dot(inward);
        if (hit.distance - height.abs()).abs() > 1e-3 * reach {
            continue;
        }
        shortfall = shortfall.max(clearance - height);
    }
    Ok(shortfall)
}

/// Detaches layer 2 over the expander's pocket: every region vertex whose layer-2 rest position
/// lies within `margin` of the implant's base triangles loses its anchor. Returns how many.
///
/// A surgeon places an expander in a pocket dissected free of the deeper tissue, a little wider
/// than the expander; outside it the tissue stays attached. Anchors over the expander would
/// pull the tissue back into it with the full stiffness of the attachment.
pub fn dissect_pocket(layers: &mut TissueLayers, implant: &Implant, margin: f32) -> usize {
    let mesh = implant.mesh();
    let p = mesh.positions();
    let base: Vec<[Vec3A; 3]> = mesh
        .triangles()
        .iter()
        .filter(|t| t.iter().all(|v| implant.base().contains(v)))
        .map(|t| t.map(|v| Vec3A::from(p[v as usize])))
        .collect();
    let inner: Vec<Vec3A> = layers
        .rest(Layer::Inner)
        .positions()
        .iter()
        .map(|&x| Vec3A::from(x))
        .collect();
    layers.detach(|r| {
        let x = inner[r as usize];
        base.iter().any(|&[a, b, c]| {
            let (q, _) = tissue_bvh::closest_point_on_triangle(x, a, b, c);
            q.distance(x) <= margin
        })
    })
}

/// The implant as a mass–spring system (module docs): particle `v` is implant vertex `v`.
pub fn implant_system(
    implant: &Implant,
    params: &ImplantParams,
) -> Result<MassSpringSystem, ImplantError> {
    params.check()?;
    let mesh = implant.mesh();
    let volume = mesh.signed_volume()?;
    let masses = masses_from_triangles(mesh, volume * params.fill_density)?;
    let mut particles = Particles::new(mesh.positions(), &masses)?;
    for v in implant.base() {
        particles.fix(v)?;
    }
    // Bent onto a curved body the dome can get very obtuse triangles next to the rim: such an
    // edge keeps eq. (3)'s shear term.
    let (springs, floored) = springs_from_triangles_floored(
        mesh,
        &SheetMaterial {
            young: params.shell_young,
            poisson: params.shell_poisson,
            thickness: params.shell_thickness,
        },
        0,
    )?;
    if !floored.is_empty() {
        tracing::warn!(
            floored = floored.len(),
            "obtuse triangles in the bent expander: springs keep only eq. (3)'s shear term"
        );
    }
    let mut system = MassSpringSystem::new(particles, springs)?;
    let area = mesh.area();
    let t = mesh.triangle_count() as f64;
    let k_v = params.radial_modulus * area * area / (3.0 * t * t * volume);
    system.add_volume_preservation(VolumePreservation::new(
        mesh,
        &masses,
        0,
        k_v as f32,
        params.volume_coupling as f32,
    )?)?;
    system.add_volume_pressure(VolumePressure::new(mesh, 0, params.fill_bulk_modulus)?)?;
    Ok(system)
}

/// A run whose skin moved more than this many times the expander's dome height (plus 1 cm) ran
/// away: [`Insertion::run`] reports it as [`ImplantError::RanAway`].
pub const RUNAWAY_FACTOR: f64 = 4.0;

/// What the caller sees between steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Steps done.
    pub steps: u64,
    /// The step limit.
    pub max_steps: u64,
    /// The last step's summary.
    pub last: StepSummary,
}

/// An implant under a skin region, ready to run (module docs).
#[derive(Debug, Clone)]
pub struct Insertion {
    run: ContactRun,
    implant_rest: TriMesh,
    implant_volume: f64,
    dome_height: f64,
    /// Layer 1's area sampled every stop window once the fill is over (the plateau rule).
    areas: Vec<f64>,
    /// Whether the plateau rule ended the run.
    plateau: bool,
    solver: Solver,
    statics: StaticParams,
    /// The last quasi-static solve's report.
    solved: Option<StaticReport>,
}

/// The plateau rule: the run has also settled when the mean of layer 1's area over the last
/// [`PLATEAU_HALF`] samples (one per stop window, 50 steps by default) differs from the mean over
/// the [`PLATEAU_HALF`] before by at most this fraction of the area gain. The ratio test and the
/// speed floor look at the particles' motion, and a run can keep a small stationary oscillation
/// (one or two particles held by the thickness guard, or contacts flickering on a limb) above
/// both for its whole step limit while its area, the result, no longer moves: Table 2's plane at
/// 170 cm³ before the skin's bending (area 164.27 ± 0.01 cm² with a 750-step period, 20 000
/// steps) and the tube's round expanders (their gains equal to 0.001 cm² after 5 000 steps).
pub const PLATEAU_TOLERANCE: f64 = 5e-4;

/// Samples in each half of the plateau rule's window.
pub const PLATEAU_HALF: usize = 5;

/// The plateau rule on layer 1's last `2 × PLATEAU_HALF` area samples (oldest first) and its
/// rest area: the two halves' means differ by at most [`PLATEAU_TOLERANCE`] of the gain.
fn on_plateau(areas: &[f64], rest: f64) -> bool {
    if areas.len() < 2 * PLATEAU_HALF {
        return false;
    }
    let areas = &areas[areas.len() - 2 * PLATEAU_HALF..];
    let mean = |a: &[f64]| a.iter().sum::<f64>() / a.len() as f64;
    let (older, newer) = areas.split_at(PLATEAU_HALF);
    let (older, newer) = (mean(older), mean(newer));
    (newer - older).abs() <= PLATEAU_TOLERANCE * (newer - rest).abs()
}

impl Insertion {
    /// Sets up the run for `region` (an open patch of the patient surface, normals out of the
    /// body) and `implant` (built on the region's layer 2 by [`place_implant`]).
    ///
    /// # Errors
    /// Parameter and mesh errors of the layers, the implant and the collider.
    pub fn new(
        region: &TriMesh,
        implant: &Implant,
        params: &InsertionParams,
    ) -> Result<Self, ImplantError> {
        let _span =
            tracing::info_span!("insertion_setup", vertices = region.vertex_count()).entered();
        if !(params.pocket_margin.is_finite() && params.pocket_margin >= 0.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::PocketMargin,
                value: f64::from(params.pocket_margin),
                expected: "finite and ≥ 0 (cm)".into(),
            });
        }
        if !(params.fill_time.is_finite() && params.fill_time >= 0.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::FillTime,
                value: f64::from(params.fill_time),
                expected: "finite and ≥ 0 (s)".into(),
            });
        }
        let mut layers = TissueLayers::new(region, &params.layers)?;
        let detached = dissect_pocket(&mut layers, implant, params.pocket_margin);
        tracing::debug!(detached, "pocket dissected");
        let body = implant_system(implant, &params.implant)?;
        let mut run = ContactRun::new(layers, body, implant.mesh(), &params.run)?;
        run.fill_body(&flat_start(implant), params.fill_time)?;
        Ok(Insertion {
            run,
            implant_rest: implant.mesh().clone(),
            implant_volume: implant.volume(),
            dome_height: implant.dome_height(),
            areas: Vec::with_capacity(2 * PLATEAU_HALF),
            plateau: false,
            solver: params.solver,
            statics: params.statics.clone(),
            solved: None,
        })
    }

    /// The same tissue, where it is now (positions, pocket, rest metric), under another
    /// implant (the next fill of an expander in an expansion over weeks): the implant is built for the new
    /// volume on the same base, and fills from where the previous one stood when both have the
    /// same vertices (from flat otherwise); the tissue starts at rest where it was. A warm
    /// start: the run then settles only the change.
    ///
    /// # Errors
    /// As [`Insertion::new`].
    pub(crate) fn refill(
        self,
        implant: &Implant,
        params: &InsertionParams,
    ) -> Result<Insertion, ImplantError> {
        let _span = tracing::debug_span!("insertion_refill", volume = implant.volume()).entered();
        let previous: Vec<Vec3A> = self.run.body().particles().positions().to_vec();
        let mut layers = self.run.into_layers();
        layers
            .system_mut()
            .particles_mut()
            .velocities_mut()
            .fill(Vec3A::ZERO);
        let body = implant_system(implant, &params.implant)?;
        let mut run = ContactRun::new(layers, body, implant.mesh(), &params.run)?;
        let (start, fraction) = if previous.len() == implant.mesh().vertex_count() {
            // The dome rises at the speed of a full fill, over the part of the height it has
            // still to go (at least a tenth of the fill's time).
            let moved = previous
                .iter()
                .zip(implant.mesh().positions())
                .map(|(&a, &b)| a.distance(Vec3A::from(b)))
                .fold(0.0f32, f32::max);
            let fraction = (f64::from(moved) / implant.dome_height().max(1e-6)).clamp(0.1, 1.0);
            (previous, fraction as f32)
        } else {
            (flat_start(implant), 1.0)
        };
        run.fill_body(&start, params.fill_time * fraction)?;
        Ok(Insertion {
            run,
            implant_rest: implant.mesh().clone(),
            implant_volume: implant.volume(),
            dome_height: implant.dome_height(),
            areas: Vec::with_capacity(2 * PLATEAU_HALF),
            plateau: false,
            solver: params.solver,
            statics: params.statics.clone(),
            solved: None,
        })
    }

    /// The implant at its current positions.
    pub(crate) fn outcome_implant(&self) -> Result<TriMesh, ImplantError> {
        Ok(self.implant_rest.with_positions(
            self.run
                .body()
                .particles()
                .positions()
                .iter()
                .map(|&p| Vec3::from(p))
                .collect(),
        )?)
    }

    /// The layers, to change their rest metric ([`TissueLayers::grow`]) before
    /// [`Insertion::settle`].
    pub(crate) fn layers_mut(&mut self) -> &mut TissueLayers {
        self.run.layers_mut()
    }

    /// Settles again from the current state (after a change of the rest metric, or a refill):
    /// steps until the stop criterion or the plateau rule fires, at most `budget` steps;
    /// returns the steps taken and whether it settled. With `quick = Some(w)` it has also
    /// settled once the summed displacement stayed under the speed floor (the mean speed under
    /// `RunParams::settle_speed`) for `w` steps in a row after the fill: the criterion's floor
    /// on a shorter window, for small changes from a settled state (a day's growth).
    /// `progress` as in [`Insertion::run`].
    ///
    /// # Errors
    /// As [`Insertion::run`].
    pub(crate) fn settle(
        &mut self,
        budget: u64,
        quick: Option<u64>,
        mut progress: impl FnMut(&Progress) -> ControlFlow<()>,
    ) -> Result<(u64, bool), ImplantError> {
        self.run.restart_settle();
        self.areas.clear();
        self.plateau = false;
        if self.solver == Solver::QuasiStatic {
            let report = self.solve_static(budget, &mut progress)?;
            return Ok((report.iterations, report.converged));
        }
        let first = self.run.steps();
        let window = self.run.stop_window().max(1) as u64;
        let floor = self.run.speed_floor();
        let mut calm = 0u64;
        while !self.run.settled() && !self.plateau && self.run.steps() - first < budget {
            let last = self.run.step()?;
            if let Some(w) = quick {
                calm = if !self.run.filling() && last.displacement <= floor {
                    calm + 1
                } else {
                    0
                };
                if calm >= w {
                    self.plateau = true;
                }
            }
            if !self.run.filling() && (self.run.steps() - first) % window == 0 {
                self.plateau = self.sample_plateau();
            }
            let report = Progress {
                steps: self.run.steps() - first,
                max_steps: budget,
                last,
            };
            if progress(&report).is_break() {
                return Err(ImplantError::Cancelled {
                    steps: self.run.steps(),
                });
            }
        }
        Ok((self.run.steps() - first, self.run.settled() || self.plateau))
    }

    /// The underlying run (time step, step count, the layers and the implant's system).
    pub fn contact_run(&self) -> &ContactRun {
        &self.run
    }

    /// One step.
    pub fn step(&mut self) -> Result<StepSummary, ImplantError> {
        self.run.step()
    }

    /// Steps until the stop criterion fires or the step limit is reached. `progress` is called
    /// after every step; [`ControlFlow::Break`] cancels the run ([`ImplantError::Cancelled`]).
    ///
    /// # Errors
    /// [`ImplantError::Cancelled`], [`ImplantError::Diverged`], [`ImplantError::RanAway`],
    /// collision errors.
    pub fn run(
        &mut self,
        mut progress: impl FnMut(&Progress) -> ControlFlow<()>,
    ) -> Result<InsertionOutcome, ImplantError> {
        let _span = tracing::info_span!("insertion_run").entered();
        let start = Instant::now();
        let max_steps = self.run.max_steps();
        let window = self.run.stop_window().max(1) as u64;
        if self.solver == Solver::QuasiStatic {
            // The run's step limit bounds the solver's iterations too (a caller's bound on
            // the work, e.g. the studio's).
            self.solve_static(max_steps, &mut progress)?;
        }
        while self.solver == Solver::Explicit
            && !self.run.settled()
            && !self.plateau
            && self.run.steps() < max_steps
        {
            let last = self.run.step()?;
            if !self.run.filling() && self.run.steps() % window == 0 {
                self.plateau = self.sample_plateau();
            }
            let report = Progress {
                steps: self.run.steps(),
                max_steps,
                last,
            };
            if progress(&report).is_break() {
                return Err(ImplantError::Cancelled {
                    steps: self.run.steps(),
                });
            }
        }
        let wall_time = start.elapsed();
        let outcome = self.outcome(wall_time)?;
        // A run that ran away while staying finite: the skin cannot rise much beyond the
        // expander that lifts it (found at a 0.09 cm simulation edge on a tube, where the "gain"
        // reached 479 cm² over a 10 cm³ expander).
        let limit = RUNAWAY_FACTOR * self.dome_height + 1.0;
        if f64::from(outcome.max_displacement) > limit {
            let vertex = outcome
                .displacement
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |(r, _)| r as u32);
            return Err(ImplantError::RanAway {
                steps: self.run.steps(),
                vertex,
                displacement: f64::from(outcome.max_displacement),
                limit,
            });
        }
        Ok(outcome)
    }

    /// The quasi-static solve of the current load (module `quasi_static`), at most `budget`
    /// iterations.
    fn solve_static(
        &mut self,
        budget: u64,
        progress: &mut impl FnMut(&Progress) -> ControlFlow<()>,
    ) -> Result<StaticReport, ImplantError> {
        let params = StaticParams {
            max_iterations: budget.min(self.statics.max_iterations),
            ..self.statics.clone()
        };
        let max_steps = params.max_iterations;
        let report = self.run.solve_static(&params, true, |steps, last| {
            let report = Progress {
                steps,
                max_steps,
                last,
            };
            match progress(&report) {
                ControlFlow::Break(()) => Err(ImplantError::Cancelled { steps }),
                ControlFlow::Continue(()) => Ok(()),
            }
        })?;
        self.solved = Some(report);
        Ok(report)
    }

    /// Samples layer 1's area for the plateau rule ([`PLATEAU_TOLERANCE`]); true when it holds.
    fn sample_plateau(&mut self) -> bool {
        if self.areas.len() == 2 * PLATEAU_HALF {
            self.areas.remove(0);
        }
        self.areas.push(self.run.layers().outer_area());
        if self.areas.len() < 2 * PLATEAU_HALF {
            return false;
        }
        let rest = self.run.layers().rest(Layer::Outer).area();
        let settled = on_plateau(&self.areas, rest);
        if settled {
            tracing::debug!(steps = self.run.steps(), "settled by the plateau rule");
        }
        settled
    }

    /// The results at the current state.
    pub fn outcome(&mut self, wall_time: Duration) -> Result<InsertionOutcome, ImplantError> {
        let _span = tracing::debug_span!("insertion_outcome").entered();
        let max_penetration = self.run.max_penetration()?;
        let layers = self.run.layers();
        let before = layers.rest(Layer::Outer).clone();
        let after = layers.current(Layer::Outer)?;
        let implant_after = self.implant_rest.with_positions(
            self.run
                .body()
                .particles()
                .positions()
                .iter()
                .map(|&p| Vec3::from(p))
                .collect(),
        )?;
        let boundary_unchanged = layers.boundary().iter().all(|&r| {
            before.positions()[r as usize].to_array().map(f32::to_bits)
                == after.positions()[r as usize].to_array().map(f32::to_bits)
        });
        let displacement = vertex_displacements(&before, &after)?;
        let stretch = vertex_stretch(&before, &after)?;
        let (area_before, area_after) = (before.area(), after.area());
        let implant_volume_after = implant_after.signed_volume()?;
        Ok(InsertionOutcome {
            area_before,
            area_after,
            area_gain: area_after - area_before,
            volume_difference: volume_between(&before, &after)?,
            implant_volume: self.implant_volume,
            implant_volume_after,
            implant_compression: 1.0 - implant_volume_after / self.implant_volume,
            dome_height: self.dome_height,
            max_displacement: displacement.iter().copied().fold(0.0, f32::max),
            max_penetration,
            boundary_unchanged,
            steps: self.run.steps(),
            solver: self.solver,
            iterations: self.solved.map_or(self.run.steps(), |r| r.iterations),
            residual_n: self.solved.map(|r| r.residual_n),
            stop_reason: if self.run.settled() || self.plateau {
                StopReason::Settled
            } else {
                StopReason::StepLimit
            },
            time_step: self.run.time_step(),
            wall_time,
            displacement,
            stretch,
            inner_after: layers.current(Layer::Inner)?,
            region_before: before,
            region_after: after,
            implant_after,
        })
    }
}

/// What a run gives the planner (SPEC A.5 step 5 and more). Units: cm, cm², cm³, s.
#[derive(Debug, Clone)]
pub struct InsertionOutcome {
    /// Region (layer 1) area before the run.
    pub area_before: f64,
    /// Region area after the run.
    pub area_after: f64,
    /// `area_after − area_before`: the skin gained for grafting.
    pub area_gain: f64,
    /// Volume between the region before and after, joined along their common boundary.
    pub volume_difference: f64,
    /// The implant's volume as built (its nominal volume within 0.5 %).
    pub implant_volume: f64,
    /// The implant's volume at the end.
    pub implant_volume_after: f64,
    /// `1 − implant_volume_after / implant_volume`: how much the tissue squeezed it.
    pub implant_compression: f64,
    /// The implant's dome height as built.
    pub dome_height: f64,
    /// The largest displacement of a region vertex.
    pub max_displacement: f32,
    /// The deepest layer-2 edge through the implant at the end (0 when none crosses).
    pub max_penetration: f32,
    /// Whether every boundary vertex is where it started, bit for bit.
    pub boundary_unchanged: bool,
    /// Steps taken (the explicit solver's; the quasi-static solver's iterations).
    pub steps: u64,
    /// The solver that found this state.
    pub solver: Solver,
    /// The solver's iterations: explicit steps, or quasi-static local/global iterations.
    pub iterations: u64,
    /// The quasi-static solver's final residual: the largest net force on a free particle (N),
    /// with the contacts' forces; `None` for the explicit solver, whose contacts are impulses.
    pub residual_n: Option<f64>,
    /// Why the run ended.
    pub stop_reason: StopReason,
    /// The time step used (s).
    pub time_step: f32,
    /// Wall-clock time of the stepping.
    pub wall_time: Duration,
    /// Per region vertex: how far it moved.
    pub displacement: Vec<f32>,
    /// Per region vertex: area after / area before of the skin around it.
    pub stretch: Vec<f32>,
    /// The region before.
    pub region_before: TriMesh,
    /// The region after.
    pub region_after: TriMesh,
    /// Layer 2 after.
    pub inner_after: TriMesh,
    /// The implant after.
    pub implant_after: TriMesh,
}

impl InsertionOutcome {
    /// The patient surface with the region replaced by the result (boundary unchanged bit for
    /// bit, so the seam is closed).
    ///
    /// # Errors
    /// As [`replace_region`].
    pub fn patient_after(
        &self,
        patient: &TriMesh,
        selection: &RegionSelection,
    ) -> Result<TriMesh, ImplantError> {
        replace_region(patient, selection, self.region_after.positions())
    }

    /// Whether every position of the result is finite.
    pub fn is_finite(&self) -> bool {
        [&self.region_after, &self.inner_after, &self.implant_after]
            .iter()
            .all(|m| m.positions().iter().all(|p| p.is_finite()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plateau_rule_stops_an_oscillation_whose_area_stands_still_but_not_a_drift() {
        let rest = 91.41;
        // Table 2's plane at 170 cm³ before the skin's bending: 164.27 ± 0.01 cm², a 750-step
        // period sampled every 50 steps, for 20 000 steps.
        let oscillating: Vec<f64> = (0..10)
            .map(|k| 164.27 + 0.01 * (std::f64::consts::TAU * f64::from(k) * 50.0 / 750.0).sin())
            .collect();
        assert!(on_plateau(&oscillating, rest));
        // Still rising by 0.05 % of the gain per window: not settled.
        let gain = 164.27 - rest;
        let drifting: Vec<f64> = (0..10)
            .map(|k| 164.27 + 5e-4 * gain * f64::from(k))
            .collect();
        assert!(!on_plateau(&drifting, rest));
        // Too few samples.
        assert!(!on_plateau(&oscillating[..9], rest));
    }
}
