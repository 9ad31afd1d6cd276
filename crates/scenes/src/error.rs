//! Why an organ or a session could not be made, or a tool action failed.

use tissue_meshio::MeshIoError;

/// A scene error: what went wrong and what to do.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The file could not be read or parsed (the loader's message names the line or element).
    #[error("{0}")]
    Read(MeshIoError),
    /// The mesh is not valid.
    #[error("{name}: not a valid mesh: {reason}")]
    Mesh {
        /// The file or organ.
        name: String,
        /// The defect.
        reason: String,
    },
    /// A surface that cannot be filled with tetrahedra.
    #[error(
        "{name} cannot be filled with tetrahedra: {reason}; an organ surface must be closed \
             and manifold, with normals out of it"
    )]
    Meshing {
        /// The file.
        name: String,
        /// The mesher's reason.
        reason: String,
    },
    /// Too many tetrahedra for real time.
    #[error(
        "{name} has {tets} tetrahedra, more than the {} a real-time session takes: \
             decimate the surface or coarsen the tet mesh",
        crate::MAX_TETS
    )]
    TooLarge {
        /// The file.
        name: String,
        /// Its tetrahedra.
        tets: usize,
    },
    /// An organ size that is not a positive length.
    #[error("an organ size of {size} cm: give a positive length in cm")]
    Size {
        /// The size asked for (cm).
        size: f32,
    },
    /// The solver refused a parameter or diverged.
    #[error("the simulation: {0}")]
    Pbd(#[from] tissue_pbd::PbdError),
    /// Cutting or suturing failed.
    #[error("surgery: {0}")]
    Surgery(#[from] tissue_surgery::SurgeryError),
    /// A tool action that cannot be done (a grab off the surface, a cut path of one point, …).
    #[error("{0}")]
    Tool(String),
}

impl SceneError {
    pub(crate) fn mesh(name: &str, e: impl std::fmt::Display) -> SceneError {
        SceneError::Mesh {
            name: name.to_owned(),
            reason: e.to_string(),
        }
    }
}
