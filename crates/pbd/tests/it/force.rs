//! Reaction forces ("Tool force") against cases whose answer statics gives exactly: a
//! block resting on a tool weighs on it with `m g`; a block on a tray pressed by a probe
//! pushes the probe up with a force growing with the depth while tray and probe together carry
//! the weight; nothing away from the tissue; a block hanging from a grasper pulls it with `m g`.
#![allow(clippy::print_stderr, clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::{
    ContactParams, Floor, Material, OrientedBox, Pose, SoftBody, Solver, StepSettings, ToolShape,
    VolumeConstraintKind, VoxelCollider, DYN_PER_NEWTON,
};

const G: f32 = 981.0;

/// A `w × h × w` cm block of `n × m × n` cells, its bottom at `y = bottom`, centred on x = z = 0.
fn block(n: u32, m: u32, size: Vec3, bottom: f32) -> TetMesh {
    let (p, t) = tet_box(n, m, n, size).unwrap().into_parts();
    let lift = Vec3::new(0.0, bottom + size.y / 2.0, 0.0);
    TetMesh::new(p.iter().map(|p| *p + lift).collect(), t).unwrap()
}

/// A flat table: a thick horizontal triangle (a blade tool) far larger than the block, its top
/// face at `y = 0`.
fn table() -> (ToolShape, Pose) {
    let shape = ToolShape::Blade {
        a: Vec3::new(-20.0, 0.0, -20.0),
        b: Vec3::new(20.0, 0.0, -20.0),
        c: Vec3::new(0.0, 0.0, 40.0),
        thickness: 0.2,
    };
    (shape, Pose::from_translation(Vec3::new(0.0, -0.1, 0.0)))
}

/// Mean of `f` over the last `avg` of `steps` steps.
fn settle(body: &mut SoftBody, steps: usize, avg: usize, f: impl Fn(&SoftBody) -> Vec3) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for i in 0..steps {
        body.step().unwrap();
        if i >= steps - avg {
            sum += f(body);
        }
    }
    sum / avg as f32
}

#[test]
fn block_resting_on_a_tool_weighs_on_it_for_any_step_and_iteration_count() {
    // Several step lengths, iteration counts and solvers: the force is the weight in each.
    let cases = [
        (0.01, 10, Solver::PbdLinearised),
        (0.005, 10, Solver::PbdLinearised),
        (0.01, 40, Solver::PbdLinearised),
        (0.01, 5, Solver::Pbd),
        (0.01, 20, Solver::Xpbd),
    ];
    for (dt, iterations, solver) in cases {
        let mesh = block(6, 3, Vec3::new(3.0, 1.5, 3.0), 0.0);
        let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
        body.set_settings(StepSettings {
            dt,
            iterations,
            solver,
            ..StepSettings::default()
        })
        .unwrap();
        let (shape, pose) = table();
        let id = body
            .add_tool(shape, pose, ContactParams::default())
            .unwrap();
        let weight = body.total_mass() as f32 * G;
        let steps = (2.0 / dt) as usize;
        let f = settle(&mut body, steps, (0.2 / dt) as usize, |b| {
            b.tool_force(id).unwrap()
        });
        let err = (f.y + weight) / weight;
        eprintln!(
            "block {:.2} g on a tool, dt {dt} s, K {iterations}, {solver:?}: F = ({:.1}, {:.1}, {:.1}) dyn, weight {weight:.1} dyn, error {:+.3} %",
            body.total_mass(),
            f.x,
            f.y,
            f.z,
            err * 100.0
        );
        assert!(err.abs() < 0.02, "force {f} vs weight {weight}");
        assert!(f.x.abs() < 0.01 * weight && f.z.abs() < 0.01 * weight);
    }
}

/// A soft block (XPBD) on a tray (a voxel collider with friction, so that it can not slide
/// away) with a frictionless vertical probe pressed `depth` cm into its top centre; returns the
/// probe's and the tray's forces, averaged over the last steps, and the weight.
fn pressed(depth: f32, steps: usize) -> (Vec3, Vec3, f32) {
    let mesh = block(8, 4, Vec3::new(4.0, 2.0, 4.0), 0.0);
    let material = Material {
        distance_compliance: 2e-5,
        volume_compliance: 2e-5,
        volume: VolumeConstraintKind::Centroid,
        ..Material::default()
    };
    let mut body = SoftBody::new(&mesh, &material).unwrap();
    body.set_settings(StepSettings {
        dt: 0.005,
        iterations: 20,
        solver: Solver::Xpbd,
        damping: 0.05,
        ..StepSettings::default()
    })
    .unwrap();
    let tray =
        VoxelCollider::from_box(OrientedBox::tray(0.0, 0.0, 0.0, 20.0, 20.0, 2.0), 0.5).unwrap();
    let tray = body.add_collider(tray, ContactParams::default()).unwrap();
    let radius = 0.6;
    let probe = ToolShape::Capsule {
        a: Vec3::ZERO,
        b: Vec3::new(0.0, 5.0, 0.0),
        radius,
    };
    let tip = |y: f32| Pose::from_translation(Vec3::new(0.0, y + radius, 0.0));
    let id = body
        .add_tool(probe, tip(2.5), ContactParams::frictionless())
        .unwrap();
    // Settle first, then lower the probe over 100 steps, then hold it.
    let weight = body.total_mass() as f32 * G;
    settle(&mut body, 200, 1, |_| Vec3::ZERO);
    let top = body
        .positions()
        .iter()
        .filter(|p| p.x.abs() < 0.3 && p.z.abs() < 0.3)
        .map(|p| p.y)
        .fold(f32::MIN, f32::max);
    for i in 1..=100 {
        let y = 2.5 + (top - depth - 2.5) * i as f32 / 100.0;
        body.set_tool_pose(id, tip(y)).unwrap();
        body.step().unwrap();
    }
    let probe_force = settle(&mut body, steps, 50, |b| b.tool_force(id).unwrap());
    let mut floor = Vec3::ZERO;
    for _ in 0..50 {
        body.step().unwrap();
        floor += body.collider_force(tray).unwrap();
    }
    (probe_force, floor / 50.0, weight)
}

#[test]
fn probe_pressed_deeper_is_pushed_back_harder_and_tray_and_probe_carry_the_weight() {
    let depths = [0.0f32, 0.1, 0.2, 0.3, 0.4];
    let mut last = -1.0f32;
    let mut forces = Vec::new();
    for &d in &depths {
        let (f, floor, weight) = pressed(d, 300);
        let balance = (floor.y + f.y + weight) / weight;
        eprintln!(
            "probe {d:.1} cm in: F = ({:.1}, {:.1}, {:.1}) dyn = {:.5} N; tray {:.1} dyn; weight {weight:.1} dyn; (tray + probe + weight)/weight = {:+.4}",
            f.x,
            f.y,
            f.z,
            f.y / DYN_PER_NEWTON,
            floor.y,
            balance
        );
        // Away from the tissue (up); growing with the depth.
        assert!(f.y >= last, "force {} at {d} cm after {last}", f.y);
        // Mostly vertical (tet_box's tets are not mirror-symmetric, so neither is the dent: a
        // few per cent sideways, which the tray's friction takes).
        assert!(f.x.abs() < 0.1 * f.y.max(1.0) && f.z.abs() < 0.1 * f.y.max(1.0));
        // Statics: the tray carries the weight plus the probe's push, sideways too.
        assert!(
            balance.abs() < 0.02,
            "tray {floor}, probe {f}, weight {weight}"
        );
        assert!((floor.x + f.x).abs() < 0.01 * weight && (floor.z + f.z).abs() < 0.01 * weight);
        last = f.y;
        forces.push(f.y);
    }
    assert!(forces[1] > 0.0, "a 0.1 cm press pushes the probe up");
    // Roughly linear for small presses: the spring of the press, F(0.2) ≈ 2 F(0.1).
    let ratio = forces[2] / forces[1];
    eprintln!(
        "stiffness of the press: {:.0}, {:.0}, {:.0}, {:.0} dyn/cm per 0.1 cm; F(0.2)/F(0.1) = {ratio:.2}",
        (forces[1] - forces[0]) / 0.1,
        (forces[2] - forces[1]) / 0.1,
        (forces[3] - forces[2]) / 0.1,
        (forces[4] - forces[3]) / 0.1
    );
    assert!((1.5..3.0).contains(&ratio), "F(0.2)/F(0.1) = {ratio}");
}

#[test]
fn no_force_away_from_the_tissue() {
    let mesh = block(4, 2, Vec3::new(2.0, 1.0, 2.0), 0.0);
    let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
    body.set_floor(Some(Floor::y(0.0))).unwrap();
    let probe = ToolShape::Capsule {
        a: Vec3::ZERO,
        b: Vec3::new(0.0, 5.0, 0.0),
        radius: 0.3,
    };
    let id = body
        .add_tool(
            probe,
            Pose::from_translation(Vec3::new(0.0, 3.0, 0.0)),
            ContactParams::default(),
        )
        .unwrap();
    assert_eq!(body.tool_force(id).unwrap(), Vec3::ZERO, "before any step");
    for _ in 0..50 {
        body.step().unwrap();
        assert_eq!(body.tool_force(id).unwrap(), Vec3::ZERO);
    }
    // The floor alone carries the block, and nothing holds it.
    let weight = body.total_mass() as f32 * G;
    assert!((body.floor_force().y + weight).abs() < 0.02 * weight);
    assert_eq!(body.holding_force(), Vec3::ZERO);
    assert!(body.tool_force(1).is_err() && body.collider_force(0).is_err());
}

#[test]
fn block_hanging_from_a_grasper_pulls_it_with_its_weight() {
    // Grasped at its top face (one attachment per node, as the trainer's appendix grasper) or
    // at a single node of it; then lifted at constant speed: still the weight.
    for single in [false, true] {
        let mesh = block(4, 4, Vec3::new(2.0, 2.0, 2.0), 0.0);
        let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
        body.set_settings(StepSettings {
            dt: 0.005,
            iterations: 20,
            damping: 0.05,
            ..StepSettings::default()
        })
        .unwrap();
        let top: Vec<u32> = (0..body.node_count() as u32)
            .filter(|&i| {
                let p = body.positions()[i as usize];
                p.y > 1.99 && (!single || (p.x.abs() < 1e-3 && p.z.abs() < 1e-3))
            })
            .collect();
        assert!(!top.is_empty());
        let mut grasp = Vec::new();
        for &i in &top {
            let p = Vec3::from(body.positions()[i as usize]);
            grasp.push((p, body.attach(i, p).unwrap()));
        }
        let weight = body.total_mass() as f32 * G;
        let f = settle(&mut body, 800, 100, |b| b.holding_force());
        let err = (f.y + weight) / weight;
        // Lifted 1 cm/s: at constant velocity still the weight.
        let mut lifted = Vec3::ZERO;
        for k in 1..=400 {
            for &(p, id) in &grasp {
                body.set_attachment_target(id, p + Vec3::new(0.0, 0.005 * k as f32, 0.0))
                    .unwrap();
            }
            body.step().unwrap();
            if k > 300 {
                lifted += body.holding_force() / 100.0;
            }
        }
        let err_lifted = (lifted.y + weight) / weight;
        eprintln!(
            "block {:.2} g hanging from {} attachment(s): F = ({:.2}, {:.1}, {:.2}) dyn, weight {weight:.1} dyn, error {:+.3} %; lifted at 1 cm/s: {:.1} dyn, error {:+.3} %",
            body.total_mass(),
            top.len(),
            f.x,
            f.y,
            f.z,
            err * 100.0,
            lifted.y,
            err_lifted * 100.0
        );
        assert!(err.abs() < 0.02, "hanging: {f} vs weight {weight}");
        assert!(
            err_lifted.abs() < 0.02,
            "lifted: {lifted} vs weight {weight}"
        );
        assert!(f.x.abs() < 0.01 * weight && f.z.abs() < 0.01 * weight);
    }
}
