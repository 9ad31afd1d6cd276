//! The thesis's stop criterion and the run loop.

use crate::{MassSpringSystem, MssError, Particles, StepReport};

/// When a run ends (SPEC A.2): each step sums the particle displacements; the run has *settled*
/// when, over the last `window` steps, the smallest of those sums divided by the largest is within
/// `tolerance` of 1 (the motion has stopped changing: it has reached its floor), or all of them
/// are zero. It also ends after `max_steps` steps.
///
/// Two limits of the ratio test, found while testing: a slow monotone creep (an overdamped soft
/// mode) has nearly equal sums and satisfies it before equilibrium, and a system at equilibrium
/// whose sums jitter at the `f32` noise floor may never satisfy it. `floor` adds the thesis's
/// other reading — "a minimum of the summed displacement has been reached": the run has also
/// settled when every sum in the window is at most `floor` (cm per step, summed over particles).
/// `floor = 0` is the ratio test alone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopCriterion {
    /// Number of steps compared (N ≥ 2).
    pub window: usize,
    /// Settled when `min / max ≥ 1 − tolerance`, tolerance in (0, 1).
    pub tolerance: f64,
    /// Hard limit on the number of steps.
    pub max_steps: u64,
    /// Settled when every sum in the window is at most this (cm); 0 disables it.
    pub floor: f64,
}

impl StopCriterion {
    pub(crate) fn check(&self) -> Result<(), MssError> {
        if self.window < 2 {
            return Err(MssError::InvalidParameter {
                name: "window",
                value: self.window as f64,
                expected: "at least 2 steps",
            });
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(MssError::InvalidParameter {
                name: "tolerance",
                value: self.tolerance,
                expected: "in (0, 1)",
            });
        }
        if !(self.floor.is_finite() && self.floor >= 0.0) {
            return Err(MssError::InvalidParameter {
                name: "floor",
                value: self.floor,
                expected: "finite and ≥ 0",
            });
        }
        Ok(())
    }
}

/// Why a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// The stop criterion fired.
    Settled,
    /// `max_steps` were taken first.
    StepLimit,
}

/// The outcome of [`MassSpringSystem::run`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunReport {
    /// Steps taken in this run.
    pub steps: u64,
    /// Why it ended.
    pub reason: StopReason,
    /// The last step's report.
    pub last: Option<StepReport>,
}

/// Watches the per-step displacement sums for the stop criterion. Allocates its window once.
#[derive(Debug, Clone)]
pub struct SettleDetector {
    sums: Vec<f64>,
    next: usize,
    filled: usize,
    tolerance: f64,
    floor: f64,
}

impl SettleDetector {
    /// A detector for `criterion`.
    pub fn new(criterion: &StopCriterion) -> Result<Self, MssError> {
        criterion.check()?;
        Ok(SettleDetector {
            sums: vec![0.0; criterion.window],
            next: 0,
            filled: 0,
            tolerance: criterion.tolerance,
            floor: criterion.floor,
        })
    }

    /// Records one step's displacement sum; `true` once the run has settled.
    pub fn push(&mut self, displacement: f64) -> bool {
        self.sums[self.next] = displacement;
        self.next = (self.next + 1) % self.sums.len();
        self.filled = (self.filled + 1).min(self.sums.len());
        if self.filled < self.sums.len() {
            return false;
        }
        let (min, max) = self
            .sums
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), &s| {
                (lo.min(s), hi.max(s))
            });
        max <= self.floor || min / max >= 1.0 - self.tolerance
    }

    /// Forgets the history (after the caller changed the system).
    pub fn reset(&mut self) {
        self.filled = 0;
        self.next = 0;
    }
}

impl MassSpringSystem {
    /// Steps with a constant `h` until the stop criterion fires or `max_steps` are taken.
    pub fn run(&mut self, h: f32, criterion: &StopCriterion) -> Result<RunReport, MssError> {
        self.run_with(h, criterion, |_| {}, true)
    }

    /// [`MassSpringSystem::run`] with the caller's collision handling in every step (see
    /// [`MassSpringSystem::step_with`]); `fused = true` uses the fused step and ignores `collide`.
    pub(crate) fn run_with(
        &mut self,
        h: f32,
        criterion: &StopCriterion,
        mut collide: impl FnMut(&mut Particles),
        fused: bool,
    ) -> Result<RunReport, MssError> {
        let _span = tracing::info_span!("mss_run", h, max_steps = criterion.max_steps).entered();
        let mut detector = SettleDetector::new(criterion)?;
        let mut last = None;
        for taken in 1..=criterion.max_steps {
            let report = if fused {
                self.step(h)?
            } else {
                self.step_with(h, &mut collide)?
            };
            last = Some(report);
            if detector.push(report.displacement) {
                return Ok(RunReport {
                    steps: taken,
                    reason: StopReason::Settled,
                    last,
                });
            }
        }
        Ok(RunReport {
            steps: criterion.max_steps,
            reason: StopReason::StepLimit,
            last,
        })
    }

    /// [`MassSpringSystem::run`] with collision handling between the velocity and position
    /// updates of every step.
    pub fn run_colliding(
        &mut self,
        h: f32,
        criterion: &StopCriterion,
        collide: impl FnMut(&mut Particles),
    ) -> Result<RunReport, MssError> {
        self.run_with(h, criterion, collide, false)
    }
}
