//! What a planner asks for: where the implant goes, the implant, the tissue, the simulation mesh
//! and the run, in one flat record whose JSON names carry their units. Every field has the
//! library's default, so `{}` is the Table 2 case.

use serde::{Deserialize, Serialize};
use tissue_app::SimMesh;
use tissue_implant::BroadPhase;
use tissue_implant::{ImplantShape, ImplantSpec, InsertionParams, LayerParams, ScanOptions};

use crate::error::{ErrorKind, PlanError};
use crate::units::{Detect, Rule, Shape, Solver, KPA};

/// One planning request. Lengths in cm unless the name says otherwise; `at` and `tangent` in
/// the mesh's unit and frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlanRequest {
    /// Where the implant goes, in the mesh's unit; snapped to the nearest surface point.
    pub at: Option<[f32; 3]>,
    /// Where the implant goes: a vertex of the mesh, from 0 in file order (wins over `at`).
    pub vertex: Option<u32>,
    /// The implant's local x direction (a rectangle's length), projected across the normal
    /// [default: +x, or +y when the normal is within 25° of ±x].
    pub tangent: Option<[f32; 3]>,
    /// Turns the tangent about the normal, degrees, counter-clockwise seen from outside.
    pub rotation_deg: f32,
    /// The base outline.
    pub shape: Shape,
    /// Round base: diameter, cm.
    pub diameter_cm: f32,
    /// Rectangular: length along the tangent; crescent: centre-line length tip to tip, cm.
    pub length_cm: Option<f32>,
    /// Rectangular or crescent: width, cm.
    pub width_cm: Option<f32>,
    /// Rectangular: corner radius, cm.
    pub corner_radius_cm: f32,
    /// Crescent: the centre line's arc radius, cm.
    pub bend_radius_cm: Option<f32>,
    /// Fill volume, cm³ (= mL).
    pub volume_cm3: f64,
    /// The implant mesh's wanted vertex count.
    pub implant_vertices: u32,
    /// The implant's base lies this far under the skin, cm.
    pub depth_cm: f64,
    /// The region's geodesic radius, cm [default: 1.5 × the footprint radius].
    pub region_radius_cm: Option<f64>,
    /// Which triangles within the radius form the region.
    pub region_rule: Rule,
    /// The simulation mesh's edge, cm [default: from the expander's size].
    pub sim_edge_cm: Option<f64>,
    /// Run on the mesh's own triangles instead of a simulation mesh of its own.
    pub scan_triangles: bool,
    /// Holes up to this size across are filled for the simulation, cm.
    pub max_hole_cm: f64,
    /// Skin Young's modulus, kPa.
    pub young_kpa: f64,
    /// Skin Poisson ratio, in [0, 0.5).
    pub poisson: f64,
    /// Skin thickness, cm.
    pub thickness_cm: f64,
    /// Tissue density, g/cm³.
    pub density_g_cm3: f64,
    /// The collision broad phase.
    pub detect: Detect,
    /// How a run finds the rest state: `explicit` (the default) or `quasi_static` (the
    /// thesis's stepping, the reference). Every mode runs with it.
    pub solver: Solver,
    /// A run's step limit.
    pub max_steps: u64,
    /// The time step, s [default: automatic].
    pub time_step_s: Option<f32>,
    /// Expansion over weeks: this many weekly fills to `volume_cm3`, with skin
    /// growth [default: none, one insertion].
    pub expand_weeks: Option<u32>,
    /// Expansion: weeks the expander is held full before removal.
    pub hold_weeks: f64,
    /// Expansion: the fraction of every fill that leaks, in [0, 0.9] (in vivo 0.29 ± 0.125).
    pub leakage: f64,
    /// Expansion: saline injected beyond `volume_cm3`, as a fraction of it, in [0, 1].
    pub overfill: f64,
    /// Expansion: samples of the uncertainty band (0: none; at least 8).
    pub band_samples: usize,
    /// Expansion: the band's seed.
    pub band_seed: u64,
    /// Expansion: the growth step, hours, in (0, 24].
    pub growth_step_h: f64,
}

impl Default for PlanRequest {
    fn default() -> Self {
        let layers = LayerParams::default();
        PlanRequest {
            at: None,
            vertex: None,
            tangent: None,
            rotation_deg: 0.0,
            shape: Shape::Round,
            diameter_cm: 7.0,
            length_cm: None,
            width_cm: None,
            corner_radius_cm: 0.5,
            bend_radius_cm: None,
            volume_cm3: 100.0,
            implant_vertices: ImplantSpec::DEFAULT_VERTEX_BUDGET,
            depth_cm: layers.depth,
            region_radius_cm: None,
            region_rule: Rule::TouchesVertex,
            sim_edge_cm: None,
            scan_triangles: false,
            max_hole_cm: tissue_implant::DEFAULT_MAX_HOLE,
            young_kpa: layers.young / KPA,
            poisson: layers.poisson,
            thickness_cm: layers.skin_thickness,
            density_g_cm3: layers.density,
            detect: Detect::Bvh,
            solver: Solver::from(InsertionParams::default().solver),
            max_steps: InsertionParams::default().run.stop.max_steps,
            time_step_s: None,
            expand_weeks: None,
            hold_weeks: 1.0,
            leakage: tissue_implant::LEAKAGE_MEAN,
            overfill: 0.0,
            band_samples: tissue_implant::BandOptions::default().samples,
            band_seed: tissue_implant::BandOptions::default().seed,
            growth_step_h: tissue_implant::GrowthParams::human().step_hours,
        }
    }
}

/// The most steps a run may take (`max_steps`): 25 × the library's default of 20 000. The
/// thesis's runs settle in 2 800–3 300 steps (Table 1), the expansion settles each growth step
/// within the same budget, and a run that has not settled after 20 000 says so; at the Table 2
/// plane's ~10 ms a step, this is over an hour of one run.
pub const MAX_STEPS: u64 = 500_000;

/// The most volumes a sweep runs (`volumes_cm3`): Table 1 sweeps 3; a chart of a few dozen points
/// is already dense.
pub const MAX_SWEEP_VOLUMES: usize = 64;

/// The largest length the request takes, cm: an implant's `diameter_cm`, `length_cm`,
/// `width_cm`, `corner_radius_cm`, `bend_radius_cm`; `region_radius_cm`, `sim_edge_cm`,
/// `max_hole_cm`. Expanders are at most about 25 cm long; a radius of 1 m covers a whole body.
pub const MAX_LENGTH_CM: f64 = 100.0;

/// The largest fill volume, cm³ (`volume_cm3`, a sweep's volumes, a search's bracket): expanders
/// hold up to about 1 000 mL.
pub const MAX_VOLUME_CM3: f64 = 5000.0;

/// The deepest placement, cm (`depth_cm`): expanders go 0.2–3 cm under the skin.
pub const MAX_DEPTH_CM: f64 = 10.0;

/// The thickest skin, cm (`thickness_cm`): skin is 0.05–0.4 cm thick, with fat a few cm.
pub const MAX_THICKNESS_CM: f64 = 10.0;

/// The stiffest skin, kPa (`young_kpa`): 100 MPa, ten times the stiffest skin measured
/// (skin: 0.1–20 MPa).
pub const MAX_YOUNG_KPA: f64 = 100_000.0;

/// The densest tissue, g/cm³ (`density_g_cm3`): soft tissue is about 1.0–1.1, bone about 2.
pub const MAX_DENSITY_G_CM3: f64 = 10.0;

/// The longest time step, s (`time_step_s`): the automatic step is 3.4·10⁻⁵ s on the Table 2
/// plane and a step of 10⁻³ s already diverges there (the run says so); beyond this the solver's
/// damping underflows and the run fails without saying why.
pub const MAX_TIME_STEP_S: f64 = 0.01;

/// The shortest growth step of an expansion, hours (`growth_step_h`): the mechanics re-settle
/// after every one, so an expansion of a year has at most 8 760 of them.
pub const MIN_GROWTH_STEP_H: f64 = 1.0;

/// `value` must be finite and positive.
fn positive(field: &'static str, value: f64, unit: &str) -> Result<(), PlanError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(PlanError::field(
            ErrorKind::Parameters,
            field,
            format!("`{field}` must be a positive number of {unit}, got {value}"),
        ))
    }
}

/// `value` must be at most `max` (`why`: what real values are).
fn at_most(
    kind: ErrorKind,
    field: &'static str,
    value: f64,
    max: f64,
    unit: &str,
    why: &str,
) -> Result<(), PlanError> {
    if value <= max {
        Ok(())
    } else {
        Err(PlanError::field(
            kind,
            field,
            format!("`{field}` must be at most {max} {unit} ({why}), got {value}"),
        ))
    }
}

/// A positive length of at most [`MAX_LENGTH_CM`].
fn length(field: &'static str, value: f64) -> Result<(), PlanError> {
    positive(field, value, "cm")?;
    at_most(
        ErrorKind::Parameters,
        field,
        value,
        MAX_LENGTH_CM,
        "cm",
        "larger than any implant or region",
    )
}

/// A positive volume of at most [`MAX_VOLUME_CM3`].
fn volume(field: &'static str, value: f64) -> Result<(), PlanError> {
    positive(field, value, "cm³ (mL)")?;
    at_most(
        ErrorKind::Parameters,
        field,
        value,
        MAX_VOLUME_CM3,
        "cm³",
        "expanders hold up to about 1000 mL",
    )
}

impl PlanRequest {
    /// Checks the numbers a user types, naming the field: a size, volume or tissue value that
    /// cannot be right is refused before anything runs, and every size and count has an upper
    /// bound no plan reaches ([`MAX_STEPS`], [`MAX_LENGTH_CM`], [`MAX_VOLUME_CM3`],
    /// [`MAX_DEPTH_CM`], [`MAX_THICKNESS_CM`], [`MAX_YOUNG_KPA`], [`MAX_DENSITY_G_CM3`],
    /// [`MAX_TIME_STEP_S`], [`MIN_GROWTH_STEP_H`], the implant's vertex budget) so that the
    /// work a request asks for is bounded.
    ///
    /// # Errors
    /// [`ErrorKind::Parameters`] (or [`ErrorKind::Placement`] for the region radius) naming the
    /// field.
    pub fn check(&self) -> Result<(), PlanError> {
        volume("volume_cm3", self.volume_cm3)?;
        match self.shape {
            Shape::Round => length("diameter_cm", f64::from(self.diameter_cm))?,
            Shape::Rectangular | Shape::Crescent => {
                for (field, value) in [
                    ("length_cm", self.length_cm),
                    ("width_cm", self.width_cm),
                    ("bend_radius_cm", self.bend_radius_cm),
                ] {
                    if let Some(v) = value {
                        length(field, f64::from(v))?;
                    }
                }
                if self.shape == Shape::Rectangular {
                    // Zero is a square corner; the implant checks it against the outline.
                    let r = f64::from(self.corner_radius_cm);
                    at_most(
                        ErrorKind::Parameters,
                        "corner_radius_cm",
                        r,
                        MAX_LENGTH_CM,
                        "cm",
                        "larger than any implant",
                    )?;
                }
            }
        }
        let budget = ImplantSpec::MIN_VERTEX_BUDGET..=ImplantSpec::MAX_VERTEX_BUDGET;
        if !budget.contains(&self.implant_vertices) {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "implant_vertices",
                format!(
                    "`implant_vertices` must be {} to {} (the thesis's implant has 514), got {}",
                    budget.start(),
                    budget.end(),
                    self.implant_vertices
                ),
            ));
        }
        positive("depth_cm", self.depth_cm, "cm")?;
        at_most(
            ErrorKind::Parameters,
            "depth_cm",
            self.depth_cm,
            MAX_DEPTH_CM,
            "cm",
            "expanders go 0.2–3 cm under the skin",
        )?;
        positive("young_kpa", self.young_kpa, "kPa")?;
        at_most(
            ErrorKind::Parameters,
            "young_kpa",
            self.young_kpa,
            MAX_YOUNG_KPA,
            "kPa",
            "skin is 100–20000 kPa",
        )?;
        positive("thickness_cm", self.thickness_cm, "cm")?;
        at_most(
            ErrorKind::Parameters,
            "thickness_cm",
            self.thickness_cm,
            MAX_THICKNESS_CM,
            "cm",
            "skin is 0.05–0.4 cm thick",
        )?;
        positive("density_g_cm3", self.density_g_cm3, "g/cm³")?;
        at_most(
            ErrorKind::Parameters,
            "density_g_cm3",
            self.density_g_cm3,
            MAX_DENSITY_G_CM3,
            "g/cm³",
            "soft tissue is about 1.0–1.1",
        )?;
        if !(self.poisson.is_finite() && (0.0..0.5).contains(&self.poisson)) {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "poisson",
                format!(
                    "`poisson` must be in [0, 0.5) (soft tissue: about 0.45), got {}",
                    self.poisson
                ),
            ));
        }
        if let Some(r) = self.region_radius_cm {
            if !(r.is_finite() && r > 0.0) {
                return Err(PlanError::field(
                    ErrorKind::Placement,
                    "region_radius_cm",
                    format!("`region_radius_cm` must be a positive region radius in cm, got {r}"),
                ));
            }
            at_most(
                ErrorKind::Placement,
                "region_radius_cm",
                r,
                MAX_LENGTH_CM,
                "cm",
                "a region of 1 m radius covers a whole body",
            )?;
        }
        if let Some(h) = self.sim_edge_cm {
            length("sim_edge_cm", h)?;
        }
        if !(self.max_hole_cm.is_finite()
            && self.max_hole_cm >= 0.0
            && self.max_hole_cm <= MAX_LENGTH_CM)
        {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "max_hole_cm",
                format!(
                    "`max_hole_cm` must be a size from 0 to {MAX_LENGTH_CM} cm, got {}",
                    self.max_hole_cm
                ),
            ));
        }
        if let Some(h) = self.time_step_s {
            positive("time_step_s", f64::from(h), "seconds")?;
            at_most(
                ErrorKind::Parameters,
                "time_step_s",
                f64::from(h),
                MAX_TIME_STEP_S,
                "s",
                "leave it null for the automatic step, 3.4e-5 s on Table 2's plane",
            )?;
        }
        if !self.rotation_deg.is_finite() {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "rotation_deg",
                "`rotation_deg` must be a finite angle in degrees",
            ));
        }
        if self.expand_weeks.is_some() {
            self.expansion_protocol()?;
            if self.band_samples != 0 && !(8..=4096).contains(&self.band_samples) {
                return Err(PlanError::field(
                    ErrorKind::Parameters,
                    "band_samples",
                    format!(
                        "`band_samples` must be 0 (no band) or 8 to 4096 (32 is the full band), \
                         got {}",
                        self.band_samples
                    ),
                ));
            }
            if !(self.growth_step_h.is_finite()
                && self.growth_step_h >= MIN_GROWTH_STEP_H
                && self.growth_step_h <= 24.0)
            {
                return Err(PlanError::field(
                    ErrorKind::Parameters,
                    "growth_step_h",
                    format!(
                        "`growth_step_h` must be in [{MIN_GROWTH_STEP_H}, 24] hours (the skin \
                         re-settles after every step, at least daily), got {}",
                        self.growth_step_h
                    ),
                ));
            }
        }
        if !(1..=MAX_STEPS).contains(&self.max_steps) {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "max_steps",
                format!(
                    "`max_steps` must be 1 to {MAX_STEPS} (the default {} is enough for the \
                     thesis's runs), got {}",
                    InsertionParams::default().run.stop.max_steps,
                    self.max_steps
                ),
            ));
        }
        Ok(())
    }

    /// The expansion's fill protocol (`expand_weeks` weekly fills to `volume_cm3` plus
    /// `overfill`, `hold_weeks`, `leakage`), or `None` without `expand_weeks`.
    ///
    /// # Errors
    /// [`ErrorKind::Parameters`] naming the field at fault.
    pub fn expansion_protocol(&self) -> Result<Option<tissue_implant::Protocol>, PlanError> {
        let Some(weeks) = self.expand_weeks else {
            return Ok(None);
        };
        tissue_implant::Protocol::weekly(
            self.volume_cm3,
            weeks,
            self.hold_weeks,
            self.leakage,
            self.overfill,
        )
        .map(Some)
        .map_err(|e| PlanError::from_implant(&e))
    }

    /// The expansion's growth parameters: human skin ([`tissue_implant::GrowthParams::human`])
    /// with `growth_step_h`.
    pub fn growth(&self) -> tissue_implant::GrowthParams {
        tissue_implant::GrowthParams {
            step_hours: self.growth_step_h,
            ..tissue_implant::GrowthParams::human()
        }
    }

    /// The band's options, or `None` when `band_samples` is 0.
    pub fn band(&self) -> Option<tissue_implant::BandOptions> {
        (self.band_samples > 0).then(|| tissue_implant::BandOptions {
            samples: self.band_samples,
            seed: self.band_seed,
            ..tissue_implant::BandOptions::default()
        })
    }

    /// The implant's outline; a missing size is [`ErrorKind::Usage`].
    ///
    /// # Errors
    /// A rectangle or crescent without its length, width (or bend radius).
    pub fn implant_shape(&self) -> Result<ImplantShape, PlanError> {
        let need = |field: &'static str, value: Option<f32>| {
            value.ok_or_else(|| {
                PlanError::field(
                    ErrorKind::Usage,
                    field,
                    format!("a {} implant needs `{field}` (cm)", self.shape.name()),
                )
            })
        };
        Ok(match self.shape {
            Shape::Round => ImplantShape::Round {
                diameter: self.diameter_cm,
            },
            Shape::Rectangular => ImplantShape::Rectangular {
                length: need("length_cm", self.length_cm)?,
                width: need("width_cm", self.width_cm)?,
                corner_radius: self.corner_radius_cm,
            },
            Shape::Crescent => ImplantShape::Crescent {
                length: need("length_cm", self.length_cm)?,
                width: need("width_cm", self.width_cm)?,
                bend_radius: need("bend_radius_cm", self.bend_radius_cm)?,
            },
        })
    }

    /// The fraction of the stability limit the automatic time step uses (`time_step_s` null):
    /// the library's default, [`tissue_implant::RunParams::step_safety`].
    pub fn automatic_step_safety(&self) -> f32 {
        self.params().run.step_safety
    }

    /// The library's parameters (its defaults for everything the request does not name).
    pub fn params(&self) -> InsertionParams {
        let mut params = InsertionParams {
            solver: self.solver.into(),
            ..InsertionParams::default()
        };
        params.layers.young = self.young_kpa * KPA;
        params.layers.poisson = self.poisson;
        params.layers.skin_thickness = self.thickness_cm;
        params.layers.density = self.density_g_cm3;
        params.layers.depth = self.depth_cm;
        params.run.broad_phase = match self.detect {
            Detect::Bvh => BroadPhase::BvhBvh,
            Detect::Voxels => BroadPhase::BvhVoxels,
        };
        params.run.stop.max_steps = self.max_steps;
        if self.time_step_s.is_some() {
            params.run.time_step = self.time_step_s;
        }
        params
    }

    /// The surface the mechanics run on: the region remeshed (a scan), or the mesh's own
    /// triangles (`scan_triangles`, and the generated Table 2 plane unless `sim_edge_cm` is
    /// given: the thesis's planes are even already).
    pub fn sim_mesh(&self, generated_plane: bool) -> SimMesh {
        if self.scan_triangles || (generated_plane && self.sim_edge_cm.is_none()) {
            SimMesh::Patient
        } else {
            SimMesh::Remeshed(ScanOptions {
                sim_edge: self.sim_edge_cm,
                max_hole: self.max_hole_cm,
                ..ScanOptions::default()
            })
        }
    }
}

/// Checks the volumes of a sweep: one to [`MAX_SWEEP_VOLUMES`], each positive and at most
/// [`MAX_VOLUME_CM3`].
///
/// # Errors
/// [`ErrorKind::Parameters`] naming `volumes_cm3`.
pub fn check_sweep(volumes: &[f64]) -> Result<(), PlanError> {
    if volumes.is_empty() {
        return Err(PlanError::field(
            ErrorKind::Parameters,
            "volumes_cm3",
            "a sweep needs at least one volume in `volumes_cm3`",
        ));
    }
    if volumes.len() > MAX_SWEEP_VOLUMES {
        return Err(PlanError::field(
            ErrorKind::Parameters,
            "volumes_cm3",
            format!(
                "a sweep runs at most {MAX_SWEEP_VOLUMES} volumes, `volumes_cm3` has {}: sweep \
                 fewer, or split the sweep",
                volumes.len()
            ),
        ));
    }
    for &v in volumes {
        if !(v.is_finite() && v > 0.0 && v <= MAX_VOLUME_CM3) {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "volumes_cm3",
                format!(
                    "every volume of `volumes_cm3` must be a positive number of cm³ (mL) up to \
                     {MAX_VOLUME_CM3}, got {v}"
                ),
            ));
        }
    }
    Ok(())
}

/// Checks a search for the volume of a target gain and gives its bracket (default: a quarter to
/// twice `volume_cm3`, at most [`MAX_VOLUME_CM3`]; a given bracket must lie within it too).
///
/// # Errors
/// [`ErrorKind::Parameters`] naming `target_gain_cm2`, `bracket_cm3` or `gain_tolerance_cm2`.
pub fn check_search(
    target_gain_cm2: f64,
    bracket_cm3: Option<(f64, f64)>,
    gain_tolerance_cm2: f64,
    volume_cm3: f64,
) -> Result<(f64, f64), PlanError> {
    if !target_gain_cm2.is_finite() {
        return Err(PlanError::field(
            ErrorKind::Parameters,
            "target_gain_cm2",
            "`target_gain_cm2` must be a finite area in cm²",
        ));
    }
    positive("gain_tolerance_cm2", gain_tolerance_cm2, "cm²")?;
    let (low, high) =
        bracket_cm3.unwrap_or((0.25 * volume_cm3, (2.0 * volume_cm3).min(MAX_VOLUME_CM3)));
    if !(low.is_finite() && low > 0.0) {
        return Err(PlanError::field(
            ErrorKind::Parameters,
            "bracket_cm3",
            format!("the low end of `bracket_cm3` must be a positive number of cm³, got {low}"),
        ));
    }
    if !(high.is_finite() && high > low) {
        return Err(PlanError::field(
            ErrorKind::Parameters,
            "bracket_cm3",
            format!("the high end of `bracket_cm3` must be larger than the low end ({low} cm³), got {high}"),
        ));
    }
    if high > MAX_VOLUME_CM3 {
        return Err(PlanError::field(
            ErrorKind::Parameters,
            "bracket_cm3",
            format!(
                "the high end of `bracket_cm3` must be at most {MAX_VOLUME_CM3} cm³ (expanders \
                 hold up to about 1000 mL), got {high}"
            ),
        ));
    }
    Ok((low, high))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_request_is_the_table2_case() -> Result<(), PlanError> {
        let r: PlanRequest = serde_json::from_str("{}")
            .map_err(|e| PlanError::new(ErrorKind::Usage, e.to_string()))?;
        assert_eq!(r, PlanRequest::default());
        r.check()?;
        assert_eq!(r.implant_shape()?, ImplantShape::Round { diameter: 7.0 });
        assert_eq!(r.params().layers, LayerParams::default());
        assert!(matches!(r.sim_mesh(true), SimMesh::Patient));
        assert!(matches!(r.sim_mesh(false), SimMesh::Remeshed(_)));
        Ok(())
    }

    #[test]
    fn bad_numbers_name_their_field() {
        let bad = PlanRequest {
            volume_cm3: -5.0,
            ..PlanRequest::default()
        };
        let e = bad.check().err();
        assert_eq!(e.as_ref().and_then(|e| e.field), Some("volume_cm3"));
        let rect = PlanRequest {
            shape: Shape::Rectangular,
            length_cm: Some(8.0),
            ..PlanRequest::default()
        };
        let e = rect.implant_shape().err();
        assert_eq!(
            e.map(|e| (e.kind, e.field)),
            Some((ErrorKind::Usage, Some("width_cm")))
        );
        let unknown: Result<PlanRequest, _> = serde_json::from_str(r#"{"volume": 3}"#);
        assert!(unknown.is_err(), "unknown fields are refused");
    }

    /// `solver`: the library's default when left out, either name taken and passed to the
    /// library's parameters, an unknown name refused naming the field and both names.
    #[test]
    fn the_solver_defaults_to_explicit_and_reaches_the_parameters() {
        use tissue_implant::Solver as Library;
        let empty = request(serde_json::json!({}));
        assert_eq!(empty.solver, Solver::Explicit);
        assert_eq!(empty.params().solver, Library::Explicit);
        assert_eq!(empty.params().solver, InsertionParams::default().solver);
        for (name, solver, library) in [
            ("quasi_static", Solver::QuasiStatic, Library::QuasiStatic),
            ("explicit", Solver::Explicit, Library::Explicit),
        ] {
            let r = request(serde_json::json!({ "solver": name }));
            assert_eq!(r.solver, solver, "{name}");
            assert_eq!(r.params().solver, library, "{name}");
            assert!(r.check().is_ok());
            assert_eq!(
                serde_json::to_value(&r).ok().map(|v| v["solver"].clone()),
                Some(serde_json::json!(name))
            );
        }
        // Only the solver changes: every other parameter is the same for both.
        let statics = request(serde_json::json!({ "solver": "quasi_static" })).params();
        assert_eq!(
            InsertionParams {
                solver: Library::Explicit,
                ..statics
            },
            empty.params()
        );
        for bad in [
            serde_json::json!({ "solver": "implicit" }),
            serde_json::json!({ "solver": "Explicit" }),
            serde_json::json!({ "solver": 1 }),
        ] {
            let e = serde_json::from_value::<PlanRequest>(bad.clone())
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            if bad["solver"].is_string() {
                assert!(e.contains("`solver`"), "{bad}: {e}");
                assert!(e.contains("`explicit` or `quasi_static`"), "{bad}: {e}");
            } else {
                assert!(!e.is_empty(), "{bad} is refused");
            }
        }
        // Through a job too, with the parser's position.
        let e = serde_json::from_str::<crate::JobSpec>(r#"{"request": {"solver": "newton"}}"#)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains(
                "unknown variant `newton` of `solver`, expected `explicit` or `quasi_static`"
            ) && e.contains("line 1"),
            "{e}"
        );
    }

    fn request(json: serde_json::Value) -> PlanRequest {
        match serde_json::from_value(json.clone()) {
            Ok(r) => r,
            Err(e) => unreachable!("{json}: {e}"),
        }
    }

    #[test]
    fn every_bound_is_refused_naming_its_field_and_a_value_just_inside_is_accepted() {
        use serde_json::json;
        let rect = |field: &str, v: f64| {
            let mut r = json!({"shape": "rectangular", "length_cm": 12, "width_cm": 6});
            r[field] = json!(v);
            r
        };
        let crescent = |v: f64| json!({"shape": "crescent", "length_cm": 12, "width_cm": 4, "bend_radius_cm": v});
        let weeks = |h: f64| json!({"expand_weeks": 3, "growth_step_h": h});
        // (field, kind, just outside, just inside)
        let cases = [
            (
                "max_steps",
                ErrorKind::Parameters,
                json!({"max_steps": MAX_STEPS + 1}),
                json!({"max_steps": MAX_STEPS}),
            ),
            (
                "max_steps",
                ErrorKind::Parameters,
                json!({"max_steps": 1_000_000_000_000u64}),
                json!({"max_steps": 1}),
            ),
            (
                "max_steps",
                ErrorKind::Parameters,
                json!({"max_steps": 0}),
                json!({"max_steps": 20_000}),
            ),
            (
                "volume_cm3",
                ErrorKind::Parameters,
                json!({"volume_cm3": 5000.01}),
                json!({"volume_cm3": MAX_VOLUME_CM3}),
            ),
            (
                "diameter_cm",
                ErrorKind::Parameters,
                json!({"diameter_cm": 100.01}),
                json!({"diameter_cm": MAX_LENGTH_CM}),
            ),
            (
                "length_cm",
                ErrorKind::Parameters,
                rect("length_cm", 100.01),
                rect("length_cm", 100.0),
            ),
            (
                "width_cm",
                ErrorKind::Parameters,
                rect("width_cm", 100.01),
                rect("width_cm", 100.0),
            ),
            (
                "corner_radius_cm",
                ErrorKind::Parameters,
                rect("corner_radius_cm", 100.01),
                rect("corner_radius_cm", 100.0),
            ),
            (
                "bend_radius_cm",
                ErrorKind::Parameters,
                crescent(100.01),
                crescent(100.0),
            ),
            (
                "region_radius_cm",
                ErrorKind::Placement,
                json!({"region_radius_cm": 100.01}),
                json!({"region_radius_cm": 100.0}),
            ),
            (
                "sim_edge_cm",
                ErrorKind::Parameters,
                json!({"sim_edge_cm": 100.01}),
                json!({"sim_edge_cm": 100.0}),
            ),
            (
                "max_hole_cm",
                ErrorKind::Parameters,
                json!({"max_hole_cm": 100.01}),
                json!({"max_hole_cm": 100.0}),
            ),
            (
                "depth_cm",
                ErrorKind::Parameters,
                json!({"depth_cm": 1e308}),
                json!({"depth_cm": MAX_DEPTH_CM}),
            ),
            (
                "depth_cm",
                ErrorKind::Parameters,
                json!({"depth_cm": 10.01}),
                json!({"depth_cm": 9.99}),
            ),
            (
                "thickness_cm",
                ErrorKind::Parameters,
                json!({"thickness_cm": 1e308}),
                json!({"thickness_cm": MAX_THICKNESS_CM}),
            ),
            (
                "thickness_cm",
                ErrorKind::Parameters,
                json!({"thickness_cm": 10.01}),
                json!({"thickness_cm": 9.99}),
            ),
            (
                "young_kpa",
                ErrorKind::Parameters,
                json!({"young_kpa": 100_000.1}),
                json!({"young_kpa": MAX_YOUNG_KPA}),
            ),
            (
                "density_g_cm3",
                ErrorKind::Parameters,
                json!({"density_g_cm3": 10.01}),
                json!({"density_g_cm3": MAX_DENSITY_G_CM3}),
            ),
            (
                "time_step_s",
                ErrorKind::Parameters,
                json!({"time_step_s": 0.0101}),
                json!({"time_step_s": MAX_TIME_STEP_S}),
            ),
            (
                "growth_step_h",
                ErrorKind::Parameters,
                weeks(0.99),
                weeks(MIN_GROWTH_STEP_H),
            ),
            (
                "implant_vertices",
                ErrorKind::Parameters,
                json!({"implant_vertices": 100_001}),
                json!({"implant_vertices": 100_000}),
            ),
            (
                "implant_vertices",
                ErrorKind::Parameters,
                json!({"implant_vertices": 49}),
                json!({"implant_vertices": 50}),
            ),
        ];
        for (field, kind, outside, inside) in cases {
            let e = request(outside.clone()).check().err();
            assert_eq!(
                e.as_ref().map(|e| (e.kind, e.field)),
                Some((kind, Some(field))),
                "{outside}: {e:?}"
            );
            let message = e.map(|e| e.message).unwrap_or_default();
            assert!(message.contains(&format!("`{field}`")), "{message}");
            assert!(
                request(inside.clone()).check().is_ok(),
                "{inside}: {:?}",
                request(inside.clone()).check()
            );
        }
    }

    #[test]
    fn sweeps_and_searches_are_bounded() {
        let field = |r: Result<(), PlanError>| r.err().map(|e| (e.kind, e.field));
        let refused = Some((ErrorKind::Parameters, Some("volumes_cm3")));
        assert_eq!(
            field(check_sweep(&vec![50.0; MAX_SWEEP_VOLUMES + 1])),
            refused
        );
        assert_eq!(field(check_sweep(&vec![50.0; 1_000_000])), refused);
        assert_eq!(field(check_sweep(&[50.0, 5000.5])), refused);
        assert_eq!(
            field(check_sweep(&vec![MAX_VOLUME_CM3; MAX_SWEEP_VOLUMES])),
            None
        );
        let bracket = Some((ErrorKind::Parameters, Some("bracket_cm3")));
        assert_eq!(
            field(check_search(30.0, Some((10.0, 5000.5)), 0.5, 100.0).map(|_| ())),
            bracket
        );
        assert_eq!(
            check_search(30.0, Some((10.0, 5000.0)), 0.5, 100.0).ok(),
            Some((10.0, 5000.0))
        );
        // The default bracket stays within the bound: a quarter to twice, at most 5000 cm³.
        assert_eq!(
            check_search(30.0, None, 0.5, 4000.0).ok(),
            Some((1000.0, 5000.0))
        );
        assert_eq!(
            check_search(30.0, None, 0.5, 100.0).ok(),
            Some((25.0, 200.0))
        );
    }
}
