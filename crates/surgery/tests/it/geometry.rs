//! The geometry of a cut: walls flat on the blade's plane (nodes snapped onto it or created on
//! the crossed edges), the crossed surface triangles split into 3 along the path (5 where a sweep
//! ended inside one), rest volume conserved by every split, no tet below the quality bound.
#![allow(clippy::unwrap_used)]

use crate::common;

use common::{check_quality, rest};

use glam::{DVec3, Vec3};
use tissue_pbd::{Pose, SoftBody, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent};

/// A big blade in the plane x = `x`, drawn down through the whole block in four steps.
fn full_cut(body: &mut SoftBody, surgery: &mut Surgery, x: f32) -> Vec<SurgeryEvent> {
    let blade = ToolShape::Blade {
        a: Vec3::new(0.0, 0.0, -5.0),
        b: Vec3::new(0.0, 0.0, 5.0),
        c: Vec3::new(0.0, 5.0, 0.0),
        thickness: 0.01,
    };
    let mut events = Vec::new();
    for k in 0..4 {
        let from = Pose::from_translation(Vec3::new(x, 2.0 - 1.5 * k as f32, 0.0));
        let to = Pose::from_translation(Vec3::new(x, 0.5 - 1.5 * k as f32, 0.0));
        events.extend(
            surgery
                .cut(body, &BladeSweep::new(&blade, &from, &to).unwrap())
                .unwrap(),
        );
        surgery.validate(body).unwrap();
    }
    events
}

/// Nodes of the cut walls (faces opened by cuts).
fn wall_nodes(body: &SoftBody, surgery: &Surgery) -> Vec<u32> {
    let mut v: Vec<u32> = surgery
        .cut_faces()
        .iter()
        .flat_map(|&(t, j)| {
            let tet = body.tets()[t as usize];
            (0..4)
                .filter(move |&k| k != j as usize)
                .map(move |k| tet[k])
        })
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

#[test]
fn a_full_cut_makes_flat_walls_on_the_blade_plane_and_keeps_the_volume() {
    let (mut body, mut surgery) = common::block(true);
    let total = body.rest_volume();
    let events = full_cut(&mut body, &mut surgery, 0.3);
    assert_eq!(surgery.component_count(), 2);
    // x = 0.3 lies 0.2 and 0.3 cm from the node planes (≥ 0.25 × 0.5 cm): nothing snaps, the
    // crossed tets are split.
    let (mut split, mut snapped) = (0, 0);
    for e in &events {
        if let SurgeryEvent::CutAdvanced {
            split_tets,
            snapped_nodes,
            ..
        } = e
        {
            split += split_tets.len();
            snapped += snapped_nodes.len();
        }
    }
    assert!(split > 0);
    assert_eq!(snapped, 0);
    let walls = wall_nodes(&body, &surgery);
    assert!(walls.len() > 100);
    let off = walls
        .iter()
        .map(|&v| {
            let p = body.positions()[v as usize];
            (p.x - 0.3).abs().max((rest(&body, v).x - 0.3).abs() as f32)
        })
        .fold(0.0f32, f32::max);
    eprintln!(
        "full cut at x = 0.3: {split} tets split, {} wall nodes, farthest {off:.2e} cm off the plane",
        walls.len()
    );
    assert!(off < 1e-5, "a wall node is {off} cm off the blade's plane");
    // Each split tiles its tet, so the rest volume is the block's, and the pieces are cut at
    // exactly x = 0.3: 3.3 × 3 × 3 and 2.7 × 3 × 3 cm³.
    assert!((body.rest_volume() / total - 1.0).abs() < 1e-6);
    let mut left = 0.0;
    for (t, &c) in surgery.tet_components().iter().enumerate() {
        if c == 0 {
            left += body.tet_rest_volumes()[t] as f64;
        }
    }
    assert!((left - 29.7).abs() < 1e-4, "left piece {left} cm³");
    check_quality(&body, &surgery);
}

#[test]
fn nodes_near_the_blade_are_snapped_onto_its_plane() {
    let (mut body, mut surgery) = common::block(true);
    // x = 0.05 is 0.05 cm from the nodes at x = 0 (< 0.25 × 0.5 cm): they snap onto it.
    let events = full_cut(&mut body, &mut surgery, 0.05);
    assert_eq!(surgery.component_count(), 2);
    let snapped: Vec<u32> = events
        .iter()
        .flat_map(|e| match e {
            SurgeryEvent::CutAdvanced { snapped_nodes, .. } => snapped_nodes.clone(),
            _ => Vec::new(),
        })
        .collect();
    // The inner node plane x = 0 (7 × 7 nodes; the boundary ones too, they are free).
    assert_eq!(snapped.len(), 49, "snapped {}", snapped.len());
    let walls = wall_nodes(&body, &surgery);
    let off = walls
        .iter()
        .map(|&v| (body.positions()[v as usize].x - 0.05).abs())
        .fold(0.0f32, f32::max);
    eprintln!(
        "full cut at x = 0.05: {} snapped, {} wall nodes, farthest {off:.2e} cm off the plane",
        snapped.len(),
        walls.len()
    );
    assert!(off < 1e-5, "a wall node is {off} cm off the blade's plane");
    check_quality(&body, &surgery);
}

#[test]
fn a_partial_incision_splits_the_crossed_top_triangles_into_three_or_five() {
    let (mut body, mut surgery) = common::block(true);
    let top_before: Vec<[u32; 3]> = surgery
        .boundary_faces(&body)
        .into_iter()
        .filter(|f| f.iter().all(|&v| (rest(&body, v).y - 1.5).abs() < 1e-6))
        .collect();
    let total = body.rest_volume();
    // As tests/cut.rs: a blade in the plane z = 0.15, its edge 1 cm deep, drawn along x from
    // −1.5 to 1.5 in ten steps.
    let blade = common::incision_blade();
    let at = common::incision_pose;
    let mut reported = 0;
    for k in 0..10 {
        let (x0, x1) = (-1.5 + 0.3 * k as f32, -1.5 + 0.3 * (k + 1) as f32);
        for e in surgery
            .cut(
                &mut body,
                &BladeSweep::new(&blade, &at(x0), &at(x1)).unwrap(),
            )
            .unwrap()
        {
            if let SurgeryEvent::CutAdvanced {
                split_triangles, ..
            } = e
            {
                reported += split_triangles.len();
            }
        }
        surgery.validate(&body).unwrap();
    }
    assert_eq!(surgery.component_count(), 1);
    assert!(reported > 0);
    // A cut continued over ten sweeps still has flat walls: on the plane z = 0.15.
    let walls = wall_nodes(&body, &surgery);
    let off = walls
        .iter()
        .map(|&v| (body.positions()[v as usize].z - 0.15).abs())
        .fold(0.0f32, f32::max);
    assert!(walls.len() > 20);
    assert!(off < 1e-5, "a wall node is {off} cm off the blade's plane");
    assert!((body.rest_volume() / total - 1.0).abs() < 1e-6);
    // The top triangles the path crossed (well inside its ends): each is now 3 boundary
    // triangles (rest centroids inside it), 1 and 2 on the two sides of the cut, or 5.
    let top_after: Vec<DVec3> = surgery
        .boundary_faces(&body)
        .into_iter()
        .filter(|f| f.iter().all(|&v| (rest(&body, v).y - 1.5).abs() < 1e-6))
        .map(|f| f.iter().map(|&v| rest(&body, v)).sum::<DVec3>() / 3.0)
        .collect();
    let (mut crossed, mut counts) = (0, Vec::new());
    for f in &top_before {
        let p = f.map(|v| rest(&body, v));
        let (zlo, zhi) = (
            p.iter().map(|q| q.z).fold(9.0, f64::min),
            p.iter().map(|q| q.z).fold(-9.0, f64::max),
        );
        let (xlo, xhi) = (
            p.iter().map(|q| q.x).fold(9.0, f64::min),
            p.iter().map(|q| q.x).fold(-9.0, f64::max),
        );
        if !(zlo < 0.15 && zhi > 0.15 && xlo > -1.01 && xhi < 1.01) {
            continue;
        }
        crossed += 1;
        let inside = |c: DVec3| {
            let s = |a: DVec3, b: DVec3| (b.x - a.x) * (c.z - a.z) - (b.z - a.z) * (c.x - a.x);
            let (u, v, w) = (s(p[0], p[1]), s(p[1], p[2]), s(p[2], p[0]));
            (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0)
        };
        counts.push(top_after.iter().filter(|&&c| inside(c)).count());
    }
    eprintln!("partial incision: {crossed} crossed top triangles, pieces {counts:?}; {reported} split triangles reported");
    assert!(crossed >= 6);
    // 5 where a sweep's front ended inside the triangle (a tip split, see tests/tip.rs): the
    // fronts at the top are at x = −0.7, −0.4, −0.1, 0.2, 0.5, 0.8; those at −0.7, −0.1 and 0.8
    // lie well inside a crossing segment; −0.4 lies in a short one (0.15 cm, its pieces would
    // be below the quality bound), 0.2 within `TIP_MARGIN` of a segment's end, 0.5 on a node.
    let mut sorted = counts.clone();
    sorted.sort_unstable();
    assert_eq!(
        sorted,
        [3, 3, 3, 3, 3, 5, 5, 5],
        "pieces per crossed triangle {counts:?}"
    );
    check_quality(&body, &surgery);
}
