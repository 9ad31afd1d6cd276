//! What a planner asks for: where the implant goes, the implant, the tissue, the simulation mesh
//! and the run, in one flat record whose JSON names carry their units. Every field has the
//! library's default, so `{}` is the Table 2 case.

use serde::{Deserialize, Serialize};
use tissue_app::SimMesh;
use tissue_collide::BroadPhase;
use tissue_implant::{ImplantShape, ImplantSpec, InsertionParams, LayerParams, ScanOptions};

use crate::error::{ErrorKind, PlanError};
use crate::units::{Detect, Rule, Shape, KPA};

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
    /// A run's step limit.
    pub max_steps: u64,
    /// The time step, s [default: automatic].
    pub time_step_s: Option<f32>,
    /// Expansion over weeks (issue 21): this many weekly fills to `volume_cm3`, with skin
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

impl PlanRequest {
    /// Checks the numbers a user types, naming the field: a size, volume or tissue value that
    /// cannot be right is refused before anything runs.
    ///
    /// # Errors
    /// [`ErrorKind::Parameters`] (or [`ErrorKind::Placement`] for the region radius) naming the
    /// field.
    pub fn check(&self) -> Result<(), PlanError> {
        positive("volume_cm3", self.volume_cm3, "cm³ (mL)")?;
        match self.shape {
            Shape::Round => positive("diameter_cm", f64::from(self.diameter_cm), "cm")?,
            Shape::Rectangular | Shape::Crescent => {
                for (field, value) in [
                    ("length_cm", self.length_cm),
                    ("width_cm", self.width_cm),
                    ("bend_radius_cm", self.bend_radius_cm),
                ] {
                    if let Some(v) = value {
                        positive(field, f64::from(v), "cm")?;
                    }
                }
            }
        }
        positive("depth_cm", self.depth_cm, "cm")?;
        positive("young_kpa", self.young_kpa, "kPa")?;
        positive("thickness_cm", self.thickness_cm, "cm")?;
        positive("density_g_cm3", self.density_g_cm3, "g/cm³")?;
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
        }
        if let Some(h) = self.sim_edge_cm {
            positive("sim_edge_cm", h, "cm")?;
        }
        if !(self.max_hole_cm.is_finite() && self.max_hole_cm >= 0.0) {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "max_hole_cm",
                format!(
                    "`max_hole_cm` must be a size ≥ 0 in cm, got {}",
                    self.max_hole_cm
                ),
            ));
        }
        if let Some(h) = self.time_step_s {
            positive("time_step_s", f64::from(h), "seconds")?;
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
                && self.growth_step_h > 0.0
                && self.growth_step_h <= 24.0)
            {
                return Err(PlanError::field(
                    ErrorKind::Parameters,
                    "growth_step_h",
                    format!(
                        "`growth_step_h` must be in (0, 24] hours (the skin re-settles at least \
                         daily), got {}",
                        self.growth_step_h
                    ),
                ));
            }
        }
        if self.max_steps == 0 {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "max_steps",
                "`max_steps` must be at least 1",
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
        let mut params = InsertionParams::default();
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

/// Checks the volumes of a sweep: at least one, each positive.
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
    for &v in volumes {
        if !(v.is_finite() && v > 0.0) {
            return Err(PlanError::field(
                ErrorKind::Parameters,
                "volumes_cm3",
                format!(
                    "every volume of `volumes_cm3` must be a positive number of cm³ (mL), got {v}"
                ),
            ));
        }
    }
    Ok(())
}

/// Checks a search for the volume of a target gain and gives its bracket (default: a quarter to
/// twice `volume_cm3`).
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
    let (low, high) = bracket_cm3.unwrap_or((0.25 * volume_cm3, 2.0 * volume_cm3));
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
}
