//! Conservation, statics, determinism, divergence and validation of the whole system.
#![allow(clippy::unwrap_used)]

use glam::{Vec3, Vec3A};
use tissue_mss::scenes::two_layer_region;
use tissue_mss::{
    spring_force, AdaptiveStep, Anchor, Integrator, MassSpringSystem, MssError, Particles, Spring,
    StopCriterion, StopReason,
};

/// A tiny deterministic generator (xorshift64*), uniform in [-1, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        ((x >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
    fn vec(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

/// A free chain of `n` particles with random masses, jittered positions and random velocities,
/// neighbours joined, every 7th particle joined to the one 3 ahead, and every 97th to a particle
/// far away (so that large chains have springs between distant particle blocks).
fn free_chain(n: u32, seed: u64) -> MassSpringSystem {
    let mut rng = Rng(seed);
    let positions: Vec<Vec3> = (0..n)
        .map(|i| Vec3::new(i as f32 * 0.1, 0.0, 0.0) + 0.02 * rng.vec())
        .collect();
    let masses: Vec<f32> = (0..n).map(|_| 1.0 + 0.5 * rng.next()).collect();
    let mut springs: Vec<Spring> = (0..n - 1)
        .map(|i| Spring::new(i, i + 1, 0.1, 500.0 + 100.0 * rng.next()))
        .collect();
    springs.extend(
        (0..n - 3)
            .step_by(7)
            .map(|i| Spring::new(i, i + 3, 0.3, 50.0)),
    );
    springs.extend((0..n).step_by(97).filter_map(|i| {
        let j = (i * 7919 + 13) % n;
        let rest = positions[i as usize].distance(positions[j as usize]);
        (j != i).then(|| Spring::new(i, j, rest, 5.0))
    }));
    let mut p = Particles::new(&positions, &masses).unwrap();
    for v in p.velocities_mut() {
        *v = Vec3A::from(rng.vec());
    }
    MassSpringSystem::new(p, springs).unwrap()
}

#[test]
fn free_chain_conserves_linear_momentum() {
    // 5000 particles: three blocks, so block-crossing springs are exercised too.
    for integrator in [Integrator::ExplicitEuler, Integrator::SymplecticEuler] {
        let mut s = free_chain(5000, 7);
        s.set_integrator(integrator);
        assert!(s.crossing_springs() > 0);
        assert!(s.far_springs() > 0);
        let p0 = s.particles().momentum();
        let scale: f64 = s
            .particles()
            .velocities()
            .iter()
            .zip(s.particles().masses())
            .map(|(v, &m)| f64::from(v.length() * m))
            .sum();
        for _ in 0..500 {
            s.step(1e-3).unwrap();
        }
        let drift = (s.particles().momentum() - p0).length();
        // Internal forces cancel pairwise: only f32 rounding of the updates remains.
        assert!(
            drift < 1e-6 * scale,
            "{integrator:?}: momentum moved by {drift:e} (scale {scale:e})"
        );
        // The springs did work: the test is not trivially still.
        assert!(s.particles().forces().iter().any(|f| f.length() > 1.0));
    }
}

#[test]
fn hanging_chain_settles_at_the_analytic_static_stretch() {
    // Particle 0 fixed; particles 1..=N of mass m hang below it on springs of stiffness k and rest
    // l. At rest, spring j (from particle j to j+1) carries the N − j masses below it, so it is
    // stretched by (N − j)·m·g/k.
    let (n, m, k, l, g) = (10u32, 2.0f32, 2.0e5f32, 0.5f32, 981.0f32);
    let positions: Vec<Vec3> = (0..=n)
        .map(|i| Vec3::new(0.0, 0.0, -(i as f32) * l))
        .collect();
    let mut p = Particles::new(&positions, &vec![m; n as usize + 1]).unwrap();
    p.fix(0).unwrap();
    let springs = (0..n).map(|j| Spring::new(j, j + 1, l, k)).collect();
    let mut s = MassSpringSystem::new(p, springs).unwrap();
    s.set_gravity(Vec3::new(0.0, 0.0, -g)).unwrap();
    s.set_damping(0.995).unwrap();
    let criterion = StopCriterion {
        window: 50,
        tolerance: 1e-3,
        max_steps: 400_000,
        floor: 0.0,
    };
    let report = s.run(1e-4, &criterion).unwrap();
    assert_eq!(report.reason, StopReason::Settled, "{report:?}");
    let x = s.particles().positions();
    let mut total = 0.0f64;
    for j in 0..n as usize {
        let stretch = f64::from(x[j].distance(x[j + 1]) - l);
        let expected = f64::from((n - j as u32) as f32 * m * g / k);
        assert!(
            (stretch - expected).abs() < 1e-3 * expected + 2e-6,
            "spring {j}: stretch {stretch} vs {expected}"
        );
        total += stretch;
    }
    let expected_total = f64::from(m * g / k) * f64::from(n * (n + 1) / 2);
    assert!((total - expected_total).abs() < 1e-3 * expected_total);
}

#[test]
fn stop_criterion_reports_the_step_limit() {
    let mut s = free_chain(20, 3);
    let criterion = StopCriterion {
        window: 10,
        tolerance: 1e-9,
        max_steps: 30,
        floor: 0.0,
    };
    let report = s.run(1e-4, &criterion).unwrap();
    assert_eq!(report.reason, StopReason::StepLimit);
    assert_eq!(report.steps, 30);
    assert!(s
        .run(
            1e-4,
            &StopCriterion {
                window: 1,
                ..criterion
            }
        )
        .is_err());
}

fn positions_bits(s: &MassSpringSystem) -> Vec<[u32; 3]> {
    s.particles()
        .positions()
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// Takes `steps` steps of `h` — serially when `threads` is `None`, else on a rayon pool of that
/// many threads — and returns the positions' bits.
fn stepped_bits(
    mut s: MassSpringSystem,
    threads: Option<usize>,
    steps: usize,
    h: f32,
) -> Vec<[u32; 3]> {
    s.set_parallel(threads.is_some());
    assert_eq!(s.is_parallel(), threads.is_some());
    let mut run = || {
        for _ in 0..steps {
            s.step(h).unwrap();
        }
    };
    match threads {
        None => run(),
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(run),
    }
    positions_bits(&s)
}

#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    let mut region = two_layer_region(129).unwrap();
    // Lift the free particles as the thesis does before a run, so everything moves.
    let free: Vec<bool> = region
        .particles()
        .inverse_masses()
        .iter()
        .map(|&w| w > 0.0)
        .collect();
    for (x, free) in region.particles_mut().positions_mut().iter_mut().zip(free) {
        if free {
            x.z += 0.05;
        }
    }
    region.set_gravity(Vec3::new(0.0, 0.0, -981.0)).unwrap();
    let serial = stepped_bits(region.clone(), None, 40, 2e-5);
    for t in [1, 2, 3] {
        assert_eq!(
            serial,
            stepped_bits(region.clone(), Some(t), 40, 2e-5),
            "{t} threads differ from serial"
        );
    }

    // A chain with springs between neighbouring and distant blocks.
    let chain = free_chain(20_000, 9);
    assert!(chain.far_springs() > 0);
    let serial = stepped_bits(chain.clone(), None, 30, 1e-3);
    for t in [1, 2] {
        assert_eq!(serial, stepped_bits(chain.clone(), Some(t), 30, 1e-3));
    }
}

#[test]
fn split_step_equals_fused_step() {
    for integrator in [Integrator::ExplicitEuler, Integrator::SymplecticEuler] {
        let mut a = free_chain(3000, 11);
        let mut b = free_chain(3000, 11);
        a.set_integrator(integrator);
        b.set_integrator(integrator);
        a.set_damping(0.98).unwrap();
        b.set_damping(0.98).unwrap();
        for _ in 0..20 {
            let ra = a.step(1e-3).unwrap();
            let rb = b.step_with(1e-3, |_| {}).unwrap();
            assert_eq!(ra.displacement.to_bits(), rb.displacement.to_bits());
        }
        assert_eq!(positions_bits(&a), positions_bits(&b));
    }
}

#[test]
fn zero_length_springs_give_finite_forces() {
    let x = Vec3A::new(0.3, -0.2, 1.0);
    assert_eq!(spring_force(x, x, 0.0, 100.0), Vec3A::ZERO);
    // A collapsed spring with a rest length has no direction: zero force, not NaN.
    assert_eq!(spring_force(x, x, 0.5, 100.0), Vec3A::ZERO);
    // A zero-length spring is linear: f = k·d.
    let d = Vec3A::new(1e-30, 0.0, 0.0);
    assert_eq!(spring_force(Vec3A::ZERO, d, 0.0, 2.0), d * 2.0);

    // In a system: two coincident particles joined by a zero-length spring, and an anchor at the
    // particle's own position.
    let p = Particles::new(&[Vec3::ONE, Vec3::ONE], &[1.0, 1.0]).unwrap();
    let mut s = MassSpringSystem::new(p, vec![Spring::new(0, 1, 0.0, 1e4)]).unwrap();
    s.add_anchors(&[Anchor {
        particle: 1,
        k: 1e3,
        target: Vec3::ONE,
    }])
    .unwrap();
    s.set_gravity(Vec3::new(0.0, 0.0, -981.0)).unwrap();
    for _ in 0..100 {
        s.step(1e-3).unwrap();
    }
    assert!(s
        .particles()
        .positions()
        .iter()
        .chain(s.particles().velocities())
        .all(|v| v.is_finite()));
}

#[test]
fn divergence_is_an_error_naming_step_and_particle_and_leaves_no_nan() {
    // Far too stiff for the step: explicit Euler blows up within a few hundred steps.
    let positions: Vec<Vec3> = (0..6).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
    let mut p = Particles::new(&positions, &[1.0; 6]).unwrap();
    p.fix(0).unwrap();
    p.velocities_mut()[5] = Vec3A::new(0.0, 1.0, 0.0);
    let springs = (0..5).map(|i| Spring::new(i, i + 1, 1.0, 1e9)).collect();
    let mut s = MassSpringSystem::new(p, springs).unwrap();
    let mut err = None;
    for _ in 0..10_000 {
        if let Err(e) = s.step(1e-2) {
            err = Some(e);
            break;
        }
    }
    match err {
        Some(MssError::Diverged { step, particle }) => {
            assert!(step > 0);
            assert!((1..6).contains(&particle));
        }
        other => panic!("expected divergence, got {other:?}"),
    }
    assert!(s
        .particles()
        .positions()
        .iter()
        .chain(s.particles().velocities())
        .all(|v| v.is_finite()));

    // A NaN put into a position is caught by the next step.
    let mut s = free_chain(10, 5);
    s.particles_mut().positions_mut()[4].x = f32::NAN;
    assert!(matches!(
        s.step(1e-4),
        Err(MssError::Diverged { step: 0, .. })
    ));
}

#[test]
fn adaptive_step_recovers_where_the_fixed_step_diverges() {
    let build = || {
        let positions: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new(i as f32 * 0.1, 0.0, 0.0))
            .collect();
        let mut p = Particles::new(&positions, &[0.1; 8]).unwrap();
        p.fix(0).unwrap();
        let springs = (0..7).map(|i| Spring::new(i, i + 1, 0.1, 1e5)).collect();
        let mut s = MassSpringSystem::new(p, springs).unwrap();
        s.set_gravity(Vec3::new(0.0, 0.0, -981.0)).unwrap();
        s.set_integrator(Integrator::SymplecticEuler);
        s
    };
    // ω_max ≈ 2√(k/m) = 2000 /s: h = 5e-3 is far beyond 2/ω.
    let mut fixed = build();
    let diverged = (0..5000).any(|_| fixed.step(5e-3).is_err());
    assert!(diverged, "the fixed large step should diverge");

    let mut s = build();
    let mut control = AdaptiveStep::new(5e-3, 1e-7, 5e-3).unwrap();
    for _ in 0..3000 {
        s.step_adaptive(&mut control).unwrap();
    }
    assert!(control.redone > 0, "it should have shrunk at least once");
    assert!(control.h < 2e-3, "h = {}", control.h);
    assert!(s.particles().positions().iter().all(|x| x.is_finite()));
    // The chain hangs below its top: the motion is physical, not frozen.
    assert!(s.particles().positions()[7].z < -0.001);

    // And from a tiny step on a gentle system, h grows towards h_max.
    let mut gentle = free_chain(10, 1);
    let mut control = AdaptiveStep::new(1e-6, 1e-7, 1e-3).unwrap();
    for _ in 0..300 {
        gentle.step_adaptive(&mut control).unwrap();
    }
    assert!(control.h > 1e-5, "h = {}", control.h);
}

#[test]
fn bad_input_is_an_error_naming_the_element() {
    let p = || Particles::new(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[1.0; 3]).unwrap();
    let cases = [
        (Spring::new(0, 3, 1.0, 1.0), "out of range"),
        (Spring::new(1, 1, 1.0, 1.0), "itself"),
        (Spring::new(0, 1, -1.0, 1.0), "rest length"),
        (Spring::new(0, 1, 1.0, f32::NAN), "stiffness"),
    ];
    for (spring, text) in cases {
        let err =
            MassSpringSystem::new(p(), vec![Spring::new(0, 2, 1.0, 1.0), spring]).unwrap_err();
        assert!(
            matches!(err, MssError::InvalidSpring { spring: 1, .. }),
            "{err:?}"
        );
        assert!(err.to_string().contains(text), "{err}");
    }
    assert!(matches!(
        Particles::new(&[Vec3::ZERO, Vec3::X], &[1.0, 0.0]),
        Err(MssError::InvalidParticle { particle: 1, .. })
    ));
    assert!(matches!(
        Particles::new(&[Vec3::ZERO, Vec3::NAN], &[1.0, 1.0]),
        Err(MssError::InvalidParticle { particle: 1, .. })
    ));
    assert!(matches!(
        Particles::new(&[Vec3::ZERO], &[1.0, 1.0]),
        Err(MssError::LengthMismatch { .. })
    ));
    let mut s = MassSpringSystem::new(p(), vec![]).unwrap();
    assert!(s.set_damping(0.0).is_err());
    assert!(s.set_damping(1.5).is_err());
    assert!(s.set_external_forces(&[Vec3::ZERO; 2]).is_err());
    assert!(matches!(
        s.add_anchors(&[Anchor {
            particle: 9,
            k: 1.0,
            target: Vec3::ZERO
        }]),
        Err(MssError::InvalidAnchor { particle: 9, .. })
    ));
    assert!(s.particles_mut().fix(3).is_err());
}

#[test]
fn removed_anchors_no_longer_pull() {
    // Three particles, each anchored 1 cm below where it is: k·1 cm downwards on each.
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let mut s = MassSpringSystem::new(Particles::new(&p, &[1.0; 3]).unwrap(), Vec::new()).unwrap();
    let anchors: Vec<Anchor> = (0..3)
        .map(|i| Anchor {
            particle: i,
            k: 10.0 * (i + 1) as f32,
            target: p[i as usize] - Vec3::Z,
        })
        .collect();
    s.add_anchors(&anchors).unwrap();
    s.retain_anchors(|i| i != 1);
    assert_eq!(s.anchored_particles().collect::<Vec<_>>().len(), 2);
    assert!(!s.anchored_particles().any(|i| i == 1));
    s.compute_forces();
    let f = s.particles().forces();
    assert!((f[0].z + 10.0).abs() < 1e-6, "{}", f[0]);
    assert_eq!(f[1].length(), 0.0);
    assert!((f[2].z + 30.0).abs() < 1e-6, "{}", f[2]);
    // The stable step no longer counts the removed anchor's stiffness: with only particle 2's
    // 30 g/s² left as the stiffest, h = 2/√(2·30).
    let h = s.stable_time_step().unwrap();
    assert!((h - 2.0 / 60f32.sqrt()).abs() < 1e-5, "{h}");
}
