//! Conservation, damping, volume and stiffness behaviour of the public API.
#![allow(clippy::print_stderr, clippy::unwrap_used)]

use crate::common;

use std::time::Instant;

use common::{bunny, non_rigid_energy, Rng};
use glam::Vec3;
use tissue_mesh::tet_box;
use tissue_pbd::{Floor, Material, SoftBody, Solver, StepSettings, VolumeConstraintKind};

fn free_settings(solver: Solver) -> StepSettings {
    StepSettings {
        dt: 0.01,
        substeps: 1,
        iterations: 10,
        solver,
        gravity: Vec3::ZERO,
        damping: 0.0,
        linear_damping: 0.0,
        parallel: false,
        over_relaxation: 0.0,
    }
}

#[test]
fn internal_constraints_conserve_linear_momentum() {
    let mesh = tet_box(5, 3, 3, Vec3::new(5.0, 3.0, 3.0)).unwrap();
    for volume in [
        VolumeConstraintKind::Centroid,
        VolumeConstraintKind::Classic,
        VolumeConstraintKind::None,
    ] {
        for solver in [Solver::PbdLinearised, Solver::Xpbd] {
            let material = Material {
                distance_stiffness: 0.8,
                volume_stiffness: 1.0,
                distance_compliance: 1e-4,
                volume_compliance: 1e-4,
                volume,
                ..Material::default()
            };
            let mut body = SoftBody::new(&mesh, &material).unwrap();
            let mut rng = Rng(7);
            let deformed: Vec<Vec3> = mesh
                .positions()
                .iter()
                .map(|p| *p + rng.vec3(0.15))
                .collect();
            body.set_positions(&deformed).unwrap();
            let v: Vec<Vec3> = (0..mesh.vertex_count()).map(|_| rng.vec3(20.0)).collect();
            body.set_velocities(&v).unwrap();
            body.set_settings(free_settings(solver)).unwrap();
            let p0 = body.linear_momentum();
            let l0 = body.angular_momentum();
            let scale: f64 = body
                .masses()
                .iter()
                .zip(&v)
                .map(|(&m, v)| m as f64 * v.length() as f64)
                .sum();
            let e0 = non_rigid_energy(&body);
            for _ in 0..20 {
                body.step().unwrap();
            }
            let dp = (body.linear_momentum() - p0).length() / scale;
            let dl = (body.angular_momentum() - l0).length() / l0.length();
            eprintln!("{volume:?} {solver:?}: |ΔP|/Σm|v| = {dp:.2e}, |ΔL|/|L| = {dl:.2e}, non-rigid KE {e0:.3e} -> {:.3e}", non_rigid_energy(&body));
            assert!(
                dp < 1e-5,
                "{volume:?} {solver:?}: linear momentum drifted by {dp:e}"
            );
            // The constraints did work (the body was deformed), so this is not a trivial pass.
            assert!((non_rigid_energy(&body) - e0).abs() > 1e-3 * e0);
        }
    }
}

#[test]
fn rigid_mode_damping_keeps_momenta_and_damps_vibration() {
    let mesh = tet_box(4, 4, 4, Vec3::splat(4.0)).unwrap();
    let material = Material {
        distance_stiffness: 0.3,
        volume_stiffness: 0.3,
        ..Material::default()
    };
    let run = |damping: f32| {
        let mut body = SoftBody::new(&mesh, &material).unwrap();
        let mut rng = Rng(3);
        let omega = Vec3::new(0.15, 1.0, -0.25);
        let v: Vec<Vec3> = mesh
            .positions()
            .iter()
            .map(|p| Vec3::new(5.0, -2.0, 1.0) + omega.cross(*p) + rng.vec3(1.0))
            .collect();
        body.set_velocities(&v).unwrap();
        body.set_settings(StepSettings {
            damping,
            ..free_settings(Solver::PbdLinearised)
        })
        .unwrap();
        let (p0, l0, e0) = (
            body.linear_momentum(),
            body.angular_momentum(),
            non_rigid_energy(&body),
        );
        for _ in 0..30 {
            body.step().unwrap();
        }
        let dp = (body.linear_momentum() - p0).length() / p0.length();
        let dl = (body.angular_momentum() - l0).length() / l0.length();
        (dp, dl, e0, non_rigid_energy(&body), body.angular_momentum())
    };
    let (dp, dl, e0, damped, l) = run(0.1);
    let (udp, udl, _, undamped, ul) = run(0.0);
    // PBD itself drifts L slightly on a spinning body (second order in Δt); the damping's own
    // share is the difference between the two runs.
    let own = (l - ul).length() / ul.length();
    eprintln!("damped: ΔP {dp:.2e}, ΔL {dl:.2e}, non-rigid KE {e0:.3e} -> {damped:.3e}; undamped: ΔP {udp:.2e}, ΔL {udl:.2e}, -> {undamped:.3e}; |L_damped − L_undamped|/|L| {own:.2e}");
    assert!(own < 1e-3, "damping's own change of L: {own:e}");
    assert!(
        dp < 0.01 && dl < 0.01,
        "damping changed the momenta: {dp:e}, {dl:e}"
    );
    assert!(
        damped < 0.2 * undamped,
        "vibration not damped: {damped:e} vs {undamped:e}"
    );
    assert!(damped < 0.2 * e0);
}

/// Rests `mesh` (standing on y = 0) on a floor under gravity for `steps` steps and returns the
/// volume ratio and the mean step time (ms).
fn rest_on_tray(
    mesh: &tissue_mesh::TetMesh,
    volume: VolumeConstraintKind,
    steps: usize,
    dt: f32,
    iterations: u32,
) -> (f64, f64) {
    let material = Material {
        distance_stiffness: 0.5,
        volume_stiffness: 1.0,
        volume,
        ..Material::default()
    };
    let mut body = SoftBody::new(mesh, &material).unwrap();
    body.set_floor(Some(Floor::y(0.0))).unwrap();
    body.set_settings(StepSettings {
        dt,
        iterations,
        damping: 0.05,
        ..StepSettings::default()
    })
    .unwrap();
    let t = Instant::now();
    for _ in 0..steps {
        body.step().unwrap();
    }
    let ms = t.elapsed().as_secs_f64() * 1e3 / steps as f64;
    assert!(body.positions().iter().all(|p| p.y >= 0.0));
    (body.volume() / body.rest_volume(), ms)
}

#[test]
fn volume_constraints_keep_a_resting_body_volume() {
    let mesh = bunny();
    let steps = 150;
    let (centroid, tc) = rest_on_tray(&mesh, VolumeConstraintKind::Centroid, steps, 0.002, 10);
    let (classic, tv) = rest_on_tray(&mesh, VolumeConstraintKind::Classic, steps, 0.002, 10);
    let (none, tn) = rest_on_tray(&mesh, VolumeConstraintKind::None, steps, 0.002, 10);
    eprintln!(
        "{} tets, {steps} steps of 2 ms, K = 10, distance k = 0.5, volume k = 1: V/V₀ centroid {centroid:.4} ({tc:.2} ms/step), classic {classic:.4} ({tv:.2} ms/step), none {none:.4} ({tn:.2} ms/step)",
        mesh.tet_count()
    );
    assert!(
        (centroid - 1.0).abs() <= 0.02,
        "centroid constraint lost volume: {centroid}"
    );
    assert!(
        (classic - 1.0).abs() <= 0.02,
        "classic constraint lost volume: {classic}"
    );
    let kept = (centroid - 1.0).abs().max((classic - 1.0).abs());
    assert!(
        1.0 - none > 0.04 && 1.0 - none > 2.0 * kept,
        "without volume constraints: {none}"
    );
}

fn cantilever_sag(solver: Solver, iterations: u32, dt: f32, seconds: f32) -> f32 {
    // An 8 × 3 × 3 cm beam along x, pinned at x = −4, gravity −y.
    let mesh = tet_box(8, 3, 3, Vec3::new(8.0, 3.0, 3.0)).unwrap();
    let material = Material {
        distance_stiffness: 0.5,
        volume_stiffness: 0.5,
        distance_compliance: 1e-5,
        volume_compliance: 1e-5,
        volume: VolumeConstraintKind::Classic,
        ..Material::default()
    };
    let mut body = SoftBody::new(&mesh, &material).unwrap();
    for (i, p) in mesh.positions().iter().enumerate() {
        if p.x < -3.99 {
            body.pin(i as u32).unwrap();
        }
    }
    body.set_settings(StepSettings {
        dt,
        iterations,
        solver,
        damping: 0.05,
        linear_damping: 0.05,
        ..StepSettings::default()
    })
    .unwrap();
    let tip: Vec<usize> = (0..mesh.vertex_count())
        .filter(|&i| mesh.positions()[i].x > 3.99)
        .collect();
    let steps = (seconds / dt).round() as usize;
    let mut sag = 0.0;
    for s in 0..steps {
        body.step().unwrap();
        if s >= steps - steps / 10 {
            // Average over the last tenth, in case a slow swing is left.
            sag += tip
                .iter()
                .map(|&i| mesh.positions()[i].y - body.positions()[i].y)
                .sum::<f32>()
                / tip.len() as f32;
        }
    }
    sag / (steps / 10) as f32
}

#[test]
fn linearised_stiffness_sag_barely_depends_on_iterations() {
    let s5 = cantilever_sag(Solver::PbdLinearised, 5, 0.002, 1.5);
    let s20 = cantilever_sag(Solver::PbdLinearised, 20, 0.002, 1.5);
    let r5 = cantilever_sag(Solver::Pbd, 5, 0.002, 1.5);
    let r20 = cantilever_sag(Solver::Pbd, 20, 0.002, 1.5);
    eprintln!("cantilever sag (cm), linearised: K=5 {s5:.3}, K=20 {s20:.3}; raw k: K=5 {r5:.3}, K=20 {r20:.3}");
    assert!(s5 > 0.1, "the beam should sag visibly");
    assert!(
        (s5 - s20).abs() <= 0.1 * s20,
        "linearised sag differs: {s5} vs {s20}"
    );
    // Without the linearisation the stiffness depends strongly on K: the test can tell.
    assert!(
        (r5 - r20).abs() > 0.1 * r20,
        "raw sag did not depend on K: {r5} vs {r20}"
    );
}

#[test]
fn xpbd_sag_depends_neither_on_iterations_nor_on_the_step() {
    let k5 = cantilever_sag(Solver::Xpbd, 5, 0.002, 1.5);
    let k20 = cantilever_sag(Solver::Xpbd, 20, 0.002, 1.5);
    let half = cantilever_sag(Solver::Xpbd, 20, 0.001, 1.5);
    eprintln!(
        "XPBD cantilever sag (cm): K=5 {k5:.3}, K=20 {k20:.3}, K=20 at dt/2 (1 ms) {half:.3}"
    );
    assert!(k20 > 0.1, "the beam should sag visibly");
    assert!(
        (k5 - k20).abs() <= 0.05 * k20,
        "XPBD sag depends on K: {k5} vs {k20}"
    );
    assert!(
        (half - k20).abs() <= 0.05 * k20,
        "XPBD sag depends on dt: {half} vs {k20}"
    );
}

#[test]
fn compare_volume_constraints_cost_and_error_at_rest() {
    let mesh = tet_box(12, 12, 12, Vec3::splat(6.0)).unwrap();
    let (p, t) = mesh.into_parts();
    let mesh =
        tissue_mesh::TetMesh::new(p.iter().map(|p| *p + Vec3::new(0.0, 3.0, 0.0)).collect(), t)
            .unwrap();
    for kind in [
        VolumeConstraintKind::Centroid,
        VolumeConstraintKind::Classic,
        VolumeConstraintKind::None,
    ] {
        let (ratio, ms) = rest_on_tray(&mesh, kind, 60, 0.005, 20);
        eprintln!("{kind:?}: {} tets, {ms:.3} ms/step (K = 20, dt = 5 ms, with distances), volume error at rest {:+.3} %", mesh.tet_count(), (ratio - 1.0) * 100.0);
        assert!(ratio.is_finite());
        if kind != VolumeConstraintKind::None {
            assert!((ratio - 1.0).abs() < 0.05, "{kind:?}: {ratio}");
        }
    }
}

/// The solver renumbers the nodes internally (domain decomposition); the public API must not
/// show it: masses, pins, attachments, velocities and previous positions all use the caller's
/// node indices, also for a mesh whose node order is scrambled.
#[test]
fn solver_node_order_is_invisible_in_the_public_api() {
    let mesh = tet_box(12, 12, 12, Vec3::splat(6.0)).unwrap();
    // Scramble the node order so that it cannot coincide with the solver's.
    let n = mesh.vertex_count();
    let mut rng = Rng(11);
    let mut perm: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        perm.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    let mut positions = vec![Vec3::ZERO; n];
    for (old, &new) in perm.iter().enumerate() {
        positions[new as usize] = mesh.positions()[old];
    }
    let tets: Vec<[u32; 4]> = mesh
        .tets()
        .iter()
        .map(|t| t.map(|i| perm[i as usize]))
        .collect();
    let material = Material {
        volume: VolumeConstraintKind::Classic,
        ..Material::default()
    };
    let mut body = SoftBody::from_tets(&positions, &tets, &material).unwrap();
    assert!(body.block_count() > 1, "the solver order must differ");
    assert!(body
        .positions()
        .iter()
        .zip(&positions)
        .all(|(a, b)| Vec3::from(*a) == *b));
    // Masses from eq. (1), by the caller's index.
    let mut mass = vec![0.0f64; n];
    for t in &tets {
        let [a, b, c, d] = t.map(|i| positions[i as usize].as_dvec3());
        for &i in t {
            mass[i as usize] += (b - a).cross(c - a).dot(d - a) / 24.0;
        }
    }
    assert!(body
        .masses()
        .iter()
        .zip(&mass)
        .all(|(&m, &e)| (m as f64 - e).abs() <= 1e-5 * e));
    // A pinned node stays put, an attached one follows its target; the rest falls.
    let (pinned, attached) = (perm[0], perm[n - 1]);
    body.pin(pinned).unwrap();
    let target = Vec3::new(3.5, 4.0, 3.5);
    body.attach(attached, target).unwrap();
    body.set_settings(StepSettings {
        parallel: true,
        damping: 0.0,
        ..StepSettings::default()
    })
    .unwrap();
    for _ in 0..10 {
        body.step().unwrap();
    }
    assert_eq!(
        Vec3::from(body.positions()[pinned as usize]),
        positions[pinned as usize]
    );
    assert_eq!(Vec3::from(body.positions()[attached as usize]), target);
    assert_eq!(body.inverse_masses()[pinned as usize], 0.0);
    assert_eq!(body.inverse_masses()[attached as usize], 0.0);
    // v = (x − x_prev)/Δt per node, in the caller's order (no damping here).
    let dt = body.settings().dt;
    for i in 0..n {
        let v = (body.positions()[i] - body.previous_positions()[i]) / dt;
        assert!(
            (v - body.velocities()[i]).length() <= 1e-3 * (1.0 + v.length()),
            "node {i}"
        );
    }
    // The body fell (gravity), except where held.
    let far = perm[n / 2] as usize;
    assert!(body.positions()[far].y < positions[far].y - 0.01);
}
