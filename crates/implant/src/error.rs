//! The one error type of the crate.

/// What can go wrong setting up or running an implant scenario.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ImplantError {
    /// A parameter is out of range.
    #[error("invalid parameter {name} = {value}: {expected}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range, and how to fix it.
        expected: String,
    },
    /// The patient surface, region or implant mesh is not usable.
    #[error("mesh: {0}")]
    Mesh(#[from] tissue_mesh::MeshError),
    /// The region given for the tissue model is a closed surface: it needs a boundary to hold.
    #[error("the region is a closed surface ({triangles} triangles); select an open patch of the patient surface")]
    ClosedRegion {
        /// Its triangle count.
        triangles: usize,
    },
    /// The mass–spring model refused its input or diverged.
    #[error("tissue model: {0}")]
    Model(#[from] tissue_mss::MssError),
}
