//! Parallel projection (sibling blocks of the domain decomposition at the same time) is
//! bit-identical to the serial sweep, on 1, 2 and 3 threads.
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::tet_box;
use tissue_pbd::{Floor, Material, SoftBody, Solver, StepSettings, VolumeConstraintKind};

fn run(kind: VolumeConstraintKind, solver: Solver, parallel: bool, threads: usize) -> Vec<u32> {
    // 20³ cells: colours of a few thousand constraints, so the parallel path really forks.
    let mesh = tet_box(20, 20, 20, Vec3::splat(10.0)).unwrap();
    let material = Material {
        distance_stiffness: 0.7,
        volume_stiffness: 0.9,
        distance_compliance: 1e-4,
        volume_compliance: 1e-4,
        volume: kind,
        ..Material::default()
    };
    let mut body = SoftBody::new(&mesh, &material).unwrap();
    body.set_floor(Some(Floor::y(-4.0))).unwrap();
    body.pin(0).unwrap();
    assert!(
        body.block_count() >= 15,
        "too few blocks to exercise the parallel path"
    );
    body.set_settings(StepSettings {
        dt: 0.01,
        iterations: 5,
        solver,
        parallel,
        ..StepSettings::default()
    })
    .unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        for _ in 0..5 {
            body.step().unwrap();
        }
    });
    body.positions()
        .iter()
        .chain(body.velocities())
        .flat_map(|p| p.to_array())
        .map(f32::to_bits)
        .collect()
}

#[test]
fn parallel_is_bit_identical_for_any_thread_count_and_to_serial() {
    for (kind, solver) in [
        (VolumeConstraintKind::Centroid, Solver::PbdLinearised),
        (VolumeConstraintKind::Classic, Solver::Xpbd),
    ] {
        let serial = run(kind, solver, false, 1);
        for threads in [1, 2, 3] {
            assert!(
                run(kind, solver, true, threads) == serial,
                "{kind:?} {solver:?}: {threads} threads differ from serial"
            );
        }
    }
}
