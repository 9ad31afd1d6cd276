//! The one error type of the crate.

/// What can go wrong cutting or suturing. Every variant names the element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SurgeryError {
    /// The soft body refused an edit (a bug in this crate if it happens) or a step.
    #[error("soft body: {0}")]
    Body(#[from] tissue_pbd::PbdError),
    /// The body given is not the one this state was made for: another body (its
    /// [`tissue_pbd::SoftBody::id`] differs, even at the same size), or its nodes or tets changed
    /// behind this state's back.
    #[error("the body given is not the one this surgery state was made with ({what} {got}, expected {expected}): pass the body the state was made with")]
    BodyMismatch {
        /// `"body id"` ([`tissue_pbd::BodyId::get`]), `"nodes"` or `"tets"`.
        what: &'static str,
        /// The body's id or count.
        got: usize,
        /// The id or count this state expects.
        expected: usize,
    },
    /// A tool is of the wrong kind or a pose is not finite.
    #[error("tool: {reason}")]
    InvalidTool {
        /// What is wrong and how to fix it.
        reason: &'static str,
    },
    /// A setting is out of range.
    #[error("invalid setting {name} = {value}: expected {expected}")]
    InvalidSetting {
        /// Setting name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range.
        expected: &'static str,
    },
    /// No suture has this id (or it was removed).
    #[error("suture {id} does not exist or was removed")]
    NoSuchSuture {
        /// The id given.
        id: usize,
    },
    /// [`crate::Surgery::validate`] found a defect.
    #[error("surface defect at {element} {index}: {what}")]
    Defect {
        /// `"edge"`, `"vertex"`, `"tet"`, `"node"`.
        element: &'static str,
        /// Its index (for an edge, its first node).
        index: usize,
        /// What is wrong.
        what: &'static str,
    },
}
