//! One spring, one free mass: the analytic harmonic oscillator against each integrator.
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_mss::{Integrator, MassSpringSystem, Particles, Spring};

const K: f32 = 100.0; // g/s²
const M: f32 = 1.0; // g
const REST: f32 = 1.0; // cm
const AMPLITUDE: f32 = 0.1; // cm

/// Particle 0 fixed at the origin, particle 1 below it stretched by `AMPLITUDE`, at rest.
fn oscillator(integrator: Integrator) -> MassSpringSystem {
    let mut p = Particles::new(
        &[Vec3::ZERO, Vec3::new(0.0, 0.0, -(REST + AMPLITUDE))],
        &[1.0, M],
    )
    .unwrap();
    p.fix(0).unwrap();
    let mut s = MassSpringSystem::new(p, vec![Spring::new(0, 1, REST, K)]).unwrap();
    s.set_integrator(integrator);
    s
}

/// Displacement from rest (cm) and velocity (cm/s) of the free mass.
fn state(s: &MassSpringSystem) -> (f64, f64) {
    let p = s.particles();
    (
        f64::from(-p.positions()[1].z) - f64::from(REST),
        f64::from(p.velocities()[1].z),
    )
}

/// ½ m v² + ½ k x², in f64.
fn energy(s: &MassSpringSystem) -> f64 {
    let (x, v) = state(s);
    0.5 * f64::from(M) * v * v + 0.5 * f64::from(K) * x * x
}

#[test]
fn period_is_two_pi_sqrt_m_over_k() {
    let expected = 2.0 * std::f64::consts::PI * (f64::from(M) / f64::from(K)).sqrt();
    for integrator in [Integrator::SymplecticEuler, Integrator::ExplicitEuler] {
        let mut s = oscillator(integrator);
        let h = 1e-5f32; // ωh = 1e-4
        let mut crossings = Vec::new();
        let (mut prev_x, _) = state(&s);
        let mut t = 0.0f64;
        while crossings.len() < 6 {
            s.step(h).unwrap();
            t += f64::from(h);
            let (x, _) = state(&s);
            // Upward zero crossings of the displacement, interpolated linearly.
            if prev_x < 0.0 && x >= 0.0 {
                crossings.push(t - f64::from(h) * x / (x - prev_x));
            }
            prev_x = x;
            assert!(t < 10.0 * expected, "no oscillation seen");
        }
        let measured = (crossings[5] - crossings[0]) / 5.0;
        let err = (measured - expected).abs() / expected;
        assert!(
            err < 0.01,
            "{integrator:?}: period {measured} s vs 2π√(m/k) = {expected} s ({:.3}%)",
            err * 100.0
        );
    }
}

#[test]
fn symplectic_energy_stays_bounded_over_1000_periods() {
    let mut s = oscillator(Integrator::SymplecticEuler);
    let omega = (f64::from(K) / f64::from(M)).sqrt();
    let h = 1e-3f32; // ωh = 0.01
    let period = 2.0 * std::f64::consts::PI / omega;
    let steps_per_period = (period / f64::from(h)).round() as usize;
    let e0 = energy(&s);
    let mut worst = 0.0f64;
    let mut first_period_mean = 0.0;
    let mut last_period_mean = 0.0;
    let total = 1000 * steps_per_period;
    for i in 0..total {
        s.step(h).unwrap();
        let e = energy(&s);
        worst = worst.max((e - e0).abs() / e0);
        if i < steps_per_period {
            first_period_mean += e / steps_per_period as f64;
        }
        if i >= total - steps_per_period {
            last_period_mean += e / steps_per_period as f64;
        }
    }
    // Symplectic Euler conserves a modified energy: E oscillates within O(ωh) and does not drift.
    assert!(
        worst < 0.01,
        "energy strayed {:.3}% from its start",
        worst * 100.0
    );
    let drift = (last_period_mean - first_period_mean).abs() / first_period_mean;
    assert!(
        drift < 1e-3,
        "period-averaged energy drifted {:.4}% over 1000 periods",
        drift * 100.0
    );
}

#[test]
fn explicit_euler_energy_grows_by_one_plus_omega_h_squared_per_step() {
    // For x' = v, v' = −ω²x, explicit Euler maps (x, v) by [[1, h], [−ω²h, 1]], whose determinant
    // is 1 + (ωh)²: the energy ω²x² + v² grows by exactly that factor each step (the amplitude by
    // its square root).
    let mut s = oscillator(Integrator::ExplicitEuler);
    let omega = (f64::from(K) / f64::from(M)).sqrt();
    let h = 1e-3f32;
    let wh2 = (omega * f64::from(h)).powi(2);
    let steps = 2000;
    let e0 = energy(&s);
    for _ in 0..steps {
        s.step(h).unwrap();
    }
    let factor = (energy(&s) / e0).powf(1.0 / f64::from(steps));
    let growth = factor - 1.0;
    assert!(
        (growth - wh2).abs() < 0.01 * wh2,
        "energy growth per step {growth:e}, theory (ωh)² = {wh2:e}"
    );
    // And with damping d the factor is (1 + (ωh)²)·d² at most: the thesis's damping is what
    // makes its explicit scheme usable.
    let mut damped = oscillator(Integrator::ExplicitEuler);
    damped.set_damping(0.999).unwrap();
    let e0 = energy(&damped);
    for _ in 0..steps {
        damped.step(h).unwrap();
    }
    assert!(energy(&damped) < e0);
}
