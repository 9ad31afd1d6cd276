//! Cuts through a block: a full cut makes two pieces that come apart; a partial incision opens
//! the surface along its length and leaves one piece.
#![allow(clippy::unwrap_used, clippy::print_stderr)]

use crate::common;

use glam::Vec3;
use tissue_pbd::{Pose, SoftBody, StepSettings, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent};

fn piece_volumes(body: &SoftBody, surgery: &Surgery) -> Vec<(u32, f64)> {
    let mut v: Vec<(u32, f64)> = Vec::new();
    for (t, &c) in surgery.tet_components().iter().enumerate() {
        let vol = body.tet_rest_volumes()[t] as f64;
        match v.iter_mut().find(|e| e.0 == c) {
            Some(e) => e.1 += vol,
            None => v.push((c, vol)),
        }
    }
    v
}

/// Mean y of the nodes of the tets of one component.
fn piece_height(body: &SoftBody, surgery: &Surgery, component: u32) -> f32 {
    let (mut sum, mut n) = (0.0, 0);
    for (t, &c) in surgery.tet_components().iter().enumerate() {
        if c == component {
            for &i in &body.tets()[t] {
                sum += body.positions()[i as usize].y;
                n += 1;
            }
        }
    }
    sum / n as f32
}

fn fall(body: &mut SoftBody) {
    body.set_settings(StepSettings {
        dt: 0.01,
        iterations: 10,
        ..StepSettings::default()
    })
    .unwrap();
    let pinned: Vec<u32> = (0..body.node_count() as u32)
        .filter(|&i| body.positions()[i as usize].x < -2.7)
        .collect();
    for i in pinned {
        body.pin(i).unwrap();
    }
    for _ in 0..40 {
        body.step().unwrap();
    }
}

#[test]
fn a_full_cut_makes_two_pieces_and_the_free_one_falls_away() {
    full_cut(true);
    full_cut(false);
}

fn full_cut(split: bool) {
    let (mut body, mut surgery) = common::block(split);
    let total = body.rest_volume();
    let blade = ToolShape::Blade {
        a: Vec3::new(0.0, 0.0, -5.0),
        b: Vec3::new(0.0, 0.0, 5.0),
        c: Vec3::new(0.0, 5.0, 0.0),
        thickness: 0.01,
    };
    // Drawn down through the block in the plane x = 0.3, in four steps.
    let mut detached = 0;
    for k in 0..4 {
        let from = Pose::from_translation(Vec3::new(0.3, 2.0 - 1.5 * k as f32, 0.0));
        let to = Pose::from_translation(Vec3::new(0.3, 0.5 - 1.5 * k as f32, 0.0));
        let events = surgery
            .cut(&mut body, &BladeSweep::new(&blade, &from, &to).unwrap())
            .unwrap();
        surgery.validate(&body).unwrap();
        detached += events
            .iter()
            .filter(|e| matches!(e, SurgeryEvent::PieceDetached { .. }))
            .count();
    }
    assert_eq!(surgery.component_count(), 2);
    assert_eq!(detached, 1);
    let pieces = piece_volumes(&body, &surgery);
    let sum: f64 = pieces.iter().map(|p| p.1).sum();
    eprintln!("full cut (split {split}): piece volumes {pieces:?}, sum {sum:.4} of {total:.4} cm³");
    assert!((sum / total - 1.0).abs() < 0.01);
    // The plane at x = 0.3 splits 54 : 54 cm³ into 33 : 21 up to one layer of cells (±4.5 cm³).
    let left = pieces.iter().find(|p| p.0 == 0).unwrap().1;
    assert!((left - 29.7).abs() < 4.5, "left piece {left}");
    // Mass is conserved by the local rebuild.
    assert!((body.total_mass() - total).abs() < 1e-3 * total);

    // The left end is pinned; under gravity the right piece falls away, the left one stays.
    let right = pieces.iter().find(|p| p.0 != 0).unwrap().0;
    fall(&mut body);
    let (hl, hr) = (
        piece_height(&body, &surgery, 0),
        piece_height(&body, &surgery, right),
    );
    eprintln!("after 0.4 s: left piece mean y {hl:.3} cm, right piece mean y {hr:.3} cm");
    assert!(hr < -50.0, "the free piece should fall ~78 cm, is at {hr}");
    assert!(hl > -1.5, "the pinned piece should hang on, is at {hl}");

    // Control: the uncut block under the same pins does not come apart.
    let (mut whole, surgery) = common::block(split);
    fall(&mut whole);
    let h = piece_height(&whole, &surgery, 0);
    assert!(h > -5.0, "uncut block sags to {h}");
}

#[test]
fn a_partial_incision_opens_the_surface_along_its_length_and_keeps_one_piece() {
    partial_incision(true);
    partial_incision(false);
}

fn partial_incision(geometric: bool) {
    let (mut body, mut surgery) = common::block(geometric);
    // A blade standing up in the plane z = 0.15, its lower edge 1 cm below the top (y = 1.5),
    // drawn along x from −1.5 to 1.5 in ten steps.
    let blade = common::incision_blade();
    let at = common::incision_pose;
    // The top triangles the plane z = 0.15 crosses well inside the path (rest positions).
    let rest = |body: &SoftBody, v: u32| body.rest_positions()[v as usize].as_dvec3();
    let crossed: Vec<[glam::DVec3; 3]> = surgery
        .boundary_faces(&body)
        .into_iter()
        .map(|f| f.map(|v| rest(&body, v)))
        .filter(|p| p.iter().all(|q| (q.y - 1.5).abs() < 1e-6))
        .filter(|p| p.iter().any(|q| q.z < 0.15) && p.iter().any(|q| q.z > 0.15))
        .filter(|p| p.iter().all(|q| q.x.abs() <= 1.0 + 1e-6))
        .collect();
    let mut opened = 0;
    for k in 0..10 {
        let (x0, x1) = (-1.5 + 0.3 * k as f32, -1.5 + 0.3 * (k + 1) as f32);
        let events = surgery
            .cut(
                &mut body,
                &BladeSweep::new(&blade, &at(x0), &at(x1)).unwrap(),
            )
            .unwrap();
        surgery.validate(&body).unwrap();
        for e in &events {
            if let SurgeryEvent::CutAdvanced { opened_faces, .. } = e {
                opened += opened_faces.len();
            }
            assert!(!matches!(e, SurgeryEvent::PieceDetached { .. }));
        }
    }
    assert_eq!(surgery.component_count(), 1);
    assert!(opened > 0);
    if geometric {
        // Into how many boundary pieces each crossed top triangle was split (by the pieces'
        // rest centroids), and how the sweeps' ends were split.
        let top: Vec<glam::DVec3> = surgery
            .boundary_faces(&body)
            .into_iter()
            .map(|f| f.map(|v| rest(&body, v)))
            .filter(|p| p.iter().all(|q| (q.y - 1.5).abs() < 1e-6))
            .map(|p| (p[0] + p[1] + p[2]) / 3.0)
            .collect();
        let inside = |t: &[glam::DVec3; 3], c: glam::DVec3| {
            let s = |a: glam::DVec3, b: glam::DVec3| {
                (b.x - a.x) * (c.z - a.z) - (b.z - a.z) * (c.x - a.x)
            };
            let (u, v, w) = (s(t[0], t[1]), s(t[1], t[2]), s(t[2], t[0]));
            (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0)
        };
        let counts: Vec<usize> = crossed
            .iter()
            .map(|t| top.iter().filter(|&&c| inside(t, c)).count())
            .collect();
        eprintln!(
            "partial incision: crossed top triangles in {counts:?} pieces; tips {:?}",
            surgery.tip_counts()
        );
        assert!(counts.iter().all(|&n| (2..=5).contains(&n)), "{counts:?}");
    }
    // The opening on the top: the top nodes that were split, and their copies.
    let x = body.positions();
    let split: Vec<f32> = (0..body.node_count())
        .filter(|&i| surgery.origins()[i] as usize != i)
        .map(|i| surgery.origins()[i] as usize)
        .filter(|&o| (x[o].y - 1.5).abs() < 1e-4)
        .map(|o| x[o].x)
        .collect();
    let lo = split.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = split.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    // The blade's width at the top surface is ±0.2 cm, so the cut spans x ∈ [−1.7, 1.7]: 3.4 cm.
    let length = hi - lo;
    eprintln!("partial incision (split {geometric}): opening on top from x = {lo} to {hi}: {length} cm (blade 3.4 cm)");
    assert!((length - 3.4).abs() <= 0.5 + 1e-4, "opening {length} cm");
    // It does not go through: no node at the bottom was split.
    assert!((0..body.node_count())
        .filter(|&i| surgery.origins()[i] as usize != i)
        .all(|i| x[i].y > -0.5));
    // The body still steps.
    body.set_settings(StepSettings::default()).unwrap();
    for _ in 0..10 {
        body.step().unwrap();
    }
}

/// A state refuses another body of the same size (regression: the check compared counts only),
/// leaving both bodies untouched, and takes a clone of its own body (a snapshot of it).
#[test]
fn a_state_refuses_another_body_of_the_same_size() {
    use tissue_surgery::SurgeryError;
    let (mut body, mut surgery) = common::block(true);
    let (mut other, _) = common::block(true);
    assert_eq!(
        (other.node_count(), other.tets().len()),
        (body.node_count(), body.tets().len())
    );
    assert_ne!(other.id(), body.id());
    let blade = ToolShape::Blade {
        a: Vec3::new(0.0, 0.0, -5.0),
        b: Vec3::new(0.0, 0.0, 5.0),
        c: Vec3::new(0.0, 5.0, 0.0),
        thickness: 0.01,
    };
    let sweep = BladeSweep::new(
        &blade,
        &Pose::from_translation(Vec3::new(0.3, 2.0, 0.0)),
        &Pose::from_translation(Vec3::new(0.3, 0.5, 0.0)),
    )
    .unwrap();
    let before = other.positions().to_vec();
    let refused = surgery.cut(&mut other, &sweep);
    assert!(
        matches!(
            refused,
            Err(SurgeryError::BodyMismatch {
                what: "body id",
                ..
            })
        ),
        "{refused:?}"
    );
    assert_eq!(other.positions(), &before[..]);
    assert_eq!(other.tets().len(), body.tets().len());
    assert!(matches!(
        surgery.validate(&other),
        Err(SurgeryError::BodyMismatch { .. })
    ));
    // Its own body, and a clone of the pair, are accepted.
    let (mut snapshot, mut snapshot_surgery) = (body.clone(), surgery.clone());
    assert!(!surgery.cut(&mut body, &sweep).unwrap().is_empty());
    surgery.validate(&body).unwrap();
    assert!(!snapshot_surgery
        .cut(&mut snapshot, &sweep)
        .unwrap()
        .is_empty());
    snapshot_surgery.validate(&snapshot).unwrap();
}
