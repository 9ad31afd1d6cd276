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
    /// Too many tetrahedra for real time ([`crate::MAX_TETS`]).
    #[error("{}", too_large(name, *tets, *estimated, *decimate_to))]
    TooLarge {
        /// The file.
        name: String,
        /// Its tetrahedra, or those a surface would fill with.
        tets: usize,
        /// Whether `tets` is the estimate made before meshing a surface (it was refused without
        /// being meshed).
        estimated: bool,
        /// About how many triangles the surface, decimated evenly, may have to stay within
        /// [`crate::MAX_TETS`] (`None` for a tet mesh).
        decimate_to: Option<usize>,
    },
    /// An organ size that is not a positive length.
    #[error("an organ size of {size} cm: give a positive length in cm")]
    Size {
        /// The size asked for (cm).
        size: f32,
    },
    /// A damping relaxation time that is not a positive number of seconds.
    #[error(
        "a relaxation time of {seconds} s: give a positive time in seconds (0.1 s damps an \
         organ's wobble in a few tenths of a second)"
    )]
    RelaxationTime {
        /// The time given (s).
        seconds: f32,
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
    /// The finite-element reference refused its input or could not factor its matrix.
    #[error("the finite-element reference: {0}")]
    Reference(#[from] tissue_fem::FemError),
}

fn too_large(name: &str, tets: usize, estimated: bool, decimate_to: Option<usize>) -> String {
    let max = crate::MAX_TETS;
    let fix = match decimate_to {
        Some(n) => format!("decimate the surface to about {n} triangles"),
        None => "decimate the surface or coarsen the tet mesh".to_owned(),
    };
    if estimated {
        format!(
            "{name} would fill with about {tets} tetrahedra (estimated before meshing), more than \
             the {max} a real-time session takes: {fix}"
        )
    } else {
        format!(
            "{name} has {tets} tetrahedra, more than the {max} a real-time session takes: {fix}"
        )
    }
}

impl SceneError {
    /// The material field this error refuses ([`crate::SessionOptions::material`]): `E`, `ν`,
    /// `ρ` out of range, or the relaxation time; `None` for any other error.
    pub fn material_field(&self) -> Option<crate::MaterialField> {
        self.material_refusal().map(|(field, _)| field)
    }

    /// The material field this error refuses and what the field expects (`"in [0, 0.495]"`,
    /// …), for a front end that words the refusal itself.
    pub fn material_refusal(&self) -> Option<(crate::MaterialField, &'static str)> {
        match self {
            SceneError::RelaxationTime { .. } => Some((
                crate::MaterialField::RelaxationTime,
                "a positive time in seconds",
            )),
            SceneError::Pbd(tissue_pbd::PbdError::InvalidParameter {
                param, expected, ..
            }) => crate::MaterialField::of_param(*param).map(|f| (f, *expected)),
            _ => None,
        }
    }
}

/// What kind of failure a [`SceneError`] is ([`SceneError::kind`]): the classes a front end
/// maps to its own codes (the `trainer`'s exit codes, the C ABI's statuses, the studio's error
/// kinds) in one `match`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SceneErrorKind {
    /// A file that cannot be read, or is not of a kind the loader takes.
    Input,
    /// A mesh that is malformed or not valid (a degenerate tet, a node out of range).
    Mesh,
    /// A surface that cannot be filled with tetrahedra (open, non-manifold, inside out).
    Meshing,
    /// An organ too large for real time ([`crate::MAX_TETS`]).
    TooLarge,
    /// A size, material, step or contact parameter out of range.
    Parameters,
    /// A tool action that cannot be done (a grab off the surface, a cut too short, a
    /// demonstration playing).
    Tool,
    /// The simulation diverged, or a cut or suture failed.
    Simulation,
}

impl SceneErrorKind {
    /// The kind of a loader's error ([`SceneError::Read`]): a file that cannot be read or is of
    /// the wrong type is input, anything else a bad mesh.
    pub fn of_mesh_io(e: &MeshIoError) -> SceneErrorKind {
        match e {
            MeshIoError::Io { .. }
            | MeshIoError::UnsupportedFormat { .. }
            | MeshIoError::WrongKind { .. } => SceneErrorKind::Input,
            _ => SceneErrorKind::Mesh,
        }
    }

    /// The kind of a solver's error ([`SceneError::Pbd`]): a bad tet is a mesh error, a
    /// parameter, tool or collider out of range a parameter error, anything else (a divergence)
    /// a simulation error.
    pub fn of_pbd(e: &tissue_pbd::PbdError) -> SceneErrorKind {
        use tissue_pbd::PbdError as E;
        match e {
            E::DegenerateTet { .. } | E::NodeOutOfRange { .. } => SceneErrorKind::Mesh,
            E::InvalidParameter { .. }
            | E::InvalidTool { .. }
            | E::InvalidColliderShape { .. }
            | E::ColliderMeshNotClosed { .. }
            | E::ColliderTooLarge { .. } => SceneErrorKind::Parameters,
            _ => SceneErrorKind::Simulation,
        }
    }
}

impl SceneError {
    /// What kind of failure this is.
    pub fn kind(&self) -> SceneErrorKind {
        match self {
            SceneError::Read(e) => SceneErrorKind::of_mesh_io(e),
            SceneError::Mesh { .. } => SceneErrorKind::Mesh,
            SceneError::Meshing { .. } => SceneErrorKind::Meshing,
            SceneError::TooLarge { .. } => SceneErrorKind::TooLarge,
            SceneError::Size { .. } | SceneError::RelaxationTime { .. } => {
                SceneErrorKind::Parameters
            }
            SceneError::Pbd(e) => SceneErrorKind::of_pbd(e),
            SceneError::Surgery(_) => SceneErrorKind::Simulation,
            SceneError::Tool(_) => SceneErrorKind::Tool,
            SceneError::Reference(e) => match e {
                tissue_fem::FemError::Material { .. } | tissue_fem::FemError::Problem { .. } => {
                    SceneErrorKind::Parameters
                }
                tissue_fem::FemError::DegenerateTet { .. } => SceneErrorKind::Mesh,
                tissue_fem::FemError::Factorisation { .. } => SceneErrorKind::Simulation,
            },
        }
    }

    pub(crate) fn mesh(name: &str, e: impl std::fmt::Display) -> SceneError {
        SceneError::Mesh {
            name: name.to_owned(),
            reason: e.to_string(),
        }
    }
}
