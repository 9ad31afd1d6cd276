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
    /// An expansion protocol cannot be run (issue 21): `field` is at fault, `problem` says
    /// what is wrong and how to fix it.
    #[error("protocol {field}: {problem}")]
    InvalidProtocol {
        /// The protocol field at fault (`fills`, `expand_weeks`, `hold_weeks`, `leakage`,
        /// `overfill`, `volume`).
        field: &'static str,
        /// What is wrong, and how to fix it.
        problem: String,
    },
    /// The point given for the implant is too far from the patient surface.
    #[error("the point {point:?} is {distance:.3} cm from the surface (nearest surface point {nearest:?}); at most {max_distance:.3} cm is accepted: pick a point on the skin")]
    PointOffSurface {
        /// The point given.
        point: [f32; 3],
        /// Its distance to the surface (cm).
        distance: f64,
        /// The largest distance accepted (cm).
        max_distance: f64,
        /// The nearest surface point.
        nearest: [f32; 3],
    },
    /// The radius is too small to select even the triangle under the centre.
    #[error("a region of radius {radius:.3} cm around triangle {triangle} is empty; use a radius of at least {min_radius:.3} cm")]
    EmptyRegion {
        /// The radius given (cm).
        radius: f64,
        /// The smallest radius that selects the centre's triangle (cm).
        min_radius: f64,
        /// The triangle under the centre.
        triangle: u32,
    },
    /// The radius selects the whole connected piece of the surface: no boundary would be left to
    /// hold the region.
    #[error("a region of radius {radius:.3} cm covers the whole surface piece ({triangles} triangles, farthest point {farthest:.3} cm away); use a smaller radius")]
    RegionCoversSurface {
        /// The radius given (cm).
        radius: f64,
        /// Triangles of the surface piece.
        triangles: usize,
        /// Geodesic distance of the piece's farthest point (cm).
        farthest: f64,
    },
    /// The surface height given for an implant's base is not finite.
    #[error("the surface height under the implant at ({x}, {y}) is {value}: it must be finite")]
    SurfaceHeight {
        /// Local x (cm).
        x: f32,
        /// Local y (cm).
        y: f32,
        /// The height returned.
        value: f32,
    },
    /// The implant's outline cannot be meshed with the parameters given.
    #[error("the implant shape cannot be meshed: {reason}")]
    ShapeNotMeshable {
        /// Why.
        reason: String,
    },
    /// The implant volume cannot be reached with a plausible height for this base.
    #[error("an implant volume of {volume:.3} cm³ is out of reach for this base: between {min:.3} and {max:.3} cm³ can be made")]
    VolumeOutOfRange {
        /// The target volume (cm³).
        volume: f64,
        /// The smallest volume possible (cm³).
        min: f64,
        /// The largest volume possible (cm³).
        max: f64,
    },
    /// Solving for the implant height did not reach the target volume within 0.5%.
    #[error("the implant height search reached {reached:.3} cm³ (height {height:.3} cm) for a target of {target:.3} cm³")]
    VolumeNotReached {
        /// The target volume (cm³).
        target: f64,
        /// The closest volume reached (cm³).
        reached: f64,
        /// The height that gave it (cm).
        height: f64,
    },
    /// A surface of the scenario cannot be given its search hierarchy (a BVH over its
    /// triangles, for closest points and rays): the hierarchy's own error, and which surface.
    #[error("the {surface} cannot be searched: {source}")]
    Search {
        /// Which surface.
        surface: SearchedSurface,
        /// Why its hierarchy could not be built.
        source: tissue_bvh::BvhError,
    },
    /// The region's triangles cancel out: it has no mean normal to press along.
    #[error("the region's {triangles} triangles cancel out (no mean normal): select a patch that faces one way")]
    NoMeanNormal {
        /// Its triangle count.
        triangles: usize,
    },
    /// The mass–spring model refused its input or diverged.
    #[error("tissue model: {0}")]
    Model(#[from] tissue_mss::MssError),
    /// Collision detection or response refused its input.
    #[error("collision: {0}")]
    Collide(#[from] tissue_collide::CollideError),
    /// The run was cancelled by its caller between two steps.
    #[error("cancelled by the caller after {steps} steps")]
    Cancelled {
        /// Steps completed before the cancel.
        steps: u64,
    },
    /// The run produced a non-finite position or velocity.
    #[error("the run diverged at step {step}: {what} of particle {particle} is not finite; use a smaller time step")]
    Diverged {
        /// The step (0-based).
        step: u64,
        /// Which particle (in the tissue or the implant, see `what`).
        particle: u32,
        /// Which quantity and which body.
        what: &'static str,
    },
    /// An inverse search was given a bracket whose ends do not enclose the target.
    #[error("target area gain {target:.3} cm² is not between the gains at the bracket ends: {low_gain:.3} cm² at {low_volume:.3} cm³ and {high_gain:.3} cm² at {high_volume:.3} cm³; widen the volume bracket")]
    TargetNotBracketed {
        /// The target gain (cm²).
        target: f64,
        /// The lower volume (cm³).
        low_volume: f64,
        /// The gain it gave (cm²).
        low_gain: f64,
        /// The upper volume (cm³).
        high_volume: f64,
        /// The gain it gave (cm²).
        high_gain: f64,
    },
    /// A point of the implant's base is not over the region's inner layer.
    #[error("the implant's base point at local ({x:.3}, {y:.3}) cm is not over the region's inner layer: select a larger region or a smaller implant")]
    FootprintOutsideRegion {
        /// Local x (cm).
        x: f32,
        /// Local y (cm).
        y: f32,
    },
    /// The expander's rim comes closer to the region's fixed border than the tissue between them
    /// can take: the region is too tight where it runs into a crease or a fold of the body.
    #[error("the expander's rim comes within {clearance:.2} cm of the region's fixed border (at least {needed:.2} cm, one simulation edge, must stay between them): use a larger region radius, or move the expander away from creases")]
    RimAtBorder {
        /// The smallest distance from the rim to the border (cm).
        clearance: f64,
        /// The least allowed (cm).
        needed: f64,
    },
    /// The region reaches the scan's outer border or a hole too large to fill: no skin around
    /// it there to hold its boundary.
    #[error("the region of radius {radius:.2} cm around {centre:?} cm reaches {what} {distance:.2} cm from its centre: shrink the region to a radius of at most {fit_radius:.2} cm (--radius), or the expander by {shrink_percent:.0} % (the default region is 1.5 × its footprint radius); or move it: {elsewhere}")]
    RegionReachesBorder {
        /// The region radius asked for (cm).
        radius: f64,
        /// The region's centre (cm).
        centre: [f32; 3],
        /// What it reaches: the outer border, or a hole with its size and place.
        what: String,
        /// Geodesic distance from the centre to the nearest point reached (cm).
        distance: f64,
        /// The largest region radius that stays off it (cm).
        fit_radius: f64,
        /// How much smaller (percent) the region, or the expander with the default region,
        /// must be.
        shrink_percent: f64,
        /// Where a region of the radius asked would fit, or the largest that fits anywhere.
        elsewhere: String,
    },
    /// Filling the scan's holes or remeshing the region failed.
    #[error("simulation surface: {0}")]
    Remesh(#[from] tissue_remesh::RemeshError),
    /// The run stayed finite but ran away: the skin moved far beyond the expander's height.
    #[error("the run ran away after {steps} steps: region vertex {vertex} moved {displacement:.2} cm, more than the {limit:.2} cm an expander of this height can lift it; use a larger simulation edge (--sim-edge) or a smaller time step")]
    RanAway {
        /// Steps taken.
        steps: u64,
        /// The simulated region's vertex that moved most.
        vertex: u32,
        /// How far it moved (cm).
        displacement: f64,
        /// The most accepted (cm): `RUNAWAY_FACTOR` × the dome height + 1 cm.
        limit: f64,
    },
}

/// The surfaces a scenario searches ([`ImplantError::Search`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SearchedSurface {
    /// The region's inner layer (layer 2), which the implant's base is placed onto.
    RegionInnerLayer,
    /// The implant's flat base, which the inner layer is checked against.
    ImplantBase,
    /// The remeshed simulation surface, which the region's vertices are bound to.
    SimulationSurface,
}

impl std::fmt::Display for SearchedSurface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SearchedSurface::RegionInnerLayer => "region's inner layer",
            SearchedSurface::ImplantBase => "implant's base",
            SearchedSurface::SimulationSurface => "simulation surface",
        })
    }
}
