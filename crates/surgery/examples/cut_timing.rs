//! Step time with and without a cut on the bunny (9217 nodes, 42117 tets, scaled to 16.7 cm):
//! a scalpel (its edge `EDGE_CM` above the bunny's mid-height, default 1) is drawn across it,
//! one cut per step, three times from the same settled state; prints the median and p99 of the
//! plain steps before the cut, of the steps during it (the step plus the cut), of the cut
//! alone (and, per cutting step, its fastest of the three runs: robust to the machine's
//! noise), of the same step of a copy of the body without the cut (timed just before the real
//! one), and of the time the cut adds (step + cut − that same step, paired per cutting step so
//! that the machine's drift cancels), and the wall and surface triangles each cut opened or
//! split.
//!
//! `cargo run --release -p tissue-surgery --example cut_timing [-- STEP_CM [EDGE_CM [faces]
//! [parallel]]]` (`faces`: face separation only, `SurgerySettings::split_tets` off; default on;
//! `parallel`: `StepSettings::parallel` on, on rayon's global pool; default serial).
#![allow(clippy::unwrap_used, clippy::print_stdout, clippy::panic)]

use std::hash::{DefaultHasher, Hash, Hasher};
use std::time::Instant;

use glam::{Quat, Vec3};
use tissue_mesh::TetMesh;
use tissue_pbd::{ConstraintSlot, Floor, Material, Pose, SoftBody, StepSettings, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgeryEvent, SurgerySettings};

const BUNNY: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../fixtures/bunny_10k_tet42k"
);

/// Traverses of the bunny, each from the same settled state.
const TRAVERSES: usize = 3;

fn stats(name: &str, v: &mut [f64]) {
    v.sort_by(f64::total_cmp);
    let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
    println!(
        "{name:<28} n = {:3}  median {:6.3} ms  p99 {:6.3} ms  max {:6.3} ms",
        v.len(),
        q(0.5) * 1e3,
        q(0.99) * 1e3,
        q(1.0) * 1e3
    );
}

/// A hash of the body and the surgery state (positions, rest positions, velocities bit for
/// bit, tets, adjacency, origins, pieces): equal outputs of two builds mean the same cut.
fn fingerprint(body: &SoftBody, surgery: &Surgery) -> u64 {
    let mut h = DefaultHasher::new();
    for field in [body.positions(), body.rest_positions(), body.velocities()] {
        for p in field {
            p.to_array().map(f32::to_bits).hash(&mut h);
        }
    }
    body.tets().hash(&mut h);
    surgery.neighbours().hash(&mut h);
    surgery.origins().hash(&mut h);
    surgery.tet_components().hash(&mut h);
    surgery.cut_faces().hash(&mut h);
    h.finish()
}

fn main() {
    let step_cm: f32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.25);
    // Height of the blade's edge above the middle of the settled bunny (cm).
    let edge: f32 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    let mesh = tissue_meshio::read_tets(BUNNY)
        .unwrap_or_else(|e| panic!("the bunny {BUNNY}.node/.ele: {e}"));
    let (p, t) = mesh.into_parts();
    let mesh = TetMesh::new(p.iter().map(|p| *p * 10.0).collect(), t).unwrap();
    let lo = mesh
        .positions()
        .iter()
        .fold(Vec3::INFINITY, |a, p| a.min(*p));
    let hi = mesh
        .positions()
        .iter()
        .fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
    let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
    body.set_floor(Some(Floor::y(lo.y))).unwrap();
    // Geometric cuts (tets split on the blade's plane) unless a word after the numbers is
    // `faces`; parallel projection if one is `parallel`.
    let words: Vec<String> = std::env::args().skip(3).collect();
    let split_tets = !words.iter().any(|w| w == "faces");
    let parallel = words.iter().any(|w| w == "parallel");
    body.set_settings(StepSettings {
        parallel,
        ..StepSettings::default()
    })
    .unwrap();
    let settings = SurgerySettings {
        split_tets,
        ..SurgerySettings::default()
    };
    let mut surgery = Surgery::new(&body, settings).unwrap();
    for _ in 0..30 {
        body.step().unwrap();
    }
    let mut plain = Vec::new();
    for _ in 0..100 {
        let t = Instant::now();
        body.step().unwrap();
        plain.push(t.elapsed().as_secs_f64());
    }
    // The blade stands in the plane z = centre, its edge 2.5 cm below the top, drawn along x.
    let blade = ToolShape::Blade {
        a: Vec3::new(-0.3, 0.0, 0.0),
        b: Vec3::new(0.3, 0.0, 0.0),
        c: Vec3::new(0.0, 6.0, 0.0),
        thickness: 0.01,
    };
    let top = body
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f32::MIN, f32::max);
    let (cz, y) = (0.5 * (lo.z + hi.z) + 0.013, 0.5 * (lo.y + top) + edge);
    let x0 = lo.x - 0.5;
    let at = |x: f32| Pose::new(Quat::IDENTITY, Vec3::new(x, y, cz));
    let (mut with_cut, mut cut_only, mut step_only, mut opened, mut split) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut same_step, mut added) = (Vec::new(), Vec::new());
    // The traverse, `TRAVERSES` times from the same settled state (the last one is kept). Each
    // cutting step is paired with the same step of a copy of the body without the cut, timed
    // just before it, so that the machine's drift cancels out of the added time. (The copy's
    // clone runs before both steps, so both find the body's data in the shared cache alike.)
    let settled = (body.clone(), surgery.clone());
    for _ in 0..TRAVERSES {
        (body, surgery) = settled.clone();
        let mut x = x0;
        while x < hi.x + 0.5 {
            let mut shadow = body.clone();
            let t = Instant::now();
            shadow.step().unwrap();
            let plain_now = t.elapsed().as_secs_f64();
            drop(shadow);
            let t = Instant::now();
            body.step().unwrap();
            let s = t.elapsed().as_secs_f64();
            let c = Instant::now();
            let events = surgery
                .cut(
                    &mut body,
                    &BladeSweep::new(&blade, &at(x), &at(x + step_cm)).unwrap(),
                )
                .unwrap();
            let c = c.elapsed().as_secs_f64();
            x += step_cm;
            let (faces, triangles): (usize, usize) = events
                .iter()
                .map(|e| match e {
                    SurgeryEvent::CutAdvanced {
                        opened_faces,
                        split_triangles,
                        ..
                    } => (opened_faces.len(), split_triangles.len()),
                    _ => (0, 0),
                })
                .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            if faces > 0 || triangles > 0 {
                opened.push(faces as f64);
                split.push(triangles as f64);
                with_cut.push(s + c);
                cut_only.push(c);
                step_only.push(s);
                same_step.push(plain_now);
                added.push(s + c - plain_now);
            }
        }
    }
    surgery.validate(&body).unwrap();
    let cut_fingerprint = fingerprint(&body, &surgery);
    let mut after = Vec::new();
    for _ in 0..100 {
        let t = Instant::now();
        body.step().unwrap();
        after.push(t.elapsed().as_secs_f64());
    }
    println!(
        "bunny: {} nodes ({} added by the cut), {} tets, blade step {step_cm} cm; dynamic set {:?} in {:?} batches",
        body.node_count(),
        body.node_count() - mesh.vertex_count(),
        body.tets().len(),
        body.dynamic_counts(),
        body.dynamic_batch_counts()
    );
    // Where the dynamic constraints are projected: by depth of their block in the tree (0 =
    // the root), and serially.
    let depth = |b: u32| (b + 1).ilog2() as usize;
    let (mut distances, mut tets) = (vec![0usize; 16], vec![0usize; 16]);
    for c in 0..body.distance_constraints().len() {
        if let Some(ConstraintSlot::Block { block, .. }) = body.distance_slot(c) {
            distances[depth(block)] += 1;
        }
    }
    for t in 0..body.tets().len() {
        if let Some(ConstraintSlot::Block { block, .. }) = body.tet_slot(t) {
            tets[depth(block)] += 1;
        }
    }
    let last = |v: &[usize]| v.iter().rposition(|&n| n > 0).map_or(0, |k| k + 1);
    println!(
        "  in the tree by depth: distances {:?}, tets {:?}; serial {:?} in {:?} batches",
        &distances[..last(&distances)],
        &tets[..last(&tets)],
        body.serial_dynamic_counts(),
        body.serial_dynamic_batch_counts()
    );
    stats("step, before the cut", &mut plain);
    stats("step + cut (cutting steps)", &mut with_cut);
    stats("  of which the step", &mut step_only);
    stats("  of which the cut", &mut cut_only);
    stats("step, after the cut", &mut after);
    stats("same step without the cut", &mut same_step);
    // The cut's own cost, robust to the machine's noise: per cutting step, the fastest of
    // the traverses (each traverse cuts the same steps alike).
    let per = cut_only.len() / TRAVERSES;
    let mut fastest: Vec<f64> = (0..per)
        .map(|i| {
            (0..TRAVERSES)
                .map(|r| cut_only[r * per + i])
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    stats("  the cut, fastest of runs", &mut fastest);
    stats("added by the cut (paired)", &mut added);
    opened.sort_by(f64::total_cmp);
    split.sort_by(f64::total_cmp);
    println!(
        "wall triangles per cutting step: median {}, max {}; boundary triangles split per cutting step: median {}, max {}",
        opened[opened.len() / 2],
        opened[opened.len() - 1],
        split[split.len() / 2],
        split[split.len() - 1]
    );
    println!(
        "fingerprint: after the cut {cut_fingerprint:016x}, after 100 more steps {:016x}",
        fingerprint(&body, &surgery)
    );
    let tips = surgery.tip_counts();
    println!(
        "tips of the last traverse: {} split into 4, {} on the crack line (fallback); four-way candidates refused: {} margin, {} neighbour, {} unsplit, {} needed, {} quality",
        tips.four_way,
        tips.fallback,
        tips.refused_margin,
        tips.refused_neighbour,
        tips.refused_unsplit,
        tips.refused_needed,
        tips.refused_quality
    );
}
