//! Steps with colliders and tools in contact allocate nothing: the contact buffer is reserved
//! when a collider or tool is added.
//!
//! Like `no_allocation.rs`, a counting global allocator (the `unsafe` trait `GlobalAlloc`); it
//! only forwards to `System`. One test per binary, so no other test allocates meanwhile.
#![allow(unsafe_code, clippy::unwrap_used)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use tissue_mesh::{tet_box, TetMesh};
use tissue_pbd::{
    ContactParams, Material, OrientedBox, Pose, SoftBody, StepSettings, ToolShape, VoxelCollider,
};

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
fn steps_with_contacts_allocate_nothing() {
    let mesh = tet_box(8, 4, 8, Vec3::new(8.0, 4.0, 8.0)).unwrap();
    let (p, t) = mesh.into_parts();
    let mesh = TetMesh::new(p.iter().map(|p| *p + Vec3::Y * 2.0).collect(), t).unwrap();
    let mut body = SoftBody::new(&mesh, &Material::default()).unwrap();
    let tray =
        VoxelCollider::from_box(OrientedBox::tray(0.0, 0.0, 0.0, 30.0, 30.0, 2.0), 0.5).unwrap();
    body.add_collider(tray, ContactParams::default()).unwrap();
    let capsule = body
        .add_tool(
            ToolShape::Capsule {
                a: Vec3::ZERO,
                b: Vec3::new(0.0, 6.0, 0.0),
                radius: 0.5,
            },
            Pose::from_translation(Vec3::new(0.0, 4.2, 0.0)),
            ContactParams::default(),
        )
        .unwrap();
    let blade = body
        .add_tool(
            ToolShape::Blade {
                a: Vec3::new(-1.0, 0.0, 0.0),
                b: Vec3::new(1.0, 0.0, 0.0),
                c: Vec3::new(0.0, 2.0, 0.0),
                thickness: 0.05,
            },
            Pose::from_translation(Vec3::new(2.0, 3.5, 0.0)),
            ContactParams::frictionless(),
        )
        .unwrap();
    body.set_settings(StepSettings {
        dt: 0.005,
        ..StepSettings::default()
    })
    .unwrap();
    body.step().unwrap();
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for i in 1..=10 {
        let s = i as f32;
        body.set_tool_pose(
            capsule,
            Pose::from_translation(Vec3::new(0.05 * s, 4.2 - 0.1 * s, 0.0)),
        )
        .unwrap();
        body.set_tool_pose(
            blade,
            Pose::from_translation(Vec3::new(2.0, 3.5 - 0.1 * s, 0.0)),
        )
        .unwrap();
        body.step().unwrap();
    }
    let after = ALLOCATIONS.load(Ordering::Relaxed);
    assert!(
        body.contacts().len() > 20,
        "{} contacts",
        body.contacts().len()
    );
    assert_eq!(after - before, 0, "a step with contacts allocated");
}
