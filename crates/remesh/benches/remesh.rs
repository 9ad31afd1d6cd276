//! Remeshing an 80k-triangle, 0.05 cm noisy plane patch to L = 0.3 cm.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion};
use tissue_remesh::{remesh, scenes, RemeshOptions};

fn bench_remesh(c: &mut Criterion) {
    // grid(201, 10.0): 200² cells of 0.05 cm, 80 000 triangles, 0.02 cm noise.
    let patch = scenes::noisy_plane(10.0, 0.05, 0.02, 7).unwrap();
    assert_eq!(patch.triangle_count(), 80_000);
    let mut group = c.benchmark_group("remesh");
    group.sample_size(10);
    group.bench_function("plane_80k_to_L0.3", |b| {
        b.iter(|| remesh(&patch, &RemeshOptions::new(0.3)).unwrap())
    });
    group.bench_function("plane_80k_to_L0.3_smoothed", |b| {
        b.iter(|| remesh(&patch, &RemeshOptions::new(0.3).with_smoothing(0.3)).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench_remesh);
criterion_main!(benches);
