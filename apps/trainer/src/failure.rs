//! Why the program stops: a one-line message and its exit code.

use tissue_meshio::MeshIoError;
use tissue_pbd::PbdError;

/// The documented exit codes (see `trainer --help`).
pub mod code {
    /// Usage: clap's code for a bad command line.
    pub const USAGE: u8 = 2;
    /// The organ file is missing, unreadable or of an unsupported type.
    pub const INPUT: u8 = 3;
    /// The organ mesh is malformed or invalid.
    pub const MESH: u8 = 4;
    /// The surface (`--surface`) cannot be tetrahedralised.
    pub const MESHING: u8 = 5;
    /// A parameter is out of range.
    pub const PARAMETERS: u8 = 6;
    /// The simulation diverged.
    pub const RUN: u8 = 7;
    /// An output could not be written.
    pub const OUTPUT: u8 = 8;
}

/// A reason to stop with a non-zero exit code.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// The exit code.
    pub code: u8,
    /// What went wrong and what to change.
    pub message: String,
}

impl Failure {
    /// A failure with `code` and `message`.
    pub fn new(code: u8, message: impl Into<String>) -> Self {
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
                code::INPUT,
                format!("cannot read the organ: {e}; check the --organ path"),
            ),
            MeshIoError::UnsupportedFormat { .. } => Failure::new(
                code::INPUT,
                format!("{e} (for --organ; a surface goes to --surface)"),
            ),
            MeshIoError::WrongKind { .. } => Failure::new(
                code::INPUT,
                format!("{e}; --organ takes a tetrahedral mesh: .vtu, .msh (Gmsh), .vtk or TetGen .node/.ele (a surface goes to --surface)"),
            ),
            _ => Failure::new(
                code::MESH,
                format!("the organ mesh is not usable: {e}; check it with meshinfo"),
            ),
        }
    }

    /// The physics library refused a parameter or failed.
    pub fn from_pbd(e: &PbdError) -> Self {
        match e {
            PbdError::Diverged { .. } => Failure::new(
                code::RUN,
                format!("{e} (lower --dt or --stiffness, or raise --iterations)"),
            ),
            PbdError::DegenerateTet { .. } | PbdError::NodeOutOfRange { .. } => {
                Failure::new(code::MESH, format!("the organ mesh is not usable: {e}"))
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
                Failure::new(code::PARAMETERS, format!("{e}{flag}"))
            }
            PbdError::InvalidTool { .. } => {
                Failure::new(code::PARAMETERS, format!("{e} (--tool-radius)"))
            }
            PbdError::ColliderTooLarge { .. } => {
                Failure::new(code::PARAMETERS, format!("{e} (--cell)"))
            }
            _ => Failure::new(code::RUN, format!("the run failed: {e}")),
        }
    }

    /// Writing an output failed.
    pub fn output(what: &str, e: impl std::fmt::Display) -> Self {
        Failure::new(
            code::OUTPUT,
            format!("cannot write the {what}: {e}; check the folder is writable"),
        )
    }
}
