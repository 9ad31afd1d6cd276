//! The one error type of the crate.

use tissue_bvh::BvhError;

use crate::Side;

/// Why a collision phase could not run. Each variant names the surface ([`Side`]) and the element
/// (particle, triangle) at fault, counted from 0 as the caller stores them.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CollideError {
    /// Building or refitting a surface's hierarchy failed (e.g. a non-finite position).
    #[error("surface {side:?}: {source}")]
    Bvh {
        /// The surface whose hierarchy failed.
        side: Side,
        /// What the hierarchy reported.
        source: BvhError,
    },
    /// A parameter is out of its range.
    #[error("{name} = {value}: must be {expected}")]
    InvalidParameter {
        /// The parameter's name as in the API.
        name: &'static str,
        /// The value given.
        value: f32,
        /// The accepted range, in words.
        expected: &'static str,
    },
    /// A per-particle array does not match the surface's vertex count.
    #[error("surface {side:?}: {what} has {got} entries for {expected} particles")]
    ParticleCount {
        /// The surface.
        side: Side,
        /// Which array (`"positions"`, `"velocities"`, `"inverse masses"`).
        what: &'static str,
        /// The surface's vertex count.
        expected: usize,
        /// The array's length.
        got: usize,
    },
    /// A contact refers to a particle the given arrays do not have (contacts from another pair
    /// of surfaces).
    #[error("surface {side:?}: contact refers to particle {particle}, but there are only {count}")]
    ParticleOutOfRange {
        /// The surface.
        side: Side,
        /// The particle index.
        particle: u32,
        /// Number of particles given.
        count: usize,
    },
    /// An inverse mass is negative or not finite (0 marks a fixed particle).
    #[error("surface {side:?}: particle {particle} has inverse mass {value}; use 0 for a fixed particle, a positive value otherwise")]
    InvalidInverseMass {
        /// The surface.
        side: Side,
        /// The particle index.
        particle: u32,
        /// The stored value.
        value: f32,
    },
    /// A particle position is NaN or infinite (a diverged simulation).
    #[error("surface {side:?}: particle {particle} has a non-finite position {position:?}")]
    NonFinitePosition {
        /// The surface.
        side: Side,
        /// The particle index.
        particle: u32,
        /// Its stored position.
        position: [f32; 3],
    },
    /// A surface view was passed in the other side's place.
    #[error("expected the view of surface {expected:?} here, got surface {got:?}: pass A's view first, B's second")]
    WrongSide {
        /// The side this argument is for.
        expected: Side,
        /// The side the view was made for.
        got: Side,
    },
    /// A hierarchy or voxel grid was built over a different surface than the one given with it.
    #[error("surface {side:?}: the {what} covers {got} triangles but the surface has {expected}")]
    TriangleCount {
        /// The surface.
        side: Side,
        /// `"hierarchy"` or `"voxel grid"`.
        what: &'static str,
        /// The surface's triangle count.
        expected: usize,
        /// The structure's triangle count.
        got: usize,
    },
    /// The voxel grid would have too many cells for the mesh's extent.
    #[error("a voxel grid of cell size {cell_size} over a box of size {extent:?} needs {cells} cells (at most {max}): choose a larger cell size")]
    TooManyCells {
        /// The cell size given.
        cell_size: f32,
        /// The mesh's bounding-box size.
        extent: [f32; 3],
        /// Cells needed.
        cells: u64,
        /// The limit.
        max: u64,
    },
}
