//! The trainer's organ material as the page gives it (issue 32): the material scheme (a stable
//! neo-Hookean organ of Young's modulus, Poisson's ratio and density, tissue-scenes'
//! [`OrganMaterial`] turned into a session by [`SessionOptions::material`]) or the classic
//! realtime preset, kept for comparison. [`DEFAULT_SCHEME`] is the one place the trainer's
//! default is chosen; [`TissueMaterial::default_for`] the material an organ starts with.

use std::ops::RangeInclusive;

use serde::{Deserialize, Serialize};
use tissue_scenes::{
    MaterialField, OrganMaterial, SceneError, SessionOptions, ShippedOrgan, TissuePreset,
};

/// The scheme a trainer session is stepped with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// A physical organ: `E`, `ν`, `ρ`, 32 XPBD substeps ([`SessionOptions::material`]).
    Material,
    /// The classic realtime preset ([`SessionOptions::default`]): its stiffness is what the
    /// iterations leave.
    Realtime,
}

/// The scheme a session starts with until the page chooses a material. Measured by the browser
/// test in `.ci/run` on a clean clone (2 cores) on the bunny (39 706 tets): the material
/// scheme's step takes 29–33 ms (median), 26–31 steps per second; realtime 60 steps per
/// second. Realtime stays the default until the material scheme
/// reaches 60 steps per second (`docs/trainer.md`, "The trainer in the browser"); with
/// `Scheme::Material` here every check of the browser test passes too, at 17 steps per second.
pub const DEFAULT_SCHEME: Scheme = Scheme::Realtime;

/// The Young's moduli the studio takes (kPa): the softest preset (fat, 3.25 kPa) and skin
/// (200 kPa, in vivo up to 1 MPa) well inside; a softer organ collapses flat on its tray.
pub const YOUNG_KPA_BOUNDS: RangeInclusive<f64> = 0.5..=1000.0;

/// The densities the studio takes (g/cm³): fat (0.95) to bone (about 1.9).
pub const DENSITY_BOUNDS: RangeInclusive<f64> = 0.5..=2.0;

/// An organ's material as the socket's `material` command and `scene` message carry it:
/// `{"scheme": "material", "young_kpa": E, "poisson": ν, "density": ρ}` or
/// `{"scheme": "realtime"}`. The material scheme's relaxation time is tissue-scenes' default
/// ([`OrganMaterial::soft_organ`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "scheme", rename_all = "snake_case", deny_unknown_fields)]
pub enum TissueMaterial {
    /// The material scheme.
    Material {
        /// Young's modulus `E` (kPa).
        young_kpa: f64,
        /// Poisson's ratio `ν` (0 to 0.495).
        poisson: f64,
        /// Density `ρ` (g/cm³).
        density: f64,
    },
    /// The classic realtime preset (no material constants; a struct variant, so that members
    /// given with it are refused).
    Realtime {},
}

/// Why a material is refused: the field at fault (its JSON name) and why.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// Outside the studio's bounds ([`YOUNG_KPA_BOUNDS`], [`DENSITY_BOUNDS`]).
    #[error("{label} of {value} {unit} is outside the {min} to {max} {unit} the trainer takes")]
    Bounds {
        /// The field (`young_kpa`, `density`).
        field: &'static str,
        /// What the page calls it.
        label: &'static str,
        /// The value given.
        value: f64,
        /// The bounds.
        min: f64,
        /// The bounds.
        max: f64,
        /// The unit.
        unit: &'static str,
    },
    /// One of the three constants refused by tissue-scenes ([`SessionOptions::material`],
    /// [`SceneError::material_refusal`]), with the value as given (the solver's is an `f32`).
    #[error("{label} of {value}: expected {expected}")]
    Parameter {
        /// The field (`young_kpa`, `poisson`, `density`).
        field: &'static str,
        /// What the page calls it.
        label: &'static str,
        /// The value given.
        value: f64,
        /// The solver's range and advice.
        expected: &'static str,
    },
    /// Refused by tissue-scenes for another reason.
    #[error("{0}")]
    Scene(SceneError),
}

impl MaterialError {
    /// The field at fault (its JSON name), if one is.
    pub fn field(&self) -> Option<&'static str> {
        match self {
            MaterialError::Bounds { field, .. } | MaterialError::Parameter { field, .. } => {
                Some(field)
            }
            MaterialError::Scene(_) => None,
        }
    }

    /// tissue-scenes' refusal of `m`'s constants, naming the field when it is one of them.
    fn scene(source: SceneError, m: &OrganMaterial) -> MaterialError {
        let Some((f, expected)) = source.material_refusal() else {
            return MaterialError::Scene(source);
        };
        MaterialError::Parameter {
            field: f.name(),
            label: label(f),
            value: f.of(m),
            expected,
        }
    }
}

/// How the page labels a material field.
fn label(field: MaterialField) -> &'static str {
    match field {
        MaterialField::YoungKpa => "Young's modulus E",
        MaterialField::Poisson => "Poisson's ratio ν",
        MaterialField::Density => "density ρ",
        MaterialField::RelaxationTime => "relaxation time τ",
    }
}

/// A preset's name as the page shows it.
pub fn preset_label(t: TissuePreset) -> &'static str {
    match t {
        TissuePreset::Liver => "Liver",
        TissuePreset::Kidney => "Kidney (renal cortex)",
        TissuePreset::Bowel => "Bowel wall",
        TissuePreset::Fat => "Fat",
        TissuePreset::Skin => "Skin",
    }
}

impl TissueMaterial {
    /// A preset tissue in the material scheme.
    pub fn preset(t: TissuePreset) -> TissueMaterial {
        TissueMaterial::of(&OrganMaterial::preset(t))
    }

    /// tissue-scenes' material in the material scheme.
    pub fn of(m: &OrganMaterial) -> TissueMaterial {
        TissueMaterial::Material {
            young_kpa: m.elastic.young_kpa,
            poisson: m.elastic.poisson,
            density: m.elastic.density,
        }
    }

    /// The material an organ starts with in [`DEFAULT_SCHEME`]: a shipped organ's tissue
    /// ([`ShippedOrgan::tissue`]), an upload's [`OrganMaterial::soft_organ`].
    pub fn default_for(organ: Option<ShippedOrgan>) -> TissueMaterial {
        match DEFAULT_SCHEME {
            Scheme::Realtime => TissueMaterial::Realtime {},
            Scheme::Material => match organ {
                Some(o) => TissueMaterial::preset(o.tissue()),
                None => TissueMaterial::of(&OrganMaterial::soft_organ()),
            },
        }
    }

    /// Its scheme.
    pub fn scheme(&self) -> Scheme {
        match self {
            TissueMaterial::Material { .. } => Scheme::Material,
            TissueMaterial::Realtime {} => Scheme::Realtime,
        }
    }

    /// A session's settings: [`SessionOptions::material`] for the material scheme,
    /// [`SessionOptions::default`] for realtime.
    ///
    /// # Errors
    /// [`MaterialError`] naming the field: out of tissue-scenes' range (`E ≤ 0`, `ν` outside
    /// 0–0.495, `ρ ≤ 0`) or of the studio's bounds.
    pub fn options(&self) -> Result<SessionOptions, MaterialError> {
        let TissueMaterial::Material {
            young_kpa,
            poisson,
            density,
        } = *self
        else {
            return Ok(SessionOptions::default());
        };
        let mut organ = OrganMaterial::soft_organ();
        organ.elastic.young_kpa = young_kpa;
        organ.elastic.poisson = poisson;
        organ.elastic.density = density;
        let options =
            SessionOptions::material(&organ).map_err(|e| MaterialError::scene(e, &organ))?;
        within(MaterialField::YoungKpa, young_kpa, &YOUNG_KPA_BOUNDS, "kPa")?;
        within(MaterialField::Density, density, &DENSITY_BOUNDS, "g/cm³")?;
        Ok(options)
    }
}

fn within(
    field: MaterialField,
    value: f64,
    bounds: &RangeInclusive<f64>,
    unit: &'static str,
) -> Result<(), MaterialError> {
    if bounds.contains(&value) {
        return Ok(());
    }
    Err(MaterialError::Bounds {
        field: field.name(),
        label: label(field),
        value,
        min: *bounds.start(),
        max: *bounds.end(),
        unit,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The presets and tissue-scenes' default pass; each constant out of range is refused
    /// naming its field; the JSON is the documented one and unknown members are refused.
    #[test]
    fn materials_are_checked_field_by_field() {
        for t in TissuePreset::ALL {
            assert!(TissueMaterial::preset(t).options().is_ok(), "{t:?}");
        }
        assert!(TissueMaterial::Realtime {}.options().is_ok());
        let liver = TissueMaterial::preset(TissuePreset::Liver);
        let with = |e: f64, nu: f64, rho: f64| TissueMaterial::Material {
            young_kpa: e,
            poisson: nu,
            density: rho,
        };
        for (m, field) in [
            (with(0.0, 0.45, 1.0), "young_kpa"),
            (with(-3.0, 0.45, 1.0), "young_kpa"),
            (with(0.1, 0.45, 1.0), "young_kpa"),
            (with(5000.0, 0.45, 1.0), "young_kpa"),
            (with(10.0, 0.5, 1.0), "poisson"),
            (with(10.0, -0.1, 1.0), "poisson"),
            (with(10.0, 0.45, 0.0), "density"),
            (with(10.0, 0.45, 7.8), "density"),
        ] {
            let e = m.options().err().unwrap_or_else(|| panic!("{m:?} taken"));
            assert_eq!(e.field(), Some(field), "{m:?}: {e}");
        }
        let e = with(10.0, 0.6, 1.0).options().err().map(|e| e.to_string());
        assert!(
            e.as_deref()
                .is_some_and(|m| m.starts_with("Poisson's ratio ν of 0.6: expected in [0, 0.495]")),
            "{e:?}"
        );
        let v = serde_json::to_value(liver).unwrap();
        assert_eq!(
            v,
            serde_json::json!({"scheme": "material", "young_kpa": 5.4, "poisson": 0.49,
                "density": 1.06})
        );
        let r: TissueMaterial = serde_json::from_str(r#"{"scheme": "realtime"}"#).unwrap();
        assert_eq!(r, TissueMaterial::Realtime {});
        for bad in [
            r#"{"scheme": "material", "young_kpa": 5, "poisson": 0.4, "density": 1, "tau": 1}"#,
            r#"{"scheme": "material", "young_kpa": 5, "poisson": 0.4}"#,
            r#"{"scheme": "legacy"}"#,
            r#"{"scheme": "realtime", "young_kpa": 5}"#,
        ] {
            assert!(
                serde_json::from_str::<TissueMaterial>(bad).is_err(),
                "{bad}"
            );
        }
        assert_eq!(TissueMaterial::default_for(None).scheme(), DEFAULT_SCHEME);
    }
}
