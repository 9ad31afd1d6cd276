//! One mass–spring step (forces + integration) on the thesis's two-layer regions of the 65², 129²
//! and 257² planes, serial and on rayon pools of 1 and 2 threads. Throughput is in springs, so
//! criterion's "elem/s" gives ns/spring as its inverse.
#![allow(clippy::expect_used)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use tissue_mss::scenes::two_layer_region;
use tissue_mss::{Integrator, MassSpringSystem};

fn scene(n: u32) -> MassSpringSystem {
    let mut s = two_layer_region(n).expect("scene builds");
    s.set_gravity(Vec3::new(0.0, 0.0, -981.0)).expect("finite");
    // Criterion runs the step millions of times: symplectic Euler stays bounded there (the
    // thesis's explicit Euler costs the same per step but gains energy without end).
    s.set_integrator(Integrator::SymplecticEuler);
    // Lift the free particles (the thesis's start) so the springs are loaded.
    let free: Vec<bool> = s
        .particles()
        .inverse_masses()
        .iter()
        .map(|&w| w > 0.0)
        .collect();
    for (x, free) in s.particles_mut().positions_mut().iter_mut().zip(free) {
        if free {
            x.z += 0.02;
        }
    }
    s
}

fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("mss_step");
    for n in [65u32, 129, 257] {
        let base = scene(n);
        group.throughput(Throughput::Elements(base.springs().len() as u64));
        let label = format!("{}x{}_{}springs", n, n, base.springs().len());

        let mut serial = base.clone();
        serial.set_parallel(false);
        group.bench_function(BenchmarkId::new("serial", &label), |b| {
            b.iter(|| serial.step(1e-6).expect("stable"))
        });
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let mut s = base.clone();
            s.set_parallel(true);
            group.bench_function(BenchmarkId::new(format!("rayon{threads}"), &label), |b| {
                pool.install(|| b.iter(|| s.step(1e-6).expect("stable")))
            });
        }
    }
    group.finish();
}

/// The force phase alone, serial, at the largest size: the rest of a step is integration.
fn forces(c: &mut Criterion) {
    let mut group = c.benchmark_group("mss_forces");
    let mut s = scene(257);
    s.set_parallel(false);
    group.throughput(Throughput::Elements(s.springs().len() as u64));
    group.bench_function("serial/257x257", |b| b.iter(|| s.compute_forces()));
    group.finish();
}

criterion_group!(benches, step, forces);
criterion_main!(benches);
