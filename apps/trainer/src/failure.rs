//! Why the program stops: tissue-cli's [`Failure`] (a one-line message and its exit code), and
//! the trainer's mappings of its libraries' errors to it: a scene error's kind to the exit-code
//! table ([`exit_of`]), the solver's parameters to the flags that set them ([`flag_of`]).

use tissue_meshio::MeshIoError;
use tissue_pbd::{PbdError, PbdParam};
use tissue_scenes::{SceneError, SceneErrorKind};

/// The exit codes (the table every tissue binary shares, see `trainer --help`) and the failure
/// the program stops with.
pub use tissue_cli::{Exit, Failure};

/// The exit code of a scene error's kind: the one place the trainer maps them.
pub fn exit_of(kind: SceneErrorKind) -> Exit {
    match kind {
        SceneErrorKind::Input => Exit::Input,
        SceneErrorKind::Mesh | SceneErrorKind::TooLarge => Exit::Mesh,
        SceneErrorKind::Meshing => Exit::Meshing,
        SceneErrorKind::Parameters | SceneErrorKind::Tool => Exit::Parameters,
        SceneErrorKind::Simulation => Exit::Run,
    }
}

/// The flag that sets a solver parameter, if the trainer has one.
pub fn flag_of(param: PbdParam) -> Option<&'static str> {
    use PbdParam as P;
    match param {
        P::Dt => Some("--dt"),
        P::Substeps => Some("--substeps"),
        P::Iterations => Some("--iterations"),
        P::DistanceStiffness => Some("--stiffness"),
        P::DistanceCompliance => Some("--compliance"),
        P::CellSize => Some("--cell"),
        P::StaticFriction | P::KineticFriction => Some("--friction"),
        P::Density => Some("--density"),
        P::YoungModulus => Some("--young-kpa"),
        P::PoissonRatio => Some("--poisson"),
        P::Solver => Some("--solver"),
        P::OverRelaxation => Some("--over-relaxation"),
        P::VolumeStiffness
        | P::VolumeCompliance
        | P::GravityX
        | P::GravityY
        | P::GravityZ
        | P::Damping
        | P::LinearDamping
        | P::Margin
        | P::Detection
        | P::ContactReach
        | P::ColliderReach
        | P::Shapes
        | P::FloorAxis
        | P::FloorHeight
        | P::NodeTetCount
        | P::NodeCount
        | P::TetCount
        | P::Mass
        | P::ConstraintNodes
        | P::RestVolume
        | P::RestLength
        | P::Stiffness
        | P::Compliance => None,
    }
}

/// Reading the organ failed.
pub fn from_mesh_io(e: &MeshIoError) -> Failure {
    let code = exit_of(SceneErrorKind::of_mesh_io(e));
    let message = match e {
        MeshIoError::Io { .. } => format!("cannot read the organ: {e}; check the --organ path"),
        MeshIoError::UnsupportedFormat { .. } => {
            format!("{e} (for --organ; a surface goes to --surface)")
        }
        MeshIoError::WrongKind { .. } => format!(
            "{e}; --organ takes a tetrahedral mesh: .vtu, .msh (Gmsh), .vtk or TetGen \
             .node/.ele (a surface goes to --surface)"
        ),
        _ => format!("the organ mesh is not usable: {e}; check it with meshinfo"),
    };
    Failure::new(code, message)
}

/// The physics library refused a parameter or failed.
pub fn from_pbd(e: &PbdError) -> Failure {
    let code = exit_of(SceneErrorKind::of_pbd(e));
    let message = match e {
        PbdError::Diverged { .. } => {
            format!("{e} (lower --dt or --stiffness, or raise --iterations)")
        }
        PbdError::DegenerateTet { .. } | PbdError::NodeOutOfRange { .. } => {
            format!("the organ mesh is not usable: {e}")
        }
        PbdError::InvalidParameter { param, .. } => match flag_of(*param) {
            Some(flag) => format!("{e} ({flag})"),
            None => e.to_string(),
        },
        PbdError::InvalidTool { .. } => format!("{e} (--tool-radius)"),
        PbdError::ColliderTooLarge { .. } => format!("{e} (--cell)"),
        _ if code == Exit::Run => format!("the run failed: {e}"),
        _ => e.to_string(),
    };
    Failure::new(code, message)
}

/// A scene error (tissue-scenes): its loader and solver errors as [`from_mesh_io`] and
/// [`from_pbd`] say them, the others by their kind ([`exit_of`]).
pub fn from_scene(e: &SceneError) -> Failure {
    match e {
        SceneError::Read(io) => from_mesh_io(io),
        SceneError::Pbd(pbd) => from_pbd(pbd),
        SceneError::Size { .. } => Failure::new(exit_of(e.kind()), format!("{e} (--size)")),
        _ => Failure::new(exit_of(e.kind()), e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solver_parameters_are_named_by_their_flags() {
        let e = PbdError::InvalidParameter {
            param: PbdParam::StaticFriction,
            value: -1.0,
            expected: "finite and ≥ 0",
        };
        let f = from_pbd(&e);
        assert_eq!(f.code, Exit::Parameters);
        assert!(f.line().ends_with("(--friction)"), "{}", f.line());
        let e = PbdError::InvalidParameter {
            param: PbdParam::Damping,
            value: 2.0,
            expected: "in [0, 1]",
        };
        assert_eq!(from_pbd(&e).line(), e.to_string(), "no flag sets damping");
        let diverged = from_pbd(&PbdError::Diverged { step: 3, node: 7 });
        assert_eq!(diverged.code, Exit::Run);
    }

    #[test]
    fn scene_errors_go_by_their_kind() {
        let tool = from_scene(&SceneError::Tool("a drag path needs two waypoints".into()));
        assert_eq!(tool.code, Exit::Parameters);
        let size = from_scene(&SceneError::Size { size: -1.0 });
        assert_eq!(size.code, Exit::Parameters);
        assert!(size.line().ends_with("(--size)"));
        let meshing = SceneError::Meshing {
            name: "open.obj".into(),
            reason: "edge [0, 1] has one triangle".into(),
        };
        assert_eq!(from_scene(&meshing).code, Exit::Meshing);
    }
}
