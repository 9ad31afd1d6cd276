//! Once its buffers have grown, a collision step (detect, impulses, separation) allocates nothing.
//!
//! The one place in this crate with `unsafe`: a counting global allocator, which must implement
//! the `unsafe` trait `GlobalAlloc`. It only forwards to `System`.
#![allow(unsafe_code, clippy::unwrap_used)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3A;
use tissue_bvh::scenes::plane_press;
use tissue_collide::{Bodies, BroadPhase, Collider, ColliderOptions, ResponseParams, Snapshot};

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
fn collision_steps_allocate_nothing_once_grown() {
    // Inside a rayon pool, as a parallel narrow phase runs: called from a thread outside the
    // pool, rayon's global job queue itself allocates a block every 63 jobs (its own
    // bookkeeping, not this crate's buffers).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.install(steps_allocate_nothing);
}

fn steps_allocate_nothing() {
    let scene = plane_press(65, 0.05, 0.02).unwrap();
    for broad_phase in [BroadPhase::BvhBvh, BroadPhase::BvhVoxels] {
        let mut collider = Collider::new(
            &scene.region,
            &scene.sphere,
            &ColliderOptions {
                broad_phase,
                ..ColliderOptions::default()
            },
        )
        .unwrap();
        let params = ResponseParams::default();
        let start_a: Vec<Vec3A> = scene.region.positions().iter().map(|&p| p.into()).collect();
        let start_b: Vec<Vec3A> = scene.sphere.positions().iter().map(|&p| p.into()).collect();
        let inv_a: Vec<f32> = vec![1.0; start_a.len()];
        let inv_b: Vec<f32> = vec![0.0; start_b.len()];
        let (mut pos_a, mut pos_b) = (start_a.clone(), start_b.clone());
        let (mut prev_a, mut prev_b) = (start_a.clone(), start_b.clone());
        let mut vel_a = vec![Vec3A::ZERO; start_a.len()];
        let mut vel_b = vec![Vec3A::new(0.0, 0.0, 5.0); start_b.len()];
        let h = 1e-3f32;

        // The sphere rises through layer 2 for ten steps: detection, impulses, motion, separation.
        let mut run = |collider: &mut Collider| {
            pos_a.copy_from_slice(&start_a);
            pos_b.copy_from_slice(&start_b);
            vel_a.iter_mut().for_each(|v| *v = Vec3A::ZERO);
            let mut contacts = 0;
            for _ in 0..10 {
                contacts += collider.detect(&pos_a, &pos_b).unwrap().len();
                collider
                    .apply_impulses(
                        &mut Bodies::two(&mut vel_a, &inv_a, &mut vel_b, &inv_b),
                        &params,
                    )
                    .unwrap();
                prev_a.copy_from_slice(&pos_a);
                prev_b.copy_from_slice(&pos_b);
                for (x, v) in pos_a.iter_mut().zip(&vel_a) {
                    *x += *v * h;
                }
                for (x, v) in pos_b.iter_mut().zip(&vel_b) {
                    *x += *v * h;
                }
                collider
                    .separate(
                        &mut Bodies::two(&mut pos_a, &inv_a, &mut pos_b, &inv_b),
                        Some(Snapshot {
                            a: &prev_a,
                            b: &prev_b,
                        }),
                        &params,
                    )
                    .unwrap();
            }
            contacts
        };
        let warm = run(&mut collider);
        assert!(warm > 0, "{broad_phase:?}: the scene should make contacts");
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        let again = run(&mut collider);
        let after = ALLOCATIONS.load(Ordering::Relaxed);
        assert_eq!(warm, again, "{broad_phase:?}: the replay differs");
        assert_eq!(
            after - before,
            0,
            "{broad_phase:?}: a collision step allocated"
        );
    }
}
