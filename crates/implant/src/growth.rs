//! Skin growth under a tissue expander (expansion over weeks): the growth law, its calibrated parameters and
//! the fill protocol.
//!
//! ## The law (Han, Lee, …, Gosain, Buganza Tepole 2022, Acta Biomater 137:136)
//! Per skin triangle, the total area stretch `θ = A / A_scan` splits into growth and elastics,
//! `θ = θg · θe` (in-plane isotropic area growth, the thickness does not grow). With `t` in hours:
//!
//! `dθg/dt = a · (θ/θg − c)`, `a = k·θp`, while `θ > c·θg`; else `dθg/dt = 0` (no resorption),
//!
//! `k` the authors' rate (1/h), `θp` = 1.198 the in-vivo area prestretch, `θ` relative to the
//! scan (the in-vivo state). `c` is a threshold on the elastic area stretch: growth runs only
//! while `θe > c`, and stops at `θg = θ/c`. **Variant chosen**: the fitted, ungated law has
//! `c = 1` and is what the pig data are checked against ([`GrowthParams::pig`]); human skin
//! gets a calibrated threshold `c > 1` ([`GrowthParams::human`], docs/validation.md "Expansion
//! over weeks"). The gate of the authors' forward code (growth only while `θ/θg > 1.198`, with
//! the rate still `a·(θ/θg − 1)`) is discontinuous; the threshold form above is its continuous
//! counterpart (GROWTH.md §3).
//!
//! ## The update ([`GrowthLaw::step`])
//! Backward Euler over `Δt` at fixed `θ`: `u − θg,n = aΔt·(θ/u − c)`, i.e. the positive root of
//! `u² + (aΔt·c − θg,n)·u − aΔt·θ = 0`. It is stable for any `Δt`, monotone (never below
//! `θg,n`) and never overshoots `θ/c`. At constant `θ` with `c = 1` the exact solution is
//! `a·t = (u₀ − u) + θ·ln((θ − u₀)/(θ − u))` ([`GrowthLaw::exact_hours`]).
//!
//! ## The protocol ([`Protocol`])
//! Fills `(day, injected volume)`; a leakage fraction of every fill is lost (Zhang 2015:
//! 29 ± 12.5 % of the injected saline); the expander is removed on the removal day. Over-filling
//! past the nominal volume is allowed up to [`MAX_OVERFILL`].
//!
//! Units: days and hours as named, cm³.

use crate::ImplantError;
use crate::{Param, ProtocolField};

/// The most a protocol may inject beyond the expander's nominal volume, as a fraction of it:
/// a series ended at +41 % on average (Agrawal 2019) and over-filling is routine (Hallock 1995);
/// beyond doubling it, the expander's maker's limits are far exceeded.
pub const MAX_OVERFILL: f64 = 1.0;

/// The longest protocol accepted (days).
pub const MAX_PROTOCOL_DAYS: f64 = 365.0;

/// The growth law `dθg/dt = k·θp·(θ/θg − c)` (module docs). Units: hours.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrowthLaw {
    /// `k`, 1/h (isotropic median 0.045; ln k ~ N(−3.096, 0.230) from the authors' samples).
    pub rate: f64,
    /// `θp`, the in-vivo area prestretch (1.198 in pigs).
    pub prestretch: f64,
    /// `c ≥ 1`: growth runs only while the elastic area stretch `θ/θg` exceeds it.
    pub threshold: f64,
}

impl GrowthLaw {
    /// `a = k·θp` (1/h).
    pub fn rate_constant(&self) -> f64 {
        self.rate * self.prestretch
    }

    /// Checks the law's parameters.
    ///
    /// # Errors
    /// [`ImplantError::InvalidParameter`] naming the parameter.
    pub fn check(&self) -> Result<(), ImplantError> {
        let bad = |param: Param, value: f64, expected: &str| {
            Err(ImplantError::InvalidParameter {
                param,
                value,
                expected: expected.into(),
            })
        };
        if !(self.rate.is_finite() && self.rate >= 0.0) {
            return bad(
                Param::GrowthRate,
                self.rate,
                "finite and ≥ 0 (1/h; median 0.045)",
            );
        }
        if !(self.prestretch.is_finite() && self.prestretch > 0.0) {
            return bad(
                Param::Prestretch,
                self.prestretch,
                "positive and finite (area prestretch; 1.198 in pigs)",
            );
        }
        if !(self.threshold.is_finite() && (1.0..=4.0).contains(&self.threshold)) {
            return bad(
                Param::GrowthThreshold,
                self.threshold,
                "in [1, 4] (the elastic area stretch above which skin grows)",
            );
        }
        Ok(())
    }

    /// `θg` after `hours` at the total area stretch `theta`, from `theta_g` (backward Euler in
    /// closed form; module docs). Never less than `theta_g`.
    pub fn step(&self, theta_g: f64, theta: f64, hours: f64) -> f64 {
        let c = self.threshold;
        // Not above the threshold (or not a number): no growth.
        let above = theta.partial_cmp(&(c * theta_g)) == Some(std::cmp::Ordering::Greater);
        if !above || hours <= 0.0 {
            return theta_g;
        }
        let adt = self.rate_constant() * hours;
        // u² + b·u − q = 0, q > 0: the positive root, written without cancellation.
        let b = adt * c - theta_g;
        let q = adt * theta;
        let root = (b * b + 4.0 * q).sqrt();
        let u = if b <= 0.0 {
            0.5 * (root - b)
        } else {
            2.0 * q / (b + root)
        };
        u.clamp(theta_g, theta / c)
    }

    /// Hours the ungated law (`c = 1`) takes from `u0` to `u` at the constant stretch `theta`
    /// (`u0 ≤ u < theta`): `a·t = (u₀ − u) + θ·ln((θ − u₀)/(θ − u))`. For tests.
    pub fn exact_hours(&self, u0: f64, u: f64, theta: f64) -> f64 {
        ((u0 - u) + theta * ((theta - u0) / (theta - u)).ln()) / self.rate_constant()
    }
}

/// Everything growth needs besides the mechanics and the protocol: one set for every human case
/// ([`GrowthParams::human`], the default), one for the pig data ([`GrowthParams::pig`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrowthParams {
    /// The law.
    pub law: GrowthLaw,
    /// The growth time step (hours, in (0, 24]): the mechanics re-settle after each, so at least
    /// daily.
    pub step_hours: f64,
    /// The area factor a flap loses when it is raised off the expander's capsule at removal,
    /// ≥ 1: expanded skin explanted retracts to 0.83 × 0.83 (Buganza Tepole 2015, BMMB 14:1007:
    /// area 1/0.689 = 1.45); the flap relaxes to its grown area divided by this.
    pub flap_release: f64,
    /// The skin's stiffness as a factor of `LayerParams::young` (1; the band samples
    /// U(0.9, 1.1), the authors' design grid).
    pub stiffness: f64,
}

/// The human growth threshold `c_h`, calibrated once (docs/validation.md, "Expansion over
/// weeks") so that the 10-week round protocol retracts by the clinical 30–32 % at removal.
pub const HUMAN_THRESHOLD: f64 = 1.5;

/// The stated uncertainty of [`HUMAN_THRESHOLD`] (± this, uniform in the band).
pub const HUMAN_THRESHOLD_SPREAD: f64 = 0.1;

/// The isotropic median rate `k` (1/h) and the lognormal `ln k ~ N(μ, σ)` of the authors'
/// posterior samples (GROWTH.md §2).
pub const RATE_MEDIAN: f64 = 0.045;
/// `μ` of `ln k`.
pub const LN_RATE_MEAN: f64 = -3.096;
/// `σ` of `ln k`.
pub const LN_RATE_SD: f64 = 0.230;
/// The pig's in-vivo area prestretch `θp` (Han 2022).
pub const PIG_PRESTRETCH: f64 = 1.198;
/// The mean in-vivo leakage of injected saline (Zhang 2015, 17 cases): 29 ± 12.5 %.
pub const LEAKAGE_MEAN: f64 = 0.29;
/// Its standard deviation.
pub const LEAKAGE_SD: f64 = 0.125;
/// The explanted expanded skin's area retraction (Buganza Tepole 2015: 0.83 × 0.83).
pub const FLAP_RELEASE: f64 = 1.0 / (0.83 * 0.83);

impl GrowthParams {
    /// Human skin: the authors' median rate and prestretch with the calibrated threshold
    /// [`HUMAN_THRESHOLD`], daily steps, the explant retraction [`FLAP_RELEASE`].
    pub fn human() -> Self {
        GrowthParams {
            law: GrowthLaw {
                rate: RATE_MEDIAN,
                prestretch: PIG_PRESTRETCH,
                threshold: HUMAN_THRESHOLD,
            },
            step_hours: 24.0,
            flap_release: FLAP_RELEASE,
            stiffness: 1.0,
        }
    }

    /// Pig skin as the authors fitted it: the ungated law (`c = 1`), median rate.
    pub fn pig() -> Self {
        GrowthParams {
            law: GrowthLaw {
                threshold: 1.0,
                ..GrowthParams::human().law
            },
            ..GrowthParams::human()
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`ImplantError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<(), ImplantError> {
        self.law.check()?;
        if !(self.step_hours.is_finite() && self.step_hours > 0.0 && self.step_hours <= 24.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::GrowthStep,
                value: self.step_hours,
                expected: "in (0, 24] hours: the mechanics re-settle at least daily".into(),
            });
        }
        if !(self.flap_release.is_finite() && self.flap_release >= 1.0) {
            return Err(ImplantError::InvalidParameter {
                param: Param::FlapRelease,
                value: self.flap_release,
                expected: "finite and ≥ 1 (an area factor)".into(),
            });
        }
        if !(self.stiffness.is_finite() && (0.5..=2.0).contains(&self.stiffness)) {
            return Err(ImplantError::InvalidParameter {
                param: Param::Stiffness,
                value: self.stiffness,
                expected: "in [0.5, 2] (a factor of the skin's modulus)".into(),
            });
        }
        Ok(())
    }
}

impl Default for GrowthParams {
    /// [`GrowthParams::human`].
    fn default() -> Self {
        GrowthParams::human()
    }
}

/// One fill: on `day`, `volume` cm³ injected.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fill {
    /// Day of the fill (day 0: the first fill).
    pub day: f64,
    /// Saline injected, cm³.
    pub volume: f64,
}

/// A fill schedule ([`Protocol::weekly`] builds the usual one; [`Protocol::validate`] checks any).
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    /// The fills, by increasing day.
    pub fills: Vec<Fill>,
    /// The day the expander is removed (at or after the last fill).
    pub removal_day: f64,
    /// The fraction of every fill that leaks away, in [0, 0.9].
    pub leakage: f64,
    /// The expander's nominal volume (cm³): the geometric gain is the dome's at the injected
    /// total, and the injected total may exceed this by at most [`MAX_OVERFILL`].
    pub nominal_volume: f64,
}

fn invalid(field: ProtocolField, problem: String) -> ImplantError {
    ImplantError::InvalidProtocol { field, problem }
}

impl Protocol {
    /// Equal weekly fills: `weeks` fills, on days 0, 7, …, injecting `volume × (1 + overfill)`
    /// in all, then a hold of `hold_weeks` before removal, `leakage` of every fill lost. The
    /// nominal volume is `volume`.
    ///
    /// # Errors
    /// [`ImplantError::InvalidProtocol`] as [`Protocol::validate`], and for `weeks` not in
    /// 1..=52 or a negative or non-finite hold.
    pub fn weekly(
        volume: f64,
        weeks: u32,
        hold_weeks: f64,
        leakage: f64,
        overfill: f64,
    ) -> Result<Protocol, ImplantError> {
        if !(1..=52).contains(&weeks) {
            return Err(invalid(
                ProtocolField::ExpandWeeks,
                format!("{weeks} weeks: give 1 to 52 weeks of fills (usually 8–12)"),
            ));
        }
        if !(hold_weeks.is_finite() && hold_weeks >= 0.0) {
            return Err(invalid(
                ProtocolField::HoldWeeks,
                format!("{hold_weeks}: give a hold of 0 or more weeks (usually 1)"),
            ));
        }
        if !(overfill.is_finite() && (0.0..=MAX_OVERFILL).contains(&overfill)) {
            return Err(invalid(
                ProtocolField::Overfill,
                format!(
                    "{overfill}: give a fraction of the nominal volume in [0, {MAX_OVERFILL}] \
                     (0.41 is the +41 % of a clinical series)"
                ),
            ));
        }
        let each = volume * (1.0 + overfill) / f64::from(weeks);
        let fills = (0..weeks)
            .map(|w| Fill {
                day: 7.0 * f64::from(w),
                volume: each,
            })
            .collect();
        let protocol = Protocol {
            fills,
            removal_day: 7.0 * (f64::from(weeks - 1) + hold_weeks),
            leakage,
            nominal_volume: volume,
        };
        protocol.validate()?;
        Ok(protocol)
    }

    /// Checks the schedule: at least one fill; days finite, ≥ 0 and strictly increasing;
    /// volumes positive; removal at or after the last fill and within [`MAX_PROTOCOL_DAYS`];
    /// leakage in [0, 0.9]; the injected total at most `(1 + MAX_OVERFILL)` × nominal.
    ///
    /// # Errors
    /// [`ImplantError::InvalidProtocol`] naming the field and how to fix it.
    pub fn validate(&self) -> Result<(), ImplantError> {
        if !(self.nominal_volume.is_finite() && self.nominal_volume > 0.0) {
            return Err(invalid(
                ProtocolField::Volume,
                format!(
                    "{} cm³: the expander's nominal volume must be positive",
                    self.nominal_volume
                ),
            ));
        }
        if self.fills.is_empty() {
            return Err(invalid(
                ProtocolField::Fills,
                "no fill: give at least one (day, volume)".into(),
            ));
        }
        let mut last = -1.0;
        for (i, f) in self.fills.iter().enumerate() {
            if !(f.day.is_finite() && f.day >= 0.0) {
                return Err(invalid(
                    ProtocolField::Fills,
                    format!("fill {i} is on day {}: days are finite and ≥ 0", f.day),
                ));
            }
            if f.day <= last {
                return Err(invalid(
                    ProtocolField::Fills,
                    format!(
                        "fill {i} on day {} is not after the fill before it (day {last}): give \
                         the fills in order, one per day at most",
                        f.day
                    ),
                ));
            }
            if !(f.volume.is_finite() && f.volume > 0.0) {
                return Err(invalid(
                    ProtocolField::Fills,
                    format!("fill {i} injects {} cm³: give a positive volume", f.volume),
                ));
            }
            last = f.day;
        }
        if !(self.removal_day.is_finite() && self.removal_day >= last) {
            return Err(invalid(
                ProtocolField::HoldWeeks,
                format!(
                    "removal on day {} is before the last fill (day {last})",
                    self.removal_day
                ),
            ));
        }
        if self.removal_day > MAX_PROTOCOL_DAYS {
            return Err(invalid(
                ProtocolField::ExpandWeeks,
                format!(
                    "the expander would stay {} days: at most {MAX_PROTOCOL_DAYS} are simulated",
                    self.removal_day
                ),
            ));
        }
        if !(self.leakage.is_finite() && (0.0..=0.9).contains(&self.leakage)) {
            return Err(invalid(
                ProtocolField::Leakage,
                format!(
                    "{}: give the fraction of each fill that leaks, in [0, 0.9] (in vivo about \
                     0.29)",
                    self.leakage
                ),
            ));
        }
        let injected = self.injected_total();
        let most = (1.0 + MAX_OVERFILL) * self.nominal_volume;
        if injected > most * (1.0 + 1e-9) {
            return Err(invalid(
                ProtocolField::Overfill,
                format!(
                    "{injected:.1} cm³ injected into a {:.1} cm³ expander: at most {most:.1} \
                     (+{:.0} %); lower the fills or the over-fill",
                    self.nominal_volume,
                    100.0 * MAX_OVERFILL
                ),
            ));
        }
        Ok(())
    }

    /// The saline injected in all (cm³).
    pub fn injected_total(&self) -> f64 {
        self.fills.iter().map(|f| f.volume).sum()
    }

    /// The saline injected up to and including `day` (cm³).
    pub fn injected_by(&self, day: f64) -> f64 {
        self.fills
            .iter()
            .filter(|f| f.day <= day)
            .map(|f| f.volume)
            .sum()
    }

    /// The expander's volume after `day`'s fills with `leakage` lost (cm³).
    pub fn volume_by(&self, day: f64, leakage: f64) -> f64 {
        self.injected_by(day) * (1.0 - leakage)
    }

    /// The first fill's day.
    pub fn start_day(&self) -> f64 {
        self.fills.first().map_or(0.0, |f| f.day)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_update_matches_the_exact_solution_at_constant_stretch() {
        let law = GrowthParams::pig().law;
        let (theta, u0) = (1.3, 1.0);
        // Integrate with small steps and compare the time to reach each value.
        let mut u = u0;
        let h = 0.001;
        let mut t = 0.0;
        while t < 100.0 {
            u = law.step(u, theta, h);
            t += h;
        }
        let exact = law.exact_hours(u0, u, theta);
        assert!((exact - t).abs() / t < 2e-3, "{exact} vs {t}");
    }

    #[test]
    fn the_update_never_overshoots_nor_resorbs() {
        let law = GrowthParams::human().law;
        for &dt in &[0.1, 1.0, 24.0, 1e6] {
            let u = law.step(1.1, 2.0, dt);
            assert!(u >= 1.1 && u <= 2.0 / law.threshold + 1e-12, "{u}");
        }
        assert_eq!(law.step(1.5, 1.2, 24.0), 1.5);
    }

    #[test]
    fn bad_protocols_say_what_to_fix() {
        assert!(Protocol::weekly(100.0, 0, 1.0, 0.29, 0.0).is_err());
        assert!(Protocol::weekly(100.0, 10, -1.0, 0.29, 0.0).is_err());
        assert!(Protocol::weekly(100.0, 10, 1.0, 0.95, 0.0).is_err());
        assert!(Protocol::weekly(100.0, 10, 1.0, 0.29, 1.5).is_err());
        let mut p = Protocol::weekly(100.0, 10, 1.0, 0.29, 0.0).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.removal_day, 70.0);
        p.fills.swap(1, 2);
        let e = p
            .validate()
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("not after"), "{e}");
    }
}
