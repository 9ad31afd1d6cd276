//! How close a run is to its stop criterion, for progress bars.

use tissue_implant::{Implant, Insertion, RunParams};

/// Mirrors the library's stop test (`tissue_mss::SettleDetector`) on the per-step summed
/// displacements, as a number in `[0, 1]` instead of a yes/no:
///
/// - `0` while fewer than `window` steps have been seen;
/// - otherwise the larger of `(min / max) / (1 − tolerance)` (the ratio test: `1` when the
///   smallest and largest displacement sums of the last `window` steps agree within the
///   tolerance) and `floor / max` (the speed floor: `1` when every sum is below it), clamped to
///   `[0, 1]`; a window of zero displacement is `1`.
///
/// It is an indicator: the library also ignores the steps of the expander's fill, so the run can
/// end a little before or after the meter reaches 1.
#[derive(Debug, Clone)]
pub(crate) struct SettleMeter {
    sums: Vec<f64>,
    next: usize,
    filled: usize,
    tolerance: f64,
    floor: f64,
}

impl SettleMeter {
    /// A meter for the criterion of `params` (floor 0 until [`SettleMeter::with_floor`]).
    pub(crate) fn new(params: &RunParams) -> Self {
        SettleMeter {
            sums: vec![0.0; params.stop.window.max(1)],
            next: 0,
            filled: 0,
            tolerance: params.stop.tolerance,
            floor: 0.0,
        }
    }

    /// The same with the speed floor in cm of summed displacement per step.
    pub(crate) fn with_floor(self, floor: f64) -> Self {
        SettleMeter {
            floor: if floor.is_finite() {
                floor.max(0.0)
            } else {
                0.0
            },
            ..self
        }
    }

    /// Records one step's summed displacement and returns the meter.
    pub(crate) fn push(&mut self, displacement: f64) -> f64 {
        let len = self.sums.len();
        self.sums[self.next] = displacement;
        self.next = (self.next + 1) % len;
        self.filled = (self.filled + 1).min(len);
        if self.filled < len {
            return 0.0;
        }
        let (min, max) = self
            .sums
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), &s| {
                (lo.min(s), hi.max(s))
            });
        // `f64::max`/`min` skip NaN, so `max` is finite or infinite and at least 0.
        if max == 0.0 {
            // Nothing moved over the whole window: settled.
            return 1.0;
        }
        let keep = 1.0 - self.tolerance;
        let ratio = if keep > 0.0 { (min / max) / keep } else { 1.0 };
        let floor = self.floor / max;
        let value = ratio.max(floor);
        if value.is_finite() {
            value.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// The speed floor of an insertion's stop criterion, as the library derives it from
/// [`RunParams::settle_speed`] when it sets up the run: `settle_speed × moving particles × h`
/// (cm per step), the moving particles being the tissue's free ones and the implant's off its
/// base (the dome is held kinematically while it fills, so it is counted from the implant).
pub(crate) fn insertion_floor(insertion: &Insertion, implant: &Implant, params: &RunParams) -> f64 {
    let run = insertion.contact_run();
    let tissue = run
        .layers()
        .system()
        .particles()
        .inverse_masses()
        .iter()
        .filter(|&&w| w > 0.0)
        .count();
    let body = implant.mesh().vertex_count() - implant.base().len();
    params.settle_speed * (tissue + body) as f64 * f64::from(run.time_step())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meter_is_zero_until_the_window_fills_then_tracks_the_ratio() {
        let mut params = RunParams::default();
        params.stop.window = 4;
        params.stop.tolerance = 0.5;
        let mut meter = SettleMeter::new(&params);
        for _ in 0..3 {
            assert_eq!(meter.push(1.0), 0.0);
        }
        // min/max = 1 → ratio 2 → clamped to 1.
        assert_eq!(meter.push(1.0), 1.0);
        // window [1, 1, 1, 4]: min/max = 0.25 → 0.5.
        assert!((meter.push(4.0) - 0.5).abs() < 1e-12);
        // with a floor of 2: floor/max = 0.5 as well; a floor of 3 gives 0.75.
        let mut meter = meter.with_floor(3.0);
        for d in [1.0, 1.0, 1.0, 4.0] {
            meter.push(d);
        }
        assert!((meter.push(4.0) - 0.75).abs() < 1e-12);
    }
}
