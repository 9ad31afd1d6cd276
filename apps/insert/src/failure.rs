//! Why the program stops: a one-line message that says what to change, and its exit code.

use tissue_app::AppError;
use tissue_implant::ImplantError;
use tissue_meshio::MeshIoError;

/// The documented exit codes (see `insert --help`).
pub mod code {
    /// Usage: clap's code for a bad command line.
    pub const USAGE: u8 = 2;
    /// The input file is missing, unreadable or of an unsupported type.
    pub const INPUT: u8 = 3;
    /// The mesh is malformed or invalid.
    pub const MESH: u8 = 4;
    /// The point is off the surface, or the region is empty, too large or too small.
    pub const PLACEMENT: u8 = 5;
    /// An implant or tissue parameter is out of range.
    pub const PARAMETERS: u8 = 6;
    /// The run diverged or failed.
    pub const RUN: u8 = 7;
    /// An output could not be written.
    pub const OUTPUT: u8 = 8;
    /// Interrupted by Ctrl-C.
    pub const INTERRUPTED: u8 = 130;
}

/// A reason to stop with a non-zero exit code.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// The exit code.
    pub code: u8,
    /// What went wrong and what to change, on one line.
    pub message: String,
}

impl Failure {
    /// A failure with `code` and `message`.
    pub fn new(code: u8, message: impl Into<String>) -> Self {
        Failure {
            code,
            message: message.into(),
        }
    }

    /// The message on one line.
    pub fn line(&self) -> String {
        self.message
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Reading the mesh file failed.
    pub fn from_mesh_io(e: &MeshIoError) -> Self {
        match e {
            MeshIoError::Io { .. } => Failure::new(
                code::INPUT,
                format!("cannot read the mesh: {e}; check the --mesh path"),
            ),
            MeshIoError::UnsupportedFormat { .. } => Failure::new(code::INPUT, e.to_string()),
            MeshIoError::Invalid { .. } => Failure::new(
                code::MESH,
                format!("{e}; repair the scan (meshinfo lists every defect)"),
            ),
            _ => Failure::new(
                code::MESH,
                format!("malformed mesh file: {e}; export the scan again as .obj, .ply or .stl"),
            ),
        }
    }

    /// Writing an output failed.
    pub fn output(what: &str, e: impl std::fmt::Display) -> Self {
        Failure::new(
            code::OUTPUT,
            format!("cannot write the {what}: {e}; check the folder exists and is writable"),
        )
    }

    /// The simulation library refused the inputs or failed.
    pub fn from_implant(e: &ImplantError) -> Self {
        use ImplantError as E;
        let (code, hint) = match e {
            E::Cancelled { .. } => (code::INTERRUPTED, ""),
            E::PointOffSurface { .. } => (
                code::PLACEMENT,
                " (distances in cm); give an --at on the skin (in the mesh's unit) or a --vertex",
            ),
            E::EmptyRegion { .. } => (code::PLACEMENT, " (set with --radius)"),
            E::RegionCoversSurface { .. } => (
                code::PLACEMENT,
                " (set with --radius, default 1.5 × the implant's footprint radius); the mesh is \
                 too small for this region: use a smaller --radius or implant, or a larger scan",
            ),
            E::FootprintOutsideRegion { .. } => (
                code::PLACEMENT,
                "; use a larger --radius or a smaller implant, away from the scan's edge",
            ),
            E::ClosedRegion { .. } => (code::PLACEMENT, ""),
            E::RimAtBorder { .. } => (code::PLACEMENT, " (--radius; --at, --vertex)"),
            E::RegionReachesBorder { .. } => (
                code::PLACEMENT,
                " (coordinates in cm; --at takes the mesh's unit; --max-hole sets the holes filled)",
            ),
            E::Remesh(_) => (
                code::MESH,
                "; check the scan with meshinfo, or give another --sim-edge",
            ),
            E::InvalidParameter { name, .. } => match *name {
                "point" | "radius" | "region_radius" | "max_distance" | "region" => {
                    (code::PLACEMENT, "")
                }
                "depth" => (code::PARAMETERS, " (--depth)"),
                "young" => (code::PARAMETERS, " (--young, here in g/(cm·s²) = 0.1 Pa)"),
                "poisson" => (code::PARAMETERS, " (--poisson)"),
                "skin_thickness" => (code::PARAMETERS, " (--thickness)"),
                "density" => (code::PARAMETERS, " (--density)"),
                "time_step" => (code::PARAMETERS, " (--time-step)"),
                "sim_edge" => (code::PARAMETERS, " (--sim-edge)"),
                "max_hole" => (code::PARAMETERS, " (--max-hole)"),
                _ => (code::PARAMETERS, ""),
            },
            E::ShapeNotMeshable { .. }
            | E::VolumeOutOfRange { .. }
            | E::VolumeNotReached { .. }
            | E::SurfaceHeight { .. } => {
                (code::PARAMETERS, "; change --volume or the implant's size")
            }
            E::TargetNotBracketed { .. } => (code::PARAMETERS, " (--bracket LOW,HIGH)"),
            E::Model(tissue_mss::MssError::InvalidSpring { .. }) => (
                code::PLACEMENT,
                "; the skin or the implant's base bent onto it has badly shaped (obtuse) \
                 triangles at this point: pick another point (--at, --vertex), a smaller or \
                 larger implant, or remesh the scan",
            ),
            E::Diverged { .. } => (code::RUN, " (leave --time-step automatic, or lower it)"),
            E::RanAway { .. } => (code::RUN, ""),
            _ => (
                code::RUN,
                "; check the scan (meshinfo) and the parameters, or report this",
            ),
        };
        let message = match code {
            code::RUN => format!("the run failed: {e}{hint}"),
            _ => format!("{e}{hint}"),
        };
        Failure::new(code, message)
    }

    /// The worker did not give a result.
    pub fn from_app(e: &AppError) -> Self {
        match e {
            AppError::Implant(inner) => Failure::from_implant(inner),
            AppError::Cancelled { steps } => Failure::interrupted(*steps),
            _ => Failure::new(
                code::RUN,
                format!("the run failed: {e}; check the scan and the parameters, or report this"),
            ),
        }
    }

    /// Ctrl-C.
    pub fn interrupted(steps: u64) -> Self {
        Failure::new(
            code::INTERRUPTED,
            format!("interrupted after {steps} steps; nothing was written"),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_are_one_line_and_codes_follow_the_table() {
        let e = ImplantError::RegionCoversSurface {
            radius: 9.0,
            triangles: 10,
            farthest: 3.0,
        };
        let f = Failure::from_implant(&e);
        assert_eq!(f.code, code::PLACEMENT);
        assert!(!f.line().contains('\n'));
        assert!(f.line().contains("--radius"));
        let d = ImplantError::Diverged {
            step: 3,
            particle: 1,
            what: "position",
        };
        assert_eq!(Failure::from_implant(&d).code, code::RUN);
        let v = ImplantError::InvalidParameter {
            name: "volume_cm3",
            value: -1.0,
            expected: "positive".into(),
        };
        assert_eq!(Failure::from_implant(&v).code, code::PARAMETERS);
    }
}
