//! The one error type of the crate.

/// What can go wrong setting up or running an implant scenario.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ImplantError {
    /// A parameter is out of range.
    #[error("invalid parameter {param} = {value}: {expected}")]
    InvalidParameter {
        /// The parameter at fault; [`Param::name`] is the name shown.
        param: Param,
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
    /// An expansion protocol (expansion over weeks) cannot be run: `field` is at fault,
    /// `problem` says what is wrong and how to fix it.
    #[error("protocol {field}: {problem}")]
    InvalidProtocol {
        /// The protocol field at fault.
        field: ProtocolField,
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

/// The parameter an [`ImplantError::InvalidParameter`] names.
///
/// Not `#[non_exhaustive]` on purpose: a front end maps every parameter to its own field with an
/// exhaustive `match`, so a new parameter fails to compile there instead of losing its field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Param {
    /// `check_same_mesh`/measurements: the surface after the run does not match the one before.
    After,
    /// `LayerParams::anchor_young`: Young's modulus of the anchoring springs (g/(cm·s²)).
    AnchorYoung,
    /// The expansion band's ladder of reference volumes (count of rungs).
    BandRungs,
    /// The expansion band's sample count.
    BandSamples,
    /// `vertex_stretch`: the surface before the run does not match the one after.
    Before,
    /// `ImplantShape::Crescent`'s bend radius (cm).
    BendRadius,
    /// `volume_for_gain`: the upper end of the volume bracket (cm³).
    BracketHigh,
    /// `volume_for_gain`: the lower end of the volume bracket (cm³).
    BracketLow,
    /// `RunParams::coherence`.
    Coherence,
    /// `RunParams::contact_distance` (cm).
    ContactDistance,
    /// `RunParams::contact_fraction`.
    ContactFraction,
    /// `ImplantShape::Rectangular`'s corner radius (cm).
    CornerRadius,
    /// `RunParams::damping_time` (s).
    DampingTime,
    /// `LayerParams::density`: the tissue's density (g/cm³).
    Density,
    /// The tissue model's depth (`LayerParams::depth`, cm), or the plane press's depth.
    Depth,
    /// `ImplantShape::Round`'s diameter (cm).
    Diameter,
    /// `ImplantParams::fill_bulk_modulus`.
    FillBulkModulus,
    /// `ImplantParams::fill_density` (g/cm³).
    FillDensity,
    /// `Insertion::new`'s fill time (s).
    FillTime,
    /// `GrowthParams::flap_release`.
    FlapRelease,
    /// `default_radius`'s footprint radius of the implant (cm).
    FootprintRadius,
    /// `volume_for_gain`: the area gain a run returned (cm²).
    Gain,
    /// `InverseOptions::gain_tolerance` (cm²).
    GainTolerance,
    /// `GrowthLaw::rate` (1/h).
    GrowthRate,
    /// `GrowthParams::step_hours`: the growth step (h).
    GrowthStep,
    /// `GrowthLaw::threshold`: the elastic area stretch above which skin grows.
    GrowthThreshold,
    /// `TissueLayers::lift_by`'s heights (cm, one per vertex).
    Heights,
    /// `ScanOptions::iterations`: the remeshing iterations.
    Iterations,
    /// An implant shape's length (cm).
    Length,
    /// `geodesic_distances`' distance limit (cm).
    Limit,
    /// `snap_to_surface`'s largest distance from the surface (cm).
    MaxDistance,
    /// `ScanOptions::max_hole`: the largest hole filled (cm).
    MaxHole,
    /// `InverseOptions::max_runs`.
    MaxRuns,
    /// `LayerParams::min_thickness` (a fraction of the depth).
    MinThickness,
    /// `ImplantFrame::new`'s normal.
    Normal,
    /// `LayerParams::offset_reach` (cm).
    OffsetReach,
    /// `ImplantFrame::new`'s origin (cm).
    Origin,
    /// The patient surface passed with a result is not the job's.
    Patient,
    /// `Insertion::new`'s pocket margin (cm).
    PocketMargin,
    /// `snap_to_surface`'s point (cm).
    Point,
    /// `LayerParams::poisson`: the tissue's Poisson ratio.
    Poisson,
    /// `GrowthLaw::prestretch` (area prestretch).
    Prestretch,
    /// `ImplantParams::radial_modulus`.
    RadialModulus,
    /// `select_region_with`'s region radius (cm).
    Radius,
    /// `replace_region`: the region after the run does not match the region.
    RegionAfter,
    /// `default_sim_edge`'s region radius (cm).
    RegionRadius,
    /// `RunParams::settle_speed` (cm/s).
    SettleSpeed,
    /// `ImplantParams::shell_poisson`.
    ShellPoisson,
    /// `ImplantParams::shell_thickness` (cm).
    ShellThickness,
    /// `ImplantParams::shell_young` (g/(cm·s²)).
    ShellYoung,
    /// `SimSurface::map_to_scan`: the simulation surface after the run does not match.
    SimAfter,
    /// `ScanOptions::sim_edge`: the simulation edge length (cm).
    SimEdge,
    /// `LayerParams::skin_thickness` (cm).
    SkinThickness,
    /// `ScanOptions::smoothing`: the MLS smoothing radius (cm).
    Smoothing,
    /// `geodesic_distances`' source triangle (not of this mesh).
    SourceTriangle,
    /// The plane press's speed (cm/s).
    Speed,
    /// The plane press's sphere radius (cm).
    SphereRadius,
    /// `fill_body`'s start positions (one per particle).
    Start,
    /// `RunParams::step_safety`, in (0, 1].
    StepSafety,
    /// A skin stiffness factor (`GrowthParams::stiffness`, `TissueLayers::scale_skin_stiffness`).
    Stiffness,
    /// `ImplantFrame::new`'s tangent.
    Tangent,
    /// `volume_for_gain`'s target area gain (cm²).
    TargetGain,
    /// `TissueLayers::grow`'s growth stretches θg (one per vertex, ≥ 1).
    ThetaG,
    /// `RunParams::time_step` (s).
    TimeStep,
    /// `StaticParams::tolerance` or `load_tolerance`: the quasi-static solver's residual.
    Tolerance,
    /// `StaticParams::load_steps`.
    LoadSteps,
    /// `StaticParams::contact_stiffness`.
    ContactStiffness,
    /// `ImplantSpec`'s vertex budget for the implant mesh.
    VertexBudget,
    /// `ImplantSpec`'s volume (cm³).
    VolumeCm3,
    /// `ImplantParams::volume_coupling`, in (0, 1).
    VolumeCoupling,
    /// `InverseOptions::volume_tolerance` (cm³).
    VolumeTolerance,
    /// An implant shape's width (cm).
    Width,
    /// `LayerParams::young`: the tissue's Young's modulus (g/(cm·s²)).
    Young,
}

impl Param {
    /// Every parameter, in name order: for tests and front ends that map each one.
    pub const ALL: &'static [Param] = &[
        Param::After,
        Param::AnchorYoung,
        Param::BandRungs,
        Param::BandSamples,
        Param::Before,
        Param::BendRadius,
        Param::BracketHigh,
        Param::BracketLow,
        Param::Coherence,
        Param::ContactDistance,
        Param::ContactFraction,
        Param::ContactStiffness,
        Param::CornerRadius,
        Param::DampingTime,
        Param::Density,
        Param::Depth,
        Param::Diameter,
        Param::FillBulkModulus,
        Param::FillDensity,
        Param::FillTime,
        Param::FlapRelease,
        Param::FootprintRadius,
        Param::Gain,
        Param::GainTolerance,
        Param::GrowthRate,
        Param::GrowthStep,
        Param::GrowthThreshold,
        Param::Heights,
        Param::Iterations,
        Param::Length,
        Param::Limit,
        Param::LoadSteps,
        Param::MaxDistance,
        Param::MaxHole,
        Param::MaxRuns,
        Param::MinThickness,
        Param::Normal,
        Param::OffsetReach,
        Param::Origin,
        Param::Patient,
        Param::PocketMargin,
        Param::Point,
        Param::Poisson,
        Param::Prestretch,
        Param::RadialModulus,
        Param::Radius,
        Param::RegionAfter,
        Param::RegionRadius,
        Param::SettleSpeed,
        Param::ShellPoisson,
        Param::ShellThickness,
        Param::ShellYoung,
        Param::SimAfter,
        Param::SimEdge,
        Param::SkinThickness,
        Param::Smoothing,
        Param::SourceTriangle,
        Param::Speed,
        Param::SphereRadius,
        Param::Start,
        Param::StepSafety,
        Param::Stiffness,
        Param::Tangent,
        Param::TargetGain,
        Param::ThetaG,
        Param::TimeStep,
        Param::Tolerance,
        Param::VertexBudget,
        Param::VolumeCm3,
        Param::VolumeCoupling,
        Param::VolumeTolerance,
        Param::Width,
        Param::Young,
    ];

    /// The name shown in messages (as it was when errors carried it as a string).
    pub const fn name(self) -> &'static str {
        match self {
            Param::After => "after",
            Param::AnchorYoung => "anchor_young",
            Param::BandRungs => "band rungs",
            Param::BandSamples => "band samples",
            Param::Before => "before",
            Param::BendRadius => "bend_radius",
            Param::BracketHigh => "bracket.high",
            Param::BracketLow => "bracket.low",
            Param::Coherence => "coherence",
            Param::ContactDistance => "contact_distance",
            Param::ContactFraction => "contact_fraction",
            Param::CornerRadius => "corner_radius",
            Param::DampingTime => "damping_time",
            Param::Density => "density",
            Param::Depth => "depth",
            Param::Diameter => "diameter",
            Param::FillBulkModulus => "fill_bulk_modulus",
            Param::FillDensity => "fill_density",
            Param::FillTime => "fill_time",
            Param::FlapRelease => "flap_release",
            Param::FootprintRadius => "footprint_radius",
            Param::Gain => "gain",
            Param::GainTolerance => "gain_tolerance",
            Param::GrowthRate => "growth rate",
            Param::GrowthStep => "growth step",
            Param::GrowthThreshold => "growth threshold",
            Param::Heights => "heights",
            Param::Iterations => "iterations",
            Param::Length => "length",
            Param::Limit => "limit",
            Param::MaxDistance => "max_distance",
            Param::MaxHole => "max_hole",
            Param::MaxRuns => "max_runs",
            Param::MinThickness => "min_thickness",
            Param::Normal => "normal",
            Param::OffsetReach => "offset_reach",
            Param::Origin => "origin",
            Param::Patient => "patient",
            Param::PocketMargin => "pocket_margin",
            Param::Point => "point",
            Param::Poisson => "poisson",
            Param::Prestretch => "prestretch",
            Param::RadialModulus => "radial_modulus",
            Param::Radius => "radius",
            Param::RegionAfter => "region_after",
            Param::RegionRadius => "region_radius",
            Param::SettleSpeed => "settle_speed",
            Param::ShellPoisson => "shell_poisson",
            Param::ShellThickness => "shell_thickness",
            Param::ShellYoung => "shell_young",
            Param::SimAfter => "sim_after",
            Param::SimEdge => "sim_edge",
            Param::SkinThickness => "skin_thickness",
            Param::Smoothing => "smoothing",
            Param::SourceTriangle => "source.triangle",
            Param::Speed => "speed",
            Param::SphereRadius => "sphere_radius",
            Param::Start => "start",
            Param::StepSafety => "step_safety",
            Param::Stiffness => "stiffness",
            Param::Tangent => "tangent",
            Param::TargetGain => "target_gain",
            Param::ThetaG => "theta_g",
            Param::TimeStep => "time_step",
            Param::Tolerance => "tolerance",
            Param::LoadSteps => "load_steps",
            Param::ContactStiffness => "contact_stiffness",
            Param::VertexBudget => "vertex_budget",
            Param::VolumeCm3 => "volume_cm3",
            Param::VolumeCoupling => "volume_coupling",
            Param::VolumeTolerance => "volume_tolerance",
            Param::Width => "width",
            Param::Young => "young",
        }
    }
}

impl std::fmt::Display for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The expansion protocol field an [`ImplantError::InvalidProtocol`] names.
///
/// Not `#[non_exhaustive]`, for the same reason as [`Param`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ProtocolField {
    /// The weeks of fills.
    ExpandWeeks,
    /// The fills (day, volume).
    Fills,
    /// The weeks held after the last fill.
    HoldWeeks,
    /// The fraction of a fill lost between fills.
    Leakage,
    /// The overfill beyond the nominal volume.
    Overfill,
    /// The nominal volume (cm³).
    Volume,
}

impl ProtocolField {
    /// Every protocol field, in name order: for tests and front ends that map each one.
    pub const ALL: &'static [ProtocolField] = &[
        ProtocolField::ExpandWeeks,
        ProtocolField::Fills,
        ProtocolField::HoldWeeks,
        ProtocolField::Leakage,
        ProtocolField::Overfill,
        ProtocolField::Volume,
    ];

    /// The name shown in messages (as it was when errors carried it as a string).
    pub const fn name(self) -> &'static str {
        match self {
            ProtocolField::ExpandWeeks => "expand_weeks",
            ProtocolField::Fills => "fills",
            ProtocolField::HoldWeeks => "hold_weeks",
            ProtocolField::Leakage => "leakage",
            ProtocolField::Overfill => "overfill",
            ProtocolField::Volume => "volume",
        }
    }
}

impl std::fmt::Display for ProtocolField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names are the strings the errors carried before they were typed: distinct, in the
    /// order of `ALL`, and shown unchanged.
    #[test]
    fn names_are_distinct_and_messages_unchanged() {
        for all in [
            Param::ALL.iter().map(|p| p.name()).collect::<Vec<_>>(),
            ProtocolField::ALL.iter().map(|f| f.name()).collect(),
        ] {
            assert!(all.windows(2).all(|w| w[0] < w[1]), "{all:?}");
        }
        let e = ImplantError::InvalidParameter {
            param: Param::BandSamples,
            value: 3.0,
            expected: "8 to 4096".into(),
        };
        assert_eq!(
            e.to_string(),
            "invalid parameter band samples = 3: 8 to 4096"
        );
        let e = ImplantError::InvalidProtocol {
            field: ProtocolField::HoldWeeks,
            problem: "give 0 or more".into(),
        };
        assert_eq!(e.to_string(), "protocol hold_weeks: give 0 or more");
    }
}
