//! Settings of cuts and sutures.

use crate::SurgeryError;

/// How cuts and sutures behave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurgerySettings {
    /// Geometric cuts: snap nodes onto the blade's plane and split the crossed tets, so the
    /// walls lie on the plane (crate docs, "Cutting"). Off: the cut only separates existing tet
    /// faces (walls within one tet of the blade), which is what a body that moves relative to
    /// the blade during a cut needs today (see `docs/surgery.md`).
    pub split_tets: bool,
    /// With `split_tets`: the surface triangle where a sweep's polygon ends is split into 4 at
    /// the tip (the tip inside it, joined to its corners), where that meets the quality bound;
    /// off, or where it does not, into 5 with the tip on the crack line (see `docs/surgery.md`,
    /// "Tip split").
    pub four_way_tips: bool,
    /// PBD stiffness `k ∈ [0, 1]` of a suture link (1 = the linked nodes are pulled together
    /// fully each iteration).
    pub suture_stiffness: f32,
    /// XPBD compliance of a suture link (cm/dyn), used when the body's solver is XPBD.
    pub suture_compliance: f32,
    /// Rest length of a suture link (cm), `≥ 0`; near zero closes the wound.
    pub suture_rest_length: f32,
}

impl Default for SurgerySettings {
    /// Geometric cuts (`split_tets` and `four_way_tips` on), sutures with `k = 1`, compliance 0, rest length 0.
    fn default() -> Self {
        Self {
            split_tets: true,
            four_way_tips: true,
            suture_stiffness: 1.0,
            suture_compliance: 0.0,
            suture_rest_length: 0.0,
        }
    }
}

impl SurgerySettings {
    pub(crate) fn validate(&self) -> Result<(), SurgeryError> {
        let checks = [
            (
                "suture_stiffness",
                self.suture_stiffness,
                (0.0..=1.0).contains(&self.suture_stiffness),
                "in [0, 1]",
            ),
            (
                "suture_compliance",
                self.suture_compliance,
                self.suture_compliance.is_finite() && self.suture_compliance >= 0.0,
                "finite and ≥ 0",
            ),
            (
                "suture_rest_length",
                self.suture_rest_length,
                self.suture_rest_length.is_finite() && self.suture_rest_length >= 0.0,
                "finite and ≥ 0 (cm)",
            ),
        ];
        for (name, value, ok, expected) in checks {
            if !ok {
                return Err(SurgeryError::InvalidSetting {
                    name,
                    value: value as f64,
                    expected,
                });
            }
        }
        Ok(())
    }
}
