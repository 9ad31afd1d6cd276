//! The step presets (the real-time preset, "physics defaults that hold"): the real-time preset keeps a pressed organ's volume, the legacy
//! scheme is still there, substeps are validated and move tools along their path.
#![allow(clippy::print_stderr, clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::{
    ContactParams, Material, OrientedBox, PbdError, PbdParam, Pose, SoftBody, Solver, StepSettings,
    ToolShape, VolumeConstraintKind, VoxelCollider,
};

/// A 4 × 4 × 4 cm block (12³ cells) on a tray, settled for 30 steps, pressed 1.2 cm by a probe of
/// radius 0.4 over 30 steps and dragged 1.5 cm over 30: the largest `|V/V₀ − 1|` after any step
/// (V₀ as built).
fn worst_drift(material: &Material, settings: StepSettings) -> f64 {
    let (p, t) = tet_box(12, 12, 12, Vec3::splat(4.0)).unwrap().into_parts();
    let block = TetMesh::new(p.iter().map(|p| *p + 2.0 * Vec3::Y).collect(), t).unwrap();
    let mut body = SoftBody::new(&block, material).unwrap();
    body.set_settings(settings).unwrap();
    let tray =
        VoxelCollider::from_box(OrientedBox::tray(0.0, 0.0, 0.0, 20.0, 20.0, 2.0), 0.5).unwrap();
    body.add_collider(tray, ContactParams::default()).unwrap();
    let probe = ToolShape::Capsule {
        a: Vec3::ZERO,
        b: Vec3::new(0.0, 5.0, 0.0),
        radius: 0.4,
    };
    let id = body
        .add_tool(
            probe,
            Pose::from_translation(Vec3::new(-0.75, 10.0, 0.0)),
            ContactParams::default(),
        )
        .unwrap();
    let mut worst = 0.0f64;
    for step in 0..90 {
        let tip = if step < 30 {
            Vec3::new(-0.75, 10.0, 0.0)
        } else if step < 60 {
            let k = (step - 29) as f32 / 30.0;
            Vec3::new(-0.75, 4.4 - 1.6 * k, 0.0)
        } else {
            let k = (step - 59) as f32 / 30.0;
            Vec3::new(-0.75 + 1.5 * k, 2.8, 0.0)
        };
        body.set_tool_pose(id, Pose::from_translation(tip)).unwrap();
        body.step().unwrap();
        worst = worst.max((body.volume() / body.rest_volume() - 1.0).abs());
    }
    assert!(
        body.contacts()
            .iter()
            .any(|c| c.source == tissue_pbd::ContactSource::Tool(id)),
        "the probe should be pressing at the end"
    );
    worst
}

#[test]
fn realtime_preset_holds_a_pressed_blocks_volume() {
    let mut material = Material::soft_tissue();
    if std::env::var("NOPIECE").is_ok() {
        material.hold_piece_volumes = false;
    }
    let realtime = worst_drift(&material, StepSettings::realtime());
    let tets_only = worst_drift(
        &Material {
            hold_piece_volumes: false,
            ..material
        },
        StepSettings::realtime(),
    );
    let legacy = worst_drift(
        &Material {
            hold_piece_volumes: false,
            ..material
        },
        StepSettings::legacy(),
    );
    let none = worst_drift(
        &Material {
            volume: VolumeConstraintKind::None,
            hold_piece_volumes: false,
            ..material
        },
        StepSettings::realtime(),
    );
    eprintln!(
        "worst |drift|: realtime {:.3} %, its tet constraints alone {:.3} %, legacy {:.3} %, \
         realtime without volume {:.3} %",
        realtime * 100.0,
        tets_only * 100.0,
        legacy * 100.0,
        none * 100.0
    );
    // Issue 19: |drift| ≤ 2 % over the press and drag. Measured: realtime 0.00x %, the tet
    // constraints alone 4.03 %, legacy 14.4 %, without volume constraints 69.7 %.
    assert!(realtime <= 0.005, "realtime worst drift {realtime}");
    assert!(
        tets_only > 0.02,
        "tets alone {tets_only}: the piece constraint is needed"
    );
    assert!(legacy > 3.0 * tets_only, "legacy {legacy}");
    assert!(none > 10.0 * tets_only, "without volume {none}");
}

#[test]
fn legacy_scheme_is_reachable_and_unchanged() {
    let legacy = StepSettings::legacy();
    assert_eq!(
        (legacy.dt, legacy.substeps, legacy.iterations, legacy.solver),
        (0.01, 1, 10, Solver::PbdLinearised)
    );
    assert_eq!(
        legacy,
        StepSettings {
            damping: 0.05,
            ..StepSettings::default()
        }
    );
    let realtime = StepSettings::realtime();
    assert_eq!(realtime.dt, legacy.dt, "one step is still one 10 ms frame");
    assert_eq!(
        (realtime.substeps, realtime.iterations),
        (StepSettings::REALTIME_SUBSTEPS, 1)
    );
    assert_eq!(realtime.substep_dt(), 0.01 / realtime.substeps as f32);
}

#[test]
fn zero_substeps_are_refused() {
    let mesh = tet_box(2, 2, 2, Vec3::ONE).unwrap();
    let mut body = SoftBody::new(&mesh, &Material::soft_tissue()).unwrap();
    let err = body
        .set_settings(StepSettings {
            substeps: 0,
            ..StepSettings::realtime()
        })
        .unwrap_err();
    assert!(matches!(
        err,
        PbdError::InvalidParameter {
            param: PbdParam::Substeps,
            ..
        }
    ));
}

#[test]
fn substeps_sweep_the_tool_in_parts_and_end_at_the_host_pose() {
    let mesh = tet_box(2, 2, 2, Vec3::ONE).unwrap();
    let mut body = SoftBody::new(&mesh, &Material::soft_tissue()).unwrap();
    body.set_settings(StepSettings::realtime()).unwrap();
    let probe = ToolShape::Capsule {
        a: Vec3::ZERO,
        b: Vec3::Y,
        radius: 0.1,
    };
    let id = body
        .add_tool(
            probe,
            Pose::from_translation(Vec3::new(5.0, 0.0, 0.0)),
            ContactParams::default(),
        )
        .unwrap();
    let to = Pose::from_translation(Vec3::new(6.0, 0.0, 0.0));
    body.set_tool_pose(id, to).unwrap();
    body.step().unwrap();
    let tool = body.tool(id).unwrap();
    assert_eq!(tool.pose(), to);
    assert_eq!(tool.start_pose(), to);
    // The last substep swept the last eighth of the path.
    let (from, end) = tool.last_sweep();
    assert_eq!(end, to);
    let expected = 6.0 - 1.0 / StepSettings::REALTIME_SUBSTEPS as f32;
    assert!((from.translation.x - expected).abs() < 1e-5, "{from:?}");
}

/// An 8 × 4 × 4 cm bar (8 × 4 × 4 cells) cut at x = 0 into two pieces: the nodes on the cut are
/// duplicated and the right half's tets moved onto the copies. Returns the body and whether
/// each tet is in the right piece.
fn cut_bar(material: &Material) -> (SoftBody, Vec<bool>) {
    let mesh = tet_box(8, 4, 4, Vec3::new(8.0, 4.0, 4.0)).unwrap();
    let mut body = SoftBody::new(&mesh, material).unwrap();
    let x: Vec<Vec3> = body.positions().iter().map(|&p| p.into()).collect();
    let on_cut: Vec<u32> = (0..x.len() as u32)
        .filter(|&i| x[i as usize].x.abs() < 1e-4)
        .collect();
    let first = body.duplicate_nodes(&on_cut).unwrap();
    let copy = |i: u32| {
        on_cut
            .iter()
            .position(|&c| c == i)
            .map_or(i, |k| first + k as u32)
    };
    let mut right = Vec::new();
    for t in 0..body.tets().len() {
        let nodes = body.tets()[t];
        let centre: Vec3 = nodes.iter().map(|&i| x[i as usize]).sum::<Vec3>() / 4.0;
        right.push(centre.x > 0.0);
        if centre.x > 0.0 {
            body.set_tet_nodes(t, nodes.map(copy)).unwrap();
        }
    }
    (body, right)
}

/// The volume of the tets with `mask[t] == want`.
fn part_volume(body: &SoftBody, mask: &[bool], want: bool) -> f64 {
    let x = body.positions();
    body.tets()
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m == want)
        .map(|(t, _)| {
            let [a, b, c, d] = t.map(|i| x[i as usize].as_dvec3());
            (b - a).cross(c - a).dot(d - a) / 6.0
        })
        .sum()
}

#[test]
fn each_piece_holds_its_own_volume_and_the_momentum_is_kept() {
    let (mut body, right) = cut_bar(&Material::soft_tissue());
    body.set_settings(StepSettings {
        gravity: Vec3::ZERO,
        damping: 0.0,
        ..StepSettings::realtime()
    })
    .unwrap();
    // Squash the right piece to 0.7 of its height and set everything spinning and drifting.
    let x: Vec<Vec3> = body.positions().iter().map(|&p| p.into()).collect();
    let mut moved = x.clone();
    let right_nodes: Vec<bool> = {
        let mut r = vec![false; x.len()];
        for (t, &is_right) in body.tets().iter().zip(&right) {
            for &i in t {
                r[i as usize] |= is_right;
            }
        }
        r
    };
    for (p, &r) in moved.iter_mut().zip(&right_nodes) {
        if r {
            p.y *= 0.7;
        }
    }
    body.set_positions(&moved).unwrap();
    let v: Vec<Vec3> = x
        .iter()
        .map(|p| Vec3::new(3.0, -1.0, 0.5) + Vec3::new(0.0, 0.0, 2.0).cross(*p))
        .collect();
    body.set_velocities(&v).unwrap();
    let (left0, right0) = (8.0 * 4.0 * 4.0 / 2.0, 8.0 * 4.0 * 4.0 / 2.0);
    let p0 = body.linear_momentum();
    body.step().unwrap();
    let (left, right_v) = (
        part_volume(&body, &right, false),
        part_volume(&body, &right, true),
    );
    eprintln!("after one step: left piece {left:.4} cm³, right piece {right_v:.4} cm³");
    // The squashed piece is restored within the step, and the other piece does not swell to
    // make up for it (as one constraint over the whole body would have it).
    assert!((right_v / right0 - 1.0).abs() < 0.01, "right {right_v}");
    assert!((left / left0 - 1.0).abs() < 0.001, "left {left}");
    for _ in 0..19 {
        body.step().unwrap();
    }
    let (left, right_v) = (
        part_volume(&body, &right, false),
        part_volume(&body, &right, true),
    );
    eprintln!(
        "left piece {:.4} cm³, right piece {:.4} cm³ (rest {left0} each)",
        left, right_v
    );
    assert!((right_v / right0 - 1.0).abs() < 0.005, "right {right_v}");
    assert!((left / left0 - 1.0).abs() < 0.005, "left {left}");
    // Internal constraints only: the linear momentum is kept (to float precision; the angular
    // momentum of the projection itself is checked in the unit tests of `pieces.rs`: PBD's
    // velocity update keeps it only to second order in the corrections).
    let p = body.linear_momentum();
    assert!((p - p0).length() < 1e-3 * p0.length(), "{p0} → {p}");
}

/// The real-time preset leaves an organ resting on the floor still: after 3 s on a frictionless
/// floor, a 4 × 4 × 2 cm block (8 × 4 × 8 cells, its piece's volume held) has no node faster
/// than 0.5 cm/s over the last 0.2 s, relative to its rigid motion or not (0.31 and 0.28 cm/s,
/// 2026-11-29). The pieces' volume correction of the last substep is positional only; given
/// as a velocity (as before that date) it kicked the surface outward every step, by 7.9 cm/s
/// here, which the next substeps pulled back (the surface breathed, and self-collision's
/// travels with it).
#[test]
fn realtime_preset_leaves_a_resting_organ_still() {
    let (p, t) = tet_box(8, 4, 8, Vec3::new(4.0, 2.0, 4.0))
        .unwrap()
        .into_parts();
    // Its bottom 0.05 cm above the floor.
    let block = TetMesh::new(p.iter().map(|p| *p + 1.05 * Vec3::Y).collect(), t).unwrap();
    let material = Material::soft_tissue();
    assert!(material.hold_piece_volumes);
    let mut body = SoftBody::new(&block, &material).unwrap();
    body.set_settings(StepSettings::realtime()).unwrap();
    body.set_floor(Some(tissue_pbd::Floor::y(0.0))).unwrap();
    let (mut deformation, mut speed) = (0.0f32, 0.0f32);
    for s in 0..300 {
        body.step().unwrap();
        if s >= 280 {
            deformation = deformation.max(crate::common::fastest_deformation(&body));
            speed = (body.velocities().iter()).fold(speed, |m, v| m.max(v.length()));
        }
    }
    eprintln!(
        "resting block: fastest node {speed:.3} cm/s, {deformation:.3} cm/s relative to its \
         rigid motion"
    );
    assert!(deformation < 0.5 && speed < 0.5, "{deformation} {speed}");
}
