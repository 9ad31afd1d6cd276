//! Tissue presets: Young's modulus, Poisson's ratio and density of the tissues a trainer's
//! organs stand for, from the literature (`docs/materials.md` has the sources and what each
//! figure was measured as).
//!
//! The moduli are small-strain, quasi-static values: a trainee presses and drags slowly next
//! to a shear wave's 50–500 Hz, at which elastography measures moduli two to three times
//! higher. Where a source gives a shear modulus `G` of a nearly incompressible tissue, the
//! Young's modulus is `E = 2G(1 + ν) ≈ 3G`. The Poisson ratio of 0.49 stands for
//! incompressible tissue (water-filled; 0.5 exactly has no finite bulk modulus).

use tissue_fem::ElasticMaterial;

use crate::ShippedOrgan;

/// A tissue with its material constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TissuePreset {
    /// Healthy liver: `G` = 1.8 kPa (acoustic radiation force, quasi-static), ρ = 1.06.
    Liver,
    /// Renal cortex: `G` = 1.81 kPa (ex vivo porcine, shear wave dispersion), ρ = 1.05.
    Kidney,
    /// Small bowel wall (terminal ileum): `E` = 3.84 kPa (shear wave elastography, 139
    /// volunteers), ρ = 1.04.
    Bowel,
    /// Fat: `E` = 3.25 kPa (breast fat, ex vivo indentation, small strain), ρ = 0.95.
    Fat,
    /// Skin: `E` = 200 kPa (in vivo, small strain: 0.1–1 MPa), ν = 0.45, ρ = 1.09 — the
    /// planner's skin.
    Skin,
}

impl TissuePreset {
    /// Every preset.
    pub const ALL: [TissuePreset; 5] = [
        TissuePreset::Liver,
        TissuePreset::Kidney,
        TissuePreset::Bowel,
        TissuePreset::Fat,
        TissuePreset::Skin,
    ];

    /// Its short name (`--tissue liver`).
    pub fn id(self) -> &'static str {
        match self {
            TissuePreset::Liver => "liver",
            TissuePreset::Kidney => "kidney",
            TissuePreset::Bowel => "bowel",
            TissuePreset::Fat => "fat",
            TissuePreset::Skin => "skin",
        }
    }

    /// The preset of `id`.
    pub fn from_id(id: &str) -> Option<TissuePreset> {
        TissuePreset::ALL.into_iter().find(|t| t.id() == id)
    }

    /// Young's modulus (kPa).
    pub fn young_kpa(self) -> f64 {
        match self {
            TissuePreset::Liver => 5.4,
            TissuePreset::Kidney => 5.4,
            TissuePreset::Bowel => 3.84,
            TissuePreset::Fat => 3.25,
            TissuePreset::Skin => 200.0,
        }
    }

    /// Poisson's ratio.
    pub fn poisson(self) -> f64 {
        match self {
            TissuePreset::Skin => 0.45,
            _ => 0.49,
        }
    }

    /// Density (g/cm³).
    pub fn density(self) -> f64 {
        match self {
            TissuePreset::Liver => 1.06,
            TissuePreset::Kidney => 1.05,
            TissuePreset::Bowel => 1.04,
            TissuePreset::Fat => 0.95,
            TissuePreset::Skin => 1.09,
        }
    }

    /// The source of the modulus (author, year, what was measured).
    pub fn source(self) -> &'static str {
        match self {
            TissuePreset::Liver => {
                "healthy liver's shear modulus 1.8 ± 0.4 kPa under quasi-static conditions \
                 (Bamber & Hill 1981, Palmeri et al. 2008, as tabulated in Phys. Med. Biol. \
                 64:225001, 2019, Table 1); density 1 060 kg/m³ (same table)"
            }
            TissuePreset::Kidney => {
                "Amador et al. 2011, Ultrasound Med. Biol. (renal cortex shear elasticity \
                 1.81 ± 0.17 kPa, ex vivo porcine, SDUV); density 1 050 kg/m³ (Mech. Mater. \
                 44:174, 2012, Table 3)"
            }
            TissuePreset::Bowel => {
                "Zhao et al. 2021, Quant. Imaging Med. Surg. (terminal ileum wall, shear wave \
                 elastography, E = 3.84 ± 1.84 kPa)"
            }
            TissuePreset::Fat => {
                "Samani et al. 2007, Phys. Med. Biol. 52:1565 (breast fat at small strain, \
                 3.25 ± 0.91 kPa); density 950 kg/m³ (Mech. Mater. 44:174, 2012, Table 3)"
            }
            TissuePreset::Skin => {
                "Agache et al. 1980, Pailler-Mattei et al. 2008 (in vivo skin, 0.1–1 MPa at \
                 small strain); the planner's skin (docs/validation.md)"
            }
        }
    }

    /// The material of `tissue-fem` (its reference).
    pub fn material(self) -> ElasticMaterial {
        ElasticMaterial {
            young_kpa: self.young_kpa(),
            poisson: self.poisson(),
            density: self.density(),
        }
    }
}

impl ShippedOrgan {
    /// The tissue the organ stands for: the liver's, the appendix's bowel wall; the bunny, a
    /// demonstration solid, has liver's.
    pub fn tissue(self) -> TissuePreset {
        match self {
            ShippedOrgan::Bunny | ShippedOrgan::Liver => TissuePreset::Liver,
            ShippedOrgan::Appendix => TissuePreset::Bowel,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every preset is a material the reference takes, its id round-trips, and the moduli
    /// stand in the order the literature has them (skin far stiffer than the organs).
    #[test]
    fn presets_are_valid_materials() {
        for t in TissuePreset::ALL {
            assert!(t.material().validate().is_ok(), "{t:?}");
            assert_eq!(TissuePreset::from_id(t.id()), Some(t));
            assert!(!t.source().is_empty());
        }
        assert!(TissuePreset::Skin.young_kpa() > 10.0 * TissuePreset::Liver.young_kpa());
        assert_eq!(TissuePreset::from_id("bone"), None);
    }
}
