//! `tetrahedralize` end to end on the bunny of `fixtures/` (10 000 triangles → about
//! 40 000 tets with the default options); a generated sphere of similar size when the folder is
//! missing. Also the sphere at the default and at a finer spacing, to see how time scales.
#![allow(missing_docs, clippy::print_stderr, clippy::expect_used, clippy::panic)]

use criterion::{criterion_group, criterion_main, Criterion};
use tissue_mesh::{uv_sphere, TriMesh};
use tissue_tetra::{tetrahedralize, TetraOptions};

fn bunny() -> (TriMesh, &'static str) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/bunny_10k.obj");
    let mesh = tissue_meshio::read_surface(path)
        .unwrap_or_else(|e| panic!("the bench's bunny {path}: {e}"));
    (mesh, "bunny_10k")
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("tetrahedralize");
    group.sample_size(10);
    group.measurement_time(std::time::Duration::from_secs(8));
    group.warm_up_time(std::time::Duration::from_secs(1));
    let (surface, name) = bunny();
    let options = TetraOptions::default();
    group.bench_function(name, |b| {
        b.iter(|| tetrahedralize(&surface, &options).expect("tetrahedralize"))
    });
    let sphere = uv_sphere(64, 32, 1.0).expect("sphere");
    for (label, factor) in [("sphere_4k_default", 1.68f32), ("sphere_4k_fine", 0.84)] {
        let options = TetraOptions {
            spacing_factor: factor,
            ..TetraOptions::default()
        };
        group.bench_function(label, |b| {
            b.iter(|| tetrahedralize(&sphere, &options).expect("tetrahedralize"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
