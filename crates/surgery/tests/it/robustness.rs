//! Seeded random blade sweeps over the bunny and the liver of `fixtures/` (both meshed by
//! `tissue-tetra`: the bunny about 40k tets): after every cut no panic, no non-finite value, the boundary closed, manifold
//! and consistently oriented ([`Surgery::validate`]), no tet below the quality bound (every
//! piece a split made at or above `MIN_RATIO`), and the body keeps stepping without
//! divergence. The worst *current* volume ratio is reported, not asserted: under gravity and floor contact with K = 5 some of the input's slivers invert with
//! or without cutting (the solver's business, not the cut's).
//!
//! The same sweeps run with self-collision on (issue 35, `tissue_pbd::SelfCollision`): a short
//! run on the liver in CI, the full ones ignored (slow: see `SESSIONS_WITH_SELF_COLLISION`).
#![allow(clippy::unwrap_used, clippy::panic, clippy::print_stderr)]

use std::hash::{DefaultHasher, Hash, Hasher};
use std::time::Instant;

use glam::{Quat, Vec3};
use tissue_mesh::TetMesh;
use tissue_pbd::{Floor, Material, Pose, SelfCollision, SoftBody, StepSettings, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgerySettings, TipCounts};

/// The bunny's surface (≈ 1 unit tall), shipped with the repository.
const BUNNY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/bunny_10k.obj");
/// SOFA's liver surface, shipped with the repository.
const LIVER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/liver_sofa.obj");

/// The closed surface at `path`, tetrahedralised by `tissue-tetra`. Panics when the file is
/// missing: the fixtures ship with the repository.
fn tetrahedralised(path: &str) -> TetMesh {
    let surface = tissue_meshio::read_surface(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    tissue_tetra::tetrahedralize(&surface, &tissue_tetra::TetraOptions::default())
        .unwrap()
        .mesh
}

/// Sessions (of 4 sweeps) in the runs with face separation only: the default (geometric cuts)
/// runs the 1000 sweeps per mesh, the other mode a quarter, to keep the binary's time
/// near 2 minutes on 2 cores.
const SESSIONS_WITHOUT_SPLITS: usize = 63;

/// xorshift64*: a fixed seed gives the same sweeps on every machine.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32) / (1u64 << 24) as f32
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.next(), self.next(), self.next()) * 2.0 - Vec3::ONE;
            if v.length_squared() > 0.01 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

struct Stats {
    piece_sizes: [usize; 20],
    seconds: [f64; 3],
    cuts: usize,
    cuts_opening: usize,
    detached: usize,
    steps: usize,
    worst_volume_ratio: f64,
    most_tets: usize,
    split_cuts: usize,
    /// The tips of all bodies (four-way, five-way fallback, four-way candidates refused).
    tips: TipCounts,
    /// A hash of every body (positions bit for bit, tets, adjacency, pieces) before it is
    /// replaced by a fresh one and at the end: equal in two builds means the same cuts.
    fingerprint: DefaultHasher,
}

/// Adds `body` and `surgery` to the fingerprint.
fn fingerprint(h: &mut DefaultHasher, body: &SoftBody, surgery: &Surgery) {
    for p in body.positions().iter().chain(body.rest_positions()) {
        p.to_array().map(f32::to_bits).hash(h);
    }
    body.tets().hash(h);
    surgery.neighbours().hash(h);
    surgery.origins().hash(h);
    surgery.tet_components().hash(h);
    surgery.cut_faces().hash(h);
}

fn add_tips(sum: &mut TipCounts, t: TipCounts) {
    sum.four_way += t.four_way;
    sum.fallback += t.fallback;
    sum.refused_margin += t.refused_margin;
    sum.refused_neighbour += t.refused_neighbour;
    sum.refused_unsplit += t.refused_unsplit;
    sum.refused_needed += t.refused_needed;
    sum.refused_quality += t.refused_quality;
}

/// `sessions` cuts of `per_session` continued sweeps each; `steps` steps after every cut; a
/// fresh body every 2 sessions (8 cuts) with splits, every 5 (20 cuts) without (splits add
/// tets, projected as dynamic batches; cut pieces pile up otherwise).
fn hammer(
    mesh: &TetMesh,
    seed: u64,
    sessions: usize,
    per_session: usize,
    steps: usize,
    split: bool,
    self_collision: bool,
) -> Stats {
    let material = Material::default();
    let mut fresh = SoftBody::new(mesh, &material).unwrap();
    if self_collision {
        fresh
            .set_self_collision(Some(SelfCollision::default()))
            .unwrap();
    }
    let settings = SurgerySettings {
        split_tets: split,
        ..SurgerySettings::default()
    };
    let fresh_surgery = Surgery::new(&fresh, settings).unwrap();
    fresh_surgery.validate(&fresh).unwrap();
    let (lo, hi) = mesh
        .positions()
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| {
            (a.min(*p), b.max(*p))
        });
    let size = (hi - lo).length();
    let (bound_volume, bound_ratio) = fresh_surgery.quality_bound();
    eprintln!(
        "  {} nodes, {} tets, size {size:.1} cm; quality bound: rest volume ≥ {bound_volume:.3e} cm³, radius ratio ≥ {bound_ratio:.4}",
        mesh.vertex_count(),
        mesh.tet_count()
    );
    let mut rng = Rng(seed);
    let mut stats = Stats {
        piece_sizes: [0; 20],
        seconds: [0.0; 3],
        cuts: 0,
        cuts_opening: 0,
        detached: 0,
        steps: 0,
        worst_volume_ratio: f64::INFINITY,
        most_tets: 0,
        split_cuts: 0,
        tips: TipCounts::default(),
        fingerprint: DefaultHasher::new(),
    };
    let (mut body, mut surgery) = (fresh.clone(), fresh_surgery.clone());
    // Parallel stepping (bit-identical to serial, tests/parallel.rs in tissue-pbd), for time.
    let settings = StepSettings {
        dt: 0.01,
        iterations: 5,
        parallel: true,
        ..StepSettings::default()
    };
    body.set_settings(settings).unwrap();
    body.set_floor(Some(Floor::y(lo.y - 0.5))).unwrap();
    for session in 0..sessions {
        if session % if split { 2 } else { 5 } == 0 {
            add_tips(&mut stats.tips, surgery.tip_counts());
            fingerprint(&mut stats.fingerprint, &body, &surgery);
            (body, surgery) = (fresh.clone(), fresh_surgery.clone());
            body.set_settings(settings).unwrap();
            body.set_floor(Some(Floor::y(lo.y - 0.5))).unwrap();
        }
        // A blade of 0.1–0.6 × the body's size, through a random point of the body, moving
        // along its own plane (cutting edge first) or at random.
        let r = size * (0.1 + 0.5 * rng.next());
        let blade = ToolShape::Blade {
            a: Vec3::new(-0.5 * r, 0.0, 0.0),
            b: Vec3::new(0.5 * r, 0.0, 0.0),
            c: Vec3::new(0.0, r, 0.0),
            thickness: 0.01,
        };
        let rotation = Quat::from_axis_angle(rng.unit(), std::f32::consts::TAU * rng.next());
        let centre = {
            let x = body.positions();
            Vec3::from(x[(rng.next() * x.len() as f32) as usize % x.len()])
        };
        let along = if rng.next() < 0.7 {
            rotation * Vec3::new(if rng.next() < 0.5 { 1.0 } else { -1.0 }, 0.0, 0.0)
        } else {
            rng.unit()
        };
        let step = along * size * (0.01 + 0.08 * rng.next());
        let mut pose = Pose::new(rotation, centre - step * (per_session as f32 * 0.5));
        for _ in 0..per_session {
            let next = Pose::new(rotation, pose.translation + step);
            let clock = Instant::now();
            let events = surgery
                .cut(&mut body, &BladeSweep::new(&blade, &pose, &next).unwrap())
                .unwrap();
            stats.seconds[0] += clock.elapsed().as_secs_f64();
            let clock = Instant::now();
            pose = next;
            stats.cuts += 1;
            stats.cuts_opening += usize::from(!events.is_empty());
            for e in &events {
                if let tissue_surgery::SurgeryEvent::CutAdvanced { split_tets, .. } = e {
                    stats.split_cuts += usize::from(!split_tets.is_empty());
                }
                if let tissue_surgery::SurgeryEvent::PieceDetached { tets, .. } = e {
                    stats.detached += 1;
                    let k = (tets.len() as f64).log2() as usize;
                    stats.piece_sizes[k.min(19)] += 1;
                }
            }
            if let Err(e) = surgery.validate(&body) {
                panic!("seed {seed}, cut {}: {e}", stats.cuts);
            }
            stats.seconds[1] += clock.elapsed().as_secs_f64();
            stats.most_tets = stats.most_tets.max(body.tets().len());
            let clock = Instant::now();
            for _ in 0..steps {
                if let Err(e) = body.step() {
                    panic!("seed {seed}, cut {}: {e}", stats.cuts);
                }
                stats.steps += 1;
            }
            stats.seconds[2] += clock.elapsed().as_secs_f64();
            let x = body.positions();
            assert!(
                x.iter().all(|p| p.is_finite() && p.length() < 1e5),
                "cut {}: a node ran away",
                stats.cuts
            );
            for (t, tet) in body.tets().iter().enumerate() {
                let [a, b, c, d] = tet.map(|i| x[i as usize].as_dvec3());
                let v = (b - a).cross(c - a).dot(d - a) / 6.0;
                stats.worst_volume_ratio = stats
                    .worst_volume_ratio
                    .min(v / body.tet_rest_volumes()[t] as f64);
            }
        }
    }
    add_tips(&mut stats.tips, surgery.tip_counts());
    fingerprint(&mut stats.fingerprint, &body, &surgery);
    stats
}

fn report(name: &str, s: &Stats, seconds: f64) {
    eprintln!(
        "  {name}: detached pieces by log2(tets): {:?}",
        s.piece_sizes
    );
    eprintln!(
        "  {name}: {} cuts ({} changed the body, {} split tets, {} pieces detached), at most {} tets, {} steps, worst current/rest tet volume {:.3}, {seconds:.1} s (cut {:.2} s, validate {:.2} s, steps {:.2} s)",
        s.cuts, s.cuts_opening, s.split_cuts, s.detached, s.most_tets, s.steps, s.worst_volume_ratio, s.seconds[0], s.seconds[1], s.seconds[2]
    );
    let t = s.tips;
    eprintln!(
        "  {name}: tips split into 4: {}, on the crack line (fallback): {}; four-way candidates refused: {} margin, {} neighbour, {} unsplit, {} needed, {} quality",
        t.four_way, t.fallback, t.refused_margin, t.refused_neighbour, t.refused_unsplit, t.refused_needed, t.refused_quality
    );
    eprintln!("  {name}: fingerprint {:016x}", s.fingerprint.finish());
}

#[test]
fn random_sweeps_over_the_bunny_keep_the_body_valid() {
    bunny(true);
}

#[test]
fn random_sweeps_over_the_bunny_keep_the_body_valid_without_splits() {
    bunny(false);
}

fn bunny(split: bool) {
    let (p, t) = tetrahedralised(BUNNY).into_parts();
    let mesh = TetMesh::new(p.iter().map(|p| *p * 10.0).collect(), t).unwrap();
    let start = Instant::now();
    let sessions = if split { 250 } else { SESSIONS_WITHOUT_SPLITS };
    let s = hammer(&mesh, 0x05EE_DB0B, sessions, 4, 10, split, false);
    report(
        if split {
            "bunny, split"
        } else {
            "bunny, faces"
        },
        &s,
        start.elapsed().as_secs_f64(),
    );
    assert_eq!(s.cuts, 4 * sessions);
    assert_eq!(s.steps, 10 * s.cuts);
    // Both ways of ending a cut on the surface are taken.
    assert!(!split || (s.tips.four_way > 0 && s.tips.fallback > 0));
    assert!(
        s.cuts_opening > s.cuts * 6 / 10,
        "too few sweeps opened anything: {}",
        s.cuts_opening
    );
}

#[test]
fn random_sweeps_over_the_liver_keep_the_body_valid() {
    liver(true);
}

#[test]
fn random_sweeps_over_the_liver_keep_the_body_valid_without_splits() {
    liver(false);
}

fn liver(split: bool) {
    let mesh = tetrahedralised(LIVER);
    let start = Instant::now();
    let sessions = if split { 250 } else { SESSIONS_WITHOUT_SPLITS };
    let s = hammer(&mesh, 0x0001_1FE2, sessions, 4, 10, split, false);
    report(
        if split {
            "liver, split"
        } else {
            "liver, faces"
        },
        &s,
        start.elapsed().as_secs_f64(),
    );
    assert_eq!(s.cuts, 4 * sessions);
    assert!(!split || (s.tips.four_way > 0 && s.tips.fallback > 0));
    assert!(
        s.cuts_opening > s.cuts / 2,
        "too few sweeps opened anything: {}",
        s.cuts_opening
    );
}

/// Sessions (of 4 sweeps) of the run with self-collision on that CI runs: 2 bodies of 8 cuts on
/// the liver. Self-collision is costly here: the bodies land on the floor at once and some of
/// their slivers invert (see the module doc), and on that tangled surface the contact buffer is
/// full from the first cut on (measured 2026-11-29 on the liver: 9 568 contacts, 4 500 of
/// them active, over 10⁵ dropped per step; 0.1–0.7 s per cut's 10 steps against 1 ms per 10
/// steps without). The full sweeps with it on are the ignored tests below.
const SESSIONS_WITH_SELF_COLLISION: usize = 4;

#[test]
fn random_sweeps_over_the_liver_with_self_collision_keep_the_body_valid() {
    self_colliding(Fixture::Liver, SESSIONS_WITH_SELF_COLLISION);
}

#[test]
#[ignore = "the issue's 1000 sweeps with self-collision on: slow (tangled surfaces, see above); run by hand with --ignored"]
fn random_sweeps_over_the_liver_with_self_collision_full() {
    self_colliding(Fixture::Liver, 250);
}

#[test]
#[ignore = "the issue's 1000 sweeps with self-collision on: slow (tangled surfaces, see above); run by hand with --ignored"]
fn random_sweeps_over_the_bunny_with_self_collision_full() {
    self_colliding(Fixture::Bunny, 250);
}

#[derive(Clone, Copy, PartialEq)]
enum Fixture {
    Bunny,
    Liver,
}

/// The seeded sweeps of [`bunny`] or [`liver`] (geometric cuts, the same seeds) with
/// self-collision on: the same checks after every cut, and the body keeps stepping.
fn self_colliding(fixture: Fixture, sessions: usize) {
    let (mesh, seed, name) = match fixture {
        Fixture::Bunny => {
            let (p, t) = tetrahedralised(BUNNY).into_parts();
            let mesh = TetMesh::new(p.iter().map(|p| *p * 10.0).collect(), t).unwrap();
            (mesh, 0x05EE_DB0B, "bunny, split, self-collision")
        }
        Fixture::Liver => (
            tetrahedralised(LIVER),
            0x0001_1FE2,
            "liver, split, self-collision",
        ),
    };
    let start = Instant::now();
    let s = hammer(&mesh, seed, sessions, 4, 10, true, true);
    report(name, &s, start.elapsed().as_secs_f64());
    assert_eq!(s.cuts, 4 * sessions);
    assert_eq!(s.steps, 10 * s.cuts);
    // The same sweeps without self-collision: it must not keep the blade from opening the
    // tissue (which sweeps open depends on where the body has moved, so a few either way).
    let off = hammer(&mesh, seed, sessions, 4, 10, true, false);
    eprintln!(
        "  {name}: {} of {} sweeps opened the tissue, {} without self-collision",
        s.cuts_opening, s.cuts, off.cuts_opening
    );
    assert!(
        s.cuts_opening * 4 >= off.cuts_opening * 3 && s.cuts_opening * 3 >= s.cuts,
        "too few sweeps opened anything: {} of {} ({} without self-collision)",
        s.cuts_opening,
        s.cuts,
        off.cuts_opening
    );
}
