//! The organ's material (issue 32): the material scheme's physical organ (Young's modulus,
//! Poisson's ratio, density, relaxation time) or the real-time preset, as a C struct filled by
//! the caller, its presets, and its one way into a session: tissue-scenes'
//! `SessionOptions::material`, which checks it (the messages here only say which field of
//! `tissue_material` the refused parameter is).

use tissue_scenes::{
    OrganMaterial, SceneError, SelfCollision, SessionOptions, ShippedOrgan, TissuePreset,
};

use crate::ffi::{guard, put, status_of, tissue_status, Error};

/// How a body is simulated (`tissue_material.scheme`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_scheme {
    /// The material scheme: a stable neo-Hookean organ of the struct's Young's modulus,
    /// Poisson's ratio and density, its damping of the struct's relaxation time, in 10 ms steps
    /// of 32 XPBD substeps (tissue-pbd's `Material::elastic` and `StepSettings::material`;
    /// `docs/trainer.md`, "The material scheme"). 0, so that a zeroed struct is refused (a
    /// modulus of 0) rather than silently taken for the real-time preset.
    TISSUE_SCHEME_MATERIAL = 0,
    /// The real-time preset `tissue_body_new` uses: soft tissue held by distance and volume
    /// constraints, 10 ms steps of 9 substeps. It has no physical parameters: the struct's
    /// other fields are not used (a body reports 0 for the modulus and the ratio, its density,
    /// and the relaxation time of its damping).
    TISSUE_SCHEME_REALTIME = 1,
}

/// The scheme of a C value.
fn scheme_of(value: u32) -> Result<tissue_scheme, Error> {
    Ok(match value {
        0 => tissue_scheme::TISSUE_SCHEME_MATERIAL,
        1 => tissue_scheme::TISSUE_SCHEME_REALTIME,
        _ => {
            return Err(Error::invalid(format!(
                "`material->scheme` {value} is not a tissue_scheme (0 material, 1 realtime)"
            )))
        }
    })
}

/// A preset tissue (`tissue_material_preset`): Young's modulus, Poisson's ratio and density
/// from the literature (tissue-scenes' `TissuePreset`; `docs/materials.md`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_preset {
    /// Liver parenchyma.
    TISSUE_PRESET_LIVER = 0,
    /// Kidney.
    TISSUE_PRESET_KIDNEY = 1,
    /// Bowel wall.
    TISSUE_PRESET_BOWEL = 2,
    /// Fat.
    TISSUE_PRESET_FAT = 3,
    /// Skin.
    TISSUE_PRESET_SKIN = 4,
}

impl From<TissuePreset> for tissue_preset {
    /// Every preset of tissue-scenes to its own C value, in one exhaustive match (a new preset
    /// is a compile error here until the header has its value).
    fn from(tissue: TissuePreset) -> Self {
        use tissue_preset::*;
        match tissue {
            TissuePreset::Liver => TISSUE_PRESET_LIVER,
            TissuePreset::Kidney => TISSUE_PRESET_KIDNEY,
            TissuePreset::Bowel => TISSUE_PRESET_BOWEL,
            TissuePreset::Fat => TISSUE_PRESET_FAT,
            TissuePreset::Skin => TISSUE_PRESET_SKIN,
        }
    }
}

/// The preset of a C value.
pub(crate) fn preset_of(value: u32) -> Result<TissuePreset, Error> {
    Ok(match value {
        0 => TissuePreset::Liver,
        1 => TissuePreset::Kidney,
        2 => TissuePreset::Bowel,
        3 => TissuePreset::Fat,
        4 => TissuePreset::Skin,
        _ => {
            return Err(Error::invalid(format!(
                "`tissue` {value} is not a tissue_preset (0 liver, 1 kidney, 2 bowel, 3 fat, \
                 4 skin)"
            )))
        }
    })
}

/// The shipped organ of a C value (a `tissue_shipped_organ`).
pub(crate) fn shipped_of(value: u32) -> Result<ShippedOrgan, Error> {
    Ok(match value {
        0 => ShippedOrgan::Bunny,
        1 => ShippedOrgan::Liver,
        2 => ShippedOrgan::Appendix,
        o => {
            return Err(Error::invalid(format!(
                "`organ` {o} is not a tissue_shipped_organ (0 bunny, 1 liver, 2 appendix)"
            )))
        }
    })
}

/// A body's material. Fill it with `tissue_material_default`, `tissue_material_preset` or
/// `tissue_material_shipped`, then change what you need; `tissue_body_get_material` reads back
/// the one in force.
///
/// Bounds (checked when a body is made, `TISSUE_PARAMETERS` with a message naming the field):
/// `young_kpa` positive, `poisson` from 0 to 0.495, `density` positive, `relaxation_time`
/// positive, all finite.
///
/// `self_collision` (issue 35, appended last) is the body's setting whatever the scheme: the
/// fill functions set it to `true` (on by default, as in the trainer, the studio and Python:
/// tissue-scenes' default); a struct zeroed by hand has it off.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct tissue_material {
    /// A `tissue_scheme`.
    pub scheme: u32,
    /// Young's modulus `E`, kPa (soft organs 1–20, skin about 200).
    pub young_kpa: f64,
    /// Poisson's ratio `ν`, 0 to 0.495 (tissue: 0.45–0.49).
    pub poisson: f64,
    /// Density `ρ`, g/cm³.
    pub density: f64,
    /// The damping's relaxation time `τ`, s: every motion relative to the organ's rigid motion
    /// decays as `exp(−t/τ)` (0.1 s damps a wobble in a few tenths of a second).
    pub relaxation_time: f64,
    /// Self-collision of the organ's surface, cut walls included (tissue-scenes'
    /// `SessionOptions::self_collision`): `true` (what the fill functions give: the default)
    /// keeps the tissue from passing through itself, `false` leaves it off, for comparison (a
    /// step costs about half as much: docs/trainer.md); `tissue_body_set_self_collision`
    /// switches it off or on in a live body.
    pub self_collision: bool,
}

impl From<&OrganMaterial> for tissue_material {
    fn from(m: &OrganMaterial) -> Self {
        tissue_material {
            scheme: tissue_scheme::TISSUE_SCHEME_MATERIAL as u32,
            young_kpa: m.elastic.young_kpa,
            poisson: m.elastic.poisson,
            density: m.elastic.density,
            relaxation_time: f64::from(m.relaxation_time),
            self_collision: SessionOptions::default().self_collision.is_some(),
        }
    }
}

impl tissue_material {
    /// tissue-scenes' organ material of the struct's fields (unchecked: the session checks).
    fn organ(&self) -> OrganMaterial {
        let mut m = OrganMaterial::soft_organ();
        m.elastic.young_kpa = self.young_kpa;
        m.elastic.poisson = self.poisson;
        m.elastic.density = self.density;
        m.relaxation_time = self.relaxation_time as f32;
        m
    }

    /// The session's settings for this material, through `SessionOptions::material` (the one
    /// check of the values), and the material as the body reports it (`None`: the real-time
    /// preset, reported from its body).
    pub(crate) fn session_options(&self) -> Result<(SessionOptions, Option<Self>), Error> {
        let (mut options, material) = match scheme_of(self.scheme)? {
            tissue_scheme::TISSUE_SCHEME_MATERIAL => {
                let organ = self.organ();
                let options = SessionOptions::material(&organ).map_err(|e| refused(&e))?;
                let material = tissue_material {
                    self_collision: self.self_collision,
                    ..tissue_material::from(&organ)
                };
                (options, Some(material))
            }
            tissue_scheme::TISSUE_SCHEME_REALTIME => (SessionOptions::default(), None),
        };
        options.self_collision = self.self_collision.then(SelfCollision::default);
        Ok((options, material))
    }
}

/// A material the session refused: `TISSUE_PARAMETERS`, the message led by the field of
/// `tissue_material` it is about.
fn refused(e: &SceneError) -> Error {
    let field = e.material_field().map(|f| f.name());
    let status = match e.kind() {
        tissue_scenes::SceneErrorKind::Parameters => tissue_status::TISSUE_PARAMETERS,
        kind => status_of(kind),
    };
    match field {
        Some(field) => Error::new(status, format!("`material->{field}`: {e}")),
        None => Error::new(status, format!("the material: {e}")),
    }
}

/// Fills `material` with the material scheme's default organ: 10 kPa, `ν = 0.45`,
/// 1.05 g/cm³, `τ = 0.1 s` (soft parenchyma; tissue-scenes' `OrganMaterial::soft_organ`).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_material_default(material: *mut tissue_material) -> tissue_status {
    guard(|| {
        let m = tissue_material::from(&OrganMaterial::soft_organ());
        // SAFETY: `material` is NULL or valid.
        unsafe { put(material, "material", m) }
    })
}

/// Fills `material` with a preset tissue's (a `tissue_preset`) Young's modulus, Poisson's ratio
/// and density in the material scheme, with the default relaxation time (0.1 s).
///
/// Errors: `TISSUE_INVALID_ARGUMENT` for a value that is not a `tissue_preset`.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_material_preset(
    tissue: u32,
    material: *mut tissue_material,
) -> tissue_status {
    guard(|| {
        let m = tissue_material::from(&OrganMaterial::preset(preset_of(tissue)?));
        // SAFETY: `material` is NULL or valid.
        unsafe { put(material, "material", m) }
    })
}

/// Fills `material` with the preset of a shipped organ's (a `tissue_shipped_organ`) tissue in
/// the material scheme: liver for the bunny and the liver, bowel for the appendix.
///
/// Errors: `TISSUE_INVALID_ARGUMENT` for a value that is not a `tissue_shipped_organ`.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_material_shipped(
    organ: u32,
    material: *mut tissue_material,
) -> tissue_status {
    guard(|| {
        let m = tissue_material::from(&OrganMaterial::preset(shipped_of(organ)?.tissue()));
        // SAFETY: `material` is NULL or valid.
        unsafe { put(material, "material", m) }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every preset of tissue-scenes has its own C value, and that value gives it back.
    #[test]
    fn every_preset_has_its_own_c_value() {
        for tissue in TissuePreset::ALL {
            let c = tissue_preset::from(tissue) as u32;
            assert_eq!(preset_of(c).ok(), Some(tissue), "{}", tissue.id());
        }
        assert!(preset_of(TissuePreset::ALL.len() as u32).is_err());
        for organ in ShippedOrgan::ALL {
            assert_eq!(shipped_of(tissue_shipped_organ_of(organ)).ok(), Some(organ));
        }
    }

    fn tissue_shipped_organ_of(organ: ShippedOrgan) -> u32 {
        use crate::trainer::tissue_shipped_organ::*;
        (match organ {
            ShippedOrgan::Bunny => TISSUE_ORGAN_BUNNY,
            ShippedOrgan::Liver => TISSUE_ORGAN_LIVER,
            ShippedOrgan::Appendix => TISSUE_ORGAN_APPENDIX,
        }) as u32
    }

    /// A refused value is `TISSUE_PARAMETERS` naming the struct's field; a bad scheme is an
    /// invalid argument.
    #[test]
    fn a_bad_value_is_refused_naming_its_field() {
        let ok = tissue_material::from(&OrganMaterial::soft_organ());
        for (bad, field) in [
            (
                tissue_material {
                    young_kpa: -1.0,
                    ..ok
                },
                "young_kpa",
            ),
            (tissue_material { poisson: 0.5, ..ok }, "poisson"),
            (tissue_material { density: 0.0, ..ok }, "density"),
            (
                tissue_material {
                    relaxation_time: f64::NAN,
                    ..ok
                },
                "relaxation_time",
            ),
        ] {
            let e = bad.session_options().unwrap_err();
            assert_eq!(e.status, tissue_status::TISSUE_PARAMETERS, "{}", e.message);
            assert!(
                e.message.starts_with(&format!("`material->{field}`")),
                "{}",
                e.message
            );
        }
        let e = tissue_material { scheme: 2, ..ok }
            .session_options()
            .unwrap_err();
        assert_eq!(e.status, tissue_status::TISSUE_INVALID_ARGUMENT);
        let (_, reported) = ok.session_options().unwrap();
        assert_eq!(reported, Some(ok));
    }
}
