//! Adaptive time step after Baraff & Witkin (SPEC A.2): grow the step while stable; on
//! instability shrink it, redo the step, and hold it for a number of steps.

use glam::Vec3A;

use crate::{MassSpringSystem, MssError, StepReport};

/// Parameters and state of the adaptive step.
///
/// **Instability test**: a step is unstable when any position or velocity becomes non-finite, or
/// when some particle moves farther than `max_move` × the shortest positive spring rest length in
/// that one step. The second is the explicit integrator's stability condition in geometric form:
/// a stable step resolves a spring's oscillation with several steps, so no particle can cross a
/// large part of a spring in one (with `ωh < 1`, a particle oscillating with amplitude `A` moves at
/// most `ωhA` a step).
#[derive(Debug, Clone, PartialEq)]
pub struct AdaptiveStep {
    /// Current step (s).
    pub h: f32,
    /// Smallest allowed step (s); below it the run fails with [`MssError::StepTooSmall`].
    pub h_min: f32,
    /// Largest allowed step (s).
    pub h_max: f32,
    /// Factor applied after a stable step once the hold is over (> 1), e.g. 1.05.
    pub grow: f32,
    /// Factor applied on instability (in (0, 1)), e.g. 0.5.
    pub shrink: f32,
    /// Steps to keep `h` unchanged after a shrink.
    pub hold: u32,
    /// Largest displacement in one step, as a fraction of the shortest rest length, e.g. 0.1.
    pub max_move: f32,
    /// Steps left before `h` may grow again.
    pub holding: u32,
    /// Number of steps redone so far.
    pub redone: u64,
    saved_position: Vec<Vec3A>,
    saved_velocity: Vec<Vec3A>,
}

impl AdaptiveStep {
    /// An adaptive step starting at `h` within `[h_min, h_max]`, with growth 1.05, shrink 0.5, a
    /// hold of 10 steps and `max_move` 0.1.
    pub fn new(h: f32, h_min: f32, h_max: f32) -> Result<Self, MssError> {
        if !(h_min > 0.0 && h_min <= h && h <= h_max && h_max.is_finite()) {
            return Err(MssError::InvalidParameter {
                name: "h",
                value: f64::from(h),
                expected: "0 < h_min ≤ h ≤ h_max, all finite",
            });
        }
        Ok(AdaptiveStep {
            h,
            h_min,
            h_max,
            grow: 1.05,
            shrink: 0.5,
            hold: 10,
            max_move: 0.1,
            holding: 0,
            redone: 0,
            saved_position: Vec::new(),
            saved_velocity: Vec::new(),
        })
    }
}

impl MassSpringSystem {
    /// One stable step of adaptive size: saves the state, steps with `control.h`, and on
    /// instability restores, shrinks `h` and tries again. The scratch copies are allocated on the
    /// first call only.
    pub fn step_adaptive(&mut self, control: &mut AdaptiveStep) -> Result<StepReport, MssError> {
        if !(control.grow >= 1.0 && control.shrink > 0.0 && control.shrink < 1.0) {
            return Err(MssError::InvalidParameter {
                name: "grow/shrink",
                value: f64::from(control.shrink),
                expected: "grow ≥ 1 and shrink in (0, 1)",
            });
        }
        let limit = control.max_move * self.shortest_rest_length();
        loop {
            let p = self.particles();
            control.saved_position.clear();
            control.saved_position.extend_from_slice(p.positions());
            control.saved_velocity.clear();
            control.saved_velocity.extend_from_slice(p.velocities());
            let step = self.steps_taken();
            let result = self.step(control.h);
            let stable = match &result {
                Ok(r) => r.max_move <= limit,
                Err(MssError::Diverged { .. }) => false,
                Err(e) => return Err(e.clone()),
            };
            if stable {
                if control.holding > 0 {
                    control.holding -= 1;
                } else {
                    control.h = (control.h * control.grow).min(control.h_max);
                }
                return result;
            }
            let p = self.particles_mut();
            p.positions_mut().copy_from_slice(&control.saved_position);
            p.velocities_mut().copy_from_slice(&control.saved_velocity);
            self.rewind_to(step);
            control.redone += 1;
            if control.h <= control.h_min {
                return Err(MssError::StepTooSmall {
                    step,
                    h_min: control.h_min,
                });
            }
            control.h = (control.h * control.shrink).max(control.h_min);
            control.holding = control.hold;
        }
    }
}
