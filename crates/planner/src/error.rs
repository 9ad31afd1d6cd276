//! The error kinds every front end shows: what went wrong, which request field it concerns, and
//! what to change, in one sentence.
//!
//! Messages name request fields in backticks (`` `volume_cm3` ``), so that a front end can show
//! its own name for them ([`PlanError::message_with`]): `insert` shows its flags, the studio its
//! labels.

use serde::Serialize;
use tissue_app::AppError;
use tissue_implant::{BvhError, ImplantError, SearchedSurface};
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
            E::InvalidParameter { name, .. } => match *name {
                "point" | "max_distance" => (K::Placement, Some("at"), ""),
                "radius" | "region_radius" => (K::Placement, Some("region_radius_cm"), ""),
                "depth" => (K::Parameters, Some("depth_cm"), " (`depth_cm`)"),
                "young" => (
                    K::Parameters,
                    Some("young_kpa"),
                    " (`young_kpa`, here in g/(cm·s²) = 0.1 Pa)",
                ),
                "poisson" => (K::Parameters, Some("poisson"), " (`poisson`)"),
                "skin_thickness" => (K::Parameters, Some("thickness_cm"), " (`thickness_cm`)"),
                "density" => (K::Parameters, Some("density_g_cm3"), " (`density_g_cm3`)"),
                "time_step" => (K::Parameters, Some("time_step_s"), " (`time_step_s`)"),
                "sim_edge" => (K::Parameters, Some("sim_edge_cm"), " (`sim_edge_cm`)"),
                "max_hole" => (K::Parameters, Some("max_hole_cm"), " (`max_hole_cm`)"),
                _ => (K::Parameters, None, ""),
            },
            E::ShapeNotMeshable { .. }
            | E::VolumeOutOfRange { .. }
            | E::VolumeNotReached { .. }
            | E::SurfaceHeight { .. } => (
                K::Parameters,
                Some("volume_cm3"),
                "; change `volume_cm3` or the implant's size",
            ),
            E::InvalidProtocol { field, .. } => match *field {
                "fills" | "expand_weeks" => {
                    (K::Parameters, Some("expand_weeks"), " (`expand_weeks`)")
                }
                "hold_weeks" => (K::Parameters, Some("hold_weeks"), " (`hold_weeks`)"),
                "leakage" => (K::Parameters, Some("leakage"), " (`leakage`)"),
                "overfill" => (K::Parameters, Some("overfill"), " (`overfill`)"),
                _ => (K::Parameters, Some("volume_cm3"), " (`volume_cm3`)"),
            },
            E::TargetNotBracketed { .. } => {
                (K::Parameters, Some("bracket_cm3"), " (`bracket_cm3`)")
            }
            E::Model(tissue_mss::MssError::InvalidSpring { .. }) => (
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
            name: "depth",
            value: -1.0,
            expected: "positive".into(),
        };
        let p = PlanError::from_implant(&v);
        assert_eq!((p.kind, p.field), (ErrorKind::Parameters, Some("depth_cm")));
    }

    /// A search hierarchy that cannot be built is its own error, classified by its type
    /// (issue 22: it was `InvalidParameter { name: "region" }`, classified by that string as a
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
}
