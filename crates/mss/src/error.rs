//! The one error type of the crate.

/// What can go wrong building or running a mass–spring system. Every variant names the element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MssError {
    /// Positions and masses (or another per-particle array) differ in length.
    #[error("{what} has {got} entries but the system has {expected} particles")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The particle count.
        expected: usize,
    },
    /// A particle's position, velocity or mass is not usable.
    #[error("particle {particle}: {what}")]
    InvalidParticle {
        /// Particle index.
        particle: u32,
        /// What is wrong, e.g. "mass -1 must be positive and finite".
        what: String,
    },
    /// A spring refers to a particle that does not exist, joins a particle to itself, or has a
    /// negative or non-finite rest length or stiffness.
    #[error("spring {spring} ({a}–{b}): {what}")]
    InvalidSpring {
        /// Spring index as given.
        spring: usize,
        /// First particle.
        a: u32,
        /// Second particle.
        b: u32,
        /// What is wrong.
        what: String,
    },
    /// An anchor (zero-length spring to a fixed point) is not usable.
    #[error("anchor {anchor} on particle {particle}: {what}")]
    InvalidAnchor {
        /// Anchor index as given.
        anchor: usize,
        /// Its particle.
        particle: u32,
        /// What is wrong.
        what: String,
    },
    /// A material or run parameter is out of range.
    #[error("invalid parameter {name} = {value}: {expected}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range.
        expected: &'static str,
    },
    /// The mesh given for masses, springs or volume preservation is not usable for it.
    #[error("mesh: {0}")]
    Mesh(#[from] tissue_mesh::MeshError),
    /// A quasi-static solve's stiffness matrix has no Cholesky factor.
    #[error("the stiffness matrix is not positive definite ({what}); fix some particle or anchor every free one")]
    NotPositiveDefinite {
        /// What the factorisation found.
        what: String,
    },
    /// A non-finite position or velocity appeared: the step is too large for the stiffness, or the
    /// input forces are not finite. The particle keeps its last finite state.
    #[error("diverged at step {step}: particle {particle} became non-finite; reduce the time step or the stiffness")]
    Diverged {
        /// Step number (0-based, counted since the system was built).
        step: u64,
        /// The first particle found non-finite.
        particle: u32,
    },
    /// The adaptive step had to shrink below its minimum and was still unstable.
    #[error("step {step}: unstable even at the minimum time step {h_min} s")]
    StepTooSmall {
        /// Step number.
        step: u64,
        /// The minimum step.
        h_min: f32,
    },
}
