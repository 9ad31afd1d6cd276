//! Why the program stops: a one-line message and its exit code.

use tissue_meshio::MeshIoError;
use tissue_pbd::PbdError;

/// The exit codes: the table every tissue binary shares (see `trainer --help`).
pub use tissue_cli::Exit;

/// A reason to stop with a non-zero exit code.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// The exit code.
    pub code: Exit,
    /// What went wrong and what to change.
    pub message: String,
}

impl Failure {
    /// A failure with `code` and `message`.
    pub fn new(code: Exit, message: impl Into<String>) -> Self {
        Self {
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

    /// Reading the organ failed.
    pub fn from_mesh_io(e: &MeshIoError) -> Self {
        match e {
            MeshIoError::Io { .. } => Failure::new(
                Exit::Input,
                format!("cannot read the organ: {e}; check the --organ path"),
            ),
            MeshIoError::UnsupportedFormat { .. } => Failure::new(
                Exit::Input,
                format!("{e} (for --organ; a surface goes to --surface)"),
            ),
            MeshIoError::WrongKind { .. } => Failure::new(
                Exit::Input,
                format!("{e}; --organ takes a tetrahedral mesh: .vtu, .msh (Gmsh), .vtk or TetGen .node/.ele (a surface goes to --surface)"),
            ),
            _ => Failure::new(
                Exit::Mesh,
                format!("the organ mesh is not usable: {e}; check it with meshinfo"),
            ),
        }
    }

    /// The physics library refused a parameter or failed.
    pub fn from_pbd(e: &PbdError) -> Self {
        match e {
            PbdError::Diverged { .. } => Failure::new(
                Exit::Run,
                format!("{e} (lower --dt or --stiffness, or raise --iterations)"),
            ),
            PbdError::DegenerateTet { .. } | PbdError::NodeOutOfRange { .. } => {
                Failure::new(Exit::Mesh, format!("the organ mesh is not usable: {e}"))
            }
            PbdError::InvalidParameter { name, .. } => {
                let flag = match *name {
                    "dt" => " (--dt)",
                    "iterations" => " (--iterations)",
                    "distance_stiffness" => " (--stiffness)",
                    "cell_size" => " (--cell)",
                    "static_friction" | "kinetic_friction" => " (--friction)",
                    _ => "",
                };
                Failure::new(Exit::Parameters, format!("{e}{flag}"))
            }
            PbdError::InvalidTool { .. } => {
                Failure::new(Exit::Parameters, format!("{e} (--tool-radius)"))
            }
            PbdError::ColliderTooLarge { .. } => {
                Failure::new(Exit::Parameters, format!("{e} (--cell)"))
            }
            _ => Failure::new(Exit::Run, format!("the run failed: {e}")),
        }
    }

    /// A scene error (tissue-scenes): its mesh, meshing, solver and script failures mapped to
    /// the table's codes.
    pub fn from_scene(e: &tissue_scenes::SceneError) -> Self {
        use tissue_scenes::SceneError;
        match e {
            SceneError::Read(e) => Failure::from_mesh_io(e),
            SceneError::Pbd(e) => Failure::from_pbd(e),
            SceneError::Meshing { .. } => Failure::new(Exit::Meshing, e.to_string()),
            SceneError::Mesh { .. } | SceneError::TooLarge { .. } => {
                Failure::new(Exit::Mesh, e.to_string())
            }
            SceneError::Size { .. } => Failure::new(Exit::Parameters, format!("{e} (--size)")),
            SceneError::Tool(_) => Failure::new(Exit::Parameters, e.to_string()),
            _ => Failure::new(Exit::Run, e.to_string()),
        }
    }

    /// Writing an output failed.
    pub fn output(what: &str, e: impl std::fmt::Display) -> Self {
        Failure::new(
            Exit::Output,
            format!("cannot write the {what}: {e}; check the folder is writable"),
        )
    }
}
