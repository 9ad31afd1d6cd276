//! A step with self-collision allocates nothing after the one that builds the surface (alone in
//! its process: the allocation counter is global).
//!
//! The one place in the crate with `unsafe`: a counting global allocator, which must implement the
//! `unsafe` trait `GlobalAlloc`. It only forwards to `System`.
#![allow(unsafe_code, clippy::unwrap_used)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use tissue_mesh::tet_box;
use tissue_pbd::{Floor, Material, SoftBody, StepSettings};

/// Counts allocations made on any thread.
struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn self_collision_steps_allocate_nothing_after_the_first() {
    // A 6 × 0.4 × 1 cm slab bent at rest into a U whose upper arm falls onto the lower one
    // (tests/it/selfcol.rs): contacts come and go during the steps counted.
    let (positions, tets) = tet_box(30, 2, 5, Vec3::new(6.0, 0.4, 1.0))
        .unwrap()
        .into_parts();
    let (s0, r) = (-0.5f32, 0.6f32);
    let loop_len = std::f32::consts::PI * r;
    let bent = positions
        .iter()
        .map(|p| {
            let (s, t) = (p.x, p.y);
            if s <= s0 {
                Vec3::new(s, t, p.z)
            } else if s <= s0 + loop_len {
                let phi = (s - s0) / r;
                Vec3::new(s0 + (r - t) * phi.sin(), r - (r - t) * phi.cos(), p.z)
            } else {
                Vec3::new(s0 - (s - s0 - loop_len), 2.0 * r - t, p.z)
            }
        })
        .collect();
    let mesh = tissue_mesh::TetMesh::new(bent, tets).unwrap();
    // Serial, then parallel on a 2-thread pool (the broad phase's chunks in parallel).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    for parallel in [false, true] {
        let mut body = SoftBody::new(&mesh, &Material::soft_tissue()).unwrap();
        body.set_settings(StepSettings {
            parallel,
            ..StepSettings::realtime()
        })
        .unwrap();
        body.set_floor(Some(Floor::y(-0.2))).unwrap();
        body.set_self_collision(Some(tissue_pbd::SelfCollision::default()))
            .unwrap();
        pool.install(|| {
            body.step().unwrap();
            let before = ALLOCATIONS.load(Ordering::Relaxed);
            let mut most = 0;
            for _ in 0..40 {
                body.step().unwrap();
                most = most.max(body.self_contact_counts().1);
            }
            let after = ALLOCATIONS.load(Ordering::Relaxed);
            assert!(most > 0, "no self-contact: the test tests nothing");
            assert_eq!(
                after - before,
                0,
                "a step with self-collision allocated (parallel = {parallel})"
            );
        });
    }
}
