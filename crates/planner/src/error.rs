//! The error kinds every front end shows: what went wrong, which request field it concerns, and
//! what to change, in one sentence.
//!
//! Messages name request fields in backticks (`` `volume_cm3` ``), so that a front end can show
//! its own name for them ([`PlanError::message_with`]): `insert` shows its flags, the studio its
//! labels.

use serde::Serialize;
use tissue_app::AppError;
use tissue_implant::{BvhError, ImplantError, Param, ProtocolField, SearchedSurface};
use tissue_meshio::MeshIoError;

/// What kind of thing went wrong: a front end maps it to an exit code or an HTTP status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorKind {
    /// The request is incomplete: a missing placement or shape size.
    Usage,
    /// The patient file is missing, unreadable or of an unsupported type.
    Input,
    /// The patient file is malformed or its surface invalid.
    Mesh,
    /// The point is off the surface, or the region is empty, too large, too small or at the
    /// scan's border.
    Placement,
    /// An implant or tissue parameter is out of range.
    Parameters,
    /// The run diverged or failed.
    Run,
    /// An output could not be written.
    Output,
    /// The job was cancelled.
    Cancelled,
}

/// A planning request that cannot be carried out, and why.
#[derive(Debug, Clone, PartialEq, Serialize, thiserror::Error)]
#[error("{message}")]
pub struct PlanError {
    /// What kind of failure.
    pub kind: ErrorKind,
    /// The request field at fault (its JSON name), if one is.
    pub field: Option<&'static str>,
    /// What went wrong and what to change, on one line; field names in backticks.
    pub message: String,
}

impl PlanError {
    /// An error of `kind` about no field in particular.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        PlanError {
            kind,
            field: None,
            message: one_line(&message.into()),
        }
    }

    /// An error of `kind` about `field`.
    pub fn field(kind: ErrorKind, field: &'static str, message: impl Into<String>) -> Self {
        PlanError {
            kind,
            field: Some(field),
            message: one_line(&message.into()),
        }
    }

    /// The message with every `` `field` `` replaced by `name(field)` (a front end's own name
    /// for it, e.g. a flag); fields `name` does not know lose their backticks.
    pub fn message_with(&self, name: impl Fn(&str) -> Option<&'static str>) -> String {
        let mut out = String::with_capacity(self.message.len());
        let mut rest = self.message.as_str();
        while let Some(start) = rest.find('`') {
            let Some(len) = rest[start + 1..].find('`') else {
                break;
            };
            let field = &rest[start + 1..start + 1 + len];
            out.push_str(&rest[..start]);
            out.push_str(name(field).unwrap_or(field));
            rest = &rest[start + len + 2..];
        }
        out.push_str(rest);
        out
    }

    /// Reading or parsing the patient file failed.
    pub fn from_mesh_io(e: &MeshIoError) -> Self {
        match e {
            MeshIoError::Io { .. } => PlanError::field(
                ErrorKind::Input,
                "mesh",
                format!("cannot read the mesh: {e}; check the `mesh` path"),
            ),
            MeshIoError::UnsupportedFormat { .. } => {
                PlanError::field(ErrorKind::Input, "mesh", e.to_string())
            }
            MeshIoError::Invalid { .. } => PlanError::field(
                ErrorKind::Mesh,
                "mesh",
                format!("{e}; repair the scan (meshinfo lists every defect)"),
            ),
            _ => PlanError::field(
                ErrorKind::Mesh,
                "mesh",
                format!("malformed mesh file: {e}; export the scan again as .obj, .ply or .stl"),
            ),
        }
    }

    /// The simulation library refused the inputs or failed.
    pub fn from_implant(e: &ImplantError) -> Self {
        use ErrorKind as K;
        use ImplantError as E;
        let (kind, field, hint): (ErrorKind, Option<&'static str>, &str) = match e {
            E::Cancelled { .. } => (K::Cancelled, None, ""),
            E::PointOffSurface { .. } => (
                K::Placement,
                Some("at"),
                " (distances in cm); give an `at` on the skin (in the mesh's unit) or a `vertex`",
            ),
            E::EmptyRegion { .. } => (
                K::Placement,
                Some("region_radius_cm"),
                " (set with `region_radius_cm`)",
            ),
            E::RegionCoversSurface { .. } => (
                K::Placement,
                Some("region_radius_cm"),
                " (set with `region_radius_cm`, default 1.5 × the implant's footprint radius); \
                 the mesh is too small for this region: use a smaller `region_radius_cm` or \
                 implant, or a larger scan",
            ),
            E::FootprintOutsideRegion { .. } => (
                K::Placement,
                Some("region_radius_cm"),
                "; use a larger `region_radius_cm` or a smaller implant, away from the scan's edge",
            ),
            E::ClosedRegion { .. } => (K::Placement, Some("region_radius_cm"), ""),
            E::RimAtBorder { .. } => (
                K::Placement,
                Some("at"),
                " (`region_radius_cm`; `at`, `vertex`)",
            ),
            E::RegionReachesBorder { .. } => (
                K::Placement,
                Some("at"),
                " (coordinates in cm; `at` takes the mesh's unit; `max_hole_cm` sets the holes \
                 filled)",
            ),
            E::Remesh(_) => (
                K::Mesh,
                Some("sim_edge_cm"),
                "; check the scan with meshinfo, or give another `sim_edge_cm`",
            ),
            E::Search { surface, source } => search_kind(*surface, source),
            E::NoMeanNormal { .. } => (K::Placement, Some("at"), " (`at`, `vertex`)"),
            E::InvalidParameter { param, .. } => param_kind(*param),
            E::ShapeNotMeshable { .. }
            | E::VolumeOutOfRange { .. }
            | E::VolumeNotReached { .. }
            | E::SurfaceHeight { .. } => (
                K::Parameters,
                Some("volume_cm3"),
                "; change `volume_cm3` or the implant's size",
            ),
            E::InvalidProtocol { field, .. } => protocol_kind(*field),
            E::TargetNotBracketed { .. } => {
                (K::Parameters, Some("bracket_cm3"), " (`bracket_cm3`)")
            }
            E::Model(tissue_implant::MssError::InvalidSpring { .. }) => (
                K::Placement,
                Some("at"),
                "; the skin or the implant's base bent onto it has badly shaped (obtuse) \
                 triangles at this point: pick another point (`at`, `vertex`), a smaller or \
                 larger implant, or remesh the scan",
            ),
            E::Diverged { .. } => (
                K::Run,
                Some("time_step_s"),
                " (leave `time_step_s` automatic, or lower it)",
            ),
            E::RanAway { .. } => (K::Run, None, ""),
            _ => (
                K::Run,
                None,
                "; check the scan (meshinfo) and the parameters, or report this",
            ),
        };
        let message = match kind {
            K::Run => format!("the run failed: {e}{hint}"),
            _ => format!("{e}{hint}"),
        };
        PlanError {
            kind,
            field,
            message: one_line(&message),
        }
    }

    /// The worker did not give a result.
    pub fn from_app(e: &AppError) -> Self {
        match e {
            AppError::Implant(inner) => PlanError::from_implant(inner),
            AppError::Cancelled { steps } => PlanError::cancelled(*steps),
            _ => PlanError::new(
                ErrorKind::Run,
                format!("the run failed: {e}; check the scan and the parameters, or report this"),
            ),
        }
    }

    /// A cancelled job.
    pub fn cancelled(steps: u64) -> Self {
        PlanError::new(
            ErrorKind::Cancelled,
            format!("cancelled after {steps} steps; nothing was written"),
        )
    }
}

/// The kind, request field and hint of a library parameter out of range: the request field
/// that sets it (a [`PlanRequest`](crate::PlanRequest) or [`JobSpec`](crate::JobSpec) key), or
/// none where no request field does. Exhaustive on purpose: a new [`Param`] must be placed here.
fn param_kind(param: Param) -> (ErrorKind, Option<&'static str>, &'static str) {
    use ErrorKind as K;
    use Param as P;
    match param {
        // Where the implant goes: `at` (or `vertex`) picks the point, its normal and the frame.
        P::Point | P::MaxDistance | P::Origin | P::Normal => (K::Placement, Some("at"), ""),
        P::Tangent => (K::Placement, Some("tangent"), " (`tangent`)"),
        P::Radius | P::RegionRadius => (K::Placement, Some("region_radius_cm"), ""),
        // The implant.
        P::Diameter => (K::Parameters, Some("diameter_cm"), " (`diameter_cm`)"),
        P::Length => (K::Parameters, Some("length_cm"), " (`length_cm`)"),
        P::Width => (K::Parameters, Some("width_cm"), " (`width_cm`)"),
        P::CornerRadius => (
            K::Parameters,
            Some("corner_radius_cm"),
            " (`corner_radius_cm`)",
        ),
        P::BendRadius => (K::Parameters, Some("bend_radius_cm"), " (`bend_radius_cm`)"),
        P::VolumeCm3 => (K::Parameters, Some("volume_cm3"), " (`volume_cm3`)"),
        P::VertexBudget => (
            K::Parameters,
            Some("implant_vertices"),
            " (`implant_vertices`)",
        ),
        // The tissue.
        P::Depth => (K::Parameters, Some("depth_cm"), " (`depth_cm`)"),
        P::Young => (
            K::Parameters,
            Some("young_kpa"),
            " (`young_kpa`, here in g/(cm·s²) = 0.1 Pa)",
        ),
        P::Poisson => (K::Parameters, Some("poisson"), " (`poisson`)"),
        P::SkinThickness => (K::Parameters, Some("thickness_cm"), " (`thickness_cm`)"),
        P::Density => (K::Parameters, Some("density_g_cm3"), " (`density_g_cm3`)"),
        // The simulation mesh and the run.
        P::SimEdge => (K::Parameters, Some("sim_edge_cm"), " (`sim_edge_cm`)"),
        P::MaxHole => (K::Parameters, Some("max_hole_cm"), " (`max_hole_cm`)"),
        P::TimeStep => (K::Parameters, Some("time_step_s"), " (`time_step_s`)"),
        // Expansion over weeks.
        P::BandSamples => (K::Parameters, Some("band_samples"), " (`band_samples`)"),
        P::GrowthStep => (K::Parameters, Some("growth_step_h"), " (`growth_step_h`)"),
        // The inverse search (job keys).
        P::TargetGain => (
            K::Parameters,
            Some("target_gain_cm2"),
            " (`target_gain_cm2`)",
        ),
        P::BracketLow | P::BracketHigh => (K::Parameters, Some("bracket_cm3"), " (`bracket_cm3`)"),
        P::GainTolerance => (
            K::Parameters,
            Some("gain_tolerance_cm2"),
            " (`gain_tolerance_cm2`)",
        ),
        // No request field sets these: the planner passes the library's defaults (layers,
        // implant, contact run, growth law, scan smoothing, search options, band rungs), or they
        // are values computed during a run (heights, θg, start positions, gains, the surfaces
        // compared after a run, a geodesic's source and limit) or by the planner itself (the
        // footprint radius, the patient). A request cannot put them out of range, so this is a
        // failed run to report.
        P::AnchorYoung
        | P::MinThickness
        | P::OffsetReach
        | P::ShellYoung
        | P::ShellThickness
        | P::ShellPoisson
        | P::FillDensity
        | P::FillBulkModulus
        | P::RadialModulus
        | P::VolumeCoupling
        | P::PocketMargin
        | P::FillTime
        | P::StepSafety
        | P::DampingTime
        | P::ContactDistance
        | P::ContactFraction
        | P::Coherence
        | P::SettleSpeed
        | P::Tolerance
        | P::LoadSteps
        | P::ContactStiffness
        | P::GrowthRate
        | P::Prestretch
        | P::GrowthThreshold
        | P::FlapRelease
        | P::Stiffness
        | P::Smoothing
        | P::Iterations
        | P::VolumeTolerance
        | P::MaxRuns
        | P::BandRungs
        | P::Heights
        | P::ThetaG
        | P::Start
        | P::Gain
        | P::Before
        | P::After
        | P::RegionAfter
        | P::SimAfter
        | P::SourceTriangle
        | P::Limit
        | P::FootprintRadius
        | P::Patient => (K::Run, None, "; report this"),
        // Not run by the planner at all: the plane-press experiment.
        P::SphereRadius | P::Speed => (K::Run, None, "; report this"),
    }
}

/// The kind, request field and hint of an expansion protocol that cannot be run, by the field
/// at fault. Exhaustive on purpose, as [`param_kind`].
fn protocol_kind(field: ProtocolField) -> (ErrorKind, Option<&'static str>, &'static str) {
    use ErrorKind as K;
    use ProtocolField as F;
    match field {
        // The fills are made from `expand_weeks` (one per week).
        F::Fills | F::ExpandWeeks => (K::Parameters, Some("expand_weeks"), " (`expand_weeks`)"),
        F::HoldWeeks => (K::Parameters, Some("hold_weeks"), " (`hold_weeks`)"),
        F::Leakage => (K::Parameters, Some("leakage"), " (`leakage`)"),
        F::Overfill => (K::Parameters, Some("overfill"), " (`overfill`)"),
        // The protocol's nominal volume is the request's volume.
        F::Volume => (K::Parameters, Some("volume_cm3"), " (`volume_cm3`)"),
    }
}

/// The kind, field and hint of a search hierarchy that could not be built, by the surface and
/// the hierarchy's reason.
fn search_kind(
    surface: SearchedSurface,
    source: &BvhError,
) -> (ErrorKind, Option<&'static str>, &'static str) {
    use ErrorKind as K;
    match (surface, source) {
        (
            _,
            BvhError::NonFiniteBounds { .. }
            | BvhError::IndexOutOfRange { .. }
            | BvhError::TooManyPrimitives { .. },
        ) => (
            K::Mesh,
            Some("mesh"),
            "; check the scan with meshinfo, or report this",
        ),
        (SearchedSurface::RegionInnerLayer, BvhError::Empty) => (
            K::Placement,
            Some("region_radius_cm"),
            "; use a larger `region_radius_cm`",
        ),
        (SearchedSurface::ImplantBase, BvhError::Empty) => (
            K::Parameters,
            Some("volume_cm3"),
            "; change the implant's size",
        ),
        (SearchedSurface::SimulationSurface, _) => (
            K::Mesh,
            Some("sim_edge_cm"),
            "; check the scan with meshinfo, or give another `sim_edge_cm`",
        ),
        _ => (K::Run, None, "; report this"),
    }
}

/// `s` with every run of white space (new lines included) made one space.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_follow_the_library_errors_and_messages_are_one_line() {
        let e = ImplantError::RegionCoversSurface {
            radius: 9.0,
            triangles: 10,
            farthest: 3.0,
        };
        let p = PlanError::from_implant(&e);
        assert_eq!(p.kind, ErrorKind::Placement);
        assert_eq!(p.field, Some("region_radius_cm"));
        assert!(!p.message.contains('\n'));
        let shown = p.message_with(|f| (f == "region_radius_cm").then_some("--radius"));
        assert!(shown.contains("smaller --radius"), "{shown}");
        assert!(!shown.contains('`'), "{shown}");
        let d = ImplantError::Diverged {
            step: 3,
            particle: 1,
            what: "position",
        };
        assert_eq!(PlanError::from_implant(&d).kind, ErrorKind::Run);
        let v = ImplantError::InvalidParameter {
            param: Param::Depth,
            value: -1.0,
            expected: "positive".into(),
        };
        let p = PlanError::from_implant(&v);
        assert_eq!((p.kind, p.field), (ErrorKind::Parameters, Some("depth_cm")));
    }

    /// A search hierarchy that cannot be built is its own error, classified by its type
    /// (regression: it was once `InvalidParameter` named `region`, classified by that string as a
    /// placement at `at`).
    #[test]
    fn search_failures_are_classified_by_type() {
        let non_finite = BvhError::NonFiniteBounds {
            primitive: 3,
            min: [f32::NAN; 3],
            max: [0.0; 3],
        };
        let cases = [
            (
                SearchedSurface::RegionInnerLayer,
                non_finite.clone(),
                ErrorKind::Mesh,
                Some("mesh"),
            ),
            (
                SearchedSurface::RegionInnerLayer,
                BvhError::Empty,
                ErrorKind::Placement,
                Some("region_radius_cm"),
            ),
            (
                SearchedSurface::ImplantBase,
                BvhError::Empty,
                ErrorKind::Parameters,
                Some("volume_cm3"),
            ),
            (
                SearchedSurface::SimulationSurface,
                BvhError::Empty,
                ErrorKind::Mesh,
                Some("sim_edge_cm"),
            ),
            (
                SearchedSurface::ImplantBase,
                BvhError::InvalidLeafSize { leaf_size: 0 },
                ErrorKind::Run,
                None,
            ),
        ];
        for (surface, source, kind, field) in cases {
            let e = ImplantError::Search {
                surface,
                source: source.clone(),
            };
            let p = PlanError::from_implant(&e);
            assert_eq!((p.kind, p.field), (kind, field), "{e}");
            assert!(p
                .message
                .contains(&format!("the {surface} cannot be searched")));
            assert!(p.message.contains(&source.to_string()), "{}", p.message);
            // Carried unchanged through the worker's error.
            let app = PlanError::from_app(&AppError::Implant(e));
            assert_eq!((app.kind, app.field), (kind, field));
        }
        let flat = PlanError::from_implant(&ImplantError::NoMeanNormal { triangles: 2 });
        assert_eq!((flat.kind, flat.field), (ErrorKind::Placement, Some("at")));
    }

    #[test]
    fn unknown_fields_lose_their_backticks_and_a_lone_backtick_stays() {
        let p = PlanError::new(ErrorKind::Usage, "give `at` or `vertex` (a ` here)");
        assert_eq!(p.message_with(|_| None), "give at or vertex (a ` here)");
    }

    /// The JSON keys a request can carry: every [`crate::PlanRequest`] field (its default,
    /// serialized) and the job keys of the inverse search, which [`crate::JobSpec`] accepts.
    fn request_keys() -> Vec<String> {
        let request = serde_json::to_value(crate::PlanRequest::default()).unwrap();
        let mut keys: Vec<String> = request.as_object().unwrap().keys().cloned().collect();
        for key in ["target_gain_cm2", "bracket_cm3", "gain_tolerance_cm2"] {
            // `JobSpec` refuses unknown keys; a known one fails on the value's type instead.
            let parsed = serde_json::from_str::<crate::JobSpec>(&format!(r#"{{"{key}": "x"}}"#));
            let message = parsed.err().map(|e| e.to_string()).unwrap_or_default();
            assert!(!message.contains("unknown field"), "{key}: {message}");
            keys.push(key.to_owned());
        }
        keys
    }

    /// Every library parameter maps to a kind and, where a request field sets it, to that
    /// field's JSON key: a parameter whose name is the start of a request key (`depth` →
    /// `depth_cm`) must not lose its field, as the string match's `_ =>` arm once did.
    #[test]
    fn every_library_parameter_maps_to_a_real_request_field() {
        let keys = request_keys();
        for &param in Param::ALL {
            let e = ImplantError::InvalidParameter {
                param,
                value: -1.0,
                expected: "positive".into(),
            };
            let p = PlanError::from_implant(&e);
            assert_eq!((p.kind, p.field), {
                let (kind, field, _) = param_kind(param);
                (kind, field)
            });
            assert!(p.message.contains(param.name()), "{param:?}: {}", p.message);
            if let Some(field) = p.field {
                assert!(
                    keys.iter().any(|k| k == field),
                    "{param:?} → {field}: not a request key"
                );
                assert!(
                    matches!(p.kind, ErrorKind::Placement | ErrorKind::Parameters),
                    "{param:?}: a request field is the user's to fix, not {:?}",
                    p.kind
                );
            }
            // The key named after the parameter, with or without its unit (`depth` → `depth_cm`).
            let name = param.name().replace(' ', "_");
            let named = |k: &&String| {
                k.strip_prefix(&name).is_some_and(|unit| {
                    ["", "_cm", "_cm2", "_cm3", "_s", "_h", "_kpa", "_g_cm3"].contains(&unit)
                })
            };
            if let Some(key) = keys.iter().find(named) {
                assert!(
                    p.field.is_some(),
                    "{param:?} is set by `{key}` but maps to no field"
                );
            }
        }
    }

    /// The same for the fields of an expansion protocol.
    #[test]
    fn every_protocol_field_maps_to_a_real_request_field() {
        let keys = request_keys();
        for &field in ProtocolField::ALL {
            let e = ImplantError::InvalidProtocol {
                field,
                problem: "wrong".into(),
            };
            let p = PlanError::from_implant(&e);
            assert_eq!(p.kind, ErrorKind::Parameters, "{field:?}");
            let key = p
                .field
                .unwrap_or_else(|| panic!("{field:?} maps to no field"));
            assert!(
                keys.iter().any(|k| k == key),
                "{field:?} → {key}: not a request key"
            );
            assert!(
                p.message.contains(&format!("protocol {field}: wrong")),
                "{}",
                p.message
            );
        }
    }
}
