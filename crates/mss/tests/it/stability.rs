//! `stable_time_step` against the exact limit of symplectic Euler on one spring.
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_mss::{Integrator, MassSpringSystem, Particles, Spring};

/// Two equal masses on one spring, stretched, stepped `steps` times at `factor` × the reported
/// limit; returns the largest |stretch| seen.
fn largest_stretch(factor: f32, steps: usize) -> f32 {
    let particles = Particles::new(&[Vec3::ZERO, Vec3::new(1.1, 0.0, 0.0)], &[0.5, 0.5]).unwrap();
    let mut s = MassSpringSystem::new(particles, vec![Spring::new(0, 1, 1.0, 200.0)]).unwrap();
    s.set_integrator(Integrator::SymplecticEuler);
    // ω² = 2k/m = 800: the exact limit is h = 2/ω.
    let h = s.stable_time_step().unwrap();
    assert!((h - 2.0 / 800f32.sqrt()).abs() < 1e-6 * h, "{h}");
    let mut worst = 0.0f32;
    for _ in 0..steps {
        if s.step(factor * h).is_err() {
            return f32::INFINITY; // diverged to a non-finite state
        }
        let p = s.particles().positions();
        worst = worst.max((p[1].x - p[0].x - 1.0).abs());
    }
    worst
}

#[test]
fn the_reported_step_is_the_stability_limit() {
    assert!(largest_stretch(0.98, 2000) < 1.0, "stable below the limit");
    assert!(largest_stretch(1.02, 2000) > 10.0, "unstable above it");
}

#[test]
fn no_stiffness_no_step() {
    let particles = Particles::new(&[Vec3::ZERO], &[1.0]).unwrap();
    let s = MassSpringSystem::new(particles, vec![]).unwrap();
    assert_eq!(s.stable_time_step(), None);
}
