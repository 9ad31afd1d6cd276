//! The one error type of the crate.

use tissue_bvh::BvhError;
use tissue_mesh::MeshError;

/// Why a surface could not be remeshed or its holes filled. Every variant says which value was
/// wrong and how to fix it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RemeshError {
    /// [`crate::RemeshOptions::target_edge`] is not a finite positive length.
    #[error(
        "target edge length {value}: must be finite and > 0, in the mesh's units \
         (e.g. 0.3 for 3 mm on a mesh in cm)"
    )]
    InvalidTargetEdge {
        /// The value given.
        value: f64,
    },
    /// [`crate::RemeshOptions::smoothing_radius`] is `Some` but not a finite positive length.
    #[error(
        "smoothing radius {value}: must be finite and > 0, in the mesh's units \
         (about the target edge length), or None for no smoothing"
    )]
    InvalidSmoothingRadius {
        /// The value given.
        value: f64,
    },
    /// The `max_diameter` of [`crate::fill_holes`] is negative or not finite.
    #[error(
        "maximum hole diameter {value}: must be finite and >= 0, in the mesh's units \
         (0 fills nothing)"
    )]
    InvalidMaxDiameter {
        /// The value given.
        value: f64,
    },
    /// The target edge is so short for this surface that the result would be enormous.
    #[error(
        "target edge {target_edge} on a surface of area {area:.4} would make about {estimated} \
         triangles, more than the {max} allowed: use a target edge of at least {min_edge:.4} \
         (or check the mesh's unit)"
    )]
    TooManyTriangles {
        /// The target edge asked for.
        target_edge: f64,
        /// Area of the input surface.
        area: f64,
        /// Estimated triangle count of the result.
        estimated: u64,
        /// The largest triangle count allowed.
        max: u64,
        /// The shortest target edge that stays within `max`.
        min_edge: f64,
    },
    /// The input surface is too large for the search hierarchy.
    #[error(
        "the surface cannot be indexed for projection ({source}): split it into smaller regions"
    )]
    Hierarchy {
        /// What the hierarchy reported.
        #[source]
        source: BvhError,
    },
    /// The result failed the mesh checks. This is a bug of tissue-remesh, not of the input.
    #[error(
        "the remeshed surface failed validation ({source}): this is a bug in tissue-remesh; \
         please report it with the input mesh and the options used"
    )]
    InvalidResult {
        /// The check that failed.
        #[source]
        source: MeshError,
    },
}
