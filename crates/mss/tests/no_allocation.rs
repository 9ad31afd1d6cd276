//! A step allocates nothing: every buffer is made when the system is built.
//!
//! The one place in the workspace with `unsafe`: a counting global allocator, which must
//! implement the `unsafe` trait `GlobalAlloc`. It only forwards to `System`.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use tissue_mesh::subdivided_cube;
use tissue_mss::scenes::two_layer_region;
use tissue_mss::{masses_from_triangles, Integrator, VolumePreservation};

/// Counts allocations made on this test's threads.
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
fn serial_steps_allocate_nothing() {
    let mut s = two_layer_region(65).unwrap();
    s.set_parallel(false);
    s.set_gravity(Vec3::new(0.0, 0.0, -981.0)).unwrap();
    // And a closed cube with volume preservation, stepped fused and split.
    let cube = subdivided_cube(4, 2.0).unwrap();
    let masses = masses_from_triangles(&cube, 1.0).unwrap();
    let mut c = tissue_mss::MassSpringSystem::new(
        tissue_mss::Particles::new(cube.positions(), &masses).unwrap(),
        tissue_mss::springs_from_triangles(
            &cube,
            &tissue_mss::SheetMaterial {
                young: 1e4,
                poisson: 0.3,
                thickness: 0.1,
            },
            0,
        )
        .unwrap(),
    )
    .unwrap();
    c.add_volume_preservation(VolumePreservation::new(&cube, &masses, 0, 5.0, 0.3).unwrap())
        .unwrap();
    for integrator in [Integrator::ExplicitEuler, Integrator::SymplecticEuler] {
        s.set_integrator(integrator);
        c.set_integrator(integrator);
        // Warm up once (nothing should allocate here either, but be fair to lazy statics).
        s.step(1e-6).unwrap();
        c.step_with(1e-5, |_| {}).unwrap();
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        for _ in 0..10 {
            s.step(1e-6).unwrap();
            c.step(1e-5).unwrap();
            c.step_with(1e-5, |_| {}).unwrap();
        }
        let after = ALLOCATIONS.load(Ordering::Relaxed);
        assert_eq!(after - before, 0, "{integrator:?}: a step allocated");
    }
}
