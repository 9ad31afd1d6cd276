//! One PBD step on the bunny of `../shared/meshes` (42k tets, scaled to 10 cm; a 20×20×20-cell
//! tet box of 48k tets when the folder is missing): distance + volume constraints, 10 % of the
//! nodes pinned, gravity, no contacts, dt = 10 ms. Serial Gauss–Seidel at K = 1, 5, 10, 20 for
//! both volume constraints, and colour-parallel on a 2-thread pool at K = 10. Throughput is in
//! constraint projections (constraints × K), so criterion's "elem/s" inverts to ns/projection.
#![allow(missing_docs, clippy::print_stderr)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::{Material, SoftBody, Solver, StepSettings, VolumeConstraintKind};

fn mesh() -> TetMesh {
    let stem = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/meshes/bunny_10k_tet42k"
    );
    match tissue_meshio::read_tetgen(stem) {
        Ok(data) => TetMesh::new(
            data.positions.iter().map(|p| *p * 10.0).collect(),
            data.tets,
        )
        .expect("bunny"),
        Err(e) => {
            eprintln!("bunny not available ({e}); benchmarking a 20³-cell tet box instead");
            tet_box(20, 20, 20, Vec3::splat(10.0)).expect("box")
        }
    }
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

fn projections(b: &SoftBody, k: u32) -> u64 {
    (b.distance_constraints().len()
        + b.tet_volume_constraints().len()
        + b.centroid_volume_constraints().len()) as u64
        * k as u64
}

fn step(c: &mut Criterion) {
    let mesh = mesh();
    let mut group = c.benchmark_group("pbd_step");
    group.sample_size(20);
    group.measurement_time(std::time::Duration::from_secs(3));
    group.warm_up_time(std::time::Duration::from_millis(500));
    for volume in [
        VolumeConstraintKind::Classic,
        VolumeConstraintKind::Centroid,
    ] {
        for k in [1u32, 5, 10, 20] {
            let mut b = body(&mesh, volume, k, false);
            group.throughput(Throughput::Elements(projections(&b, k)));
            group.bench_function(
                BenchmarkId::new(format!("{volume:?}/serial"), format!("K{k}")),
                |bench| bench.iter(|| b.step().expect("stable")),
            );
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("pool");
        let mut b = body(&mesh, volume, 10, true);
        group.throughput(Throughput::Elements(projections(&b, 10)));
        group.bench_function(
            BenchmarkId::new(format!("{volume:?}/colour2"), "K10"),
            |bench| pool.install(|| bench.iter(|| b.step().expect("stable"))),
        );
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
