//! Bad input is refused with an error naming the element.
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::tet_box;
use tissue_pbd::{Material, PbdError, PbdParam, SoftBody, StepSettings};

fn corners() -> Vec<Vec3> {
    vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        Vec3::new(1.0, 1.0, 0.0),
    ]
}

#[test]
fn bad_input_is_refused_naming_the_element() {
    let m = Material::default();
    let bad_k = Material {
        distance_stiffness: 1.5,
        ..m
    };
    assert!(matches!(
        SoftBody::from_tets(&corners(), &[[0, 1, 2, 3]], &bad_k),
        Err(PbdError::InvalidParameter {
            param: PbdParam::DistanceStiffness,
            ..
        })
    ));
    let bad_k = Material {
        volume_stiffness: -0.1,
        ..m
    };
    assert!(matches!(
        SoftBody::from_tets(&corners(), &[[0, 1, 2, 3]], &bad_k),
        Err(PbdError::InvalidParameter {
            param: PbdParam::VolumeStiffness,
            ..
        })
    ));
    assert_eq!(
        SoftBody::from_tets(&corners(), &[[0, 1, 2, 3], [0, 1, 2, 9]], &m).unwrap_err(),
        PbdError::NodeOutOfRange {
            element: "tet",
            index: 1,
            node: 9,
            count: 5
        }
    );
    // Tet 1 is flat (all in z = 0); tet 2 is inverted.
    let e = SoftBody::from_tets(&corners(), &[[0, 1, 2, 3], [0, 1, 2, 4], [0, 2, 1, 3]], &m)
        .unwrap_err();
    assert!(matches!(e, PbdError::DegenerateTet { tet: 1, .. }), "{e}");
    let e = SoftBody::from_tets(&corners(), &[[0, 1, 2, 3], [0, 2, 1, 3]], &m).unwrap_err();
    assert!(matches!(e, PbdError::DegenerateTet { tet: 1, .. }), "{e}");
    assert!(e.to_string().contains("tet 1"));

    let mut body = SoftBody::new(&tet_box(1, 1, 1, Vec3::ONE).unwrap(), &m).unwrap();
    for (settings, name) in [
        (
            StepSettings {
                dt: 0.0,
                ..StepSettings::default()
            },
            PbdParam::Dt,
        ),
        (
            StepSettings {
                dt: -1.0,
                ..StepSettings::default()
            },
            PbdParam::Dt,
        ),
        (
            StepSettings {
                iterations: 0,
                ..StepSettings::default()
            },
            PbdParam::Iterations,
        ),
        (
            StepSettings {
                damping: 2.0,
                ..StepSettings::default()
            },
            PbdParam::Damping,
        ),
    ] {
        assert!(
            matches!(body.set_settings(settings), Err(PbdError::InvalidParameter { param, .. }) if param == name)
        );
    }
    assert!(matches!(
        body.pin(8),
        Err(PbdError::NodeOutOfRange {
            node: 8,
            count: 8,
            ..
        })
    ));
    assert!(matches!(
        body.attach(99, Vec3::ZERO),
        Err(PbdError::NodeOutOfRange {
            element: "attachment",
            ..
        })
    ));
    // An id whose node was freed is refused.
    let stale = body.attach(3, Vec3::ZERO).unwrap();
    body.unpin(3).unwrap();
    assert!(matches!(
        body.set_attachment_target(stale, Vec3::ZERO),
        Err(PbdError::NoSuchAttachment { id, count: 0 }) if id == stale
    ));
    assert!(matches!(
        body.set_velocities(&[Vec3::ZERO]),
        Err(PbdError::LengthMismatch { .. })
    ));
}

#[test]
fn pins_and_attachments_move_as_told() {
    let mesh = tet_box(4, 1, 1, Vec3::new(4.0, 1.0, 1.0)).unwrap();
    let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
    body.pin(0).unwrap();
    let id = body.attach(4, mesh.positions()[4]).unwrap();
    let start = mesh.positions()[4];
    for i in 1..=10 {
        body.set_attachment_target(id, start + Vec3::new(0.0, 0.1 * i as f32, 0.0))
            .unwrap();
        body.step().unwrap();
    }
    assert_eq!(Vec3::from(body.positions()[0]), mesh.positions()[0]);
    assert!((Vec3::from(body.positions()[4]) - (start + Vec3::new(0.0, 1.0, 0.0))).length() < 1e-6);
    assert!(
        (body.velocities()[4].y - 10.0).abs() < 1e-3,
        "kinematic velocity {}",
        body.velocities()[4]
    );
    // Masses follow eq. (1): they sum to density × volume.
    assert!((body.total_mass() - mesh.volume()).abs() < 1e-4 * mesh.volume());
}

/// Freeing one attached node leaves the other attachments' ids pointing at their own nodes
/// (regression: `unpin` used to remove with `retain`, shifting the later ids onto other nodes).
#[test]
fn unpinning_one_attachment_keeps_the_others_ids() {
    let mesh = tet_box(4, 1, 1, Vec3::new(4.0, 1.0, 1.0)).unwrap();
    let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
    let (a, b, c) = (1u32, 4u32, 7u32);
    let p = |n: u32| mesh.positions()[n as usize];
    let id_a = body.attach(a, p(a)).unwrap();
    let id_b = body.attach(b, p(b)).unwrap();
    let id_c = body.attach(c, p(c)).unwrap();
    body.unpin(a).unwrap();
    // A new attachment may reuse A's slot, never A's id.
    let id_d = body.attach(a, p(a)).unwrap();
    assert_ne!(id_d, id_a);
    let lift = Vec3::new(0.0, 0.5, 0.0);
    body.set_attachment_target(id_b, p(b) + lift).unwrap();
    body.step().unwrap();
    let x = |n: u32| Vec3::from(body.positions()[n as usize]);
    assert!(
        (x(b) - (p(b) + lift)).length() < 1e-6,
        "B's node moved to B's target"
    );
    assert!((x(c) - p(c)).length() < 1e-6, "C's node stayed");
    assert!(
        (x(a) - p(a)).length() < 1e-6,
        "A's node, attached again, stayed"
    );
    // The stale id is refused; the others still work.
    assert!(matches!(
        body.set_attachment_target(id_a, Vec3::ZERO),
        Err(PbdError::NoSuchAttachment { .. })
    ));
    body.set_attachment_target(id_c, p(c) + lift).unwrap();
    body.set_attachment_target(id_d, p(a) + lift).unwrap();
    body.step().unwrap();
    let x = |n: u32| Vec3::from(body.positions()[n as usize]);
    assert!((x(c) - (p(c) + lift)).length() < 1e-6);
    assert!((x(a) - (p(a) + lift)).length() < 1e-6);
    assert!((x(b) - (p(b) + lift)).length() < 1e-6);
}
