//! Detection and response on the thesis's largest case: the two-layer region of the 257² plane
//! (≈ 117 k triangles, surface A) and the r = 0.25 cm sphere of 1984 triangles (surface B) pushed
//! into layer 2 from below, from `tissue_bvh::scenes`.
//!
//! Target (issue): detection (broad + narrow) ≤ 0.3 ms per step when the sphere touches the
//! region, by BVH vs BVH and by BVH vs voxels.
#![allow(clippy::expect_used)]

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use glam::Vec3A;
use tissue_bvh::scenes::{self, to_vec3a, PlanePress};
use tissue_bvh::{BuildOptions, Bvh, Split};
use tissue_collide::{
    apply_impulses, detect_bvh_bvh, detect_bvh_voxels, Bodies, BroadPhase, Collider,
    ColliderOptions, ContactParams, DetectWorkspace, ImpulseWorkspace, ResponseParams, Side,
    Surface, VoxelGrid,
};

/// How far the sphere's top is pushed into layer 2 (cm): just touching, and pressed.
const PENETRATIONS: [f32; 2] = [0.005, 0.02];

fn scene(penetration: f32) -> PlanePress {
    scenes::plane_press(257, 0.05, penetration).expect("scene")
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

fn options(leaf_size: u32, split: Split) -> BuildOptions {
    BuildOptions {
        leaf_size,
        split,
        margin: 0.0,
    }
}

fn detect(c: &mut Criterion) {
    let params = ContactParams::default();
    let mut g = configure(c, "detect_region_117k_vs_sphere_1984");
    for pen in PENETRATIONS {
        let s = scene(pen);
        let (pa, pb) = (
            to_vec3a(s.region.positions()),
            to_vec3a(s.sphere.positions()),
        );
        let (sa, sb) = (Surface::new(&s.region), Surface::new(&s.sphere));
        let va = sa.view(Side::A, &pa).expect("positions");
        let vb = sb.view(Side::B, &pb).expect("positions");
        let mut ws = DetectWorkspace::new();
        let mut out = Vec::new();
        for (split, la, lb) in [
            (Split::EqualArea, 8, 4),
            (Split::EqualArea, 16, 2),
            (Split::Sah, 8, 4),
        ] {
            let ba = Bvh::build(va.triangles(), &options(la, split)).expect("build");
            let bb = Bvh::build(vb.triangles(), &options(lb, split)).expect("build");
            let id = format!(
                "bvh_bvh_{}_A{la}_B{lb}",
                if split == Split::Sah {
                    "sah"
                } else {
                    "equal_area"
                }
            );
            g.bench_function(BenchmarkId::new(id, format!("pen{pen}")), |b| {
                b.iter(|| {
                    detect_bvh_bvh(&va, &ba, &vb, &bb, &params, &mut ws, &mut out).expect("detect")
                })
            });
        }
        let ba = Bvh::build(va.triangles(), &options(8, Split::EqualArea)).expect("build");
        for cell in [0.01f32, 0.02, 0.03] {
            let grid = VoxelGrid::new(&vb, cell).expect("grid");
            g.bench_function(
                BenchmarkId::new(format!("bvh_voxels_A8_cell{cell}"), format!("pen{pen}")),
                |b| {
                    b.iter(|| {
                        detect_bvh_voxels(&va, &ba, &vb, &grid, &params, &mut ws, &mut out)
                            .expect("detect")
                    })
                },
            );
        }
    }
    g.finish();
}

fn update(c: &mut Criterion) {
    let s = scene(0.005);
    let pb = to_vec3a(s.sphere.positions());
    let sb = Surface::new(&s.sphere);
    let vb = sb.view(Side::B, &pb).expect("positions");
    let mut g = configure(c, "update_sphere_1984");
    for cell in [0.01f32, 0.02, 0.03] {
        let mut grid = VoxelGrid::new(&vb, cell).expect("grid");
        g.bench_function(format!("voxel_update_cell{cell}"), |b| {
            b.iter(|| grid.update(&vb).expect("update"))
        });
    }
    let mut bvh = Bvh::build(vb.triangles(), &options(4, Split::EqualArea)).expect("build");
    g.bench_function("bvh_refit_leaf4", |b| {
        b.iter(|| bvh.refit(vb.triangles()).expect("refit"))
    });
    g.finish();
}

fn step(c: &mut Criterion) {
    // The collision phase of a step as the implant crate runs it: refit (or re-bin) and detect.
    let s = scene(0.005);
    let (pa, pb) = (
        to_vec3a(s.region.positions()),
        to_vec3a(s.sphere.positions()),
    );
    let mut g = configure(c, "collider_step_region_117k");
    for method in [BroadPhase::BvhBvh, BroadPhase::BvhVoxels] {
        let opts = ColliderOptions {
            broad_phase: method,
            cell_size: Some(0.02),
            ..ColliderOptions::default()
        };
        let mut collider = Collider::new(&s.region, &s.sphere, &opts).expect("collider");
        // Two position sets a rounding apart, alternated: a detection at the positions of the
        // last one returns its contacts without work.
        let mut nudged = pa.clone();
        nudged[0].x = f32::from_bits(nudged[0].x.to_bits() ^ 1);
        let mut flip = false;
        g.bench_function(format!("{method:?}_update_and_detect"), |b| {
            b.iter(|| {
                flip = !flip;
                let a = if flip { &nudged } else { &pa };
                collider.detect(a, &pb).expect("detect").len()
            })
        });
    }
    let mut collider =
        Collider::new(&s.region, &s.sphere, &ColliderOptions::default()).expect("collider");
    let contacts = collider.detect(&pa, &pb).expect("detect").to_vec();
    let inv_a = vec![1.0f32; pa.len()];
    let inv_b = vec![0.0f32; pb.len()];
    let va0 = vec![Vec3A::new(0.0, 0.0, -5.0); pa.len()];
    let vb0 = vec![Vec3A::new(0.0, 0.0, 5.0); pb.len()];
    let (mut va, mut vb) = (va0.clone(), vb0.clone());
    let mut ws = ImpulseWorkspace::new();
    let params = ResponseParams::default();
    g.bench_function(format!("impulses_{}_contacts", contacts.len()), |b| {
        b.iter(|| {
            va.copy_from_slice(&va0);
            vb.copy_from_slice(&vb0);
            apply_impulses(
                &contacts,
                &mut Bodies::two(&mut va, &inv_a, &mut vb, &inv_b),
                &params,
                &mut ws,
            )
            .expect("impulses")
        })
    });
    g.finish();
}

criterion_group!(benches, detect, update, step);
criterion_main!(benches);
