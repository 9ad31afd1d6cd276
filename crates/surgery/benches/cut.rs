//! A cut advancing through about twenty wall triangles of the bunny per step (42k tets), and the
//! step of the body around it. Inputs are built outside the timed closures; each iteration cuts
//! a fresh clone, so every sample is the same cut.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use criterion::{criterion_group, criterion_main, Criterion};
use glam::{Quat, Vec3};
use tissue_mesh::TetMesh;
use tissue_pbd::{Material, Pose, SoftBody, ToolShape};
use tissue_surgery::{BladeSweep, Surgery, SurgerySettings};

const BUNNY: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../fixtures/bunny_10k_tet42k"
);

fn bench(c: &mut Criterion) {
    let mesh = tissue_meshio::read_tets(BUNNY)
        .unwrap_or_else(|e| panic!("the bench's bunny {BUNNY}.node/.ele: {e}"));
    let (p, t) = mesh.into_parts();
    let mesh = TetMesh::new(p.iter().map(|p| *p * 10.0).collect(), t).unwrap();
    let lo = mesh
        .positions()
        .iter()
        .fold(Vec3::INFINITY, |a, p| a.min(*p));
    let hi = mesh
        .positions()
        .iter()
        .fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
    let body = SoftBody::new(&mesh, &Material::default()).unwrap();
    let surgery = Surgery::new(&body, SurgerySettings::default()).unwrap();
    let blade = ToolShape::Blade {
        a: Vec3::new(-0.3, 0.0, 0.0),
        b: Vec3::new(0.3, 0.0, 0.0),
        c: Vec3::new(0.0, 6.0, 0.0),
        thickness: 0.01,
    };
    let (cz, y) = (0.5 * (lo.z + hi.z) + 0.013, 0.5 * (lo.y + hi.y) + 1.0);
    let at = |x: f32| Pose::new(Quat::IDENTITY, Vec3::new(x, y, cz));
    let mid = 0.5 * (lo.x + hi.x);
    // Cut up to the middle first; the timed cut continues from there by 0.2 cm.
    let (mut cut_body, mut cut_surgery) = (body.clone(), surgery.clone());
    let mut x = lo.x - 0.5;
    while x < mid {
        cut_surgery
            .cut(
                &mut cut_body,
                &BladeSweep::new(&blade, &at(x), &at(x + 0.2)).unwrap(),
            )
            .unwrap();
        x += 0.2;
    }
    let sweep = BladeSweep::new(&blade, &at(x), &at(x + 0.2)).unwrap();
    let mut group = c.benchmark_group("bunny_cut");
    group.sample_size(20);
    group.bench_function("cut_0.2cm", |b| {
        b.iter_batched(
            || (cut_body.clone(), cut_surgery.clone()),
            |(mut body, mut surgery)| surgery.cut(&mut body, &sweep).unwrap(),
            criterion::BatchSize::LargeInput,
        )
    });
    let mut stepped = cut_body.clone();
    group.bench_function("step_after_cut", |b| b.iter(|| stepped.step().unwrap()));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
