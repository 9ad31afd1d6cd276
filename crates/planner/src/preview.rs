//! The live preview: while a planner drags the expander or moves the volume or depth, the dome
//! and its area gain, computed on a coarse simulation mesh with a short step budget, so that a
//! front end can draw it within a fraction of a second and without Run.
//!
//! A preview is a planning run through the front door like any other: the request placed on the
//! patient ([`Scenario::new`], with every check of a run), then made coarse ([`coarse`]):
//! - **the simulation edge** is [`PREVIEW_COARSENING`] × the default edge for the region's
//!   radius ([`tissue_implant::default_sim_edge`], the edge that gives the region about Table 2's
//!   1 008 vertices), or the request's own edge when that is coarser: the region then has about
//!   1 008 / [`PREVIEW_COARSENING`]² vertices whatever the patient and the expander's size, so
//!   the work of a preview does not grow with the scan. The region is remeshed at that edge
//!   even on the generated Table 2 plane (whose full runs use its own triangles);
//! - **the step budget** is at most [`PREVIEW_MAX_STEPS`];
//! - **the implant** has at most [`PREVIEW_IMPLANT_VERTICES`] vertices;
//! - an expansion over weeks is previewed as its single insertion at the full volume.
//!
//! [`Previewer`] keeps the last preview: the same coarse request again (a drag that came back,
//! a slider moved and moved back) is answered from it without running; the patient is shared,
//! not copied, between previews. The run is cancelled through a [`CancelToken`] within one step.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};
use tissue_app::{CancelToken, SimMesh};
use tissue_implant::ScanOptions;

#[cfg(test)]
use crate::error::ErrorKind;
use crate::error::PlanError;
use crate::patient::Patient;
use crate::request::PlanRequest;
use crate::run::Stopped;
use crate::scenario::Scenario;

/// The preview's simulation edge over the default edge for the region's radius: 3, so a region
/// has about 1 008 / 3² ≈ 110 vertices a layer (136 on Table 2's 7 cm expander, edge 0.945 cm).
/// Measured with the explicit solver (Table 2 and the chest, 120 cm³): 2.5 and 3 give the same
/// gain within 1 %, 3 is the cheaper; the cost of a step is mostly the implant's.
pub const PREVIEW_COARSENING: f64 = 3.0;

/// The most steps a preview runs: 300. With the explicit solver the coarse run's gain is within
/// 0.5 % of its settled value after 250 steps (Table 2 and the chest, 120 cm³; 150 steps is
/// still in the fill's overshoot, +13 %), and a step costs about 0.7 ms there on one core.
pub const PREVIEW_MAX_STEPS: u64 = 300;

/// The most vertices of a preview's implant: 250 (the full run's default is 500). Fewer move the
/// gain off the full run's: +10 % at 150, +4 % at 200, +2 % at 250 (Table 2, 120 cm³).
pub const PREVIEW_IMPLANT_VERTICES: u32 = 250;

/// The preview's simulation edge (cm) for a region of radius `region_radius_cm`:
/// [`PREVIEW_COARSENING`] × [`tissue_implant::default_sim_edge`].
///
/// # Errors
/// A radius that is not finite and positive ([`ErrorKind::Placement`]).
pub fn preview_edge_cm(region_radius_cm: f64) -> Result<f64, PlanError> {
    tissue_implant::default_sim_edge(region_radius_cm)
        .map(|h| h * PREVIEW_COARSENING)
        .map_err(|e| PlanError::from_implant(&e))
}

/// `scenario` made coarse for a preview (the module's rules): the edge, the step budget, the
/// implant's vertices, no expansion. The placement is the scenario's.
///
/// # Errors
/// The region radius cannot be known ([`Scenario::region_radius`]).
pub fn coarse(mut scenario: Scenario) -> Result<Scenario, PlanError> {
    let radius = scenario.region_radius()?;
    let edge = preview_edge_cm(radius)?.max(scenario.request.sim_edge_cm.unwrap_or(0.0));
    let steps = scenario.request.max_steps.min(PREVIEW_MAX_STEPS);
    let vertices = scenario
        .request
        .implant_vertices
        .min(PREVIEW_IMPLANT_VERTICES);
    let request = &mut scenario.request;
    request.sim_edge_cm = Some(edge);
    request.scan_triangles = false;
    request.max_steps = steps;
    request.implant_vertices = vertices;
    request.expand_weeks = None;
    let job = &mut scenario.job;
    job.sim = SimMesh::Remeshed(ScanOptions {
        sim_edge: Some(edge),
        max_hole: request.max_hole_cm,
        ..ScanOptions::default()
    });
    job.params.run.stop.max_steps = steps;
    job.implant = job.implant.with_vertex_budget(vertices);
    Ok(scenario)
}

/// A preview: the area gain and the dome to draw.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DomePreview {
    /// The region's area gain, cm² (the report's `area_gain_cm2`, on the coarse mesh).
    pub gain_cm2: f64,
    /// The simulation edge used, cm.
    pub edge_cm: f64,
    /// Steps run.
    pub steps: u64,
    /// Whether the run settled within its budget (else it stopped at [`PREVIEW_MAX_STEPS`]).
    pub settled: bool,
    /// The simulation surface after the run (layer 1, the skin), cm, `[x0, y0, z0, x1, …]`.
    pub positions: Vec<f32>,
    /// Its triangles, `[a0, b0, c0, a1, …]`.
    pub triangles: Vec<u32>,
    /// The largest displacement of the skin, cm.
    pub max_displacement_cm: f32,
    /// Wall time of the set-up and the run, ms.
    pub compute_ms: f64,
    /// Whether it was the last preview again (not run).
    pub reused: bool,
}

/// Runs previews for one front-end client, keeping the last one ([`Previewer::preview`]).
#[derive(Debug, Default)]
pub struct Previewer {
    last: Option<(PlanRequest, Arc<Patient>, DomePreview)>,
}

impl Previewer {
    /// A previewer with nothing kept.
    pub fn new() -> Previewer {
        Previewer::default()
    }

    /// The preview of `request` on `patient`: placed as a run is ([`Scenario::new`]), made
    /// [`coarse`], and run to its stop or [`PREVIEW_MAX_STEPS`]; the last preview when the
    /// coarse request and the patient are the same. `cancel` ends it within one step.
    ///
    /// # Errors
    /// [`Stopped::Cancelled`], or [`Stopped::Failed`] with the placement's or the run's error
    /// (as Run would give it, naming the request field).
    pub fn preview(
        &mut self,
        patient: &Arc<Patient>,
        request: PlanRequest,
        cancel: &CancelToken,
    ) -> Result<DomePreview, Stopped> {
        let _span = tracing::info_span!("planner_live_preview").entered();
        let started = Instant::now();
        if cancel.is_cancelled() {
            return Err(Stopped::Cancelled { steps: 0 });
        }
        let scenario = coarse(Scenario::new(Patient::clone(patient), request)?)?;
        if let Some((last, who, kept)) = &self.last {
            if *last == scenario.request && Arc::ptr_eq(who, patient) {
                return Ok(DomePreview {
                    reused: true,
                    compute_ms: ms(started.elapsed()),
                    ..kept.clone()
                });
            }
        }
        let preview = run(&scenario, cancel, started)?;
        self.last = Some((scenario.request, Arc::clone(patient), preview.clone()));
        Ok(preview)
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1000.0
}

/// Sets up and runs the coarse `scenario` on this thread.
fn run(
    scenario: &Scenario,
    cancel: &CancelToken,
    started: Instant,
) -> Result<DomePreview, Stopped> {
    let edge = scenario.sim_edge()?.unwrap_or(0.0);
    let planned = tissue_app::plan(&scenario.job, |_| {
        if cancel.is_cancelled() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })
    .map_err(|e| match e {
        tissue_implant::ImplantError::Cancelled { steps } => Stopped::Cancelled { steps },
        e => Stopped::Failed(PlanError::from_implant(&e)),
    })?;
    let outcome = &planned.outcome;
    if !outcome.is_finite() {
        return Err(crate::report::diverged().into());
    }
    let skin = &outcome.region_after;
    Ok(DomePreview {
        gain_cm2: outcome.area_gain,
        edge_cm: edge,
        steps: outcome.steps,
        settled: outcome.stop_reason == tissue_implant::StopReason::Settled,
        positions: skin.positions().iter().flat_map(|p| p.to_array()).collect(),
        triangles: skin.triangles().iter().flatten().copied().collect(),
        max_displacement_cm: outcome.max_displacement,
        compute_ms: ms(started.elapsed()),
        reused: false,
    })
}

#[cfg(test)]
#[allow(clippy::panic)]
mod tests {
    use super::*;
    use crate::{JobReport, JobSpec, Shipped, Tool};

    fn table2() -> Result<Arc<Patient>, PlanError> {
        Ok(Arc::new(Patient::shipped(Shipped::Table2)?))
    }

    /// The preview's gain is within 10 % of the full run's at the same place, on a mesh
    /// [`PREVIEW_COARSENING`] times coarser, within [`PREVIEW_MAX_STEPS`].
    #[test]
    fn the_preview_gain_is_within_a_tenth_of_the_full_runs() -> Result<(), Stopped> {
        let patient = table2()?;
        let request = PlanRequest {
            volume_cm3: 120.0,
            ..PlanRequest::default()
        };
        let preview = Previewer::new().preview(&patient, request.clone(), &CancelToken::new())?;
        let radius = Scenario::new(Patient::clone(&patient), request.clone())?.region_radius()?;
        assert_eq!(preview.edge_cm, preview_edge_cm(radius)?);
        assert!(preview.steps <= PREVIEW_MAX_STEPS);
        assert_eq!(preview.positions.len() % 3, 0);
        assert!(preview
            .triangles
            .iter()
            .all(|&t| (t as usize) < preview.positions.len() / 3));
        let scenario = Scenario::new(Patient::clone(&patient), request.clone())?;
        let full = JobSpec {
            request,
            ..JobSpec::default()
        }
        .plan(&scenario)?
        .run(&scenario, Tool::Studio, &CancelToken::new(), |_| {})?;
        let JobReport::Single(report) = &full.report else {
            panic!("a single run's report");
        };
        let gain = report.body.area_gain_cm2;
        let off = (preview.gain_cm2 - gain).abs() / gain;
        assert!(
            off < 0.1,
            "preview {} cm², full run {gain} cm²",
            preview.gain_cm2
        );
        Ok(())
    }

    #[test]
    fn a_cancelled_preview_stops_and_a_repeated_one_is_reused() -> Result<(), Stopped> {
        let patient = table2()?;
        let mut previewer = Previewer::new();
        let token = CancelToken::new();
        token.cancel();
        let stopped = previewer.preview(&patient, PlanRequest::default(), &token);
        assert!(
            matches!(stopped, Err(Stopped::Cancelled { .. })),
            "{stopped:?}"
        );
        let request = PlanRequest {
            max_steps: 20,
            ..PlanRequest::default()
        };
        let first = previewer.preview(&patient, request.clone(), &CancelToken::new())?;
        assert!(!first.reused && first.steps == 20);
        let again = previewer.preview(&patient, request.clone(), &CancelToken::new())?;
        assert!(again.reused);
        assert_eq!(again.gain_cm2, first.gain_cm2);
        let other = PlanRequest {
            volume_cm3: 90.0,
            ..request
        };
        assert!(
            !previewer
                .preview(&patient, other, &CancelToken::new())?
                .reused
        );
        Ok(())
    }

    #[test]
    fn a_placement_that_cannot_run_is_refused_naming_its_field() -> Result<(), PlanError> {
        let patient = table2()?;
        let request = PlanRequest {
            at: Some([8.0, 0.0, 0.0]),
            ..PlanRequest::default()
        };
        match Previewer::new().preview(&patient, request, &CancelToken::new()) {
            Err(Stopped::Failed(e)) => assert_eq!(e.kind, ErrorKind::Placement),
            other => panic!("a preview at the border: {other:?}"),
        }
        let bad = PlanRequest {
            depth_cm: -1.0,
            ..PlanRequest::default()
        };
        match Previewer::new().preview(&patient, bad, &CancelToken::new()) {
            Err(Stopped::Failed(e)) => assert_eq!(e.field, Some("depth_cm")),
            other => panic!("a negative depth: {other:?}"),
        }
        Ok(())
    }
}
