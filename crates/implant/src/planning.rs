//! Treatment planning over many simulations: parameter sweeps and the inverse question "which
//! implant volume gives a target area gain".
//!
//! Both are written over a closure that runs one simulation, so they do not depend on how the
//! simulation is set up:
//! - [`sweep`] runs a list of inputs in parallel (rayon) and returns the results in input order;
//! - [`volume_for_gain`] searches a volume bracket for the volume whose run gives a target area
//!   gain (a bracketing root search on `g(V) − target`: Brent's method, interpolation with a
//!   bisection fallback), within [`InverseOptions`]' tolerances and run budget, and reports every
//!   run it took ([`InverseSearch`], [`PlanningRun`]).
//!
//! Threads: the crate spawns none of its own. [`sweep`] uses rayon's global pool (created by rayon
//! on first use); install your own pool with `rayon::ThreadPool::install` to choose the thread
//! count. [`volume_for_gain`] is sequential: each run depends on the previous ones.
//!
//! Units: volumes in cm³, area gains in cm².
//!
//! ```
//! use tissue_implant::{sweep, volume_for_gain, InverseOptions};
//!
//! // An analytic stand-in for the simulation: the area gain grows as 0.3 cm²/cm³.
//! let gain = |volume: f64| Ok(0.3 * volume);
//!
//! // Which volume between 10 and 400 cm³ gives 30 cm² more skin?
//! let search = volume_for_gain(30.0, (10.0, 400.0), &InverseOptions::default(), gain)?;
//! assert!(search.converged);
//! assert!((search.gain - 30.0).abs() <= 0.5);
//! assert!((search.volume - 100.0).abs() <= 0.5 / 0.3);
//! assert!(search.runs.len() <= InverseOptions::default().max_runs);
//!
//! // The gains of three volumes, run in parallel, in input order.
//! let gains = sweep(&[100.0, 200.0, 300.0], |&volume: &f64| gain(volume));
//! assert_eq!(gains, vec![Ok(30.0), Ok(60.0), Ok(90.0)]);
//! # Ok::<(), tissue_implant::ImplantError>(())
//! ```

use rayon::prelude::*;

use crate::ImplantError;
use crate::Param;

/// Runs `run` on every input in parallel and returns the results in input order.
///
/// Each run is independent of the others, so the results do not depend on the number of threads
/// (as long as `run` itself is deterministic). A failed run does not stop the others: its error
/// is returned in its place.
///
/// The crate spawns no threads of its own: this uses rayon's global pool (created by rayon on
/// first use, one thread per core by default). To choose the threads, call it inside your own
/// pool: `pool.install(|| sweep(&inputs, run))` with a `rayon::ThreadPool`. A panic in `run` is
/// propagated to the caller once the other runs have finished.
pub fn sweep<I, R, F>(inputs: &[I], run: F) -> Vec<Result<R, ImplantError>>
where
    I: Sync,
    R: Send,
    F: Fn(&I) -> Result<R, ImplantError> + Sync,
{
    inputs.par_iter().map(&run).collect()
}

/// Stopping rules and run budget of [`volume_for_gain`].
#[derive(Debug, Clone, PartialEq)]
pub struct InverseOptions {
    /// Stop when a run's area gain is within this of the target, cm² (default 0.5). Positive and
    /// finite.
    pub gain_tolerance: f64,
    /// Stop when the volume bracket enclosing the target is at most this wide, cm³ (default
    /// 0.5). Positive and finite.
    pub volume_tolerance: f64,
    /// The most simulation runs to take, including the two bracket ends (default 12). At least 2.
    pub max_runs: usize,
}

impl Default for InverseOptions {
    /// Within 0.5 cm² of the target gain or a bracket of 0.5 cm³, at most 12 runs.
    fn default() -> Self {
        InverseOptions {
            gain_tolerance: 0.5,
            volume_tolerance: 0.5,
            max_runs: 12,
        }
    }
}

impl InverseOptions {
    fn check(&self) -> Result<(), ImplantError> {
        let positive = |param: Param, value: f64, unit: &str| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ImplantError::InvalidParameter {
                    param,
                    value,
                    expected: format!("positive and finite, in {unit}"),
                })
            }
        };
        positive(Param::GainTolerance, self.gain_tolerance, "cm²")?;
        positive(Param::VolumeTolerance, self.volume_tolerance, "cm³")?;
        if self.max_runs < 2 {
            return Err(ImplantError::InvalidParameter {
                param: Param::MaxRuns,
                value: self.max_runs as f64,
                expected: "at least 2 (the two bracket ends are run first)".into(),
            });
        }
        Ok(())
    }
}

/// One simulation run of an inverse search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanningRun {
    /// The implant volume run, cm³.
    pub volume: f64,
    /// The area gain it gave, cm².
    pub gain: f64,
}

/// The outcome of [`volume_for_gain`].
#[derive(Debug, Clone, PartialEq)]
pub struct InverseSearch {
    /// The volume found, cm³: the run that met the gain tolerance, or else the end of the final
    /// bracket whose gain is closer to the target (always one of [`runs`](Self::runs)).
    pub volume: f64,
    /// The area gain of that run, cm².
    pub gain: f64,
    /// Whether a stopping rule was met: the gain is within `gain_tolerance` of the target, or the
    /// bracket enclosing the target is at most `volume_tolerance` wide (so the target's volume is
    /// within `volume_tolerance` of `volume`). `false` when the run budget ran out first:
    /// `volume` is then the best estimate so far.
    pub converged: bool,
    /// Every run the search took, in order (the two bracket ends first): exactly the calls of the
    /// closure.
    pub runs: Vec<PlanningRun>,
}

/// A run seen by the search: its volume, gain and residual `gain − target`.
#[derive(Debug, Clone, Copy)]
struct Point {
    volume: f64,
    gain: f64,
    residual: f64,
}

impl Point {
    fn run(self) -> PlanningRun {
        PlanningRun {
            volume: self.volume,
            gain: self.gain,
        }
    }
}

/// Finds the implant volume whose run gives the area gain `target_gain` (cm²), searching between
/// the volumes `bracket = (low, high)` (cm³); `run(volume)` runs one simulation and returns its
/// area gain in cm².
///
/// A bracketing root search on `g(V) − target`:
/// 1. both ends are run first; if either gain is within `options.gain_tolerance` of the target,
///    that end is the answer; otherwise the two gains must lie on either side of the target;
/// 2. then Brent's method: secant or inverse quadratic interpolation through the last runs,
///    falling back to bisection whenever an interpolated step would leave the bracket or does not
///    shrink it fast enough (a step must be less than half the step before last), and stepping
///    at least `options.volume_tolerance / 2` so that the bracket closes on the target;
/// 3. it stops when a run's gain is within `options.gain_tolerance` of the target or the
///    bracket enclosing the target is at most `options.volume_tolerance` wide
///    ([`InverseSearch::converged`]), or when `options.max_runs` runs are spent (not converged).
///
/// Every run lies inside the bracket. The gain is expected to grow with the volume, but this is
/// not assumed: a decreasing gain works as well, since the bracket always encloses a sign change
/// of `g(V) − target` (for a gain that jumps across the target, the bracket closes on the jump).
/// Every run is reported in [`InverseSearch::runs`], in order.
///
/// # Errors
/// - [`ImplantError::InvalidParameter`] when `target_gain` is not finite, the bracket is not
///   `0 < low < high` with finite ends, `options` are not positive and finite (`max_runs` ≥ 2),
///   or a run returns a gain that is not finite ([`Param::Gain`]);
/// - [`ImplantError::TargetNotBracketed`] when the gains at the two ends are both above or both
///   below the target (by more than `gain_tolerance`), with both ends' volumes and gains;
/// - any error of `run`, unchanged (the search stops at the first).
pub fn volume_for_gain<F>(
    target_gain: f64,
    bracket: (f64, f64),
    options: &InverseOptions,
    mut run: F,
) -> Result<InverseSearch, ImplantError>
where
    F: FnMut(f64) -> Result<f64, ImplantError>,
{
    options.check()?;
    if !target_gain.is_finite() {
        return Err(ImplantError::InvalidParameter {
            param: Param::TargetGain,
            value: target_gain,
            expected: "a finite area gain in cm²".into(),
        });
    }
    let (low, high) = bracket;
    if !(low.is_finite() && low > 0.0) {
        return Err(ImplantError::InvalidParameter {
            param: Param::BracketLow,
            value: low,
            expected: "a positive, finite volume in cm³".into(),
        });
    }
    if !(high.is_finite() && high > low) {
        return Err(ImplantError::InvalidParameter {
            param: Param::BracketHigh,
            value: high,
            expected: format!("a finite volume in cm³ above the lower end {low}"),
        });
    }

    let mut runs: Vec<PlanningRun> = Vec::with_capacity(options.max_runs);
    // Runs one simulation and records it.
    let mut evaluate = |volume: f64, runs: &mut Vec<PlanningRun>| -> Result<Point, ImplantError> {
        let gain = run(volume)?;
        if !gain.is_finite() {
            return Err(ImplantError::InvalidParameter {
                param: Param::Gain,
                value: gain,
                expected: format!(
                    "a finite area gain in cm² from the run at volume {volume} cm³ (run {})",
                    runs.len() + 1
                ),
            });
        }
        let point = Point {
            volume,
            gain,
            residual: gain - target_gain,
        };
        runs.push(point.run());
        Ok(point)
    };
    let finish = |point: Point, converged: bool, runs: Vec<PlanningRun>| InverseSearch {
        volume: point.volume,
        gain: point.gain,
        converged,
        runs,
    };
    let within = |point: &Point| point.residual.abs() <= options.gain_tolerance;

    // Brent's method (zeroin, R. P. Brent, "Algorithms for Minimization without Derivatives",
    // 1973, ch. 4): `b` is the best run so far, `c` the other end of the bracket [b, c] holding
    // the target, `a` the previous `b`.
    let mut a = evaluate(low, &mut runs)?;
    let mut b = evaluate(high, &mut runs)?;
    if within(&a) || within(&b) {
        let best = if a.residual.abs() < b.residual.abs() {
            a
        } else {
            b
        };
        return Ok(finish(best, true, runs));
    }
    if (a.residual > 0.0) == (b.residual > 0.0) {
        return Err(ImplantError::TargetNotBracketed {
            target: target_gain,
            low_volume: a.volume,
            low_gain: a.gain,
            high_volume: b.volume,
            high_gain: b.gain,
        });
    }
    let mut c = a;
    // The last step and the one before it.
    let mut step = b.volume - a.volume;
    let mut step_before = step;
    loop {
        // Keep the bracket [b, c] around the sign change, and `b` the better end.
        if (b.residual > 0.0) == (c.residual > 0.0) {
            c = a;
            step = b.volume - a.volume;
            step_before = step;
        }
        if c.residual.abs() < b.residual.abs() {
            a = b;
            b = c;
            c = a;
        }
        // The smallest step: half the volume tolerance (or what f64 resolves at this volume).
        let min_step = 2.0 * f64::EPSILON * b.volume.abs() + 0.5 * options.volume_tolerance;
        let half = 0.5 * (c.volume - b.volume);
        if half.abs() <= min_step {
            return Ok(finish(b, true, runs));
        }
        if runs.len() >= options.max_runs {
            return Ok(finish(b, false, runs));
        }

        let mut bisect = true;
        if step_before.abs() >= min_step && a.residual.abs() > b.residual.abs() {
            // Interpolate: secant through a and b, or inverse quadratic through a, b and c.
            let s = b.residual / a.residual;
            let (mut p, mut q) = if a.volume == c.volume {
                (2.0 * half * s, 1.0 - s)
            } else {
                let qa = a.residual / c.residual;
                let r = b.residual / c.residual;
                (
                    s * (2.0 * half * qa * (qa - r) - (b.volume - a.volume) * (r - 1.0)),
                    (qa - 1.0) * (r - 1.0) * (s - 1.0),
                )
            };
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            // Accept the step if it stays well inside the bracket and is less than half the step
            // before last (a NaN from an overflow refuses it).
            if 2.0 * p < (3.0 * half * q - (min_step * q).abs()).min((step_before * q).abs()) {
                step_before = step;
                step = p / q;
                bisect = false;
            }
        }
        if bisect {
            step = half;
            step_before = half;
        }

        a = b;
        let volume = if step.abs() > min_step {
            b.volume + step
        } else {
            b.volume + min_step.copysign(half)
        };
        b = evaluate(volume, &mut runs)?;
        if within(&b) {
            return Ok(finish(b, true, runs));
        }
    }
}
