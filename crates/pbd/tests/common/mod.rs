//! Shared test scenes and helpers.
#![allow(dead_code, clippy::print_stderr, clippy::expect_used)]

use glam::{DVec3, Vec3, Vec3A};
use tissue_mesh::TetMesh;
use tissue_pbd::SoftBody;

/// A file of the repository's `fixtures/` folder.
pub fn fixture(name: &str) -> std::path::PathBuf {
    std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures")).join(name)
}

/// The bunny of `fixtures/bunny_10k.obj` (≈ 1 unit tall, +y up, min y = 0), tetrahedralised
/// by `tissue-tetra` (about 40k tets, 0.2 s) and scaled ×10 to a 10 cm body. Panics when the
/// fixture is missing: it ships with the repository.
pub fn bunny() -> TetMesh {
    let surface =
        tissue_meshio::read_surface(fixture("bunny_10k.obj")).expect("fixtures/bunny_10k.obj");
    let tets = tissue_tetra::tetrahedralize(&surface, &tissue_tetra::TetraOptions::default())
        .expect("the bunny tetrahedralises")
        .mesh;
    let (positions, tets) = tets.into_parts();
    TetMesh::new(positions.iter().map(|p| *p * 10.0).collect(), tets).expect("bunny is valid")
}

/// SplitMix64.
pub struct Rng(pub u64);
impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [-1, 1).
    pub fn signed(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 23) as f32 - 1.0
    }
    pub fn vec3(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.signed(), self.signed(), self.signed()) * scale
    }
}

/// Centre of mass, linear momentum, angular momentum about the centre of mass, and the kinetic
/// energy not in the body's best-fit rigid motion (all nodes).
pub fn non_rigid_energy(body: &SoftBody) -> f64 {
    let m: Vec<f64> = body.masses().iter().map(|&m| m as f64).collect();
    let x: Vec<DVec3> = body.positions().iter().map(|p| p.as_dvec3()).collect();
    let v: Vec<DVec3> = body.velocities().iter().map(|p| p.as_dvec3()).collect();
    let total: f64 = m.iter().sum();
    let xc = m.iter().zip(&x).map(|(m, x)| *m * *x).sum::<DVec3>() / total;
    let vc = m.iter().zip(&v).map(|(m, v)| *m * *v).sum::<DVec3>() / total;
    let mut l = DVec3::ZERO;
    let mut i = glam::DMat3::ZERO;
    for k in 0..m.len() {
        let r = x[k] - xc;
        l += r.cross(m[k] * v[k]);
        i += m[k]
            * (glam::DMat3::from_diagonal(DVec3::splat(r.length_squared()))
                - glam::DMat3::from_cols(r * r.x, r * r.y, r * r.z));
    }
    let omega = i.inverse() * l;
    let ke = 0.5
        * m.iter()
            .zip(&v)
            .map(|(m, v)| m * v.length_squared())
            .sum::<f64>();
    ke - 0.5 * total * vc.length_squared() - 0.5 * omega.dot(l)
}

/// The fastest node's velocity relative to the body's rigid motion (cm/s): each node's
/// velocity less the mean velocity and the rigid rotation `ω × (x − c)` that carries the
/// body's angular momentum about its centre `c` (`ω = I⁻¹ L`, equal node weights). The U on
/// the tray turns slowly about the vertical (9 cm/s at its ends without self-collision, 21 with
/// it, 2026-11-29): a rigid drift, not the jitter measured here.
pub fn fastest_deformation(body: &SoftBody) -> f32 {
    let (x, v) = (body.positions(), body.velocities());
    let n = x.len() as f32;
    let c = x.iter().copied().sum::<Vec3A>() / n;
    let mean = v.iter().copied().sum::<Vec3A>() / n;
    let (mut l, mut inertia) = (Vec3A::ZERO, glam::Mat3::ZERO);
    for (p, u) in x.iter().zip(v) {
        let r = *p - c;
        l += r.cross(*u - mean);
        let r3 = glam::Vec3::from(r);
        inertia += glam::Mat3::from_diagonal(glam::Vec3::splat(r3.length_squared()))
            - glam::Mat3::from_cols(r3 * r3.x, r3 * r3.y, r3 * r3.z);
    }
    let omega = Vec3A::from(inertia.inverse() * glam::Vec3::from(l));
    x.iter()
        .zip(v)
        .map(|(p, u)| (*u - mean - omega.cross(*p - c)).length())
        .fold(0.0, f32::max)
}
