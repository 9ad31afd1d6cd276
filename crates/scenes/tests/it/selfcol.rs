//! Self-collision in the trainer (issue 35, items 2 and 4), through a session and its tools:
//! a thin slab folded onto itself by the probe, a flap cut with the scalpel and laid over its
//! own base, a long thin organ dropped in a coil onto the tray, and the appendix procedure with
//! self-collision on. Each scenario is run with self-collision off as well, and the number of
//! intersecting surface triangle pairs at its end (`tissue_pbd::count_intersecting_pairs`, an
//! exact triangle–triangle test) is printed for both: the scenarios are built so that without
//! self-collision the tissue passes through itself (more than 0 pairs), which each test checks
//! too (the check can fail), and with it none. The pairs are counted all and far (`Pairs`: the
//! surface folding over itself within a one-ring at a crease is not the tissue passing through
//! itself, and vertex–triangle self-collision leaves it to the material). The scenarios that
//! still fail with self-collision on are ignored, with what they measured and why.
#![allow(clippy::unwrap_used, clippy::print_stderr)]

use std::time::Instant;

use glam::{Vec3, Vec3A};
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::{count_intersecting_pairs, SelfCollision};
use tissue_scenes::{Organ, Session, SessionOptions, Setting, ShippedOrgan, TrainerEventKind as K};

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

/// Intersecting pairs of the body's surface triangles (the faces used by one tet only), all of
/// them and the far ones.
#[derive(Debug, Clone, Copy)]
struct Pairs {
    /// Every intersecting pair ([`count_intersecting_pairs`]).
    all: usize,
    /// Those whose triangles are not neighbours in the tet mesh: no corner of one is a corner of
    /// the other or shares a tet with one (the exclusion of `selfcol.rs`). The others are the
    /// surface folding over itself within a vertex's one-ring, at a crease: the mesh's scale,
    /// which vertex–triangle self-collision leaves to the material by design. The two walls of
    /// a cut share no tet: their pairs are far.
    far: usize,
}

fn self_intersections(s: &Session) -> Pairs {
    pairs_of(s.body())
}

fn pairs_of(body: &tissue_pbd::SoftBody) -> Pairs {
    let tris = body.surface_triangles();
    let x = body.positions();
    let mut ring = std::collections::HashSet::new();
    for t in body.tets() {
        for &a in t {
            for &b in t {
                ring.insert((a, b));
            }
        }
    }
    let pairs = tissue_pbd::intersecting_pairs(x, &tris).unwrap();
    let far = pairs
        .iter()
        .filter(|pr| {
            let [a, b] = pr.map(|i| tris[i as usize]);
            !a.iter()
                .any(|&i| b.iter().any(|&j| i == j || ring.contains(&(i, j))))
        })
        .count();
    Pairs {
        all: pairs.len(),
        far,
    }
}

/// A session on `mesh` placed on the tray (its underside on the tray's top), with or without
/// self-collision.
fn on_tray(mesh: &TetMesh, name: &str, self_collision: bool) -> Result<Session> {
    let organ = Organ::from_tets(mesh, name)?;
    assert_eq!(organ.setting, Setting::Tray);
    // A forceps-like grab (the picked triangle's corners and little more): the flap turns
    // about it as it is folded over instead of being held flat (a 180° crease beside a wide
    // grab).
    let options = SessionOptions {
        grab_radius: 0.3,
        ..SessionOptions::default()
    };
    let mut s = Session::new(&organ, options)?;
    s.set_self_collision(self_collision.then(SelfCollision::default))?;
    Ok(s)
}

/// The surface triangle whose centroid is nearest `p`, and that centroid.
fn surface_near(s: &Session, p: Vec3) -> (usize, Vec3) {
    let x = s.positions();
    s.surface()
        .iter()
        .enumerate()
        .map(|(i, t)| {
            (
                i,
                t.iter().map(|&n| Vec3::from(x[n as usize])).sum::<Vec3>() / 3.0,
            )
        })
        .min_by(|a, b| a.1.distance_squared(p).total_cmp(&b.1.distance_squared(p)))
        .unwrap()
}

/// Largest speed of a node over the last step (cm/s): the tissue at rest, not jittering.
fn speed(before: &[Vec3A], s: &Session) -> f32 {
    s.positions()
        .iter()
        .zip(before)
        .map(|(a, b)| a.distance(*b) / 0.01)
        .fold(0.0, f32::max)
}

/// The probe grabs the surface at `from`, carries it over a half circle in the x–y plane to
/// `to` (150 steps), holds it there for 30 steps and lets go; then 120 steps. Returns the
/// intersecting pairs at the end and the largest node speed over one more step.
fn fold_over(s: &mut Session, from: Vec3, to: Vec3) -> Result<(Pairs, f32)> {
    let (steps, hold, settle) = (150, 30, 120);
    let (t, p) = surface_near(s, from);
    assert_eq!(s.grab(p, t)?.kind, K::Grabbed);
    let centre = 0.5 * (p + to);
    let radius = 0.5 * (to.x - p.x).abs();
    for k in 1..=steps {
        let a = std::f32::consts::PI * k as f32 / steps as f32;
        let f = k as f32 / steps as f32;
        // x from p.x to to.x over the top of the circle, y up by the radius and down to to.y.
        let x = centre.x + (p.x - centre.x) * a.cos();
        let y = p.y + (to.y - p.y) * f + radius * a.sin();
        let z = p.z + (to.z - p.z) * f;
        s.drag(Vec3::new(x, y, z));
        s.step()?;
    }
    for _ in 0..hold {
        s.step()?;
    }
    s.release()?;
    for _ in 0..settle {
        s.step()?;
    }
    let before = s.positions().to_vec();
    s.step()?;
    Ok((self_intersections(s), speed(&before, s)))
}

/// A 10 × 0.6 × 3 cm slab (cells of 0.2 cm) on the tray; the probe takes its right end's
/// top, folds it over in a half circle onto the left half, 0.6 cm off the middle across it (so
/// that the folded half's side edges do not land on the base's: edge–edge contact is not
/// handled), the grabbed point 1.3 cm above the tray (about where the folded end's top lies
/// on the base), holds it 0.3 s and lets go: the folded half lies on the base under its own
/// weight, 1.2 s. Returns the pairs at the end and the largest node speed over the last step.
fn folded_slab(self_collision: bool) -> Result<(Pairs, f32)> {
    let mesh = tet_box(50, 3, 15, Vec3::new(10.0, 0.6, 3.0))?;
    let mut s = on_tray(&mesh, "slab", self_collision)?;
    for _ in 0..20 {
        s.step()?;
    }
    fold_over(&mut s, Vec3::new(4.9, 0.6, 0.0), Vec3::new(-2.0, 1.3, 0.6))
}

/// Fails (issue 35, measured 2026-11-29, grab radius 0.3 cm): with self-collision on 23
/// intersecting pairs (1 573 off), 6 of them far (4–12 before the detection's rework of the
/// third session; the fastest node at the end 2.0 cm/s): the folded half turned about the grab,
/// and its side edge lies across the base's top side edge, edge on edge (edge–edge contact is
/// not handled by `selfcol.rs`); the others are the top surface folded over itself within a
/// one-ring at the fold's root (triangles sharing a vertex or one edge apart).
#[test]
#[ignore = "fails with self-collision on: 6 far pairs, edge on edge at the slab's side edges (issue 35)"]
fn a_slab_folded_onto_itself_by_the_probe_does_not_pass_through_itself() -> Result {
    let clock = Instant::now();
    let (off, _) = folded_slab(false)?;
    let (on, v) = folded_slab(true)?;
    eprintln!(
        "slab folded by the probe: intersecting pairs off {off:?}, on {on:?} (fastest node \
         {v:.2} cm/s), {:.1} s",
        clock.elapsed().as_secs_f64()
    );
    assert!(
        off.far > 0,
        "without self-collision the fold passes through: {off:?}"
    );
    assert_eq!(on.far, 0, "with self-collision: {on:?}");
    assert!(v < 5.0, "the folded slab jitters: {v} cm/s");
    Ok(())
}

/// The slab of [`folded_slab`]; the scalpel cuts a slit along it (z = 0.06) from its right
/// end to x = 0, through its whole thickness: two tongues. The probe takes the far tongue's
/// end (z > 0), folds it over in a half circle onto the middle of the slab's left half (the
/// tongue's edges well inside the base's) and lets go, as in [`folded_slab`]. Returns the
/// pairs at the end and the largest node speed over the last step.
fn cut_flap(self_collision: bool) -> Result<(Pairs, f32)> {
    let mesh = tet_box(50, 3, 15, Vec3::new(10.0, 0.6, 3.0))?;
    let mut s = on_tray(&mesh, "slab", self_collision)?;
    for _ in 0..10 {
        s.step()?;
    }
    let path: Vec<Vec3> = (0..=11)
        .map(|i| Vec3::new(5.5 - 0.5 * i as f32, 0.6, 0.06))
        .collect();
    let segments = s.cut(&path, Vec3::NEG_Y)?;
    let before = s.surface().len();
    for _ in 0..segments + 5 {
        s.step()?;
    }
    assert!(s.surface().len() > before, "the scalpel opened nothing");
    fold_over(&mut s, Vec3::new(4.9, 0.6, 0.8), Vec3::new(-2.0, 1.3, 0.0))
}

/// Without self-collision the flap sinks through its base (over 1 000 far pairs); with it, no
/// far pair remains: the flap lies on its base. Measured 2026-11-29: 0 far pairs (1 577 off),
/// the fastest node at the end 2.8 cm/s. (Before the third session's rework of the detection:
/// 0 to 4 far pairs and up to 44 cm/s, as the narrow phase's bound on pushing back, `BEHIND`,
/// went from 0 to 0.1 h; the contacts that persist from one substep to the next keep the
/// tongue's vertices held where the iterations let them through.) The surface also folds over
/// itself within a one-ring at the creases (6 pairs), the mesh's scale, which the far count
/// leaves out.
#[test]
fn a_flap_cut_with_the_scalpel_and_laid_over_its_base_does_not_pass_through_it() -> Result {
    let clock = Instant::now();
    let (off, _) = cut_flap(false)?;
    let (on, v) = cut_flap(true)?;
    eprintln!(
        "flap laid over its base: intersecting pairs off {off:?}, on {on:?} (fastest node \
         {v:.2} cm/s), {:.1} s",
        clock.elapsed().as_secs_f64()
    );
    assert!(
        off.far > 0,
        "without self-collision the flap passes through: {off:?}"
    );
    assert_eq!(on.far, 0, "with self-collision: {on:?}");
    assert!(v < 5.0, "the flap jitters: {v} cm/s");
    Ok(())
}

/// A rod of 0.6 × 0.6 cm section (2 × 2 cells of 0.3 cm, `n` along it) bent at rest into a
/// helix of radius `r` (of its centre line) about the y axis, `turns` turns of pitch `pitch`:
/// the box's x along the centre line, its y towards the axis, its z along the binormal (a
/// right-handed frame, so the tets keep their orientation).
fn coil(r: f32, pitch: f32, turns: f32) -> Result<TetMesh> {
    let rise = pitch / std::f32::consts::TAU;
    let length = turns * std::f32::consts::TAU * (r * r + rise * rise).sqrt();
    let n = (length / 0.3).round() as u32;
    let (positions, tets) = tet_box(n, 2, 2, Vec3::new(length, 0.6, 0.6))?.into_parts();
    let arc = (r * r + rise * rise).sqrt();
    let bent = positions
        .iter()
        .map(|p| {
            let theta = (p.x + 0.5 * length) / arc;
            let (sin, cos) = theta.sin_cos();
            let centre = Vec3::new(r * cos, rise * theta, r * sin);
            let tangent = Vec3::new(-r * sin, rise, r * cos) / arc;
            let normal = Vec3::new(-cos, 0.0, -sin);
            let binormal = tangent.cross(normal);
            centre + normal * p.y + binormal * p.z
        })
        .collect();
    Ok(TetMesh::new(bent, tets)?)
}

/// The coil (radius 2 cm, 2.5 turns 1.5 cm apart: 0.9 cm between turns) on the tray, dropped
/// from 1 cm above it, 2 s: it falls and collapses under its own weight, each turn onto the
/// one below. Returns the pairs at the end, the largest node speed over the last step, the
/// height of the collapsed coil and the self-contacts dropped in the last step.
fn dropped_coil(self_collision: bool) -> Result<(Pairs, f32, f32, usize)> {
    let mesh = coil(2.0, 1.5, 2.5)?;
    let placed = Organ::from_tets(&mesh, "coil")?;
    let lifted = TetMesh::new(
        placed
            .mesh
            .positions()
            .iter()
            .map(|&p| p + Vec3::Y)
            .collect(),
        placed.mesh.tets().to_vec(),
    )?;
    let organ = Organ {
        mesh: lifted,
        ..placed
    };
    let mut s = Session::new(&organ, SessionOptions::default())?;
    s.set_self_collision(self_collision.then(SelfCollision::default))?;
    for _ in 0..200 {
        s.step()?;
    }
    let before = s.positions().to_vec();
    s.step()?;
    let top = s.positions().iter().map(|p| p.y).fold(f32::MIN, f32::max);
    Ok((
        self_intersections(&s),
        speed(&before, &s),
        top,
        s.body().self_contacts_dropped(),
    ))
}

#[test]
fn a_coil_dropped_onto_the_tray_does_not_pass_through_itself() -> Result {
    let clock = Instant::now();
    let (off, _, top_off, _) = dropped_coil(false)?;
    let (on, v, top_on, dropped) = dropped_coil(true)?;
    eprintln!(
        "coil dropped on the tray: intersecting pairs off {off:?} (height {top_off:.2} cm), on \
         {on:?} (height {top_on:.2} cm, fastest node {v:.2} cm/s, {dropped} contacts dropped), \
         {:.1} s",
        clock.elapsed().as_secs_f64()
    );
    assert!(
        off.far > 0,
        "without self-collision the coil passes through: {off:?}"
    );
    // All of them: no fold within a one-ring either.
    assert_eq!(on.all, 0, "with self-collision: {on:?}");
    assert_eq!(dropped, 0, "self-contacts dropped");
    // The turns lie on each other: the collapsed coil stands at least two sections (0.6 cm)
    // high, squeezed by less than a fifth.
    assert!(top_on > 2.0 * 0.6 * 0.8, "the coil is {top_on} cm high");
    assert!(v < 5.0, "the coil jitters: {v} cm/s");
    Ok(())
}

/// The appendix procedure ([`Session::play`]: grasp and lift, incise at x = −2.45, cut the tip
/// off, three stitches across the incision), 200 steps, then 50 steps more. Returns the
/// intersecting pairs among the surface triangles near the incision (every corner within
/// 0.3 cm of its plane at rest: its two walls and the surface just beside them), among all
/// surface triangles, the stitches placed, the largest piece detached (cm³, from the events'
/// text) and the worst volume drift.
fn appendix(self_collision: bool) -> Result<(usize, Pairs, usize, f64, f64)> {
    let organ = Organ::shipped(ShippedOrgan::Appendix)?;
    let mut s = Session::new(&organ, SessionOptions::default())?;
    s.set_self_collision(self_collision.then(SelfCollision::default))?;
    s.play()?;
    let mut kinds: Vec<(K, String)> = Vec::new();
    let mut steps = 0;
    while s.playing() {
        for e in s.step()? {
            kinds.push((e.kind, e.text));
        }
        steps += 1;
        assert!(steps <= 200, "the demonstration did not end");
    }
    assert_eq!(kinds.last().map(|k| k.0), Some(K::DemoFinished));
    for _ in 0..50 {
        s.step()?;
    }
    let sutures = kinds.iter().filter(|k| k.0 == K::SuturePlaced).count();
    let largest = crate::largest_detached(&kinds);
    let tris = s.body().surface_triangles();
    let rest = s.body().rest_positions();
    let incision = tissue_scenes::AppendixPlan::default().incision.0;
    let walls: Vec<[u32; 3]> = tris
        .iter()
        .copied()
        .filter(|t| {
            t.iter()
                .all(|&n| (rest[n as usize].x - incision).abs() < 0.3)
        })
        .collect();
    let near = count_intersecting_pairs(s.positions(), &walls)?;
    let all = self_intersections(&s);
    Ok((near, all, sutures, largest, s.worst_drift()))
}

/// The appendix procedure with self-collision on, against off: the three stitches are placed,
/// the tip comes off (held by the grasper until the blade is through), and the surface does not
/// tangle: no more intersecting pairs than without self-collision, the volume held. Measured
/// 2026-11-29: 3 stitches, tip 8.76 cm³ either way, 193 pairs on (113 far) against 362 off
/// (240 far), drift 0.4 %. (Before `BEHIND` bounded the push back, the cut-off tangled the
/// surface: 6 × 10³ – 1.4 × 10⁵ pairs, drift up to 7 ×.)
#[test]
fn the_appendix_procedure_with_self_collision_places_its_stitches_and_cuts_the_tip_off() -> Result {
    let clock = Instant::now();
    let (near_off, all_off, sutures_off, tip_off, _) = appendix(false)?;
    let (near, all, sutures, tip, drift) = appendix(true)?;
    eprintln!(
        "appendix: incision {near_off} intersecting pairs off, {near} on; whole surface \
         {all_off:?} off, {all:?} on; {sutures} stitches ({sutures_off} off), tip {tip:.2} cm³ \
         ({tip_off:.2} off), drift {drift:.4}, {:.1} s",
        clock.elapsed().as_secs_f64()
    );
    assert_eq!((sutures, sutures_off), (3, 3));
    assert!((6.0..11.0).contains(&tip), "tip {tip} cm³");
    assert!((6.0..11.0).contains(&tip_off), "tip {tip_off} cm³ without");
    assert!(drift < 0.02, "drift {drift}");
    assert!(
        all.all <= all_off.all && all.far <= all_off.far,
        "the surface tangled: {all:?} on, {all_off:?} off"
    );
    Ok(())
}

/// Issue 35's item 4: after the appendix procedure the incision's walls do not intersect. Not
/// met (measured 2026-11-29): 84 intersecting pairs among the triangles within 0.3 cm of the
/// incision at rest with self-collision on (112 before the third session's rework of the
/// detection), 157 off. Most are the walls' rims folding over the
/// organ's side within a few split tets of the cut (rest neighbours, which vertex–triangle
/// self-collision excludes), and edge on edge (not handled).
#[test]
#[ignore = "not met: the incision's walls still intersect (84 pairs on, 157 off; issue 35)"]
fn the_appendix_procedure_with_self_collision_keeps_the_incision_walls_apart() -> Result {
    let (near_off, ..) = appendix(false)?;
    let (near, ..) = appendix(true)?;
    eprintln!("appendix: incision {near_off} intersecting pairs off, {near} on");
    assert_eq!(near, 0, "the incision's walls intersect");
    Ok(())
}

/// The appendix's tip comes off (a piece over 0.5 cm³ detached by step 115) with the cut-off's
/// plane anywhere in x = 1.95 … 2.15 cm, with and without self-collision (`AppendixProcedure` on
/// the session's physics). Measured 2026-11-29: off at all ten, 8.3–9.2 cm³ at steps 100–103.
/// (When the grasper let go as the blade came down, the tip, falling while it was cut, stayed on
/// at 2.0 and 2.1 without self-collision and at 2.05 and 2.1 with it.)
#[test]
fn the_appendix_cut_off_across_nearby_planes() -> Result {
    use tissue_scenes::{AppendixPlan, AppendixProcedure, Script, Tray};
    use tissue_surgery::{Surgery, SurgeryEvent, SurgerySettings};
    let organ = Organ::shipped(ShippedOrgan::Appendix)?;
    let o = SessionOptions::default();
    let tray = Tray::for_extent(organ.extent());
    for x in [1.95f32, 2.0, 2.05, 2.1, 2.15] {
        for on in [false, true] {
            let mut body = organ.body(&o.material, o.step, o.contact, tray)?;
            body.set_self_collision(on.then(SelfCollision::default))?;
            let mut surgery = Surgery::new(&body, SurgerySettings::default())?;
            let plan = AppendixPlan {
                total: 115,
                cutoff_x: x,
                ..AppendixPlan::default()
            };
            let mut script = AppendixProcedure::new(&mut body, plan)?;
            let mut tip = None;
            for k in 1..=script.steps() {
                script.before_step(k, &mut body)?;
                body.step()?;
                for e in script.after_step(k, &mut body, &mut surgery)?.events {
                    if let SurgeryEvent::PieceDetached { rest_volume, .. } = e {
                        if rest_volume > 0.5 && tip.is_none() {
                            tip = Some((k, rest_volume));
                        }
                    }
                }
            }
            eprintln!("cut-off at x = {x} cm, self-collision {on}: tip off (step, cm³) {tip:?}");
            assert!(
                tip.is_some_and(|(_, v)| (6.0..11.0).contains(&v)),
                "the tip stayed on: cut-off at x = {x} cm, self-collision {on}: {tip:?}"
            );
        }
    }
    Ok(())
}

/// A surface tangled by a violent drag suspends its self-collision instead of paying for it:
/// the bunny grabbed at its top and dragged at once to the tray's corner (the grab snaps there,
/// flinging and stretching it until its surface passes through itself; 853 intersecting pairs
/// without self-collision) fills every broad-phase list, which vertex–triangle contacts cannot
/// untangle. Self-collision is then suspended for 50 steps at a time, tried again after each
/// (2026-11-29: 130 ms a step serial without the suspension, the median step 4.9 ms with it,
/// as without self-collision). The bunny at rest on the tray never suspends it.
#[test]
fn a_tangled_surface_suspends_self_collision() -> Result {
    let organ = Organ::shipped(ShippedOrgan::Bunny)?;
    let mut s = Session::new(&organ, SessionOptions::default())?;
    assert!(s.options().self_collision.is_some(), "on by default");
    for _ in 0..5 {
        s.step()?;
    }
    assert_eq!(s.body().self_collision_suspensions(), 0);
    let highest = (s.positions().iter().map(|&p| Vec3::from(p)))
        .max_by(|a, b| a.y.total_cmp(&b.y))
        .ok_or("no nodes")?;
    let (t, p) = surface_near(&s, highest);
    s.grab(p, t)?;
    s.drag(Vec3::splat(1e30));
    let mut suspended = 0;
    for _ in 0..60 {
        s.step()?;
        suspended += usize::from(s.body().self_collision_suspended() > 0);
    }
    assert!(s.positions().iter().all(|p| p.is_finite()));
    let tried = s.body().self_collision_suspensions();
    eprintln!("tangled bunny: suspended in {suspended} of 60 steps, {tried} suspensions");
    assert!(tried >= 1 && suspended >= 45, "{suspended} {tried}");
    Ok(())
}
