//! A suture across an incision held open closes it; removing it lets the wound open again.
#![allow(clippy::unwrap_used)]

use glam::{Quat, Vec3};
use tissue_mesh::tet_box;
use tissue_pbd::{Material, Pose, SoftBody, StepSettings, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent, SurgerySettings};

/// A 4 × 2 × 2 cm block with an incision 1.2 cm deep in the plane x = 0.1 across its whole
/// width, its upper outer edges pulled 0.4 cm outward so that the wound gapes.
fn gaping_wound(settings: SurgerySettings) -> (SoftBody, Surgery) {
    let mesh = tet_box(8, 4, 4, Vec3::new(4.0, 2.0, 2.0)).unwrap();
    let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
    let mut surgery = Surgery::new(&body, settings).unwrap();
    let blade = ToolShape::Blade {
        a: Vec3::new(0.0, 0.0, -0.3),
        b: Vec3::new(0.0, 0.0, 0.3),
        c: Vec3::new(0.0, 3.0, 0.0),
        thickness: 0.01,
    };
    let at = |z: f32| Pose::new(Quat::IDENTITY, Vec3::new(0.1, -0.2, z));
    for k in 0..8 {
        let (z0, z1) = (-1.6 + 0.4 * k as f32, -1.2 + 0.4 * k as f32);
        surgery
            .cut(
                &mut body,
                &BladeSweep::new(&blade, &at(z0), &at(z1)).unwrap(),
            )
            .unwrap();
    }
    surgery.validate(&body).unwrap();
    assert_eq!(surgery.component_count(), 1);
    body.set_settings(StepSettings {
        gravity: Vec3::ZERO,
        ..StepSettings::default()
    })
    .unwrap();
    for i in 0..body.node_count() as u32 {
        let p = Vec3::from(body.positions()[i as usize]);
        if p.x.abs() > 1.99 && p.y > 0.4 {
            body.attach(i, p + Vec3::new(0.4 * p.x.signum(), 0.0, 0.0))
                .unwrap();
        }
    }
    for _ in 0..100 {
        body.step().unwrap();
    }
    (body, surgery)
}

fn gap(body: &SoftBody, nodes: [u32; 2]) -> f32 {
    let x = body.positions();
    x[nodes[0] as usize].distance(x[nodes[1] as usize])
}

#[test]
fn a_suture_across_an_open_incision_closes_it() {
    let (mut body, mut surgery) = gaping_wound(SurgerySettings::default());
    // The needle runs along x at mid-depth of the wound, from inside the left side to inside
    // the right side.
    let needle = ToolShape::Capsule {
        a: Vec3::new(-0.7, 0.0, 0.0),
        b: Vec3::new(0.7, 0.0, 0.0),
        radius: 0.02,
    };
    let event = surgery
        .suture(
            &mut body,
            &needle,
            &Pose::from_translation(Vec3::new(0.0, 0.55, 0.1)),
        )
        .unwrap()
        .unwrap();
    let SurgeryEvent::SuturePlaced { suture, nodes, .. } = event else {
        panic!("{event:?}");
    };
    let initial = gap(&body, nodes);
    assert!(initial > 0.2, "the wound should gape, gap {initial}");
    assert_ne!(nodes[0], nodes[1]);
    // The same needle again finds the same, already linked, pair: nothing new.
    assert!(surgery
        .suture(
            &mut body,
            &needle,
            &Pose::from_translation(Vec3::new(0.0, 0.55, 0.1))
        )
        .unwrap()
        .is_none());
    let mut closed_at = None;
    for step in 1..=50 {
        body.step().unwrap();
        if closed_at.is_none() && gap(&body, nodes) < 0.05 * initial {
            closed_at = Some(step);
        }
    }
    let last = gap(&body, nodes);
    eprintln!("suture: nodes {nodes:?}, gap {initial:.3} cm → < 5 % after {closed_at:?} steps, {last:.5} cm after 50");
    assert!(
        closed_at.is_some_and(|s| s <= 10),
        "closed at {closed_at:?}"
    );
    assert!(last < 0.05 * initial);

    // Removed, the wound opens again.
    let removed = surgery.remove_suture(&mut body, suture).unwrap();
    assert_eq!(removed, SurgeryEvent::SutureRemoved { suture, nodes });
    for _ in 0..100 {
        body.step().unwrap();
    }
    let reopened = gap(&body, nodes);
    eprintln!("suture removed: gap {reopened:.3} cm after 100 steps");
    assert!(reopened > 0.5 * initial);
    assert!(surgery.remove_suture(&mut body, suture).is_err());
}

#[test]
fn without_a_suture_the_wound_stays_open() {
    let (mut body, surgery) = gaping_wound(SurgerySettings::default());
    // The wall nodes at the top: a split node and its copy.
    let x = body.positions();
    let pair = (0..body.node_count() as u32)
        .filter(|&i| surgery.origins()[i as usize] != i)
        .map(|i| [surgery.origins()[i as usize], i])
        .max_by(|a, b| x[a[0] as usize].y.total_cmp(&x[b[0] as usize].y))
        .unwrap();
    let before = gap(&body, pair);
    for _ in 0..50 {
        body.step().unwrap();
    }
    let after = gap(&body, pair);
    eprintln!("no suture: wall gap {before:.3} → {after:.3} cm");
    assert!(before > 0.3 && after > 0.9 * before);
}

#[test]
fn a_softer_suture_pulls_less_against_the_held_tissue() {
    // With k < 1 the link meets the tissue (k = 1, held open by the attachments) at an
    // equilibrium: the stiffer the suture, the smaller the gap left.
    let mut left = Vec::new();
    for k in [0.2f32, 0.6, 0.95] {
        let settings = SurgerySettings {
            suture_stiffness: k,
            ..SurgerySettings::default()
        };
        let (mut body, mut surgery) = gaping_wound(settings);
        let needle = ToolShape::Capsule {
            a: Vec3::new(-0.7, 0.0, 0.0),
            b: Vec3::new(0.7, 0.0, 0.0),
            radius: 0.02,
        };
        let Some(SurgeryEvent::SuturePlaced { nodes, .. }) = surgery
            .suture(
                &mut body,
                &needle,
                &Pose::from_translation(Vec3::new(0.0, 0.55, 0.1)),
            )
            .unwrap()
        else {
            panic!("no suture placed");
        };
        let initial = gap(&body, nodes);
        for _ in 0..100 {
            body.step().unwrap();
        }
        left.push(gap(&body, nodes) / initial);
    }
    eprintln!("suture stiffness 0.2, 0.6, 0.95: gap left {left:?} of the initial");
    assert!(left[0] > left[1] && left[1] > left[2], "{left:?}");
    assert!(left[2] < 0.8, "{left:?}");
}
