//! The enclosed fill's pressure against closed-form answers.
#![allow(clippy::unwrap_used)]

use glam::Vec3A;
use tissue_mesh::uv_sphere;
use tissue_mss::{masses_from_triangles, Integrator, MassSpringSystem, Particles, VolumePressure};

/// A fill alone (no springs) inside a unit sphere of mass `m`, squeezed uniformly by 1 % and
/// released: it breathes. The pressure over the area gives `M·δ̈ = −(3K/r)·δ·A`, so
/// `ω² = 3·K·A/(M·r)`. Returns the measured period over several cycles.
fn breathing_period(k: f64, m: f64) -> (f64, f64) {
    let mesh = uv_sphere(32, 24, 1.0).unwrap();
    let masses = masses_from_triangles(&mesh, m).unwrap();
    let mut s =
        MassSpringSystem::new(Particles::new(mesh.positions(), &masses).unwrap(), vec![]).unwrap();
    let fill = VolumePressure::new(&mesh, 0, k).unwrap();
    s.add_volume_pressure(fill.clone()).unwrap();
    s.set_integrator(Integrator::SymplecticEuler);
    for x in s.particles_mut().positions_mut() {
        *x *= 0.99;
    }
    let h = 0.05 * s.stable_time_step().unwrap();
    let rest = fill.rest_volume();
    let mut crossings = Vec::new();
    let mut last = fill.volume(s.particles().positions()) - rest;
    for step in 1..200_000u32 {
        s.step(h).unwrap();
        let now = fill.volume(s.particles().positions()) - rest;
        if last < 0.0 && now >= 0.0 {
            // Upward zero crossing, interpolated.
            crossings.push((f64::from(step) - now / (now - last)) * f64::from(h));
            if crossings.len() == 6 {
                break;
            }
        }
        last = now;
    }
    let period = (crossings[5] - crossings[0]) / 5.0;
    let area = mesh.area();
    let expected = 2.0 * std::f64::consts::PI / (3.0 * k * area / m).sqrt();
    (period, expected)
}

#[test]
fn a_squeezed_fill_breathes_at_its_bulk_frequency() {
    for (k, m) in [(1e5, 4.0), (1e7, 0.5)] {
        let (period, expected) = breathing_period(k, m);
        assert!(
            (period - expected).abs() < 0.02 * expected,
            "K = {k}, M = {m}: period {period} s, expected {expected} s"
        );
    }
}

#[test]
fn the_stable_step_holds_a_filled_shell() {
    // A shell (a fill alone has no shape: its wrinkles cost nothing and grow) filled at a
    // bulk modulus that dominates the step: at 0.9 of the reported limit the run stays bounded
    // for many breathing periods.
    let mesh = uv_sphere(16, 12, 1.0).unwrap();
    let masses = masses_from_triangles(&mesh, 1.0).unwrap();
    let shell = tissue_mss::SheetMaterial {
        young: 1e5,
        poisson: 0.3,
        thickness: 0.1,
    };
    let springs = tissue_mss::springs_from_triangles(&mesh, &shell, 0).unwrap();
    let mut s =
        MassSpringSystem::new(Particles::new(mesh.positions(), &masses).unwrap(), springs).unwrap();
    let fill = VolumePressure::new(&mesh, 0, 1e6).unwrap();
    s.add_volume_pressure(fill.clone()).unwrap();
    s.set_integrator(Integrator::SymplecticEuler);
    for x in s.particles_mut().positions_mut() {
        *x *= 0.99;
    }
    let h = 0.9 * s.stable_time_step().unwrap();
    for _ in 0..20_000 {
        s.step(h).unwrap();
    }
    let loss = (fill.rest_volume() - fill.volume(s.particles().positions())) / fill.rest_volume();
    assert!(loss.abs() < 0.05, "{loss}");
}

#[test]
fn the_fill_adds_no_net_force() {
    let mesh = uv_sphere(16, 12, 2.0).unwrap();
    let masses = masses_from_triangles(&mesh, 1.0).unwrap();
    let mut s =
        MassSpringSystem::new(Particles::new(mesh.positions(), &masses).unwrap(), vec![]).unwrap();
    s.add_volume_pressure(VolumePressure::new(&mesh, 0, 1e6).unwrap())
        .unwrap();
    // Squash it: the fill pushes back, with zero net force.
    for x in s.particles_mut().positions_mut() {
        x.z *= 0.7;
    }
    s.compute_forces();
    let f: Vec3A = s.particles().forces().iter().copied().sum();
    let scale: f32 = s.particles().forces().iter().map(|f| f.length()).sum();
    assert!(scale > 0.0 && f.length() < 1e-5 * scale, "{f} of {scale}");
}

#[test]
fn an_open_surface_or_bad_modulus_is_refused() {
    let open = tissue_mesh::grid(5, 1.0).unwrap();
    assert!(VolumePressure::new(&open, 0, 1e6).is_err());
    let closed = uv_sphere(8, 6, 1.0).unwrap();
    for k in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(VolumePressure::new(&closed, 0, k).is_err());
    }
}
