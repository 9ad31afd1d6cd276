//! A step allocates nothing: every buffer is made when the body is built.
//!
//! The one place in the crate with `unsafe`: a counting global allocator, which must implement the
//! `unsafe` trait `GlobalAlloc`. It only forwards to `System`.
#![allow(unsafe_code, clippy::unwrap_used)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use tissue_mesh::tet_box;
use tissue_pbd::{Floor, Material, SoftBody, Solver, StepSettings, VolumeConstraintKind};

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
fn steps_allocate_nothing_after_the_first() {
    let mesh = tet_box(14, 14, 14, Vec3::splat(6.0)).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    // `None`: the elastic material (neo-Hookean pairs, XPBD only).
    for kind in [
        Some(VolumeConstraintKind::Centroid),
        Some(VolumeConstraintKind::Classic),
        Some(VolumeConstraintKind::None),
        None,
    ] {
        for solver in [Solver::Pbd, Solver::PbdLinearised, Solver::Xpbd] {
            if kind.is_none() && solver != Solver::Xpbd {
                continue;
            }
            for parallel in [false, true] {
                let material = Material {
                    distance_compliance: 1e-5,
                    volume_compliance: 1e-5,
                    volume: kind.unwrap_or(VolumeConstraintKind::None),
                    hold_piece_volumes: true,
                    elastic: kind.is_none().then_some(tissue_pbd::Elastic {
                        young_kpa: 5.0,
                        poisson: 0.45,
                    }),
                    ..Material::default()
                };
                let mut body = SoftBody::new(&mesh, &material).unwrap();
                body.set_floor(Some(Floor::y(-3.5))).unwrap();
                let id = body.attach(0, Vec3::new(-3.0, -3.0, -3.0)).unwrap();
                // A topology edit (it may allocate; the steps after it must not): a node
                // duplicated, one tet moved onto it, an edge added, an edge removed.
                let t = body.tets()[7];
                let copy = body.duplicate_nodes(&[t[0]]).unwrap();
                body.set_tet_nodes(7, [copy, t[1], t[2], t[3]]).unwrap();
                body.add_distance_constraint(tissue_pbd::DistanceConstraint {
                    nodes: [t[0], copy],
                    rest_length: 0.0,
                    stiffness: 1.0,
                    compliance: 0.0,
                })
                .unwrap();
                body.remove_distance_constraint(3).unwrap();
                // Copies of another node until its leaf is full, the last one (past the block
                // tree) tied to it: a constraint of the serial dynamic set.
                let count = 2 * body.node_count();
                let first = body.duplicate_nodes(&vec![t[1]; count]).unwrap();
                body.add_distance_constraint(tissue_pbd::DistanceConstraint {
                    nodes: [t[1], first + count as u32 - 1],
                    rest_length: 0.0,
                    stiffness: 1.0,
                    compliance: 0.0,
                })
                .unwrap();
                assert_eq!(body.serial_dynamic_counts(), (1, 0));
                body.set_settings(StepSettings {
                    solver,
                    parallel,
                    damping: 0.1,
                    ..StepSettings::default()
                })
                .unwrap();
                pool.install(|| {
                    body.step().unwrap();
                    let before = ALLOCATIONS.load(Ordering::Relaxed);
                    for i in 0..5 {
                        body.set_attachment_target(
                            id,
                            Vec3::new(-3.0, -3.0 + 0.01 * i as f32, -3.0),
                        )
                        .unwrap();
                        body.step().unwrap();
                    }
                    let after = ALLOCATIONS.load(Ordering::Relaxed);
                    assert_eq!(
                        after - before,
                        0,
                        "{kind:?} {solver:?} parallel={parallel}: a step allocated"
                    );
                });
            }
        }
    }
}
