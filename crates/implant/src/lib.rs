//! # tissue-implant: the implant-insertion scenario of the thesis (SPEC A.5)
//!
//! ## Brief overview
//! - [`RegionSelection`]: the geodesic disc of the patient surface around the implant position
//!   ([`select_region`]; radius by default [`default_radius`]), as its own mesh with vertex maps,
//!   boundary loops, area and distances.
//! - [`SurfacePoint`]: a point snapped to a surface ([`snap_to_surface`]), the source of
//!   [`geodesic_distances`] (fast marching with point-source updates).
//! - [`TissueLayers`]: the two-layer mass–spring model of a skin region (layer 1 the region,
//!   layer 2 offset inward by the placement depth, springs between the layers against
//!   compression and shear, zero-length anchors on layer 2, the boundary fixed).
//! - [`ImplantSpec`]: a tissue expander ([`ImplantShape`]: round, rectangular, crescent) of a
//!   target volume, built as a closed outward mesh ([`Implant`]) by solving for its dome height,
//!   flat or bent onto the body surface it lies on ([`ImplantFrame`]).
//! - [`Insertion`]: the run (SPEC A.5 step 4) — the layers against the implant (its own
//!   mass–spring system with volume preservation, base held by the deeper tissue) in the thesis's
//!   step order ([`ContactRun`]), the expander filled from flat, a progress callback that can
//!   cancel — and its [`InsertionOutcome`]: areas, volume difference, implant compression,
//!   per-vertex displacement and stretch, the patient with the region replaced. [`Solver`]
//!   chooses how the rest state is found: the thesis's explicit stepping (the default), or the
//!   experimental quasi-static solve of the same model ([`StaticParams`]: Newton–CG on the
//!   Hessian, penalty contacts, load steps; its status in docs/validation.md).
//! - [`sweep`] and [`volume_for_gain`]: series of runs in parallel and the inverse question
//!   "which volume gives this area gain".
//! - [`prepare_scan`] and [`SimSurface`]: planning on a real scan — its small holes
//!   filled, the region refused where it reaches an open border
//!   ([`ImplantError::RegionReachesBorder`]), remeshed into a simulation surface of its own
//!   (edge [`default_sim_edge`], smoothed below it), every scan vertex of the region bound to
//!   it and moved with it afterwards ([`SimSurface::map_to_scan`], [`ScanResult`]).
//! - [`expand`]: expansion over weeks — a fill [`Protocol`], skin growth by the
//!   calibrated law ([`GrowthLaw`], [`GrowthParams`]) re-settled at least daily from the
//!   previous state, removal, the flap ([`ExpansionOutcome`]) and its band ([`Band`]).
//! - [`walk_on_surface`]: straightest geodesics, the exponential map that wraps an expander's
//!   base onto the body ([`ImplantSpec::build_wrapped`], [`place_implant`]).
//!
//! How the pieces fit on a real scan: the expander's base is wrapped onto layer 2 by the
//! exponential map and lowered where layer 2 dips between its vertices; layer 2 is offset along
//! normals averaged over a length of the model ([`SimSurface::offset_reach`]), so a fold
//! narrower than the depth is untangled, and the smoothing and offset lengths do not shrink with
//! the simulation edge (halving it samples the same model). Layer 1 bends as a plate
//! (discrete-shell hinges; off for Table 1's press). A run stops by the thesis's criterion or
//! when layer 1's area has stopped moving (the plateau rule). An expansion refills the expander
//! under the tissue where it is and re-settles both layers on the grown
//! rest metric ([`TissueLayers::grow`]) after every growth step (at most 24 h). Validation
//! status: `docs/validation.md`.
//!
//! Pure scenario logic on top of `tissue-mesh`, `tissue-mss`, `tissue-bvh` and `tissue-collide`:
//! no threads of its own (a sweep uses rayon's pool), no terminal, no file I/O. Units: cm, g, s.
//!
//! ```
//! use tissue_implant::{Layer, LayerParams, TissueLayers};
//!
//! // A flat skin patch of radius 3 cm, its inner layer 1 cm below, lifted 0.5 cm.
//! let region = tissue_mesh::disc(6, 24, 3.0)?;
//! let mut layers = TissueLayers::new(&region, &LayerParams::default())?;
//! layers.lift(0.5)?;
//! let centre = layers.positions(Layer::Outer)[0];
//! assert!((centre.z - 0.5).abs() < 1e-6);
//! # Ok::<(), tissue_implant::ImplantError>(())
//! ```
#![forbid(unsafe_code)]

mod adjacency;
mod bending;
mod contact_run;
mod error;
mod expansion;
mod geodesic;
mod growth;
mod insertion;
mod krylov;
mod layers;
mod outcome;
mod plane_press;
mod planning;
mod quasi_static;
mod region;
mod scan;

mod shape;
mod walk;

pub use contact_run::{ContactRun, RunParams, StepSummary};
pub use error::{ImplantError, Param, ProtocolField, SearchedSurface};
pub use expansion::{
    expand, Band, BandOptions, ExpansionMonitor, ExpansionOutcome, ExpansionProgress,
    ExpansionRecord, ExpansionSetup, ExpansionStage, Percentiles, SampleParams, SampleResult,
    QUICK_WINDOW,
};
pub use growth::{
    Fill, GrowthLaw, GrowthParams, Protocol, FLAP_RELEASE, HUMAN_THRESHOLD, HUMAN_THRESHOLD_SPREAD,
    LEAKAGE_MEAN, LEAKAGE_SD, LN_RATE_MEAN, LN_RATE_SD, MAX_OVERFILL, MAX_PROTOCOL_DAYS,
    PIG_PRESTRETCH, RATE_MEDIAN,
};
pub use insertion::{
    dissect_pocket, implant_system, place_implant, rim_border_clearance, ImplantParams, Insertion,
    InsertionOutcome, InsertionParams, Progress, Solver, PLATEAU_HALF, PLATEAU_TOLERANCE,
    RUNAWAY_FACTOR,
};
pub use layers::{Layer, LayerParams, TissueLayers};
pub use outcome::{replace_region, vertex_displacements, vertex_stretch, FieldRange};
pub use plane_press::{plane_press, plane_press_region, PlanePressOutcome, PlanePressParams};
pub use planning::{sweep, volume_for_gain, InverseOptions, InverseSearch, PlanningRun};
pub use quasi_static::{StaticParams, StaticReport};
pub use region::{
    default_radius, default_snap_distance, geodesic_distances, select_region, select_region_with,
    snap_to_surface, RegionOptions, RegionRule, RegionSelection, SurfacePoint,
    DEFAULT_RADIUS_FACTOR, DEFAULT_SNAP_FRACTION, NOT_IN_REGION,
};
pub use scan::{
    default_sim_edge, model_edge, prepare_scan, ScanOptions, ScanResult, SimSurface,
    DEFAULT_MAX_HOLE, TABLE2_REGION_VERTICES,
};
pub use shape::{Implant, ImplantFrame, ImplantShape, ImplantSpec};
/// The search hierarchy's error, carried by [`ImplantError::Search`].
pub use tissue_bvh::BvhError;
/// The broad phase of a run's collision detection ([`RunParams`]), so that callers need not
/// depend on tissue-collide.
pub use tissue_collide::BroadPhase;
/// The tissue model's error ([`ImplantError::Model`]) and why a run stopped, so that callers
/// need not depend on tissue-mss.
pub use tissue_mss::{MssError, StopReason};
pub use walk::{walk_on_surface, WalkEnd};
