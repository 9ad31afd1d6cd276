//! The scenario set-up in one place: region, layers, implant, run — usable without threads.
//!
//! [`prepare`] / [`plan`] run one insertion, [`plan_sweep`] a series of implant volumes in
//! parallel, [`plan_inverse`] the search for the volume of a target area gain. The worker
//! ([`Handle`](crate::Handle)) calls the same code, so a result from the worker and from these
//! functions with the same inputs is the same, bit for bit (the runs are deterministic).

use std::ops::ControlFlow;
use std::time::Duration;

use glam::Vec3;
use tissue_implant::{
    default_radius, expand, place_implant, prepare_scan, rim_border_clearance, select_region_with,
    sweep, volume_for_gain, BandOptions, ExpansionOutcome, ExpansionProgress, ExpansionSetup,
    GrowthParams, Implant, ImplantError, ImplantShape, ImplantSpec, InsertionOutcome,
    InsertionParams, InverseOptions, InverseSearch, Progress, Protocol, RegionOptions,
    RegionSelection, ScanOptions, ScanResult, SimSurface, Solver, StopReason, TissueLayers,
};
use tissue_mesh::TriMesh;

use crate::settle::insertion_floor;

/// Table 2's round 7 cm expander's footprint radius (cm): the size the run's times are set for.
const TABLE2_FOOTPRINT_RADIUS: f64 = 3.5;

/// Where the implant goes on the patient surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// The picked point (cm). It is snapped to the nearest surface point, which becomes the
    /// region's centre and the implant's centre; a point farther from the surface than
    /// [`RegionOptions::max_snap_distance`] is refused ([`ImplantError::PointOffSurface`]).
    pub point: Vec3,
    /// The outward normal of the body at the point (the implant's dome side).
    pub normal: Vec3,
    /// The implant's local `x` direction (a rectangle's length); only its part across `normal`
    /// is used.
    pub tangent: Vec3,
}

impl Placement {
    /// A placement at `point` facing `normal`, oriented by `tangent`.
    pub fn new(point: Vec3, normal: Vec3, tangent: Vec3) -> Self {
        Placement {
            point,
            normal,
            tangent,
        }
    }
}

/// Which surface the mechanics run on.
#[derive(Debug, Clone, PartialEq)]
pub enum SimMesh {
    /// The region's own triangles of the patient surface, as the thesis ran its planes (Tables
    /// 1 and 2, whose figures are for those grids). For clean, even meshes only: a scan's
    /// triangles set the time step by their size and fold the layers by their noise.
    Patient,
    /// The region filled, remeshed and smoothed into a simulation surface of its own, the
    /// result mapped back onto the patient's vertices ([`tissue_implant::prepare_scan`]): what
    /// a real scan needs. The default.
    Remeshed(ScanOptions),
}

impl Default for SimMesh {
    /// [`SimMesh::Remeshed`] with the default [`ScanOptions`] (edge from the region's size).
    fn default() -> Self {
        SimMesh::Remeshed(ScanOptions::default())
    }
}

/// The inputs of one insertion run.
#[derive(Debug, Clone)]
pub struct InsertionJob {
    /// The patient surface (normals out of the body).
    pub patient: TriMesh,
    /// Where the implant goes.
    pub placement: Placement,
    /// The implant (shape, volume, vertex budget).
    pub implant: ImplantSpec,
    /// The region's geodesic radius (cm); `None`: [`default_radius`] of the implant's footprint
    /// radius ([`footprint_radius`]).
    pub region_radius: Option<f64>,
    /// How the region is selected (snap distance, triangle rule).
    pub region: RegionOptions,
    /// Tissue, implant and run parameters.
    pub params: InsertionParams,
    /// The surface the mechanics run on (default: the region remeshed, [`SimMesh::Remeshed`]).
    pub sim: SimMesh,
}

impl InsertionJob {
    /// A job with the default region radius, [`RegionOptions::default`],
    /// [`InsertionParams::default`] and the region remeshed ([`SimMesh::default`]).
    pub fn new(patient: TriMesh, placement: Placement, implant: ImplantSpec) -> Self {
        InsertionJob {
            patient,
            placement,
            implant,
            region_radius: None,
            region: RegionOptions::default(),
            params: InsertionParams::default(),
            sim: SimMesh::default(),
        }
    }

    /// The simulation edge the job uses (cm): the one asked for, or the default of the region's
    /// radius ([`tissue_implant::default_sim_edge`]); `None` when the mechanics run on the
    /// patient's own triangles.
    ///
    /// # Errors
    /// Those of [`InsertionJob::radius`].
    pub fn sim_edge(&self) -> Result<Option<f64>, ImplantError> {
        match &self.sim {
            SimMesh::Patient => Ok(None),
            SimMesh::Remeshed(options) => match options.sim_edge {
                Some(h) => Ok(Some(h)),
                None => Ok(Some(tissue_implant::default_sim_edge(self.radius()?)?)),
            },
        }
    }

    /// The factor the run's times are scaled by: on a simulation surface of its own, its
    /// model edge (the larger of the asked edge and the default for the region's radius) over
    /// Table 2's default edge (0.315 cm); 1 on the patient's own triangles.
    ///
    /// The fill's duration and the damping time ([`InsertionParams::fill_time`],
    /// `RunParams::damping_time`) are set for Table 2's 7 cm expander, and the end state does
    /// not depend on them (docs/validation.md); a region's waves cross it in a time that scales
    /// with its size, as the time step does with the edge. Scaled, a small expander's run
    /// takes about Table 2's number of steps.
    ///
    /// # Errors
    /// Those of [`InsertionJob::radius`].
    pub fn time_scale(&self) -> Result<f64, ImplantError> {
        match &self.sim {
            SimMesh::Patient => Ok(1.0),
            SimMesh::Remeshed(options) => {
                let model = tissue_implant::model_edge(self.radius()?, options.sim_edge)?;
                let table2 =
                    tissue_implant::default_sim_edge(default_radius(TABLE2_FOOTPRINT_RADIUS)?)?;
                Ok(model / table2)
            }
        }
    }

    /// The parameters the run uses: [`InsertionJob::params`] with the fill's duration and the
    /// damping time scaled by [`InsertionJob::time_scale`].
    ///
    /// # Errors
    /// Those of [`InsertionJob::radius`].
    pub fn run_params(&self) -> Result<InsertionParams, ImplantError> {
        let scale = self.time_scale()? as f32;
        let mut params = self.params.clone();
        params.fill_time *= scale;
        params.run.damping_time *= scale;
        Ok(params)
    }

    /// The region radius the job uses (cm): [`InsertionJob::region_radius`] or the default.
    ///
    /// # Errors
    /// Those of [`default_radius`].
    pub fn radius(&self) -> Result<f64, ImplantError> {
        match self.region_radius {
            Some(r) => Ok(r),
            None => default_radius(footprint_radius(&self.implant.shape)),
        }
    }
}

/// A series of insertions that differ only in the implant volume.
#[derive(Debug, Clone)]
pub struct SweepJob {
    /// Everything but the volume (its `implant.volume_cm3` is ignored).
    pub base: InsertionJob,
    /// The implant volumes to run (cm³), in the order the results are wanted.
    pub volumes: Vec<f64>,
}

/// The search for the implant volume that gives a target area gain ([`volume_for_gain`]).
#[derive(Debug, Clone)]
pub struct InverseJob {
    /// Everything but the volume (its `implant.volume_cm3` is ignored).
    pub base: InsertionJob,
    /// The wanted area gain (cm²).
    pub target_gain: f64,
    /// The volumes to search between, `(low, high)` (cm³).
    pub bracket: (f64, f64),
    /// Tolerances and run budget.
    pub options: InverseOptions,
}

/// The plane press of SPEC Table 1 ([`tissue_implant::plane_press`]).
#[derive(Debug, Clone)]
pub struct PlanePressJob {
    /// The region pressed (an open patch; e.g. [`tissue_implant::plane_press_region`]`(65)`'s
    /// mesh).
    pub region: TriMesh,
    /// The press's parameters.
    pub params: tissue_implant::PlanePressParams,
}

/// The radius of the smallest circle around the implant's local origin that holds its base
/// (cm): half the diameter of a round base, the centre-to-corner distance of a rectangle, half
/// the centre-line length of a crescent (which bounds its tips).
pub fn footprint_radius(shape: &ImplantShape) -> f64 {
    match *shape {
        ImplantShape::Round { diameter } => 0.5 * f64::from(diameter),
        ImplantShape::Rectangular {
            length,
            width,
            corner_radius,
        } => {
            let r = f64::from(corner_radius);
            let x = (0.5 * f64::from(length) - r).max(0.0);
            let y = (0.5 * f64::from(width) - r).max(0.0);
            x.hypot(y) + r
        }
        ImplantShape::Crescent { length, .. } => 0.5 * f64::from(length),
    }
}

/// The region, the surface the mechanics run on and its tissue layers, shared by every run of a
/// job.
struct Scene {
    selection: RegionSelection,
    surface: Option<SimSurface>,
    layers: TissueLayers,
    /// The implant frame's normal: the placement's, or the simulation surface's at the centre.
    normal: Vec3,
    /// The job's parameters, with layer 2's offset reach of the simulation surface if any.
    params: InsertionParams,
}

impl Scene {
    /// The mesh the mechanics run on (layer 1 at rest).
    fn sim_mesh(&self) -> &TriMesh {
        match &self.surface {
            Some(surface) => surface.mesh(),
            None => self.selection.mesh(),
        }
    }
}

fn cancelled_check(cancelled: &dyn Fn() -> bool) -> Result<(), ImplantError> {
    if cancelled() {
        Err(ImplantError::Cancelled { steps: 0 })
    } else {
        Ok(())
    }
}

fn scene(job: &InsertionJob, cancelled: &dyn Fn() -> bool) -> Result<Scene, ImplantError> {
    let _span = tracing::info_span!("app_region").entered();
    let radius = job.radius()?;
    let (selection, surface) = match &job.sim {
        SimMesh::Patient => (
            select_region_with(&job.patient, job.placement.point, radius, &job.region)?,
            None,
        ),
        SimMesh::Remeshed(options) => {
            let (selection, surface) = prepare_scan(
                &job.patient,
                job.placement.point,
                radius,
                job.params.layers.depth,
                &job.region,
                options,
            )?;
            (selection, Some(surface))
        }
    };
    cancelled_check(cancelled)?;
    let normal = match &surface {
        // The scan's own normal is as noisy as the scan: the smooth surface's is the frame's.
        Some(surface) => {
            let n = surface.normal_near(selection.centre().position());
            if n.dot(job.placement.normal) < 0.0 {
                -n
            } else {
                n
            }
        }
        None => job.placement.normal,
    };
    let sim = match &surface {
        Some(surface) => surface.mesh(),
        None => selection.mesh(),
    };
    let mut params = job.run_params()?;
    if let Some(surface) = &surface {
        params.layers.offset_reach = Some(surface.offset_reach());
    }
    let layers = TissueLayers::new(sim, &params.layers)?;
    cancelled_check(cancelled)?;
    Ok(Scene {
        selection,
        surface,
        layers,
        normal,
        params,
    })
}

fn build(
    scene: &Scene,
    job: &InsertionJob,
    spec: &ImplantSpec,
    cancelled: &dyn Fn() -> bool,
) -> Result<(Implant, tissue_implant::Insertion), ImplantError> {
    let _span = tracing::info_span!("app_implant", volume = spec.volume_cm3).entered();
    let implant = place_implant(
        &scene.layers,
        spec,
        scene.selection.centre().position(),
        scene.normal,
        job.placement.tangent,
    )?;
    if let Some(surface) = &scene.surface {
        // Tissue must be left between the expander and the fixed border: a scan's region can
        // run into a crease (docs/validation.md, the closed body's belly).
        let clearance = rim_border_clearance(&scene.layers, &implant);
        let needed = surface.model_edge();
        if clearance < needed {
            return Err(ImplantError::RimAtBorder { clearance, needed });
        }
    }
    cancelled_check(cancelled)?;
    let insertion = tissue_implant::Insertion::new(scene.sim_mesh(), &implant, &scene.params)?;
    cancelled_check(cancelled)?;
    Ok((implant, insertion))
}

/// An insertion set up and ready to run ([`prepare`]).
#[derive(Debug, Clone)]
pub struct PreparedInsertion {
    selection: RegionSelection,
    surface: Option<SimSurface>,
    implant: Implant,
    insertion: tissue_implant::Insertion,
    settle_floor: f64,
}

impl PreparedInsertion {
    /// The region of the patient surface.
    pub fn selection(&self) -> &RegionSelection {
        &self.selection
    }

    /// The simulation surface, when the region was remeshed ([`SimMesh::Remeshed`]).
    pub fn surface(&self) -> Option<&SimSurface> {
        self.surface.as_ref()
    }

    /// The implant as built on layer 2.
    pub fn implant(&self) -> &Implant {
        &self.implant
    }

    /// The run, not yet started.
    pub fn insertion(&self) -> &tissue_implant::Insertion {
        &self.insertion
    }

    /// The speed floor of the run's stop criterion (cm of summed displacement per step), as the
    /// library derives it from [`tissue_implant::RunParams::settle_speed`].
    pub fn settle_floor(&self) -> f64 {
        self.settle_floor
    }

    /// Runs to the stop criterion or the step limit; `progress` is called after every step and
    /// cancels with [`ControlFlow::Break`] ([`ImplantError::Cancelled`]).
    ///
    /// # Errors
    /// Those of [`tissue_implant::Insertion::run`].
    pub fn run(
        self,
        progress: impl FnMut(&Progress) -> ControlFlow<()>,
    ) -> Result<PlannedInsertion, ImplantError> {
        let PreparedInsertion {
            selection,
            surface,
            mut insertion,
            ..
        } = self;
        let _span = tracing::info_span!("app_run").entered();
        let outcome = insertion.run(progress)?;
        Ok(PlannedInsertion {
            selection,
            surface,
            outcome,
        })
    }
}

/// The result of one insertion: the region, the simulation surface and the run's outcome.
#[derive(Debug, Clone)]
pub struct PlannedInsertion {
    /// The region of the patient surface (on a remeshed run: selected on the patient with its
    /// small holes filled, whose vertices come after the patient's).
    pub selection: RegionSelection,
    /// The simulation surface the run used, when the region was remeshed
    /// ([`SimMesh::Remeshed`]); `None` when it ran on the patient's own triangles.
    pub surface: Option<SimSurface>,
    /// Areas, volumes, fields and meshes after the run, measured on the surface the mechanics
    /// ran on (the simulation surface, or the patient's region).
    pub outcome: InsertionOutcome,
}

/// The patient after a run, with per-vertex fields ([`PlannedInsertion::on_patient`]).
#[derive(Debug, Clone)]
pub struct PatientAfter {
    /// The patient surface after the run: its own vertices and triangles, the region moved.
    pub mesh: TriMesh,
    /// Per patient vertex: how far it moved, cm (0 outside the region).
    pub displacement: Vec<f32>,
    /// Per patient vertex: area after / before of the skin around it (1 outside the region).
    pub stretch: Vec<f32>,
    /// Per patient vertex: whether it is in the region.
    pub in_region: Vec<bool>,
    /// The areas and volume measured on the patient's own triangles when the region was
    /// remeshed (`None` on a run on the patient's triangles, where they are the outcome's).
    pub scan: Option<ScanResult>,
}

impl PlannedInsertion {
    /// The patient surface with the region replaced by the result.
    ///
    /// # Errors
    /// As [`PlannedInsertion::on_patient`].
    pub fn patient_after(&self, patient: &TriMesh) -> Result<TriMesh, ImplantError> {
        Ok(self.on_patient(patient)?.mesh)
    }

    /// The result on every vertex of `patient` (the job's): on a remeshed run each region
    /// vertex follows the deformed simulation surface ([`SimSurface::map_to_scan`]); otherwise
    /// the region's vertices are the simulated ones. Vertices outside the region keep their
    /// positions bit for bit.
    ///
    /// # Errors
    /// [`ImplantError::InvalidParameter`] when `patient` is not the job's, and mesh errors if the
    /// result is not a valid mesh.
    pub fn on_patient(&self, patient: &TriMesh) -> Result<PatientAfter, ImplantError> {
        match &self.surface {
            Some(surface) => {
                let scan =
                    surface.map_to_scan(&self.selection, patient, &self.outcome.region_after)?;
                Ok(PatientAfter {
                    mesh: scan.patient_after.clone(),
                    displacement: scan.displacement.clone(),
                    stretch: scan.stretch.clone(),
                    in_region: scan.in_region.clone(),
                    scan: Some(scan),
                })
            }
            None => {
                let mesh = self.outcome.patient_after(patient, &self.selection)?;
                let n = patient.vertex_count();
                let (mut displacement, mut stretch, mut in_region) =
                    (vec![0.0f32; n], vec![1.0f32; n], vec![false; n]);
                for (r, &p) in self.selection.region_to_patient().iter().enumerate() {
                    let p = p as usize;
                    if p < n {
                        displacement[p] = self.outcome.displacement[r];
                        stretch[p] = self.outcome.stretch[r];
                        in_region[p] = true;
                    }
                }
                Ok(PatientAfter {
                    mesh,
                    displacement,
                    stretch,
                    in_region,
                    scan: None,
                })
            }
        }
    }
}

/// Sets up one insertion: selects the region around the snapped point, builds the tissue
/// layers, places the implant on layer 2 under the region's centre (frame from
/// [`Placement::normal`] and [`Placement::tangent`]), and prepares the run.
///
/// # Errors
/// - [`ImplantError::PointOffSurface`], [`ImplantError::EmptyRegion`],
///   [`ImplantError::RegionCoversSurface`] from the region selection;
/// - [`ImplantError::FootprintOutsideRegion`] when the implant does not fit under the region;
/// - [`ImplantError::RimAtBorder`] when, on a simulation surface of its own, the expander's rim
///   comes within [`SimSurface::model_edge`] of the region's border;
/// - [`ImplantError::InvalidParameter`] for a non-positive volume or another parameter out of
///   range, and the other errors of the library's set-up.
pub fn prepare(job: &InsertionJob) -> Result<PreparedInsertion, ImplantError> {
    prepare_with(job, &|| false)
}

/// [`prepare`] with a cancel check between the set-up phases (a cancel gives
/// [`ImplantError::Cancelled`] with 0 steps).
pub(crate) fn prepare_with(
    job: &InsertionJob,
    cancelled: &dyn Fn() -> bool,
) -> Result<PreparedInsertion, ImplantError> {
    let _span = tracing::info_span!("app_setup").entered();
    let scene = scene(job, cancelled)?;
    let (implant, insertion) = build(&scene, job, &job.implant, cancelled)?;
    let settle_floor = insertion_floor(&insertion, &implant, &scene.params.run);
    Ok(PreparedInsertion {
        selection: scene.selection,
        surface: scene.surface,
        implant,
        insertion,
        settle_floor,
    })
}

/// Sets up and runs one insertion ([`prepare`], then [`PreparedInsertion::run`]): the
/// function the `insert` binary calls.
///
/// # Errors
/// Those of [`prepare`] and [`tissue_implant::Insertion::run`].
pub fn plan(
    job: &InsertionJob,
    progress: impl FnMut(&Progress) -> ControlFlow<()>,
) -> Result<PlannedInsertion, ImplantError> {
    prepare(job)?.run(progress)
}

/// An expansion over weeks: the insertion's patient, placement, expander shape
/// and parameters, a fill protocol, growth, and the band.
#[derive(Debug, Clone)]
pub struct ExpansionJob {
    /// The patient, placement, expander (its volume is the protocol's nominal volume) and
    /// mechanics, as for one insertion.
    pub insertion: InsertionJob,
    /// The fills, leakage and removal day.
    pub protocol: Protocol,
    /// The growth law and the flap's release at removal.
    pub growth: GrowthParams,
    /// The band; `None` for the nominal run only.
    pub band: Option<BandOptions>,
}

impl ExpansionJob {
    /// The usual protocol on `insertion`'s expander: `weeks` equal weekly fills to its volume,
    /// a week's hold, the mean in-vivo leakage, no over-fill, human growth, the default band.
    ///
    /// # Errors
    /// [`ImplantError::InvalidProtocol`] as [`Protocol::weekly`].
    pub fn weekly(insertion: InsertionJob, weeks: u32) -> Result<Self, ImplantError> {
        let protocol = Protocol::weekly(
            insertion.implant.volume_cm3,
            weeks,
            1.0,
            tissue_implant::LEAKAGE_MEAN,
            0.0,
        )?;
        Ok(ExpansionJob {
            insertion,
            protocol,
            growth: GrowthParams::human(),
            band: Some(BandOptions::default()),
        })
    }
}

/// The result of an expansion: the region, the simulation surface and the outcome.
#[derive(Debug, Clone)]
pub struct PlannedExpansion {
    /// The region of the patient surface.
    pub selection: RegionSelection,
    /// The simulation surface, when the region was remeshed.
    pub surface: Option<SimSurface>,
    /// The weekly figures, the flap at removal and the band (on the simulation surface).
    pub outcome: ExpansionOutcome,
}

/// Runs an expansion without a thread: the region and the simulation surface set up as for
/// one insertion (the expander at the protocol's injected total must fit, as
/// [`plan`] checks it), then [`tissue_implant::expand`]. `monitor` is called from the runs'
/// threads and cancels with [`ControlFlow::Break`].
///
/// # Errors
/// Those of [`prepare`] and [`tissue_implant::expand`].
pub fn plan_expansion(
    job: &ExpansionJob,
    monitor: &(dyn Fn(&ExpansionProgress) -> ControlFlow<()> + Sync),
) -> Result<PlannedExpansion, ImplantError> {
    expansion_with(job, &|| false, monitor)
}

pub(crate) fn expansion_with(
    job: &ExpansionJob,
    cancelled: &dyn Fn() -> bool,
    monitor: &(dyn Fn(&ExpansionProgress) -> ControlFlow<()> + Sync),
) -> Result<PlannedExpansion, ImplantError> {
    let _span = tracing::info_span!("app_expansion").entered();
    job.protocol.validate()?;
    let scene = scene(&job.insertion, cancelled)?;
    let mut top = job.insertion.implant;
    top.volume_cm3 = job.protocol.injected_total();
    // Placement and the rim's clearance at the largest volume, as for one insertion.
    build(&scene, &job.insertion, &top, cancelled)?;
    let setup = ExpansionSetup {
        region: scene.sim_mesh().clone(),
        centre: scene.selection.centre().position(),
        normal: scene.normal,
        tangent: job.insertion.placement.tangent,
        implant: job.insertion.implant,
        params: scene.params.clone(),
    };
    let outcome = expand(
        &setup,
        &job.protocol,
        &job.growth,
        job.band.as_ref(),
        monitor,
    )?;
    Ok(PlannedExpansion {
        selection: scene.selection,
        surface: scene.surface,
        outcome,
    })
}

/// One run of a sweep.
#[derive(Debug, Clone)]
pub struct SweepRun {
    /// The implant volume run (cm³).
    pub volume: f64,
    /// Its outcome, or why it failed (a failed run does not stop the others).
    pub result: Result<InsertionOutcome, ImplantError>,
}

/// The result of a sweep: the region (the same for every run) and one run per volume, in the
/// order of [`SweepJob::volumes`].
#[derive(Debug, Clone)]
pub struct SweepResult {
    /// The region of the patient surface.
    pub selection: RegionSelection,
    /// The simulation surface every run used, when the region was remeshed.
    pub surface: Option<SimSurface>,
    /// One entry per volume, in input order.
    pub runs: Vec<SweepRun>,
}

/// Runs every volume of `job` in parallel ([`tissue_implant::sweep`], rayon's global pool) on
/// one region; `progress(run, p)` is called after every step of run `run` (the index into
/// [`SweepJob::volumes`]) from the thread running it, and cancels that run with
/// [`ControlFlow::Break`].
///
/// # Errors
/// The region set-up's errors (as [`prepare`]); the errors of single runs are in
/// [`SweepRun::result`].
pub fn plan_sweep(
    job: &SweepJob,
    progress: impl Fn(usize, &Progress) -> ControlFlow<()> + Sync,
) -> Result<SweepResult, ImplantError> {
    sweep_with(job, &|| false, |run, _| {
        let progress = &progress;
        move |p: &Progress| progress(run, p)
    })
}

/// [`plan_sweep`] with a cancel check before every set-up phase and a per-run observer made by
/// `observer(run, settle_floor)` once the run is set up.
pub(crate) fn sweep_with<M, O>(
    job: &SweepJob,
    cancelled: &(dyn Fn() -> bool + Sync),
    observer: O,
) -> Result<SweepResult, ImplantError>
where
    O: Fn(usize, f64) -> M + Sync,
    M: FnMut(&Progress) -> ControlFlow<()>,
{
    let _span = tracing::info_span!("app_sweep", runs = job.volumes.len()).entered();
    let scene = scene(&job.base, cancelled)?;
    let indexed: Vec<(usize, f64)> = job.volumes.iter().copied().enumerate().collect();
    let results = sweep(&indexed, |&(run, volume)| {
        let _span = tracing::info_span!("app_sweep_run", run, volume).entered();
        cancelled_check(cancelled)?;
        let spec = ImplantSpec {
            volume_cm3: volume,
            ..job.base.implant
        };
        let (implant, mut insertion) = build(&scene, &job.base, &spec, cancelled)?;
        let observe = observer(
            run,
            insertion_floor(&insertion, &implant, &job.base.params.run),
        );
        insertion.run(observe)
    });
    let runs = job
        .volumes
        .iter()
        .zip(results)
        .map(|(&volume, result)| SweepRun { volume, result })
        .collect();
    Ok(SweepResult {
        selection: scene.selection,
        surface: scene.surface,
        runs,
    })
}

/// How the solver ended one run: what a report repeats of a run it keeps no outcome of.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverFigures {
    /// The solver that found the run's state ([`InsertionOutcome::solver`]).
    pub solver: Solver,
    /// Steps taken ([`InsertionOutcome::steps`]).
    pub steps: u64,
    /// The solver's iterations ([`InsertionOutcome::iterations`]).
    pub iterations: u64,
    /// The quasi-static solver's final residual, N ([`InsertionOutcome::residual_n`]); `None`
    /// for the explicit solver.
    pub residual_n: Option<f64>,
    /// Why the run ended.
    pub stop_reason: StopReason,
}

impl SolverFigures {
    /// The figures of `outcome`.
    pub fn of(outcome: &InsertionOutcome) -> Self {
        SolverFigures {
            solver: outcome.solver,
            steps: outcome.steps,
            iterations: outcome.iterations,
            residual_n: outcome.residual_n,
            stop_reason: outcome.stop_reason,
        }
    }
}

/// The result of an inverse search: the search, and how the solver ended each of its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedInverse {
    /// The volume found and every run taken ([`volume_for_gain`]).
    pub search: InverseSearch,
    /// One per run of [`InverseSearch::runs`], in the same order: the search's runs are
    /// exactly the runs that returned (a run that failed fails the search).
    pub runs: Vec<SolverFigures>,
}

/// Searches the volume of [`InverseJob::bracket`] whose run gives [`InverseJob::target_gain`]
/// ([`volume_for_gain`]: sequential, each run depends on the ones before); `progress(run, p)` is
/// called after every step of run `run` (0 for the first run of the search) and cancels the
/// search with [`ControlFlow::Break`].
///
/// # Errors
/// The region set-up's errors (as [`prepare`]), those of [`volume_for_gain`] (e.g.
/// [`ImplantError::TargetNotBracketed`]) and the first failed run's.
pub fn plan_inverse(
    job: &InverseJob,
    mut progress: impl FnMut(usize, &Progress) -> ControlFlow<()>,
) -> Result<PlannedInverse, ImplantError> {
    inverse_with(job, &|| false, |event| match event {
        RunEvent::Start(..) => ControlFlow::Continue(()),
        RunEvent::Step(run, p) => progress(run, p),
    })
}

/// What [`inverse_with`]'s observer sees: a run set up, or a step of it.
pub(crate) enum RunEvent<'a> {
    /// Run `run` is set up and about to start; its criterion's speed floor.
    Start(usize, f64),
    /// A step of run `run`.
    Step(usize, &'a Progress),
}

/// [`plan_inverse`] with a cancel check and an observer of every run's start and steps.
pub(crate) fn inverse_with(
    job: &InverseJob,
    cancelled: &dyn Fn() -> bool,
    mut observe: impl FnMut(RunEvent<'_>) -> ControlFlow<()>,
) -> Result<PlannedInverse, ImplantError> {
    let _span = tracing::info_span!("app_inverse", target = job.target_gain).entered();
    let scene = scene(&job.base, cancelled)?;
    let mut run = 0usize;
    let mut figures: Vec<SolverFigures> = Vec::new();
    let search = volume_for_gain(job.target_gain, job.bracket, &job.options, |volume| {
        let _span = tracing::info_span!("app_inverse_run", run, volume).entered();
        let spec = ImplantSpec {
            volume_cm3: volume,
            ..job.base.implant
        };
        let (implant, mut insertion) = build(&scene, &job.base, &spec, cancelled)?;
        let this = run;
        run += 1;
        let floor = insertion_floor(&insertion, &implant, &job.base.params.run);
        if observe(RunEvent::Start(this, floor)).is_break() {
            return Err(ImplantError::Cancelled { steps: 0 });
        }
        let outcome = insertion.run(|p| observe(RunEvent::Step(this, p)))?;
        figures.push(SolverFigures::of(&outcome));
        Ok(outcome.area_gain)
    })?;
    Ok(PlannedInverse {
        search,
        runs: figures,
    })
}

/// Wall time helper shared with the worker: a duration that never panics on clock oddities.
pub(crate) fn saturating_elapsed(start: std::time::Instant) -> Duration {
    std::time::Instant::now().saturating_duration_since(start)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tissue_implant::ImplantShape;

    fn job(diameter: f32, sim: SimMesh) -> InsertionJob {
        let mut job = InsertionJob::new(
            tissue_mesh::grid(9, 20.0).unwrap(),
            Placement::new(Vec3::ZERO, Vec3::Z, Vec3::X),
            ImplantSpec::new(ImplantShape::Round { diameter }, 10.0),
        );
        job.sim = sim;
        job
    }

    #[test]
    fn the_runs_times_scale_with_the_model_edge_and_only_on_a_remeshed_run() {
        let default = InsertionParams::default();
        // Table 2's 7 cm expander: its own times.
        let table2 = job(7.0, SimMesh::default());
        assert!((table2.time_scale().unwrap() - 1.0).abs() < 1e-12);
        // A 2.5 cm one: its edge (0.06 × 1.875 cm) over Table 2's (0.06 × 5.25 cm).
        let small = job(2.5, SimMesh::default());
        let scale = small.time_scale().unwrap();
        assert!((scale - 1.875 / 5.25).abs() < 1e-9, "{scale}");
        let p = small.run_params().unwrap();
        assert!((f64::from(p.fill_time) - scale * f64::from(default.fill_time)).abs() < 1e-9);
        assert!(
            (f64::from(p.run.damping_time) - scale * f64::from(default.run.damping_time)).abs()
                < 1e-9
        );
        // Halving the edge keeps the model edge, so the times too; a coarser edge lengthens them.
        let half = job(
            2.5,
            SimMesh::Remeshed(ScanOptions {
                sim_edge: Some(0.5 * 0.06 * 1.875),
                ..ScanOptions::default()
            }),
        );
        assert!((half.time_scale().unwrap() - scale).abs() < 1e-12);
        let coarse = job(
            2.5,
            SimMesh::Remeshed(ScanOptions {
                sim_edge: Some(tissue_implant::default_sim_edge(5.25).unwrap()),
                ..ScanOptions::default()
            }),
        );
        assert!((coarse.time_scale().unwrap() - 1.0).abs() < 1e-9);
        // The patient's own triangles (the thesis's planes) keep the set times.
        let own = job(2.5, SimMesh::Patient);
        assert_eq!(own.time_scale().unwrap(), 1.0);
        assert_eq!(own.run_params().unwrap(), own.params);
    }
}
