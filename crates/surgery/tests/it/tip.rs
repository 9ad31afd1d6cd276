//! The cut's ends on the surface: an incision that stops in the middle of the block's top
//! splits the top triangle where the blade's front crosses the surface (the tip split), and
//! the opening on the top ends exactly at the tip; continued, it goes on from there.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::print_stderr
)]

use crate::common;

use common::{check_quality, rest};

use glam::DVec3;
use tissue_pbd::{SoftBody, StepSettings};
use tissue_surgery::{BladeSweep, SplitTriangle, Surgery, SurgeryEvent, SurgerySettings};

/// The node at rest position `p` (within 1e-4 cm).
fn node_at(body: &SoftBody, p: DVec3) -> Option<u32> {
    (0..body.node_count() as u32).find(|&v| rest(body, v).distance(p) < 1e-4)
}

/// Whether node `v` was duplicated by an opening (some other node copies it).
fn duplicated(surgery: &Surgery, v: u32) -> bool {
    surgery
        .origins()
        .iter()
        .enumerate()
        .any(|(i, &o)| o == v && i as u32 != v)
}

/// x of the top nodes (rest y = 1.5, on the blade's plane z = 0.15) an opening duplicated.
fn opening_on_top(body: &SoftBody, surgery: &Surgery) -> Vec<f64> {
    let mut x: Vec<f64> = (0..body.node_count())
        .filter(|&i| surgery.origins()[i] as usize != i)
        .map(|i| rest(body, surgery.origins()[i]))
        .filter(|p| (p.y - 1.5).abs() < 1e-6 && (p.z - 0.15).abs() < 1e-6)
        .map(|p| p.x)
        .collect();
    x.sort_by(f64::total_cmp);
    x
}

fn area(p: [DVec3; 3]) -> f64 {
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}

/// The top boundary triangles (rest y = 1.5) whose rest centroids lie in the top triangle `t`.
fn pieces_in(body: &SoftBody, surgery: &Surgery, t: [DVec3; 3]) -> Vec<[u32; 3]> {
    let inside = |c: DVec3| {
        let s = |a: DVec3, b: DVec3| (b.x - a.x) * (c.z - a.z) - (b.z - a.z) * (c.x - a.x);
        let (u, v, w) = (s(t[0], t[1]), s(t[1], t[2]), s(t[2], t[0]));
        (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0)
    };
    surgery
        .boundary_faces(body)
        .into_iter()
        .filter(|f| f.iter().all(|&v| (rest(body, v).y - 1.5).abs() < 1e-6))
        .filter(|f| inside(f.iter().map(|&v| rest(body, v)).sum::<DVec3>() / 3.0))
        .collect()
}

/// Checks the tip split of the top triangle `corners` (rest positions) where the polygon's
/// boundary crosses the top at `x_tip` (on z = 0.15), the crossing point `x_e` on the
/// triangle's edge inside the polygon. Four-way (`pieces` 4): 4 boundary pieces tiling it
/// (areas within 1e-6), reported as one split triangle with those 4 pieces; the tip node there
/// (within 1e-4 cm of where the blade's edge crosses the top), inside the triangle, joined by
/// the pieces to exactly the crossing node `E` and the two corners of the edges it lies
/// between; `E` duplicated. The five-way fallback (`pieces` 5): 5 pieces, reported once, the
/// tip on the crack line. Both: the tip not duplicated, on the opened walls.
fn check_tip(
    body: &SoftBody,
    surgery: &Surgery,
    reported: &[SplitTriangle],
    corners: [DVec3; 3],
    x_tip: f64,
    x_e: f64,
    expected: usize,
) {
    let pieces = pieces_in(body, surgery, corners);
    let sum: f64 = pieces.iter().map(|f| area(f.map(|v| rest(body, v)))).sum();
    eprintln!(
        "tip at x = {x_tip}: {} pieces, area {sum:.9} of {:.9}",
        pieces.len(),
        area(corners)
    );
    assert_eq!(pieces.len(), expected, "pieces of the tip triangle");
    assert!((sum - area(corners)).abs() < 1e-6);
    // Reported as one triangle split into exactly these 4 pieces.
    let original = corners.map(|p| node_at(body, p).unwrap());
    let key = |f: &[u32; 3]| {
        let mut k = *f;
        k.sort_unstable();
        k
    };
    let entry = reported
        .iter()
        .find(|s| key(&s.original) == key(&original))
        .expect("the tip triangle is reported");
    let mut got: Vec<[u32; 3]> = entry.pieces.iter().map(key).collect();
    // (The pieces as reported: before the opening duplicated E.)
    let origins = surgery.origins();
    let mut want: Vec<[u32; 3]> = pieces
        .iter()
        .map(|f| key(&f.map(|v| origins[v as usize])))
        .collect();
    got.sort_unstable();
    want.sort_unstable();
    assert_eq!(got, want, "the reported pieces");
    // The tip: a node at the crossing, not duplicated, on the opened walls.
    let tip = node_at(body, DVec3::new(x_tip, 1.5, 0.15));
    let tip = tip.unwrap_or_else(|| panic!("no node at the tip x = {x_tip}"));
    assert!(!duplicated(surgery, tip), "the tip is duplicated");
    let on_wall = surgery.cut_faces().iter().any(|&(t, j)| {
        let tet = body.tets()[t as usize];
        (0..4).any(|k| k != j as usize && tet[k] == tip)
    });
    assert!(on_wall, "the opening does not reach the tip");
    if expected != 4 {
        return;
    }
    // Inside the triangle: in 3 of its pieces, joined to E and the two corners beside E–E2.
    let mut joined: Vec<DVec3> = pieces
        .iter()
        .filter(|f| f.contains(&tip))
        .flat_map(|f| f.iter().filter(|&&v| v != tip).map(|&v| rest(body, v)))
        .collect();
    joined.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.z.total_cmp(&b.z)));
    joined.dedup_by(|a, b| a.distance(*b) < 1e-6);
    assert_eq!(joined.len(), 3, "the tip's neighbours {joined:?}");
    let e = DVec3::new(x_e, 1.5, 0.15);
    assert!(joined.iter().any(|p| p.distance(e) < 1e-6), "{joined:?}");
    let at_corners = joined
        .iter()
        .filter(|p| corners.iter().any(|c| c.distance(**p) < 1e-6));
    assert_eq!(at_corners.count(), 2, "{joined:?}");
    // E opened: one of its copies is on the top.
    let e_node = node_at(body, e).unwrap();
    assert!(duplicated(surgery, e_node), "E is not duplicated");
}

/// [`check_tip`] for the top triangle holding the front of the one-sweep incisions (x =
/// −0.175, halfway along its crossing segment [−0.35, 0]).
fn check_front_tip(
    body: &SoftBody,
    surgery: &Surgery,
    reported: &[SplitTriangle],
    expected: usize,
) {
    let top = |x: f64, z: f64| DVec3::new(x, 1.5, z);
    check_tip(
        body,
        surgery,
        reported,
        [top(-0.5, 0.0), top(0.0, 0.0), top(0.0, 0.5)],
        -0.175,
        -0.35,
        expected,
    );
}

/// One sweep of `blade` from `from` to `to` (incision poses): the body stays valid and in one
/// piece; returns the split boundary triangles the events reported.
fn sweep_once(
    body: &mut SoftBody,
    surgery: &mut Surgery,
    blade: &tissue_pbd::ToolShape,
    from: f32,
    to: f32,
) -> Vec<SplitTriangle> {
    let at = common::incision_pose;
    let events = surgery
        .cut(body, &BladeSweep::new(blade, &at(from), &at(to)).unwrap())
        .unwrap();
    surgery.validate(body).unwrap();
    let mut reported = Vec::new();
    for e in events {
        assert!(!matches!(e, SurgeryEvent::PieceDetached { .. }));
        if let SurgeryEvent::CutAdvanced {
            split_triangles, ..
        } = e
        {
            reported.extend(split_triangles);
        }
    }
    reported
}

/// The blade's front crosses the top (y = 1.5) 0.2 cm ahead of the pose: the tip on the top
/// row of triangles z ∈ [0, 0.5] is at x = x1 + 0.2; a first sweep from −1.5 to −0.375 puts
/// the front at −0.175, halfway along the crossing segment [−0.35, 0] of the top triangle
/// (−0.5, 0) (0, 0) (0, 0.5) (x, z), and the start at −1.7, along [−1.85, −1.5] of the
/// triangle (−2, 0) (−1.5, 0) (−1.5, 0.5). Both triangles are split into 4 at their tips (the
/// four-way split, counted as such); the continued cut's later fronts are four-way or
/// five-way, as the rules allow.
#[test]
fn an_incision_ending_inside_a_top_triangle_splits_it_at_the_tip_and_opens_up_to_it() {
    incision_ending_inside_a_top_triangle(true);
}

/// The same with [`SurgerySettings::four_way_tips`] off: the fallback, both triangles in 5
/// pieces with the tip on their crack line (what a refused four-way candidate gets).
#[test]
fn with_four_way_tips_off_the_tip_triangles_are_split_into_five() {
    incision_ending_inside_a_top_triangle(false);
}

fn incision_ending_inside_a_top_triangle(four_way: bool) {
    let (mut body, mut surgery) = common::block(true);
    if !four_way {
        let settings = SurgerySettings {
            four_way_tips: false,
            ..SurgerySettings::default()
        };
        surgery = Surgery::new(&body, settings).unwrap();
    }
    let total = body.rest_volume();
    let blade = common::incision_blade();
    let at = common::incision_pose;
    let reported = sweep_once(&mut body, &mut surgery, &blade, -1.5, -0.375);
    let counts = surgery.tip_counts();
    eprintln!("first sweep: {counts:?}");
    let expected = if four_way { 4 } else { 5 };
    assert_eq!(
        (counts.four_way, counts.fallback),
        if four_way { (2, 0) } else { (0, 2) }
    );
    let top = |x: f64, z: f64| DVec3::new(x, 1.5, z);
    // The front end and the start.
    check_front_tip(&body, &surgery, &reported, expected);
    check_tip(
        &body,
        &surgery,
        &reported,
        [top(-2.0, 0.0), top(-1.5, 0.0), top(-1.5, 0.5)],
        -1.7,
        -1.5,
        expected,
    );
    // The opening on the top: from the first node past the start's tip to the last before the
    // front's; nothing beyond the tips.
    let open = opening_on_top(&body, &surgery);
    eprintln!("opening on top (duplicated nodes): {open:?}");
    let near = |a: f64, b: f64| (a - b).abs() < 1e-6;
    assert!(near(open[0], -1.5) && near(open[open.len() - 1], -0.35));
    assert!((body.rest_volume() / total - 1.0).abs() < 1e-6);
    assert_eq!(surgery.component_count(), 1);
    check_quality(&body, &surgery);

    // Continued from there in steps of 0.3 cm to x = 1.5: still valid, one piece, and the
    // opening runs on past the old tip to the new front's.
    let mut x = -0.375f32;
    let mut k = 0;
    while x < 1.5 {
        let x1 = (x + 0.3).min(1.5);
        for e in surgery
            .cut(
                &mut body,
                &BladeSweep::new(&blade, &at(x), &at(x1)).unwrap(),
            )
            .unwrap()
        {
            assert!(!matches!(e, SurgeryEvent::PieceDetached { .. }));
        }
        surgery.validate(&body).unwrap();
        x = x1;
        k += 1;
    }
    let open = opening_on_top(&body, &surgery);
    let (lo, hi) = (open[0], open[open.len() - 1]);
    eprintln!(
        "continued over {k} sweeps: opening on top from x = {lo} to {hi}; {:?}",
        surgery.tip_counts()
    );
    // The old front triangle: once the cut went past, its far edge A C is split too and the
    // old tip lies on the crack between E and the crossing point E2 (5 pieces either way).
    let old_front = pieces_in(
        &body,
        &surgery,
        [top(-0.5, 0.0), top(0.0, 0.0), top(0.0, 0.5)],
    );
    eprintln!("the old front triangle is in {} pieces", old_front.len());
    assert!(hi > 1.0, "the opening did not extend: {hi}");
    assert!((lo + 1.5).abs() < 1e-6);
    // The old tip is now an ordinary wall node (duplicated).
    let old = node_at(&body, DVec3::new(-0.175, 1.5, 0.15)).unwrap();
    assert!(duplicated(&surgery, old), "the old tip was not opened");
    assert_eq!(surgery.component_count(), 1);
    assert!((body.rest_volume() / total - 1.0).abs() < 1e-6);
    check_quality(&body, &surgery);
    body.set_settings(StepSettings::default()).unwrap();
    for _ in 0..10 {
        body.step().unwrap();
    }
}

/// A blade whose front edge leans forward (1 cm ahead per 1 cm down): under the tip the cut
/// runs ahead of it, so the faces on the plane just beyond the tip have their centroid segments
/// inside the swept polygon. A four-way tip would keep the tets around the triangle's far edge
/// `A C` whole and glued, and with them faces at its crossing point that this cut opens: the
/// four-way candidate is refused (counted as "needed") and the triangle falls back to the
/// five-way split. The faces just beyond the tip stay glued all the same (the tets beyond the
/// tip are the cut's front), so the opening on the top still ends at the tip, which keeps one
/// node.
#[test]
fn under_a_forward_leaning_blade_the_surface_opening_still_ends_at_the_tip() {
    let (mut body, mut surgery) = common::block(true);
    // Its front edge from (3, 0) to (0, 3) in the blade's frame: at the top (y = 1.5 at the
    // pose's y = 0.5) 2 cm ahead of the pose, 1 cm below it 3 cm ahead.
    let blade = tissue_pbd::ToolShape::Blade {
        a: glam::Vec3::new(-0.3, 0.0, 0.0),
        b: glam::Vec3::new(3.0, 0.0, 0.0),
        c: glam::Vec3::new(0.0, 3.0, 0.0),
        thickness: 0.01,
    };
    // One sweep from x = −3.5 (its rear out of the block) to −2.175: the front at the top is at
    // x = −0.175, halfway along the crossing segment [−0.35, 0].
    let reported = sweep_once(&mut body, &mut surgery, &blade, -3.5, -2.175);
    let counts = surgery.tip_counts();
    eprintln!("leaning blade: {counts:?}");
    assert!(
        counts.refused_needed >= 1 && counts.fallback >= 1,
        "{counts:?}"
    );
    check_front_tip(&body, &surgery, &reported, 5);
    let open = opening_on_top(&body, &surgery);
    eprintln!("leaning blade: opening on top (duplicated nodes): {open:?}");
    assert!((open[open.len() - 1] + 0.35).abs() < 1e-6, "{open:?}");
    // Under the top the cut went on ahead of the tip: duplicated nodes on the plane below.
    let ahead = (0..body.node_count())
        .filter(|&i| surgery.origins()[i] as usize != i)
        .map(|i| rest(&body, surgery.origins()[i]))
        .filter(|p| p.y < 1.5 - 1e-6 && p.x > -0.175)
        .count();
    eprintln!("leaning blade: {ahead} duplicated nodes below the top ahead of the tip");
    assert_eq!(surgery.component_count(), 1);
    check_quality(&body, &surgery);
}
