//! Build, refit and queries on the thesis's largest case: the two-layer region of the 257² plane
//! (≈ 117 k triangles) and the pressing sphere (1984 triangles), from `tissue_bvh::scenes`.
//!
//! Targets (issue): build ≤ 15 ms, refit ≤ 0.5 ms on the region.
#![allow(clippy::expect_used)]

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use glam::Vec3A;
use tissue_bvh::scenes::{self, jitter, to_vec3a, Rng};
use tissue_bvh::{Aabb, BuildOptions, BuildWorkspace, Bvh, BvhWorkspace, Ray, Split, Triangles};

fn options(leaf_size: u32, split: Split) -> BuildOptions {
    BuildOptions {
        leaf_size,
        split,
        margin: 0.0,
    }
}

fn name(split: Split) -> &'static str {
    match split {
        Split::EqualArea => "equal_area",
        Split::Sah => "sah",
    }
}

fn configure<'a>(
    c: &'a mut Criterion,
    group: &str,
) -> criterion::BenchmarkGroup<'a, criterion::measurement::WallTime> {
    let mut g = c.benchmark_group(group);
    g.sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    g
}

fn build(c: &mut Criterion) {
    let scene = scenes::plane_press(257, 0.05, 0.005).expect("scene");
    let pos = to_vec3a(scene.region.positions());
    let tris = Triangles::from_mesh(&scene.region, &pos).expect("positions");
    let mut g = configure(c, "bvh_build_region_117k");
    for (split, leaf) in [
        (Split::EqualArea, 8),
        (Split::EqualArea, 16),
        (Split::EqualArea, 32),
        (Split::Sah, 8),
        (Split::Sah, 16),
    ] {
        let mut ws = BuildWorkspace::new();
        let mut bvh = Bvh::build_with(&tris, &options(leaf, split), &mut ws).expect("build");
        g.bench_function(BenchmarkId::new(name(split), format!("leaf{leaf}")), |b| {
            b.iter(|| bvh.rebuild(&tris, &mut ws).expect("rebuild"))
        });
    }
    g.bench_function("equal_area/leaf8_fresh_allocation", |b| {
        b.iter(|| Bvh::build(&tris, &options(8, Split::EqualArea)).expect("build"))
    });
    g.finish();

    let spos = to_vec3a(scene.sphere.positions());
    let stris = Triangles::from_mesh(&scene.sphere, &spos).expect("positions");
    let mut g = configure(c, "bvh_build_sphere_1984");
    let mut ws = BuildWorkspace::new();
    let mut bvh = Bvh::build_with(&stris, &options(4, Split::EqualArea), &mut ws).expect("build");
    g.bench_function("equal_area/leaf4", |b| {
        b.iter(|| bvh.rebuild(&stris, &mut ws).expect("rebuild"))
    });
    g.finish();
}

fn refit(c: &mut Criterion) {
    let scene = scenes::plane_press(257, 0.05, 0.005).expect("scene");
    let p0 = to_vec3a(scene.region.positions());
    let mut p1 = p0.clone();
    jitter(&mut p1, &mut Rng::new(1), 1e-3);
    let t0 = Triangles::from_mesh(&scene.region, &p0).expect("positions");
    let t1 = Triangles::from_mesh(&scene.region, &p1).expect("positions");
    let mut g = configure(c, "bvh_refit_region_117k");
    for (split, leaf) in [
        (Split::EqualArea, 8),
        (Split::EqualArea, 16),
        (Split::Sah, 8),
    ] {
        let mut bvh = Bvh::build(&t0, &options(leaf, split)).expect("build");
        // Every vertex moves every iteration (alternating between two states): all leaves change.
        let mut flip = false;
        g.bench_function(
            BenchmarkId::new(name(split), format!("leaf{leaf}_all_moved")),
            |b| {
                b.iter(|| {
                    flip = !flip;
                    bvh.refit(if flip { &t1 } else { &t0 }).expect("refit")
                })
            },
        );
        bvh.refit(&t0).expect("refit");
        g.bench_function(
            BenchmarkId::new(name(split), format!("leaf{leaf}_unchanged")),
            |b| b.iter(|| bvh.refit(&t0).expect("refit")),
        );
    }
    g.finish();
}

fn queries(c: &mut Criterion) {
    let scene = scenes::plane_press(257, 0.05, 0.005).expect("scene");
    let pr = to_vec3a(scene.region.positions());
    let ps = to_vec3a(scene.sphere.positions());
    let tr = Triangles::from_mesh(&scene.region, &pr).expect("positions");
    let ts = Triangles::from_mesh(&scene.sphere, &ps).expect("positions");
    let mut rng = Rng::new(7);
    let points: Vec<Vec3A> = (0..256).map(|_| rng.in_cube(0.4)).collect();
    let rays: Vec<Ray> = (0..256)
        .map(|_| {
            Ray::new(
                rng.in_cube(0.4) + Vec3A::new(0.0, 0.0, 0.5),
                rng.in_cube(1.0) - Vec3A::Z,
            )
        })
        .collect();
    let probes: Vec<Aabb> = (0..256)
        .map(|_| {
            let c = rng.in_cube(0.4);
            Aabb::new((c - 0.01).into(), (c + 0.01).into())
        })
        .collect();
    let mut g = configure(c, "bvh_query_region_117k");
    for split in [Split::EqualArea, Split::Sah] {
        let br = Bvh::build(&tr, &options(8, split)).expect("build");
        let bs = Bvh::build(&ts, &options(4, split)).expect("build");
        let mut ws = BvhWorkspace::new();
        let mut out = Vec::new();
        let mut hits = Vec::new();
        g.bench_function(
            BenchmarkId::new(name(split), "leaf_pairs_sphere_touching"),
            |b| {
                b.iter(|| {
                    br.leaf_pairs(&bs, 0.0, &mut ws, &mut out);
                    out.len()
                })
            },
        );
        g.bench_function(BenchmarkId::new(name(split), "256_boxes"), |b| {
            b.iter(|| {
                let mut n = 0;
                for p in &probes {
                    br.overlapping_primitives(&tr, p, 0.0, &mut ws, &mut hits);
                    n += hits.len();
                }
                n
            })
        });
        g.bench_function(BenchmarkId::new(name(split), "256_closest_points"), |b| {
            b.iter(|| {
                points
                    .iter()
                    .filter_map(|&p| br.closest_point(&tr, p, f32::INFINITY, &mut ws))
                    .count()
            })
        });
        g.bench_function(BenchmarkId::new(name(split), "256_rays"), |b| {
            b.iter(|| {
                rays.iter()
                    .filter_map(|r| br.cast_ray(&tr, r, 10.0, &mut ws))
                    .count()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, build, refit, queries);
criterion_main!(benches);
