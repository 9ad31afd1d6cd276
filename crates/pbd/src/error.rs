//! The one error type of the crate.

/// What can go wrong building or stepping a soft body. Every variant names the element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PbdError {
    /// A material or step parameter is out of range.
    #[error("invalid parameter {} = {value}: expected {expected}", param.name())]
    InvalidParameter {
        /// Which parameter (its [`PbdParam::name`] is the field's name, e.g.
        /// `distance_stiffness` or `dt`).
        param: PbdParam,
        /// The value given.
        value: f64,
        /// The accepted range.
        expected: &'static str,
    },
    /// An element (tetrahedron, pin, attachment) refers to a node that does not exist.
    #[error("{element} {index} refers to node {node}, but the body has {count} nodes")]
    NodeOutOfRange {
        /// What refers to the node: `"tet"`, `"pin"`, `"attachment"`.
        element: &'static str,
        /// Index of that element (for a pin or attachment, the node itself).
        index: usize,
        /// The node index given.
        node: u32,
        /// Number of nodes.
        count: usize,
    },
    /// A tetrahedron has (numerically) zero or negative volume, or repeats a node: it cannot carry
    /// mass or volume constraints. Fix or drop it in the mesh.
    #[error("tet {tet} is degenerate (signed volume {volume}); it must be positively oriented and not flat")]
    DegenerateTet {
        /// Tetrahedron index as given.
        tet: usize,
        /// Its signed volume `(b−a)×(c−a)·(d−a)/6`.
        volume: f64,
    },
    /// A node position or velocity given is not finite.
    #[error("node {node}: {what} is not finite")]
    NonFinite {
        /// Node index.
        node: u32,
        /// `"position"` or `"velocity"`.
        what: &'static str,
    },
    /// An array given has the wrong length.
    #[error("{what} has {got} entries but the body has {expected} nodes")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The node count.
        expected: usize,
    },
    /// No attachment has this id: it was never made on this body, or its node was freed.
    #[error("attachment {id} does not exist or its node was freed (the body has {count} live attachments)")]
    NoSuchAttachment {
        /// The id given.
        id: crate::AttachmentId,
        /// Number of live attachments.
        count: usize,
    },
    /// A node became non-finite during a step: the step or the stiffness is too large, or the
    /// input is not finite. Reduce `dt` or raise the compliance.
    #[error("diverged at step {step}: node {node} became non-finite; reduce dt or the stiffness")]
    Diverged {
        /// Step number (0-based, counted since the body was built).
        step: u64,
        /// The first node found non-finite.
        node: u32,
    },
    /// A collider shape cannot be voxelised: the message says which shape (its index in the list
    /// given to [`crate::VoxelCollider::new`]) and why.
    #[error("collider shape {shape}: {reason}")]
    InvalidColliderShape {
        /// Index of the shape in the list given.
        shape: usize,
        /// What is wrong and how to fix it.
        reason: &'static str,
    },
    /// A collider mesh is not closed, so inside and outside are undefined.
    #[error("collider shape {shape}: the mesh is not closed ({boundary_edges} boundary edges); a static collider needs a closed surface to tell inside from outside: close the holes, or use boxes")]
    ColliderMeshNotClosed {
        /// Index of the shape in the list given.
        shape: usize,
        /// Number of edges used by one triangle only.
        boundary_edges: usize,
    },
    /// The voxel grid would be too large.
    #[error("the collider's voxel grid would have {corners} corners (limit {limit}) at cell size {cell_size} cm; use a larger cell size")]
    ColliderTooLarge {
        /// Grid corners needed.
        corners: u64,
        /// The largest grid accepted.
        limit: u64,
        /// The cell size given (cm).
        cell_size: f32,
    },
    /// A tool primitive is degenerate or has a bad size.
    #[error("tool: {reason}")]
    InvalidTool {
        /// What is wrong and how to fix it.
        reason: &'static str,
    },
    /// No collider (`what = "collider"`) or tool (`what = "tool"`) has this id.
    #[error("{what} {id} does not exist (the body has {count})")]
    NoSuchContactSource {
        /// `"collider"` or `"tool"`.
        what: &'static str,
        /// The id given.
        id: usize,
        /// How many there are.
        count: usize,
    },
    /// A topology edit names a constraint or tet that does not exist or was removed.
    #[error("{what} {index} does not exist or was removed (the body has {count})")]
    NoSuchElement {
        /// `"distance constraint"` or `"tet"`.
        what: &'static str,
        /// The index given.
        index: usize,
        /// How many there are.
        count: usize,
    },
}

/// A parameter the crate checks ([`PbdError::InvalidParameter`]): a closed list (deliberately
/// not `#[non_exhaustive]`), so a front end maps each to its own flag or field in an exhaustive
/// `match`, and a new parameter is a compile error there until it is mapped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PbdParam {
    /// [`crate::Material::density`] (g/cm³).
    Density,
    /// [`crate::Material::distance_stiffness`].
    DistanceStiffness,
    /// [`crate::Material::volume_stiffness`].
    VolumeStiffness,
    /// [`crate::Material::distance_compliance`].
    DistanceCompliance,
    /// [`crate::Material::volume_compliance`].
    VolumeCompliance,
    /// [`crate::StepSettings::dt`] (s).
    Dt,
    /// [`crate::StepSettings::substeps`].
    Substeps,
    /// [`crate::StepSettings::iterations`].
    Iterations,
    /// [`crate::StepSettings::gravity`]'s x (cm/s²).
    GravityX,
    /// [`crate::StepSettings::gravity`]'s y (cm/s²).
    GravityY,
    /// [`crate::StepSettings::gravity`]'s z (cm/s²).
    GravityZ,
    /// [`crate::StepSettings::damping`].
    Damping,
    /// [`crate::StepSettings::linear_damping`].
    LinearDamping,
    /// [`crate::ContactParams::margin`] (cm).
    Margin,
    /// [`crate::ContactParams::detection`] (cm).
    Detection,
    /// [`crate::ContactParams::static_friction`].
    StaticFriction,
    /// [`crate::ContactParams::kinetic_friction`].
    KineticFriction,
    /// A contact's margin plus its detection distance, against a collider's reach (cm).
    ContactReach,
    /// A [`crate::VoxelCollider`]'s cell size (cm).
    CellSize,
    /// A [`crate::VoxelCollider`]'s reach (cm).
    ColliderReach,
    /// A [`crate::VoxelCollider`]'s shapes (at least one).
    Shapes,
    /// [`crate::Floor::axis`].
    FloorAxis,
    /// [`crate::Floor::height`] (cm).
    FloorHeight,
    /// A new body's node and tet counts.
    NodeTetCount,
    /// The nodes (solver slots) a body can hold.
    NodeCount,
    /// The tets a body can hold.
    TetCount,
    /// A node's mass (g).
    Mass,
    /// The nodes of a constraint or tet (distinct).
    ConstraintNodes,
    /// A tet's rest volume (cm³).
    RestVolume,
    /// A distance constraint's rest length (cm).
    RestLength,
    /// A distance constraint's stiffness.
    Stiffness,
    /// A distance constraint's compliance (cm/dyn).
    Compliance,
    /// [`crate::Elastic::young_kpa`] (kPa).
    YoungModulus,
    /// [`crate::Elastic::poisson`].
    PoissonRatio,
    /// [`crate::StepSettings::solver`] (0 = PBD, 1 = linearised PBD, 2 = XPBD).
    Solver,
    /// [`crate::StepSettings::over_relaxation`].
    OverRelaxation,
}

impl PbdParam {
    /// Every parameter, in declaration order.
    pub const ALL: [PbdParam; 36] = [
        PbdParam::Density,
        PbdParam::DistanceStiffness,
        PbdParam::VolumeStiffness,
        PbdParam::DistanceCompliance,
        PbdParam::VolumeCompliance,
        PbdParam::Dt,
        PbdParam::Substeps,
        PbdParam::Iterations,
        PbdParam::GravityX,
        PbdParam::GravityY,
        PbdParam::GravityZ,
        PbdParam::Damping,
        PbdParam::LinearDamping,
        PbdParam::Margin,
        PbdParam::Detection,
        PbdParam::StaticFriction,
        PbdParam::KineticFriction,
        PbdParam::ContactReach,
        PbdParam::CellSize,
        PbdParam::ColliderReach,
        PbdParam::Shapes,
        PbdParam::FloorAxis,
        PbdParam::FloorHeight,
        PbdParam::NodeTetCount,
        PbdParam::NodeCount,
        PbdParam::TetCount,
        PbdParam::Mass,
        PbdParam::ConstraintNodes,
        PbdParam::RestVolume,
        PbdParam::RestLength,
        PbdParam::Stiffness,
        PbdParam::Compliance,
        PbdParam::YoungModulus,
        PbdParam::PoissonRatio,
        PbdParam::Solver,
        PbdParam::OverRelaxation,
    ];

    /// The parameter's name as the messages give it: the field's name (`distance_stiffness`,
    /// `dt`, `gravity.y`, …) or what is counted (`node count`).
    pub fn name(self) -> &'static str {
        match self {
            PbdParam::Density => "density",
            PbdParam::DistanceStiffness => "distance_stiffness",
            PbdParam::VolumeStiffness => "volume_stiffness",
            PbdParam::DistanceCompliance => "distance_compliance",
            PbdParam::VolumeCompliance => "volume_compliance",
            PbdParam::Dt => "dt",
            PbdParam::Substeps => "substeps",
            PbdParam::Iterations => "iterations",
            PbdParam::GravityX => "gravity.x",
            PbdParam::GravityY => "gravity.y",
            PbdParam::GravityZ => "gravity.z",
            PbdParam::Damping => "damping",
            PbdParam::LinearDamping => "linear_damping",
            PbdParam::Margin => "margin",
            PbdParam::Detection => "detection",
            PbdParam::StaticFriction => "static_friction",
            PbdParam::KineticFriction => "kinetic_friction",
            PbdParam::ContactReach => "margin + detection",
            PbdParam::CellSize => "cell_size",
            PbdParam::ColliderReach => "reach",
            PbdParam::Shapes => "shapes",
            PbdParam::FloorAxis => "floor.axis",
            PbdParam::FloorHeight => "floor.height",
            PbdParam::NodeTetCount => "node/tet count",
            PbdParam::NodeCount => "node count",
            PbdParam::TetCount => "tet count",
            PbdParam::Mass => "mass",
            PbdParam::ConstraintNodes => "constraint nodes",
            PbdParam::RestVolume => "rest volume",
            PbdParam::RestLength => "rest_length",
            PbdParam::Stiffness => "stiffness",
            PbdParam::Compliance => "compliance",
            PbdParam::YoungModulus => "elastic.young_kpa",
            PbdParam::PoissonRatio => "elastic.poisson",
            PbdParam::Solver => "solver",
            PbdParam::OverRelaxation => "over_relaxation",
        }
    }
}

impl std::fmt::Display for PbdParam {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_parameter_error_reads_as_before_the_names_were_typed() {
        let e = PbdError::InvalidParameter {
            param: PbdParam::DistanceStiffness,
            value: 1.5,
            expected: "in [0, 1]",
        };
        assert_eq!(
            e.to_string(),
            "invalid parameter distance_stiffness = 1.5: expected in [0, 1]"
        );
    }

    #[test]
    fn every_parameter_has_its_own_name() {
        let mut names: Vec<&str> = PbdParam::ALL.iter().map(|p| p.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), PbdParam::ALL.len());
    }
}
