//! One PBD step on the TetGen bunny of `fixtures/` (42k tets, scaled to 10 cm; a 20×20×20-cell
//! tet box of 48k tets when the folder is missing): distance + volume constraints, 10 % of the
//! nodes pinned, gravity, no contacts, dt = 10 ms. K = 1, 5, 10, 20 for both volume constraints,
//! serial (`serial`) and parallel on a 2-thread pool (`par2`; same results). Throughput is in
//! constraint projections (constraints × K), so criterion's "elem/s" inverts to ns/projection;
//! a table of medians in ms/step and ns/projection (over `SUMMARY_STEPS` steps each, measured
//! back to back after criterion's runs) closes the output.
//!
//! `pbd_selfcol`: the bunny in the trainer's real-time preset (9 substeps × K = 1, parallel on the
//! 2-thread pool, soft tissue, the same pins), weightless (at rest: the cost is the detection's)
//! and under gravity (sagging on its pins: the broad phase's lists are found again as it
//! moves), with self-collision off and on (issue 35's budget: on at most 35 % over off); a
//! closing table gives both medians, interleaved in one run, and their ratio.
#![allow(missing_docs, clippy::print_stderr, clippy::expect_used, clippy::panic)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use tissue_mesh::TetMesh;
use tissue_pbd::{Material, SelfCollision, SoftBody, Solver, StepSettings, VolumeConstraintKind};

fn mesh() -> TetMesh {
    let stem = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/bunny_10k_tet42k"
    );
    let data = tissue_meshio::read_tetgen(stem)
        .unwrap_or_else(|e| panic!("the bench's bunny {stem}.node/.ele: {e}"));
    TetMesh::new(
        data.positions.iter().map(|p| *p * 10.0).collect(),
        data.tets,
    )
    .expect("bunny")
}

fn body(mesh: &TetMesh, volume: VolumeConstraintKind, iterations: u32, parallel: bool) -> SoftBody {
    let material = Material {
        distance_stiffness: 0.8,
        volume_stiffness: 1.0,
        volume,
        ..Material::default()
    };
    let mut body = SoftBody::new(mesh, &material).expect("body");
    // Pin the lowest 10 % of the nodes (the bunny's base).
    let mut order: Vec<usize> = (0..mesh.vertex_count()).collect();
    order.sort_by(|&a, &b| mesh.positions()[a].y.total_cmp(&mesh.positions()[b].y));
    for &i in &order[..mesh.vertex_count() / 10] {
        body.pin(i as u32).expect("pin");
    }
    body.set_settings(StepSettings {
        dt: 0.01,
        iterations,
        solver: Solver::PbdLinearised,
        parallel,
        ..StepSettings::default()
    })
    .expect("settings");
    // Get past the first, unloaded steps.
    for _ in 0..5 {
        body.step().expect("stable");
    }
    body
}

/// The bunny in the real-time preset, its base pinned, weightless or not, self-collision on or
/// off.
fn realtime_body(mesh: &TetMesh, gravity: bool, self_collision: bool) -> SoftBody {
    let mut body = SoftBody::new(mesh, &Material::soft_tissue()).expect("body");
    let mut order: Vec<usize> = (0..mesh.vertex_count()).collect();
    order.sort_by(|&a, &b| mesh.positions()[a].y.total_cmp(&mesh.positions()[b].y));
    for &i in &order[..mesh.vertex_count() / 10] {
        body.pin(i as u32).expect("pin");
    }
    body.set_settings(StepSettings {
        parallel: true,
        gravity: if gravity {
            StepSettings::default().gravity
        } else {
            Vec3::ZERO
        },
        ..StepSettings::realtime()
    })
    .expect("settings");
    if self_collision {
        body.set_self_collision(Some(SelfCollision::default()))
            .expect("self-collision");
    }
    for _ in 0..5 {
        body.step().expect("stable");
    }
    body
}

fn self_collision(c: &mut Criterion) {
    let mesh = mesh();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let mut group = c.benchmark_group("pbd_selfcol");
    group.sample_size(20);
    group.measurement_time(std::time::Duration::from_secs(3));
    group.warm_up_time(std::time::Duration::from_millis(500));
    let cases = [("weightless", false), ("gravity", true)];
    for (case, gravity) in cases {
        for (name, on) in [("off", false), ("on", true)] {
            let mut b = realtime_body(&mesh, gravity, on);
            group.bench_function(
                BenchmarkId::new(format!("bunny_realtime_{case}"), name),
                |bench| pool.install(|| bench.iter(|| b.step().expect("stable"))),
            );
        }
    }
    group.finish();
    eprintln!(
        "\npbd_selfcol summary (bunny, real-time preset, off and on interleaved, 200 steps each)"
    );
    for (case, gravity) in cases {
        // Interleaved, in one run: 20 blocks of 10 steps each, off then on.
        let (mut off, mut on) = (
            realtime_body(&mesh, gravity, false),
            realtime_body(&mesh, gravity, true),
        );
        let (mut t_off, mut t_on) = (Vec::new(), Vec::new());
        pool.install(|| {
            for _ in 0..20 {
                for (body, times) in [(&mut off, &mut t_off), (&mut on, &mut t_on)] {
                    for _ in 0..10 {
                        let t = std::time::Instant::now();
                        body.step().expect("stable");
                        times.push(t.elapsed().as_secs_f64() * 1e3);
                    }
                }
            }
        });
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (a, b) = (median(&mut t_off), median(&mut t_on));
        eprintln!(
            "{case:<10} median off {a:.3} ms/step, on {b:.3} ms/step, on/off {:.3} (+{:.0} %), \
             self-contacts {:?}",
            b / a,
            100.0 * (b / a - 1.0),
            on.self_contact_counts()
        );
    }
}

fn projections(b: &SoftBody, k: u32) -> u64 {
    (b.distance_constraints().len()
        + b.tet_volume_constraints().len()
        + b.centroid_volume_constraints().len()) as u64
        * k as u64
}

/// Steps per configuration for the closing table.
const SUMMARY_STEPS: usize = 60;

fn step(c: &mut Criterion) {
    let mesh = mesh();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let kinds = [
        VolumeConstraintKind::Classic,
        VolumeConstraintKind::Centroid,
    ];
    let modes = [("serial", false), ("par2", true)];
    let mut group = c.benchmark_group("pbd_step");
    group.sample_size(20);
    group.measurement_time(std::time::Duration::from_secs(3));
    group.warm_up_time(std::time::Duration::from_millis(500));
    for volume in kinds {
        for (mode, parallel) in modes {
            for k in [1u32, 5, 10, 20] {
                let mut b = body(&mesh, volume, k, parallel);
                group.throughput(Throughput::Elements(projections(&b, k)));
                group.bench_function(
                    BenchmarkId::new(format!("{volume:?}/{mode}"), format!("K{k}")),
                    |bench| pool.install(|| bench.iter(|| b.step().expect("stable"))),
                );
            }
        }
    }
    group.finish();

    eprintln!(
        "\npbd_step summary: median of {SUMMARY_STEPS} steps (wall clock; check the machine load)"
    );
    eprintln!(
        "{:<10} {:<7} {:>3} {:>9} {:>8} {:>12}",
        "volume", "mode", "K", "ms/step", "ns/proj", "projections"
    );
    for volume in kinds {
        for (mode, parallel) in modes {
            for k in [1u32, 5, 10, 20] {
                let mut b = body(&mesh, volume, k, parallel);
                let mut times: Vec<f64> = pool.install(|| {
                    (0..SUMMARY_STEPS)
                        .map(|_| {
                            let t = std::time::Instant::now();
                            b.step().expect("stable");
                            t.elapsed().as_secs_f64()
                        })
                        .collect()
                });
                times.sort_by(f64::total_cmp);
                let median = times[SUMMARY_STEPS / 2];
                let n = projections(&b, k);
                eprintln!(
                    "{:<10} {:<7} {:>3} {:>9.3} {:>8.2} {:>12}",
                    format!("{volume:?}"),
                    mode,
                    k,
                    median * 1e3,
                    median * 1e9 / n as f64,
                    n
                );
            }
        }
    }
}

criterion_group!(benches, step, self_collision);
criterion_main!(benches);
