//! Validation + topology build and the f64 measures on the thesis's plane sizes.
#![allow(clippy::expect_used)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use tissue_mesh::{grid, TriMesh};

fn build_and_measure(c: &mut Criterion) {
    let mut group = c.benchmark_group("trimesh");
    group.sample_size(20);
    for n in [65u32, 129, 257] {
        let plane = grid(n, 1.0).expect("valid grid");
        let (positions, triangles) = plane.clone().into_parts();
        group.throughput(Throughput::Elements(triangles.len() as u64));
        group.bench_with_input(BenchmarkId::new("new", n * n), &n, |b, _| {
            b.iter(|| TriMesh::new(positions.clone(), triangles.clone()).expect("valid"))
        });
        group.bench_with_input(BenchmarkId::new("area", n * n), &n, |b, _| {
            b.iter(|| plane.area())
        });
        group.bench_with_input(BenchmarkId::new("vertex_normals", n * n), &n, |b, _| {
            b.iter(|| plane.vertex_normals())
        });
    }
    group.finish();
}

criterion_group!(benches, build_and_measure);
criterion_main!(benches);
